//! The PLC side: a reference client that sends and receives exactly as the
//! corrected sample code of 001 §6 does (ruling R5), and with transaction
//! numbers learns which messages were sent (000 §5.2).

use std::collections::VecDeque;

use crate::handshake;
use crate::image::{
    ImageLayout, InputImage, MessageError, MessageRepr, MessageView, OutputImage, SizeError,
};

/// One PLC program using the CAN interface.
///
/// Requirements: HS-TX-001, HS-RX-002, HS-RX-003, ERR-R5, CL-TN-002.
#[derive(Debug, Clone)]
pub struct PlcClient {
    layout: ImageLayout,
    outputs: Vec<u8>,
    to_send: VecDeque<MessageRepr>,
    received: Vec<MessageRepr>,
    /// Transaction numbers of the messages handed over and not yet known to
    /// be sent, oldest first.
    in_flight: VecDeque<u16>,
    sent: Vec<u16>,
}

impl PlcClient {
    pub fn new(layout: ImageLayout) -> Self {
        PlcClient {
            outputs: vec![0; layout.output_size()],
            layout,
            to_send: VecDeque::new(),
            received: Vec::new(),
            in_flight: VecDeque::new(),
            sent: Vec::new(),
        }
    }

    /// Queues a message in the PLC program; refused when the interface's message
    /// structure cannot carry it.
    pub fn send(&mut self, message: MessageRepr) -> Result<(), MessageError> {
        let mut scratch = [0u8; 80];
        let mut view = MessageView::new_checked(
            &mut scratch[..self.layout.tx_message.size],
            self.layout.tx_message,
        )
        .map_err(|_| MessageError::NotRepresentable {
            layout: self.layout.tx_message.name,
            frame_kind: "any",
        })?;
        message.emit(&mut view)?;
        self.to_send.push_back(message);
        Ok(())
    }

    /// Messages queued in the PLC program and not yet handed to the interface.
    pub fn pending(&self) -> usize {
        self.to_send.len()
    }

    /// The output image the client last wrote.
    pub fn outputs(&self) -> &[u8] {
        &self.outputs
    }

    /// The output image for writing: for stimulus that departs from the sample
    /// code on purpose, such as jumping the TxCounter (any change counts, G1).
    pub fn outputs_mut(&mut self) -> &mut [u8] {
        &mut self.outputs
    }

    /// Messages read from the interface so far, in order; drains them.
    pub fn take_received(&mut self) -> Vec<MessageRepr> {
        std::mem::take(&mut self.received)
    }

    /// Transaction numbers of the messages learned to be sent so far, in the
    /// order sent; drains them. Empty without transaction numbers.
    pub fn take_sent(&mut self) -> Vec<u16> {
        std::mem::take(&mut self.sent)
    }

    /// One PLC task cycle: the read sample, then the send sample of 001 §6.
    pub fn task(&mut self, inputs: &[u8]) -> Result<&[u8], SizeError> {
        let inputs = InputImage::new_checked(inputs, self.layout)?;
        let mut outputs = OutputImage::new_checked(&mut self.outputs[..], self.layout)?;

        // Inputs.TransactionNumber names the last message on the bus (TN-002);
        // the device sends in order, so every message handed over before it
        // was sent too. A message accepted (Inputs.TxCounter) may still wait
        // in the device's queue: only the number tells.
        if let Some(last) = inputs.transaction_number() {
            if let Some(at) = self.in_flight.iter().position(|n| *n == last) {
                self.sent.extend(self.in_flight.drain(..=at));
            }
        }

        // if Outputs.RxCounter <> Inputs.RxCounter then … Outputs.RxCounter := Inputs.RxCounter
        if handshake::new_messages(outputs.rx_counter(), inputs.rx_counter()) {
            let count = usize::from(inputs.no_of_rx_messages()).min(self.layout.rx_slots);
            for slot in 0..count {
                if let Some(view) = inputs.rx_message(slot) {
                    self.received.push(MessageRepr::parse_clamped(&view).0);
                }
            }
            outputs.set_rx_counter(inputs.rx_counter());
        }

        // if (Outputs.TxCounter = Inputs.TxCounter) and NumberOfMessagesToSend > 0 then …
        if handshake::ready_to_send(outputs.tx_counter(), inputs.tx_counter())
            && !self.to_send.is_empty()
        {
            let count = self.to_send.len().min(self.layout.tx_slots);
            for slot in 0..count {
                let (Some(message), Some(mut view)) =
                    (self.to_send.pop_front(), outputs.tx_message_mut(slot))
                else {
                    break;
                };
                // Checked in `send`.
                let _ = message.emit(&mut view);
                if self.layout.transaction_number {
                    self.in_flight.push_back(message.transaction_number);
                }
            }
            outputs.set_no_of_tx_messages(count as u16);
            // Outputs.TxCounter := Inputs.TxCounter + 1
            outputs.set_tx_counter(handshake::next(inputs.tx_counter()));
        }
        Ok(&self.outputs)
    }
}
