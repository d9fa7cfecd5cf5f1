//! The simulated CAN bus both sides run on: frames in virtual time,
//! arbitration by identifier, and a `sim::Controller` trait for the one node
//! whose controller it serves (the device side's pair of model and IUT, or the
//! device the harness plays for a client).

pub mod sim;
