//! The harness's side of the adapter protocol: an implementation under test in
//! another process, in any language, one JSON object per line on its stdin
//! and stdout; its stderr is its log.
//!
//! Whatever the process does — exit, hang, print garbage, speak another
//! protocol version, return an image of the wrong size — becomes an error
//! naming what happened and the last lines of its stderr; the harness never
//! waits longer than the per-exchange timeout.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Write};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::frame::Frame;
use canif_model::image::ImageLayout;
use canif_model::info_data::ControllerStatus;
use canif_model::Nanos;

use super::protocol::{
    Answer, BusEvent, Caps, Config, Hex, OwnedBus, PlannedFrame, Request, SteppedLine, Transmitted,
    WireFrame, PROTOCOL_VERSION,
};
use crate::device::iut::{InvalidFrame, Iut, Planned, Transmit};
use crate::error::IutError;

/// How many lines of the IUT's stderr an error shows.
const STDERR_LINES: usize = 20;

/// The longest line an IUT may print: far above any answer the protocol has
/// (an input image of 32 FD slots is about 5 KB of hex), far below what could
/// exhaust the harness's memory.
pub const MAX_LINE: usize = 1 << 20;

/// What reading the IUT's next line gave.
enum Line {
    Text(String),
    /// The IUT printed what no line of the protocol can be.
    Broken(String),
    /// Nothing within the timeout.
    Silent,
    /// Its stdout closed.
    Closed,
}

/// The IUT's stdout, read on the harness's own thread: waiting with poll(2)
/// instead of handing lines over from a reader thread saves a context switch
/// per exchange, which is most of an exchange's cost.
struct LineReader {
    source: ChildStdout,
    buffer: Vec<u8>,
    /// What one read fills, allocated once (not zeroed again per read).
    chunk: Box<[u8]>,
    /// Bytes of `buffer` already handed out.
    used: usize,
}

impl LineReader {
    fn new(source: ChildStdout) -> Self {
        LineReader {
            source,
            buffer: Vec::with_capacity(1 << 16),
            chunk: vec![0; 1 << 16].into_boxed_slice(),
            used: 0,
        }
    }

