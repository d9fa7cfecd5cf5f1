//! The feature files: how many scenarios, well-formed tags, and every fault of
//! the soft device caught by at least one scenario (the mutation self-check).

use canif_features::{run_scenario, scenarios, ScenarioOutcome, Target};
use canif_harness::declare::Declaration;
use canif_harness::device::blame;
use canif_harness::device::IutKind;
use canif_harness::door::{Door, Timeouts};
use canif_softdevice::Fault;
use canif_spec::Catalogue;

#[test]
fn at_least_120_scenarios_counting_each_examples_row() {
    let list = scenarios().unwrap();
    assert!(list.len() >= 120, "{} scenarios", list.len());
}

#[test]
fn every_tag_is_a_requirement_a_capability_or_a_run_mode() {
    let catalogue = Catalogue::embedded().unwrap();
    for scenario in scenarios().unwrap() {
        assert!(
            !scenario.requirements.is_empty(),
            "{}:{} names no requirement",
            scenario.file,
            scenario.line
        );
        for id in &scenario.requirements {
            assert!(
                catalogue.requirement(id).is_some(),
                "{}:{}: @{id} is no requirement",
                scenario.file,
                scenario.line
            );
        }
    }
}

/// Faults that show only on output images the sample code of 001 §6 never
/// writes (a batch of nothing, out-of-range counts and lengths, reserved bits)
/// or only with every slot in use: the Gherkin PLC is the sample code, so the
/// lockstep's untrusted-input and full-slots scenarios catch these
/// (harness/tests/self_check.rs holds it).
const UNTRUSTED_INPUT: [Fault; 8] = [
    Fault::ZeroBatchNotAcknowledged,
    Fault::TrustsNoOfTxMessages,
    Fault::BatchCappedAt31,
    Fault::RxCountCappedAt31,
    Fault::StandardIdKeepsHighBits,
    Fault::ClassicLengthUnbounded,
    Fault::BrsWithoutEdlSendsFd,
    Fault::InfoDataTwoBytesLate,
];

#[test]
fn every_fault_is_caught_by_a_scenario() {
    let catalogue = Catalogue::embedded().unwrap();
    let list = scenarios().unwrap();
    let mut uncaught = Vec::new();
    for fault in Fault::ALL {
        if UNTRUSTED_INPUT.contains(&fault) {
            continue;
        }
        let profile_name = canif_harness::device::suite::profile_for(fault);
        let profile = catalogue.profile(profile_name).unwrap();
        let caught: Vec<String> = list
            .iter()
            .filter(|s| !s.model_only && (s.once || s.capabilities.iter().all(|c| profile.has(c))))
            .filter(|s| {
                let target = Target::new(
                    IutKind::SoftDevice {
                        faults: vec![fault],
                        choices: vec![],
                    },
                    profile.name.clone(),
                    profile.model_capabilities(),
                );
                matches!(
                    run_scenario(&s.file, s.line, target),
                    ScenarioOutcome::Failed { .. }
                )
            })
            .map(|s| format!("{}:{}", s.file, s.line))
            .collect();
        if caught.is_empty() {
            uncaught.push(fault.name());
        } else {
            eprintln!(
                "{:<36} caught by {} scenario(s), e.g. {}",
                fault.name(),
                caught.len(),
                caught[0]
            );
        }
    }
    assert!(uncaught.is_empty(), "no scenario catches: {uncaught:?}");
}

/// The tags the scenario named `name` blames when it fails against the
/// soft device with `fault` on el6751-mdp, and the scenario's tags.
fn blamed_by(name: &str, fault: Fault) -> (Vec<String>, Vec<String>) {
    let scenario = scenarios()
        .unwrap()
        .into_iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no scenario named {name:?}"));
    // The profile's own capabilities: with every capability the InfoData
    // words of other devices differ first, and a witness outside the tags
    // blames every tag - which once made this pass for the wrong reason.
    let catalogue = Catalogue::embedded().unwrap();
    let target = Target::new(
        IutKind::SoftDevice {
            faults: vec![fault],
            choices: vec![],
        },
        "el6751-mdp",
        catalogue
            .profile("el6751-mdp")
            .unwrap()
            .model_capabilities(),
    );
    match run_scenario(&scenario.file, scenario.line, target) {
        ScenarioOutcome::Failed { witness, .. } => (
            blame::narrow_tags(&scenario.requirements, &witness),
            scenario.requirements,
        ),
        other => panic!("{name}: expected a failure, got {other:?}"),
    }
}

