//! Reports of a run: JUnit XML for CI, JSON for tools (`file`), Markdown
//! and HTML for people (`html`).

mod file;
mod html;

pub use file::{
    FailureEntry, ProfileEntry, ReportFile, RunEntry, ScenarioEntry, VerdictEntry, VerdictKind,
};
pub use html::{details, headline, timing_diagram};

use std::fmt::Write as _;
use std::path::Path;

use canif_spec::Catalogue;

use crate::outcome::Outcome;
use crate::suite::{ProfileRun, Verdict};

/// One Gherkin scenario (or Examples row) run against one profile.
#[derive(Debug, Clone)]
pub struct ScenarioResult {
    /// The profile, or `model` / `any-profile` for scenarios that run once.
    pub suite: String,
    pub name: String,
    pub file: String,
    pub line: usize,
    pub requirements: Vec<String>,
    /// `Err` holds cucumber's report of the failing step.
    pub outcome: Result<(), String>,
    /// The IUT broke during the scenario: an error, not a failure.
    pub error: bool,
}

/// What a whole run produced, and how it was asked for.
#[derive(Debug, Clone)]
pub struct RunReport {
    pub iut: String,
    pub seed: u64,
    pub bus: String,
    pub profiles: Vec<ProfileRun>,
    pub scenarios: Vec<ScenarioResult>,
    pub wall_time_ms: u128,
    /// The run was asked to stop (SIGINT, SIGTERM): it reports what ran.
    pub interrupted: bool,
}

/// Counts of verdicts over every requirement × profile.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Totals {
    pub pass: usize,
    pub fail: usize,
    pub error: usize,
    pub not_applicable: usize,
    pub not_testable: usize,
}

impl RunReport {
    pub fn totals(&self) -> Totals {
        let mut totals = Totals::default();
        for verdict in self.profiles.iter().flat_map(|p| p.verdicts.values()) {
            match verdict {
                Verdict::Pass => totals.pass += 1,
                Verdict::Fail(_) => totals.fail += 1,
                Verdict::Error(_) => totals.error += 1,
                Verdict::NotApplicable(_) => totals.not_applicable += 1,
                Verdict::NotTestable(_) => totals.not_testable += 1,
            }
        }
        totals
    }

    pub fn failed_scenarios(&self) -> usize {
        self.scenarios
            .iter()
            .filter(|s| s.outcome.is_err() && !s.error)
            .count()
    }

    pub fn scenario_errors(&self) -> usize {
        self.scenarios.iter().filter(|s| s.error).count()
    }

    /// 0 when everything conforms, 1 on any failure, 2 on any error, 130
    /// when interrupted.
    pub fn exit_code(&self) -> u8 {
        let totals = self.totals();
        if self.interrupted {
            130
        } else if totals.error > 0 || self.scenario_errors() > 0 {
            2
        } else if totals.fail > 0 || self.failed_scenarios() > 0 {
            1
        } else {
            0
        }
    }

    /// Writes `junit.xml`, `report.json` and `summary.md` into `dir`.
    pub fn write(&self, catalogue: &Catalogue, dir: &Path) -> std::io::Result<()> {
        std::fs::create_dir_all(dir)?;
        std::fs::write(dir.join("junit.xml"), self.junit(catalogue))?;
        std::fs::write(
            dir.join("report.json"),
            serde_json::to_string_pretty(&self.json(catalogue)).map_err(std::io::Error::other)?,
        )?;
        std::fs::write(dir.join("summary.md"), self.summary(catalogue))?;
        std::fs::write(dir.join("report.html"), self.html(catalogue))?;
        Ok(())
    }

