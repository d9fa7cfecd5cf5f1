//! The harness's side of the adapter protocol's device role: an IUT in
//! another process (`AdapterProcess`) behind the [`crate::door::iut::Iut`] trait.
//! An image of the wrong size or a frame no controller can send is an error
//! naming it, as is anything the process itself does wrong.

use std::collections::VecDeque;

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::frame::Frame;
use canif_model::image::ImageLayout;
use canif_model::info_data::ControllerStatus;
use canif_model::Nanos;

use crate::declare::choices::Declared;
use crate::declare::Declaration;
use crate::door::adapter::process::{AdapterProcess, Channel};
use crate::door::adapter::protocol::{
    Answer, BusEvent, Caps, Config, Expected, Hex, OwnedBus, PlannedFrame, Request, SteppedLine,
    Transmitted, WireFrame, PROTOCOL_VERSION,
};
use crate::door::iut::{InvalidFrame, Iut, Planned, Transmit};
use crate::door::Timeouts;
use crate::error::{IutCause, IutError};

pub(crate) mod client;
mod transport;

pub use transport::ExecDoor;

/// Offers a device process a configuration: a refusal is its answer, judged
/// by the refusal grid; a broken exchange is a failure to build.
pub(crate) fn offer(
    iut: &mut ExecIut,
    caps: &Capabilities,
    config: &InterfaceConfig,
    bus: Option<&OwnedBus>,
) -> Result<(), crate::door::iut::BuildError> {
    use crate::door::iut::BuildError;
    match iut
        .configure(caps, config, bus)
        .map_err(BuildError::Failed)?
    {
        Configured::Accepted => Ok(()),
        Configured::Refused(reason) => Err(BuildError::Refused(reason)),
    }
}

/// A device process started with `command` on `channel` and offered a
/// configuration: what the exec door and a hosted library both open.
pub(crate) fn spawned_device(
    (command, timeouts, same_cpu, channel): (&str, Timeouts, bool, Channel),
    caps: &Capabilities,
    config: &InterfaceConfig,
    bus: Option<&OwnedBus>,
) -> Result<Box<dyn crate::door::iut::Iut>, crate::door::iut::BuildError> {
    let mut iut = ExecIut::spawn_on(command, timeouts, same_cpu, channel)
        .map_err(crate::door::iut::BuildError::Failed)?;
    offer(&mut iut, caps, config, bus)?;
    Ok(Box::new(iut))
}

/// One process that answers configuration after configuration (the
/// refusal grid): started at the first, kept for the rest.
pub(crate) fn configurer(
    command: String,
    timeouts: Timeouts,
    same_cpu: bool,
    channel: Channel,
) -> crate::door::Configurer {
    let mut process: Option<ExecIut> = None;
    Box::new(move |caps, config| {
        let iut = match process.as_mut() {
            Some(iut) => iut,
            None => process.insert(
                ExecIut::spawn_on(&command, timeouts, same_cpu, channel)
                    .map_err(crate::door::iut::BuildError::Failed)?,
            ),
        };
        offer(iut, caps, config, None)
    })
}

/// How an IUT answered a configuration.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Configured {
    Accepted,
    /// A legitimate answer, judged by the refusal grid.
    Refused(String),
}

/// A device under test in another process.
pub struct ExecIut {
    process: AdapterProcess,
    input_size: usize,
    /// When a held frame (Distributed Clocks) becomes due, as the IUT said.
    next_release: Option<Nanos>,
    /// The protocol version `configure` agreed.
    version: u64,
    /// One exchange per cycle (version 2, or 3 with a device that steps):
    /// the bus events are gathered and the plan kept here.
    batched: bool,
    /// Protocol 2: what happened on the bus since the last step.
    events: Vec<BusEvent>,
    /// Protocol 2: the frames the IUT will start next, and from when.
    plan: VecDeque<Planned>,
    /// Protocol 3: the plan was cut short; the rest is asked for once these
    /// frames have started.
    more: bool,
    /// Protocol 2: a frame of the plan is on the wire.
    on_wire: bool,
    /// What it declared in its `configured` answer.
    declared: Declared,
    /// Protocol 3: the step posted ahead by [`Iut::announce_cycle`], its
    /// answer not yet read.
    announced: Option<Request>,
}

impl ExecIut {
    /// Starts `command`, speaking the protocol on its stdin and stdout (see
    /// `AdapterProcess::spawn`).
    pub fn spawn(command: &str, timeouts: Timeouts, same_cpu: bool) -> Result<Self, IutError> {
        Self::spawn_on(command, timeouts, same_cpu, Channel::Stdio)
    }

