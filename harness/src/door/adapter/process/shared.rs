//! Protocol 3's exchange: a record in the shared mapping, the answer
//! waited for there, the line channel watched meanwhile.

use std::time::Duration;

use super::{truncate, AdapterProcess};
use crate::door::adapter::lines::Line;
use crate::door::adapter::protocol::{BusEvent, Expected, Request};
use crate::error::{IutCause, IutError};

impl AdapterProcess {
    /// Protocol 3: posts `request` (after `events`, for a polled device) in
    /// the shared mapping and waits there for
    /// the answer `expected`, watching the line channel meanwhile as
    /// [`Self::exchange_line`] watches it for an answer: a host's report of
    /// an access past an image, a line nobody asked for, its end; and the
    /// per-request limit.
    pub(crate) fn exchange_shared<T>(
        &mut self,
        events: &[BusEvent],
        request: &Request,
        expected: Expected<T>,
    ) -> Result<T, IutError> {
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
        if let Err(why) = posted {
            return Err(self.fail(IutCause::HarnessBug, why));
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
            let what = match line {
                Line::Silent if started.elapsed() < limit => continue,
                Line::Silent => {
                    self.kill();
                    return Err(self.fail(
                        IutCause::Silent,
                        format!(
                            "no answer to `{}` within {} ms, the per-request limit (--timeout-ms) (hung; killed)",
                            request.name(),
                            limit.as_millis()
                        ),
                    ));
                }
                Line::Text(line) if self.reports_outside(&line) => {
                    format!("while answering `{}`", request.name())
                }
                Line::Text(line) => format!(
                    "printed a line on its channel while its answer to `{}` was due in shared memory: {}",
                    request.name(),
                    truncate(&line)
                ),
                Line::Broken(what) => format!("{what} instead of answering `{}`", request.name()),
                Line::Closed => match self.exit_status() {
                    Some(status) => format!("exited ({status}) instead of answering `{}`", request.name()),
                    None => format!("closed its channel instead of answering `{}` (still running; killed)", request.name()),
                },
            };
            self.kill();
            let cause = match self.outside {
                Some(_) => IutCause::Gone,
                None if what.starts_with("exited") || what.starts_with("closed") => IutCause::Gone,
                None => IutCause::Protocol,
            };
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
