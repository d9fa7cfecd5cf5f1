//! `canif run` (the interface suite) and `canif self-check`.

use std::io::{IsTerminal, Write as _};
use std::path::Path;
use std::process::ExitCode;

#[cfg(feature = "socketcan")]
use canif_harness::bus::kernel::KernelBusOptions;
use canif_harness::bus::BusChoice;
use canif_harness::report::{RunReport, ScenarioResult};
use canif_harness::suite::{run_profile, Options};
use canif_harness::{IutKind, Outcome};
use canif_spec::Catalogue;

use super::resolve_iut;
use crate::cli::{BusArg, IutOptions, RealTimeOptions};

pub fn run(
    catalogue: &Catalogue,
    iut: &IutOptions,
    profile: &str,
    options: &Options,
    report_dir: &Path,
) -> ExitCode {
    let kind = match resolve_iut(iut) {
        Ok(kind) => kind,
        Err(code) => return code,
    };
    let profiles: Vec<_> = if profile == "all" {
        catalogue.profiles.iter().collect()
    } else {
        match catalogue.profile(profile) {
            Some(p) => vec![p],
            None => {
                let names: Vec<_> = catalogue.profiles.iter().map(|p| p.name.as_str()).collect();
                eprintln!("unknown profile `{profile}`; known: {}", names.join(", "));
                return ExitCode::from(2);
            }
        }
    };
    #[cfg(feature = "socketcan")]
    if let BusChoice::SocketCan(kernel) = &options.bus {
        // A bus that cannot be opened at all is one error, not one per scenario.
        let opened = canif_kernel::probe().and_then(|()| {
            canif_kernel::KernelSocket::open(&kernel.spec.iut, false)?;
            canif_kernel::KernelSocket::open(&kernel.spec.tester, false).map(|_| ())
        });
        if let Err(error) = opened {
            eprintln!("error: --bus {}: {error}", kernel.spec.describe());
            return ExitCode::from(2);
        }
    }
    let started = std::time::Instant::now();
    let terminal = std::io::stderr().is_terminal();
    let mut results = Vec::new();
    for (n, p) in profiles.iter().enumerate() {
        if canif_harness::interrupt::requested() {
            eprintln!("interrupted: the remaining profiles are not run");
            break;
        }
        let mut done = 0;
        let result = run_profile(catalogue, p, &kind, options, |scenario_run| {
            done += 1;
            if terminal {
                eprint!(
                    "\r\x1b[2K[{}/{}] {}: {} ({} scenarios)",
                    n + 1,
                    profiles.len(),
                    p.name,
                    scenario_run.scenario,
                    done
                );
                let _ = std::io::stderr().flush();
            }
        });
        let failed = result
            .runs
            .iter()
            .filter(|r| matches!(r.outcome, Outcome::Fail(_)))
            .count();
        let errors = result
            .runs
            .iter()
            .filter(|r| matches!(r.outcome, Outcome::Error(_)))
            .count();
        if terminal {
            eprint!("\r\x1b[2K");
        }
        eprintln!(
            "[{}/{}] {:<22} {} scenarios, {} cycles, {} frames checked: {}",
            n + 1,
            profiles.len(),
            p.name,
            result.runs.len(),
            result.cycles(),
            result.frames_checked(),
            match (failed, errors) {
                (0, 0) => "conforms".to_string(),
                (f, 0) => format!("{f} scenario(s) FAIL"),
                (f, e) => format!("{f} fail, {e} ERROR"),
            }
        );
        results.push(result);
    }
    let iut_broke = results.iter().flat_map(|p| &p.runs).any(|r| {
        matches!(
            r.outcome,
            Outcome::Error(canif_harness::RunError::Iut(_) | canif_harness::RunError::Skipped(_))
        )
    });
    let scenarios = if canif_harness::interrupt::requested() {
        eprintln!("Gherkin scenarios: not run (interrupted)");
        Vec::new()
    } else if iut_broke && options.fail_fast {
        eprintln!(
            "Gherkin scenarios: not run (the IUT broke above; --no-fail-fast runs them anyway)"
        );
        Vec::new()
    } else if !options.bus.is_sim() || !options.only.is_empty() {
        // The Gherkin scenarios run on the simulated bus; a SocketCAN or filtered run leaves them out.
        eprintln!(
            "Gherkin scenarios: not run (they use the simulated bus; run without --bus/--scenario)"
        );
        Vec::new()
    } else {
        match run_features(&kind, &profiles) {
            Ok(scenarios) => scenarios,
            Err(error) => {
                eprintln!("the feature files do not parse: {error}");
                return ExitCode::from(2);
            }
        }
    };
    let failed = scenarios
        .iter()
        .filter(|s| s.outcome.is_err() && !s.error)
        .count();
    let broken = scenarios.iter().filter(|s| s.error).count();
    if !scenarios.is_empty() {
        eprintln!(
            "Gherkin scenarios: {} run, {} failed, {} error",
            scenarios.len(),
            failed,
            broken
        );
    }
    let report = RunReport {
        iut: kind.name(),
        seed: options.seed,
        bus: describe_bus(&options.bus),
        profiles: results,
        scenarios,
        wall_time_ms: started.elapsed().as_millis(),
        interrupted: canif_harness::interrupt::requested(),
    };
    if let Err(error) = report.write(catalogue, report_dir) {
        eprintln!(
            "cannot write the reports to {}: {error}",
            report_dir.display()
        );
        return ExitCode::from(2);
    }
    let totals = report.totals();
    if report.interrupted {
        eprintln!("interrupted: the reports hold what ran before the signal");
    }
    println!(
        "{}: {} pass, {} fail, {} error, {} not applicable, {} not testable — reports in {}",
        report.iut,
        totals.pass,
        totals.fail,
        totals.error,
        totals.not_applicable,
        totals.not_testable,
        report_dir.display()
    );
    ExitCode::from(report.exit_code())
}

