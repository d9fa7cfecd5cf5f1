//! # canif-features — the manual as executable scenarios
//!
//! The `.feature` files in this folder say, in the manual's words, what the CAN
//! interface does; the steps in [`steps`] drive any implementation the harness
//! supports. [`run_scenario`] runs one scenario against one target.

#![forbid(unsafe_code)]

mod bus_coupler;
pub mod catalogue;
pub mod client_world;
pub mod schedule;
pub mod steps;
pub mod world;

pub use catalogue::{scenarios, ScenarioInfo};
pub use client_world::{set_client_target, ClientTarget, ClientWorld};
pub use schedule::UnderTest;
pub use world::{set_target, CanWorld, Target};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/features.rs"));
}

use std::io;
use std::sync::{Arc, Mutex};

use canif_spec::ReqId;
use cucumber::writer::Stats as _;
use cucumber::writer::{self, Coloring, Verbosity};
use cucumber::WriterExt as _;

/// Output captured from cucumber's writer.
#[derive(Clone, Default)]
struct Captured(Arc<Mutex<Vec<u8>>>);

impl io::Write for Captured {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0
            .lock()
            .map_err(|_| io::Error::other("poisoned"))?
            .extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// Feeds cucumber the embedded features instead of reading a folder.
struct Embedded;

impl cucumber::Parser<Vec<cucumber::gherkin::Feature>> for Embedded {
    type Cli = cucumber::cli::Empty;
    type Output = futures::stream::Iter<
        std::vec::IntoIter<cucumber::parser::Result<cucumber::gherkin::Feature>>,
    >;

    fn parse(self, input: Vec<cucumber::gherkin::Feature>, _: Self::Cli) -> Self::Output {
        futures::stream::iter(input.into_iter().map(Ok).collect::<Vec<_>>())
    }
}

/// How one scenario ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ScenarioOutcome {
    Passed,
    /// Cucumber's report of the failing step, and the requirements its failed
    /// check witnesses (empty: every tag of the scenario).
    Failed {
        report: String,
        witness: Vec<ReqId>,
    },
    /// The IUT itself broke (could not start, broke the protocol): not a non-conformance.
    Error(String),
    /// The IUT refused the interface the scenario needs, which the profile offers.
    Refused {
        interface: String,
        reason: String,
    },
}

impl ScenarioOutcome {
    fn failed(report: String) -> Self {
        ScenarioOutcome::Failed {
            report,
            witness: Vec::new(),
        }
    }
}

/// Runs the scenario at `line` of `file` against `target`.
pub fn run_scenario(file: &str, line: usize, target: Target) -> ScenarioOutcome {
    set_target(target);
    run_in::<CanWorld>(file, line)
}

/// Runs the PLC-side scenario at `line` of `file` (a `@plc` feature) against `target`.
pub fn run_client_scenario(file: &str, line: usize, target: ClientTarget) -> ScenarioOutcome {
    set_client_target(target);
    run_in::<ClientWorld>(file, line)
}

fn run_in<W>(file: &str, line: usize) -> ScenarioOutcome
where
    W: cucumber::World + cucumber::codegen::WorldInventory + std::fmt::Debug,
{
    let Some(feature) = catalogue::feature(file).and_then(|f| catalogue::only(f, line)) else {
        return ScenarioOutcome::failed(format!("no scenario at {file}:{line}"));
    };
    // What cucumber's own parser does after reading a file: fill in the outline.
    let feature = match cucumber::feature::Ext::expand_examples(feature) {
        Ok(feature) => feature,
        Err(error) => return ScenarioOutcome::failed(format!("{file}:{line}: {error}")),
    };
    let _ = world::take_iut_error();
    let _ = world::take_witness();
    let _ = world::take_refused();
    let captured = Captured::default();
    let writer =
        writer::Basic::new(captured.clone(), Coloring::Never, Verbosity::ShowWorld).summarized();
    let result = futures::executor::block_on(
        W::cucumber::<&str>()
            .with_parser(Embedded)
            .with_writer(writer)
            .with_default_cli()
            .max_concurrent_scenarios(1)
            .filter_run(vec![feature], |_, _, _| true),
    );
    let output = String::from_utf8_lossy(&captured.0.lock().map(|b| b.clone()).unwrap_or_default())
        .into_owned();
    let stats = result.scenarios_stats();
    if let Some((interface, reason)) = world::take_refused() {
        ScenarioOutcome::Refused { interface, reason }
    } else if let Some(error) = world::take_iut_error() {
        ScenarioOutcome::Error(format!("the IUT broke: {error}\n{output}"))
    } else if result.execution_has_failed() || stats.failed > 0 || result.parsing_errors() > 0 {
        ScenarioOutcome::Failed {
            report: output,
            witness: world::take_witness(),
        }
    } else if stats.passed == 0 {
        ScenarioOutcome::failed(format!("no scenario ran at line {line} (skipped steps mean a step has no definition):\n{output}"))
    } else {
        ScenarioOutcome::Passed
    }
}