    /// The next line (without its newline), waiting at most `timeout` in all.
    fn next(&mut self, timeout: Duration) -> Line {
        use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
        use std::io::Read;
        use std::os::fd::AsFd;
        let deadline = std::time::Instant::now() + timeout;
        let mut searched = self.used;
        loop {
            if let Some(at) = self.buffer[searched..].iter().position(|b| *b == b'\n') {
                let end = searched + at;
                let bytes = &self.buffer[self.used..end];
                let line = match std::str::from_utf8(bytes) {
                    Ok(text) => Line::Text(text.to_string()),
                    Err(e) => Line::Broken(format!(
                        "printed a line that is not UTF-8 (byte {} of {:02X?}…)",
                        e.valid_up_to(),
                        &bytes[..bytes.len().min(16)]
                    )),
                };
                self.used = end + 1;
                if self.used == self.buffer.len() {
                    self.buffer.clear();
                    self.used = 0;
                }
                return line;
            }
            searched = self.buffer.len();
            if self.buffer.len() - self.used > MAX_LINE {
                return Line::Broken(format!("printed a line longer than {MAX_LINE} bytes"));
            }
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            let wait = PollTimeout::try_from(left).unwrap_or(PollTimeout::MAX);
            let mut fds = [PollFd::new(self.source.as_fd(), PollFlags::POLLIN)];
            match poll(&mut fds, wait) {
                Ok(0) => return Line::Silent,
                Ok(_) => {}
                Err(nix::errno::Errno::EINTR) => continue,
                Err(e) => return Line::Broken(format!("its stdout failed: {e}")),
            }
            if self.used > 0 {
                self.buffer.drain(..self.used);
                searched -= self.used;
                self.used = 0;
            }
            match self.source.read(&mut self.chunk) {
                Ok(0) => return Line::Closed,
                Ok(n) => self.buffer.extend_from_slice(&self.chunk[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Line::Broken(format!("its stdout failed: {e}")),
            }
        }
    }
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

/// How an IUT answered a configuration.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Configured {
    Accepted,
    /// A legitimate answer, judged by the refusal grid.
    Refused(String),
}

/// A running IUT process, in a process group of its own: whatever it starts
/// ends with it.
pub struct ExecIut {
    command: String,
    child: Child,
    stdin: Option<ChildStdin>,
    lines: LineReader,
    stderr: Arc<Mutex<VecDeque<String>>>,
    timeout: Duration,
    input_size: usize,
    /// When a held frame (Distributed Clocks) becomes due, as the IUT said.
    next_release: Option<Nanos>,
    /// The first failure; every later call reports it.
    failed: Option<String>,
    /// The protocol version `configure` agreed.
    version: u64,
    /// Protocol 2: what happened on the bus since the last step.
    events: Vec<BusEvent>,
    /// Protocol 2: the frames the IUT will start next, and from when.
    plan: VecDeque<Planned>,
    /// Protocol 2: a frame of the plan is on the wire.
    on_wire: bool,
}

impl ExecIut {
    /// Starts `command` (through `sh -c`) in a new process group; with
    /// `same_cpu`, the calling thread and the IUT share the CPU the thread is on.
    pub fn spawn(command: &str, timeout: Duration, same_cpu: bool) -> Result<Self, IutError> {
        use std::os::unix::process::CommandExt;
        if same_cpu {
            share_cpu();
        }
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(command)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .process_group(0)
            .spawn()
            .map_err(|e| IutError(format!("cannot start `{command}`: {e}")))?;
        let stdout = child.stdout.take().ok_or(IutError("no stdout".into()))?;
        let stderr = child.stderr.take().ok_or(IutError("no stderr".into()))?;
        let lines = LineReader::new(stdout);
        let log = Arc::new(Mutex::new(VecDeque::new()));
        let log_writer = log.clone();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(stderr);
            let mut line = Vec::new();
            loop {
                line.clear();
                match std::io::Read::take(&mut reader, 4096).read_until(b'\n', &mut line) {
                    Ok(0) | Err(_) => break,
                    Ok(_) => {}
                }
                let text = String::from_utf8_lossy(&line).trim_end().to_string();
                if let Ok(mut log) = log_writer.lock() {
                    log.push_back(text);
                    if log.len() > STDERR_LINES {
                        log.pop_front();
                    }
                }
            }
        });
        let stdin = child.stdin.take();
        Ok(ExecIut {
            command: command.to_string(),
            child,
            stdin,
            lines,
            stderr: log,
            timeout,
            input_size: 0,
            next_release: None,
            failed: None,
            version: 1,
            events: Vec::new(),
            plan: VecDeque::new(),
            on_wire: false,
        })
    }

    /// Ends the IUT and everything it started (its process group).
    fn kill(&mut self) {
        use nix::sys::signal::{killpg, Signal};
        use nix::unistd::Pid;
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

    pub(crate) fn fail(&mut self, what: String) -> IutError {
        let message = format!("IUT `{}`: {what}; {}", self.command, self.stderr_tail());
        IutError(self.failed.get_or_insert(message).clone())
    }

    /// Sends one request and waits for the one-line answer of the expected type.
    pub(crate) fn exchange(
        &mut self,
        request: &Request,
        expected: &str,
    ) -> Result<Answer, IutError> {
        let line = self.exchange_line(request)?;
        self.answer_of(&line, expected)
    }

    /// Sends one request; its answer line, unread.
    fn exchange_line(&mut self, request: &Request) -> Result<String, IutError> {
        if let Some(failure) = &self.failed {
            return Err(IutError(failure.clone()));
        }
        let mut line = serde_json::to_vec(request).expect("requests serialize");
        line.push(b'\n');
        // One write per request: the IUT wakes once.
        let written = match self.stdin.as_mut() {
            Some(stdin) => stdin.write_all(&line).and_then(|_| stdin.flush()),
            None => Err(std::io::Error::other("stdin closed")),
        };
        if let Err(error) = written {
            let what = match self.exit_status() {
                Some(status) => {
                    format!("exited ({status}) before the `{}` request", request.name())
                }
                None => format!("cannot write to its stdin ({error}; killed)"),
            };
            self.kill();
            return Err(self.fail(what));
        }
        let line = match self.lines.next(self.timeout) {
            Line::Text(line) => line,
            Line::Broken(what) => {
                self.kill();
                return Err(self.fail(format!(
                    "{what} instead of answering `{}` (killed)",
                    request.name()
                )));
            }
            Line::Silent => {
                self.kill();
                return Err(self.fail(format!(
                    "no answer to `{}` within {} ms (hung; killed)",
                    request.name(),
                    self.timeout.as_millis()
                )));
            }
            Line::Closed => {
                let what = match self.exit_status() {
                    Some(status) => format!("exited ({status})"),
                    None => "closed its stdout (still running; killed)".to_string(),
                };
                self.kill();
                return Err(self.fail(format!("{what} instead of answering `{}`", request.name())));
            }
        };
        Ok(line)
    }

    /// The answer a line holds, of the expected type.
    fn answer_of(&mut self, line: &str, expected: &str) -> Result<Answer, IutError> {
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
            Err(what) => return Err(self.fail(format!("{what}: {}", truncate(line)))),
        };
        match answer {
            answer if answer.name() == expected => Ok(answer),
            Answer::Error { message } => Err(self.fail(format!("reported an error: {message}"))),
            other => Err(self.fail(format!(
                "answered `{}` where `{expected}` was due: {}",
                other.name(),
                truncate(line)
            ))),
        }
    }

