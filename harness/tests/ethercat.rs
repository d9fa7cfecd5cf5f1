//! The device suite through real EtherCAT frames: canif's master (ethercrab)
//! on one end of an in-memory link, the soft device behind an emulated ESC on
//! the other. Every EtherCAT terminal profile conforms; a fault of the soft
//! device is caught on the requirement it breaks in process; a SubDevice that
//! answers wrongly is an error naming what it did, never a FAIL.

use canif_harness::device::suite::Options;
use canif_harness::device::IutKind;
use canif_harness::door::ethercat::{Emulated, EthercatLink, LinkFault};
use canif_harness::door::Door;
use canif_harness::outcome::Outcome;
use canif_harness::run::{run_profile, ProfileRun};
use canif_softdevice::Fault;
use canif_spec::{Catalogue, Profile};

fn terminals(catalogue: &Catalogue) -> Vec<&Profile> {
    catalogue
        .profiles
        .iter()
        .filter(|p| p.ethercat.is_some())
        .collect()
}

fn run(profile: &Profile, faults: Vec<Fault>, link_fault: Option<LinkFault>) -> ProfileRun {
    let iut = IutKind::Door(Door::Ethercat(canif_harness::door::EthercatDoor {
        identity: None, // the suite takes it from the profile
        link: EthercatLink::Emulated(Emulated {
            faults,
            link_fault,
            ..Emulated::default()
        }),
    }));
    run_profile(profile, &iut, &Options::quick(7), |_| {})
}

fn errors(run: &ProfileRun) -> Vec<String> {
    run.runs
        .iter()
        .filter_map(|r| match &r.outcome {
            Outcome::Error(e) => Some(format!("{}: {e}", r.scenario)),
            _ => None,
        })
        .collect()
}

#[test]
fn every_ethercat_terminal_profile_conforms_through_ethercat_frames() {
    let catalogue = Catalogue::embedded().unwrap();
    let terminals = terminals(&catalogue);
    assert_eq!(terminals.len(), 2, "el6751-legacy and el6751-mdp");
    for profile in terminals {
        let run = run(profile, vec![], None);
        assert!(
            run.failures.is_empty(),
            "{}: {:#?}",
            profile.name,
            run.failures.first()
        );
        assert_eq!(errors(&run), Vec::<String>::new(), "{}", profile.name);
        assert!(
            run.runs.len() > 10,
            "{} ran {} scenarios",
            profile.name,
            run.runs.len()
        );
    }
}

/// The same fault of the soft device, in process and behind the emulated
/// terminal, fails the same requirements: EtherCAT hides nothing and adds nothing.
#[test]
fn a_soft_device_fault_behind_the_terminal_fails_what_it_fails_in_process() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    for fault in [Fault::SendsBatchReversed, Fault::FilterLastMatchWins] {
        let through_ethercat = run(profile, vec![fault], None);
        let in_process = run_profile(
            profile,
            &IutKind::SoftDevice {
                faults: vec![fault],
                choices: vec![],
            },
            &Options::quick(7),
            |_| {},
        );
        let failed = through_ethercat.failed_requirements(&catalogue, profile);
        assert!(!failed.is_empty(), "{fault:?} passed through EtherCAT");
        assert_eq!(
            failed,
            in_process.failed_requirements(&catalogue, profile),
            "{fault:?}"
        );
        assert_eq!(errors(&through_ethercat), Vec::<String>::new());
    }
}

/// What a SubDevice or its wire does wrong is an error naming it, never a
/// failure of an interface requirement, and never a hang.
#[test]
fn a_terminal_that_answers_wrongly_is_an_error_naming_what_it_did() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-legacy").unwrap();
    for (fault, named) in [
        (LinkFault::WorkingCounter, "working counter"),
        (LinkFault::Truncated, "EtherCAT"),
        (LinkFault::Oversized, "EtherCAT"),
        (LinkFault::SilentAfter(400), "timeout"),
        // 0x0011, invalid requested state change: an AL error, no refusal.
        (LinkFault::AlError(0x0011), "code 0x0011"),
    ] {
        let run = run(profile, vec![], Some(fault));
        assert!(
            run.failures.is_empty(),
            "{fault:?}: {:?}",
            run.failures.first()
        );
        let errors = errors(&run);
        assert!(!errors.is_empty(), "{fault:?} went unnoticed");
        assert!(
            errors.iter().all(|e| e.contains(named)),
            "{fault:?}: {}",
            errors[0]
        );
    }
}

