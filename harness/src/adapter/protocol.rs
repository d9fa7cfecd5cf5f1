//! The adapter protocol's messages (docs/adapter-protocol.md), written once as
//! serde types: the harness's client and `canif device --stdio`'s server both
//! speak through them, and `tests/adapter_protocol.rs` holds them to the JSON
//! Schema in `docs/adapter-protocol.schema.json`.

use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode, Synchronization};
use canif_model::filter::{FilterAction, FilterMatch, FilterRow};
use canif_model::frame::{CanId, Frame, FrameKind};
use canif_model::image::ImageLayout;
use canif_model::info_data::{BitTiming, ControllerStatus};
use canif_model::Nanos;
use serde::{Deserialize, Serialize};

/// The highest protocol version this harness speaks; `configure` offers it
/// and the IUT answers the version it will speak (1 or 2).
pub const PROTOCOL_VERSION: u64 = 2;

/// What the harness asks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Request {
    Configure {
        protocol: u64,
        config: Config,
        capabilities: Caps,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bus: Option<OwnedBus>,
    },
    Cycle {
        now_ns: Nanos,
        outputs: Hex,
    },
    Receive {
        frame: WireFrame,
        end_ns: Nanos,
    },
    PollTransmit {
        now_ns: Nanos,
    },
    TransmitComplete,
    ControllerStatus {
        status: Status,
    },
    /// Version 2: one exchange per cycle. What happened on the bus since the
    /// last step, in order, then the cycle itself.
    Step {
        now_ns: Nanos,
        outputs: Hex,
        events: Vec<BusEvent>,
    },
    Bye,
}

/// Something that happened at the IUT's controller since the last step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "EventLine", into = "EventLine")]
pub enum BusEvent {
    /// The controller received `frame`; its last bit ended at `end_ns`.
    Received { frame: WireFrame, end_ns: Nanos },
    /// The controller started the next frame of its plan at `at_ns`.
    Started { at_ns: Nanos },
    /// The frame it started is on the bus.
    Completed,
    /// The controller's status and counters changed.
    Status { status: Status },
}

/// A [`BusEvent`] as the line carries it: `{"event": KIND, …}`. Read as a
/// flat struct, then checked, so the many events of a step are not buffered
/// twice (as an internally tagged enum would be).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EventLine {
    event: EventKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    frame: Option<WireFrame>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    end_ns: Option<Nanos>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    at_ns: Option<Nanos>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    status: Option<Status>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum EventKind {
    Received,
    Started,
    Completed,
    Status,
}

impl TryFrom<EventLine> for BusEvent {
    type Error = String;
    fn try_from(line: EventLine) -> Result<Self, String> {
        let event = match (line.event, line.frame, line.end_ns, line.at_ns, line.status) {
            (EventKind::Received, Some(frame), Some(end_ns), None, None) => {
                BusEvent::Received { frame, end_ns }
            }
            (EventKind::Started, None, None, Some(at_ns), None) => BusEvent::Started { at_ns },
            (EventKind::Completed, None, None, None, None) => BusEvent::Completed,
            (EventKind::Status, None, None, None, Some(status)) => BusEvent::Status { status },
            (kind, ..) => {
                return Err(format!(
                    "a `{}` event has exactly {}",
                    serde_json::to_value(kind)
                        .unwrap_or_default()
                        .as_str()
                        .unwrap_or("?"),
                    match kind {
                        EventKind::Received => "\"frame\" and \"end_ns\"",
                        EventKind::Started => "\"at_ns\"",
                        EventKind::Completed => "no other field",
                        EventKind::Status => "\"status\"",
                    }
                ))
            }
        };
        Ok(event)
    }
}

