//! The adapter protocol (docs/adapter-protocol.md): how an implementation
//! under test in another process, in any language, joins the suite.
//!
//! - [`protocol`]: the messages, as serde types, written once.
//! - `process`: an implementation in another process, in either role.
//!
//! Each side's use of it is the side's own: `device::exec_iut` (a device
//! process), `device::server` (an in-process device served over stdin and
//! stdout), `client::exec` (a client process).

pub(crate) mod process;
pub mod protocol;
