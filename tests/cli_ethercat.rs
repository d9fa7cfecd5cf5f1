//! `canif run --iut ethercat:emulated` as a new user runs it: the soft device
//! behind an emulated EtherCAT terminal, reached through real EtherCAT frames
//! by canif's master. Exit 0 on every terminal profile; exit 1 with a fault,
//! on the fault's requirement; exit 2 for a profile that is no terminal.

use std::process::{Command, Output};

fn canif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(args)
        .output()
        .expect("canif runs")
}

fn report_dir(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("canif-ecat-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir.to_string_lossy().into_owned()
}

#[test]
fn every_terminal_profile_conforms_through_ethercat_and_a_fault_fails_its_requirement() {
    let dir = report_dir("pass");
    let out = canif(&[
        "run",
        "--iut",
        "ethercat:emulated",
        "--profile",
        "el6751-legacy",
        "--profile",
        "el6751-mdp",
        "--requirement",
        "HS-TX-001",
        "--requirement",
        "FLT-001",
        "--report",
        &dir,
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A selection is a partial run: it passes what ran, it does not "conform".
    assert!(
        stdout.contains("ethercat:emulated PASSES WHAT RAN"),
        "{stdout}"
    );
    assert!(stdout.contains(" 0 fail, 0 error"), "{stdout}");

    let dir = report_dir("fault");
    let out = canif(&[
        "run",
        "--iut",
        "ethercat:emulated",
        "--fault",
        "filter-last-match-wins",
        "--profile",
        "el6751-mdp",
        "--requirement",
        "FLT-001",
        "--report",
        &dir,
    ]);
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(said.contains("FAIL el6751-mdp::FLT-001"), "{said}");
}

#[test]
fn a_profile_that_is_no_terminal_is_a_usage_error_naming_the_terminals() {
    let out = canif(&["run", "--iut", "ethercat:emulated", "--profile", "fc510x"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("fc510x is no EtherCAT terminal"),
        "{stderr}"
    );
    assert!(stderr.contains("el6751-legacy, el6751-mdp"), "{stderr}");
}
