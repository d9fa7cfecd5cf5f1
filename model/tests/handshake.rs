//! The Tx and Rx counter handshakes (000/001 §6, 003, G1, G2, G4).

mod common;

use canif_model::client::PlcClient;
use canif_model::config::{FrameFormat, QueueMode, TxQueueAccounting};
use canif_model::device::Device;
use canif_model::handshake;
use common::*;

/// Covers: HS-TX-001, ERR-R5
#[test]
fn plc_sends_only_when_counters_are_equal_and_messages_wait() {
    let device = device(FrameFormat::Base11, QueueMode::Standard, 4);
    let mut plc = PlcClient::new(device.layout());
    // Nothing to send: the counter stays (001's guard `NumberOfMessagesToSend > 0`).
    let outputs = plc.task(device.inputs()).unwrap().to_vec();
    assert_eq!(&outputs[..6], &[0, 0, 0, 0, 0, 0]);

    for i in 0..3 {
        plc.send(message(std_frame(0x100 + i, &[i as u8]), 0))
            .unwrap();
    }
    let outputs = plc.task(device.inputs()).unwrap().to_vec();
    // Outputs.TxCounter := Inputs.TxCounter + 1, NoOfTxMessages = 3, slots 0..2 filled.
    assert_eq!(&outputs[..6], &[1, 0, 0, 0, 3, 0]);
    assert_eq!(&outputs[6..8], &(0x100u16 << 5 | 1).to_le_bytes());
    assert_eq!(&outputs[36..46], &[0; 10], "slot 3 untouched");

    // Not acknowledged yet: a second task does not touch the Tx part.
    plc.send(message(std_frame(0x200, &[]), 0)).unwrap();
    let again = plc.task(device.inputs()).unwrap().to_vec();
    assert_eq!(again, outputs);
}

/// Covers: HS-TX-002, HS-TX-007, HS-TX-004, HS-TX-009
#[test]
fn device_accepts_and_acknowledges_before_the_bus_has_sent() {
    let mut device = device(FrameFormat::Base11, QueueMode::Standard, 4);
    let frames = [
        std_frame(0x10, &[1]),
        std_frame(0x11, &[2]),
        std_frame(0x12, &[3]),
    ];
    let junk = std_frame(0x7FF, &[0xEE; 8]);
    let messages: Vec<_> = frames
        .iter()
        .chain([&junk])
        .map(|f| message(*f, 0))
        .collect();
    let outputs = outputs_with(&device, 1, 0, &messages, 3);
    device.cycle(&outputs, 0).unwrap();
    // Acknowledged in the accepting cycle although nothing is on the bus yet (G2).
    assert_eq!(inputs_of(&device).tx_counter(), 1);
    assert_eq!(device.queued_tx(), 3);
    // First message at once, the rest one after another from the send queue.
    assert_eq!(device.poll_transmit(0), Some(frames[0]));
    assert_eq!(device.poll_transmit(0), None, "one frame at a time");
    device.handle_transmit_complete();
    assert_eq!(device.poll_transmit(0), Some(frames[1]));
    device.handle_transmit_complete();
    assert_eq!(device.poll_transmit(0), Some(frames[2]));
    device.handle_transmit_complete();
    assert_eq!(
        device.poll_transmit(0),
        None,
        "slot 3 is past NoOfTxMessages"
    );
}

/// Covers: HS-TX-009
#[test]
fn zero_messages_are_acknowledged_and_nothing_is_sent() {
    let mut device = device(FrameFormat::Base11, QueueMode::Standard, 2);
    let outputs = outputs_with(&device, 7, 0, &[message(std_frame(1, &[]), 0)], 0);
    device.cycle(&outputs, 0).unwrap();
    assert_eq!(inputs_of(&device).tx_counter(), 7);
    assert_eq!(device.poll_transmit(0), None);
}

