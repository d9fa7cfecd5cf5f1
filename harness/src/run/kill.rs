//! The kill matrix: every deliberate fault of a side on every profile, and
//! the requirements each was caught on. The suite's power, proved on itself.

use canif_spec::Catalogue;

use super::{run_profile, Cases};

/// A side with deliberate faults of its own implementation (the soft device,
/// the soft client), to prove the suite catches each.
pub trait SelfCheck: Cases + Sized {
    type Fault: Copy;
    /// Every fault, in the order the matrix lists them.
    fn faults() -> Vec<Self::Fault>;
    fn fault_name(fault: Self::Fault) -> &'static str;
    /// The options and the faulty implementation a fault's row runs with.
    fn with_fault(&self, fault: Self::Fault) -> (Self, Self::UnderTest);
}

/// One row: a fault and what it broke on each profile.
#[derive(Debug, Clone)]
pub struct KillRow<F> {
    pub fault: F,
    /// Profile name → requirement ids that failed (empty: not caught there).
    pub caught: Vec<(String, Vec<String>)>,
}

/// Runs each fault of the side on every profile.
pub fn kill_matrix<S: SelfCheck>(
    catalogue: &Catalogue,
    side: &S,
    mut progress: impl FnMut(&str),
) -> Vec<KillRow<S::Fault>> {
    S::faults()
        .into_iter()
        .map(|fault| {
            progress(S::fault_name(fault));
            let (side, under_test) = side.with_fault(fault);
            let caught = catalogue
                .profiles
                .iter()
                .map(|profile| {
                    let run = run_profile(profile, &under_test, &side, |_| {});
                    (
                        profile.name.clone(),
                        run.failed_requirements(catalogue, profile),
                    )
                })
                .collect();
            KillRow { fault, caught }
        })
        .collect()
}

/// The requirements of side `S`'s suite that a test judges (whatever their
/// status: an assumption is judged too) and that no fault failed, given the
/// ids the faults failed: statements the self-check has not yet shown it catches a
/// breach of. In catalogue order.
pub fn unreached<S: SelfCheck>(
    catalogue: &Catalogue,
    failed: impl IntoIterator<Item = impl AsRef<str>>,
) -> Vec<&str> {
    let failed: std::collections::BTreeSet<String> = failed
        .into_iter()
        .map(|id| id.as_ref().to_string())
        .collect();
    catalogue
        .requirements()
        .filter(|r| r.side == S::SIDE && r.suite == S::SUITE)
        .filter(|r| r.verification == canif_spec::Verification::Test)
        .map(|r| r.id.as_str())
        .filter(|id| !failed.contains(*id))
        .collect()
}

impl<F> KillRow<F> {
    /// Every requirement the fault failed on some profile.
    pub fn failed(&self) -> impl Iterator<Item = &str> {
        self.caught
            .iter()
            .flat_map(|(_, ids)| ids.iter().map(String::as_str))
    }
}
