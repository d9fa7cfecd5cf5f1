//! A run of one side, planned and checked before anything starts, then
//! executed stage by stage: each profile's cases (`--jobs` side by side),
//! the Gherkin scenarios, and the report assembled from both.

use canif_features::{ScenarioInfo, UnderTest};
use canif_harness::report::{
    Product, ProfilePart, ProfileReport, RunMeta, RunReport, ShardPart, PART_FORMAT,
};
use canif_harness::run::{run_profile, ProfileRun, Side};
use canif_harness::verdict::NotRunReason;
use canif_harness::GherkinRun;
use canif_spec::{Catalogue, Profile, ReqId};

use super::progress::Progress;
use super::rerun::Rerun;
use crate::stop::{stop, Stop};

/// A run of one side, checked before anything starts.
pub(crate) struct Plan<'c, S> {
    pub profiles: Vec<&'c Profile>,
    pub options: S,
    pub product: Option<Product>,
    /// The Gherkin scenarios of this side these profiles run, read once: (profile, scenario).
    pub gherkin: Vec<(String, ScenarioInfo)>,
    /// Profiles run at once (`--jobs`).
    pub jobs: usize,
    /// `--rerun-failed`: what failed before, to tell flaky checks.
    pub rerun: Option<Rerun>,
    /// What the command line asked, as every shard of one campaign must ask it.
    pub campaign: Vec<String>,
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
            jobs: 1,
            rerun: None,
            campaign: Vec::new(),
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
                let near = crate::commands::did_you_mean(
                    id,
                    catalogue.requirements().map(|r| r.id.as_str()),
                );
                return Err(stop!(
                    "--requirement {id}: no such requirement{near}; `canif spec list` lists them"
                ));
            }
        }
        if selection.is_everything()
            || self.candidates().iter().any(|(profile, name, covers)| {
                selection.admits(profile, name, covers.iter().map(String::as_str))
            })
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
    pub(super) fn run_profiles(
        &self,
        catalogue: &Catalogue,
        under_test: &S::UnderTest,
        unit: Option<&str>,
    ) -> Vec<ProfileRun> {
        let count = self.profiles.len();
        let started = std::time::Instant::now();
        let mut runs = Vec::new();
        for (n, profile) in self.profiles.iter().enumerate() {
            if canif_harness::interrupt::requested() {
                errln!("interrupted: the remaining profiles are not run");
                break;
            }
            // How many of its cases the selection takes, for the terminal's pace.
            let selection = self.options.selection();
            let cases = self
                .options
                .cases(profile)
                .iter()
                .filter(|case| {
                    selection.admits(
                        &profile.name,
                        &S::name(case),
                        S::covers(case).iter().map(ReqId::as_str),
                    )
                })
                .count();
            let mut progress = Progress::new(n, count, &profile.name).of_cases(cases);
            let run = run_profile(profile, under_test, &self.options, |run| {
                progress.scenario(run)
            });
            progress.done_after(&run, (catalogue, profile, unit), (n + 1, started.elapsed()));
            runs.push(run);
        }
        runs
    }

    /// [`Plan::run_profiles`] on `jobs` threads, one profile each at a time:
    /// the profiles are independent (each case starts a fresh instance of
    /// what is under test), so the runs, returned in the plan's order, are
    /// those of a serial run.
    pub(super) fn run_profiles_on(
        &self,
        catalogue: &Catalogue,
        under_test: &S::UnderTest,
        unit: Option<&str>,
        jobs: usize,
    ) -> Vec<ProfileRun>
    where
        S: Sync,
        S::UnderTest: Sync,
    {
        if jobs <= 1 || self.profiles.len() <= 1 {
            return self.run_profiles(catalogue, under_test, unit);
        }
        let count = self.profiles.len();
        let finished = std::sync::atomic::AtomicUsize::new(0);
        let started = std::time::Instant::now();
        let runs = in_parallel(&self.profiles, jobs, |n, profile| {
            let run = run_profile(profile, under_test, &self.options, |_| {});
            let done = 1 + finished.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            Progress::new(n, count, &profile.name).done_after(
                &run,
                (catalogue, profile, unit),
                (done, started.elapsed()),
            );
            run
        });
        if canif_harness::interrupt::requested() {
            errln!("interrupted: the remaining profiles are not run");
        }
        // In the plan's order; a profile an interrupt kept from starting is
        // not run, as in a serial run.
        runs.into_iter().map_while(|run| run).collect()
    }

    /// The selected Gherkin scenarios against what is under test: (profile, run).
    pub(super) fn run_gherkin(&self, under_test: &UnderTest) -> Vec<(String, GherkinRun)> {
        let selection = self.options.selection();
        let chosen: Vec<(&Profile, &ScenarioInfo)> = self
            .gherkin
            .iter()
            .filter(|(profile, scenario)| {
                selection.admits(
                    profile,
                    &scenario.id(),
                    scenario.requirements.iter().map(String::as_str),
                )
            })
            .filter_map(|(name, scenario)| {
                let profile = self.profiles.iter().find(|p| p.name == *name)?;
                Some((*profile, scenario))
            })
            .collect();
        // Each scenario's world is its thread's own: `--jobs` runs them side
        // by side, and they are reported in the plan's order.
        let results: Vec<(String, GherkinRun)> =
            in_parallel(&chosen, self.jobs, |_, (profile, scenario)| {
                let run = canif_features::schedule::run(profile, scenario, under_test);
                (profile.name.clone(), run)
            })
            .into_iter()
            .map_while(|run| run)
            .collect();
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
    pub(super) fn assemble(
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
                if let Some(why) = NotRunReason::of_run(&left_out, interrupted) {
                    reach.left_out = why;
                }
                let runs: Vec<GherkinRun> = gherkin
                    .iter()
                    .filter(|(p, _)| *p == profile.name)
                    .map(|(_, r)| r.clone())
                    .collect();
                ProfileReport::new(catalogue, profile, run, runs, Vec::new(), &reach)
            })
            .collect::<Vec<_>>();
        let flaky = self
            .rerun
            .as_ref()
            .map_or_else(Vec::new, |rerun| rerun.flaky(&profiles));
        for key in &flaky {
            errln!("FLAKY {key}: it failed in the run before and passes now");
        }
        let meta = RunMeta {
            product: self.product.clone(),
            shard: self.options.selection().shard,
            ..meta
        }
        .left_out(&left_out, interrupted);
        let wall_time_ms = started.elapsed().as_millis();
        let part = self.options.selection().shard.map(|shard| {
            let candidates = self.candidates();
            Box::new(ShardPart {
                format: PART_FORMAT,
                shard,
                meta: meta.clone(),
                selection: self.options.selection().clone(),
                command: self.campaign.clone(),
                left_out,
                interrupted,
                flaky: flaky.clone(),
                wall_time_ms: wall_time_ms as u64,
                profiles: profiles
                    .iter()
                    .map(|p| Self::part_of(&candidates, p))
                    .collect(),
            })
        });
        RunReport {
            meta,
            profiles,
            wall_time_ms,
            interrupted,
            flaky,
            part,
        }
    }

    /// A profile's checks as a shard keeps them, each placed among the plan's cases.
    fn part_of(
        candidates: &[(String, String, Vec<String>)],
        report: &ProfileReport,
    ) -> ProfilePart {
        let plan: Vec<String> = candidates
            .iter()
            .filter(|(profile, _, _)| *profile == report.profile)
            .map(|(_, name, _)| name.clone())
            .collect();
        ProfilePart::new(&report.profile, report.ran.clone(), &plan)
    }

    /// The selection as the run's first left-out line, when it leaves anything out.
    pub(super) fn selection_left_out(&self) -> Vec<String> {
        let selection = self.options.selection();
        if selection.is_everything() {
            Vec::new()
        } else {
            vec![selection.describe()]
        }
    }
}
/// `work` on each item, on up to `jobs` threads, in the items' order: `None`
/// for an item a SIGINT kept from starting.
pub(super) fn in_parallel<T: Sync, R: Send>(
    items: &[T],
    jobs: usize,
    work: impl Fn(usize, &T) -> R + Sync,
) -> Vec<Option<R>> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;
    if jobs <= 1 {
        let mut results = Vec::new();
        for (n, item) in items.iter().enumerate() {
            if canif_harness::interrupt::requested() {
                break;
            }
            results.push(Some(work(n, item)));
        }
        return results;
    }
    let next = AtomicUsize::new(0);
    let results: Vec<Mutex<Option<R>>> = items.iter().map(|_| Mutex::new(None)).collect();
    let worker = || loop {
        let n = next.fetch_add(1, Ordering::SeqCst);
        let Some(item) = items.get(n) else { break };
        if canif_harness::interrupt::requested() {
            break;
        }
        let result = work(n, item);
        *results[n].lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
    };
    std::thread::scope(|scope| {
        let mut spawned = 0;
        for _ in 0..jobs.min(items.len()) {
            // A Gherkin world and the model's state machines want the
            // stack a main thread has, not a spawned thread's 2 MiB.
            let thread = std::thread::Builder::new()
                .stack_size(16 << 20)
                .spawn_scoped(scope, worker);
            spawned += usize::from(thread.is_ok());
        }
        if spawned == 0 {
            // No thread to be had: the work is done here, one at a time.
            worker();
        }
    });
    results
        .into_iter()
        .map(|slot| slot.into_inner().unwrap_or_else(|e| e.into_inner()))
        .collect()
}
