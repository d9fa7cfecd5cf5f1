//! Runs the model beside the IUT on the same stimulus and reports the first
//! difference against the requirements it breaks.

use std::collections::VecDeque;

use canif_model::client::PlcClient;
use canif_model::config::Capabilities;
use canif_model::device::Device;
use canif_model::exchange::ProcessDataExchange;
use canif_model::frame::Frame;
use canif_model::image::{field, ImageLayout, InputImage, LengthField, MessageRepr, MessageView};
use canif_model::Nanos;

use crate::bus::{arbitration_key, duration, Nodes};
use crate::iut::{InvalidFrame, Iut, IutKind};
use crate::kernel_bus::{InFlight, KernelBus, Side};
use crate::scenario::{Scenario, Step};
use canif_kernel::KernelSocket;

/// How many cycles of history a failure shows.
pub const CONTEXT_CYCLES: usize = 6;

/// One non-conformance: where, what, and which requirements it breaks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Failure {
    pub requirements: Vec<String>,
    pub scenario: String,
    pub cycle: u64,
    pub time: Nanos,
    pub what: String,
    pub expected: String,
    pub actual: String,
    /// The last cycles before the failure, oldest first.
    pub context: Vec<String>,
    /// The same cycles as data, for the timing diagram.
    pub timeline: Vec<CycleView>,
}

/// One cycle of a failure's history: the PLC's outputs, the model's (expected)
/// and the IUT's (actual) input header, and the frames that ended on the bus
/// since the cycle before.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CycleView {
    pub cycle: u64,
    pub time: Nanos,
    /// Outputs.TxCounter, RxCounter, NoOfTxMessages.
    pub outputs: [u16; 3],
    /// Inputs.TxCounter, RxCounter, NoOfRxMessages, TransactionNumber (0 without).
    pub expected: [u16; 4],
    pub actual: [u16; 4],
    /// (end of the frame, sent by the IUT, the frame in candump notation).
    pub frames: Vec<(Nanos, bool, String)>,
}

/// How one scenario ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    Pass,
    Fail(Box<Failure>),
    /// The IUT or the harness could not run the scenario (not a non-conformance).
    Error(String),
}

/// What one scenario run produced.
#[derive(Debug, Clone)]
pub struct ScenarioRun {
    pub scenario: String,
    pub covers: Vec<String>,
    pub outcome: Outcome,
    pub cycles: u64,
    pub frames_checked: u64,
}

/// Requirements a difference in each place can break; the scenario's own list
/// narrows them to what it exercises.
mod blame {
    pub const TX_COUNTER: &[&str] = &[
        "HS-TX-002",
        "HS-TX-003",
        "HS-TX-005",
        "HS-TX-007",
        "HS-TX-008",
        "FQ-003",
    ];
    /// The device filled a buffer the PLC had not released.
    pub const RX_UNRELEASED: &[&str] = &["HS-RX-001", "HS-RX-004"];
    /// RxCounter moved with nothing new.
    pub const RX_EMPTY_DELIVERY: &[&str] = &["HS-RX-006"];
    /// A frame came in that should not have (or one was held back that should not).
    pub const RX_ADMISSION: &[&str] = &[
        "RXQ-005", "FLT-001", "FLT-002", "FLT-003", "FLT-004", "FLT-005", "FLT-006", "FLT-007",
        "FLT-008", "FLT-009",
    ];
    /// Nothing delivered although there was something and the buffer was free.
    pub const RX_WITHHELD_FAST: &[&str] = &["FQ-001", "FQ-002"];
    pub const RX_WITHHELD: &[&str] = &[
        "BQ-002",
        "HS-RX-001",
        "FLT-001",
        "FLT-005",
        "FLT-006",
        "FLT-008",
    ];
    /// Both moved, to different values.
    pub const RX_COUNTING: &[&str] = &["HS-RX-005", "HS-RX-006"];
    pub const RX_SET: &[&str] = &[
        "HS-RX-001",
        "HS-RX-002",
        "HS-RX-004",
        "HS-RX-007",
        "BQ-002",
        "RXQ-003",
        "RXQ-004",
        "RXQ-005",
        "RXQ-006",
        "FQ-004",
        "FLT-001",
        "FLT-002",
        "FLT-003",
        "FLT-004",
        "FLT-005",
        "FLT-006",
        "FLT-007",
        "FLT-008",
        "FLT-009",
    ];
    pub const TRANSACTION_NUMBER: &[&str] = &["TN-002", "TN-003"];
    pub const COB_WORD: &[&str] = &["LAY-11-002", "LAY-11-003", "LAY-11-004", "LAY-GEN-003"];
    pub const COB_LOW: &[&str] = &["LAY-29-003", "LAY-GEN-003"];
    pub const COB_RTR: &[&str] = &["LAY-29-004"];
    pub const COB_FORMAT: &[&str] = &["LAY-29-005"];
    pub const LENGTH: &[&str] = &["LAY-11-002", "LAY-29-002", "FD-LEN-005", "LAY-GEN-003"];
    pub const FLAGS: &[&str] = &["FD-BIT-001", "FD-BIT-002", "FD-BIT-003"];
    pub const TIME_STAMP: &[&str] = &["TS-001", "TS-003", "TS-004"];
    pub const TX_MISSING: &[&str] = &[
        "HS-TX-002",
        "HS-TX-004",
        "HS-TX-006",
        "HS-TX-007",
        "HS-TX-009",
        "PDX-003",
        "PDX-005",
    ];
    pub const TX_EXTRA: &[&str] = &["HS-TX-006", "HS-TX-009", "HS-TX-011", "PDX-004", "PDX-005"];
    pub const TX_OTHER_FRAME: &[&str] = &["HS-TX-004", "HS-TX-006", "HS-TX-009"];
    pub const TX_REMOTE: &[&str] = &["LAY-11-003", "LAY-29-004"];
    pub const TX_FORMAT: &[&str] = &["LAY-29-005", "FD-BIT-001"];
    pub const TX_FD_FLAGS: &[&str] = &["FD-BIT-001", "FD-BIT-002", "FD-BIT-003"];
    pub const TX_LENGTH: &[&str] = &[
        "FD-LEN-003",
        "FD-LEN-004",
        "ERR-R1",
        "LAY-11-002",
        "LAY-29-002",
        "HS-TX-009",
    ];
    pub const TX_PADDING: &[&str] = &["FD-LEN-005"];
    pub const TX_DATA: &[&str] = &["HS-TX-006", "LAY-GEN-003"];
    pub const TX_INVALID: &[&str] = &["FD-LEN-003", "FD-LEN-004", "ERR-R1", "LAY-GEN-008"];
    pub const CONFIRMATION: &[&str] = &["PDX-001", "PDX-002"];