    /// One testsuite per profile, one testcase per requirement.
    pub fn junit(&self, catalogue: &Catalogue) -> String {
        let mut xml = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        let totals = self.totals();
        let _ = writeln!(
            xml,
            "<testsuites name=\"canif {}\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\">",
            escape(&self.iut),
            totals.pass + totals.fail + totals.error + totals.not_applicable + totals.not_testable,
            totals.fail,
            totals.error,
            totals.not_applicable + totals.not_testable
        );
        for profile in &self.profiles {
            let count =
                |f: fn(&Verdict) -> bool| profile.verdicts.values().filter(|v| f(v)).count();
            let _ = writeln!(
                xml,
                "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\">",
                escape(&profile.profile),
                profile.verdicts.len(),
                count(|v| matches!(v, Verdict::Fail(_))),
                count(|v| matches!(v, Verdict::Error(_))),
                count(|v| matches!(v, Verdict::NotApplicable(_) | Verdict::NotTestable(_)))
            );
            for requirement in catalogue.requirements() {
                let Some(verdict) = profile.verdicts.get(&requirement.id) else {
                    continue;
                };
                let name = format!("{}: {}", requirement.id, requirement.statement);
                let _ = write!(
                    xml,
                    "    <testcase classname=\"{}\" name=\"{}\"",
                    escape(&profile.profile),
                    escape(&name)
                );
                match verdict {
                    Verdict::Pass => xml.push_str("/>\n"),
                    Verdict::Fail(indexes) => {
                        let first = &profile.failures[indexes[0]];
                        let _ = writeln!(
                            xml,
                            ">\n      <failure message=\"{}\">{}</failure>\n    </testcase>",
                            escape(&headline(first)),
                            escape(
                                &indexes
                                    .iter()
                                    .map(|i| details(&profile.failures[*i]))
                                    .collect::<Vec<_>>()
                                    .join("\n\n")
                            )
                        );
                    }
                    Verdict::Error(message) => {
                        let _ = writeln!(
                            xml,
                            ">\n      <error message=\"{}\"/>\n    </testcase>",
                            escape(message)
                        );
                    }
                    Verdict::NotApplicable(reason) | Verdict::NotTestable(reason) => {
                        let _ = writeln!(
                            xml,
                            ">\n      <skipped message=\"{}: {}\"/>\n    </testcase>",
                            verdict.label(),
                            escape(reason)
                        );
                    }
                }
            }
            xml.push_str("  </testsuite>\n");
        }
        let mut suites: Vec<&str> = self.scenarios.iter().map(|s| s.suite.as_str()).collect();
        suites.dedup();
        for suite in suites {
            let cases: Vec<&ScenarioResult> =
                self.scenarios.iter().filter(|s| s.suite == suite).collect();
            let _ = writeln!(
                xml,
                "  <testsuite name=\"features: {}\" tests=\"{}\" failures=\"{}\" errors=\"0\" skipped=\"0\">",
                escape(suite),
                cases.len(),
                cases.iter().filter(|c| c.outcome.is_err()).count()
            );
            for case in cases {
                let name = format!(
                    "{}:{}: {} ({})",
                    case.file,
                    case.line,
                    case.name,
                    case.requirements.join(", ")
                );
                let _ = write!(
                    xml,
                    "    <testcase classname=\"features.{}\" name=\"{}\"",
                    escape(suite),
                    escape(&name)
                );
                match &case.outcome {
                    Ok(()) => xml.push_str("/>\n"),
                    Err(report) if case.error => {
                        let _ = writeln!(
                            xml,
                            ">\n      <error message=\"the IUT broke\">{}</error>\n    </testcase>",
                            escape(report)
                        );
                    }
                    Err(report) => {
                        let _ = writeln!(xml, ">\n      <failure message=\"scenario failed\">{}</failure>\n    </testcase>", escape(report));
                    }
                }
            }
            xml.push_str("  </testsuite>\n");
        }
        xml.push_str("</testsuites>\n");
        xml
    }

    /// The run as `report.json` holds it.
    pub fn json(&self, catalogue: &Catalogue) -> ReportFile {
        ReportFile::new(self, catalogue)
    }

    pub fn summary(&self, catalogue: &Catalogue) -> String {
        let totals = self.totals();
        let mut md = format!(
            "# canif conformance run\n\nIUT `{}` on {}, seed {}, {} ms.\n\n**{}**: {} pass, {} fail, {} error, {} not applicable, {} not testable by a run.\n\n",
            self.iut,
            self.bus,
            self.seed,
            self.wall_time_ms,
            match self.exit_code() {
                0 => "CONFORMS",
                1 => "DOES NOT CONFORM",
                _ => "ERROR",
            },
            totals.pass,
            totals.fail,
            totals.error,
            totals.not_applicable,
            totals.not_testable
        );
        let _ = writeln!(
            md,
            "Gherkin scenarios: {} run, {} failed, {} error.\n",
            self.scenarios.len(),
            self.failed_scenarios(),
            self.scenario_errors()
        );
        md.push_str("| profile | pass | fail | error | n/a | not testable | cycles | frames checked |\n|---|---|---|---|---|---|---|---|\n");
        for p in &self.profiles {
            let count = |label: &str| p.verdicts.values().filter(|v| v.label() == label).count();
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} |",
                p.profile,
                count("pass"),
                count("fail"),
                count("error"),
                count("not applicable"),
                count("not testable"),
                p.cycles(),
                p.frames_checked()
            );
        }
        for scenario in self.scenarios.iter().filter(|s| s.outcome.is_err()) {
            let _ = write!(
                md,
                "\n## {} — scenario {}:{} {} ({})\n\n```\n{}\n```\n",
                scenario.suite,
                scenario.file,
                scenario.line,
                scenario.name,
                scenario.requirements.join(", "),
                scenario.outcome.as_ref().err().map_or("", String::as_str)
            );
        }
        for p in &self.profiles {
            for failure in &p.failures {
                let _ = write!(md, "\n## {} — {}\n\n", p.profile, headline(failure));
                for id in &failure.requirements {
                    if let Some(r) = catalogue.requirement(id.as_str()) {
                        let _ = writeln!(md, "- **{id}**: {}", r.statement);
                    }
                }
                let _ = write!(md, "\n```\n{}\n```\n", details(failure));
            }
            for run in &p.runs {
                if let Outcome::Error(message) = &run.outcome {
                    let _ = write!(
                        md,
                        "\n## {} — error in {}\n\n{message}\n",
                        p.profile, run.scenario
                    );
                }
            }
        }
        md
    }
}

fn escape(text: &str) -> String {
    text.chars()
        .map(|c| match c {
            '&' => "&amp;".to_string(),
            '<' => "&lt;".to_string(),
            '>' => "&gt;".to_string(),
            '"' => "&quot;".to_string(),
            '\'' => "&apos;".to_string(),
            c if (c as u32) < 0x20 && c != '\n' && c != '\t' => format!("&#{};", c as u32),
            c => c.to_string(),
        })
        .collect()
}
