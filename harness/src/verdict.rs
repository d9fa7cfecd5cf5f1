//! One verdict per requirement and profile, merged from every check that
//! exercised it: lockstep scenarios, Gherkin scenarios and CANopen node checks.
//!
//! A fail outranks an error, an error outranks a pass, and a pass names its
//! evidence. A requirement the run could have exercised but did not is `not
//! run`; `not testable` is kept for what nothing in canif exercises against an
//! implementation, with the catalogue's reason.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

use canif_spec::{Catalogue, Profile, Scope, Side, Suite, Verification};
use serde::{Deserialize, Serialize};

/// One check that ran against the implementation, named stably (no line
/// numbers, no statement text), so that two runs can be compared.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Evidence {
    /// A lockstep scenario of the interface suite (scripted or generated).
    Scenario(String),
    /// A Gherkin scenario: `feature file: scenario name`, with an Examples row's values.
    Gherkin(String),
    /// A CANopen node check (002, 004).
    NodeCheck(String),
}

impl Evidence {
    /// The stable key reports and `compare` use: `scenario: …`, `gherkin: …`, `canopen: …`.
    pub fn key(&self) -> String {
        self.to_string()
    }

    /// The check's name as the plan and `--scenario` know it.
    pub fn name(&self) -> &str {
        match self {
            Evidence::Scenario(name) | Evidence::Gherkin(name) | Evidence::NodeCheck(name) => name,
        }
    }
}

impl fmt::Display for Evidence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Evidence::Scenario(name) => write!(f, "scenario: {name}"),
            Evidence::Gherkin(id) => write!(f, "gherkin: {id}"),
            Evidence::NodeCheck(name) => write!(f, "canopen: {name}"),
        }
    }
}

/// What a failing check found: the requirements it blames and why, in one line.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Finding {
    pub requirements: Vec<String>,
    /// One line: where it differs and how.
    pub cause: String,
    /// Expected, actual and the steps or cycles before.
    pub details: String,
    /// The lockstep failure it came from (an index into the profile's failures).
    pub failure: Option<usize>,
    /// What the check says of the requirements it covers and does not blame.
    pub rest: Rest,
}

/// What a failing check says of the requirements it covers and does not blame.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Rest {
    /// It stopped at the failure: they were exercised up to it only, which
    /// is evidence neither way.
    #[default]
    Stopped,
    /// It ran to its end, and they held (the refusal grid tries every configuration).
    Held,
    /// It could not start (the IUT refused the interface it needs): they were not run.
    NotRun(NotRunReason),
}

/// How one check ended.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum CheckResult {
    Pass,
    Fail(Finding),
    /// The implementation or the harness could not run it.
    Error(String),
}

impl CheckResult {
    /// `pass`, `fail` or `error`, as reports spell a check's outcome.
    pub fn kind(&self) -> VerdictKind {
        match self {
            CheckResult::Pass => VerdictKind::Pass,
            CheckResult::Fail(_) => VerdictKind::Fail,
            CheckResult::Error(_) => VerdictKind::Error,
        }
    }

    /// Why it did not pass, in one line.
    pub fn cause(&self) -> Option<&str> {
        match self {
            CheckResult::Pass => None,
            CheckResult::Fail(finding) => Some(&finding.cause),
            CheckResult::Error(cause) => Some(cause.lines().next().unwrap_or_default()),
        }
    }
}

/// One check against one profile, with the requirements it exercises.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Check {
    pub evidence: Evidence,
    pub covers: Vec<String>,
    pub result: CheckResult,
    /// Wall time the check took.
    pub elapsed: std::time::Duration,
}

/// The kinds of verdict, as reports spell them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum VerdictKind {
    #[serde(rename = "pass")]
    Pass,
    #[serde(rename = "fail")]
    Fail,
    #[serde(rename = "error")]
    Error,
    #[serde(rename = "not applicable")]
    NotApplicable,
    #[serde(rename = "not run")]
    NotRun,
    #[serde(rename = "not testable")]
    NotTestable,
}

