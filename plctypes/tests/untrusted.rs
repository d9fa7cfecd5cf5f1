//! A user's file is untrusted: whatever it holds, reading, laying out and
//! checking it ends with an answer or an error naming a place, never a
//! panic, and in time proportional to the file (no layout is computed twice).

use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::image::ImageLayout;
use canif_plctypes::{check, parse, Declarations, ImageTypes, Roots, Source};
use proptest::prelude::*;

fn image() -> ImageTypes {
    ImageTypes::of(
        &ImageLayout::new(&InterfaceConfig::new(FrameFormat::Extended29, 4), false),
        String::new(),
    )
}

fn read_all(text: &str) {
    let Ok(sources) = Source::of_bytes("u.st", text.as_bytes()) else {
        return;
    };
    for source in sources {
        let Ok(types) = parse(&source) else { continue };
        let Ok(declarations) = Declarations::new(types, 8) else {
            continue;
        };
        let _ = check(&declarations, &image(), &Roots::default());
    }
}

/// Pieces of declarations, so that the generated files get deep into the grammar.
fn piece() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("TYPE ".to_string()),
        Just("END_TYPE ".to_string()),
        Just("STRUCT ".to_string()),
        Just("END_STRUCT ".to_string()),
        Just("{attribute 'pack_mode' := '0'} ".to_string()),
        Just(" : ".to_string()),
        Just("; ".to_string()),
        Just("ARRAY [".to_string()),
        Just("] OF ".to_string()),
        Just("..".to_string()),
        Just("NoOfTxMessages : UINT; ".to_string()),
        Just("TxMessage : ARRAY [0..3] OF M; ".to_string()),
        Just("BIT ".to_string()),
        Just("(* ".to_string()),
        Just("*) ".to_string()),
        "[A-Za-z_][A-Za-z0-9_]{0,6} ",
        "-?[0-9]{1,20}",
        "16#[0-9A-F]{1,3}",
        "[\\PC\n]{0,4}",
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    #[test]
    fn no_text_panics_the_reader(pieces in proptest::collection::vec(piece(), 0..40)) {
        read_all(&pieces.concat());
    }

    #[test]
    fn no_bytes_panic_the_reader(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let _ = Source::of_bytes("u.TcDUT", &bytes);
        if let Ok(text) = std::str::from_utf8(&bytes) {
            read_all(text);
        }
    }
}

/// Ten structures each holding ten of the next: laid out naively this is
/// 10^10 member layouts; once each, 100.
#[test]
fn deeply_shared_types_are_laid_out_once() {
    let mut text = String::from("TYPE T0 : STRUCT NoOfTxMessages : UINT; a : ARRAY [0..9] OF T1; b, c, d, e, f, g, h, i, j : T1; END_STRUCT END_TYPE\n");
    for n in 1..10 {
        text.push_str(&format!(
            "TYPE T{n} : STRUCT a, b, c, d, e, f, g, h, i, j : T{}; END_STRUCT END_TYPE\n",
            n + 1
        ));
    }
    text.push_str("TYPE T10 : STRUCT x : BYTE; END_STRUCT END_TYPE\n");
    let types = parse(&Source {
        file: "deep.st".into(),
        text,
        first_line: 1,
    })
    .expect("parses");
    let declarations = Declarations::new(types, 8).expect("no duplicates");
    let laid = declarations
        .lay_out("T0")
        .expect("sized")
        .expect("a structure");
    assert_eq!(laid.size, 2 + 19 * 10usize.pow(9));
}
