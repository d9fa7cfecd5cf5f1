//! An external IUT must not be the bottleneck: the soak scenario (one virtual
//! minute of a 1 Mbit/s bus at full load, 32 slots) checked frame by frame
//! against the soft device in process, the C example device loaded over the C
//! ABI (`lib:`) in process and in `canif lib-host` (protocol 3: a record per
//! cycle with its `canif_transmit_plan`, a record per bus event without it),
//! and the soft device behind the adapter protocol as its own
//! process (`canif device --stdio`): protocol 3 (a cycle's records in shared
//! memory) on any CPU and on the harness's, protocol 2 (a line per cycle)
//! and protocol 1 (a line per bus event). Plain main: prints figures and the
//! ratios of one run; asserts nothing.

use std::time::Instant;

use canif_harness::device::scenario;
use canif_harness::device::{run_scenario, IutKind};
use canif_harness::door::{Door, LibHost, Timeouts};
use canif_harness::Outcome;
use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::timing::BitRates;
use canif_spec::Catalogue;

fn main() {
    let catalogue = Catalogue::embedded().unwrap();
    let caps = catalogue
        .profile("el6751-mdp")
        .unwrap()
        .model_capabilities();
    let config = InterfaceConfig::new(FrameFormat::Base11, 32);
    let seconds: u64 = std::env::var("CANIF_BENCH_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    let mut soak = scenario::generated(&config, 42, seconds * 1000, 100);
    soak.bit_rates = BitRates::classic(1_000_000);
    let device = env!("CARGO_BIN_EXE_canif");
    let library = c_example(&[]);
    // The same library without its plan: polled frame by frame.
    let polled = c_example(&["-Dcanif_transmit_plan=example_transmit_plan"]);
    // `canif device --stdio` over protocol `version`, on the harness's CPU or any.
    let stdio = |version: u8, same_cpu: bool| {
        IutKind::Door(Door::Exec(canif_harness::door::ExecDoor {
            command: format!("{device} device --stdio --protocol {version}"),
            timeouts: Timeouts::with_request(std::time::Duration::from_millis(10_000)),
            same_cpu,
        }))
    };
    let iuts = [
        (
            "soft device in process",
            IutKind::SoftDevice {
                faults: vec![],
                choices: vec![],
            },
        ),
        (
            "examples/c over lib:, in process",
            IutKind::Door(Door::Lib(canif_harness::door::LibDoor {
                path: library.clone(),
                host: None,
            })),
        ),
        (
            "examples/c over lib:, canif lib-host",
            IutKind::Door(Door::Lib(canif_harness::door::LibDoor {
                path: library.clone(),
                host: Some(LibHost {
                    canif: device.into(),
                    timeouts: Timeouts::with_request(std::time::Duration::from_millis(10_000)),
                }),
            })),
        ),
        (
            "the same without its plan (polled)",
            IutKind::Door(Door::Lib(canif_harness::door::LibDoor {
                path: polled,
                host: Some(LibHost {
                    canif: device.into(),
                    timeouts: Timeouts::with_request(std::time::Duration::from_millis(10_000)),
                }),
            })),
        ),
        ("canif device --stdio, protocol 3", stdio(3, false)),
        ("the same, IUT on the harness's CPU", stdio(3, true)),
        ("canif device --stdio, protocol 2", stdio(2, true)),
        ("canif device --stdio, protocol 1", stdio(1, true)),
    ];
    // CANIF_BENCH_ONLY=TEXT: the in-process row and those whose label holds
    // TEXT (for profiling one door).
    let only = std::env::var("CANIF_BENCH_ONLY").ok();
    let iuts: Vec<_> = iuts
        .into_iter()
        .enumerate()
        .filter(|(n, (label, _))| {
            *n == 0 || only.as_ref().is_none_or(|o| label.contains(o.as_str()))
        })
        .map(|(_, iut)| iut)
        .collect();
    let iuts = &iuts[..];
    let mut rates = Vec::new();
    for (label, kind) in iuts {
        // A fresh thread each: a same-CPU IUT pins the thread that starts it.
        let (run, wall) = std::thread::scope(|scope| {
            scope
                .spawn(|| {
                    let started = Instant::now();
                    let run = run_scenario(kind, &caps, &soak, soak.steps());
                    (run, started.elapsed().as_secs_f64())
                })
                .join()
                .expect("the measurement thread")
        });
        let rate = run.frames_checked as f64 / wall;
        println!(
            "soak vs {label:<33}: {} frames checked in {wall:.2} s = {rate:>10.0} checked frames/s ({})",
            run.frames_checked,
            if matches!(run.outcome, Outcome::Pass) { "pass" } else { "NOT PASS" }
        );
        rates.push(rate);
    }
    for ((label, _), rate) in iuts.iter().zip(&rates).skip(1) {
        println!("{label}: {:.3} of the in-process rate", rate / rates[0]);
    }
}

/// The C example device, built with the machine's C compiler and `flags`.
fn c_example(flags: &[&str]) -> std::path::PathBuf {
    let root = env!("CARGO_MANIFEST_DIR");
    let library = std::env::temp_dir().join(format!(
        "canif-bench-{}-{}.so",
        std::process::id(),
        flags.len()
    ));
    let status = std::process::Command::new("cc")
        .args(["-shared", "-fPIC", "-O2"])
        .args(flags)
        .arg("-I")
        .arg(format!("{root}/include"))
        .arg("-o")
        .arg(&library)
        .arg(format!("{root}/examples/c/minimal_device.c"))
        .status()
        .expect("cc runs");
    assert!(status.success(), "cc failed");
    library
}
