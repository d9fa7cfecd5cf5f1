//! `canif run plc`: its arguments made into a plan of the PLC side, once.

use std::process::ExitCode;

use crate::stop::{stop, Stop};

use canif_harness::client::master::Master;
use canif_harness::client::suite::{ClientBus, ClientOptions};
use canif_spec::Catalogue;

use super::{campaign_plan, profiles, run_and_finish, selected};
use crate::cli::{BusArg, FrameTimeout, PlcRunArgs};
use crate::commands::{client_kind, declared};

pub(crate) fn command(catalogue: &Catalogue, args: PlcRunArgs) -> Result<ExitCode, Stop> {
    let PlcRunArgs {
        iut,
        common,
        campaign,
        master,
        bus,
        frame_timeout,
    } = args;
    let Some(selected) = selected(&common, &campaign, canif_spec::Side::Plc)? else {
        return Ok(ExitCode::SUCCESS);
    };
    let bus = client_bus(&bus, frame_timeout)?;
    let profiles = profiles(catalogue, &selected.profiles)?;
    let kind = client_kind(&iut)?;
    let options = ClientOptions {
        seed: common.seed,
        bus,
        counter_wrap: !campaign.no_counter_wrap,
        masters: masters(&master)?,
        selection: selected.selection,
        declared: Ok(declared(&iut.declare)?),
    };
    // What the client declares of itself, asked once.
    let options = options.declared_by(&kind);
    let plan = campaign_plan(profiles, options, &common, &campaign, selected.rerun)?;
    run_and_finish(catalogue, &plan, &kind, &common.report)
}

/// The master models named on the command line (all when none), or the exit code of a usage error.
pub(crate) fn masters(names: &[String]) -> Result<Vec<Master>, Stop> {
    if names.is_empty() {
        return Ok(Master::ALL.to_vec());
    }
    names
        .iter()
        .map(|name| {
            Master::by_name(name).ok_or_else(|| {
                let known: Vec<&str> = Master::ALL.iter().map(|m| m.name).collect();
                stop!("unknown master `{name}`; known: {}", known.join(", "))
            })
        })
        .collect()
}

/// The bus of `canif run plc`: the simulated one, or one SocketCAN interface
/// that the played device's controller and the other nodes share.
#[cfg_attr(not(feature = "socketcan"), allow(unused_variables))]
fn client_bus(bus: &BusArg, frame_timeout: FrameTimeout) -> Result<ClientBus, Stop> {
    match bus {
        BusArg::Sim => Ok(ClientBus::Sim),
        #[cfg(feature = "socketcan")]
        BusArg::SocketCan(spec) => {
            if spec.iut != spec.tester {
                return Err(stop!("canif run plc: one interface (socketcan:IFACE); the device and the other nodes share it"));
            }
            Ok(ClientBus::SocketCan {
                interface: spec.iut.clone(),
                timeout: frame_timeout.duration(),
            })
        }
    }
}
