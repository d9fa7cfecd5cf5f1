//! A run of the device side: an IUT that must behave like an EL6751, with
//! the harness playing the PLC and the other nodes. Each profile's lockstep,
//! then the Gherkin scenarios, judged once over all of them.

use canif_harness::device::medium::BusChoice;
use canif_harness::device::{IutKind, Options};
use canif_harness::door::Role;
use canif_harness::report::{ChoiceEntry, RunMeta, RunReport, TerminalEntry};
use canif_harness::run::ProfileRun;
use canif_harness::{Outcome, RunError};
use canif_spec::Catalogue;

use crate::error::PlanError;
use crate::event::{Event, Observer};
use crate::{Campaign, Plan};

impl Campaign for Options {
    const UNIT: Option<&'static str> = Some("cycles");

    fn name_of(kind: &IutKind) -> String {
        kind.name()
    }

    fn shared(plan: &Plan<'_, Self>, kind: &IutKind) -> Option<&'static str> {
        let door = match kind {
            IutKind::Door(door) => door.transport().shared_between_profiles(),
            _ => None,
        };
        door.or((!plan.options.bus.is_sim()).then_some(crate::socketcan::ONE_INTERFACE))
    }

    fn preflight(
        plan: &Plan<'_, Self>,
        catalogue: &Catalogue,
        kind: &IutKind,
    ) -> Result<(), PlanError> {
        // What the command line declares must agree with what the IUT
        // declares itself, on every route that runs it.
        if let Some(contradiction) = kind.contradicts(&plan.options.declared) {
            return Err(PlanError::Preflight(contradiction));
        }
        if let IutKind::Door(door) = kind {
            door.transport()
                .preflight(
                    &plan.profiles,
                    plan.options.bus.is_sim(),
                    &catalogue.terminal_names(),
                )
                .map_err(PlanError::Preflight)?;
            door.starts(Role::Device).map_err(PlanError::not_started)?;
        }
        #[cfg(feature = "socketcan")]
        if let BusChoice::SocketCan(kernel) = &plan.options.bus {
            let spec = &kernel.spec;
            crate::socketcan::opens(&spec.describe(), &[&spec.iut, &spec.tester])?;
        }
        Ok(())
    }

    fn execute(
        plan: &Plan<'_, Self>,
        catalogue: &Catalogue,
        kind: &IutKind,
        observer: &dyn Observer,
    ) -> RunReport {
        let options = &plan.options;
        let started = std::time::Instant::now();
        let mut meta = RunMeta::new(
            kind.name(),
            describe_bus(&options.bus),
            options.seed,
            catalogue,
        );
        meta.terminals = survey_terminals(kind, plan, observer);
        let lockstep = plan.run_profiles(kind, observer);
        meta.choices = judged_choices(options, kind, &lockstep);
        let iut_broke = lockstep.iter().flat_map(|p| &p.runs).any(|r| {
            matches!(
                r.outcome,
                Outcome::Error(RunError::Iut(_) | RunError::Skipped(_))
            )
        });
        let mut left_out = plan.left_out(&lockstep);
        let skip = match () {
            _ if iut_broke && options.fail_fast => {
                Some("the IUT broke (--no-fail-fast runs them anyway)")
            }
            _ if !options.bus.is_sim() => Some("they use the simulated bus"),
            _ => None,
        };
        let under_test =
            || canif_features::UnderTest::Device(kind.clone(), options.declared_by(kind));
        let gherkin = plan.gherkin_stage(skip, under_test, &mut left_out, observer);
        plan.assemble(
            catalogue,
            (lockstep, gherkin),
            left_out,
            meta,
            (started, observer),
        )
    }
}

/// Each profile's terminal brought up once before the run, where the door
/// has one to survey: its identity, 0x1C32:05 and the time of an exchange,
/// for the report.
fn survey_terminals(
    kind: &IutKind,
    plan: &Plan<'_, Options>,
    observer: &dyn Observer,
) -> Vec<TerminalEntry> {
    let IutKind::Door(door) = kind else {
        return Vec::new();
    };
    let mut terminals = Vec::new();
    for profile in &plan.profiles {
        match door.transport().survey(profile, plan.options.survey) {
            None => {}
            Some(Ok(facts)) => {
                observer.event(Event::TerminalSurveyed {
                    profile,
                    facts: &facts,
                });
                terminals.push(facts);
            }
            Some(Err(error)) => observer.event(Event::TerminalNotSurveyed {
                profile,
                error: &error.to_string(),
            }),
        }
    }
    terminals
}

/// The choices the verdicts rest on: declared for the device (on the
/// command line or by its kind), then what each profile's run learned (what
/// the IUT declared itself, what a scenario showed where it declared
/// nothing), each once.
fn judged_choices(options: &Options, kind: &IutKind, runs: &[ProfileRun]) -> Vec<ChoiceEntry> {
    let mut choices = ChoiceEntry::declared(&options.declared_by(kind));
    for learned in runs.iter().flat_map(|run| &run.choices) {
        if !choices.contains(learned) {
            choices.push(learned.clone());
        }
    }
    choices
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
