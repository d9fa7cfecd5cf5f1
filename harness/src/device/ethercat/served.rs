//! `canif device --ethercat IFACE`: the emulated terminal on a network
//! interface, for any EtherCAT master (ethercrab, SOEM/pysoem, IgH) and the
//! PLC-side drivers running on it. Its CAN controller sends into a bus where
//! every frame is acknowledged at once, and each frame it sends is written on
//! `log` in candump's format: what a driver asked for can be watched here.

use std::io::Write;
use std::time::{Duration, Instant};

use canif_ethercat::SubDevice;
use canif_kernel::{KernelError, PacketSocket};
use canif_softdevice::ethercat::Terminal;

/// How long one wait for a frame lasts before `stop` is asked again.
const POLL: Duration = Duration::from_millis(50);

/// What a served terminal saw.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Served {
    pub frames: u64,
    pub not_ethercat: u64,
    pub cycles: u64,
    pub can_frames: u64,
}

/// Answers EtherCAT frames on `interface` with `answer` until `stop` says so;
/// `after` runs once each answered frame is sent.
pub fn answer_frames(
    interface: &str,
    socket: &PacketSocket,
    answer: &mut dyn FnMut(&[u8]) -> Option<Vec<u8>>,
    after: &mut dyn FnMut(),
    stop: &dyn Fn() -> bool,
) -> Result<Served, KernelError> {
    let failed = |error: std::io::Error| KernelError::Interface {
        interface: interface.to_string(),
        operation: canif_kernel::Operation::Open,
        error: error.into(),
    };
    let mut served = Served::default();
    let mut buffer = vec![0u8; 2048];
    while !stop() {
        let Some(n) = socket.recv(&mut buffer, POLL).map_err(failed)? else {
            continue;
        };
        // An answer of another ESC (source address marked on its way back) is no request.
        if n < 12 || buffer[6] & 0x02 != 0 {
            continue;
        }
        match answer(&buffer[..n]) {
            Some(reply) => {
                served.frames += 1;
                socket.send(&reply).map_err(failed)?;
                after();
            }
            None => served.not_ethercat += 1,
        }
    }
    Ok(served)
}

/// `canif device --ethercat`: the terminal in wall-clock time, its CAN frames
/// acknowledged at once and written on `log` in candump's format.
pub fn serve(
    interface: &str,
    terminal: &mut SubDevice<Terminal>,
    log: &mut dyn Write,
    stop: &dyn Fn() -> bool,
) -> Result<Served, KernelError> {
    let started = Instant::now();
    let now = || started.elapsed().as_nanos() as u64;
    let terminal = std::cell::RefCell::new(terminal);
    let can_frames = std::cell::Cell::new(0u64);
    let socket = PacketSocket::open(interface, canif_ethercat::wire::ETHERTYPE)?;
    let mut served = answer_frames(
        interface,
        &socket,
        &mut |frame| terminal.borrow_mut().process(frame, now()),
        &mut || {
            let mut terminal = terminal.borrow_mut();
            let Some(device) = terminal.application.device_mut() else {
                return;
            };
            let now = now();
            while let Some(frame) = device.controller_idle(now) {
                can_frames.set(can_frames.get() + 1);
                let data: String = frame.data[..frame.len.min(64)]
                    .iter()
                    .map(|b| format!("{b:02X}"))
                    .collect();
                let id = if frame.extended {
                    format!("{:08X}", frame.id)
                } else {
                    format!("{:03X}", frame.id)
                };
                let remote = if frame.remote { "R" } else { "" };
                let _ = writeln!(
                    log,
                    "({}.{:06}) {interface} {id}#{remote}{data}",
                    now / 1_000_000_000,
                    now % 1_000_000_000 / 1_000
                );
                device.tx_done_interrupt();
            }
        },
        stop,
    )?;
    served.cycles = terminal.borrow().cycles;
    served.can_frames = can_frames.get();
    Ok(served)
}
