//! The kill matrix: every deliberate fault of a side on every profile, and
//! the requirements each was caught on. The suite's power, proved on itself.

use canif_spec::Catalogue;

use super::{run_profile, Side};

/// One row: a fault and what it broke on each profile.
#[derive(Debug, Clone)]
pub struct KillRow<F> {
    pub fault: F,
    /// Profile name → requirement ids that failed (empty: not caught there).
    pub caught: Vec<(String, Vec<String>)>,
}

/// Runs each fault on every profile; `setup` gives the side's options and
/// what is under test for one fault, `name` what `progress` is told.
pub fn kill_matrix<S: Side, F: Copy>(
    catalogue: &Catalogue,
    faults: impl IntoIterator<Item = F>,
    setup: impl Fn(F) -> (S, S::UnderTest),
    name: impl Fn(F) -> &'static str,
    mut progress: impl FnMut(&str),
) -> Vec<KillRow<F>> {
    faults
        .into_iter()
        .map(|fault| {
            progress(name(fault));
            let (side, under_test) = setup(fault);
            let caught = catalogue
                .profiles
                .iter()
                .map(|profile| {
                    let run = run_profile(profile, &side, &under_test, |_| {});
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