    pub fn info_data(index: usize) -> &'static [&'static str] {
        match index {
            0 => &["INFO-002"],
            1 | 2 => &["INFO-003"],
            3 => &["INFO-004"],
            4..=6 => &["INFO-005", "INFO-007"],
            11 | 15 => &["INFO-006"],
            _ => &["INFO-005"],
        }
    }
}

/// The requirements a difference breaks: those of the differing field that the
/// scenario exercises, or, when it exercises none of them, the field's own.
fn blame(scenario: &Scenario, candidates: &[&str]) -> Vec<String> {
    let narrowed: Vec<String> = candidates
        .iter()
        .filter(|id| scenario.covers.iter().any(|c| c == *id))
        .map(|id| id.to_string())
        .collect();
    if narrowed.is_empty() {
        candidates.iter().map(|id| id.to_string()).collect()
    } else {
        narrowed
    }
}

/// A difference found, before it becomes a [`Failure`].
struct Difference {
    candidates: &'static [&'static str],
    what: String,
    expected: String,
    actual: String,
}

/// Bytes as `01 02 0A`.
pub fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn describe_slot(layout: &ImageLayout, bytes: &[u8]) -> String {
    match MessageView::new_checked(bytes, layout.rx_message) {
        Ok(view) => match MessageRepr::parse(&view) {
            Ok(m) => format!("{} ts={} [{}]", m.frame, m.time_stamp, hex(bytes)),
            Err(e) => format!("invalid ({e}) [{}]", hex(bytes)),
        },
        Err(_) => hex(bytes),
    }
}

/// What the Rx handshake looked like going into the cycle (both devices agreed
/// until now, so one previous RxCounter serves both).
#[derive(Debug, Clone, Copy)]
struct RxState {
    before: u16,
    plc_released: u16,
    fast: bool,
}

