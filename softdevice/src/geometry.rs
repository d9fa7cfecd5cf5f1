//! Where each field of a message structure sits, per frame format and
//! option (000/001 §6), and the little-endian words of the image.

use crate::settings::Format;

/// Byte offsets of one message structure. Names follow the PLC types of the manual.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MsgGeometry {
    pub(crate) size: usize,
    pub(crate) tn: Option<usize>,
    pub(crate) len16: Option<usize>,
    pub(crate) len8: Option<usize>,
    pub(crate) flags: Option<usize>,
    pub(crate) cob: usize,
    pub(crate) cob_wide: bool,
    pub(crate) data: usize,
    pub(crate) data_cap: usize,
    pub(crate) ts: Option<usize>,
}

impl MsgGeometry {
    pub(crate) fn tx(format: Format, tn: bool) -> Self {
        let shift = if tn { 2 } else { 0 };
        match format {
            // COB ID word (length bits 0-3, RTR bit 4, id bits 5-15), then 8 bytes.
            Format::Std11 => MsgGeometry {
                size: 10 + shift,
                tn: tn.then_some(0),
                len16: None,
                len8: None,
                flags: None,
                cob: shift,
                cob_wide: false,
                data: shift + 2,
                data_cap: 8,
                ts: None,
            },
            // Length UINT, COB ID UDINT, 8 bytes.
            Format::Ext29 => MsgGeometry {
                size: 14 + shift,
                tn: tn.then_some(0),
                len16: Some(shift),
                len8: None,
                flags: None,
                cob: shift + 2,
                cob_wide: true,
                data: shift + 6,
                data_cap: 8,
                ts: None,
            },
            // CANFDTXQUEUE.
            Format::Fd => MsgGeometry {
                size: 72,
                tn: Some(0),
                len16: None,
                len8: Some(2),
                flags: Some(3),
                cob: 4,
                cob_wide: true,
                data: 8,
                data_cap: 64,
                ts: None,
            },
        }
    }

    pub(crate) fn rx(format: Format, ts: bool) -> Self {
        match format {
            Format::Std11 => MsgGeometry {
                size: 10,
                tn: None,
                len16: None,
                len8: None,
                flags: None,
                cob: 0,
                cob_wide: false,
                data: 2,
                data_cap: 8,
                ts: None,
            },
            Format::Ext29 => MsgGeometry {
                size: if ts { 22 } else { 14 },
                tn: None,
                len16: Some(0),
                len8: None,
                flags: None,
                cob: 2,
                cob_wide: true,
                data: 6,
                data_cap: 8,
                ts: ts.then_some(14),
            },
            // CANFDTSRXQUEUE.
            Format::Fd => MsgGeometry {
                size: 78,
                tn: None,
                len16: None,
                len8: Some(0),
                flags: Some(1),
                cob: 2,
                cob_wide: true,
                data: 6,
                data_cap: 64,
                ts: Some(70),
            },
        }
    }
}

pub(crate) fn get16(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}
pub(crate) fn put16(b: &mut [u8], at: usize, v: u16) {
    b[at..at + 2].copy_from_slice(&v.to_le_bytes());
}
pub(crate) fn get32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}
pub(crate) fn put32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}
