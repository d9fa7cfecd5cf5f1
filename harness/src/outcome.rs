//! What judging a scenario produces: a pass, a failure naming the requirements
//! it breaks with the cycles before it, or an error.

use canif_model::image::{InputHeader, OutputHeader};
use canif_model::Nanos;
use canif_spec::ReqId;

use crate::error::RunError;

/// One non-conformance: where, what, and which requirements it breaks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Failure {
    pub requirements: Vec<ReqId>,
    pub scenario: String,
    pub cycle: u64,
    pub time: Nanos,
    pub what: String,
    pub expected: String,
    pub actual: String,
    /// The last cycles before the failure, oldest first.
    pub context: Vec<String>,
    /// The same cycles as data, for the timing diagram.
    pub timeline: Vec<CycleView>,
}

/// A frame that ended on the bus, as a failure's history shows it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusFrame {
    /// The end of its last bit.
    pub end: Nanos,
    pub from_iut: bool,
    /// The frame in candump notation.
    pub text: String,
}

/// One cycle of a failure's history: the PLC's outputs, the model's (expected)
/// and the IUT's (actual) input header, and the frames that ended on the bus
/// since the cycle before.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CycleView {
    pub cycle: u64,
    pub time: Nanos,
    pub outputs: OutputHeader,
    pub expected: InputHeader,
    pub actual: InputHeader,
    pub frames: Vec<BusFrame>,
}

/// How one scenario ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    Pass,
    Fail(Box<Failure>),
    /// The IUT or the harness could not run the scenario (not a non-conformance).
    Error(RunError),
}

/// What one scenario run produced.
#[derive(Debug, Clone)]
pub struct ScenarioRun {
    pub scenario: String,
    pub covers: Vec<ReqId>,
    pub outcome: Outcome,
    pub cycles: u64,
    pub frames_checked: u64,
}
