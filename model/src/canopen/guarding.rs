//! Node guarding: the master's RTR and the coupler's status byte with toggle bit.
//!
//! Source: 002 "node guarding" (RTR on 0x700 + node id, one status byte: bits 6..0
//! the state, bit 7 toggles with every transmission; reaction time guard time ×
//! life time factor, objects 0x100C / 0x100D).

use super::cob_id::{default_cob_id, Channel};
use super::nmt::NmtState;
use super::NodeId;
use crate::frame::{CanId, Frame};
use crate::Nanos;

/// Guard time (ms) and life time factor objects.
pub const GUARD_TIME: u16 = 0x100C;
pub const LIFE_TIME_FACTOR: u16 = 0x100D;

/// The master's guarding request: a remote frame on 0x700 + node id that asks
/// for the one status byte (the RTR's length is 1: assumption GRD-006).
///
/// Requirements: GRD-001.
pub fn request(node: NodeId) -> Frame {
    Frame::remote(
        CanId::Standard(default_cob_id(Channel::ErrorControl, node)),
        1,
    )
    .expect("length 1 is valid")
}

/// Bits 6..0: the state; bit 7: the toggle.
///
/// Requirements: GRD-002, GRD-003.
pub fn status_byte(state: NmtState, toggle: bool) -> u8 {
    (state.code() & 0x7F) | if toggle { 0x80 } else { 0 }
}

/// The state and toggle of a status byte.
pub fn parse_status(byte: u8) -> (Option<NmtState>, bool) {
    (NmtState::from_code(byte & 0x7F), byte & 0x80 != 0)
}

/// The coupler side: answers each request, inverting the toggle every time
/// (the first answer has toggle 0, CiA 301).
///
/// Requirements: GRD-002.
#[derive(Debug, Clone, Default)]
pub struct GuardResponder {
    next_toggle: bool,
}

impl GuardResponder {
    pub fn respond(&mut self, node: NodeId, state: NmtState) -> Frame {
        let byte = status_byte(state, self.next_toggle);
        self.next_toggle = !self.next_toggle;
        let id = CanId::Standard(default_cob_id(Channel::ErrorControl, node));
        Frame::classic(id, &[byte]).expect("1 byte fits")
    }

    /// Reset communication restarts the toggle at 0.
    pub fn reset(&mut self) {
        self.next_toggle = false;
    }
}

/// What is wrong with a guarding answer (002, "node guarding").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GuardError {
    /// 002: the module answers with one status byte; this answer has `.0`.
    Length(usize),
    /// 002: bit 7 inverts with every answer; this one did not.
    Toggle { expected: bool },
    /// 002: bits 6-0 are the node state; these (`.0`) name none.
    NotAState(u8),
}

impl std::fmt::Display for GuardError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GuardError::Length(len) => {
                write!(f, "a guarding answer has 1 data byte, not {len}")
            }
            GuardError::Toggle { expected } => write!(
                f,
                "toggle bit is {}, expected {}",
                u8::from(!expected),
                u8::from(*expected)
            ),
            GuardError::NotAState(bits) => write!(f, "0x{bits:02X} is not an NMT state"),
        }
    }
}

impl std::error::Error for GuardError {}

impl From<GuardError> for String {
    fn from(error: GuardError) -> String {
        error.to_string()
    }
}

/// The master side: checks that every answer inverts the toggle.
///
/// Requirements: GRD-002, GRD-004.
#[derive(Debug, Clone, Default)]
pub struct GuardChecker {
    expected_toggle: bool,
}

impl GuardChecker {
    /// `Ok(state)` for a correct answer; `Err` names what was wrong.
    pub fn check(&mut self, answer: &Frame) -> Result<NmtState, GuardError> {
        let [byte] = answer.data() else {
            return Err(GuardError::Length(answer.data().len()));
        };
        let (state, toggle) = parse_status(*byte);
        if toggle != self.expected_toggle {
            return Err(GuardError::Toggle {
                expected: self.expected_toggle,
            });
        }
        self.expected_toggle = !self.expected_toggle;
        state.ok_or(GuardError::NotAState(byte & 0x7F))
    }
}

/// How long the coupler waits for guarding before it reacts: guard time × life
/// time factor. `None` (no life guarding) when either is 0.
///
/// Requirements: GRD-005.
pub fn life_time(guard_time_ms: u16, life_time_factor: u8) -> Option<Nanos> {
    if guard_time_ms == 0 || life_time_factor == 0 {
        return None;
    }
    Some(u64::from(guard_time_ms) * u64::from(life_time_factor) * 1_000_000)
}
