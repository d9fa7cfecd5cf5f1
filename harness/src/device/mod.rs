//! The device side under test: what judges a device (an EL6751 or anything
//! that must behave like one) against the model. The harness plays the PLC
//! ([`played_plc`]) and the other nodes, runs the model beside the IUT on the
//! same stimulus ([`lockstep`], [`pair`]) and blames each difference on the
//! requirements of the field that differs ([`diff`], [`blame`], [`bounds`]).
//!
//! The arrows run one way: `suite` → `cases`, `refusals`, `lockstep` → `played_plc`, `pair`,
//! `crate::bus` → `diff`, `blame`, `history`; `iut_kind` → `crate::adapter`,
//! `iut`, `lib_iut`.

pub mod blame;
pub mod bounds;
pub mod cases;
pub mod diff;
pub(crate) mod history;
pub mod iut;
pub mod iut_kind;
pub mod lib_iut;
pub mod lockstep;
pub(crate) mod pair;
pub mod played_plc;
pub mod protocol_order;
pub mod refusals;
pub mod scenario;
pub mod suite;

pub use iut::{BuildError, Iut};
pub use iut_kind::IutKind;
pub use lockstep::run_scenario;
pub use suite::{run_profile, DeviceCase, Options};
