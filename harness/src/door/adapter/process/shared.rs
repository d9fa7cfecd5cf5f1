//! The exchanges of the cycle: where the agreed version carries them, and
//! protocol 3's (a record in the shared mapping, the answer waited for
//! there, the line channel watched meanwhile).

use std::time::Duration;

use super::{truncate, AdapterProcess};
use crate::door::adapter::lines::Line;
use crate::door::adapter::protocol::{BusEvent, Expected, Request};
use crate::error::{IutCause, IutError};

impl AdapterProcess {
    /// A request of the cycle and its answer, where the agreed version
    /// carries it: a record in the shared mapping (after `events`, a polled
    /// device's bus events), or a line (`events` must then be empty: the
    /// lines carry them as requests of their own).
    pub(crate) fn exchange_record<T>(
        &mut self,
        events: &[BusEvent],
        request: &Request,
        expected: Expected<T>,
    ) -> Result<T, IutError> {
        self.post_record(events, request)?;
        self.collect_record(request, expected)
    }

    /// [`Self::exchange_record`] in two halves, so that the harness can work
    /// while the IUT answers: in the shared mapping the request is posted
    /// here; on lines it is sent by [`Self::collect_record`].
    pub(crate) fn post_record(
        &mut self,
        events: &[BusEvent],
        request: &Request,
    ) -> Result<(), IutError> {
        match self.shared_agreed {
            true => self.post_shared(events, request),
            false => Ok(()),
        }
    }

    /// The answer to `request`, posted by [`Self::post_record`].
    pub(crate) fn collect_record<T>(
        &mut self,
        request: &Request,
        expected: Expected<T>,
    ) -> Result<T, IutError> {
        match self.shared_agreed {
            true => self.collect_shared(request.name(), expected),
            false => self.exchange(request, expected),
        }
    }

    /// Protocol 3: posts `request` (after `events`, for a polled device) in
    /// the shared mapping; [`Self::collect_shared`] waits for its answer.
    pub(super) fn post_shared(
        &mut self,
        events: &[BusEvent],
        request: &Request,
    ) -> Result<(), IutError> {
        if let Some(failure) = &self.failed {
            return Err(failure.clone());
        }
        // No look at the lines before posting (a system call per record):
        // what comes there meanwhile is found while waiting, or before the
        // next line's request.
        let posted = match self.shared.as_mut() {
            Some(shared) => shared.post(events, request),
            None => Err("no shared mapping was handed to it".to_string()),
        };
        posted.map_err(|why| self.fail(IutCause::HarnessBug, why))
    }

    /// Protocol 3: waits in the shared mapping for the answer `expected` to
    /// the request `name` posted last, watching the line channel meanwhile
    /// as [`Self::exchange_line`] watches it for an answer: a host's report
    /// of an access past an image, a line nobody asked for, its end; and the
    /// per-request limit.
    pub(super) fn collect_shared<T>(
        &mut self,
        name: &str,
        expected: Expected<T>,
    ) -> Result<T, IutError> {
        if let Some(failure) = &self.failed {
            return Err(failure.clone());
        }
        let started = std::time::Instant::now();
        let limit = self.timeouts.request;
        loop {
            if self
                .shared
                .as_ref()
                .is_some_and(|shared| shared.wait(Duration::from_millis(10)))
            {
                break;
            }
            let line = self.lines.next(Duration::ZERO);
            let (cause, what) = match line {
                Line::Silent if started.elapsed() < limit => continue,
                Line::Silent => {
                    self.kill();
                    return Err(self.fail(
                        IutCause::Silent,
                        format!(
                            "no answer to `{name}` within {} ms, the per-request limit (--timeout-ms) (hung; killed)",
                            limit.as_millis()
                        ),
                    ));
                }
                // A host's report of an access past an image: `fail` says where.
                Line::Text(line) if self.reports_outside(&line) => {
                    (IutCause::Gone, format!("while answering `{name}`"))
                }
                Line::Text(line) => (
                    IutCause::Protocol,
                    format!(
                        "printed a line on its channel while its answer to `{name}` was due in shared memory: {}",
                        truncate(&line)
                    ),
                ),
                Line::Broken(what) => (
                    IutCause::Protocol,
                    format!("{what} instead of answering `{name}`"),
                ),
                Line::Closed => (
                    IutCause::Gone,
                    match self.exit_status() {
                        Some(status) => format!("exited ({status}) instead of answering `{name}`"),
                        None => format!(
                            "closed its channel instead of answering `{name}` (still running; killed)"
                        ),
                    },
                ),
            };
            self.kill();
            return Err(self.fail(cause, what));
        }
        let answer = match self.shared.as_mut() {
            Some(shared) => shared.answer(),
            None => Err("no shared mapping".to_string()),
        };
        match answer {
            // (The answer's kind is named by `take` where it is not the one due.)
            Ok(answer) => self.take(answer, expected, "(a record in shared memory)"),
            Err(why) => Err(self.fail(
                IutCause::Protocol,
                format!("wrote a record that is no answer: {why}"),
            )),
        }
    }
}
