//! An implementation under test in another process, in any language: one
//! JSON object per line on its stdin and stdout, its stderr its log. One
//! type serves both roles of the adapter protocol.
//!
//! Whatever the process does — exit, hang, print garbage, answer out of
//! turn — becomes an error naming what happened and the last lines of its
//! stderr; the harness never waits longer than the per-exchange timeout,
//! nor, for the first answer (the process, an interpreter, a library
//! loading), longer than the start timeout: a slow start is not a hang.

use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::os::fd::{AsFd, OwnedFd};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::lines::{Line, LineReader};
use super::protocol::{Answer, Expected, Request, SharedOffer};
use super::shared::HarnessEnd;
use super::CONTROL_FDS;

mod shared;
use crate::door::Timeouts;
use crate::error::{IutCause, IutError};

/// How many lines of the IUT's stderr an error shows.
const STDERR_LINES: usize = 20;

/// Where the protocol runs between canif and the process.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Channel {
    /// Its stdin and stdout (any language: docs/adapter-protocol.md).
    Stdio,
    /// Descriptors [`CONTROL_FDS`], apart from stdin, stdout and stderr,
    /// which stay the library's own: a `canif lib-host`. What the library
    /// prints is its output, and the host's report of an access past an
    /// image comes on the channel, where printing cannot forge it.
    Control,
}

/// Reads `stream` line by line into `log`, keeping the last [`STDERR_LINES`].
fn read_log(
    stream: impl std::io::Read + Send + 'static,
    log: Arc<Mutex<VecDeque<String>>>,
) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        let mut reader = BufReader::new(stream);
        let mut line = Vec::new();
        loop {
            line.clear();
            match std::io::Read::take(&mut reader, 4096).read_until(b'\n', &mut line) {
                Ok(0) | Err(_) => break,
                Ok(_) => {}
            }
            let text = String::from_utf8_lossy(&line).trim_end().to_string();
            if let Ok(mut log) = log.lock() {
                log.push_back(text);
                if log.len() > STDERR_LINES {
                    log.pop_front();
                }
            }
        }
    })
}

/// Pins the calling thread to the CPU it runs on; a child started from it
/// inherits that. Where the system says no, nothing changes.
fn share_cpu() {
    use nix::sched::{sched_getcpu, sched_setaffinity, CpuSet};
    use nix::unistd::Pid;
    if let Ok(cpu) = sched_getcpu() {
        let mut set = CpuSet::new();
        if set.set(cpu).is_ok() {
            let _ = sched_setaffinity(Pid::from_raw(0), &set);
        }
    }
}

/// An implementation under test in another process, the subreaper of
/// whatever it starts (`canif_cabi::isolation`: a process that leaves its
/// group or session, a daemon's double fork, still ends with it), in either role: a device (`device::exec_iut`)
/// or a client (`client::exec`).
pub(crate) struct AdapterProcess {
    command: String,
    child: Child,
    /// Where requests go (its stdin, or its control channel).
    requests: Option<File>,
    /// Where answers come from.
    lines: LineReader,
    channel: Channel,
    /// Where the library stopped, as a hosting `canif lib-host` reported it.
    outside: Option<canif_cabi::guard::OutsideImage>,
    stderr: Arc<Mutex<VecDeque<String>>>,
    /// Read its log (stderr; and stdout, where that is no channel) until
    /// the IUT's tree closes them.
    log_readers: Vec<std::thread::JoinHandle<()>>,
    timeouts: Timeouts,
    /// It has answered once: it started, and the per-request limit holds.
    started: bool,
    /// The first failure; every later call reports it.
    failed: Option<IutError>,
    /// Protocol 3's mapping and wake-ups, handed to the process at its start.
    shared: Option<HarnessEnd>,
    /// The process agreed to version 3: the cycle's requests go there.
    shared_agreed: bool,
}

