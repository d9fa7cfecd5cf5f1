//! What changed between two runs: `canif compare BASE.json NEW.json`.
//!
//! A regression is anything that passed (or did not exist) in the base and now
//! fails or errs. Fixes and other changes are listed too; removed checks are
//! changes, not regressions.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::report::ReportFile;

/// Verdicts of a report, keyed `profile :: requirement` and `suite :: file:line name`.
pub fn verdicts(report: &ReportFile) -> BTreeMap<String, String> {
    let mut all = BTreeMap::new();
    for profile in &report.profiles {
        for (id, verdict) in &profile.verdicts {
            all.insert(
                format!("{} :: {id}", profile.profile),
                verdict.verdict.label().to_string(),
            );
        }
    }
    for scenario in &report.scenarios {
        let key = format!(
            "{} :: {}:{} {}",
            scenario.suite, scenario.file, scenario.line, scenario.name
        );
        all.insert(key, scenario.outcome.label().to_string());
    }
    all
}

fn bad(verdict: &str) -> bool {
    verdict == "fail" || verdict == "error"
}

/// The comparison of two runs.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Comparison {
    pub regressions: Vec<(String, String, String)>,
    pub fixes: Vec<(String, String, String)>,
    pub changes: Vec<(String, String, String)>,
    pub unchanged: usize,
}

pub fn compare(base: &BTreeMap<String, String>, new: &BTreeMap<String, String>) -> Comparison {
    let mut result = Comparison::default();
    let keys: std::collections::BTreeSet<&String> = base.keys().chain(new.keys()).collect();
    for key in keys {
        let before = base.get(key).map_or("absent", String::as_str);
        let after = new.get(key).map_or("absent", String::as_str);
        let entry = (key.clone(), before.to_string(), after.to_string());
        if before == after {
            result.unchanged += 1;
        } else if bad(after) && !bad(before) {
            result.regressions.push(entry);
        } else if bad(before) && after == "pass" {
            result.fixes.push(entry);
        } else {
            result.changes.push(entry);
        }
    }
    result
}

impl Comparison {
    /// Markdown for a CI summary.
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "# canif: changes since the baseline\n\n{} regression(s), {} fix(es), {} other change(s), {} unchanged.\n",
            self.regressions.len(),
            self.fixes.len(),
            self.changes.len(),
            self.unchanged
        );
        for (title, rows) in [
            ("Regressions", &self.regressions),
            ("Fixes", &self.fixes),
            ("Other changes", &self.changes),
        ] {
            if rows.is_empty() {
                continue;
            }
            let _ = write!(
                md,
                "\n## {title}\n\n| check | before | now |\n|---|---|---|\n"
            );
            for (key, before, after) in rows {
                let _ = writeln!(md, "| {key} | {before} | {after} |");
            }
        }
        md
    }
}
