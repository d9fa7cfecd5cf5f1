//! Helpers shared by the model's tests: a direct PLC ⇄ device loop on an ideal bus.
#![allow(dead_code)]

use canif_model::client::PlcClient;
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode};
use canif_model::device::Device;
use canif_model::frame::{CanId, Frame};
use canif_model::image::{InputImage, MessageRepr, OutputImage};

pub(crate) fn std_frame(id: u16, data: &[u8]) -> Frame {
    Frame::classic(CanId::Standard(id), data).unwrap()
}

pub(crate) fn message(frame: Frame, transaction_number: u16) -> MessageRepr {
    MessageRepr {
        transaction_number,
        frame,
        time_stamp: 0,
    }
}

pub(crate) fn caps() -> Capabilities {
    Capabilities::everything()
}

pub(crate) fn config(format: FrameFormat, queue: QueueMode, slots: u8) -> InterfaceConfig {
    let mut config = InterfaceConfig::new(format, slots);
    config.queue = queue;
    config
}

pub(crate) fn device(format: FrameFormat, queue: QueueMode, slots: u8) -> Device {
    Device::new(&caps(), config(format, queue, slots)).unwrap()
}

/// A PLC and a device exchanging images directly (separate input update).
pub(crate) struct Rig {
    pub device: Device,
    pub plc: PlcClient,
    pub now: u64,
    pub cycle_time: u64,
    /// Frames that completed on the bus, in order.
    pub on_bus: Vec<Frame>,
}

impl Rig {
    pub(crate) fn new(device: Device) -> Self {
        let plc = PlcClient::new(device.layout());
        Rig {
            device,
            plc,
            now: 0,
            cycle_time: 1_000_000,
            on_bus: Vec::new(),
        }
    }

    /// One task cycle: PLC task, device cycle, then up to `completions` frames on the bus.
    pub(crate) fn cycle(&mut self, completions: usize) {
        let outputs = self.plc.task(self.device.inputs()).unwrap().to_vec();
        self.device.cycle(&outputs, self.now).unwrap();
        self.transmit(completions);
        self.now += self.cycle_time;
    }

    pub(crate) fn transmit(&mut self, completions: usize) {
        for _ in 0..completions {
            match self.device.poll_transmit(self.now) {
                Some(frame) => {
                    self.on_bus.push(frame);
                    self.device.handle_transmit_complete();
                }
                None => break,
            }
        }
    }

    /// Identifiers of the messages the PLC has read so far (drains them).
    pub(crate) fn received_ids(&mut self) -> Vec<u32> {
        self.plc
            .take_received()
            .iter()
            .map(|m| m.frame.id.raw())
            .collect()
    }

    pub(crate) fn inputs(&self) -> InputImage<&[u8]> {
        InputImage::new_checked(self.device.inputs(), self.device.layout()).unwrap()
    }
}

/// Writes an output image by hand.
pub(crate) fn outputs_with(
    device: &Device,
    tx_counter: u16,
    rx_counter: u16,
    messages: &[MessageRepr],
    no_of_tx: u16,
) -> Vec<u8> {
    let layout = device.layout();
    let mut buffer = vec![0u8; layout.output_size()];
    let mut image = OutputImage::new_checked(&mut buffer[..], layout).unwrap();
    image.set_tx_counter(tx_counter);
    image.set_rx_counter(rx_counter);
    image.set_no_of_tx_messages(no_of_tx);
    for (slot, message) in messages.iter().enumerate() {
        message
            .emit(&mut image.tx_message_mut(slot).unwrap())
            .unwrap();
    }
    buffer
}

pub(crate) fn inputs_of(device: &Device) -> InputImage<&[u8]> {
    InputImage::new_checked(device.inputs(), device.layout()).unwrap()
}