impl AdapterProcess {
    /// Starts `command` (through `sh -c`) in a new process group; with
    /// `same_cpu`, the calling thread and the IUT share the CPU the thread is
    /// on. It is handed protocol 3's mapping and eventfds (`shared::SHARED_FDS`),
    /// to use if it agrees to version 3.
    pub(crate) fn spawn(
        command: &str,
        timeouts: Timeouts,
        same_cpu: bool,
        channel: Channel,
    ) -> Result<Self, IutError> {
        use std::os::unix::process::CommandExt;
        if same_cpu {
            share_cpu();
        }
        let broken = |what: &str, e: std::io::Error| {
            IutError::new(
                IutCause::NotStarted,
                format!("cannot start `{command}`: {what}: {e}"),
            )
        };
        canif_cabi::isolation::adopt_orphans();
        let mut sh = Command::new("sh");
        canif_cabi::isolation::as_subreaper(&mut sh)
            .arg("-c")
            .arg(command)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .process_group(0);
        // The control channel's far ends, kept open until the host has them.
        let mut far_ends: Vec<OwnedFd> = Vec::new();
        // Where the system gives no memfd or eventfd, version 3 is not
        // offered: the lines still are.
        let shared = HarnessEnd::new().ok();
        let mut handed: Vec<_> = shared.iter().flat_map(HarnessEnd::handed).collect();
        let control = match channel {
            Channel::Stdio => {
                sh.stdin(Stdio::piped());
                None
            }
            Channel::Control => {
                let (host_reads, requests) = std::io::pipe().map_err(|e| broken("pipe", e))?;
                let (answers, host_writes) = std::io::pipe().map_err(|e| broken("pipe", e))?;
                far_ends.push(host_reads.into());
                far_ends.push(host_writes.into());
                handed.push((far_ends[0].as_fd(), CONTROL_FDS.0));
                handed.push((far_ends[1].as_fd(), CONTROL_FDS.1));
                sh.stdin(Stdio::null());
                Some((
                    File::from(OwnedFd::from(requests)),
                    File::from(OwnedFd::from(answers)),
                ))
            }
        };
        canif_cabi::isolation::hand_over(&mut sh, &handed);
        drop(handed);
        let mut child = sh.spawn().map_err(|e| {
            IutError::new(
                IutCause::NotStarted,
                format!("cannot start `{command}`: {e}"),
            )
        })?;
        drop(far_ends);
        let stdout = child
            .stdout
            .take()
            .ok_or(IutError::new(IutCause::NotStarted, "no stdout"))?;
        let stderr = child
            .stderr
            .take()
            .ok_or(IutError::new(IutCause::NotStarted, "no stderr"))?;
        let log = Arc::new(Mutex::new(VecDeque::new()));
        let mut log_readers = vec![read_log(stderr, log.clone())];
        let (requests, answers) = match control {
            Some((requests, answers)) => {
                // What the library prints is its output, not the protocol.
                log_readers.push(read_log(stdout, log.clone()));
                (Some(requests), answers)
            }
            None => {
                let stdin = child.stdin.take().map(|s| File::from(OwnedFd::from(s)));
                (stdin, File::from(OwnedFd::from(stdout)))
            }
        };
        Ok(AdapterProcess {
            command: command.to_string(),
            child,
            requests,
            lines: LineReader::new(answers),
            channel,
            outside: None,
            stderr: log,
            log_readers,
            timeouts,
            started: false,
            failed: None,
            shared,
            shared_agreed: false,
        })
    }

    /// Whether nothing has gone wrong with it yet (a process that failed
    /// once is never asked again).
    pub(crate) fn is_sound(&self) -> bool {
        self.failed.is_none()
    }

    /// What `configure` or `start` agreed: whether the requests of the
    /// cycle go to the shared mapping ([`Self::exchange_record`]).
    pub(crate) fn agree_shared(&mut self, agreed: bool) {
        self.shared_agreed = agreed && self.shared.is_some();
    }

    /// What `configure` and `start` offer for protocol 3.
    pub(crate) fn shared_offer(&self) -> Option<SharedOffer> {
        self.shared.as_ref().map(|_| HarnessEnd::offer())
    }

