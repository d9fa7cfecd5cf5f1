//! What a run says while it works: one typed stream of events (nextest's
//! shape), rendered by whoever runs it — the CLI's progress lines, a test
//! that counts, a bench that says nothing. The run's result is the
//! [`RunReport`](canif_harness::report::RunReport) it returns, computed once;
//! the events only tell how it is getting on.

use std::time::Duration;

use canif_harness::report::TerminalEntry;
use canif_harness::run::ProfileRun;
use canif_harness::ScenarioRun;
use canif_spec::Profile;

/// Where a profile stands in its run: the `index`-th of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Position {
    pub index: usize,
    pub count: usize,
}

/// The stage of a run a signal stopped before.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The profiles not yet started are not run.
    Profiles,
    /// The Gherkin scenarios are not run.
    Gherkin,
}

/// One thing a run tells as it happens.
#[derive(Debug, Clone, Copy)]
pub enum Event<'a> {
    /// A profile's cases begin, one profile at a time: `cases` of them are selected.
    ProfileStarted {
        at: Position,
        profile: &'a Profile,
        cases: usize,
    },
    /// One case of a profile ran (profiles run one at a time only: beside
    /// others, `--jobs`, a profile is told when it is done).
    ScenarioFinished {
        at: Position,
        profile: &'a Profile,
        run: &'a ScenarioRun,
    },
    /// A profile's cases are done: `done` profiles of the run after `elapsed`.
    ProfileFinished {
        at: Position,
        profile: &'a Profile,
        run: &'a ProfileRun,
        done: usize,
        elapsed: Duration,
        /// What its cycles are (device or task cycles); `None` for checks
        /// that run no cycles (the CANopen node's).
        unit: Option<&'static str>,
    },
    /// An EtherCAT terminal was brought up once before the run, for the report.
    TerminalSurveyed {
        profile: &'a Profile,
        facts: &'a TerminalEntry,
    },
    /// It could not be: the run itself meets the same terminal and reports what broke.
    TerminalNotSurveyed {
        profile: &'a Profile,
        error: &'a str,
    },
    /// The Gherkin stage is over: how many scenarios ran, failed and erred.
    GherkinFinished {
        ran: usize,
        failed: usize,
        errors: usize,
    },
    /// Something the run leaves out, and why (the report says it too).
    LeftOut(&'a str),
    /// `profile::check` failed in the run being rerun and passes now.
    Flaky(&'a str),
    /// A signal stopped the run before this stage.
    Interrupted(Stage),
}

/// Who hears a run's events. Profiles may run on several threads (`--jobs`),
/// so an observer is shared between them.
pub trait Observer: Sync {
    fn event(&self, event: Event<'_>);
}

impl<F: Fn(Event<'_>) + Sync> Observer for F {
    fn event(&self, event: Event<'_>) {
        self(event)
    }
}

/// An observer that hears nothing: a test's or a bench's run.
pub struct Quiet;

impl Observer for Quiet {
    fn event(&self, _: Event<'_>) {}
}
