//! The simulated coupler as a node on a SocketCAN interface, in real time.

use canif_kernel::{KernelSocket, Received};
use canif_model::canopen::coupler::Coupler;

use crate::error::{BusCause, BusError};

/// Runs `coupler` on `socket` until an error: frames in, answers and its own
/// frames (heartbeats) out.
pub fn serve(socket: &KernelSocket, coupler: &mut Coupler) -> BusError {
    let epoch = canif_kernel::realtime_ns();
    loop {
        let _ = KernelSocket::wait(&[socket], std::time::Duration::from_millis(1));
        let mut out = Vec::new();
        loop {
            match socket.recv() {
                Ok(Some(Received::Frame { frame, at, .. })) => {
                    out.extend(coupler.handle(&frame, at.saturating_sub(epoch)))
                }
                Ok(Some(_)) => {}
                Ok(None) => break,
                Err(error) => {
                    return BusError::new(BusCause::Io, format!("{}: {error}", socket.interface))
                }
            }
        }
        out.extend(coupler.poll(canif_kernel::realtime_ns().saturating_sub(epoch)));
        for frame in out {
            if let Err(error) = socket.send(&frame) {
                eprintln!("{}: sending {frame}: {error}", socket.interface);
            }
        }
    }
}
