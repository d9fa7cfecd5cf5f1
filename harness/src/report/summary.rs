//! `summary.md`: the run for a CI page or a pull request.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use canif_spec::Catalogue;

use super::RunReport;
use crate::verdict::{CheckResult, VerdictKind};

/// Seconds since the Unix epoch as RFC 3339 in UTC.
pub fn utc(seconds: u64) -> String {
    chrono::DateTime::from_timestamp(seconds as i64, 0)
        .map_or_else(|| seconds.to_string(), |t| t.to_rfc3339())
}

impl RunReport {
    /// One line of metadata: what ran, against what, when, with which canif and catalogue.
    pub fn provenance(&self) -> String {
        let m = &self.meta;
        format!(
            "IUT `{}`{} ({} side, {:?} suite{}) on {}, seed {}, started {}, canif {} ({}), catalogue SHA-256 `{}`, {} ms",
            m.iut,
            m.product
                .as_ref()
                .map_or(String::new(), |p| format!(" — {} {}", p.name, p.version)),
            m.side,
            m.suite,
            if m.masters.is_empty() {
                String::new()
            } else {
                format!(", masters {}", m.masters.join(", "))
            },
            m.bus,
            m.seed,
            utc(m.started_unix),
            m.canif_version,
            m.canif_commit,
            m.catalogue_sha256,
            self.wall_time_ms
        )
    }

    /// The totals in words.
    pub fn totals_line(&self) -> String {
        self.totals()
            .iter()
            .map(|(kind, n)| format!("{n} {}", kind.label()))
            .collect::<Vec<_>>()
            .join(", ")
    }

    pub fn summary(&self, catalogue: &Catalogue) -> String {
        let mut md = format!(
            "# canif conformance run\n\n**{}**: {}.\n\n{}.\n",
            self.headline(),
            self.totals_line(),
            self.provenance()
        );
        if let Some(left_out) = &self.meta.left_out {
            let _ = writeln!(md, "\nLeft out: {left_out}.");
        }
        if let Some(shard) = self.meta.shard {
            let _ = writeln!(
                md,
                "\nShard {shard} of a campaign: the other shards run the rest, and `canif merge` joins their folders (each with its shard.json) into one verdict."
            );
        }
        if !self.meta.choices.is_empty() {
            let choices: Vec<String> = self.meta.choices.iter().map(ToString::to_string).collect();
            let _ = writeln!(
                md,
                "\nJudged by the choices the documents leave: {}.",
                choices.join("; ")
            );
        }
        if !self.meta.terminals.is_empty() {
            md.push_str("\n| EtherCAT terminal | identity (vendor, product, revision, serial) | SyncManagers 0–3 | process data out/in (CAN status) | 0x1C32:05 | idle cycles | period | missed | mean | worst |\n|---|---|---|---|---|---|---|---|---|---|\n");
            for t in &self.meta.terminals {
                let _ = writeln!(
                    md,
                    "| {} ({}) | {:#010x}, {:#010x}, {:#010x}, {} | {} | {}/{} ({}) | {} | {} | {} | {} | {} µs | {} µs |",
                    t.profile,
                    t.name,
                    t.vendor_id,
                    t.product_code,
                    t.revision,
                    t.serial,
                    t.layout(),
                    t.output_bytes,
                    t.input_bytes,
                    t.status_bytes,
                    t.local_cycle_ns
                        .map_or("not answered".into(), |ns| format!("{ns} ns")),
                    t.cycles,
                    t.period_ns
                        .map_or("unpaced".into(), |ns| format!("{} µs", ns / 1_000)),
                    t.missed_cycles,
                    t.mean_cycle_ns / 1_000,
                    t.worst_cycle_ns / 1_000
                );
            }
        }
        // The scenario counts are those the run's progress lines say.
        md.push_str("\n| profile | pass | fail | error | n/a | not run | not testable | scenarios | Gherkin scenarios | checks | cycles | frames checked |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for p in &self.profiles {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                p.profile,
                p.count(VerdictKind::Pass),
                p.count(VerdictKind::Fail),
                p.count(VerdictKind::Error),
                p.count(VerdictKind::NotApplicable),
                p.count(VerdictKind::NotRun),
                p.count(VerdictKind::NotTestable),
                p.ran.tally.scenarios,
                p.ran.tally.gherkin_scenarios,
                p.ran.checks.len(),
                p.ran.tally.cycles,
                p.ran.tally.frames_checked
            );
        }
        let not_served: Vec<String> = self
            .not_served()
            .iter()
            .map(|line| format!("- {line}"))
            .collect();
        if !not_served.is_empty() {
            md.push_str(
                "\n## Not applicable: what the implementation declares it does not serve\n\n",
            );
            md.push_str(&not_served.join("\n"));
            md.push('\n');
        }
        let advised: Vec<String> = self
            .profiles
            .iter()
            .filter(|p| !p.ran.advisories.is_empty())
            .map(|p| format!("- {}: {}", p.profile, p.ran.advisories.line()))
            .collect();
        if !advised.is_empty() {
            md.push_str("\n## Advisories (allowed, never a verdict)\n\n");
            md.push_str(&advised.join("\n"));
            md.push('\n');
        }
        let mut failing = self
            .problems(catalogue)
            .into_iter()
            .filter(|p| p.verdict.kind() == VerdictKind::Fail)
            .peekable();
        if !self.flaky.is_empty() {
            md.push_str("\n## Flaky: failed in the run before, pass now (never a pass)\n\n");
            for key in &self.flaky {
                let _ = writeln!(md, "- {key}");
            }
        }
        if failing.peek().is_some() {
            md.push_str("\n## Failing requirements\n\n");
            for problem in failing {
                let _ = writeln!(md, "- {problem}");
            }
        }
        for p in &self.profiles {
            for check in &p.ran.checks {
                let CheckResult::Fail(finding) = &check.result else {
                    continue;
                };
                let _ = write!(md, "\n## {} — {}\n\n", p.profile, check.evidence);
                for id in &finding.requirements {
                    if let Some(r) = catalogue.requirement(id) {
                        let _ = writeln!(md, "- **{id}**: {}", r.statement);
                    }
                }
                let _ = write!(md, "\n```\n{}\n```\n", finding.details);
            }
        }
        let errors = self.errors_by_cause();
        if !errors.is_empty() {
            md.push_str("\n## Errors\n\n");
            for (cause, checks) in errors {
                let _ = writeln!(
                    md,
                    "- {} check(s), first `{}`: {cause}",
                    checks.len(),
                    checks[0]
                );
            }
        }
        // The documents by title and edition: a requirement's source names
        // the file it is kept in.
        md.push_str("\n## Sources\n\n| document | kept as |\n|---|---|\n");
        for source in &catalogue.sources {
            let _ = writeln!(md, "| {} | `{}` |", source.title, source.file);
        }
        md
    }

    /// Checks that could not run, grouped by their cause (a broken IUT is one
    /// entry, not one per scenario).
    pub fn errors_by_cause(&self) -> BTreeMap<String, Vec<String>> {
        let mut grouped: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for (profile, check) in self.checks() {
            if let CheckResult::Error(cause) = &check.result {
                grouped
                    .entry(cause.lines().next().unwrap_or_default().to_string())
                    .or_default()
                    .push(format!("{}: {}", profile.profile, check.evidence));
            }
        }
        grouped
    }
}
