//! The field-by-field judgement of a cycle on static images: what each
//! difference is blamed on.

use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::frame::CanId;
use canif_model::image::InputImage;

use super::*;

fn layout(format: FrameFormat) -> ImageLayout {
    ImageLayout::new(&InterfaceConfig::new(format, 4), false)
}

/// An input image with TxCounter 3, RxCounter 1 and `messages` in its slots.
fn image(layout: ImageLayout, messages: &[Frame]) -> Vec<u8> {
    let mut bytes = vec![0; layout.input_size()];
    let mut image = InputImage::new_checked(&mut bytes[..], layout).unwrap();
    image.set_tx_counter(3);
    image.set_rx_counter(1);
    image.set_no_of_rx_messages(messages.len() as u16);
    for (slot, frame) in messages.iter().enumerate() {
        let mut view = image.rx_message_mut(slot).unwrap();
        MessageRepr {
            transaction_number: 0,
            frame: *frame,
            time_stamp: 0,
        }
        .emit(&mut view)
        .unwrap();
    }
    bytes
}

fn check(layout: &ImageLayout, plc_released: u16) -> InputCheck<'_> {
    InputCheck {
        layout,
        received: &|_| None,
        overflowed: false,
        filters: &[],
        waiting_to_send: &|_| false,
        time_stamp_tolerance: 0,
        controller_reported: true,
        handshake: Handshake {
            rx_before: 0,
            plc_released,
            fast: false,
            no_of_tx_messages: 1,
            tx_before: 0,
            tx_requested: 3,
        },
        declared: DeclaredRx::default(),
    }
}

fn frame(id: u16, data: &[u8]) -> Frame {
    Frame::classic(CanId::Standard(id), data).unwrap()
}

#[test]
fn identical_images_do_not_differ_and_a_wrong_size_is_the_layout() {
    let layout = layout(FrameFormat::Base11);
    let expected = image(layout, &[frame(0x123, &[1, 2])]);
    assert_eq!(check(&layout, 0).compare(&expected, &expected), None);
    let difference = check(&layout, 0)
        .compare(&expected, &expected[..expected.len() - 2])
        .unwrap();
    assert_eq!(difference.candidates, blame::INPUT_IMAGE_SIZE);
}

#[test]
fn the_idle_count_and_stale_slots_are_judged_only_where_declared() {
    let layout = layout(FrameFormat::Base11);
    let expected = image(layout, &[frame(0x123, &[1, 2])]);
    // A delivery leaves old bytes in slot 1, past NoOfRxMessages.
    let mut stale = expected.clone();
    let old = image(layout, &[frame(0x1, &[9]), frame(0x2, &[8])]);
    let slot = layout.rx_slot(1);
    stale[slot.clone()].copy_from_slice(&old[slot]);
    assert_eq!(check(&layout, 0).compare(&expected, &stale), None);
    let declared = InputCheck {
        declared: DeclaredRx {
            stale_slots: true,
            idle_count: true,
        },
        ..check(&layout, 0)
    };
    let difference = declared.compare(&expected, &stale).unwrap();
    assert_eq!(difference.candidates, blame::RX_STALE_SLOTS);
    assert!(
        difference.what.contains("RxMessage[1]"),
        "{}",
        difference.what
    );
    // Nothing new (the PLC released RxCounter 1): a 0 where the count stayed.
    let mut zero = expected.clone();
    InputImage::new_checked(&mut zero[..], layout)
        .unwrap()
        .set_no_of_rx_messages(0);
    assert_eq!(check(&layout, 1).compare(&expected, &zero), None);
    let declared = InputCheck {
        declared: DeclaredRx {
            stale_slots: false,
            idle_count: true,
        },
        ..check(&layout, 1)
    };
    let difference = declared.compare(&expected, &zero).unwrap();
    assert_eq!(difference.candidates, blame::RX_IDLE_COUNT);
}

#[test]
fn a_header_field_is_blamed_on_its_handshake() {
    let layout = layout(FrameFormat::Base11);
    let expected = image(layout, &[]);
    let mut actual = expected.clone();
    InputImage::new_checked(&mut actual[..], layout)
        .unwrap()
        .set_tx_counter(4);
    // The model acknowledged the PLC's 3; the device still shows its 4.
    let mut not_acknowledged = check(&layout, 0);
    not_acknowledged.handshake.tx_before = 4;
    let difference = not_acknowledged.compare(&expected, &actual).unwrap();
    assert_eq!(difference.what, "Inputs.TxCounter");
    assert_eq!(difference.candidates, blame::TX_COUNTER);
    assert_eq!(
        (difference.expected.as_str(), difference.actual.as_str()),
        ("3", "4")
    );
}

#[test]
fn rx_slots_are_dont_care_until_the_plc_reads_them_and_past_the_length() {
    let layout = layout(FrameFormat::Base11);
    let expected = image(layout, &[frame(0x123, &[1, 2])]);
    let other = image(layout, &[frame(0x124, &[1, 2])]);
    // Outputs.RxCounter equals Inputs.RxCounter: the PLC does not read the slots (HS-RX-008).
    assert_eq!(check(&layout, 1).compare(&expected, &other), None);
    let difference = check(&layout, 0).compare(&expected, &other).unwrap();
    assert_eq!(difference.what, "Inputs.RxMessage[0]");
    // Data bytes past the length are don't-care.
    let mut padded = expected.clone();
    let mut image = InputImage::new_checked(&mut padded[..], layout).unwrap();
    image.rx_message_mut(0).unwrap().data_field_mut()[5] = 0xEE;
    assert_eq!(check(&layout, 0).compare(&expected, &padded), None);
}

