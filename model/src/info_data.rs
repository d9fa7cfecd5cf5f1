//! InfoData: the CAN controller's status and counters in the input image.
//!
//! Source: 000 §8.3.3 (entries 0-2, 4-10), 001 §8.3.3 (adds 3 and 11-15).

/// One bit timing register set as `InfoData[1]` and `InfoData[2]` report it: byte 0 jump
/// width, byte 1 time A, byte 2 time B, byte 3 prescaler.
///
/// Requirements: INFO-003.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct BitTiming {
    pub jump_width: u8,
    pub time_a: u8,
    pub time_b: u8,
    pub prescaler: u8,
}

impl BitTiming {
    pub fn to_word(self) -> u32 {
        u32::from_le_bytes([self.jump_width, self.time_a, self.time_b, self.prescaler])
    }

    pub fn from_word(word: u32) -> Self {
        let [jump_width, time_a, time_b, prescaler] = word.to_le_bytes();
        BitTiming {
            jump_width,
            time_a,
            time_b,
            prescaler,
        }
    }
}

/// `InfoData[0]` status bits.
///
/// Requirements: INFO-002.
pub mod status {
    pub const BUS_OFF: u32 = 1 << 0;
    pub const ERROR_PASSIVE: u32 = 1 << 1;
    pub const NODE_ACTIVE: u32 = 1 << 2;
    pub const WARNING_LIMIT: u32 = 1 << 3;
    pub const OVERLOAD: u32 = 1 << 4;
    pub const BUS_IDLE: u32 = 1 << 6;
}

/// What the CAN controller reports about itself; the device copies it into
/// InfoData at the end of each cycle.
///
/// Requirements: INFO-002, INFO-004, INFO-005, INFO-006.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct ControllerStatus {
    pub bus_off: bool,
    pub error_passive: bool,
    pub node_active: bool,
    pub warning_limit: bool,
    pub overload: bool,
    pub bus_idle: bool,
    /// Transceiver delay in time quanta (CAN FD only).
    pub transceiver_delay: u32,
    pub ack_errors: u32,
    pub bit_errors: u32,
    pub crc_errors: u32,
    pub form_errors: u32,
    pub stuff_errors: u32,
    pub receive_error_counter: u32,
    pub transmit_error_counter: u32,
    pub core_running: bool,
}

impl ControllerStatus {
    /// `InfoData[0]`.
    pub fn status_word(&self) -> u32 {
        [
            (self.bus_off, status::BUS_OFF),
            (self.error_passive, status::ERROR_PASSIVE),
            (self.node_active, status::NODE_ACTIVE),
            (self.warning_limit, status::WARNING_LIMIT),
            (self.overload, status::OVERLOAD),
            (self.bus_idle, status::BUS_IDLE),
        ]
        .iter()
        .filter(|(set, _)| *set)
        .fold(0, |word, (_, bit)| word | bit)
    }
}

/// Index of each InfoData entry.
pub mod index {
    pub const CAN_STATUS: usize = 0;
    pub const ARBITRATION_BAUDRATE: usize = 1;
    pub const DATA_BAUDRATE: usize = 2;
    pub const TRANSCEIVER_DELAY: usize = 3;
    pub const SEND_FIFO_HIGH_PRIO: usize = 4;
    pub const SEND_FIFO_LOW_PRIO: usize = 5;
    pub const RECEIVE_FIFO: usize = 6;
    pub const ACK_ERRORS: usize = 7;
    pub const BIT_ERRORS: usize = 8;
    pub const CRC_ERRORS: usize = 9;
    pub const FORM_ERRORS: usize = 10;
    pub const CAN_CORE: usize = 11;
    pub const STUFF_ERRORS: usize = 12;
    pub const RECEIVE_ERROR_COUNTER: usize = 13;
    pub const TRANSMIT_ERROR_COUNTER: usize = 14;
    pub const UNUSED: usize = 15;
}

/// The 16 InfoData words.
///
/// The send FIFO entries count queued Tx messages and the receive FIFO entry
/// counts messages waiting in the local Rx queue (the manual names no unit:
/// assumption INFO-007). The interface queues every Tx message at low priority.
///
/// Requirements: INFO-001..INFO-007.
pub fn words(
    status: &ControllerStatus,
    nominal: BitTiming,
    data: BitTiming,
    queued_tx: usize,
    queued_rx: usize,
) -> [u32; 16] {
    let mut words = [0u32; 16];
    words[index::CAN_STATUS] = status.status_word();
    words[index::ARBITRATION_BAUDRATE] = nominal.to_word();
    words[index::DATA_BAUDRATE] = data.to_word();
    words[index::TRANSCEIVER_DELAY] = status.transceiver_delay;
    words[index::SEND_FIFO_HIGH_PRIO] = 0;
    words[index::SEND_FIFO_LOW_PRIO] = saturate(queued_tx);
    words[index::RECEIVE_FIFO] = saturate(queued_rx);
    words[index::ACK_ERRORS] = status.ack_errors;
    words[index::BIT_ERRORS] = status.bit_errors;
    words[index::CRC_ERRORS] = status.crc_errors;
    words[index::FORM_ERRORS] = status.form_errors;
    words[index::CAN_CORE] = u32::from(status.core_running);
    words[index::STUFF_ERRORS] = status.stuff_errors;
    words[index::RECEIVE_ERROR_COUNTER] = status.receive_error_counter;
    words[index::TRANSMIT_ERROR_COUNTER] = status.transmit_error_counter;
    words
}

fn saturate(count: usize) -> u32 {
    u32::try_from(count).unwrap_or(u32::MAX)
}
