//! `canif device --stdio --bus socketcan:IFACE`: the served device's CAN side
//! on a SocketCAN interface, while its process image goes over the protocol.

use std::time::Duration;

use canif_kernel::{KernelSocket, Received};
use canif_model::frame::Frame;
use canif_model::Nanos;

use super::device::{write_answer, Build, Server};
use crate::door::adapter::protocol::{Answer, Request};
use crate::door::iut::Iut;
use crate::error::{BusCause, BusError};

/// The device's controller on a SocketCAN interface (also the CAN side of
/// the emulated EtherCAT terminal, `canif device --ethercat … --bus …`).
pub(crate) struct DeviceBus {
    socket: KernelSocket,
    epoch: Nanos,
    /// The frame the controller is sending, and whether the kernel took it.
    sending: Option<Frame>,
    written: bool,
}

impl DeviceBus {
    pub(crate) fn open(interface: &str, epoch: Nanos) -> Result<Self, String> {
        canif_kernel::probe()?;
        Ok(DeviceBus {
            socket: KernelSocket::open(interface, true)?,
            epoch,
            sending: None,
            written: false,
        })
    }

    fn now(&self) -> Nanos {
        canif_kernel::realtime_ns().saturating_sub(self.epoch)
    }

    /// The controller's interrupts: frames received (with the kernel's time
    /// stamp), the frame sent confirmed, the next one started.
    pub(crate) fn pump(&mut self, iut: &mut dyn Iut) -> Result<(), BusError> {
        let name = &self.socket.interface;
        while let Some(received) = self
            .socket
            .recv()
            .map_err(|e| BusError::new(BusCause::Io, format!("{name}: {e}")))?
        {
            match received {
                Received::Frame {
                    frame,
                    at,
                    own: false,
                } => iut
                    .receive(&frame, at.saturating_sub(self.epoch))
                    .map_err(device_broke)?,
                Received::Frame { own: true, .. } => {
                    self.sending = None;
                    self.written = false;
                    iut.transmit_complete().map_err(device_broke)?;
                }
                Received::Error { .. } => {}
            }
        }
        loop {
            let frame = match (self.sending, self.written) {
                (Some(_), true) => return Ok(()),
                (Some(frame), false) => frame,
                (None, _) => match iut.poll_transmit(self.now()).map_err(device_broke)? {
                    None => return Ok(()),
                    Some(Err(invalid)) => {
                        eprintln!(
                            "{name}: the device produced an invalid frame, not sent: {invalid}"
                        );
                        continue;
                    }
                    Some(Ok(frame)) => frame,
                },
            };
            self.sending = Some(frame);
            match self.socket.send(&frame) {
                Ok(()) => self.written = true,
                // The queue is full: the frame goes out on a later pump.
                Err(error) if error.raw_os_error() == Some(canif_kernel::ENOBUFS) => {
                    self.written = false;
                    return Ok(());
                }
                Err(error) => return Err(BusError::new(BusCause::Io, format!("{name}: {error}"))),
            }
        }
    }
}

fn device_broke(error: crate::error::IutError) -> BusError {
    BusError::new(BusCause::PlayedDevice, format!("the device broke: {error}"))
}

/// Serves an in-process IUT over the adapter protocol on stdin/stdout with its
/// CAN side on a SocketCAN interface. The interface is the one
/// `configure.bus.socketcan` names, else `interface`.
pub fn serve_on_bus(build: &Build<'_>, interface: Option<&str>) -> Result<(), BusError> {
    let (lines, requests) = std::sync::mpsc::channel::<String>();
    std::thread::spawn(move || {
        for line in std::io::stdin().lines().map_while(Result::ok) {
            if lines.send(line).is_err() {
                break;
            }
        }
    });
    let mut output = std::io::stdout();
    let io = |e: std::io::Error| BusError::new(BusCause::Io, format!("stdout: {e}"));
    // The CAN side is the interface's own: one request per cycle is protocol 1.
    let mut server = Server::new(build, false).at_most(1);
    let mut bus: Option<DeviceBus> = None;
    loop {
        let line = match requests.recv_timeout(Duration::from_micros(500)) {
            Ok(line) => Some(line),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => None,
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => return Ok(()),
        };
        if let (Some(bus), Some(device)) = (bus.as_mut(), server.iut()) {
            // Frames the kernel delivered before a request count as received before it.
            bus.pump(device)?;
        }
        let Some(line) = line.filter(|l| !l.trim().is_empty()) else {
            continue;
        };
        let request = match Server::parse_line(&line) {
            Ok(request) => request,
            Err(answer) => {
                write_answer(&mut output, &answer).map_err(io)?;
                continue;
            }
        };
        let Some(mut reply) = server.answer(&request) else {
            return Ok(());
        };
        if let (Request::Configure { bus: asked, .. }, Some(_)) = (&request, server.iut()) {
            let name = asked.as_ref().map(|b| b.interface.as_str()).or(interface);
            let epoch = asked.as_ref().map_or(0, |b| b.epoch_ns);
            bus = None;
            match name.map(|name| DeviceBus::open(name, epoch)) {
                Some(Ok(opened)) => bus = Some(opened),
                Some(Err(error)) => reply = Answer::error(error),
                None => {
                    reply = Answer::error(
                        "no SocketCAN interface: start with --bus socketcan:IFACE or send configure.bus",
                    )
                }
            }
        }
        write_answer(&mut output, &reply).map_err(io)?;
        if let (Some(bus), Some(device)) = (bus.as_mut(), server.iut()) {
            bus.pump(device)?;
        }
    }
}