    /// Offers a configuration; `Err`: the IUT failed (refusing is an answer).
    pub fn configure(
        &mut self,
        caps: &Capabilities,
        config: &InterfaceConfig,
        bus: Option<&OwnedBus>,
    ) -> Result<Configured, IutError> {
        let layout = ImageLayout::new(config, caps.info_data);
        // On a SocketCAN bus the IUT owns its CAN side: there is nothing to batch.
        let offered = if bus.is_some() { 1 } else { PROTOCOL_VERSION };
        let request = Request::Configure {
            protocol: offered,
            config: Config::new(config, &layout),
            capabilities: Caps::from(caps),
            bus: bus.cloned(),
        };
        let Answer::Configured {
            protocol,
            accepted,
            reason,
        } = self.exchange(&request, "configured")?
        else {
            unreachable!("exchange returns the expected type");
        };
        if !(1..=offered).contains(&protocol) {
            return Err(self.fail(format!(
                "speaks protocol version {protocol} (this harness offered 1 to {offered})"
            )));
        }
        self.version = protocol;
        self.events.clear();
        self.plan.clear();
        self.on_wire = false;
        self.input_size = layout.input_size();
        Ok(if accepted {
            Configured::Accepted
        } else {
            Configured::Refused(reason.unwrap_or_else(|| "refused".into()))
        })
    }
}

impl Drop for ExecIut {
    /// `bye` and end of input tell a well-behaved IUT to leave; then its
    /// whole process group ends, whatever it started.
    fn drop(&mut self) {
        if self.failed.is_none() {
            if let Some(stdin) = self.stdin.as_mut() {
                let bye = serde_json::to_string(&Request::Bye).expect("requests serialize");
                let _ = writeln!(stdin, "{bye}");
            }
        }
        self.stdin = None;
        let _ = self.exit_status();
        self.kill();
    }
}

fn truncate(line: &str) -> String {
    if line.chars().count() > 200 {
        format!("{}…", line.chars().take(200).collect::<String>())
    } else {
        line.to_string()
    }
}

