//! The device's side of the adapter protocol: an in-process IUT served over
//! stdin/stdout, what `canif device --stdio` runs.

use std::io::{BufRead, Write};

use canif_model::config::{Capabilities, InterfaceConfig};

use super::protocol::{
    Answer, Hex, InvalidWireFrame, Request, Transmitted, WireFrame, PROTOCOL_VERSION,
};
use crate::iut::{BuildError, Iut};

/// Builds the IUT a `configure` asks for.
pub type Build<'a> =
    dyn Fn(&Capabilities, &InterfaceConfig) -> Result<Box<dyn Iut>, BuildError> + 'a;

/// One served device: the IUT the last accepted `configure` built.
pub struct Server<'a> {
    build: &'a Build<'a>,
    iut: Option<Box<dyn Iut>>,
    /// The harness drives the CAN side through the protocol (no SocketCAN bus).
    drives_bus: bool,
}

impl<'a> Server<'a> {
    pub fn new(build: &'a Build<'a>, drives_bus: bool) -> Self {
        Server {
            build,
            iut: None,
            drives_bus,
        }
    }

    /// The IUT built by the last accepted `configure`.
    pub fn iut(&mut self) -> Option<&mut (dyn Iut + 'static)> {
        self.iut.as_deref_mut()
    }

    /// Reads one request line: the request, or the error answer to give.
    pub fn parse(line: &str) -> Result<Request, Answer> {
        serde_json::from_str(line).map_err(|e| Answer::error(format!("not a request: {e}")))
    }

    /// The answer to one request; `None` for `bye`.
    pub fn answer(&mut self, request: &Request) -> Option<Answer> {
        let iut = match (request, self.iut.as_mut()) {
            (Request::Bye, _) => return None,
            (
                Request::Configure {
                    config,
                    capabilities,
                    ..
                },
                _,
            ) => return Some(self.configure(&capabilities.into(), &config.interface())),
            (_, None) => return Some(Answer::error("configure first")),
            (request, Some(_)) if request.is_bus_request() && !self.drives_bus => {
                return Some(Answer::error(format!(
                    "`{}`: this device is on a SocketCAN bus and owns its CAN side",
                    request.name()
                )))
            }
            (_, Some(iut)) => iut,
        };
        Some(match request {
            Request::Cycle { now_ns, outputs } => match iut.cycle(&outputs.0, *now_ns) {
                Ok(inputs) => Answer::Inputs {
                    inputs: Hex(inputs),
                },
                Err(error) => Answer::error(error.0),
            },
            Request::Receive { frame, end_ns } => {
                match canif_model::frame::Frame::try_from(frame) {
                    Ok(frame) => ok_or_error(iut.receive(&frame, *end_ns)),
                    Err(error) => Answer::error(error),
                }
            }
            Request::PollTransmit { now_ns } => match iut.poll_transmit(*now_ns) {
                Ok(frame) => Answer::Transmit {
                    frame: frame.map(|frame| match frame {
                        Ok(frame) => Transmitted::Frame(WireFrame::from(&frame)),
                        Err(invalid) => {
                            Transmitted::Invalid(InvalidWireFrame { invalid: invalid.0 })
                        }
                    }),
                    next_ns: iut.poll_timeout(),
                },
                Err(error) => Answer::error(error.0),
            },
            Request::TransmitComplete => ok_or_error(iut.transmit_complete()),
            Request::ControllerStatus { status } => {
                ok_or_error(iut.controller_status(&status.into()))
            }
            Request::Configure { .. } | Request::Bye => unreachable!("answered above"),
        })
    }

    fn configure(&mut self, caps: &Capabilities, config: &InterfaceConfig) -> Answer {
        match (self.build)(caps, config) {
            Ok(built) => {
                self.iut = Some(built);
                Answer::Configured {
                    protocol: PROTOCOL_VERSION,
                    accepted: true,
                    reason: None,
                }
            }
            Err(error) => {
                self.iut = None;
                Answer::Configured {
                    protocol: PROTOCOL_VERSION,
                    accepted: false,
                    reason: Some(error.to_string()),
                }
            }
        }
    }
}

fn ok_or_error(result: Result<(), crate::error::IutError>) -> Answer {
    match result {
        Ok(()) => Answer::Ok,
        Err(error) => Answer::error(error.0),
    }
}

/// Writes one answer as a line.
pub fn write_answer(output: &mut impl Write, answer: &Answer) -> std::io::Result<()> {
    let line = serde_json::to_string(answer).expect("answers serialize");
    writeln!(output, "{line}")?;
    output.flush()
}

/// Serves an in-process IUT over the adapter protocol. Returns when the
/// harness says `bye` or closes the input. Whatever a line holds — not JSON,
/// not UTF-8, fields the protocol does not name — it gets an `error` answer.
pub fn serve(
    build: &Build<'_>,
    mut input: impl BufRead,
    mut output: impl Write,
) -> std::io::Result<()> {
    let mut server = Server::new(build, true);
    let mut bytes = Vec::new();
    loop {
        bytes.clear();
        if input.read_until(b'\n', &mut bytes)? == 0 {
            return Ok(());
        }
        let answer = match std::str::from_utf8(&bytes) {
            Err(error) => Answer::error(format!("not UTF-8: {error}")),
            Ok(line) if line.trim().is_empty() => continue,
            Ok(line) => match Server::parse(line) {
                Ok(request) => match server.answer(&request) {
                    Some(answer) => answer,
                    None => return Ok(()),
                },
                Err(answer) => answer,
            },
        };
        write_answer(&mut output, &answer)?;
    }
}