/// A failing scenario blames the tags of the field that differs, not every
/// tag: a counter that does not wrap breaks HS-RX-005 in the scenario tagged
/// HS-RX-005 and HS-TX-005 (harness/tests/self_check.rs names the same set
/// for the lockstep).
#[test]
fn a_failing_check_blames_only_the_tags_it_witnesses() {
    let (blamed, tags) = blamed_by("RxCounter wraps from 65535 to 0", Fault::CounterDoesNotWrap);
    assert_eq!(tags, ["HS-RX-005", "HS-TX-005"]);
    assert_eq!(blamed, ["HS-RX-005"]);
}

/// A device that keeps one message fewer than its depth fails the scenario
/// written for the depth on the depth's own statement (RXQ-001), not only on
/// the loss it causes (RXQ-003): the messages a flood leaves are the queue's
/// depth's to decide.
#[test]
fn a_queue_one_message_short_fails_the_depth_it_breaks() {
    let (blamed, _) = blamed_by(
        "The EL6751 keeps 150 messages while the PLC does not read",
        Fault::RxQueueOneShort,
    );
    assert_eq!(blamed, ["RXQ-001", "RXQ-003"]);
}

/// A failure whose check witnesses none of the scenario's tags (or nothing
/// at all) blames every tag: never less than was exercised.
#[test]
fn a_witness_outside_the_tags_blames_every_tag() {
    let tags = vec!["FLT-001".to_string(), "HS-RX-004".to_string()];
    assert_eq!(
        blame::narrow_tags(&tags, blame::RX_UNRELEASED),
        ["HS-RX-004"]
    );
    assert_eq!(blame::narrow_tags(&tags, blame::TIME_STAMP), tags);
    assert_eq!(blame::narrow_tags(&tags, &[]), tags);
}

/// A scenario against an IUT that hangs is an error, not a failure.
#[test]
fn a_broken_iut_makes_a_scenario_an_error() {
    let scenario = scenarios()
        .unwrap()
        .into_iter()
        .find(|s| s.file.ends_with("tx-handshake.feature"))
        .unwrap();
    let target = Target::new(
        IutKind::Door(Door::Exec(canif_harness::door::ExecDoor {
            command: "echo stuck >&2; sleep 30".into(),
            // It never answers, so a short start limit judges it the same
            // on any machine, and the test need not wait out the default.
            timeouts: Timeouts {
                start: std::time::Duration::from_millis(200),
                request: std::time::Duration::from_millis(200),
            },
            same_cpu: false,
        })),
        "el6751-mdp",
        canif_model::config::Capabilities::everything(),
    );
    match run_scenario(&scenario.file, scenario.line, target) {
        ScenarioOutcome::Error(report) => assert!(
            report.contains("no answer to `configure`") && report.contains("stuck"),
            "{report}"
        ),
        other => panic!("expected an error, got {other:?}"),
    }
}

/// A babbling controller (a frame at every poll) or a due time that never
/// advances cannot spin a scenario for ever. The babble is what the device
/// did wrong: the first frame the model does not send fails the scenario on
/// the Tx path. A due time that never advances is a broken exchange: the bus
/// stops polling after a bounded number of times in one cycle and names why.
#[test]
fn a_babbling_iut_ends_a_scenario_in_bounded_time() {
    let scenario = scenarios()
        .unwrap()
        .into_iter()
        .find(|s| s.file.ends_with("tx-handshake.feature"))
        .unwrap();
    for mode in ["babble", "stuck-time"] {
        let target = Target::new(
            IutKind::Door(Door::Exec(canif_harness::door::ExecDoor {
                command: format!(
                    "python3 {}/../tests/iuts/misbehave.py {mode}",
                    env!("CARGO_MANIFEST_DIR")
                ),
                timeouts: Timeouts::with_request(std::time::Duration::from_millis(2_000)),
                same_cpu: false,
            })),
            "el6751-mdp",
            canif_model::config::Capabilities::everything(),
        );
        let started = std::time::Instant::now();
        let outcome = run_scenario(&scenario.file, scenario.line, target);
        assert!(
            started.elapsed() < std::time::Duration::from_secs(60),
            "{mode}: took {:?}",
            started.elapsed()
        );
        match (mode, outcome) {
            ("babble", ScenarioOutcome::Failed { report, witness }) => {
                assert!(
                    report.contains("expected no frame, actual 123#"),
                    "{mode}: {report}"
                );
                assert!(
                    witness.iter().all(|id| id.as_str().starts_with("HS-TX-")),
                    "{mode}: {witness:?}"
                );
            }
            ("stuck-time", ScenarioOutcome::Error(report)) => {
                assert!(
                    report.contains("asked to be polled 10000 times within one cycle"),
                    "{mode}: {report}"
                )
            }
            (mode, other) => panic!("{mode}: ended otherwise: {other:?}"),
        }
    }
}

