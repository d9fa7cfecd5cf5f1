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

use canif_kernel::{BusSpec, KernelSocket, Received};
use canif_model::frame::{Frame, FrameKind};
use canif_model::Nanos;

use super::Bus;
use crate::device::blame;
use crate::device::diff::{hex, Difference};
use crate::device::pair::Pair;
use crate::door::adapter::protocol::OwnedBus;
use crate::error::{BusCause, BusError};
use crate::outcome::Outcome;

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

/// The frame `synchronize` sends; one that a driver held back and delivers
/// late is dropped by the harness too.
pub fn marker() -> Frame {
    Frame::classic(canif_model::frame::CanId::Standard(0x7FF), b"canif-sy").expect("8 bytes")
}

/// Where the IUT sits on the kernel bus.
enum IutEnd {
    Attached(KernelSocket),
    Owned,
}

/// A frame written to a socket, waiting to show up on the other side.
struct InFlight {
    frame: Frame,
    since: Instant,
}

pub struct KernelBus {
    options: KernelBusOptions,
    iut_end: IutEnd,
    tester: KernelSocket,
    /// CLOCK_REALTIME at scenario time 0.
    epoch: Nanos,
    /// Other nodes' frames not yet written, by the time they are due.
    waiting: VecDeque<(Nanos, Frame)>,
    /// Since when, and on which interface, a write has answered ENOBUFS.
    blocked_since: Option<(Instant, String)>,
    /// Written by the tester, not yet seen by the IUT's socket (attached) or
    /// echoed (owned).
    tester_in_flight: VecDeque<InFlight>,
    /// Attached: the IUT's frame written, not yet echoed.
    iut_in_flight: Option<InFlight>,
    /// Attached: IUT frames echoed, not yet seen on the tester socket.
    crossing: VecDeque<InFlight>,
    /// Owned: the model's frame waiting for the IUT to send it.
    model_next: Option<(Frame, Nanos)>,
    /// The driver's last error frame, described, for messages.
    last_error: Option<String>,
}

impl KernelBus {
    /// Opens the sockets; `owned`: the IUT opens its own.
    pub fn open(options: &KernelBusOptions, owned: bool) -> Result<Self, BusError> {
        Self::open_sockets(options, owned).map_err(|e| BusError::new(BusCause::Unavailable, e))
    }

