//! The adapter protocol (docs/adapter-protocol.md): how an implementation
//! under test in another process, in any language, joins the suite.
//!
//! - [`protocol`]: the messages, as serde types, written once.
//! - [`process`]: an implementation in another process, in either role.
//! - [`exec_iut`]: the harness's side of the device role — an IUT process behind the [`crate::device::Iut`] trait.
//! - [`server`]: the device's side — an in-process IUT served over stdin/stdout.

#[cfg(feature = "socketcan")]
pub mod device_bus;
pub mod exec_iut;
pub mod process;
pub mod protocol;
pub mod server;