/// Compares two input images field by field, ignoring what the spec calls
/// don't-care: Rx slots at and past NoOfRxMessages (HS-RX-008, FQ-005).
fn compare_inputs(
    layout: &ImageLayout,
    expected: &[u8],
    actual: &[u8],
    was_on_bus: impl Fn(&Frame) -> bool,
    time_stamp_tolerance: Nanos,
    rx: RxState,
) -> Option<Difference> {
    if expected.len() != actual.len() {
        return Some(Difference {
            candidates: &["LAY-GEN-004"],
            what: "input image size".into(),
            expected: format!("{} bytes", expected.len()),
            actual: format!("{} bytes", actual.len()),
        });
    }
    let value = |b: &[u8], at: usize| u16::from_le_bytes([b[at], b[at + 1]]);
    if expected[field::TX_COUNTER] != actual[field::TX_COUNTER] {
        return Some(Difference {
            candidates: blame::TX_COUNTER,
            what: "Inputs.TxCounter".into(),
            expected: value(expected, 0).to_string(),
            actual: value(actual, 0).to_string(),
        });
    }
    if expected[field::RX_COUNTER] != actual[field::RX_COUNTER] {
        let (expected_rx, actual_rx) = (value(expected, 2), value(actual, 2));
        let (model_moved, iut_moved) = (expected_rx != rx.before, actual_rx != rx.before);
        let released = rx.fast || rx.plc_released == rx.before;
        let candidates = match (model_moved, iut_moved) {
            (false, true) if !released => blame::RX_UNRELEASED,
            (false, true) if value(actual, 4) == 0 => blame::RX_EMPTY_DELIVERY,
            (false, true) => blame::RX_ADMISSION,
            (true, false) if rx.before == u16::MAX => blame::RX_COUNTING,
            (true, false) if rx.fast => blame::RX_WITHHELD_FAST,
            (true, false) => blame::RX_WITHHELD,
            _ => blame::RX_COUNTING,
        };
        return Some(Difference {
            candidates,
            what: "Inputs.RxCounter".into(),
            expected: format!(
                "{expected_rx} (was {}, Outputs.RxCounter {})",
                rx.before, rx.plc_released
            ),
            actual: actual_rx.to_string(),
        });
    }
    if expected[field::NO_OF_MESSAGES] != actual[field::NO_OF_MESSAGES] {
        return Some(Difference {
            candidates: blame::RX_SET,
            what: "Inputs.NoOfRxMessages".into(),
            expected: value(expected, 4).to_string(),
            actual: value(actual, 4).to_string(),
        });
    }
    if layout.transaction_number
        && expected[field::TRANSACTION_NUMBER] != actual[field::TRANSACTION_NUMBER]
    {
        let value = |b: &[u8]| u16::from_le_bytes([b[6], b[7]]);
        return Some(Difference {
            candidates: blame::TRANSACTION_NUMBER,
            what: "Inputs.TransactionNumber".into(),
            expected: value(expected).to_string(),
            actual: value(actual).to_string(),
        });
    }
    let in_use = InputImage::new_checked(expected, *layout)
        .map_or(0, |i| usize::from(i.no_of_rx_messages()));
    let message = layout.rx_message;
    for slot in 0..in_use.min(layout.rx_slots) {
        let range = layout.rx_slot(slot);
        let (e, a) = (&expected[range.clone()], &actual[range]);
        if e == a {
            continue;
        }
        let data_len = MessageView::new_checked(e, message).map_or(0, |v| {
            MessageRepr::parse(&v).map_or(0, |m| m.frame.data().len())
        });
        let length_field = match &message.length {
            LengthField::InCobIdWord => None,
            LengthField::Word(f) | LengthField::Byte(f) => Some(f.clone()),
        };
        let cob = message.cob_id.clone();
        let data = message.data.start..message.data.start + data_len;
        let frame_of = |bytes: &[u8]| {
            MessageView::new_checked(bytes, message)
                .ok()
                .and_then(|v| MessageRepr::parse(&v).ok())
                .map(|m| m.frame)
        };
        let different_frame = match (frame_of(e), frame_of(a)) {
            (Some(expected_frame), Some(actual_frame)) => {
                expected_frame != actual_frame && was_on_bus(&actual_frame)
            }
            _ => false,
        };
        let candidates: &'static [&'static str] = if different_frame {
            blame::RX_SET
        } else if e[cob.clone()] != a[cob.clone()] {
            if cob.len() == 2 {
                blame::COB_WORD
            } else {
                let word = |b: &[u8]| {
                    u32::from_le_bytes([
                        b[cob.start],
                        b[cob.start + 1],
                        b[cob.start + 2],
                        b[cob.start + 3],
                    ])
                };
                let diff = word(e) ^ word(a);
                if diff & 0x8000_0000 != 0 {
                    blame::COB_FORMAT
                } else if diff & 0x4000_0000 != 0 {
                    blame::COB_RTR
                } else {
                    blame::COB_LOW
                }
            }
        } else if length_field
            .as_ref()
            .is_some_and(|f| e[f.clone()] != a[f.clone()])
        {
            blame::LENGTH
        } else if message
            .flags
            .as_ref()
            .is_some_and(|f| e[f.clone()] != a[f.clone()])
        {
            blame::FLAGS
        } else if e[data.clone()] != a[data.clone()] {
            blame::RX_SET
        } else if message.time_stamp.as_ref().is_some_and(|f| {
            let stamp = |b: &[u8]| u64::from_le_bytes(b[f.clone()].try_into().unwrap_or([0; 8]));
            stamp(e).abs_diff(stamp(a)) > time_stamp_tolerance
        }) {
            blame::TIME_STAMP
        } else {
            continue; // only don't-care bytes (data past the length) differ
        };
        return Some(Difference {
            candidates,
            what: format!("Inputs.RxMessage[{slot}]"),
            expected: describe_slot(layout, e),
            actual: describe_slot(layout, a),
        });
    }
    if layout.info_data {
        for index in 0..field::INFO_DATA_WORDS {
            let at = layout.info_data_start() + 4 * index;
            if expected[at..at + 4] != actual[at..at + 4] {
                let word = |b: &[u8]| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
                return Some(Difference {
                    candidates: blame::info_data(index),
                    what: format!("InfoData[{index}]"),
                    expected: format!("0x{:08X}", word(expected)),
                    actual: format!("0x{:08X}", word(actual)),
                });
            }
        }
    }
    None
}

fn compare_frames(expected: &Frame, actual: &Frame) -> &'static [&'static str] {
    if expected.id != actual.id {
        if expected.id.raw() == actual.id.raw() {
            return blame::TX_FORMAT;
        }
        return blame::TX_OTHER_FRAME;
    }
    if expected.is_remote() != actual.is_remote() {
        return blame::TX_REMOTE;
    }
    if expected.is_fd() != actual.is_fd() {
        return blame::TX_FORMAT;
    }
    if expected.kind != actual.kind {
        return blame::TX_FD_FLAGS;
    }
    if expected.len() != actual.len() {
        return blame::TX_LENGTH;
    }
    if expected.is_fd() {
        return blame::TX_PADDING;
    }
    blame::TX_DATA
}

/// `frame` came as the next of `queue` (frames on their way, in order): it
/// leaves the queue. `false` when something else was expected.
fn arrived(queue: &mut VecDeque<InFlight>, frame: Frame) -> bool {
    let next = queue.front().is_some_and(|f| f.frame == frame);
    if next {
        queue.pop_front();
    }
    next
}

