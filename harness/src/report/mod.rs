//! Reports of a run: JUnit XML for CI (`junit`), JSON for tools (`file`),
//! Markdown and HTML for people (`summary`, `html`). Every one of them is
//! written from the same [`RunReport`], so they cannot disagree.

mod canvas;
mod diagram;
mod file;
mod html;
mod junit;
mod merge;
mod part;
mod summary;
mod task_diagram;

pub use diagram::timing_diagram;
pub use file::{
    CheckEntry, ChoiceEntry, ChoiceSource, FailureEntry, Product, ProfileEntry, ReportFile,
    RunMeta, SuiteKind, TerminalEntry, TotalsEntry, VerdictEntry, REPORT_FORMAT,
};
pub use merge::{merge, MergeError};
pub use part::{ProfilePart, ShardPart, PART_FORMAT};
pub use summary::utc;

use std::collections::BTreeMap;
use std::path::Path;

use canif_spec::{Catalogue, Profile};

use crate::canopen::NodeCheck;
use serde::{Deserialize, Serialize};

use crate::advisory::Advisories;
use crate::outcome::{Failure, GherkinOutcome, GherkinRun};
use crate::run::ProfileRun;
use crate::verdict::{self, Check, CheckResult, Evidence, Finding, Reach, Verdict, VerdictKind};

/// Everything that ran against one profile, and the merged verdicts. It
/// keeps what the reports show, not the runs themselves, so that shards'
/// parts can be joined into one (`merge`).
#[derive(Debug, Clone)]
pub struct ProfileReport {
    pub profile: String,
    /// The checks and what they rest on.
    pub ran: ProfileChecks,
    /// One per requirement: [`verdict::judge`] over every check.
    pub verdicts: BTreeMap<String, Verdict>,
}

/// How much one profile's checks ran: the summary's columns.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tally {
    /// Lockstep scenarios (or, in the CANopen suite, node checks) run.
    pub scenarios: usize,
    pub gherkin_scenarios: usize,
    pub cycles: u64,
    pub frames_checked: u64,
}

impl std::ops::AddAssign for Tally {
    fn add_assign(&mut self, other: Tally) {
        self.scenarios += other.scenarios;
        self.gherkin_scenarios += other.gherkin_scenarios;
        self.cycles += other.cycles;
        self.frames_checked += other.frames_checked;
    }
}

impl ProfileReport {
    pub fn new(
        catalogue: &Catalogue,
        profile: &Profile,
        lockstep: ProfileRun,
        gherkin: Vec<GherkinRun>,
        node_checks: Vec<NodeCheck>,
        reach: &Reach,
    ) -> Self {
        let mut checks = lockstep.checks();
        checks.extend(gherkin.iter().map(gherkin_check));
        checks.extend(node_checks.iter().map(NodeCheck::check));
        let tally = Tally {
            scenarios: lockstep.runs.len(),
            gherkin_scenarios: gherkin.len(),
            cycles: lockstep.cycles(),
            frames_checked: lockstep.frames_checked(),
        };
        Self::judged(
            catalogue,
            profile,
            ProfileChecks {
                tally,
                advisories: lockstep.advisories(),
                failures: lockstep.failures,
                reach: reach.clone(),
                checks,
            },
        )
    }

    /// The verdicts over `ran`, judged once.
    pub fn judged(catalogue: &Catalogue, profile: &Profile, ran: ProfileChecks) -> Self {
        let verdicts = verdict::judge(catalogue, profile, &ran.checks, &ran.reach);
        ProfileReport {
            profile: profile.name.clone(),
            ran,
            verdicts,
        }
    }

    pub fn count(&self, kind: VerdictKind) -> usize {
        self.verdicts.values().filter(|v| v.kind() == kind).count()
    }
}

/// A profile's checks before they are judged (what a shard keeps of its
/// run for `merge`).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct ProfileChecks {
    pub tally: Tally,
    /// What the documents allow but a client's author wants to know (never a verdict).
    pub advisories: Advisories,
    /// The lockstep scenarios' failures, each drawn and listed; a finding's
    /// `failure` indexes this list.
    pub failures: Vec<Failure>,
    /// What the verdicts rest on besides the checks.
    pub reach: Reach,
    /// Every check: the lockstep scenarios, the Gherkin scenarios, the node checks.
    pub checks: Vec<Check>,
}

/// A Gherkin scenario as a check: it covers the scenario's tags, and a
/// failure blames those its failed check witnesses.
fn gherkin_check(run: &GherkinRun) -> Check {
    Check {
        evidence: Evidence::Gherkin(run.id.clone()),
        covers: run.requirements.clone(),
        result: match &run.outcome {
            GherkinOutcome::Pass => CheckResult::Pass,
            GherkinOutcome::Fail {
                step,
                report,
                blamed,
                rest,
            } => CheckResult::Fail(Finding {
                requirements: blamed.clone(),
                cause: step.clone(),
                details: report.clone(),
                failure: None,
                rest: rest.clone(),
            }),
            GherkinOutcome::Error(cause) => CheckResult::Error(cause.clone()),
        },
        elapsed: run.elapsed,
    }
}

/// A requirement that failed or erred on a profile; shown as one line,
/// `FAIL profile::ID: check: cause`, or `FAIL profile::ID (assumption): …`
/// where what broke is a decision of canif's, not a document's statement.
#[derive(Debug, Clone, Copy)]
pub struct Problem<'a> {
    pub profile: &'a str,
    pub id: &'a str,
    pub verdict: &'a Verdict,
    pub assumption: bool,
}

