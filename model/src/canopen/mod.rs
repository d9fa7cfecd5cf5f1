//! CANopen telegrams the PLC builds on the CAN interface to drive Beckhoff bus
//! couplers: NMT, default identifiers, PDO payloads, node guarding, heartbeat
//! and expedited SDO.
//!
//! Source: 002 "Quick Start for Experienced Users", 004 (FC5101/FC5102 manual
//! p. 54), CiA 301 for what they cite (rulings R6, R7, R8).

pub mod cob_id;
pub mod coupler;
pub mod guarding;
pub mod heartbeat;
pub mod nmt;
pub mod pdo;
pub mod sdo;

/// A CANopen node id of a Beckhoff coupler: 1..=63 (002 "Hardware configuration";
/// 0 addresses all nodes in NMT and is no node's address).
///
/// Requirements: NMT-006, COB-001.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(u8);

impl NodeId {
    pub const MAX: u8 = 63;

    pub fn new(id: u8) -> Option<Self> {
        (1..=Self::MAX).contains(&id).then_some(NodeId(id))
    }

    pub fn get(self) -> u8 {
        self.0
    }
}