impl From<BusEvent> for EventLine {
    fn from(event: BusEvent) -> Self {
        let mut line = EventLine {
            event: EventKind::Completed,
            frame: None,
            end_ns: None,
            at_ns: None,
            status: None,
        };
        match event {
            BusEvent::Received { frame, end_ns } => {
                (line.event, line.frame, line.end_ns) =
                    (EventKind::Received, Some(frame), Some(end_ns))
            }
            BusEvent::Started { at_ns } => {
                (line.event, line.at_ns) = (EventKind::Started, Some(at_ns))
            }
            BusEvent::Completed => {}
            BusEvent::Status { status } => {
                (line.event, line.status) = (EventKind::Status, Some(status))
            }
        }
        line
    }
}

/// One frame of the IUT's plan: what it will start next (`frame`, or
/// `invalid` with why it is no frame), and from when.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannedFrame {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<WireFrame>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub invalid: Option<String>,
    pub not_before_ns: Nanos,
}

/// `step` and `stepped` as plain structs: protocol 2's hot path reads them
/// without the buffering an internally tagged enum needs (the general
/// [`Request`] / [`Answer`] read everything else, and say what is wrong).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepLine {
    #[serde(rename = "type")]
    pub kind: StepTag,
    pub now_ns: Nanos,
    pub outputs: Hex,
    pub events: Vec<BusEvent>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepTag {
    Step,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SteppedLine {
    #[serde(rename = "type")]
    pub kind: SteppedTag,
    pub inputs: Hex,
    pub plan: Vec<PlannedFrame>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SteppedTag {
    Stepped,
}

impl Request {
    /// The request's `type`, for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Request::Configure { .. } => "configure",
            Request::Cycle { .. } => "cycle",
            Request::Receive { .. } => "receive",
            Request::PollTransmit { .. } => "poll_transmit",
            Request::TransmitComplete => "transmit_complete",
            Request::ControllerStatus { .. } => "controller_status",
            Request::Step { .. } => "step",
            Request::Bye => "bye",
        }
    }

    /// Whether the request drives the controller side (the bus).
    pub fn is_bus_request(&self) -> bool {
        matches!(
            self,
            Request::Receive { .. }
                | Request::PollTransmit { .. }
                | Request::TransmitComplete
                | Request::Step { .. }
        )
    }
}

/// What the IUT answers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Answer {
    Configured {
        protocol: u64,
        accepted: bool,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reason: Option<String>,
    },
    Inputs {
        inputs: Hex,
    },
    Ok,
    Transmit {
        frame: Option<Transmitted>,
        #[serde(default)]
        next_ns: Option<Nanos>,
    },
    /// Version 2: the new input image, and the frames the controller will
    /// start, in order, with the earliest time each may start.
    Stepped {
        inputs: Hex,
        plan: Vec<PlannedFrame>,
    },
    Error {
        message: String,
    },
}

impl Answer {
    pub fn name(&self) -> &'static str {
        match self {
            Answer::Configured { .. } => "configured",
            Answer::Inputs { .. } => "inputs",
            Answer::Ok => "ok",
            Answer::Transmit { .. } => "transmit",
            Answer::Stepped { .. } => "stepped",
            Answer::Error { .. } => "error",
        }
    }

    pub fn error(message: impl Into<String>) -> Self {
        Answer::Error {
            message: message.into(),
        }
    }
}

/// A frame the controller starts sending: a valid frame, or what the device
/// produced that is none (the soft device reports such a frame rather than
/// hiding it; the harness judges it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Transmitted {
    Frame(WireFrame),
    Invalid(InvalidWireFrame),
}

/// `{"invalid": "why"}`: the device's controller started something that is no
/// CAN frame (the harness judges it against LAY-GEN-008, FD-LEN-00x).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InvalidWireFrame {
    pub invalid: String,
}

/// Bytes as a lower-case hex string.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct Hex(pub Vec<u8>);

