//! The catalogue loads, is complete where the issue demands, and its loader
//! names file, line and field for every kind of mistake.

use canif_spec::{Catalogue, Status};

fn files(overrides: &[(&str, &str)]) -> Vec<(String, String)> {
    let base = [
        ("spec/sources.yaml", "- {file: a.txt, title: A}\n"),
        ("spec/capabilities.yaml", "- {name: ext29, description: x}\n- {name: base11, description: y}\n"),
        ("spec/rulings.yaml", "- {id: R1, title: t}\n"),
        (
            "spec/requirements/x.yaml",
            "area: X\ntitle: X\nrequirements:\n  - id: X-001\n    statement: s\n    source: {file: a.txt, section: '1'}\n    status: normative\n",
        ),
        (
            "spec/profiles/p.yaml",
            "name: p\ndevice: d\nsource: {file: a.txt, section: '2'}\ncapabilities: [base11]\nmax_slots: 32\nrx_queue_depth: 150\ntx_queue_depth: 64\ntimestamp_tolerance_ns: 1000\n",
        ),
    ];
    base.iter()
        .map(|(path, text)| {
            let text = overrides
                .iter()
                .find(|(p, _)| p == path)
                .map_or(*text, |(_, t)| *t);
            (path.to_string(), text.to_string())
        })
        .collect()
}

fn errors(overrides: &[(&str, &str)]) -> Vec<String> {
    match Catalogue::from_files(&files(overrides)) {
        Ok(_) => Vec::new(),
        Err(errors) => errors.0.iter().map(ToString::to_string).collect(),
    }
}

#[test]
fn the_minimal_catalogue_is_valid() {
    assert_eq!(errors(&[]), Vec::<String>::new());
}

#[test]
fn the_embedded_catalogue_loads_and_is_large() {
    let catalogue = Catalogue::embedded().unwrap();
    assert!(catalogue.requirements().count() > 80);
    assert_eq!(catalogue.profiles.len(), 9);
    for status in [Status::Normative, Status::Derived, Status::Assumption] {
        assert!(catalogue.requirements().any(|r| r.status == status));
    }
}

#[test]
fn the_folder_on_disk_equals_the_embedded_catalogue() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let on_disk = Catalogue::load_dir(dir).unwrap();
    let embedded = Catalogue::embedded().unwrap();
    let ids = |c: &Catalogue| c.requirements().map(|r| r.id.clone()).collect::<Vec<_>>();
    assert_eq!(ids(&on_disk), ids(&embedded));
    assert_eq!(on_disk.profiles.len(), embedded.profiles.len());
}

#[test]
fn every_ruling_r1_to_r8_is_an_erratum_entry() {
    let catalogue = Catalogue::embedded().unwrap();
    for n in 1..=8 {
        let entry = catalogue
            .requirement(&format!("ERR-R{n}"))
            .unwrap_or_else(|| panic!("ERR-R{n} missing"));
        assert!(
            entry.is_erratum() && entry.corrected.is_some(),
            "ERR-R{n} names the text and the correction"
        );
        assert!(entry.rulings.contains(&format!("R{n}")));
    }
}

#[test]
fn unknown_keys_name_file_line_and_field() {
    let bad = "area: X\ntitle: X\nrequirements:\n  - id: X-001\n    statement: s\n    colour: red\n    source: {file: a.txt, section: '1'}\n    status: normative\n";
    let errors = errors(&[("spec/requirements/x.yaml", bad)]);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].starts_with(
            "spec/requirements/x.yaml:6: field `requirements[0].colour`: unknown field `colour`"
        ),
        "{}",
        errors[0]
    );
}

#[test]
fn a_misspelt_status_names_its_line() {
    let bad = "area: X\ntitle: X\nrequirements:\n  - id: X-001\n    statement: s\n    source: {file: a.txt, section: '1'}\n    status: normativ\n";
    let errors = errors(&[("spec/requirements/x.yaml", bad)]);
    assert!(errors[0].starts_with("spec/requirements/x.yaml:7: field `requirements[0].status`: unknown variant `normativ`"), "{errors:?}");
}

#[test]
fn duplicates_unknown_names_and_dangling_references() {
    let bad = "area: X\ntitle: X\nrequirements:\n  - id: X-001\n    statement: s\n    source: {file: a.txt, section: '1'}\n    status: normative\n    capabilities: [warp]\n    rulings: [R9]\n    related: [X-404]\n  - id: X-001\n    statement: s\n    source: {file: b.txt, section: '1'}\n    status: derived\n";
    let errors = errors(&[("spec/requirements/x.yaml", bad)]);
    let expect = [
        "spec/requirements/x.yaml:8: field `X-001.capabilities`: unknown capability `warp`",
        "spec/requirements/x.yaml:9: field `X-001.rulings`: unknown ruling `R9`",
        "spec/requirements/x.yaml:10: field `X-001.related`: `X-404` names no requirement",
        "spec/requirements/x.yaml:11: field `X-001.id`: duplicate id, first at spec/requirements/x.yaml:4",
        "spec/requirements/x.yaml:13: field `X-001.source.file`: `b.txt` is not in sources.yaml",
    ];
    for expected in expect {
        assert!(
            errors.iter().any(|e| e.starts_with(expected)),
            "missing {expected:?} in {errors:#?}"
        );
    }
}

