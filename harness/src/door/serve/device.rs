//! The device's side of the adapter protocol: an in-process IUT served over
//! stdin/stdout, what `canif device --stdio` runs.

use std::collections::VecDeque;
use std::io::{BufRead, Write};

use super::session::{self, Serves, Switch};

use canif_model::config::{Capabilities, InterfaceConfig};

use canif_model::Nanos;

use crate::door::adapter::protocol::{
    Answer, BusEvent, Hex, InvalidWireFrame, PlannedFrame, Request, StepLine, Transmitted,
    WireFrame, PROTOCOL_VERSION,
};
use crate::door::iut::{BuildError, Iut, Planned};
use crate::error::{IutCause, IutError};

/// Builds the IUT a `configure` asks for.
pub type Build<'a> =
    dyn Fn(&Capabilities, &InterfaceConfig) -> Result<Box<dyn Iut>, BuildError> + 'a;

/// One served device: the IUT the last accepted `configure` built.
pub struct Server<'a> {
    build: &'a Build<'a>,
    iut: Option<Box<dyn Iut>>,
    /// The harness drives the CAN side through the protocol (no SocketCAN bus).
    drives_bus: bool,
    /// The highest protocol version this server answers with.
    most: u64,
    /// The version the last `configure` agreed.
    version: u64,
    /// What the served device declares in its `configured` answer.
    declares: std::collections::BTreeMap<String, String>,
    /// It can tell its transmit plan (versions 2 and 3 in steps); a device
    /// that can only be polled (a library without `canif_transmit_plan`)
    /// speaks 1, or 3 a record per bus event.
    steps: bool,
    /// Where the requests after the last `configured` come from.
    switch: Option<Switch>,
    /// The frames the last plan sent put first, in order: each frame the
    /// harness starts must be the one the device hands out.
    promised: VecDeque<Planned>,
}

impl<'a> Server<'a> {
    pub fn new(build: &'a Build<'a>, drives_bus: bool) -> Self {
        Server {
            build,
            iut: None,
            drives_bus,
            most: PROTOCOL_VERSION,
            version: 1,
            declares: Default::default(),
            steps: true,
            switch: None,
            promised: VecDeque::new(),
        }
    }

    /// A device that can only be polled (a library without
    /// `canif_transmit_plan`).
    pub fn polled(mut self) -> Self {
        self.steps = false;
        self
    }

    /// Declares these choices (name to value) in every `configured` answer.
    pub fn declaring(mut self, declares: std::collections::BTreeMap<String, String>) -> Self {
        self.declares = declares;
        self
    }

    /// Speaks at most `version` (1 keeps a harness to one request per event).
    pub fn at_most(mut self, version: u64) -> Self {
        self.most = version.clamp(1, PROTOCOL_VERSION);
        self
    }

    /// The IUT built by the last accepted `configure`.
    pub fn iut(&mut self) -> Option<&mut (dyn Iut + 'static)> {
        self.iut.as_deref_mut()
    }

    /// Reads one request line: the request, or the error answer to give.
    pub fn parse_line(line: &str) -> Result<Request, Answer> {
        // Protocol 2's one request per cycle first, as a plain struct (fast).
        if let Ok(step) = serde_json::from_str::<StepLine>(line) {
            return Ok(Request::Step {
                now_ns: step.now_ns,
                outputs: step.outputs,
                events: step.events,
            });
        }
        serde_json::from_str(line).map_err(|e| Answer::error(format!("not a request: {e}")))
    }

