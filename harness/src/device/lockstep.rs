//! The lockstep: the reference PLC (001 §6) writes outputs, the model and the
//! IUT run the same cycle on them, their input images are compared field by
//! field and every frame either hands to its controller is compared on the
//! bus. The first difference ends the scenario as a failure naming the
//! requirements of the differing field.

use canif_model::config::{Capabilities, QueueMode};
use canif_model::device::Device;
use canif_model::exchange::ExchangeMode;
use canif_model::image::{InputImage, OutputImage};
use canif_model::Nanos;
use canif_spec::ReqId;

use crate::declare::Declares;
use crate::device::blame;
use crate::device::bounds::Bounds;
use crate::device::diff::{DeclaredRx, Difference, Handshake, InputCheck};
use crate::device::iut_kind::IutKind;
use crate::device::medium::Bus;
use crate::device::pair::Pair;
use crate::device::played_plc::{PlcSide, TaskReport, TaskStimulus};
use crate::device::protocol_order::Ordered;
use crate::device::scenario::{Judgement, Scenario, Step};
use crate::device::sync1_window::Sync1Window;
use crate::door::iut::BuildError;
use crate::error::{HarnessError, IutCause, IutError, Refusal, RunError};
use crate::outcome::{Outcome, ScenarioRun};
use crate::trace::TraceWriter;

/// Runs one scenario against an IUT beside the model.
pub fn run_scenario(
    kind: &IutKind,
    caps: &Capabilities,
    scenario: &Scenario,
    steps: impl Iterator<Item = Step>,
) -> ScenarioRun {
    let run = |outcome, cycles, (frames_checked, tolerated)| ScenarioRun {
        cycles,
        frames_checked,
        tolerated,
        ..ScenarioRun::ended(scenario.name.clone(), scenario.covers.clone(), outcome)
    };
    let bus = match scenario.bus.open(scenario.bit_rates, kind.owns_its_bus()) {
        Ok(bus) => bus,
        Err(error) => return run(Outcome::Error(error), 0, (0, 0)),
    };
    let mut lockstep = match Lockstep::start(kind, caps, scenario, bus) {
        Ok(lockstep) => lockstep,
        Err(error) => return run(Outcome::Error(error), 0, (0, 0)),
    };
    // A declared freedom is judged, so a pass is evidence for it too.
    let judged_declared = lockstep.judged_declared(scenario);
    let result = lockstep.run(steps);
    let iut_declares = std::mem::take(&mut lockstep.iut_declares);
    let pair = &mut lockstep.pair;
    let result = match (result, pair.bounds.as_ref().and_then(Bounds::still_cycling)) {
        (Ok(cycles), Some(stopped)) => Err((pair.fail(stopped), cycles)),
        (result, _) => result,
    };
    pair.finish();
    let run = match result {
        Ok(cycles) => run(Outcome::Pass, cycles, (pair.frames, pair.tolerated)),
        Err((outcome, cycle)) => run(outcome, cycle, (pair.frames, pair.tolerated)),
    };
    let mut covers = run.covers.clone();
    covers.extend(judged_declared);
    ScenarioRun {
        iut_declares,
        covers,
        ..run
    }
}

/// What a cycle needs of its scenario, kept by the lockstep (a Gherkin
/// world's steps may add declared lengths as they go).
#[derive(Debug, Clone)]
pub struct Rules {
    pub exchange: ExchangeMode,
    pub fast_queue: bool,
    pub declared_lengths: Vec<(u16, u8)>,
    pub check_confirmation_delay: bool,
    /// The cycle the scenario's offsets are written for.
    pub scenario_cycle_time: Nanos,
    /// The don't-care fields the device declared what it writes into.
    pub declared_rx: DeclaredRx,
}

/// One scenario in progress: the played PLC, the pair of model and IUT, and
/// the bus under them. Scripted and generated scenarios run it step after
/// step ([`run_scenario`]); a Gherkin world drives the same cycle one step
/// at a time.
pub struct Lockstep<B: Bus + ?Sized = dyn Bus> {
    pub pair: Pair,
    pub plc: PlcSide,
    pub rules: Rules,
    pub bus: Box<B>,
    /// What the IUT itself declared and was judged by (`NAME=VALUE`).
    pub iut_declares: Declares,
    cycle_time: Nanos,
    time_stamp_tolerance: Nanos,
}