impl TryFrom<String> for Hex {
    type Error = String;
    fn try_from(text: String) -> Result<Self, String> {
        if !text.len().is_multiple_of(2) || !text.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(format!(
                "not a hex string of whole bytes: {:?}",
                shorten(&text)
            ));
        }
        let digit = |b: u8| match b {
            b'0'..=b'9' => b - b'0',
            b'a'..=b'f' => b - b'a' + 10,
            _ => b - b'A' + 10, // checked above: a hex digit
        };
        Ok(Hex(text
            .as_bytes()
            .chunks_exact(2)
            .map(|pair| (digit(pair[0]) << 4) | digit(pair[1]))
            .collect()))
    }
}

impl From<Hex> for String {
    fn from(hex: Hex) -> String {
        const DIGITS: &[u8; 16] = b"0123456789abcdef";
        let mut text = String::with_capacity(2 * hex.0.len());
        for byte in &hex.0 {
            text.push(char::from(DIGITS[usize::from(byte >> 4)]));
            text.push(char::from(DIGITS[usize::from(byte & 0x0F)]));
        }
        text
    }
}

fn shorten(text: &str) -> String {
    text.chars().take(40).collect()
}

/// A CAN frame on the protocol.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireFrame {
    pub id: u32,
    #[serde(default)]
    pub extended: bool,
    #[serde(default)]
    pub rtr: bool,
    #[serde(default)]
    pub fd: bool,
    #[serde(default)]
    pub brs: bool,
    #[serde(default)]
    pub esi: bool,
    #[serde(default)]
    pub len: u8,
    pub data: Hex,
}

impl From<&Frame> for WireFrame {
    fn from(frame: &Frame) -> Self {
        let (rtr, fd, brs, esi) = match frame.kind {
            FrameKind::Classic { rtr } => (rtr, false, false, false),
            FrameKind::Fd { brs, esi } => (false, true, brs, esi),
        };
        WireFrame {
            id: frame.id.raw(),
            extended: frame.id.is_extended(),
            rtr,
            fd,
            brs,
            esi,
            len: frame.len(),
            data: Hex(frame.data().to_vec()),
        }
    }
}

impl WireFrame {
    /// Whether the message is consistent in itself: `len` and `data` agree,
    /// a remote frame has no data, BRS/ESI only with FD, the identifier fits
    /// its format. A message that is not is a broken protocol, not a frame.
    pub fn check(&self) -> Result<(), String> {
        let limit = if self.extended { 0x1FFF_FFFF } else { 0x7FF };
        if self.id > limit {
            return Err(format!(
                "identifier 0x{:X} does not fit a {} identifier",
                self.id,
                if self.extended { "29-bit" } else { "11-bit" }
            ));
        }
        let data = self.data.0.len();
        if self.rtr && (data != 0 || self.fd) {
            return Err(format!(
                "a remote frame carries no data (and CAN FD has none): {data} data bytes{}",
                if self.fd { ", FD" } else { "" }
            ));
        }
        if !self.rtr && usize::from(self.len) != data {
            return Err(format!(
                "\"len\" is {} but \"data\" has {data} bytes",
                self.len
            ));
        }
        if !self.fd && (self.brs || self.esi) {
            return Err("BRS and ESI exist only in CAN FD frames".into());
        }
        Ok(())
    }
}

impl TryFrom<&WireFrame> for Frame {
    type Error = String;
    /// The CAN frame a consistent message describes; `Err` for one that no
    /// controller can send (9 classic bytes, 36 FD bytes, a remote frame above 8).
    fn try_from(wire: &WireFrame) -> Result<Frame, String> {
        wire.check()?;
        let id = if wire.extended {
            CanId::extended(wire.id)
        } else {
            CanId::standard(wire.id)
        }
        .ok_or_else(|| format!("identifier 0x{:X} out of range", wire.id))?;
        let frame = if wire.fd {
            Frame::fd(id, wire.brs, wire.esi, &wire.data.0)
        } else if wire.rtr {
            Frame::remote(id, wire.len)
        } else {
            Frame::classic(id, &wire.data.0)
        };
        frame.map_err(|e| e.to_string())
    }
}