impl VerdictKind {
    pub const ALL: [VerdictKind; 6] = [
        VerdictKind::Pass,
        VerdictKind::Fail,
        VerdictKind::Error,
        VerdictKind::NotApplicable,
        VerdictKind::NotRun,
        VerdictKind::NotTestable,
    ];

    pub fn label(self) -> &'static str {
        match self {
            VerdictKind::Pass => "pass",
            VerdictKind::Fail => "fail",
            VerdictKind::Error => "error",
            VerdictKind::NotApplicable => "not applicable",
            VerdictKind::NotRun => "not run",
            VerdictKind::NotTestable => "not testable",
        }
    }

    /// A verdict that stops a gate.
    pub fn is_bad(self) -> bool {
        matches!(self, VerdictKind::Fail | VerdictKind::Error)
    }
}

/// A requirement's verdict on one profile, with what it rests on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    /// Every check that exercised it passed; they are listed.
    Pass(Vec<Evidence>),
    /// The checks that failed on it, each with its finding.
    Fail(Vec<(Evidence, Finding)>),
    /// The checks that could not run, each with its cause (none failed).
    Error(Vec<(Evidence, String)>),
    /// The profile lacks a capability the requirement needs.
    NotApplicable(String),
    /// Something in canif exercises it, but not this run (the selection, an
    /// earlier error, another suite or side), or the run found nothing to judge.
    NotRun(NotRunReason),
    /// Nothing in canif exercises it against an implementation: the catalogue's reason.
    NotTestable(String),
}

impl Verdict {
    pub fn kind(&self) -> VerdictKind {
        match self {
            Verdict::Pass(_) => VerdictKind::Pass,
            Verdict::Fail(_) => VerdictKind::Fail,
            Verdict::Error(_) => VerdictKind::Error,
            Verdict::NotApplicable(_) => VerdictKind::NotApplicable,
            Verdict::NotRun(_) => VerdictKind::NotRun,
            Verdict::NotTestable(_) => VerdictKind::NotTestable,
        }
    }

    pub fn label(&self) -> &'static str {
        self.kind().label()
    }

    /// Why, in one line: the first finding or error, or the reason given.
    pub fn reason(&self) -> Option<String> {
        match self {
            Verdict::Pass(_) => None,
            Verdict::Fail(found) => found.first().map(|(e, f)| format!("{e}: {}", f.cause)),
            Verdict::Error(errors) => errors.first().map(|(e, cause)| format!("{e}: {cause}")),
            Verdict::NotApplicable(reason) | Verdict::NotTestable(reason) => Some(reason.clone()),
            Verdict::NotRun(reason) => Some(reason.to_string()),
        }
    }

    /// The checks the verdict rests on.
    pub fn evidence(&self) -> Vec<&Evidence> {
        match self {
            Verdict::Pass(evidence) => evidence.iter().collect(),
            Verdict::Fail(found) => found.iter().map(|(e, _)| e).collect(),
            Verdict::Error(errors) => errors.iter().map(|(e, _)| e).collect(),
            _ => Vec::new(),
        }
    }
}

/// Why a requirement the run could not judge was not run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum NotRunReason {
    /// The run selected everything, yet no check of it ran.
    NotSelected,
    /// `--scenario` or `--requirement` left it out (the flags).
    Selection(String),
    /// The run left out a stage, as it said (Gherkin scenarios not run, a signal).
    LeftOut(String),
    /// The checks that exercise it ran, but the implementation gave them nothing to judge.
    NothingToJudge(Unobserved),
    /// The IUT refused the interface its checks need, which the profile
    /// offers (a failure of its own): the interface, and the IUT's words.
    Refused { interface: String, reason: String },
    /// Its checks ended at a failure blamed on other requirements before
    /// they could judge it (the check that stopped).
    StoppedEarlier(Evidence),
}

impl NotRunReason {
    /// Why a run left its unreached requirements out, when it left something
    /// out: the stages it names (`left_out`, the selection first), or a
    /// signal. `None`: nothing was left out but by the side's own reach.
    pub fn of_run(left_out: &[String], interrupted: bool) -> Option<NotRunReason> {
        match (left_out, interrupted) {
            ([], false) => None,
            ([], true) => Some(NotRunReason::LeftOut("interrupted".into())),
            (lines, _) => Some(NotRunReason::LeftOut(lines.join("; "))),
        }
    }
}

