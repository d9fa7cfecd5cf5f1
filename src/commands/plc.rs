//! `canif run --side plc`: a PLC-side client under test. The harness plays
//! the device, the EtherCAT master and the application; the report has the
//! same shape as the device side's, with `side: plc` and the master models.

use std::path::Path;
use std::process::ExitCode;

use canif_harness::client::master::Master;
use canif_harness::client::suite::{self, ClientBus, ClientKind, ClientOptions};
use canif_harness::report::{Product, ProfileReport, RunMeta, RunReport};
use canif_harness::{GherkinOutcome, GherkinRun, Selection};
use canif_spec::{Catalogue, Profile, Side};

use canif_harness::bus::BusChoice;

/// What `--side plc` was asked for, checked.
pub struct PlcPlan<'c> {
    pub profiles: Vec<&'c Profile>,
    pub options: ClientOptions,
    pub product: Option<Product>,
}

/// The master models named on the command line (all when none), or the exit code of a usage error.
pub fn masters(names: &[String]) -> Result<Vec<Master>, ExitCode> {
    if names.is_empty() {
        return Ok(Master::ALL.to_vec());
    }
    names
        .iter()
        .map(|name| {
            Master::by_name(name).ok_or_else(|| {
                let known: Vec<&str> = Master::ALL.iter().map(|m| m.name).collect();
                eprintln!("unknown master `{name}`; known: {}", known.join(", "));
                ExitCode::from(2)
            })
        })
        .collect()
}

/// The bus of `--side plc`: the simulated one, or one SocketCAN interface
/// that the played device's controller and the other nodes share.
pub fn client_bus(bus: &BusChoice) -> Result<ClientBus, ExitCode> {
    match bus {
        BusChoice::Sim => Ok(ClientBus::Sim),
        #[cfg(feature = "socketcan")]
        BusChoice::SocketCan(options) => {
            let spec = &options.spec;
            if spec.iut != spec.tester {
                eprintln!("--side plc: one interface (socketcan:IFACE); the device and the other nodes share it");
                return Err(ExitCode::from(2));
            }
            if let Err(error) = canif_kernel::probe()
                .and_then(|()| canif_kernel::KernelSocket::open(&spec.iut, false).map(|_| ()))
            {
                eprintln!("error: --bus {}: {error}", spec.describe());
                return Err(ExitCode::from(2));
            }
            Ok(ClientBus::SocketCan {
                interface: spec.iut.clone(),
                timeout: options.timeout,
            })
        }
    }
}

/// A selection that matches no check of the plan is a usage error, as on the device side.
fn check_selection(catalogue: &Catalogue, plan: &PlcPlan) -> Result<(), ExitCode> {
    let selection: &Selection = &plan.options.selection;
    for id in &selection.requirements {
        if catalogue.requirement(id).is_none() {
            eprintln!("--requirement {id}: no such requirement; `canif spec list` lists them");
            return Err(ExitCode::from(2));
        }
    }
    let matched = plan.profiles.iter().any(|profile| {
        suite::scenarios(&profile.model_capabilities(), &plan.options)
            .iter()
            .any(|(scenario, master)| {
                selection.admits(
                    &suite::run_name(scenario, *master),
                    scenario.covers.iter().map(|id| id.as_str()),
                )
            })
    });
    if matched || selection.is_everything() {
        Ok(())
    } else {
        eprintln!("{} matches no PLC-side check", selection.flags());
        Err(ExitCode::from(2))
    }
}

pub fn run(
    catalogue: &Catalogue,
    kind: &ClientKind,
    plan: &PlcPlan,
    report_dir: &Path,
) -> ExitCode {
    if let Err(code) = check_selection(catalogue, plan) {
        return code;
    }
    let report = execute(catalogue, kind, plan);
    super::run::finish(catalogue, &report, report_dir)
}

