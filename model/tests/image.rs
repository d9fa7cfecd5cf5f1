//! Process-image layouts, byte for byte (000 §6, §8.3; 003).

mod common;

use canif_model::cob_id::{CobId32, CobIdWord};
use canif_model::config::{FrameFormat, InterfaceConfig, QueueMode};
use canif_model::frame::{CanId, Frame};
use canif_model::image::{
    ImageLayout, InputImage, MessageError, MessageLayout, MessageRepr, MessageView, OutputImage,
};
use common::*;

static BASE11_BYTES: [u8; 10] = [0x08, 0x63, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08];
static BASE11_RTR_BYTES: [u8; 10] = [0x12, 0xE3, 0, 0, 0, 0, 0, 0, 0, 0];
static EXT29_BYTES: [u8; 14] = [
    0x03, 0x00, 0x78, 0x56, 0x34, 0x92, 0xAA, 0xBB, 0xCC, 0, 0, 0, 0, 0,
];
static EXT29_STD_RTR_BYTES: [u8; 14] = [0x02, 0x00, 0x23, 0x01, 0x00, 0x40, 0, 0, 0, 0, 0, 0, 0, 0];
static EXT29_TN_BYTES: [u8; 16] = [
    0x34, 0x12, 0x01, 0x00, 0x78, 0x56, 0x34, 0x92, 0x5A, 0, 0, 0, 0, 0, 0, 0,
];
static EXT29_TS_BYTES: [u8; 22] = [
    0x01, 0x00, 0x78, 0x56, 0x34, 0x92, 0x5A, 0, 0, 0, 0, 0, 0, 0, 0x08, 0x07, 0x06, 0x05, 0x04,
    0x03, 0x02, 0x01,
];

fn fd_tx_bytes() -> [u8; 72] {
    let mut bytes = [0u8; 72];
    bytes[..8].copy_from_slice(&[0x07, 0x00, 0x0C, 0x03, 0xF0, 0xDE, 0xBC, 0x9A]);
    for (i, byte) in bytes[8..20].iter_mut().enumerate() {
        *byte = i as u8 + 1;
    }
    bytes
}

fn fd_rx_bytes() -> [u8; 78] {
    let mut bytes = [0u8; 78];
    bytes[..6].copy_from_slice(&[0x0C, 0x05, 0x23, 0x01, 0x00, 0x00]);
    for (i, byte) in bytes[6..18].iter_mut().enumerate() {
        *byte = i as u8 + 1;
    }
    bytes[70..78].copy_from_slice(&0x0123_4567_89AB_CDEFu64.to_le_bytes());
    bytes
}

fn std_id(id: u16) -> CanId {
    CanId::Standard(id)
}

/// Covers: LAY-11-001, LAY-11-002, LAY-11-003, LAY-11-004, LAY-GEN-003
#[test]
fn base11_deconstruct() {
    let view = MessageView::new_checked(&BASE11_BYTES[..], &MessageLayout::BASE11).unwrap();
    let word = view.cob_id_word();
    assert_eq!(word, CobIdWord(0x6308));
    assert_eq!((word.id(), word.rtr(), word.length()), (0x318, false, 8));
    assert_eq!(view.data_field(), &[1, 2, 3, 4, 5, 6, 7, 8]);

    let rtr = MessageView::new_checked(&BASE11_RTR_BYTES[..], &MessageLayout::BASE11).unwrap();
    assert_eq!(
        (
            rtr.cob_id_word().id(),
            rtr.cob_id_word().rtr(),
            rtr.cob_id_word().length()
        ),
        (0x718, true, 2)
    );
}

