//! A run of one side, planned and checked before anything starts, then
//! executed stage by stage: each profile's cases (`--jobs` side by side),
//! the Gherkin scenarios, and the report assembled from both, once.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use canif_features::{ScenarioInfo, UnderTest};
use canif_harness::report::{
    Product, ProfilePart, ProfileReport, RunMeta, RunReport, ShardPart, PART_FORMAT,
};
use canif_harness::run::{run_profile, Cases, ProfileRun};
use canif_harness::verdict::NotRunReason;
use canif_harness::{GherkinOutcome, GherkinRun};
use canif_spec::{Catalogue, Profile, ReqId};

use crate::error::{nearest, PlanError};
use crate::event::{Event, Observer, Position, Stage};
use crate::parallel::in_parallel;
use crate::rerun::Rerun;
use crate::Campaign;

/// The error of a profile's run whose implementation never started (it
/// could not be started, or never answered within the start limit).
fn never_started_in(run: &ProfileRun) -> Option<&canif_harness::IutError> {
    run.runs.iter().find_map(|r| match &r.outcome {
        canif_harness::Outcome::Error(canif_harness::RunError::Iut(error))
            if error.cause == canif_harness::error::IutCause::NotStarted =>
        {
            Some(error)
        }
        _ => None,
    })
}

/// A run of one side, checked before anything starts.
#[derive(Clone)]
pub struct Plan<'c, S> {
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

impl<'c, S: Cases> Plan<'c, S> {
    /// The plan, or why the feature files do not parse.
    pub fn new(
        profiles: Vec<&'c Profile>,
        options: S,
        product: Option<Product>,
    ) -> Result<Self, PlanError> {
        let scenarios = canif_features::scenarios()
            .map_err(|error| PlanError::FeatureFiles(error.to_string()))?;
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
    pub fn candidates(&self) -> Vec<(String, String, Vec<String>)> {
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
    pub fn check_selection(&self, catalogue: &Catalogue) -> Result<(), PlanError> {
        let selection = self.options.selection();
        for id in &selection.requirements {
            if catalogue.requirement(id).is_none() {
                let near = nearest(id, catalogue.requirements().map(|r| r.id.as_str()));
                return Err(PlanError::UnknownRequirement {
                    id: id.clone(),
                    near: near.map(str::to_string),
                });
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
                let own = requirement
                    .related
                    .iter()
                    .filter(|r| catalogue.requirement(r).is_some_and(|r| r.side == S::SIDE))
                    .cloned()
                    .collect();
                return Err(PlanError::OtherSide {
                    id: id.clone(),
                    binds: requirement.side,
                    this: S::SIDE,
                    own,
                });
            }
        }
        Err(PlanError::NothingSelected {
            flags: selection.flags(),
            profiles: self.profiles.iter().map(|p| p.name.clone()).collect(),
        })
    }

    /// How many of a profile's cases the selection takes.
    fn selected_cases(&self, profile: &Profile) -> usize {
        let selection = self.options.selection();
        self.options
            .cases(profile)
            .iter()
            .filter(|case| {
                selection.admits(
                    &profile.name,
                    &S::name(case),
                    S::covers(case).iter().map(ReqId::as_str),
                )
            })
            .count()
    }

    /// What the run left out after its profiles: the selection, and the
    /// profiles not run because what is under test never started (the
    /// error named once).
    pub(crate) fn left_out(&self, runs: &[ProfileRun]) -> Vec<String> {
        let selection = self.options.selection();
        let mut lines = Vec::new();
        if !selection.is_everything() {
            lines.push(selection.describe());
        }
        if let Some(error) = runs.iter().find_map(never_started_in) {
            let not_run = self.profiles.len() - runs.len();
            lines.push(format!(
                "{} never started ({}); {not_run} profile(s) not run",
                S::UNDER_TEST,
                error.what
            ));
        }
        lines
    }

    /// The Gherkin stage, unless a signal came or `skip` says why the side
    /// leaves it out (both said in `left_out`).
    pub(crate) fn gherkin_stage(
        &self,
        skip: Option<&str>,
        under_test: impl FnOnce() -> UnderTest,
        left_out: &mut Vec<String>,
        observer: &dyn Observer,
    ) -> Vec<(String, GherkinRun)> {
        if canif_harness::interrupt::requested() {
            observer.event(Event::Interrupted(Stage::Gherkin));
            left_out.push("interrupted before the Gherkin scenarios".into());
            return Vec::new();
        }
        if let Some(why) = skip {
            left_out.push(format!("Gherkin scenarios not run: {why}"));
            return Vec::new();
        }
        self.run_gherkin(&under_test(), observer)
    }

    /// The selected Gherkin scenarios against what is under test: (profile, run).
    pub fn run_gherkin(
        &self,
        under_test: &UnderTest,
        observer: &dyn Observer,
    ) -> Vec<(String, GherkinRun)> {
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
        observer.event(Event::GherkinFinished {
            ran: results.len(),
            failed: count(|r| matches!(r.outcome, GherkinOutcome::Fail { .. })),
            errors: count(|r| matches!(r.outcome, GherkinOutcome::Error(_))),
        });
        results
    }

    /// The report: every profile's checks judged once, with what the run left out.
    pub(crate) fn assemble(
        &self,
        catalogue: &Catalogue,
        (lockstep, gherkin): (Vec<ProfileRun>, Vec<(String, GherkinRun)>),
        left_out: Vec<String>,
        meta: RunMeta,
        (started, observer): (Instant, &dyn Observer),
    ) -> RunReport {
        for line in &left_out {
            observer.event(Event::LeftOut(line));
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
            observer.event(Event::Flaky(key));
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
}

impl<S: Campaign> Plan<'_, S> {
    /// Each profile's cases against what is under test, on up to
    /// [`Plan::jobs`] threads, one profile each at a time: the profiles are
    /// independent (each case starts a fresh instance of what is under
    /// test), so the runs, returned in the plan's order, are those of a
    /// serial run. A profile a signal kept from starting is not run.
    pub fn run_profiles(
        &self,
        under_test: &S::UnderTest,
        observer: &dyn Observer,
    ) -> Vec<ProfileRun> {
        let count = self.profiles.len();
        let finished = AtomicUsize::new(0);
        let started = Instant::now();
        // What never started on one profile starts on none: the profiles
        // not begun are not run (issue 52), and the report says why.
        let never_started = std::sync::atomic::AtomicBool::new(false);
        // One at a time, each case is told as it ends; beside others, only
        // each profile's end is.
        let serial = self.jobs <= 1 || count <= 1;
        let runs = in_parallel(&self.profiles, self.jobs, |index, profile| {
            if never_started.load(Ordering::SeqCst) {
                return None;
            }
            let at = Position { index, count };
            if serial {
                let cases = self.selected_cases(profile);
                observer.event(Event::ProfileStarted { at, profile, cases });
            }
            let run = run_profile(profile, under_test, &self.options, |run| {
                if serial {
                    observer.event(Event::ScenarioFinished { at, profile, run });
                }
            });
            let done = 1 + finished.fetch_add(1, Ordering::SeqCst);
            observer.event(Event::ProfileFinished {
                at,
                profile,
                run: &run,
                done,
                elapsed: started.elapsed(),
                unit: S::UNIT,
            });
            if never_started_in(&run).is_some() {
                never_started.store(true, Ordering::SeqCst);
            }
            Some(run)
        });
        if canif_harness::interrupt::requested() {
            observer.event(Event::Interrupted(Stage::Profiles));
        }
        runs.into_iter().map_while(Option::flatten).collect()
    }
}
