//! `canif run`, `canif list scenarios` and `canif self-check`, for either
//! side. A run is planned (profiles, selection, the Gherkin scenarios),
//! executed (each profile's cases, then the Gherkin scenarios), judged once
//! per requirement × profile, and reported. What differs between the sides
//! is in `device` and `plc`; everything else is here, once.

mod canopen;
pub(crate) mod device;
pub(crate) mod plc;
mod progress;

use std::path::Path;
use std::process::ExitCode;

use crate::cli::{RunArgs, SideArg, Suite};
use crate::stop::{stop, Stop};

use canif_features::{ScenarioInfo, UnderTest};
use canif_harness::report::{Product, ProfileReport, RunMeta, RunReport};
use canif_harness::run::{run_profile, KillRow, ProfileRun, Side};
use canif_harness::verdict::NotRunReason;
use canif_harness::GherkinRun;
use canif_spec::{Catalogue, Profile, ReqId};

pub(crate) use progress::Progress;

/// A run of one side, checked before anything starts.
pub(crate) struct Plan<'c, S> {
    pub profiles: Vec<&'c Profile>,
    pub options: S,
    pub product: Option<Product>,
    /// The Gherkin scenarios of this side these profiles run, read once: (profile, scenario).
    pub gherkin: Vec<(String, ScenarioInfo)>,
}

impl<'c, S: Side> Plan<'c, S> {
    /// The plan, or the exit code of feature files that do not parse (said on stderr).
    pub(crate) fn new(
        profiles: Vec<&'c Profile>,
        options: S,
        product: Option<Product>,
    ) -> Result<Self, Stop> {
        let scenarios = canif_features::scenarios()
            .map_err(|error| stop!("the feature files do not parse: {error}"))?;
        // The feature files are the interface suite's.
        let gherkin = match S::SUITE {
            canif_spec::Suite::Interface => {
                canif_features::schedule::targets(&scenarios, &profiles, S::SIDE)
            }
            canif_spec::Suite::Canopen => Vec::new(),
        };
        Ok(Plan {
            profiles,
            options,
            product,
            gherkin,
        })
    }

    /// Every check the plan could run: (profile, name, requirements exercised).
    pub(crate) fn candidates(&self) -> Vec<(String, String, Vec<String>)> {
        let mut list = Vec::new();
        for profile in &self.profiles {
            for case in self.options.cases(profile) {
                let covers = S::covers(&case).iter().map(ReqId::to_string).collect();
                list.push((profile.name.clone(), S::name(&case), covers));
            }
            for (_, scenario) in self.gherkin.iter().filter(|(p, _)| *p == profile.name) {
                list.push((
                    profile.name.clone(),
                    scenario.id(),
                    scenario.requirements.clone(),
                ));
            }
        }
        list
    }

