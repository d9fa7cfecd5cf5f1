//! CAN frames as they appear on the bus: identifier, format, flags and data.
//!
//! Source: 000 §2 (11-bit base and 29-bit extended frame format), §8.3.2 (EDL,
//! BRS, ESI), ISO 11898-1.

use crate::dlc::{fd_round_up, CLASSIC_MAX_LEN, FD_MAX_LEN};

/// Largest 11-bit identifier.
pub const STANDARD_ID_MAX: u32 = 0x7FF;
/// Largest 29-bit identifier.
pub const EXTENDED_ID_MAX: u32 = 0x1FFF_FFFF;

/// A CAN identifier: "Base Frame Format" (CAN 2.0A, 11 bit) or "Extended Frame
/// Format" (CAN 2.0B, 29 bit).
///
/// Requirements: LAY-GEN-001.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CanId {
    Standard(u16),
    Extended(u32),
}

impl CanId {
    /// An 11-bit identifier; `None` above 0x7FF.
    pub fn standard(raw: u32) -> Option<Self> {
        (raw <= STANDARD_ID_MAX).then_some(CanId::Standard(raw as u16))
    }

    /// A 29-bit identifier; `None` above 0x1FFF_FFFF.
    pub fn extended(raw: u32) -> Option<Self> {
        (raw <= EXTENDED_ID_MAX).then_some(CanId::Extended(raw))
    }

    /// The identifier's numeric value.
    pub fn raw(self) -> u32 {
        match self {
            CanId::Standard(id) => u32::from(id),
            CanId::Extended(id) => id,
        }
    }

    pub fn is_extended(self) -> bool {
        matches!(self, CanId::Extended(_))
    }
}

/// Classic CAN or CAN FD, with the flags that belong to each.
///
/// Requirements: FD-BIT-001, FD-BIT-002, FD-BIT-003.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum FrameKind {
    /// Classic CAN (EDL = 0). `rtr`: a remote transmission request.
    Classic { rtr: bool },
    /// CAN FD (EDL = 1). `brs`: the data phase uses the data bit rate;
    /// `esi`: the transmitter is error passive.
    Fd { brs: bool, esi: bool },
}

/// What is wrong with the parts of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameError {
    /// A classic frame carries at most 8 data bytes.
    ClassicTooLong { len: usize },
    /// An FD frame carries at most 64 data bytes.
    FdTooLong { len: usize },
    /// An FD frame's data field is one of 0..=8, 12, 16, 20, 24, 32, 48, 64.
    FdInvalidSize { len: usize },
    /// A remote frame's requested length is 0..=8.
    RemoteLengthTooLarge { len: u8 },
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FrameError::ClassicTooLong { len } => write!(
                f,
                "a classic CAN frame carries at most 8 data bytes, not {len}"
            ),
            FrameError::FdTooLong { len } => {
                write!(f, "a CAN FD frame carries at most 64 data bytes, not {len}")
            }
            FrameError::FdInvalidSize { len } => write!(
                f,
                "{len} bytes is not a CAN FD data field size (0..8, 12, 16, 20, 24, 32, 48, 64)"
            ),
            FrameError::RemoteLengthTooLarge { len } => {
                write!(f, "a remote frame requests 0..8 bytes, not {len}")
            }
        }
    }
}

impl std::error::Error for FrameError {}

/// One CAN frame. Bytes past the data length are always zero, so frames compare
/// by content.
///
/// Requirements: LAY-GEN-001.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Frame {
    pub id: CanId,
    pub kind: FrameKind,
    /// Data length; for a remote frame the requested length (its DLC).
    len: u8,
    data: [u8; 64],
}

impl Frame {
    /// A classic data frame with 0..=8 bytes.
    pub fn classic(id: CanId, data: &[u8]) -> Result<Self, FrameError> {
        if data.len() > usize::from(CLASSIC_MAX_LEN) {
            return Err(FrameError::ClassicTooLong { len: data.len() });
        }
        Ok(Self::with_data(id, FrameKind::Classic { rtr: false }, data))
    }

    /// A classic remote frame (RTR) that requests `len` bytes.
    pub fn remote(id: CanId, len: u8) -> Result<Self, FrameError> {
        if len > CLASSIC_MAX_LEN {
            return Err(FrameError::RemoteLengthTooLarge { len });
        }
        Ok(Frame {
            id,
            kind: FrameKind::Classic { rtr: true },
            len,
            data: [0; 64],
        })
    }

    /// A CAN FD frame; `data.len()` must be a valid FD data field size.
    pub fn fd(id: CanId, brs: bool, esi: bool, data: &[u8]) -> Result<Self, FrameError> {
        if data.len() > usize::from(FD_MAX_LEN) {
            return Err(FrameError::FdTooLong { len: data.len() });
        }
        if fd_round_up(data.len() as u8) != Some(data.len() as u8) {
            return Err(FrameError::FdInvalidSize { len: data.len() });
        }
        Ok(Self::with_data(id, FrameKind::Fd { brs, esi }, data))
    }

    fn with_data(id: CanId, kind: FrameKind, data: &[u8]) -> Self {
        let mut buf = [0u8; 64];
        buf[..data.len()].copy_from_slice(data);
        Frame {
            id,
            kind,
            len: data.len() as u8,
            data: buf,
        }
    }

    /// The data bytes (empty for a remote frame).
    pub fn data(&self) -> &[u8] {
        if self.is_remote() {
            &[]
        } else {
            &self.data[..usize::from(self.len)]
        }
    }

    /// The data length: bytes carried, or for a remote frame the bytes requested.
    pub fn len(&self) -> u8 {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn is_remote(&self) -> bool {
        matches!(self.kind, FrameKind::Classic { rtr: true })
    }

    pub fn is_fd(&self) -> bool {
        matches!(self.kind, FrameKind::Fd { .. })
    }
}

impl core::fmt::Debug for Frame {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{self}")
    }
}

/// candump style: `123#0102`, `12345678#R8`, `123##1` + flags + data for FD.
impl core::fmt::Display for Frame {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.id {
            CanId::Standard(id) => write!(f, "{id:03X}")?,
            CanId::Extended(id) => write!(f, "{id:08X}")?,
        }
        match self.kind {
            FrameKind::Classic { rtr: true } => return write!(f, "#R{}", self.len),
            FrameKind::Classic { rtr: false } => write!(f, "#")?,
            FrameKind::Fd { brs, esi } => {
                write!(f, "##{:X}", u8::from(brs) | (u8::from(esi) << 1))?
            }
        }
        for byte in self.data() {
            write!(f, "{byte:02X}")?;
        }
        Ok(())
    }
}
