//! The emulated terminal on one end of a veth pair and canif's master on the
//! other, in one process: every frame crosses the kernel's packet path, the
//! harness still drives the terminal's CAN controller, and the terminal's
//! clock is the harness's virtual time.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

use super::link::{lock, SharedTerminal};
use canif_kernel::{KernelError, PacketSocket};

use super::served::answer_frames;

/// How long one wait for a frame lasts before the thread asks whether to stop.
const POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// The thread serving the terminal; it stops and is joined on drop.
pub(crate) struct Serving {
    stop: Arc<AtomicBool>,
    pub(crate) clock: Arc<AtomicU64>,
    thread: Option<JoinHandle<Result<(), String>>>,
}

impl Serving {
    /// Opens `interface` here (so the terminal answers before the master
    /// scans) and serves it from a thread.
    pub(crate) fn start(
        interface: &str,
        terminal: &SharedTerminal,
    ) -> Result<Serving, KernelError> {
        let socket = PacketSocket::open(interface, canif_ethercat::wire::ETHERTYPE)?;
        let stop = Arc::new(AtomicBool::new(false));
        let clock = Arc::new(AtomicU64::new(0));
        let (interface, terminal) = (interface.to_string(), Arc::clone(terminal));
        let thread = {
            let (stop, clock) = (Arc::clone(&stop), Arc::clone(&clock));
            std::thread::Builder::new()
                .name(format!("terminal-{interface}"))
                .spawn(move || {
                    answer_frames(
                        &interface,
                        &socket,
                        &mut |frame| lock(&terminal).process(frame, clock.load(Ordering::SeqCst)),
                        &mut || {},
                        (POLL, &|| stop.load(Ordering::SeqCst)),
                    )
                    .map(|_| ())
                    .map_err(|e| e.to_string())
                })
                .ok()
        };
        Ok(Serving {
            stop,
            clock,
            thread,
        })
    }
}

impl Drop for Serving {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}