    /// An unknown requirement or a selection that matches nothing is a usage error.
    pub(crate) fn check_selection(&self, catalogue: &Catalogue) -> Result<(), Stop> {
        let selection = self.options.selection();
        for id in &selection.requirements {
            if catalogue.requirement(id).is_none() {
                let near = super::did_you_mean(id, catalogue.requirements().map(|r| r.id.as_str()));
                return Err(stop!(
                    "--requirement {id}: no such requirement{near}; `canif spec list` lists them"
                ));
            }
        }
        if selection.is_everything()
            || self
                .candidates()
                .iter()
                .any(|(_, name, covers)| selection.admits(name, covers.iter().map(String::as_str)))
        {
            return Ok(());
        }
        // A statement of the other side: say where it is judged, and this side's own.
        for id in &selection.requirements {
            let Some(requirement) = catalogue.requirement(id) else {
                continue;
            };
            if requirement.side != S::SIDE {
                let own: Vec<&str> = requirement
                    .related
                    .iter()
                    .filter(|r| catalogue.requirement(r).is_some_and(|r| r.side == S::SIDE))
                    .map(String::as_str)
                    .collect();
                let own = match own.is_empty() {
                    true => String::new(),
                    false => format!("; this side's own statement: {}", own.join(", ")),
                };
                return Err(stop!(
                    "--requirement {id} binds the {} side, not the {} side: `canif run --side {} --requirement {id}` judges it{own}",
                    requirement.side,
                    S::SIDE,
                    requirement.side,
                ));
            }
        }
        Err(stop!(
            "{} matches no check on {}; `canif list scenarios` lists them",
            selection.flags(),
            self.profiles
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    }

    /// Each profile's cases against what is under test, with a progress line each.
    fn run_profiles(
        &self,
        catalogue: &Catalogue,
        under_test: &S::UnderTest,
        unit: Option<&str>,
    ) -> Vec<ProfileRun> {
        let count = self.profiles.len();
        let mut runs = Vec::new();
        for (n, profile) in self.profiles.iter().enumerate() {
            if canif_harness::interrupt::requested() {
                errln!("interrupted: the remaining profiles are not run");
                break;
            }
            let mut progress = Progress::new(n, count, &profile.name);
            let run = run_profile(profile, under_test, &self.options, |run| {
                progress.scenario(run)
            });
            progress.done(&run, catalogue, profile, unit);
            runs.push(run);
        }
        runs
    }

    /// The selected Gherkin scenarios against what is under test: (profile, run).
    fn run_gherkin(&self, under_test: &UnderTest) -> Vec<(String, GherkinRun)> {
        let mut results = Vec::new();
        let selection = self.options.selection();
        for (profile_name, scenario) in &self.gherkin {
            if !selection.admits(
                &scenario.id(),
                scenario.requirements.iter().map(String::as_str),
            ) {
                continue;
            }
            if canif_harness::interrupt::requested() {
                break;
            }
            let Some(profile) = self.profiles.iter().find(|p| p.name == *profile_name) else {
                continue;
            };
            let run = canif_features::schedule::run(profile, scenario, under_test);
            results.push((profile_name.clone(), run));
        }
        let count = |f: fn(&GherkinRun) -> bool| results.iter().filter(|(_, r)| f(r)).count();
        errln!(
            "Gherkin scenarios: {} run, {} failed, {} error",
            results.len(),
            count(|r| matches!(r.outcome, canif_harness::GherkinOutcome::Fail { .. })),
            count(|r| matches!(r.outcome, canif_harness::GherkinOutcome::Error(_))),
        );
        results
    }

    /// The report: every profile's checks judged once, with what the run left out.
    fn assemble(
        &self,
        catalogue: &Catalogue,
        lockstep: Vec<ProfileRun>,
        gherkin: Vec<(String, GherkinRun)>,
        left_out: Vec<String>,
        meta: RunMeta,
        started: std::time::Instant,
    ) -> RunReport {
        for line in &left_out {
            errln!("left out: {line}");
        }
        let interrupted = canif_harness::interrupt::requested();
        let profiles = lockstep
            .into_iter()
            .zip(&self.profiles)
            .map(|(run, profile)| {
                let mut reach = run.reach.clone();
                reach.here.extend(
                    self.gherkin
                        .iter()
                        .filter(|(p, _)| *p == profile.name)
                        .flat_map(|(_, s)| s.requirements.iter().cloned()),
                );
                if !left_out.is_empty() {
                    reach.left_out = NotRunReason::LeftOut(left_out.join("; "));
                } else if interrupted {
                    reach.left_out = NotRunReason::LeftOut("interrupted".into());
                }
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
                product: self.product.clone(),
                left_out: (!left_out.is_empty()).then(|| left_out.join("; ")),
                ..meta
            },
            profiles,
            wall_time_ms: started.elapsed().as_millis(),
            interrupted,
        }
    }

    /// The selection as the run's first left-out line, when it leaves anything out.
    fn selection_left_out(&self) -> Vec<String> {
        let selection = self.options.selection();
        if selection.is_everything() {
            Vec::new()
        } else {
            vec![selection.describe()]
        }
    }
}
/// `canif run`: either side, or the CANopen suite, with its reports.
pub(crate) fn command(catalogue: &Catalogue, args: RunArgs) -> Result<ExitCode, Stop> {
    let RunArgs {
        iut,
        profile,
        seed,
        product,
        cases,
        duration,
        no_counter_wrap,
        report,
        trace,
        suite,
        bus,
        real_time,
        no_fail_fast,
        scenario,
        requirement,
        trace_epoch,
        node,
        coupler_fault,
        side,
        master,
    } = args;
    let bus = device::bus_choice(&bus, &real_time);
    let pace = device::pace(&real_time);
    let selection = canif_harness::run::Selection {
        scenarios: scenario,
        requirements: requirement,
    };
    let device_only = [
        (suite == Suite::Canopen, "--suite canopen"),
        (cases.is_some(), "--cases"),
        (duration.is_some(), "--duration"),
        (trace.is_some(), "--trace"),
        (no_fail_fast, "--no-fail-fast"),
        (real_time.ethercat_soak_s > 0, "--ethercat-soak-s"),
    ];
    let plc_only = [(!master.is_empty(), "--master")];
    crate::cli::side_conflicts(side, &device_only, &plc_only)?;
    if suite == Suite::Canopen {
        let target = canopen::target(&iut, &bus, node, coupler_fault.as_deref())?;
        let profile = canopen::node_profile(catalogue, &target)?;
        let side = canif_harness::canopen::side::CanopenSide::new(selection);
        let plan = Plan::new(vec![&profile], side, product.product())?;
        return canopen::run(catalogue, &target, &plan, seed, &report);
    }
    let mut profiles = profiles(catalogue, &profile)?;
    // A terminal over EtherCAT can only be one of the terminal profiles:
    // `all` (the default) means all of those.
    let every = profile.is_empty() || profile.iter().any(|p| p == "all");
    if every && matches!(iut.iut, Some(crate::cli::IutArg::Ethercat(_))) {
        profiles.retain(|p| p.ethercat.is_some());
    }
    if side == SideArg::Plc {
        let client_bus = plc::client_bus(&bus)?;
        let kind = crate::commands::resolve_client(&iut)?;
        let masters = plc::masters(&master)?;
        let declared = crate::commands::client_declaration(&iut.declare)?;
        let options = canif_harness::client::suite::ClientOptions {
            seed,
            bus: client_bus,
            counter_wrap: !no_counter_wrap,
            masters,
            selection,
            declared: Ok(declared),
        };
        // What the client declares of itself, asked once.
        let options = options.declared_by(&kind);
        let plan = Plan::new(profiles, options, product.product())?;
        return plc::run(catalogue, &kind, &plan, &report);
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
    let declared = crate::commands::declared_choices(&iut.declare)?;
    let started = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    let options = canif_harness::device::Options {
        seed,
        cases: if duration.is_some() {
            1
        } else {
            cases.unwrap_or(4)
        },
        generated_cycles: duration.map_or(200, |s| (s * 1000.0).max(1.0) as u64),
        counter_wrap: !no_counter_wrap && bus.is_sim(),
        trace_dir: trace,
        trace_epoch: trace_epoch.map_or(started.as_nanos() as u64, |s| {
            s.saturating_mul(1_000_000_000)
        }),
        bus,
        selection,
        fail_fast: !no_fail_fast,
        declared,
        observed: Default::default(),
        iut_declared: Default::default(),
    };
    let plan = Plan::new(profiles, options, product.product())?;
    device::run(catalogue, &iut, &plan, pace, &report)
}

/// `canif list scenarios`: every check a run of these profiles can select.
pub(crate) fn list_scenarios<S: Side>(
    catalogue: &Catalogue,
    names: &[String],
    options: S,
    out: &mut String,
) -> Result<ExitCode, Stop> {
    let profiles = profiles(catalogue, names)?;
    let plan = Plan::new(profiles, options, None)?;
    for (profile, name, covers) in plan.candidates() {
        outln!(out, "{profile}\t{name}\t{}", covers.join(" "));
    }
    Ok(ExitCode::SUCCESS)
}

/// The profiles named on the command line (`all`, or names), or the exit code of a usage error.
pub(crate) fn profiles<'c>(
    catalogue: &'c Catalogue,
    names: &[String],
) -> Result<Vec<&'c Profile>, Stop> {
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
                let near = super::did_you_mean(name, known.iter().copied());
                return Err(stop!(
                    "unknown profile `{name}`{near}; known: {}",
                    known.join(", ")
                ));
            }
        }
    }
    Ok(chosen)
}

