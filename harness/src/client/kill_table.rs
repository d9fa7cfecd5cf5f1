//! What each faulty client is caught on, over every profile
//! (`harness/tests/client_side.rs` holds every run to it; `canif spec plan`
//! lists them as the faults that prove a check can fail).

use super::soft_client::ClientFault;

/// What each faulty client must be caught on, over every profile.
pub const KILL_TABLE: &[(ClientFault, &[&str])] = &[
    (ClientFault::SendSample000, &["CL-IMG-001"]),
    (
        ClientFault::DecodeOverNoOfTxMessages,
        // With more Tx than Rx slots its loop runs past the Rx slots too.
        &["CL-FQ-001", "CL-IMG-001", "CL-RX-002", "CL-RX-004"],
    ),
    // After a restart its own counter is out of step: judged by what its
    // application sees (P1), the batch it reads again after a PLC restart
    // (CL-RX-002) and nothing more after a device restart (CL-RST-002).
    (
        ClientFault::OwnRxCounter,
        &["CL-FQ-001", "CL-RST-002", "CL-RX-002"],
    ),
    // Also CL-TX-001 since the triple-buffered separate input update hands
    // it an old image to count on from.
    (
        ClientFault::TxCounterPlusOne,
        &["CL-FQ-001", "CL-RX-002", "CL-TX-001", "CL-TX-002"],
    ),
    (
        ClientFault::WritesBeforeAcknowledge,
        &["CL-TX-001", "CL-TX-002"],
    ),
    // What it reads past NoOfRxMessages is no message of the batch, however
    // right its decoding: CL-RX-002, or with the Fast CAN Queue CL-FQ-001
    // (issue 36: before, charged to the decoding, CL-RX-003).
    (ClientFault::ReadsAllSlots, &["CL-FQ-001", "CL-RX-002"]),
    (
        ClientFault::IgnoresWrap,
        &["CL-FQ-001", "CL-RST-002", "CL-TX-003"],
    ),
    // Its last Tx message lands behind the slots: seen since the judge goes
    // on after the first breach (issue 27).
    (
        ClientFault::OneBasedSlots,
        &[
            "CL-FQ-001",
            "CL-IMG-001",
            "CL-RX-002",
            "CL-RX-003",
            "CL-TX-004",
        ],
    ),
    // What it reads past the slots it delivers: messages the device never
    // entered (CL-RX-002), and no frames (CL-RX-003).
    (
        ClientFault::NoBoundOnNoOfRxMessages,
        &["CL-IMG-001", "CL-RX-002", "CL-RX-003"],
    ),
    (
        ClientFault::AcknowledgesAfterFirstMessage,
        &["CL-FQ-001", "CL-RX-004"],
    ),
    (ClientFault::TransactionNumberZero, &["CL-TN-001"]),
    (ClientFault::DropsRtr, &["CL-TX-004"]),
    (ClientFault::FastQueueRereads, &["CL-FQ-001"]),
    (ClientFault::IgnoresExtendedFlag, &["CL-RX-003"]),
    (ClientFault::NoOfTxMessagesIsTheSlotCount, &["CL-TX-005"]),
    (ClientFault::RestartReadsAllSlots, &["CL-RST-001"]),
    (ClientFault::IgnoresRxCounterZero, &["CL-RST-002"]),
    (ClientFault::SentOnAcknowledge, &["CL-TN-002"]),
    // With the Fast CAN Queue Outputs.RxCounter is its memory of the batch
    // it saw last, so the wrong copy rereads batches (CL-FQ-001); with an
    // acknowledge it breaks the copy rule first, then rereads (CL-RX-002).
    (
        ClientFault::AcknowledgesWithTxCounter,
        &["CL-FQ-001", "CL-RX-001", "CL-RX-002"],
    ),
    // Seen where the Rx slots outnumber the Tx slots: its batch runs past
    // the Tx slots into what the master maps behind the image, says more
    // messages than the slots hold, and the ones past them never go.
    (
        ClientFault::TxBatchBoundedByRxSlots,
        &["CL-IMG-001", "CL-TX-003", "CL-TX-005"],
    ),
];