/// A well-formed LRW with the wrong inputs is what the terminal did wrong
/// in the exchange: a failure of the LRW's confirmation (PDX-001/002), not
/// an error of the telegram.
#[test]
fn an_lrw_that_reads_the_wrong_inputs_fails_the_exchange() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-legacy").unwrap();
    let run = run(profile, vec![], Some(LinkFault::LrwReadsZeros));
    assert!(errors(&run).is_empty(), "{:?}", errors(&run).first());
    assert!(!run.failures.is_empty(), "the wrong LRW went unnoticed");
    for failure in &run.failures {
        assert!(
            failure
                .requirements
                .iter()
                .all(|id| ["PDX-001", "PDX-002"].contains(&id.as_str())),
            "{}: {:?}",
            failure.scenario,
            failure.requirements
        );
        assert!(failure.what.contains("LRW"), "{}", failure.what);
    }
}

/// The survey a report shows: the terminal's identity as the profile gives
/// it, 0x1C32:05 read back, and a paced soak's cycles (how many missed their
/// deadline is the machine's load, not asserted).
/// Covers: PDX-006
#[test]
fn a_survey_names_the_terminal_and_counts_a_soak() {
    use canif_harness::door::ethercat::{survey, Pace};
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-legacy").unwrap();
    let identity = profile.ethercat.unwrap();
    let link = EthercatLink::Emulated(Emulated::default());
    let pace = Pace::Every {
        period: std::time::Duration::from_millis(2),
        soak: std::time::Duration::from_millis(100),
    };
    let facts = survey(profile, &link, pace).unwrap();
    assert_eq!(facts.profile, "el6751-legacy");
    assert_eq!(
        (facts.vendor_id, facts.product_code, facts.revision),
        (identity.vendor_id, identity.product_code, identity.revision)
    );
    assert_eq!(facts.name, "EL6751");
    assert_eq!((facts.cycles, facts.period_ns), (50, Some(2_000_000)));
    assert!(
        facts.local_cycle_ns.is_some(),
        "0x1C32:05 was not read back"
    );
    assert!(facts.worst_cycle_ns >= facts.mean_cycle_ns);
    // The master configured the real EL6751's layout from the SII, and
    // left the CAN status (0x1A85) out of the image it judges.
    let starts: Vec<[u16; 2]> = facts.sync_managers.iter().map(|s| [s[0], s[1]]).collect();
    assert_eq!(
        starts[..2],
        [[0x1000, 1024], [0x1400, 1024]],
        "{:X?}",
        facts.sync_managers
    );
    assert_eq!(
        (starts[2][0], starts[3][0], facts.sync_managers[2][2] & 3),
        (0x1800, 0x2400, 0b10),
        "process data at 0x1800/0x2400 in 1-buffer mode: {:X?}",
        facts.sync_managers
    );
    assert_eq!(facts.status_bytes, 6, "the CAN status behind the image");
}

