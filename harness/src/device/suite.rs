//! One profile's run of a device: the configuration-refusal grid, then every
//! scenario of every interface the profile offers, each in lockstep with the
//! model. The device side of [`crate::run::Cases`].

use canif_model::config::{Capabilities, TxQueueAccounting};
use canif_model::freedoms::Named;
use canif_model::Nanos;
use canif_spec::{Profile, ReqId, Scope, Side, Suite};

use super::cases::{scenarios, Generation};
use super::iut_kind::IutKind;
use super::lockstep::run_scenario;
use super::refusals::{check_refusals, refused, REFUSALS, REFUSAL_IDS};
use super::scenario::{Judgement, Scenario};
use crate::declare::choices::{
    Choice, Declared, Observed, TX_QUEUE_ACCOUNTING_IDS, TX_QUEUE_ACCOUNTING_SETTLED_BY,
};
use crate::declare::{ChoiceEntry, ChoiceSource, Declaration};
use crate::device::medium::BusChoice;
use crate::error::{Refusal, RunError};
use crate::outcome::{Outcome, ScenarioRun};
use crate::run::{Cases, Selection, SelfCheck};
use crate::verdict::Reach;

/// What to run.
#[derive(Debug, Clone)]
pub struct Options {
    pub seed: u64,
    /// Generated scenarios per interface.
    pub cases: u64,
    /// Cycles of each generated scenario.
    pub generated_cycles: u64,
    /// Include the 65,540-cycle RxCounter wrap.
    pub counter_wrap: bool,
    /// Write each scenario's bus trace under this folder (`PROFILE/SCENARIO.{log,pcapng}`).
    pub trace_dir: Option<std::path::PathBuf>,
    /// What a trace stamps scenario time 0 with, in ns since the Unix epoch.
    pub trace_epoch: Nanos,
    /// The bus the scenarios run on.
    pub bus: BusChoice,
    /// Which scenarios run (all by default).
    pub selection: Selection,
    /// After the IUT breaks in a profile, report the profile's remaining
    /// scenarios as skipped instead of starting the broken IUT again.
    pub fail_fast: bool,
    /// What the command line declares of the device's choices (over what
    /// the IUT kind declares itself).
    pub declared: Declared,
    /// How a terminal over EtherCAT is surveyed before the run (behind
    /// another door, nothing is).
    pub survey: crate::door::Pace,
}

/// What a profile's device run learns as its cases run: what an undeclared
/// device showed of its Tx queue accounting (and where), what the IUT
/// declared itself in its `configured` answers.
#[derive(Debug, Clone, Default)]
pub struct Learned {
    pub observed: Option<Observed>,
    pub by_iut: Declared,
}

impl Options {
    /// What the generated scenarios are made of.
    pub fn generation(&self) -> Generation {
        Generation {
            seed: self.seed,
            cases: self.cases,
            generated_cycles: self.generated_cycles,
            counter_wrap: self.counter_wrap,
        }
    }

    /// A short run for tests: one generated case of 100 cycles, no counter wrap.
    pub fn quick(seed: u64) -> Self {
        Options {
            seed,
            cases: 1,
            generated_cycles: 100,
            counter_wrap: false,
            trace_dir: None,
            trace_epoch: 0,
            bus: BusChoice::Sim,
            fail_fast: true,
            selection: Selection::default(),
            declared: Declared::default(),
            survey: Default::default(),
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            cases: 4,
            generated_cycles: 200,
            counter_wrap: true,
            ..Options::quick(1)
        }
    }
}

impl Options {
    /// What the device declares: the command line's word over the IUT's own.
    pub fn declared_by(&self, kind: &IutKind) -> Declared {
        self.declared.or(kind.declared())
    }

