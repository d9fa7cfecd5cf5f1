//! The input image (device → PLC, CoE 0x600z).
//!
//! Source: 003 (0x600z:01 TxCounter, :02 RxCounter, :03 NoOfRxMessages,
//! :04 TransactionNumber, :05.. Rx messages), 000 §6, §8.3.3 (InfoData).

use super::{field, read_u16, read_u32, write_u16, write_u32, ImageLayout, MessageView, SizeError};

/// A read/write view of an input image.
///
/// Requirements: LAY-GEN-004, LAY-GEN-005, INFO-001.
#[derive(Debug)]
pub struct InputImage<T> {
    buffer: T,
    layout: ImageLayout,
}

impl<T: AsRef<[u8]>> InputImage<T> {
    pub fn new_checked(buffer: T, layout: ImageLayout) -> Result<Self, SizeError> {
        let actual = buffer.as_ref().len();
        let expected = layout.input_size();
        if actual != expected {
            return Err(SizeError { expected, actual });
        }
        Ok(InputImage { buffer, layout })
    }

    pub fn layout(&self) -> &ImageLayout {
        &self.layout
    }

    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Inputs.TxCounter: the last Outputs.TxCounter the device accepted.
    pub fn tx_counter(&self) -> u16 {
        read_u16(self.buffer.as_ref(), field::TX_COUNTER)
    }

    /// Inputs.RxCounter: changes when new messages are in the image.
    pub fn rx_counter(&self) -> u16 {
        read_u16(self.buffer.as_ref(), field::RX_COUNTER)
    }

    /// Inputs.NoOfRxMessages.
    pub fn no_of_rx_messages(&self) -> u16 {
        read_u16(self.buffer.as_ref(), field::NO_OF_MESSAGES)
    }

    /// Inputs.TransactionNumber; `None` when the layout has none.
    pub fn transaction_number(&self) -> Option<u16> {
        self.layout
            .transaction_number
            .then(|| read_u16(self.buffer.as_ref(), field::TRANSACTION_NUMBER))
    }

    /// `Inputs.RxMessage[slot]`; `None` past the last slot.
    pub fn rx_message(&self, slot: usize) -> Option<MessageView<&[u8]>> {
        if slot >= self.layout.rx_slots {
            return None;
        }
        MessageView::new_checked(
            &self.buffer.as_ref()[self.layout.rx_slot(slot)],
            self.layout.rx_message,
        )
        .ok()
    }

    /// `InfoData[index]`; `None` without InfoData or past index 15.
    pub fn info_data(&self, index: usize) -> Option<u32> {
        if !self.layout.info_data || index >= field::INFO_DATA_WORDS {
            return None;
        }
        let start = self.layout.info_data_start() + 4 * index;
        Some(read_u32(self.buffer.as_ref(), start..start + 4))
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> InputImage<T> {
    pub fn set_tx_counter(&mut self, value: u16) {
        write_u16(self.buffer.as_mut(), field::TX_COUNTER, value);
    }

    pub fn set_rx_counter(&mut self, value: u16) {
        write_u16(self.buffer.as_mut(), field::RX_COUNTER, value);
    }

    pub fn set_no_of_rx_messages(&mut self, value: u16) {
        write_u16(self.buffer.as_mut(), field::NO_OF_MESSAGES, value);
    }

    pub fn set_transaction_number(&mut self, value: u16) {
        if self.layout.transaction_number {
            write_u16(self.buffer.as_mut(), field::TRANSACTION_NUMBER, value);
        }
    }

    pub fn rx_message_mut(&mut self, slot: usize) -> Option<MessageView<&mut [u8]>> {
        if slot >= self.layout.rx_slots {
            return None;
        }
        let range = self.layout.rx_slot(slot);
        MessageView::new_checked(&mut self.buffer.as_mut()[range], self.layout.rx_message).ok()
    }

    pub fn set_info_data(&mut self, index: usize, value: u32) {
        if self.layout.info_data && index < field::INFO_DATA_WORDS {
            let start = self.layout.info_data_start() + 4 * index;
            write_u32(self.buffer.as_mut(), start..start + 4, value);
        }
    }
}
