//! Reports of a run: JUnit XML for CI (`junit`), JSON for tools (`file`),
//! Markdown and HTML for people (`summary`, `html`). Every one of them is
//! written from the same [`RunReport`], so they cannot disagree.

mod canvas;
mod diagram;
mod file;
mod html;
mod junit;
mod summary;
mod task_diagram;

pub use diagram::timing_diagram;
pub use file::{
    CheckEntry, ChoiceEntry, ChoiceSource, FailureEntry, Product, ProfileEntry, ReportFile,
    RunMeta, SuiteKind, TerminalEntry, TotalsEntry, VerdictEntry, REPORT_FORMAT,
};
pub use summary::utc;

use std::collections::BTreeMap;
use std::path::Path;

use canif_spec::{Catalogue, Profile};

use crate::canopen::NodeCheck;
use crate::outcome::{GherkinOutcome, GherkinRun};
use crate::run::ProfileRun;
use crate::verdict::{self, Check, CheckResult, Evidence, Finding, Reach, Verdict, VerdictKind};

/// Everything that ran against one profile, and the merged verdicts.
#[derive(Debug, Clone)]
pub struct ProfileReport {
    pub profile: String,
    /// The lockstep scenarios (empty for the CANopen suite).
    pub lockstep: ProfileRun,
    pub gherkin: Vec<GherkinRun>,
    pub node_checks: Vec<NodeCheck>,
    /// Every check above, in that order.
    pub checks: Vec<Check>,
    /// One per requirement: [`verdict::judge`] over every check.
    pub verdicts: BTreeMap<String, Verdict>,
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
        let verdicts = verdict::judge(catalogue, profile, &checks, reach);
        ProfileReport {
            profile: profile.name.clone(),
            lockstep,
            gherkin,
            node_checks,
            checks,
            verdicts,
        }
    }

    pub fn count(&self, kind: VerdictKind) -> usize {
        self.verdicts.values().filter(|v| v.kind() == kind).count()
    }
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
                let served = &p.lockstep.reach.not_served;
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
            .flat_map(|p| p.checks.iter().map(move |c| (p, c)))
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
        Ok(())
    }

    /// The run as `report.json` holds it.
    pub fn json(&self, catalogue: &Catalogue) -> ReportFile {
        ReportFile::new(self, catalogue)
    }
}
