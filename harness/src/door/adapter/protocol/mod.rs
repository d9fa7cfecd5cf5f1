//! The adapter protocol's messages (docs/adapter-protocol.md), written once as
//! serde types: the harness's client and `canif device --stdio`'s server both
//! speak through them, and `tests/adapter_protocol.rs` holds them to the JSON
//! Schema in `docs/adapter-protocol.schema.json`.

mod client;
mod config;
mod frame;
mod step;

pub use client::WireMessage;
pub use config::{Action, Caps, Config, Filter, Format, OwnedBus, Queue, SharedOffer, Status};
pub use frame::{FrameData, Hex, InvalidWireFrame, Transmitted, WireFrame};
pub use step::{BusEvent, PlannedFrame, StepLine, StepTag, SteppedLine, SteppedTag};

use canif_model::Nanos;
use serde::{Deserialize, Serialize};

/// The highest protocol version this harness speaks; `configure` offers it
/// and the IUT answers the version it will speak (1, 2 or 3).
pub const PROTOCOL_VERSION: u64 = 3;

/// What the harness asks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Request {
    Configure {
        protocol: u64,
        config: Config,
        capabilities: Caps,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bus: Option<OwnedBus>,
        /// Version 3 offered: the descriptors of the shared mapping.
        #[serde(
            default,
            deserialize_with = "SharedOffer::not_null",
            skip_serializing_if = "Option::is_none"
        )]
        shared: Option<SharedOffer>,
    },
    Cycle {
        now_ns: Nanos,
        outputs: Hex,
    },
    Receive {
        frame: WireFrame,
        end_ns: Nanos,
    },
    PollTransmit {
        now_ns: Nanos,
    },
    /// (A struct variant, so a field the schema does not allow is refused.)
    TransmitComplete {},
    ControllerStatus {
        status: Status,
    },
    /// Version 2: one exchange per cycle. What happened on the bus since the
    /// last step, in order, then the cycle itself.
    Step {
        now_ns: Nanos,
        outputs: Hex,
        events: Vec<BusEvent>,
    },
    /// Version 3, a record only (never a line): the rest of a plan a
    /// `stepped` cut short, after the bus events since — no cycle.
    #[serde(skip)]
    Plan {
        now_ns: Nanos,
        events: Vec<BusEvent>,
    },
    /// Client role: a PLC program starts for this interface (a fresh one
    /// after each PLC restart: a new process).
    Start {
        protocol: u64,
        config: Config,
        /// Version 3 offered: the descriptors of the shared mapping.
        #[serde(
            default,
            deserialize_with = "SharedOffer::not_null",
            skip_serializing_if = "Option::is_none"
        )]
        shared: Option<SharedOffer>,
    },
    /// Client role: one PLC task: the input image as the master delivers
    /// it, the output buffer as the master hands it, the application's send
    /// requests since the last task.
    Task {
        inputs: Hex,
        outputs: Hex,
        requests: Vec<WireMessage>,
    },
    /// Client role: what the client declares it is, asked before any
    /// `start` (include/canif.h's `canif_client_declares`), so canif can
    /// start it only on interfaces it serves. Answered `declared`; canif
    /// asks only its own `lib-host`.
    Declare {},
    Bye {},
}

impl Request {
    /// The request's `type`, for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Request::Configure { .. } => "configure",
            Request::Cycle { .. } => "cycle",
            Request::Receive { .. } => "receive",
            Request::PollTransmit { .. } => "poll_transmit",
            Request::TransmitComplete {} => "transmit_complete",
            Request::ControllerStatus { .. } => "controller_status",
            Request::Step { .. } => "step",
            Request::Plan { .. } => "plan",
            Request::Start { .. } => "start",
            Request::Task { .. } => "task",
            Request::Declare {} => "declare",
            Request::Bye {} => "bye",
        }
    }

    /// Whether the request drives the controller side (the bus).
    pub fn is_bus_request(&self) -> bool {
        matches!(
            self,
            Request::Receive { .. }
                | Request::PollTransmit { .. }
                | Request::TransmitComplete {}
                | Request::Step { .. }
                | Request::Plan { .. }
        )
    }
}

/// The fields of a `configured` answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Configured {
    pub protocol: u64,
    pub accepted: bool,
    pub reason: Option<String>,
    pub declares: std::collections::BTreeMap<String, String>,
    pub steps: Option<bool>,
}

/// The fields of a `started` answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Started {
    pub protocol: u64,
    pub tells_sent: Option<bool>,
    pub restarts: Option<bool>,
    pub declares: std::collections::BTreeMap<String, String>,
}

