//! Every Gherkin scenario (each Examples row once) as its own test, scheduled
//! as `canif run` schedules it (`canif_features::schedule`): device scenarios
//! against the soft device, `@plc` scenarios against the reference client, on
//! every profile that offers what they need; the manual's tables (`@model`)
//! run once against the model. A profile lacking a capability lists the
//! scenario as ignored with the reason. Works under `cargo test` and nextest.

use canif_features::schedule::{self, UnderTest};
use canif_features::{run_scenario, scenarios, ScenarioInfo, Target};
use canif_harness::client::suite::ClientKind;
use canif_harness::device::IutKind;
use canif_harness::GherkinOutcome;
use canif_spec::{Catalogue, Side};
use libtest_mimic::{Arguments, Failed, Trial};

fn under_test(side: Side) -> UnderTest {
    match side {
        Side::Device => {
            let soft = IutKind::SoftDevice {
                faults: vec![],
                choices: vec![],
            };
            UnderTest::Device(soft.clone(), soft.declared())
        }
        Side::Plc => UnderTest::Client(ClientKind::Reference, Default::default()),
    }
}

fn trial_name(profile: &str, scenario: &ScenarioInfo) -> String {
    let file = scenario
        .file
        .trim_start_matches("features/")
        .trim_end_matches(".feature");
    let side = match scenario.side {
        Side::Plc => "plc::",
        Side::Device => "",
    };
    format!(
        "{side}{profile}::{file}:{}: {}",
        scenario.line, scenario.name
    )
}

fn main() {
    let args = Arguments::from_args();
    let catalogue = Box::leak(Box::new(
        Catalogue::embedded().expect("the catalogue loads"),
    ));
    let scenarios = scenarios().expect("the features parse");
    let profiles: Vec<_> = catalogue.profiles.iter().collect();
    let mut trials = Vec::new();
    for scenario in scenarios.iter().filter(|s| s.model_only) {
        let (path, line) = (scenario.file.clone(), scenario.line);
        let target = Target::new(
            IutKind::Model,
            "model",
            canif_model::config::Capabilities::everything(),
        );
        trials.push(Trial::test(
            trial_name("model", scenario),
            move || match run_scenario(&path, line, target) {
                canif_features::ScenarioOutcome::Passed => Ok(()),
                other => Err(Failed::from(format!("{other:?}"))),
            },
        ));
    }
    for side in [Side::Device, Side::Plc] {
        let targets = schedule::targets(&scenarios, &profiles, side);
        for (profile_name, scenario) in &targets {
            let profile = catalogue
                .profile(profile_name)
                .expect("a catalogued profile");
            let (scenario, under_test) = (scenario.clone(), under_test(side));
            trials.push(Trial::test(
                trial_name(profile_name, &scenario),
                move || match schedule::run(profile, &scenario, &under_test).outcome {
                    GherkinOutcome::Pass => Ok(()),
                    GherkinOutcome::Fail { report, .. } => Err(Failed::from(report)),
                    GherkinOutcome::Error(report) => Err(Failed::from(format!("error: {report}"))),
                },
            ));
        }
        // What the schedule leaves out on a profile, listed with the reason.
        for scenario in scenarios
            .iter()
            .filter(|s| s.side == side && !s.model_only && !s.once)
        {
            for profile in &profiles {
                let missing = profile.lacks(&scenario.capabilities);
                if !missing.is_empty() {
                    trials.push(
                        Trial::test(trial_name(&profile.name, scenario), || Ok(()))
                            .with_kind(format!("n/a: lacks {}", missing.join("+")))
                            .with_ignored_flag(true),
                    );
                }
            }
        }
    }
    libtest_mimic::run(&args, trials).exit();
}