/// Writes the reports and says the verdict: each failing requirement in one line.
pub(crate) fn finish(
    catalogue: &Catalogue,
    report: &RunReport,
    report_dir: &Path,
) -> Result<ExitCode, Stop> {
    if let Err(error) = report.write(catalogue, report_dir) {
        return Err(stop!(
            "cannot write the reports to {}: {error}",
            report_dir.display()
        ));
    }
    if report.interrupted {
        errln!("interrupted: the reports hold what ran before the signal");
    }
    let problems = report.problems(catalogue);
    for line in problems.iter().take(40) {
        errln!("{line}");
    }
    if problems.len() > 40 {
        errln!(
            "… and {} more in {}",
            problems.len() - 40,
            report_dir.join("summary.md").display()
        );
    }
    // The first failures whose input image differs, member by member: what
    // to look at first, without opening a report.
    let imaged = report.profiles.iter().flat_map(|p| {
        p.lockstep
            .failures
            .iter()
            .filter_map(move |f| Some((p, f, f.images.as_ref()?)))
    });
    for (p, failure, images) in imaged.take(3) {
        errln!(
            "{} {} at cycle {}: the input image's members that differ:",
            p.profile,
            failure.scenario,
            failure.cycle
        );
        for line in images.lines(6) {
            errln!("  {line}");
        }
    }
    sayln!(
        "{} {}: {} — reports in {}",
        report.meta.iut,
        report.headline(),
        report.totals_line(),
        report_dir.display()
    );
    Ok(ExitCode::from(report.exit_code()))
}

