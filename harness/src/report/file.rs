//! `report.json` as types, written and read through one definition: `canif
//! run` writes it, `canif compare` and `canif certify` read it back. Fields are
//! in alphabetical order.

use std::collections::BTreeMap;

use canif_spec::{Catalogue, Side};
use serde::{Deserialize, Serialize};

use super::RunReport;
use crate::outcome::Failure;
use crate::verdict::{CheckResult, Verdict, VerdictKind};

/// The shape of `report.json` this canif writes; older ones are refused with this number.
pub const REPORT_FORMAT: u32 = 2;

/// Which suite ran.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SuiteKind {
    /// The CAN interface of a device.
    Interface,
    /// A CANopen node (002, 004).
    Canopen,
}

/// The implementation's own name and version, as its maker declares them.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Product {
    pub name: String,
    pub version: String,
}

/// How a run was asked for, and with what.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunMeta {
    pub bus: String,
    pub canif_commit: String,
    pub canif_version: String,
    /// SHA-256 over the catalogue's files as this run loaded them.
    pub catalogue_sha256: String,
    /// Everything the suite can run here ran: no selection, no stage left out, no signal.
    pub complete: bool,
    pub iut: String,
    pub product: Option<Product>,
    pub seed: u64,
    /// What was left out and why, when the run is not complete.
    pub left_out: Option<String>,
    /// Which side of the interface was under test.
    pub side: Side,
    /// The EtherCAT master models a PLC-side run used (none on the device side).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub masters: Vec<String>,
    /// `--shard K/N`: this run is one shard of a campaign, `canif merge` joins them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<crate::run::Shard>,
    /// Seconds since the Unix epoch when the run started.
    pub started_unix: u64,
    pub suite: SuiteKind,
    /// The EtherCAT terminals the run met, one per profile (device side over EtherCAT).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub terminals: Vec<TerminalEntry>,
    /// The choices the documents leave, as the device declared them or a
    /// scenario showed them (device side).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub choices: Vec<ChoiceEntry>,
}

pub use crate::declare::{ChoiceEntry, ChoiceSource};
pub use crate::door::TerminalFacts as TerminalEntry;

impl RunMeta {
    /// What the run left out (its lines, the selection first) and whether
    /// a signal stopped it: a run is complete only when neither.
    pub fn left_out(self, lines: &[String], interrupted: bool) -> Self {
        RunMeta {
            complete: lines.is_empty() && !interrupted,
            left_out: (!lines.is_empty()).then(|| lines.join("; ")),
            ..self
        }
    }

    /// A complete run of the interface suite on the device side, started now,
    /// by this canif, with `catalogue`.
    pub fn new(iut: String, bus: String, seed: u64, catalogue: &Catalogue) -> Self {
        RunMeta {
            bus,
            canif_commit: env!("CANIF_COMMIT").into(),
            canif_version: env!("CARGO_PKG_VERSION").into(),
            catalogue_sha256: catalogue.sha256.clone(),
            complete: true,
            iut,
            product: None,
            seed,
            left_out: None,
            side: Side::Device,
            masters: Vec::new(),
            shard: None,
            started_unix: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
            suite: SuiteKind::Interface,
            terminals: Vec::new(),
            choices: Vec::new(),
        }
    }
}

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReportFile {
    #[serde(default)]
    pub format: u32,
    /// Present only when the run was asked to stop before it ended.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub interrupted: bool,
    /// Checks that failed in the run before and pass now (`--rerun-failed`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub flaky: Vec<String>,
    pub meta: RunMeta,
    pub profiles: Vec<ProfileEntry>,
    pub totals: TotalsEntry,
    pub wall_time_ms: u64,
}

/// Counts of verdicts over every requirement × profile.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TotalsEntry {
    pub error: usize,
    pub fail: usize,
    pub not_applicable: usize,
    pub not_run: usize,
    pub not_testable: usize,
    pub pass: usize,
}

/// One profile's run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProfileEntry {
    /// What the documents allow but a client's author wants to know (never a verdict).
    #[serde(default, skip_serializing_if = "crate::advisory::Advisories::is_empty")]
    pub advisories: crate::advisory::Advisories,
    pub checks: Vec<CheckEntry>,
    pub cycles: u64,
    pub failures: Vec<FailureEntry>,
    pub frames_checked: u64,
    /// What the profile offers and the implementation declares it does not
    /// serve: not run, never a verdict of its own (the requirements only
    /// these would exercise are not applicable).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_served: Vec<NotServedEntry>,
    pub profile: String,
    pub verdicts: BTreeMap<String, VerdictEntry>,
}

