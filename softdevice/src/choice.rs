/// What the documents leave to the implementer. A device that makes any of
/// these choices conforms, and the suite must not fail it: each one is a
/// don't-care the harness has to honour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Choice {
    ClearsRxCountWhenIdle,
    KeepsStaleRxSlots,
    RefusesOversizeBatch,
    DropsMessageWithBadLength,
    Sync1Jitter,
    CountsFrameOnWire,
}

impl Choice {
    pub const ALL: [Choice; 6] = [
        Choice::ClearsRxCountWhenIdle,
        Choice::KeepsStaleRxSlots,
        Choice::RefusesOversizeBatch,
        Choice::DropsMessageWithBadLength,
        Choice::Sync1Jitter,
        Choice::CountsFrameOnWire,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Choice::ClearsRxCountWhenIdle => "clears-rx-count-when-idle",
            Choice::KeepsStaleRxSlots => "keeps-stale-rx-slots",
            Choice::RefusesOversizeBatch => "refuses-oversize-batch",
            Choice::DropsMessageWithBadLength => "drops-message-with-bad-length",
            Choice::Sync1Jitter => "sync1-jitter",
            Choice::CountsFrameOnWire => "counts-frame-on-wire",
        }
    }

    /// What the device does, and where the documents allow it.
    pub fn description(self) -> &'static str {
        match self {
            Choice::ClearsRxCountWhenIdle => "writes NoOfRxMessages = 0 in a cycle that enters nothing once the PLC has acknowledged (003; the read sample reads it only with a new RxCounter, HS-RX-008)",
            Choice::KeepsStaleRxSlots => "leaves old bytes in the Rx slots past NoOfRxMessages (HS-RX-008, FQ-005)",
            Choice::RefusesOversizeBatch => "acknowledges a batch whose NoOfTxMessages exceeds the slots and sends none of it (G3, HS-TX-010)",
            Choice::DropsMessageWithBadLength => "skips a Tx message whose length field is out of range instead of clamping it (G3, LAY-GEN-008)",
            Choice::Sync1Jitter => "starts the first message of a batch 400 ns after SYNC1, within the 500 ns jitter (003, PDX-004)",
            Choice::CountsFrameOnWire => "counts the frame on the wire against the send queue's depth until it is sent (HS-TX-012 the other way; declared as tx-queue-accounting=wire-in-queue)",
        }
    }

    pub fn from_name(name: &str) -> Option<Choice> {
        Choice::ALL.into_iter().find(|c| c.name() == name)
    }
}
