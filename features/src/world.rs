//! The world a scenario runs in: the lockstep of the harness
//! (`canif_harness::device::lockstep`) one cycle at a time. The played PLC
//! (the reference client of 001 §6) writes the outputs, the model and the
//! implementation under test run the same cycle on them and on the same
//! simulated bus, and every cycle is judged against the model as in a
//! scripted scenario; the steps then check what the manual's sentence says.

use std::collections::VecDeque;

use canif_harness::bus::sim::SimBus;
use canif_harness::declare::choices::Declared;
use canif_harness::device::lockstep::Lockstep;
use canif_harness::device::medium::BusChoice;
use canif_harness::device::scenario::{Judgement, Scenario, Step, Steps};
use canif_harness::device::IutKind;
use canif_harness::door::iut::BuildError;
use canif_harness::error::{Refusal, RunError};
use canif_harness::Outcome;
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig};
use canif_model::exchange::ExchangeMode;
use canif_model::frame::Frame;
use canif_model::image::{ImageLayout, InputImage, MessageRepr};
use canif_model::info_data::ControllerStatus;
use canif_model::timing::BitRates;
use canif_model::Nanos;
use canif_spec::ReqId;
use std::cell::RefCell;

use crate::bus_coupler::BusCoupler;

/// Who the scenario runs against; set by the runner before each run.
#[derive(Debug, Clone)]
pub struct Target {
    pub iut: IutKind,
    pub profile: String,
    pub caps: Capabilities,
    /// What the device declares where the documents leave a choice: the
    /// command line's over its kind's own, as the lockstep reads it
    /// (issue 36: Gherkin honours `--declare` too).
    pub declared: Declared,
}

impl Target {
    /// `iut` on `profile` with `caps`, declaring what its kind declares.
    pub fn new(iut: IutKind, profile: impl Into<String>, caps: Capabilities) -> Target {
        let declared = iut.declared();
        Target {
            iut,
            profile: profile.into(),
            caps,
            declared,
        }
    }
}

thread_local! {
    static TARGET: RefCell<Option<Target>> = const { RefCell::new(None) };
    /// Set when the IUT itself broke (could not start, broke the protocol):
    /// the scenario's verdict is then `error`, not `fail`.
    static IUT_ERROR: RefCell<Option<String>> = const { RefCell::new(None) };
    /// The requirements the failed check of the last scenario witnesses.
    static WITNESS: RefCell<Vec<ReqId>> = const { RefCell::new(Vec::new()) };
    /// Set when the IUT refused an interface the profile offers: (the
    /// interface, the IUT's words). The scenario is then its failure, and
    /// what it needed the interface for is not run.
    static REFUSED: RefCell<Option<(String, String)>> = const { RefCell::new(None) };
}

/// Takes the requirements the last scenario's failed check witnesses on this
/// thread (empty when the failure was not a check that names them).
pub fn take_witness() -> Vec<ReqId> {
    WITNESS.with(|w| std::mem::take(&mut *w.borrow_mut()))
}

pub(crate) fn record_witness(witness: &[&[ReqId]]) {
    WITNESS.with(|w| *w.borrow_mut() = witness.concat());
}

/// Takes the IUT error of the last scenario on this thread, if any.
pub fn take_refused() -> Option<(String, String)> {
    REFUSED.with(|r| r.borrow_mut().take())
}

pub fn take_iut_error() -> Option<String> {
    IUT_ERROR.with(|e| e.borrow_mut().take())
}

pub(crate) fn record_iut_error(message: &str) {
    IUT_ERROR.with(|e| *e.borrow_mut() = Some(message.to_string()));
}

/// How a cycle that ended the lockstep reads in a step: a difference from
/// the model fails the step on the requirements of the differing field; a
/// broken IUT is the scenario's error.
fn ended(outcome: Outcome) -> String {
    match outcome {
        Outcome::Fail(failure) => {
            record_witness(&[&failure.requirements]);
            format!(
                "cycle {}: {} differs from the model: expected {}, actual {}",
                failure.cycle, failure.what, failure.expected, failure.actual
            )
        }
        Outcome::Error(RunError::Iut(error)) => {
            let said = error.to_string();
            record_iut_error(&said);
            said
        }
        Outcome::Error(error) => error.to_string(),
        Outcome::Pass => "the lockstep ended".into(),
    }
}

/// Sets the target for scenarios run on this thread.
pub fn set_target(target: Target) {
    TARGET.with(|t| *t.borrow_mut() = Some(target));
}

fn target() -> Target {
    TARGET
        .with(|t| t.borrow().clone())
        .unwrap_or_else(|| Target::new(IutKind::Model, "everything", Capabilities::everything()))
}

