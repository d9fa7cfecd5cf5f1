//! The exported declarations are the model's images byte for byte: for
//! every profile and every interface it offers, the generated Structured
//! Text, laid out as TwinCAT lays it out, reads from an image the model
//! wrote exactly what the model's views read; the C header and the Rust
//! module compile with their assertions on every offset and size.

use std::path::Path;
use std::process::Command;

use canif_model::cob_id::{CobId32, CobIdWord};
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig};
use canif_model::image::{ImageLayout, InputImage, MessageView, OutputImage};
use canif_plctypes::export::{export, Language};
use canif_plctypes::{parse, Declarations, ImageTypes, Source, TypeExpr, INPUTS, OUTPUTS};

/// Every interface a profile offers, at a few slot counts.
fn interfaces(caps: &Capabilities) -> Vec<InterfaceConfig> {
    let mut out = Vec::new();
    for format in [
        FrameFormat::Base11,
        FrameFormat::Extended29,
        FrameFormat::Fd,
    ] {
        for (tn, ts) in [(false, false), (true, false), (true, true), (false, true)] {
            for (tx, rx) in [(1, caps.max_slots), (caps.max_slots, 1), (7, 3)] {
                let mut config = InterfaceConfig::new(format, tx);
                config.rx_slots = rx;
                config.transaction_number = tn;
                config.time_stamp = ts;
                if config.validate(caps).is_ok() {
                    out.push(config);
                }
            }
        }
    }
    out
}

/// A leaf of a laid-out structure: its path, byte, size and bit.
type Leaf = (String, usize, usize, Option<u8>);

fn leaves(decls: &Declarations, type_name: &str, base: usize, path: &str, out: &mut Vec<Leaf>) {
    let laid = decls
        .lay_out(type_name)
        .expect("sized")
        .expect("a structure");
    for member in &laid.members {
        let at = base + member.offset;
        let name = format!("{path}{}", member.name.to_ascii_lowercase());
        expand(decls, &member.data_type, at, &name, member.bit, out);
    }
}

fn expand(
    decls: &Declarations,
    ty: &TypeExpr,
    at: usize,
    path: &str,
    bit: Option<u8>,
    out: &mut Vec<Leaf>,
) {
    match ty {
        TypeExpr::Elementary(e) => out.push((path.to_string(), at, e.size(), bit)),
        TypeExpr::Array { low, high, element } => {
            let element_size = size(decls, element);
            for (n, i) in (*low..=*high).enumerate() {
                expand(
                    decls,
                    element,
                    at + n * element_size,
                    &format!("{path}[{i}]"),
                    None,
                    out,
                );
            }
        }
        TypeExpr::Named(name) => leaves(decls, name, at, &format!("{path}."), out),
        TypeExpr::String { .. } => panic!("no string in an image"),
    }
}

fn size(decls: &Declarations, ty: &TypeExpr) -> usize {
    match ty {
        TypeExpr::Elementary(e) => e.size(),
        TypeExpr::Array { low, high, element } => (high - low + 1) as usize * size(decls, element),
        TypeExpr::Named(name) => decls.lay_out(name).unwrap().unwrap().size,
        TypeExpr::String { bytes } => *bytes,
    }
}

fn read(image: &[u8], (_, at, size, bit): &Leaf) -> u64 {
    // At the ST layout's offset, with the images' encoding (a BIT's byte whole).
    let value = canif_model::image::le::read(image, *at..*at + (*size).max(1));
    match bit {
        Some(b) => (value >> b) & 1,
        None => value,
    }
}

