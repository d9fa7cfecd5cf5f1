//! `junit.xml`, written by quick-junit: one suite of requirement verdicts and
//! one of checks per profile, with names that stay put when files are edited
//! (`profile::REQ-ID`; a check by its key) and counts that match the cases.

use std::collections::BTreeMap;
use std::time::Duration;

use canif_spec::Catalogue;
use quick_junit::{NonSuccessKind, Property, Report, TestCase, TestCaseStatus, TestSuite};

use super::RunReport;
use crate::verdict::{CheckResult, Evidence, Verdict};

impl RunReport {
    pub fn junit(&self, catalogue: &Catalogue) -> std::io::Result<String> {
        let mut report = Report::new(format!("canif {}", self.meta.iut));
        report.set_time(Duration::from_millis(self.wall_time_ms as u64));
        let properties = self.junit_properties();
        for profile in &self.profiles {
            let elapsed: BTreeMap<&Evidence, Duration> = profile
                .ran
                .checks
                .iter()
                .map(|c| (&c.evidence, c.elapsed))
                .collect();
            let mut verdicts = TestSuite::new(profile.profile.clone());
            verdicts.add_properties(properties.clone());
            for requirement in catalogue.requirements() {
                let Some(verdict) = profile.verdicts.get(&requirement.id) else {
                    continue;
                };
                let status = match verdict {
                    Verdict::Pass(_) => TestCaseStatus::success(),
                    Verdict::Fail(found) => {
                        let mut status = TestCaseStatus::non_success(NonSuccessKind::Failure);
                        status.set_message(verdict.reason().unwrap_or_default());
                        status.set_description(
                            found
                                .iter()
                                .map(|(evidence, finding)| {
                                    format!("{evidence}\n{}", finding.details)
                                })
                                .collect::<Vec<_>>()
                                .join("\n\n"),
                        );
                        status
                    }
                    Verdict::Error(_) => {
                        let mut status = TestCaseStatus::non_success(NonSuccessKind::Error);
                        status.set_message(verdict.reason().unwrap_or_default());
                        status
                    }
                    _ => {
                        let mut status = TestCaseStatus::skipped();
                        status.set_message(format!(
                            "{}: {}",
                            verdict.label(),
                            verdict.reason().unwrap_or_default()
                        ));
                        status
                    }
                };
                let mut case =
                    TestCase::new(format!("{}::{}", profile.profile, requirement.id), status);
                case.set_classname(format!("canif.{}", profile.profile));
                case.set_time(
                    verdict
                        .evidence()
                        .iter()
                        .filter_map(|e| elapsed.get(e))
                        .sum(),
                );
                let evidence: Vec<String> = verdict.evidence().iter().map(|e| e.key()).collect();
                if !evidence.is_empty() {
                    case.set_system_out(format!("evidence:\n{}", evidence.join("\n")));
                }
                verdicts.add_test_case(case);
            }
            report.add_test_suite(verdicts);
            let mut checks = TestSuite::new(format!("{} checks", profile.profile));
            checks.add_properties(properties.clone());
            for check in &profile.ran.checks {
                let status = match &check.result {
                    CheckResult::Pass => TestCaseStatus::success(),
                    CheckResult::Fail(finding) => {
                        let mut status = TestCaseStatus::non_success(NonSuccessKind::Failure);
                        status.set_message(format!(
                            "{} ({})",
                            finding.cause,
                            finding.requirements.join(", ")
                        ));
                        status.set_description(finding.details.clone());
                        status
                    }
                    CheckResult::Error(cause) => {
                        let mut status = TestCaseStatus::non_success(NonSuccessKind::Error);
                        status.set_message(cause.lines().next().unwrap_or_default().to_string());
                        status.set_description(cause.clone());
                        status
                    }
                };
                let mut case = TestCase::new(check.evidence.key(), status);
                case.set_classname(format!("canif.{}.checks", profile.profile));
                case.set_time(check.elapsed);
                checks.add_test_case(case);
            }
            report.add_test_suite(checks);
        }
        report.to_string().map_err(std::io::Error::other)
    }

    fn junit_properties(&self) -> Vec<Property> {
        let meta = &self.meta;
        let mut properties = vec![
            Property::new("iut", meta.iut.clone()),
            Property::new("bus", meta.bus.clone()),
            Property::new("seed", meta.seed.to_string()),
            Property::new("catalogue_sha256", meta.catalogue_sha256.clone()),
            Property::new("canif_version", meta.canif_version.clone()),
            Property::new("canif_commit", meta.canif_commit.clone()),
        ];
        if let Some(product) = &meta.product {
            properties.push(Property::new("product", product.name.clone()));
            properties.push(Property::new("product_version", product.version.clone()));
        }
        properties
    }
}