/// One cycle: 1 ms.
pub const CYCLE: Nanos = 1_000_000;

/// The world's bus: an idle, fast bus (100 Mbit/s, about 1 µs a classic
/// frame), so what a step sends between two cycles has ended before the next
/// one, in the order the step sent it, as the manual's sentences mean it.
const FAST_BUS: BitRates = BitRates {
    nominal: 100_000_000,
    data: 100_000_000,
};

#[derive(cucumber::World)]
#[world(init = Self::new)]
pub struct CanWorld {
    pub target: Target,
    pub config: InterfaceConfig,
    pub exchange_mode: ExchangeMode,
    /// The scenario once started: the played PLC, model and IUT, and the bus.
    run: Option<Lockstep<SimBus>>,
    /// The IUT accepted a configuration the model refuses (one the profile
    /// does not allow): there is nothing to run it against.
    accepted_alone: bool,
    pub refused: Option<String>,
    /// The input image the IUT returned last.
    pub inputs: Vec<u8>,
    /// When the coming cycle starts.
    pub now: Nanos,
    pub cycle: u64,
    pub bus_blocked: bool,
    /// Frames the IUT put on the bus, in order, and when each started.
    pub on_bus: Vec<Frame>,
    pub bus_times: Vec<Nanos>,
    /// Frames other nodes sent, with the end of their reception.
    pub sent_by_nodes: Vec<(Frame, Nanos)>,
    /// Frames other nodes sent that have not ended yet, in order.
    awaited: VecDeque<Frame>,
    /// When the next frame of another node is ready: once the one before has
    /// ended (one node's queue), so the frames keep the order the steps sent
    /// them in.
    next_ready: Nanos,
    /// Messages the PLC read, in order.
    pub received: Vec<MessageRepr>,
    pub tx_counter_override: Option<u16>,
    pub declared_lengths: Vec<(u16, u8)>,
    pub next_tn: u16,
    pub status: Option<ControllerStatus>,
    /// Cycles from the PLC's TxCounter increment to its confirmation, as the PLC saw it.
    pub confirmation_delay: Option<u64>,
    /// A CANopen bus coupler on the bus (the quick start).
    pub coupler: Option<BusCoupler>,
    /// When the coupler stopped, for loss detection times.
    pub coupler_failed_at: Option<Nanos>,
    /// Every message the PLC read, with the cycle's time, for CANopen timing.
    pub received_at: Vec<(Nanos, Frame)>,
}

/// How many frames a failing step shows of the bus and of what the PLC
/// received: a babbling IUT must not bury the cause under its frames.
const SHOWN_FRAMES: usize = 8;

/// The count of `frames` and the last [`SHOWN_FRAMES`] of them.
fn last(frames: &[Frame]) -> String {
    let shown = &frames[frames.len().saturating_sub(SHOWN_FRAMES)..];
    let list: Vec<String> = shown.iter().map(Frame::to_string).collect();
    match frames.len() - shown.len() {
        0 => format!("[{}]", list.join(", ")),
        more => format!(
            "{} frames, the last: [… {more} more, {}]",
            frames.len(),
            list.join(", ")
        ),
    }
}

impl std::fmt::Debug for CanWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "CanWorld {{ iut: {}, profile: {}, {:?} {:?} with {} slots, cycle: {}, input header: {:02X?}, on the bus: {}, the PLC received: {} }}\n      last cycles:\n        {}",
            self.target.iut.name(),
            self.target.profile,
            self.config.format,
            self.config.queue,
            self.config.tx_slots,
            self.cycle,
            &self.inputs[..self.inputs.len().min(8)],
            last(&self.on_bus),
            last(&self.received.iter().map(|m| m.frame).collect::<Vec<_>>()),
            self.run
                .as_ref()
                .map(|run| run.pair.history.context().join("\n        "))
                .unwrap_or_default()
        )
    }
}

impl CanWorld {
    fn new() -> Self {
        let target = target();
        CanWorld {
            target,
            config: InterfaceConfig::new(FrameFormat::Base11, 4),
            exchange_mode: ExchangeMode::SeparateInputUpdate,
            run: None,
            accepted_alone: false,
            refused: None,
            inputs: Vec::new(),
            // The first cycle starts one cycle in, so frames can end before it.
            now: CYCLE,
            cycle: 0,
            bus_blocked: false,
            on_bus: Vec::new(),
            bus_times: Vec::new(),
            sent_by_nodes: Vec::new(),
            awaited: VecDeque::new(),
            next_ready: 0,
            received: Vec::new(),
            tx_counter_override: None,
            declared_lengths: Vec::new(),
            next_tn: 1,
            status: None,
            confirmation_delay: None,
            coupler: None,
            coupler_failed_at: None,
            received_at: Vec::new(),
        }
    }