#[test]
fn profile_mistakes() {
    let bad = "name: p\ndevice: d\nsource: {file: a.txt, section: '2'}\ncapabilities: [base11, fd]\nmax_slots: 40\nrx_queue_depth: 150\ntx_queue_depth: 8\ntimestamp_tolerance_ns: 1000\ntransaction_number_only_ext29: true\n";
    let errors = errors(&[("spec/profiles/p.yaml", bad)]);
    for expected in [
        "spec/profiles/p.yaml:4: field `capabilities`: unknown capability `fd`",
        "spec/profiles/p.yaml:5: field `max_slots`: 40 is outside 1..=32",
        "spec/profiles/p.yaml:7: field `tx_queue_depth`",
        "spec/profiles/p.yaml:9: field `transaction_number_only_ext29`",
    ] {
        assert!(
            errors.iter().any(|e| e.starts_with(expected)),
            "missing {expected:?} in {errors:#?}"
        );
    }
}

#[test]
fn inspection_needs_a_reason_and_errata_both_texts() {
    let bad = "area: X\ntitle: X\nrequirements:\n  - id: X-001\n    statement: s\n    source: {file: a.txt, section: '1'}\n    status: normative\n    verification: inspection\n  - id: X-002\n    statement: s\n    source: {file: a.txt, section: '1'}\n    status: derived\n    document_says: 'x'\n";
    let errors = errors(&[("spec/requirements/x.yaml", bad)]);
    assert!(
        errors.iter().any(|e| e.contains("X-001.reason")
            && e.contains("inspection and model verification need a reason")),
        "{errors:#?}"
    );
    assert!(
        errors.iter().any(|e| e.contains("X-002.corrected")),
        "{errors:#?}"
    );
}

#[test]
fn a_missing_folder_is_named() {
    let error = Catalogue::load_dir(std::path::Path::new("/nonexistent/spec")).unwrap_err();
    assert!(
        error
            .to_string()
            .contains("/nonexistent/spec/sources.yaml: cannot read"),
        "{error}"
    );
}

/// A folder on disk holding the minimal catalogue, with `overrides` as raw bytes.
fn folder(name: &str, overrides: &[(&str, Vec<u8>)]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-spec-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for (path, text) in files(&[]) {
        let target = dir.join(path.strip_prefix("spec/").unwrap());
        std::fs::create_dir_all(target.parent().unwrap()).unwrap();
        let bytes = overrides
            .iter()
            .find(|(p, _)| *p == path)
            .map_or(text.into_bytes(), |(_, b)| b.clone());
        std::fs::write(target, bytes).unwrap();
    }
    dir
}

#[test]
fn a_file_that_starts_with_a_byte_order_mark_loads() {
    let mut bytes = "\u{FEFF}".as_bytes().to_vec();
    bytes.extend_from_slice(files(&[])[3].1.as_bytes());
    let dir = folder("bom", &[("spec/requirements/x.yaml", bytes)]);
    let catalogue = Catalogue::load_dir(&dir).unwrap();
    assert_eq!(catalogue.requirement("X-001").unwrap().line, 4);
}

#[test]
fn a_fifo_named_yaml_is_refused_not_waited_for() {
    let dir = folder("fifo", &[]);
    let fifo = dir.join("requirements/stuck.yaml");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let errors = Catalogue::load_dir(&dir).unwrap_err().to_string();
    assert!(
        errors.contains("stuck.yaml") && errors.contains("not a regular file"),
        "{errors}"
    );
}

#[test]
fn deep_nesting_and_aliases_are_refused_with_their_line() {
    let deep = format!("area: X\ntitle: X\nrequirements: {}\n", "[".repeat(100_000));
    let found = errors(&[("spec/requirements/x.yaml", &deep)]);
    assert!(
        found
            .iter()
            .any(|e| e.contains("x.yaml:3") && e.contains("nest deeper than 64")),
        "{found:?}"
    );
    let aliases = "area: X\ntitle: &t X\nrequirements:\n  - id: X-001\n    statement: *t\n    source: {file: a.txt, section: '1'}\n    status: normative\n";
    let found = errors(&[("spec/requirements/x.yaml", aliases)]);
    assert!(
        found
            .iter()
            .any(|e| e.contains("x.yaml:2") && e.contains("anchors and aliases")),
        "{found:?}"
    );
    // '&' and '*' inside text are text.
    let text = "area: X\ntitle: R&D * 2\nrequirements:\n  - id: X-001\n    statement: 'a & b, *c'\n    source: {file: a.txt, section: '1'}\n    status: normative\n";
    assert_eq!(
        errors(&[("spec/requirements/x.yaml", text)]),
        Vec::<String>::new()
    );
}

