//! The device side of the CAN interface as a state machine without I/O.
//!
//! Source: 003 (the CAN interface cycle in Buffered and Fast CAN Queue mode),
//! 000 §4 (local Rx queue, silent loss), §5 (queues, transaction number, time
//! stamp), §7 (filters), §8 (CAN FD), rulings G1-G9.
//!
//! The CAN controller is outside: it hands received frames in with
//! [`Device::handle_received`], takes the next frame to send with
//! [`Device::poll_transmit`] (one at a time) and reports it on the bus with
//! [`Device::handle_transmit_complete`]. The cycle task is [`Device::cycle`],
//! called with the output image of the process-data telegram and the time.

use std::collections::VecDeque;

use crate::config::{
    Capabilities, ConfigError, FrameFormat, InterfaceConfig, QueueMode, Synchronization,
};
use crate::filter;
use crate::frame::Frame;
use crate::freedoms::{BadTxLength, RxIdleCount, StaleRxSlots};
use crate::handshake;
use crate::image::{ImageLayout, InputImage, MessageRepr, OutputImage, SizeError};
use crate::info_data::{self, ControllerStatus};
use crate::Nanos;

/// What became of a frame the controller received.
///
/// Requirements: RXQ-003, FQ-004, FLT-005.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RxOutcome {
    /// Waiting for the next cycle (local Rx queue or, in the Fast queue, the free buffer).
    Queued,
    /// Held back by the filter table.
    Filtered,
    /// The interface's message format cannot carry it (29-bit on an 11-bit
    /// interface, FD on a classic one): not delivered (assumption RXQ-005).
    NotRepresentable,
    /// Lost without indication: the local Rx queue was full (tail drop), or in the
    /// Fast queue more frames arrived in one cycle than there are slots.
    Lost,
}

#[derive(Debug, Clone, Copy)]
struct Pending {
    frame: Frame,
    transaction_number: u16,
    /// Distributed Clocks: not before SYNC1 (first message of a batch).
    not_before: Nanos,
}

#[derive(Debug, Clone, Copy)]
struct Received {
    frame: Frame,
    end_of_reception: Nanos,
}

/// The reference device.
#[derive(Debug, Clone)]
pub struct Device {
    config: InterfaceConfig,
    caps: Capabilities,
    layout: ImageLayout,
    inputs: Vec<u8>,
    send_queue: VecDeque<Pending>,
    in_flight: Option<Pending>,
    last_transmitted: u16,
    rx_queue: VecDeque<Received>,
    status: ControllerStatus,
    /// Whether `status` came from the controller or is the initial one (INFO-009).
    controller_reported: bool,
    lost: u64,
}

impl Device {
    /// A device with `config`, refused when `caps` do not allow it.
    ///
    /// Requirements: PROF-002, PROF-003.
    pub fn new(caps: &Capabilities, config: InterfaceConfig) -> Result<Self, ConfigError> {
        config.validate(caps)?;
        let layout = ImageLayout::new(&config, caps.info_data);
        Ok(Device {
            inputs: vec![0; layout.input_size()],
            layout,
            config,
            caps: caps.clone(),
            send_queue: VecDeque::new(),
            in_flight: None,
            last_transmitted: 0,
            rx_queue: VecDeque::new(),
            status: ControllerStatus {
                core_running: true,
                node_active: true,
                ..ControllerStatus::default()
            },
            lost: 0,
            controller_reported: false,
        })
    }

    pub fn layout(&self) -> ImageLayout {
        self.layout
    }

    pub fn config(&self) -> &InterfaceConfig {
        &self.config
    }

    /// The input image as the last cycle left it (all zero before the first).
    pub fn inputs(&self) -> &[u8] {
        &self.inputs
    }

    /// Frames lost without indication so far (not visible to the PLC).
    pub fn lost(&self) -> u64 {
        self.lost
    }

    /// Messages accepted and not yet on the bus.
    pub fn queued_tx(&self) -> usize {
        self.send_queue.len() + usize::from(self.in_flight.is_some())
    }