/// Everything that runs in lockstep for one scenario.
struct Lockstep<'a> {
    scenario: &'a Scenario,
    iut: Box<dyn Iut>,
    model: Device,
    layout: ImageLayout,
    nodes: Nodes,
    /// The frame on the bus: its end, whether the IUT sent it.
    on_bus: Option<(Nanos, Frame, bool)>,
    iut_pending: Option<Frame>,
    now: Nanos,
    cycle: u64,
    frames: u64,
    /// The last cycles' image headers and the frames around them (bounded),
    /// formatted only when a failure needs them.
    history: VecDeque<CycleRecord>,
    bus_log: VecDeque<(u64, bool, Frame, Nanos)>,
    /// Frames other nodes sent lately: a slot holding one of them carries a real
    /// frame (the wrong one), anything else is a frame the IUT encoded wrongly.
    recent_rx: VecDeque<Frame>,
    trace: Option<crate::trace::TraceWriter>,
    /// Set when the bus is a SocketCAN interface (real time) instead of the simulation.
    kernel: Option<KernelBus>,
}

/// What one cycle looked like, kept raw until a failure shows it.
#[derive(Debug, Clone, Copy)]
struct CycleRecord {
    cycle: u64,
    now: Nanos,
    outputs: [u16; 3],
    inputs: [u16; 3],
    transaction_number: Option<u16>,
    expected: [u16; 4],
}

/// How many frames of bus history a failure can show.
const BUS_LOG: usize = 256;

/// How many received frames the oracle remembers (bounded memory).
const RECENT_RX: usize = 4_096;

