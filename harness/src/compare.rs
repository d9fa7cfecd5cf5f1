//! What changed between two runs: `canif compare BASE.json NEW.json`.
//!
//! A regression is a verdict or check that was not fail or error and now is,
//! and — unless removals are allowed — one that passed and is now absent, not
//! run or no longer testable: a gate must not go green because less was
//! checked. Reports of different implementations, sides, suites, catalogues
//! or profile sets are not compared unless forced.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

use serde::Serialize;

use crate::report::ReportFile;
use crate::verdict::VerdictKind;

/// Verdicts and check outcomes of a report, keyed `profile::REQ-ID` and
/// `profile::scenario: …` (`gherkin: …`, `canopen: …`).
pub fn verdicts(report: &ReportFile) -> BTreeMap<String, VerdictKind> {
    outcomes(report)
        .into_iter()
        .map(|(key, (kind, _))| (key, kind))
        .collect()
}

/// [`verdicts`] with each one's reason as the report gives it (a verdict's
/// reason, a check's cause): what a regression is shown with.
fn outcomes(report: &ReportFile) -> BTreeMap<String, (VerdictKind, Option<String>)> {
    let mut all = BTreeMap::new();
    for profile in &report.profiles {
        for (id, verdict) in &profile.verdicts {
            all.insert(
                format!("{}::{id}", profile.profile),
                (verdict.verdict, verdict.reason.clone()),
            );
        }
        for check in &profile.checks {
            all.insert(
                format!("{}::{}", profile.profile, check.check),
                (check.outcome, check.cause.clone()),
            );
        }
    }
    all
}

/// How the comparison is asked for.
#[derive(Debug, Clone, Copy, Default)]
pub struct CompareOptions {
    /// A check that passed and is gone is a change, not a regression.
    pub allow_removed: bool,
    /// Compare reports that do not describe the same thing, saying so.
    pub force: bool,
}

/// One key whose verdict changed.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Change {
    pub check: String,
    /// `absent` when the report lacks it.
    pub before: String,
    pub now: String,
    /// Why it is what it is now, as the new report says (a failure's cause,
    /// why it was not run); none for a pass.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why: Option<String>,
}

/// The comparison of two runs.
#[derive(Debug, Default, Clone, PartialEq, Eq, Serialize)]
pub struct Comparison {
    pub regressions: Vec<Change>,
    /// Passed before, absent or not run now (regressions unless allowed).
    pub removed: Vec<Change>,
    pub removed_allowed: bool,
    pub fixes: Vec<Change>,
    pub changes: Vec<Change>,
    pub unchanged: usize,
    /// What differs between the two reports' runs, compared anyway with `--force`.
    pub forced_despite: Vec<String>,
}

/// Where two reports do not describe the same thing.
pub fn mismatches(base: &ReportFile, new: &ReportFile) -> Vec<String> {
    let mut found = Vec::new();
    let mut differs = |what: &str, a: String, b: String| {
        if a != b {
            found.push(format!("{what}: `{a}` in the base, `{b}` now"));
        }
    };
    differs(
        "implementation",
        base.meta.iut.clone(),
        new.meta.iut.clone(),
    );
    differs(
        "side",
        base.meta.side.to_string(),
        new.meta.side.to_string(),
    );
    differs(
        "suite",
        format!("{:?}", base.meta.suite),
        format!("{:?}", new.meta.suite),
    );
    differs(
        "catalogue",
        base.meta.catalogue_sha256.clone(),
        new.meta.catalogue_sha256.clone(),
    );
    let profiles = |r: &ReportFile| {
        r.profiles
            .iter()
            .map(|p| p.profile.as_str())
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect::<Vec<_>>()
            .join(", ")
    };
    differs("profiles", profiles(base), profiles(new));
    found
}

/// Compares two reports; `Err` lists why they are not comparable (without `force`).
pub fn compare(
    base: &ReportFile,
    new: &ReportFile,
    options: CompareOptions,
) -> Result<Comparison, Vec<String>> {
    let mismatched = mismatches(base, new);
    if !mismatched.is_empty() && !options.force {
        return Err(mismatched);
    }
    let (before_all, now_all) = (verdicts(base), outcomes(new));
    let mut result = Comparison {
        removed_allowed: options.allow_removed,
        forced_despite: mismatched,
        ..Comparison::default()
    };
    let keys: BTreeSet<&String> = before_all.keys().chain(now_all.keys()).collect();
    for key in keys {
        let before = before_all.get(key).copied();
        let (now, why) = match now_all.get(key) {
            Some((kind, why)) => (Some(*kind), why.clone()),
            None => (None, None),
        };
        let label = |v: Option<VerdictKind>| v.map_or("absent", VerdictKind::label).to_string();
        let change = Change {
            check: key.clone(),
            before: label(before),
            now: label(now),
            why,
        };
        let bad = |v: Option<VerdictKind>| v.is_some_and(VerdictKind::is_bad);
        if before == now {
            result.unchanged += 1;
        } else if bad(now) && !bad(before) {
            result.regressions.push(change);
        } else if before == Some(VerdictKind::Pass) && now != Some(VerdictKind::Pass) {
            result.removed.push(change);
        } else if bad(before) && now == Some(VerdictKind::Pass) {
            result.fixes.push(change);
        } else {
            result.changes.push(change);
        }
    }
    Ok(result)
}

impl Comparison {
    /// Does the gate stop?
    pub fn regressed(&self) -> bool {
        !self.regressions.is_empty() || (!self.removed.is_empty() && !self.removed_allowed)
    }

    /// Markdown for a CI summary.
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "# canif: changes since the baseline\n\n**{}**: {} regression(s), {} removed check(s){}, {} fix(es), {} other change(s), {} unchanged.\n",
            if self.regressed() { "REGRESSED" } else { "NO REGRESSION" },
            self.regressions.len(),
            self.removed.len(),
            if self.removed_allowed { " (allowed)" } else { "" },
            self.fixes.len(),
            self.changes.len(),
            self.unchanged
        );
        if !self.forced_despite.is_empty() {
            let _ = write!(
                md,
                "\nCompared with --force although the runs differ:\n\n{}\n",
                self.forced_despite
                    .iter()
                    .map(|m| format!("- {m}"))
                    .collect::<Vec<_>>()
                    .join("\n")
            );
        }
        for (title, rows) in [
            ("Regressions", &self.regressions),
            (
                if self.removed_allowed {
                    "Removed (allowed)"
                } else {
                    "Removed: passed before, not checked now"
                },
                &self.removed,
            ),
            ("Fixes", &self.fixes),
            ("Other changes", &self.changes),
        ] {
            if rows.is_empty() {
                continue;
            }
            let _ = write!(
                md,
                "\n## {title}\n\n| check | before | now | why |\n|---|---|---|---|\n"
            );
            for change in rows {
                let why = change.why.as_deref().unwrap_or("").replace('|', "\\|");
                let _ = writeln!(
                    md,
                    "| {} | {} | {} | {} |",
                    change.check, change.before, change.now, why
                );
            }
        }
        md
    }
}
