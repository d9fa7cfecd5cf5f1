//! What a run says on stderr while it works through the profiles: the
//! scenario running (on a terminal), then one line per profile with how
//! many are done and about how long the rest take. Its scenario counts are
//! the summary's `scenarios` column.

use std::io::{IsTerminal, Write as _};

use canif_harness::run::ProfileRun;
use canif_harness::{Outcome, ScenarioRun};
use canif_spec::{Catalogue, Profile};

pub(crate) struct Progress<'a> {
    n: usize,
    count: usize,
    profile: &'a str,
    done: usize,
    /// The profile's cases, when known; and when its first began.
    cases: Option<usize>,
    started: std::time::Instant,
    terminal: bool,
}

impl<'a> Progress<'a> {
    pub(crate) fn new(n: usize, count: usize, profile: &'a str) -> Self {
        Progress {
            n,
            count,
            profile,
            done: 0,
            cases: None,
            started: std::time::Instant::now(),
            terminal: std::io::stderr().is_terminal(),
        }
    }

    /// With the number of cases the profile's run has: the terminal's line
    /// then says how far it is and about how long the rest take.
    pub(crate) fn of_cases(self, cases: usize) -> Self {
        Progress {
            cases: Some(cases),
            ..self
        }
    }

    pub(crate) fn scenario(&mut self, run: &ScenarioRun) {
        self.done += 1;
        if self.terminal {
            let elapsed = self.started.elapsed().as_secs_f64();
            let pace = match self.cases {
                Some(cases) if cases > self.done => format!(
                    "{} of {cases} scenarios, {elapsed:.0} s, about {:.0} s left",
                    self.done,
                    elapsed / self.done as f64 * (cases - self.done) as f64
                ),
                Some(cases) => format!("{} of {cases} scenarios, {elapsed:.0} s", self.done),
                None => format!("{} scenarios, {elapsed:.0} s", self.done),
            };
            err!(
                "\r\x1b[2K[{}/{}] {}: {} ({pace})",
                self.n + 1,
                self.count,
                self.profile,
                run.scenario,
            );
            let _ = std::io::stderr().flush();
        }
    }

    /// The line of a profile run beside others (`--jobs`): how many are
    /// done after how long, and about how long the rest take at that pace.
    pub(crate) fn done_after(
        self,
        result: &ProfileRun,
        (catalogue, profile, unit): (&Catalogue, &Profile, Option<&str>),
        (done, elapsed): (usize, std::time::Duration),
    ) {
        let left = elapsed.as_secs_f64() / done as f64 * (self.count - done) as f64;
        let pace = match self.count - done {
            0 => format!(
                "{done} of {} profiles done in {:.0} s",
                self.count,
                elapsed.as_secs_f64()
            ),
            _ => format!(
                "{done} of {} profiles done in {:.0} s, about {left:.0} s left",
                self.count,
                elapsed.as_secs_f64()
            ),
        };
        if self.terminal {
            err!("\r\x1b[2K");
        }
        let line = self.line(result, catalogue, profile, unit);
        errln!("{line} [{pace}]");
    }

    /// The profile's line; `unit`: what its cycles are (device or task
    /// cycles), `None` for cases that run no cycles (the CANopen checks).
    fn line(
        &self,
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
            self.n + 1,
            self.count,
            self.profile,
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
