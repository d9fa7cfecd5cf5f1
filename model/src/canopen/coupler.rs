//! A Beckhoff CANopen bus coupler as the quick start describes it, as a state
//! machine without I/O: frames in, frames out, time as an argument.
//!
//! Source: 002 (NMT start/stop, default identifiers, event-driven digital
//! inputs, analog inputs by RTR or after 0x6423 > 0, node guarding with toggle
//! bit, guard time × life time factor, heartbeat 0x1017), 004 (expedited SDO),
//! rulings R6-R8.

use std::collections::BTreeMap;

use super::cob_id::{classify, default_cob_id, Channel};
use super::guarding::{life_time, GuardResponder, GUARD_TIME, LIFE_TIME_FACTOR};
use super::heartbeat::PRODUCER_HEARTBEAT_TIME;
use super::nmt::{parse_command, NmtState};
use super::pdo::{
    ANALOG_INPUT_DELTA, ANALOG_INPUT_INTERRUPT_ENABLE, ANALOG_INPUT_LOWER_LIMIT,
    ANALOG_INPUT_UPPER_LIMIT, TPDO2_PARAMETER,
};
use super::sdo::{abort_code, SdoRequest, SdoResponse};
use super::NodeId;
use crate::frame::{CanId, Frame};
use crate::Nanos;

/// An object dictionary entry: its bytes and whether the client may write it.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Entry {
    value: Vec<u8>,
    writable: bool,
}

/// Deliberate defects of a coupler, for the CANopen checks' self-test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CouplerFault {
    /// The guarding answer's toggle bit never inverts.
    ToggleStuck,
    /// Upload responses always say 4 bytes (0x43), whatever the entry's size.
    SdoSizeAlways4,
    /// Unknown objects get no answer instead of an abort.
    NoAbort,
}

