//! The wire under canif's EtherCAT master: ethercrab's frame interface on one
//! end, on the other the emulated terminal in memory (frames answered in the
//! same thread, time virtual) or a network interface (a raw socket, ethercrab's
//! own task in a thread of its own).

use std::cell::{Cell, RefCell};
use std::future::Future;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::task::{Context, Poll, Wake, Waker};
use std::time::Duration;

use canif_ethercat::SubDevice;
use canif_softdevice::ethercat::Terminal;
use ethercrab::{MainDevice, MainDeviceConfig, PduRx, PduStorage, PduTx, Timeouts};

/// Frames in flight at once, and the largest frame's data. A group's
/// largest process image (4 KiB) takes four frames; ethercrab looks through
/// every slot for each frame it sends, so there are no more than twice that.
const MAX_FRAMES: usize = 8;
const MAX_PDU_DATA: usize = PduStorage::element_size(1100);

/// What the link does to the terminal's answers: the faults a SubDevice or a
/// wire can have, for canif's own tests of its EtherCAT errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkFault {
    /// Every logical datagram comes back with working counter 0.
    WorkingCounter,
    /// Frames after the first `n` are not answered.
    SilentAfter(u64),
    /// The answer is cut short.
    Truncated,
    /// Each datagram comes back two bytes longer than it was sent.
    Oversized,
    /// The terminal's firmware refuses SAFEOP with this AL status code (an
    /// AL error that is no refusal of the configuration, e.g. 0x0011).
    AlError(u16),
    /// With Distributed Clocks the terminal's firmware still runs its cycle
    /// on every SyncManager 2 event, not on SYNC0 (a failure of PDX-005).
    CyclesOnFrames,
    /// An LRW reads zeros instead of what the last SyncManager 2 event left
    /// (a well-formed telegram with the wrong inputs: a failure of the
    /// exchange, PDX-001).
    LrwReadsZeros,
}

thread_local! {
    /// The in-memory link's time: the harness's virtual time, which the
    /// terminal's ESC and ethercrab's Distributed Clocks both read.
    static CLOCK: Cell<u64> = const { Cell::new(0) };
}

pub(super) fn now() -> u64 {
    CLOCK.with(Cell::get)
}

pub(super) fn set_now(time: u64) {
    CLOCK.with(|c| c.set(time));
}

/// An emulated terminal, shared between the link that carries its frames and
/// the harness that drives its CAN controller.
pub(crate) type SharedTerminal = Arc<Mutex<SubDevice<Terminal>>>;

/// The terminal, also after a panic elsewhere left its lock poisoned (the
/// run reports that panic; the terminal's state is still what it was).
pub(crate) fn lock(terminal: &SharedTerminal) -> MutexGuard<'_, SubDevice<Terminal>> {
    terminal.lock().unwrap_or_else(|e| e.into_inner())
}

/// The emulated terminal at the other end of the in-memory link.
pub(super) struct Peer {
    pub(super) terminal: SharedTerminal,
    pub(super) fault: Option<LinkFault>,
    pub(super) frames: Cell<u64>,
}

impl Peer {
    /// The terminal's answer to `frame` in `answer`, as the link's fault
    /// leaves it; `false` for no answer.
    fn answer(&self, frame: &[u8], answer: &mut Vec<u8>) -> bool {
        use canif_ethercat::wire::{Command, Datagram, Frame};
        let n = self.frames.get() + 1;
        self.frames.set(n);
        answer.clear();
        match lock(&self.terminal).process(frame, now()) {
            Some(bytes) => answer.extend_from_slice(bytes),
            None => return false,
        }
        let mut rewrite = |change: fn(&mut Datagram)| match Frame::parse(answer) {
            Ok(mut parsed) => {
                parsed.datagrams.iter_mut().for_each(change);
                parsed.emit_into(answer);
                true
            }
            Err(_) => false,
        };
        match self.fault {
            None | Some(LinkFault::AlError(_) | LinkFault::CyclesOnFrames) => true,
            Some(LinkFault::SilentAfter(after)) => n <= after,
            Some(LinkFault::Truncated) => {
                answer.truncate(20);
                true
            }
            Some(LinkFault::Oversized) => rewrite(|d| d.data.extend_from_slice(&[0xEE, 0xEE])),
            Some(LinkFault::LrwReadsZeros) => rewrite(|d| {
                if d.command == Command::Lrw {
                    d.data.fill(0);
                }
            }),
            Some(LinkFault::WorkingCounter) => rewrite(|d| {
                if matches!(d.command, Command::Lrw | Command::Lrd | Command::Lwr) {
                    d.working_counter = 0;
                }
            }),
        }
    }
}