/// canif's master takes the layout from the terminal's SII, never its own:
/// the same terminal advertising a second layout (128-byte mailboxes,
/// 3-buffer process data elsewhere) is configured there and conforms.
#[test]
fn canif_s_master_takes_the_layout_the_terminal_advertises() {
    use canif_ethercat::sii::Layout;
    use canif_harness::door::ethercat::{survey, Pace};
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    let emulated = Emulated {
        layout: Layout::COMPACT,
        ..Emulated::default()
    };
    let link = EthercatLink::Emulated(emulated.clone());
    let facts = survey(profile, &link, Pace::Unpaced(10)).unwrap();
    assert_eq!(
        facts.sync_managers.iter().map(|s| s[0]).collect::<Vec<_>>(),
        [0x1000, 0x1080, 0x1100, 0x1D00]
    );
    let iut = IutKind::Door(Door::Ethercat(canif_harness::door::EthercatDoor {
        identity: None,
        link: EthercatLink::Emulated(emulated),
    }));
    let run = run_profile(profile, &iut, &Options::quick(7), |_| {});
    assert!(run.failures.is_empty(), "{:#?}", run.failures.first());
    assert_eq!(errors(&run), Vec::<String>::new());
}

/// With Distributed Clocks SYNC0 starts the terminal's cycle (003, PDX-005):
/// a terminal whose firmware still runs it on every process-data telegram
/// runs it on the master's half-cycle telegram too, and fails PDX-005 there,
/// never an error; the same terminal conforms where SYNC0 is not in use.
#[test]
fn a_terminal_that_cycles_on_telegrams_under_distributed_clocks_fails_pdx_005() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    let with_dc = run(profile, vec![], Some(LinkFault::CyclesOnFrames));
    assert!(
        errors(&with_dc).is_empty(),
        "{:?}",
        errors(&with_dc).first()
    );
    assert!(
        !with_dc.failures.is_empty(),
        "a cycle on the telegram went unnoticed"
    );
    for failure in &with_dc.failures {
        assert_eq!(
            failure
                .requirements
                .iter()
                .map(|id| id.as_str())
                .collect::<Vec<_>>(),
            ["PDX-005"],
            "{}: {}",
            failure.scenario,
            failure.what
        );
        assert!(failure.scenario.contains("DC"), "{}", failure.scenario);
    }
    let legacy = catalogue.profile("el6751-legacy").unwrap();
    let without_dc = run(legacy, vec![], Some(LinkFault::CyclesOnFrames));
    assert!(
        without_dc.failures.is_empty(),
        "{:?}",
        without_dc.failures.first()
    );
}

/// The refusal grid writes configuration after configuration to one
/// terminal held in PREOP (a scan each would be four fifths of the grid's
/// time). Each configuration gets the answer a fresh bring-up of it gets: on
/// a clean terminal and on one that refuses what it should take.
#[test]
fn a_terminal_held_in_preop_answers_each_configuration_as_a_fresh_one() {
    use canif_harness::device::refusals::grid;
    use canif_harness::door::ethercat::{build, Configurer};
    use canif_harness::door::iut::BuildError;
    let answer = |result: Result<(), BuildError>| match result {
        Ok(()) => "taken".to_string(),
        Err(BuildError::Refused(_)) => "refused".to_string(),
        Err(BuildError::Failed(e)) => format!("failed: {e}"),
    };
    let catalogue = Catalogue::embedded().unwrap();
    for profile in terminals(&catalogue) {
        let identity = profile.ethercat.unwrap();
        let caps = profile.model_capabilities();
        for faults in [vec![], vec![Fault::RefusesThirtyTwoSlots]] {
            let link = EthercatLink::Emulated(Emulated {
                faults: faults.clone(),
                ..Emulated::default()
            });
            let sample: Vec<_> = grid().step_by(7).collect();
            // Fresh bring-ups first: the held terminal keeps the link of this thread.
            let fresh: Vec<String> = sample
                .iter()
                .map(|config| answer(build(&caps, config, &identity, &link).map(|_| ())))
                .collect();
            let mut held = Configurer::new(identity, link.clone());
            for (config, fresh) in sample.iter().zip(&fresh) {
                let offered = answer(held.offer(&caps, config));
                assert_eq!(&offered, fresh, "{} {faults:?}: {config:?}", profile.name);
            }
            let count = |what: &str| fresh.iter().filter(|a| *a == what).count();
            assert!(
                count("taken") > 0 && count("refused") > 0,
                "{}: the sample has both answers",
                profile.name
            );
        }
    }
}
