//! Transaction number (000 §5.2, 003, G6) and time stamps (000 §5.3, G8).

mod common;

use canif_model::config::{ConfigError, FrameFormat, InterfaceConfig};
use canif_model::device::Device;
use canif_model::frame::{CanId, Frame};
use common::*;

fn ext29_tn_ts() -> Device {
    let mut config = InterfaceConfig::new(FrameFormat::Extended29, 4);
    config.transaction_number = true;
    config.time_stamp = true;
    Device::new(&caps(), config).unwrap()
}

/// Covers: TN-001, TN-002, TN-003
#[test]
fn transaction_number_of_the_last_frame_on_the_bus() {
    let mut device = ext29_tn_ts();
    let batch: Vec<_> = (0..3)
        .map(|i| message(std_frame(0x10 + i, &[]), 100 + i))
        .collect();
    device
        .cycle(&outputs_with(&device, 1, 0, &batch, 3), 0)
        .unwrap();
    assert_eq!(
        inputs_of(&device).transaction_number(),
        Some(0),
        "0 before any message went on the bus"
    );

    let frame = device.poll_transmit(0).unwrap();
    assert_eq!(frame.id, CanId::Standard(0x10));
    device
        .cycle(&outputs_with(&device, 1, 0, &batch, 3), 0)
        .unwrap();
    assert_eq!(
        inputs_of(&device).transaction_number(),
        Some(0),
        "handed to the controller is not sent"
    );
    device.handle_transmit_complete();
    device
        .cycle(&outputs_with(&device, 1, 0, &batch, 3), 0)
        .unwrap();
    assert_eq!(inputs_of(&device).transaction_number(), Some(100));
    while device.poll_transmit(0).is_some() {
        device.handle_transmit_complete();
    }
    device
        .cycle(&outputs_with(&device, 1, 0, &batch, 3), 0)
        .unwrap();
    assert_eq!(
        inputs_of(&device).transaction_number(),
        Some(102),
        "the last one sent, not the first"
    );
}

/// Covers: TN-004, PROF-005
#[test]
fn legacy_mapping_offers_the_transaction_number_only_in_29_bit_mode() {
    let mut legacy = caps();
    legacy.transaction_number_only_ext29 = true;
    let mut base = InterfaceConfig::new(FrameFormat::Base11, 4);
    base.transaction_number = true;
    assert_eq!(
        base.validate(&legacy),
        Err(ConfigError::TransactionNumberOnlyExt29)
    );
    assert!(base.validate(&caps()).is_ok());
    let mut ext = InterfaceConfig::new(FrameFormat::Extended29, 4);
    ext.transaction_number = true;
    assert!(ext.validate(&legacy).is_ok());
}

/// Covers: TS-001, TS-003
#[test]
fn time_stamp_is_the_end_of_reception_in_nanoseconds() {
    let mut rig = Rig::new(ext29_tn_ts());
    let times = [
        0x0000_0123_4567_89ABu64,
        0x0000_0123_4567_89AB,
        0x0000_0200_0000_0000,
    ];
    for (i, t) in times.iter().enumerate() {
        rig.device
            .handle_received(Frame::classic(CanId::Extended(i as u32), &[]).unwrap(), *t);
    }
    rig.cycle(0);
    rig.cycle(0);
    let stamps: Vec<u64> = rig
        .plc
        .take_received()
        .iter()
        .map(|m| m.time_stamp)
        .collect();
    assert_eq!(stamps, times);
}

/// Covers: TS-002, PROF-004, LAY-FD-004
#[test]
fn time_stamp_only_in_29_bit_mode_with_transaction_number() {
    let caps = caps();
    let mut base = InterfaceConfig::new(FrameFormat::Base11, 4);
    base.transaction_number = true;
    base.time_stamp = true;
    assert_eq!(
        base.validate(&caps),
        Err(ConfigError::TimeStampNeedsExt29WithTransactionNumber)
    );
    let mut no_tn = InterfaceConfig::new(FrameFormat::Extended29, 4);
    no_tn.time_stamp = true;
    assert_eq!(
        no_tn.validate(&caps),
        Err(ConfigError::TimeStampNeedsExt29WithTransactionNumber)
    );
    let mut without = caps.clone();
    without.time_stamp = false;
    let mut ok = InterfaceConfig::new(FrameFormat::Extended29, 4);
    ok.transaction_number = true;
    ok.time_stamp = true;
    assert!(ok.validate(&caps).is_ok());
    assert_eq!(ok.validate(&without), Err(ConfigError::TimeStampNotOffered));
    let mut fd = InterfaceConfig::new(FrameFormat::Fd, 4);
    fd.time_stamp = false;
    assert_eq!(
        fd.validate(&caps),
        Err(ConfigError::FdStructuresCarryTransactionNumberAndTimeStamp)
    );
}
