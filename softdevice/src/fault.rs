/// Deliberate defects, each breaking one requirement of the catalogue, so the
/// suite can prove it notices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Fault {
    AckBeforeAccept,
    OverwritesUnacknowledgedRx,
    FdLengthRoundsDown,
    FdLength32As36,
    RtrBitMisplaced,
    ExtendedFlagMissing,
    TransactionNumberOfFirstFrame,
    TransactionNumberOnHandover,
    TimeStampInMicroseconds,
    HeadDropWhenFull,
    FilterLastMatchWins,
    FastQueueWaitsForAck,
    CounterDoesNotWrap,
    RxCounterCountsEmptyCycles,
    SendsBatchReversed,
    SendsOneMoreThanAsked,
    FdPaddingFf,
    CobIdWordBigEndian,
    BrsEsiSwapped,
    ReceiveFifoNotReported,
}

impl Fault {
    pub const ALL: [Fault; 20] = [
        Fault::AckBeforeAccept,
        Fault::OverwritesUnacknowledgedRx,
        Fault::FdLengthRoundsDown,
        Fault::FdLength32As36,
        Fault::RtrBitMisplaced,
        Fault::ExtendedFlagMissing,
        Fault::TransactionNumberOfFirstFrame,
        Fault::TransactionNumberOnHandover,
        Fault::TimeStampInMicroseconds,
        Fault::HeadDropWhenFull,
        Fault::FilterLastMatchWins,
        Fault::FastQueueWaitsForAck,
        Fault::CounterDoesNotWrap,
        Fault::RxCounterCountsEmptyCycles,
        Fault::SendsBatchReversed,
        Fault::SendsOneMoreThanAsked,
        Fault::FdPaddingFf,
        Fault::CobIdWordBigEndian,
        Fault::BrsEsiSwapped,
        Fault::ReceiveFifoNotReported,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Fault::AckBeforeAccept => "ack-before-accept",
            Fault::OverwritesUnacknowledgedRx => "overwrites-unacknowledged-rx",
            Fault::FdLengthRoundsDown => "fd-length-rounds-down",
            Fault::FdLength32As36 => "fd-length-32-as-36",
            Fault::RtrBitMisplaced => "rtr-bit-misplaced",
            Fault::ExtendedFlagMissing => "extended-flag-missing",
            Fault::TransactionNumberOfFirstFrame => "transaction-number-of-first-frame",
            Fault::TransactionNumberOnHandover => "transaction-number-on-handover",
            Fault::TimeStampInMicroseconds => "time-stamp-in-microseconds",
            Fault::HeadDropWhenFull => "head-drop-when-full",
            Fault::FilterLastMatchWins => "filter-last-match-wins",
            Fault::FastQueueWaitsForAck => "fast-queue-waits-for-ack",
            Fault::CounterDoesNotWrap => "counter-does-not-wrap",
            Fault::RxCounterCountsEmptyCycles => "rx-counter-counts-empty-cycles",
            Fault::SendsBatchReversed => "sends-batch-reversed",
            Fault::SendsOneMoreThanAsked => "sends-one-more-than-asked",
            Fault::FdPaddingFf => "fd-padding-ff",
            Fault::CobIdWordBigEndian => "cob-id-word-big-endian",
            Fault::BrsEsiSwapped => "brs-esi-swapped",
            Fault::ReceiveFifoNotReported => "receive-fifo-not-reported",
        }
    }

    /// What the fault does, in a sentence.
    pub fn description(self) -> &'static str {
        match self {
            Fault::AckBeforeAccept => "acknowledges a Tx batch in the cycle it sees it but reads the messages a cycle later",
            Fault::OverwritesUnacknowledgedRx => "fills the Rx messages although the PLC has not released the buffer",
            Fault::FdLengthRoundsDown => "rounds an FD length down to a valid size instead of up",
            Fault::FdLength32As36 => "sends an FD length of 25..32 as 36 bytes, as the manual misprints",
            Fault::RtrBitMisplaced => "reads the RTR bit of the 11-bit COB ID word from bit 3",
            Fault::ExtendedFlagMissing => "leaves bit 31 (29-bit identifier) clear in received messages",
            Fault::TransactionNumberOfFirstFrame => "reports the transaction number of a batch's first frame",
            Fault::TransactionNumberOnHandover => "reports a transaction number when the frame is handed to the controller, not when it is sent",
            Fault::TimeStampInMicroseconds => "writes receive time stamps in microseconds",
            Fault::HeadDropWhenFull => "drops the oldest frame when the local Rx queue is full",
            Fault::FilterLastMatchWins => "lets the last matching filter row decide",
            Fault::FastQueueWaitsForAck => "waits for the Rx acknowledge in the Fast CAN Queue",
            Fault::CounterDoesNotWrap => "stops the counters at 0xFFFF instead of wrapping",
            Fault::RxCounterCountsEmptyCycles => "increments RxCounter in cycles without new messages",
            Fault::SendsBatchReversed => "sends a batch in reverse slot order",
            Fault::SendsOneMoreThanAsked => "sends NoOfTxMessages + 1 messages (000's loop bug)",
            Fault::FdPaddingFf => "pads rounded-up FD frames with 0xFF",
            Fault::CobIdWordBigEndian => "writes the 11-bit COB ID word big-endian",
            Fault::BrsEsiSwapped => "swaps BRS and ESI in received FD messages",
            Fault::ReceiveFifoNotReported => "reports an empty receive FIFO in InfoData",
        }
    }

    pub fn from_name(name: &str) -> Option<Fault> {
        Fault::ALL.into_iter().find(|f| f.name() == name)
    }
}
