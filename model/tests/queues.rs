//! Buffered/Optimized and Fast CAN Queue, the local Rx queue and silent loss
//! (000 §4, §5.1; 003; G4, G5).

mod common;

use canif_model::config::{ConfigError, FrameFormat, InterfaceConfig, QueueMode};
use canif_model::device::{Device, RxOutcome};
use canif_model::filter::FilterRow;
use canif_model::frame::{CanId, Frame};
use common::*;

/// Covers: FQ-001, FQ-002, FQ-004
#[test]
fn fast_queue_delivers_without_acknowledge_and_loses_the_excess() {
    let mut device = device(FrameFormat::Base11, QueueMode::Fast, 3);
    let never_acknowledges = outputs_with(&device, 0, 0, &[], 0);
    let mut outcomes = Vec::new();
    for i in 0..5 {
        outcomes.push(device.handle_received(std_frame(0x100 + i, &[]), 0));
    }
    assert_eq!(&outcomes[3..], &[RxOutcome::Lost, RxOutcome::Lost]);
    device.cycle(&never_acknowledges, 0).unwrap();
    assert_eq!(
        (
            inputs_of(&device).rx_counter(),
            inputs_of(&device).no_of_rx_messages()
        ),
        (1, 3)
    );
    assert_eq!(device.queued_rx(), 0, "no local queue: nothing left over");
    assert_eq!(device.lost(), 2);

    // Not acknowledged, yet the next frames go straight in.
    device.handle_received(std_frame(0x200, &[]), 0);
    device.cycle(&never_acknowledges, 0).unwrap();
    assert_eq!(
        (
            inputs_of(&device).rx_counter(),
            inputs_of(&device).no_of_rx_messages()
        ),
        (2, 1)
    );
    // A cycle with nothing new: RxCounter stays.
    device.cycle(&never_acknowledges, 0).unwrap();
    assert_eq!(inputs_of(&device).rx_counter(), 2);
}

/// Covers: FQ-003, BQ-001
#[test]
fn transmit_works_alike_in_every_queue_mode() {
    for mode in [QueueMode::Standard, QueueMode::Optimized, QueueMode::Fast] {
        let mut rig = Rig::new(device(FrameFormat::Base11, mode, 2));
        let frames: Vec<_> = (0..5)
            .map(|i| std_frame(0x600 + i, &[i as u8; 3]))
            .collect();
        for frame in &frames {
            rig.plc.send(message(*frame, 0)).unwrap();
        }
        for _ in 0..6 {
            rig.cycle(1);
        }
        assert_eq!(rig.on_bus, frames, "{mode:?}");
    }
    // Optimized buffers: frames wait in the local queue until released.
    let mut device = device(FrameFormat::Base11, QueueMode::Optimized, 1);
    device.handle_received(std_frame(1, &[]), 0);
    device.handle_received(std_frame(2, &[]), 0);
    device
        .cycle(&outputs_with(&device, 0, 0, &[], 0), 0)
        .unwrap();
    assert_eq!(device.queued_rx(), 1);
}

/// Covers: RXQ-003, RXQ-004
#[test]
fn full_local_queue_drops_new_frames_silently() {
    let mut caps = caps();
    caps.rx_queue_depth = 5;
    let mut device =
        Device::new(&caps, config(FrameFormat::Base11, QueueMode::Standard, 2)).unwrap();
    let outcomes: Vec<_> = (0..8)
        .map(|i| device.handle_received(std_frame(i, &[]), 0))
        .collect();
    assert_eq!(
        outcomes.iter().filter(|o| **o == RxOutcome::Queued).count(),
        5
    );
    assert_eq!(
        &outcomes[5..],
        &[RxOutcome::Lost; 3],
        "tail drop: the newest are lost"
    );
    let mut rig = Rig::new(device);
    for _ in 0..6 {
        rig.cycle(0);
    }
    let ids = rig.received_ids();
    assert_eq!(ids, [0, 1, 2, 3, 4], "the oldest survive, in order");
    // No indication in the image: InfoData is absent on this interface and no field counts losses.
    assert_eq!(rig.device.lost(), 3);
}

/// Covers: RXQ-001, RXQ-002
#[test]
fn queue_depths_of_el6751_and_ccat() {
    for (depth, caps_depth) in [(150usize, 150usize), (512, 512)] {
        let mut caps = caps();
        caps.rx_queue_depth = caps_depth;
        let mut device = Device::new(
            &caps,
            config(FrameFormat::Extended29, QueueMode::Standard, 32),
        )
        .unwrap();
        let queued = (0..depth + 50)
            .filter(|i| {
                device.handle_received(std_frame((*i % 0x7FF) as u16, &[]), 0) == RxOutcome::Queued
            })
            .count();
        assert_eq!(queued, depth);
    }
}

/// Covers: RXQ-005
#[test]
fn frames_the_format_cannot_carry_are_not_delivered() {
    let mut base = device(FrameFormat::Base11, QueueMode::Standard, 2);
    assert_eq!(
        base.handle_received(Frame::classic(CanId::Extended(0x100), &[]).unwrap(), 0),
        RxOutcome::NotRepresentable
    );
    let mut ext = device(FrameFormat::Extended29, QueueMode::Standard, 2);
    assert_eq!(
        ext.handle_received(
            Frame::fd(CanId::Standard(1), false, false, &[0; 12]).unwrap(),
            0
        ),
        RxOutcome::NotRepresentable
    );
    assert_eq!(
        ext.handle_received(Frame::classic(CanId::Extended(0x100), &[]).unwrap(), 0),
        RxOutcome::Queued
    );
    assert_eq!((base.queued_rx(), base.lost()), (0, 0));
}

/// Covers: RXQ-006
#[test]
fn overload_shows_as_full_no_of_rx_messages() {
    let mut rig = Rig::new(device(FrameFormat::Base11, QueueMode::Standard, 4));
    let mut counts = Vec::new();
    for cycle in 0..20u16 {
        for i in 0..6 {
            rig.device.handle_received(std_frame(cycle * 6 + i, &[]), 0);
        }
        let before = rig.inputs().rx_counter();
        rig.cycle(0);
        if rig.inputs().rx_counter() != before {
            counts.push(rig.inputs().no_of_rx_messages());
        }
    }
    assert!(!counts.is_empty());
    assert!(counts.iter().all(|&n| n == 4), "{counts:?}");
}

/// Covers: BQ-003, BQ-004, BQ-005, PROF-003
#[test]
fn optimized_and_fast_queues_refuse_29_bit_filters_and_transaction_numbers() {
    let caps = caps();
    for mode in [QueueMode::Optimized, QueueMode::Fast] {
        let ext = config(FrameFormat::Extended29, mode, 4);
        assert_eq!(
            ext.validate(&caps),
            Err(ConfigError::QueueModeNeedsBase11(mode))
        );
        let mut tn = config(FrameFormat::Base11, mode, 4);
        tn.transaction_number = true;
        assert_eq!(
            tn.validate(&caps),
            Err(ConfigError::QueueModeWithoutTransactionNumber(mode))
        );
        let mut filtered = config(FrameFormat::Base11, mode, 4);
        filtered.filters = vec![FilterRow::accept_range(0, 0x100)];
        assert_eq!(
            filtered.validate(&caps),
            Err(ConfigError::FiltersNotAllowed(mode))
        );
        assert!(config(FrameFormat::Base11, mode, 4).validate(&caps).is_ok());
    }
    let mut standard = InterfaceConfig::new(FrameFormat::Extended29, 4);
    standard.filters = vec![FilterRow::accept_range(0, 0x100)];
    assert!(standard.validate(&caps).is_ok());
}
