//! How many message slots a cycle time needs.
//!
//! Source: 000/001 §4 "Buffer-Größe in Abhängigkeit der Zykluszeit", ruling R4
//! (amended): the manual's figure is ceil(cycle time / CiA frame time), and its
//! examples are its acceptance cases (500 kbit/s, 8 bytes, ≈ 260 µs → 1 ms
//! needs 4, 5 ms needs 20; 1 Mbit/s, 0 bytes, ≈ 50 µs → 1 ms needs 20). Frames
//! can be shorter than the CiA times (no stuff bits), and then more of them end
//! inside one cycle; the safe figure divides by the shortest frame time, and the
//! advisor recommends it.

use crate::cia_table;
use crate::timing::{bits_duration, classic_bits};
use crate::Nanos;

/// Which frame time the sizing divides by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameTimeBasis {
    /// The manual's CiA table (11-bit, 0..=8 bytes, its five bit rates).
    CiaTable,
    /// The shortest possible frame: no stuff bits. Never too few slots.
    Nominal,
    /// The longest possible frame: every stuff bit.
    WorstCase,
}

/// A sizing: the frame time used and the slots it gives.
///
/// Requirements: TIM-007, TIM-008.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sizing {
    pub basis: FrameTimeBasis,
    pub frame_time: Nanos,
    pub slots: u64,
}

/// Frame time of an 11-bit frame with `payload` bytes on `basis`; `None` when
/// the CiA table has no such cell or the payload exceeds 8.
pub fn frame_time(bitrate: u32, payload: u8, basis: FrameTimeBasis) -> Option<Nanos> {
    if payload > 8 || bitrate == 0 {
        return None;
    }
    let bits = classic_bits(false, payload);
    match basis {
        FrameTimeBasis::CiaTable => cia_table::frame_time(bitrate, payload),
        FrameTimeBasis::Nominal => Some(bits_duration(bits.nominal, bitrate)),
        FrameTimeBasis::WorstCase => Some(bits_duration(bits.worst_case, bitrate)),
    }
}

/// ceil(cycle / frame time): frames that can arrive in one cycle at 100 % load.
///
/// Requirements: TIM-007.
pub fn slots_needed(cycle: Nanos, frame_time: Nanos) -> u64 {
    if frame_time == 0 {
        return u64::MAX;
    }
    cycle.div_ceil(frame_time)
}

/// The sizing on one basis.
pub fn size(bitrate: u32, cycle: Nanos, payload: u8, basis: FrameTimeBasis) -> Option<Sizing> {
    let frame_time = frame_time(bitrate, payload, basis)?;
    Some(Sizing {
        basis,
        frame_time,
        slots: slots_needed(cycle, frame_time),
    })
}

/// What the advisor says for one bus, cycle and payload.
///
/// Requirements: TIM-007, TIM-008.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Advice {
    /// The manual's figure: the CiA table's frame time (where the table has the cell).
    pub manual: Option<Sizing>,
    /// The figure that cannot overflow: the shortest (nominal) frame time, so
    /// the most frames that can end within one cycle.
    pub safe: Sizing,
}

impl Advice {
    /// The recommendation: always the safe figure.
    pub fn recommended(&self) -> Sizing {
        self.safe
    }

    /// Whether the manual's figure is too small: more frames can end in a cycle.
    pub fn manual_can_overflow(&self) -> bool {
        self.manual.is_some_and(|m| m.slots < self.safe.slots)
    }
}

/// The manual's figure: ceil(cycle / CiA frame time); `None` outside the table.
///
/// Requirements: TIM-007.
pub fn manual_figure(bitrate: u32, cycle: Nanos, payload: u8) -> Option<Sizing> {
    size(bitrate, cycle, payload, FrameTimeBasis::CiaTable)
}

/// Both figures; `None` when no frame time exists (payload above 8, bit rate 0).
///
/// Requirements: TIM-007, TIM-008.
pub fn advise(bitrate: u32, cycle: Nanos, payload: u8) -> Option<Advice> {
    Some(Advice {
        manual: manual_figure(bitrate, cycle, payload),
        safe: size(bitrate, cycle, payload, FrameTimeBasis::Nominal)?,
    })
}