impl<B: Bus + ?Sized> Lockstep<B> {
    /// The model, then the IUT on `bus`, in the order a real bus needs them:
    /// the IUT is told which socket to open.
    pub fn start(
        kind: &IutKind,
        caps: &Capabilities,
        scenario: &Scenario,
        bus: Box<B>,
    ) -> Result<Self, RunError> {
        // Checked first: a configuration the model refuses starts no IUT.
        Device::new(caps, scenario.interface.clone())
            .map_err(|e| RunError::Configuration(Refusal::Model(e)))?;
        let built = kind
            .build_on(caps, &scenario.interface, bus.owned_bus().as_ref())
            .map(|mut iut| {
                if let Some(telegrams) = iut.telegrams() {
                    telegrams.exchange_with(scenario.exchange);
                }
                iut
            });
        let iut = match built {
            // On a real-time bus the kernel's clock, not the harness, orders the times.
            Ok(iut) if bus.real_time() => iut,
            Ok(iut) => Box::new(Ordered::new(iut)),
            Err(BuildError::Refused(reason)) => {
                return Err(RunError::Configuration(Refusal::Iut(reason)))
            }
            Err(BuildError::Failed(error)) => return Err(error.into()),
        };
        // What the IUT declares itself counts where canif was told nothing;
        // where both speak, they must say the same.
        let own = iut.declared();
        let told = scenario.declared;
        if let Some((choice, said, declares)) = told.contradiction(&own) {
            return Err(IutError::new(
                IutCause::Protocol,
                format!(
                    "declares `{choice}={declares}` itself, where canif was told `{choice}={said}` (--declare): one of them is wrong"
                ),
            )
            .into());
        }
        let declared = told.or(own);
        let caps = &declared.apply(caps);
        let iut_declares = Declares::Device(own.except(&told));
        let model = Device::new(caps, scenario.interface.clone())
            .map_err(|e| RunError::Configuration(Refusal::Model(e)))?;
        let trace = scenario.trace.as_ref().and_then(|(dir, name, epoch)| {
            TraceWriter::create(dir, name, &bus.interface_name(), *epoch).ok()
        });
        let mut pair = Pair::new(iut, model, (&scenario.name, &scenario.covers), trace);
        if let Judgement::Bounds { decided_by } = scenario.judgement {
            // Decided by nothing a device declares: the bounds alone.
            if decided_by.is_empty() || decided_by.iter().any(|c| declared.value(*c).is_none()) {
                pair.bounds = Some(Bounds::default());
            }
        }
        pair.sync1 = Sync1Window::new(caps.sync1_output_delay, declared.sync1_jitter);
        Ok(Lockstep {
            plc: PlcSide::new(pair.layout, scenario.exchange),
            rules: Rules {
                exchange: scenario.exchange,
                fast_queue: scenario.interface.queue == QueueMode::Fast,
                declared_lengths: scenario.declared_lengths.clone(),
                check_confirmation_delay: scenario.check_confirmation_delay,
                scenario_cycle_time: scenario.cycle_time,
                declared_rx: DeclaredRx {
                    idle_count: declared.rx_idle_count.is_some(),
                    stale_slots: declared.stale_rx_slots.is_some(),
                },
            },
            // On a real-time bus the cycle is real time, and the scenario's offsets scale with it.
            cycle_time: bus.cycle_time().unwrap_or(scenario.cycle_time),
            time_stamp_tolerance: scenario
                .time_stamp_tolerance
                .max(bus.time_stamp_tolerance()),
            pair,
            bus,
            iut_declares,
        })
    }

