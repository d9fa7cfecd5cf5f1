//! Clients are judged on what they declare (issue 27): each way of working the
//! documents allow only where declared conforms declared, and is rejected
//! undeclared by the requirement it then breaks; what a client does not
//! serve is "not applicable" with the declaration as the reason.

use canif_harness::declare::Declaration;
use std::collections::BTreeSet;

use canif_harness::client::soft_client::ClientShape;
use canif_harness::client::suite::{ClientKind, ClientOptions};
use canif_harness::client::ClientDeclaration;
use canif_harness::run::run_profile;
use canif_harness::verdict::{Verdict, VerdictKind};
use canif_spec::Catalogue;

fn options(lines: &[&str]) -> ClientOptions {
    ClientOptions {
        counter_wrap: false,
        declared: Ok(ClientDeclaration::parse(lines).unwrap()),
        ..ClientOptions::new(3)
    }
}

fn shaped(shape: ClientShape, declared: bool) -> ClientKind {
    ClientKind::Shaped { shape, declared }
}

/// Every requirement's verdict on `profile` for `kind`, its declaration read
/// as `canif run` reads it.
fn verdicts(
    kind: &ClientKind,
    profile: &str,
    lines: &[&str],
) -> std::collections::BTreeMap<String, Verdict> {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile(profile).unwrap();
    let options = options(lines).declared_by(kind);
    let run = run_profile(profile, kind, &options, |_| {});
    run.verdicts(&catalogue, profile)
}

fn with(
    verdicts: &std::collections::BTreeMap<String, Verdict>,
    kind: VerdictKind,
) -> BTreeSet<&str> {
    verdicts
        .iter()
        .filter(|(_, v)| v.kind() == kind)
        .map(|(id, _)| id.as_str())
        .collect()
}

/// A client's declared way passes; every verdict is a pass, or not
/// applicable for the reasons `reason` names.
fn conforms(kind: &ClientKind, profile: &str, reason: &str) -> BTreeSet<String> {
    let verdicts = verdicts(kind, profile, &[]);
    let broken: Vec<String> = verdicts
        .iter()
        .filter(|(_, v)| {
            matches!(
                v.kind(),
                VerdictKind::Fail | VerdictKind::Error | VerdictKind::NotRun
            )
        })
        .map(|(id, v)| format!("{id}: {}", v.reason().unwrap_or_default()))
        .collect();
    assert!(broken.is_empty(), "{}", broken.join("\n"));
    let declined: BTreeSet<String> = verdicts
        .iter()
        .filter(|(_, v)| v.kind() == VerdictKind::NotApplicable)
        .filter(|(_, v)| v.reason().is_some_and(|r| r.contains(reason)))
        .map(|(id, _)| id.clone())
        .collect();
    assert!(!with(&verdicts, VerdictKind::Pass).is_empty());
    declined
}

/// Covers: CL-RX-001, CL-RX-002, CL-RX-003
#[test]
fn a_tx_only_client_is_certified_on_sending_and_fails_reception_undeclared() {
    let declined = conforms(
        &shaped(ClientShape::TxOnly, true),
        "el6751-mdp",
        "direction=tx",
    );
    for id in ["CL-RX-001", "CL-RX-002", "CL-RX-003", "CL-FQ-001"] {
        assert!(declined.contains(id), "{id} not declined: {declined:?}");
    }
    let undeclared = verdicts(&shaped(ClientShape::TxOnly, false), "el6751-mdp", &[]);
    let failed = with(&undeclared, VerdictKind::Fail);
    assert!(failed.contains("CL-RX-001"), "{failed:?}");
}

/// Covers: CL-TX-003
#[test]
fn an_rx_only_client_is_not_judged_on_sending() {
    let declined = conforms(&shaped(ClientShape::RxOnly, true), "fc510x", "direction=rx");
    for id in ["CL-TX-001", "CL-TX-002", "CL-TX-003", "CL-TX-005"] {
        assert!(declined.contains(id), "{id} not declined: {declined:?}");
    }
}

/// Covers: CL-IMG-001, CL-TX-005
#[test]
fn a_ten_slot_client_runs_at_ten_slots_and_breaks_the_image_at_eight() {
    conforms(&shaped(ClientShape::TenSlots, true), "fc532x", "slots=10");
    let undeclared = verdicts(&shaped(ClientShape::TenSlots, false), "fc532x", &[]);
    let failed = with(&undeclared, VerdictKind::Fail);
    assert!(
        failed.contains("CL-IMG-001") || failed.contains("CL-TX-005"),
        "{failed:?}"
    );
}

/// Covers: CL-TX-003
#[test]
fn a_client_with_a_stream_per_identifier_keeps_each_in_order() {
    conforms(&shaped(ClientShape::Streams, true), "fc510x", "");
    let undeclared = verdicts(&shaped(ClientShape::Streams, false), "fc510x", &[]);
    assert!(with(&undeclared, VerdictKind::Fail).contains("CL-TX-003"));
}