/// 40,000 requirements in one file: each gets its own line (the lookup that
/// assigns them runs once over the file; `cargo bench` is where speed is measured).
#[test]
fn a_large_area_gets_every_line_right() {
    let mut text = String::from("area: X\ntitle: X\nrequirements:\n");
    for n in 0..40_000 {
        text.push_str(&format!(
            "  - id: X-{n:05}\n    statement: s\n    source: {{file: a.txt, section: '1'}}\n    status: assumption\n    notes: generated\n"
        ));
    }
    let mut all = files(&[]);
    all[3].1 = text;
    let catalogue = Catalogue::from_files(&all).unwrap();
    assert_eq!(catalogue.requirements().count(), 40_000);
    assert_eq!(
        catalogue.requirement("X-39999").unwrap().line,
        4 + 5 * 39_999
    );
}

/// A requirement that rests on a ruling cites one a reader can find: a
/// RULINGS.md source names a ruling of `spec/rulings.yaml` first, and no note
/// cites a decision ("D8", "D10") that exists only in a session's notes
/// (issue 26: INFO-009 cited "new gap D10").
#[test]
fn every_ruling_a_requirement_cites_can_be_found() {
    let catalogue = Catalogue::embedded().unwrap();
    let rulings: Vec<&str> = catalogue.rulings.iter().map(|r| r.id.as_str()).collect();
    let decision = |text: &str| {
        text.split(|c: char| !c.is_ascii_alphanumeric())
            .any(|word| {
                word.len() >= 2
                    && word.starts_with('D')
                    && word[1..].chars().all(|c| c.is_ascii_digit())
            })
    };
    for requirement in catalogue.requirements() {
        if requirement.source.file == "RULINGS.md" {
            let first = requirement
                .source
                .section
                .split(|c: char| !c.is_ascii_alphanumeric())
                .next()
                .unwrap_or_default();
            assert!(
                rulings.contains(&first),
                "{}: cites RULINGS.md section {:?}, which names no ruling",
                requirement.id,
                requirement.source.section
            );
        }
        for text in [Some(&requirement.statement), requirement.notes.as_ref()]
            .into_iter()
            .flatten()
        {
            assert!(
                !decision(text),
                "{} cites a decision no reader can find: {text}",
                requirement.id
            );
        }
    }
}

/// Every seed document says which document wins where they differ (issue 26:
/// the catalogue followed 001 over 000 in places without saying so).
#[test]
fn every_seed_document_states_its_precedence() {
    let catalogue = canif_spec::Catalogue::embedded().unwrap();
    let silent: Vec<&str> = catalogue
        .sources
        .iter()
        .filter(|s| s.file.ends_with(".txt") && s.precedence.as_deref().is_none_or(str::is_empty))
        .map(|s| s.file.as_str())
        .collect();
    assert!(silent.is_empty(), "no precedence: {silent:?}");
    let manual = catalogue
        .sources
        .iter()
        .find(|s| s.file.starts_with("000_"))
        .unwrap();
    assert!(manual.precedence.as_deref().unwrap().contains("001 wins"));
}

/// The review of the catalogue against its sources (issue 26): what is
/// inferred is `derived`, a citation names the document that says it, and a
/// statement of the EL6751 on EtherCAT binds only the EL6751.
#[test]
fn the_reviewed_statements_say_what_their_sources_say() {
    use canif_spec::Status;
    let catalogue = canif_spec::Catalogue::embedded().unwrap();
    let requirement = |id: &str| catalogue.requirement(id).unwrap();
    for id in [
        "HS-TX-009",
        "BQ-004",
        "TIM-007",
        "INFO-001",
        "FD-BIT-003",
        "FD-BIT-004",
        "HB-001",
    ] {
        assert_eq!(requirement(id).status, Status::Derived, "{id} is inferred");
    }
    assert_eq!(requirement("HB-001").source.file, "CiA-301");
    assert_eq!(requirement("SDO-009").source.file, "CiA-301");
    // Issue 36: what canif decided is its assumption, and a citation names
    // the document that says it.
    for id in ["PROF-012", "HS-TX-012", "PROF-010", "FLT-003"] {
        assert_eq!(
            requirement(id).status,
            Status::Assumption,
            "{id} is canif's"
        );
    }
    assert_eq!(requirement("HB-003").source.file, "CiA-301");
    assert_eq!(requirement("CL-ORD-001").source.file, "RULINGS.md");
    assert!(requirement("TIM-007").statement.contains("CiA frame time"));
    assert!(requirement("TIM-007").statement.contains("safe figure"));
    assert!(!requirement("ERR-R5")
        .source
        .section
        .contains("keeps the NoOfTxMessages"));
    assert!(requirement("HS-RX-006").source.file.starts_with("000_"));
    assert_eq!(requirement("LAY-FD-004").status, Status::Assumption);
    assert!(requirement("LAY-GEN-008")
        .notes
        .as_deref()
        .is_some_and(|n| n.contains("RTR with EDL is added here")));
    for id in ["PDX-001", "PDX-002", "PDX-003"] {
        assert_eq!(requirement(id).capabilities, ["el6751"], "{id}");
    }
    let pdx004 = requirement("PDX-004");
    assert!(pdx004.statement.contains("output delay") && pdx004.rulings == ["R10"]);
}
