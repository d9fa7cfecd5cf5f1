//! The adapter protocol (docs/adapter-protocol.md): how an implementation
//! under test in another process, in any language, joins the suite.
//!
//! - [`protocol`]: the messages, as serde types, written once.
//! - [`client`]: the harness's side — an IUT process behind the [`crate::device::Iut`] trait.
//! - [`server`]: the device's side — an in-process IUT served over stdin/stdout.

pub mod client;
#[cfg(feature = "socketcan")]
pub mod device_bus;
pub mod protocol;
pub mod server;