/// A master whose frames this thread carries to a [`Peer`].
pub(super) struct MemoryMaster {
    pub(super) maindevice: MainDevice<'static>,
    tx: RefCell<PduTx<'static>>,
    rx: RefCell<PduRx<'static>>,
    pub(super) peer: RefCell<Option<Peer>>,
    /// The peer's last answer (its buffer kept from frame to frame).
    answer: RefCell<Vec<u8>>,
}

/// Timeouts of a master that waits for an emulated terminal: its answers
/// and state changes come at once; only a silent one waits them out. (ethercrab
/// waits out a refused state change instead of reading the AL error flag.)
pub(super) fn timeouts() -> Timeouts {
    Timeouts {
        state_transition: Duration::from_millis(200),
        pdu: Duration::from_millis(100),
        eeprom: Duration::from_millis(100),
        wait_loop_delay: Duration::from_micros(100),
        mailbox_echo: Duration::from_millis(500),
        mailbox_response: Duration::from_secs(2),
    }
}

pub(super) fn config() -> MainDeviceConfig {
    MainDeviceConfig {
        // Static drift compensation: a handful of frames, not ethercrab's 10,000.
        dc_static_sync_iterations: 10,
        ..MainDeviceConfig::default()
    }
}

thread_local! {
    /// One master per thread for the thread's life: ethercrab's storage must
    /// outlive the master, and a run builds a terminal per configuration.
    static MEMORY_MASTER: &'static MemoryMaster = {
        let storage: &'static PduStorage<MAX_FRAMES, MAX_PDU_DATA> =
            Box::leak(Box::new(PduStorage::new()));
        let (tx, rx, pdu_loop) = storage.try_split().expect("a fresh storage splits");
        Box::leak(Box::new(MemoryMaster {
            maindevice: MainDevice::new(pdu_loop, timeouts(), config()),
            tx: RefCell::new(tx),
            rx: RefCell::new(rx),
            peer: RefCell::new(None),
            answer: RefCell::new(Vec::new()),
        }))
    };
}

impl MemoryMaster {
    pub(super) fn of_this_thread() -> &'static MemoryMaster {
        MEMORY_MASTER.with(|m| *m)
    }

    /// Runs `operation` to its end, carrying its frames to the peer.
    pub(super) fn drive<T>(&self, operation: impl Future<Output = T>) -> T {
        let mut sendable = None;
        let pump = std::future::poll_fn(|cx| {
            let mut tx = self.tx.borrow_mut();
            if !Sendable::look(&mut sendable, &tx, cx) {
                return Poll::Pending;
            }
            // One frame a look: a look that finds none still claims every
            // slot in turn, so the look after the last frame is left to the
            // next poll, which the operation usually wakes for a frame of
            // its own (and this wake makes sure of).
            if let Some(frame) = tx.next_sendable_frame() {
                let mut answer = self.answer.borrow_mut();
                let mut answered = false;
                let sent = frame.send_blocking(|bytes| {
                    let peer = self.peer.borrow();
                    answered = peer.as_ref().is_some_and(|p| p.answer(bytes, &mut answer));
                    Ok(bytes.len())
                });
                if sent.is_ok() && answered {
                    // What the master cannot match is its own timeout to find.
                    let _ = self.rx.borrow_mut().receive_frame(&answer);
                }
                Sendable::look_again(&sendable, cx);
            }
            Poll::<T>::Pending
        });
        super::timer::block_on(futures_lite::future::or(operation, pump))
    }
}