    /// One scenario, judged by the choice the device declared, or the one a
    /// scenario before showed; a device that declared none and has shown
    /// none yet passes under any documented choice, and the first scenario
    /// that tells them apart settles which one holds for the rest.
    fn run_judged_by_choice(
        &self,
        kind: &IutKind,
        mut caps: Capabilities,
        scenario: &Scenario,
        (profile, learned): (&str, &mut Learned),
    ) -> ScenarioRun {
        let declared = self.declared_by(kind);
        caps.sync1_output_delay = declared.sync1_output_delay;
        let scenario = &Scenario {
            declared,
            ..scenario.clone()
        };
        let settled = declared
            .tx_queue_accounting
            .or_else(|| learned.observed.as_ref().map(|o| o.tx_queue_accounting));
        caps.tx_queue_accounting = settled.unwrap_or_default();
        let run = run_scenario(kind, &caps, scenario, scenario.steps());
        let run = self.judged_as_declared(kind, &caps, scenario, run);
        learned.by_iut = run.iut_declares.device().or(learned.by_iut);
        // The IUT declared its accounting itself: judged by that, nothing to find out.
        let self_declared = run.iut_declares.device().tx_queue_accounting.is_some();
        if settled.is_some() || self_declared {
            return run;
        }
        match &run.outcome {
            Outcome::Fail(failure)
                if failure
                    .requirements
                    .iter()
                    .any(|id| TX_QUEUE_ACCOUNTING_IDS.contains(id)) =>
            {
                let tried = caps.tx_queue_accounting;
                for other in TxQueueAccounting::ALL
                    .iter()
                    .copied()
                    .filter(|a| *a != tried)
                {
                    caps.tx_queue_accounting = other;
                    let again = run_scenario(kind, &caps, scenario, scenario.steps());
                    if matches!(again.outcome, Outcome::Pass) {
                        learned.observed = Some(Observed {
                            profile: profile.to_string(),
                            tx_queue_accounting: other,
                            scenario: scenario.name.clone(),
                        });
                        return again;
                    }
                }
                run
            }
            // It settles the accounting only where the other one fails: a
            // scenario that passes under both told nothing apart.
            Outcome::Pass if scenario.covers.contains(&TX_QUEUE_ACCOUNTING_SETTLED_BY) => {
                let passed_under = caps.tx_queue_accounting;
                let told_apart = TxQueueAccounting::ALL
                    .iter()
                    .filter(|a| **a != passed_under)
                    .all(|other| {
                        let caps = Capabilities {
                            tx_queue_accounting: *other,
                            ..caps.clone()
                        };
                        let again = run_scenario(kind, &caps, scenario, scenario.steps());
                        matches!(again.outcome, Outcome::Fail(_))
                    });
                if told_apart {
                    learned.observed = Some(Observed {
                        profile: profile.to_string(),
                        tx_queue_accounting: passed_under,
                        scenario: scenario.name.clone(),
                    });
                }
                run
            }
            _ => run,
        }
    }
}

impl Options {
    /// A scenario of G3's freedoms judged exactly, as the device declared
    /// them, that failed: if it passes under another value of one of them,
    /// the device does the other thing and broke that declaration (the
    /// failure is that choice's requirement); if it fails under every value,
    /// the difference is no freedom of G3 and the scenario is judged by its
    /// bounds alone, as for an undeclared device (the scenarios written for
    /// that difference blame it on its own requirement).
    fn judged_as_declared(
        &self,
        kind: &IutKind,
        caps: &Capabilities,
        scenario: &Scenario,
        mut run: ScenarioRun,
    ) -> ScenarioRun {
        let Judgement::Bounds { decided_by } = scenario.judgement else {
            return run;
        };
        let declared = scenario.declared.or(run.iut_declares.device());
        let exact = decided_by.iter().all(|c| declared.value(*c).is_some());
        if !exact || !matches!(run.outcome, Outcome::Fail(_)) {
            return run;
        }
        let passes_under = |choice: Choice, value: &str| {
            let mut otherwise = scenario.clone();
            otherwise.declared = declared;
            let line = format!("{choice}={value}");
            otherwise
                .declared
                .declare(&line)
                .expect("a choice's own value");
            let again = run_scenario(kind, caps, &otherwise, otherwise.steps());
            matches!(again.outcome, Outcome::Pass)
        };
        let broken: Vec<ReqId> = decided_by
            .iter()
            .filter(|choice| {
                let current = declared.value(**choice);
                choice
                    .named_values()
                    .iter()
                    .filter(|v| Some(v.to_string()) != current)
                    .any(|other| passes_under(**choice, other))
            })
            .filter_map(|choice| choice.settled_by())
            .collect();
        if broken.is_empty() {
            let bounds = Scenario {
                judgement: Judgement::Bounds { decided_by: &[] },
                ..scenario.clone()
            };
            return run_scenario(kind, caps, &bounds, bounds.steps());
        }
        if let Outcome::Fail(failure) = &mut run.outcome {
            failure.requirements = broken;
        }
        run
    }
}

/// One case of a device's run.
#[derive(Debug, Clone)]
pub enum DeviceCase {
    /// The configuration-refusal grid (`configuration refusals`).
    Refusals,
    /// One scenario in lockstep with the model.
    Scenario(Box<Scenario>),
}

impl Cases for Options {
    type UnderTest = IutKind;
    type Case = DeviceCase;
    const UNDER_TEST: &'static str = "the IUT";
    const SIDE: Side = Side::Device;
    type Learned = Learned;

    fn cases(&self, profile: &Profile) -> Vec<DeviceCase> {
        device_cases(&profile.model_capabilities(), self)
    }

    fn name(case: &DeviceCase) -> String {
        match case {
            DeviceCase::Refusals => REFUSALS.into(),
            DeviceCase::Scenario(scenario) => scenario.name.clone(),
        }
    }

    fn covers(case: &DeviceCase) -> &[ReqId] {
        match case {
            DeviceCase::Refusals => REFUSAL_IDS,
            DeviceCase::Scenario(scenario) => &scenario.covers,
        }
    }

