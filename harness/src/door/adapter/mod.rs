//! The adapter protocol (docs/adapter-protocol.md): how an implementation
//! under test in another process, in any language, joins the suite.
//!
//! - [`protocol`]: the messages, as serde types, written once.
//! - `process`: an implementation in another process, in either role.
//! - [`shared`]: protocol 3, the cycle's records in shared memory.
//!
//! Its users are the doors: `door::exec` (a device or client process, and
//! a hosted library on its control channel), and `door::serve` (canif
//! serving an in-process implementation: `canif device --stdio`, `canif lib-host`).

mod lines;
pub(crate) mod process;
pub mod protocol;
pub mod shared;

/// The descriptors a `canif lib-host --control` reads requests from and
/// writes answers to: its control channel, apart from the library's own
/// stdin, stdout and stderr.
pub const CONTROL_FDS: (i32, i32) = (3, 4);
