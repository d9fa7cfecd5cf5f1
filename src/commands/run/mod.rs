//! `canif run`, `canif list scenarios` and `canif self-check`, for either
//! side. A run is planned (profiles, selection, the Gherkin scenarios),
//! executed (each profile's cases, then the Gherkin scenarios), judged once
//! per requirement × profile, and reported. What differs between the sides
//! is in `device` and `plc`; everything else is here, once.

mod canopen;
pub(crate) mod device;
mod plan;
pub(crate) mod plc;
mod progress;
mod rerun;
mod self_check;

use std::path::Path;
use std::process::ExitCode;

use crate::cli::{RunArgs, SideArg, Suite};
use crate::stop::{stop, Stop};

use canif_harness::report::RunReport;
use canif_harness::run::Side;
use canif_spec::{Catalogue, Profile};

pub(crate) use plan::Plan;
pub(crate) use self_check::self_check;

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
        jobs,
        rerun_failed,
        shard,
    } = args;
    let jobs = usize::from(jobs);
    // What every shard of a campaign must have asked alike, read once.
    let campaign = campaign_args(std::env::args().skip(1));
    let bus = device::bus_choice(&bus, &real_time);
    let pace = device::pace(&real_time);
    let rerun = match &rerun_failed {
        Some(path) => {
            let role = match side {
                SideArg::Device => canif_spec::Side::Device,
                SideArg::Plc => canif_spec::Side::Plc,
            };
            Some(rerun::Rerun::read(path, role)?)
        }
        None => None,
    };
    let (scenario, profile) = match &rerun {
        Some(rerun) if rerun.failed.is_empty() => {
            sayln!(
                "--rerun-failed: nothing failed or erred in {}; nothing to rerun",
                rerun.report.display()
            );
            return Ok(ExitCode::SUCCESS);
        }
        Some(rerun) => (rerun.scenarios(), rerun.profiles()),
        None => (scenario, profile),
    };
    let selection = canif_harness::run::Selection {
        scenarios: scenario,
        requirements: requirement,
        shard,
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
    if jobs > 1 {
        let shared = match &iut.iut {
            Some(crate::cli::IutArg::Ethercat(_)) => Some("an EtherCAT terminal: one link"),
            Some(crate::cli::IutArg::Lib(_)) if iut.lib_in_process => {
                Some("--lib-in-process: one library in canif's process")
            }
            _ if bus != canif_harness::device::bus::BusChoice::Sim => {
                Some("a SocketCAN bus: one interface")
            }
            _ if suite == Suite::Canopen => Some("the CANopen suite: one node"),
            _ => None,
        };
        if let Some(why) = shared {
            return Err(stop!(
                "--jobs {jobs}: the profiles would share {why}; run them one at a time"
            ));
        }
    }
    if suite == Suite::Canopen && selection.shard.is_some() {
        return Err(stop!(
            "--shard: the CANopen suite checks one node, whose profile is made for the run; run it whole"
        ));
    }
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
        if let Some(rerun) = &rerun {
            rerun.same_iut(&kind.name())?;
        }
        let mut plan = Plan::new(profiles, options, product.product())?;
        plan.jobs = jobs;
        plan.rerun = rerun;
        plan.campaign = campaign;
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
    let mut plan = Plan::new(profiles, options, product.product())?;
    plan.jobs = jobs;
    plan.rerun = rerun;
    plan.campaign = campaign;
    device::run(catalogue, &iut, &plan, pace, &report)
}

/// The run's arguments as a campaign's shards must share them: without
/// what may differ between shards (`--shard`, where the reports and traces
/// go, `--jobs`), and in sorted order, so that the order flags were written
/// in does not matter.
fn campaign_args(args: impl Iterator<Item = String>) -> Vec<String> {
    const PER_SHARD: [&str; 5] = ["--shard", "--report", "--jobs", "--trace", "--trace-epoch"];
    let mut kept = Vec::new();
    let mut skip_value = false;
    for arg in args {
        if std::mem::take(&mut skip_value) {
            continue;
        }
        let flag = arg.split('=').next().unwrap_or_default();
        if PER_SHARD.contains(&flag) {
            skip_value = !arg.contains('=');
            continue;
        }
        kept.push(arg);
    }
    kept.sort();
    kept
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
        p.ran
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
    if let Some(shard) = report.meta.shard {
        sayln!(
            "shard {shard}: `canif merge` joins {} with the other shards' folders into one verdict",
            report_dir.display()
        );
    }
    Ok(ExitCode::from(report.exit_code()))
}
