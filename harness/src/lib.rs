//! # canif-harness — judging an implementation against the model
//!
//! The harness plays the side of the interface that is not under test. With a
//! device under test it owns the PLC side (the reference client of 001 §6
//! writes the output image and reads the input image once per task cycle,
//! with the LRW or separate-input-update timing) and the bus (a simulated CAN
//! bus in virtual time, or a Linux SocketCAN interface in real time, plays the
//! other nodes). It runs the reference model beside the implementation under
//! test on the same stimulus and reports the first difference of each
//! scenario against the requirement ids it breaks (a PLC-side client: every
//! breach, each judge part stopping at its own first). What the documents
//! allow but an author wants to know is counted beside, as `advisory`.
//!
//! The arrows run one way (see README.md): the two sides, [`device`] and
//! [`client`], stand on what both share: [`run`] (one profile's run of
//! either) and [`door`] (how an implementation under test is reached, in
//! either role). Neither side imports the other.

#![forbid(unsafe_code)]

pub mod advisory;
pub mod bus;
pub mod canopen;
pub mod certificate;
pub mod client;
pub mod compare;
pub mod declare;
pub mod device;
pub mod door;
pub mod error;
pub mod interrupt;
pub mod outcome;
pub mod report;
pub mod run;
mod trace;
pub mod verdict;

pub use error::{BusError, IutError, RunError};
pub use outcome::{Failure, GherkinOutcome, GherkinRun, Outcome, ScenarioRun};
pub use verdict::{Evidence, Verdict, VerdictKind};
