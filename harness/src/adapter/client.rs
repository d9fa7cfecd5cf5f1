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
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::frame::Frame;
use canif_model::image::ImageLayout;
use canif_model::info_data::ControllerStatus;
use canif_model::Nanos;

use super::protocol::{
    Answer, Caps, Config, Hex, OwnedBus, Request, Transmitted, WireFrame, PROTOCOL_VERSION,
};
use crate::error::IutError;
use crate::iut::{InvalidFrame, Iut, Transmit};

/// How many lines of the IUT's stderr an error shows.
const STDERR_LINES: usize = 20;

/// The longest line an IUT may print: far above any answer the protocol has
/// (an input image of 32 FD slots is about 5 KB of hex), far below what could
/// exhaust the harness's memory.
pub const MAX_LINE: usize = 1 << 20;

/// What the reader of the IUT's stdout passes on.
enum Line {
    Text(String),
    /// The IUT printed what no line of the protocol can be; reading stopped.
    Broken(String),
}

/// Reads one line of at most `MAX_LINE` bytes; `None` at the end of the stream.
fn read_line(reader: &mut impl BufRead) -> Option<Line> {
    let mut bytes = Vec::new();
    match std::io::Read::take(&mut *reader, MAX_LINE as u64 + 1).read_until(b'\n', &mut bytes) {
        Ok(0) => None,
        Ok(_) if bytes.last() != Some(&b'\n') && bytes.len() > MAX_LINE => Some(Line::Broken(
            format!("printed a line longer than {MAX_LINE} bytes"),
        )),
        Ok(_) => {
            if bytes.last() == Some(&b'\n') {
                bytes.pop();
            }
            Some(match String::from_utf8(bytes) {
                Ok(text) => Line::Text(text),
                Err(e) => Line::Broken(format!(
                    "printed a line that is not UTF-8 (byte {} of {:02X?}…)",
                    e.utf8_error().valid_up_to(),
                    &e.as_bytes()[..e.as_bytes().len().min(16)]
                )),
            })
        }
        Err(error) => Some(Line::Broken(format!("its stdout failed: {error}"))),
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
    lines: Receiver<Line>,
    stderr: Arc<Mutex<VecDeque<String>>>,
    timeout: Duration,
    input_size: usize,
    /// When a held frame (Distributed Clocks) becomes due, as the IUT said.
    next_release: Option<Nanos>,
    /// The first failure; every later call reports it.
    failed: Option<String>,
}

impl ExecIut {
    /// Starts `command` (through `sh -c`) in a new process group.
    pub fn spawn(command: &str, timeout: Duration) -> Result<Self, IutError> {
        use std::os::unix::process::CommandExt;
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
        let (sender, lines) = mpsc::channel();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(stdout);
            while let Some(line) = read_line(&mut reader) {
                let broken = matches!(line, Line::Broken(_));
                if sender.send(line).is_err() || broken {
                    break;
                }
            }
        });
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

    fn fail(&mut self, what: String) -> IutError {
        let message = format!("IUT `{}`: {what}; {}", self.command, self.stderr_tail());
        IutError(self.failed.get_or_insert(message).clone())
    }

    /// Sends one request and waits for the one-line answer of the expected type.
    fn exchange(&mut self, request: &Request, expected: &str) -> Result<Answer, IutError> {
        if let Some(failure) = &self.failed {
            return Err(IutError(failure.clone()));
        }
        let line = serde_json::to_string(request).expect("requests serialize");
        let written = match self.stdin.as_mut() {
            Some(stdin) => writeln!(stdin, "{line}").and_then(|_| stdin.flush()),
            None => Err(std::io::Error::other("stdin closed")),
        };
        if let Err(error) = written {
            let status = self.child.try_wait().ok().flatten();
            return Err(self.fail(match status {
                Some(status) => {
                    format!("exited ({status}) before the `{}` request", request.name())
                }
                None => format!("cannot write to its stdin: {error}"),
            }));
        }
        let line = match self.lines.recv_timeout(self.timeout) {
            Ok(Line::Text(line)) => line,
            Ok(Line::Broken(what)) => {
                self.kill();
                return Err(self.fail(format!(
                    "{what} instead of answering `{}` (killed)",
                    request.name()
                )));
            }
            Err(RecvTimeoutError::Timeout) => {
                self.kill();
                return Err(self.fail(format!(
                    "no answer to `{}` within {} ms (hung; killed)",
                    request.name(),
                    self.timeout.as_millis()
                )));
            }
            Err(RecvTimeoutError::Disconnected) => {
                let what = match self.exit_status() {
                    Some(status) => format!("exited ({status})"),
                    None => "closed its stdout (still running; killed)".to_string(),
                };
                self.kill();
                return Err(self.fail(format!("{what} instead of answering `{}`", request.name())));
            }
        };
        let answer = match serde_json::from_str::<serde_json::Value>(&line) {
            Err(error) => Err(format!(
                "printed something that is not a JSON object ({error})"
            )),
            Ok(value) => serde_json::from_value::<Answer>(value).map_err(|error| {
                format!("answered something the protocol does not know ({error})")
            }),
        };
        let answer = match answer {
            Ok(answer) => answer,
            Err(what) => return Err(self.fail(format!("{what}: {}", truncate(&line)))),
        };
        match answer {
            answer if answer.name() == expected => Ok(answer),
            Answer::Error { message } => Err(self.fail(format!("reported an error: {message}"))),
            other => Err(self.fail(format!(
                "answered `{}` where `{expected}` was due: {}",
                other.name(),
                truncate(&line)
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
        let request = Request::Configure {
            protocol: PROTOCOL_VERSION,
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
        if protocol != PROTOCOL_VERSION {
            return Err(self.fail(format!(
                "speaks protocol version {protocol} (this harness speaks {PROTOCOL_VERSION})"
            )));
        }
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

impl Iut for ExecIut {
    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
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
        let request = Request::Receive {
            frame: WireFrame::from(frame),
            end_ns: end_of_reception,
        };
        self.exchange(&request, "ok").map(|_| ())
    }

    fn poll_transmit(&mut self, now: Nanos) -> Result<Transmit, IutError> {
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
        self.next_release
    }

    fn transmit_complete(&mut self) -> Result<(), IutError> {
        self.exchange(&Request::TransmitComplete, "ok").map(|_| ())
    }

    fn controller_status(&mut self, status: &ControllerStatus) -> Result<(), IutError> {
        let request = Request::ControllerStatus {
            status: status.into(),
        };
        self.exchange(&request, "ok").map(|_| ())
    }
}
