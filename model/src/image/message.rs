//! The message structures inside the images: one per frame format and option.
//!
//! Source: 000/001 §6 (11-bit: COB ID word + 8 data bytes; 29-bit: length UINT,
//! COB ID UDINT, 8 data bytes), §5.2/§5.3 (transaction number, time stamp),
//! §8.3 (CANFDTXQUEUE, CANFDTSRXQUEUE). Field order of the options and the FD
//! flag bits are reconstructed: LAY-GEN-006, LAY-FD-002.

use super::{read_u16, read_u32, read_u64, write_u16, write_u32, write_u64, Field, SizeError};
use crate::cob_id::{CobId32, CobIdWord};
use crate::dlc::{fd_round_up, CLASSIC_MAX_LEN, FD_MAX_LEN};
use crate::frame::{CanId, Frame, FrameKind};

/// Where a message keeps its data length.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LengthField {
    /// Bits 0-3 of the 11-bit COB ID word.
    InCobIdWord,
    /// A `UINT` of its own (29-bit message).
    Word(Field),
    /// A `BYTE` of its own (CAN FD message, `dataLength`).
    Byte(Field),
}

/// Byte layout of one message structure.
///
/// Requirements: LAY-11-001, LAY-29-001, LAY-FD-001, LAY-FD-002, LAY-GEN-006.
#[derive(Debug, PartialEq, Eq)]
pub struct MessageLayout {
    pub name: &'static str,
    /// Its data type's name: 000/001 §8.3's for the CAN FD structures; the
    /// manual draws the classic ones (Abb. 7, 8) without naming them, so
    /// theirs are canif's, in the same style.
    pub type_name: &'static str,
    pub transaction_number: Option<Field>,
    pub length: LengthField,
    /// CAN FD only: bit 0 EDL, bit 1 BRS ("BSR" in the manual), bit 2 ESI.
    pub flags: Option<Field>,
    /// 2 bytes (11-bit word) or 4 bytes (`UDINT`).
    pub cob_id: Field,
    pub data: Field,
    pub time_stamp: Option<Field>,
    pub size: usize,
}

impl MessageLayout {
    /// 11-bit message: COB ID word, 8 data bytes (10 bytes).
    pub const BASE11: MessageLayout = MessageLayout {
        type_name: "CAN11MESSAGE",
        name: "11-bit",
        transaction_number: None,
        length: LengthField::InCobIdWord,
        flags: None,
        cob_id: 0..2,
        data: 2..10,
        time_stamp: None,
        size: 10,
    };
    /// 11-bit Tx message with transaction number in front (12 bytes).
    pub const BASE11_TN: MessageLayout = MessageLayout {
        type_name: "CAN11TXMESSAGE",
        name: "11-bit with transaction number",
        transaction_number: Some(0..2),
        length: LengthField::InCobIdWord,
        flags: None,
        cob_id: 2..4,
        data: 4..12,
        time_stamp: None,
        size: 12,
    };
    /// 29-bit message: length UINT, COB ID UDINT, 8 data bytes (14 bytes).
    pub const EXT29: MessageLayout = MessageLayout {
        type_name: "CAN29MESSAGE",
        name: "29-bit",
        transaction_number: None,
        length: LengthField::Word(0..2),
        flags: None,
        cob_id: 2..6,
        data: 6..14,
        time_stamp: None,
        size: 14,
    };
    /// 29-bit Tx message with transaction number in front (16 bytes).
    pub const EXT29_TN: MessageLayout = MessageLayout {
        type_name: "CAN29TXMESSAGE",
        name: "29-bit with transaction number",
        transaction_number: Some(0..2),
        length: LengthField::Word(2..4),
        flags: None,
        cob_id: 4..8,
        data: 8..16,
        time_stamp: None,
        size: 16,
    };
    /// 29-bit Rx message with the time stamp behind the data (22 bytes).
    pub const EXT29_TS: MessageLayout = MessageLayout {
        type_name: "CAN29TSRXMESSAGE",
        name: "29-bit with time stamp",
        transaction_number: None,
        length: LengthField::Word(0..2),
        flags: None,
        cob_id: 2..6,
        data: 6..14,
        time_stamp: Some(14..22),
        size: 22,
    };
    /// `CANFDTXQUEUE`: transactionNumber, dataLength, EDL/BRS/ESI, cobId, 64 bytes (72 bytes).
    pub const FD_TX: MessageLayout = MessageLayout {
        type_name: "CANFDTXQUEUE",
        name: "CAN FD Tx (CANFDTXQUEUE)",
        transaction_number: Some(0..2),
        length: LengthField::Byte(2..3),
        flags: Some(3..4),
        cob_id: 4..8,
        data: 8..72,
        time_stamp: None,
        size: 72,
    };
    /// `CANFDTSRXQUEUE`: dataLength, EDL/BRS/ESI, cobId, 64 bytes, timeStamp (78 bytes).
    pub const FD_RX: MessageLayout = MessageLayout {
        type_name: "CANFDTSRXQUEUE",
        name: "CAN FD Rx (CANFDTSRXQUEUE)",
        transaction_number: None,
        length: LengthField::Byte(0..1),
        flags: Some(1..2),
        cob_id: 2..6,
        data: 6..70,
        time_stamp: Some(70..78),
        size: 78,
    };

