//! A device written in C against include/canif.h, loaded in process with
//! `--iut lib:`: the example is built with the machine's C compiler and
//! certified; a library of another ABI version or missing a function is an
//! error that says so.

use std::path::{Path, PathBuf};
use std::process::Command;

use canif_harness::device::suite::Options;
use canif_harness::device::IutKind;
use canif_harness::door::Door;
use canif_harness::run::run_profile;
use canif_harness::Outcome;
use canif_spec::Catalogue;

/// Compiles `source` (plus `extra` C text) into a shared library named `name`.
fn build(name: &str, source: &Path, extra: &str) -> PathBuf {
    build_with(name, source, extra, &[])
}

fn build_with(name: &str, source: &Path, extra: &str, flags: &[&str]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-abi");
    std::fs::create_dir_all(&dir).unwrap();
    let combined = dir.join(format!("{name}.c"));
    let mut text = std::fs::read_to_string(source).unwrap();
    text.push_str(extra);
    std::fs::write(&combined, text).unwrap();
    let library = dir.join(format!("lib{name}.so"));
    let status = Command::new("cc")
        .args(["-shared", "-fPIC", "-O2", "-Wall", "-Werror"])
        .args(flags)
        .arg("-I")
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/include"))
        .arg("-o")
        .arg(&library)
        .arg(&combined)
        .status()
        .expect("cc runs (the machine has gcc)");
    assert!(status.success(), "cc failed on {}", combined.display());
    library
}

/// `canif run` of `library` on fc510x-before-fw2.14's tx-batches scenarios,
/// its reports in `report`, with `env` set for canif.
fn run_tx_batches(
    library: &Path,
    report: &Path,
    env: &[(&str, &std::ffi::OsStr)],
) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_canif"))
        .args([
            "run",
            "--profile",
            "fc510x-before-fw2.14",
            "--scenario",
            "tx-batches",
        ])
        .arg(format!("--iut=lib:{}", library.display()))
        .arg("--report")
        .arg(report)
        .envs(env.iter().copied())
        .output()
        .expect("canif runs")
}

/// `canif run --profile fc510x-before-fw2.14 --iut lib:LIBRARY`, all of it,
/// as a new user runs it, reports into `report`.
fn run_whole_profile(library: &Path, report: &Path) -> std::process::Output {
    let _ = std::fs::remove_dir_all(report);
    Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(["run", "--profile", "fc510x-before-fw2.14", "--report"])
        .arg(report)
        .arg(format!("--iut=lib:{}", library.display()))
        .output()
        .expect("canif runs")
}

fn example() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/c/minimal_device.c")
}

#[test]
fn the_c_example_is_certified_in_process() {
    let library = build("minimal", &example(), "");
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("fc510x-before-fw2.14").unwrap();
    let run = run_profile(
        profile,
        &IutKind::Door(Door::Lib(canif_harness::door::LibDoor {
            path: library,
            host: None,
        })),
        &Options::quick(3),
        |_| {},
    );
    let bad: Vec<String> = run
        .runs
        .iter()
        .filter(|r| !matches!(r.outcome, Outcome::Pass))
        .map(|r| format!("{}: {:?}", r.scenario, r.outcome))
        .collect();
    assert!(bad.is_empty(), "{bad:#?}");
    assert!(
        run.verdicts(&catalogue, profile)
            .values()
            .filter(|v| v.kind() == canif_harness::VerdictKind::Pass)
            .count()
            > 30
    );
}

#[test]
fn canif_run_takes_a_library_from_the_command_line() {
    let library = build("minimal-cli", &example(), "");
    let report = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-abi-report");
    let output = run_whole_profile(&library, &report);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        stdout.contains("lib:") && stdout.contains(" 0 fail, 0 error"),
        "{stdout}"
    );
}

