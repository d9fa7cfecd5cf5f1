//! `canif run --rerun-failed [REPORT]`: only what failed or erred in a
//! report, on the profiles it failed on; and a check that failed there and
//! passes now is flaky, reported as such and never as a pass.

use std::path::{Path, PathBuf};

use canif_harness::report::{ProfileReport, ReportFile};
use canif_harness::verdict::{CheckResult, VerdictKind};

use crate::error::RerunError;

/// What a report said failed: `(profile, check key)`.
#[derive(Debug, Clone)]
pub struct Rerun {
    pub report: PathBuf,
    pub iut: String,
    pub failed: Vec<(String, String)>,
}

impl Rerun {
    /// The report's failing and erring checks, from a run of the same side.
    pub fn read(path: &Path, side: canif_spec::Side) -> Result<Self, RerunError> {
        let unreadable = |cause: String| RerunError::Unreadable {
            report: path.to_path_buf(),
            cause,
        };
        let text = std::fs::read_to_string(path).map_err(|e| unreadable(e.to_string()))?;
        let report = ReportFile::parse(&text).map_err(|e| unreadable(e.to_string()))?;
        if report.meta.side != side {
            return Err(RerunError::OtherSide {
                report: path.to_path_buf(),
                was: report.meta.side,
                this: side,
            });
        }
        let mut failed = Vec::new();
        for profile in &report.profiles {
            for check in &profile.checks {
                let key = (profile.profile.clone(), check.check.clone());
                if check.outcome.is_bad() && !failed.contains(&key) {
                    failed.push(key);
                }
            }
        }
        Ok(Rerun {
            report: path.to_path_buf(),
            iut: report.meta.iut,
            failed,
        })
    }

    /// The checks' names as `--scenario` takes them (without `scenario: `).
    pub fn scenarios(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .failed
            .iter()
            .map(|(_, key)| {
                key.split_once(": ")
                    .map_or(key.as_str(), |(_, n)| n)
                    .to_string()
            })
            .collect();
        names.sort();
        names.dedup();
        names
    }

    pub fn profiles(&self) -> Vec<String> {
        let mut names: Vec<String> = self.failed.iter().map(|(p, _)| p.clone()).collect();
        names.sort();
        names.dedup();
        names
    }

    /// The rerun is of the implementation the report was.
    pub fn same_iut(&self, iut: &str) -> Result<(), RerunError> {
        match self.iut == iut {
            true => Ok(()),
            false => Err(RerunError::OtherIut {
                report: self.report.clone(),
                was: self.iut.clone(),
                this: iut.to_string(),
            }),
        }
    }

    /// `profile::check` of every check that failed before and all of whose
    /// runs pass now.
    pub fn flaky(&self, profiles: &[ProfileReport]) -> Vec<String> {
        self.failed
            .iter()
            .filter(|(profile, key)| {
                let now: Vec<&CheckResult> = profiles
                    .iter()
                    .filter(|p| p.profile == *profile)
                    .flat_map(|p| &p.ran.checks)
                    .filter(|c| c.evidence.key() == *key)
                    .map(|c| &c.result)
                    .collect();
                !now.is_empty() && now.iter().all(|r| r.kind() == VerdictKind::Pass)
            })
            .map(|(profile, key)| format!("{profile}::{key}"))
            .collect()
    }
}
