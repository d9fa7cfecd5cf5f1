//! The PLC side judged on itself: the reference client conforms on every
//! profile under every master, the independent soft client too, and each
//! faulty client is caught on exactly the requirements it breaks.

use std::collections::BTreeSet;

use canif_harness::client::kill_table::KILL_TABLE;
use canif_harness::client::soft_client::ClientFault;
use canif_harness::client::suite::{ClientKind, ClientOptions};
use canif_harness::run::{kill_matrix, run_profile, unreached};
use canif_harness::Outcome;
use canif_spec::Catalogue;

fn options() -> ClientOptions {
    ClientOptions {
        counter_wrap: false,
        ..ClientOptions::new(1)
    }
}

/// Every scenario the client runs on every profile, failures in full.
fn problems(kind: &ClientKind, options: &ClientOptions) -> Vec<String> {
    let catalogue = Catalogue::embedded().unwrap();
    let mut bad = Vec::new();
    for profile in &catalogue.profiles {
        let run = run_profile(profile, kind, options, |_| {});
        assert!(
            run.runs.len() >= 25,
            "{}: {} runs",
            profile.name,
            run.runs.len()
        );
        bad.extend(run.runs.iter().filter_map(|r| match &r.outcome {
            Outcome::Pass => None,
            Outcome::Fail(f) => Some(format!("{}: {}", profile.name, f.details())),
            Outcome::Error(e) => Some(format!("{}: {}: {e}", profile.name, r.scenario)),
        }));
    }
    bad
}

/// Covers: CL-TX-001, CL-TX-002, CL-TX-003, CL-TX-004, CL-TX-005, CL-RX-001, CL-RX-002, CL-RX-003, CL-RX-004, CL-IMG-001, CL-FQ-001, CL-RST-001, CL-RST-002, CL-TN-001, CL-TN-002
#[test]
fn the_reference_client_conforms_on_every_profile_under_every_master() {
    let bad = problems(&ClientKind::Reference, &options());
    assert!(bad.is_empty(), "{}", bad.join("\n\n"));
}

#[test]
fn the_soft_client_without_a_fault_conforms_too() {
    let bad = problems(&ClientKind::Faulty(None), &options());
    assert!(bad.is_empty(), "{}", bad.join("\n\n"));
}

/// Covers: CL-TX-001, CL-RX-001
#[test]
fn both_counters_wrap_at_0xffff_under_the_reference_client() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("fc510x-before-fw2.14").unwrap();
    let run = run_profile(
        profile,
        &ClientKind::Reference,
        &ClientOptions::new(1),
        |_| {},
    );
    let wrap = run
        .runs
        .iter()
        .find(|r| r.scenario.contains("wrap"))
        .expect("the counter wrap runs");
    assert_eq!(wrap.outcome, Outcome::Pass, "{}", wrap.scenario);
    assert!(wrap.cycles > 65_536, "{} task cycles", wrap.cycles);
}

/// Covers: CL-TX-001, CL-TX-002, CL-TX-003, CL-TX-004, CL-TX-005, CL-RX-001, CL-RX-002, CL-RX-003, CL-RX-004, CL-IMG-001, CL-FQ-001, CL-RST-001, CL-RST-002, CL-TN-001, CL-TN-002
#[test]
fn each_faulty_client_is_caught_on_exactly_its_requirements() {
    let catalogue = Catalogue::embedded().unwrap();
    let rows = kill_matrix(&catalogue, &options(), |_| {});
    assert_eq!(rows.len(), ClientFault::ALL.len());
    for row in rows {
        let caught: BTreeSet<&str> = row
            .caught
            .iter()
            .flat_map(|(_, ids)| ids.iter().map(String::as_str))
            .collect();
        let expected = KILL_TABLE
            .iter()
            .find(|(fault, _)| *fault == row.fault)
            .map(|(_, ids)| ids.iter().copied().collect::<BTreeSet<_>>())
            .unwrap_or_else(|| panic!("{} is missing from the kill table", row.fault));
        assert_eq!(caught, expected, "{}", row.fault);
    }
}

/// Every client requirement a test can judge (not those verified by
/// inspection, such as CL-ORD-001's order inside one task) is broken by some
/// faulty client: `canif self-check` lists none as unreached.
#[test]
fn every_client_requirement_is_broken_by_some_faulty_client() {
    let catalogue = Catalogue::embedded().unwrap();
    let killed = KILL_TABLE.iter().flat_map(|(_, ids)| ids.iter().copied());
    assert_eq!(
        unreached::<ClientOptions>(&catalogue, killed),
        Vec::<&str>::new()
    );
}

#[test]
fn every_client_fault_has_a_name_and_a_description_of_its_own() {
    let names: BTreeSet<&str> = ClientFault::ALL.iter().map(|f| f.name()).collect();
    let descriptions: BTreeSet<&str> = ClientFault::ALL.iter().map(|f| f.description()).collect();
    assert_eq!(names.len(), ClientFault::ALL.len());
    assert_eq!(descriptions.len(), ClientFault::ALL.len());
    for fault in ClientFault::ALL {
        assert_eq!(ClientFault::from_name(fault.name()), Some(fault));
    }
}
