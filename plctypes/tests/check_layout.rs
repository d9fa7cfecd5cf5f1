//! `check_files` finds each declaration defect of real clients in ST
//! written as a PLC programmer writes it, on the member's file and line, and
//! refuses input it cannot size instead of guessing.

use std::path::{Path, PathBuf};

use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::image::ImageLayout;
use canif_plctypes::export::{export, Language};
use canif_plctypes::{check_files, Cause, Checked, Difference, ImageTypes, Roots};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/st")
}

/// The examples' interface: 29-bit with transaction numbers, 10 slots, no InfoData.
fn image(format: FrameFormat, tn: bool, slots: u8, info_data: bool) -> ImageTypes {
    let mut config = InterfaceConfig::new(format, slots);
    config.transaction_number |= tn;
    ImageTypes::of(&ImageLayout::new(&config, info_data), String::new())
}

fn check(files: &[PathBuf], image: &ImageTypes) -> Checked {
    check_files(files, image, &Roots::default(), 8).expect("readable")
}

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-check-layout-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn the_hand_written_example_matches_byte_for_byte() {
    let checked = check(
        &[examples().join("can_interface.st")],
        &image(FrameFormat::Extended29, true, 10, false),
    );
    assert_eq!(checked.defects, []);
    assert!(checked.unmatched.is_empty());
    assert_eq!(
        checked.matched.len(),
        4,
        "both images and both message types"
    );
    assert_eq!(checked.members_checked, 16);
}

#[test]
fn a_one_based_array_an_overrun_and_a_missing_pack_mode_are_each_found_on_their_line() {
    let checked = check(
        &[examples().join("can_interface_defects.st")],
        &image(FrameFormat::Extended29, true, 10, false),
    );
    let at = |line: usize| -> Vec<&Difference> {
        checked
            .defects
            .iter()
            .filter(|d| d.place.line == line)
            .map(|d| &d.difference)
            .collect()
    };
    assert_eq!(
        at(29),
        [&Difference::LowBound {
            low: 1,
            expected_high: 9
        }],
        "ARRAY [1..10] OF the Tx message"
    );
    assert_eq!(
        at(40),
        [&Difference::Overrun {
            count: 11,
            expected: 10
        }],
        "ARRAY [0..10] for 10 slots"
    );
    assert_eq!(
        at(18),
        [&Difference::Offset {
            expected: 2,
            actual: 4
        }],
        "CobID aligned without pack_mode"
    );
    assert!(
        matches!(
            at(15)[..],
            [Difference::StructSize {
                expected: 14,
                actual: 16,
                unpacked: true
            }]
        ),
        "{:?}",
        at(15)
    );
    assert!(checked
        .defects
        .iter()
        .all(|d| d.place.file.ends_with("can_interface_defects.st")));
}

#[test]
fn a_short_array_a_missing_member_a_wrong_width_and_swapped_bits_are_found() {
    let text = "{attribute 'pack_mode' := '0'}
TYPE ST_Out :
STRUCT
    TxCounter : UDINT;
    RxCounter : UINT;
    NoOfTxMessages : UINT;
    TxMessage : ARRAY [0..2] OF CANFDTXQUEUE;
END_STRUCT
END_TYPE
{attribute 'pack_mode' := '0'}
TYPE CANFDTXQUEUE :
STRUCT
    transactionNumber : UINT;
    dataLength : BYTE;
    EDL : BIT;
    ESI : BIT;
    BSR : BIT;
    cobId : UDINT;
    txData : ARRAY [0..63] OF USINT;
END_STRUCT
END_TYPE
{attribute 'pack_mode' := '0'}
TYPE ST_In :
STRUCT
    TxCounter : UINT;
    RxCounter : UINT;
    NoOfRxMessages : UINT;
    RxMessage : ARRAY [0..3] OF CANFDTSRXQUEUE;
END_STRUCT
END_TYPE
TYPE CANFDTSRXQUEUE : ARRAY [0..75] OF BYTE; END_TYPE
";
    let checked = check(
        &[write("fd.st", text)],
        &image(FrameFormat::Fd, true, 4, false),
    );
    let found: Vec<(usize, &Difference)> = checked
        .defects
        .iter()
        .map(|d| (d.place.line, &d.difference))
        .collect();
    assert!(
        found.contains(&(
            4,
            &Difference::Size {
                expected: 2,
                actual: 4
            }
        )),
        "{found:?}"
    );
    assert!(
        found.contains(&(
            7,
            &Difference::TooShort {
                count: 3,
                expected: 4
            }
        )),
        "{found:?}"
    );
    assert!(
        found.contains(&(
            16,
            &Difference::Bit {
                expected: 2,
                actual: Some(1)
            }
        )),
        "ESI: {found:?}"
    );
    assert!(
        found.contains(&(
            17,
            &Difference::Bit {
                expected: 1,
                actual: Some(2)
            }
        )),
        "BSR: {found:?}"
    );
    assert!(
        found.contains(&(
            28,
            &Difference::Size {
                expected: 78,
                actual: 76
            }
        )),
        "an Rx queue declared as too few bytes: {found:?}"
    );
    assert!(
        found.iter().any(|(_, d)| matches!(d, Difference::Missing { member, .. } if member == "TransactionNumber")),
        "{found:?}"
    );
}