    fn run(
        &self,
        kind: &IutKind,
        profile: &Profile,
        case: DeviceCase,
        learned: &mut Learned,
    ) -> ScenarioRun {
        let kind = &kind.for_profile(profile);
        let caps = profile.model_capabilities();
        let mut scenario = match case {
            DeviceCase::Refusals => return check_refusals(kind, &caps),
            DeviceCase::Scenario(scenario) => scenario,
        };
        scenario.time_stamp_tolerance = profile.timestamp_tolerance_ns;
        scenario.bus = self.bus.clone();
        if let Some(dir) = &self.trace_dir {
            let name: String = scenario
                .name
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            scenario.trace = Some((dir.join(&profile.name), name, self.trace_epoch));
        }
        let mut run = self.run_judged_by_choice(kind, caps, &scenario, (&profile.name, learned));
        // Refusing an interface the profile offers is the device's failure,
        // not a broken exchange; what the scenario needed it for is not run.
        if let Outcome::Error(RunError::Configuration(Refusal::Iut(reason))) = &run.outcome {
            let failure = refused(&scenario.name, &scenario.interface, reason.clone());
            run.outcome = Outcome::Fail(Box::new(failure));
        }
        run
    }

    fn choices(learned: Learned) -> Vec<ChoiceEntry> {
        let by_iut = learned
            .by_iut
            .lines()
            .into_iter()
            .map(|choice| ChoiceEntry {
                choice,
                how: ChoiceSource::DeclaredByIut,
            });
        let observed = learned.observed.map(|o| ChoiceEntry {
            choice: o.line(),
            how: ChoiceSource::Observed {
                profile: o.profile,
                scenario: o.scenario,
            },
        });
        by_iut.chain(observed).collect()
    }

    fn selection(&self) -> &Selection {
        &self.selection
    }

    fn fail_fast(&self) -> bool {
        self.fail_fast
    }

    fn reach(&self, profile: &Profile, _: &[ScenarioRun]) -> Reach {
        Reach {
            scope: Scope {
                side: Side::Device,
                suite: Suite::Interface,
            },
            here: exercised(&profile.model_capabilities(), self)
                .into_iter()
                .collect(),
            left_out: self.selection.not_run(),
            ..Reach::default()
        }
    }
}

/// A device run's cases on a device with these capabilities: the refusal
/// grid, then every scenario.
pub fn device_cases(caps: &Capabilities, options: &Options) -> Vec<DeviceCase> {
    let scenarios = scenarios(caps, &options.generation());
    std::iter::once(DeviceCase::Refusals)
        .chain(
            scenarios
                .into_iter()
                .map(|s| DeviceCase::Scenario(Box::new(s))),
        )
        .collect()
}

/// Every requirement a run exercises on a device with these capabilities
/// (with at least one generated case): exactly what `judge` can call pass
/// or fail, whatever the selection.
pub fn exercised(caps: &Capabilities, options: &Options) -> Vec<String> {
    let everything = Options {
        cases: options.cases.max(1),
        ..options.clone()
    };
    crate::run::checked_ids::<Options>(&device_cases(caps, &everything))
}

/// A profile that has the feature `fault` breaks, for tests that need one.
pub fn profile_for(fault: canif_softdevice::Fault) -> &'static str {
    use canif_softdevice::Fault::*;
    match fault {
        FdLengthRoundsDown
        | FdLength32As36
        | FdPaddingFf
        | BrsEsiSwapped
        | ReceiveFifoNotReported
        | BrsWithoutEdlSendsFd
        | InfoDataTwoBytesLate
        | TimeStampOn11Bit
        | FdWithoutTransactionNumber
        | FdLengthAsDlc
        | FdKeepsRemote
        | InfoDataStartsZero => "fc532x",
        TransactionNumberOn11Bit => "el6751-legacy",
        AcceptsEveryFormat => "fc510x-before-fw2.14",
        TransactionNumberNotOffered => "ccat-before-fw1.17",
        ExtendedFlagMissing
        | TransactionNumberOfFirstFrame
        | TransactionNumberOnHandover
        | TimeStampInMicroseconds
        | FilterLastMatchWins
        | FilterRangeEndExcluded
        | FilterUnmatchedAccepted
        | StandardIdKeepsHighBits => "ccat",
        _ => "el6751-mdp",
    }
}

/// The soft device's faults, each alone.
impl SelfCheck for Options {
    type Fault = canif_softdevice::Fault;

    fn faults() -> Vec<Self::Fault> {
        canif_softdevice::Fault::ALL.to_vec()
    }

    fn fault_name(fault: Self::Fault) -> &'static str {
        fault.name()
    }

    fn with_fault(&self, fault: Self::Fault) -> (Self, IutKind) {
        let options = Options {
            counter_wrap: fault == canif_softdevice::Fault::CounterDoesNotWrap,
            ..self.clone()
        };
        let kind = IutKind::SoftDevice {
            faults: vec![fault],
            choices: vec![],
        };
        (options, kind)
    }
}
