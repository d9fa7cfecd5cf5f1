//! Where things are in the process images, written once, firmware style:
//! the header entries of 003 (0x700z / 0x600z) and the InfoData words of
//! 000 §8.3.3. The message structures are `crate::MsgGeometry`'s table.

/// Header offsets, shared by the output and the input image.
pub mod header {
    /// Outputs.TxCounter (0x700z:01), Inputs.TxCounter (0x600z:01).
    pub const TX_COUNTER: usize = 0;
    /// Outputs.RxCounter (0x700z:02), Inputs.RxCounter (0x600z:02).
    pub const RX_COUNTER: usize = 2;
    /// Outputs.NoOfTxMessages (0x700z:03), Inputs.NoOfRxMessages (0x600z:03).
    pub const NO_OF_MESSAGES: usize = 4;
    /// Inputs.TransactionNumber (0x600z:04), where the interface has one.
    pub const TRANSACTION_NUMBER: usize = 6;
    /// The first message slot without a transaction number in the header.
    pub const MESSAGES: usize = 6;
    /// The first Rx message slot behind Inputs.TransactionNumber.
    pub const MESSAGES_AFTER_TRANSACTION_NUMBER: usize = 8;
}

/// InfoData words (UDINT each, 16 of them).
pub mod info {
    pub const WORDS: usize = 16;
    /// Status bits: bus-off, error passive, node active (bit 2), …
    pub const STATUS: usize = 0;
    pub const NOMINAL_TIMING: usize = 1;
    pub const DATA_TIMING: usize = 2;
    pub const TX_ERROR_FRAMES: usize = 4;
    pub const TX_FIFO_LEVEL: usize = 5;
    pub const RX_FIFO_LEVEL: usize = 6;
    pub const TRANSCEIVER_DELAY: usize = 3;
    pub const ACK_ERRORS: usize = 7;
    pub const BIT_ERRORS: usize = 8;
    pub const CRC_ERRORS: usize = 9;
    pub const FORM_ERRORS: usize = 10;
    pub const CORE_RUNNING: usize = 11;
    pub const STUFF_ERRORS: usize = 12;
    pub const RECEIVE_ERROR_COUNTER: usize = 13;
    pub const TRANSMIT_ERROR_COUNTER: usize = 14;
    /// Status bit 2: the node takes part in bus traffic.
    pub const NODE_ACTIVE: u32 = 1 << 2;
}