/// Issue 36: a scenario whose requirements all need a capability does not
/// run on a profile without it, where its requirements are not applicable
/// (the EL6751's process-data scenarios on fc510x).
#[test]
fn a_scenario_runs_only_where_some_requirement_it_names_applies() {
    let catalogue = Catalogue::embedded().unwrap();
    let list = scenarios().unwrap();
    let lrw = list
        .iter()
        .find(|s| s.name == "LRW confirms after two task cycles")
        .unwrap();
    assert!(lrw.capabilities.contains(&"el6751".to_string()));
    let profiles: Vec<_> = catalogue.profiles.iter().collect();
    let targets = canif_features::schedule::targets(&list, &profiles, canif_spec::Side::Device);
    for (profile, scenario) in &targets {
        let profile = catalogue.profile(profile).unwrap();
        assert!(
            scenario.requirements.iter().any(|id| {
                let r = catalogue.requirement(id).unwrap();
                profile.lacks(&r.capabilities).is_empty()
            }),
            "{}:{} runs on {} where none of {:?} applies",
            scenario.file,
            scenario.line,
            profile.name,
            scenario.requirements
        );
    }
    assert!(targets
        .iter()
        .any(|(p, s)| p == "el6751-mdp" && s.name == lrw.name));
}

/// Issue 36: a Gherkin scenario reads the declarations the lockstep reads,
/// the command line's over the device's own: told that the device waits
/// 5 µs after SYNC1, the scenario judges it by that delay and fails the soft
/// device, which does not wait; the declaration was once ignored there.
#[test]
fn a_gherkin_scenario_honours_the_command_lines_declaration() {
    use canif_features::schedule::{run, UnderTest};
    use canif_harness::declare::choices::Declared;
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    let scenario = scenarios()
        .unwrap()
        .into_iter()
        .find(|s| s.name == "With Distributed Clocks the first message waits for SYNC1")
        .unwrap();
    let soft = IutKind::SoftDevice {
        faults: vec![],
        choices: vec![],
    };
    let own = run(
        profile,
        &scenario,
        &UnderTest::Device(soft.clone(), soft.declared()),
    );
    assert!(
        matches!(own.outcome, canif_harness::GherkinOutcome::Pass),
        "{:?}",
        own.outcome
    );
    let told = Declared {
        sync1_output_delay: Some(5_000),
        ..Declared::default()
    }
    .or(soft.declared());
    let contradicted = run(profile, &scenario, &UnderTest::Device(soft, told));
    match contradicted.outcome {
        canif_harness::GherkinOutcome::Fail { blamed, .. } => {
            assert!(blamed.contains(&"PDX-004".to_string()), "{blamed:?}")
        }
        other => panic!("expected a failure, got {other:?}"),
    }
}

/// Issue 36: a client that declares it does without transaction numbers
/// (or time stamps) is not run on the scenario that needs them, which was
/// an ERROR; one that needs them is not run where the profile has none.
#[test]
fn a_client_declaration_leaves_out_what_it_does_not_serve() {
    use canif_features::schedule::declined_by_client;
    use canif_harness::client::ClientDeclaration;
    let catalogue = Catalogue::embedded().unwrap();
    let list = scenarios().unwrap();
    let in_flight = list
        .iter()
        .find(|s| s.name == "Transaction numbers tell the messages in flight apart")
        .unwrap();
    let ccat = catalogue.profile("ccat").unwrap();
    let declared = |line: &str| ClientDeclaration::parse(&[line]).unwrap();
    assert_eq!(
        declined_by_client(in_flight, ccat, &declared("transaction-numbers=no")).as_deref(),
        Some("the client declares transaction-numbers=no")
    );
    assert_eq!(
        declined_by_client(in_flight, ccat, &declared("transaction-numbers=yes")),
        None
    );
    let plain = list
        .iter()
        .find(|s| s.name == "A batch stays as it is until the device has acknowledged it")
        .unwrap();
    let fc510x = catalogue.profile("fc510x").unwrap();
    assert!(
        declined_by_client(plain, fc510x, &declared("transaction-numbers=yes")).is_some(),
        "{}:{}",
        plain.file,
        plain.line
    );
}
