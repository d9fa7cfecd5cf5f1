//! Every requirement id the code names — in a blame table, a scenario's list,
//! a fault's target, a step, a model type's `Requirements:` line — is in the
//! catalogue. A renamed or mistyped id fails here, not silently in a report.

use std::path::{Path, PathBuf};

use canif_spec::Catalogue;

/// The shape of a catalogue id: `HS-TX-002`, `LAY-11-004`, `FD-001`, `ERR-R5`.
fn looks_like_id(text: &str) -> bool {
    let Some((head, tail)) = text.rsplit_once('-') else {
        return false;
    };
    let number = (tail.len() == 3 && tail.bytes().all(|b| b.is_ascii_digit()))
        || (tail.len() == 2 && tail.starts_with('R') && tail.as_bytes()[1].is_ascii_digit());
    number
        && head.starts_with(|c: char| c.is_ascii_uppercase())
        && head.split('-').all(|part| {
            !part.is_empty()
                && part
                    .bytes()
                    .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit())
        })
}

/// Ids named in one source file: string literals of an id's shape, and the
/// ids of `Requirements:` doc lines. Returns (line, id).
fn named_ids(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (n, line) in text.lines().enumerate() {
        for literal in line.split('"').skip(1).step_by(2) {
            if looks_like_id(literal) {
                found.push((n + 1, literal.to_string()));
            }
        }
        if let Some(list) = line.trim_start().strip_prefix("/// Requirements:") {
            // `A, B` and ranges `A..B` (both ends named); a list may wrap.
            let items = list.split(',').flat_map(|item| item.split(".."));
            for id in items.map(|id| id.trim().trim_end_matches('.')) {
                if !id.is_empty() {
                    found.push((n + 1, id.to_string()));
                }
            }
        }
    }
    found
}

fn rust_files(dir: &Path, into: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, into);
        } else if path.extension().is_some_and(|e| e == "rs") {
            into.push(path);
        }
    }
}

#[test]
fn every_id_named_in_code_is_in_the_catalogue() {
    let catalogue = Catalogue::embedded().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let mut files = Vec::new();
    for dir in [
        "src",
        "harness/src",
        "features/src",
        "softdevice/src",
        "model/src",
        "spec/src",
    ] {
        rust_files(&root.join(dir), &mut files);
    }
    let mut named = 0;
    let mut unknown = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (line, id) in named_ids(&text) {
            named += 1;
            if catalogue.requirement(&id).is_none() {
                let file = file.strip_prefix(root).unwrap_or(file).display();
                unknown.push(format!("{file}:{line}: {id}"));
            }
        }
    }
    assert!(
        named > 300,
        "only {named} ids found: is the scan still reading the code?"
    );
    assert!(
        unknown.is_empty(),
        "ids the catalogue does not have:\n{}",
        unknown.join("\n")
    );
}

#[test]
fn the_scan_sees_literals_and_requirement_lines_but_not_other_numbers() {
    let source = "const A: &[ReqId] = req_ids![\"HS-TX-002\", \"NO-SUCH-999\"];\n\
                  /// Requirements: LAY-GEN-002, TN-002..TN-004,\n\
                  let sha = \"SHA256\"; let v = \"v1-002x\"; let r = \"ERR-R5\";\n";
    let ids: Vec<String> = named_ids(source).into_iter().map(|(_, id)| id).collect();
    assert_eq!(
        ids,
        [
            "HS-TX-002",
            "NO-SUCH-999",
            "LAY-GEN-002",
            "TN-002",
            "TN-004",
            "ERR-R5"
        ]
    );
}