/// What the IUT answers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Answer {
    Configured {
        protocol: u64,
        accepted: bool,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reason: Option<String>,
        /// What the device declares where the documents leave a choice
        /// (docs/choices.md), choice name to value.
        #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
        declares: std::collections::BTreeMap<String, String>,
        /// Version 3: whether the device answers `step` records (it tells
        /// its plan, as in version 2; the default) or one record per bus
        /// event (as in version 1: a device that can only be polled).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        steps: Option<bool>,
    },
    Inputs {
        inputs: Hex,
    },
    Ok,
    Transmit {
        frame: Option<Transmitted>,
        #[serde(default)]
        next_ns: Option<Nanos>,
    },
    /// Version 2: the new input image, and the frames the controller will
    /// start, in order, with the earliest time each may start.
    Stepped {
        inputs: Hex,
        plan: Vec<PlannedFrame>,
        /// Version 3: the plan goes on past these frames; the harness asks
        /// for the rest (`plan`) when it has started them.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        more: bool,
    },
    /// Client role: what the client declares, before any start (docs/plc-side.md), name to value.
    Declared {
        #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
        declares: std::collections::BTreeMap<String, String>,
    },
    /// Client role: the program runs, speaking this version; it may say
    /// whether it tells its application which Tx messages were sent, and
    /// declare what it is (docs/plc-side.md), name to value.
    Started {
        protocol: u64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        tells_sent: Option<bool>,
        #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
        declares: std::collections::BTreeMap<String, String>,
        /// Each `start` begins a new program in this process, nothing of the
        /// one before kept: canif may hand the next program's `start` to
        /// this process instead of starting another (`true`), or not.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        restarts: Option<bool>,
    },
    /// Client role: the output image the task left, the messages it
    /// delivered to its application, the requests (by index) it cannot send,
    /// and, optionally, the transaction numbers of the Tx messages it tells
    /// its application were sent (CL-TN-002).
    Tasked {
        outputs: Hex,
        delivered: Vec<WireMessage>,
        refused: Vec<usize>,
        #[serde(default)]
        sent: Vec<u16>,
    },
    Error {
        message: String,
    },
}

impl Answer {
    pub fn name(&self) -> &'static str {
        match self {
            Answer::Configured { .. } => "configured",
            Answer::Inputs { .. } => "inputs",
            Answer::Ok => "ok",
            Answer::Transmit { .. } => "transmit",
            Answer::Stepped { .. } => "stepped",
            Answer::Started { .. } => "started",
            Answer::Declared { .. } => "declared",
            Answer::Tasked { .. } => "tasked",
            Answer::Error { .. } => "error",
        }
    }

    pub fn error(message: impl Into<String>) -> Self {
        Answer::Error {
            message: message.into(),
        }
    }

    /// `configured`: the version agreed, accepted or not, why not, and
    /// what the device declares.
    pub const CONFIGURED: Expected<Configured> = Expected {
        name: "configured",
        take: |answer| match answer {
            Answer::Configured {
                protocol,
                accepted,
                reason,
                declares,
                steps,
            } => Ok(Configured {
                protocol,
                accepted,
                reason,
                declares,
                steps,
            }),
            other => Err(other),
        },
    };
    /// `inputs`: the input image of a version 1 cycle.
    pub const INPUTS: Expected<Hex> = Expected {
        name: "inputs",
        take: |answer| match answer {
            Answer::Inputs { inputs } => Ok(inputs),
            other => Err(other),
        },
    };
    pub const OK: Expected<()> = Expected {
        name: "ok",
        take: |answer| match answer {
            Answer::Ok => Ok(()),
            other => Err(other),
        },
    };
    /// `transmit`: the frame the controller starts, and when a held one is due.
    pub const TRANSMIT: Expected<(Option<Transmitted>, Option<Nanos>)> = Expected {
        name: "transmit",
        take: |answer| match answer {
            Answer::Transmit { frame, next_ns } => Ok((frame, next_ns)),
            other => Err(other),
        },
    };
    /// `stepped`: the input image and the plan of a version 2 step.
    pub const STEPPED: Expected<(Hex, Vec<PlannedFrame>, bool)> = Expected {
        name: "stepped",
        take: |answer| match answer {
            Answer::Stepped { inputs, plan, more } => Ok((inputs, plan, more)),
            other => Err(other),
        },
    };
    /// `started`: the client role's version the program speaks, whether it
    /// says it tells its application what was sent, and what it declares.
    pub const STARTED: Expected<Started> = Expected {
        name: "started",
        take: |answer| match answer {
            Answer::Started {
                protocol,
                tells_sent,
                declares,
                restarts,
            } => Ok(Started {
                protocol,
                tells_sent,
                declares,
                restarts,
            }),
            other => Err(other),
        },
    };
    /// `declared`: what a client declares before any start.
    pub const DECLARED: Expected<std::collections::BTreeMap<String, String>> = Expected {
        name: "declared",
        take: |answer| match answer {
            Answer::Declared { declares } => Ok(declares),
            other => Err(other),
        },
    };
    /// `tasked`: outputs, delivered messages, refused requests, messages told sent.
    pub const TASKED: Expected<Tasked> = Expected {
        name: "tasked",
        take: |answer| match answer {
            Answer::Tasked {
                outputs,
                delivered,
                refused,
                sent,
            } => Ok(Tasked {
                outputs,
                delivered,
                refused,
                sent,
            }),
            other => Err(other),
        },
    };
}

