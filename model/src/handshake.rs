//! The TxCounter / RxCounter handshake between PLC and device, both sides.
//!
//! Source: 000/001 §6 (the counters and the sample code, 001's send sample per
//! ruling R5), 003 (the device's per-cycle sequence), rulings G1, G2, G4.
//!
//! Send: when `Outputs.TxCounter = Inputs.TxCounter` the PLC may fill the Tx
//! messages, set `NoOfTxMessages` and write `Outputs.TxCounter := Inputs.TxCounter + 1`.
//! The device reacts to any *change* (G1), accepts the messages (sends the first
//! or queues them) and acknowledges with `Inputs.TxCounter := Outputs.TxCounter` (G2).
//!
//! Receive: when `Outputs.RxCounter = Inputs.RxCounter` the device may put new
//! messages into the image, set `NoOfRxMessages` and increment `Inputs.RxCounter`.
//! The PLC copies them and releases the buffer with `Outputs.RxCounter := Inputs.RxCounter`
//! (G4). In the Fast CAN Queue the device does not wait for that release (G5).

/// The next counter value: 16-bit unsigned, wrapping 0xFFFF → 0 (G1).
///
/// Requirements: HS-TX-005, HS-RX-005.
pub fn next(counter: u16) -> u16 {
    counter.wrapping_add(1)
}

/// Device side: a new Tx batch is waiting when the PLC's TxCounter differs from
/// the last one the device acknowledged (any change counts, not only +1).
///
/// Requirements: HS-TX-002, HS-TX-003.
pub fn tx_batch_waiting(outputs_tx_counter: u16, inputs_tx_counter: u16) -> bool {
    outputs_tx_counter != inputs_tx_counter
}

/// PLC side: the interface is ready for the next Tx batch.
///
/// Requirements: HS-TX-001.
pub fn ready_to_send(outputs_tx_counter: u16, inputs_tx_counter: u16) -> bool {
    outputs_tx_counter == inputs_tx_counter
}

/// Device side: the PLC has released the Rx buffer, new messages may go in.
///
/// Requirements: HS-RX-001, HS-RX-004.
pub fn rx_buffer_released(outputs_rx_counter: u16, inputs_rx_counter: u16) -> bool {
    outputs_rx_counter == inputs_rx_counter
}

/// PLC side: new messages are in the image.
///
/// Requirements: HS-RX-002.
pub fn new_messages(outputs_rx_counter: u16, inputs_rx_counter: u16) -> bool {
    outputs_rx_counter != inputs_rx_counter
}