    /// The answer to one request; `None` for `bye`.
    pub fn answer(&mut self, request: &Request) -> Option<Answer> {
        let batched = self.batched();
        // In records (version 3) a plan is cut after what one cycle can
        // start, the rest asked for when needed; on lines it is whole.
        let most = match self.version {
            3 => PLAN_IN_RECORDS,
            _ => crate::door::iut::MOST_PLANNED,
        };
        let iut = match (request, self.iut.as_mut()) {
            (Request::Bye {}, _) => return None,
            (Request::Start { .. } | Request::Task { .. } | Request::Declare {}, _) => {
                return Some(Answer::error(
                    "this is a device; `start`, `task` and `declare` are the client role's requests",
                ))
            }
            (
                Request::Configure {
                    protocol,
                    config,
                    capabilities,
                    shared,
                    ..
                },
                _,
            ) => {
                // The versions the schema names: a harness that offers
                // another has misread the protocol, and is told so.
                if !(1..=PROTOCOL_VERSION).contains(protocol) {
                    return Some(Answer::error(format!(
                        "protocol {protocol} is no version of the adapter protocol (1 to {PROTOCOL_VERSION})"
                    )));
                }
                self.version = match ((*protocol).min(self.most), self.steps) {
                    // Version 2 is steps only.
                    (2, false) => 1,
                    (version, _) => version,
                };
                // Version 3 where the mapping opens; else the best below it.
                let switch = session::agree(self.version, shared.as_ref());
                if self.version == 3 && matches!(switch, Switch::ToLines) {
                    self.version = if self.steps { 2 } else { 1 };
                }
                self.switch = Some(switch);
                return Some(self.configure(&capabilities.into(), &config.interface()));
            }
            (_, None) => return Some(Answer::error("configure first")),
            (Request::Plan { .. }, Some(_)) if !batched || self.version < 3 => {
                return Some(Answer::error("`plan` is a record of version 3 in steps"))
            }
            (Request::Step { .. }, Some(_)) if !batched => {
                return Some(Answer::error(format!(
                    "`step` is for a device that tells its plan; configure agreed on version {} without it",
                    self.version
                )))
            }
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
                Err(error) => Answer::error(error.to_string()),
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
                        Err(invalid) => Transmitted::Invalid(InvalidWireFrame {
                            invalid: invalid.to_string(),
                        }),
                    }),
                    next_ns: iut.poll_timeout(),
                },
                Err(error) => Answer::error(error.to_string()),
            },
            Request::TransmitComplete {} => ok_or_error(iut.transmit_complete()),
            Request::ControllerStatus { status } => {
                ok_or_error(iut.controller_status(&status.into()))
            }
            Request::Step {
                now_ns,
                outputs,
                events,
            } => {
                let promised = &mut self.promised;
                match step(
                    iut.as_mut(),
                    promised,
                    *now_ns,
                    Some(&outputs.0),
                    events,
                    most,
                ) {
                    Ok(answer) => answer,
                    Err(error) => Answer::error(error.to_string()),
                }
            }
            Request::Plan { now_ns, events } => {
                match step(
                    iut.as_mut(),
                    &mut self.promised,
                    *now_ns,
                    None,
                    events,
                    most,
                ) {
                    Ok(answer) => answer,
                    Err(error) => Answer::error(error.to_string()),
                }
            }
            Request::Configure { .. }
            | Request::Bye {}
            | Request::Start { .. }
            | Request::Declare {}
            | Request::Task { .. } => unreachable!("answered above"),
        })
    }

    /// One exchange per cycle agreed.
    fn batched(&self) -> bool {
        self.steps && self.version >= 2
    }

    fn configure(&mut self, caps: &Capabilities, config: &InterfaceConfig) -> Answer {
        let steps = (self.version == 3).then_some(self.steps);
        match (self.build)(caps, config) {
            Ok(built) => {
                // What the device declares itself, and what the server was told to add.
                let mut declares = built.declared().entries();
                declares.extend(self.declares.clone());
                self.iut = Some(built);
                Answer::Configured {
                    protocol: self.version,
                    accepted: true,
                    reason: None,
                    declares,
                    steps,
                }
            }
            Err(BuildError::Refused(reason)) => {
                self.iut = None;
                Answer::Configured {
                    protocol: self.version,
                    accepted: false,
                    reason: Some(reason),
                    declares: Default::default(),
                    steps,
                }
            }
            // Not a refusal: the device could not be made (a library that
            // broke its own ABI, say). The harness reports it as an error.
            Err(BuildError::Failed(error)) => {
                self.iut = None;
                Answer::error(error.to_string())
            }
        }
    }
}

/// The most frames of a plan one `stepped` record carries: more than a cycle
/// of 1 ms starts at 1 Mbit/s (about eight), few enough that a long queue is
/// not written and read again every cycle.
const PLAN_IN_RECORDS: usize = 16;