/// Covers: HS-TX-003
#[test]
fn any_change_of_the_tx_counter_counts() {
    let mut device = device(FrameFormat::Base11, QueueMode::Standard, 2);
    let outputs = outputs_with(&device, 5, 0, &[message(std_frame(0x55, &[5]), 0)], 1);
    device.cycle(&outputs, 0).unwrap();
    assert_eq!(inputs_of(&device).tx_counter(), 5);
    assert_eq!(device.poll_transmit(0), Some(std_frame(0x55, &[5])));
    device.handle_transmit_complete();
    // The same counter again: nothing new.
    device.cycle(&outputs, 0).unwrap();
    assert_eq!(device.poll_transmit(0), None);
    // Backwards is a change too.
    let outputs = outputs_with(&device, 2, 0, &[message(std_frame(0x22, &[2]), 0)], 1);
    device.cycle(&outputs, 0).unwrap();
    assert_eq!(inputs_of(&device).tx_counter(), 2);
    assert_eq!(device.poll_transmit(0), Some(std_frame(0x22, &[2])));
}

/// Covers: HS-TX-005, HS-RX-005
#[test]
fn counters_wrap_from_ffff_to_zero() {
    assert_eq!(handshake::next(0xFFFF), 0);
    let mut rig = Rig::new(device(FrameFormat::Base11, QueueMode::Standard, 1));
    // 65,537 Tx batches and Rx deliveries: both counters pass the wrap.
    for i in 0..=0x1_0000u32 {
        rig.plc
            .send(message(std_frame((i & 0x7FF) as u16, &[]), 0))
            .unwrap();
        rig.device
            .handle_received(std_frame(0x7FF - (i & 0x7FF) as u16, &[]), 0);
        rig.cycle(1);
    }
    rig.cycle(1);
    assert_eq!(rig.on_bus.len(), 0x1_0001);
    assert_eq!(rig.plc.take_received().len(), 0x1_0001);
    assert_eq!(rig.inputs().tx_counter(), 1, "0x10001 increments from 0");
    assert_eq!(rig.inputs().rx_counter(), 1);
}

/// A device whose send queue holds 4 messages, after a batch of 4 (ids 0-3)
/// was accepted.
fn four_accepted_of_a_queue_of_four() -> Device {
    four_accepted_counting(TxQueueAccounting::WireOutsideQueue)
}

fn four_accepted_counting(accounting: TxQueueAccounting) -> Device {
    let mut caps = caps();
    caps.tx_queue_depth = 4;
    caps.tx_queue_accounting = accounting;
    let mut device =
        Device::new(&caps, config(FrameFormat::Base11, QueueMode::Standard, 4)).unwrap();
    let batch: Vec<_> = (0..4).map(|i| message(std_frame(i, &[]), 0)).collect();
    device
        .cycle(&outputs_with(&device, 1, 0, &batch, 4), 0)
        .unwrap();
    device
}

/// Covers: HS-TX-008
#[test]
fn a_batch_that_does_not_fit_the_send_queue_waits_unacknowledged() {
    let mut device = four_accepted_of_a_queue_of_four();
    assert_eq!(inputs_of(&device).tx_counter(), 1);
    let second = outputs_with(&device, 2, 0, &[message(std_frame(0x40, &[]), 0)], 1);
    device.cycle(&second, 0).unwrap();
    assert_eq!(
        inputs_of(&device).tx_counter(),
        1,
        "queue full: not accepted"
    );
    assert_eq!(device.poll_transmit(0), Some(std_frame(0, &[])));
    device.handle_transmit_complete();
    device.cycle(&second, 0).unwrap();
    assert_eq!(inputs_of(&device).tx_counter(), 2);
    let mut order = Vec::new();
    while let Some(frame) = device.poll_transmit(0) {
        order.push(frame.id.raw());
        device.handle_transmit_complete();
    }
    assert_eq!(order, [1, 2, 3, 0x40], "nothing dropped, nothing reordered");
}

