//! `canif run` (the interface suite), `canif list scenarios` and `canif
//! self-check`. A run is planned (profiles, selection), executed (lockstep,
//! then Gherkin), judged once per requirement × profile, and reported.

use std::io::{IsTerminal, Write as _};
use std::path::Path;
use std::process::ExitCode;

#[cfg(feature = "socketcan")]
use canif_harness::bus::kernel::KernelBusOptions;
use canif_harness::bus::BusChoice;
use canif_harness::report::{Product, ProfileReport, RunMeta, RunReport};
use canif_harness::suite::{checked_ids, run_profile, scenarios, Options, REFUSALS};
use canif_harness::verdict::Reach;
use canif_harness::{GherkinOutcome, GherkinRun, IutKind, Outcome};
use canif_spec::{Catalogue, Profile};

use super::resolve_iut;
use crate::cli::{BusArg, IutOptions, RealTimeOptions};

/// A run, checked before anything starts.
pub struct Plan<'c> {
    pub profiles: Vec<&'c Profile>,
    pub options: Options,
    pub product: Option<Product>,
    /// The Gherkin scenarios these profiles run, read once: (profile, scenario).
    pub gherkin: Vec<(String, canif_features::ScenarioInfo)>,
}

impl<'c> Plan<'c> {
    /// The plan, or the exit code of feature files that do not parse (said on stderr).
    pub fn new(
        profiles: Vec<&'c Profile>,
        options: Options,
        product: Option<Product>,
    ) -> Result<Self, ExitCode> {
        let gherkin = gherkin_targets(&profiles).map_err(|error| {
            eprintln!("the feature files do not parse: {error}");
            ExitCode::from(2)
        })?;
        Ok(Plan {
            profiles,
            options,
            product,
            gherkin,
        })
    }
}

/// The profiles named on the command line (`all`, or names), or the exit code of a usage error.
pub fn profiles<'c>(
    catalogue: &'c Catalogue,
    names: &[String],
) -> Result<Vec<&'c Profile>, ExitCode> {
    if names.is_empty() || names.iter().any(|n| n == "all") {
        return Ok(catalogue.profiles.iter().collect());
    }
    let mut chosen = Vec::new();
    for name in names {
        match catalogue.profile(name) {
            Some(p) if !chosen.iter().any(|c: &&Profile| c.name == p.name) => chosen.push(p),
            Some(_) => {}
            None => {
                let known: Vec<_> = catalogue.profiles.iter().map(|p| p.name.as_str()).collect();
                eprintln!("unknown profile `{name}`; known: {}", known.join(", "));
                return Err(ExitCode::from(2));
            }
        }
    }
    Ok(chosen)
}

/// Every check a plan could run: (profile, name, requirements exercised).
fn candidates(plan: &Plan) -> Vec<(String, String, Vec<String>)> {
    let mut list = Vec::new();
    for profile in &plan.profiles {
        let caps = profile.model_capabilities();
        list.push((
            profile.name.clone(),
            REFUSALS.to_string(),
            canif_harness::suite::REFUSAL_IDS
                .iter()
                .map(|id| id.to_string())
                .collect(),
        ));
        for scenario in scenarios(&caps, &plan.options) {
            let covers = scenario.covers.iter().map(|id| id.to_string()).collect();
            list.push((profile.name.clone(), scenario.name, covers));
        }
    }
    for (profile, scenario) in &plan.gherkin {
        list.push((
            profile.clone(),
            scenario.id(),
            scenario.requirements.clone(),
        ));
    }
    list
}

