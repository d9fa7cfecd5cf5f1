//! Verdicts as a new user meets them on the command line (issue 14's
//! numbered problems): a selection that matches nothing, a partial run, the
//! CANopen suite's reports, and a compare gate that refuses other runs.

use std::path::PathBuf;
use std::process::{Command, Output};

fn canif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(args)
        .output()
        .expect("canif runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn report(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

/// A trace folder that cannot be written is a usage error naming it, before
/// the run (it wrote nothing and said nothing, exit 0; issue 26).
#[test]
fn an_unwritable_trace_folder_is_refused_with_its_path() {
    let dir = scratch("trace");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, b"").unwrap();
    let target = file.join("traces");
    let out = canif(&[
        "run",
        "--profile",
        "fc510x",
        "--trace",
        target.to_str().unwrap(),
        "--report",
        dir.join("report").to_str().unwrap(),
    ]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(said.contains(target.to_str().unwrap()), "{said}");
    assert!(!dir.join("report").exists(), "the run started");
    let _ = std::fs::remove_dir_all(dir);
}

/// Problem 2: a selection that matches nothing is a usage error, not "conforms".
#[test]
fn a_selection_that_matches_nothing_is_a_usage_error() {
    // The report folder cannot be written: only a refusal before the run can exit without it.
    for (args, said) in [
        (
            &["run", "--profile", "fc532x", "--scenario", "FD-LEN-005"][..],
            "matches no check",
        ),
        (
            &["run", "--scenario", "no-such-scenario-xyz"],
            "matches no check",
        ),
        (
            &["run", "--requirement", "NO-SUCH-001"],
            "no such requirement",
        ),
    ] {
        let out = canif(&[args, &["--report", "/nonexistent/never"]].concat());
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(said), "{args:?}: {stderr}");
        assert!(!String::from_utf8_lossy(&out.stdout).contains("CONFORMS"));
    }
}