/// What a hosted library prints is its own output (issue 34: `printf` went
/// to the host's stdout, the protocol, and failed a conforming library's
/// run), and a line it prints cannot forge the host's report of an access
/// past an image (which once came on stderr, where any library can write).
#[test]
fn a_hosted_library_prints_freely_and_cannot_forge_the_guards_report() {
    const FORGED: &str = "canif-lib-host: access outside the image: input offset=120 size=110";
    let chatty = build(
        "chatty",
        &example(),
        &format!(
            r#"
#include <stdio.h>
__attribute__((constructor)) static void chatty_at_load(void) {{
    printf("hello from the library on stdout\n");
    fflush(stdout);
    fprintf(stderr, "{FORGED}\n");
    fflush(stderr);
}}
"#
        ),
    );
    let report = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-abi-chatty");
    let output = run_whole_profile(&chatty, &report);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    // A library that says it stopped outside an image, and leaves.
    let forger = build(
        "forger",
        &example(),
        &format!(
            r#"
#include <stdio.h>
#include <unistd.h>
__attribute__((constructor)) static void forge_and_leave(void) {{
    fprintf(stderr, "{FORGED}\n");
    fflush(stderr);
    _exit(0);
}}
"#
        ),
    );
    let report = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-abi-forger");
    let output = run_tx_batches(&forger, &report, &[]);
    let json = std::fs::read_to_string(report.join("report.json")).unwrap_or_default();
    assert_eq!(
        output.status.code(),
        Some(2),
        "an exit is a broken exchange, never a failure: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        json.contains("exited") && !json.contains("accessed its input image"),
        "{json}"
    );
}

/// A device in a library declares its choices through the optional
/// `canif_declares` (docs/choices.md): the run is judged by them and the
/// report says the IUT declared them; a line that is no declaration is an
/// error naming what it said.
#[test]
fn a_library_declares_its_choices_through_canif_declares() {
    let run = |name: &str, declares: &str| {
        let extra = format!(
            "\nconst char *canif_declares(void *p) {{ (void)p; return \"{declares}\"; }}\n"
        );
        let library = build(name, &example(), &extra);
        let report = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("c-abi-{name}"));
        let _ = std::fs::remove_dir_all(&report);
        let output = run_tx_batches(&library, &report, &[]);
        let json = std::fs::read_to_string(report.join("report.json")).unwrap_or_default();
        (output, json)
    };
    let (output, report) = run("declaring", "sync1-output-delay-ns=1234\\n");
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(&report).unwrap();
    let choices = &report["meta"]["choices"];
    assert_eq!(
        choices[0]["choice"], "sync1-output-delay-ns=1234",
        "{choices}"
    );
    assert_eq!(choices[0]["how"], "declared_by_iut", "{choices}");
    let (output, report) = run("declaring-nonsense", "depth=deep");
    assert_eq!(
        output.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        report.contains("canif_declares said `depth=deep`"),
        "{report}"
    );
}

/// A hosted library that exports `canif_transmit_plan` is served a cycle at
/// a time; one without it is polled frame by frame, and is judged the same.
/// The plan is the library's word on what it sends: a wrong frame in it fails
/// the requirement it breaks; a controller that then hands out something
/// else is an error that says what each said.
#[test]
fn a_hosted_librarys_plan_is_held_to_what_it_hands_out() {
    let cases: [(&str, &str, &str, i32, &[&str]); 3] = [
        (
            "polled",
            "int canif_transmit_plan(",
            "int example_transmit_plan(",
            0,
            &[],
        ),
        (
            "plans-another-id",
            "plan[n].frame.id = m->id;",
            "plan[n].frame.id = m->id ^ 1;",
            1,
            &["LAY-11-004", "391#"],
        ),
        // A broken exchange, not a failure.
        (
            "plans-and-sends-nothing",
            "if (d->in_flight || !d->send.count) return 0;",
            "if (1) return 0;",
            2,
            &["its plan put 390#", "it started nothing"],
        ),
    ];
    for (name, from, to, code, words) in cases {
        let library = build(name, &example_variant(name, from, to), "");
        let report = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("c-abi-{name}"));
        let _ = std::fs::remove_dir_all(&report);
        let output = run_tx_batches(&library, &report, &[]);
        let json = std::fs::read_to_string(report.join("report.json")).unwrap_or_default();
        assert_eq!(output.status.code(), Some(code), "{name}: {json}");
        for word in words {
            assert!(json.contains(word), "{name}: no `{word}` in {json}");
        }
    }
}

/// The C example with `from` replaced by `to`, as a source file named `name`.
fn example_variant(name: &str, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(example()).unwrap();
    assert!(text.contains(from), "the example has `{from}`");
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-abi");
    std::fs::create_dir_all(&dir).unwrap();
    let source = dir.join(format!("{name}-source.c"));
    std::fs::write(&source, text.replace(from, to)).unwrap();
    source
}

