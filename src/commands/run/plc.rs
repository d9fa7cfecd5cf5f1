//! `canif run --side plc`: a PLC-side client under test. The harness plays
//! the device, the EtherCAT master and the application; the report has the
//! same shape as the device side's, with `side: plc` and the master models.

use std::path::Path;
use std::process::ExitCode;

use crate::stop::{stop, Stop};

use canif_features::schedule::declined_by_client;
use canif_harness::client::master::Master;
use canif_harness::client::suite::{ClientBus, ClientKind, ClientOptions};
use canif_harness::device::bus::BusChoice;
use canif_harness::report::{ChoiceEntry, ChoiceSource, RunMeta, RunReport};
use canif_spec::{Catalogue, Side};

use super::{finish, Plan};

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

/// The bus of `--side plc`: the simulated one, or one SocketCAN interface
/// that the played device's controller and the other nodes share.
pub(crate) fn client_bus(bus: &BusChoice) -> Result<ClientBus, Stop> {
    match bus {
        BusChoice::Sim => Ok(ClientBus::Sim),
        #[cfg(feature = "socketcan")]
        BusChoice::SocketCan(options) => {
            let spec = &options.spec;
            if spec.iut != spec.tester {
                return Err(stop!("--side plc: one interface (socketcan:IFACE); the device and the other nodes share it"));
            }
            if let Err(error) = canif_kernel::probe()
                .and_then(|()| canif_kernel::KernelSocket::open(&spec.iut, false).map(|_| ()))
            {
                return Err(stop!("error: --bus {}: {error}", spec.describe()));
            }
            Ok(ClientBus::SocketCan {
                interface: spec.iut.clone(),
                timeout: options.timeout,
            })
        }
    }
}

pub(crate) fn run(
    catalogue: &Catalogue,
    kind: &ClientKind,
    plan: &Plan<ClientOptions>,
    report_dir: &Path,
) -> Result<ExitCode, Stop> {
    plan.check_selection(catalogue)?;
    finish(catalogue, &execute(catalogue, kind, plan), report_dir)
}

/// Every profile's client run and the `@plc` Gherkin scenarios, judged and put in one report.
pub(crate) fn execute(
    catalogue: &Catalogue,
    kind: &ClientKind,
    plan: &Plan<ClientOptions>,
) -> RunReport {
    let options = &plan.options;
    let started = std::time::Instant::now();
    let declared = options.declaration();
    let meta = RunMeta {
        side: Side::Plc,
        masters: options.masters.iter().map(|m| m.name.to_string()).collect(),
        // What the client declares: the verdicts rest on it.
        choices: declared
            .lines()
            .into_iter()
            .map(|choice| ChoiceEntry {
                choice,
                how: ChoiceSource::Declared,
            })
            .collect(),
        ..RunMeta::new(kind.name(), options.bus.describe(), options.seed, catalogue)
    };
    // The Gherkin scenarios the client's declaration leaves out, with why.
    let (gherkin, declined): (Vec<_>, Vec<_>) =
        plan.gherkin
            .iter()
            .cloned()
            .partition(|(profile, scenario)| {
                let profile = plan.profiles.iter().find(|p| p.name == *profile);
                profile.is_none_or(|p| declined_by_client(scenario, p, &declared).is_none())
            });
    let plan = &Plan {
        profiles: plan.profiles.clone(),
        options: plan.options.clone(),
        product: plan.product.clone(),
        gherkin,
        jobs: plan.jobs,
        rerun: plan.rerun.clone(),
        campaign: plan.campaign.clone(),
    };
    let mut lockstep = plan.run_profiles_on(catalogue, kind, Some("task cycles"), plan.jobs);
    for run in &mut lockstep {
        for (profile, scenario) in declined.iter().filter(|(p, _)| *p == run.profile) {
            let profile = plan.profiles.iter().find(|p| p.name == *profile);
            if let Some(why) = profile.and_then(|p| declined_by_client(scenario, p, &declared)) {
                run.reach
                    .not_served
                    .push((format!("gherkin: {}", scenario.id()), why));
            }
        }
    }
    let mut left_out = plan.selection_left_out();
    if !options.counter_wrap {
        left_out.push("the 65,600-cycle counter wrap (--no-counter-wrap)".to_string());
    }
    if options.masters.len() < Master::ALL.len() {
        left_out.push("master models left out by --master".to_string());
    }
    let gherkin = if canif_harness::interrupt::requested() {
        left_out.push("interrupted before the Gherkin scenarios".into());
        Vec::new()
    } else if options.bus != ClientBus::Sim {
        left_out.push("Gherkin scenarios not run: they use the simulated bus".into());
        Vec::new()
    } else {
        plan.run_gherkin(&canif_features::UnderTest::Client(
            kind.clone(),
            declared.clone(),
        ))
    };
    // Client processes kept for the next program have none left to run.
    canif_harness::door::Door::release_idle_clients();
    plan.assemble(catalogue, lockstep, gherkin, left_out, meta, started)
}