/// Covers: LAY-11-001, LAY-11-002, LAY-11-003, LAY-11-004
#[test]
fn base11_parse_and_emit() {
    let view = MessageView::new_checked(&BASE11_BYTES[..], &MessageLayout::BASE11).unwrap();
    let repr = MessageRepr::parse(&view).unwrap();
    assert_eq!(repr.frame, std_frame(0x318, &[1, 2, 3, 4, 5, 6, 7, 8]));

    let mut bytes = [0xFFu8; 10];
    repr.emit(&mut MessageView::new_checked(&mut bytes[..], &MessageLayout::BASE11).unwrap())
        .unwrap();
    assert_eq!(bytes, BASE11_BYTES);

    let remote = MessageRepr {
        transaction_number: 0,
        frame: Frame::remote(std_id(0x718), 2).unwrap(),
        time_stamp: 0,
    };
    let mut bytes = [0xFFu8; 10];
    remote
        .emit(&mut MessageView::new_checked(&mut bytes[..], &MessageLayout::BASE11).unwrap())
        .unwrap();
    assert_eq!(bytes, BASE11_RTR_BYTES);
}

/// The manual's decode sample: Length := word AND 16#0F; RTR := word.4;
/// CobID := ROR(word, 5) AND 16#07FF — on the identifiers of its CASE.
///
/// Covers: LAY-11-005
#[test]
fn base11_manual_decode_sample() {
    for id in [0x318u16, 0x718, 0x1CD, 0x1ED] {
        for (rtr, len) in [(false, 8u8), (true, 0), (false, 2)] {
            let word = CobIdWord::new(id, rtr, len).0;
            assert_eq!(word & 0x0F, u16::from(len));
            assert_eq!(word & (1 << 4) != 0, rtr);
            assert_eq!(
                word.rotate_right(5) & 0x07FF,
                id,
                "ROR decode of 0x{word:04X}"
            );
        }
    }
}

/// Covers: LAY-29-001, LAY-29-002, LAY-29-003, LAY-29-004, LAY-29-005, LAY-GEN-003
#[test]
fn ext29_deconstruct_parse_emit() {
    let view = MessageView::new_checked(&EXT29_BYTES[..], &MessageLayout::EXT29).unwrap();
    assert_eq!(view.raw_length(), 3);
    assert_eq!(view.cob_id32(), CobId32(0x9234_5678));
    let repr = MessageRepr::parse(&view).unwrap();
    assert_eq!(
        repr.frame,
        Frame::classic(CanId::Extended(0x1234_5678), &[0xAA, 0xBB, 0xCC]).unwrap()
    );
    let mut bytes = [0xFFu8; 14];
    repr.emit(&mut MessageView::new_checked(&mut bytes[..], &MessageLayout::EXT29).unwrap())
        .unwrap();
    assert_eq!(bytes, EXT29_BYTES);

    // Bit 31 = 0: an 11-bit identifier in the 29-bit structure; bit 30: RTR.
    let view = MessageView::new_checked(&EXT29_STD_RTR_BYTES[..], &MessageLayout::EXT29).unwrap();
    let repr = MessageRepr::parse(&view).unwrap();
    assert_eq!(repr.frame, Frame::remote(std_id(0x123), 2).unwrap());
    let mut bytes = [0u8; 14];
    repr.emit(&mut MessageView::new_checked(&mut bytes[..], &MessageLayout::EXT29).unwrap())
        .unwrap();
    assert_eq!(bytes, EXT29_STD_RTR_BYTES);
}

/// Covers: LAY-29-006
#[test]
fn ext29_reserved_bits_are_ignored() {
    // Bit 29 set and garbage in bits 11..28 of a standard identifier.
    assert_eq!(CobId32(0x2000_0000 | 0x0012_3123).id(), std_id(0x123));
    assert_eq!(
        CobId32(0x8000_0000 | 0x2000_0000 | 0x0000_0001).id(),
        CanId::Extended(1)
    );
    assert_eq!(
        CobId32::new(CanId::Extended(0x1FFF_FFFF), false).0 & 0x2000_0000,
        0
    );
}

