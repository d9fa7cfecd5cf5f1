//! Protocol 2's step: the bus events of a cycle and the IUT's transmit plan.

use canif_model::Nanos;
use serde::{Deserialize, Serialize};

use super::{Hex, Status, WireFrame};

/// Something that happened at the IUT's controller since the last step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "EventLine", into = "EventLine")]
pub enum BusEvent {
    /// The controller received `frame`; its last bit ended at `end_ns`.
    Received { frame: WireFrame, end_ns: Nanos },
    /// The controller started the next frame of its plan at `at_ns`.
    Started { at_ns: Nanos },
    /// The frame it started is on the bus.
    Completed,
    /// The controller's status and counters changed.
    Status { status: Status },
}

impl BusEvent {
    /// The version 1 request that says the same (a step's `started` is
    /// that version's `poll_transmit`).
    pub fn into_request(self) -> super::Request {
        use super::Request;
        match self {
            BusEvent::Received { frame, end_ns } => Request::Receive { frame, end_ns },
            BusEvent::Started { at_ns } => Request::PollTransmit { now_ns: at_ns },
            BusEvent::Completed => Request::TransmitComplete {},
            BusEvent::Status { status } => Request::ControllerStatus { status },
        }
    }
}

/// A [`BusEvent`] as the line carries it: `{"event": KIND, …}`. Read as a
/// flat struct, then checked, so the many events of a step are not buffered
/// twice (as an internally tagged enum would be).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EventLine {
    event: EventKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    frame: Option<WireFrame>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    end_ns: Option<Nanos>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    at_ns: Option<Nanos>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    status: Option<Status>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum EventKind {
    Received,
    Started,
    Completed,
    Status,
}

impl TryFrom<EventLine> for BusEvent {
    type Error = String;
    fn try_from(line: EventLine) -> Result<Self, String> {
        let event = match (line.event, line.frame, line.end_ns, line.at_ns, line.status) {
            (EventKind::Received, Some(frame), Some(end_ns), None, None) => {
                BusEvent::Received { frame, end_ns }
            }
            (EventKind::Started, None, None, Some(at_ns), None) => BusEvent::Started { at_ns },
            (EventKind::Completed, None, None, None, None) => BusEvent::Completed,
            (EventKind::Status, None, None, None, Some(status)) => BusEvent::Status { status },
            (kind, ..) => {
                return Err(format!(
                    "a `{}` event has exactly {}",
                    serde_json::to_value(kind)
                        .unwrap_or_default()
                        .as_str()
                        .unwrap_or("?"),
                    match kind {
                        EventKind::Received => "\"frame\" and \"end_ns\"",
                        EventKind::Started => "\"at_ns\"",
                        EventKind::Completed => "no other field",
                        EventKind::Status => "\"status\"",
                    }
                ))
            }
        };
        Ok(event)
    }
}

impl From<BusEvent> for EventLine {
    fn from(event: BusEvent) -> Self {
        let mut line = EventLine {
            event: EventKind::Completed,
            frame: None,
            end_ns: None,
            at_ns: None,
            status: None,
        };
        match event {
            BusEvent::Received { frame, end_ns } => {
                (line.event, line.frame, line.end_ns) =
                    (EventKind::Received, Some(frame), Some(end_ns))
            }
            BusEvent::Started { at_ns } => {
                (line.event, line.at_ns) = (EventKind::Started, Some(at_ns))
            }
            BusEvent::Completed => {}
            BusEvent::Status { status } => {
                (line.event, line.status) = (EventKind::Status, Some(status))
            }
        }
        line
    }
}

/// One frame of the IUT's plan: what it will start next (`frame`, or
/// `invalid` with why it is no frame), and from when.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannedFrame {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<WireFrame>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub invalid: Option<String>,
    pub not_before_ns: Nanos,
}

/// `step` and `stepped` as plain structs: protocol 2's hot path reads them
/// without the buffering an internally tagged enum needs (the general
/// `Request` / `Answer` read everything else, and say what is wrong).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepLine {
    #[serde(rename = "type")]
    pub kind: StepTag,
    pub now_ns: Nanos,
    pub outputs: Hex,
    pub events: Vec<BusEvent>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepTag {
    Step,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SteppedLine {
    #[serde(rename = "type")]
    pub kind: SteppedTag,
    pub inputs: Hex,
    pub plan: Vec<PlannedFrame>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SteppedTag {
    Stepped,
}
