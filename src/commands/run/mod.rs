//! `canif run device|plc|canopen`, `canif list scenarios` and `canif
//! self-check`. Each side's arguments become a [`Plan`] once (its module);
//! the run itself is the library's ([`canif_runner`]); what is said while it
//! runs is [`progress`]'s, and the verdict's lines are [`finish`]'s.

mod canopen;
pub(crate) mod device;
pub(crate) mod plc;
mod progress;
mod self_check;

use std::path::Path;
use std::process::ExitCode;

use crate::cli::{CampaignArgs, RunCommand, RunCommon, RunTarget};
use crate::stop::{stop, Stop};

use canif_harness::report::RunReport;
use canif_harness::run::{Cases, Selection};
use canif_runner::{Campaign, Plan, Rerun};
use canif_spec::{Catalogue, Profile};

pub(crate) use progress::Progress;
pub(crate) use self_check::self_check;

/// `canif run`: either side, or the CANopen suite, with its reports.
pub(crate) fn command(catalogue: &Catalogue, args: RunCommand) -> Result<ExitCode, Stop> {
    match args.target() {
        RunTarget::Device(args) => device::command(catalogue, args),
        RunTarget::Plc(args) => plc::command(catalogue, args),
        RunTarget::Canopen(args) => canopen::command(catalogue, args),
    }
}

/// A plan's run, said as it goes, and its reports written.
fn run_and_finish<S: Campaign>(
    catalogue: &Catalogue,
    plan: &Plan<'_, S>,
    under_test: &S::UnderTest,
    report_dir: &Path,
) -> Result<ExitCode, Stop> {
    let report = plan.run(catalogue, under_test, &Progress::new(catalogue))?;
    finish(catalogue, &report, report_dir)
}

/// What a run of profiles selects: the command line's selection and
/// profiles, or with `--rerun-failed` what failed in that report. `None`
/// when a rerun finds nothing to run (said on stdout).
struct Selected {
    selection: Selection,
    profiles: Vec<String>,
    rerun: Option<Rerun>,
}

fn selected(
    common: &RunCommon,
    campaign: &CampaignArgs,
    side: canif_spec::Side,
) -> Result<Option<Selected>, Stop> {
    let rerun = match &campaign.rerun_failed {
        Some(path) => Some(Rerun::read(path, side).map_err(canif_runner::PlanError::from)?),
        None => None,
    };
    let (scenarios, profiles) = match &rerun {
        Some(rerun) if rerun.failed.is_empty() => {
            sayln!(
                "--rerun-failed: nothing failed or erred in {}; nothing to rerun",
                rerun.report.display()
            );
            return Ok(None);
        }
        Some(rerun) => (rerun.scenarios(), rerun.profiles()),
        None => (common.scenario.clone(), campaign.profile.clone()),
    };
    Ok(Some(Selected {
        selection: Selection {
            scenarios,
            requirements: common.requirement.clone(),
            shard: campaign.shard,
        },
        profiles,
        rerun,
    }))
}

/// The plan of a run over profiles, with the campaign's settings.
fn campaign_plan<'c, S: Cases>(
    profiles: Vec<&'c Profile>,
    options: S,
    common: &RunCommon,
    campaign: &CampaignArgs,
    rerun: Option<Rerun>,
) -> Result<Plan<'c, S>, Stop> {
    let mut plan = Plan::new(profiles, options, common.product.product())?;
    plan.jobs = usize::from(campaign.jobs);
    plan.rerun = rerun;
    plan.campaign = campaign_args(std::env::args().skip(1));
    Ok(plan)
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
pub(crate) fn list_scenarios<S: Cases>(
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
