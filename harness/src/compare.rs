//! What changed between two runs: `canif compare BASE.json NEW.json`.
//!
//! A regression is anything that passed (or did not exist) in the base and now
//! fails or errs. Fixes and other changes are listed too; removed checks are
//! changes, not regressions.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde_json::Value;

/// Verdicts of a report.json, keyed `profile :: requirement` and `suite :: file:line`.
pub fn verdicts(report: &Value) -> Result<BTreeMap<String, String>, String> {
    let profiles = report["profiles"]
        .as_array()
        .ok_or("not a canif report.json: no \"profiles\"")?;
    let mut all = BTreeMap::new();
    for profile in profiles {
        let name = profile["profile"].as_str().unwrap_or("?");
        for (id, verdict) in profile["verdicts"].as_object().into_iter().flatten() {
            all.insert(
                format!("{name} :: {id}"),
                verdict["verdict"].as_str().unwrap_or("?").to_string(),
            );
        }
    }
    for scenario in report["scenarios"].as_array().into_iter().flatten() {
        let key = format!(
            "{} :: {}:{} {}",
            scenario["suite"].as_str().unwrap_or("?"),
            scenario["file"].as_str().unwrap_or("?"),
            scenario["line"],
            scenario["name"].as_str().unwrap_or("")
        );
        all.insert(key, scenario["outcome"].as_str().unwrap_or("?").to_string());
    }
    Ok(all)
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