/// Covers: LAY-GEN-006, TN-001, TS-001
#[test]
fn options_put_transaction_number_first_and_time_stamp_last() {
    let tx = MessageView::new_checked(&EXT29_TN_BYTES[..], &MessageLayout::EXT29_TN).unwrap();
    let repr = MessageRepr::parse(&tx).unwrap();
    assert_eq!(repr.transaction_number, 0x1234);
    assert_eq!(
        repr.frame,
        Frame::classic(CanId::Extended(0x1234_5678), &[0x5A]).unwrap()
    );

    let rx = MessageView::new_checked(&EXT29_TS_BYTES[..], &MessageLayout::EXT29_TS).unwrap();
    let repr = MessageRepr::parse(&rx).unwrap();
    assert_eq!(repr.time_stamp, 0x0102_0304_0506_0708);
    let mut bytes = [0u8; 22];
    repr.emit(&mut MessageView::new_checked(&mut bytes[..], &MessageLayout::EXT29_TS).unwrap())
        .unwrap();
    assert_eq!(bytes, EXT29_TS_BYTES);

    let mut base_tn = [0u8; 12];
    let message = MessageRepr {
        transaction_number: 0xBEEF,
        frame: std_frame(0x318, &[9]),
        time_stamp: 0,
    };
    message
        .emit(&mut MessageView::new_checked(&mut base_tn[..], &MessageLayout::BASE11_TN).unwrap())
        .unwrap();
    assert_eq!(base_tn, [0xEF, 0xBE, 0x01, 0x63, 9, 0, 0, 0, 0, 0, 0, 0]);
}

/// Covers: LAY-FD-001, LAY-FD-002, LAY-FD-003, FD-BIT-001, FD-BIT-002, FD-BIT-003, FD-001
#[test]
fn fd_structures() {
    let tx = fd_tx_bytes();
    let view = MessageView::new_checked(&tx[..], &MessageLayout::FD_TX).unwrap();
    let repr = MessageRepr::parse(&view).unwrap();
    let data: Vec<u8> = (1..=12).collect();
    assert_eq!(repr.transaction_number, 7);
    assert_eq!(
        repr.frame,
        Frame::fd(CanId::Extended(0x1ABC_DEF0), true, false, &data).unwrap()
    );
    let mut bytes = [0xFFu8; 72];
    repr.emit(&mut MessageView::new_checked(&mut bytes[..], &MessageLayout::FD_TX).unwrap())
        .unwrap();
    assert_eq!(bytes, tx);

    let rx = fd_rx_bytes();
    let view = MessageView::new_checked(&rx[..], &MessageLayout::FD_RX).unwrap();
    let repr = MessageRepr::parse(&view).unwrap();
    assert_eq!(
        repr.frame,
        Frame::fd(std_id(0x123), false, true, &data).unwrap()
    );
    assert_eq!(repr.time_stamp, 0x0123_4567_89AB_CDEF);
    let mut bytes = [0xFFu8; 78];
    repr.emit(&mut MessageView::new_checked(&mut bytes[..], &MessageLayout::FD_RX).unwrap())
        .unwrap();
    assert_eq!(bytes, rx);

    // EDL = 0: a classic frame through the FD structure.
    let mut classic = [0u8; 72];
    classic[2] = 2; // dataLength
    classic[4..8].copy_from_slice(&0x0000_0321u32.to_le_bytes());
    classic[8..10].copy_from_slice(&[0xA1, 0xA2]);
    let repr =
        MessageRepr::parse(&MessageView::new_checked(&classic[..], &MessageLayout::FD_TX).unwrap())
            .unwrap();
    assert_eq!(repr.frame, std_frame(0x321, &[0xA1, 0xA2]));

    // RTR with EDL: CAN FD has no remote frames.
    let mut remote_fd = tx;
    remote_fd[7] |= 0x40;
    let view = MessageView::new_checked(&remote_fd[..], &MessageLayout::FD_TX).unwrap();
    assert_eq!(MessageRepr::parse(&view), Err(MessageError::RemoteFdFrame));
}

