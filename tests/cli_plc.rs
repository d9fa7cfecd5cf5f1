//! `canif export` and `canif check-layout` as docs/plc-side.md shows them:
//! the exported declarations hold 001 §6's samples' names and compile; the
//! check passes the hand-written example, prints exactly the documented
//! differences for the defective one, and refuses what it cannot read.

use std::path::Path;
use std::process::{Command, Output};

use canif_plctypes::{parse, Body, Source};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn canif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("canif runs")
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

const EXAMPLE_INTERFACE: [&str; 6] = [
    "--profile",
    "el6751-mdp",
    "--frame",
    "29",
    "--transaction-number",
    "--tx-slots",
];

/// The doc's block that follows `after`, up to the closing fence.
fn doc_block(after: &str) -> String {
    let doc = std::fs::read_to_string(root().join("docs/plc-side.md")).unwrap();
    let start = doc
        .find(after)
        .unwrap_or_else(|| panic!("docs/plc-side.md: `{after}`"));
    let rest = &doc[start..];
    let body = &rest[rest.find('\n').unwrap() + 1..];
    body[..body.find("```").unwrap()].to_string()
}

#[test]
fn the_send_and_read_samples_use_only_what_the_export_declares() {
    let mut args = vec!["export"];
    args.extend(EXAMPLE_INTERFACE);
    args.push("10");
    let output = canif(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    let types = parse(&Source {
        file: "export".into(),
        text: stdout(&output),
        first_line: 1,
    })
    .expect("the export parses");
    let members = |name: &str| -> Vec<String> {
        match &types.iter().find(|t| t.name == name).expect(name).body {
            Body::Struct(members) => members.iter().map(|m| m.name.clone()).collect(),
            Body::Alias(_) => Vec::new(),
        }
    };
    let sample = std::fs::read_to_string(root().join("examples/st/send_and_read.st")).unwrap();
    for type_name in [
        "CANINTERFACE_INPUTS",
        "CANINTERFACE_OUTPUTS",
        "CAN29TXMESSAGE",
        "CAN29MESSAGE",
    ] {
        assert!(sample.contains(type_name));
        assert!(
            types.iter().any(|t| t.name == type_name),
            "{type_name} is exported"
        );
    }
    let mut referenced = 0;
    for (image, type_name) in [
        ("Outputs.", "CANINTERFACE_OUTPUTS"),
        ("Inputs.", "CANINTERFACE_INPUTS"),
    ] {
        let declared = members(type_name);
        for (at, _) in sample.match_indices(image) {
            let name: String = sample[at + image.len()..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            assert!(
                declared.contains(&name),
                "{image}{name} is not declared by the export"
            );
            referenced += 1;
        }
    }
    assert!(
        referenced >= 12,
        "the samples read and write the image ({referenced})"
    );
    let shown = doc_block("`examples/st/send_and_read.st`:");
    assert!(
        sample.contains(shown.trim_end()),
        "docs/plc-side.md shows the example file's code"
    );
}

#[test]
fn check_layout_passes_the_example_and_prints_the_documented_differences() {
    let mut args = vec!["check-layout", "examples/st/can_interface.st"];
    args.extend(&EXAMPLE_INTERFACE[..5]);
    let output = canif(&args);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}{}",
        stdout(&output),
        stderr(&output)
    );
    assert!(stdout(&output).contains("they match the image byte for byte"));

    let mut args = vec!["check-layout", "examples/st/can_interface_defects.st"];
    args.extend(&EXAMPLE_INTERFACE[..5]);
    let output = canif(&args);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    let shown =
        doc_block("$ cargo run --release -- check-layout examples/st/can_interface_defects.st");
    assert_eq!(
        stdout(&output),
        shown,
        "docs/plc-side.md shows the run as it is"
    );
    assert!(shown.contains("counts from 1") && shown.contains("overrun the image"));
}

#[test]
fn the_exported_c_header_of_an_fd_interface_compiles() {
    let output = canif(&[
        "export",
        "--profile",
        "fc532x",
        "--frame",
        "fd",
        "--format",
        "c",
        "--tx-slots",
        "4",
        "--rx-slots",
        "6",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let dir = std::env::temp_dir().join(format!("canif-cli-plc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("can_interface.h"), stdout(&output)).unwrap();
    std::fs::write(
        dir.join("use.c"),
        "#include \"can_interface.h\"\nint main(void) { CANINTERFACE_INPUTS in; return (int)sizeof in.RxMessage[5].rxData; }\n",
    )
    .unwrap();
    let cc = Command::new("cc")
        .args(["-std=c11", "-Wall", "-Werror", "-o", "use", "use.c"])
        .current_dir(&dir)
        .output()
        .expect("a C compiler (cc) is needed by the tests");
    assert!(
        cc.status.success(),
        "{}",
        String::from_utf8_lossy(&cc.stderr)
    );
    let run = Command::new(dir.join("use")).output().unwrap();
    assert_eq!(run.status.code(), Some(64), "64 data bytes per FD message");
}

#[test]
fn what_the_profile_does_not_offer_and_unreadable_files_are_refused() {
    let output = canif(&["export", "--profile", "fc510x", "--frame", "fd"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains("fc510x does not offer this interface"),
        "{}",
        stderr(&output)
    );
    let output = canif(&["export", "--profile", "el6751-mpd"]);
    assert!(
        stderr(&output).contains("did you mean `el6751-mdp`"),
        "{}",
        stderr(&output)
    );
    let output = canif(&["export"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("--profile"), "{}", stderr(&output));

    let output = canif(&["check-layout", "include/canif.h", "--profile", "fc510x"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains("include/canif.h:1: no TYPE"),
        "{}",
        stderr(&output)
    );
    let output = canif(&[
        "check-layout",
        "examples/st/send_and_read.st",
        "--profile",
        "el6751-mdp",
    ]);
    assert_eq!(
        output.status.code(),
        Some(2),
        "types declared nowhere cannot be sized"
    );
    assert!(
        stderr(&output).contains("no structure in the files declares the image")
            || stderr(&output).contains("no TYPE"),
        "{}",
        stderr(&output)
    );
    let output = canif(&[
        "check-layout",
        "examples/st/can_interface.st",
        "--profile",
        "el6751-mdp",
        "--pack-mode",
        "3",
    ]);
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains("0, 1, 2, 4 and 8"),
        "{}",
        stderr(&output)
    );
}