/// Covers: CL-TX-003, CL-RX-002
#[test]
fn a_byte_stream_client_may_cut_the_bytes_into_frames_its_own_way() {
    conforms(&shaped(ClientShape::ByteStream, true), "fc510x", "");
    let undeclared = verdicts(&shaped(ClientShape::ByteStream, false), "fc510x", &[]);
    let failed = with(&undeclared, VerdictKind::Fail);
    assert!(
        failed.contains("CL-TX-003") || failed.contains("CL-TX-004"),
        "{failed:?}"
    );
    // FD frames cannot be cut at any byte: not served, with why.
    let catalogue = Catalogue::embedded().unwrap();
    let kind = shaped(ClientShape::ByteStream, true);
    let profile = catalogue.profile("fc532x").unwrap();
    let run = run_profile(profile, &kind, &options(&[]).declared_by(&kind), |_| {});
    assert!(
        run.reach
            .not_served
            .iter()
            .any(|(what, why)| what.starts_with("FD") && why.contains("application=byte-stream")),
        "{:?}",
        run.reach.not_served
    );
}

/// Covers: CL-RST-001
#[test]
fn the_restart_choice_is_either_undeclared_and_the_declared_one_only_declared() {
    conforms(&shaped(ClientShape::DropsRestartBatch, true), "fc510x", "");
    conforms(&shaped(ClientShape::DropsRestartBatch, false), "fc510x", "");
    // The command line says it delivers the batch again; it drops it.
    let lied = verdicts(
        &shaped(ClientShape::DropsRestartBatch, false),
        "fc510x",
        &["restart=delivers-twice"],
    );
    assert_eq!(
        with(&lied, VerdictKind::Fail),
        BTreeSet::from(["CL-RST-001"])
    );
    // With the Fast CAN Queue too, where the one batch is the first a
    // restarted program is shown.
    let kind = shaped(ClientShape::DropsRestartBatch, false);
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    let options = options(&["restart=delivers-twice"]).declared_by(&kind);
    let run = run_profile(profile, &kind, &options, |_| {});
    assert!(
        run.failures.iter().any(|f| f.scenario.contains(", fast, ")
            && f.requirements.iter().any(|id| id.as_str() == "CL-RST-001")),
        "{:?}",
        run.failures
            .iter()
            .map(|f| f.headline())
            .collect::<Vec<_>>()
    );
    // And the soft client that delivers it again, declared to drop it.
    let lied = verdicts(&ClientKind::Faulty(None), "fc510x", &["restart=drops-once"]);
    assert_eq!(
        with(&lied, VerdictKind::Fail),
        BTreeSet::from(["CL-RST-001"])
    );
}

#[test]
fn a_client_declining_29_bit_gets_not_applicable_not_an_error() {
    let catalogue = Catalogue::embedded().unwrap();
    let kind = shaped(ClientShape::Only11Bit, true);
    // A profile with 29-bit interfaces beside 11-bit ones: the 29-bit ones
    // are listed as not served, the rest passes.
    let profile = catalogue.profile("fc510x").unwrap();
    let options = options(&[]).declared_by(&kind);
    let run = run_profile(profile, &kind, &options, |_| {});
    assert!(
        run.reach
            .not_served
            .iter()
            .any(|(what, why)| what.starts_with("29-bit")
                && why == "the client declares formats=11-bit"),
        "{:?}",
        run.reach.not_served
    );
    assert!(run.runs.iter().all(|r| !r.scenario.contains("29-bit")));
    conforms(&kind, "fc510x", "formats=11-bit");
    // A profile with 29-bit interfaces only: not applicable, every one.
    let only29 = verdicts(&kind, "ccat", &[]);
    assert!(with(&only29, VerdictKind::Error).is_empty());
    assert!(with(&only29, VerdictKind::Pass).is_empty());
    assert!(!with(&only29, VerdictKind::NotApplicable).is_empty());
    // Undeclared, a client that cannot start on an interface is an error.
    let undeclared = verdicts(&shaped(ClientShape::Only11Bit, false), "fc510x", &[]);
    assert!(!with(&undeclared, VerdictKind::Error).is_empty());
}

#[test]
fn a_declaration_the_client_contradicts_is_an_error_naming_both() {
    let kind = shaped(ClientShape::TxOnly, true);
    let options = options(&["direction=rx"]).declared_by(&kind);
    let error = options.declared.unwrap_err().to_string();
    assert!(
        error.contains("direction=rx") && error.contains("direction=tx"),
        "{error}"
    );
}

#[test]
fn the_edges_of_the_slot_range_run_beside_the_default() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("fc532x").unwrap();
    let run = run_profile(profile, &ClientKind::Reference, &options(&[]), |_| {});
    // Issue 36: and the edges apart, as a terminal's settings may hold them.
    for slots in [
        ", 1 slots)",
        ", 8 slots)",
        ", 32 slots)",
        ", 32 Tx and 1 Rx slots)",
        ", 1 Tx and 32 Rx slots)",
    ] {
        assert!(
            run.runs.iter().any(|r| r.scenario.contains(slots)),
            "no scenario at {slots}"
        );
    }
}
