//! `canif run canopen`: its arguments made into a plan of the CANopen node
//! checks (002, 004), on the simulated coupler or a node on a SocketCAN
//! interface.

use std::process::ExitCode;

use canif_harness::canopen::side::{CanopenSide, NodeTarget};
use canif_runner::{node_profile, Plan};
use canif_spec::Catalogue;

use super::run_and_finish;
use crate::cli::{BusArg, CanopenRunArgs};
use crate::commands::device::{coupler_fault, node_id};
use crate::stop::Stop;

pub(crate) fn command(catalogue: &Catalogue, args: CanopenRunArgs) -> Result<ExitCode, Stop> {
    let target = target(&args)?;
    let profile = node_profile(catalogue, &target)?;
    let mut side = CanopenSide::new(canif_harness::run::Selection {
        scenarios: args.common.scenario.clone(),
        requirements: args.common.requirement.clone(),
        shard: None,
    });
    side.seed = args.common.seed;
    let plan = Plan::new(vec![&profile], side, args.common.product.product())?;
    run_and_finish(catalogue, &plan, &target, &args.common.report)
}

/// The node `--bus`, `--node` and `--coupler-fault` name.
fn target(args: &CanopenRunArgs) -> Result<NodeTarget, Stop> {
    let node = node_id(args.node)?;
    Ok(match &args.bus {
        BusArg::Sim => NodeTarget::Simulated {
            node,
            fault: coupler_fault(args.coupler_fault.as_deref())?,
        },
        #[cfg(feature = "socketcan")]
        BusArg::SocketCan(spec) => {
            if args.coupler_fault.is_some() {
                return Err(crate::stop::stop!("--coupler-fault applies to the simulated coupler; on a SocketCAN bus, start `canif coupler --bus … --fault …` instead"));
            }
            NodeTarget::SocketCan {
                interface: spec.tester.clone(),
                node,
                answer_timeout: args
                    .frame_timeout
                    .duration()
                    .min(std::time::Duration::from_millis(500)),
            }
        }
    })
}