impl Lockstep<'_> {
    fn fail(&self, difference: Difference) -> Outcome {
        Outcome::Fail(Box::new(Failure {
            requirements: blame(self.scenario, difference.candidates),
            scenario: self.scenario.name.clone(),
            cycle: self.cycle,
            time: self.now,
            what: difference.what,
            expected: difference.expected,
            actual: difference.actual,
            context: self.context(),
            timeline: self.timeline(),
        }))
    }

    /// Asks both devices for their next frame when the controller is free.
    fn poll(&mut self) -> Result<(), Outcome> {
        if self.iut_pending.is_some() {
            return Ok(());
        }
        let expected = self.model.poll_transmit(self.now);
        let actual = self.iut.poll_transmit(self.now);
        match self.transmit_difference(expected, actual) {
            Ok(frame) => {
                self.iut_pending = frame;
                Ok(())
            }
            Err(difference) => Err(self.fail(difference)),
        }
    }

    /// The frame both devices agree to send (or none), or how they differ.
    fn transmit_difference(
        &self,
        expected: Option<Frame>,
        actual: Option<Result<Frame, InvalidFrame>>,
    ) -> Result<Option<Frame>, Difference> {
        Err(match (expected, actual) {
            (None, None) => return Ok(None),
            (Some(e), Some(Ok(a))) if e == a => return Ok(Some(a)),
            (Some(e), Some(Ok(a))) => {
                // A frame the model still holds is a real message sent out of turn.
                let queued_later = self.model.send_queue().any(|f| *f == a);
                Difference {
                    candidates: if queued_later {
                        blame::TX_OTHER_FRAME
                    } else {
                        compare_frames(&e, &a)
                    },
                    what: "frame handed to the controller".into(),
                    expected: e.to_string(),
                    actual: a.to_string(),
                }
            }
            (e, Some(Err(invalid))) => Difference {
                candidates: blame::TX_INVALID,
                what: "frame handed to the controller".into(),
                expected: e.map_or("no frame".into(), |f| f.to_string()),
                actual: format!("invalid frame: {}", invalid.0),
            },
            (Some(e), None) => Difference {
                candidates: blame::TX_MISSING,
                what: "frame handed to the controller".into(),
                expected: e.to_string(),
                actual: "no frame".into(),
            },
            (None, Some(Ok(a))) => Difference {
                candidates: blame::TX_EXTRA,
                what: "frame handed to the controller".into(),
                expected: "no frame".into(),
                actual: a.to_string(),
            },
        })
    }

    /// Runs the bus up to `until`: completes frames, starts the next winner.
    fn run_bus(&mut self, until: Nanos) -> Result<(), Outcome> {
        if self.kernel.is_some() {
            return self.run_kernel(until);
        }
        loop {
            self.poll()?;
            if self.on_bus.is_none() {
                let node = self.nodes.best_key(self.now);
                let iut = self.iut_pending.as_ref().map(arbitration_key);
                let start = match (node, iut) {
                    (Some(n), Some(k)) if n < k => {
                        self.nodes.take_best(self.now).map(|f| (f, false))
                    }
                    (Some(_), None) => self.nodes.take_best(self.now).map(|f| (f, false)),
                    (_, Some(_)) => self.iut_pending.take().map(|f| (f, true)),
                    (None, None) => None,
                };
                if let Some((frame, from_iut)) = start {
                    let end = self.now + duration(&frame, self.scenario.bit_rates);
                    self.on_bus = Some((end, frame, from_iut));
                }
            }
            let next = [
                self.on_bus.as_ref().map(|(end, _, _)| *end),
                self.nodes.next_ready_after(self.now),
                self.iut.poll_timeout().filter(|t| *t > self.now),
            ]
            .into_iter()
            .flatten()
            .min();
            match next {
                Some(t) if t <= until => {
                    self.now = t;
                    if let Some((end, frame, from_iut)) = self.on_bus.take() {
                        if end == t {
                            self.complete(frame, from_iut, end);
                        } else {
                            self.on_bus = Some((end, frame, from_iut));
                        }
                    }
                }
                _ => {
                    self.now = until;
                    return Ok(());
                }
            }
        }
    }

    fn kernel(&mut self) -> &mut KernelBus {
        self.kernel
            .as_mut()
            .expect("only called on a SocketCAN bus")
    }

    /// Runs the SocketCAN bus in real time up to scenario time `until`: writes
    /// the other nodes' frames when due, hands the IUT what its socket gets,
    /// sends what it sends, and returns once everything written has arrived.
    fn run_kernel(&mut self, until: Nanos) -> Result<(), Outcome> {
        let owned = matches!(self.kernel().side, Side::Owned);
        loop {
            self.now = self.now.max(self.kernel().now());
            if !owned && self.kernel().iut_in_flight.is_none() {
                self.poll()?;
                if let Some(frame) = self.iut_pending.take() {
                    self.kernel_send_iut(frame)?;
                }
            }
            self.kernel_send_due()?;
            self.kernel_read(owned)?;
            if owned {
                self.kernel_model_waits()?;
            }
            let bus = self.kernel();
            if let Some(why) = bus.overdue() {
                return Err(Outcome::Error(why));
            }
            let due_now = bus.waiting.front().is_some_and(|(t, _)| *t <= until);
            if bus.reached(until) && bus.settled() && !due_now {
                self.now = self.now.max(until);
                return Ok(());
            }
            let wait = until.saturating_sub(bus.now()).clamp(50_000, 1_000_000);
            let result = match &bus.side {
                Side::Attached(iut) => {
                    KernelSocket::wait(&[iut, &bus.tester], std::time::Duration::from_nanos(wait))
                }
                Side::Owned => {
                    KernelSocket::wait(&[&bus.tester], std::time::Duration::from_nanos(wait))
                }
            };
            if let Err(error) = result {
                return Err(Outcome::Error(format!("poll on the CAN sockets: {error}")));
            }
        }
    }

    fn kernel_error(&mut self, interface: &str, error: std::io::Error) -> Outcome {
        Outcome::Error(format!(
            "{interface}: {error} (while {})",
            if self.kernel().settled() {
                "idle"
            } else {
                "frames were on their way"
            }
        ))
    }

    /// Writes the IUT's frame on its socket; a full queue (ENOBUFS) keeps it
    /// pending for the next turn, as for the other nodes.
    fn kernel_send_iut(&mut self, frame: Frame) -> Result<(), Outcome> {
        let bus = self.kernel();
        let Side::Attached(socket) = &bus.side else {
            return Ok(());
        };
        match socket.send(&frame) {
            Ok(()) => {}
            Err(error) if error.raw_os_error() == Some(canif_kernel::ENOBUFS) => {
                let name = socket.interface.clone();
                bus.blocked(name);
                self.iut_pending = Some(frame);
                return Ok(());
            }
            Err(error) => {
                let name = socket.interface.clone();
                return Err(self.kernel_error(&name, error));
            }
        }
        bus.blocked_since = None;
        let since = std::time::Instant::now();
        bus.iut_in_flight = Some(InFlight { frame, since });
        // On one interface the other nodes may see it before the IUT's echo.
        bus.crossing.push_back(InFlight { frame, since });
        Ok(())
    }

    /// Writes the other nodes' frames that are due.
    fn kernel_send_due(&mut self) -> Result<(), Outcome> {
        loop {
            let bus = self.kernel();
            let now = bus.now();
            let Some((at, frame)) = bus.waiting.front().cloned() else {
                return Ok(());
            };
            if at > now || bus.tester_in_flight.len() >= bus.window() {
                return Ok(());
            }
            match bus.tester.send(&frame) {
                Ok(()) => {
                    bus.waiting.pop_front();
                    bus.blocked_since = None;
                    bus.tester_in_flight.push_back(InFlight {
                        frame,
                        since: std::time::Instant::now(),
                    });
                }
                Err(error) if error.raw_os_error() == Some(canif_kernel::ENOBUFS) => {
                    let name = bus.tester.interface.clone();
                    bus.blocked(name);
                    return Ok(()); // the queue drains; overdue() ends a stuck run
                }
                Err(error) => {
                    let name = bus.tester.interface.clone();
                    return Err(self.kernel_error(&name, error));
                }
            }
        }
    }

    /// Reads both sockets dry and turns what arrived into bus events.
    fn kernel_read(&mut self, owned: bool) -> Result<(), Outcome> {
        loop {
            let bus = self.kernel();
            let epoch = bus.epoch;
            let from_iut = match &bus.side {
                Side::Attached(socket) => socket
                    .recv()
                    .map_err(|e| (socket.interface.clone(), e))
                    .map(|r| r.map(|r| (true, r))),
                Side::Owned => Ok(None),
            };
            let received = match from_iut {
                Ok(Some(event)) => Some(event),
                Ok(None) => match bus.tester.recv() {
                    Ok(r) => r.map(|r| (false, r)),
                    Err(e) => {
                        let name = bus.tester.interface.clone();
                        return Err(self.kernel_error(&name, e));
                    }
                },
                Err((name, e)) => return Err(self.kernel_error(&name, e)),
            };
            let Some((on_iut_socket, received)) = received else {
                return Ok(());
            };
            let (frame, at, own) = match received {
                canif_kernel::Received::Frame { frame, at, own } => {
                    (frame, at.saturating_sub(epoch), own)
                }
                canif_kernel::Received::Error { class, data, .. } => {
                    self.kernel().last_error = Some(format!(
                        "the driver's last error frame: class 0x{class:X}, data {}",
                        hex(&data)
                    ));
                    if class & canif_kernel::CAN_ERR_BUSOFF != 0 {
                        let bus = self.kernel();
                        let name = if on_iut_socket {
                            bus.options.spec.iut.clone()
                        } else {
                            bus.options.spec.tester.clone()
                        };
                        return Err(Outcome::Error(format!(
                            "{name}: the controller went bus-off (error frame class 0x{class:X}, data {})",
                            hex(&data)
                        )));
                    }
                    continue; // other error frames: the driver's retries go on
                }
            };
            if frame == crate::kernel_bus::marker() && !own {
                continue; // a synchronization marker a driver delivered late
            }
            self.now = self.now.max(at);
            let bus = self.kernel();
            let mismatch = |bus: &KernelBus, expected: Option<&InFlight>, side: &str| {
                Outcome::Error(
                    format!(
                        "the kernel delivered {frame} on {side}, but {}",
                        expected.map_or("nothing was on its way".to_string(), |f| format!(
                            "{} was on its way",
                            f.frame
                        ))
                    ) + &format!(
                        " ({}{})",
                        bus.options.spec.describe(),
                        bus.last_error
                            .as_ref()
                            .map_or(String::new(), |e| format!("; {e}"))
                    ),
                )
            };
            match (owned, on_iut_socket, own) {
                // Attached: the IUT's own frame is on the bus.
                (false, true, true) => {
                    if bus.iut_in_flight.as_ref().map(|f| f.frame) != Some(frame) {
                        return Err(mismatch(
                            bus,
                            bus.iut_in_flight.as_ref(),
                            "the IUT's socket (echo)",
                        ));
                    }
                    bus.iut_in_flight = None;
                    self.complete(frame, true, at);
                }
                // Attached: another node's frame reached the IUT.
                (false, true, false) => {
                    if !arrived(&mut bus.tester_in_flight, frame) {
                        return Err(mismatch(
                            bus,
                            bus.tester_in_flight.front(),
                            "the IUT's socket",
                        ));
                    }
                    self.complete(frame, false, at);
                }
                // Attached: the IUT's frame reached the other nodes.
                (false, false, _) => {
                    if !arrived(&mut bus.crossing, frame) {
                        return Err(mismatch(bus, bus.crossing.front(), "the tester's socket"));
                    }
                }
                // Owned: the harness's own frame is on the bus; the IUT has it too.
                (true, _, true) => {
                    if !arrived(&mut bus.tester_in_flight, frame) {
                        return Err(mismatch(
                            bus,
                            bus.tester_in_flight.front(),
                            "the tester's socket (echo)",
                        ));
                    }
                    self.observe(frame, false, at);
                }
                // Owned: a frame the IUT sent.
                (true, _, false) => {
                    let expected = match bus.model_next.take() {
                        Some((frame, _)) => Some(frame),
                        None => self.model.poll_transmit(at),
                    };
                    match self.transmit_difference(expected, Some(Ok(frame))) {
                        Ok(_) => self.observe(frame, true, at),
                        Err(difference) => return Err(self.fail(difference)),
                    }
                }
            }
        }
    }

    /// Owned: a frame the model sent long ago that the IUT has not sent is missing.
    fn kernel_model_waits(&mut self) -> Result<(), Outcome> {
        let now = self.now;
        if self.kernel().model_next.is_none() {
            let next = self.model.poll_transmit(now);
            self.kernel().model_next = next.map(|f| (f, now));
        }
        let bus = self.kernel();
        let patience = bus.options.timeout.as_nanos() as Nanos;
        if let Some((frame, since)) = bus.model_next {
            if now.saturating_sub(since) > patience {
                let difference = Difference {
                    candidates: blame::TX_MISSING,
                    what: format!(
                        "frame on {} within {} ms",
                        bus.options.spec.tester,
                        patience / 1_000_000
                    ),
                    expected: frame.to_string(),
                    actual: "no frame".into(),
                };
                return Err(self.fail(difference));
            }
        }
        Ok(())
    }

    fn write_trace(&mut self, at: Nanos, frame: &Frame) {
        if let Some(trace) = self.trace.as_mut() {
            if trace.frame(at, frame).is_err() {
                self.trace = None;
            }
        }
    }

    fn complete(&mut self, frame: Frame, from_iut: bool, end: Nanos) {
        if from_iut {
            self.iut.transmit_complete();
        } else {
            self.iut.receive(&frame, end);
        }
        self.observe(frame, from_iut, end);
    }

    /// A frame ended on the bus: the model, the trace and the history learn of it.
    fn observe(&mut self, frame: Frame, from_iut: bool, end: Nanos) {
        self.frames += 1;
        self.write_trace(end, &frame); // a full disk ends the trace, not the run
        if from_iut {
            self.model.handle_transmit_complete();
        } else {
            self.model.handle_received(frame, end);
            self.recent_rx.push_back(frame);
            if self.recent_rx.len() > RECENT_RX {
                self.recent_rx.pop_front();
            }
        }
        self.log(from_iut, frame, end);
    }

    fn log(&mut self, from_iut: bool, frame: Frame, end: Nanos) {
        self.bus_log.push_back((self.cycle, from_iut, frame, end));
        if self.bus_log.len() > BUS_LOG {
            self.bus_log.pop_front();
        }
    }

    fn remember(&mut self, outputs: &[u8], expected: &[u8], inputs: &[u8]) {
        let header = |b: &[u8]| [0, 2, 4].map(|at| u16::from_le_bytes([b[at], b[at + 1]]));
        let with_tn = |b: &[u8]| {
            let [tx, rx, n] = header(b);
            let tn = if self.layout.transaction_number && b.len() >= 8 {
                u16::from_le_bytes([b[6], b[7]])
            } else {
                0
            };
            [tx, rx, n, tn]
        };
        let expected = with_tn(expected);
        self.history.push_back(CycleRecord {
            expected,
            cycle: self.cycle,
            now: self.now,
            outputs: header(outputs),
            inputs: header(inputs),
            transaction_number: self
                .layout
                .transaction_number
                .then(|| u16::from_le_bytes([inputs[6], inputs[7]])),
        });
        if self.history.len() > CONTEXT_CYCLES {
            self.history.pop_front();
        }
    }

    /// The remembered cycles as data.
    fn timeline(&self) -> Vec<CycleView> {
        self.history
            .iter()
            .map(|r| {
                let [tx, rx, n] = r.inputs;
                CycleView {
                    cycle: r.cycle,
                    time: r.now,
                    outputs: r.outputs,
                    expected: r.expected,
                    actual: [tx, rx, n, r.transaction_number.unwrap_or(0)],
                    frames: self
                        .bus_log
                        .iter()
                        .filter(|(cycle, ..)| *cycle + 1 == r.cycle)
                        .map(|(_, from_iut, frame, end)| (*end, *from_iut, frame.to_string()))
                        .collect(),
                }
            })
            .collect()
    }

    /// The remembered cycles as text, each with the frames that ended on the bus
    /// since the cycle before.
    fn context(&self) -> Vec<String> {
        self.history
            .iter()
            .map(|r| {
                let [otx, orx, on] = r.outputs;
                let [itx, irx, inn] = r.inputs;
                let tn = r.transaction_number.map_or(String::new(), |tn| format!(" tn={tn}"));
                let frames: Vec<String> = self
                    .bus_log
                    .iter()
                    .filter(|(cycle, ..)| *cycle + 1 == r.cycle)
                    .map(|(_, from_iut, f, _)| format!("{} {f}", if *from_iut { "tx" } else { "rx" }))
                    .collect();
                let bus = if frames.is_empty() { String::new() } else { format!(" | bus: {}", frames.join(", ")) };
                format!("cycle {:>5} t={:>9.3} ms  out[tx={otx} rx={orx} n={on}]  in[tx={itx} rx={irx} n={inn}{tn}]{bus}", r.cycle, r.now as f64 / 1e6)
            })
            .collect()
    }
}

