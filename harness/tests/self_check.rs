//! The suite proves its power on itself: the model and the unfaulted soft
//! device pass every profile; every fault of the soft device is caught, on the
//! requirement it breaks.

use canif_harness::suite::{run_profile, Options};
use canif_harness::{IutKind, Outcome, ProfileRun, Verdict};
use canif_softdevice::Fault;
use canif_spec::Catalogue;

fn quick() -> Options {
    Options {
        seed: 1,
        cases: 2,
        generated_cycles: 120,
        counter_wrap: false,
        trace_dir: None,
    }
}

fn run(kind: &IutKind, profile: &str, options: &Options) -> ProfileRun {
    let catalogue = Catalogue::embedded().unwrap();
    run_profile(
        &catalogue,
        catalogue.profile(profile).unwrap(),
        kind,
        options,
        |_| {},
    )
}

fn problems(run: &ProfileRun) -> Vec<String> {
    run.runs
        .iter()
        .filter_map(|r| match &r.outcome {
            Outcome::Pass => None,
            Outcome::Fail(f) => Some(format!(
                "{}: cycle {} {}: expected {} actual {} ({})\n    {}",
                r.scenario,
                f.cycle,
                f.what,
                f.expected,
                f.actual,
                f.requirements.join(", "),
                f.context.join("\n    ")
            )),
            Outcome::Error(e) => Some(format!("{}: error: {e}", r.scenario)),
        })
        .collect()
}

#[test]
fn the_model_conforms_to_itself_on_every_profile() {
    let catalogue = Catalogue::embedded().unwrap();
    for profile in &catalogue.profiles {
        let result = run(&IutKind::Model, &profile.name, &quick());
        assert!(
            problems(&result).is_empty(),
            "{}:\n{}",
            profile.name,
            problems(&result).join("\n")
        );
    }
}

#[test]
fn the_soft_device_conforms_on_every_profile() {
    let catalogue = Catalogue::embedded().unwrap();
    for profile in &catalogue.profiles {
        let result = run(
            &IutKind::SoftDevice { faults: vec![] },
            &profile.name,
            &quick(),
        );
        assert!(
            problems(&result).is_empty(),
            "{}:\n{}",
            profile.name,
            problems(&result).join("\n")
        );
        assert!(result.verdicts.values().any(|v| *v == Verdict::Pass));
    }
}

/// Each fault, a profile that has the feature it breaks, and the requirements
/// at least one of which the failure must name.
pub const KILL_TABLE: [(Fault, &str, &[&str]); 20] = [
    (
        Fault::AckBeforeAccept,
        "el6751-mdp",
        &["HS-TX-006", "HS-TX-007"],
    ),
    (
        Fault::OverwritesUnacknowledgedRx,
        "el6751-mdp",
        &["HS-RX-001", "HS-RX-004"],
    ),
    (Fault::FdLengthRoundsDown, "fc532x", &["FD-LEN-003"]),
    (Fault::FdLength32As36, "fc532x", &["FD-LEN-004", "ERR-R1"]),
    (Fault::RtrBitMisplaced, "el6751-mdp", &["LAY-11-003"]),
    (Fault::ExtendedFlagMissing, "ccat", &["LAY-29-005"]),
    (Fault::TransactionNumberOfFirstFrame, "ccat", &["TN-002"]),
    (Fault::TransactionNumberOnHandover, "ccat", &["TN-003"]),
    (Fault::TimeStampInMicroseconds, "ccat", &["TS-001"]),
    (Fault::HeadDropWhenFull, "el6751-mdp", &["RXQ-004"]),
    (Fault::FilterLastMatchWins, "ccat", &["FLT-005"]),
    (Fault::FastQueueWaitsForAck, "el6751-mdp", &["FQ-002"]),
    (Fault::CounterDoesNotWrap, "fc510x", &["HS-RX-005"]),
    (
        Fault::RxCounterCountsEmptyCycles,
        "el6751-mdp",
        &["HS-RX-006"],
    ),
    (Fault::SendsBatchReversed, "el6751-mdp", &["HS-TX-004"]),
    (Fault::SendsOneMoreThanAsked, "el6751-mdp", &["HS-TX-009"]),
    (Fault::FdPaddingFf, "fc532x", &["FD-LEN-005"]),
    (Fault::CobIdWordBigEndian, "el6751-mdp", &["LAY-GEN-003"]),
    (
        Fault::BrsEsiSwapped,
        "fc532x",
        &["FD-BIT-002", "FD-BIT-003"],
    ),
    (Fault::ReceiveFifoNotReported, "fc532x", &["INFO-007"]),
];

#[test]
fn every_fault_is_caught_on_the_requirement_it_breaks() {
    assert!(KILL_TABLE.len() >= 15);
    assert_eq!(
        KILL_TABLE.len(),
        Fault::ALL.len(),
        "every fault is in the table"
    );
    let mut misses = Vec::new();
    for (fault, profile, expected) in KILL_TABLE {
        let options = Options {
            counter_wrap: fault == Fault::CounterDoesNotWrap,
            ..quick()
        };
        let result = run(
            &IutKind::SoftDevice {
                faults: vec![fault],
            },
            profile,
            &options,
        );
        let failed = result.failed_requirements();
        if !expected.iter().any(|id| failed.iter().any(|f| f == id)) {
            misses.push(format!(
                "{}: expected a failure on {:?}, failed: {:?}\n{}",
                fault.name(),
                expected,
                failed,
                problems(&result).join("\n")
            ));
        }
    }
    assert!(misses.is_empty(), "{}", misses.join("\n\n"));
}

#[test]
fn runs_check_real_traffic() {
    let result = run(
        &IutKind::SoftDevice { faults: vec![] },
        "el6751-mdp",
        &quick(),
    );
    for r in &result.runs {
        eprintln!(
            "{:<50} cycles {:>6} frames {:>6} {:?}",
            r.scenario,
            r.cycles,
            r.frames_checked,
            matches!(r.outcome, Outcome::Pass)
        );
    }
    assert!(
        result.frames_checked() > 1_000,
        "frames checked: {}",
        result.frames_checked()
    );
}
