//! One test per requirement × profile: the soft device, certified by the
//! harness on the simulated bus. Works under `cargo test` and `cargo nextest`.
//! A requirement the profile lacks, or that no run against an IUT checks on
//! that profile, is listed as ignored with the reason as its kind.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, OnceLock};

use canif_harness::suite::{checked_ids, run_profile, Options};
use canif_harness::{IutKind, ProfileRun, Verdict};
use canif_spec::Catalogue;
use libtest_mimic::{Arguments, Failed, Trial};

type Runs = Mutex<BTreeMap<String, Arc<ProfileRun>>>;

fn options() -> Options {
    Options {
        cases: 2,
        ..Options::default()
    }
}

/// Each profile runs once, whichever of its trials comes first.
fn profile_run(catalogue: &Catalogue, name: &str) -> Arc<ProfileRun> {
    static RUNS: OnceLock<Runs> = OnceLock::new();
    let runs = RUNS.get_or_init(Default::default);
    if let Some(run) = runs.lock().unwrap().get(name) {
        return run.clone();
    }
    let profile = catalogue.profile(name).expect("profile of the catalogue");
    let run = Arc::new(run_profile(
        catalogue,
        profile,
        &IutKind::SoftDevice {
            faults: vec![],
            choices: vec![],
        },
        &options(),
        |_| {},
    ));
    runs.lock()
        .unwrap()
        .entry(name.to_string())
        .or_insert(run)
        .clone()
}

fn main() {
    let args = Arguments::from_args();
    let catalogue = Arc::new(Catalogue::embedded().expect("the embedded catalogue loads"));
    let mut trials = Vec::new();
    for profile in &catalogue.profiles {
        let checked = checked_ids(&profile.model_capabilities(), &options());
        for requirement in catalogue.requirements() {
            let name = format!("{}::{}", profile.name, requirement.id);
            let missing = profile.lacks(&requirement.capabilities);
            if !missing.is_empty() {
                trials.push(
                    Trial::test(name, || Ok(()))
                        .with_kind(format!("n/a: lacks {}", missing.join("+")))
                        .with_ignored_flag(true),
                );
                continue;
            }
            if !checked.contains(&requirement.id) {
                trials.push(
                    Trial::test(name, || Ok(()))
                        .with_kind("not testable by a run")
                        .with_ignored_flag(true),
                );
                continue;
            }
            let catalogue = catalogue.clone();
            let (profile_name, id) = (profile.name.clone(), requirement.id.clone());
            trials.push(Trial::test(name, move || {
                let run = profile_run(&catalogue, &profile_name);
                match run.verdicts.get(&id) {
                    Some(Verdict::Pass(_)) => Ok(()),
                    Some(Verdict::Fail(found)) => Err(Failed::from(
                        found
                            .iter()
                            .map(|(_, finding)| finding.details.clone())
                            .collect::<Vec<_>>()
                            .join("\n\n"),
                    )),
                    Some(verdict @ Verdict::Error(_)) => Err(Failed::from(format!(
                        "error: {}",
                        verdict.reason().unwrap_or_default()
                    ))),
                    other => Err(Failed::from(format!(
                        "listed as checked on this profile, but the run says {other:?}"
                    ))),
                }
            }));
        }
    }
    libtest_mimic::run(&args, trials).exit();
}
