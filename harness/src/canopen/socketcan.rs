//! A CANopen node on a SocketCAN interface, checked in real time.

use canif_model::canopen::cob_id::{default_cob_id, Channel};
use canif_model::canopen::NodeId;
use canif_model::frame::{CanId, Frame};
use canif_model::Nanos;

use super::CanNode;

/// A CANopen node on a SocketCAN interface, checked in real time: `now` is
/// time since the node was opened; requests go out when their time has come.
pub struct SocketCanNode {
    socket: canif_kernel::KernelSocket,
    epoch: Nanos,
    /// How long to wait for the first answer to a request.
    pub answer_timeout: std::time::Duration,
    /// Frames that came but answered nothing (heartbeats, emergencies), for `poll`.
    backlog: Vec<Frame>,
    node: NodeId,
}

impl SocketCanNode {
    pub fn open(interface: &str, node: NodeId) -> Result<Self, String> {
        canif_kernel::probe()?;
        Ok(SocketCanNode {
            socket: canif_kernel::KernelSocket::open(interface, false)?,
            epoch: canif_kernel::realtime_ns(),
            answer_timeout: std::time::Duration::from_millis(200),
            backlog: Vec::new(),
            node,
        })
    }

    /// Real time catches up with `now`; when real time is already past it
    /// (answers take real time the checks do not count), the time base slips,
    /// so that intervals from here on are real.
    fn wait_until(&mut self, now: Nanos) {
        let real = canif_kernel::realtime_ns();
        let at = self.epoch + now;
        if at > real {
            std::thread::sleep(std::time::Duration::from_nanos(at - real));
        } else {
            self.epoch = real - now;
        }
    }

    fn drain(&mut self) -> Vec<Frame> {
        let mut frames = Vec::new();
        while let Ok(Some(received)) = self.socket.recv() {
            if let canif_kernel::Received::Frame { frame, .. } = received {
                frames.push(frame);
            }
        }
        frames
    }

    /// The identifier a request's answer comes on, if it has one.
    fn answer_id(&self, request: &Frame) -> Option<CanId> {
        let sdo_request = CanId::Standard(default_cob_id(Channel::SdoRequest, self.node));
        match request.id {
            CanId::Standard(0) => None, // NMT commands are not answered
            id if id == sdo_request => Some(CanId::Standard(default_cob_id(
                Channel::SdoResponse,
                self.node,
            ))),
            id if request.is_remote() => Some(id),
            _ => None,
        }
    }
}

impl CanNode for SocketCanNode {
    fn handle(&mut self, frame: &Frame, now: Nanos) -> Vec<Frame> {
        self.wait_until(now);
        let stale = self.drain();
        self.backlog.extend(stale);
        if self.socket.send(frame).is_err() {
            return Vec::new();
        }
        let Some(answer_id) = self.answer_id(frame) else {
            // Give the node a moment to act on an unanswered command.
            std::thread::sleep(std::time::Duration::from_millis(20));
            return Vec::new();
        };
        let started = std::time::Instant::now();
        let mut answers = Vec::new();
        let mut quiet_since: Option<std::time::Instant> = None;
        loop {
            for received in self.drain() {
                if received.id == answer_id {
                    answers.push(received);
                    quiet_since = Some(std::time::Instant::now());
                } else {
                    self.backlog.push(received);
                }
            }
            // After the first answer, a short quiet time shows whether a second one follows.
            let done = match quiet_since {
                Some(t) => t.elapsed() > std::time::Duration::from_millis(10),
                None => started.elapsed() > self.answer_timeout,
            };
            if done {
                return answers;
            }
            let _ = canif_kernel::KernelSocket::wait(
                &[&self.socket],
                std::time::Duration::from_millis(2),
            );
        }
    }

    fn poll(&mut self, now: Nanos) -> Vec<Frame> {
        self.wait_until(now);
        let mut frames = std::mem::take(&mut self.backlog);
        frames.extend(self.drain());
        frames
    }
}
