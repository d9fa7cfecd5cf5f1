//! Throughput of the whole stack (soft device + simulated bus + model checker)
//! in virtual time, and the wall time of the default run. Plain main: prints
//! figures, asserts nothing (speed is measured, never asserted).

use std::time::Instant;

use canif_harness::device::run_scenario;
use canif_harness::device::scenario;
use canif_harness::device::suite::Options;
use canif_harness::device::IutKind;
use canif_harness::run::run_profile;
use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::timing::BitRates;
use canif_spec::Catalogue;

fn main() {
    let catalogue = Catalogue::embedded().unwrap();
    let softdevice = IutKind::SoftDevice {
        faults: vec![],
        choices: vec![],
    };

    // One minute of a 1 Mbit/s bus at full load, checked frame by frame.
    let profile = catalogue.profile("el6751-mdp").unwrap();
    let caps = profile.model_capabilities();
    let config = InterfaceConfig::new(FrameFormat::Base11, 32);
    let mut soak = scenario::generated(&config, 42, 60_000, 100);
    soak.bit_rates = BitRates::classic(1_000_000);
    for (label, kind) in [("softdevice", &softdevice), ("model", &IutKind::Model)] {
        let started = Instant::now();
        let run = run_scenario(kind, &caps, &soak, soak.steps());
        let seconds = started.elapsed().as_secs_f64();
        println!(
            "soak vs {label:<10}: {} virtual s, {} cycles, {} frames checked in {:.3} s wall = {:.0} frames/s, {:.0} virtual s per wall s ({:?})",
            run.cycles / 1000,
            run.cycles,
            run.frames_checked,
            seconds,
            run.frames_checked as f64 / seconds,
            run.cycles as f64 / 1000.0 / seconds,
            matches!(run.outcome, canif_harness::Outcome::Pass)
        );
    }

    let started = Instant::now();
    let mut frames = 0;
    for profile in &catalogue.profiles {
        frames += run_profile(profile, &softdevice, &Options::default(), |_| {}).frames_checked();
    }
    let seconds = started.elapsed().as_secs_f64();
    println!(
        "default run (9 profiles): {:.3} s wall, {frames} frames checked, {:.0} frames/s",
        seconds,
        frames as f64 / seconds
    );
}
