//! CAN FD: length, DLC, padding, bits (000/001 §8.3, R1, G9).

mod common;

use canif_model::config::{FrameFormat, InterfaceConfig, QueueMode};
use canif_model::device::Device;
use canif_model::dlc::{fd_data_size, fd_dlc, fd_dlc_for_length, fd_round_up, FD_DATA_SIZES};
use canif_model::frame::{CanId, Frame, FrameKind};
use canif_model::image::{MessageLayout, MessageRepr, MessageView};
use common::*;

/// 001 §8.3.1's table with DLC 13 corrected to 32 (R1).
#[rustfmt::skip]
static DLC_TABLE: [(u8, u8); 16] = [
    (0, 0), (1, 1), (2, 2), (3, 3), (4, 4), (5, 5), (6, 6), (7, 7), (8, 8),
    (9, 12), (10, 16), (11, 20), (12, 24), (13, 32), (14, 48), (15, 64),
];

/// Covers: FD-LEN-002, ERR-R1
#[test]
fn dlc_table() {
    for (dlc, size) in DLC_TABLE {
        assert_eq!(fd_data_size(dlc), Some(size));
        assert_eq!(fd_dlc(size), Some(dlc));
    }
    assert_eq!(fd_data_size(16), None);
    assert_eq!(fd_dlc(36), None, "36 is the manual's misprint, not a size");
}

/// Covers: FD-LEN-003, FD-LEN-004, ERR-R1, FD-LEN-001
#[test]
fn lengths_round_up_to_the_next_valid_size() {
    for (len, size, dlc) in [
        (0, 0, 0),
        (8, 8, 8),
        (9, 12, 9),
        (13, 16, 10),
        (21, 24, 12),
        (25, 32, 13),
        (32, 32, 13),
        (33, 48, 14),
        (49, 64, 15),
        (64, 64, 15),
    ] {
        assert_eq!(fd_round_up(len), Some(size), "{len}");
        assert_eq!(fd_dlc_for_length(len), Some(dlc), "{len}");
    }
    assert_eq!(fd_round_up(65), None);
    assert_eq!(FD_DATA_SIZES.len(), 16);
}

fn fd_device() -> Device {
    Device::new(&caps(), InterfaceConfig::new(FrameFormat::Fd, 4)).unwrap()
}

/// Covers: FD-LEN-003, FD-LEN-004, FD-LEN-005, ERR-R1, FD-BIT-001, FD-BIT-002
#[test]
fn the_device_sends_length_32_as_32_bytes_padded_with_zero() {
    let mut device = fd_device();
    let layout = device.layout();
    let mut outputs = vec![0u8; layout.output_size()];
    outputs[0] = 1; // TxCounter
    outputs[4] = 1; // NoOfTxMessages
    let slot = layout.tx_slot(0);
    let message = &mut outputs[slot];
    message[2] = 30; // dataLength 30
    message[3] = 0b011; // EDL, BRS
    message[4..8].copy_from_slice(&0x123u32.to_le_bytes());
    for (i, byte) in message[8..72].iter_mut().enumerate() {
        *byte = 0xC0 | i as u8; // bytes beyond 30 are junk the device must not send
    }
    device.cycle(&outputs, 0).unwrap();
    let frame = device.poll_transmit(0).unwrap();
    assert_eq!(frame.len(), 32);
    assert_eq!(fd_dlc(frame.len()), Some(13));
    assert_eq!(
        frame.kind,
        FrameKind::Fd {
            brs: true,
            esi: false
        }
    );
    assert_eq!(&frame.data()[..30], &outputs[layout.tx_slot(0)][8..38]);
    assert_eq!(&frame.data()[30..], &[0, 0], "padding is 0x00");
}

/// Covers: FD-LEN-005, FD-BIT-001, FD-BIT-002, FD-BIT-003, FD-001, TS-001
#[test]
fn received_fd_frames_report_rounded_length_flags_and_time_stamp() {
    let mut rig = Rig::new(fd_device());
    let fd = Frame::fd(CanId::Extended(0x1AB), true, true, &[0x11; 48]).unwrap();
    let classic = Frame::classic(CanId::Standard(0x22), &[1, 2]).unwrap();
    rig.device.handle_received(fd, 1_000);
    rig.device.handle_received(classic, 2_000);
    rig.cycle(0);
    let inputs = rig.inputs();
    let first = inputs.rx_message(0).unwrap();
    assert_eq!((first.raw_length(), first.flags()), (48, 0b111));
    assert_eq!(first.time_stamp(), 1_000);
    let second = inputs.rx_message(1).unwrap();
    assert_eq!(
        (second.raw_length(), second.flags()),
        (2, 0),
        "EDL = 0: a classic frame"
    );
    rig.cycle(0);
    let received = rig.plc.take_received();
    assert_eq!(
        received.iter().map(|m| m.frame).collect::<Vec<_>>(),
        [fd, classic]
    );
}

/// Covers: FD-LEN-006
#[test]
fn classic_frames_through_the_fd_structure_stay_classic() {
    let message = MessageRepr {
        transaction_number: 3,
        frame: Frame::remote(CanId::Standard(0x7E5), 4).unwrap(),
        time_stamp: 0,
    };
    let mut bytes = [0u8; 72];
    let mut view = MessageView::new_checked(&mut bytes[..], &MessageLayout::FD_TX).unwrap();
    message.emit(&mut view).unwrap();
    assert_eq!(MessageRepr::parse(&view).unwrap(), message);
    assert_eq!(bytes[3], 0, "EDL = 0");
    let fd_rejected = InterfaceConfig::new(FrameFormat::Fd, 4);
    let mut no_fd = caps();
    no_fd.fd = false;
    assert!(Device::new(&no_fd, fd_rejected).is_err());
    let _ = QueueMode::Standard;
}
