//! Network management: the commands and the states they lead to.
//!
//! Source: 002 "Starting the modules" (0x00 | 0x01 0x00), "Stopping the modules"
//! (0x00 | 0x80 0xYZ), ruling R6 (all CiA 301 commands; 0x80 is "enter
//! pre-operational", 0x02 is "stop").

use super::NodeId;
use crate::frame::{CanId, Frame};

/// COB-ID of the NMT command telegram.
pub const NMT_COB_ID: u16 = 0x000;

/// The CiA 301 NMT command specifiers.
///
/// Requirements: NMT-001, NMT-002, NMT-003, ERR-R6.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NmtCommand {
    StartRemoteNode = 0x01,
    StopRemoteNode = 0x02,
    EnterPreOperational = 0x80,
    ResetNode = 0x81,
    ResetCommunication = 0x82,
}

impl NmtCommand {
    pub fn from_byte(byte: u8) -> Option<Self> {
        use NmtCommand::*;
        [
            StartRemoteNode,
            StopRemoteNode,
            EnterPreOperational,
            ResetNode,
            ResetCommunication,
        ]
        .into_iter()
        .find(|command| *command as u8 == byte)
    }
}

/// The NMT states of a node, with the code its guarding reply and heartbeat carry.
///
/// Requirements: NMT-004, GRD-003.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NmtState {
    /// Boot-up (code 0x00); the node passes on to pre-operational by itself.
    Initialising = 0x00,
    Stopped = 0x04,
    Operational = 0x05,
    PreOperational = 0x7F,
}

impl NmtState {
    pub fn code(self) -> u8 {
        self as u8
    }

    pub fn from_code(code: u8) -> Option<Self> {
        use NmtState::*;
        [Initialising, Stopped, Operational, PreOperational]
            .into_iter()
            .find(|state| *state as u8 == code)
    }

    /// The state after `command`. The resets pass through initialisation and end
    /// in pre-operational (after the boot-up message).
    ///
    /// Requirements: NMT-004, NMT-005.
    pub fn apply(self, command: NmtCommand) -> NmtState {
        match command {
            NmtCommand::StartRemoteNode => NmtState::Operational,
            NmtCommand::StopRemoteNode => NmtState::Stopped,
            NmtCommand::EnterPreOperational => NmtState::PreOperational,
            NmtCommand::ResetNode | NmtCommand::ResetCommunication => NmtState::PreOperational,
        }
    }

    /// Are PDOs exchanged in this state?
    ///
    /// Requirements: NMT-005.
    pub fn pdo_allowed(self) -> bool {
        self == NmtState::Operational
    }
}

/// The NMT telegram: id 0x000, two bytes: command, node id (0 = all nodes).
///
/// Requirements: NMT-001, NMT-006.
pub fn command_frame(command: NmtCommand, target: Option<NodeId>) -> Frame {
    let node = target.map_or(0, NodeId::get);
    Frame::classic(CanId::Standard(NMT_COB_ID), &[command as u8, node])
        .expect("2 bytes fit a classic frame")
}

/// Reads an NMT telegram: the command and whom it addresses (`None` = all).
/// Not an NMT telegram (other id, not 2 bytes, unknown command): `None`.
pub fn parse_command(frame: &Frame) -> Option<(NmtCommand, Option<u8>)> {
    if frame.id != CanId::Standard(NMT_COB_ID) || frame.is_remote() || frame.data().len() != 2 {
        return None;
    }
    let command = NmtCommand::from_byte(frame.data()[0])?;
    let node = frame.data()[1];
    Some((command, (node != 0).then_some(node)))
}

/// Does an NMT telegram for `target` (`None` = broadcast) address `node`?
///
/// Requirements: NMT-006.
pub fn addresses(target: Option<u8>, node: NodeId) -> bool {
    target.is_none_or(|target| target == node.get())
}