/// Covers: LAY-GEN-002, LAY-GEN-003, HS-TX-002
#[test]
fn output_image_header() {
    let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Base11, 2), false);
    assert_eq!(layout.output_size(), 6 + 2 * 10);
    let mut bytes = [0u8; 26];
    bytes[..6].copy_from_slice(&[0x34, 0x12, 0x02, 0x00, 0x01, 0x00]);
    bytes[6..16].copy_from_slice(&BASE11_BYTES);
    let image = OutputImage::new_checked(&bytes[..], layout).unwrap();
    assert_eq!(
        (
            image.tx_counter(),
            image.rx_counter(),
            image.no_of_tx_messages()
        ),
        (0x1234, 2, 1)
    );
    let message = MessageRepr::parse(&image.tx_message(0).unwrap()).unwrap();
    assert_eq!(message.frame.id, std_id(0x318));
    assert!(image.tx_message(2).is_none());

    let mut built = [0u8; 26];
    let mut image = OutputImage::new_checked(&mut built[..], layout).unwrap();
    image.set_tx_counter(0x1234);
    image.set_rx_counter(2);
    image.set_no_of_tx_messages(1);
    message.emit(&mut image.tx_message_mut(0).unwrap()).unwrap();
    assert_eq!(built, bytes);
}

/// Covers: LAY-GEN-004, LAY-GEN-005, LAY-GEN-003
#[test]
fn input_image_header_with_and_without_transaction_number() {
    let plain = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Extended29, 3), false);
    assert_eq!(plain.rx_slot(0), 6..20);
    assert_eq!(plain.input_size(), 6 + 3 * 14);

    let mut config = InterfaceConfig::new(FrameFormat::Extended29, 3);
    config.transaction_number = true;
    config.time_stamp = true;
    let with_tn = ImageLayout::new(&config, false);
    assert_eq!(with_tn.rx_slot(0), 8..30);
    assert_eq!(with_tn.tx_slot(1), 22..38);
    let mut bytes = vec![0u8; with_tn.input_size()];
    bytes[..8].copy_from_slice(&[0x01, 0x00, 0xFF, 0xFF, 0x01, 0x00, 0x2A, 0x00]);
    bytes[8..30].copy_from_slice(&EXT29_TS_BYTES);
    let image = InputImage::new_checked(&bytes[..], with_tn).unwrap();
    assert_eq!(image.tx_counter(), 1);
    assert_eq!(image.rx_counter(), 0xFFFF);
    assert_eq!(image.no_of_rx_messages(), 1);
    assert_eq!(image.transaction_number(), Some(42));
    assert_eq!(
        MessageRepr::parse(&image.rx_message(0).unwrap())
            .unwrap()
            .time_stamp,
        0x0102_0304_0506_0708
    );
    assert_eq!(
        InputImage::new_checked(&bytes[..6 + 3 * 14], plain)
            .unwrap()
            .transaction_number(),
        None
    );
}

/// Covers: INFO-008, INFO-001
#[test]
fn info_data_follows_the_rx_messages() {
    let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Fd, 2), true);
    assert_eq!(layout.info_data_start(), 8 + 2 * 78);
    assert_eq!(layout.input_size(), 8 + 2 * 78 + 16 * 4);
    let mut bytes = vec![0u8; layout.input_size()];
    bytes[layout.info_data_start() + 4..layout.info_data_start() + 8]
        .copy_from_slice(&[1, 2, 3, 4]);
    let image = InputImage::new_checked(&bytes[..], layout).unwrap();
    assert_eq!(image.info_data(1), Some(0x0403_0201));
    assert_eq!(image.info_data(16), None);
}

/// The manual prints "11 bis 32" but its own examples use 4 and 10 (R2).
///
/// Covers: LAY-GEN-007, PROF-011, ERR-R2
#[test]
fn slot_counts_from_1_to_32() {
    let caps = caps();
    for slots in [1u8, 4, 10, 11, 32] {
        assert!(InterfaceConfig::new(FrameFormat::Base11, slots)
            .validate(&caps)
            .is_ok());
        let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Base11, slots), false);
        assert_eq!(layout.output_size(), 6 + usize::from(slots) * 10);
    }
    for slots in [0u8, 33] {
        assert!(
            InterfaceConfig::new(FrameFormat::Base11, slots)
                .validate(&caps)
                .is_err(),
            "{slots} slots"
        );
    }
    let mut narrow = caps.clone();
    narrow.max_slots = 16;
    assert!(InterfaceConfig::new(FrameFormat::Base11, 17)
        .validate(&narrow)
        .is_err());
}

