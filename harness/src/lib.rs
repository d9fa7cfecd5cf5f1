//! # canif-harness — judging an implementation against the model
//!
//! The harness owns the PLC side (the reference client of 001 §6 writes the
//! output image and reads the input image, once per task cycle, with the LRW or
//! separate-input-update timing) and the bus side (a simulated CAN bus in
//! virtual time, or a Linux SocketCAN interface in real time, plays the other
//! nodes). It runs the reference model beside the
//! implementation under test on the same stimulus and reports the first
//! difference of each scenario against the requirement ids it breaks.

#![forbid(unsafe_code)]

pub mod bus;
pub mod canopen;
pub mod certificate;
pub mod check;
pub mod compare;
pub mod exec;
pub mod iut;
pub mod kernel_bus;
pub mod report;
pub mod scenario;
pub mod suite;
pub mod trace;

pub use check::{Failure, Outcome, ScenarioRun};
pub use iut::{BuildError, Iut, IutKind};
pub use suite::{run_profile, Options, ProfileRun, Verdict};