pub fn self_check(catalogue: &Catalogue, seed: u64) -> ExitCode {
    let options = Options {
        cases: 2,
        generated_cycles: 150,
        ..Options::quick(seed)
    };
    let rows = canif_harness::suite::kill_matrix(catalogue, &options, |fault| {
        eprintln!("running {fault} on every profile")
    });
    let mut uncaught = 0;
    println!("| fault | caught on | requirements that failed |\n|---|---|---|");
    for row in &rows {
        let caught: Vec<&str> = row
            .caught
            .iter()
            .filter(|(_, ids)| !ids.is_empty())
            .map(|(p, _)| p.as_str())
            .collect();
        let mut ids: Vec<&str> = row
            .caught
            .iter()
            .flat_map(|(_, ids)| ids.iter().map(String::as_str))
            .collect();
        ids.sort();
        ids.dedup();
        if caught.is_empty() {
            uncaught += 1;
        }
        println!(
            "| {} | {}/{} profiles | {} |",
            row.fault.name(),
            caught.len(),
            row.caught.len(),
            if ids.is_empty() {
                "NOT CAUGHT".to_string()
            } else {
                ids.join(", ")
            }
        );
    }
    println!(
        "\n{} of {} faults caught",
        rows.len() - uncaught,
        rows.len()
    );
    ExitCode::from(u8::from(uncaught > 0))
}

/// Every Gherkin scenario against the IUT: once per profile whose capabilities
/// it needs, the manual's tables (`@model`) and `@once` scenarios once.
pub fn run_features(
    kind: &IutKind,
    profiles: &[&canif_spec::Profile],
) -> Result<Vec<ScenarioResult>, String> {
    let mut results = Vec::new();
    for scenario in canif_features::scenarios()? {
        let mut targets = Vec::new();
        if scenario.model_only {
            targets.push((
                "model".to_string(),
                IutKind::Model,
                canif_model::config::Capabilities::everything(),
            ));
        } else if scenario.once {
            // A profile scenario names its device; it runs when that profile is certified.
            let named = profiles
                .iter()
                .find(|p| scenario.profile.as_deref().is_none_or(|n| n == p.name));
            if let Some(profile) = named {
                targets.push((
                    profile.name.clone(),
                    kind.clone(),
                    profile.model_capabilities(),
                ));
            }
        } else {
            for profile in profiles
                .iter()
                .filter(|p| scenario.capabilities.iter().all(|c| p.has(c)))
            {
                targets.push((
                    profile.name.clone(),
                    kind.clone(),
                    profile.model_capabilities(),
                ));
            }
        }
        for (suite, iut, caps) in targets {
            let target = canif_features::Target {
                iut,
                profile: suite.clone(),
                caps,
            };
            let (outcome, error) =
                match canif_features::run_scenario(&scenario.file, scenario.line, target) {
                    canif_features::ScenarioOutcome::Passed => (Ok(()), false),
                    canif_features::ScenarioOutcome::Failed(report) => (Err(report), false),
                    canif_features::ScenarioOutcome::Error(report) => (Err(report), true),
                };
            results.push(ScenarioResult {
                suite,
                name: scenario.name.clone(),
                file: scenario.file.clone(),
                line: scenario.line,
                requirements: scenario.requirements.clone(),
                outcome,
                error,
            });
        }
    }
    results.sort_by(|a, b| (&a.suite, &a.file, a.line).cmp(&(&b.suite, &b.file, b.line)));
    Ok(results)
}

/// The bus as the report names it.
fn describe_bus(bus: &BusChoice) -> String {
    match bus {
        BusChoice::Sim => "simulated bus (virtual time)".into(),
        #[cfg(feature = "socketcan")]
        BusChoice::SocketCan(k) => format!(
            "{} on Linux {}, real time, {} µs cycle, time stamps within {} µs{}",
            k.spec.describe(),
            canif_kernel::kernel_release(),
            k.cycle_time / 1_000,
            k.time_stamp_tolerance / 1_000,
            match (k.remote_frames, k.esi_settable) {
                (true, true) => "",
                (false, true) => ", remote frames sent as data frames",
                (true, false) => ", ESI left to the controllers",
                (false, false) =>
                    ", remote frames sent as data frames, ESI left to the controllers",
            }
        ),
    }
}

/// The bus the command line chose, with its real-time options.
#[cfg_attr(not(feature = "socketcan"), allow(unused_variables))]
pub fn bus_choice(bus: &BusArg, real_time: &RealTimeOptions) -> BusChoice {
    match bus {
        BusArg::Sim => BusChoice::Sim,
        #[cfg(feature = "socketcan")]
        BusArg::SocketCan(spec) => BusChoice::SocketCan(KernelBusOptions {
            spec: spec.clone(),
            cycle_time: real_time.cycle_us * 1_000,
            time_stamp_tolerance: real_time.time_stamp_tolerance_us * 1_000,
            timeout: std::time::Duration::from_millis(real_time.frame_timeout_ms),
            remote_frames: !real_time.no_remote_frames,
            esi_settable: !real_time.esi_from_controller,
        }),
    }
}
