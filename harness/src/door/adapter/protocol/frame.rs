//! Frames and bytes on the protocol's lines.

use canif_model::frame::{CanId, Frame, FrameKind};

use crate::error::InvalidFrame;
use serde::{Deserialize, Serialize};

/// A frame the controller starts sending: a valid frame, or what the device
/// produced that is none (the soft device reports such a frame rather than
/// hiding it; the harness judges it).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Transmitted {
    Frame(WireFrame),
    Invalid(InvalidWireFrame),
}

/// Told apart by the `invalid` field, so that an error says which field of
/// which shape is wrong and with what value (serde's untagged enums say only
/// that nothing matched).
impl<'de> Deserialize<'de> for Transmitted {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let value = serde_json::Value::deserialize(deserializer)?;
        if value.get("invalid").is_some() {
            InvalidWireFrame::deserialize(value)
                .map(Transmitted::Invalid)
                .map_err(|e| D::Error::custom(format!("an invalid frame: {e}")))
        } else {
            WireFrame::deserialize(value)
                .map(Transmitted::Frame)
                .map_err(|e| D::Error::custom(format!("a frame: {e}")))
        }
    }
}

/// `{"invalid": "why"}`: the device's controller started something that is no
/// CAN frame (the harness judges it against LAY-GEN-008, FD-LEN-00x).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InvalidWireFrame {
    pub invalid: String,
}

/// Bytes as a lower-case hex string, held in `B`: a `Vec` for an image, a
/// [`FrameData`] for a frame's data.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(
    try_from = "String",
    into = "String",
    bound = "B: FromIterator<u8> + AsRef<[u8]> + Clone"
)]
pub struct Hex<B = Vec<u8>>(pub B);

/// A frame's data, held inline up to the 64 bytes of an FD frame, so that
/// the frames of every cycle's records and plans cost no allocation. (A
/// longer one, which only a broken message carries, still reads, so that
/// [`WireFrame::check`] can say what is wrong.)
pub type FrameData = Hex<smallvec::SmallVec<[u8; 64]>>;

impl<B: FromIterator<u8>> TryFrom<String> for Hex<B> {
    type Error = String;
    fn try_from(text: String) -> Result<Self, String> {
        from_hex(&text).map(Hex)
    }
}

impl<B: AsRef<[u8]>> From<Hex<B>> for String {
    fn from(hex: Hex<B>) -> String {
        to_hex(hex.0.as_ref())
    }
}

impl From<&[u8]> for FrameData {
    fn from(bytes: &[u8]) -> Self {
        Hex(smallvec::SmallVec::from_slice(bytes))
    }
}

impl FrameData {
    pub fn as_slice(&self) -> &[u8] {
        &self.0
    }
}

fn from_hex<B: FromIterator<u8>>(text: &str) -> Result<B, String> {
    if !text.len().is_multiple_of(2) || !text.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Err(format!(
            "not a hex string of whole bytes: {:?}",
            shorten(text)
        ));
    }
    let digit = |b: u8| match b {
        b'0'..=b'9' => b - b'0',
        b'a'..=b'f' => b - b'a' + 10,
        _ => b - b'A' + 10, // checked above: a hex digit
    };
    Ok(text
        .as_bytes()
        .chunks_exact(2)
        .map(|pair| (digit(pair[0]) << 4) | digit(pair[1]))
        .collect())
}

fn to_hex(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 16] = b"0123456789abcdef";
    let mut text = String::with_capacity(2 * bytes.len());
    for byte in bytes {
        text.push(char::from(DIGITS[usize::from(byte >> 4)]));
        text.push(char::from(DIGITS[usize::from(byte & 0x0F)]));
    }
    text
}

fn shorten(text: &str) -> String {
    text.chars().take(40).collect()
}

/// A CAN frame on the protocol.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireFrame {
    // Every field is required, as the schema says: a frame without its
    // flags is refused, not read as a classic 11-bit data frame.
    pub id: u32,
    pub extended: bool,
    pub rtr: bool,
    pub fd: bool,
    pub brs: bool,
    pub esi: bool,
    pub len: u8,
    pub data: FrameData,
}

impl From<&Frame> for WireFrame {
    fn from(frame: &Frame) -> Self {
        let (rtr, fd, brs, esi) = match frame.kind {
            FrameKind::Classic { rtr } => (rtr, false, false, false),
            FrameKind::Fd { brs, esi } => (false, true, brs, esi),
        };
        WireFrame {
            id: frame.id.raw(),
            extended: frame.id.is_extended(),
            rtr,
            fd,
            brs,
            esi,
            len: frame.len(),
            data: FrameData::from(frame.data()),
        }
    }
}

impl WireFrame {
    /// Whether the message is consistent in itself: `len` and `data` agree
    /// and a remote frame carries no data. A message that is not is a broken
    /// protocol, not a frame. A consistent message can still describe what no
    /// controller can send (an identifier beyond its format, BRS on a classic
    /// frame): that is the device's doing, [`WireFrame::to_frame`] says what.
    pub fn check(&self) -> Result<(), String> {
        let data = self.data.as_slice().len();
        if self.rtr && data != 0 {
            return Err(format!(
                "a remote frame carries no data, but \"data\" has {data} bytes"
            ));
        }
        if !self.rtr && usize::from(self.len) != data {
            return Err(format!(
                "\"len\" is {} but \"data\" has {data} bytes",
                self.len
            ));
        }
        Ok(())
    }
}

impl WireFrame {
    /// The CAN frame a consistent message (see [`WireFrame::check`])
    /// describes; `Err` for one that no controller can send (9 classic bytes,
    /// 36 FD bytes, a remote frame above 8, an identifier beyond its format).
    pub fn to_frame(&self) -> Result<Frame, InvalidFrame> {
        let id = if self.extended {
            CanId::extended(self.id)
        } else {
            CanId::standard(self.id)
        }
        .ok_or(InvalidFrame::Identifier {
            id: self.id,
            extended: self.extended,
        })?;
        InvalidFrame::of_fd_bits(self.fd, self.rtr, self.brs, self.esi)?;
        let frame = if self.fd {
            Frame::fd(id, self.brs, self.esi, self.data.as_slice())
        } else if self.rtr {
            Frame::remote(id, self.len)
        } else {
            Frame::classic(id, self.data.as_slice())
        };
        frame.map_err(InvalidFrame::Parts)
    }
}

impl TryFrom<&WireFrame> for Frame {
    type Error = String;
    /// A consistent message's frame, or why there is none, in words.
    fn try_from(wire: &WireFrame) -> Result<Frame, String> {
        wire.check()?;
        wire.to_frame().map_err(|e| e.to_string())
    }
}
