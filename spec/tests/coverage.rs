//! Every normative and derived requirement is named by a test, read from the
//! tests themselves (the `Covers:` markers), never from a hand-kept list.

use canif_spec::coverage::{coverage, markers, test_sources};
use canif_spec::Catalogue;

#[test]
fn every_normative_and_derived_requirement_is_covered() {
    let catalogue = Catalogue::embedded().unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap();
    let sources = test_sources(root).unwrap();
    assert!(
        sources.len() > 10,
        "found the workspace's tests: {}",
        sources.len()
    );
    let result = coverage(&catalogue, &sources);
    let problems: Vec<String> = result
        .problems
        .iter()
        .map(|p| format!("{}:{}: {}", p.file, p.line, p.message))
        .collect();
    assert!(
        problems.is_empty(),
        "marker problems:\n{}",
        problems.join("\n")
    );
    assert!(
        result.uncovered.is_empty(),
        "no test names: {}",
        result.uncovered.join(", ")
    );
}

#[test]
fn markers_must_stand_above_a_test_and_name_known_ids() {
    let source =
        "/// Covers: X-001, X-002\n#[test]\nfn a() {}\n\n// Covers: X-003\nlet floating = 1;\n";
    let (found, problems) = markers("t.rs", source);
    assert_eq!(found.len(), 2);
    assert_eq!(found[0].ids, ["X-001", "X-002"]);
    assert_eq!(problems.len(), 1);
    assert_eq!(problems[0].line, 5);

    let catalogue = Catalogue::embedded().unwrap();
    let result = coverage(
        &catalogue,
        &[(
            "t.rs".into(),
            "/// Covers: HS-TX-001, NOPE-001\n#[test]\nfn t() {}\n".into(),
        )],
    );
    assert!(result.covered_by.contains_key("HS-TX-001"));
    assert!(result
        .problems
        .iter()
        .any(|p| p.message.contains("NOPE-001")));
    assert!(
        result.uncovered.contains(&"HS-TX-002".to_string()),
        "one marker does not cover the rest"
    );
}
