//! The SocketCAN options of the command line where the bus cannot be opened:
//! a clear error and exit 2, never a pass. On this machine kind the kernel has
//! no AF_CAN (the message carries its errno); on a kernel with CAN the
//! interface below does not exist (the message says so). The runs over real
//! interfaces are in `socketcan_lane.rs`.

use std::process::Command;

const MISSING: &str = "socketcan:canifnone0";

fn canif(args: &[&str]) -> (Option<i32>, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(args)
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// What the kernel says about opening the missing interface.
fn expected_reason() -> &'static str {
    match canif_kernel::probe() {
        Err(_) => "Address family not supported by protocol (os error 97)",
        Ok(()) => "No such device",
    }
}

#[test]
fn run_on_a_bus_that_cannot_be_opened_is_an_error_with_the_kernels_reason() {
    let report = std::env::temp_dir().join(format!("canif-nobus-{}", std::process::id()));
    let (code, stderr) = canif(&[
        "run",
        "--bus",
        MISSING,
        "--profile",
        "fc510x",
        "--report",
        &report.display().to_string(),
    ]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("canifnone0") && stderr.contains(expected_reason()),
        "{stderr}"
    );
}

#[test]
fn the_device_the_coupler_and_the_canopen_checks_say_why_they_cannot_start() {
    for args in [
        &["device", "--stdio", "--bus", MISSING][..],
        &["coupler", "--bus", MISSING, "--node", "5"][..],
        &["run", "canopen", "--bus", MISSING, "--node", "5"][..],
    ] {
        let (code, stderr) = canif(args);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected_reason()), "{args:?}: {stderr}");
    }
}

#[test]
fn a_bus_that_is_neither_sim_nor_socketcan_is_a_usage_error() {
    for bus in ["vcan0", "socketcan:", "socketcan:a,b,c"] {
        let (code, stderr) = canif(&["run", "--bus", bus]);
        assert_eq!(code, Some(2), "{bus}: {stderr}");
        assert!(stderr.contains("socketcan:IFACE"), "{bus}: {stderr}");
    }
}