/// Covers: HS-TX-012
#[test]
fn the_frame_on_the_wire_has_left_the_send_queue() {
    let mut device = four_accepted_of_a_queue_of_four();
    // Frame 0 goes on the wire: three wait, so one more fits the depth of 4.
    assert_eq!(device.poll_transmit(0), Some(std_frame(0, &[])));
    let second = outputs_with(&device, 2, 0, &[message(std_frame(0x40, &[]), 0)], 1);
    device.cycle(&second, 0).unwrap();
    assert_eq!(
        inputs_of(&device).tx_counter(),
        2,
        "the frame on the wire does not count against tx_queue_depth"
    );
}

/// The other documented reading of 003, as a device declares it.
/// Covers: HS-TX-012
#[test]
fn a_device_that_declares_the_frame_on_the_wire_in_its_queue_waits_for_it() {
    let mut device = four_accepted_counting(TxQueueAccounting::WireInQueue);
    assert_eq!(device.poll_transmit(0), Some(std_frame(0, &[])));
    let second = outputs_with(&device, 2, 0, &[message(std_frame(0x40, &[]), 0)], 1);
    device.cycle(&second, 0).unwrap();
    assert_eq!(
        inputs_of(&device).tx_counter(),
        1,
        "three waiting and one on the wire fill a depth of 4"
    );
    device.handle_transmit_complete();
    device.cycle(&second, 0).unwrap();
    assert_eq!(
        inputs_of(&device).tx_counter(),
        2,
        "accepted once it is sent"
    );
}

/// Covers: HS-TX-010, HS-TX-011
#[test]
fn no_more_messages_than_slots_per_cycle() {
    let mut device = device(FrameFormat::Extended29, QueueMode::Standard, 3);
    let batch: Vec<_> = (0..3).map(|i| message(std_frame(i, &[]), 0)).collect();
    device
        .cycle(&outputs_with(&device, 1, 0, &batch, 0xFFFF), 0)
        .unwrap();
    assert_eq!(device.queued_tx(), 3);
    assert_eq!(
        inputs_of(&device).tx_counter(),
        1,
        "keeps cycling and acknowledges"
    );
}

/// Covers: HS-RX-001, HS-RX-004, HS-RX-006, BQ-002, HS-RX-002
#[test]
fn device_waits_for_the_plc_to_release_the_rx_buffer() {
    let mut device = device(FrameFormat::Base11, QueueMode::Standard, 4);
    let idle = outputs_with(&device, 0, 0, &[], 0);
    device.cycle(&idle, 0).unwrap();
    assert_eq!(
        inputs_of(&device).rx_counter(),
        0,
        "no messages, no increment"
    );

    for i in 0..3 {
        device.handle_received(std_frame(0x180 + i, &[i as u8]), 10);
    }
    device.cycle(&idle, 0).unwrap();
    // RxCounter, NoOfRxMessages and the messages; InfoData may move on meanwhile.
    let held = ..device.layout().info_data_start();
    let first = device.inputs()[held].to_vec();
    assert_eq!(
        (
            inputs_of(&device).rx_counter(),
            inputs_of(&device).no_of_rx_messages()
        ),
        (1, 3)
    );

    // More arrive; the PLC has not released (Outputs.RxCounter 0 ≠ 1): the image stays.
    device.handle_received(std_frame(0x200, &[]), 20);
    for _ in 0..3 {
        device.cycle(&idle, 0).unwrap();
        assert_eq!(&device.inputs()[held], &first[..]);
    }
    // Released: the new message goes in and RxCounter moves on.
    device
        .cycle(&outputs_with(&device, 0, 1, &[], 0), 0)
        .unwrap();
    assert_eq!(
        (
            inputs_of(&device).rx_counter(),
            inputs_of(&device).no_of_rx_messages()
        ),
        (2, 1)
    );
    // Nothing new: no increment although released.
    device
        .cycle(&outputs_with(&device, 0, 2, &[], 0), 0)
        .unwrap();
    assert_eq!(inputs_of(&device).rx_counter(), 2);
}