#[test]
fn a_swapped_cob_id_word_is_the_byte_order() {
    let layout = layout(FrameFormat::Base11);
    let expected = image(layout, &[frame(0x123, &[1, 2])]);
    let mut actual = expected.clone();
    let mut image = InputImage::new_checked(&mut actual[..], layout).unwrap();
    let mut slot = image.rx_message_mut(0).unwrap();
    let word = slot.cob_id_word();
    slot.set_cob_id_word(canif_model::cob_id::CobIdWord(word.0.swap_bytes()));
    let difference = check(&layout, 0).compare(&expected, &actual).unwrap();
    assert_eq!(difference.candidates, blame::BYTE_ORDER);
}

#[test]
fn a_frame_is_blamed_on_its_first_differing_property() {
    let a = frame(0x123, &[1, 2]);
    assert_eq!(
        frame_difference(&a, &frame(0x123, &[1, 3]), true),
        blame::TX_DATA
    );
    assert_eq!(
        frame_difference(&a, &frame(0x123, &[1]), true),
        blame::TX_LENGTH
    );
    assert_eq!(
        frame_difference(&a, &frame(0x124, &[1, 2]), true),
        blame::TX_ID_WORD
    );
    assert_eq!(
        frame_difference(&a, &frame(0x124, &[9, 9]), true),
        blame::TX_OTHER_FRAME
    );
    let extended = Frame::classic(CanId::Extended(0x123), &[1, 2]).unwrap();
    assert_eq!(frame_difference(&a, &extended, false), blame::TX_FORMAT);
    let remote = Frame::remote(CanId::Standard(0x123), 2).unwrap();
    assert_eq!(frame_difference(&a, &remote, true), blame::TX_REMOTE);
    // Bits above the 11 kept in a standard identifier (LAY-29-006).
    let high = Frame::classic(CanId::Standard(0x123 | 0x800), &[1, 2]).unwrap();
    assert_eq!(frame_difference(&a, &high, false), blame::TX_ID_RESERVED);
}

/// Issue 36: which frames a full queue loses is assumption RXQ-004's (G4),
/// not the statement that frames are lost (RXQ-003): a device kept a frame
/// the model's tail drop lost, or after an overflow misses one the model
/// queued with places to spare (evicted later). One the model queued into
/// its last place is the depth's to lose, and so is any without an overflow.
#[test]
fn a_frame_the_model_dropped_is_charged_to_the_drop_policy() {
    use crate::device::history::Taken::{LastPlace, Lost, WithRoom};
    let layout = layout(FrameFormat::Base11);
    let expected = image(layout, &[frame(0x123, &[1])]);
    let kept = image(layout, &[frame(0x456, &[2])]);
    let blamed = |missing, shown, overflowed| {
        let received = move |f: &Frame| match f.id == CanId::Standard(0x123) {
            true => Some(missing),
            false => Some(shown),
        };
        InputCheck {
            received: &received,
            overflowed,
            ..check(&layout, 0)
        }
        .compare(&expected, &kept)
        .unwrap()
        .candidates
    };
    assert_eq!(blamed(WithRoom, Lost, true), blame::RX_DROP_POLICY);
    assert_eq!(blamed(WithRoom, WithRoom, true), blame::RX_DROP_POLICY);
    assert_eq!(blamed(WithRoom, WithRoom, false), blame::RX_SET);
    assert_eq!(blamed(LastPlace, WithRoom, true), blame::RX_SET);
}

/// Issue 36: Inputs.TransactionNumber naming a message the model still has
/// to complete on the bus reads "sent" as ruling G6 does not: TN-003 alone.
/// Another wrong number is TN-002's.
#[test]
fn a_transaction_number_of_a_message_not_yet_sent_is_charged_to_the_ruling() {
    let mut config = InterfaceConfig::new(FrameFormat::Extended29, 4);
    config.transaction_number = true;
    let layout = ImageLayout::new(&config, false);
    let with_number = |n: u16| {
        let mut bytes = image(layout, &[]);
        InputImage::new_checked(&mut bytes[..], layout)
            .unwrap()
            .set_transaction_number(n);
        bytes
    };
    let blamed = |waiting: &[u16]| {
        InputCheck {
            waiting_to_send: &|n| waiting.contains(&n),
            ..check(&layout, 0)
        }
        .compare(&with_number(6), &with_number(7))
        .unwrap()
        .candidates
    };
    assert_eq!(blamed(&[7, 8]), blame::TRANSACTION_NUMBER_EARLY);
    assert_eq!(blamed(&[8]), blame::TRANSACTION_NUMBER);
}

/// Issue 36: an acknowledge that is neither the last TxCounter nor
/// Outputs.TxCounter contradicts HS-TX-007's copy, not the counting rules.
#[test]
fn an_acknowledge_that_is_no_copy_is_charged_to_the_copy() {
    let layout = layout(FrameFormat::Base11);
    let expected = image(layout, &[]);
    let mut acknowledged = expected.clone();
    InputImage::new_checked(&mut acknowledged[..], layout)
        .unwrap()
        .set_tx_counter(2);
    let judged = |tx_before, tx_requested| {
        let mut check = check(&layout, 1);
        check.handshake.tx_before = tx_before;
        check.handshake.tx_requested = tx_requested;
        check.compare(&expected, &acknowledged).unwrap().candidates
    };
    // The PLC stepped from 1 to 3; the device counted 1 up to 2.
    assert_eq!(judged(1, 3), blame::TX_ACKNOWLEDGE_VALUE);
    // Not acknowledged yet (2 was the last): the handshake's timing.
    assert_eq!(judged(2, 3), blame::TX_COUNTER);
}
