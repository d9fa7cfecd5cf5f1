//! A run driven as a library call, without the command line: the plan
//! checked, the stages run, the events heard, the report judged.

use std::sync::Mutex;

use canif_harness::client::suite::{ClientKind, ClientOptions};
use canif_harness::device::{IutKind, Options};
use canif_harness::run::Selection;
use canif_harness::VerdictKind;
use canif_runner::{Event, Plan, PlanError, Quiet};
use canif_spec::Catalogue;

/// What an observer heard, by kind.
#[derive(Default, Debug, PartialEq, Eq)]
struct Heard {
    started: usize,
    scenarios: usize,
    finished: Vec<(usize, usize)>,
    gherkin: usize,
    left_out: Vec<String>,
}

fn listen(heard: &Mutex<Heard>) -> impl Fn(Event<'_>) + Sync + '_ {
    move |event| {
        let mut heard = heard.lock().unwrap();
        match event {
            Event::ProfileStarted { .. } => heard.started += 1,
            Event::ScenarioFinished { .. } => heard.scenarios += 1,
            Event::ProfileFinished { at, done, .. } => heard.finished.push((at.index, done)),
            Event::GherkinFinished { ran, .. } => heard.gherkin += ran,
            Event::LeftOut(line) => heard.left_out.push(line.to_string()),
            _ => {}
        }
    }
}

fn catalogue() -> Catalogue {
    Catalogue::embedded().expect("the embedded catalogue loads")
}

/// A device run of one requirement on one profile: its verdict and what it told.
fn device_run(
    catalogue: &Catalogue,
    kind: &IutKind,
    jobs: usize,
) -> (canif_harness::report::RunReport, Heard) {
    let profiles = ["fc532x", "el6751-legacy"]
        .iter()
        .map(|name| catalogue.profile(name).expect("a catalogued profile"))
        .collect();
    let options = Options {
        selection: Selection {
            requirements: vec!["FD-LEN-005".into()],
            ..Selection::default()
        },
        ..Options::quick(1)
    };
    let mut plan = Plan::new(profiles, options, None).expect("the plan");
    plan.jobs = jobs;
    let heard = Mutex::new(Heard::default());
    let report = plan
        .run(catalogue, kind, &listen(&heard))
        .expect("the plan runs");
    (report, heard.into_inner().unwrap())
}

fn verdict(report: &canif_harness::report::RunReport, profile: &str, id: &str) -> VerdictKind {
    let profile = report
        .profiles
        .iter()
        .find(|p| p.profile == profile)
        .expect("the profile ran");
    profile
        .verdicts
        .get(id)
        .expect("the requirement is judged")
        .kind()
}

#[test]
fn a_device_run_is_a_library_call_that_judges_and_tells_its_progress() {
    let catalogue = catalogue();
    let correct = IutKind::SoftDevice {
        faults: vec![],
        choices: vec![],
    };
    let (report, heard) = device_run(&catalogue, &correct, 1);
    assert_eq!(verdict(&report, "fc532x", "FD-LEN-005"), VerdictKind::Pass);
    assert_eq!(report.exit_code(), 0, "{}", report.headline());
    // One at a time: each profile begins, each case is told, each ends in order.
    assert_eq!(heard.started, 2);
    assert!(heard.scenarios > 0);
    assert_eq!(heard.finished, vec![(0, 1), (1, 2)]);
    assert!(
        heard.left_out.iter().any(|l| l.contains("FD-LEN-005")),
        "the selection is said to leave the rest out: {:?}",
        heard.left_out
    );

    let faulty = IutKind::SoftDevice {
        faults: vec![canif_softdevice::Fault::FdPaddingFf],
        choices: vec![],
    };
    let (report, _) = device_run(&catalogue, &faulty, 1);
    assert_eq!(verdict(&report, "fc532x", "FD-LEN-005"), VerdictKind::Fail);
    assert_eq!(report.exit_code(), 1);
}

#[test]
fn profiles_side_by_side_report_what_a_serial_run_reports() {
    let catalogue = catalogue();
    let faulty = IutKind::SoftDevice {
        faults: vec![canif_softdevice::Fault::FdPaddingFf],
        choices: vec![],
    };
    let (serial, _) = device_run(&catalogue, &faulty, 1);
    let (parallel, heard) = device_run(&catalogue, &faulty, 2);
    // Beside each other, profiles are told only when done.
    assert_eq!(heard.started, 0);
    assert_eq!(heard.scenarios, 0);
    assert_eq!(heard.finished.len(), 2);
    let verdicts = |r: &canif_harness::report::RunReport| {
        r.profiles
            .iter()
            .map(|p| {
                let kinds: Vec<(String, VerdictKind)> = p
                    .verdicts
                    .iter()
                    .map(|(id, v)| (id.clone(), v.kind()))
                    .collect();
                (p.profile.clone(), kinds)
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(verdicts(&serial), verdicts(&parallel));
}

#[test]
fn a_plc_side_run_rejects_a_client_that_acknowledges_with_its_own_counter() {
    let catalogue = catalogue();
    let profiles = vec![catalogue.profile("fc510x").expect("fc510x")];
    let options = ClientOptions {
        counter_wrap: false,
        selection: Selection {
            requirements: vec!["CL-RX-002".into()],
            ..Selection::default()
        },
        ..ClientOptions::new(1)
    };
    let plan = Plan::new(profiles, options, None).expect("the plan");
    let faulty = ClientKind::Faulty(Some(
        canif_harness::client::soft_client::ClientFault::OwnRxCounter,
    ));
    let report = plan
        .run(&catalogue, &faulty, &Quiet)
        .expect("the plan runs");
    assert_eq!(verdict(&report, "fc510x", "CL-RX-002"), VerdictKind::Fail);
    let report = plan
        .run(&catalogue, &ClientKind::Reference, &Quiet)
        .expect("the plan runs");
    assert_eq!(verdict(&report, "fc510x", "CL-RX-002"), VerdictKind::Pass);
}

#[test]
fn a_plan_that_selects_nothing_or_the_other_side_is_refused_before_it_runs() {
    let catalogue = catalogue();
    let kind = IutKind::SoftDevice {
        faults: vec![],
        choices: vec![],
    };
    let plan_of = |selection: Selection| {
        let options = Options {
            selection,
            ..Options::quick(1)
        };
        Plan::new(vec![&catalogue.profiles[0]], options, None).expect("the plan")
    };
    let nothing = plan_of(Selection {
        scenarios: vec!["no check is called this".into()],
        ..Selection::default()
    });
    assert!(matches!(
        nothing.run(&catalogue, &kind, &Quiet),
        Err(PlanError::NothingSelected { .. })
    ));
    let plc = plan_of(Selection {
        requirements: vec!["CL-RX-002".into()],
        ..Selection::default()
    });
    match plc.run(&catalogue, &kind, &Quiet) {
        Err(error @ PlanError::OtherSide { .. }) => {
            assert!(error
                .to_string()
                .contains("`canif run plc --requirement CL-RX-002`"))
        }
        other => panic!("a PLC-side requirement on the device side: {other:?}"),
    }
    let typo = plan_of(Selection {
        requirements: vec!["FD-LEN-05".into()],
        ..Selection::default()
    });
    assert!(matches!(
        typo.run(&catalogue, &kind, &Quiet),
        Err(PlanError::UnknownRequirement { near: Some(_), .. })
    ));
}
