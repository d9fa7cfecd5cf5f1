//! The device the harness plays for a client, with its controller on a Linux
//! SocketCAN interface: the model device's frames and the other nodes' cross
//! the kernel's CAN stack. One socket is the device's controller, another the
//! other nodes; each frame is waited for on the far side before the next
//! goes, so a run is as deterministic as on the simulated bus (the device's
//! time stays the scenario's, the kernel carries the frames).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use canif_kernel::{KernelSocket, Received};
use canif_model::config::{Capabilities, ConfigError, InterfaceConfig};
use canif_model::device::Device;
use canif_model::frame::Frame;
use canif_model::image::{ImageLayout, SizeError};
use canif_model::Nanos;

use crate::client::played_device::{Ended, PlayedDevice};
use crate::error::{BusCause, BusError};

pub(crate) struct KernelDeviceSide {
    device: Device,
    caps: Capabilities,
    config: InterfaceConfig,
    controller: KernelSocket,
    nodes: KernelSocket,
    scheduled: VecDeque<(Nanos, Frame)>,
    now: Nanos,
    timeout: Duration,
}

impl KernelDeviceSide {
    /// The model device's controller and the other nodes, both on `interface`.
    pub(crate) fn open(
        caps: &Capabilities,
        config: InterfaceConfig,
        interface: &str,
        timeout: Duration,
    ) -> Result<Self, String> {
        let device = Device::new(caps, config.clone()).map_err(|e| e.to_string())?;
        let controller = KernelSocket::open(interface, false)?;
        let nodes = KernelSocket::open(interface, false)?;
        Ok(KernelDeviceSide {
            device,
            caps: caps.clone(),
            config,
            controller,
            nodes,
            scheduled: VecDeque::new(),
            now: 0,
            timeout,
        })
    }

    /// Sends `frame` from one socket and waits until the other has it.
    fn cross(&self, from_device: bool, frame: &Frame) -> Result<(), BusError> {
        let (sender, receiver) = if from_device {
            (&self.controller, &self.nodes)
        } else {
            (&self.nodes, &self.controller)
        };
        let error =
            |what: String| BusError::new(BusCause::Io, format!("{}: {what}", sender.interface));
        let deadline = Instant::now() + self.timeout;
        loop {
            match sender.send(frame) {
                Ok(()) => break,
                Err(e) if e.raw_os_error() == Some(canif_kernel::ENOBUFS) => {
                    if Instant::now() > deadline {
                        return Err(error("the send queue stayed full".into()));
                    }
                    std::thread::sleep(Duration::from_micros(200));
                }
                Err(e) => return Err(error(format!("cannot send {frame}: {e}"))),
            }
        }
        loop {
            match receiver.recv().map_err(|e| error(e.to_string()))? {
                Some(Received::Frame { frame: got, .. }) if got == *frame => return Ok(()),
                Some(Received::Frame { frame: got, .. }) => {
                    return Err(error(format!("sent {frame}, the far side read {got}")))
                }
                Some(Received::Error { class, .. }) => {
                    return Err(error(format!(
                        "the driver reported error class 0x{class:X}"
                    )))
                }
                None => {
                    let left = deadline.saturating_duration_since(Instant::now());
                    if left.is_zero() {
                        return Err(error(format!(
                            "{frame} did not arrive within {:?}",
                            self.timeout
                        )));
                    }
                    KernelSocket::wait(&[receiver], left).map_err(|e| error(e.to_string()))?;
                }
            }
        }
    }
}

impl PlayedDevice for KernelDeviceSide {
    fn layout(&self) -> ImageLayout {
        self.device.layout()
    }

    fn schedule(&mut self, at: Nanos, frame: Frame) {
        self.scheduled.push_back((at, frame));
    }

    fn run_until(&mut self, until: Nanos) -> Result<Vec<Ended>, BusError> {
        let mut ended = Vec::new();
        while let Some(&(at, frame)) = self.scheduled.front().filter(|(at, _)| *at <= until) {
            self.scheduled.pop_front();
            self.cross(false, &frame)?;
            let end = at.max(self.now);
            self.device.handle_received(frame, end);
            ended.push(Ended {
                frame,
                end,
                from_device: false,
            });
        }
        self.now = until;
        // A frame held for SYNC1 goes in the run that reaches its time.
        while let Some(frame) = self.device.poll_transmit(until) {
            self.cross(true, &frame)?;
            self.device.handle_transmit_complete();
            ended.push(Ended {
                frame,
                end: until,
                from_device: true,
            });
        }
        Ok(ended)
    }

    fn cycle(&mut self, outputs: &[u8]) -> Result<Vec<u8>, SizeError> {
        self.device.cycle(outputs, self.now).map(<[u8]>::to_vec)
    }

    fn restart(&mut self) -> Result<(), ConfigError> {
        self.device = Device::new(&self.caps, self.config.clone())?;
        Ok(())
    }

    fn queued_rx(&self) -> usize {
        self.device.queued_rx()
    }
}
