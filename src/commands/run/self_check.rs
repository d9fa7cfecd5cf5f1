//! `canif self-check`: the suite's power shown on itself, both sides.

use std::process::ExitCode;

use canif_features::UnderTest;
use canif_harness::run::KillRow;
use canif_spec::Catalogue;

use canif_runner::Plan;

use super::Progress;
use crate::stop::Stop;

/// `canif self-check`: both kill matrices, every fault of each side on every profile.
pub(crate) fn self_check(catalogue: &Catalogue, seed: u64) -> Result<ExitCode, Stop> {
    let options = canif_harness::device::Options {
        cases: 2,
        generated_cycles: 150,
        ..canif_harness::device::Options::quick(seed)
    };
    let mut devices = canif_harness::run::kill_matrix(catalogue, &options, |fault| {
        errln!("running {fault} on every profile")
    });
    let plan = Plan::new(catalogue.profiles.iter().collect(), options, None)?;
    for row in &mut devices {
        errln!("running {} in the Gherkin scenarios", row.fault.name());
        add_gherkin_failures(&plan, catalogue, row);
    }
    let uncaught = print_kill_table("device fault", &devices, |f| f.name());
    let device_unreached = print_unreached::<canif_harness::device::Options>(
        catalogue,
        devices.iter().flat_map(KillRow::failed),
    );
    let clients = canif_harness::run::kill_matrix(
        catalogue,
        &canif_harness::client::suite::ClientOptions {
            counter_wrap: false,
            ..canif_harness::client::suite::ClientOptions::new(seed)
        },
        |fault| errln!("running client fault {fault} on every profile"),
    );
    sayln!();
    let clients_uncaught = print_kill_table("client fault", &clients, |f| f.name());
    let client_unreached = print_unreached::<canif_harness::client::suite::ClientOptions>(
        catalogue,
        clients.iter().flat_map(KillRow::failed),
    );
    let short = uncaught + clients_uncaught + device_unreached + client_unreached;
    Ok(ExitCode::from(u8::from(short > 0)))
}

/// What the Gherkin scenarios failed with the device fault of `row`, added
/// to what its lockstep scenarios failed: a run blames both, and some
/// statements only a scenario tagged with them isolates (RXQ-001's depth).
fn add_gherkin_failures(
    plan: &Plan<'_, canif_harness::device::Options>,
    catalogue: &Catalogue,
    row: &mut KillRow<canif_softdevice::Fault>,
) {
    let kind = canif_harness::device::IutKind::SoftDevice {
        faults: vec![row.fault],
        choices: vec![],
    };
    let faulty = UnderTest::Device(kind.clone(), kind.declared());
    for (profile_name, run) in plan.run_gherkin(&faulty, &Progress::new(catalogue)) {
        let canif_harness::GherkinOutcome::Fail { blamed, .. } = run.outcome else {
            continue;
        };
        let Some(profile) = catalogue.profile(&profile_name) else {
            continue;
        };
        let applies = |id: &String| {
            catalogue
                .requirement(id)
                .is_some_and(|r| profile.lacks(&r.capabilities).is_empty())
        };
        let caught = match row
            .caught
            .iter_mut()
            .find(|(name, _)| *name == profile_name)
        {
            Some((_, ids)) => ids,
            None => {
                row.caught.push((profile_name.clone(), Vec::new()));
                &mut row.caught.last_mut().expect("just pushed").1
            }
        };
        for id in blamed.into_iter().filter(applies) {
            if !caught.contains(&id) {
                caught.push(id);
            }
        }
    }
}

/// The side's requirements no fault failed, listed (issue 36: every
/// requirement is shown able to fail); how many.
fn print_unreached<'a, S: canif_harness::run::SelfCheck>(
    catalogue: &Catalogue,
    failed: impl IntoIterator<Item = &'a str>,
) -> usize {
    let unreached = canif_harness::run::unreached::<S>(catalogue, failed);
    match unreached.as_slice() {
        [] => sayln!("\nevery {} requirement is failed by some fault", S::SIDE),
        ids => sayln!(
            "\n{} {} requirements no fault fails yet: {}",
            ids.len(),
            S::SIDE,
            ids.join(", ")
        ),
    }
    unreached.len()
}

/// One kill matrix as Markdown: each fault, the profiles it was caught on and
/// the requirements that failed. The faults not caught anywhere, counted.
fn print_kill_table<F: Copy>(
    what: &str,
    rows: &[KillRow<F>],
    name: impl Fn(F) -> &'static str,
) -> usize {
    let mut uncaught = 0;
    sayln!("| {what} | caught on | requirements that failed |\n|---|---|---|");
    for row in rows {
        let on = row.caught.iter().filter(|(_, ids)| !ids.is_empty()).count();
        let ids: std::collections::BTreeSet<&str> = row.failed().collect();
        if on == 0 {
            uncaught += 1;
        }
        sayln!(
            "| {} | {on}/{} profiles | {} |",
            name(row.fault),
            row.caught.len(),
            if ids.is_empty() {
                "NOT CAUGHT".to_string()
            } else {
                ids.into_iter().collect::<Vec<_>>().join(", ")
            }
        );
    }
    sayln!(
        "\n{} of {} {what}s caught",
        rows.len() - uncaught,
        rows.len()
    );
    uncaught
}