    /// The scenario the lockstep runs: the world's interface and exchange;
    /// its steps come one at a time. It covers nothing by itself: a
    /// difference names the requirements of its field, and the Gherkin
    /// scenario's tags among them are blamed.
    fn scenario(&self) -> Scenario {
        Scenario {
            name: "gherkin".into(),
            covers: Vec::new(),
            interface: self.config.clone(),
            exchange: self.exchange_mode,
            bit_rates: FAST_BUS,
            cycle_time: CYCLE,
            check_confirmation_delay: false,
            declared_lengths: self.declared_lengths.clone(),
            time_stamp_tolerance: 0,
            trace: None,
            bus: BusChoice::Sim,
            judgement: Judgement::Exact,
            declared: self.target.declared,
            steps: Steps::Scripted(Vec::new()),
        }
    }

    /// Builds the IUT (and the model beside it) the first time a scenario needs it.
    pub fn start(&mut self) -> Result<(), String> {
        if self.run.is_some() || self.accepted_alone {
            return Ok(());
        }
        if let Some(reason) = &self.refused {
            return Err(reason.clone());
        }
        let mut bus = SimBus::new(FAST_BUS);
        if let Some(coupler) = &self.coupler {
            bus.answer_with(Box::new(coupler.clone()));
        }
        let (kind, caps) = (&self.target.iut, &self.target.caps);
        let refusal = match Lockstep::start(kind, caps, &self.scenario(), Box::new(bus)) {
            Ok(mut run) => {
                run.pair.ended = Some(Vec::new());
                self.inputs = vec![0; run.pair.layout.input_size()];
                self.run = Some(run);
                return Ok(());
            }
            // A configuration the profile does not allow: what counts is
            // whether the IUT refuses it too.
            Err(RunError::Configuration(Refusal::Model(_))) => match kind.build(caps, &self.config)
            {
                Ok(_) => {
                    self.accepted_alone = true;
                    return Ok(());
                }
                Err(BuildError::Refused(reason)) => reason,
                Err(BuildError::Failed(broke)) => {
                    let said = broke.to_string();
                    record_iut_error(&said);
                    return Err(said);
                }
            },
            // The model accepts it, so the profile offers it: refusing it
            // is the scenario's failure, and what it needed is not run.
            Err(RunError::Configuration(Refusal::Iut(reason))) => {
                let interface = self.config.describe();
                REFUSED.with(|r| *r.borrow_mut() = Some((interface, reason.clone())));
                reason
            }
            Err(RunError::Iut(broke)) => {
                let said = broke.to_string();
                record_iut_error(&said);
                return Err(said);
            }
            Err(error) => return Err(error.to_string()),
        };
        let reason = format!("the IUT refuses the configuration: {refusal}");
        self.refused = Some(reason.clone());
        Err(reason)
    }

    /// The running lockstep, or why there is none.
    fn lockstep(&mut self) -> Result<&mut Lockstep<SimBus>, String> {
        self.start()?;
        self.run.as_mut().ok_or_else(|| {
            "the IUT accepted a configuration the profile does not allow: \
             the model refuses it, so there is nothing to run it against"
                .to_string()
        })
    }

    pub fn layout(&self) -> ImageLayout {
        self.run.as_ref().expect("started").pair.layout
    }

    pub fn input_image(&self) -> InputImage<&[u8]> {
        InputImage::new_checked(&self.inputs[..], self.layout())
            .expect("the IUT's input image has the layout's size")
    }

    /// One task cycle of the lockstep: the PLC's task (unless busy), the
    /// model's and the IUT's cycle, compared; then the bus up to the half
    /// cycle, where the IUT's frames of the cycle have gone out.
    pub fn cycle(&mut self, plc_busy: bool) -> Result<(), String> {
        let (k, blocked) = (self.cycle + 1, self.bus_blocked);
        let step = Step {
            plc_busy,
            set_tx_counter: match plc_busy {
                true => None,
                false => self.tx_counter_override.take(),
            },
            status: self.status.take(),
            ..Step::default()
        };
        let declared_lengths = self.declared_lengths.clone();
        let run = self.lockstep()?;
        run.rules.declared_lengths = declared_lengths;
        run.bus.hold_own(blocked);
        let task = run.cycle(k, step).map_err(ended)?;
        let read = run.plc.take_received();
        self.inputs = task.inputs;
        if let Some(delay) = task.report.confirmed_after {
            self.confirmation_delay = Some(delay);
        }
        self.received_at
            .extend(read.iter().map(|m| (self.now, m.frame)));
        self.received.extend(read);
        self.bus_until(self.now + CYCLE / 2)?;
        if let Some(coupler) = &self.coupler {
            let frames = coupler.poll(self.now + CYCLE / 2);
            self.run
                .as_mut()
                .expect("started")
                .bus
                .schedule_all(self.now + CYCLE / 2, frames);
        }
        self.now += CYCLE;
        self.cycle += 1;
        Ok(())
    }