/// What an implementation did not show, so that a requirement had nothing to judge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Unobserved {
    /// CL-TN-002: the client told its application of no message sent.
    SentMessages,
}

impl fmt::Display for NotRunReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NotRunReason::NotSelected => f.write_str("no check of this run reached it (nothing was left out by a selection)"),
            NotRunReason::Selection(flags) => write!(f, "left out by the selection ({flags})"),
            NotRunReason::LeftOut(what) => f.write_str(what),
            NotRunReason::StoppedEarlier(check) => write!(
                f,
                "not reached: its check stopped at an earlier failure of other requirements ({check})"
            ),
            NotRunReason::Refused { interface, reason } => write!(
                f,
                "the IUT refuses the interface its checks need ({interface}), which the profile offers: {reason}"
            ),
            NotRunReason::NothingToJudge(Unobserved::SentMessages) => f.write_str(
                "the client told its application of no Tx message sent (it does not use Inputs.TransactionNumber that way): nothing to judge",
            ),
        }
    }
}

/// What the suite can exercise on a profile, beyond what this run did.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Reach {
    /// The side and suite the run judges: requirements outside it get no verdict.
    pub scope: Scope,
    /// Requirements this run's suite exercises on the profile when nothing is left out.
    pub here: BTreeSet<String>,
    /// Requirements whose checks ran and had nothing to judge, with why.
    pub unobserved: BTreeMap<String, NotRunReason>,
    /// Requirements the implementation declares it does not take up (a
    /// client that tells its application nothing of what was sent), with why.
    pub not_applicable: BTreeMap<String, String>,
    /// What the profile offers and the implementation declares it does not
    /// serve (an interface, a slot count, a direction), each with why.
    pub not_served: Vec<(String, String)>,
    /// Why this run left out what it could have run (the selection, an error, a signal).
    pub left_out: NotRunReason,
}

impl Default for Reach {
    fn default() -> Self {
        Reach {
            scope: Scope {
                side: Side::Device,
                suite: Suite::Interface,
            },
            here: BTreeSet::new(),
            unobserved: BTreeMap::new(),
            not_applicable: BTreeMap::new(),
            not_served: Vec::new(),
            left_out: NotRunReason::NotSelected,
        }
    }
}

