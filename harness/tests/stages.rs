//! Each stage of a run on its own, through the harness's public API: one
//! profile's run of any side (`run_profile`, with a side written here), the
//! lockstep of one device scenario, the rig of one client scenario, and the
//! door's one dispatch.

use canif_harness::client::rig;
use canif_harness::client::soft_client::ClientFault;
use canif_harness::client::suite::{scenarios as client_scenarios, ClientKind, ClientOptions};
use canif_harness::declare::{ChoiceEntry, ChoiceSource};
use canif_harness::device::cases::{scenarios as device_scenarios, Generation};
use canif_harness::device::{run_scenario, IutKind};
use canif_harness::door::{Door, Role, Settings, Timeouts};
use canif_harness::run::{run_profile, Cases, Selection};
use canif_harness::verdict::Reach;
use canif_harness::{IutError, Outcome, RunError, ScenarioRun};
use canif_spec::{Catalogue, Profile, ReqId};

fn catalogue() -> Catalogue {
    Catalogue::embedded().expect("the embedded catalogue loads")
}

/// A side written for the test: three cases, each ending as the table under
/// test says, each learning its own name.
struct Table {
    selection: Selection,
}

const IDS: [&[ReqId]; 3] = [
    &[ReqId::new("HS-TX-001")],
    &[ReqId::new("HS-TX-002")],
    &[ReqId::new("HS-TX-003")],
];

