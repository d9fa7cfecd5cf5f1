//! Records read back: one decoder for requests and answers.

use super::{entry, get, get_frame, get_message, get_status, get_text, kind, record, tag};
use crate::door::adapter::protocol::{
    Answer, BusEvent, Hex, InvalidWireFrame, PlannedFrame, Request, Status, Transmitted,
};

/// A record read back: its kind, time, entries and images.
pub struct Decoded<'a> {
    pub kind: u32,
    pub time: u64,
    entries: &'a [u8],
    pub outputs: Vec<u8>,
    pub inputs: Vec<u8>,
}

impl<'a> Decoded<'a> {
    /// The record in `bytes` (head and entries), with the images read by `image`.
    pub fn new(bytes: &'a [u8], outputs: Vec<u8>, inputs: Vec<u8>) -> Result<Self, String> {
        let count = get(bytes, record::COUNT) as usize;
        let kind = get(bytes, record::KIND) as u32;
        let room = if kind == kind::ERROR {
            count
        } else {
            count.saturating_mul(entry::SIZE)
        };
        let entries = bytes
            .get(record::ENTRIES..)
            .and_then(|rest| rest.get(..room))
            .ok_or_else(|| format!("a record of {count} entries does not fit its area"))?;
        Ok(Decoded {
            kind,
            time: get(bytes, record::TIME),
            entries,
            outputs,
            inputs,
        })
    }

    fn slots(&self) -> impl Iterator<Item = (u32, &'a [u8])> {
        self.entries
            .chunks_exact(entry::SIZE)
            .map(|slot| (get(slot, entry::TAG) as u32, slot))
    }

    fn unexpected(&self, tag: u32) -> String {
        format!("an entry tagged {tag} in a record of kind {}", self.kind)
    }

    /// The bus events a record carries, in order.
    fn events(&self) -> Result<Vec<BusEvent>, String> {
        let mut events = Vec::with_capacity(self.entries.len() / entry::SIZE);
        for (tag, slot) in self.slots() {
            events.push(match tag {
                tag::RECEIVED => BusEvent::Received {
                    frame: get_frame(slot),
                    end_ns: get(slot, entry::TIME),
                },
                tag::STARTED => BusEvent::Started {
                    at_ns: get(slot, entry::TIME),
                },
                tag::COMPLETED => BusEvent::Completed,
                tag::STATUS => BusEvent::Status {
                    status: Status(get_status(slot)),
                },
                other => return Err(self.unexpected(other)),
            });
        }
        Ok(events)
    }

    /// The request, and the bus events before it (of a polled device's
    /// `cycle` and `poll_transmit`: [`super::encode_batch`]).
    pub fn batch(self) -> Result<(Vec<BusEvent>, Request), String> {
        match self.kind {
            kind::CYCLE | kind::POLL_TRANSMIT => {
                let events = self.events()?;
                if events.iter().any(|e| matches!(e, BusEvent::Started { .. })) {
                    return Err("`started` is an event of a step only".into());
                }
                let request = match self.kind {
                    kind::CYCLE => Request::Cycle {
                        now_ns: self.time,
                        outputs: Hex(self.outputs),
                    },
                    _ => Request::PollTransmit { now_ns: self.time },
                };
                Ok((events, request))
            }
            _ => Ok((Vec::new(), self.request()?)),
        }
    }

    fn request(self) -> Result<Request, String> {
        let time = self.time;
        let single = |want: u32| -> Result<&'a [u8], String> {
            match self.slots().collect::<Vec<_>>().as_slice() {
                [(tag, slot)] if *tag == want => Ok(*slot),
                _ => Err(format!(
                    "a record of kind {} has one entry tagged {want}",
                    self.kind
                )),
            }
        };
        Ok(match self.kind {
            kind::CYCLE => Request::Cycle {
                now_ns: time,
                outputs: Hex(self.outputs),
            },
            kind::RECEIVE => Request::Receive {
                frame: get_frame(single(tag::RECEIVED)?),
                end_ns: time,
            },
            kind::POLL_TRANSMIT => Request::PollTransmit { now_ns: time },
            kind::TRANSMIT_COMPLETE => Request::TransmitComplete {},
            kind::CONTROLLER_STATUS => Request::ControllerStatus {
                status: Status(get_status(single(tag::STATUS)?)),
            },
            kind::STEP => Request::Step {
                now_ns: time,
                events: self.events()?,
                outputs: Hex(self.outputs),
            },
            kind::PLAN => Request::Plan {
                now_ns: time,
                events: self.events()?,
            },
            kind::TASK => {
                let mut requests = Vec::new();
                for (tag, slot) in self.slots() {
                    match tag {
                        tag::MESSAGE => requests.push(get_message(slot)),
                        other => return Err(self.unexpected(other)),
                    }
                }
                Request::Task {
                    inputs: Hex(self.inputs),
                    outputs: Hex(self.outputs),
                    requests,
                }
            }
            other => return Err(format!("no request is of kind {other}")),
        })
    }

    pub fn answer(self) -> Result<Answer, String> {
        Ok(match self.kind {
            kind::OK => Answer::Ok,
            kind::ERROR => Answer::Error {
                message: String::from_utf8_lossy(self.entries).into_owned(),
            },
            kind::INPUTS => Answer::Inputs {
                inputs: Hex(self.inputs),
            },
            kind::TRANSMIT => {
                let mut slots = self.slots();
                let frame = match (slots.next(), slots.next()) {
                    (None, _) => None,
                    (Some((tag::FRAME, slot)), None) => Some(Transmitted::Frame(get_frame(slot))),
                    (Some((tag::INVALID, slot)), None) => {
                        Some(Transmitted::Invalid(InvalidWireFrame {
                            invalid: get_text(slot)?,
                        }))
                    }
                    _ => return Err("a `transmit` record holds one frame or none".into()),
                };
                Answer::Transmit {
                    frame,
                    next_ns: (self.time != u64::MAX).then_some(self.time),
                }
            }
            kind::STEPPED => {
                let mut plan = Vec::with_capacity(self.entries.len() / entry::SIZE);
                for (tag, slot) in self.slots() {
                    let not_before_ns = get(slot, entry::TIME);
                    plan.push(match tag {
                        tag::PLANNED => PlannedFrame {
                            frame: Some(get_frame(slot)),
                            invalid: None,
                            not_before_ns,
                        },
                        tag::PLANNED_INVALID => PlannedFrame {
                            frame: None,
                            invalid: Some(get_text(slot)?),
                            not_before_ns,
                        },
                        other => return Err(self.unexpected(other)),
                    });
                }
                Answer::Stepped {
                    inputs: Hex(self.inputs),
                    plan,
                    more: self.time == 1,
                }
            }
            kind::TASKED => {
                let (mut delivered, mut refused, mut sent) = (Vec::new(), Vec::new(), Vec::new());
                for (tag, slot) in self.slots() {
                    match tag {
                        tag::MESSAGE => delivered.push(get_message(slot)),
                        tag::REFUSED => refused.push(get(slot, entry::AUX) as usize),
                        tag::SENT => sent.push(get(slot, entry::TRANSACTION_NUMBER) as u16),
                        other => return Err(self.unexpected(other)),
                    }
                }
                Answer::Tasked {
                    outputs: Hex(self.outputs),
                    delivered,
                    refused,
                    sent,
                }
            }
            other => return Err(format!("no answer is of kind {other}")),
        })
    }
}