/// `configure.config`: the interface as the PLC configured it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    pub format: Format,
    pub queue: Queue,
    pub transaction_number: bool,
    pub time_stamp: bool,
    pub tx_slots: u8,
    pub rx_slots: u8,
    #[serde(default)]
    pub filters: Vec<Filter>,
    #[serde(default)]
    pub sync1_shift_ns: Option<Nanos>,
    #[serde(default)]
    pub nominal_timing: u32,
    #[serde(default)]
    pub data_timing: u32,
    #[serde(default)]
    pub output_size: usize,
    #[serde(default)]
    pub input_size: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Format {
    #[serde(rename = "11-bit")]
    Base11,
    #[serde(rename = "29-bit")]
    Extended29,
    #[serde(rename = "fd")]
    Fd,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Queue {
    Standard,
    Optimized,
    Fast,
}

/// One row of the filter table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Filter {
    Range {
        action: Action,
        from: u32,
        to: u32,
    },
    Mask {
        action: Action,
        code: u32,
        mask: u32,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Action {
    Accept,
    Reject,
}

/// `configure.capabilities`: what the profile offers.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Caps {
    #[serde(default)]
    pub base11: bool,
    #[serde(default)]
    pub ext29: bool,
    #[serde(default)]
    pub fd: bool,
    #[serde(default)]
    pub fast_queue: bool,
    #[serde(default)]
    pub optimized_queue: bool,
    #[serde(default)]
    pub transaction_number: bool,
    #[serde(default)]
    pub transaction_number_only_ext29: bool,
    #[serde(default)]
    pub timestamp: bool,
    #[serde(default)]
    pub filters: bool,
    #[serde(default)]
    pub info_data: bool,
    #[serde(default)]
    pub distributed_clocks: bool,
    pub max_slots: u8,
    pub rx_queue_depth: usize,
    pub tx_queue_depth: usize,
}

/// `configure.bus`: a SocketCAN interface an external IUT opens itself; its
/// time stamps count from `epoch_ns` of CLOCK_REALTIME.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OwnedBus {
    pub epoch_ns: u64,
    #[serde(rename = "socketcan")]
    pub interface: String,
}

/// `controller_status.status`.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Status {
    pub bus_off: bool,
    pub error_passive: bool,
    pub node_active: bool,
    pub warning_limit: bool,
    pub overload: bool,
    pub bus_idle: bool,
    pub transceiver_delay: u32,
    pub ack_errors: u32,
    pub bit_errors: u32,
    pub crc_errors: u32,
    pub form_errors: u32,
    pub stuff_errors: u32,
    pub receive_error_counter: u32,
    pub transmit_error_counter: u32,
    pub core_running: bool,
}

impl From<&ControllerStatus> for Status {
    fn from(s: &ControllerStatus) -> Self {
        Status {
            bus_off: s.bus_off,
            error_passive: s.error_passive,
            node_active: s.node_active,
            warning_limit: s.warning_limit,
            overload: s.overload,
            bus_idle: s.bus_idle,
            transceiver_delay: s.transceiver_delay,
            ack_errors: s.ack_errors,
            bit_errors: s.bit_errors,
            crc_errors: s.crc_errors,
            form_errors: s.form_errors,
            stuff_errors: s.stuff_errors,
            receive_error_counter: s.receive_error_counter,
            transmit_error_counter: s.transmit_error_counter,
            core_running: s.core_running,
        }
    }
}

impl From<&Status> for ControllerStatus {
    fn from(s: &Status) -> Self {
        ControllerStatus {
            bus_off: s.bus_off,
            error_passive: s.error_passive,
            node_active: s.node_active,
            warning_limit: s.warning_limit,
            overload: s.overload,
            bus_idle: s.bus_idle,
            transceiver_delay: s.transceiver_delay,
            ack_errors: s.ack_errors,
            bit_errors: s.bit_errors,
            crc_errors: s.crc_errors,
            form_errors: s.form_errors,
            stuff_errors: s.stuff_errors,
            receive_error_counter: s.receive_error_counter,
            transmit_error_counter: s.transmit_error_counter,
            core_running: s.core_running,
        }
    }
}

