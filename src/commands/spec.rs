//! `canif spec …` and `canif profiles`: the catalogue, read.

use std::path::Path;
use std::process::ExitCode;

use crate::stop::{stop, Stop};

use canif_harness::device::suite::Options;
use canif_spec::{coverage, Catalogue, Status, Verification};

use crate::cli::SpecCommand;

pub(crate) fn spec(
    catalogue: &Catalogue,
    command: SpecCommand,
    out: &mut String,
) -> Result<ExitCode, Stop> {
    match command {
        SpecCommand::List { area } => {
            for r in catalogue
                .requirements()
                .filter(|r| area.as_ref().is_none_or(|a| r.id.starts_with(a.as_str())))
            {
                outln!(
                    out,
                    "{:<12} {:<10} {}",
                    r.id,
                    format!("{:?}", r.status).to_lowercase(),
                    r.statement
                );
            }
        }
        SpecCommand::Show { id } => {
            let Some(r) = catalogue.requirement(&id) else {
                let near =
                    super::did_you_mean(&id, catalogue.requirements().map(|r| r.id.as_str()));
                return Err(stop!(
                    "no requirement `{id}`{near}; `canif spec list` lists them"
                ));
            };
            outln!(out, "{}  [{:?}]  {}:{}", r.id, r.status, r.file, r.line);
            outln!(out, "  {}", r.statement);
            // A document by its title and edition, the file it is kept in after it.
            match catalogue.sources.iter().find(|s| s.file == r.source.file) {
                Some(document) => outln!(
                    out,
                    "  source: {}, {} ({})",
                    document.title,
                    r.source.section,
                    r.source.file
                ),
                None => outln!(out, "  source: {} {}", r.source.file, r.source.section),
            }
            if !r.capabilities.is_empty() {
                outln!(out, "  needs: {}", r.capabilities.join(", "));
            }
            for id in &r.rulings {
                match catalogue.rulings.iter().find(|ruling| ruling.id == *id) {
                    Some(ruling) => {
                        outln!(out, "  ruling {id}: {}", ruling.title);
                        if let Some(text) = &ruling.text {
                            outln!(out, "    {text}");
                        }
                    }
                    None => outln!(out, "  ruling {id}"),
                }
            }
            // Coverage is read from the tests where they are (the workspace), never kept by hand.
            if let Ok(sources) = coverage::test_sources(Path::new(".")) {
                let found = coverage::coverage(catalogue, &sources);
                for (file, line) in found.covered_by.get(&r.id).into_iter().flatten() {
                    outln!(out, "  covered by: {file}:{line}");
                }
            }
            let reason_label = match r.verification {
                Verification::Model => "checked on the reference model",
                _ => "not tested because",
            };
            for (label, text) in [
                ("document says", &r.document_says),
                ("corrected", &r.corrected),
                ("notes", &r.notes),
                (reason_label, &r.reason),
            ] {
                if let Some(text) = text {
                    outln!(out, "  {label}: {}", text.trim());
                }
            }
        }
        SpecCommand::Summary => summary(catalogue, out),
        SpecCommand::Check => {
            outln!(
                out,
                "catalogue ok: {} requirements in {} areas, {} profiles, {} capabilities",
                catalogue.requirements().count(),
                catalogue.areas.len(),
                catalogue.profiles.len(),
                catalogue.capabilities.len()
            );
        }
        SpecCommand::Plan { out: dir } => return super::plan::write(catalogue, &dir, out),
        SpecCommand::Coverage { root, each } => return spec_coverage(catalogue, &root, each, out),
    }
    Ok(ExitCode::SUCCESS)
}

