//! The emulated terminal on one end of a veth pair and canif's master on the
//! other, in one process: every frame crosses the kernel's packet path, the
//! harness still drives the terminal's CAN controller, and the terminal's
//! clock is the harness's virtual time.
//!
//! One thread and one socket serve each interface for the process's life,
//! and each configuration's terminal takes its turn there: closing a packet
//! socket waits for the kernel's RCU grace period (packet(7) release), which
//! cost 6–20 ms per configuration of the refusal grid, most of a run.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use super::link::{lock, SharedTerminal};
use canif_kernel::{KernelError, PacketSocket};

use super::served::answer_frames;

/// How long one wait for a frame lasts.
const POLL: std::time::Duration = std::time::Duration::from_millis(1);

/// The terminal an interface's thread answers for now (none between
/// configurations: frames then go unanswered, as on an empty wire).
type Slot = Arc<Mutex<Option<SharedTerminal>>>;

/// An interface's serving thread: its terminal slot and the terminal's clock.
#[derive(Clone)]
struct Wire {
    slot: Slot,
    clock: Arc<AtomicU64>,
    /// Cleared when the thread ended (the interface went away): the next
    /// configuration opens it afresh.
    alive: Arc<AtomicBool>,
}

static WIRES: OnceLock<Mutex<HashMap<String, Wire>>> = OnceLock::new();

/// A configuration's turn on the interface; the terminal leaves on drop.
pub(crate) struct Serving {
    slot: Slot,
    pub(crate) clock: Arc<AtomicU64>,
}

impl Serving {
    /// Puts `terminal` on `interface`, opening it and starting its thread
    /// the first time (so the terminal answers before the master scans).
    pub(crate) fn start(
        interface: &str,
        terminal: &SharedTerminal,
    ) -> Result<Serving, KernelError> {
        let wires = WIRES.get_or_init(Default::default);
        let mut wires = wires.lock().unwrap_or_else(|e| e.into_inner());
        let wire = match wires.get(interface) {
            Some(wire) if wire.alive.load(Ordering::SeqCst) => wire.clone(),
            _ => {
                let wire = serve(interface)?;
                wires.insert(interface.to_string(), wire.clone());
                wire
            }
        };
        wire.clock.store(0, Ordering::SeqCst);
        *wire.slot.lock().unwrap_or_else(|e| e.into_inner()) = Some(Arc::clone(terminal));
        Ok(Serving {
            slot: wire.slot,
            clock: wire.clock,
        })
    }
}

/// Opens `interface` and answers its frames from a thread of its own.
fn serve(interface: &str) -> Result<Wire, KernelError> {
    let socket = PacketSocket::open(interface, canif_ethercat::wire::ETHERTYPE)?;
    let wire = Wire {
        slot: Arc::new(Mutex::new(None)),
        clock: Arc::new(AtomicU64::new(0)),
        alive: Arc::new(AtomicBool::new(true)),
    };
    let (name, served) = (interface.to_string(), wire.clone());
    let _ = std::thread::Builder::new()
        .name(format!("terminal-{interface}"))
        .spawn(move || {
            let answer = &mut |frame: &[u8]| {
                let terminal = served
                    .slot
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .clone();
                let now = served.clock.load(Ordering::SeqCst);
                terminal
                    .and_then(|terminal| lock(&terminal).process(frame, now).map(<[u8]>::to_vec))
            };
            let ended = answer_frames(&name, &socket, answer, &mut || {}, (POLL, &|| false));
            served.alive.store(false, Ordering::SeqCst);
            ended
        });
    Ok(wire)
}

impl Drop for Serving {
    fn drop(&mut self) {
        *self.slot.lock().unwrap_or_else(|e| e.into_inner()) = None;
    }
}
