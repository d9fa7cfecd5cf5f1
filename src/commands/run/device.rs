//! `canif run` on the device side: an IUT that must behave like an EL6751,
//! with the harness playing the PLC and the other nodes.

use std::path::Path;
use std::process::ExitCode;

use crate::stop::{stop, Stop};

#[cfg(feature = "socketcan")]
use canif_harness::device::bus::kernel::KernelBusOptions;
use canif_harness::device::bus::BusChoice;
use canif_harness::device::{IutKind, Options};
use canif_harness::door::ethercat::Pace;
use canif_harness::door::Door;
use canif_harness::report::{ChoiceEntry, ChoiceSource, RunMeta, RunReport};
use canif_harness::{Outcome, RunError};
use canif_spec::Catalogue;

use super::{finish, Plan};
use crate::cli::{BusArg, IutOptions, RealTimeOptions};
use crate::commands::resolve_iut;

pub(crate) fn run(
    catalogue: &Catalogue,
    iut: &IutOptions,
    plan: &Plan<Options>,
    pace: Pace,
    report_dir: &Path,
) -> Result<ExitCode, Stop> {
    let kind = resolve_iut(iut)?;
    if let Some(rerun) = &plan.rerun {
        rerun.same_iut(&kind.name())?;
    }
    plan.check_selection(catalogue)?;
    if let IutKind::Door(Door::Ethercat {
        link: canif_harness::door::ethercat::EthercatLink::Interface { name, .. },
        ..
    }) = &kind
    {
        if plan.options.bus.is_sim() {
            return Err(stop!(
                "--iut ethercat:{name}: a terminal on a network interface has its CAN port on a real bus; \
                 add --bus socketcan:IFACE (the CAN adapter cabled to it), or use ethercat:emulated"
            ));
        }
    }
    if let IutKind::Door(Door::Ethercat { .. }) = kind {
        let not_terminals: Vec<&str> = plan
            .profiles
            .iter()
            .filter(|p| p.ethercat.is_none())
            .map(|p| p.name.as_str())
            .collect();
        if !not_terminals.is_empty() {
            let terminals = catalogue.terminal_names();
            return Err(stop!(
                "--iut ethercat: {} {} no EtherCAT terminal; name terminal profiles with --profile ({})",
                not_terminals.join(", "),
                if not_terminals.len() == 1 { "is" } else { "are" },
                terminals.join(", ")
            ));
        }
    }
    #[cfg(feature = "socketcan")]
    if let BusChoice::SocketCan(kernel) = &plan.options.bus {
        // A bus that cannot be opened at all is one error, not one per scenario.
        let opened = canif_kernel::probe().and_then(|()| {
            canif_kernel::KernelSocket::open(&kernel.spec.iut, false)?;
            canif_kernel::KernelSocket::open(&kernel.spec.tester, false).map(|_| ())
        });
        if let Err(error) = opened {
            return Err(stop!("error: --bus {}: {error}", kernel.spec.describe()));
        }
    }
    finish(
        catalogue,
        &execute(catalogue, &kind, plan, pace),
        report_dir,
    )
}

/// Over EtherCAT, each profile's terminal brought up once before the run:
/// its identity, 0x1C32:05 and the time of an exchange, for the report.
fn survey_terminals(
    kind: &IutKind,
    plan: &Plan<Options>,
    pace: Pace,
) -> Vec<canif_harness::report::TerminalEntry> {
    let IutKind::Door(Door::Ethercat { link, .. }) = kind else {
        return Vec::new();
    };
    let mut terminals = Vec::new();
    for profile in &plan.profiles {
        if profile.ethercat.is_none() {
            continue;
        }
        match canif_harness::door::ethercat::survey(profile, link, pace) {
            Ok(facts) => {
                errln!(
                    "{}: {} vendor {:#010x} product {:#010x} revision {:#010x}, SyncManagers {}, {} output and {} input bytes ({} of CAN status), 0x1C32:05 {}, an idle cycle {} µs (worst {} µs)",
                    profile.name,
                    facts.name,
                    facts.vendor_id,
                    facts.product_code,
                    facts.revision,
                    facts.layout(),
                    facts.output_bytes,
                    facts.input_bytes,
                    facts.status_bytes,
                    facts.local_cycle_ns.map_or("not answered".into(), |ns| format!("{ns} ns")),
                    facts.mean_cycle_ns / 1_000,
                    facts.worst_cycle_ns / 1_000
                );
                if let Some(period) = facts.period_ns {
                    errln!(
                        "{}: soak of {} cycles every {} µs: {} missed their deadline",
                        profile.name,
                        facts.cycles,
                        period / 1_000,
                        facts.missed_cycles
                    );
                }
                terminals.push(facts);
            }
            // The run itself meets the same terminal and reports what broke.
            Err(error) => errln!(
                "{}: the terminal could not be surveyed: {error}",
                profile.name
            ),
        }
    }
    terminals
}

/// Idle cycles an unpaced survey times.
pub(crate) const SURVEY_CYCLES: u32 = 1_000;