/// Every profile's client run, judged and put in one report.
pub fn execute(catalogue: &Catalogue, kind: &ClientKind, plan: &PlcPlan) -> RunReport {
    let started = std::time::Instant::now();
    let count = plan.profiles.len();
    let mut profiles = Vec::new();
    let mut gherkin_left_out = None;
    for (n, profile) in plan.profiles.iter().enumerate() {
        if canif_harness::interrupt::requested() {
            eprintln!("interrupted: the remaining profiles are not run");
            break;
        }
        let mut progress = super::run::Progress::new(n, count, &profile.name);
        let run = suite::run_profile(catalogue, profile, kind, &plan.options, |scenario_run| {
            progress.scenario(scenario_run)
        });
        progress.done(&run, "task cycles");
        let gherkin = match run_features(kind, profile, &plan.options) {
            Ok(runs) => runs,
            Err(why) => {
                gherkin_left_out = Some(why);
                Vec::new()
            }
        };
        let reach = suite::reach(catalogue, &profile.model_capabilities(), &plan.options);
        profiles.push(ProfileReport::new(
            catalogue,
            profile,
            run,
            gherkin,
            Vec::new(),
            &reach,
        ));
    }
    let interrupted = canif_harness::interrupt::requested();
    let mut left_out = Vec::new();
    if !plan.options.selection.is_everything() {
        left_out.push(plan.options.selection.describe());
    }
    if !plan.options.counter_wrap {
        left_out.push("the 65,600-cycle counter wrap (--no-counter-wrap)".to_string());
    }
    if plan.options.masters.len() < Master::ALL.len() {
        left_out.push("master models left out by --master".to_string());
    }
    left_out.extend(gherkin_left_out);
    for line in &left_out {
        eprintln!("left out: {line}");
    }
    RunReport {
        meta: RunMeta {
            complete: left_out.is_empty() && !interrupted,
            product: plan.product.clone(),
            left_out: (!left_out.is_empty()).then(|| left_out.join("; ")),
            side: Side::Plc,
            masters: plan
                .options
                .masters
                .iter()
                .map(|m| m.name.to_string())
                .collect(),
            ..RunMeta::new(
                kind.name(),
                plan.options.bus.describe(),
                plan.options.seed,
                catalogue,
            )
        },
        profiles,
        wall_time_ms: started.elapsed().as_millis(),
        interrupted,
    }
}

/// The `@plc` Gherkin scenarios the profile offers, against the client, or
/// why none ran (the report says it, so the run is not complete).
fn run_features(
    kind: &ClientKind,
    profile: &Profile,
    options: &ClientOptions,
) -> Result<Vec<GherkinRun>, String> {
    if options.bus != ClientBus::Sim {
        return Err("Gherkin scenarios not run: they use the simulated bus".into());
    }
    let scenarios = canif_features::scenarios()
        .map_err(|e| format!("Gherkin scenarios not run: the feature files do not parse: {e}"))?;
    let mut runs = Vec::new();
    for scenario in scenarios {
        let id = scenario.id();
        if scenario.side != Side::Plc
            || !profile.lacks(&scenario.capabilities).is_empty()
            || !options
                .selection
                .admits(&id, scenario.requirements.iter().map(String::as_str))
        {
            continue;
        }
        let target = canif_features::ClientTarget {
            client: kind.clone(),
            profile: profile.name.clone(),
            caps: profile.model_capabilities(),
        };
        let started = std::time::Instant::now();
        let outcome =
            match canif_features::run_client_scenario(&scenario.file, scenario.line, target) {
                canif_features::ScenarioOutcome::Passed => GherkinOutcome::Pass,
                // The judge names exactly what a client broke, whatever the
                // scenario is tagged with.
                canif_features::ScenarioOutcome::Failed { report, witness } => {
                    GherkinOutcome::Fail {
                        step: super::run::failing_step(&report),
                        blamed: if witness.is_empty() {
                            scenario.requirements.clone()
                        } else {
                            witness.iter().map(|id| id.to_string()).collect()
                        },
                        report,
                    }
                }
                canif_features::ScenarioOutcome::Error(report) => GherkinOutcome::Error(report),
            };
        runs.push(GherkinRun {
            id,
            file: scenario.file.clone(),
            line: scenario.line,
            requirements: scenario.requirements.clone(),
            outcome,
            elapsed: started.elapsed(),
        });
    }
    Ok(runs)
}

/// `canif list scenarios --side plc`: every check a client run of these
/// profiles can select, with the requirements each exercises.
pub fn list_scenarios(catalogue: &Catalogue, names: &[String], out: &mut String) -> ExitCode {
    let profiles = match super::run::profiles(catalogue, names) {
        Ok(p) => p,
        Err(code) => return code,
    };
    let options = ClientOptions::new(1);
    let gherkin = canif_features::scenarios().unwrap_or_default();
    for profile in profiles {
        let caps = profile.model_capabilities();
        for (scenario, master) in suite::scenarios(&caps, &options) {
            let covers: Vec<&str> = scenario.covers.iter().map(|id| id.as_str()).collect();
            outln!(
                out,
                "{}\t{}\t{}",
                profile.name,
                suite::run_name(&scenario, master),
                covers.join(" ")
            );
        }
        for scenario in gherkin
            .iter()
            .filter(|s| s.side == Side::Plc && profile.lacks(&s.capabilities).is_empty())
        {
            outln!(
                out,
                "{}\t{}\t{}",
                profile.name,
                scenario.id(),
                scenario.requirements.join(" ")
            );
        }
    }
    ExitCode::SUCCESS
}