    /// Runs the bus to `until` and reads what ended on it.
    fn bus_until(&mut self, until: Nanos) -> Result<(), String> {
        let run = self.run.as_mut().expect("started");
        let result = run.run_bus(until).map_err(ended);
        let ended = run
            .pair
            .ended
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default();
        for (frame, own, end) in ended {
            if own {
                self.on_bus.push(frame);
                self.bus_times.push(end - run.bus.duration(&frame));
            } else if self.awaited.front() == Some(&frame) {
                self.awaited.pop_front();
                self.sent_by_nodes.push((frame, end));
            }
        }
        result
    }

    /// The bus, blocked until now, takes frames again before the coming cycle.
    pub fn release_bus(&mut self) -> Result<(), String> {
        self.bus_blocked = false;
        self.lockstep()?.bus.hold_own(false);
        self.bus_until(self.now - CYCLE / 4)
    }

    /// Puts a CANopen coupler on the bus, answering what the IUT sends.
    pub fn put_coupler(&mut self, coupler: BusCoupler) {
        if let Some(run) = self.run.as_mut() {
            run.bus.answer_with(Box::new(coupler.clone()));
        }
        self.coupler = Some(coupler);
    }

    /// The coupler stops: no more answers, heartbeats or events.
    pub fn coupler_fails(&mut self) {
        if let Some(coupler) = &self.coupler {
            coupler.fail();
        }
        self.coupler_failed_at = Some(self.now);
    }

    /// The coupler's own frames (an input changed) go on the bus before the coming cycle.
    pub fn coupler_sends(&mut self, frames: Vec<Frame>) -> Result<(), String> {
        let at = self.before_cycle();
        self.lockstep()?.bus.schedule_all(at, frames);
        Ok(())
    }

    /// When a frame sent before the coming cycle starts: in the half cycle
    /// before it, where the bus has run to.
    fn before_cycle(&self) -> Nanos {
        self.now - CYCLE / 2
    }

    /// Another node sends `frame` before the coming cycle.
    pub fn node_sends(&mut self, frame: Frame) -> Result<(), String> {
        let at = self.before_cycle().max(self.next_ready);
        let bus = &mut self.lockstep()?.bus;
        let ends = at + bus.duration(&frame);
        bus.schedule(at, frame);
        self.next_ready = ends;
        self.awaited.push_back(frame);
        Ok(())
    }

    /// The output delay after SYNC1 the IUT is judged by (R10), once known.
    pub fn sync1_output_delay(&self) -> Option<Nanos> {
        self.run.as_ref()?.pair.sync1_output_delay()
    }

    /// How many frames other nodes have sent, ended or still on their way.
    pub fn frames_from_nodes(&self) -> usize {
        self.sent_by_nodes.len() + self.awaited.len()
    }

    /// One frame from another node in each of the next `cycles` cycles, the PLC reading all.
    pub fn one_frame_per_cycle(&mut self, cycles: u32) -> Result<(), String> {
        for k in 0..cycles {
            self.node_sends(
                Frame::classic(
                    canif_model::frame::CanId::Standard((k % 0x7FF) as u16),
                    &[k as u8],
                )
                .expect("1 byte"),
            )?;
            self.cycle(false)?;
            self.sent_by_nodes.clear();
            self.received.clear();
        }
        Ok(())
    }

    pub fn plc_sends(&mut self, frame: Frame) -> Result<(), String> {
        let transaction_number = self.next_tn;
        self.next_tn = self.next_tn.wrapping_add(1);
        self.lockstep()?
            .plc
            .send(MessageRepr {
                transaction_number,
                frame,
                time_stamp: 0,
            })
            .map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use canif_model::frame::{CanId, Frame};

    use super::{last, SHOWN_FRAMES};

    #[test]
    fn a_failing_step_shows_the_last_frames_and_how_many_there_were() {
        let frames: Vec<Frame> = (0..100u16)
            .map(|id| Frame::classic(CanId::Standard(id), &[]).unwrap())
            .collect();
        let shown = last(&frames);
        assert!(
            shown.starts_with("100 frames, the last: [… 92 more"),
            "{shown}"
        );
        assert_eq!(shown.matches("#").count(), SHOWN_FRAMES, "{shown}");
        assert_eq!(last(&frames[..2]).matches('#').count(), 2);
    }
}
