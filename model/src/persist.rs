//! Frames and image layouts kept in a file (a shard's part of a run, read
//! back by `canif merge`). They are read back through their constructors, so
//! a file cannot make a frame or a layout the model could not.

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::frame::{CanId, Frame, FrameKind};
use crate::image::{ImageLayout, MessageLayout};

/// A frame as its parts: identifier, kind, and the data (or, for a remote
/// frame, the length it requests).
#[derive(Serialize, Deserialize)]
struct FrameParts {
    id: CanId,
    kind: FrameKind,
    len: u8,
    data: Vec<u8>,
}

impl Serialize for Frame {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        FrameParts {
            id: self.id,
            kind: self.kind,
            len: self.len(),
            data: self.data().to_vec(),
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Frame {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let parts = FrameParts::deserialize(deserializer)?;
        let frame = match parts.kind {
            FrameKind::Classic { rtr: true } => Frame::remote(parts.id, parts.len),
            FrameKind::Classic { rtr: false } => Frame::classic(parts.id, &parts.data),
            FrameKind::Fd { brs, esi } => Frame::fd(parts.id, brs, esi, &parts.data),
        };
        frame.map_err(|e| D::Error::custom(format!("not a frame: {e}")))
    }
}

/// A layout by its message structures' names (001 §8.3 and canif's names
/// for the classic ones) and its counts.
#[derive(Serialize, Deserialize)]
struct LayoutParts {
    tx_message: String,
    rx_message: String,
    transaction_number: bool,
    info_data: bool,
    tx_slots: usize,
    rx_slots: usize,
}

impl Serialize for ImageLayout {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        LayoutParts {
            tx_message: self.tx_message.type_name.into(),
            rx_message: self.rx_message.type_name.into(),
            transaction_number: self.transaction_number,
            info_data: self.info_data,
            tx_slots: self.tx_slots,
            rx_slots: self.rx_slots,
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for ImageLayout {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let parts = LayoutParts::deserialize(deserializer)?;
        let message = |name: &str| {
            MessageLayout::ALL
                .into_iter()
                .find(|m| m.type_name == name)
                .ok_or_else(|| D::Error::custom(format!("no message structure is named {name}")))
        };
        Ok(ImageLayout {
            tx_message: message(&parts.tx_message)?,
            rx_message: message(&parts.rx_message)?,
            transaction_number: parts.transaction_number,
            info_data: parts.info_data,
            tx_slots: parts.tx_slots,
            rx_slots: parts.rx_slots,
        })
    }
}
