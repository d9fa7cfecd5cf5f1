//! `canif device --ethercat IFACE [--bus socketcan:CANIFACE]`: the emulated
//! terminal on a network interface, for any EtherCAT master (ethercrab,
//! SOEM/pysoem, IgH) and the PLC-side drivers running on it. Its CAN
//! controller is on a SocketCAN interface, where `canif run --iut
//! ethercat:… --bus socketcan:…` certifies it as it would a real terminal;
//! without one it sends into a bus where every frame is acknowledged at
//! once, and each frame it sends is written on `log` in candump's format:
//! what a driver asked for can be watched here.

use std::io::Write;
use std::time::Duration;

use canif_ethercat::SubDevice;
use canif_kernel::{KernelError, PacketSocket};
use canif_softdevice::ethercat::Terminal;

use crate::door::iut::SoftDeviceIut;
use crate::door::serve::can_side::DeviceBus;
use crate::error::BusError;

/// How long one wait for a frame lasts: a batch's next CAN frame goes out
/// once the kernel confirms the one before, and a SYNC0 event comes, whenever
/// the master sends (also how often `stop` is asked).
const CAN_POLL: Duration = Duration::from_micros(200);

/// How long the terminal looks for the next frame awake before it sleeps: a
/// master's next telegram usually follows within this, and a thread woken
/// from poll(2) would add tens of microseconds to its round trip.
const SPIN: Duration = Duration::from_micros(200);

/// What a served terminal saw.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Served {
    pub frames: u64,
    pub not_ethercat: u64,
    pub cycles: u64,
    pub can_frames: u64,
    /// SYNC0 events the terminal was too late for (ran its cycle once for several).
    pub missed_sync0: u64,
}

/// Answers EtherCAT frames on `interface` with `answer` until `stop` says so;
/// `between` runs before each frame is answered, once its answer is sent, and
/// after each `wait` that ended without a frame.
pub fn answer_frames(
    interface: &str,
    socket: &PacketSocket,
    answer: &mut dyn FnMut(&[u8]) -> Option<Vec<u8>>,
    between: &mut dyn FnMut(),
    (wait, stop): (Duration, &dyn Fn() -> bool),
) -> Result<Served, KernelError> {
    let failed = |error: std::io::Error| KernelError::Interface {
        interface: interface.to_string(),
        operation: canif_kernel::Operation::Open,
        error: error.into(),
    };
    let mut served = Served::default();
    let mut buffer = vec![0u8; 2048];
    while !stop() {
        let Some(n) = socket
            .recv_spinning(&mut buffer, SPIN.min(wait), wait)
            .map_err(failed)?
        else {
            between();
            continue;
        };
        // An ESC processes every EtherCAT frame, whatever its source address:
        // a master on a veth, a VM or a USB NIC sends from a locally
        // administered one (those were ignored here once). Its own answers
        // never come back: the socket leaves out what this machine sent.
        if n < 14 {
            continue;
        }
        // What the kernel delivered before this frame happened before it:
        // a CAN frame received just before the master's LRW is in that cycle.
        between();
        match answer(&buffer[..n]) {
            Some(reply) => {
                served.frames += 1;
                socket.send(&reply).map_err(failed)?;
                between();
            }
            None => served.not_ethercat += 1,
        }
    }
    Ok(served)
}

/// Why serving the terminal ended.
#[derive(Debug)]
pub enum ServeError {
    /// The EtherCAT interface failed.
    Ethercat(KernelError),
    /// The CAN interface failed (or could not be opened).
    Can(BusError),
}

impl std::fmt::Display for ServeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ServeError::Ethercat(error) => write!(f, "{error}"),
            ServeError::Can(error) => write!(f, "its CAN side: {error}"),
        }
    }
}

impl std::error::Error for ServeError {}

/// `canif device --ethercat`: the terminal in wall-clock time (the kernel's
/// clock, which also stamps the CAN frames it receives). Its CAN controller
/// is on `can` (a SocketCAN interface); without one its frames are
/// acknowledged at once and written on `log` in candump's format. `ready`
/// runs once both interfaces are open: a master may scan from then on.
pub fn serve(
    interface: &str,
    terminal: &mut SubDevice<Terminal>,
    (can, log): (Option<&str>, &mut dyn Write),
    (ready, stop): (&dyn Fn(), &dyn Fn() -> bool),
) -> Result<Served, ServeError> {
    let epoch = canif_kernel::realtime_ns();
    let now = || canif_kernel::realtime_ns().saturating_sub(epoch);
    let mut bus = match can {
        Some(name) => Some(
            DeviceBus::open(name, epoch)
                .map_err(|e| ServeError::Can(BusError::new(crate::error::BusCause::Io, e)))?,
        ),
        None => None,
    };
    let terminal = std::cell::RefCell::new(terminal);
    let can_frames = std::cell::Cell::new(0u64);
    let bus_failed = std::cell::RefCell::new(None);
    let socket = PacketSocket::open(interface, canif_ethercat::wire::ETHERTYPE)
        .map_err(ServeError::Ethercat)?;
    // Short waits: a CAN bus to serve between frames, and with Distributed
    // Clocks the SYNC0 events, which come whether a frame does or not.
    let wait = CAN_POLL;
    ready();
    let mut served = answer_frames(
        interface,
        &socket,
        &mut |frame| {
            terminal
                .borrow_mut()
                .process(frame, now())
                .map(<[u8]>::to_vec)
        },
        &mut || {
            let mut terminal = terminal.borrow_mut();
            terminal.handle_timeout(now());
            let Some(device) = terminal.application.device_mut() else {
                return;
            };
            match bus.as_mut() {
                Some(bus) => {
                    if let Err(error) = bus.pump(&mut SoftDeviceIut(device)) {
                        bus_failed.borrow_mut().get_or_insert(error);
                    }
                }
                None => {
                    let now = now();
                    while let Some(frame) = device.controller_idle(now) {
                        can_frames.set(can_frames.get() + 1);
                        log_frame(log, interface, now, &frame);
                        device.tx_done_interrupt();
                    }
                }
            }
        },
        (wait, &|| stop() || bus_failed.borrow().is_some()),
    )
    .map_err(ServeError::Ethercat)?;
    if let Some(error) = bus_failed.into_inner() {
        return Err(ServeError::Can(error));
    }
    served.cycles = terminal.borrow().cycles;
    served.missed_sync0 = terminal.borrow().missed_sync0();
    served.can_frames = can_frames.get();
    Ok(served)
}

/// One frame in candump's format (the trace's own line); a frame that is
/// none is said as what it is.
fn log_frame(log: &mut dyn Write, interface: &str, now: u64, frame: &canif_softdevice::CanFrame) {
    let line = match crate::door::iut::from_soft(frame) {
        Ok(frame) => crate::trace::candump_line(now, interface, &frame),
        Err(invalid) => format!("{interface}: an invalid frame: {invalid}"),
    };
    let _ = writeln!(log, "{line}");
}
