//! A run of the CANopen suite: the node checks (002, 004) on the simulated
//! coupler or a node on a SocketCAN interface, with the same selection,
//! events and reports as the two sides of the interface.

use canif_harness::canopen::side::{CanopenSide, NodeTarget};
use canif_harness::report::{RunMeta, RunReport, SuiteKind};
use canif_spec::Catalogue;

use crate::error::PlanError;
use crate::event::Observer;
use crate::{Campaign, Plan};

impl Campaign for CanopenSide {
    const UNIT: Option<&'static str> = None;

    fn name_of(target: &NodeTarget) -> String {
        target.describe()
    }

    /// One node, one run.
    fn shared(_: &Plan<'_, Self>, _: &NodeTarget) -> Option<&'static str> {
        Some("the CANopen suite: one node")
    }

    /// The node reached once to see that it can be: a missing interface is
    /// one line, not an error per check.
    fn preflight(_: &Plan<'_, Self>, _: &Catalogue, target: &NodeTarget) -> Result<(), PlanError> {
        target
            .reachable()
            .map_err(|error| PlanError::Preflight(format!("canif: {}", error.what)))
    }

    fn execute(
        plan: &Plan<'_, Self>,
        catalogue: &Catalogue,
        target: &NodeTarget,
        observer: &dyn Observer,
    ) -> RunReport {
        let started = std::time::Instant::now();
        let name = plan
            .profiles
            .first()
            .map_or_else(String::new, |p| p.name.clone());
        let meta = RunMeta {
            suite: SuiteKind::Canopen,
            ..RunMeta::new(name, described(target), plan.options.seed, catalogue)
        };
        let checks = plan.run_profiles(target, observer);
        let left_out = plan.left_out(&checks);
        plan.assemble(
            catalogue,
            (checks, Vec::new()),
            left_out,
            meta,
            (started, observer),
        )
    }
}

fn described(target: &NodeTarget) -> String {
    match target {
        NodeTarget::Simulated { .. } => target.describe(),
        #[cfg(feature = "socketcan")]
        NodeTarget::SocketCan { .. } => format!(
            "{} (Linux {})",
            target.describe(),
            canif_kernel::kernel_release()
        ),
    }
}

/// The one "profile" a node is judged on: every requirement, every
/// capability, named after the node (`canopen-node-5`).
pub fn node_profile(
    catalogue: &Catalogue,
    target: &NodeTarget,
) -> Result<canif_spec::Profile, PlanError> {
    let mut profile = catalogue.profiles.first().cloned().ok_or_else(|| {
        PlanError::Preflight("the catalogue has no profile to judge the node against".into())
    })?;
    profile.name = format!("canopen-node-{}", target.node().get());
    profile.capabilities = catalogue
        .capabilities
        .iter()
        .map(|c| c.name.clone())
        .collect();
    Ok(profile)
}
