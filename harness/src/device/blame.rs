//! Which requirements a difference in each place of the interface can break.
//! The scenario's own list narrows them to what it exercises; a Gherkin check
//! names the same sets for the fields it reads.

use canif_spec::{req_ids, ReqId};

use canif_model::filter::{self, FilterAction, FilterMatch, FilterRow};
use canif_model::frame::CanId;

use crate::error::InvalidFrame;

pub const INPUT_IMAGE_SIZE: &[ReqId] = req_ids!["LAY-GEN-004"];
pub const TX_COUNTER: &[ReqId] = req_ids![
    "HS-TX-002",
    "HS-TX-003",
    "HS-TX-005",
    "HS-TX-007",
    "HS-TX-008",
    "HS-TX-012",
    "FQ-003",
];
/// Inputs.TxCounter moved to a value that is neither its last nor
/// Outputs.TxCounter: 003 says the acknowledge "is set to the value of the
/// TxCounter in the EtherCAT output data" (HS-TX-007), whatever the PLC's step.
pub const TX_ACKNOWLEDGE_VALUE: &[ReqId] = req_ids!["HS-TX-007"];
/// The device filled a buffer the PLC had not released.
pub const RX_UNRELEASED: &[ReqId] = req_ids!["HS-RX-001", "HS-RX-004"];
/// RxCounter moved with nothing new.
pub const RX_EMPTY_DELIVERY: &[ReqId] = req_ids!["HS-RX-006"];
/// A frame came in that should not have (or one was held back that should not).
pub const RX_ADMISSION: &[ReqId] = req_ids![
    "RXQ-005", "FLT-001", "FLT-002", "FLT-003", "FLT-004", "FLT-005", "FLT-006", "FLT-007",
    "FLT-008", "FLT-009",
];
/// Nothing delivered although there was something and the buffer was free.
pub const RX_WITHHELD_FAST: &[ReqId] = req_ids!["FQ-001", "FQ-002"];
pub const RX_WITHHELD: &[ReqId] = req_ids![
    "BQ-002",
    "HS-RX-001",
    "FLT-001",
    "FLT-005",
    "FLT-006",
    "FLT-008",
];
/// NoOfRxMessages with nothing new, against the device's declared rx-idle-count.
pub const RX_IDLE_COUNT: &[ReqId] = req_ids!["HS-RX-009"];
/// A slot past NoOfRxMessages, against the device's declared stale-rx-slots.
pub const RX_STALE_SLOTS: &[ReqId] = req_ids!["HS-RX-008"];
/// Both moved, to different values.
pub const RX_COUNTING: &[ReqId] = req_ids!["HS-RX-005", "HS-RX-006"];
/// The messages delivered, or their order: the local queue's depth (how
/// many it keeps) decides which survive a flood. Which ones a full queue
/// drops (RXQ-004) is told apart by the history ([`RX_DROP_POLICY`]).
pub const RX_SET: &[ReqId] = req_ids![
    "HS-RX-001",
    "HS-RX-002",
    "HS-RX-004",
    "HS-RX-007",
    "BQ-002",
    "RXQ-001",
    "RXQ-002",
    "RXQ-003",
    "RXQ-005",
    "RXQ-006",
    "FQ-004",
    "FLT-001",
    "FLT-002",
    "FLT-003",
    "FLT-004",
    "FLT-005",
    "FLT-006",
    "FLT-007",
    "FLT-008",
    "FLT-009",
];
/// A full local Rx queue lost other frames than the newest: the device kept
/// one the model's tail drop lost, or evicted one the model queued with
/// room. Which frames go is what assumption RXQ-004 (G4's tail drop) decides
/// and no normative statement does (RXQ-003 says only that frames are lost).
pub const RX_DROP_POLICY: &[ReqId] = req_ids!["RXQ-004"];
pub const TRANSACTION_NUMBER: &[ReqId] = req_ids!["TN-002", "TN-003"];
/// Inputs.TransactionNumber names a message the device has not yet completed
/// on the bus: that "sent" means complete is ruling G6's, assumption TN-003.
pub const TRANSACTION_NUMBER_EARLY: &[ReqId] = req_ids!["TN-003"];
pub const COB_WORD: &[ReqId] = req_ids!["LAY-11-002", "LAY-11-003", "LAY-11-004", "LAY-GEN-003"];
/// A multi-byte field with its bytes swapped.
pub const BYTE_ORDER: &[ReqId] = req_ids!["LAY-GEN-003"];
pub const COB_LOW: &[ReqId] = req_ids!["LAY-29-003", "LAY-GEN-003"];
pub const COB_RTR: &[ReqId] = req_ids!["LAY-29-004"];
pub const COB_FORMAT: &[ReqId] = req_ids!["LAY-29-005"];
pub const LENGTH: &[ReqId] = req_ids!["LAY-11-002", "LAY-29-002", "FD-LEN-005", "LAY-GEN-003"];
pub const FLAGS: &[ReqId] = req_ids!["FD-BIT-001", "FD-BIT-002", "FD-BIT-003"];
pub const TIME_STAMP: &[ReqId] = req_ids!["TS-001", "TS-003", "TS-004"];
pub const TX_MISSING: &[ReqId] = req_ids![
    "HS-TX-002",
    "HS-TX-004",
    "HS-TX-006",
    "HS-TX-007",
    "HS-TX-009",
];
pub const TX_EXTRA: &[ReqId] = req_ids!["HS-TX-006", "HS-TX-009", "HS-TX-011"];
/// Distributed Clocks: the first message of a batch before SYNC1 less the jitter.
pub const SYNC1_EARLY: &[ReqId] = req_ids!["PDX-004", "PDX-005"];
pub const TX_OTHER_FRAME: &[ReqId] = req_ids!["HS-TX-004", "HS-TX-006", "HS-TX-009"];
pub const TX_REMOTE: &[ReqId] = req_ids!["LAY-11-003", "LAY-29-004"];
pub const TX_FORMAT: &[ReqId] = req_ids!["LAY-29-005", "FD-BIT-001"];
pub const TX_FD_FLAGS: &[ReqId] = req_ids!["FD-BIT-001", "FD-BIT-002", "FD-BIT-003"];
pub const TX_LENGTH: &[ReqId] = req_ids![
    "FD-LEN-003",
    "FD-LEN-004",
    "ERR-R1",
    "LAY-11-002",
    "LAY-29-002",
    "HS-TX-009",
];
pub const TX_PADDING: &[ReqId] = req_ids!["FD-LEN-005"];
pub const TX_DATA: &[ReqId] = req_ids!["HS-TX-006", "LAY-GEN-003"];
/// A Tx frame the IUT decoded from the output image with another message
/// structure's stride and offsets (a transaction number skipped or read as
/// the COB ID).
pub const TX_STRIDE: &[ReqId] = req_ids!["LAY-GEN-006", "LAY-GEN-002"];
pub const TX_INVALID: &[ReqId] = req_ids!["FD-LEN-003", "FD-LEN-004", "ERR-R1", "LAY-GEN-008"];
/// An FD frame whose data field is no valid size (36 bytes): the rounding
/// to the next valid size and its DLC.
pub const TX_LENGTH_ROUNDING: &[ReqId] = req_ids!["FD-LEN-003", "FD-LEN-004", "ERR-R1"];
/// A length field beyond the frame's on the CAN FD interface (EDL = 0 and
/// above 8, or above 64) sent as it is.
pub const TX_INVALID_FD_LENGTH: &[ReqId] = req_ids!["FD-LEN-006", "LAY-GEN-008"];
/// RTR with EDL sent as a remote FD frame, which CAN FD does not have.
pub const TX_REMOTE_FD: &[ReqId] = req_ids!["LAY-FD-003", "LAY-GEN-008"];
/// A received FD frame's DLC in dataLength where its byte count belongs.
pub const RX_LENGTH_AS_DLC: &[ReqId] = req_ids!["FD-LEN-002"];
pub const CONFIRMATION: &[ReqId] = req_ids!["PDX-001", "PDX-002"];
/// A device that read or wrote past its images (G3: nothing is read outside
/// the image, whatever NoOfTxMessages or a length field says).
pub const OUTSIDE_IMAGE: &[ReqId] = req_ids!["HS-TX-010", "LAY-GEN-008"];
/// With Distributed Clocks the cycle ran on a telegram, not on SYNC0.
pub const SYNC0_STARTS_THE_CYCLE: &[ReqId] = req_ids!["PDX-005"];
/// What a door saw the device do where the lockstep does not look.
pub fn deviated(kind: crate::door::iut::Deviated) -> &'static [ReqId] {
    use crate::door::iut::Deviated;
    match kind {
        Deviated::Sync0StartsTheCycle => SYNC0_STARTS_THE_CYCLE,
        Deviated::Confirmation => CONFIRMATION,
    }
}
/// A batch of nothing was not acknowledged.
pub const TX_EMPTY_BATCH: &[ReqId] = req_ids!["HS-TX-009"];
/// A Tx identifier decoded from the wrong bits of the COB ID.
pub const TX_ID_WORD: &[ReqId] = req_ids!["LAY-11-004"];
pub const TX_ID_29: &[ReqId] = req_ids!["LAY-29-003"];
/// Bits 11-28 of a COB ID with bit 31 = 0 taken as part of the identifier.
pub const TX_ID_RESERVED: &[ReqId] = req_ids!["LAY-29-006"];
/// The Rx messages sit at another offset of the input image.
pub const RX_MESSAGES_OFFSET: &[ReqId] = req_ids!["LAY-GEN-005"];
pub const RX_MESSAGES_OFFSET_TN: &[ReqId] = req_ids!["LAY-GEN-004"];
/// InfoData sits at another offset of the input image.
pub const INFO_DATA_OFFSET: &[ReqId] = req_ids!["INFO-008"];
/// Distributed Clocks: the first message of a batch later than SYNC1 plus the jitter.
pub const SYNC1_LATE: &[ReqId] = req_ids!["PDX-004"];