impl CouplerFault {
    pub const ALL: [CouplerFault; 3] = [
        CouplerFault::ToggleStuck,
        CouplerFault::SdoSizeAlways4,
        CouplerFault::NoAbort,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            CouplerFault::ToggleStuck => "toggle-stuck",
            CouplerFault::SdoSizeAlways4 => "sdo-size-always-4",
            CouplerFault::NoAbort => "no-abort",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// The coupler.
///
/// Requirements: NMT-001..NMT-010, COB-001, PDO-001..PDO-003, GRD-001..GRD-005,
/// HB-001..HB-003, HB-005, SDO-001..SDO-009.
#[derive(Debug, Clone)]
pub struct Coupler {
    node: NodeId,
    state: NmtState,
    objects: BTreeMap<(u16, u8), Entry>,
    /// The object dictionary at power-on: nothing is stored, so a reset
    /// restores these (CiA 301: reset communication 0x1000-0x1FFF, reset node all).
    power_on: BTreeMap<(u16, u8), Entry>,
    digital_inputs: Vec<u8>,
    analog_inputs: Vec<i16>,
    guard: GuardResponder,
    last_guard_request: Option<Nanos>,
    life_guarding_lost: bool,
    last_heartbeat: Option<Nanos>,
    faults: Vec<CouplerFault>,
    /// The latest time the coupler has seen (a frame or a poll).
    clock: Nanos,
    /// The analog values last sent, and when.
    analog_sent: Vec<i16>,
    analog_sent_at: Option<Nanos>,
    /// An analog event waits for the inhibit time to pass.
    analog_pending: bool,
}

impl Coupler {
    /// A coupler with `digital` input bytes (1..=8) and `analog` input channels (1..=4).
    pub fn new(node: NodeId, digital: usize, analog: usize) -> Self {
        let mut objects = BTreeMap::new();
        let mut put = |index: u16, sub: u8, value: &[u8], writable: bool| {
            objects.insert(
                (index, sub),
                Entry {
                    value: value.to_vec(),
                    writable,
                },
            );
        };
        put(0x1000, 0, &0x0019_0191u32.to_le_bytes(), false); // device type: CiA 401 I/O
        put(0x1001, 0, &[0], false); // error register
        put(0x1018, 1, &2u32.to_le_bytes(), false); // vendor id: Beckhoff
        put(GUARD_TIME, 0, &0u16.to_le_bytes(), true);
        put(LIFE_TIME_FACTOR, 0, &[0], true);
        put(PRODUCER_HEARTBEAT_TIME, 0, &0u16.to_le_bytes(), true);
        put(ANALOG_INPUT_INTERRUPT_ENABLE, 0, &[0], true);
        let channels = analog.clamp(1, 4);
        for index in [
            ANALOG_INPUT_UPPER_LIMIT,
            ANALOG_INPUT_LOWER_LIMIT,
            ANALOG_INPUT_DELTA,
        ] {
            put(index, 0, &[channels as u8], false);
            for sub in 1..=channels as u8 {
                put(index, sub, &0u32.to_le_bytes(), true);
            }
        }
        // TPDO2 (the analog inputs): COB ID, transmission type, inhibit time
        // (100 µs units), event timer (ms).
        put(TPDO2_PARAMETER, 0, &[5], false);
        put(
            TPDO2_PARAMETER,
            1,
            &(0x280 + u32::from(node.get())).to_le_bytes(),
            false,
        );
        put(TPDO2_PARAMETER, 2, &[255], false);
        put(TPDO2_PARAMETER, 3, &0u16.to_le_bytes(), true);
        put(TPDO2_PARAMETER, 5, &0u16.to_le_bytes(), true);
        Coupler {
            node,
            state: NmtState::PreOperational,
            power_on: objects.clone(),
            objects,
            digital_inputs: vec![0; digital.clamp(1, 8)],
            analog_inputs: vec![0; analog.clamp(1, 4)],
            guard: GuardResponder::default(),
            last_guard_request: None,
            life_guarding_lost: false,
            last_heartbeat: None,
            faults: Vec::new(),
            clock: 0,
            analog_sent: vec![0; analog.clamp(1, 4)],
            analog_sent_at: None,
            analog_pending: false,
        }
    }

    pub fn inject(&mut self, fault: CouplerFault) {
        self.faults.push(fault);
    }

    pub fn state(&self) -> NmtState {
        self.state
    }

    pub fn node(&self) -> NodeId {
        self.node
    }

    /// Did the coupler notice the master's loss (no guarding within guard time × life time factor)?
    pub fn life_guarding_lost(&self) -> bool {
        self.life_guarding_lost
    }

    fn u16_object(&self, index: u16) -> u16 {
        self.objects.get(&(index, 0)).map_or(0, |e| {
            u16::from_le_bytes([e.value[0], *e.value.get(1).unwrap_or(&0)])
        })
    }

    fn id(&self, channel: Channel) -> CanId {
        CanId::Standard(default_cob_id(channel, self.node))
    }

    fn pdo(&self, channel: Channel, data: &[u8]) -> Frame {
        Frame::classic(self.id(channel), data).expect("at most 8 bytes")
    }

    fn analog_frame(&self) -> Frame {
        self.pdo(
            Channel::AnalogInputs1To4,
            &super::pdo::analog_payload(&self.analog_inputs),
        )
    }

    /// A frame from the bus arrives at `now`; the frames the coupler answers with.
    pub fn handle(&mut self, frame: &Frame, now: Nanos) -> Vec<Frame> {
        self.clock = self.clock.max(now);
        if let Some((command, target)) = parse_command(frame) {
            if super::nmt::addresses(target, self.node) {
                self.state = self.state.apply(command);
                let restore = match command {
                    super::nmt::NmtCommand::ResetNode => Some(0x0000..=0xFFFF),
                    super::nmt::NmtCommand::ResetCommunication => Some(0x1000..=0x1FFF),
                    _ => None,
                };
                if let Some(range) = restore {
                    self.restore(range);
                    self.analog_pending = false;
                    self.analog_sent_at = None;
                    self.guard.reset();
                    self.last_guard_request = None;
                    self.last_heartbeat = None;
                    // boot-up
                    return vec![self.pdo(Channel::ErrorControl, &[NmtState::Initialising.code()])];
                }
            }
            return Vec::new();
        }
        let CanId::Standard(raw) = frame.id else {
            return Vec::new();
        };
        let Some((channel, node)) = classify(raw) else {
            return Vec::new();
        };
        if node != self.node {
            return Vec::new();
        }
        match channel {
            Channel::ErrorControl if frame.is_remote() => {
                self.last_guard_request = Some(now);
                let mut answer = self.guard.respond(self.node, self.state);
                if self.faults.contains(&CouplerFault::ToggleStuck) {
                    self.guard.reset();
                    answer = self.guard.respond(self.node, self.state);
                    self.guard.reset();
                }
                vec![answer]
            }
            Channel::AnalogInputs1To4 if frame.is_remote() && self.state.pdo_allowed() => {
                vec![self.analog_frame()]
            }
            Channel::DigitalOutputs | Channel::AnalogOutputs1To4 if self.state.pdo_allowed() => {
                Vec::new()
            }
            // CiA 301: a stopped node serves NMT and error control only.
            Channel::SdoRequest if !frame.is_remote() && self.state != NmtState::Stopped => {
                self.sdo(frame.data()).into_iter().collect()
            }
            _ => Vec::new(),
        }
    }

    /// Objects whose index is in `range` return to their power-on values.
    ///
    /// Requirements: NMT-009, NMT-010.
    fn restore(&mut self, range: std::ops::RangeInclusive<u16>) {
        for (key, entry) in &self.power_on {
            if range.contains(&key.0) {
                self.objects.insert(*key, entry.clone());
            }
        }
    }

    fn sdo(&mut self, data: &[u8]) -> Option<Frame> {
        let answer_id = self.id(Channel::SdoResponse);
        let respond = move |response: SdoResponse| {
            Frame::classic(answer_id, &response.to_bytes()).expect("8 bytes")
        };
        let abort = |index, sub_index, code| {
            Some(respond(SdoResponse::Abort {
                index,
                sub_index,
                code,
            }))
        };
        let request = match SdoRequest::parse(data) {
            Ok(request) => request,
            Err(_) => {
                let index =
                    u16::from_le_bytes([*data.get(1).unwrap_or(&0), *data.get(2).unwrap_or(&0)]);
                return abort(
                    index,
                    *data.get(3).unwrap_or(&0),
                    abort_code::COMMAND_SPECIFIER_INVALID,
                );
            }
        };
        // The object exists with other sub-indexes, or not at all.
        let missing = |index: u16, objects: &BTreeMap<(u16, u8), Entry>| {
            if objects.keys().any(|(i, _)| *i == index) {
                abort_code::SUB_INDEX_DOES_NOT_EXIST
            } else {
                abort_code::OBJECT_DOES_NOT_EXIST
            }
        };
        let no_abort = self.faults.contains(&CouplerFault::NoAbort);
        match request {
            SdoRequest::Upload { index, sub_index } => {
                match self.objects.get(&(index, sub_index)) {
                    Some(entry) => {
                        let mut value = [0u8; 4];
                        value[..entry.value.len()].copy_from_slice(&entry.value);
                        let size = if self.faults.contains(&CouplerFault::SdoSizeAlways4) {
                            4
                        } else {
                            entry.value.len() as u8
                        };
                        Some(respond(SdoResponse::Upload {
                            index,
                            sub_index,
                            data: value,
                            size,
                        }))
                    }
                    None if no_abort => None,
                    None => abort(index, sub_index, missing(index, &self.objects)),
                }
            }
            SdoRequest::Download {
                index,
                sub_index,
                data,
                size,
            } => {
                let Some(entry) = self.objects.get_mut(&(index, sub_index)) else {
                    return if no_abort {
                        None
                    } else {
                        abort(index, sub_index, missing(index, &self.objects))
                    };
                };
                if !entry.writable {
                    return abort(index, sub_index, abort_code::READ_ONLY);
                }
                // 0x22 writes the entry's length (SDO-004); a stated size must match it.
                if size.is_some_and(|n| usize::from(n) != entry.value.len()) {
                    return abort(index, sub_index, abort_code::LENGTH_MISMATCH);
                }
                let length = entry.value.len();
                entry.value.copy_from_slice(&data[..length]);
                Some(respond(SdoResponse::DownloadAck { index, sub_index }))
            }
            SdoRequest::Abort { .. } => None,
        }
    }

    /// Sets a digital input byte; in operational state a change goes out at once.
    ///
    /// Requirements: NMT-007, PDO-001.
    pub fn set_digital_input(&mut self, byte: usize, value: u8) -> Vec<Frame> {
        let Some(slot) = self.digital_inputs.get_mut(byte) else {
            return Vec::new();
        };
        let changed = *slot != value;
        *slot = value;
        if changed && self.state.pdo_allowed() {
            vec![self.pdo(Channel::DigitalInputs, &self.digital_inputs.clone())]
        } else {
            Vec::new()
        }
    }

    fn object_u32(&self, index: u16, sub: u8) -> u32 {
        self.objects.get(&(index, sub)).map_or(0, |e| {
            let mut bytes = [0u8; 4];
            bytes[..e.value.len().min(4)].copy_from_slice(&e.value[..e.value.len().min(4)]);
            u32::from_le_bytes(bytes)
        })
    }

    fn analog_events_enabled(&self) -> bool {
        self.object_u32(ANALOG_INPUT_INTERRUPT_ENABLE, 0) > 0 && self.state.pdo_allowed()
    }

    /// Whether the new value of `channel` is an event: it moved at least the
    /// delta (0x6426) from the value last sent, and, where limits are set
    /// (0x6424, 0x6425), it lies outside them.
    ///
    /// Requirements: PDO-004, PDO-005.
    fn analog_event(&self, channel: usize, value: i16) -> bool {
        let sub = channel as u8 + 1;
        let delta = self.object_u32(ANALOG_INPUT_DELTA, sub);
        let moved = (i32::from(value) - i32::from(self.analog_sent[channel])).unsigned_abs();
        let upper = self.object_u32(ANALOG_INPUT_UPPER_LIMIT, sub) as i32;
        let lower = self.object_u32(ANALOG_INPUT_LOWER_LIMIT, sub) as i32;
        let outside =
            (upper, lower) == (0, 0) || i32::from(value) > upper || i32::from(value) < lower;
        moved >= delta.max(1) && outside
    }

    /// The inhibit time of the analog PDO (0x1801:3, in 100 µs).
    fn inhibit(&self) -> Nanos {
        Nanos::from(self.object_u32(TPDO2_PARAMETER, 3)) * 100_000
    }

    /// Sends the analog PDO now, or marks it pending until the inhibit time ends.
    fn send_analog(&mut self, now: Nanos) -> Vec<Frame> {
        let inhibited = self
            .analog_sent_at
            .is_some_and(|at| now < at + self.inhibit());
        if inhibited {
            self.analog_pending = true;
            return Vec::new();
        }
        self.analog_pending = false;
        self.analog_sent = self.analog_inputs.clone();
        self.analog_sent_at = Some(now);
        vec![self.analog_frame()]
    }

    /// Sets an analog input; only with 0x6423 > 0 a change goes out by itself,
    /// thinned out by delta, limits and inhibit time.
    ///
    /// Requirements: PDO-003, PDO-004, PDO-005.
    pub fn set_analog_input(&mut self, channel: usize, value: i16) -> Vec<Frame> {
        let Some(slot) = self.analog_inputs.get_mut(channel) else {
            return Vec::new();
        };
        let changed = *slot != value;
        *slot = value;
        if changed && self.analog_events_enabled() && self.analog_event(channel, value) {
            self.send_analog(self.clock)
        } else {
            Vec::new()
        }
    }

    /// Time passes: heartbeats when due; life guarding watches the master.
    ///
    /// Requirements: HB-001, HB-003, HB-005, GRD-005.
    pub fn poll(&mut self, now: Nanos) -> Vec<Frame> {
        self.clock = self.clock.max(now);
        let mut out = Vec::new();
        // An event held back by the inhibit time goes out with the latest values;
        // the event timer (0x1801:5, ms) sends them periodically.
        if self.analog_events_enabled() {
            let timer = Nanos::from(self.object_u32(TPDO2_PARAMETER, 5)) * 1_000_000;
            let timer_due = timer > 0 && self.analog_sent_at.is_none_or(|at| now >= at + timer);
            if self.analog_pending || timer_due {
                out.extend(self.send_analog(now));
            }
        }
        if let (Some(limit), Some(last)) = (
            life_time(
                self.u16_object(GUARD_TIME),
                self.objects
                    .get(&(LIFE_TIME_FACTOR, 0))
                    .map_or(0, |e| e.value[0]),
            ),
            self.last_guard_request,
        ) {
            if now.saturating_sub(last) > limit {
                self.life_guarding_lost = true;
            }
        }
        let period = self.u16_object(PRODUCER_HEARTBEAT_TIME);
        if period > 0 {
            let due = match self.last_heartbeat {
                None => Some(now),
                Some(last) => super::heartbeat::next_due(last, period).filter(|at| now >= *at),
            };
            if let Some(due) = due {
                // The schedule runs from the nominal time, so lateness does not add
                // up; a node more than a period behind starts afresh.
                let behind = now.saturating_sub(due) >= u64::from(period) * 1_000_000;
                self.last_heartbeat = Some(if behind { now } else { due });
                out.push(super::heartbeat::heartbeat(self.node, self.state));
            }
        }
        out
    }
}
