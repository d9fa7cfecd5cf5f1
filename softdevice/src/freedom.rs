/// What the documents leave to the implementer. A device that makes any of
/// these choices conforms, and the suite must not fail it: each one is a
/// don't-care the harness has to honour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Freedom {
    ClearsRxCountWhenIdle,
    KeepsStaleRxSlots,
    RefusesOversizeBatch,
    DropsMessageWithBadLength,
    Sync1Jitter,
    CountsFrameOnWire,
}

impl Freedom {
    pub const ALL: [Freedom; 6] = [
        Freedom::ClearsRxCountWhenIdle,
        Freedom::KeepsStaleRxSlots,
        Freedom::RefusesOversizeBatch,
        Freedom::DropsMessageWithBadLength,
        Freedom::Sync1Jitter,
        Freedom::CountsFrameOnWire,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Freedom::ClearsRxCountWhenIdle => "clears-rx-count-when-idle",
            Freedom::KeepsStaleRxSlots => "keeps-stale-rx-slots",
            Freedom::RefusesOversizeBatch => "refuses-oversize-batch",
            Freedom::DropsMessageWithBadLength => "drops-message-with-bad-length",
            Freedom::Sync1Jitter => "sync1-jitter",
            Freedom::CountsFrameOnWire => "counts-frame-on-wire",
        }
    }

    /// What the device does, and where the documents allow it.
    pub fn description(self) -> &'static str {
        match self {
            Freedom::ClearsRxCountWhenIdle => "writes NoOfRxMessages = 0 in a cycle that enters nothing once the PLC has acknowledged (003; the read sample reads it only with a new RxCounter, HS-RX-008)",
            Freedom::KeepsStaleRxSlots => "leaves old bytes in the Rx slots past NoOfRxMessages (HS-RX-008, FQ-005)",
            Freedom::RefusesOversizeBatch => "acknowledges a batch whose NoOfTxMessages exceeds the slots and sends none of it (G3, HS-TX-010)",
            Freedom::DropsMessageWithBadLength => "skips a Tx message whose length field is out of range instead of clamping it (G3, LAY-GEN-008)",
            Freedom::Sync1Jitter => "starts the first message of a batch 400 ns after SYNC1, within the 500 ns jitter (003, PDX-004)",
            Freedom::CountsFrameOnWire => "counts the frame on the wire against the send queue's depth until it is sent (HS-TX-012 the other way; declared as tx-queue-accounting=wire-in-queue)",
        }
    }

    pub fn from_name(name: &str) -> Option<Freedom> {
        Freedom::ALL.into_iter().find(|c| c.name() == name)
    }
}