/// The requirements a frame no controller can send breaks, by what is wrong
/// with it: an identifier beyond 11 bits comes from COB ID bits that with bit
/// 31 clear are not the identifier's (LAY-29-006); beyond 29 bits, from the
/// COB ID's flag bits (LAY-29-003); BRS or ESI on a classic frame, or a
/// remote FD frame, from the FD flags (FD-BIT-*); a length beyond the
/// format's from the length field (LAY-GEN-008, FD-LEN-*).
///
/// On the CAN FD interface a length beyond the frame's is what FD-LEN-006
/// says of its structure, and a remote FD frame what LAY-FD-003 says; both
/// before G3's general bound. A length that is no FD size is the rounding's.
pub fn invalid_frame(invalid: &InvalidFrame, fd_interface: bool) -> &'static [ReqId] {
    use canif_model::frame::FrameError;
    match invalid {
        InvalidFrame::Identifier {
            extended: false, ..
        } => TX_ID_RESERVED,
        InvalidFrame::Identifier { extended: true, .. } => TX_ID_29,
        InvalidFrame::FdBitsOnClassic { .. } => TX_FD_FLAGS,
        InvalidFrame::RemoteFd => TX_REMOTE_FD,
        InvalidFrame::Parts(FrameError::FdInvalidSize { .. }) => TX_LENGTH_ROUNDING,
        InvalidFrame::Parts(FrameError::ClassicTooLong { .. } | FrameError::FdTooLong { .. })
            if fd_interface =>
        {
            TX_INVALID_FD_LENGTH
        }
        InvalidFrame::Parts(_) | InvalidFrame::Declared(_) => TX_INVALID,
    }
}