    /// Every step, one cycle each: the number of cycles run, or how it ended
    /// early and in which cycle.
    fn run(&mut self, steps: impl Iterator<Item = Step>) -> Result<u64, (Outcome, u64)> {
        for (k, step) in steps.enumerate() {
            let k = k as u64;
            if crate::interrupt::requested() {
                return Err((Outcome::Error(RunError::Interrupted), k));
            }
            self.cycle(k, step).map_err(|outcome| (outcome, k))?;
            // The checker judges the images; what the PLC read is not kept (bounded memory).
            drop(self.plc.take_received());
        }
        Ok(self.pair.cycle + 1)
    }

    /// When cycle `k` starts, in scenario time.
    pub fn start_of(&self, k: u64) -> Nanos {
        k * self.cycle_time
    }

    /// Runs the bus on to scenario time `until` (frames end, the pair learns of them).
    pub fn run_bus(&mut self, until: Nanos) -> Result<(), Outcome> {
        self.bus.run_until(&mut self.pair, until)
    }

    /// Cycle `k`: the bus up to its start, the PLC's task, the model's and
    /// the IUT's cycle on the same outputs, their inputs compared; then the
    /// other nodes' frames of the step go on the bus.
    /// The PLC's part of cycle `k`: the step's messages handed to it, the
    /// controller status given to both devices, and its task run (unless
    /// the step keeps it busy), its confirmation delay checked.
    fn plc_task(&mut self, k: u64, step: &mut Step) -> Result<TaskReport, Outcome> {
        let rules = &self.rules;
        let layout = self.pair.layout;
        for message in &mut step.send {
            message.frame = self.bus.adapt(message.frame);
        }
        for message in std::mem::take(&mut step.send) {
            if self.plc.send(message).is_err() {
                return Err(Outcome::Error(RunError::Harness(HarnessError::Scenario(
                    format!("a message that does not fit {}", layout.tx_message.name),
                ))));
            }
        }
        if let Some(status) = step.status.take() {
            self.pair
                .iut
                .controller_status(&status)
                .map_err(crate::device::pair::iut_broke)?;
            self.pair.model.handle_controller_status(status);
        }
        let mut report = TaskReport::default();
        if !step.plc_busy {
            let stimulus = TaskStimulus {
                declared_lengths: &rules.declared_lengths,
                set_tx_counter: step.set_tx_counter,
                edits: &step.edits,
                raw_outputs: step.raw_outputs.as_deref(),
            };
            report = self.plc.task(k, stimulus).map_err(|e| {
                Outcome::Error(RunError::Iut(IutError::new(
                    IutCause::Impossible,
                    format!("the PLC cannot read the IUT's input image: {e}"),
                )))
            })?;
            let wanted = u64::from(rules.exchange.confirmation_cycles());
            match report.confirmed_after {
                Some(delay) if rules.check_confirmation_delay && delay != wanted => {
                    return Err(self.pair.fail(Difference {
                        frames: None,
                        candidates: blame::CONFIRMATION,
                        what: "cycles until the PLC sees TxCounter confirmed".into(),
                        expected: wanted.to_string(),
                        actual: delay.to_string(),
                    }));
                }
                _ => {}
            }
        }
        Ok(report)
    }

