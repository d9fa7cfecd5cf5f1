//! When the PLC sees what the device wrote: the process-data exchange.
//!
//! Source: 003 "EtherCAT Update" (LRW: the TxCounter increment is confirmed two
//! task cycles later; "separate input update", LWR + LRD: one), "Synchronization
//! with SYNC0/SYNC1 event" (first Tx message at SYNC1, jitter at most 500 ns),
//! ruling G10.

use crate::Nanos;

/// How the EtherCAT master moves the images.
///
/// Requirements: PDX-001, PDX-002.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ExchangeMode {
    /// One LRW telegram: it reads the inputs before the device's cycle runs.
    Lrw,
    /// LWR after the task, LRD just before the next task.
    SeparateInputUpdate,
}

impl ExchangeMode {
    /// Task cycles from writing `Outputs.TxCounter + 1` to seeing it confirmed.
    ///
    /// Requirements: PDX-001, PDX-002.
    pub fn confirmation_cycles(self) -> u32 {
        match self {
            ExchangeMode::Lrw => 2,
            ExchangeMode::SeparateInputUpdate => 1,
        }
    }
}

/// The largest jitter of the first Tx message's start against SYNC1 plus the
/// device's output delay (003; ruling R10: the start lies in
/// `[SYNC1 + delay, SYNC1 + delay + SYNC1_TX_JITTER]`).
///
/// Requirements: PDX-004.
pub const SYNC1_TX_JITTER: Nanos = 500;

/// Carries the device's input image to the PLC with the delay of the exchange mode.
///
/// Per task cycle: the PLC task reads [`ProcessDataExchange::plc_inputs`] and
/// writes its outputs; the device cycle runs on those outputs; then
/// [`ProcessDataExchange::device_cycle_done`] is called with the device's new inputs.
///
/// Requirements: PDX-001, PDX-002, PDX-003.
#[derive(Debug, Clone)]
pub struct ProcessDataExchange {
    mode: ExchangeMode,
    plc_inputs: Vec<u8>,
    in_device_memory: Vec<u8>,
}

impl ProcessDataExchange {
    pub fn new(mode: ExchangeMode, initial_inputs: &[u8]) -> Self {
        ProcessDataExchange {
            mode,
            plc_inputs: initial_inputs.to_vec(),
            in_device_memory: initial_inputs.to_vec(),
        }
    }

    /// The inputs the PLC task sees in this cycle.
    pub fn plc_inputs(&self) -> &[u8] {
        &self.plc_inputs
    }

    pub fn device_cycle_done(&mut self, device_inputs: &[u8]) {
        match self.mode {
            // The LRW of this cycle read the memory before the device updated it.
            ExchangeMode::Lrw => {
                self.plc_inputs.clear();
                self.plc_inputs.extend_from_slice(&self.in_device_memory);
                self.in_device_memory.clear();
                self.in_device_memory.extend_from_slice(device_inputs);
            }
            // The LRD before the next task reads what the device just wrote.
            ExchangeMode::SeparateInputUpdate => {
                self.plc_inputs.clear();
                self.plc_inputs.extend_from_slice(device_inputs);
            }
        }
    }
}
