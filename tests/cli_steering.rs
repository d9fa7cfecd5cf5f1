//! Steering a long run: `canif run --jobs N` runs profiles side by side and
//! says the same as a serial run, on both sides, and refuses where the
//! profiles would share one link, bus or process; `--rerun-failed` runs
//! only what failed, and a check that failed and passes now is FLAKY, exit
//! 1, never a pass.

use std::process::{Command, Output};

fn canif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(args)
        .output()
        .expect("canif runs")
}

fn dir(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("canif-jobs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir.display().to_string()
}

/// report.json without what a run's timing puts in it.
fn verdicts(report_dir: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(format!("{report_dir}/report.json")).unwrap();
    let mut report: serde_json::Value = serde_json::from_str(&text).unwrap();
    report["wall_time_ms"] = 0.into();
    report["meta"]["started_unix"] = 0.into();
    for profile in report["profiles"].as_array_mut().unwrap() {
        for check in profile["checks"].as_array_mut().unwrap() {
            check["elapsed_ms"] = 0.into();
        }
    }
    report
}

fn run(side: &str, fault: &str, jobs: &str, name: &str) -> (Option<i32>, serde_json::Value) {
    let report = dir(name);
    let output = canif(&[
        "run",
        side,
        "--fault",
        fault,
        "--profile",
        "fc510x",
        "--profile",
        "fc532x",
        "--profile",
        "el6751-mdp",
        "--jobs",
        jobs,
        "--report",
        &report,
    ]);
    (output.status.code(), verdicts(&report))
}

#[test]
fn parallel_profiles_give_a_serial_runs_verdicts_on_both_sides() {
    for (side, fault) in [("device", "fd-padding-ff"), ("plc", "own-rx-counter")] {
        let (serial_code, serial) = run(side, fault, "1", &format!("{side}-1"));
        let (parallel_code, parallel) = run(side, fault, "3", &format!("{side}-3"));
        assert_eq!(serial_code, Some(1), "{side}: the fault fails");
        assert_eq!(parallel_code, serial_code, "{side}");
        assert!(serial == parallel, "{side}: --jobs 3 changed the report");
    }
}

#[test]
fn profiles_that_would_share_a_link_a_bus_or_a_process_are_refused() {
    for (args, shared) in [
        (vec!["--iut", "ethercat:emulated"], "an EtherCAT terminal"),
        (vec!["--bus", "socketcan:vcan0"], "a SocketCAN bus"),
        (
            vec!["--iut", "lib:./no.so", "--lib-in-process"],
            "--lib-in-process",
        ),
    ] {
        let mut all = vec!["run", "--jobs", "2"];
        all.extend(args);
        let output = canif(&all);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{all:?}: {stderr}");
        assert!(stderr.contains(shared), "{all:?}: {stderr}");
    }
}

#[test]
fn a_rerun_runs_only_what_failed_and_calls_a_check_that_now_passes_flaky() {
    let first = dir("first");
    let output = canif(&["run", "--profile", "fc510x", "--report", &first]);
    assert_eq!(output.status.code(), Some(0));
    // The run before, as an IUT that failed once would have left it: one
    // check failed (the soft device is deterministic; the report is edited).
    let mut report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{first}/report.json")).unwrap())
            .unwrap();
    let checks = report["profiles"][0]["checks"].as_array_mut().unwrap();
    let check = checks
        .iter_mut()
        .find(|c| c["check"] == "scenario: rx-handshake [11-bit]")
        .expect("the Rx handshake ran");
    check["outcome"] = "fail".into();
    let edited = format!("{first}/edited.json");
    std::fs::write(&edited, report.to_string()).unwrap();

    let again = dir("again");
    let output = canif(&["run", "--rerun-failed", &edited, "--report", &again]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr),
    );
    assert_eq!(output.status.code(), Some(1), "{stdout}{stderr}");
    assert!(stdout.contains("FLAKY (1 check(s)"), "{stdout}");
    assert!(
        stderr.contains("FLAKY fc510x::scenario: rx-handshake [11-bit]"),
        "{stderr}"
    );
    let rerun = verdicts(&again);
    assert_eq!(rerun["flaky"][0], "fc510x::scenario: rx-handshake [11-bit]");
    let ran: Vec<&str> = rerun["profiles"][0]["checks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["check"].as_str().unwrap())
        .collect();
    assert!(
        !ran.is_empty() && ran.iter().all(|c| c.contains("rx-handshake [11-bit")),
        "{ran:?}"
    );
    let summary = std::fs::read_to_string(format!("{again}/summary.md")).unwrap();
    assert!(summary.contains("## Flaky"), "{summary}");

    // Nothing failed: nothing to rerun, and no verdict claimed.
    let output = canif(&[
        "run",
        "--rerun-failed",
        &format!("{first}/report.json"),
        "--report",
        &dir("none"),
    ]);
    assert_eq!(output.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&output.stdout).contains("nothing to rerun"));
    // Another implementation's report is not this one's to rerun.
    let output = canif(&["run", "--rerun-failed", &edited, "--fault", "fd-padding-ff"]);
    assert_eq!(output.status.code(), Some(2));
}

/// On a terminal a run says which scenario of how many it is at and about
/// how long the rest take; its count is the summary's `scenarios` column.
#[test]
fn a_run_on_a_terminal_shows_its_pace_with_the_summarys_counts() {
    let report = dir("tty");
    let command = format!(
        "{} run --profile fc510x --report {report}",
        env!("CARGO_BIN_EXE_canif")
    );
    // script(1) gives canif a terminal, as a user's shell would.
    let output = Command::new("script")
        .args(["-qc", &command, "/dev/null"])
        .output()
        .expect("script (util-linux) gives the run a terminal");
    let shown = String::from_utf8_lossy(&output.stdout).replace('\r', "\n");
    let summary = std::fs::read_to_string(format!("{report}/summary.md")).unwrap();
    let row = summary
        .lines()
        .find(|l| l.starts_with("| fc510x |"))
        .expect("the profile's row");
    let scenarios: usize = row.split('|').nth(8).unwrap().trim().parse().unwrap();
    assert!(
        shown.contains(&format!("(1 of {scenarios} scenarios, ")),
        "{shown}"
    );
    assert!(shown.contains("s left)"), "{shown}");
    assert!(
        shown.contains(&format!("{scenarios} scenarios, ")),
        "the profile's line says the summary's count: {shown}"
    );
}