    /// Starts `command`, speaking the protocol on `channel`.
    pub(crate) fn spawn_on(
        command: &str,
        timeouts: Timeouts,
        same_cpu: bool,
        channel: Channel,
    ) -> Result<Self, IutError> {
        Ok(ExecIut {
            process: AdapterProcess::spawn(command, timeouts, same_cpu, channel)?,
            input_size: 0,
            next_release: None,
            version: 1,
            batched: false,
            events: Vec::new(),
            plan: VecDeque::new(),
            more: false,
            on_wire: false,
            declared: Declared::default(),
            announced: None,
        })
    }

    fn fail(&mut self, cause: IutCause, what: String) -> IutError {
        self.process.fail(cause, what)
    }

    /// One request and its answer where the agreed version carries it; in
    /// version 3 after the bus events gathered since the last record.
    fn exchange<T>(&mut self, request: &Request, expected: Expected<T>) -> Result<T, IutError> {
        // The buffer goes back, emptied, to gather the next events.
        let mut events = std::mem::take(&mut self.events);
        let answer = self.process.exchange_record(&events, request, expected);
        events.clear();
        self.events = events;
        answer
    }

    /// The bus events wait for the next record or step instead of a line
    /// each (they are all answered `ok`).
    fn gathers(&self) -> bool {
        self.batched || self.version == 3
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
            shared: self.process.shared_offer().filter(|_| offered >= 3),
        };
        let configured = self.process.exchange(&request, Answer::CONFIGURED)?;
        let (protocol, accepted, reason) = (
            configured.protocol,
            configured.accepted,
            configured.reason.clone(),
        );
        let mut declared = Declared::default();
        for (name, value) in &configured.declares {
            if let Err(error) = declared.declare(&format!("{name}={value}")) {
                return Err(self.fail(
                    IutCause::Protocol,
                    format!("`configured` declares `{name}`: `{value}`: {error}"),
                ));
            }
        }
        self.declared = declared;
        if !(1..=offered).contains(&protocol) {
            return Err(self.fail(
                IutCause::Protocol,
                format!("speaks protocol version {protocol} (this harness offered 1 to {offered})"),
            ));
        }
        self.version = protocol;
        self.process.agree_shared(protocol == 3);
        self.batched = protocol == 2 || (protocol == 3 && configured.steps != Some(false));
        self.events.clear();
        self.plan.clear();
        self.announced = None;
        self.more = false;
        self.on_wire = false;
        self.input_size = layout.input_size();
        Ok(if accepted {
            Configured::Accepted
        } else {
            Configured::Refused(reason.unwrap_or_else(|| "refused".into()))
        })
    }

    /// Protocol 2: the cycle, with the bus events since the last one; the new
    /// plan replaces the old (frames not started are in it again).
    fn step(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        let (inputs, plan, more) = if self.version == 3 {
            let request = match self.announced.take() {
                Some(request) if matches!(request, Request::Step { now_ns, .. } if now_ns == now) => {
                    request
                }
                Some(request) => {
                    return Err(self.fail(
                        IutCause::HarnessBug,
                        format!(
                            "harness bug: a cycle at {now} ns after a `{}` announced for another",
                            request.name()
                        ),
                    ))
                }
                None => {
                    let request = self.step_request(outputs, now);
                    self.process.post_record(&[], &request)?;
                    request
                }
            };
            let stepped = self.process.collect_record(&request, Answer::STEPPED);
            self.reuse(request);
            stepped?
        } else {
            let request = self.step_request(outputs, now);
            let line = self.process.exchange_line(&request)?;
            match serde_json::from_str::<SteppedLine>(&line) {
                Ok(stepped) => (stepped.inputs, stepped.plan, false),
                Err(_) => self.process.answer_of(&line, Answer::STEPPED)?,
            }
        };
        self.take_plan(plan, more)?;
        Ok(inputs.0)
    }

    /// The cycle with the bus events since the last one.
    fn step_request(&mut self, outputs: &[u8], now: Nanos) -> Request {
        Request::Step {
            now_ns: now,
            outputs: Hex(outputs.to_vec()),
            events: std::mem::take(&mut self.events),
        }
    }

    /// Protocol 3: the rest of a plan cut short, after the bus events since.
    fn refill(&mut self, now: Nanos) -> Result<(), IutError> {
        let request = Request::Plan {
            now_ns: now,
            events: std::mem::take(&mut self.events),
        };
        let stepped = self.process.exchange_record(&[], &request, Answer::STEPPED);
        self.reuse(request);
        let (_, plan, more) = stepped?;
        self.take_plan(plan, more)
    }

    /// The events' room back from a request sent: a cycle's events then
    /// cost no allocation.
    fn reuse(&mut self, request: Request) {
        if let Request::Step { mut events, .. } | Request::Plan { mut events, .. } = request {
            events.clear();
            self.events = events;
        }
    }

    /// The plan an answer gave, checked frame by frame, in place of the old.
    fn take_plan(&mut self, plan: Vec<PlannedFrame>, more: bool) -> Result<(), IutError> {
        let mut planned = std::mem::take(&mut self.plan);
        planned.clear();
        for PlannedFrame {
            frame,
            invalid,
            not_before_ns,
        } in plan
        {
            let frame = match (frame, invalid) {
                (None, Some(invalid)) => Err(InvalidFrame::Declared(invalid)),
                (Some(wire), None) => match wire.check() {
                    Ok(()) => wire.to_frame(),
                    Err(lie) => {
                        return Err(self.fail(
                            IutCause::Impossible,
                            format!("answered `step` with a broken frame: {lie}"),
                        ))
                    }
                },
                _ => {
                    return Err(self.fail(IutCause::Protocol,
                        "answered `step` with a plan entry that is not exactly one of \"frame\" and \"invalid\""
                            .into(),
                    ))
                }
            };
            planned.push_back((frame, not_before_ns));
        }
        self.plan = planned;
        self.more = more;
        Ok(())
    }
}