    pub fn cycle(&mut self, k: u64, mut step: Step) -> Result<Seen, Outcome> {
        let start = self.start_of(k);
        let layout = self.pair.layout;
        self.bus.run_until(&mut self.pair, start)?;
        let t = if self.bus.real_time() {
            self.pair.now
        } else {
            start
        };
        self.pair.cycle = k;
        let report = self.plc_task(k, &mut step)?;
        // Borrowed, not copied: the pair's devices and its history are
        // fields of their own, so nothing here needs a second image.
        let outputs = self.plc.outputs();
        self.pair.outputs(outputs);
        let written = OutputImage::new_checked(outputs, layout)
            .map(|o| o.header())
            .unwrap_or_default();
        let before = InputImage::new_checked(self.pair.model.inputs(), layout)
            .map_or((0, 0), |i| (i.rx_counter(), i.tx_counter()));
        let handshake = Handshake {
            rx_before: before.0,
            plc_released: written.rx_counter,
            fast: self.rules.fast_queue,
            no_of_tx_messages: written.no_of_tx_messages,
            tx_before: before.1,
            tx_requested: written.tx_counter,
        };
        // Told first: an IUT in another process then works while the model does.
        if let Err(e) = self.pair.iut.announce_cycle(outputs, t) {
            return Err(Outcome::Error(e.into()));
        }
        if let Err(e) = self.pair.model.cycle(outputs, t) {
            return Err(Outcome::Error(RunError::Harness(HarnessError::Model(
                e.to_string(),
            ))));
        }
        // Borrowed shared, so that the comparison can ask the model too.
        let expected = self.pair.model.inputs();
        let actual = match self.pair.iut.cycle(outputs, t) {
            Ok(actual) => actual,
            // Stopped at an image's end by its host: what it did, judged (G3).
            Err(e) if e.cause == IutCause::OutsideImage => {
                return Err(self.pair.fail(Difference {
                    frames: None,
                    candidates: blame::OUTSIDE_IMAGE,
                    what: "an access of the process image".into(),
                    expected: "within the image".into(),
                    actual: e.what,
                }))
            }
            Err(e) => return Err(Outcome::Error(e.into())),
        };
        let deviation = self.pair.iut.telegrams().and_then(|t| t.take_deviation());
        if let Some(deviation) = deviation {
            return Err(self.pair.fail(Difference {
                frames: None,
                candidates: blame::deviated(deviation.kind),
                what: deviation.what,
                expected: deviation.expected,
                actual: deviation.actual,
            }));
        }
        self.pair
            .history
            .cycle(layout, (k, self.pair.now), outputs, expected, &actual);
        // Most cycles agree byte for byte: then there is nothing to judge
        // field by field, and nothing was tolerated.
        let identical = expected == &actual[..];
        let difference = match self.pair.bounds.as_mut() {
            Some(bounds) => bounds.cycle(&layout, outputs, &actual),
            None if identical => None,
            None => {
                let (model, history) = (&self.pair.model, &self.pair.history);
                InputCheck {
                    layout: &layout,
                    received: &|f| history.taken(f),
                    overflowed: history.overflowed(),
                    filters: &model.config().filters,
                    waiting_to_send: &|n| model.waiting_transaction_numbers().any(|w| w == n),
                    time_stamp_tolerance: self.time_stamp_tolerance,
                    controller_reported: model.controller_reported(),
                    handshake,
                    declared: self.rules.declared_rx,
                }
                .compare(expected, &actual)
            }
        };
        if let Some(difference) = difference {
            let images = crate::outcome::ImageDiff {
                layout,
                expected: expected.to_vec(),
                actual: actual.clone(),
            };
            let mut outcome = self.pair.fail(difference);
            if let Outcome::Fail(failure) = &mut outcome {
                failure.images = Some(Box::new(images));
            }
            return Err(outcome);
        }
        self.pair.tolerated += u64::from(!identical);
        self.plc.device_cycle_done(&actual);
        for (offset, frame) in step.bus {
            let offset = offset * self.cycle_time / self.rules.scenario_cycle_time.max(1);
            self.bus.schedule(start + offset, self.bus.adapt(frame));
        }
        Ok(Seen {
            report,
            inputs: actual,
        })
    }
}

impl<B: Bus + ?Sized> Lockstep<B> {
    /// The requirements of the don't-care fields `scenario` judges because
    /// the device declared what it writes there (a buffered delivery's).
    pub fn judged_declared(&self, scenario: &Scenario) -> Vec<ReqId> {
        if !scenario.delivers_buffered() {
            return Vec::new();
        }
        let declared = self.rules.declared_rx;
        [
            (declared.idle_count, blame::RX_IDLE_COUNT),
            (declared.stale_slots, blame::RX_STALE_SLOTS),
        ]
        .into_iter()
        .filter(|(judged, _)| *judged)
        .flat_map(|(_, ids)| ids.iter().copied())
        .collect()
    }
}

/// What a cycle showed beyond the judgement, for steps that check more.
#[derive(Debug, Clone)]
pub struct Seen {
    /// What the PLC's task saw (its confirmation of an increment).
    pub report: TaskReport,
    /// The IUT's input image.
    pub inputs: Vec<u8>,
}
