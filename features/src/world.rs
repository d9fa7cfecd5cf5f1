//! The world a scenario runs in: a PLC (the reference client of 001 §6), an
//! implementation under test built through the harness, and the bus around it.

use canif_harness::device::played_plc::{PlcSide, TaskStimulus};
use canif_harness::device::protocol_order::Ordered;
use canif_harness::device::{Iut, IutKind};
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig};
use canif_model::exchange::ExchangeMode;
use canif_model::frame::Frame;
use canif_model::image::{ImageLayout, InputImage, MessageRepr, OutputImage};
use canif_model::info_data::ControllerStatus;
use canif_model::Nanos;
use canif_spec::ReqId;
use std::cell::RefCell;

/// Who the scenario runs against; set by the runner before each run.
#[derive(Debug, Clone)]
pub struct Target {
    pub iut: IutKind,
    pub profile: String,
    pub caps: Capabilities,
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

/// What the IUT answered; when it broke, that is recorded as the scenario's
/// error (not a failure) and the step ends.
fn iut_said<T>(result: Result<T, canif_harness::IutError>) -> Result<T, String> {
    result.map_err(|e| {
        let said = e.to_string();
        record_iut_error(&said);
        said
    })
}

/// How many frames (or due times) one cycle may ask of the IUT's controller:
/// far more than a 1 ms cycle carries at 1 Mbit/s (about 20), so only a
/// babbling controller or a time that never advances reaches it.
const MOST_POLLS_PER_CYCLE: usize = 10_000;

/// Sets the target for scenarios run on this thread.
pub fn set_target(target: Target) {
    TARGET.with(|t| *t.borrow_mut() = Some(target));
}

fn target() -> Target {
    TARGET
        .with(|t| t.borrow().clone())
        .unwrap_or_else(|| Target {
            iut: IutKind::Model,
            profile: "everything".into(),
            caps: Capabilities::everything(),
        })
}

/// One cycle: 1 ms.
pub const CYCLE: Nanos = 1_000_000;

#[derive(cucumber::World)]
#[world(init = Self::new)]
pub struct CanWorld {
    pub target: Target,
    pub config: InterfaceConfig,
    pub exchange_mode: ExchangeMode,
    pub iut: Option<Box<dyn Iut>>,
    pub refused: Option<String>,
    pub plc: Option<PlcSide>,
    /// The input image the IUT returned last.
    pub inputs: Vec<u8>,
    pub now: Nanos,
    /// The latest time any request to the IUT carried: the next one may not be
    /// earlier (docs/adapter-protocol.md: times are non-decreasing).
    pub clock: Nanos,
    pub cycle: u64,
    pub bus_blocked: bool,
    /// The frame the controller took but could not finish while the bus was blocked.
    pub in_controller: Option<Frame>,
    /// Frames the IUT put on the bus, in order, and when each started.
    pub on_bus: Vec<Frame>,
    pub bus_times: Vec<Nanos>,
    /// Frames other nodes sent, with the end of their reception.
    pub sent_by_nodes: Vec<(Frame, Nanos)>,
    /// Messages the PLC read, in order.
    pub received: Vec<MessageRepr>,
    pub tx_counter_override: Option<u16>,
    pub declared_lengths: Vec<(u16, u8)>,
    pub next_tn: u16,
    pub status: Option<ControllerStatus>,
    /// Cycles from the PLC's TxCounter increment to its confirmation, as the PLC saw it.
    pub confirmation_delay: Option<u64>,
    /// The last cycles, shown when a step fails (bounded).
    pub trace: canif_harness::run::Ring<String>,
    /// A CANopen bus coupler on the bus (the quick start), and whether it still runs.
    pub coupler: Option<canif_model::canopen::coupler::Coupler>,
    pub coupler_alive: bool,
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
            self.trace.iter().cloned().collect::<Vec<_>>().join("\n        ")
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
            iut: None,
            refused: None,
            plc: None,
            inputs: Vec::new(),
            // The first cycle starts one cycle in, so frames can end before it.
            now: CYCLE,
            clock: 0,
            cycle: 0,
            bus_blocked: false,
            in_controller: None,
            on_bus: Vec::new(),
            bus_times: Vec::new(),
            sent_by_nodes: Vec::new(),
            received: Vec::new(),
            tx_counter_override: None,
            declared_lengths: Vec::new(),
            next_tn: 1,
            status: None,
            confirmation_delay: None,
            trace: canif_harness::run::Ring::context(),
            coupler: None,
            coupler_alive: true,
            coupler_failed_at: None,
            received_at: Vec::new(),
        }
    }

    /// Builds the IUT the first time a scenario needs it.
    pub fn start(&mut self) -> Result<(), String> {
        if self.iut.is_some() {
            return Ok(());
        }
        if let Some(reason) = &self.refused {
            return Err(reason.clone());
        }
        match self.target.iut.build(&self.target.caps, &self.config) {
            Ok(iut) => {
                let iut: Box<dyn Iut> = Box::new(Ordered::new(iut));
                let layout = ImageLayout::new(&self.config, self.target.caps.info_data);
                self.inputs = vec![0; layout.input_size()];
                self.plc = Some(PlcSide::new(layout, self.exchange_mode));
                self.iut = Some(iut);
                Ok(())
            }
            Err(error) => {
                match &error {
                    canif_harness::device::BuildError::Failed(broke) => {
                        record_iut_error(&broke.to_string())
                    }
                    canif_harness::device::BuildError::Refused(reason)
                        if self.config.validate(&self.target.caps).is_ok() =>
                    {
                        let interface = canif_harness::device::cases::describe(&self.config);
                        REFUSED.with(|r| *r.borrow_mut() = Some((interface, reason.clone())));
                    }
                    canif_harness::device::BuildError::Refused(_) => {}
                }
                let reason = error.to_string();
                self.refused = Some(reason.clone());
                Err(reason)
            }
        }
    }

    pub fn layout(&self) -> ImageLayout {
        self.plc.as_ref().expect("started").layout()
    }

    pub fn input_image(&self) -> InputImage<&[u8]> {
        InputImage::new_checked(&self.inputs[..], self.layout())
            .expect("the IUT's input image has the layout's size")
    }

    /// One task cycle: the PLC's task (unless busy), the IUT's cycle, then the bus.
    pub fn cycle(&mut self, plc_busy: bool) -> Result<(), String> {
        self.start()?;
        let layout = self.layout();
        let plc = self.plc.as_mut().expect("started");
        if !plc_busy {
            let stimulus = TaskStimulus {
                declared_lengths: &self.declared_lengths,
                set_tx_counter: self.tx_counter_override.take(),
                ..TaskStimulus::default()
            };
            let report = plc.task(self.cycle, stimulus).map_err(|e| e.to_string())?;
            if let Some(delay) = report.confirmed_after {
                self.confirmation_delay = Some(delay);
            }
            let read = plc.take_received();
            self.received_at
                .extend(read.iter().map(|m| (self.now, m.frame)));
            self.received.extend(read);
        }
        let outputs = plc.outputs().to_vec();
        let iut = self.iut.as_mut().expect("started");
        if let Some(status) = self.status.take() {
            iut_said(iut.controller_status(&status))?;
        }
        self.clock = self.clock.max(self.now);
        self.inputs = iut_said(iut.cycle(&outputs, self.now))?;
        plc.device_cycle_done(&self.inputs);
        let sent_before = self.on_bus.len();
        let result = self.run_bus(self.now);
        let out = OutputImage::new_checked(&outputs[..], layout)
            .map(|o| o.header())
            .unwrap_or_default();
        let inp = InputImage::new_checked(&self.inputs[..], layout)
            .map(|i| i.header())
            .unwrap_or_default();
        let sent: Vec<String> = self.on_bus[sent_before..]
            .iter()
            .map(ToString::to_string)
            .collect();
        self.trace.push(format!(
            "cycle {:>3}{}: out[tx={} rx={} n={}] in[tx={} rx={} n={}] bus: {}",
            self.cycle,
            if plc_busy { " (PLC busy)" } else { "" },
            out.tx_counter,
            out.rx_counter,
            out.no_of_tx_messages,
            inp.tx_counter,
            inp.rx_counter,
            inp.no_of_rx_messages,
            if sent.is_empty() {
                "-".to_string()
            } else {
                sent.join(" ")
            }
        ));
        result?;
        if let (Some(coupler), true) = (self.coupler.as_mut(), self.coupler_alive) {
            for frame in coupler.poll(self.now + CYCLE / 2) {
                self.receive(frame, self.now + CYCLE / 2)?;
            }
        }
        self.now += CYCLE;
        self.cycle += 1;
        Ok(())
    }

    /// The bus, blocked until now, takes frames again before the coming cycle.
    pub fn release_bus(&mut self) -> Result<(), String> {
        self.bus_blocked = false;
        self.run_bus(self.before_cycle())
    }

    /// Lets every frame the IUT offers from `from` on go on the bus (an idle,
    /// fast bus), up to the next cycle; a blocked bus takes none.
    fn run_bus(&mut self, from: Nanos) -> Result<(), String> {
        let iut = self.iut.as_mut().expect("started");
        if self.bus_blocked {
            // The controller takes the first frame but loses every arbitration.
            if self.in_controller.is_none() {
                self.clock = self.clock.max(from);
                match iut_said(iut.poll_transmit(self.clock))? {
                    Some(Ok(frame)) => self.in_controller = Some(frame),
                    Some(Err(invalid)) => {
                        return Err(format!(
                            "the IUT put an invalid frame on the bus: {invalid}"
                        ))
                    }
                    None => {}
                }
            }
            return Ok(());
        }
        if let Some(frame) = self.in_controller.take() {
            self.on_bus.push(frame);
            self.bus_times.push(from.max(self.clock));
            iut_said(iut.transmit_complete())?;
        }
        let mut at = from.max(self.clock);
        for _ in 0..MOST_POLLS_PER_CYCLE {
            if let Some(due) = iut.poll_timeout() {
                at = at.max(due);
            }
            self.clock = at;
            match iut_said(iut.poll_transmit(at))? {
                Some(Ok(frame)) => {
                    self.on_bus.push(frame);
                    self.bus_times.push(at);
                    iut_said(iut.transmit_complete())?;
                    at += 1_000;
                    if let (Some(coupler), true) = (self.coupler.as_mut(), self.coupler_alive) {
                        for answer in coupler.handle(&frame, at) {
                            at += 200;
                            iut_said(iut.receive(&answer, at))?;
                        }
                    }
                    self.clock = at;
                }
                Some(Err(invalid)) => {
                    return Err(format!(
                        "the IUT put an invalid frame on the bus: {invalid}"
                    ))
                }
                None if iut
                    .poll_timeout()
                    .is_some_and(|due| due > at && due < self.now + CYCLE) =>
                {
                    continue
                }
                None => return Ok(()),
            }
        }
        let error = format!(
            "the IUT's controller was polled {MOST_POLLS_PER_CYCLE} times in one cycle \
             (a babbling controller, or a due time that never advances: now {at} ns)"
        );
        record_iut_error(&error);
        Err(error)
    }

    /// The coupler's own frames (an input changed) go on the bus now.
    pub fn coupler_sends(&mut self, frames: Vec<Frame>) -> Result<(), String> {
        self.start()?;
        if !self.coupler_alive {
            return Ok(());
        }
        for frame in frames {
            self.receive(frame, self.before_cycle())?;
        }
        Ok(())
    }

    /// When a frame sent before the coming cycle ends: in the half cycle
    /// before it, after everything the IUT was told so far.
    fn before_cycle(&self) -> Nanos {
        self.now - CYCLE / 2
    }

    /// The IUT's controller receives `frame`, ending at `earliest` or, when
    /// the IUT has been told of a later time already, just after that.
    fn receive(&mut self, frame: Frame, earliest: Nanos) -> Result<Nanos, String> {
        let end = earliest.max(self.clock);
        self.clock = end + 200;
        iut_said(self.iut.as_mut().expect("started").receive(&frame, end))?;
        Ok(end)
    }

    /// A frame from another node ends its reception now (plus a few µs per frame).
    pub fn node_sends(&mut self, frame: Frame) -> Result<(), String> {
        self.start()?;
        let end = self.receive(frame, self.before_cycle())?;
        self.sent_by_nodes.push((frame, end));
        Ok(())
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
            self.sent_by_nodes.clear();
            self.cycle(false)?;
            self.received.clear();
        }
        Ok(())
    }

    pub fn plc_sends(&mut self, frame: Frame) -> Result<(), String> {
        self.start()?;
        let transaction_number = self.next_tn;
        self.next_tn = self.next_tn.wrapping_add(1);
        self.plc
            .as_mut()
            .expect("started")
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