    /// The accepted messages waiting to be sent, in sending order.
    pub fn send_queue(&self) -> impl Iterator<Item = &Frame> + '_ {
        self.send_queue.iter().map(|pending| &pending.frame)
    }

    /// The transaction numbers of the messages accepted and not yet complete
    /// on the bus: the one on the bus first, then the queue in sending order.
    pub fn waiting_transaction_numbers(&self) -> impl Iterator<Item = u16> + '_ {
        self.in_flight
            .iter()
            .chain(self.send_queue.iter())
            .map(|pending| pending.transaction_number)
    }

    /// Places left in the local Rx queue (in the Fast CAN Queue, the slots).
    pub fn rx_room(&self) -> usize {
        let capacity = match self.config.queue {
            QueueMode::Fast => self.layout.rx_slots,
            QueueMode::Standard | QueueMode::Optimized => self.caps.rx_queue_depth,
        };
        capacity.saturating_sub(self.rx_queue.len())
    }

    /// Messages received and not yet in the image.
    pub fn queued_rx(&self) -> usize {
        self.rx_queue.len()
    }

    /// One CAN interface cycle (003): Tx acceptance, Rx delivery, transaction
    /// number, CAN status. Returns the new input image.
    ///
    /// Requirements: HS-TX-002..HS-TX-008, HS-TX-012, HS-RX-001..HS-RX-007, BQ-002, FQ-002,
    /// FQ-003, TN-002, TN-003, INFO-001.
    pub fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<&[u8], SizeError> {
        let outputs = OutputImage::new_checked(outputs, self.layout)?;
        self.accept_tx(&outputs, now);
        self.deliver_rx(outputs.rx_counter());
        let mut inputs = InputImage::new_checked(&mut self.inputs[..], self.layout)?;
        inputs.set_transaction_number(self.last_transmitted);
        if self.layout.info_data {
            let words = info_data::words(
                &self.status,
                self.config.nominal_timing,
                self.config.data_timing,
                self.send_queue.len() + usize::from(self.in_flight.is_some()),
                self.rx_queue.len(),
            );
            for (index, word) in words.into_iter().enumerate() {
                inputs.set_info_data(index, word);
            }
        }
        Ok(&self.inputs)
    }

    fn accept_tx(&mut self, outputs: &OutputImage<&[u8]>, now: Nanos) {
        let inputs_tx =
            InputImage::new_checked(&self.inputs[..], self.layout).map_or(0, |i| i.tx_counter());
        if !handshake::tx_batch_waiting(outputs.tx_counter(), inputs_tx) {
            return;
        }
        // G3: never more than the slots the image has; how many is the device's choice.
        let count = self.caps.freedoms.oversize_batch.sends(
            usize::from(outputs.no_of_tx_messages()),
            self.layout.tx_slots,
        );
        // HS-TX-012: whether the frame on the wire still takes a place is the
        // device's declared choice (by default it has left the queue, 003).
        let waiting = self
            .caps
            .tx_queue_accounting
            .taken(self.send_queue.len(), self.in_flight.is_some());
        if waiting > 0 && waiting + count > self.caps.tx_queue_depth {
            return; // HS-TX-008: not accepted (and not acknowledged) until there is room.
        }
        let not_before = match self.config.synchronization {
            Synchronization::Sm2 => 0,
            Synchronization::DistributedClocks { sync1_shift } => now.saturating_add(sync1_shift),
        };
        let queued_before = self.send_queue.len();
        for slot in 0..count {
            let Some(view) = outputs.tx_message(slot) else {
                break;
            };
            let (message, _clamped) = MessageRepr::parse_clamped(&view);
            if view.length_out_of_range()
                && self.caps.freedoms.bad_tx_length == BadTxLength::DropsTheMessage
            {
                continue;
            }
            let first = self.send_queue.len() == queued_before;
            self.send_queue.push_back(Pending {
                frame: message.frame,
                transaction_number: message.transaction_number,
                not_before: if first { not_before } else { 0 },
            });
        }
        if let Ok(mut inputs) = InputImage::new_checked(&mut self.inputs[..], self.layout) {
            inputs.set_tx_counter(outputs.tx_counter());
        }
    }

    fn deliver_rx(&mut self, outputs_rx_counter: u16) {
        let Ok(mut inputs) = InputImage::new_checked(&mut self.inputs[..], self.layout) else {
            return;
        };
        let may_deliver = match self.config.queue {
            QueueMode::Fast => true,
            QueueMode::Standard | QueueMode::Optimized => {
                handshake::rx_buffer_released(outputs_rx_counter, inputs.rx_counter())
            }
        };
        if !may_deliver {
            return;
        }
        if self.rx_queue.is_empty() {
            let buffered = self.config.queue != QueueMode::Fast;
            if buffered && self.caps.freedoms.rx_idle_count == RxIdleCount::WritesZero {
                inputs.set_no_of_rx_messages(0);
            }
            return;
        }
        let stale = match self.config.queue {
            QueueMode::Fast => StaleRxSlots::Zeroed,
            QueueMode::Standard | QueueMode::Optimized => self.caps.freedoms.stale_rx_slots,
        };
        let count = self.rx_queue.len().min(self.layout.rx_slots);
        for slot in 0..self.layout.rx_slots {
            let Some(mut view) = inputs.rx_message_mut(slot) else {
                break;
            };
            match (slot < count).then(|| self.rx_queue.pop_front()).flatten() {
                Some(received) => {
                    let message = MessageRepr {
                        transaction_number: 0,
                        frame: received.frame,
                        time_stamp: received.end_of_reception,
                    };
                    // Frames were checked for this layout when they were received.
                    let _ = message.emit(&mut view);
                }
                // Slots past NoOfRxMessages are "don't care" (HS-RX-008): the
                // reference zeroes them, a device may declare it keeps them.
                None if stale == StaleRxSlots::Kept => {}
                None => view.clear(),
            }
        }
        inputs.set_no_of_rx_messages(count as u16);
        inputs.set_rx_counter(handshake::next(inputs.rx_counter()));
    }

    /// The controller received `frame`; its last bit ended at `end_of_reception`
    /// on the device clock (the time stamp, G8).
    ///
    /// Requirements: RXQ-003, RXQ-004, RXQ-005, FQ-004, FLT-005, TS-001.
    pub fn handle_received(&mut self, frame: Frame, end_of_reception: Nanos) -> RxOutcome {
        let representable = match self.config.format {
            FrameFormat::Base11 => !frame.id.is_extended() && !frame.is_fd(),
            FrameFormat::Extended29 => !frame.is_fd(),
            FrameFormat::Fd => true,
        };
        if !representable {
            return RxOutcome::NotRepresentable;
        }
        if !filter::accepts(&self.config.filters, frame.id) {
            return RxOutcome::Filtered;
        }
        if self.rx_room() == 0 {
            self.lost += 1;
            return RxOutcome::Lost;
        }
        self.rx_queue.push_back(Received {
            frame,
            end_of_reception,
        });
        RxOutcome::Queued
    }

    /// The next frame for the controller, if it is idle and one is due.
    ///
    /// Requirements: HS-TX-004, HS-TX-006, PDX-005.
    pub fn poll_transmit(&mut self, now: Nanos) -> Option<Frame> {
        if self.in_flight.is_some() {
            return None;
        }
        if self.send_queue.front()?.not_before > now {
            return None;
        }
        let pending = self.send_queue.pop_front()?;
        self.in_flight = Some(pending);
        Some(pending.frame)
    }

    /// When [`Device::poll_transmit`] will next have a frame although the
    /// controller is idle (Distributed Clocks: SYNC1).
    pub fn poll_timeout(&self) -> Option<Nanos> {
        match (&self.in_flight, self.send_queue.front()) {
            (None, Some(front)) if front.not_before > 0 => Some(front.not_before),
            _ => None,
        }
    }

    /// The frame handed out by [`Device::poll_transmit`] is on the bus.
    ///
    /// Requirements: TN-002.
    pub fn handle_transmit_complete(&mut self) {
        if let Some(done) = self.in_flight.take() {
            self.last_transmitted = done.transaction_number;
        }
    }

    /// The controller's status and error counters, shown in InfoData.
    ///
    /// Requirements: INFO-002, INFO-005.
    pub fn handle_controller_status(&mut self, status: ControllerStatus) {
        self.status = status;
        self.controller_reported = true;
    }

    /// Whether the controller has reported a status yet: before, InfoData
    /// shows INFO-009's initial words.
    pub fn controller_reported(&self) -> bool {
        self.controller_reported
    }
}
