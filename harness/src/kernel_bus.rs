//! The harness's bus on a Linux SocketCAN interface, in real time.
//!
//! Two ways to sit on it:
//! - **attached**: an in-process IUT (the soft device, the model) gets a
//!   socket of its own on the IUT interface; the harness hands it what that
//!   socket receives (with the kernel's time stamp) and writes what it sends,
//!   completing a transmission when the kernel echoes it back.
//! - **owned**: an external IUT (`exec:`) opens its own socket; the harness
//!   sees its frames only as another node does, on the tester interface.
//!
//! Either way the harness plays the other nodes on the tester socket and the
//! model is fed the same events, at the times the kernel stamped them.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use canif_kernel::{BusSpec, KernelSocket};
use canif_model::frame::{Frame, FrameKind};
use canif_model::Nanos;

/// How scenarios run on a SocketCAN bus.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KernelBusOptions {
    pub spec: BusSpec,
    /// The real cycle time (scenario offsets are scaled to it).
    pub cycle_time: Nanos,
    /// How far the IUT's receive time stamps may be from the harness's.
    pub time_stamp_tolerance: Nanos,
    /// How long a frame may take to cross the kernel before the run is an error.
    pub timeout: Duration,
    /// Whether the bus carries remote frames. QEMU's emulated SJA1000 garbles
    /// every frame after a remote frame with a length, so the kernel lane runs
    /// the controller pair with the scenarios' remote frames sent as data frames.
    pub remote_frames: bool,
    /// Whether a sender sets the ESI bit of an FD frame. A real CAN FD
    /// controller sends its own error state there (the CTU CAN FD driver
    /// ignores CANFD_ESI on transmit), so on one the scenarios' ESI is left out.
    pub esi_settable: bool,
}

impl KernelBusOptions {
    /// `frame` as this bus can carry it: a remote frame becomes a data frame
    /// of its length (zeros) where remote frames are off; an FD frame loses its
    /// ESI where the controller sets it.
    pub fn adapt(&self, frame: Frame) -> Frame {
        match frame.kind {
            FrameKind::Classic { rtr: true } if !self.remote_frames => {
                Frame::classic(frame.id, &vec![0; usize::from(frame.len().min(8))]).unwrap_or(frame)
            }
            FrameKind::Fd { brs, esi: true } if !self.esi_settable => {
                Frame::fd(frame.id, brs, false, frame.data()).unwrap_or(frame)
            }
            _ => frame,
        }
    }

    pub fn new(spec: BusSpec) -> Self {
        KernelBusOptions {
            spec,
            cycle_time: 2_000_000,
            time_stamp_tolerance: 1_000_000,
            timeout: Duration::from_secs(2),
            remote_frames: true,
            esi_settable: true,
        }
    }
}

/// Before a scenario on an attached bus: the other nodes send a marker frame
/// until the IUT's socket has it, and everything before it is dropped. What a
/// previous scenario left on the bus (or a frame a driver held back) must not
/// reach this one's IUT. The IUT never sees the markers.
fn synchronize(iut: &KernelSocket, tester: &KernelSocket, timeout: Duration) -> Result<(), String> {
    let marker =
        Frame::classic(canif_model::frame::CanId::Standard(0x7FF), b"canif-sy").expect("8 bytes");
    let started = Instant::now();
    let drain = |socket: &KernelSocket| -> Result<Vec<Frame>, String> {
        let mut frames = Vec::new();
        while let Some(received) = socket
            .recv()
            .map_err(|e| format!("{}: {e}", socket.interface))?
        {
            if let canif_kernel::Received::Frame { frame, .. } = received {
                frames.push(frame);
            }
        }
        Ok(frames)
    };
    while started.elapsed() < timeout {
        match tester.send(&marker) {
            Ok(()) => {}
            Err(e) if e.raw_os_error() == Some(canif_kernel::ENOBUFS) => {}
            Err(e) => return Err(format!("{}: {e}", tester.interface)),
        }
        let sent = Instant::now();
        while sent.elapsed() < Duration::from_millis(50) {
            let _ = KernelSocket::wait(&[iut], Duration::from_millis(5));
            if drain(iut)?.contains(&marker) {
                // Markers still on their way arrive within a moment; drop them too.
                std::thread::sleep(Duration::from_millis(20));
                drain(iut)?;
                drain(tester)?;
                return Ok(());
            }
        }
    }
    Err(format!(
        "no frame from {} reached {} within {timeout:?} (bus down, or nothing acknowledges)",
        tester.interface, iut.interface
    ))
}

/// The frame [`synchronize`] sends; one that a driver held back and delivers
/// late is dropped by the harness too.
pub fn marker() -> Frame {
    Frame::classic(canif_model::frame::CanId::Standard(0x7FF), b"canif-sy").expect("8 bytes")
}

/// Where the IUT sits on the kernel bus.
pub(crate) enum Side {
    Attached(KernelSocket),
    Owned,
}

/// A frame written to a socket, waiting to show up on the other side.
pub(crate) struct InFlight {
    pub frame: Frame,
    pub since: Instant,
}