    fn open_sockets(options: &KernelBusOptions, owned: bool) -> Result<Self, String> {
        canif_kernel::probe()?;
        let side = if owned {
            IutEnd::Owned
        } else {
            IutEnd::Attached(KernelSocket::open(&options.spec.iut, true)?)
        };
        let tester = KernelSocket::open(&options.spec.tester, owned)?;
        match &side {
            IutEnd::Attached(iut) => synchronize(iut, &tester, options.timeout)?,
            // Before the IUT opens its socket: a socket of the harness's own stands in.
            IutEnd::Owned => synchronize(
                &KernelSocket::open(&options.spec.iut, false)?,
                &tester,
                options.timeout,
            )?,
        }
        Ok(KernelBus {
            options: options.clone(),
            iut_end: side,
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

    fn now(&self) -> Nanos {
        canif_kernel::realtime_ns().saturating_sub(self.epoch)
    }

    /// Scenario time `t` has come in real time.
    fn reached(&self, t: Nanos) -> bool {
        self.now() >= t
    }

    /// A write on `interface` answered ENOBUFS (the first time counts).
    fn blocked(&mut self, interface: String) {
        self.blocked_since
            .get_or_insert_with(|| (Instant::now(), interface));
    }

    /// Nothing written is still on its way, and (owned) the IUT has sent what
    /// the model says is due: the IUT acts on a cycle before the next one.
    fn settled(&self) -> bool {
        self.tester_in_flight.is_empty()
            && self.iut_in_flight.is_none()
            && self.crossing.is_empty()
            && self.model_next.is_none()
    }

    /// How many of the other nodes' frames may be on their way at once. Two
    /// controllers are paced one frame at a time: a burst would overrun the
    /// receiving controller's FIFO when its driver is slow (as under emulation),
    /// which a real bus paces by its bit rate.
    fn window(&self) -> usize {
        if self.options.spec.iut == self.options.spec.tester {
            256
        } else {
            1
        }
    }

    /// A frame that has been on its way longer than the timeout, described.
    fn overdue(&self) -> Option<String> {
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

/// `frame` came as the next of `queue` (frames on their way, in order): it
/// leaves the queue. `false` when something else was expected.
fn arrived(queue: &mut VecDeque<InFlight>, frame: Frame) -> bool {
    let next = queue.front().is_some_and(|f| f.frame == frame);
    if next {
        queue.pop_front();
    }
    next
}

fn bus_error(message: String) -> Outcome {
    Outcome::Error(BusError::new(BusCause::Io, message).into())
}

impl Bus for KernelBus {
    fn schedule(&mut self, at: Nanos, frame: Frame) {
        let index = self.waiting.partition_point(|(t, _)| *t <= at);
        self.waiting.insert(index, (at, frame));
    }

    /// Runs the SocketCAN bus in real time up to scenario time `until`: writes
    /// the other nodes' frames when due, hands the IUT what its socket gets,
    /// sends what it sends, and returns once everything written has arrived.
    fn run_until(&mut self, pair: &mut Pair, until: Nanos) -> Result<(), Outcome> {
        let owned = matches!(self.iut_end, IutEnd::Owned);
        loop {
            pair.now = pair.now.max(self.now());
            if !owned && self.iut_in_flight.is_none() {
                pair.poll()?;
                if let Some(frame) = pair.iut_pending.take() {
                    self.send_iut(pair, frame)?;
                }
            }
            self.send_due()?;
            self.read(pair, owned)?;
            if owned {
                self.model_waits(pair)?;
            }
            if let Some(why) = self.overdue() {
                return Err(bus_error(why));
            }
            let due_now = self.waiting.front().is_some_and(|(t, _)| *t <= until);
            if self.reached(until) && self.settled() && !due_now {
                pair.now = pair.now.max(until);
                return Ok(());
            }
            let wait =
                Duration::from_nanos(until.saturating_sub(self.now()).clamp(50_000, 1_000_000));
            let result = match &self.iut_end {
                IutEnd::Attached(iut) => KernelSocket::wait(&[iut, &self.tester], wait),
                IutEnd::Owned => KernelSocket::wait(&[&self.tester], wait),
            };
            if let Err(error) = result {
                return Err(bus_error(format!("poll on the CAN sockets: {error}")));
            }
        }
    }

    fn cycle_time(&self) -> Option<Nanos> {
        Some(self.options.cycle_time)
    }

    fn time_stamp_tolerance(&self) -> Nanos {
        self.options.time_stamp_tolerance
    }

    fn real_time(&self) -> bool {
        true
    }

    fn adapt(&self, frame: Frame) -> Frame {
        self.options.adapt(frame)
    }

    fn interface_name(&self) -> String {
        self.options.spec.iut.clone()
    }

    fn owned_bus(&self) -> Option<OwnedBus> {
        matches!(self.iut_end, IutEnd::Owned).then(|| OwnedBus {
            interface: self.options.spec.iut.clone(),
            epoch_ns: self.epoch,
        })
    }
}

impl KernelBus {
    fn error(&self, interface: &str, error: std::io::Error) -> Outcome {
        bus_error(format!(
            "{interface}: {error} (while {})",
            if self.settled() {
                "idle"
            } else {
                "frames were on their way"
            }
        ))
    }

    /// Writes the IUT's frame on its socket; a full queue (ENOBUFS) keeps it
    /// pending for the next turn, as for the other nodes.
    fn send_iut(&mut self, pair: &mut Pair, frame: Frame) -> Result<(), Outcome> {
        let IutEnd::Attached(socket) = &self.iut_end else {
            return Ok(());
        };
        match socket.send(&frame) {
            Ok(()) => {}
            Err(error) if error.raw_os_error() == Some(canif_kernel::ENOBUFS) => {
                let name = socket.interface.clone();
                self.blocked(name);
                pair.iut_pending = Some(frame);
                return Ok(());
            }
            Err(error) => {
                let name = socket.interface.clone();
                return Err(self.error(&name, error));
            }
        }
        self.blocked_since = None;
        let since = Instant::now();
        self.iut_in_flight = Some(InFlight { frame, since });
        // On one interface the other nodes may see it before the IUT's echo.
        self.crossing.push_back(InFlight { frame, since });
        Ok(())
    }

    /// Writes the other nodes' frames that are due.
    fn send_due(&mut self) -> Result<(), Outcome> {
        loop {
            let now = self.now();
            let Some((at, frame)) = self.waiting.front().cloned() else {
                return Ok(());
            };
            if at > now || self.tester_in_flight.len() >= self.window() {
                return Ok(());
            }
            match self.tester.send(&frame) {
                Ok(()) => {
                    self.waiting.pop_front();
                    self.blocked_since = None;
                    self.tester_in_flight.push_back(InFlight {
                        frame,
                        since: Instant::now(),
                    });
                }
                Err(error) if error.raw_os_error() == Some(canif_kernel::ENOBUFS) => {
                    let name = self.tester.interface.clone();
                    self.blocked(name);
                    return Ok(()); // the queue drains; overdue() ends a stuck run
                }
                Err(error) => {
                    let name = self.tester.interface.clone();
                    return Err(self.error(&name, error));
                }
            }
        }
    }

    /// The next thing a socket received: (on the IUT's socket, what).
    fn next_received(&self) -> Result<Option<(bool, Received)>, Outcome> {
        if let IutEnd::Attached(socket) = &self.iut_end {
            match socket.recv() {
                Ok(Some(received)) => return Ok(Some((true, received))),
                Ok(None) => {}
                Err(e) => return Err(self.error(&socket.interface, e)),
            }
        }
        match self.tester.recv() {
            Ok(received) => Ok(received.map(|r| (false, r))),
            Err(e) => Err(self.error(&self.tester.interface, e)),
        }
    }

    /// What arrived on `side` does not match what was on its way.
    fn mismatch(&self, frame: Frame, expected: Option<&InFlight>, side: &str) -> Outcome {
        bus_error(format!(
            "the kernel delivered {frame} on {side}, but {} ({}{})",
            expected.map_or("nothing was on its way".to_string(), |f| format!(
                "{} was on its way",
                f.frame
            )),
            self.options.spec.describe(),
            self.last_error
                .as_ref()
                .map_or(String::new(), |e| format!("; {e}"))
        ))
    }

    /// Reads both sockets dry and turns what arrived into bus events.
    fn read(&mut self, pair: &mut Pair, owned: bool) -> Result<(), Outcome> {
        loop {
            let Some((on_iut_socket, received)) = self.next_received()? else {
                return Ok(());
            };
            let (frame, at, own) = match received {
                Received::Frame { frame, at, own } => (frame, at.saturating_sub(self.epoch), own),
                Received::Error { class, data, .. } => {
                    self.last_error = Some(format!(
                        "the driver's last error frame: class 0x{class:X}, data {}",
                        hex(&data)
                    ));
                    if class & canif_kernel::CAN_ERR_BUSOFF != 0 {
                        let name = if on_iut_socket {
                            &self.options.spec.iut
                        } else {
                            &self.options.spec.tester
                        };
                        return Err(bus_error(format!(
                            "{name}: the controller went bus-off (error frame class 0x{class:X}, data {})",
                            hex(&data)
                        )));
                    }
                    continue; // other error frames: the driver's retries go on
                }
            };
            if frame == marker() && !own {
                continue; // a synchronization marker a driver delivered late
            }
            pair.now = pair.now.max(at);
            match (owned, on_iut_socket, own) {
                // Attached: the IUT's own frame is on the bus.
                (false, true, true) => {
                    if self.iut_in_flight.as_ref().map(|f| f.frame) != Some(frame) {
                        let expected = self.iut_in_flight.as_ref();
                        return Err(self.mismatch(frame, expected, "the IUT's socket (echo)"));
                    }
                    self.iut_in_flight = None;
                    pair.complete(frame, true, at)?;
                }
                // Attached: another node's frame reached the IUT.
                (false, true, false) => {
                    if !arrived(&mut self.tester_in_flight, frame) {
                        let expected = self.tester_in_flight.front();
                        return Err(self.mismatch(frame, expected, "the IUT's socket"));
                    }
                    pair.complete(frame, false, at)?;
                }
                // Attached: the IUT's frame reached the other nodes.
                (false, false, _) => {
                    if !arrived(&mut self.crossing, frame) {
                        let expected = self.crossing.front();
                        return Err(self.mismatch(frame, expected, "the tester's socket"));
                    }
                }
                // Owned: the harness's own frame is on the bus; the IUT has it too.
                (true, _, true) => {
                    if !arrived(&mut self.tester_in_flight, frame) {
                        let expected = self.tester_in_flight.front();
                        return Err(self.mismatch(frame, expected, "the tester's socket (echo)"));
                    }
                    pair.observe(frame, false, at);
                }
                // Owned: a frame the IUT sent.
                (true, _, false) => {
                    let expected = match self.model_next.take() {
                        Some((frame, _)) => Some(frame),
                        None => pair.model.poll_transmit(at),
                    };
                    match pair.transmit_difference(expected, Some(Ok(frame))) {
                        Ok(_) => pair.observe(frame, true, at),
                        Err(difference) => return Err(pair.fail(difference)),
                    }
                }
            }
        }
    }

    /// Owned: a frame the model sent long ago that the IUT has not sent is missing.
    fn model_waits(&mut self, pair: &mut Pair) -> Result<(), Outcome> {
        let now = pair.now;
        if self.model_next.is_none() {
            self.model_next = pair.model.poll_transmit(now).map(|f| (f, now));
        }
        let patience = self.options.timeout.as_nanos() as Nanos;
        if let Some((frame, since)) = self.model_next {
            if now.saturating_sub(since) > patience {
                return Err(pair.fail(Difference {
                    frames: None,
                    candidates: blame::TX_MISSING,
                    what: format!(
                        "frame on {} within {} ms",
                        self.options.spec.tester,
                        patience / 1_000_000
                    ),
                    expected: frame.to_string(),
                    actual: "no frame".into(),
                }));
            }
        }
        Ok(())
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