impl ExecIut {
    /// Protocol 2: the cycle, with the bus events since the last one; the new
    /// plan replaces the old (frames not started are in it again).
    fn step(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        let request = Request::Step {
            now_ns: now,
            outputs: Hex(outputs.to_vec()),
            events: std::mem::take(&mut self.events),
        };
        let line = self.exchange_line(&request)?;
        let (inputs, plan) = match serde_json::from_str::<SteppedLine>(&line) {
            Ok(stepped) => (stepped.inputs, stepped.plan),
            Err(_) => match self.answer_of(&line, "stepped")? {
                Answer::Stepped { inputs, plan } => (inputs, plan),
                _ => unreachable!("answer_of returns the expected type"),
            },
        };
        let mut planned = VecDeque::with_capacity(plan.len());
        for PlannedFrame {
            frame,
            invalid,
            not_before_ns,
        } in plan
        {
            let frame = match (frame, invalid) {
                (None, Some(invalid)) => Err(InvalidFrame(invalid)),
                (Some(wire), None) => match wire.check() {
                    Ok(()) => Frame::try_from(&wire).map_err(InvalidFrame),
                    Err(lie) => {
                        return Err(self.fail(format!("answered `step` with a broken frame: {lie}")))
                    }
                },
                _ => {
                    return Err(self.fail(
                        "answered `step` with a plan entry that is not exactly one of \"frame\" and \"invalid\""
                            .into(),
                    ))
                }
            };
            planned.push_back((frame, not_before_ns));
        }
        self.plan = planned;
        Ok(inputs.0)
    }
}

impl Iut for ExecIut {
    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        let inputs = if self.version >= 2 {
            self.step(outputs, now)?
        } else {
            let request = Request::Cycle {
                now_ns: now,
                outputs: Hex(outputs.to_vec()),
            };
            let Answer::Inputs {
                inputs: Hex(inputs),
            } = self.exchange(&request, "inputs")?
            else {
                unreachable!("exchange returns the expected type");
            };
            inputs
        };
        if inputs.len() != self.input_size {
            return Err(self.fail(format!(
                "returned an input image of {} bytes; the layout has {}",
                inputs.len(),
                self.input_size
            )));
        }
        Ok(inputs)
    }

    fn receive(&mut self, frame: &Frame, end_of_reception: Nanos) -> Result<(), IutError> {
        if self.version >= 2 {
            self.events.push(BusEvent::Received {
                frame: WireFrame::from(frame),
                end_ns: end_of_reception,
            });
            return Ok(());
        }
        let request = Request::Receive {
            frame: WireFrame::from(frame),
            end_ns: end_of_reception,
        };
        self.exchange(&request, "ok").map(|_| ())
    }

    fn poll_transmit(&mut self, now: Nanos) -> Result<Transmit, IutError> {
        if self.version >= 2 {
            if self.on_wire {
                return Ok(None);
            }
            return Ok(match self.plan.front() {
                Some((_, not_before)) if *not_before <= now => {
                    let (frame, _) = self.plan.pop_front().expect("a front");
                    self.on_wire = true;
                    self.events.push(BusEvent::Started { at_ns: now });
                    Some(frame)
                }
                _ => None,
            });
        }
        let answer = self.exchange(&Request::PollTransmit { now_ns: now }, "transmit")?;
        let Answer::Transmit { frame, next_ns } = answer else {
            unreachable!("exchange returns the expected type");
        };
        self.next_release = next_ns;
        match frame {
            None => Ok(None),
            Some(Transmitted::Invalid(frame)) => Ok(Some(Err(InvalidFrame(frame.invalid)))),
            Some(Transmitted::Frame(wire)) => match wire.check() {
                Ok(()) => Ok(Some(Frame::try_from(&wire).map_err(InvalidFrame))),
                Err(lie) => Err(self.fail(format!(
                    "answered `poll_transmit` with a broken frame: {lie}"
                ))),
            },
        }
    }

    fn poll_timeout(&self) -> Option<Nanos> {
        if self.version >= 2 {
            return self
                .plan
                .front()
                .filter(|_| !self.on_wire)
                .map(|(_, not_before)| *not_before);
        }
        self.next_release
    }

    fn transmit_complete(&mut self) -> Result<(), IutError> {
        if self.version >= 2 {
            self.events.push(BusEvent::Completed);
            self.on_wire = false;
            return Ok(());
        }
        self.exchange(&Request::TransmitComplete, "ok").map(|_| ())
    }

    fn controller_status(&mut self, status: &ControllerStatus) -> Result<(), IutError> {
        if self.version >= 2 {
            self.events.push(BusEvent::Status {
                status: status.into(),
            });
            return Ok(());
        }
        let request = Request::ControllerStatus {
            status: status.into(),
        };
        self.exchange(&request, "ok").map(|_| ())
    }
}