/// Runs a plan: the lockstep on each profile, then the Gherkin scenarios, and
/// judges every requirement once over all of them.
pub(crate) fn execute(
    catalogue: &Catalogue,
    kind: &IutKind,
    plan: &Plan<Options>,
    pace: Pace,
) -> RunReport {
    let options = &plan.options;
    let started = std::time::Instant::now();
    let meta = RunMeta::new(
        kind.name(),
        describe_bus(&options.bus),
        options.seed,
        catalogue,
    );
    let mut meta = meta;
    meta.terminals = survey_terminals(kind, plan, pace);
    let lockstep = plan.run_profiles_on(catalogue, kind, Some("cycles"), plan.jobs);
    meta.choices = judged_choices(options, kind);
    let iut_broke = lockstep.iter().flat_map(|p| &p.runs).any(|r| {
        matches!(
            r.outcome,
            Outcome::Error(RunError::Iut(_) | RunError::Skipped(_))
        )
    });
    let mut left_out = plan.selection_left_out();
    let gherkin = if canif_harness::interrupt::requested() {
        left_out.push("interrupted before the Gherkin scenarios".into());
        Vec::new()
    } else if iut_broke && options.fail_fast {
        left_out.push(
            "Gherkin scenarios not run: the IUT broke (--no-fail-fast runs them anyway)".into(),
        );
        Vec::new()
    } else if !options.bus.is_sim() {
        left_out.push("Gherkin scenarios not run: they use the simulated bus".into());
        Vec::new()
    } else {
        plan.run_gherkin(&canif_features::UnderTest::Device(
            kind.clone(),
            options.declared_by(kind),
        ))
    };
    plan.assemble(catalogue, lockstep, gherkin, left_out, meta, started)
}

/// The choices the verdicts rest on: declared for the device (on the command
/// line, by its kind, or by the IUT itself), or shown by a scenario on a
/// profile where it declared none.
fn judged_choices(options: &Options, kind: &IutKind) -> Vec<ChoiceEntry> {
    let declared = options
        .declared_by(kind)
        .lines()
        .into_iter()
        .map(|choice| ChoiceEntry {
            choice,
            how: ChoiceSource::Declared,
        });
    let observed = options
        .observed
        .lock()
        .map(|o| o.clone())
        .unwrap_or_default();
    let by_iut = options
        .iut_declared
        .lock()
        .map(|d| d.clone())
        .unwrap_or_default();
    declared
        .chain(by_iut.into_iter().map(|choice| ChoiceEntry {
            choice,
            how: ChoiceSource::DeclaredByIut,
        }))
        .chain(observed.into_iter().map(|o| ChoiceEntry {
            choice: o.line(),
            how: ChoiceSource::Observed {
                profile: o.profile,
                scenario: o.scenario,
            },
        }))
        .collect()
}

/// The bus as the report names it.
fn describe_bus(bus: &BusChoice) -> String {
    match bus {
        BusChoice::Sim => "simulated bus (virtual time)".into(),
        #[cfg(feature = "socketcan")]
        BusChoice::SocketCan(k) => format!(
            "{} on Linux {}, real time, {} µs cycle, time stamps within {} µs{}",
            k.spec.describe(),
            canif_kernel::kernel_release(),
            k.cycle_time / 1_000,
            k.time_stamp_tolerance / 1_000,
            match (k.remote_frames, k.esi_settable) {
                (true, true) => "",
                (false, true) => ", remote frames sent as data frames",
                (true, false) => ", ESI left to the controllers",
                (false, false) =>
                    ", remote frames sent as data frames, ESI left to the controllers",
            }
        ),
    }
}

/// The bus the command line chose, with its real-time options.
#[cfg_attr(not(feature = "socketcan"), allow(unused_variables))]
/// How the terminals of a run over EtherCAT are surveyed before it: a soak
/// at the real-time cycle when asked for, else a burst of idle cycles.
pub(crate) fn pace(real_time: &RealTimeOptions) -> Pace {
    match real_time.ethercat_soak_s {
        0 => Pace::Unpaced(SURVEY_CYCLES),
        seconds => Pace::Every {
            period: std::time::Duration::from_micros(real_time.cycle_us),
            soak: std::time::Duration::from_secs(seconds),
        },
    }
}

#[cfg_attr(not(feature = "socketcan"), allow(unused_variables))]
pub(crate) fn bus_choice(bus: &BusArg, real_time: &RealTimeOptions) -> BusChoice {
    match bus {
        BusArg::Sim => BusChoice::Sim,
        #[cfg(feature = "socketcan")]
        BusArg::SocketCan(spec) => BusChoice::SocketCan(KernelBusOptions {
            spec: spec.clone(),
            cycle_time: real_time.cycle_us * 1_000,
            time_stamp_tolerance: real_time.time_stamp_tolerance_us * 1_000,
            timeout: std::time::Duration::from_millis(real_time.frame_timeout_ms),
            remote_frames: !real_time.no_remote_frames,
            esi_settable: !real_time.esi_from_controller,
        }),
    }
}