/// The filter statement that decides whether identifier `id` passes `table`
/// (000 §7, ruling G7): where matching rows disagree, their order (FLT-005);
/// where none matches, the default (FLT-006); otherwise the deciding row, its
/// range first when `id` is at its edge (FLT-004), or its mask (FLT-003),
/// and the manual's example table first of all (FLT-009). At the edge of a
/// row that a later row overlaps both the range and the order can be what
/// broke. `None` without filters. A device that decides `id` otherwise
/// contradicts this statement first; the assumptions (FLT-005, FLT-006) are
/// charged alone.
pub fn filter_statement(table: &[FilterRow], id: CanId) -> Option<&'static [ReqId]> {
    if table.is_empty() {
        return None;
    }
    let mut matching = table.iter().filter(|row| row.matches(id));
    let Some(first) = matching.next() else {
        return Some(req_ids!["FLT-006"]);
    };
    let disagree = matching.any(|row| row.action != first.action);
    let raw = id.raw();
    let edge = matches!(first.matches, FilterMatch::Range { from, to } if raw == from || raw == to);
    // At the deciding row's edge, a later row that disagrees decides for a
    // device whose range ends early as for one whose last match wins.
    match (disagree, edge) {
        (true, true) => return Some(req_ids!["FLT-004", "FLT-005"]),
        (true, false) => return Some(req_ids!["FLT-005"]),
        _ => {}
    }
    let manual = table == filter::manual_example();
    let mask = matches!(first.matches, FilterMatch::CodeMask { .. });
    Some(match (manual, first.action, edge, mask) {
        (true, FilterAction::Accept, true, _) => req_ids!["FLT-009", "FLT-004", "FLT-001"],
        (true, FilterAction::Reject, true, _) => req_ids!["FLT-009", "FLT-004", "FLT-002"],
        (true, FilterAction::Accept, false, _) => req_ids!["FLT-009", "FLT-001"],
        (true, FilterAction::Reject, false, _) => req_ids!["FLT-009", "FLT-002"],
        (false, FilterAction::Accept, true, _) => req_ids!["FLT-004", "FLT-001"],
        (false, FilterAction::Reject, true, _) => req_ids!["FLT-004", "FLT-002"],
        (false, FilterAction::Accept, false, true) => req_ids!["FLT-003", "FLT-001"],
        (false, FilterAction::Reject, false, true) => req_ids!["FLT-003", "FLT-002"],
        (false, FilterAction::Accept, false, false) => req_ids!["FLT-001"],
        (false, FilterAction::Reject, false, false) => req_ids!["FLT-002"],
    })
}

