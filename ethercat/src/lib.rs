//! An emulated EtherCAT SubDevice and the EtherCAT wire format: what canif's
//! terminal presents to a MainDevice, and what canif's MainDevice speaks in
//! CoE where its master crate stops (segmented download, complete access).
//! See the README for the modules.

#![forbid(unsafe_code)]

pub mod esc;
pub mod mailbox;
pub mod register;
pub mod sdo;
pub mod sdo_info;
pub mod sii;
pub mod subdevice;
pub mod sync0;
pub mod wire;

pub use sdo::{Entry, ObjectDictionary};
pub use sii::Identity;
pub use subdevice::{AlState, Application, Start, SubDevice, Synchronization, Telegrams};
