//! The process images: the bytes the PLC writes (outputs) and reads (inputs).
//!
//! The manual's figures are missing from the text; the layout below is
//! reconstructed from 003 (CoE entries 0x700z:01.. and 0x600z:01..) and 000 §6/§8.3
//! and recorded in the catalogue as LAY-GEN-002..007. In one place:
//!
//! * every multi-byte field is little-endian, structures are packed
//!   (`pack_mode := 0`): no padding anywhere;
//! * **outputs** (0x700z): `TxCounter: UINT` at 0, `RxCounter: UINT` at 2,
//!   `NoOfTxMessages: UINT` at 4, then `TxMessage[0..tx_slots]`;
//! * **inputs** (0x600z): `TxCounter: UINT` at 0, `RxCounter: UINT` at 2,
//!   `NoOfRxMessages: UINT` at 4, `TransactionNumber: UINT` at 6 when the interface
//!   has transaction numbers, then `RxMessage[0..rx_slots]`, then
//!   `InfoData: ARRAY[0..15] OF UDINT` when the device offers InfoData;
//! * the message structures are those of [`MessageLayout`]'s constants.

mod header;
mod input;
pub mod le;
mod message;
mod output;

pub use header::{InputHeader, OutputHeader};
pub use input::InputImage;
pub use message::{flag, LengthField, MessageError, MessageLayout, MessageRepr, MessageView};
pub use output::OutputImage;

use crate::config::{FrameFormat, InterfaceConfig};

/// A byte range inside a buffer, as in smoltcp's `wire` modules.
pub type Field = core::ops::Range<usize>;

/// Named ranges of the fixed image headers.
pub mod field {
    use super::Field;
    /// Outputs.TxCounter (0x700z:01) and Inputs.TxCounter (0x600z:01).
    pub const TX_COUNTER: Field = 0..2;
    /// Outputs.RxCounter (0x700z:02) and Inputs.RxCounter (0x600z:02).
    pub const RX_COUNTER: Field = 2..4;
    /// Outputs.NoOfTxMessages (0x700z:03) and Inputs.NoOfRxMessages (0x600z:03).
    pub const NO_OF_MESSAGES: Field = 4..6;
    /// Inputs.TransactionNumber (0x600z:04), only with transaction numbers.
    pub const TRANSACTION_NUMBER: Field = 6..8;
    /// Where the messages start when there is no transaction number in the header.
    pub const MESSAGES: usize = 6;
    /// Where the Rx messages start when the input header has a transaction number.
    pub const MESSAGES_AFTER_TRANSACTION_NUMBER: usize = 8;
    /// InfoData has 16 UDINT entries.
    pub const INFO_DATA_WORDS: usize = 16;

    /// Each header member's role in the handshake, in its own image (000 §6,
    /// 003's object entries): the PLC writes the outputs, the device the
    /// inputs, so a counter of the same name means a different step in each.
    pub mod role {
        pub const OUTPUTS_TX_COUNTER: &str =
            "003: 0x700z:01; the PLC adds 1 to hand over NoOfTxMessages messages (000 §6)";
        pub const INPUTS_TX_COUNTER: &str =
            "003: 0x600z:01; the device's confirmation: equals Outputs.TxCounter once it took the batch (000 §6)";
        pub const OUTPUTS_RX_COUNTER: &str =
            "003: 0x700z:02; the PLC's acknowledge: it copies Inputs.RxCounter once it read the messages (000 §6)";
        pub const INPUTS_RX_COUNTER: &str =
            "003: 0x600z:02; the device adds 1 when new messages wait in RxMessage (000 §6)";
        pub const NO_OF_TX_MESSAGES: &str = "003: 0x700z:03, messages to send from TxMessage[0]";
        pub const NO_OF_RX_MESSAGES: &str = "003: 0x600z:03, new messages from RxMessage[0]";
    }
}

