//! `report.json` as types, written and read through one definition: `canif
//! run` writes it, `canif compare` reads it back. Fields are in alphabetical
//! order, the order the file has always had.

use std::collections::BTreeMap;

use canif_spec::Catalogue;
use serde::{Deserialize, Serialize};

use super::{RunReport, Totals};
use crate::outcome::{Failure, Outcome};
use crate::suite::Verdict;

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReportFile {
    #[serde(default)]
    pub bus: String,
    #[serde(default)]
    pub harness_version: String,
    /// Present only when the run was asked to stop before it ended.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub interrupted: bool,
    #[serde(default)]
    pub iut: String,
    pub profiles: Vec<ProfileEntry>,
    #[serde(default)]
    pub scenarios: Vec<ScenarioEntry>,
    #[serde(default)]
    pub seed: u64,
    #[serde(default)]
    pub totals: TotalsEntry,
    #[serde(default)]
    pub wall_time_ms: u64,
}

/// Counts of verdicts over every requirement × profile.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TotalsEntry {
    pub error: usize,
    pub fail: usize,
    pub not_applicable: usize,
    pub not_testable: usize,
    pub pass: usize,
}

/// One profile's run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProfileEntry {
    #[serde(default)]
    pub cycles: u64,
    #[serde(default)]
    pub failures: Vec<FailureEntry>,
    #[serde(default)]
    pub frames_checked: u64,
    pub profile: String,
    #[serde(default)]
    pub scenarios: Vec<RunEntry>,
    pub verdicts: BTreeMap<String, VerdictEntry>,
}

/// One requirement's verdict on a profile.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct VerdictEntry {
    /// Indexes into the profile's failures.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failures: Option<Vec<usize>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    pub verdict: VerdictKind,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum VerdictKind {
    #[serde(rename = "pass")]
    Pass,
    #[serde(rename = "fail")]
    Fail,
    #[serde(rename = "error")]
    Error,
    #[serde(rename = "not applicable")]
    NotApplicable,
    #[serde(rename = "not testable")]
    NotTestable,
}

impl VerdictKind {
    pub fn label(self) -> &'static str {
        match self {
            VerdictKind::Pass => "pass",
            VerdictKind::Fail => "fail",
            VerdictKind::Error => "error",
            VerdictKind::NotApplicable => "not applicable",
            VerdictKind::NotTestable => "not testable",
        }
    }

    /// A verdict that stops a gate.
    pub fn is_bad(self) -> bool {
        matches!(self, VerdictKind::Fail | VerdictKind::Error)
    }
}

/// One scenario of the lockstep.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunEntry {
    pub cycles: u64,
    pub frames_checked: u64,
    /// `pass`, `fail` or `error: …`.
    pub outcome: String,
    pub scenario: String,
}

/// One failure, as text.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FailureEntry {
    pub actual: String,
    pub context: Vec<String>,
    pub cycle: u64,
    pub expected: String,
    pub requirements: Vec<String>,
    pub scenario: String,
    pub time_ns: u64,
    pub what: String,
}

/// One Gherkin scenario (or Examples row) against one profile.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ScenarioEntry {
    pub file: String,
    pub line: usize,
    pub name: String,
    pub outcome: VerdictKind,
    /// cucumber's report of the failing step.
    pub report: Option<String>,
    pub requirements: Vec<String>,
    pub suite: String,
}

impl From<&Verdict> for VerdictEntry {
    fn from(verdict: &Verdict) -> Self {
        let (verdict, failures, reason) = match verdict {
            Verdict::Pass => (VerdictKind::Pass, None, None),
            Verdict::Fail(indexes) => (VerdictKind::Fail, Some(indexes.clone()), None),
            Verdict::Error(message) => (VerdictKind::Error, None, Some(message.clone())),
            Verdict::NotApplicable(reason) => {
                (VerdictKind::NotApplicable, None, Some(reason.clone()))
            }
            Verdict::NotTestable(reason) => (VerdictKind::NotTestable, None, Some(reason.clone())),
        };
        VerdictEntry {
            failures,
            reason,
            verdict,
        }
    }
}

impl From<&Failure> for FailureEntry {
    fn from(failure: &Failure) -> Self {
        FailureEntry {
            actual: failure.actual.clone(),
            context: failure.context.clone(),
            cycle: failure.cycle,
            expected: failure.expected.clone(),
            requirements: failure
                .requirements
                .iter()
                .map(|id| id.to_string())
                .collect(),
            scenario: failure.scenario.clone(),
            time_ns: failure.time,
            what: failure.what.clone(),
        }
    }
}

impl From<Totals> for TotalsEntry {
    fn from(t: Totals) -> Self {
        TotalsEntry {
            error: t.error,
            fail: t.fail,
            not_applicable: t.not_applicable,
            not_testable: t.not_testable,
            pass: t.pass,
        }
    }
}

impl ReportFile {
    pub fn new(report: &RunReport, catalogue: &Catalogue) -> Self {
        ReportFile {
            bus: report.bus.clone(),
            harness_version: env!("CARGO_PKG_VERSION").into(),
            interrupted: report.interrupted,
            iut: report.iut.clone(),
            profiles: report
                .profiles
                .iter()
                .map(|p| ProfileEntry {
                    cycles: p.cycles(),
                    failures: p.failures.iter().map(FailureEntry::from).collect(),
                    frames_checked: p.frames_checked(),
                    profile: p.profile.clone(),
                    scenarios: p
                        .runs
                        .iter()
                        .map(|r| RunEntry {
                            cycles: r.cycles,
                            frames_checked: r.frames_checked,
                            outcome: match &r.outcome {
                                Outcome::Pass => "pass".into(),
                                Outcome::Fail(_) => "fail".into(),
                                Outcome::Error(e) => format!("error: {e}"),
                            },
                            scenario: r.scenario.clone(),
                        })
                        .collect(),
                    verdicts: catalogue
                        .requirements()
                        .filter_map(|r| p.verdicts.get(&r.id).map(|v| (r.id.clone(), v.into())))
                        .collect(),
                })
                .collect(),
            scenarios: report
                .scenarios
                .iter()
                .map(|s| ScenarioEntry {
                    file: s.file.clone(),
                    line: s.line,
                    name: s.name.clone(),
                    outcome: match &s.outcome {
                        Ok(()) => VerdictKind::Pass,
                        Err(_) if s.error => VerdictKind::Error,
                        Err(_) => VerdictKind::Fail,
                    },
                    report: s.outcome.as_ref().err().cloned(),
                    requirements: s.requirements.clone(),
                    suite: s.suite.clone(),
                })
                .collect(),
            seed: report.seed,
            totals: report.totals().into(),
            wall_time_ms: report.wall_time_ms as u64,
        }
    }

    /// Reads a `report.json`; the error names what does not fit.
    pub fn parse(text: &str) -> Result<Self, String> {
        serde_json::from_str(text).map_err(|e| format!("not a canif report.json: {e}"))
    }
}
