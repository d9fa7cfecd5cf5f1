//! What each fault of the soft device is caught on: the requirements its
//! failures name (`harness/tests/self_check.rs` holds every run to it, and
//! `canif spec plan` lists them as the faults that prove a check can fail).

use canif_softdevice::Fault;

/// Each fault and exactly the requirements its failures name (blame per
/// field: the requirement of the field that differs, not every id the
/// scenario exercises); it runs on `profile_for(fault)`, a profile with the
/// feature it breaks.
pub const KILL_TABLE: [(Fault, &[&str]); 50] = [
    (
        Fault::AckBeforeAccept,
        &[
            "HS-TX-002",
            "HS-TX-004",
            "HS-TX-006",
            "HS-TX-007",
            "HS-TX-009",
        ],
    ),
    (
        Fault::OverwritesUnacknowledgedRx,
        &["HS-RX-001", "HS-RX-004"],
    ),
    (
        Fault::FdLengthRoundsDown,
        &["ERR-R1", "FD-LEN-003", "FD-LEN-004"],
    ),
    // 36 bytes is the rounding's misprint (R1), not input out of G3's range.
    (
        Fault::FdLength32As36,
        &["ERR-R1", "FD-LEN-003", "FD-LEN-004"],
    ),
    (Fault::RtrBitMisplaced, &["LAY-11-003"]),
    (Fault::ExtendedFlagMissing, &["LAY-29-005"]),
    (Fault::TransactionNumberOfFirstFrame, &["TN-002", "TN-003"]),
    // It names a message handed to the controller and not yet complete:
    // that "sent" means complete is ruling G6's, assumption TN-003 alone.
    (Fault::TransactionNumberOnHandover, &["TN-003"]),
    (
        Fault::TimeStampInMicroseconds,
        &["TS-001", "TS-003", "TS-004"],
    ),
    // Which frames a full queue loses is assumption RXQ-004's (G4) alone:
    // the head drop still loses frames without indication (RXQ-003) and
    // fills every slot (RXQ-006), in the order received (HS-RX-007).
    (Fault::HeadDropWhenFull, &["RXQ-004"]),
    // Which of two disagreeing rows decides is assumption FLT-005's (G7)
    // alone: the rows themselves (FLT-001) and the default (FLT-006) hold.
    (Fault::FilterLastMatchWins, &["FLT-005"]),
    // The manual's 0x700 held back: its table (FLT-009), the range's edge
    // (FLT-004), the acceptance row (FLT-001). At 0x1FF, where a later row
    // overlaps, an early end and a last match look alike (FLT-004, FLT-005).
    (
        Fault::FilterRangeEndExcluded,
        &["FLT-001", "FLT-004", "FLT-005", "FLT-009"],
    ),
    (Fault::FilterUnmatchedAccepted, &["FLT-006"]),
    (Fault::FastQueueWaitsForAck, &["FQ-001", "FQ-002"]),
    (Fault::CounterDoesNotWrap, &["HS-RX-005"]),
    (Fault::RxCounterCountsEmptyCycles, &["HS-RX-006"]),
    (
        Fault::SendsBatchReversed,
        &["HS-TX-004", "HS-TX-006", "HS-TX-009", "HS-TX-011"],
    ),
    (
        Fault::SendsOneMoreThanAsked,
        &["HS-TX-004", "HS-TX-006", "HS-TX-009", "HS-TX-011"],
    ),
    (Fault::FdPaddingFf, &["FD-LEN-005"]),
    (Fault::CobIdWordBigEndian, &["LAY-GEN-003"]),
    (
        Fault::BrsEsiSwapped,
        &["FD-BIT-001", "FD-BIT-002", "FD-BIT-003"],
    ),
    (Fault::ReceiveFifoNotReported, &["INFO-005", "INFO-007"]),
    (Fault::ZeroBatchNotAcknowledged, &["HS-TX-009"]),
    (Fault::TrustsNoOfTxMessages, &["HS-TX-010"]),
    (Fault::BatchCappedAt31, &["HS-TX-009"]),
    (Fault::RxCountCappedAt31, &["HS-RX-002", "HS-RX-007"]),
    (Fault::StandardIdKeepsHighBits, &["LAY-29-006"]),
    (Fault::ClassicLengthUnbounded, &["LAY-GEN-008"]),
    (Fault::BrsWithoutEdlSendsFd, &["FD-BIT-001"]),
    (Fault::Sync1Late, &["PDX-004"]),
    (Fault::InfoDataTwoBytesLate, &["INFO-008"]),
    (Fault::RxMessagesAfterReservedWord, &["LAY-GEN-005"]),
    // RXQ-001 too, in the Gherkin scenario tagged with it (canif self-check).
    // It drops the newest, as G4 says: not the drop order (RXQ-004).
    (Fault::RxQueueOneShort, &["HS-RX-007", "RXQ-003", "RXQ-006"]),
    (Fault::QueueTakes29Bit, &["BQ-003", "PROF-003"]),
    (Fault::QueueTakesTransactionNumber, &["BQ-005", "PROF-003"]),
    (Fault::QueueTakesFilters, &["BQ-004"]),
    (Fault::TimeStampOn11Bit, &["PROF-004", "TS-002"]),
    (Fault::TransactionNumberOn11Bit, &["PROF-005", "TN-004"]),
    (Fault::SlotCountUnbounded, &["LAY-GEN-007", "PROF-011"]),
    (Fault::AcceptsEveryFormat, &["PROF-002", "PROF-009"]),
    (
        Fault::TransactionNumberNotOffered,
        &["PROF-002", "PROF-008"],
    ),
    (
        Fault::RefusesThirtyTwoSlots,
        &["LAY-GEN-007", "PROF-001", "PROF-011"],
    ),
    (Fault::AcceptsMalformedFilter, &["FLT-010"]),
    (
        Fault::FdWithoutTransactionNumber,
        &["LAY-FD-001", "LAY-FD-004"],
    ),
    (
        Fault::DropsWhatDoesNotFit,
        &["HS-TX-007", "HS-TX-008", "HS-TX-012"],
    ),
    (Fault::FdLengthAsDlc, &["FD-LEN-002"]),
    // G3 names the lengths; LAY-FD-003 says it of RTR with EDL.
    (Fault::FdKeepsRemote, &["LAY-FD-003", "LAY-GEN-008"]),
    (Fault::InfoDataStartsZero, &["INFO-009"]),
    // Seen where the PLC steps TxCounter by more than one: the value is
    // not Outputs.TxCounter's, which HS-TX-007 says it is set to.
    (Fault::AcknowledgesByIncrement, &["HS-TX-007"]),
    // The frames are the slots read at the wrong stride: the layout, not
    // the handshake or the transaction numbers.
    (
        Fault::TxReadWithoutTransactionNumber,
        &["LAY-GEN-002", "LAY-GEN-006"],
    ),
];
