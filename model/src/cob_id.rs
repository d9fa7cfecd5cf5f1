//! How identifier, RTR and length are packed into the COB ID fields of a message.
//!
//! Source: 000/001 §6 "Message-Struktur bei Verwendung des 11 Bit Identifiers"
//! and "… des 29 Bit Identifiers".

use crate::frame::{CanId, EXTENDED_ID_MAX, STANDARD_ID_MAX};

/// The 16-bit COB ID word of the 11-bit message: bit 0-3 data length (0…8),
/// bit 4 RTR, bit 5-15 the 11-bit identifier.
///
/// Requirements: LAY-11-002, LAY-11-003, LAY-11-004.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CobIdWord(pub u16);

impl CobIdWord {
    const LENGTH_MASK: u16 = 0x000F;
    const RTR: u16 = 1 << 4;
    const ID_SHIFT: u32 = 5;

    /// Packs an identifier (masked to 11 bits), RTR and a length (masked to 4 bits).
    pub fn new(id: u16, rtr: bool, len: u8) -> Self {
        let id = (id & STANDARD_ID_MAX as u16) << Self::ID_SHIFT;
        let rtr = if rtr { Self::RTR } else { 0 };
        CobIdWord(id | rtr | (u16::from(len) & Self::LENGTH_MASK))
    }

    /// Bits 0-3. Values 9..=15 are representable but not valid (G3).
    pub fn length(self) -> u8 {
        (self.0 & Self::LENGTH_MASK) as u8
    }

    /// Bit 4.
    pub fn rtr(self) -> bool {
        self.0 & Self::RTR != 0
    }

    /// Bits 5-15.
    pub fn id(self) -> u16 {
        self.0 >> Self::ID_SHIFT
    }
}

/// The 32-bit COB ID of the 29-bit (and CAN FD) message: bit 0-28 identifier,
/// bit 30 RTR, bit 31 frame format (0: 11-bit, 1: 29-bit). Bit 29 is reserved.
///
/// Requirements: LAY-29-002, LAY-29-003, LAY-29-004, LAY-29-005.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CobId32(pub u32);

impl CobId32 {
    const EXTENDED: u32 = 1 << 31;
    const RTR: u32 = 1 << 30;

    pub fn new(id: CanId, rtr: bool) -> Self {
        let format = if id.is_extended() { Self::EXTENDED } else { 0 };
        let rtr = if rtr { Self::RTR } else { 0 };
        CobId32(format | rtr | (id.raw() & EXTENDED_ID_MAX))
    }

    /// Bit 31 selects the format; a standard identifier is the low 11 bits of
    /// bits 0-28 (higher bits are ignored: assumption LAY-29-006).
    pub fn id(self) -> CanId {
        if self.0 & Self::EXTENDED != 0 {
            CanId::Extended(self.0 & EXTENDED_ID_MAX)
        } else {
            CanId::Standard((self.0 & STANDARD_ID_MAX) as u16)
        }
    }

    pub fn rtr(self) -> bool {
        self.0 & Self::RTR != 0
    }
}