/// Protocols 2 and 3: the step's bus events replayed in order — exactly the
/// calls protocol 1 would have made — then the cycle (none for the rest of a
/// plan: `outputs` is `None`), then at most `most` frames of the plan.
fn step(
    iut: &mut dyn Iut,
    promised: &mut VecDeque<Planned>,
    now: Nanos,
    outputs: Option<&[u8]>,
    events: &[BusEvent],
    most: usize,
) -> Result<Answer, IutError> {
    for event in events {
        match event {
            BusEvent::Received { frame, end_ns } => {
                let frame = canif_model::frame::Frame::try_from(frame).map_err(|e| {
                    IutError::new(IutCause::HarnessBug, format!("a received frame: {e}"))
                })?;
                iut.receive(&frame, *end_ns)?;
            }
            BusEvent::Started { at_ns } => {
                // The plan is the device's word on what it sends (the
                // harness judges those frames); its controller must then
                // hand out just that.
                let started = iut.poll_transmit(*at_ns)?;
                match (promised.pop_front(), started) {
                    (Some((planned, _)), started) if Some(&planned) != started.as_ref() => {
                        return Err(IutError::new(
                            IutCause::Impossible,
                            format!(
                                "its plan put {} first, but at {at_ns} ns it started {}",
                                shown(&planned),
                                started.as_ref().map_or("nothing".into(), shown)
                            ),
                        ));
                    }
                    (None, None) => {
                        let what =
                            format!("the harness started at {at_ns} ns a frame no plan held");
                        return Err(IutError::new(IutCause::HarnessBug, what));
                    }
                    _ => {}
                }
            }
            BusEvent::Completed => iut.transmit_complete()?,
            BusEvent::Status { status } => iut.controller_status(&status.into())?,
        }
    }
    let inputs = match outputs {
        Some(outputs) => iut.cycle(outputs, now)?,
        None => Vec::new(),
    };
    // One past the most: whether the plan goes on.
    let mut plan = iut.transmit_plan(now, most + 1).ok_or_else(|| {
        IutError::new(
            IutCause::Impossible,
            "this device cannot tell its plan (protocols 2 and 3)",
        )
    })?;
    let more = plan.len() > most;
    plan.truncate(most);
    let answer = Answer::Stepped {
        inputs: Hex(inputs),
        plan: plan.iter().map(planned).collect(),
        more,
    };
    *promised = plan.into();
    Ok(answer)
}

/// A frame of a plan, or what is none, in words.
fn shown(frame: &Result<canif_model::frame::Frame, crate::error::InvalidFrame>) -> String {
    match frame {
        Ok(frame) => frame.to_string(),
        Err(invalid) => format!("no frame ({invalid})"),
    }
}

fn planned((frame, not_before_ns): &Planned) -> PlannedFrame {
    let (frame, invalid) = match frame {
        Ok(frame) => (Some(WireFrame::from(frame)), None),
        Err(invalid) => (None, Some(invalid.to_string())),
    };
    PlannedFrame {
        frame,
        invalid,
        not_before_ns: *not_before_ns,
    }
}

fn ok_or_error(result: Result<(), crate::error::IutError>) -> Answer {
    match result {
        Ok(()) => Answer::Ok,
        Err(error) => Answer::error(error.to_string()),
    }
}

pub use session::write_answer;

impl Serves for Server<'_> {
    fn parse(&self, line: &str) -> Result<Request, Answer> {
        Server::parse_line(line)
    }
    fn answer(&mut self, request: &Request) -> Option<Answer> {
        Server::answer(self, request)
    }
    fn switch(&mut self) -> Switch {
        self.switch.take().unwrap_or(Switch::Stay)
    }
}

/// Serves an in-process IUT over the adapter protocol, the requests' lines
/// on `input` (descriptor `line_fd`), the answers on `output`. Returns when
/// the harness says `bye` or closes the input.
pub fn serve(
    server: Server<'_>,
    input: impl BufRead,
    line_fd: i32,
    output: impl Write,
) -> std::io::Result<()> {
    let mut server = server;
    session::run(&mut server, input, line_fd, output)
}

/// Serves the device of the library at `path` (what `canif lib-host --role
/// device` runs): each `configure` creates one, its images behind guard
/// pages, so what the library does wrong ends in this process.
pub fn serve_library(
    path: &std::path::Path,
    input: impl BufRead,
    line_fd: i32,
    output: impl Write,
) -> std::io::Result<()> {
    // Loaded once: whether it tells its plan decides how it is served, and
    // its load-time code runs once. (One that cannot be loaded is told so at
    // `configure`.)
    let library = crate::door::lib::open(path);
    let build = |caps: &Capabilities, config: &InterfaceConfig| {
        let output_size =
            canif_model::image::ImageLayout::new(config, caps.info_data).output_size();
        let library = library.as_ref().map_err(Clone::clone)?;
        crate::door::lib::create(library, caps, config)?
            .guarded(output_size)
            .map(|iut| Box::new(iut) as Box<dyn Iut>)
    };
    // A library that tells its transmit plan steps (a cycle's requests in
    // one record); one that does not is polled: version 1, or 3 a record per
    // bus event.
    let server = Server::new(&build, true);
    let plans = library.as_ref().is_ok_and(|library| library.plans());
    let server = if plans { server } else { server.polled() };
    serve(server, input, line_fd, output)
}