/// Every requirement's verdict on `profile`, from the checks that ran.
pub fn judge(
    catalogue: &Catalogue,
    profile: &Profile,
    checks: &[Check],
    reach: &Reach,
) -> BTreeMap<String, Verdict> {
    let mut passed: BTreeMap<&str, Vec<Evidence>> = BTreeMap::new();
    let mut failed: BTreeMap<&str, Vec<(Evidence, Finding)>> = BTreeMap::new();
    let mut broke: BTreeMap<&str, Vec<(Evidence, String)>> = BTreeMap::new();
    let mut unjudged: BTreeMap<&str, NotRunReason> = BTreeMap::new();
    for check in checks {
        match &check.result {
            CheckResult::Pass => {
                for id in &check.covers {
                    passed.entry(id).or_default().push(check.evidence.clone());
                }
            }
            CheckResult::Fail(finding) => {
                // A failure blamed only on what the profile lacks must not
                // vanish into "not applicable": it falls to what the check covers.
                let applies = |id: &&String| {
                    catalogue
                        .requirement(id)
                        .is_some_and(|r| profile.lacks(&r.capabilities).is_empty())
                };
                let blamed: Vec<&String> = if finding.requirements.iter().any(|id| applies(&id)) {
                    finding.requirements.iter().collect()
                } else {
                    check.covers.iter().filter(applies).collect()
                };
                for id in blamed {
                    failed
                        .entry(id)
                        .or_default()
                        .push((check.evidence.clone(), finding.clone()));
                }
                let rest = check
                    .covers
                    .iter()
                    .filter(|id| !finding.requirements.contains(id));
                match &finding.rest {
                    Rest::Stopped => {
                        let why = NotRunReason::StoppedEarlier(check.evidence.clone());
                        for id in rest {
                            unjudged.entry(id).or_insert_with(|| why.clone());
                        }
                    }
                    Rest::Held => {
                        for id in rest {
                            passed.entry(id).or_default().push(check.evidence.clone());
                        }
                    }
                    Rest::NotRun(why) => {
                        for id in rest {
                            unjudged.entry(id).or_insert_with(|| why.clone());
                        }
                    }
                }
            }
            CheckResult::Error(cause) => {
                for id in &check.covers {
                    broke
                        .entry(id)
                        .or_default()
                        .push((check.evidence.clone(), cause.clone()));
                }
            }
        }
    }
    let mut verdicts = BTreeMap::new();
    for requirement in catalogue.requirements() {
        let id = requirement.id.as_str();
        if !reach.scope.reports(requirement, reach.here.contains(id)) {
            continue;
        }
        let missing = profile.lacks(&requirement.capabilities);
        let verdict = if !missing.is_empty() {
            Verdict::NotApplicable(format!("{} lacks {}", profile.name, missing.join(", ")))
        } else if let Some(found) = failed.remove(id) {
            // A declaration never hides what was seen broken.
            Verdict::Fail(found)
        } else if let Some(why) = reach.not_applicable.get(id) {
            Verdict::NotApplicable(why.clone())
        } else if let Some(errors) = broke.remove(id) {
            Verdict::Error(errors)
        } else if let Some(evidence) = passed.remove(id) {
            Verdict::Pass(evidence)
        } else if let Some(why) = unjudged.remove(id) {
            Verdict::NotRun(why)
        } else if let Some(why) = reach.unobserved.get(id) {
            Verdict::NotRun(why.clone())
        } else if reach.here.contains(id) {
            Verdict::NotRun(reach.left_out.clone())
        } else {
            Verdict::NotTestable(match (&requirement.reason, requirement.verification) {
                (Some(reason), _) => reason.clone(),
                (None, Verification::Inspection) => "verified by inspection".into(),
                (None, Verification::Model) => "checked on the reference model".into(),
                (None, Verification::Test) => {
                    "no scenario of this suite reaches it on the interfaces this profile offers"
                        .into()
                }
            })
        };
        verdicts.insert(requirement.id.clone(), verdict);
    }
    verdicts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn catalogue() -> Catalogue {
        Catalogue::embedded().expect("the embedded catalogue loads")
    }

    fn check(name: &str, covers: &[&str], result: CheckResult) -> Check {
        Check {
            evidence: Evidence::Gherkin(name.into()),
            covers: covers.iter().map(|s| s.to_string()).collect(),
            result,
            elapsed: std::time::Duration::ZERO,
        }
    }

    fn finding(blames: &[&str]) -> Finding {
        Finding {
            rest: Rest::Stopped,
            requirements: blames.iter().map(|s| s.to_string()).collect(),
            cause: "differs".into(),
            details: String::new(),
            failure: None,
        }
    }

    #[test]
    fn a_failure_outranks_a_pass_and_an_error_from_other_checks() {
        let catalogue = catalogue();
        let profile = catalogue.profile("fc532x").unwrap();
        let checks = [
            check("a", &["HS-TX-001", "HS-TX-002"], CheckResult::Pass),
            check(
                "b",
                &["HS-TX-001"],
                CheckResult::Fail(finding(&["HS-TX-001"])),
            ),
            check(
                "c",
                &["HS-TX-001", "HS-TX-003"],
                CheckResult::Error("died".into()),
            ),
        ];
        let verdicts = judge(&catalogue, profile, &checks, &Reach::default());
        assert_eq!(verdicts["HS-TX-001"].kind(), VerdictKind::Fail);
        assert_eq!(
            verdicts["HS-TX-002"],
            Verdict::Pass(vec![Evidence::Gherkin("a".into())])
        );
        assert_eq!(verdicts["HS-TX-003"].kind(), VerdictKind::Error);
    }

    #[test]
    fn a_failure_blamed_only_on_what_the_profile_lacks_falls_to_what_the_check_covers() {
        let catalogue = catalogue();
        // fc510x has no CAN FD: FD-BIT-002 does not apply there.
        let profile = catalogue.profile("fc510x").unwrap();
        let checks = [check(
            "brs on a classic frame",
            &["HS-TX-001", "HS-TX-006"],
            CheckResult::Fail(finding(&["FD-BIT-002"])),
        )];
        let verdicts = judge(&catalogue, profile, &checks, &Reach::default());
        assert_eq!(verdicts["FD-BIT-002"].kind(), VerdictKind::NotApplicable);
        assert_eq!(verdicts["HS-TX-001"].kind(), VerdictKind::Fail);
        assert_eq!(verdicts["HS-TX-006"].kind(), VerdictKind::Fail);
    }

    /// A check that stopped at a failure blamed elsewhere judged nothing
    /// more: what else it covers is not run because of that failure, never
    /// "not selected" (nothing was left out by a selection).
    #[test]
    fn what_a_stopped_check_did_not_reach_is_not_run_because_it_stopped() {
        let catalogue = catalogue();
        let profile = catalogue.profile("el6751-mdp").unwrap();
        let checks = [check(
            "queue depth",
            &["RXQ-001", "RXQ-003"],
            CheckResult::Fail(finding(&["RXQ-003"])),
        )];
        let reach = Reach {
            here: ["RXQ-001".to_string(), "RXQ-003".to_string()].into(),
            ..Reach::default()
        };
        let verdicts = judge(&catalogue, profile, &checks, &reach);
        assert_eq!(verdicts["RXQ-003"].kind(), VerdictKind::Fail);
        assert_eq!(
            verdicts["RXQ-001"].reason().unwrap(),
            "not reached: its check stopped at an earlier failure of other requirements (gherkin: queue depth)"
        );
    }

    #[test]
    fn what_the_run_left_out_is_not_run_and_never_not_testable() {
        let catalogue = catalogue();
        let profile = catalogue.profile("fc532x").unwrap();
        let reach = Reach {
            here: ["HS-TX-001".to_string()].into(),
            left_out: NotRunReason::Selection("--scenario x".into()),
            ..Reach::default()
        };
        let verdicts = judge(&catalogue, profile, &[], &reach);
        assert_eq!(
            verdicts["HS-TX-001"].reason().unwrap(),
            "left out by the selection (--scenario x)"
        );
        assert!(!verdicts.values().any(|v| v.kind() == VerdictKind::Pass));
    }

    #[test]
    fn a_run_reports_only_its_side_and_suite_and_what_it_exercises_of_another_suite() {
        let catalogue = catalogue();
        let profile = catalogue.profile("fc532x").unwrap();
        let reach = Reach {
            here: ["NMT-001".to_string()].into(),
            ..Reach::default()
        };
        let verdicts = judge(&catalogue, profile, &[], &reach);
        assert!(verdicts.contains_key("HS-TX-001"));
        assert!(verdicts.contains_key("NMT-001"), "exercised here");
        assert!(!verdicts.contains_key("NMT-002"), "the CANopen suite's");
        assert!(
            !verdicts.keys().any(|id| id.starts_with("CL-")),
            "the PLC side's"
        );
        let client = Reach {
            scope: Scope {
                side: Side::Plc,
                suite: Suite::Interface,
            },
            ..Reach::default()
        };
        let verdicts = judge(&catalogue, profile, &[], &client);
        assert!(verdicts.keys().all(|id| id.starts_with("CL-")));
        assert!(!verdicts.is_empty());
    }

    /// Every "not testable" says why: the catalogue's reason for a statement
    /// checked on the model, or that no scenario reaches it on this profile.
    #[test]
    fn not_testable_names_why() {
        let catalogue = catalogue();
        let profile = catalogue.profile("fc532x").unwrap();
        let verdicts = judge(&catalogue, profile, &[], &Reach::default());
        let reason = |id: &str| verdicts[id].reason().unwrap();
        assert!(
            reason("TIM-001").contains("frame-time model"),
            "{}",
            reason("TIM-001")
        );
        assert_eq!(
            reason("HS-TX-001"),
            "no scenario of this suite reaches it on the interfaces this profile offers"
        );
    }
}
