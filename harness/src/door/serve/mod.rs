//! The far end of a door: canif serving an in-process implementation over
//! the adapter protocol to another process.
//!
//! - [`device`]: a device over stdin and stdout (`canif device --stdio`), or
//!   a library's device in `canif lib-host --role device`.
//! - `can_side`: that device's CAN side on a SocketCAN interface.
//! - [`client`]: a library's client in `canif lib-host --role client`.

#[cfg(feature = "socketcan")]
pub mod can_side;
pub mod client;
pub mod device;
pub mod session;

use crate::door::adapter::CONTROL_FDS;

/// A `canif lib-host --control`'s channel: requests on descriptor 3,
/// answers on 4, as canif hands them over. The guard pages' fault report
/// goes there too, where what the library prints cannot forge it.
pub fn control_channel() -> std::io::Result<(std::io::BufReader<std::fs::File>, std::fs::File)> {
    // Our own descriptors for the ones handed over (as protocol 3's are).
    let open = |fd: i32| canif_cabi::shared::inherited(fd).map(std::fs::File::from);
    let requests = open(CONTROL_FDS.0)?;
    let answers = open(CONTROL_FDS.1)?;
    canif_cabi::guard::report_to(&answers);
    Ok((std::io::BufReader::new(requests), answers))
}
