//! What judging a scenario produces: a pass, a failure naming the requirements
//! it breaks with the cycles before it, or an error.

use canif_model::image::{InputHeader, OutputHeader};
use canif_model::Nanos;
use canif_spec::ReqId;

use crate::error::RunError;

/// One non-conformance: where, what, and which requirements it breaks.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
    /// The same cycles (a device's) or tasks (a client's) as data, for the
    /// timing diagram.
    pub timeline: Timeline,
    /// The frames that differ, when the failure is a frame.
    pub frames: Option<FrameDiff>,
    /// The input images, when the failure is one of the image's fields.
    pub images: Option<Box<ImageDiff>>,
    /// What the failure says of the rest of what the scenario covers.
    pub rest: crate::verdict::Rest,
    /// Later breaches of the same scenario, each of requirements not blamed
    /// before, at its first cycle (the PLC side judges on after a breach).
    pub further: Vec<Failure>,
}

/// The frame the model expected and the one the IUT gave (`None`: no frame).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct FrameDiff {
    pub expected: Option<canif_model::frame::Frame>,
    pub actual: Option<canif_model::frame::Frame>,
}

/// The input image the model expected and the one the IUT wrote.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ImageDiff {
    pub layout: canif_model::image::ImageLayout,
    pub expected: Vec<u8>,
    pub actual: Vec<u8>,
}

impl ImageDiff {
    /// One line per member whose bytes differ, named as `canif export`
    /// declares it (`Inputs.RxMessage[0].CobID`), with both values' bytes;
    /// the first `most`, then how many more.
    pub fn lines(&self, most: usize) -> Vec<String> {
        use canif_plctypes::{ImageTypes, INPUTS};
        let types = ImageTypes::of(&self.layout, String::new());
        let hex = |bytes: &[u8]| {
            bytes
                .iter()
                .map(|b| format!("{b:02X}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let length = self.expected.len().max(self.actual.len());
        let byte = |image: &[u8], at: usize| image.get(at).copied();
        let mut lines = Vec::new();
        let mut at = 0;
        while at < length {
            if byte(&self.expected, at) == byte(&self.actual, at) {
                at += 1;
                continue;
            }
            let (name, range) = types
                .path_at(INPUTS, at)
                .map(|(path, range)| (format!("Inputs.{path}"), range))
                .unwrap_or_else(|| ("beyond the image".to_string(), at..at + 1));
            let part = |image: &[u8]| {
                let end = range.end.min(image.len());
                hex(image.get(range.start.min(end)..end).unwrap_or_default())
            };
            lines.push(format!(
                "byte {}..{} {name}: expected {}, actual {}",
                range.start,
                range.end,
                part(&self.expected),
                part(&self.actual)
            ));
            at = range.end.max(at + 1);
        }
        if lines.len() > most {
            let more = lines.len() - most;
            lines.truncate(most);
            lines.push(format!("… and {more} more members differ"));
        }
        lines
    }
}

impl Failure {
    /// A failure with nothing before it to show: `what` was `actual`, not
    /// `expected`, in a check that stops there (a refusal, a node's answer).
    /// A cycle's history is added to it where there is one (`..Failure::stopped`).
    pub fn stopped(
        (requirements, scenario): (Vec<ReqId>, String),
        what: String,
        (expected, actual): (String, String),
    ) -> Self {
        Failure {
            requirements,
            scenario,
            cycle: 0,
            time: 0,
            what,
            expected,
            actual,
            context: Vec::new(),
            timeline: Default::default(),
            frames: None,
            images: None,
            rest: crate::verdict::Rest::Stopped,
            further: Vec::new(),
        }
    }

    /// This breach and the later ones of the same scenario, each alone.
    pub fn breaches(&self) -> Vec<Failure> {
        let first = Failure {
            further: Vec::new(),
            ..self.clone()
        };
        std::iter::once(first)
            .chain(self.further.iter().cloned())
            .collect()
    }

    /// Where and what, and the requirements it breaks.
    pub fn headline(&self) -> String {
        format!(
            "{} at cycle {}: {} differs ({})",
            self.scenario,
            self.cycle,
            self.what,
            ReqId::join(&self.requirements, ", ")
        )
    }

    /// One line: what differs, expected and actual.
    pub fn cause(&self) -> String {
        format!(
            "cycle {}: {} differs: expected {}, actual {}",
            self.cycle, self.what, self.expected, self.actual
        )
    }

    /// Expected and actual, and the cycles before.
    pub fn details(&self) -> String {
        let bytes = match &self.images {
            Some(images) => format!(
                "\nthe input image's members that differ:\n  {}",
                images.lines(12).join("\n  ")
            ),
            None => String::new(),
        };
        format!(
            "{}\n  expected: {}\n  actual:   {}\n  at t = {:.6} ms{bytes}\ncycles before:\n  {}",
            self.headline(),
            self.expected,
            self.actual,
            self.time as f64 / 1e6,
            self.context.join("\n  ")
        )
    }
}

/// A frame that ended on the bus, as a failure's history shows it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct BusFrame {
    /// The end of its last bit.
    pub end: Nanos,
    pub from_iut: bool,
    /// The frame in candump notation.
    pub text: String,
}

/// A failure's last cycles as data: each side's own rows.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Timeline {
    /// A device under test: the model's input header against the IUT's.
    Cycles(Vec<CycleView>),
    /// A client under test: what each task was handed and left, and the row
    /// of the diagram the breach is about.
    Tasks { tasks: Vec<TaskView>, row: TaskRow },
}

impl Timeline {
    pub fn is_empty(&self) -> bool {
        match self {
            Timeline::Cycles(cycles) => cycles.is_empty(),
            Timeline::Tasks { tasks, .. } => tasks.is_empty(),
        }
    }
}

impl Default for Timeline {
    fn default() -> Self {
        Timeline::Cycles(Vec::new())
    }
}

/// One task of a client's failure: the input header the master handed it,
/// the output header it left, what its application asked and got, and the
/// frames that ended on the bus since the task before.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct TaskView {
    pub task: u64,
    pub time: Nanos,
    pub inputs: InputHeader,
    pub outputs: OutputHeader,
    /// The application's requests this task was given.
    pub requests: usize,
    /// The messages it delivered to its application.
    pub delivered: usize,
    pub frames: Vec<BusFrame>,
}

