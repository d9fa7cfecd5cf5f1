//! What a run says on stderr while it works: the run's events
//! ([`canif_runner::Event`]) as lines. The scenario running (on a terminal),
//! then one line per profile with how many are done and about how long the
//! rest take; the terminals surveyed, what was left out, what is flaky. Its
//! scenario counts are the summary's `scenarios` column.

use std::io::{IsTerminal, Write as _};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use canif_harness::run::ProfileRun;
use canif_harness::Outcome;
use canif_runner::{Event, Observer, Position, Stage};
use canif_spec::{Catalogue, Profile};

/// The run's events said on stderr.
pub(crate) struct Progress<'c> {
    catalogue: &'c Catalogue,
    terminal: bool,
    /// The profile running one at a time: its cases so far, of how many,
    /// since when.
    current: Mutex<(usize, usize, Instant)>,
}

impl<'c> Progress<'c> {
    pub(crate) fn new(catalogue: &'c Catalogue) -> Self {
        Progress {
            catalogue,
            terminal: std::io::stderr().is_terminal(),
            current: Mutex::new((0, 0, Instant::now())),
        }
    }

    /// The running scenario on the terminal's last line, with how far the
    /// profile is and about how long the rest takes.
    fn scenario(&self, at: Position, profile: &Profile, scenario: &str) {
        if !self.terminal {
            return;
        }
        let mut current = self.current.lock().unwrap_or_else(|e| e.into_inner());
        current.0 += 1;
        let (done, cases, started) = *current;
        let elapsed = started.elapsed().as_secs_f64();
        let pace = match cases > done {
            true => format!(
                "{done} of {cases} scenarios, {elapsed:.0} s, about {:.0} s left",
                elapsed / done as f64 * (cases - done) as f64
            ),
            false => format!("{done} of {cases} scenarios, {elapsed:.0} s"),
        };
        err!(
            "\r\x1b[2K[{}/{}] {}: {scenario} ({pace})",
            at.index + 1,
            at.count,
            profile.name,
        );
        let _ = std::io::stderr().flush();
    }

    /// A profile's line: how many profiles are done after how long, and
    /// about how long the rest take at that pace.
    fn profile_done(
        &self,
        (at, profile, result): (Position, &Profile, &ProfileRun),
        (done, elapsed): (usize, Duration),
        unit: Option<&str>,
    ) {
        let left = elapsed.as_secs_f64() / done as f64 * (at.count - done) as f64;
        let pace = match at.count - done {
            0 => format!(
                "{done} of {} profiles done in {:.0} s",
                at.count,
                elapsed.as_secs_f64()
            ),
            _ => format!(
                "{done} of {} profiles done in {:.0} s, about {left:.0} s left",
                at.count,
                elapsed.as_secs_f64()
            ),
        };
        if self.terminal {
            err!("\r\x1b[2K");
        }
        let line = Self::line(at, result, self.catalogue, profile, unit);
        errln!("{line} [{pace}]");
    }

    /// The profile's line; `unit`: what its cycles are (device or task
    /// cycles), `None` for cases that run no cycles (the CANopen checks).
    fn line(
        at: Position,
        result: &ProfileRun,
        catalogue: &Catalogue,
        profile: &Profile,
        unit: Option<&str>,
    ) -> String {
        let count = |error: bool| {
            result
                .runs
                .iter()
                .filter(|r| match r.outcome {
                    Outcome::Fail(_) => !error,
                    Outcome::Error(_) => error,
                    Outcome::Pass => false,
                })
                .count()
        };
        let volume = match unit {
            Some(unit) => format!(
                "{} scenarios, {} {unit}, {} frames checked",
                result.runs.len(),
                result.cycles(),
                result.frames_checked()
            ),
            None => format!("{} checks", result.runs.len()),
        };
        format!(
            "[{}/{}] {:<22} {volume}: {}",
            at.index + 1,
            at.count,
            profile.name,
            match (count(false), count(true)) {
                (0, 0) => "all pass".to_string(),
                (f, 0) => format!(
                    "{f} FAIL ({})",
                    result.failed_requirements(catalogue, profile).join(", ")
                ),
                (f, e) => format!("{f} fail, {e} ERROR"),
            }
        )
    }
}

impl Observer for Progress<'_> {
    fn event(&self, event: Event<'_>) {
        match event {
            Event::ProfileStarted { cases, .. } => {
                *self.current.lock().unwrap_or_else(|e| e.into_inner()) =
                    (0, cases, Instant::now());
            }
            Event::ScenarioFinished { at, profile, run } => {
                self.scenario(at, profile, &run.scenario)
            }
            Event::ProfileFinished {
                at,
                profile,
                run,
                done,
                elapsed,
                unit,
            } => self.profile_done((at, profile, run), (done, elapsed), unit),
            Event::TerminalSurveyed { profile, facts } => {
                errln!(
                    "{}: {} vendor {:#010x} product {:#010x} revision {:#010x}, SyncManagers {}, {} output and {} input bytes ({} of CAN status), 0x1C32:05 {}, an idle cycle {} µs (worst {} µs)",
                    profile.name,
                    facts.name,
                    facts.vendor_id,
                    facts.product_code,
                    facts.revision,
                    facts.layout(),
                    facts.output_bytes,
                    facts.input_bytes,
                    facts.status_bytes,
                    facts.local_cycle_ns.map_or("not answered".into(), |ns| format!("{ns} ns")),
                    facts.mean_cycle_ns / 1_000,
                    facts.worst_cycle_ns / 1_000
                );
                if let Some(period) = facts.period_ns {
                    errln!(
                        "{}: soak of {} cycles every {} µs: {} missed their deadline",
                        profile.name,
                        facts.cycles,
                        period / 1_000,
                        facts.missed_cycles
                    );
                }
            }
            Event::TerminalNotSurveyed { profile, error } => errln!(
                "{}: the terminal could not be surveyed: {error}",
                profile.name
            ),
            Event::GherkinFinished {
                ran,
                failed,
                errors,
            } => errln!("Gherkin scenarios: {ran} run, {failed} failed, {errors} error"),
            Event::LeftOut(line) => errln!("left out: {line}"),
            Event::Flaky(key) => {
                errln!("FLAKY {key}: it failed in the run before and passes now")
            }
            Event::Interrupted(Stage::Profiles) => {
                errln!("interrupted: the remaining profiles are not run")
            }
            Event::Interrupted(Stage::Gherkin) => {}
        }
    }
}