    /// Every message structure an interface can have, in the manual's order.
    pub const ALL: [&'static MessageLayout; 7] = [
        &MessageLayout::BASE11,
        &MessageLayout::BASE11_TN,
        &MessageLayout::EXT29,
        &MessageLayout::EXT29_TN,
        &MessageLayout::EXT29_TS,
        &MessageLayout::FD_TX,
        &MessageLayout::FD_RX,
    ];

    fn max_data(&self) -> usize {
        self.data.len()
    }
}

/// FD flag bits in the flags byte.
pub mod flag {
    pub const EDL: u8 = 1 << 0;
    pub const BRS: u8 = 1 << 1;
    pub const ESI: u8 = 1 << 2;
}

/// A read/write view of one message slot, smoltcp style.
#[derive(Debug)]
pub struct MessageView<T> {
    buffer: T,
    layout: &'static MessageLayout,
}

impl<T: AsRef<[u8]>> MessageView<T> {
    /// A view that checks the buffer has exactly the layout's size.
    pub fn new_checked(buffer: T, layout: &'static MessageLayout) -> Result<Self, SizeError> {
        let actual = buffer.as_ref().len();
        if actual != layout.size {
            return Err(SizeError {
                expected: layout.size,
                actual,
            });
        }
        Ok(MessageView { buffer, layout })
    }

