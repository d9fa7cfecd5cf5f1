//! Every Gherkin scenario (each Examples row once) as its own test, against the
//! soft device for every profile whose capabilities the scenario needs; the
//! manual's tables (`@model`) run once. A profile lacking a capability lists the
//! scenario as ignored with the reason. Works under `cargo test` and nextest.

use canif_features::{
    run_client_scenario, run_scenario, scenarios, ClientTarget, ScenarioOutcome, Target,
};
use canif_harness::client::suite::ClientKind;
use canif_harness::IutKind;
use canif_spec::{Catalogue, Side};
use libtest_mimic::{Arguments, Failed, Trial};

fn main() {
    let args = Arguments::from_args();
    let catalogue = Catalogue::embedded().expect("the catalogue loads");
    let scenarios = scenarios().expect("the features parse");
    let mut trials = Vec::new();
    for scenario in scenarios {
        let file = scenario
            .file
            .trim_start_matches("features/")
            .trim_end_matches(".feature")
            .to_string();
        if scenario.side == Side::Plc {
            // The PLC side: the reference client on every profile that offers the interface.
            for profile in &catalogue.profiles {
                let name = format!(
                    "plc::{}::{file}:{}: {}",
                    profile.name, scenario.line, scenario.name
                );
                let missing = profile.lacks(&scenario.capabilities);
                if !missing.is_empty() {
                    trials.push(
                        Trial::test(name, || Ok(()))
                            .with_kind(format!("n/a: lacks {}", missing.join("+")))
                            .with_ignored_flag(true),
                    );
                    continue;
                }
                let (path, line) = (scenario.file.clone(), scenario.line);
                let target = ClientTarget {
                    client: ClientKind::Reference,
                    profile: profile.name.clone(),
                    caps: profile.model_capabilities(),
                };
                trials.push(Trial::test(name, move || {
                    outcome(run_client_scenario(&path, line, target))
                }));
            }
            continue;
        }
        if scenario.model_only || scenario.once {
            let iut = if scenario.model_only {
                IutKind::Model
            } else {
                IutKind::SoftDevice {
                    faults: vec![],
                    choices: vec![],
                }
            };
            let label = if scenario.model_only {
                "model"
            } else {
                "any-profile"
            };
            let name = format!("{label}::{file}:{}: {}", scenario.line, scenario.name);
            let (path, line) = (scenario.file.clone(), scenario.line);
            let target = Target {
                iut,
                profile: label.into(),
                caps: canif_model::config::Capabilities::everything(),
            };
            trials.push(Trial::test(name, move || {
                outcome(run_scenario(&path, line, target))
            }));
            continue;
        }
        for profile in &catalogue.profiles {
            let name = format!(
                "{}::{file}:{}: {}",
                profile.name, scenario.line, scenario.name
            );
            let missing = profile.lacks(&scenario.capabilities);
            if !missing.is_empty() {
                trials.push(
                    Trial::test(name, || Ok(()))
                        .with_kind(format!("n/a: lacks {}", missing.join("+")))
                        .with_ignored_flag(true),
                );
                continue;
            }
            let (path, line) = (scenario.file.clone(), scenario.line);
            let target = Target {
                iut: IutKind::SoftDevice {
                    faults: vec![],
                    choices: vec![],
                },
                profile: profile.name.clone(),
                caps: profile.model_capabilities(),
            };
            trials.push(Trial::test(name, move || {
                outcome(run_scenario(&path, line, target))
            }));
        }
    }
    libtest_mimic::run(&args, trials).exit();
}

fn outcome(outcome: ScenarioOutcome) -> Result<(), Failed> {
    match outcome {
        ScenarioOutcome::Passed => Ok(()),
        ScenarioOutcome::Failed { report, .. } => Err(Failed::from(report)),
        ScenarioOutcome::Error(report) => Err(Failed::from(format!("error: {report}"))),
    }
}