/// What the model's views read for a message member, by its ST name.
fn message_value<T: AsRef<[u8]>>(view: &MessageView<T>, member: &str) -> u64 {
    let (field, index) = match member.split_once('[') {
        Some((field, index)) => (field, index.trim_end_matches(']').parse::<usize>().ok()),
        None => (member, None),
    };
    match (field, index) {
        ("transactionnumber", _) => u64::from(view.transaction_number()),
        ("length" | "datalength", _) => u64::from(view.raw_length()),
        ("cobid", _) if view.layout().cob_id.len() == 2 => u64::from(view.cob_id_word().0),
        ("cobid", _) => u64::from(view.cob_id32().0),
        ("edl", _) => u64::from(view.flags() & 1),
        ("bsr", _) => u64::from(view.flags() >> 1 & 1),
        ("esi", _) => u64::from(view.flags() >> 2 & 1),
        ("data" | "txdata" | "rxdata", Some(k)) => u64::from(view.data_field()[k]),
        ("timestamp", _) => view.time_stamp(),
        other => panic!("no member {other:?} in the model's message"),
    }
}

fn fill<T: AsRef<[u8]> + AsMut<[u8]>>(view: &mut MessageView<T>, slot: usize) {
    let n = slot as u32 + 1;
    view.set_transaction_number(0x4000 + n as u16);
    if view.layout().cob_id.len() == 2 {
        view.set_cob_id_word(CobIdWord::new(0x123 + n as u16, slot.is_multiple_of(2), 0));
    } else {
        view.set_cob_id32(CobId32(0x8000_0000 | (0x0123_4567 + n)));
    }
    view.set_raw_length((slot % 8) as u16 + 1);
    view.set_flags((slot % 8) as u8);
    for (k, byte) in view.data_field_mut().iter_mut().enumerate() {
        *byte = (k as u8).wrapping_mul(7).wrapping_add(slot as u8);
    }
    view.set_time_stamp(0x0102_0304_0506_0708 + u64::from(n));
}

fn declarations_of(types: &ImageTypes) -> Declarations {
    let text = export(types, Language::StructuredText, "the test");
    let source = Source {
        file: "exported.st".into(),
        text,
        first_line: 1,
    };
    // The attribute must do the packing: TwinCAT 3's own default would not.
    Declarations::new(parse(&source).expect("the export parses"), 8).expect("no duplicates")
}

/// Every byte of the image is one leaf's (or one run of bits'), once.
fn assert_tiles(leaves: &[Leaf], size: usize, what: &str) {
    let mut owner = vec![0u32; size];
    for (_, at, len, bit) in leaves {
        if bit.is_some_and(|b| b > 0) {
            continue;
        }
        for byte in &mut owner[*at..*at + (*len).max(1)] {
            *byte += 1;
        }
    }
    assert!(
        owner.iter().all(|&n| n == 1),
        "{what}: bytes not covered exactly once: {owner:?}"
    );
}

