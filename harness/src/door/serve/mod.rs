//! The far end of a door: canif serving an in-process implementation over
//! the adapter protocol to another process.
//!
//! - [`device`]: a device over stdin and stdout (`canif device --stdio`), or
//!   a library's device in `canif lib-host --role device`.
//! - `bus`: that device's CAN side on a SocketCAN interface.
//! - [`client`]: a library's client in `canif lib-host --role client`.

#[cfg(feature = "socketcan")]
pub mod bus;
pub mod client;
pub mod device;