impl Cases for Table {
    /// How each case ends, by name.
    type UnderTest = Vec<(&'static str, Outcome)>;
    type Case = usize;
    const UNDER_TEST: &'static str = "the table";
    const SIDE: canif_spec::Side = canif_spec::Side::Device;
    /// The cases that ran before, in order.
    type Learned = Vec<String>;

    fn cases(&self, _: &Profile) -> Vec<usize> {
        vec![0, 1, 2]
    }

    fn name(case: &usize) -> String {
        ["a", "b", "c"][*case].to_string()
    }

    fn covers(case: &usize) -> &[ReqId] {
        IDS[*case]
    }

    fn run(
        &self,
        table: &Self::UnderTest,
        _: &Profile,
        case: usize,
        learned: &mut Vec<String>,
    ) -> ScenarioRun {
        let name = Self::name(&case);
        let outcome = table
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(Outcome::Pass, |(_, o)| o.clone());
        learned.push(name.clone());
        ScenarioRun::ended(name, Self::covers(&case).to_vec(), outcome)
    }

    fn choices(learned: Vec<String>) -> Vec<ChoiceEntry> {
        learned
            .into_iter()
            .map(|choice| ChoiceEntry {
                choice,
                how: ChoiceSource::DeclaredByIut,
            })
            .collect()
    }

    fn selection(&self) -> &Selection {
        &self.selection
    }

    fn fail_fast(&self) -> bool {
        true
    }

    fn reach(&self, _: &Profile, _: &[ScenarioRun]) -> Reach {
        Reach::default()
    }
}

fn ran(run: &canif_harness::run::ProfileRun) -> Vec<&str> {
    run.choices.iter().map(|c| c.choice.as_str()).collect()
}

#[test]
fn each_case_learns_what_the_cases_before_it_learned_and_the_profile_run_returns_it() {
    let catalogue = catalogue();
    let side = Table {
        selection: Selection::default(),
    };
    let run = run_profile(&catalogue.profiles[0], &vec![], &side, |_| {});
    assert_eq!(ran(&run), ["a", "b", "c"]);
    assert!(run.runs.iter().all(|r| r.outcome == Outcome::Pass));
}

#[test]
fn after_what_is_under_test_broke_the_rest_are_skipped_and_not_started_again() {
    let catalogue = catalogue();
    let side = Table {
        selection: Selection::default(),
    };
    let broke = RunError::Iut(IutError::new(canif_harness::error::IutCause::Gone, "gone"));
    let table = vec![("b", Outcome::Error(broke))];
    let mut told = Vec::new();
    let run = run_profile(&catalogue.profiles[0], &table, &side, |r| {
        told.push(r.scenario.clone())
    });
    // c was never run: it learned nothing, and is reported skipped after b.
    assert_eq!(ran(&run), ["a", "b"]);
    assert_eq!(told, ["a", "b", "c"], "every case is told, skipped or not");
    assert!(matches!(
        &run.runs[2].outcome,
        Outcome::Error(RunError::Skipped(after)) if after.scenario == "b"
    ));
}

#[test]
fn a_selection_runs_only_the_cases_it_admits() {
    let catalogue = catalogue();
    let side = Table {
        selection: Selection {
            requirements: vec!["HS-TX-002".into()],
            ..Selection::default()
        },
    };
    let run = run_profile(&catalogue.profiles[0], &vec![], &side, |_| {});
    assert_eq!(ran(&run), ["b"]);
    assert_eq!(run.runs.len(), 1);
}

/// One device scenario in lockstep: the model against itself passes; the
/// soft device with its COB ID word byte-swapped fails exactly LAY-GEN-003.
#[test]
fn the_lockstep_passes_the_model_and_fails_a_swapped_cob_id_word_on_its_requirement() {
    let catalogue = catalogue();
    let caps = catalogue
        .profile("el6751-mdp")
        .unwrap()
        .model_capabilities();
    let generation = Generation {
        seed: 1,
        cases: 1,
        generated_cycles: 50,
        counter_wrap: false,
    };
    let exercising: Vec<_> = device_scenarios(&caps, &generation)
        .into_iter()
        .filter(|s| s.covers.contains(&ReqId::new("LAY-GEN-003")))
        .collect();
    assert!(!exercising.is_empty(), "scenarios exercise the COB ID word");
    let swapped = IutKind::SoftDevice {
        faults: vec![canif_softdevice::Fault::CobIdWordBigEndian],
        choices: vec![],
    };
    let mut failed = Vec::new();
    for scenario in &exercising {
        let model = run_scenario(&IutKind::Model, &caps, scenario, scenario.steps());
        assert_eq!(model.outcome, Outcome::Pass, "{}", scenario.name);
        let run = run_scenario(&swapped, &caps, scenario, scenario.steps());
        match run.outcome {
            Outcome::Pass => {}
            Outcome::Fail(failure) => failed.push(failure.requirements),
            other => panic!("{}: {other:?}", scenario.name),
        }
    }
    assert!(!failed.is_empty(), "no scenario saw the swapped word");
    for requirements in failed {
        assert_eq!(requirements, [ReqId::new("LAY-GEN-003")]);
    }
}

/// One client scenario in the rig: the reference client passes, one that
/// acknowledges with its own counter fails CL-RX-002 among what it breaks.
#[test]
fn the_client_rig_passes_the_reference_and_fails_a_client_with_its_own_rx_counter() {
    let catalogue = catalogue();
    let caps = catalogue.profile("fc510x").unwrap().model_capabilities();
    let options = ClientOptions {
        counter_wrap: false,
        ..ClientOptions::new(1)
    };
    let exercising: Vec<_> = client_scenarios(&caps, &options)
        .into_iter()
        .filter(|(s, _)| s.covers.contains(&ReqId::new("CL-RX-002")))
        .collect();
    assert!(!exercising.is_empty(), "life cycles exercise CL-RX-002");
    let mut caught = false;
    for (scenario, master) in &exercising {
        let run_of = |kind: ClientKind| {
            let build = |layout| kind.build(&scenario.config, layout);
            rig::run(&caps, scenario, *master, &build, &rig::simulated)
        };
        assert_eq!(run_of(ClientKind::Reference).outcome, Outcome::Pass);
        if let Outcome::Fail(failure) =
            run_of(ClientKind::Faulty(Some(ClientFault::OwnRxCounter))).outcome
        {
            caught |= failure
                .breaches()
                .iter()
                .any(|b| b.requirements.contains(&ReqId::new("CL-RX-002")));
        }
    }
    assert!(caught, "no life cycle caught the client's own RxCounter");
}

fn settings(faults: Vec<canif_softdevice::Fault>) -> Settings {
    Settings {
        timeouts: Timeouts::default(),
        same_cpu: true,
        host: None,
        faults,
        choices: vec![],
    }
}

/// `--iut` parses into one door arm each, and each transport answers for itself.
#[test]
fn the_door_parses_each_transport_and_dispatches_to_it_once() {
    let door = |text: &str| Door::parse(text).expect("a door").expect("valid");
    let exec = door("exec:python3 iut.py");
    assert_eq!(exec.name(), "exec:python3 iut.py");
    assert!(exec.owns_its_bus());
    assert!(exec.transport().serves_clients());
    let lib = door("lib:./libx.so");
    assert_eq!(lib.name(), "lib:./libx.so");
    assert!(!lib.owns_its_bus());
    assert!(
        lib.transport().shared_between_profiles().is_some(),
        "in process"
    );
    let terminal = door("ethercat:emulated");
    assert!(
        !terminal.transport().serves_clients(),
        "a terminal is a device"
    );
    assert!(terminal.transport().shared_between_profiles().is_some());
    let catalogue = catalogue();
    let fc510x = catalogue.profile("fc510x").unwrap();
    assert!(
        !terminal.transport().serves(fc510x),
        "fc510x is no terminal"
    );
    assert!(exec.transport().serves(fc510x));
    assert!(exec
        .transport()
        .survey(fc510x, Default::default())
        .is_none());
    // Words that name no door are left to the caller; a door without its
    // argument is refused, naming what it needs.
    assert!(Door::parse("softdevice").is_none());
    assert!(Door::parse("exec: ").unwrap().is_err());
    assert!(Door::parse("lib:").unwrap().is_err());
}

#[test]
fn a_door_takes_the_settings_that_apply_behind_it_and_refuses_the_others() {
    let fault = canif_softdevice::Fault::CobIdWordBigEndian;
    let exec = Door::parse("exec:true").unwrap().unwrap();
    let refused = exec.clone().settled(&settings(vec![fault])).unwrap_err();
    assert!(
        refused.contains("--fault applies to the soft device only"),
        "{refused}"
    );
    // An emulated terminal has the soft device behind it: its name says the fault.
    let terminal = Door::parse("ethercat:emulated").unwrap().unwrap();
    let settled = terminal.settled(&settings(vec![fault])).unwrap();
    assert!(settled.name().contains(fault.name()), "{}", settled.name());
    // A library with a host runs in a process of its own: nothing shared.
    let hosted = Settings {
        host: Some("/usr/bin/canif".into()),
        ..settings(vec![])
    };
    let lib = Door::parse("lib:./libx.so").unwrap().unwrap();
    let lib = lib.settled(&hosted).unwrap();
    assert!(lib.transport().shared_between_profiles().is_none());
    // A library that is no file cannot start, in either role.
    for role in [Role::Device, Role::Client] {
        let error = lib.starts(role).unwrap_err();
        assert!(error.what.contains("no such file"), "{}", error.what);
    }
}
