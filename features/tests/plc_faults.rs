//! The PLC side's Gherkin scenarios reject faulty clients: each fault fails
//! the scenario of its life cycle, and the failed check names the
//! requirement it broke.

use canif_features::{run_client_scenario, scenarios, ClientTarget, ScenarioOutcome};
use canif_harness::client::soft_client::ClientFault;
use canif_harness::client::suite::ClientKind;
use canif_harness::declare::Declaration;
use canif_model::config::Capabilities;
use canif_spec::Side;

/// (fault, words of the scenario's name, the requirement its check witnesses)
const CAUGHT: &[(ClientFault, &str, &str)] = &[
    (
        ClientFault::SendSample000,
        "once and in order",
        "CL-IMG-001",
    ),
    (
        ClientFault::WritesBeforeAcknowledge,
        "until the device has acknowledged",
        "CL-TX-002",
    ),
    (
        ClientFault::AcknowledgesAfterFirstMessage,
        "exactly NoOfRxMessages",
        "CL-RX-004",
    ),
    // With nothing sent Inputs.TxCounter stays 0: the wrong copy leaves
    // Outputs.RxCounter as it was, so it reads the batch again (the lockstep,
    // sending as well, catches the copy itself on CL-RX-001).
    (
        ClientFault::AcknowledgesWithTxCounter,
        "exactly NoOfRxMessages",
        "CL-RX-002",
    ),
    // Out of step after the restart, its own counter is judged by what its
    // application sees (P1): the batch it reads again.
    (
        ClientFault::OwnRxCounter,
        "After a PLC restart",
        "CL-RX-002",
    ),
    (
        ClientFault::IgnoresRxCounterZero,
        "After the device restarts",
        "CL-RST-002",
    ),
    (
        ClientFault::NoBoundOnNoOfRxMessages,
        "whatever NoOfRxMessages says",
        "CL-IMG-001",
    ),
    (ClientFault::FastQueueRereads, "Fast CAN Queue", "CL-FQ-001"),
    (
        ClientFault::TxCounterPlusOne,
        "[master=lrw-zeroed-outputs]",
        "CL-TX-002",
    ),
    (
        ClientFault::TransactionNumberZero,
        "Transaction numbers",
        "CL-TN-001",
    ),
];

#[test]
fn each_faulty_client_fails_the_scenario_of_its_life_cycle_on_its_requirement() {
    let plc: Vec<_> = scenarios()
        .unwrap()
        .into_iter()
        .filter(|s| s.side == Side::Plc)
        .collect();
    for (fault, words, requirement) in CAUGHT {
        let scenario = plc
            .iter()
            .find(|s| s.id().contains(words))
            .unwrap_or_else(|| panic!("no PLC-side scenario says {words:?}"));
        let target = ClientTarget {
            client: ClientKind::Faulty(Some(*fault)),
            declared: Default::default(),
            profile: "everything".into(),
            caps: Capabilities::everything(),
        };
        match run_client_scenario(&scenario.file, scenario.line, target) {
            ScenarioOutcome::Failed { witness, report } => assert!(
                witness.iter().any(|id| id.as_str() == *requirement),
                "{fault} in {:?}: the failed check witnesses {witness:?}, not {requirement}\n{report}",
                scenario.id()
            ),
            other => panic!("{fault} in {:?}: {other:?}, not a failure", scenario.id()),
        }
    }
}

/// What the run holds a client to reaches the Gherkin steps: a client that
/// delivers the batch it finds after a restart again passes undeclared, and
/// fails CL-RST-001 when the command line says it drops it.
#[test]
fn a_declared_restart_choice_is_judged_in_the_gherkin_scenario_too() {
    let scenario = scenarios()
        .unwrap()
        .into_iter()
        .find(|s| s.id().contains("After a PLC restart"))
        .expect("the PLC restart scenario");
    let run = |declared: &[&str]| {
        let target = ClientTarget {
            client: ClientKind::Faulty(None),
            declared: canif_harness::client::ClientDeclaration::parse(declared).unwrap(),
            profile: "everything".into(),
            caps: Capabilities::everything(),
        };
        run_client_scenario(&scenario.file, scenario.line, target)
    };
    assert!(
        matches!(run(&[]), ScenarioOutcome::Passed),
        "{:?}",
        run(&[])
    );
    match run(&["restart=drops-once"]) {
        ScenarioOutcome::Failed { witness, report } => assert!(
            witness.iter().any(|id| id.as_str() == "CL-RST-001"),
            "{witness:?}\n{report}"
        ),
        other => panic!("{other:?}"),
    }
}