/// The requirements of `InfoData[index]`; before the controller reported
/// anything, the status and core words are assumption INFO-009's alone.
pub fn info_data(index: usize, controller_reported: bool) -> &'static [ReqId] {
    match index {
        0 | 11 if !controller_reported => req_ids!["INFO-009"],
        0 => req_ids!["INFO-002"],
        1 | 2 => req_ids!["INFO-003"],
        3 => req_ids!["INFO-004"],
        4..=6 => req_ids!["INFO-005", "INFO-007"],
        11 => req_ids!["INFO-006"],
        15 => req_ids!["INFO-006"],
        _ => req_ids!["INFO-005"],
    }
}

/// The requirements a difference breaks: those of the differing field that the
/// scenario exercises, or, when it exercises none of them, the field's own.
pub fn narrow(covers: &[ReqId], candidates: &[ReqId]) -> Vec<ReqId> {
    let narrowed: Vec<ReqId> = candidates
        .iter()
        .filter(|id| covers.contains(id))
        .copied()
        .collect();
    if narrowed.is_empty() {
        candidates.to_vec()
    } else {
        narrowed
    }
}

/// The tags a failed Gherkin check blames: those among the requirements it
/// `witnessed`, or every tag when none is. Unlike [`narrow`] it never goes
/// past the tags: a step fails on what the whole scenario set up, so outside
/// them nothing says which requirement broke.
pub fn narrow_tags(tags: &[String], witnessed: &[ReqId]) -> Vec<String> {
    let narrowed: Vec<String> = tags
        .iter()
        .filter(|tag| witnessed.iter().any(|id| id == *tag))
        .cloned()
        .collect();
    if narrowed.is_empty() {
        tags.to_vec()
    } else {
        narrowed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_difference_blames_what_the_scenario_exercises_of_the_field_else_the_field() {
        let covers = req_ids!["LAY-GEN-003", "HS-TX-001"];
        assert_eq!(narrow(covers, BYTE_ORDER), req_ids!["LAY-GEN-003"]);
        assert_eq!(narrow(covers, COB_WORD), req_ids!["LAY-GEN-003"]);
        assert_eq!(narrow(req_ids!["HS-TX-001"], COB_RTR), COB_RTR);
    }

    #[test]
    fn a_gherkin_check_blames_only_witnessed_tags_else_every_tag() {
        let tags = vec!["HS-RX-005".to_string(), "HS-TX-005".to_string()];
        assert_eq!(narrow_tags(&tags, RX_COUNTING), ["HS-RX-005"]);
        assert_eq!(narrow_tags(&tags, TIME_STAMP), tags);
    }

    #[test]
    fn every_info_data_word_has_its_requirement() {
        for index in 0..canif_model::image::field::INFO_DATA_WORDS {
            assert!(!info_data(index, true).is_empty(), "InfoData[{index}]");
        }
        assert_eq!(info_data(3, true), req_ids!["INFO-004"]);
    }

    /// Issue 36: the initial status and core words are assumption
    /// INFO-009's alone; once the controller reported, its statements'.
    #[test]
    fn the_initial_info_data_is_charged_to_its_assumption_alone() {
        assert_eq!(info_data(0, false), req_ids!["INFO-009"]);
        assert_eq!(info_data(11, false), req_ids!["INFO-009"]);
        assert_eq!(info_data(0, true), req_ids!["INFO-002"]);
        assert_eq!(info_data(11, true), req_ids!["INFO-006"]);
        assert_eq!(info_data(3, false), req_ids!["INFO-004"]);
    }

    /// Issue 36: what no controller sends is charged to the statement
    /// that says so for its interface, the general bound after it.
    #[test]
    fn an_invalid_frame_names_the_statement_of_its_interface_first() {
        use canif_model::frame::FrameError;
        let too_long = InvalidFrame::Parts(FrameError::ClassicTooLong { len: 15 });
        assert_eq!(invalid_frame(&too_long, false), TX_INVALID);
        assert_eq!(invalid_frame(&too_long, true)[0], ReqId::new("FD-LEN-006"));
        let remote = invalid_frame(&InvalidFrame::RemoteFd, true);
        assert_eq!(remote[0], ReqId::new("LAY-FD-003"));
        let size = InvalidFrame::Parts(FrameError::FdInvalidSize { len: 36 });
        assert!(!invalid_frame(&size, true).contains(&ReqId::new("LAY-GEN-008")));
    }

    /// Issue 36: a filter difference names the statement deciding the
    /// identifier - the order of disagreeing rows and the default are
    /// assumptions charged alone; a range's edge names the range first; the
    /// manual's example table names itself.
    #[test]
    fn a_filter_difference_names_the_statement_that_decides_the_identifier() {
        let id = |raw: u32| CanId::Extended(raw);
        let overlapping = [
            FilterRow::accept_range(0x100, 0x1FF),
            FilterRow::reject_range(0x180, 0x2FF),
        ];
        let decided = |table: &[FilterRow], raw| filter_statement(table, id(raw)).unwrap();
        assert_eq!(decided(&overlapping, 0x190), req_ids!["FLT-005"]);
        assert_eq!(decided(&overlapping, 0x400), req_ids!["FLT-006"]);
        assert_eq!(decided(&overlapping, 0x1FF), req_ids!["FLT-004", "FLT-005"]);
        assert_eq!(decided(&overlapping, 0x100), req_ids!["FLT-004", "FLT-001"]);
        assert_eq!(decided(&overlapping, 0x120), req_ids!["FLT-001"]);
        assert_eq!(decided(&overlapping, 0x2FF), req_ids!["FLT-004", "FLT-002"]);
        let manual = filter::manual_example();
        assert_eq!(
            decided(&manual, 0x700),
            req_ids!["FLT-009", "FLT-004", "FLT-001"]
        );
        assert_eq!(decided(&manual, 0x500), req_ids!["FLT-009", "FLT-001"]);
        let mask = [FilterRow::accept_code_mask(0x100, 0x700)];
        assert_eq!(decided(&mask, 0x101), req_ids!["FLT-003", "FLT-001"]);
        assert_eq!(filter_statement(&[], id(0x100)), None);
    }
}