impl Config {
    pub fn new(config: &InterfaceConfig, layout: &ImageLayout) -> Self {
        Config {
            format: match config.format {
                FrameFormat::Base11 => Format::Base11,
                FrameFormat::Extended29 => Format::Extended29,
                FrameFormat::Fd => Format::Fd,
            },
            queue: match config.queue {
                QueueMode::Standard => Queue::Standard,
                QueueMode::Optimized => Queue::Optimized,
                QueueMode::Fast => Queue::Fast,
            },
            transaction_number: config.transaction_number,
            time_stamp: config.time_stamp,
            tx_slots: config.tx_slots,
            rx_slots: config.rx_slots,
            filters: config
                .filters
                .iter()
                .map(|row| {
                    let action = match row.action {
                        FilterAction::Accept => Action::Accept,
                        FilterAction::Reject => Action::Reject,
                    };
                    match row.matches {
                        FilterMatch::Range { from, to } => Filter::Range { action, from, to },
                        FilterMatch::CodeMask { code, mask } => Filter::Mask { action, code, mask },
                    }
                })
                .collect(),
            sync1_shift_ns: match config.synchronization {
                Synchronization::Sm2 => None,
                Synchronization::DistributedClocks { sync1_shift } => Some(sync1_shift),
            },
            nominal_timing: config.nominal_timing.to_word(),
            data_timing: config.data_timing.to_word(),
            output_size: layout.output_size(),
            input_size: layout.input_size(),
        }
    }

    /// The model's configuration.
    pub fn interface(&self) -> InterfaceConfig {
        let format = match self.format {
            Format::Base11 => FrameFormat::Base11,
            Format::Extended29 => FrameFormat::Extended29,
            Format::Fd => FrameFormat::Fd,
        };
        let mut interface = InterfaceConfig::new(format, self.tx_slots);
        interface.queue = match self.queue {
            Queue::Standard => QueueMode::Standard,
            Queue::Optimized => QueueMode::Optimized,
            Queue::Fast => QueueMode::Fast,
        };
        interface.rx_slots = self.rx_slots;
        interface.transaction_number = self.transaction_number;
        interface.time_stamp = self.time_stamp;
        interface.synchronization = match self.sync1_shift_ns {
            Some(sync1_shift) => Synchronization::DistributedClocks { sync1_shift },
            None => Synchronization::Sm2,
        };
        interface.nominal_timing = BitTiming::from_word(self.nominal_timing);
        interface.data_timing = BitTiming::from_word(self.data_timing);
        interface.filters = self
            .filters
            .iter()
            .map(|row| {
                let (action, matches) = match *row {
                    Filter::Range { action, from, to } => (action, FilterMatch::Range { from, to }),
                    Filter::Mask { action, code, mask } => {
                        (action, FilterMatch::CodeMask { code, mask })
                    }
                };
                FilterRow {
                    action: match action {
                        Action::Accept => FilterAction::Accept,
                        Action::Reject => FilterAction::Reject,
                    },
                    matches,
                }
            })
            .collect();
        interface
    }
}

impl From<&Capabilities> for Caps {
    fn from(c: &Capabilities) -> Self {
        Caps {
            base11: c.base11,
            ext29: c.ext29,
            fd: c.fd,
            fast_queue: c.fast_queue,
            optimized_queue: c.optimized_queue,
            transaction_number: c.transaction_number,
            transaction_number_only_ext29: c.transaction_number_only_ext29,
            timestamp: c.time_stamp,
            filters: c.filters,
            info_data: c.info_data,
            distributed_clocks: c.distributed_clocks,
            max_slots: c.max_slots,
            rx_queue_depth: c.rx_queue_depth,
            tx_queue_depth: c.tx_queue_depth,
        }
    }
}

