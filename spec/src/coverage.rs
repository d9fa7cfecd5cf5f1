//! Which requirements the tests name.
//!
//! A test names what it checks in a marker line right above it, read here from
//! the test sources (not from a hand-kept list):
//!
//! ```text
//! /// Covers: HS-TX-001, HS-TX-005
//! #[test]
//! fn …
//! ```
//!
//! A marker must be followed (after further doc comments or attributes) by a
//! `#[test]`, `fn` or `proptest!` item, so it cannot float free.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use crate::catalogue::Catalogue;

/// A marker in a file: the ids and where they stand.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Marker {
    pub file: String,
    pub line: usize,
    pub ids: Vec<String>,
}

/// A marker whose ids are not in the catalogue, or that stands before no test.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MarkerProblem {
    pub file: String,
    pub line: usize,
    pub message: String,
}

/// Reads the `Covers:` markers of one source file, or the `@ID` tags of a
/// Gherkin feature (tags with a `-` name requirements; others are capabilities
/// and run modes).
pub fn markers(file: &str, text: &str) -> (Vec<Marker>, Vec<MarkerProblem>) {
    if file.ends_with(".feature") {
        let found = text
            .lines()
            .enumerate()
            .filter(|(_, line)| line.trim_start().starts_with('@'))
            .map(|(index, line)| Marker {
                file: file.into(),
                line: index + 1,
                ids: line
                    .split_whitespace()
                    .filter_map(|tag| tag.strip_prefix('@'))
                    .filter(|tag| tag.contains('-'))
                    .map(String::from)
                    .collect(),
            })
            .filter(|marker| !marker.ids.is_empty())
            .collect();
        return (found, Vec::new());
    }
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    let mut problems = Vec::new();
    for (index, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let Some(rest) = trimmed
            .strip_prefix("/// Covers:")
            .or_else(|| trimmed.strip_prefix("// Covers:"))
        else {
            continue;
        };
        let ids: Vec<String> = rest
            .split(',')
            .map(|id| id.trim().to_string())
            .filter(|id| !id.is_empty())
            .collect();
        let next_item = lines[index + 1..]
            .iter()
            .map(|l| l.trim_start())
            .find(|l| !(l.starts_with("///") || l.starts_with("//")));
        let before_test = next_item.is_some_and(|l| {
            l.starts_with("#[") || l.starts_with("fn ") || l.starts_with("proptest!")
        });
        if !before_test {
            problems.push(MarkerProblem {
                file: file.into(),
                line: index + 1,
                message: "a Covers: marker must stand right above a test".into(),
            });
        }
        found.push(Marker {
            file: file.into(),
            line: index + 1,
            ids,
        });
    }
    (found, problems)
}

/// Coverage of the catalogue by markers.
#[derive(Debug, Clone, Default)]
pub struct Coverage {
    /// Requirement id → where it is named.
    pub covered_by: BTreeMap<String, Vec<(String, usize)>>,
    /// Requirements that need coverage and have none.
    pub uncovered: Vec<String>,
    pub problems: Vec<MarkerProblem>,
}

/// Matches markers in `sources` (path, text) against the catalogue.
pub fn coverage(catalogue: &Catalogue, sources: &[(String, String)]) -> Coverage {
    let known: BTreeSet<&str> = catalogue.requirements().map(|r| r.id.as_str()).collect();
    let mut result = Coverage::default();
    for (file, text) in sources {
        let (found, problems) = markers(file, text);
        result.problems.extend(problems);
        for marker in found {
            for id in &marker.ids {
                if known.contains(id.as_str()) {
                    result
                        .covered_by
                        .entry(id.clone())
                        .or_default()
                        .push((marker.file.clone(), marker.line));
                } else {
                    result.problems.push(MarkerProblem {
                        file: marker.file.clone(),
                        line: marker.line,
                        message: format!("`{id}` is not a requirement of the catalogue"),
                    });
                }
            }
        }
    }
    result.uncovered = catalogue
        .requirements()
        .filter(|r| r.needs_coverage() && !result.covered_by.contains_key(&r.id))
        .map(|r| r.id.clone())
        .collect();
    result
}

/// The test sources of a workspace: every `<member>/tests/*.rs` and
/// `features/*.feature`, paths shown relative to `root`.
pub fn test_sources(root: &Path) -> std::io::Result<Vec<(String, String)>> {
    let mut members: Vec<_> = std::fs::read_dir(root)?
        .filter_map(|entry| entry.ok().map(|entry| entry.path()))
        .collect();
    members.push(root.to_path_buf());
    members.sort();
    let mut sources = Vec::new();
    for member in members {
        // Feature files sit in features/ itself; Rust tests in <member>/tests/.
        let folders = [member.join("tests"), member.clone()];
        let mut paths: Vec<_> = folders
            .iter()
            .filter_map(|folder| std::fs::read_dir(folder).ok())
            .flatten()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                let in_tests = p.parent().is_some_and(|d| d.ends_with("tests"));
                (in_tests && p.extension().is_some_and(|x| x == "rs"))
                    || p.extension().is_some_and(|x| x == "feature")
            })
            .collect();
        paths.sort();
        for path in paths {
            let text = std::fs::read_to_string(&path)?;
            let shown = path
                .strip_prefix(root)
                .unwrap_or(&path)
                .display()
                .to_string();
            sources.push((shown, text));
        }
    }
    Ok(sources)
}
