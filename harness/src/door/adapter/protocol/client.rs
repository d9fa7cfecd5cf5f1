//! The client role's messages (docs/adapter-protocol.md, "The client role"):
//! a PLC-side client under test, the harness playing the device, the master
//! and the application.

use canif_model::image::MessageRepr;
use serde::{Deserialize, Serialize};

use super::frame::WireFrame;

/// A message as the application and the client exchange it: the frame, and
/// the transaction number and time stamp where the interface has them (0
/// where it has none).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireMessage {
    pub frame: WireFrame,
    pub transaction_number: u16,
    pub time_stamp_ns: u64,
}

impl From<&MessageRepr> for WireMessage {
    fn from(message: &MessageRepr) -> Self {
        WireMessage {
            frame: WireFrame::from(&message.frame),
            transaction_number: message.transaction_number,
            time_stamp_ns: message.time_stamp,
        }
    }
}

impl TryFrom<&WireMessage> for MessageRepr {
    type Error = String;
    fn try_from(message: &WireMessage) -> Result<Self, String> {
        Ok(MessageRepr {
            transaction_number: message.transaction_number,
            frame: (&message.frame).try_into()?,
            time_stamp: message.time_stamp_ns,
        })
    }
}