/// Covers: LAY-GEN-008, HS-TX-010, FD-LEN-006
#[test]
fn invalid_lengths_are_clamped_and_named() {
    let mut word = BASE11_BYTES;
    word[0] = 0x0F; // length 15
    let view = MessageView::new_checked(&word[..], &MessageLayout::BASE11).unwrap();
    assert_eq!(
        MessageRepr::parse(&view),
        Err(MessageError::ClassicLengthTooLarge { len: 15 })
    );
    let (clamped, error) = MessageRepr::parse_clamped(&view);
    assert_eq!(clamped.frame.data().len(), 8);
    assert!(error.is_some());

    let mut fd = fd_tx_bytes();
    fd[2] = 200;
    let view = MessageView::new_checked(&fd[..], &MessageLayout::FD_TX).unwrap();
    assert_eq!(
        MessageRepr::parse(&view),
        Err(MessageError::FdLengthTooLarge { len: 200 })
    );
    assert_eq!(MessageRepr::parse_clamped(&view).0.frame.len(), 64);

    let mut classic_long = fd_tx_bytes();
    classic_long[3] = 0; // EDL = 0 …
    classic_long[2] = 12; // … with 12 bytes
    let view = MessageView::new_checked(&classic_long[..], &MessageLayout::FD_TX).unwrap();
    assert_eq!(
        MessageRepr::parse(&view),
        Err(MessageError::ClassicLengthTooLarge { len: 12 })
    );
    let (frame, _) = MessageRepr::parse_clamped(&view);
    assert!(!frame.frame.is_fd() && frame.frame.len() == 8);

    // The device keeps cycling and sends at most the slot count.
    let mut device = device(FrameFormat::Base11, QueueMode::Standard, 2);
    let mut outputs = outputs_with(&device, 1, 0, &[], 1000);
    outputs[6] = 0xFF; // slot 0: length 15, RTR, id 0x7FF
    device.cycle(&outputs, 0).unwrap();
    let mut sent = 0;
    while let Some(frame) = device.poll_transmit(0) {
        assert!(frame.len() <= 8);
        sent += 1;
        device.handle_transmit_complete();
    }
    assert_eq!(sent, 2);
}

/// Covers: LAY-GEN-001
#[test]
fn frames_that_do_not_fit_a_layout_are_refused() {
    let extended = MessageRepr {
        transaction_number: 0,
        frame: Frame::classic(CanId::Extended(0x100), &[]).unwrap(),
        time_stamp: 0,
    };
    let mut bytes = [0u8; 10];
    let mut view = MessageView::new_checked(&mut bytes[..], &MessageLayout::BASE11).unwrap();
    assert!(matches!(
        extended.emit(&mut view),
        Err(MessageError::NotRepresentable { .. })
    ));
    let fd = MessageRepr {
        transaction_number: 0,
        frame: Frame::fd(std_id(1), false, false, &[0; 12]).unwrap(),
        time_stamp: 0,
    };
    let mut bytes = [0u8; 14];
    let mut view = MessageView::new_checked(&mut bytes[..], &MessageLayout::EXT29).unwrap();
    assert!(fd.emit(&mut view).is_err());
    // Both identifier formats through the 29-bit structure.
    for id in [std_id(0x7FF), CanId::Extended(0x1FFF_FFFF)] {
        let message = MessageRepr {
            transaction_number: 0,
            frame: Frame::classic(id, &[1]).unwrap(),
            time_stamp: 0,
        };
        let mut bytes = [0u8; 14];
        let mut view = MessageView::new_checked(&mut bytes[..], &MessageLayout::EXT29).unwrap();
        message.emit(&mut view).unwrap();
        assert_eq!(MessageRepr::parse(&view).unwrap(), message);
    }
}

#[test]
fn wrong_sizes_are_errors_not_panics() {
    let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Base11, 2), false);
    assert!(OutputImage::new_checked(&[0u8; 25][..], layout).is_err());
    assert!(InputImage::new_checked(&[0u8; 27][..], layout).is_err());
    assert!(MessageView::new_checked(&[0u8; 9][..], &MessageLayout::BASE11).is_err());
    let mut device = device(FrameFormat::Base11, QueueMode::Standard, 2);
    assert!(device.cycle(&[0u8; 3], 0).is_err());
}