    pub fn layout(&self) -> &'static MessageLayout {
        self.layout
    }

    /// The whole slot, every byte (for showing it, or comparing it whole).
    pub fn as_bytes(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    fn buf(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    /// 0 where the layout has no transaction number.
    pub fn transaction_number(&self) -> u16 {
        self.layout
            .transaction_number
            .clone()
            .map_or(0, |f| read_u16(self.buf(), f))
    }

    /// The length as written, before any validation.
    pub fn raw_length(&self) -> u16 {
        match &self.layout.length {
            LengthField::InCobIdWord => u16::from(self.cob_id_word().length()),
            LengthField::Word(f) => read_u16(self.buf(), f.clone()),
            LengthField::Byte(f) => u16::from(self.buf()[f.start]),
        }
    }

    /// Whether the length as written is beyond its frame's: above 8 without
    /// EDL, above 64 with it (G3).
    pub fn length_out_of_range(&self) -> bool {
        let most = if self.flags() & flag::EDL != 0 {
            FD_MAX_LEN
        } else {
            CLASSIC_MAX_LEN
        };
        self.raw_length() > u16::from(most)
    }

    /// The 11-bit COB ID word (meaningful for the 11-bit layouts only).
    pub fn cob_id_word(&self) -> CobIdWord {
        CobIdWord(read_u16(
            self.buf(),
            self.layout.cob_id.start..self.layout.cob_id.start + 2,
        ))
    }

    /// The 32-bit COB ID (meaningful for the 29-bit and FD layouts only).
    pub fn cob_id32(&self) -> CobId32 {
        if self.layout.cob_id.len() == 4 {
            CobId32(read_u32(self.buf(), self.layout.cob_id.clone()))
        } else {
            CobId32(0)
        }
    }

    /// The FD flags byte; 0 for classic layouts.
    pub fn flags(&self) -> u8 {
        self.layout.flags.clone().map_or(0, |f| self.buf()[f.start])
    }

    /// The whole data field (8 or 64 bytes).
    pub fn data_field(&self) -> &[u8] {
        &self.buf()[self.layout.data.clone()]
    }

    /// 0 where the layout has no time stamp.
    pub fn time_stamp(&self) -> u64 {
        self.layout
            .time_stamp
            .clone()
            .map_or(0, |f| read_u64(self.buf(), f))
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> MessageView<T> {
    fn buf_mut(&mut self) -> &mut [u8] {
        self.buffer.as_mut()
    }

    /// Zeroes every byte of the slot.
    pub fn clear(&mut self) {
        self.buf_mut().fill(0);
    }

    pub fn set_transaction_number(&mut self, value: u16) {
        if let Some(f) = self.layout.transaction_number.clone() {
            write_u16(self.buf_mut(), f, value);
        }
    }

    /// Writes the length field; for the 11-bit word only bits 0-3 change.
    pub fn set_raw_length(&mut self, value: u16) {
        match self.layout.length.clone() {
            LengthField::InCobIdWord => {
                let word = self.cob_id_word();
                self.set_cob_id_word(CobIdWord::new(word.id(), word.rtr(), value as u8));
            }
            LengthField::Word(f) => write_u16(self.buf_mut(), f, value),
            LengthField::Byte(f) => self.buf_mut()[f.start] = value as u8,
        }
    }

    pub fn set_cob_id_word(&mut self, word: CobIdWord) {
        let start = self.layout.cob_id.start;
        write_u16(self.buf_mut(), start..start + 2, word.0);
    }

    pub fn set_cob_id32(&mut self, cob_id: CobId32) {
        if self.layout.cob_id.len() == 4 {
            let f = self.layout.cob_id.clone();
            write_u32(self.buf_mut(), f, cob_id.0);
        }
    }

    pub fn set_flags(&mut self, value: u8) {
        if let Some(f) = self.layout.flags.clone() {
            self.buf_mut()[f.start] = value;
        }
    }

    pub fn data_field_mut(&mut self) -> &mut [u8] {
        let f = self.layout.data.clone();
        &mut self.buf_mut()[f]
    }

    pub fn set_time_stamp(&mut self, value: u64) {
        if let Some(f) = self.layout.time_stamp.clone() {
            write_u64(self.buf_mut(), f, value);
        }
    }
}

/// Why a message slot does not hold a valid frame, or a frame does not fit a slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MessageError {
    /// Classic length field above 8 (G3).
    ClassicLengthTooLarge { len: u16 },
    /// FD dataLength above 64 (G3).
    FdLengthTooLarge { len: u16 },
    /// RTR together with EDL: CAN FD has no remote frames.
    RemoteFdFrame,
    /// The frame cannot be written into this layout (e.g. 29-bit id in an 11-bit slot).
    NotRepresentable {
        layout: &'static str,
        frame_kind: &'static str,
    },
}

impl core::fmt::Display for MessageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MessageError::ClassicLengthTooLarge { len } => {
                write!(f, "classic length field is {len}, at most 8 is valid")
            }
            MessageError::FdLengthTooLarge { len } => {
                write!(f, "FD dataLength is {len}, at most 64 is valid")
            }
            MessageError::RemoteFdFrame => write!(
                f,
                "RTR is set together with EDL; CAN FD has no remote frames"
            ),
            MessageError::NotRepresentable { layout, frame_kind } => {
                write!(
                    f,
                    "a {frame_kind} frame cannot be written into a {layout} message"
                )
            }
        }
    }
}

impl std::error::Error for MessageError {}

/// A decoded message: the frame plus the interface's extra fields.
///
/// Requirements: LAY-11-001, LAY-29-001, LAY-FD-001, FD-LEN-003, FD-LEN-005.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MessageRepr {
    /// 0 where the layout has none.
    pub transaction_number: u16,
    pub frame: Frame,
    /// Nanoseconds; 0 where the layout has none.
    pub time_stamp: u64,
}