/// Issue 37: a mistyped name gets the nearest known one; a name near
/// nothing gets none.
#[test]
fn a_typo_gets_a_did_you_mean() {
    for (args, said) in [
        (
            &["run", "--profile", "el6751-mpd"][..],
            "unknown profile `el6751-mpd` (did you mean `el6751-mdp`?)",
        ),
        (
            &["run", "--fault", "fd-lenght-as-dlc"],
            "unknown fault `fd-lenght-as-dlc` (did you mean `fd-length-as-dlc`?)",
        ),
        (
            &["run", "--requirement", "HS-TX-07"],
            "no such requirement (did you mean `HS-TX-007`?)",
        ),
    ] {
        let out = canif(&[args, &["--report", "/nonexistent/never"]].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(said), "{args:?}: {stderr}");
    }
    let out = canif(&["spec", "show", "hs-tx-007x"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("(did you mean `HS-TX-007`?)"), "{stderr}");
    let out = canif(&["run", "--profile", "xyz", "--report", "/nonexistent/never"]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("did you mean"));
}

/// A requirement selected alone: its checks run, the rest is `not run`, and
/// the run is not called conforming.
#[test]
fn a_partial_run_says_so() {
    let dir = scratch("partial");
    let out = canif(&[
        "run",
        "--profile",
        "fc532x",
        "--requirement",
        "FD-LEN-005",
        "--cases",
        "1",
        "--report",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("PASSES WHAT RAN") && !stdout.contains("CONFORMS"),
        "{stdout}"
    );
    let r = report(&dir);
    let verdicts = &r["profiles"][0]["verdicts"];
    assert_eq!(verdicts["FD-LEN-005"]["verdict"], "pass");
    assert_eq!(verdicts["FLT-001"]["verdict"], "not run");
    assert_eq!(r["meta"]["complete"], false);
    // A device run reports on device requirements of the interface suite
    // only: no PLC-side requirement, no CANopen node requirement it cannot
    // reach, and so no "not run" for what another side or suite judges.
    let ids: Vec<&str> = verdicts
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    assert!(!ids.iter().any(|id| id.starts_with("CL-")), "{ids:?}");
    assert!(!ids.contains(&"HB-005"), "the CANopen suite's: {ids:?}");
    assert!(
        ids.contains(&"SDO-001"),
        "exercised by the Gherkin quick start: {ids:?}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// Problem 5's last point: `canif run canopen` writes the same reports and
/// refuses options that do not apply to it.
#[test]
fn the_canopen_suite_writes_reports_and_refuses_iut_options() {
    let dir = scratch("canopen");
    let out = canif(&[
        "run",
        "canopen",
        "--coupler-fault",
        "toggle-stuck",
        "--report",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let r = report(&dir);
    assert_eq!(r["meta"]["suite"], "canopen");
    // A stuck toggle bit breaks the guarding answer (GRD-002), not the NMT
    // start whose state that answer could not show (issue 36).
    assert_eq!(r["profiles"][0]["verdicts"]["GRD-002"]["verdict"], "fail");
    assert_ne!(r["profiles"][0]["verdicts"]["NMT-006"]["verdict"], "fail");
    assert_ne!(r["profiles"][0]["verdicts"]["GRD-001"]["verdict"], "fail");
    // The node's requirements only: none of the interface's.
    assert!(r["profiles"][0]["verdicts"].get("HS-TX-001").is_none());
    assert!(std::fs::read_to_string(dir.join("junit.xml"))
        .unwrap()
        .contains("GRD-002"));
    for args in [&["--iut", "model"][..], &["--fault", "fd-padding-ff"]] {
        let out = canif(&[&["run", "canopen", "--report", dir.to_str().unwrap()], args].concat());
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        // clap refuses a flag `canif run canopen` does not have, naming it.
        let said = String::from_utf8_lossy(&out.stderr);
        assert!(
            said.contains(&format!("unexpected argument '{}'", args[0])),
            "{args:?}: {said}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Problem 3: a report with fewer profiles is refused, and with --force the
/// vanished checks are regressions.
#[test]
fn compare_refuses_a_report_of_fewer_profiles() {
    let dir = scratch("compare");
    std::fs::create_dir_all(&dir).unwrap();
    let baseline = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/reports/baseline/softdevice.json"
    );
    let mut r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(baseline).unwrap()).unwrap();
    r["profiles"].as_array_mut().unwrap().truncate(1);
    let fewer = dir.join("fewer.json");
    std::fs::write(&fewer, r.to_string()).unwrap();
    let out = canif(&["compare", baseline, fewer.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("profiles"));
    let out = canif(&[
        "compare",
        baseline,
        fewer.to_str().unwrap(),
        "--force",
        "--format",
        "json",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let answer: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(answer["removed"].as_array().unwrap().len() > 1000);
    let _ = std::fs::remove_dir_all(dir);
}

/// The PLC side as a new user meets it: the reference client conforms and the
/// report says side plc and names the masters; a client fault exits 1 naming
/// its requirement; a selection that matches nothing and a wrong --iut or
/// --master are usage errors; `list scenarios --side plc` lists what
/// --scenario selects.
#[test]
fn the_plc_side_on_the_command_line() {
    let dir = scratch("plc");
    let dir_text = dir.display().to_string();
    let output = canif(&["run", "plc", "--profile", "fc510x", "--report", &dir_text]);
    assert_eq!(output.status.code(), Some(0), "{output:?}");
    let report = report(&dir);
    assert_eq!(report["meta"]["side"], "plc");
    // The PLC side's requirements only: no device requirement as "not run".
    let verdicts = report["profiles"][0]["verdicts"].as_object().unwrap();
    assert!(
        verdicts.keys().all(|id| id.starts_with("CL-")),
        "{verdicts:?}"
    );
    assert_eq!(report["meta"]["masters"][0], "lrw");
    assert!(report["meta"]["masters"].as_array().unwrap().len() >= 7);
    // The certificate names what the client was driven under, not only the side.
    let certificate_dir = scratch("plc-certificate");
    let output = canif(&[
        "certify",
        "--side",
        "plc",
        "--profile",
        "fc510x",
        "--out",
        &certificate_dir.display().to_string(),
    ]);
    assert_eq!(output.status.code(), Some(0), "{output:?}");
    let certificate: serde_json::Value =
        serde_json::from_slice(&std::fs::read(certificate_dir.join("certificate.json")).unwrap())
            .unwrap();
    assert_eq!(certificate["conforms"], true, "{certificate}");
    assert_eq!(certificate["side"], "plc");
    assert_eq!(certificate["masters"], report["meta"]["masters"]);
    assert_eq!(certificate["bus"], report["meta"]["bus"]);
    assert!(certificate.get("left_out").is_none(), "{certificate}");
    // A client that only sends, declaring it: certified on that, and the
    // certificate says what it rests on and what was not run.
    let tx_only = scratch("plc-certificate-tx-only");
    let output = canif(&[
        "certify",
        "--side",
        "plc",
        "--profile",
        "fc510x",
        "--iut",
        "softclient",
        "--choice",
        "tx-only",
        "--out",
        &tx_only.display().to_string(),
    ]);
    assert_eq!(output.status.code(), Some(0), "{output:?}");
    let certificate: serde_json::Value =
        serde_json::from_slice(&std::fs::read(tx_only.join("certificate.json")).unwrap()).unwrap();
    assert_eq!(certificate["conforms"], true, "{certificate}");
    assert!(
        certificate["choices"].to_string().contains("direction=tx"),
        "{certificate}"
    );
    assert!(
        certificate["not_served"]
            .to_string()
            .contains("frames from the bus — the client declares direction=tx"),
        "{certificate}"
    );
    assert_eq!(
        certificate["verdicts"]["fc510x::CL-RX-002"]["verdict"],
        "not applicable"
    );
    let page = std::fs::read_to_string(tx_only.join("certificate.html")).unwrap();
    assert!(page.contains("not served (not run)"), "{page}");
    let summary = std::fs::read_to_string(tx_only.join("run/summary.md")).unwrap();
    assert!(
        summary.contains("- fc510x: frames from the bus — the client declares direction=tx"),
        "{summary}"
    );
    let html = std::fs::read_to_string(tx_only.join("run/report.html")).unwrap();
    assert!(html.contains("<ul id=\"not-served\">"), "{html}");
    let output = canif(&[
        "run",
        "plc",
        "--profile",
        "fc510x",
        "--fault",
        "drops-rtr",
        "--report",
        &dir_text,
    ]);
    let said = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{said}");
    assert!(said.contains("fc510x::CL-TX-004"), "{said}");
    for (args, words) in [
        (
            &["run", "plc", "--scenario", "no-such-xyz"][..],
            "matches no check",
        ),
        (
            &["run", "plc", "--iut", "model"],
            "the PLC side runs a client",
        ),
        (
            &["run", "plc", "--master", "ethercat-9000"],
            "unknown master",
        ),
        (
            &["run", "plc", "--fault", "no-such-fault"],
            "unknown client fault",
        ),
        (&["run", "--iut", "reference"], "use `canif run plc`"),
        // Issue 36: a statement of the other side says where it is judged.
        (
            &["run", "plc", "--requirement", "HS-TX-001"],
            "binds the device side, not the plc side: `canif run device --requirement HS-TX-001` judges it; this side's own statement: CL-TX-001",
        ),
        (
            &["run", "--requirement", "CL-RX-004"],
            "`canif run plc --requirement CL-RX-004` judges it",
        ),
        (
            &["run", "plc", "--cases", "9"],
            "unexpected argument '--cases'",
        ),
    ] {
        let output = canif(args);
        let said = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {said}");
        assert!(said.contains(words), "{args:?}: {said}");
    }
    let listed = canif(&["list", "scenarios", "--side", "plc", "--profile", "fc510x"]);
    let listed = String::from_utf8_lossy(&listed.stdout);
    assert!(listed
        .lines()
        .any(|l| l.contains("device restart") && l.contains("CL-RST-002")));
    assert!(listed.lines().any(|l| l.contains("plc-client.feature")));
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 36: the manual's rule "Es müssen immer alle Daten ausgelesen werden"
/// (000 §6) is the PLC side's own requirement: selected by its id, a client
/// that acknowledges a batch half read fails it, and the copy rule passes.
#[test]
fn a_client_acknowledging_a_half_read_batch_fails_the_read_all_rule() {
    let dir = std::env::temp_dir().join(format!("canif-read-all-{}", std::process::id()));
    let dir_text = dir.to_str().unwrap().to_string();
    let output = canif(&[
        "run",
        "plc",
        "--profile",
        "fc510x",
        "--requirement",
        "CL-RX-004",
        "--fault",
        "acknowledges-after-first-message",
        "--report",
        &dir_text,
    ]);
    let said = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{said}");
    let report = report(&dir);
    let verdicts = &report["profiles"][0]["verdicts"];
    assert_eq!(verdicts["CL-RX-004"]["verdict"], "fail", "{verdicts}");
    assert_ne!(verdicts["CL-RX-001"]["verdict"], "fail", "{verdicts}");
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 36: a device that drops the oldest frames of a full queue breaks the
/// tail drop canif assumes (G4, RXQ-004), no statement of the documents: the
/// failure is charged to that assumption alone and says it is one.
#[test]
fn a_breached_assumption_is_charged_alone_and_said_to_be_one() {
    let dir = scratch("assumption");
    let out = canif(&[
        "run",
        "--profile",
        "el6751-mdp",
        "--fault",
        "head-drop-when-full",
        "--report",
        dir.to_str().unwrap(),
    ]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(
        said.contains("FAIL el6751-mdp::RXQ-004 (assumption): "),
        "{said}"
    );
    // Neither the lockstep nor a Gherkin scenario charges it to a statement
    // of the documents: not the depth, the loss, the slots or the order.
    let verdicts = &report(&dir)["profiles"][0]["verdicts"];
    for normative in ["RXQ-001", "RXQ-003", "RXQ-006", "HS-RX-007"] {
        assert_ne!(verdicts[normative]["verdict"], "fail", "{normative}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// `canif run --side plc`, the spelling before `canif run plc`, still runs
/// the PLC side for one release, and says it is deprecated.
#[test]
fn the_old_spelling_of_the_plc_side_still_runs_it_and_says_so() {
    let dir = scratch("deprecated-side");
    let output = canif(&[
        "run",
        "--side",
        "plc",
        "--profile",
        "fc510x",
        "--requirement",
        "CL-RX-002",
        "--report",
        dir.to_str().unwrap(),
    ]);
    let said = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{said}");
    assert!(
        said.contains("`--side plc` is deprecated") && said.contains("`canif run plc`"),
        "{said}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["meta"]["side"], "plc");
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 57: a certificate that names a product names what it tested: with
/// `--product` and no `--iut`, `canif certify` refuses, before any run.
#[test]
fn a_product_certificate_needs_the_iut_it_vouches_for() {
    let dir = scratch("product-without-iut");
    let out_dir = dir.display().to_string();
    let args = [
        "certify",
        "--profile",
        "fc510x",
        "--product",
        "My gateway",
        "--product-version",
        "1.2",
        "--out",
        &out_dir,
    ];
    let output = canif(&args);
    let said = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{said}");
    assert!(
        said.contains("--iut") && said.contains("My gateway"),
        "{said}"
    );
    assert!(
        !dir.join("certificate.json").exists(),
        "a certificate was written"
    );
}
