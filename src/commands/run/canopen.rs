//! `canif run --suite canopen`: the CANopen node checks (002, 004) as a side
//! of the suite, on the simulated coupler or a node on a SocketCAN
//! interface, with the same selection, progress and reports as the others.

use std::path::Path;
use std::process::ExitCode;

use canif_harness::canopen::side::{CanopenSide, NodeTarget};
use canif_harness::report::{RunMeta, SuiteKind};
use canif_spec::{Catalogue, Profile};

use super::{finish, Plan};
use crate::cli::{IutArg, IutOptions};
use crate::commands::device::{coupler_fault, node_id};
use crate::stop::{stop, Stop};
use canif_harness::device::bus::BusChoice;

/// The node `--bus`, `--node` and `--coupler-fault` name, reached once to
/// see that it can be (a missing interface is one line, not an error per check).
pub(crate) fn target(
    iut: &IutOptions,
    bus: &BusChoice,
    node: u8,
    fault: Option<&str>,
) -> Result<NodeTarget, Stop> {
    if iut.iut.as_ref().is_some_and(|i| *i != IutArg::SoftDevice) || !iut.fault.is_empty() {
        return Err(stop!("--suite canopen checks a CANopen node (the simulated coupler, or a node on --bus), not an interface IUT: --iut and --fault do not apply (--coupler-fault does)"));
    }
    let node = node_id(node)?;
    let target = match bus {
        BusChoice::Sim => NodeTarget::Simulated {
            node,
            fault: coupler_fault(fault)?,
        },
        #[cfg(feature = "socketcan")]
        BusChoice::SocketCan(options) => {
            if fault.is_some() {
                return Err(stop!("--coupler-fault applies to the simulated coupler; on a SocketCAN bus, start `canif coupler --bus … --fault …` instead"));
            }
            NodeTarget::SocketCan {
                interface: options.spec.tester.clone(),
                node,
                answer_timeout: options.timeout.min(std::time::Duration::from_millis(500)),
            }
        }
    };
    target
        .reachable()
        .map_err(|error| stop!("canif: {}", error.what))?;
    Ok(target)
}

/// The one "profile" a node is judged on: every requirement, every
/// capability, named after the node (`canopen-node-5`).
pub(crate) fn node_profile(catalogue: &Catalogue, target: &NodeTarget) -> Result<Profile, Stop> {
    let mut profile = catalogue
        .profiles
        .first()
        .cloned()
        .ok_or_else(|| stop!("the catalogue has no profile to judge the node against"))?;
    profile.name = format!("canopen-node-{}", target.node().get());
    profile.capabilities = catalogue
        .capabilities
        .iter()
        .map(|c| c.name.clone())
        .collect();
    Ok(profile)
}

/// Runs the checks against `target` and writes the reports.
pub(crate) fn run(
    catalogue: &Catalogue,
    target: &NodeTarget,
    plan: &Plan<CanopenSide>,
    seed: u64,
    report_dir: &Path,
) -> Result<ExitCode, Stop> {
    plan.check_selection(catalogue)?;
    let started = std::time::Instant::now();
    let meta = RunMeta {
        suite: SuiteKind::Canopen,
        ..RunMeta::new(
            plan.profiles[0].name.clone(),
            described(target),
            seed,
            catalogue,
        )
    };
    let checks = plan.run_profiles(catalogue, target, None);
    let left_out = plan.selection_left_out();
    let report = plan.assemble(catalogue, checks, Vec::new(), left_out, meta, started);
    finish(catalogue, &report, report_dir)
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
