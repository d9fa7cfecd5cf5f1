//! Issue 26's declared choices, as a user meets them: where 003 leaves open
//! whether the frame on the wire counts against the send queue (HS-TX-012),
//! a device that declares its choice is judged by it, one that declares
//! nothing passes under either and is held to the one it showed, and `canif
//! probe` finds the choice and writes it as a declaration `run` takes.
//!
//! The device that counts the frame on the wire is the soft device with
//! `--choice counts-frame-on-wire`; behind the adapter protocol (`canif
//! device --stdio`) it declares nothing, as an independent device would.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_canif");

fn canif(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("canif runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-choices-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn report(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

/// The device that counts the frame on the wire, as another process.
fn counting_device() -> String {
    format!("exec:{BIN} device --stdio --choice counts-frame-on-wire")
}

/// `canif run` of the scenario that tells the accountings apart, on fc510x.
fn backpressure(name: &str, iut: &str, extra: &[&str]) -> (Output, PathBuf) {
    let dir = scratch(name);
    let mut args = vec![
        "run",
        "--profile",
        "fc510x",
        "--scenario",
        "tx-backpressure",
        "--iut",
        iut,
        "--report",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    (canif(&args), dir)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn an_undeclared_device_passes_under_the_choice_it_shows_and_the_report_says_which() {
    let (out, dir) = backpressure("undeclared", &counting_device(), &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let choices = &report(&dir)["meta"]["choices"];
    assert_eq!(
        choices[0]["choice"], "tx-queue-accounting=wire-in-queue",
        "{choices}"
    );
    assert_eq!(
        choices[0]["how"]["observed"]["profile"], "fc510x",
        "{choices}"
    );
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(
        summary.contains("undeclared; shown by `tx-backpressure"),
        "{summary}"
    );
}

#[test]
fn a_declared_choice_is_judged_as_declared_and_breaking_it_fails() {
    let declare = ["--declare", "tx-queue-accounting=wire-in-queue"];
    let (out, dir) = backpressure("declared", &counting_device(), &declare);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(report(&dir)["meta"]["choices"][0]["how"], "declared");
    // The same device declaring the other reading fails the Tx handshake.
    let other = ["--declare", "tx-queue-accounting=wire-outside-queue"];
    let (out, dir) = backpressure("declared-other", &counting_device(), &other);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(summary.contains("FAIL fc510x::HS-TX-"), "{summary}");
    // The built-in soft device, which does not count it, declares so
    // itself: told otherwise, the run is refused, naming both (issue 52).
    let (out, _) = backpressure("soft-declared", "softdevice", &declare);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("one of them is wrong"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn the_soft_devices_choice_is_its_declaration() {
    let (out, dir) = backpressure(
        "soft-choice",
        "softdevice",
        &["--choice", "counts-frame-on-wire"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(
        report(&dir)["meta"]["choices"][0]["choice"],
        "tx-queue-accounting=wire-in-queue"
    );
}

#[test]
fn probe_finds_the_choice_and_run_takes_its_file() {
    let dir = scratch("probe");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("choices.json");
    let out = canif(&[
        "probe",
        "--profile",
        "fc510x",
        "--iut",
        &counting_device(),
        "--out",
        file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // The served soft device declares nothing itself: every value is found
    // by the probes (its accounting the other way round, the rest the reference's).
    let found = [
        "tx-queue-accounting=wire-in-queue",
        "oversize-batch=sends-the-slots",
        "bad-tx-length=clamps",
        "rx-idle-count=keeps-the-last",
        "stale-rx-slots=zeroed",
    ];
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        found.join("\n")
    );
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(
        written,
        serde_json::json!({
            "tx-queue-accounting": "wire-in-queue",
            "oversize-batch": "sends-the-slots",
            "bad-tx-length": "clamps",
            "rx-idle-count": "keeps-the-last",
            "stale-rx-slots": "zeroed",
        })
    );
    let at_file = format!("@{}", file.display());
    let (out, report_dir) = backpressure("probed", &counting_device(), &["--declare", &at_file]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(report(&report_dir)["meta"]["choices"][0]["how"], "declared");
}

#[test]
fn a_declaration_that_cannot_be_read_is_a_usage_error_naming_it() {
    for (declare, says) in [
        ("wire-in-queue", "is not NAME=VALUE"),
        (
            "choices.json",
            "a file of declarations is `--declare @choices.json`",
        ),
        ("queue=deep", "`queue` is no choice"),
        (
            "tx-queue-accounting=maybe",
            "wire-outside-queue or wire-in-queue",
        ),
        (
            "@/nonexistent/choices.json",
            "--declare @/nonexistent/choices.json",
        ),
    ] {
        let out = canif(&["run", "--profile", "fc510x", "--declare", declare]);
        assert_eq!(out.status.code(), Some(2), "{declare}: {}", stderr(&out));
        assert!(stderr(&out).contains(says), "{declare}: {}", stderr(&out));
    }
    let out = canif(&[
        "run",
        "plc",
        "--declare",
        "tx-queue-accounting=wire-in-queue",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
}

/// Ruling R10: a device's first message starts its own output delay after
/// SYNC1, within 500 ns, and no document gives the delay. A device that
/// starts every batch 2 µs after SYNC1 conforms when it declares nothing or
/// declares 2 µs, and fails PDX-004 when it declares 0.
#[test]
fn a_constant_output_delay_after_sync1_conforms_unless_another_is_declared() {
    let late = format!("exec:{BIN} device --stdio --fault sync1-late");
    let dc = |name: &str, extra: &[&str]| {
        let dir = scratch(name);
        let mut args = vec![
            "run",
            "--profile",
            "el6751-mdp",
            "--scenario",
            "distributed-clocks",
            "--iut",
            &late,
            "--report",
            dir.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        (canif(&args), dir)
    };
    let (out, _) = dc("r10-undeclared", &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let (out, _) = dc("r10-declared", &["--declare", "sync1-output-delay-ns=2000"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let (out, dir) = dc("r10-zero", &["--declare", "sync1-output-delay-ns=0"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(summary.contains("FAIL el6751-mdp::PDX-004"), "{summary}");
}

/// A device can declare its choice itself, in its `configured` answer: it is
/// judged by it, the report says the IUT declared it, and a device that
/// declares the frame on the wire in its queue but does not count it fails.
#[test]
fn a_device_declares_its_choice_in_its_configured_answer() {
    let declaring = |extra: &str| {
        format!("exec:{BIN} device --stdio {extra} --declare tx-queue-accounting=wire-in-queue")
    };
    let (out, dir) = backpressure(
        "self-declared",
        &declaring("--choice counts-frame-on-wire"),
        &[],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let choices = &report(&dir)["meta"]["choices"];
    assert_eq!(
        choices[0]["choice"], "tx-queue-accounting=wire-in-queue",
        "{choices}"
    );
    assert_eq!(choices[0]["how"], "declared_by_iut", "{choices}");
    let (out, dir) = backpressure("self-declared-broken", &declaring(""), &[]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(summary.contains("FAIL fc510x::HS-TX-"), "{summary}");
}

/// HS-TX-008's depth is an assumption (no document gives it): a device
/// declares its own and is judged by it. The soft device holds the profile's
/// 64 messages: declared as 64 it conforms, declared as 8 it fails the Tx
/// handshake, as a device that claims a depth it does not have would.
#[test]
fn a_declared_send_queue_depth_is_the_one_judged() {
    let (out, dir) = backpressure(
        "depth-64",
        "softdevice",
        &["--declare", "tx-queue-depth=64"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(
        summary.contains("tx-queue-depth=64 (declared)"),
        "{summary}"
    );
    let (out, dir) = backpressure("depth-8", "softdevice", &["--declare", "tx-queue-depth=8"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(summary.contains("FAIL fc510x::HS-TX-"), "{summary}");
    let out = canif(&[
        "run",
        "--profile",
        "fc510x",
        "--declare",
        "tx-queue-depth=0",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("a number of messages"),
        "{}",
        stderr(&out)
    );
}

/// The freedoms of G3 and what a buffered delivery leaves: a device behind
/// the protocol that takes the other value of each, declaring nothing, is
/// found out by the probe, conforms declaring what it found, and fails
/// declaring the reference's values, each on its own requirement.
#[test]
fn probe_finds_every_freedom_and_a_declaration_against_it_fails_on_its_requirement() {
    let dir = scratch("probe-freedoms");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("choices.json");
    let device = format!(
        "exec:{BIN} device --stdio --choice clears-rx-count-when-idle --choice keeps-stale-rx-slots \
         --choice refuses-oversize-batch --choice drops-message-with-bad-length"
    );
    let out = canif(&[
        "probe",
        "--profile",
        "fc510x",
        "--iut",
        &device,
        "--out",
        file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(
        written,
        serde_json::json!({
            "tx-queue-accounting": "wire-outside-queue",
            "oversize-batch": "drops-the-batch",
            "bad-tx-length": "drops-the-message",
            "rx-idle-count": "writes-zero",
            "stale-rx-slots": "kept",
        })
    );
    let run = |name: &str, declares: &[&str]| {
        let report_dir = scratch(name);
        let mut args = vec!["run", "--profile", "fc510x", "--iut", &device];
        for line in declares {
            args.extend(["--declare", line]);
        }
        let report = report_dir.to_str().unwrap().to_string();
        args.extend(["--report", &report]);
        let out = canif(&args);
        (out, report_dir)
    };
    let at_file = format!("@{}", file.display());
    let (out, _) = run("freedoms-found", &[&at_file]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    for (line, requirement) in [
        ("oversize-batch=sends-the-slots", "HS-TX-010"),
        ("bad-tx-length=clamps", "LAY-GEN-008"),
        ("rx-idle-count=keeps-the-last", "HS-RX-009"),
        ("stale-rx-slots=zeroed", "HS-RX-008"),
    ] {
        // Against the file, the line contradicts it: refused, naming both.
        let (out, _) = run(line, &[&at_file, line]);
        assert_eq!(out.status.code(), Some(2), "{line}: {}", stderr(&out));
        assert!(
            stderr(&out).contains("declared twice, two ways") && stderr(&out).contains(line),
            "{line}: {}",
            stderr(&out)
        );
        let (out, report_dir) = run(line, &[line]);
        assert_eq!(out.status.code(), Some(1), "{line}: {}", stderr(&out));
        let verdicts = &report(&report_dir)["profiles"][0]["verdicts"];
        assert_eq!(
            verdicts[requirement]["verdict"], "fail",
            "{line}: {requirement} is {}",
            verdicts[requirement]
        );
    }
}

/// Issue 52: a declaration is never dropped. `canif probe` reads `--declare`
/// as `canif run` does (a bad one exits 2 naming it; a good one is not probed
/// and is in the file it writes), and a declaration that contradicts the
/// built-in soft device's own choice is the same error on every route.
#[test]
fn a_declaration_is_never_dropped_and_a_contradiction_is_one_error_everywhere() {
    let dir = scratch("never-dropped");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("choices.json");
    let file_text = file.display().to_string();
    for bad in ["foo", "warp-drive=on"] {
        let out = canif(&[
            "probe",
            "--profile",
            "fc510x",
            "--declare",
            bad,
            "--out",
            &file_text,
        ]);
        assert_eq!(out.status.code(), Some(2), "{bad}: {}", stderr(&out));
        assert!(
            stderr(&out).contains(bad.split('=').next().unwrap()),
            "{}",
            stderr(&out)
        );
        assert!(!file.exists(), "{bad}: a file was written");
    }
    let declared = "tx-queue-accounting=wire-in-queue";
    let out = canif(&[
        "probe",
        "--profile",
        "fc510x",
        "--choice",
        "counts-frame-on-wire",
        "--declare",
        declared,
        "--out",
        &file_text,
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("(declared, not probed)"));
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(written["tx-queue-accounting"], "wire-in-queue");
    // The soft device told to count the frame on the wire declares so
    // itself: a command line that says otherwise is refused on every route.
    let contradiction = [
        "--choice",
        "counts-frame-on-wire",
        "--declare",
        "tx-queue-accounting=wire-outside-queue",
    ];
    let report_dir = dir.join("run").display().to_string();
    let certificate_dir = dir.join("certificate").display().to_string();
    for route in [
        &["run", "--profile", "fc510x", "--report", &report_dir][..],
        &["probe", "--profile", "fc510x", "--out", &file_text],
        &["certify", "--profile", "fc510x", "--out", &certificate_dir],
    ] {
        let out = canif(&[route, &contradiction[..]].concat());
        assert_eq!(out.status.code(), Some(2), "{route:?}: {}", stderr(&out));
        for words in [
            "wire-in-queue",
            "wire-outside-queue",
            "one of them is wrong",
        ] {
            assert!(stderr(&out).contains(words), "{route:?}: {}", stderr(&out));
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}
