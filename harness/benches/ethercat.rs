//! The device suite's speed through EtherCAT beside in process, in one run:
//! the same profile and scenarios (el6751-mdp, one case each) on the soft
//! device in process, behind the emulated terminal over the in-memory link,
//! and (as root, on a veth pair made here) across the kernel's packet path.
//! Prints, for each: EtherCAT cycles per second of an idle terminal (one LRW
//! and one input read each, after bring-up), and the wall time and checked
//! frames per second of the run (which also brings the terminal up once per
//! configuration of the refusal grid). Plain main: asserts only that each run
//! conformed.

use std::process::Command;
use std::time::Instant;

use canif_harness::device::suite::Options;
use canif_harness::device::IutKind;
use canif_harness::door::ethercat::{Emulated, EthercatLink};
use canif_harness::door::Door;
use canif_harness::run::run_profile;
use canif_spec::Catalogue;

const IDLE_CYCLES: u32 = 10_000;

/// Cycles and checked frames per second of one run.
fn measure(name: &str, iut: &IutKind) -> (f64, f64) {
    let catalogue = Catalogue::embedded().expect("the embedded catalogue");
    let profile = catalogue.profile("el6751-mdp").expect("el6751-mdp");
    let started = Instant::now();
    let run = run_profile(profile, iut, &Options::quick(1), |_| {});
    let seconds = started.elapsed().as_secs_f64();
    let errors = run
        .runs
        .iter()
        .filter(|r| matches!(r.outcome, canif_harness::outcome::Outcome::Error(_)))
        .count();
    let first_error = run.runs.iter().find_map(|r| match &r.outcome {
        canif_harness::outcome::Outcome::Error(e) => Some(format!("{}: {e}", r.scenario)),
        _ => None,
    });
    assert!(
        run.failures.is_empty() && errors == 0,
        "{name} did not conform: {errors} errors, first {first_error:?}"
    );
    if let IutKind::Door(Door::Ethercat(canif_harness::door::EthercatDoor { link, .. })) = iut {
        let idle = canif_harness::door::ethercat::survey(
            profile,
            link,
            canif_harness::door::ethercat::Pace::Unpaced(IDLE_CYCLES),
        )
        .expect("the terminal comes up");
        println!(
            "{name:<28} idle: {:>8.0} EtherCAT cycles/s (mean {} µs, worst {} µs)",
            1e9 / idle.mean_cycle_ns.max(1) as f64,
            idle.mean_cycle_ns / 1_000,
            idle.worst_cycle_ns / 1_000
        );
    }
    let cycles: u64 = run.runs.iter().map(|r| r.cycles).sum();
    let frames: u64 = run.runs.iter().map(|r| r.frames_checked).sum();
    let (per_cycle, per_frame) = (cycles as f64 / seconds, frames as f64 / seconds);
    println!(
        "{name:<28} {seconds:>7.2} s  {cycles:>7} cycles  {per_cycle:>10.0} cycles/s  {per_frame:>10.0} checked frames/s"
    );
    (per_cycle, per_frame)
}

fn emulated() -> Emulated {
    Emulated::default()
}

fn veth() -> Option<(String, String)> {
    let (a, b) = ("cifbenchm".to_string(), "cifbencht".to_string());
    let ip = |args: &[&str]| {
        Command::new("ip")
            .args(args)
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let _ = ip(&["link", "del", &a]);
    (ip(&["link", "add", &a, "type", "veth", "peer", "name", &b])
        && ip(&["link", "set", &a, "up"])
        && ip(&["link", "set", &b, "up"]))
    .then_some((a, b))
}

fn main() {
    let in_process = measure(
        "soft device, in process",
        &IutKind::SoftDevice {
            faults: vec![],
            choices: vec![],
        },
    );
    let memory = measure(
        "EtherCAT, in-memory link",
        &IutKind::Door(Door::Ethercat(canif_harness::door::EthercatDoor {
            identity: None,
            link: EthercatLink::Emulated(emulated()),
        })),
    );
    println!(
        "in process runs {:.1}x the checked frames/s of the in-memory EtherCAT run",
        in_process.1 / memory.1
    );
    match veth() {
        Some((master, terminal)) => {
            let over_veth = measure(
                "EtherCAT, veth pair",
                &IutKind::Door(Door::Ethercat(canif_harness::door::EthercatDoor {
                    identity: None,
                    link: EthercatLink::Veth {
                        master: master.clone(),
                        terminal,
                        emulated: emulated(),
                    },
                })),
            );
            println!(
                "the in-memory EtherCAT run checks {:.1}x the frames/s of the veth run",
                memory.1 / over_veth.1
            );
            let _ = Command::new("ip").args(["link", "del", &master]).output();
        }
        None => println!("EtherCAT, veth pair: not measured (no veth pair here: needs root)"),
    }
}