/// Which fields an interface's images have and how many message slots.
///
/// Requirements: LAY-GEN-002, LAY-GEN-003, LAY-GEN-004, LAY-GEN-005.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageLayout {
    pub tx_message: &'static MessageLayout,
    pub rx_message: &'static MessageLayout,
    pub transaction_number: bool,
    pub info_data: bool,
    pub tx_slots: usize,
    pub rx_slots: usize,
}

impl ImageLayout {
    /// The layout of a (valid) configuration; `info_data` comes from the device.
    pub fn new(config: &InterfaceConfig, info_data: bool) -> Self {
        let (tx_message, rx_message) =
            match (config.format, config.transaction_number, config.time_stamp) {
                (FrameFormat::Base11, false, _) => (&MessageLayout::BASE11, &MessageLayout::BASE11),
                (FrameFormat::Base11, true, _) => {
                    (&MessageLayout::BASE11_TN, &MessageLayout::BASE11)
                }
                (FrameFormat::Extended29, false, _) => {
                    (&MessageLayout::EXT29, &MessageLayout::EXT29)
                }
                (FrameFormat::Extended29, true, false) => {
                    (&MessageLayout::EXT29_TN, &MessageLayout::EXT29)
                }
                (FrameFormat::Extended29, true, true) => {
                    (&MessageLayout::EXT29_TN, &MessageLayout::EXT29_TS)
                }
                (FrameFormat::Fd, _, _) => (&MessageLayout::FD_TX, &MessageLayout::FD_RX),
            };
        ImageLayout {
            tx_message,
            rx_message,
            transaction_number: config.transaction_number || config.format == FrameFormat::Fd,
            info_data,
            tx_slots: usize::from(config.tx_slots),
            rx_slots: usize::from(config.rx_slots),
        }
    }

    /// Whether this is the CAN FD interface (000 §8.3): its messages carry the EDL, BRS and ESI bits.
    pub fn is_fd(&self) -> bool {
        self.tx_message.flags.is_some()
    }

    pub fn output_size(&self) -> usize {
        field::MESSAGES + self.tx_slots * self.tx_message.size
    }

    fn rx_messages_start(&self) -> usize {
        if self.transaction_number {
            field::MESSAGES_AFTER_TRANSACTION_NUMBER
        } else {
            field::MESSAGES
        }
    }

    pub fn input_size(&self) -> usize {
        self.info_data_start()
            + if self.info_data {
                4 * field::INFO_DATA_WORDS
            } else {
                0
            }
    }

    /// Byte range of `Outputs.TxMessage[slot]`.
    pub fn tx_slot(&self, slot: usize) -> Field {
        let start = field::MESSAGES + slot * self.tx_message.size;
        start..start + self.tx_message.size
    }

    /// Byte range of `Inputs.RxMessage[slot]`.
    pub fn rx_slot(&self, slot: usize) -> Field {
        let start = self.rx_messages_start() + slot * self.rx_message.size;
        start..start + self.rx_message.size
    }

    /// Where `InfoData[0]` starts (equal to the end of the Rx messages).
    pub fn info_data_start(&self) -> usize {
        self.rx_messages_start() + self.rx_slots * self.rx_message.size
    }
}

/// An image of the wrong size for its layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SizeError {
    pub expected: usize,
    pub actual: usize,
}

impl core::fmt::Display for SizeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "process image has {} bytes, the layout needs {}",
            self.actual, self.expected
        )
    }
}

impl std::error::Error for SizeError {}

pub(crate) fn read_u16(buf: &[u8], field: Field) -> u16 {
    le::read(buf, field) as u16
}

pub(crate) fn write_u16(buf: &mut [u8], field: Field, value: u16) {
    le::write(buf, field, value.into());
}

pub(crate) fn read_u32(buf: &[u8], field: Field) -> u32 {
    le::read(buf, field) as u32
}

pub(crate) fn write_u32(buf: &mut [u8], field: Field, value: u32) {
    le::write(buf, field, value.into());
}

pub(crate) fn read_u64(buf: &[u8], field: Field) -> u64 {
    le::read(buf, field)
}

pub(crate) fn write_u64(buf: &mut [u8], field: Field, value: u64) {
    le::write(buf, field, value);
}
