//! The declaration read, merged and applied, on lines as clients write them.

use super::*;

#[test]
fn every_line_reads_back_as_written() {
    let lines = [
        "formats=11-bit,29-bit",
        "queues=standard,fast",
        "transaction-numbers=no",
        "time-stamps=no",
        "slots=10",
        "direction=tx",
        "application=streams",
        "restart=drops-once",
        "tells-sent=no",
    ];
    let declaration = ClientDeclaration::parse(&lines).unwrap();
    assert_eq!(declaration.lines(), lines);
    assert_eq!(declaration.tx_slots, Some(SlotRange { min: 10, max: 10 }));
    assert_eq!(declaration.rx_slots, declaration.tx_slots);
    assert_eq!(declaration.direction(), Direction::Tx);
}

#[test]
fn a_bad_line_is_named_with_what_was_expected() {
    let error = ClientDeclaration::parse(&["slots=0..40"]).unwrap_err();
    assert_eq!(
        error.to_string(),
        "slots=0..40: expected a slot count N or a range MIN..MAX within 1..32"
    );
    assert!(matches!(
        ClientDeclaration::parse(&["slots"]),
        Err(DeclarationError::Malformed { .. })
    ));
    let unknown = ClientDeclaration::parse(&["colour=red"]).unwrap_err();
    assert!(unknown.to_string().contains("known: formats, queues"));
    assert!(ClientDeclaration::parse(&["slots=12..4"]).is_err());
    assert!(ClientDeclaration::parse(&["formats=11-bit,can"]).is_err());
}

#[test]
fn the_same_value_twice_is_fine_two_values_conflict() {
    let cli = ClientDeclaration::parse(&["direction=tx"]).unwrap();
    let same = ClientDeclaration::parse(&["direction=tx", "slots=1..32"]).unwrap();
    assert_eq!(cli.merged(&same).unwrap().rx_slots.unwrap().max, 32);
    let other = ClientDeclaration::parse(&["direction=rx"]).unwrap();
    assert_eq!(
        cli.merged(&other).unwrap_err().to_string(),
        "direction is declared twice: direction=tx and direction=rx"
    );
}

#[test]
fn a_declined_format_is_not_served_a_declined_option_is_switched_off() {
    let declaration =
        ClientDeclaration::parse(&["formats=11-bit,fd", "transaction-numbers=no"]).unwrap();
    let mut ext = InterfaceConfig::new(FrameFormat::Extended29, 8);
    assert_eq!(
        declaration.serve(&ext).unwrap_err(),
        "the client declares formats=11-bit,fd"
    );
    let mut base = InterfaceConfig::new(FrameFormat::Base11, 8);
    base.transaction_number = true;
    let served = declaration.serve(&base).unwrap();
    assert!(!served.transaction_number);
    // FD messages always carry a transaction number.
    let fd = InterfaceConfig::new(FrameFormat::Fd, 8);
    assert_eq!(
        declaration.serve(&fd).unwrap_err(),
        "the client declares transaction-numbers=no"
    );
    ext.format = FrameFormat::Base11;
    assert!(ClientDeclaration::default().serve(&ext).is_ok());
}

#[test]
fn geometries_are_the_default_and_the_edges_the_client_takes() {
    let any = ClientDeclaration::default();
    assert_eq!(any.geometries(32)[..3], [(8, 8), (1, 1), (32, 32)]);
    assert_eq!(any.geometries(8), [(8, 8), (1, 1), (8, 1), (1, 8)]);
    let ten = ClientDeclaration::parse(&["slots=10"]).unwrap();
    assert_eq!(ten.geometries(32), [(10, 10)]);
    assert!(ten.geometries(8).is_empty());
    let range = ClientDeclaration::parse(&["slots=4..16"]).unwrap();
    assert_eq!(range.geometries(32)[..3], [(8, 8), (4, 4), (16, 16)]);
}

/// Issue 36: the Tx and Rx slot counts are declared apart, as a terminal's
/// settings hold them; `slots` is both, and conflicts with either that
/// says otherwise.
#[test]
fn tx_and_rx_slots_are_declared_apart() {
    let apart = ClientDeclaration::parse(&["tx-slots=10", "rx-slots=20"]).unwrap();
    assert_eq!(apart.geometries(32), [(10, 20)]);
    assert_eq!(apart.lines(), ["tx-slots=10", "rx-slots=20"]);
    assert!(apart.serves_slots(10, 20) && !apart.serves_slots(10, 10));
    assert_eq!(
        apart.declined_geometry(),
        "the client declares tx-slots=10, rx-slots=20"
    );
    let both = ClientDeclaration::parse(&["slots=10"]).unwrap();
    assert_eq!(both.lines(), ["slots=10"]);
    assert!(ClientDeclaration::parse(&["slots=10", "tx-slots=12"]).is_err());
    assert!(ClientDeclaration::parse(&["slots=10", "rx-slots=10"]).is_ok());
}

/// Issue 36: a client that serves only interfaces with transaction numbers
/// (or time stamps) is left out of those without them, and one that does
/// without them is left out of a scenario that needs them.
#[test]
fn a_yes_leaves_out_interfaces_without_and_a_no_scenarios_that_need_them() {
    use canif_model::config::{FrameFormat, InterfaceConfig};
    let plain = InterfaceConfig::new(FrameFormat::Base11, 4);
    let with = ClientDeclaration::parse(&["transaction-numbers=yes"]).unwrap();
    assert_eq!(
        with.serve(&plain).unwrap_err(),
        "the client declares transaction-numbers=yes"
    );
    let stamped = ClientDeclaration::parse(&["time-stamps=yes"]).unwrap();
    assert!(stamped.serve(&plain).is_err());
    let without = ClientDeclaration::parse(&["transaction-numbers=no"]).unwrap();
    assert!(without.serve(&plain).is_ok());
    assert_eq!(
        without.declined_capability("transaction_number").as_deref(),
        Some("the client declares transaction-numbers=no")
    );
    assert_eq!(without.declined_capability("timestamp"), None);
    assert_eq!(with.declined_capability("transaction_number"), None);
}