impl std::fmt::Display for Problem<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {}::{}{}: {}",
            self.verdict.label().to_uppercase(),
            self.profile,
            self.id,
            if self.assumption { " (assumption)" } else { "" },
            self.verdict.reason().unwrap_or_default()
        )
    }
}

/// What a whole run produced, and how it was asked for.
#[derive(Debug, Clone)]
pub struct RunReport {
    pub meta: RunMeta,
    pub profiles: Vec<ProfileReport>,
    pub wall_time_ms: u128,
    /// The run was asked to stop (SIGINT, SIGTERM): it reports what ran.
    pub interrupted: bool,
    /// `--rerun-failed`: checks that failed in the run before and pass now,
    /// `profile::check`. Flaky is never a pass.
    pub flaky: Vec<String>,
    /// A shard's run (`--shard K/N`): what it keeps for `canif merge`,
    /// written as `shard.json` beside its reports.
    pub part: Option<Box<ShardPart>>,
}

/// Counts of verdicts over every requirement × profile.
pub type Totals = BTreeMap<VerdictKind, usize>;

impl RunReport {
    pub fn totals(&self) -> Totals {
        let mut totals: Totals = VerdictKind::ALL.iter().map(|k| (*k, 0)).collect();
        for verdict in self.profiles.iter().flat_map(|p| p.verdicts.values()) {
            *totals.entry(verdict.kind()).or_default() += 1;
        }
        totals
    }

    /// What the implementation declares it does not serve, over every
    /// profile: `profile: what — why`.
    pub fn not_served(&self) -> Vec<String> {
        self.profiles
            .iter()
            .flat_map(|p| {
                let served = &p.ran.reach.not_served;
                served
                    .iter()
                    .map(move |(what, why)| format!("{}: {what} — {why}", p.profile))
            })
            .collect()
    }

    /// Checks that ran, over every profile.
    pub fn checks(&self) -> impl Iterator<Item = (&ProfileReport, &Check)> {
        self.profiles
            .iter()
            .flat_map(|p| p.ran.checks.iter().map(move |c| (p, c)))
    }

    /// 130 when interrupted, 1 on any failure (what the implementation did
    /// wrong, whatever else broke) or a flaky check, 2 on an error or when nothing was
    /// checked, 0 when everything that ran passed.
    pub fn exit_code(&self) -> u8 {
        let totals = self.totals();
        if self.interrupted {
            130
        } else if totals[&VerdictKind::Fail] > 0 || !self.flaky.is_empty() {
            1
        } else if totals[&VerdictKind::Error] > 0 || totals[&VerdictKind::Pass] == 0 {
            2
        } else {
            0
        }
    }

    /// The verdict in words: never "conforms" for a run that left something out.
    pub fn headline(&self) -> String {
        let totals = self.totals();
        match self.exit_code() {
            130 => "INTERRUPTED".into(),
            1 if totals[&VerdictKind::Fail] == 0 => format!(
                "FLAKY ({} check(s) failed in the run before and pass now)",
                self.flaky.len()
            ),
            1 => "DOES NOT CONFORM".into(),
            2 if totals[&VerdictKind::Error] > 0 => "ERROR".into(),
            2 => "NOTHING CHECKED".into(),
            _ if self.meta.complete => "CONFORMS".into(),
            _ => format!(
                "PASSES WHAT RAN (partial run: {} not run)",
                totals[&VerdictKind::NotRun]
            ),
        }
    }

    /// The failing and erring requirements, every profile.
    pub fn problems(&self, catalogue: &Catalogue) -> Vec<Problem<'_>> {
        self.profiles
            .iter()
            .flat_map(|p| {
                p.verdicts
                    .iter()
                    .filter(|(_, v)| v.kind().is_bad())
                    .map(|(id, verdict)| Problem {
                        profile: &p.profile,
                        id,
                        verdict,
                        assumption: catalogue
                            .requirement(id)
                            .is_some_and(|r| r.status == canif_spec::Status::Assumption),
                    })
            })
            .collect()
    }

    /// Writes `junit.xml`, `report.json`, `summary.md` and `report.html` into `dir`.
    pub fn write(&self, catalogue: &Catalogue, dir: &Path) -> std::io::Result<()> {
        std::fs::create_dir_all(dir)?;
        std::fs::write(dir.join("junit.xml"), self.junit(catalogue)?)?;
        std::fs::write(
            dir.join("report.json"),
            serde_json::to_string_pretty(&self.json(catalogue)).map_err(std::io::Error::other)?,
        )?;
        std::fs::write(dir.join("summary.md"), self.summary(catalogue))?;
        std::fs::write(dir.join("report.html"), self.html(catalogue))?;
        let part = dir.join("shard.json");
        match &self.part {
            Some(part_of_run) => std::fs::write(
                part,
                serde_json::to_string(part_of_run).map_err(std::io::Error::other)?,
            )?,
            // A shard.json left by an earlier run in this folder is not this run's.
            None => crate::trace::remove_stale(&part)?,
        }
        Ok(())
    }

    /// The run as `report.json` holds it.
    pub fn json(&self, catalogue: &Catalogue) -> ReportFile {
        ReportFile::new(self, catalogue)
    }
}