pub(crate) fn summary(catalogue: &Catalogue, out: &mut String) {
    outln!(
        out,
        "{:<8} {:>9} {:>8} {:>10} {:>6}  title",
        "area",
        "normative",
        "derived",
        "assumption",
        "total"
    );
    let mut totals = [0usize; 3];
    for area in &catalogue.areas {
        let count = |status| {
            area.requirements
                .iter()
                .filter(|r| r.status == status)
                .count()
        };
        let counts = [
            count(Status::Normative),
            count(Status::Derived),
            count(Status::Assumption),
        ];
        for (total, n) in totals.iter_mut().zip(counts) {
            *total += n;
        }
        outln!(
            out,
            "{:<8} {:>9} {:>8} {:>10} {:>6}  {}",
            area.area,
            counts[0],
            counts[1],
            counts[2],
            area.requirements.len(),
            area.title
        );
    }
    outln!(
        out,
        "{:<8} {:>9} {:>8} {:>10} {:>6}",
        "all",
        totals[0],
        totals[1],
        totals[2],
        totals.iter().sum::<usize>()
    );
    let verified = |how: Verification| -> String {
        let ids: Vec<&str> = catalogue
            .requirements()
            .filter(|r| r.verification == how)
            .map(|r| r.id.as_str())
            .collect();
        ids.join(", ")
    };
    outln!(
        out,
        "\nchecked by inspection, not by tests: {}",
        verified(Verification::Inspection)
    );
    outln!(
        out,
        "checked on the reference model (no implementation shows them): {}",
        verified(Verification::Model)
    );
}

pub(crate) fn spec_coverage(
    catalogue: &Catalogue,
    root: &Path,
    each: bool,
    out: &mut String,
) -> Result<ExitCode, Stop> {
    let sources = match coverage::test_sources(root) {
        Ok(sources) if !sources.is_empty() => sources,
        Ok(_) => {
            return Err(stop!(
                "no test sources under {} (run from the workspace root or pass --root)",
                root.display()
            ));
        }
        Err(error) => {
            return Err(stop!("cannot read tests under {}: {error}", root.display()));
        }
    };
    let result = coverage::coverage(catalogue, &sources);
    if each {
        for r in catalogue.requirements() {
            let places: Vec<String> = result
                .covered_by
                .get(&r.id)
                .into_iter()
                .flatten()
                .map(|(file, line)| format!("{file}:{line}"))
                .collect();
            let status = format!("{:?}", r.status).to_lowercase();
            let how = if r.verification == Verification::Inspection {
                "inspection".to_string()
            } else {
                places.join(" ")
            };
            outln!(
                out,
                "{:<11} {:<10} {}",
                r.id,
                status,
                if how.is_empty() { "-" } else { &how }
            );
        }
        outln!(out);
    }
    let in_runs = canif_harness::device::suite::exercised(
        &canif_model::config::Capabilities::everything(),
        &Options::default(),
    );
    outln!(
        out,
        "{:<8} {:>9} {:>13}  title",
        "area",
        "by tests",
        "in IUT runs"
    );
    for area in &catalogue.areas {
        let needing: Vec<_> = area
            .requirements
            .iter()
            .filter(|r| r.needs_coverage())
            .collect();
        let covered = needing
            .iter()
            .filter(|r| result.covered_by.contains_key(&r.id))
            .count();
        let run = area
            .requirements
            .iter()
            .filter(|r| in_runs.contains(&r.id))
            .count();
        outln!(
            out,
            "{:<8} {:>4}/{:<4} {:>7}/{:<5}  {}",
            area.area,
            covered,
            needing.len(),
            run,
            area.requirements.len(),
            area.title
        );
    }
    outln!(out, "(by tests: normative and derived requirements named by a test's Covers: line; in IUT runs: any requirement a `canif run` scenario checks)");
    for problem in &result.problems {
        outln!(
            out,
            "{}:{}: {}",
            problem.file,
            problem.line,
            problem.message
        );
    }
    if result.uncovered.is_empty() && result.problems.is_empty() {
        outln!(
            out,
            "every normative and derived requirement is named by a test"
        );
        Ok(ExitCode::SUCCESS)
    } else {
        outln!(out, "not covered: {}", result.uncovered.join(", "));
        Ok(ExitCode::from(1))
    }
}

pub(crate) fn profiles(catalogue: &Catalogue, out: &mut String) -> Result<ExitCode, Stop> {
    for profile in &catalogue.profiles {
        outln!(out, "{:<22} {}", profile.name, profile.device);
        outln!(
            out,
            "{:<22} offers: {}; slots ≤ {}; Rx queue {} messages{}",
            "",
            profile.capabilities.join(", "),
            profile.max_slots,
            profile.rx_queue_depth,
            if profile.transaction_number_only_ext29 {
                "; transaction number only in 29-bit mode"
            } else {
                ""
            }
        );
    }
    Ok(ExitCode::SUCCESS)
}
