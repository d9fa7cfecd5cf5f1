//! # canif-runner — a run of canif as one library call
//!
//! The command line, the tests and the benches run the suite the same way:
//! a [`Plan`] of one side (the profiles, the selection, `--jobs`, a rerun,
//! a shard), then [`Plan::run`], which checks the plan, runs every profile's
//! cases and the Gherkin scenarios, and returns the
//! `RunReport`, finished in one place.
//! While it works it tells an [`Observer`] typed [`Event`]s; what to print
//! is the observer's business.
//!
//! A side is a [`Campaign`]: the device side (`canif_harness::device::Options`),
//! the PLC side (`canif_harness::client::suite::ClientOptions`) and the
//! CANopen suite (`canif_harness::canopen::side::CanopenSide`).

#![forbid(unsafe_code)]

mod canopen;
mod device;
mod error;
mod event;
mod parallel;
mod plan;
mod plc;
mod rerun;
mod socketcan;

pub use canopen::node_profile;
pub use error::{nearest, PlanError, RerunError};
pub use event::{Event, Observer, Position, Quiet, Stage};
pub use plan::Plan;
pub use rerun::Rerun;

use canif_harness::report::RunReport;
use canif_harness::run::Cases;
use canif_spec::Catalogue;

/// A side of the suite as a whole run: what it checks before it starts and
/// how its stages make one report.
pub trait Campaign: Cases<UnderTest: Sync> + Sync + Sized {
    /// What its cycles are called in progress lines (`None`: no cycles).
    const UNIT: Option<&'static str>;

    /// What is under test, as reports and `--rerun-failed` name it.
    fn name_of(under_test: &Self::UnderTest) -> String;

    /// What profiles run side by side (`--jobs`) would share that cannot
    /// be shared (one link, one library in canif's process, one bus).
    fn shared(plan: &Plan<'_, Self>, under_test: &Self::UnderTest) -> Option<&'static str>;

    /// What must hold before anything runs (a door's or a bus's own
    /// conditions, what is declared against what is under test).
    fn preflight(
        plan: &Plan<'_, Self>,
        catalogue: &Catalogue,
        under_test: &Self::UnderTest,
    ) -> Result<(), PlanError>;

    /// Every stage of the run, judged once into the report.
    fn execute(
        plan: &Plan<'_, Self>,
        catalogue: &Catalogue,
        under_test: &Self::UnderTest,
        observer: &dyn Observer,
    ) -> RunReport;
}

impl<S: Campaign> Plan<'_, S> {
    /// The run: the selection and the side's conditions checked, then every
    /// stage, told to `observer` as it goes; the report, finished.
    pub fn run(
        &self,
        catalogue: &Catalogue,
        under_test: &S::UnderTest,
        observer: &dyn Observer,
    ) -> Result<RunReport, PlanError> {
        self.check_selection(catalogue)?;
        // A rerun is of the implementation the report was.
        if let Some(rerun) = &self.rerun {
            rerun.same_iut(&S::name_of(under_test))?;
        }
        if let Some(why) = S::shared(self, under_test).filter(|_| self.jobs > 1) {
            return Err(PlanError::Preflight(format!(
                "--jobs {}: the profiles would share {why}; run them one at a time",
                self.jobs
            )));
        }
        S::preflight(self, catalogue, under_test)?;
        Ok(S::execute(self, catalogue, under_test, observer))
    }
}
