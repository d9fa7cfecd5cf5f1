//! The PLC side's default run must cost no more than the device side's: both
//! README commands (`canif run` and `canif run plc`), three times each,
//! in one run; prints the medians and their ratio. Plain main: asserts nothing.

use std::process::Command;
use std::time::{Duration, Instant};

fn median_of_three(args: &[&str]) -> Duration {
    let report = std::env::temp_dir().join(format!("canif-bench-sides-{}", std::process::id()));
    let mut times: Vec<Duration> = (0..3)
        .map(|_| {
            let started = Instant::now();
            let status = Command::new(env!("CARGO_BIN_EXE_canif"))
                .args(args)
                .arg("--report")
                .arg(&report)
                .output()
                .expect("canif runs")
                .status;
            assert!(status.success(), "canif {args:?} did not conform");
            started.elapsed()
        })
        .collect();
    let _ = std::fs::remove_dir_all(report);
    times.sort();
    times[1]
}

fn main() {
    let device = median_of_three(&["run"]);
    let plc = median_of_three(&["run", "plc"]);
    println!("canif run (device side, soft device):  {device:?}");
    println!("canif run plc (reference client): {plc:?}");
    println!(
        "ratio PLC side / device side: {:.2}",
        plc.as_secs_f64() / device.as_secs_f64()
    );
}
