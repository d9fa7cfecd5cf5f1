//! The output image (PLC → device, CoE 0x700z).
//!
//! Source: 003 (0x700z:01 TxCounter, :02 RxCounter, :03 NoOfTxMessages,
//! :04.. Tx messages), 000 §6.

use super::{field, read_u16, write_u16, ImageLayout, MessageView, SizeError};

/// A read/write view of an output image.
///
/// Requirements: LAY-GEN-002, LAY-GEN-003.
#[derive(Debug)]
pub struct OutputImage<T> {
    buffer: T,
    layout: ImageLayout,
}

impl<T: AsRef<[u8]>> OutputImage<T> {
    pub fn new_checked(buffer: T, layout: ImageLayout) -> Result<Self, SizeError> {
        let actual = buffer.as_ref().len();
        let expected = layout.output_size();
        if actual != expected {
            return Err(SizeError { expected, actual });
        }
        Ok(OutputImage { buffer, layout })
    }

    pub fn layout(&self) -> &ImageLayout {
        &self.layout
    }

    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Outputs.TxCounter.
    pub fn tx_counter(&self) -> u16 {
        read_u16(self.buffer.as_ref(), field::TX_COUNTER)
    }

    /// Outputs.RxCounter.
    pub fn rx_counter(&self) -> u16 {
        read_u16(self.buffer.as_ref(), field::RX_COUNTER)
    }

    /// Outputs.NoOfTxMessages, as written (it may exceed the slot count: G3).
    pub fn no_of_tx_messages(&self) -> u16 {
        read_u16(self.buffer.as_ref(), field::NO_OF_MESSAGES)
    }

    /// `Outputs.TxMessage[slot]`; `None` past the last slot.
    pub fn tx_message(&self, slot: usize) -> Option<MessageView<&[u8]>> {
        if slot >= self.layout.tx_slots {
            return None;
        }
        MessageView::new_checked(
            &self.buffer.as_ref()[self.layout.tx_slot(slot)],
            self.layout.tx_message,
        )
        .ok()
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> OutputImage<T> {
    pub fn set_tx_counter(&mut self, value: u16) {
        write_u16(self.buffer.as_mut(), field::TX_COUNTER, value);
    }

    pub fn set_rx_counter(&mut self, value: u16) {
        write_u16(self.buffer.as_mut(), field::RX_COUNTER, value);
    }

    pub fn set_no_of_tx_messages(&mut self, value: u16) {
        write_u16(self.buffer.as_mut(), field::NO_OF_MESSAGES, value);
    }

    pub fn tx_message_mut(&mut self, slot: usize) -> Option<MessageView<&mut [u8]>> {
        if slot >= self.layout.tx_slots {
            return None;
        }
        let range = self.layout.tx_slot(slot);
        MessageView::new_checked(&mut self.buffer.as_mut()[range], self.layout.tx_message).ok()
    }
}