/// The one answer the harness waits for after a request: its name on the
/// wire, and how its fields are taken out (any other answer is given back,
/// for the error that names it).
#[derive(Clone, Copy)]
pub struct Expected<T> {
    pub name: &'static str,
    pub take: fn(Answer) -> Result<T, Answer>,
}

/// The fields of a `tasked` answer.
#[derive(Debug, Clone)]
pub struct Tasked {
    pub outputs: Hex,
    pub delivered: Vec<WireMessage>,
    pub refused: Vec<usize>,
    pub sent: Vec<u16>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use canif_model::frame::{CanId, Frame};

    #[test]
    fn requests_read_as_the_document_writes_them() {
        let line = r#"{"type":"receive","frame":{"id":1701,"extended":false,"rtr":false,"fd":false,"brs":false,"esi":false,"len":2,"data":"0a0B"},"end_ns":10000}"#;
        let Request::Receive { frame, end_ns } = serde_json::from_str(line).unwrap() else {
            panic!("not a receive");
        };
        assert_eq!(end_ns, 10_000);
        let frame = Frame::try_from(&frame).unwrap();
        assert_eq!(
            frame,
            Frame::classic(CanId::Standard(1701), &[0x0A, 0x0B]).unwrap()
        );
        assert_eq!(
            serde_json::to_string(&Request::PollTransmit { now_ns: 5 }).unwrap(),
            r#"{"type":"poll_transmit","now_ns":5}"#
        );
    }

    #[test]
    fn a_transmit_answer_that_does_not_parse_names_the_field_and_the_value() {
        let line = r#"{"type":"transmit","frame":{"id":4294967297,"len":0,"data":""}}"#;
        let error = serde_json::from_str::<Answer>(line)
            .unwrap_err()
            .to_string();
        assert!(error.contains("4294967297"), "{error}");
        assert!(error.contains("a frame"), "{error}");
        let line = r#"{"type":"transmit","frame":{"invalid":7}}"#;
        let error = serde_json::from_str::<Answer>(line)
            .unwrap_err()
            .to_string();
        assert!(error.contains("an invalid frame"), "{error}");
    }

    #[test]
    fn a_frame_that_is_no_frame_is_refused_with_the_reason() {
        let flags = r#""extended":false,"rtr":false,"fd":false,"brs":false,"esi":false"#;
        let wire: WireFrame =
            serde_json::from_str(&format!(r#"{{"id":2048,{flags},"len":0,"data":""}}"#)).unwrap();
        assert_eq!(
            Frame::try_from(&wire).unwrap_err(),
            "identifier 0x800 does not fit an 11-bit identifier"
        );
        assert!(serde_json::from_str::<WireFrame>(r#"{"id":1,"data":"abc"}"#).is_err());
        assert!(serde_json::from_str::<WireFrame>(r#"{"id":4294967297,"data":""}"#).is_err());
        assert!(serde_json::from_str::<WireFrame>(r#"{"id":1,"data":"+0"}"#).is_err());
        assert!(serde_json::from_str::<WireFrame>(r#"{"id":1,"data":"","color":1}"#).is_err());
        // The schema's required fields: a frame without its flags is none.
        assert!(serde_json::from_str::<WireFrame>(r#"{"id":1,"len":0,"data":""}"#).is_err());
        let lie: WireFrame = serde_json::from_str(&format!(
            r#"{{"id":1,{flags},"len":15,"data":"0102030405060708"}}"#
        ))
        .unwrap();
        assert_eq!(
            Frame::try_from(&lie).unwrap_err(),
            "\"len\" is 15 but \"data\" has 8 bytes"
        );
        let config = r#"{"type":"configure","protocol":1,"config":{"format":"11-bit","queue":"standard","transaction_number":false,"time_stamp":false,"tx_slots":257,"rx_slots":4},"capabilities":{"max_slots":32,"rx_queue_depth":64,"tx_queue_depth":64}}"#;
        let error = serde_json::from_str::<Request>(config)
            .unwrap_err()
            .to_string();
        assert!(error.contains("257"), "{error}");
    }

    #[test]
    fn answers_keep_the_field_order_of_the_document() {
        let answer = Answer::Transmit {
            frame: None,
            next_ns: None,
        };
        assert_eq!(
            serde_json::to_string(&answer).unwrap(),
            r#"{"type":"transmit","frame":null,"next_ns":null}"#
        );
        let configured = Answer::Configured {
            steps: None,
            declares: Default::default(),
            protocol: 1,
            accepted: false,
            reason: Some("no".into()),
        };
        assert_eq!(
            serde_json::to_string(&configured).unwrap(),
            r#"{"type":"configured","protocol":1,"accepted":false,"reason":"no"}"#
        );
    }
}
