//! The PLC side's default run must cost no more than the device side's: the
//! runs the README's two commands start (`canif run`, `canif run plc`),
//! made as the library call they are (`canif_runner::Plan::run`), three
//! times each in one run; prints the medians and their ratio. Plain main:
//! asserts nothing.

use std::time::{Duration, Instant};

use canif_harness::client::suite::{ClientKind, ClientOptions};
use canif_harness::device::{IutKind, Options};
use canif_runner::{Campaign, Plan, Quiet};
use canif_spec::Catalogue;

fn median_of_three<S: Campaign>(
    catalogue: &Catalogue,
    options: impl Fn() -> S,
    under_test: &S::UnderTest,
) -> Duration {
    let mut times: Vec<Duration> = (0..3)
        .map(|_| {
            let plan = Plan::new(catalogue.profiles.iter().collect(), options(), None)
                .expect("the feature files parse");
            let started = Instant::now();
            let report = plan
                .run(catalogue, under_test, &Quiet)
                .expect("the plan runs");
            assert_eq!(report.exit_code(), 0, "{}", report.headline());
            started.elapsed()
        })
        .collect();
    times.sort();
    times[1]
}

fn main() {
    let catalogue = Catalogue::embedded().expect("the embedded catalogue loads");
    let soft_device = IutKind::SoftDevice {
        faults: vec![],
        choices: vec![],
    };
    let device = median_of_three(&catalogue, Options::default, &soft_device);
    let plc = median_of_three(&catalogue, || ClientOptions::new(1), &ClientKind::Reference);
    println!("device side, soft device (canif run):      {device:?}");
    println!("PLC side, reference client (canif run plc): {plc:?}");
    println!(
        "ratio PLC side / device side: {:.2}",
        plc.as_secs_f64() / device.as_secs_f64()
    );
}
