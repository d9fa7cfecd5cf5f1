//! One test per requirement × profile, on either side through the one
//! runner: device requirements against the soft device, PLC-side (CL-*)
//! requirements against the reference client, each on the simulated bus.
//! Works under `cargo test` and `cargo nextest`. A requirement the profile
//! lacks, or that no case of its side exercises on that profile, is listed
//! as ignored with the reason as its kind.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Mutex, OnceLock};

use canif_harness::client::suite::{ClientKind, ClientOptions};
use canif_harness::device::{IutKind, Options};
use canif_harness::run::{run_profile, Cases};
use canif_harness::Verdict;
use canif_spec::{Catalogue, Profile, Side};
use libtest_mimic::{Arguments, Failed, Trial};

type Verdicts = Arc<BTreeMap<String, Verdict>>;
type Runs = Mutex<BTreeMap<(Side, String), Verdicts>>;

fn device() -> (Options, IutKind) {
    let options = Options {
        cases: 2,
        ..Options::default()
    };
    let soft_device = IutKind::SoftDevice {
        faults: vec![],
        choices: vec![],
    };
    (options, soft_device)
}

fn client() -> (ClientOptions, ClientKind) {
    (ClientOptions::new(1), ClientKind::Reference)
}

/// Every requirement some case of `side` exercises on `profile`.
fn exercised<S: Cases>(side: &S, profile: &Profile) -> BTreeSet<String> {
    side.cases(profile)
        .iter()
        .flat_map(|case| S::covers(case).iter().map(|id| id.to_string()))
        .collect()
}

/// Each side runs once on each profile, whichever of its trials comes first.
fn verdicts<S: Cases>(
    catalogue: &Catalogue,
    profile: &Profile,
    (side, under_test): (S, S::UnderTest),
) -> Verdicts {
    static RUNS: OnceLock<Runs> = OnceLock::new();
    let runs = RUNS.get_or_init(Default::default);
    let key = (S::SIDE, profile.name.clone());
    if let Some(verdicts) = runs.lock().unwrap().get(&key) {
        return verdicts.clone();
    }
    let run = run_profile(profile, &under_test, &side, |_| {});
    let verdicts = Arc::new(run.verdicts(catalogue, profile));
    runs.lock().unwrap().entry(key).or_insert(verdicts).clone()
}

fn judged(verdict: Option<&Verdict>) -> Result<(), Failed> {
    match verdict {
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
}

fn main() {
    let args = Arguments::from_args();
    let catalogue = Arc::new(Catalogue::embedded().expect("the embedded catalogue loads"));
    let mut trials = Vec::new();
    for profile in &catalogue.profiles {
        let exercised_by = |side: Side| match side {
            Side::Device => exercised(&device().0, profile),
            Side::Plc => exercised(&client().0, profile),
        };
        let checked = [
            (Side::Device, exercised_by(Side::Device)),
            (Side::Plc, exercised_by(Side::Plc)),
        ];
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
            let side = requirement.side;
            if !checked
                .iter()
                .any(|(s, ids)| *s == side && ids.contains(&requirement.id))
            {
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
                let profile = catalogue
                    .profile(&profile_name)
                    .expect("a catalogued profile");
                let verdicts = match side {
                    Side::Device => verdicts(&catalogue, profile, device()),
                    Side::Plc => verdicts(&catalogue, profile, client()),
                };
                judged(verdicts.get(&id))
            }));
        }
    }
    libtest_mimic::run(&args, trials).exit();
}