#[test]
fn every_profiles_exported_images_read_what_the_model_wrote() {
    let catalogue = canif_spec::Catalogue::embedded().expect("the embedded catalogue");
    let mut checked = 0;
    for profile in &catalogue.profiles {
        let caps = profile.model_capabilities();
        for config in interfaces(&caps) {
            let layout = ImageLayout::new(&config, caps.info_data);
            let what = format!("{} {config:?}", profile.name);
            let decls = declarations_of(&ImageTypes::of(&layout, what.clone()));

            let mut outputs = vec![0u8; layout.output_size()];
            let mut image = OutputImage::new_checked(&mut outputs[..], layout).unwrap();
            image.set_tx_counter(0x1101);
            image.set_rx_counter(0x2202);
            image.set_no_of_tx_messages(0x3303);
            for slot in 0..layout.tx_slots {
                fill(&mut image.tx_message_mut(slot).unwrap(), slot);
            }
            let image = OutputImage::new_checked(&outputs[..], layout).unwrap();
            let mut found = Vec::new();
            leaves(&decls, OUTPUTS, 0, "", &mut found);
            assert_tiles(&found, layout.output_size(), &what);
            for leaf in &found {
                let expected = match leaf.0.as_str() {
                    "txcounter" => u64::from(image.tx_counter()),
                    "rxcounter" => u64::from(image.rx_counter()),
                    "nooftxmessages" => u64::from(image.no_of_tx_messages()),
                    path => {
                        let rest = path.strip_prefix("txmessage[").expect(path);
                        let (slot, member) = rest.split_once("].").expect(path);
                        message_value(&image.tx_message(slot.parse().unwrap()).unwrap(), member)
                    }
                };
                assert_eq!(read(&outputs, leaf), expected, "{what}: Outputs.{}", leaf.0);
            }

            let mut inputs = vec![0u8; layout.input_size()];
            let mut image = InputImage::new_checked(&mut inputs[..], layout).unwrap();
            image.set_tx_counter(0x1101);
            image.set_rx_counter(0x2202);
            image.set_no_of_rx_messages(0x3303);
            image.set_transaction_number(0x4404);
            for slot in 0..layout.rx_slots {
                fill(&mut image.rx_message_mut(slot).unwrap(), slot);
            }
            for index in 0..16 {
                image.set_info_data(index, 0x5000_0000 + index as u32);
            }
            let image = InputImage::new_checked(&inputs[..], layout).unwrap();
            let mut found = Vec::new();
            leaves(&decls, INPUTS, 0, "", &mut found);
            assert_tiles(&found, layout.input_size(), &what);
            for leaf in &found {
                let expected = match leaf.0.as_str() {
                    "txcounter" => u64::from(image.tx_counter()),
                    "rxcounter" => u64::from(image.rx_counter()),
                    "noofrxmessages" => u64::from(image.no_of_rx_messages()),
                    "transactionnumber" => u64::from(image.transaction_number().expect(&what)),
                    path if path.starts_with("infodata[") => {
                        let index = path["infodata[".len()..path.len() - 1].parse().unwrap();
                        u64::from(image.info_data(index).unwrap())
                    }
                    path => {
                        let rest = path.strip_prefix("rxmessage[").expect(path);
                        let (slot, member) = rest.split_once("].").expect(path);
                        message_value(&image.rx_message(slot.parse().unwrap()).unwrap(), member)
                    }
                };
                assert_eq!(read(&inputs, leaf), expected, "{what}: Inputs.{}", leaf.0);
            }
            checked += 1;
        }
    }
    assert!(
        checked >= 3 * catalogue.profiles.len(),
        "only {checked} interfaces checked"
    );
}

fn compile(dir: &Path, program: &str, args: &[&str]) -> std::process::Output {
    Command::new(program)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| panic!("{program}: {e} (the tests need a C compiler and rustc)"))
}

fn sample_types() -> Vec<ImageTypes> {
    let mut configs = vec![ImageTypes::messages()];
    for (format, tn, ts) in [
        (FrameFormat::Base11, true, false),
        (FrameFormat::Extended29, true, true),
        (FrameFormat::Fd, true, true),
    ] {
        let mut config = InterfaceConfig::new(format, 5);
        config.transaction_number = tn;
        config.time_stamp = ts;
        configs.push(ImageTypes::of(
            &ImageLayout::new(&config, true),
            format!("{format:?}"),
        ));
    }
    configs
}

