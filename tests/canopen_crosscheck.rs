//! The independent check of the CANopen part: Python's `canopen` package (an
//! SDO/NMT client written by others) drives the simulated coupler through
//! python-can's socketcand interface on loopback TCP and must agree with it;
//! against a coupler that never aborts, it must disagree.
//!
//! Needs python3 with `canopen` and `python-can`; .ci/run installs them. Under
//! CI their absence fails the test; elsewhere it says SKIPPED.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

fn python_canopen_available() -> bool {
    Command::new("python3")
        .args(["-c", "import canopen, can.interfaces.socketcand"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Runs the cross-check against `canif coupler --socketcand 0 [--fault F]`; its exit status and output.
/// `canif coupler` as a socketcand server for node 5, and the port it prints.
fn socketcand_coupler(fault: Option<&str>) -> (std::process::Child, u16) {
    let mut coupler = Command::new(env!("CARGO_BIN_EXE_canif"));
    coupler.args(["coupler", "--socketcand", "0", "--node", "5"]);
    if let Some(fault) = fault {
        coupler.args(["--fault", fault]);
    }
    let mut coupler = coupler
        .stdout(Stdio::piped())
        .spawn()
        .expect("canif coupler starts");
    let mut port = String::new();
    BufReader::new(coupler.stdout.take().unwrap())
        .read_line(&mut port)
        .unwrap();
    let port = port.trim().parse().expect("the coupler prints its port");
    (coupler, port)
}

fn crosscheck(fault: Option<&str>) -> (bool, String) {
    assert!(
        python_canopen_available(),
        "python3 -c 'import canopen, can' fails (pip install canopen python-can; .ci/run does); elsewhere than CI this test is ignored without them"
    );
    let (mut coupler, port) = socketcand_coupler(fault);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/canopen_crosscheck.py"
    );
    let out = Command::new("timeout")
        .args(["120", "python3", script, &port.to_string(), "5"])
        .output()
        .expect("python3 runs");
    let _ = coupler.kill();
    let _ = coupler.wait();
    (
        out.status.success(),
        format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ),
    )
}

/// Covers: SDO-001, SDO-002, SDO-003, SDO-005, SDO-007, SDO-008, HB-001, HB-002, NMT-003, NMT-004, NMT-008, NMT-009
#[test]
#[cfg_attr(
    canif_no_python_canopen,
    ignore = "python3 lacks canopen and python-can (pip install canopen python-can; .ci/run does)"
)]
fn pythons_canopen_agrees_with_the_simulated_coupler() {
    let (ok, output) = crosscheck(None);
    assert!(ok, "the canopen package disagrees:\n{output}");
    // 8 checks of 002/004, and a stopped node and reset communication (CiA 301).
    assert_eq!(output.matches("\"ok\": true").count(), 10, "{output}");
}

#[test]
#[cfg_attr(
    canif_no_python_canopen,
    ignore = "python3 lacks canopen and python-can (pip install canopen python-can; .ci/run does)"
)]
fn pythons_canopen_notices_a_coupler_that_does_not_abort() {
    let (ok, output) = crosscheck(Some("no-abort"));
    assert!(
        !ok,
        "the cross-check passed a coupler without aborts:\n{output}"
    );
    assert!(
        output.contains("\"SDO abort: object does not exist\": {\"ok\": false"),
        "{output}"
    );
}

/// A socketcand server keeps serving: one client leaves, the next is greeted.
#[test]
fn the_socketcand_coupler_serves_one_client_after_another() {
    use std::io::Read;
    let (mut coupler, port) = socketcand_coupler(None);
    for client in 0..3 {
        let mut stream = std::net::TcpStream::connect(("127.0.0.1", port))
            .unwrap_or_else(|e| panic!("client {client}: {e}"));
        stream
            .set_read_timeout(Some(std::time::Duration::from_secs(5)))
            .unwrap();
        let mut greeting = [0u8; 6];
        stream.read_exact(&mut greeting).unwrap();
        assert_eq!(&greeting, b"< hi >", "client {client}");
    }
    let _ = coupler.kill();
    let _ = coupler.wait();
}
