//! The device side under test: what judges a device (an EL6751 or anything
//! that must behave like one) against the model. The harness plays the PLC
//! ([`played_plc`]) and the other nodes, runs the model beside the IUT on the
//! same stimulus ([`lockstep`], [`pair`]) and blames each difference on the
//! requirements of the field that differs ([`diff`], [`blame`], [`bounds`]).
//!
//! The arrows run one way: `suite` → `cases`, `refusals`, `lockstep` →
//! `played_plc`, `pair` (`sync1_window`), `bus` (`crate::bus::sim`, `kernel_bus`) → `diff`,
//! `blame`, `history`; `iut_kind` → `iut`, `exec_iut` (`crate::adapter`),
//! `lib_iut`. `server` (and `server_bus`) serve an in-process device over the
//! adapter protocol; `quick_start` drives the CANopen quick start through an
//! IUT's process image.

pub mod blame;
mod bounds;
pub mod bus;
pub mod cases;
pub mod choices;
pub mod diff;
pub mod ethercat;
pub mod exec_iut;
pub(crate) mod history;
pub mod iut;
pub mod iut_kind;
#[cfg(feature = "socketcan")]
pub mod kernel_bus;
pub(crate) mod lib_iut;
pub mod lockstep;
pub(crate) mod pair;
pub mod played_plc;
pub mod probe;
pub mod protocol_order;
pub mod quick_start;
pub mod refusals;
pub mod scenario;
pub mod server;
#[cfg(feature = "socketcan")]
pub mod server_bus;
pub mod suite;
pub(crate) mod sync1_window;

pub use iut::{BuildError, Iut};
pub use iut_kind::IutKind;
pub use lockstep::run_scenario;
pub use suite::{DeviceCase, Options};