/// Runs one scenario against an IUT beside the model.
pub fn run_scenario(
    kind: &IutKind,
    caps: &Capabilities,
    scenario: &Scenario,
    steps: impl Iterator<Item = Step>,
) -> ScenarioRun {
    let run = |outcome, cycles, frames| ScenarioRun {
        scenario: scenario.name.clone(),
        covers: scenario.covers.clone(),
        outcome,
        cycles,
        frames_checked: frames,
    };
    let model = match Device::new(caps, scenario.interface.clone()) {
        Ok(model) => model,
        Err(e) => {
            return run(
                Outcome::Error(format!(
                    "the model refuses the scenario's configuration: {e}"
                )),
                0,
                0,
            )
        }
    };
    let kernel = match &scenario.kernel {
        None => None,
        Some(options) => match KernelBus::open(options, matches!(kind, IutKind::Exec { .. })) {
            Ok(bus) => Some(bus),
            Err(reason) => return run(Outcome::Error(reason), 0, 0),
        },
    };
    let owned_bus = kernel.as_ref().map(|bus| crate::iut::OwnedBus {
        interface: bus.options.spec.iut.clone(),
        epoch_ns: bus.epoch,
    });
    let iut = match kind.build_on(caps, &scenario.interface, owned_bus.as_ref()) {
        Ok(iut) => iut,
        Err(crate::iut::BuildError::Refused(reason)) => {
            return run(
                Outcome::Error(format!(
                    "the IUT refuses a configuration the profile allows: {reason}"
                )),
                0,
                0,
            )
        }
        Err(crate::iut::BuildError::Failed(reason)) => return run(Outcome::Error(reason), 0, 0),
    };
    let layout = model.layout();
    let mut plc = PlcClient::new(layout);
    let mut exchange = ProcessDataExchange::new(scenario.exchange, model.inputs());
    let mut state = Lockstep {
        scenario,
        iut,
        model,
        layout,
        nodes: Nodes::default(),
        on_bus: None,
        iut_pending: None,
        now: 0,
        cycle: 0,
        frames: 0,
        history: VecDeque::new(),
        bus_log: VecDeque::new(),
        recent_rx: VecDeque::new(),
        trace: scenario
            .trace
            .as_ref()
            .and_then(|(dir, name)| crate::trace::TraceWriter::create(dir, name).ok()),
        kernel,
    };
    // On a SocketCAN bus the cycle is real time, and the scenario's offsets scale with it.
    let cycle_time = scenario
        .kernel
        .as_ref()
        .map_or(scenario.cycle_time, |k| k.cycle_time);
    let scale = |offset: Nanos| offset * cycle_time / scenario.cycle_time.max(1);
    let time_stamp_tolerance = scenario
        .kernel
        .as_ref()
        .map_or(scenario.time_stamp_tolerance, |k| {
            k.time_stamp_tolerance.max(scenario.time_stamp_tolerance)
        });
    let mut outputs = plc.outputs().to_vec();
    let mut increment_at: Option<(u64, u16)> = None;
    for (k, step) in steps.enumerate() {
        let k = k as u64;
        let t = k * cycle_time;
        if let Err(outcome) = state.run_bus(t) {
            return run(outcome, k, state.frames);
        }
        let t = if state.kernel.is_some() { state.now } else { t };
        state.cycle = k;
        let mut step = step;
        if let Some(kernel) = &scenario.kernel {
            for message in &mut step.send {
                message.frame = kernel.adapt(message.frame);
            }
            for (_, frame) in &mut step.bus {
                *frame = kernel.adapt(*frame);
            }
        }
        for message in step.send {
            if plc.send(message).is_err() {
                return run(
                    Outcome::Error(format!(
                        "scenario bug: a message that does not fit {}",
                        layout.tx_message.name
                    )),
                    k,
                    state.frames,
                );
            }
        }
        if let Some(status) = step.status {
            state.iut.controller_status(&status);
            state.model.handle_controller_status(status);
        }
        if !step.plc_busy {
            let seen_tx = InputImage::new_checked(exchange.plc_inputs(), layout)
                .map_or(0, |i| i.tx_counter());
            if let Some((since, counter)) = increment_at {
                if seen_tx == counter {
                    let delay = k - since;
                    let wanted = u64::from(scenario.exchange.confirmation_cycles());
                    if scenario.check_confirmation_delay && delay != wanted {
                        let difference = Difference {
                            candidates: blame::CONFIRMATION,
                            what: "cycles until the PLC sees TxCounter confirmed".into(),
                            expected: wanted.to_string(),
                            actual: delay.to_string(),
                        };
                        return run(state.fail(difference), k, state.frames);
                    }
                    increment_at = None;
                }
            }
            match plc.task(exchange.plc_inputs()) {
                Ok(o) => outputs = o.to_vec(),
                Err(e) => {
                    return run(
                        Outcome::Error(format!("the PLC cannot read the IUT's input image: {e}")),
                        k,
                        state.frames,
                    )
                }
            }
            if !scenario.declared_lengths.is_empty() {
                declare_lengths(&layout, &scenario.declared_lengths, plc.outputs_mut());
                outputs = plc.outputs().to_vec();
            }
            if let Some(counter) = step.set_tx_counter {
                plc.outputs_mut()[..2].copy_from_slice(&counter.to_le_bytes());
                outputs[..2].copy_from_slice(&counter.to_le_bytes());
            }
            let written = u16::from_le_bytes([outputs[0], outputs[1]]);
            if increment_at.is_none() && written != seen_tx {
                increment_at = Some((k, written));
            }
        }
        let rx_state = RxState {
            before: InputImage::new_checked(state.model.inputs(), layout)
                .map_or(0, |i| i.rx_counter()),
            plc_released: u16::from_le_bytes([outputs[2], outputs[3]]),
            fast: scenario.interface.queue == canif_model::config::QueueMode::Fast,
        };
        let expected = match state.model.cycle(&outputs, t) {
            Ok(inputs) => inputs.to_vec(),
            Err(e) => return run(Outcome::Error(format!("harness bug: {e}")), k, state.frames),
        };
        let actual = match state.iut.cycle(&outputs, t) {
            Ok(inputs) => inputs,
            Err(e) => return run(Outcome::Error(e.0), k, state.frames),
        };
        state.remember(&outputs, &expected, &actual);
        let recent = &state.recent_rx;
        if let Some(difference) = compare_inputs(
            &layout,
            &expected,
            &actual,
            |f| recent.contains(f),
            time_stamp_tolerance,
            rx_state,
        ) {
            return run(state.fail(difference), k, state.frames);
        }
        if actual.len() != layout.input_size() {
            return run(
                Outcome::Error("input image of the wrong size".into()),
                k,
                state.frames,
            );
        }
        exchange.device_cycle_done(&actual);
        // The checker judges the images; what the PLC read is not kept (bounded memory).
        drop(plc.take_received());
        for (offset, frame) in step.bus {
            match state.kernel.as_mut() {
                Some(bus) => bus.schedule(k * cycle_time + scale(offset), frame),
                None => state.nodes.schedule(t + offset, frame),
            }
        }
    }
    let cycles = state.cycle + 1;
    if let Some(trace) = state.trace.take() {
        let _ = trace.finish();
    }
    run(Outcome::Pass, cycles, state.frames)
}

/// Rewrites the dataLength of FD Tx messages to the length the PLC means (not a
/// valid size) and fills the bytes past it with junk the device must not send.
pub fn declare_lengths(layout: &ImageLayout, lengths: &[(u16, u8)], outputs: &mut [u8]) {
    let message = layout.tx_message;
    let (Some(tn), LengthField::Byte(length)) =
        (message.transaction_number.clone(), &message.length)
    else {
        return;
    };
    for slot in 0..layout.tx_slots {
        let at = layout.tx_slot(slot).start;
        let number = u16::from_le_bytes([outputs[at + tn.start], outputs[at + tn.start + 1]]);
        let Some(&(_, declared)) = lengths.iter().find(|(n, _)| *n == number) else {
            continue;
        };
        let current = outputs[at + length.start];
        if current == declared {
            continue;
        }
        outputs[at + length.start] = declared;
        let data = at + message.data.start;
        for byte in
            &mut outputs[data + usize::from(declared)..data + usize::from(current.max(declared))]
        {
            *byte = 0xEE;
        }
    }
}