    /// Ends the IUT and everything it started: the tree below it (see
    /// `canif_cabi::isolation`), and its process group.
    fn kill(&mut self) {
        use nix::sys::signal::{killpg, Signal};
        use nix::unistd::Pid;
        canif_cabi::isolation::end_tree(self.child.id());
        let _ = killpg(Pid::from_raw(self.child.id() as i32), Signal::SIGKILL);
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// The IUT's exit status, waiting a moment for it; `None` if it still runs.
    fn exit_status(&mut self) -> Option<std::process::ExitStatus> {
        for _ in 0..20 {
            if let Ok(Some(status)) = self.child.try_wait() {
                return Some(status);
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        None
    }

    fn stderr_tail(&self) -> String {
        // Give the stderr reader a moment to catch the last words of a dying process.
        std::thread::sleep(Duration::from_millis(20));
        let log = self
            .stderr
            .lock()
            .map(|l| l.iter().cloned().collect::<Vec<_>>())
            .unwrap_or_default();
        if log.is_empty() {
            "(its stderr is empty)".into()
        } else {
            format!("last lines of its stderr:\n  {}", log.join("\n  "))
        }
    }

    /// A line on a host's control channel saying where the library it hosts
    /// stopped (kept for [`Self::fail`]); never taken from a plain IUT.
    fn reports_outside(&mut self, line: &str) -> bool {
        if self.channel == Channel::Control {
            self.outside = canif_cabi::guard::OutsideImage::parse(line);
        }
        self.outside.is_some()
    }

    /// A process that ended before its first answer with the shell's "not
    /// found" (127) or "cannot execute" (126) never started: one error, the
    /// shell's own words.
    fn not_started(&mut self, status: Option<std::process::ExitStatus>) -> Option<IutError> {
        let code = status?.code()?;
        if self.started || !(code == 126 || code == 127) {
            return None;
        }
        // Its whole tree has ended: its log reaches its end, all of it read.
        self.kill();
        for reader in self.log_readers.drain(..) {
            let _ = reader.join();
        }
        let said = self
            .stderr
            .lock()
            .ok()
            .and_then(|log| log.back().cloned())
            .unwrap_or_else(|| format!("exit status {code}"));
        let error = IutError::new(
            IutCause::NotStarted,
            format!("cannot start `{}`: {said}", self.command),
        );
        Some(self.failed.get_or_insert(error).clone())
    }

    /// What broke, with the last lines of its log; every later call reports it too.
    /// A `canif lib-host` that died of an access past an image said where on
    /// its control channel: that is what the library did, not a broken exchange.
    pub(crate) fn fail(&mut self, cause: IutCause, what: String) -> IutError {
        let log = self.stderr_tail();
        let outside = self.outside.clone();
        let error = match outside {
            Some(outside) => IutError {
                cause: IutCause::OutsideImage,
                what: format!(
                    "accessed its {} image at offset {} (the image has {} bytes; stopped there, {what})",
                    outside.image, outside.offset, outside.size
                ),
                log: Some(log),
            },
            None => IutError {
                cause,
                what: format!("IUT `{}`: {what}", self.command),
                log: Some(log),
            },
        };
        self.failed.get_or_insert(error).clone()
    }

    /// A line already waiting answers nothing the harness asked: read as
    /// the next answer, it would desynchronise every exchange after it.
    fn no_stray_line(&mut self, request: &Request) -> Result<(), IutError> {
        match self.lines.next(Duration::ZERO) {
            Line::Text(stray) => {
                self.kill();
                // Garbage is garbage whenever it comes: say so, as for an answer.
                let what = match serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(
                    &stray,
                ) {
                    Ok(_) => "answered twice",
                    Err(_) => "printed what is not a JSON object",
                };
                return Err(self.fail(
                    IutCause::Protocol,
                    format!(
                        "{what}: a line nobody asked for before the `{}` request: {}",
                        request.name(),
                        truncate(&stray)
                    ),
                ));
            }
            // A broken line is broken before a request too (it was dropped
            // here once, and the run then waited for an answer in vain).
            Line::Broken(what) => {
                self.kill();
                return Err(self.fail(
                    IutCause::Protocol,
                    format!("{what} before the `{}` request (killed)", request.name()),
                ));
            }
            // Nothing waiting; a closed stdout shows at the answer.
            Line::Silent | Line::Closed => {}
        }
        Ok(())
    }

    /// Sends one request and waits for the one-line answer `expected`.
    pub(crate) fn exchange<T>(
        &mut self,
        request: &Request,
        expected: Expected<T>,
    ) -> Result<T, IutError> {
        let line = self.exchange_line(request)?;
        self.answer_of(&line, expected)
    }

    /// Sends one request; its answer line, unread.
    pub(crate) fn exchange_line(&mut self, request: &Request) -> Result<String, IutError> {
        if let Some(failure) = &self.failed {
            return Err(failure.clone());
        }
        self.no_stray_line(request)?;
        let mut line = serde_json::to_vec(request).expect("requests serialize");
        line.push(b'\n');
        // One write per request: the IUT wakes once.
        let written = match self.requests.as_mut() {
            Some(requests) => requests.write_all(&line).and_then(|_| requests.flush()),
            None => Err(std::io::Error::other("stdin closed")),
        };
        if let Err(error) = written {
            let status = self.exit_status();
            if let Some(error) = self.not_started(status) {
                return Err(error);
            }
            let what = match status {
                Some(status) => {
                    format!("exited ({status}) before the `{}` request", request.name())
                }
                None => format!("cannot write to its stdin ({error}; killed)"),
            };
            self.kill();
            return Err(self.fail(IutCause::Gone, what));
        }
        let (limit, which) = match self.started {
            true => (
                self.timeouts.request,
                "the per-request limit (--timeout-ms)",
            ),
            false => (
                self.timeouts.start,
                "the start limit (--start-timeout-ms, CANIF_START_TIMEOUT_MS)",
            ),
        };
        let line = match self.lines.next(limit) {
            Line::Text(line) if self.reports_outside(&line) => {
                self.kill();
                return Err(self.fail(
                    IutCause::Gone,
                    format!("while answering `{}`", request.name()),
                ));
            }
            Line::Text(line) => {
                self.started = true;
                line
            }
            Line::Broken(what) => {
                self.kill();
                return Err(self.fail(
                    IutCause::Protocol,
                    format!("{what} instead of answering `{}` (killed)", request.name()),
                ));
            }
            // Never answered its first request: it cannot start, and every
            // later start would wait the same limit (issue 52). Said once,
            // with how to raise the limit and the usual cause.
            Line::Silent if !self.started => {
                self.kill();
                return Err(self.fail(
                    IutCause::NotStarted,
                    format!(
                        "no answer to `{}` within {} ms, {which} (killed). Raise it with \
                         --start-timeout-ms or {}; an IUT that never answers is most often \
                         one that does not flush its stdout after each answer",
                        request.name(),
                        limit.as_millis(),
                        crate::door::Timeouts::START_VARIABLE
                    ),
                ));
            }
            Line::Silent => {
                self.kill();
                return Err(self.fail(
                    IutCause::Silent,
                    format!(
                        "no answer to `{}` within {} ms, {which} (hung; killed)",
                        request.name(),
                        limit.as_millis()
                    ),
                ));
            }
            Line::Closed => {
                let status = self.exit_status();
                if let Some(error) = self.not_started(status) {
                    return Err(error);
                }
                let what = match status {
                    Some(status) => format!("exited ({status})"),
                    None => "closed its stdout (still running; killed)".to_string(),
                };
                self.kill();
                return Err(self.fail(
                    IutCause::Gone,
                    format!("{what} instead of answering `{}`", request.name()),
                ));
            }
        };
        Ok(line)
    }

    /// The answer `expected` a line holds.
    pub(crate) fn answer_of<T>(
        &mut self,
        line: &str,
        expected: Expected<T>,
    ) -> Result<T, IutError> {
        // Straight into the typed answer; only a line that is not one is read
        // again, to say whether it is JSON at all.
        let answer =
            serde_json::from_str::<Answer>(line).map_err(|error| {
                match serde_json::from_str::<serde_json::Value>(line) {
                    Err(error) => format!("printed something that is not a JSON object ({error})"),
                    Ok(_) => format!("answered something the protocol does not know ({error})"),
                }
            });
        let answer = match answer {
            Ok(answer) => answer,
            Err(what) => {
                return Err(self.fail(IutCause::Protocol, format!("{what}: {}", truncate(line))))
            }
        };
        self.take(answer, expected, line)
    }

    /// The fields of the answer `expected`; an error answer is the IUT's
    /// report, any other a broken exchange (`shown`: the answer as it came).
    fn take<T>(
        &mut self,
        answer: Answer,
        expected: Expected<T>,
        shown: &str,
    ) -> Result<T, IutError> {
        match (expected.take)(answer) {
            Ok(fields) => Ok(fields),
            Err(Answer::Error { message }) => {
                Err(self.fail(IutCause::Reported, format!("reported an error: {message}")))
            }
            Err(other) => Err(self.fail(
                IutCause::Protocol,
                format!(
                    "answered `{}` where `{}` was due: {}",
                    other.name(),
                    expected.name,
                    truncate(shown)
                ),
            )),
        }
    }
}

impl Drop for AdapterProcess {
    /// `bye` and end of input tell a well-behaved IUT to leave; then its
    /// whole process group ends, whatever it started.
    fn drop(&mut self) {
        // What it started, taken while it still stands over them: when it
        // leaves, they come to canif (a subreaper) and are found by this.
        let below = canif_cabi::isolation::Snapshot::below(self.child.id());
        if self.failed.is_none() {
            if let Some(requests) = self.requests.as_mut() {
                let bye = serde_json::to_string(&Request::Bye {}).expect("requests serialize");
                let _ = writeln!(requests, "{bye}");
            }
        }
        self.requests = None;
        let _ = self.exit_status();
        self.kill();
        below.end();
    }
}

fn truncate(line: &str) -> String {
    if line.chars().count() > 200 {
        format!("{}…", line.chars().take(200).collect::<String>())
    } else {
        line.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line the IUT prints before the harness asks anything is read at
    /// the next request, whatever it holds: a line that is not UTF-8 too (it
    /// was dropped once, and the harness then waited for an answer in vain).
    #[test]
    fn a_broken_line_before_a_request_is_an_error_at_that_request() {
        let mut iut = AdapterProcess::spawn(
            r"printf '\377\n'; cat >/dev/null",
            Timeouts::default(),
            false,
            Channel::Stdio,
        )
        .unwrap();
        // Let the line arrive before the request, as a slow harness would.
        std::thread::sleep(Duration::from_millis(300));
        let started = std::time::Instant::now();
        let error = iut
            .exchange_line(&Request::TransmitComplete {})
            .unwrap_err();
        assert_eq!(error.cause, IutCause::Protocol, "{error}");
        assert!(
            error.to_string().contains("not UTF-8")
                && error
                    .to_string()
                    .contains("before the `transmit_complete` request"),
            "{error}"
        );
        assert!(
            started.elapsed() < Duration::from_secs(2),
            "it waited for an answer"
        );
    }
}