/// What a client's breach is about, as a row of its diagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TaskRow {
    TxCounter,
    RxCounter,
    NoOfTxMessages,
    /// What it delivered to its application, or told it was sent.
    Application,
    /// What the device sent on the bus from its batches.
    Bus,
}

/// One cycle of a failure's history: the PLC's outputs, the model's (expected)
/// and the IUT's (actual) input header, and the frames that ended on the bus
/// since the cycle before.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
    /// Cycles and polls in which the IUT differed from the model only where
    /// the documents leave it open (don't-care bytes, the SYNC1 jitter, the
    /// bounds of G3): what its pass tolerated.
    pub tolerated: u64,
    /// Wall time the scenario took.
    pub elapsed: std::time::Duration,
    /// What the IUT itself declared (a device's `configure` answer, a
    /// client's `started`): the run judged it by this.
    pub iut_declares: crate::declare::Declares,
    /// What the documents allow but an author wants to know (PLC side).
    pub advisories: crate::advisory::Advisories,
}

impl ScenarioRun {
    /// A run of `scenario` that ended as `outcome` before any cycle: an
    /// error, a skip after what is under test broke, a check that counts
    /// no cycles. What a run counts is added to it (`..ScenarioRun::ended`).
    pub fn ended(scenario: String, covers: Vec<ReqId>, outcome: Outcome) -> Self {
        ScenarioRun {
            scenario,
            covers,
            outcome,
            cycles: 0,
            frames_checked: 0,
            tolerated: 0,
            elapsed: std::time::Duration::ZERO,
            iut_declares: Default::default(),
            advisories: Default::default(),
        }
    }
}

/// How one Gherkin scenario (or Examples row) ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GherkinOutcome {
    Pass,
    /// `step` is the failing step's line; `report` is cucumber's whole account;
    /// `blamed` the scenario's tags the failed check witnesses.
    /// `rest`: what the failure says of the tags not blamed.
    Fail {
        step: String,
        report: String,
        blamed: Vec<String>,
        rest: crate::verdict::Rest,
    },
    /// The implementation broke: not a non-conformance.
    Error(String),
}

/// One Gherkin scenario (or Examples row) run against one profile.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GherkinRun {
    /// `feature file: scenario name`, and an Examples row's values: stable
    /// while lines move.
    pub id: String,
    pub file: String,
    pub line: usize,
    pub requirements: Vec<String>,
    pub outcome: GherkinOutcome,
    pub elapsed: std::time::Duration,
}