/// Checks the selection against the catalogue and the scenarios: an unknown
/// requirement or a selection that matches nothing is a usage error.
pub fn check_selection(catalogue: &Catalogue, plan: &Plan) -> Result<(), ExitCode> {
    let selection = &plan.options.selection;
    for id in &selection.requirements {
        if catalogue.requirement(id).is_none() {
            eprintln!("--requirement {id}: no such requirement; `canif spec list` lists them");
            return Err(ExitCode::from(2));
        }
    }
    if selection.is_everything() {
        return Ok(());
    }
    let matched = candidates(plan)
        .iter()
        .any(|(_, name, covers)| selection.admits(name, covers.iter().map(String::as_str)));
    if matched {
        Ok(())
    } else {
        eprintln!(
            "{} matches no check on {}; `canif list scenarios` lists them",
            selection.flags(),
            plan.profiles
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
        Err(ExitCode::from(2))
    }
}

/// `canif list scenarios`: every check a run of these profiles can run.
pub fn list_scenarios(catalogue: &Catalogue, names: &[String], out: &mut String) -> ExitCode {
    let profiles = match profiles(catalogue, names) {
        Ok(p) => p,
        Err(code) => return code,
    };
    let plan = match Plan::new(profiles, Options::default(), None) {
        Ok(plan) => plan,
        Err(code) => return code,
    };
    for (profile, name, covers) in candidates(&plan) {
        outln!(out, "{profile}\t{name}\t{}", covers.join(" "));
    }
    ExitCode::SUCCESS
}

pub fn run(catalogue: &Catalogue, iut: &IutOptions, plan: &Plan, report_dir: &Path) -> ExitCode {
    let kind = match resolve_iut(iut) {
        Ok(kind) => kind,
        Err(code) => return code,
    };
    if let Err(code) = check_selection(catalogue, plan) {
        return code;
    }
    #[cfg(feature = "socketcan")]
    if let BusChoice::SocketCan(kernel) = &plan.options.bus {
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
    finish(catalogue, &execute(catalogue, &kind, plan), report_dir)
}

/// Writes the reports and says the verdict: each failing requirement in one line.
pub fn finish(catalogue: &Catalogue, report: &RunReport, report_dir: &Path) -> ExitCode {
    if let Err(error) = report.write(catalogue, report_dir) {
        eprintln!(
            "cannot write the reports to {}: {error}",
            report_dir.display()
        );
        return ExitCode::from(2);
    }
    if report.interrupted {
        eprintln!("interrupted: the reports hold what ran before the signal");
    }
    let problems = report.problems();
    for line in problems.iter().take(40) {
        eprintln!("{line}");
    }
    if problems.len() > 40 {
        eprintln!(
            "… and {} more in {}",
            problems.len() - 40,
            report_dir.join("summary.md").display()
        );
    }
    println!(
        "{} {}: {} — reports in {}",
        report.meta.iut,
        report.headline(),
        report.totals_line(),
        report_dir.display()
    );
    ExitCode::from(report.exit_code())
}

/// Runs a plan: the lockstep on each profile, then the Gherkin scenarios, and
/// judges every requirement once over all of them.
pub fn execute(catalogue: &Catalogue, kind: &IutKind, plan: &Plan) -> RunReport {
    let options = &plan.options;
    let started_unix = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let started = std::time::Instant::now();
    let count = plan.profiles.len();
    let mut lockstep = Vec::new();
    for (n, p) in plan.profiles.iter().enumerate() {
        if canif_harness::interrupt::requested() {
            eprintln!("interrupted: the remaining profiles are not run");
            break;
        }
        let mut progress = Progress::new(n, count, &p.name);
        let result = run_profile(catalogue, p, kind, options, |scenario_run| {
            progress.scenario(scenario_run)
        });
        progress.done(&result, "cycles");
        lockstep.push(result);
    }
    let iut_broke = lockstep.iter().flat_map(|p| &p.runs).any(|r| {
        matches!(
            r.outcome,
            Outcome::Error(canif_harness::RunError::Iut(_) | canif_harness::RunError::Skipped(_))
        )
    });
    let mut left_out: Vec<String> = Vec::new();
    if !options.selection.is_everything() {
        left_out.push(options.selection.describe());
    }
    let gherkin = if canif_harness::interrupt::requested() {
        left_out.push("interrupted before the Gherkin scenarios".into());
        Vec::new()
    } else if iut_broke && options.fail_fast {
        left_out.push(
            "Gherkin scenarios not run: the IUT broke (--no-fail-fast runs them anyway)".into(),
        );
        Vec::new()
    } else if !options.bus.is_sim() {
        left_out.push("Gherkin scenarios not run: they use the simulated bus".into());
        Vec::new()
    } else {
        run_features(kind, plan)
    };
    for line in &left_out {
        eprintln!("left out: {line}");
    }
    let interrupted = canif_harness::interrupt::requested();
    let node_ids = canif_harness::canopen::node_check_ids();
    let profiles = lockstep
        .into_iter()
        .zip(&plan.profiles)
        .map(|(run, profile)| {
            let mut here: std::collections::BTreeSet<String> =
                checked_ids(&profile.model_capabilities(), options)
                    .into_iter()
                    .collect();
            here.extend(
                plan.gherkin
                    .iter()
                    .filter(|(p, _)| *p == profile.name)
                    .flat_map(|(_, s)| s.requirements.iter().cloned()),
            );
            let plc_side = catalogue
                .requirements()
                .filter(|r| r.side == canif_spec::Side::Plc)
                .map(|r| {
                    (
                        r.id.clone(),
                        "a PLC-side requirement: exercised by `canif run --side plc`".to_string(),
                    )
                });
            let reach = Reach {
                elsewhere: node_ids
                    .iter()
                    .filter(|id| !here.contains(**id))
                    .map(|id| {
                        (
                            id.to_string(),
                            "exercised by `canif run --suite canopen` against a CANopen node"
                                .into(),
                        )
                    })
                    .chain(plc_side)
                    .collect(),
                here,
                left_out: if left_out.is_empty() && interrupted {
                    "interrupted".into()
                } else {
                    left_out.join("; ")
                },
            };
            let runs: Vec<GherkinRun> = gherkin
                .iter()
                .filter(|(p, _)| *p == profile.name)
                .map(|(_, r)| r.clone())
                .collect();
            ProfileReport::new(catalogue, profile, run, runs, Vec::new(), &reach)
        })
        .collect();
    RunReport {
        meta: RunMeta {
            complete: left_out.is_empty() && !interrupted,
            product: plan.product.clone(),
            left_out: (!left_out.is_empty()).then(|| left_out.join("; ")),
            started_unix,
            ..RunMeta::new(
                kind.name(),
                describe_bus(&options.bus),
                options.seed,
                catalogue,
            )
        },
        profiles,
        wall_time_ms: started.elapsed().as_millis(),
        interrupted,
    }
}

/// What a run says on stderr while it works through the profiles: the
/// scenario running (on a terminal), then one line per profile.
pub struct Progress<'a> {
    n: usize,
    count: usize,
    profile: &'a str,
    done: usize,
    terminal: bool,
}

impl<'a> Progress<'a> {
    pub fn new(n: usize, count: usize, profile: &'a str) -> Self {
        Progress {
            n,
            count,
            profile,
            done: 0,
            terminal: std::io::stderr().is_terminal(),
        }
    }

    pub fn scenario(&mut self, run: &canif_harness::ScenarioRun) {
        self.done += 1;
        if self.terminal {
            eprint!(
                "\r\x1b[2K[{}/{}] {}: {} ({} scenarios)",
                self.n + 1,
                self.count,
                self.profile,
                run.scenario,
                self.done
            );
            let _ = std::io::stderr().flush();
        }
    }

    /// The profile's line; `unit`: what its cycles are (device or task cycles).
    pub fn done(self, result: &canif_harness::ProfileRun, unit: &str) {
        if self.terminal {
            eprint!("\r\x1b[2K");
        }
        let count = |error: bool| {
            result
                .runs
                .iter()
                .filter(|r| match r.outcome {
                    Outcome::Fail(_) => !error,
                    Outcome::Error(_) => error,
                    Outcome::Pass => false,
                })
                .count()
        };
        eprintln!(
            "[{}/{}] {:<22} {} scenarios, {} {unit}, {} frames checked: {}",
            self.n + 1,
            self.count,
            self.profile,
            result.runs.len(),
            result.cycles(),
            result.frames_checked(),
            match (count(false), count(true)) {
                (0, 0) => "all pass".to_string(),
                (f, 0) => format!("{f} FAIL ({})", result.failed_requirements().join(", ")),
                (f, e) => format!("{f} fail, {e} ERROR"),
            }
        );
    }
}

/// Which Gherkin scenario runs on which profile: once per profile whose
/// capabilities it needs, a `@once` scenario on the profile it names. The
/// manual's tables (`@model`) check the model, not an IUT: `cargo test` runs them.
pub fn gherkin_targets(
    profiles: &[&Profile],
) -> Result<Vec<(String, canif_features::ScenarioInfo)>, String> {
    let mut targets = Vec::new();
    for scenario in canif_features::scenarios()? {
        // The manual's tables check the model; `@plc` scenarios a client (`--side plc`).
        if scenario.model_only || scenario.side == canif_spec::Side::Plc {
            continue;
        }
        if scenario.once {
            let named = profiles
                .iter()
                .find(|p| scenario.profile.as_deref().is_none_or(|n| n == p.name));
            if let Some(profile) = named {
                targets.push((profile.name.clone(), scenario.clone()));
            }
        } else {
            for profile in profiles
                .iter()
                .filter(|p| scenario.capabilities.iter().all(|c| p.has(c)))
            {
                targets.push((profile.name.clone(), scenario.clone()));
            }
        }
    }
    Ok(targets)
}

/// The selected Gherkin scenarios against the IUT: (profile, run).
pub fn run_features(kind: &IutKind, plan: &Plan) -> Vec<(String, GherkinRun)> {
    let mut results = Vec::new();
    for (profile_name, scenario) in &plan.gherkin {
        let id = scenario.id();
        if !plan
            .options
            .selection
            .admits(&id, scenario.requirements.iter().map(String::as_str))
        {
            continue;
        }
        if canif_harness::interrupt::requested() {
            break;
        }
        let Some(profile) = plan.profiles.iter().find(|p| p.name == *profile_name) else {
            continue;
        };
        let target = canif_features::Target {
            iut: kind.clone(),
            profile: profile_name.clone(),
            caps: profile.model_capabilities(),
        };
        let started = std::time::Instant::now();
        let outcome = match canif_features::run_scenario(&scenario.file, scenario.line, target) {
            canif_features::ScenarioOutcome::Passed => GherkinOutcome::Pass,
            canif_features::ScenarioOutcome::Failed { report, witness } => GherkinOutcome::Fail {
                step: failing_step(&report),
                blamed: canif_harness::blame::narrow_tags(&scenario.requirements, &witness),
                report,
            },
            canif_features::ScenarioOutcome::Error(report) => GherkinOutcome::Error(report),
        };
        results.push((
            profile_name.clone(),
            GherkinRun {
                id,
                file: scenario.file.clone(),
                line: scenario.line,
                requirements: scenario.requirements.clone(),
                outcome,
                elapsed: started.elapsed(),
            },
        ));
    }
    let failed = results
        .iter()
        .filter(|(_, r)| matches!(r.outcome, GherkinOutcome::Fail { .. }))
        .count();
    let broken = results
        .iter()
        .filter(|(_, r)| matches!(r.outcome, GherkinOutcome::Error(_)))
        .count();
    eprintln!(
        "Gherkin scenarios: {} run, {failed} failed, {broken} error",
        results.len()
    );
    results
}

/// The failing step of cucumber's report and what it said, in one line:
/// `✘ And the bytes after the first 10 are 00: padding is not 00: FF FF`.
pub fn failing_step(report: &str) -> String {
    let mut lines = report.lines().map(str::trim).filter(|l| !l.is_empty());
    let Some(step) = lines.find(|l| l.contains('✘')) else {
        return report
            .lines()
            .next()
            .unwrap_or("the scenario failed")
            .trim()
            .to_string();
    };
    let said = lines
        .take_while(|l| !l.contains('✘') && !l.contains('✔') && !l.starts_with('['))
        .find_map(|l| {
            l.strip_prefix("Step panicked. Captured output:")
                .or_else(|| {
                    (!l.starts_with("Step failed")
                        && !l.starts_with("Defined:")
                        && !l.starts_with("Matched:"))
                    .then_some(l)
                })
        });
    match said {
        Some(said) => format!("{step}: {}", said.trim()),
        None => step.to_string(),
    }
}

pub fn self_check(catalogue: &Catalogue, seed: u64) -> ExitCode {
    let options = Options {
        cases: 2,
        generated_cycles: 150,
        ..Options::quick(seed)
    };
    let devices = canif_harness::suite::kill_matrix(catalogue, &options, |fault| {
        eprintln!("running {fault} on every profile")
    });
    let uncaught = print_kill_table(
        "device fault",
        devices.iter().map(|row| (row.fault.name(), &row.caught)),
    );
    let clients = canif_harness::client::suite::kill_matrix(
        catalogue,
        &canif_harness::client::suite::ClientOptions {
            counter_wrap: false,
            ..canif_harness::client::suite::ClientOptions::new(seed)
        },
        |fault| eprintln!("running client fault {fault} on every profile"),
    );
    println!();
    let clients_uncaught = print_kill_table(
        "client fault",
        clients.iter().map(|row| (row.fault.name(), &row.caught)),
    );
    ExitCode::from(u8::from(uncaught + clients_uncaught > 0))
}

/// One kill matrix as Markdown: each fault, the profiles it was caught on and
/// the requirements that failed. The faults not caught anywhere, counted.
fn print_kill_table<'a>(
    what: &str,
    rows: impl ExactSizeIterator<Item = (&'a str, &'a Vec<(String, Vec<String>)>)>,
) -> usize {
    let (total, mut uncaught) = (rows.len(), 0);
    println!("| {what} | caught on | requirements that failed |\n|---|---|---|");
    for (fault, caught) in rows {
        let on = caught.iter().filter(|(_, ids)| !ids.is_empty()).count();
        let ids: std::collections::BTreeSet<&str> = caught
            .iter()
            .flat_map(|(_, ids)| ids.iter().map(String::as_str))
            .collect();
        if on == 0 {
            uncaught += 1;
        }
        println!(
            "| {fault} | {on}/{} profiles | {} |",
            caught.len(),
            if ids.is_empty() {
                "NOT CAUGHT".to_string()
            } else {
                ids.into_iter().collect::<Vec<_>>().join(", ")
            }
        );
    }
    println!("\n{} of {total} {what}s caught", total - uncaught);
    uncaught
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