/// `canif self-check`: both kill matrices, every fault of each side on every profile.
pub(crate) fn self_check(catalogue: &Catalogue, seed: u64) -> Result<ExitCode, Stop> {
    let options = canif_harness::device::Options {
        cases: 2,
        generated_cycles: 150,
        ..canif_harness::device::Options::quick(seed)
    };
    let mut devices = canif_harness::run::kill_matrix(catalogue, &options, |fault| {
        errln!("running {fault} on every profile")
    });
    let plan = Plan::new(catalogue.profiles.iter().collect(), options, None)?;
    for row in &mut devices {
        errln!("running {} in the Gherkin scenarios", row.fault.name());
        add_gherkin_failures(&plan, catalogue, row);
    }
    let uncaught = print_kill_table("device fault", &devices, |f| f.name());
    let device_unreached = print_unreached::<canif_harness::device::Options>(
        catalogue,
        devices.iter().flat_map(KillRow::failed),
    );
    let clients = canif_harness::run::kill_matrix(
        catalogue,
        &canif_harness::client::suite::ClientOptions {
            counter_wrap: false,
            ..canif_harness::client::suite::ClientOptions::new(seed)
        },
        |fault| errln!("running client fault {fault} on every profile"),
    );
    sayln!();
    let clients_uncaught = print_kill_table("client fault", &clients, |f| f.name());
    let client_unreached = print_unreached::<canif_harness::client::suite::ClientOptions>(
        catalogue,
        clients.iter().flat_map(KillRow::failed),
    );
    let short = uncaught + clients_uncaught + device_unreached + client_unreached;
    Ok(ExitCode::from(u8::from(short > 0)))
}

/// What the Gherkin scenarios failed with the device fault of `row`, added
/// to what its lockstep scenarios failed: a run blames both, and some
/// statements only a scenario tagged with them isolates (RXQ-001's depth).
fn add_gherkin_failures(
    plan: &Plan<'_, canif_harness::device::Options>,
    catalogue: &Catalogue,
    row: &mut KillRow<canif_softdevice::Fault>,
) {
    let kind = canif_harness::device::IutKind::SoftDevice {
        faults: vec![row.fault],
        choices: vec![],
    };
    let faulty = UnderTest::Device(kind.clone(), kind.declared());
    for (profile_name, run) in plan.run_gherkin(&faulty) {
        let canif_harness::GherkinOutcome::Fail { blamed, .. } = run.outcome else {
            continue;
        };
        let Some(profile) = catalogue.profile(&profile_name) else {
            continue;
        };
        let applies = |id: &String| {
            catalogue
                .requirement(id)
                .is_some_and(|r| profile.lacks(&r.capabilities).is_empty())
        };
        let caught = match row
            .caught
            .iter_mut()
            .find(|(name, _)| *name == profile_name)
        {
            Some((_, ids)) => ids,
            None => {
                row.caught.push((profile_name.clone(), Vec::new()));
                &mut row.caught.last_mut().expect("just pushed").1
            }
        };
        for id in blamed.into_iter().filter(applies) {
            if !caught.contains(&id) {
                caught.push(id);
            }
        }
    }
}

/// The side's requirements no fault failed, listed (issue 36: every
/// requirement is shown able to fail); how many.
fn print_unreached<'a, S: canif_harness::run::SelfCheck>(
    catalogue: &Catalogue,
    failed: impl IntoIterator<Item = &'a str>,
) -> usize {
    let unreached = canif_harness::run::unreached::<S>(catalogue, failed);
    match unreached.as_slice() {
        [] => sayln!("\nevery {} requirement is failed by some fault", S::SIDE),
        ids => sayln!(
            "\n{} {} requirements no fault fails yet: {}",
            ids.len(),
            S::SIDE,
            ids.join(", ")
        ),
    }
    unreached.len()
}

/// One kill matrix as Markdown: each fault, the profiles it was caught on and
/// the requirements that failed. The faults not caught anywhere, counted.
fn print_kill_table<F: Copy>(
    what: &str,
    rows: &[KillRow<F>],
    name: impl Fn(F) -> &'static str,
) -> usize {
    let mut uncaught = 0;
    sayln!("| {what} | caught on | requirements that failed |\n|---|---|---|");
    for row in rows {
        let on = row.caught.iter().filter(|(_, ids)| !ids.is_empty()).count();
        let ids: std::collections::BTreeSet<&str> = row.failed().collect();
        if on == 0 {
            uncaught += 1;
        }
        sayln!(
            "| {} | {on}/{} profiles | {} |",
            name(row.fault),
            row.caught.len(),
            if ids.is_empty() {
                "NOT CAUGHT".to_string()
            } else {
                ids.into_iter().collect::<Vec<_>>().join(", ")
            }
        );
    }
    sayln!(
        "\n{} of {} {what}s caught",
        rows.len() - uncaught,
        rows.len()
    );
    uncaught
}