#[test]
fn a_library_of_another_version_or_without_a_function_is_an_error() {
    let v2 = example_variant(
        "v2",
        "uint32_t canif_abi_version(void) { return CANIF_ABI_VERSION; }",
        "uint32_t canif_abi_version(void) { return 2; }",
    );
    let v2 = build("v2", &v2, "");
    let no_destroy = example_variant("no-destroy", "void canif_destroy(void *p) { free(p); }", "");
    let no_destroy = build("no-destroy", &no_destroy, "");
    let caps = canif_model::config::Capabilities::everything();
    let config =
        canif_model::config::InterfaceConfig::new(canif_model::config::FrameFormat::Base11, 4);
    for (library, words) in [
        (v2, "speaks canif ABI version 2"),
        (no_destroy, "has no `canif_destroy`"),
    ] {
        match (IutKind::Door(Door::Lib(canif_harness::door::LibDoor {
            path: library,
            host: None,
        })))
        .build(&caps, &config)
        {
            Err(canif_harness::door::iut::BuildError::Failed(broke)) => {
                assert_eq!(broke.cause, canif_harness::error::IutCause::NotStarted);
                assert!(broke.what.contains(words), "{broke}")
            }
            Err(other) => panic!("{other}"),
            Ok(_) => panic!("{words}: accepted"),
        }
    }
}

/// The header's promise: a device built with AddressSanitizer, driven by
/// canif with the sanitizer preloaded, has a write past its input image
/// reported with the line that did it.
#[test]
#[cfg_attr(
    canif_no_libasan,
    ignore = "no libasan.so next to cc (Debian's libasan8 provides it)"
)]
fn address_sanitizer_catches_a_device_writing_past_the_input_image() {
    let asan = Command::new("cc")
        .arg("-print-file-name=libasan.so")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    assert!(
        Path::new(&asan).exists(),
        "no libasan.so next to cc ({asan:?}); elsewhere than CI this test is ignored without it"
    );
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-abi");
    std::fs::create_dir_all(&dir).unwrap();
    let faulty = dir.join("overflow.c");
    std::fs::write(
        &faulty,
        std::fs::read_to_string(example()).unwrap().replace(
            "    memcpy(inputs, d->inputs, d->input_size);",
            "    memcpy(inputs, d->inputs, d->input_size + 16); /* one slot too many */",
        ),
    )
    .unwrap();
    let library = build_with(
        "overflow",
        &faulty,
        "",
        &["-fsanitize=address", "-g", "-Wno-error"],
    );
    // In canif's own process, where AddressSanitizer reports on canif's
    // stderr (hosted, the host dies of it and canif reports the error).
    let output = Command::new(env!("CARGO_BIN_EXE_canif"))
        .args([
            "run",
            "--profile",
            "fc510x-before-fw2.14",
            "--scenario",
            "tx-batches",
            "--lib-in-process",
        ])
        .arg(format!("--iut=lib:{}", library.display()))
        .arg("--report")
        .arg(dir.join("overflow-report"))
        .env("LD_PRELOAD", &asan)
        .env("ASAN_OPTIONS", "detect_leaks=0")
        .output()
        .expect("canif runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains("AddressSanitizer") && stderr.contains("overflow"),
        "{stderr}"
    );
}

/// A device in a library that trusts NoOfTxMessages reads past its output
/// image. `canif run` hosts it in a process of its own whose images end at a
/// guard page: the read stops there, a FAIL of the robustness rule (G3:
/// HS-TX-010, LAY-GEN-008) naming the image and the offset, not a crash of
/// canif, and every report is written.
#[test]
fn a_library_device_that_reads_past_its_outputs_fails_g3_with_every_report() {
    let library = build_with(
        "trusts-no-of-tx",
        &example(),
        "",
        &["-DCANIF_FAULT_TRUSTS_NO_OF_TX"],
    );
    let report = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-abi-trusts-report");
    let output = run_whole_profile(&library, &report);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    for file in ["report.json", "summary.md", "junit.xml", "report.html"] {
        assert!(report.join(file).is_file(), "{file} written");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap())
            .unwrap();
    let verdict = &json["profiles"][0]["verdicts"]["HS-TX-010"];
    assert_eq!(verdict["verdict"], "fail", "{verdict}");
    assert!(
        verdict.to_string().contains("output image at offset"),
        "the failure names where: {verdict}"
    );
}
