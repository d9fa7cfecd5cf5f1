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
    assert_eq!(declaration.slots, Some(SlotRange { min: 10, max: 10 }));
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
    assert_eq!(cli.merged(&same).unwrap().slots.unwrap().max, 32);
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
    assert_eq!(any.geometries(32), [8, 1, 32]);
    assert_eq!(any.geometries(8), [8, 1]);
    let ten = ClientDeclaration::parse(&["slots=10"]).unwrap();
    assert_eq!(ten.geometries(32), [10]);
    assert!(ten.geometries(8).is_empty());
    let range = ClientDeclaration::parse(&["slots=4..16"]).unwrap();
    assert_eq!(range.geometries(32), [8, 4, 16]);
}