#[test]
fn every_exported_declaration_passes_its_own_check() {
    for (format, tn, info) in [
        (FrameFormat::Base11, false, false),
        (FrameFormat::Base11, true, true),
        (FrameFormat::Extended29, true, false),
        (FrameFormat::Fd, true, true),
    ] {
        let types = image(format, tn, 5, info);
        let path = write(
            "exported.st",
            &export(&types, Language::StructuredText, "t"),
        );
        let checked = check(&[path], &types);
        assert_eq!(checked.defects, [], "{format:?}");
        assert!(checked.unmatched.is_empty());
    }
}

#[test]
fn a_tcdut_is_read_with_the_files_own_lines() {
    let message = "<?xml version=\"1.0\" encoding=\"utf-8\"?>
<TcPlcObject Version=\"1.1.0.1\">
  <DUT Name=\"ST_Msg\" Id=\"{00000000-0000-0000-0000-000000000001}\">
    <Declaration><![CDATA[TYPE ST_Msg :
STRUCT
    Length : UINT;
    CobID : UDINT;
    Data : ARRAY [0..7] OF BYTE;
END_STRUCT
END_TYPE
]]></Declaration>
  </DUT>
</TcPlcObject>";
    let outputs = "{attribute 'pack_mode' := '0'}
TYPE ST_Out :
STRUCT
    TxCounter : UINT;
    RxCounter : UINT;
    NoOfTxMessages : UINT;
    TxMessage : ARRAY [0..9] OF ST_Msg;
END_STRUCT
END_TYPE";
    let files = [write("ST_Msg.TcDUT", message), write("out.st", outputs)];
    let checked = check(&files, &image(FrameFormat::Extended29, false, 10, false));
    let cob_id = checked
        .defects
        .iter()
        .find(|d| d.member == "ST_Msg.CobID")
        .expect("found");
    assert!(cob_id.place.file.ends_with("ST_Msg.TcDUT"));
    assert_eq!(cob_id.place.line, 7, "the .TcDUT's line, not the CDATA's");
    assert_eq!(
        checked.unmatched,
        ["CANINTERFACE_INPUTS"],
        "the inputs are said unchecked"
    );
}

#[test]
fn input_canif_cannot_size_is_an_error_naming_file_and_line() {
    let header = write(
        "image.h",
        "#include <stdint.h>\ntypedef struct { uint16_t TxCounter; } out;\n",
    );
    let image = image(FrameFormat::Base11, false, 2, false);
    let error = check_files(&[header], &image, &Roots::default(), 8).unwrap_err();
    assert_eq!(error.cause, Cause::NoTypes);
    assert!(error.to_string().starts_with(error.place.file.as_str()));
    let unknown = write(
        "u.st",
        "TYPE A :\nSTRUCT\n  NoOfTxMessages : UINT;\n  m : ST_Nowhere;\nEND_STRUCT\nEND_TYPE\n",
    );
    let error = check_files(&[unknown], &image, &Roots::default(), 8).unwrap_err();
    assert_eq!(
        (error.place.line, error.cause),
        (4, Cause::UnknownType("ST_Nowhere".into()))
    );
    let itself = write(
        "r.st",
        "TYPE A :\nSTRUCT\n  NoOfTxMessages : UINT;\n  m : A;\nEND_STRUCT\nEND_TYPE\n",
    );
    let error = check_files(&[itself], &image, &Roots::default(), 8).unwrap_err();
    assert!(matches!(error.cause, Cause::TooDeep(_)), "{error}");
    let missing = check_files(
        &[PathBuf::from("/nonexistent/x.st")],
        &image,
        &Roots::default(),
        8,
    )
    .unwrap_err();
    assert!(matches!(missing.cause, Cause::Unreadable(_)), "{missing}");
    assert!(
        missing
            .to_string()
            .starts_with("/nonexistent/x.st: cannot read"),
        "a file-wide error names the file alone: {missing}"
    );
}