pub(crate) struct KernelBus {
    pub options: KernelBusOptions,
    pub side: Side,
    pub tester: KernelSocket,
    /// CLOCK_REALTIME at scenario time 0.
    pub epoch: Nanos,
    /// Other nodes' frames not yet written, by the time they are due.
    pub waiting: VecDeque<(Nanos, Frame)>,
    /// Since when, and on which interface, a write has answered ENOBUFS.
    pub blocked_since: Option<(Instant, String)>,
    /// Written by the tester, not yet seen by the IUT's socket (attached) or
    /// echoed (owned).
    pub tester_in_flight: VecDeque<InFlight>,
    /// Attached: the IUT's frame written, not yet echoed.
    pub iut_in_flight: Option<InFlight>,
    /// Attached: IUT frames echoed, not yet seen on the tester socket.
    pub crossing: VecDeque<InFlight>,
    /// Owned: the model's frame waiting for the IUT to send it.
    pub model_next: Option<(Frame, Nanos)>,
    /// The driver's last error frame, described, for messages.
    pub last_error: Option<String>,
}

impl KernelBus {
    /// Opens the sockets; `owned`: the IUT opens its own.
    pub fn open(options: &KernelBusOptions, owned: bool) -> Result<Self, String> {
        canif_kernel::probe()?;
        let side = if owned {
            Side::Owned
        } else {
            Side::Attached(KernelSocket::open(&options.spec.iut, true)?)
        };
        let tester = KernelSocket::open(&options.spec.tester, owned)?;
        match &side {
            Side::Attached(iut) => synchronize(iut, &tester, options.timeout)?,
            // Before the IUT opens its socket: a socket of the harness's own stands in.
            Side::Owned => synchronize(
                &KernelSocket::open(&options.spec.iut, false)?,
                &tester,
                options.timeout,
            )?,
        }
        Ok(KernelBus {
            options: options.clone(),
            side,
            tester,
            epoch: canif_kernel::realtime_ns(),
            waiting: VecDeque::new(),
            blocked_since: None,
            tester_in_flight: VecDeque::new(),
            iut_in_flight: None,
            crossing: VecDeque::new(),
            model_next: None,
            last_error: None,
        })
    }

    pub fn now(&self) -> Nanos {
        canif_kernel::realtime_ns().saturating_sub(self.epoch)
    }

    /// Scenario time `t` has come in real time.
    pub fn reached(&self, t: Nanos) -> bool {
        self.now() >= t
    }

    pub fn schedule(&mut self, at: Nanos, frame: Frame) {
        let index = self.waiting.partition_point(|(t, _)| *t <= at);
        self.waiting.insert(index, (at, frame));
    }

    /// A write on `interface` answered ENOBUFS (the first time counts).
    pub fn blocked(&mut self, interface: String) {
        self.blocked_since
            .get_or_insert_with(|| (Instant::now(), interface));
    }

    /// Nothing written is still on its way, and (owned) the IUT has sent what
    /// the model says is due: the IUT acts on a cycle before the next one.
    pub fn settled(&self) -> bool {
        self.tester_in_flight.is_empty()
            && self.iut_in_flight.is_none()
            && self.crossing.is_empty()
            && self.model_next.is_none()
    }

    /// How many of the other nodes' frames may be on their way at once. Two
    /// controllers are paced one frame at a time: a burst would overrun the
    /// receiving controller's FIFO when its driver is slow (as under emulation),
    /// which a real bus paces by its bit rate.
    pub fn window(&self) -> usize {
        if self.options.spec.iut == self.options.spec.tester {
            256
        } else {
            1
        }
    }

    /// A frame that has been on its way longer than the timeout, described.
    pub fn overdue(&self) -> Option<String> {
        let late = |f: &InFlight| f.since.elapsed() > self.options.timeout;
        let (iut, tester) = (&self.options.spec.iut, &self.options.spec.tester);
        if let Some(f) = self.tester_in_flight.front().filter(|f| late(f)) {
            return Some(format!(
                "{} written on {tester} did not arrive on {iut} within {:?}",
                f.frame, self.options.timeout
            ));
        }
        if let Some(f) = self.iut_in_flight.as_ref().filter(|f| late(f)) {
            return Some(format!(
                "{} written on {iut} was not confirmed as sent within {:?} (no ACK on the bus, bus-off, or the interface is down)",
                f.frame, self.options.timeout
            ));
        }
        if let Some(f) = self.crossing.front().filter(|f| late(f)) {
            return Some(format!(
                "{} sent on {iut} did not arrive on {tester} within {:?}",
                f.frame, self.options.timeout
            ));
        }
        if let Some((since, interface)) = self
            .blocked_since
            .as_ref()
            .filter(|(since, _)| since.elapsed() > self.options.timeout)
        {
            return Some(format!(
                "{interface}: the send buffer stayed full (ENOBUFS) for {:?}",
                since.elapsed()
            ));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canif_model::frame::CanId;

    #[test]
    fn without_remote_frames_a_remote_frame_goes_as_data_of_its_length() {
        let mut options = KernelBusOptions::new(BusSpec::parse("socketcan:can0,can1").unwrap());
        let remote = Frame::remote(CanId::Standard(0x285), 8).unwrap();
        let data = Frame::classic(CanId::Standard(0x185), &[1, 2]).unwrap();
        assert_eq!(options.adapt(remote), remote);
        options.remote_frames = false;
        assert_eq!(
            options.adapt(remote),
            Frame::classic(CanId::Standard(0x285), &[0; 8]).unwrap()
        );
        assert_eq!(options.adapt(data), data);
        let esi = Frame::fd(CanId::Extended(0x1234), true, true, &[7; 12]).unwrap();
        assert_eq!(options.adapt(esi), esi);
        options.esi_settable = false;
        assert_eq!(
            options.adapt(esi),
            Frame::fd(CanId::Extended(0x1234), true, false, &[7; 12]).unwrap()
        );
    }
}
