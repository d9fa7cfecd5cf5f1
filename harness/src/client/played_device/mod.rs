//! The device side of a cycle, as the harness plays it when a PLC-side client
//! is under test: the reference model device (the EL6751 of 000/001/003) with
//! its controller on the simulated bus, and the other nodes. The mirror of
//! [`crate::device::played_plc::PlcSide`]; swapping which side is the IUT swaps which of the
//! two the harness plays.

#[cfg(feature = "socketcan")]
pub(crate) mod kernel;

use canif_model::config::{Capabilities, ConfigError, InterfaceConfig};
use canif_model::device::Device;
use canif_model::frame::Frame;
use canif_model::image::{ImageLayout, SizeError};
use canif_model::timing::BitRates;
use canif_model::Nanos;

use crate::bus::sim::{Controller, SimBus};
use crate::error::{BusCause, BusError};

/// The device as the harness plays it for a client: on the simulated bus
/// ([`DeviceSide`]) or with its controller on a SocketCAN interface
/// (`crate::client::played_device::kernel::KernelDeviceSide`).
pub trait PlayedDevice {
    fn layout(&self) -> ImageLayout;
    /// Another node's frame, ready to send from `at`.
    fn schedule(&mut self, at: Nanos, frame: Frame);
    /// The bus runs to `until`; the frames that ended on it meanwhile.
    fn run_until(&mut self, until: Nanos) -> Result<Vec<Ended>, BusError>;
    /// The device's cycle on the client's outputs: the new input image.
    fn cycle(&mut self, outputs: &[u8]) -> Result<Vec<u8>, SizeError>;
    /// The device goes INIT → OP: counters, queues and the frame it was about
    /// to send are gone; the bus and the other nodes go on.
    fn restart(&mut self) -> Result<(), ConfigError>;
    /// Messages the device received and has not entered in the image.
    fn queued_rx(&self) -> usize;
}

/// A frame that ended on the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ended {
    pub frame: Frame,
    pub end: Nanos,
    /// The device sent it (else another node did).
    pub from_device: bool,
}

/// The model device on a simulated bus.
#[derive(Debug)]
pub struct DeviceSide {
    device: ModelController,
    bus: SimBus,
    caps: Capabilities,
    config: InterfaceConfig,
}

#[derive(Debug)]
struct ModelController {
    device: Device,
    now: Nanos,
    pending: Option<Frame>,
    ended: Vec<Ended>,
}

impl Controller for ModelController {
    type Error = BusError;
    fn now(&mut self) -> &mut Nanos {
        &mut self.now
    }
    fn pending(&mut self) -> &mut Option<Frame> {
        &mut self.pending
    }
    fn poll(&mut self) -> Result<(), BusError> {
        if self.pending.is_none() {
            self.pending = self.device.poll_transmit(self.now);
        }
        Ok(())
    }
    fn due(&self) -> Option<Nanos> {
        self.device.poll_timeout()
    }
    fn ended(&mut self, frame: Frame, own: bool, end: Nanos) -> Result<(), BusError> {
        if own {
            self.device.handle_transmit_complete();
        } else {
            self.device.handle_received(frame, end);
        }
        self.ended.push(Ended {
            frame,
            end,
            from_device: own,
        });
        Ok(())
    }
    fn stalled(&self, steps: usize) -> BusError {
        BusError::new(
            BusCause::PlayedDevice,
            format!("the model device took {steps} bus events in one cycle (a harness bug)"),
        )
    }
}

impl DeviceSide {
    pub fn new(
        caps: &Capabilities,
        config: InterfaceConfig,
        bit_rates: BitRates,
    ) -> Result<Self, ConfigError> {
        Ok(DeviceSide {
            device: ModelController {
                device: Device::new(caps, config.clone())?,
                now: 0,
                pending: None,
                ended: Vec::new(),
            },
            bus: SimBus::new(bit_rates),
            caps: caps.clone(),
            config,
        })
    }
}

impl PlayedDevice for DeviceSide {
    fn layout(&self) -> ImageLayout {
        self.device.device.layout()
    }

    fn schedule(&mut self, at: Nanos, frame: Frame) {
        self.bus.schedule(at, frame);
    }

    fn run_until(&mut self, until: Nanos) -> Result<Vec<Ended>, BusError> {
        self.bus.drive(&mut self.device, until)?;
        Ok(std::mem::take(&mut self.device.ended))
    }

    fn cycle(&mut self, outputs: &[u8]) -> Result<Vec<u8>, SizeError> {
        let now = self.device.now;
        self.device.device.cycle(outputs, now).map(<[u8]>::to_vec)
    }

    fn restart(&mut self) -> Result<(), ConfigError> {
        self.device.device = Device::new(&self.caps, self.config.clone())?;
        self.device.pending = None;
        self.bus.abort_own();
        Ok(())
    }

    fn queued_rx(&self) -> usize {
        self.device.device.queued_rx()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canif_model::client::PlcClient;
    use canif_model::config::FrameFormat;
    use canif_model::frame::CanId;
    use canif_model::image::MessageRepr;

    #[test]
    fn the_reference_client_and_the_device_side_carry_frames_both_ways() {
        let config = InterfaceConfig::new(FrameFormat::Base11, 4);
        let mut device = DeviceSide::new(
            &Capabilities::everything(),
            config,
            BitRates::classic(500_000),
        )
        .unwrap();
        let mut plc = PlcClient::new(device.layout());
        let mut inputs = vec![0; device.layout().input_size()];
        let sent = Frame::classic(CanId::Standard(0x123), &[1, 2, 3]).unwrap();
        let arriving = Frame::classic(CanId::Standard(0x456), &[9]).unwrap();
        plc.send(MessageRepr {
            transaction_number: 0,
            frame: sent,
            time_stamp: 0,
        })
        .unwrap();
        device.schedule(300_000, arriving);
        let (mut on_bus, mut read) = (Vec::new(), Vec::new());
        for k in 0..5u64 {
            on_bus.extend(device.run_until(k * 1_000_000).unwrap());
            let outputs = plc.task(&inputs).unwrap().to_vec();
            inputs = device.cycle(&outputs).unwrap().to_vec();
            read.extend(plc.take_received().into_iter().map(|m| m.frame));
        }
        let from_device: Vec<Frame> = on_bus
            .iter()
            .filter(|e| e.from_device)
            .map(|e| e.frame)
            .collect();
        assert_eq!(from_device, [sent]);
        assert_eq!(read, [arriving]);
    }
}