impl MessageRepr {
    /// Decodes a slot strictly: out-of-range lengths and remote FD frames are errors.
    /// An FD length that is not a valid size is rounded up with 0x00 padding (R1, G9).
    pub fn parse<T: AsRef<[u8]>>(view: &MessageView<T>) -> Result<Self, MessageError> {
        match Self::decode(view) {
            (repr, None) => Ok(repr),
            (_, Some(error)) => Err(error),
        }
    }

    /// Decodes a slot the way the reference device treats invalid input (G3,
    /// assumption LAY-GEN-008): lengths are clamped to 8 (classic) or 64 (FD), RTR
    /// is dropped from an FD frame. The error says what was clamped.
    pub fn parse_clamped<T: AsRef<[u8]>>(view: &MessageView<T>) -> (Self, Option<MessageError>) {
        Self::decode(view)
    }

    fn decode<T: AsRef<[u8]>>(view: &MessageView<T>) -> (Self, Option<MessageError>) {
        let layout = view.layout();
        let raw_len = view.raw_length();
        let (id, rtr) = match layout.length {
            LengthField::InCobIdWord => {
                let word = view.cob_id_word();
                (CanId::Standard(word.id()), word.rtr())
            }
            _ => {
                let cob_id = view.cob_id32();
                (cob_id.id(), cob_id.rtr())
            }
        };
        let flags = view.flags();
        let mut error = None;
        let frame = if flags & flag::EDL != 0 {
            let len = if raw_len > u16::from(FD_MAX_LEN) {
                error = Some(MessageError::FdLengthTooLarge { len: raw_len });
                FD_MAX_LEN
            } else {
                raw_len as u8
            };
            if rtr {
                error = Some(MessageError::RemoteFdFrame);
            }
            let size = fd_round_up(len).unwrap_or(FD_MAX_LEN);
            let mut data = [0u8; 64];
            data[..usize::from(len)].copy_from_slice(&view.data_field()[..usize::from(len)]);
            let frame = Frame::fd(
                id,
                flags & flag::BRS != 0,
                flags & flag::ESI != 0,
                &data[..usize::from(size)],
            );
            frame.expect("rounded FD size is valid")
        } else {
            let len = if raw_len > u16::from(CLASSIC_MAX_LEN) {
                error = Some(MessageError::ClassicLengthTooLarge { len: raw_len });
                CLASSIC_MAX_LEN
            } else {
                raw_len as u8
            };
            let frame = if rtr {
                Frame::remote(id, len)
            } else {
                Frame::classic(id, &view.data_field()[..usize::from(len)])
            };
            frame.expect("clamped classic length is valid")
        };
        let repr = MessageRepr {
            transaction_number: view.transaction_number(),
            frame,
            time_stamp: view.time_stamp(),
        };
        (repr, error)
    }

    /// Writes the message into a slot; every byte of the slot is written (unused
    /// data bytes as 0x00).
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(
        &self,
        view: &mut MessageView<T>,
    ) -> Result<(), MessageError> {
        let layout = view.layout();
        let frame = &self.frame;
        let not_representable = |frame_kind| MessageError::NotRepresentable {
            layout: layout.name,
            frame_kind,
        };
        if frame.id.is_extended() && layout.length == LengthField::InCobIdWord {
            return Err(not_representable("29-bit"));
        }
        if frame.is_fd() && layout.flags.is_none() {
            return Err(not_representable("CAN FD"));
        }
        if usize::from(frame.len()) > layout.max_data() && !frame.is_remote() {
            return Err(not_representable("too long"));
        }
        view.clear();
        view.set_transaction_number(self.transaction_number);
        match layout.length {
            LengthField::InCobIdWord => view.set_cob_id_word(CobIdWord::new(
                frame.id.raw() as u16,
                frame.is_remote(),
                frame.len(),
            )),
            _ => {
                view.set_cob_id32(CobId32::new(frame.id, frame.is_remote()));
                view.set_raw_length(u16::from(frame.len()));
            }
        }
        if let FrameKind::Fd { brs, esi } = frame.kind {
            view.set_flags(
                flag::EDL | if brs { flag::BRS } else { 0 } | if esi { flag::ESI } else { 0 },
            );
        }
        view.data_field_mut()[..frame.data().len()].copy_from_slice(frame.data());
        view.set_time_stamp(self.time_stamp);
        Ok(())
    }
}
