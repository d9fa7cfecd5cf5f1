//! The device side under test: what judges a device (an EL6751 or anything
//! that must behave like one) against the model. The harness plays the PLC
//! ([`played_plc`]) and the other nodes, runs the model beside the IUT on the
//! same stimulus ([`lockstep`], `pair`) and blames each difference on the
//! requirements of the field that differs ([`diff`], [`blame`], `bounds`).
//!
//! The arrows run one way: `suite` → `cases`, `refusals`, `lockstep` →
//! `played_plc`, `pair` (`sync1_window`), `bus` (`crate::bus::sim`,
//! `bus::kernel`) → `diff`, `blame`, `history`; `iut_kind` → the in-process
//! devices and the doors of [`crate::door`]. `quick_start` drives the
//! CANopen quick start through an IUT's process image.

pub mod blame;
mod bounds;
pub mod cases;
pub mod diff;
pub(crate) mod history;
pub mod iut_kind;
pub mod kill_table;
pub mod lockstep;
pub mod medium;
pub(crate) mod pair;
pub mod played_plc;
pub mod probe;
pub mod protocol_order;
pub mod quick_start;
pub mod refusals;
pub mod scenario;
pub mod suite;
pub(crate) mod sync1_window;

pub use iut_kind::IutKind;
pub use lockstep::run_scenario;
pub use suite::{DeviceCase, Options};