/// Whether ethercrab marked a frame sendable since a drive's pump last
/// looked (ethercrab wakes the sender after each frame it marks), or the
/// pump left a look for its next poll (`look_again`). Looking claims each
/// of the storage's frames in turn with an atomic exchange, and the pump is
/// polled whenever anything wakes the drive: an eighth of the in-memory run
/// went to looks that found nothing (perf).
struct Sendable {
    marked: AtomicBool,
    drive: Waker,
}

impl Wake for Sendable {
    fn wake(self: Arc<Self>) {
        self.wake_by_ref();
    }

    fn wake_by_ref(self: &Arc<Self>) {
        self.marked.store(true, Ordering::Release);
        self.drive.wake_by_ref();
    }
}

impl Sendable {
    /// Whether to look for frames to send now (the first poll of a drive
    /// always looks). A wake-up takes the sender's waker out of ethercrab's
    /// storage, so it is put back before each look: a frame marked during
    /// or after the look wakes the drive again.
    fn look(
        sendable: &mut Option<(Arc<Sendable>, Waker)>,
        tx: &PduTx<'_>,
        cx: &Context<'_>,
    ) -> bool {
        let (sendable, waker) = sendable.get_or_insert_with(|| {
            let sendable = Arc::new(Sendable {
                marked: AtomicBool::new(true),
                drive: cx.waker().clone(),
            });
            let waker = Waker::from(Arc::clone(&sendable));
            (sendable, waker)
        });
        let marked = sendable.marked.swap(false, Ordering::AcqRel);
        if marked {
            tx.replace_waker(waker);
        }
        marked
    }

    /// The next poll looks again, and comes.
    fn look_again(sendable: &Option<(Arc<Sendable>, Waker)>, cx: &Context<'_>) {
        if let Some((sendable, _)) = sendable {
            sendable.marked.store(true, Ordering::Release);
        }
        cx.waker().wake_by_ref();
    }
}

/// A master on a network interface. With Linux sockets the calling thread
/// carries its frames itself through a raw packet socket, as the in-memory
/// master does to its peer: each frame handed to a second thread and back
/// (ethercrab's own task) cost two wake-ups across threads per round trip.
pub(super) struct InterfaceMaster {
    pub(super) maindevice: MainDevice<'static>,
    #[cfg(feature = "socketcan")]
    wire: Mutex<Wire>,
    /// No master on an interface is built without a packet socket.
    #[cfg(not(feature = "socketcan"))]
    none: std::convert::Infallible,
}

/// The socket under a master, and the frames it waits answers for.
#[cfg(feature = "socketcan")]
struct Wire {
    tx: PduTx<'static>,
    rx: PduRx<'static>,
    socket: canif_kernel::PacketSocket,
    buffer: Vec<u8>,
    in_flight: usize,
    /// Since when no answer came while frames were in flight.
    silent_since: Option<std::time::Instant>,
}

#[cfg(feature = "socketcan")]
impl Wire {
    /// Sends the frames ethercrab marked sendable.
    fn send_queued(&mut self) {
        while let Some(frame) = self.tx.next_sendable_frame() {
            let socket = &self.socket;
            let sent = frame.send_blocking(|bytes| {
                socket
                    .send(bytes)
                    .map(|()| bytes.len())
                    .map_err(|_| ethercrab::error::Error::SendFrame)
            });
            if sent.is_ok() {
                self.in_flight += 1;
            }
        }
    }

    /// Sends what the master queued, then takes what came back: waits (up
    /// to a slice) only while answers are due, so a timer the master waits
    /// on still fires; answers overdue past the master's own timeouts are
    /// given up.
    fn pump(&mut self, cx: &mut std::task::Context<'_>, look: bool) {
        const SLICE: Duration = Duration::from_millis(1);
        // An answer usually comes within tens of microseconds: looked for
        // awake, it is not delayed by a sleeping thread's wake-up.
        const SPIN: Duration = Duration::from_micros(200);
        if look {
            self.send_queued();
        }
        let mut wait = if self.in_flight > 0 {
            SLICE
        } else {
            Duration::ZERO
        };
        while let Ok(Some(n)) = self
            .socket
            .recv_spinning(&mut self.buffer, SPIN.min(wait), wait)
        {
            if let Ok(ethercrab::ReceiveAction::Processed) =
                self.rx.receive_frame(&self.buffer[..n])
            {
                self.in_flight = self.in_flight.saturating_sub(1);
                self.silent_since = None;
            }
            wait = Duration::ZERO;
        }
        if self.in_flight > 0 {
            let since = *self
                .silent_since
                .get_or_insert_with(std::time::Instant::now);
            if since.elapsed() > Duration::from_secs(2) {
                (self.in_flight, self.silent_since) = (0, None);
            }
            cx.waker().wake_by_ref();
        }
    }
}

