//! One profile's run of either side: the side names its cases and runs one;
//! selection, fail-fast, interrupts and progress are the same for both, and
//! written here once.

use std::collections::BTreeMap;
use std::time::Instant;

use canif_spec::{Catalogue, Profile, ReqId};

use super::Selection;
use crate::declare::ChoiceEntry;
use crate::error::{Broke, RunError};
use crate::outcome::{Failure, Outcome, ScenarioRun};
use crate::verdict::{self, Check, CheckResult, Evidence, Finding, Reach, Verdict, VerdictKind};

/// A side of the interface under test: what its cases are and how one runs.
/// The other side is played by the harness inside [`Cases::run`].
pub trait Cases {
    /// What is under test: a device's IUT kind, a client's kind.
    type UnderTest;
    /// One case of a profile's run.
    type Case;
    /// How a skip names what broke: "the IUT", "the client".
    const UNDER_TEST: &'static str;
    /// Which side of the interface this is (the catalogue's and the feature files' word).
    const SIDE: canif_spec::Side;
    /// Which suite: the CAN interface's (with its Gherkin scenarios), or the
    /// CANopen node checks'.
    const SUITE: canif_spec::Suite = canif_spec::Suite::Interface;
    /// What a profile's run learns of what is under test as its cases run
    /// (what an undeclared device chose, what it declared itself), handed
    /// from each case to the next and returned with the [`ProfileRun`].
    type Learned: Default;

    /// Every case a profile's run has, in the order they run.
    fn cases(&self, profile: &Profile) -> Vec<Self::Case>;
    /// The name a case is selected, reported and compared by.
    fn name(case: &Self::Case) -> String;
    /// The requirements a case exercises.
    fn covers(case: &Self::Case) -> &[ReqId];
    /// Runs one case against a fresh instance of what is under test, with
    /// what the profile's cases before it learned.
    fn run(
        &self,
        under_test: &Self::UnderTest,
        profile: &Profile,
        case: Self::Case,
        learned: &mut Self::Learned,
    ) -> ScenarioRun;
    /// The choices a profile's run learned, as its report lists them.
    fn choices(learned: Self::Learned) -> Vec<ChoiceEntry>;
    fn selection(&self) -> &Selection;
    /// After what is under test broke, skip the profile's remaining cases
    /// instead of starting it again and again.
    fn fail_fast(&self) -> bool;
    /// What a profile's run could judge, given the runs it made.
    fn reach(&self, profile: &Profile, runs: &[ScenarioRun]) -> Reach;
}

/// Everything one profile's run produced, and what it could have reached.
#[derive(Debug, Clone)]
pub struct ProfileRun {
    pub profile: String,
    pub runs: Vec<ScenarioRun>,
    pub failures: Vec<Failure>,
    /// What the verdicts over these runs rest on besides the runs.
    pub reach: Reach,
    /// The choices the run learned of what is under test (what it declared
    /// itself, what an undeclared device showed).
    pub choices: Vec<ChoiceEntry>,
}

impl ProfileRun {
    pub fn new(profile: &str, runs: Vec<ScenarioRun>, reach: Reach) -> Self {
        // Each breach a failure of its own (drawn and listed), in run order.
        let failures = runs
            .iter()
            .filter_map(|run| match &run.outcome {
                Outcome::Fail(failure) => Some(failure.breaches()),
                _ => None,
            })
            .flatten()
            .collect();
        ProfileRun {
            profile: profile.to_string(),
            runs,
            failures,
            reach,
            choices: Vec::new(),
        }
    }

    /// Every requirement's verdict over these runs alone (a report merges
    /// the Gherkin scenarios' in through the same [`verdict::judge`]).
    pub fn verdicts(&self, catalogue: &Catalogue, profile: &Profile) -> BTreeMap<String, Verdict> {
        verdict::judge(catalogue, profile, &self.checks(), &self.reach)
    }

    /// The requirements that failed on this profile.
    pub fn failed_requirements(&self, catalogue: &Catalogue, profile: &Profile) -> Vec<String> {
        self.verdicts(catalogue, profile)
            .into_iter()
            .filter(|(_, v)| v.kind() == VerdictKind::Fail)
            .map(|(id, _)| id)
            .collect()
    }