/// Something the implementation declares it does not serve.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct NotServedEntry {
    pub what: String,
    pub why: String,
}

/// One check that ran: a lockstep scenario, a Gherkin scenario, a node check.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckEntry {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cause: Option<String>,
    /// The stable key (`scenario: …`, `gherkin: …`, `canopen: …`).
    pub check: String,
    pub covers: Vec<String>,
    pub elapsed_ms: f64,
    /// `pass`, `fail` or `error`.
    pub outcome: VerdictKind,
}

/// One requirement's verdict on a profile.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct VerdictEntry {
    /// The checks it rests on (keys of [`CheckEntry::check`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub evidence: Vec<String>,
    /// Indexes into the profile's failures.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub failures: Vec<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    pub verdict: VerdictKind,
}

/// One lockstep failure, as text.
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

impl From<&Verdict> for VerdictEntry {
    fn from(verdict: &Verdict) -> Self {
        let failures = match verdict {
            Verdict::Fail(found) => found.iter().filter_map(|(_, f)| f.failure).collect(),
            _ => Vec::new(),
        };
        VerdictEntry {
            evidence: verdict.evidence().iter().map(|e| e.key()).collect(),
            failures,
            reason: verdict.reason(),
            verdict: verdict.kind(),
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

impl TotalsEntry {
    pub fn of(totals: &super::Totals) -> Self {
        let n = |k: VerdictKind| totals.get(&k).copied().unwrap_or(0);
        TotalsEntry {
            error: n(VerdictKind::Error),
            fail: n(VerdictKind::Fail),
            not_applicable: n(VerdictKind::NotApplicable),
            not_run: n(VerdictKind::NotRun),
            not_testable: n(VerdictKind::NotTestable),
            pass: n(VerdictKind::Pass),
        }
    }
}

impl ReportFile {
    pub fn new(report: &RunReport, catalogue: &Catalogue) -> Self {
        ReportFile {
            format: REPORT_FORMAT,
            interrupted: report.interrupted,
            flaky: report.flaky.clone(),
            meta: report.meta.clone(),
            profiles: report
                .profiles
                .iter()
                .map(|p| ProfileEntry {
                    not_served: p
                        .ran
                        .reach
                        .not_served
                        .iter()
                        .map(|(what, why)| NotServedEntry {
                            what: what.clone(),
                            why: why.clone(),
                        })
                        .collect(),
                    advisories: p.ran.advisories,
                    checks: p
                        .ran
                        .checks
                        .iter()
                        .map(|c| CheckEntry {
                            cause: match &c.result {
                                CheckResult::Pass => None,
                                CheckResult::Fail(finding) => Some(finding.cause.clone()),
                                CheckResult::Error(cause) => Some(cause.clone()),
                            },
                            check: c.evidence.key(),
                            covers: c.covers.clone(),
                            elapsed_ms: c.elapsed.as_secs_f64() * 1e3,
                            outcome: c.result.kind(),
                        })
                        .collect(),
                    cycles: p.ran.tally.cycles,
                    failures: p.ran.failures.iter().map(FailureEntry::from).collect(),
                    frames_checked: p.ran.tally.frames_checked,
                    profile: p.profile.clone(),
                    verdicts: catalogue
                        .requirements()
                        .filter_map(|r| p.verdicts.get(&r.id).map(|v| (r.id.clone(), v.into())))
                        .collect(),
                })
                .collect(),
            totals: TotalsEntry::of(&report.totals()),
            wall_time_ms: report.wall_time_ms as u64,
        }
    }

    /// Reads a `report.json`; the error names what does not fit.
    pub fn parse(text: &str) -> Result<Self, String> {
        let not_a_report = |e: serde_json::Error| format!("not a canif report.json: {e}");
        let value: serde_json::Value = serde_json::from_str(text).map_err(not_a_report)?;
        // Reports before format 2 had no `format` field.
        let format = value.get("format").and_then(|f| f.as_u64()).unwrap_or(1);
        if format != u64::from(REPORT_FORMAT) {
            return Err(format!(
                "a report.json of format {format}; this canif reads format {REPORT_FORMAT}: write it again with this canif"
            ));
        }
        serde_json::from_str(text).map_err(not_a_report)
    }
}