impl Iut for ExecIut {
    fn declared(&self) -> Declared {
        self.declared
    }

    /// Protocol 3 in steps: the step is posted now, its answer read by
    /// `cycle`.
    fn announce_cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<(), IutError> {
        if !(self.batched && self.version == 3) || self.announced.is_some() {
            return Ok(());
        }
        let request = self.step_request(outputs, now);
        let posted = self.process.post_record(&[], &request);
        self.announced = Some(request);
        posted
    }

    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        let inputs = if self.batched {
            self.step(outputs, now)?
        } else {
            let request = Request::Cycle {
                now_ns: now,
                outputs: Hex(outputs.to_vec()),
            };
            self.exchange(&request, Answer::INPUTS)?.0
        };
        if inputs.len() != self.input_size {
            return Err(self.fail(
                IutCause::Impossible,
                format!(
                    "returned an input image of {} bytes; the layout has {}",
                    inputs.len(),
                    self.input_size
                ),
            ));
        }
        Ok(inputs)
    }

    fn receive(&mut self, frame: &Frame, end_of_reception: Nanos) -> Result<(), IutError> {
        if self.gathers() {
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
        self.exchange(&request, Answer::OK)
    }

    fn poll_transmit(&mut self, now: Nanos) -> Result<Transmit, IutError> {
        if self.batched {
            if self.on_wire {
                return Ok(None);
            }
            if self.plan.is_empty() && self.more {
                self.refill(now)?;
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
        let (frame, next_ns) =
            self.exchange(&Request::PollTransmit { now_ns: now }, Answer::TRANSMIT)?;
        self.next_release = next_ns;
        match frame {
            None => Ok(None),
            Some(Transmitted::Invalid(frame)) => {
                Ok(Some(Err(InvalidFrame::Declared(frame.invalid))))
            }
            Some(Transmitted::Frame(wire)) => match wire.check() {
                Ok(()) => Ok(Some(wire.to_frame())),
                Err(lie) => Err(self.fail(
                    IutCause::Impossible,
                    format!("answered `poll_transmit` with a broken frame: {lie}"),
                )),
            },
        }
    }

    fn poll_timeout(&self) -> Option<Nanos> {
        if self.batched {
            return self
                .plan
                .front()
                .filter(|_| !self.on_wire)
                .map(|(_, not_before)| *not_before);
        }
        self.next_release
    }

    fn transmit_complete(&mut self) -> Result<(), IutError> {
        if self.gathers() {
            self.events.push(BusEvent::Completed);
            self.on_wire = false;
            return Ok(());
        }
        self.exchange(&Request::TransmitComplete {}, Answer::OK)
    }

    fn controller_status(&mut self, status: &ControllerStatus) -> Result<(), IutError> {
        if self.gathers() {
            self.events.push(BusEvent::Status {
                status: status.into(),
            });
            return Ok(());
        }
        let request = Request::ControllerStatus {
            status: status.into(),
        };
        self.exchange(&request, Answer::OK)
    }
}
