//! Default CAN identifiers of a Beckhoff coupler's objects, derived from the node id.
//!
//! Source: 002 "CAN identifier" (pre-defined connection set), 004 (SDO 0x580/0x600),
//! ruling R7 (0x600 = 1536).

use super::NodeId;

/// The objects of the pre-defined connection set a coupler uses.
///
/// Requirements: COB-001, COB-002, SDO-001, GRD-001, ERR-R7.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Channel {
    DigitalInputs,
    DigitalOutputs,
    AnalogInputs1To4,
    AnalogOutputs1To4,
    AnalogInputs5To8,
    AnalogOutputs5To8,
    AnalogInputs9To12,
    AnalogOutputs9To12,
    /// Server → client (responses): 0x580.
    SdoResponse,
    /// Client → server (requests): 0x600.
    SdoRequest,
    /// Node guarding and heartbeat: 0x700.
    ErrorControl,
}

impl Channel {
    /// The base the node id is added to.
    pub fn base(self) -> u16 {
        use Channel::*;
        match self {
            DigitalInputs => 0x180,
            DigitalOutputs => 0x200,
            AnalogInputs1To4 => 0x280,
            AnalogOutputs1To4 => 0x300,
            AnalogInputs5To8 => 0x380,
            AnalogOutputs5To8 => 0x400,
            AnalogInputs9To12 => 0x480,
            AnalogOutputs9To12 => 0x500,
            SdoResponse => 0x580,
            SdoRequest => 0x600,
            ErrorControl => 0x700,
        }
    }

    pub const ALL: [Channel; 11] = [
        Channel::DigitalInputs,
        Channel::DigitalOutputs,
        Channel::AnalogInputs1To4,
        Channel::AnalogOutputs1To4,
        Channel::AnalogInputs5To8,
        Channel::AnalogOutputs5To8,
        Channel::AnalogInputs9To12,
        Channel::AnalogOutputs9To12,
        Channel::SdoResponse,
        Channel::SdoRequest,
        Channel::ErrorControl,
    ];
}

/// The default identifier: base + node id.
///
/// Requirements: COB-001, COB-002.
pub fn default_cob_id(channel: Channel, node: NodeId) -> u16 {
    channel.base() + u16::from(node.get())
}

/// Which channel and node a default identifier belongs to, if any.
pub fn classify(cob_id: u16) -> Option<(Channel, NodeId)> {
    Channel::ALL.into_iter().find_map(|channel| {
        let node = cob_id.checked_sub(channel.base())?;
        let node = NodeId::new(u8::try_from(node).ok()?)?;
        Some((channel, node))
    })
}
