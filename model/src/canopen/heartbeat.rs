//! Heartbeat: a status telegram the node sends by itself every producer time.
//!
//! Source: 002 "heartbeat" (producer heartbeat time, object 0x1017, set by SDO
//! 0x22 0x17 0x10 0x00 0xcd 0xab 0x00 0x00 for 0xabcd ms; no remote frames).

use super::cob_id::{default_cob_id, Channel};
use super::nmt::NmtState;
use super::sdo::SdoRequest;
use super::NodeId;
use crate::frame::{CanId, Frame};
use crate::Nanos;

/// Producer heartbeat time object (UNSIGNED16, ms).
pub const PRODUCER_HEARTBEAT_TIME: u16 = 0x1017;

/// The heartbeat telegram: 0x700 + node id, one byte, the NMT state (no toggle).
///
/// Requirements: HB-001.
pub fn heartbeat(node: NodeId, state: NmtState) -> Frame {
    Frame::classic(
        CanId::Standard(default_cob_id(Channel::ErrorControl, node)),
        &[state.code()],
    )
    .expect("1 byte fits")
}

/// The SDO download that sets the producer time to `period_ms` (0 switches it off).
///
/// Requirements: HB-002.
pub fn set_producer_time(period_ms: u16) -> SdoRequest {
    SdoRequest::download(PRODUCER_HEARTBEAT_TIME, 0, u32::from(period_ms))
}

/// When the next heartbeat is due after one sent at `last`; `None` when off.
///
/// Requirements: HB-003.
pub fn next_due(last: Nanos, period_ms: u16) -> Option<Nanos> {
    (period_ms != 0).then(|| last + u64::from(period_ms) * 1_000_000)
}