impl From<&Caps> for Capabilities {
    fn from(c: &Caps) -> Self {
        Capabilities {
            base11: c.base11,
            ext29: c.ext29,
            fd: c.fd,
            fast_queue: c.fast_queue,
            optimized_queue: c.optimized_queue,
            transaction_number: c.transaction_number,
            transaction_number_only_ext29: c.transaction_number_only_ext29,
            time_stamp: c.timestamp,
            filters: c.filters,
            info_data: c.info_data,
            distributed_clocks: c.distributed_clocks,
            max_slots: c.max_slots,
            rx_queue_depth: c.rx_queue_depth,
            tx_queue_depth: c.tx_queue_depth,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_read_as_the_document_writes_them() {
        let line = r#"{"type":"receive","frame":{"id":1701,"extended":false,"rtr":false,"fd":false,"brs":false,"esi":false,"len":2,"data":"0a0B"},"end_ns":10000}"#;
        let Request::Receive { frame, end_ns } = serde_json::from_str(line).unwrap() else {
            panic!("not a receive");
        };
        assert_eq!(end_ns, 10_000);
        let frame = Frame::try_from(&frame).unwrap();
        assert_eq!(
            frame,
            Frame::classic(CanId::Standard(1701), &[0x0A, 0x0B]).unwrap()
        );
        assert_eq!(
            serde_json::to_string(&Request::PollTransmit { now_ns: 5 }).unwrap(),
            r#"{"type":"poll_transmit","now_ns":5}"#
        );
    }

    #[test]
    fn a_frame_that_is_no_frame_is_refused_with_the_reason() {
        let wire: WireFrame = serde_json::from_str(r#"{"id":2048,"len":0,"data":""}"#).unwrap();
        assert_eq!(
            Frame::try_from(&wire).unwrap_err(),
            "identifier 0x800 does not fit a 11-bit identifier"
        );
        assert!(serde_json::from_str::<WireFrame>(r#"{"id":1,"data":"abc"}"#).is_err());
        assert!(serde_json::from_str::<WireFrame>(r#"{"id":4294967297,"data":""}"#).is_err());
        assert!(serde_json::from_str::<WireFrame>(r#"{"id":1,"data":"+0"}"#).is_err());
        assert!(serde_json::from_str::<WireFrame>(r#"{"id":1,"data":"","color":1}"#).is_err());
        let lie: WireFrame =
            serde_json::from_str(r#"{"id":1,"len":15,"data":"0102030405060708"}"#).unwrap();
        assert_eq!(
            Frame::try_from(&lie).unwrap_err(),
            "\"len\" is 15 but \"data\" has 8 bytes"
        );
        let config = r#"{"type":"configure","protocol":1,"config":{"format":"11-bit","queue":"standard","transaction_number":false,"time_stamp":false,"tx_slots":257,"rx_slots":4},"capabilities":{"max_slots":32,"rx_queue_depth":64,"tx_queue_depth":64}}"#;
        let error = serde_json::from_str::<Request>(config)
            .unwrap_err()
            .to_string();
        assert!(error.contains("257"), "{error}");
    }

    #[test]
    fn answers_keep_the_field_order_of_the_document() {
        let answer = Answer::Transmit {
            frame: None,
            next_ns: None,
        };
        assert_eq!(
            serde_json::to_string(&answer).unwrap(),
            r#"{"type":"transmit","frame":null,"next_ns":null}"#
        );
        let configured = Answer::Configured {
            protocol: 1,
            accepted: false,
            reason: Some("no".into()),
        };
        assert_eq!(
            serde_json::to_string(&configured).unwrap(),
            r#"{"type":"configured","protocol":1,"accepted":false,"reason":"no"}"#
        );
    }
}