/// Covers: HS-RX-002, HS-RX-003, HS-RX-007, ERR-R5
#[test]
fn plc_reads_no_of_rx_messages_in_order_and_acknowledges() {
    let mut rig = Rig::new(device(FrameFormat::Base11, QueueMode::Standard, 2));
    let frames: Vec<_> = (0..5).map(|i| std_frame(0x300 + i, &[i as u8])).collect();
    for frame in &frames {
        rig.device.handle_received(*frame, 0);
    }
    rig.cycle(0); // device delivers 2
    assert_eq!(rig.inputs().no_of_rx_messages(), 2);
    rig.cycle(0); // PLC reads 2 and acknowledges; device then delivers 2 more
    rig.cycle(0);
    rig.cycle(0);
    let received: Vec<_> = rig
        .plc
        .take_received()
        .into_iter()
        .map(|m| m.frame)
        .collect();
    assert_eq!(
        received, frames,
        "all, in arrival order, at most 2 per cycle"
    );
    assert_eq!(
        &rig.plc.outputs()[2..4],
        &rig.device.inputs()[2..4],
        "Outputs.RxCounter = Inputs.RxCounter"
    );
}

/// Covers: HS-RX-008, FQ-005
#[test]
fn plc_ignores_slots_past_no_of_rx_messages() {
    let device = device(FrameFormat::Base11, QueueMode::Fast, 3);
    let layout = device.layout();
    let mut inputs = vec![0u8; layout.input_size()];
    inputs[2] = 1; // RxCounter 1
    inputs[4] = 1; // NoOfRxMessages 1
    inputs[6..16].copy_from_slice(&[0x08, 0x63, 1, 2, 3, 4, 5, 6, 7, 8]);
    for slot in 1..3 {
        let range = layout.rx_slot(slot);
        inputs[range].fill(0xA5); // stale bytes of the 3-buffer mode
    }
    let mut plc = PlcClient::new(layout);
    plc.task(&inputs).unwrap();
    let received = plc.take_received();
    assert_eq!(received.len(), 1);
    assert_eq!(
        received[0].frame,
        std_frame(0x318, &[1, 2, 3, 4, 5, 6, 7, 8])
    );
}

/// Covers: CL-TN-002, TN-002
#[test]
fn the_transaction_number_not_the_acknowledge_tells_the_client_what_was_sent() {
    let mut config = config(FrameFormat::Base11, QueueMode::Standard, 4);
    config.transaction_number = true;
    let layout = canif_model::image::ImageLayout::new(&config, false);
    let mut plc = PlcClient::new(layout);
    for (n, id) in [(7, 0x101), (8, 0x102), (9, 0x103)] {
        plc.send(message(std_frame(id, &[]), n)).unwrap();
    }
    let inputs = |tx_counter: u16, number: u16| {
        let mut bytes = vec![0u8; layout.input_size()];
        let mut image =
            canif_model::image::InputImage::new_checked(&mut bytes[..], layout).unwrap();
        image.set_tx_counter(tx_counter);
        image.set_transaction_number(number);
        bytes
    };
    plc.task(&inputs(0, 0)).unwrap(); // hands over 7, 8, 9 under TxCounter 1
    assert!(plc.take_sent().is_empty());
    // The device took the batch (Inputs.TxCounter = 1): in its queue, not on the bus.
    plc.task(&inputs(1, 0)).unwrap();
    assert!(
        plc.take_sent().is_empty(),
        "an acknowledge is no sign of sending"
    );
    // Inputs.TransactionNumber 8: 7 and 8 are on the bus, 9 may wait.
    plc.task(&inputs(1, 8)).unwrap();
    assert_eq!(plc.take_sent(), [7, 8]);
    plc.task(&inputs(1, 8)).unwrap();
    assert!(plc.take_sent().is_empty(), "each told once");
    plc.task(&inputs(1, 9)).unwrap();
    assert_eq!(plc.take_sent(), [9]);
}