#[cfg(feature = "socketcan")]
type Masters = std::sync::Mutex<std::collections::HashMap<String, &'static InterfaceMaster>>;

#[cfg(feature = "socketcan")]
static INTERFACE_MASTERS: std::sync::OnceLock<Masters> = std::sync::OnceLock::new();

impl InterfaceMaster {
    /// The master on `interface`, started on first use (needs CAP_NET_RAW).
    #[cfg(feature = "socketcan")]
    pub(super) fn on(interface: &str) -> Result<&'static InterfaceMaster, std::io::Error> {
        let masters = INTERFACE_MASTERS.get_or_init(Default::default);
        let mut masters = masters.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(master) = masters.get(interface) {
            return Ok(master);
        }
        let storage: &'static PduStorage<MAX_FRAMES, MAX_PDU_DATA> =
            Box::leak(Box::new(PduStorage::new()));
        let (tx, rx, pdu_loop) = storage.try_split().expect("a fresh storage splits");
        let socket = canif_kernel::PacketSocket::open(interface, canif_ethercat::wire::ETHERTYPE)
            .map_err(|e| std::io::Error::other(e.to_string()))?;
        let master: &'static InterfaceMaster = Box::leak(Box::new(InterfaceMaster {
            maindevice: MainDevice::new(pdu_loop, real_timeouts(), config()),
            wire: Mutex::new(Wire {
                tx,
                rx,
                socket,
                buffer: vec![0; 2048],
                in_flight: 0,
                silent_since: None,
            }),
        }));
        masters.insert(interface.to_string(), master);
        Ok(master)
    }

    /// Without SocketCAN's crate there is no packet socket to carry frames.
    #[cfg(not(feature = "socketcan"))]
    pub(super) fn on(interface: &str) -> Result<&'static InterfaceMaster, std::io::Error> {
        Err(std::io::Error::new(
            std::io::ErrorKind::Unsupported,
            format!(
                "{interface}: this canif was built without SocketCAN (cargo feature `socketcan`), \
                 whose packet sockets carry canif's EtherCAT frames"
            ),
        ))
    }

    #[cfg(feature = "socketcan")]
    pub(super) fn drive<T>(&self, operation: impl Future<Output = T>) -> T {
        let mut sendable = None;
        let pump = std::future::poll_fn(|cx| {
            let mut wire = self.wire.lock().unwrap_or_else(|e| e.into_inner());
            let look = Sendable::look(&mut sendable, &wire.tx, cx);
            wire.pump(cx, look);
            Poll::<T>::Pending
        });
        super::timer::block_on(futures_lite::future::or(operation, pump))
    }

    #[cfg(not(feature = "socketcan"))]
    pub(super) fn drive<T>(&self, _: impl Future<Output = T>) -> T {
        match self.none {}
    }
}

/// Timeouts of a master that waits for a terminal across a wire: generous,
/// since a loaded machine may not run the other end for a while (a refused
/// SAFEOP does not wait them out: canif watches that transition itself).
#[cfg(feature = "socketcan")]
fn real_timeouts() -> Timeouts {
    Timeouts {
        state_transition: Duration::from_secs(5),
        pdu: Duration::from_secs(1),
        eeprom: Duration::from_secs(1),
        wait_loop_delay: Duration::from_micros(100),
        mailbox_echo: Duration::from_millis(500),
        mailbox_response: Duration::from_secs(2),
    }
}
