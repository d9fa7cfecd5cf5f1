//! How long a frame occupies the bus: bit counts and durations.
//!
//! Source: ruling R3 (worst-case stuffing after Davis et al. 2007,
//! `8n + g + 13 + floor((g + 8n - 1) / 4)`, g = 34 standard, 54 extended) and
//! ISO 11898-1:2015 for the CAN FD frame (stuff count, CRC-17/21, fixed stuff
//! bits, bit rate switch). The counts include the 3-bit intermission, so
//! back-to-back frames at 100 % load follow each other by exactly this time.

use crate::frame::{Frame, FrameKind};
use crate::Nanos;

/// Nominal (no stuff bits) and worst-case (most stuff bits) bit counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BitCount {
    pub nominal: u32,
    pub worst_case: u32,
}

/// Bits at the arbitration (nominal) bit rate and at the data bit rate.
///
/// Requirements: TIM-001, TIM-002, TIM-003.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrameBits {
    pub arbitration: BitCount,
    /// Zero for classic frames and for FD frames without bit rate switch.
    pub data: BitCount,
}

/// The two bit rates of a CAN FD bus (equal for classic CAN).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BitRates {
    pub nominal: u32,
    pub data: u32,
}

impl BitRates {
    pub fn classic(bitrate: u32) -> Self {
        BitRates {
            nominal: bitrate,
            data: bitrate,
        }
    }
}

/// Which bit count a duration uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stuffing {
    Nominal,
    WorstCase,
}

/// Bits of a classic frame with `data_len` bytes on the wire (0 for a remote
/// frame), including the 3-bit intermission.
///
/// Requirements: TIM-001, TIM-002.
pub fn classic_bits(extended: bool, data_len: u8) -> BitCount {
    let g: u32 = if extended { 54 } else { 34 };
    let data = 8 * u32::from(data_len);
    BitCount {
        nominal: data + g + 13,
        worst_case: data + g + 13 + (g + data - 1) / 4,
    }
}

/// Bits of an FD frame with `data_len` bytes (a valid FD size), split between
/// the phases when `brs` is set.
///
/// Requirements: TIM-003.
pub fn fd_bits(extended: bool, data_len: u8, brs: bool) -> FrameBits {
    // SOF, identifier(s), SRR/IDE, RRS, FDF, res, BRS: dynamically stuffed, nominal rate.
    let arbitration_stuffed: u32 = if extended { 36 } else { 17 };
    // CRC delimiter, ACK slot, ACK delimiter, EOF, intermission.
    let arbitration_tail: u32 = 1 + 1 + 1 + 7 + 3;
    // ESI, DLC, data: dynamically stuffed, data rate.
    let data_stuffed = 1 + 4 + 8 * u32::from(data_len);
    // Stuff count (4) and CRC with their fixed stuff bits.
    let (crc, fixed_stuff) = if data_len <= 16 { (17, 6) } else { (21, 7) };
    let data_tail = 4 + crc + fixed_stuff;

    // Worst case: a stuff bit after bit 5 of the stuffed region, then after
    // every 4th bit. One that follows the BRS bit itself is sent after the
    // switch, at the data rate (ISO 11898-1: the bit rate switches at BRS's
    // sample point), so the arbitration phase keeps those strictly before it.
    let stuff_arbitration = (arbitration_stuffed - 2) / 4;
    let stuff_total = (arbitration_stuffed + data_stuffed - 1) / 4;
    let arbitration = BitCount {
        nominal: arbitration_stuffed + arbitration_tail,
        worst_case: arbitration_stuffed + arbitration_tail + stuff_arbitration,
    };
    let data = BitCount {
        nominal: data_stuffed + data_tail,
        worst_case: data_stuffed + data_tail + (stuff_total - stuff_arbitration),
    };
    if brs {
        FrameBits { arbitration, data }
    } else {
        let all = BitCount {
            nominal: arbitration.nominal + data.nominal,
            worst_case: arbitration.worst_case + data.worst_case,
        };
        FrameBits {
            arbitration: all,
            data: BitCount::default(),
        }
    }
}

/// The bits a frame puts on the bus.
///
/// Requirements: TIM-001, TIM-002, TIM-003.
pub fn frame_bits(frame: &Frame) -> FrameBits {
    let extended = frame.id.is_extended();
    match frame.kind {
        FrameKind::Classic { .. } => FrameBits {
            arbitration: classic_bits(extended, frame.data().len() as u8),
            data: BitCount::default(),
        },
        FrameKind::Fd { brs, .. } => fd_bits(extended, frame.len(), brs),
    }
}

/// Nanoseconds for `bits` at `bitrate` bit/s, rounded up.
pub fn bits_duration(bits: u32, bitrate: u32) -> Nanos {
    if bitrate == 0 {
        return Nanos::MAX;
    }
    (u64::from(bits) * 1_000_000_000).div_ceil(u64::from(bitrate))
}

/// How long `frame` occupies the bus, intermission included.
///
/// Requirements: TIM-001, TIM-002, TIM-003.
pub fn frame_duration(frame: &Frame, rates: BitRates, stuffing: Stuffing) -> Nanos {
    let bits = frame_bits(frame);
    let pick = |count: BitCount| match stuffing {
        Stuffing::Nominal => count.nominal,
        Stuffing::WorstCase => count.worst_case,
    };
    bits_duration(pick(bits.arbitration), rates.nominal)
        .saturating_add(bits_duration(pick(bits.data), rates.data))
}