#[test]
fn the_c_header_compiles_with_every_offset_asserted_as_c_and_cpp() {
    let dir = tempdir("c");
    for (n, types) in sample_types().iter().enumerate() {
        let header = export(types, Language::C, "the test");
        assert!(header.contains("offsetof(CANINTERFACE_OUTPUTS, TxMessage)") || n == 0);
        std::fs::write(dir.join("image.h"), &header).unwrap();
        std::fs::write(
            dir.join("use.c"),
            "#include \"image.h\"\nint main(void) { return 0; }\n",
        )
        .unwrap();
        for (compiler, std) in [("cc", "-std=c11"), ("c++", "-std=c++17")] {
            let lang = if compiler == "cc" { "c" } else { "c++" };
            let out = compile(
                &dir,
                compiler,
                &[
                    std,
                    "-x",
                    lang,
                    "-Wall",
                    "-Werror",
                    "-fsyntax-only",
                    "use.c",
                ],
            );
            assert!(
                out.status.success(),
                "{compiler}: {}\n{header}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
    // A wrong offset is refused: the assertions are checked, not decoration.
    let types = &sample_types()[1];
    let broken = export(types, Language::C, "the test").replacen(
        "uint16_t RxCounter;",
        "uint32_t RxCounter;",
        1,
    );
    std::fs::write(dir.join("image.h"), broken).unwrap();
    let out = compile(&dir, "cc", &["-std=c11", "-fsyntax-only", "use.c"]);
    assert!(
        !out.status.success(),
        "a moved member must fail its assertion"
    );
}

#[test]
fn the_rust_module_compiles_with_every_offset_asserted() {
    let dir = tempdir("rust");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    for types in sample_types() {
        let module = export(&types, Language::Rust, "the test");
        std::fs::write(dir.join("image.rs"), &module).unwrap();
        let out = compile(
            &dir,
            &rustc,
            &[
                "--edition",
                "2021",
                "--crate-type",
                "lib",
                "-D",
                "warnings",
                "--emit",
                "metadata",
                "-o",
                "image.rmeta",
                "image.rs",
            ],
        );
        assert!(
            out.status.success(),
            "rustc: {}\n{module}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn canif_h_declares_the_exported_message_structures() {
    let header =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../include/canif.h"))
            .unwrap();
    let fragment = canif_plctypes::export::c_fragment(&ImageTypes::messages());
    assert!(
        header.contains(&fragment),
        "include/canif.h's message structures differ from `canif export --messages --format c`: regenerate them (docs/plc-side.md)"
    );
}

fn tempdir(what: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-plctypes-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Issue 57: each counter is described by its own image's role in the
/// handshake (000 §6), in every language: Outputs.TxCounter hands over a
/// batch and Inputs.TxCounter confirms it; Inputs.RxCounter says new
/// messages wait and Outputs.RxCounter acknowledges them.
#[test]
fn each_counter_is_described_by_its_direction_and_its_role_in_the_handshake() {
    let config = InterfaceConfig::new(FrameFormat::Base11, 4);
    let types = ImageTypes::of(
        &ImageLayout::new(&config, false),
        "one interface".to_string(),
    );
    let comment = |structure: &str, member: &str| {
        let found = types.structs.iter().find(|s| s.name == structure).unwrap();
        found
            .members
            .iter()
            .find(|m| m.name == member)
            .unwrap()
            .comment
    };
    for (structure, member, says, never) in [
        (OUTPUTS, "TxCounter", "the PLC adds 1", "confirmation"),
        (
            INPUTS,
            "TxCounter",
            "the device's confirmation",
            "the PLC adds 1",
        ),
        (
            OUTPUTS,
            "RxCounter",
            "the PLC's acknowledge",
            "new messages wait",
        ),
        (INPUTS, "RxCounter", "new messages wait", "acknowledge"),
    ] {
        let text = comment(structure, member);
        assert!(text.contains(says), "{structure}.{member}: {text}");
        assert!(!text.contains(never), "{structure}.{member}: {text}");
    }
    // The generated declarations carry them, each in its own structure (the
    // outputs are declared first, in every language).
    for language in [Language::StructuredText, Language::C, Language::Rust] {
        let text = export(&types, language, "test");
        let inputs_begin = text
            .find(INPUTS)
            .unwrap_or_else(|| panic!("{language:?}: {text}"));
        let (outputs, inputs) = text.split_at(inputs_begin);
        assert!(outputs.contains("the PLC adds 1"), "{language:?}: {text}");
        assert!(
            !outputs.contains("the device's confirmation"),
            "{language:?}: {text}"
        );
        assert!(
            inputs.contains("the device's confirmation"),
            "{language:?}: {text}"
        );
        assert!(!inputs.contains("the PLC adds 1"), "{language:?}: {text}");
    }
}
