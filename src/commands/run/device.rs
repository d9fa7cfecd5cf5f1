//! `canif run device` (and `canif run`): its arguments made into a plan of
//! the device side, once.

use std::process::ExitCode;

use crate::stop::{stop, Stop};

#[cfg(feature = "socketcan")]
use canif_harness::device::medium::kernel::KernelBusOptions;
use canif_harness::device::medium::BusChoice;
use canif_harness::device::{IutKind, Options};
use canif_harness::door::Pace;
use canif_spec::Catalogue;

use super::{campaign_plan, profiles, run_and_finish, selected};
use crate::cli::{BusArg, DeviceRunArgs, RealTimeOptions};
use crate::commands::{declared, iut_kind};

pub(crate) fn command(catalogue: &Catalogue, args: DeviceRunArgs) -> Result<ExitCode, Stop> {
    let DeviceRunArgs {
        iut,
        common,
        campaign,
        cases,
        duration,
        trace,
        trace_epoch,
        bus,
        real_time,
        no_fail_fast,
    } = args;
    let Some(selected) = selected(&common, &campaign, canif_spec::Side::Device)? else {
        return Ok(ExitCode::SUCCESS);
    };
    let bus = bus_choice(&bus, &real_time);
    let kind = iut_kind(&iut)?;
    let door = match &kind {
        IutKind::Door(door) => Some(door.transport()),
        _ => None,
    };
    let mut profiles = profiles(catalogue, &selected.profiles)?;
    // A door that serves only some profiles (a terminal only terminal
    // profiles): `all` (the default) means all of those.
    let every = selected.profiles.is_empty() || selected.profiles.iter().any(|p| p == "all");
    if let Some(door) = door.filter(|_| every) {
        profiles.retain(|p| door.serves(p));
    }
    if let Some(dir) = &trace {
        // A trace folder that cannot be written is said before the
        // run, not found missing after it.
        let writable = std::fs::create_dir_all(dir).and_then(|()| {
            let probe = dir.join(".canif-trace-probe");
            std::fs::write(&probe, b"").and_then(|()| std::fs::remove_file(probe))
        });
        if let Err(error) = writable {
            return Err(stop!(
                "--trace {}: cannot write there: {error}",
                dir.display()
            ));
        }
    }
    let started = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    let options = Options {
        seed: common.seed,
        cases: if duration.is_some() {
            1
        } else {
            cases.unwrap_or(4)
        },
        generated_cycles: duration.map_or(200, |s| (s * 1000.0).max(1.0) as u64),
        counter_wrap: !campaign.no_counter_wrap && bus.is_sim(),
        trace_dir: trace,
        trace_epoch: trace_epoch.map_or(started.as_nanos() as u64, |s| {
            s.saturating_mul(1_000_000_000)
        }),
        bus,
        selection: selected.selection,
        fail_fast: !no_fail_fast,
        declared: declared(&iut.declare)?,
        survey: pace(&real_time),
    };
    let plan = campaign_plan(profiles, options, &common, &campaign, selected.rerun)?;
    run_and_finish(catalogue, &plan, &kind, &common.report)
}

/// How the terminals of a run over EtherCAT are surveyed before it: a soak
/// at the real-time cycle when asked for, else a burst of idle cycles.
fn pace(real_time: &RealTimeOptions) -> Pace {
    match real_time.ethercat_soak_s {
        0 => Pace::default(),
        seconds => Pace::Every {
            period: std::time::Duration::from_micros(real_time.cycle_us),
            soak: std::time::Duration::from_secs(seconds),
        },
    }
}

/// The bus the command line chose, with its real-time options.
#[cfg_attr(not(feature = "socketcan"), allow(unused_variables))]
pub(crate) fn bus_choice(bus: &BusArg, real_time: &RealTimeOptions) -> BusChoice {
    match bus {
        BusArg::Sim => BusChoice::Sim,
        #[cfg(feature = "socketcan")]
        BusArg::SocketCan(spec) => BusChoice::SocketCan(KernelBusOptions {
            spec: spec.clone(),
            cycle_time: real_time.cycle_us * 1_000,
            time_stamp_tolerance: real_time.time_stamp_tolerance_us * 1_000,
            timeout: real_time.frame_timeout.duration(),
            remote_frames: !real_time.no_remote_frames,
            esi_settable: !real_time.esi_from_controller,
        }),
    }
}