    /// The scenario runs as checks for [`verdict::judge`]: a run that broke
    /// several requirements one after the other is one check per breach, the
    /// later ones covering only what they blame.
    pub fn checks(&self) -> Vec<Check> {
        let mut failures = 0;
        let mut checks = Vec::new();
        for run in &self.runs {
            let check = |covers: Vec<String>, result| Check {
                evidence: Evidence::Scenario(run.scenario.clone()),
                covers,
                result,
                elapsed: run.elapsed,
            };
            let covers: Vec<String> = run.covers.iter().map(|id| id.to_string()).collect();
            match &run.outcome {
                Outcome::Pass => checks.push(check(covers, CheckResult::Pass)),
                Outcome::Error(error) => {
                    checks.push(check(covers, CheckResult::Error(error.to_string())))
                }
                Outcome::Fail(failure) => {
                    for (n, breach) in failure.breaches().into_iter().enumerate() {
                        let finding = Finding {
                            requirements: breach
                                .requirements
                                .iter()
                                .map(|id| id.to_string())
                                .collect(),
                            cause: breach.cause(),
                            details: breach.details(),
                            failure: Some(failures),
                            rest: breach.rest.clone(),
                        };
                        failures += 1;
                        let covers = match n {
                            0 => covers.clone(),
                            _ => finding.requirements.clone(),
                        };
                        checks.push(check(covers, CheckResult::Fail(finding)));
                    }
                }
            }
        }
        checks
    }

    /// The advisories of every run together.
    pub fn advisories(&self) -> crate::advisory::Advisories {
        let mut total = crate::advisory::Advisories::default();
        for run in &self.runs {
            total.add(&run.advisories);
        }
        total
    }

    pub fn frames_checked(&self) -> u64 {
        self.runs.iter().map(|r| r.frames_checked).sum()
    }

    pub fn cycles(&self) -> u64 {
        self.runs.iter().map(|r| r.cycles).sum()
    }
}

/// Every requirement `cases` exercise, each once, in order: what a run of
/// them can call pass or fail, whatever the selection (either side).
pub fn checked_ids<S: Cases>(cases: &[S::Case]) -> Vec<String> {
    let mut ids: Vec<String> = cases
        .iter()
        .flat_map(|case| S::covers(case))
        .map(ReqId::to_string)
        .collect();
    ids.sort();
    ids.dedup();
    ids
}

/// Runs every selected case of a profile, in order, and says each to `progress`.
pub fn run_profile<S: Cases>(
    profile: &Profile,
    under_test: &S::UnderTest,
    side: &S,
    mut progress: impl FnMut(&ScenarioRun),
) -> ProfileRun {
    let mut runs = Vec::new();
    let mut broken: Option<Broke> = None;
    let mut learned = S::Learned::default();
    for case in side.cases(profile) {
        let name = S::name(&case);
        if !side.selection().admits(
            &profile.name,
            &name,
            S::covers(&case).iter().map(ReqId::as_str),
        ) {
            continue;
        }
        if crate::interrupt::requested() {
            break;
        }
        let run = match &broken {
            Some(after) => ScenarioRun::ended(
                name,
                S::covers(&case).to_vec(),
                Outcome::Error(RunError::Skipped(Box::new(after.clone()))),
            ),
            None => {
                let started = Instant::now();
                let mut run = side.run(under_test, profile, case, &mut learned);
                run.elapsed = started.elapsed();
                run
            }
        };
        if side.fail_fast() && broken.is_none() {
            broken = broke_in::<S>(&run);
        }
        progress(&run);
        runs.push(run);
    }
    let reach = side.reach(profile, &runs);
    ProfileRun {
        choices: S::choices(learned),
        ..ProfileRun::new(&profile.name, runs, reach)
    }
}

/// Where and how what is under test broke in `run`, if it did: what the
/// profile's later cases are skipped after.
fn broke_in<S: Cases>(run: &ScenarioRun) -> Option<Broke> {
    match &run.outcome {
        Outcome::Error(RunError::Iut(error)) => Some(Broke {
            under_test: S::UNDER_TEST,
            scenario: run.scenario.clone(),
            error: error.clone(),
        }),
        _ => None,
    }
}
