//! The judge on single tasks: what it lets pass and what it blames.

use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::frame::CanId;

use super::*;
use crate::client::master::NEIGHBOUR_PATTERN;

fn layout() -> ImageLayout {
    ImageLayout::new(&InterfaceConfig::new(FrameFormat::Base11, 2), false)
}

fn request(id: u16) -> MessageRepr {
    MessageRepr {
        transaction_number: 0,
        frame: Frame::classic(CanId::Standard(id), &[id as u8]).unwrap(),
        time_stamp: 0,
    }
}

/// An output buffer with `batch` written under TxCounter `counter`, the
/// neighbour's pattern behind it.
fn outputs(counter: u16, batch: &[MessageRepr]) -> Vec<u8> {
    let layout = layout();
    let mut bytes = vec![0; layout.output_size()];
    let mut image = OutputImage::new_checked(&mut bytes[..], layout).unwrap();
    image.set_tx_counter(counter);
    image.set_no_of_tx_messages(batch.len() as u16);
    for (slot, message) in batch.iter().enumerate() {
        message
            .emit(&mut image.tx_message_mut(slot).unwrap())
            .unwrap();
    }
    bytes.extend([NEIGHBOUR_PATTERN; 8]);
    bytes
}

fn task<'a>(inputs: &'a [u8], before: &'a [u8], after: &'a [u8]) -> TaskSeen<'a> {
    TaskSeen {
        inputs,
        before,
        after,
        accepted: &[],
        delivered: &[],
        not_frames: &[],
        sent: &[],
    }
}

#[test]
fn a_batch_of_what_the_application_asked_passes_and_a_second_before_the_acknowledge_does_not() {
    let layout = layout();
    let mut judge = Judge::new(layout, QueueMode::Standard, &Default::default());
    let inputs = vec![0; layout.input_size()];
    let idle = outputs(0, &[]);
    let first = outputs(1, &[request(0x101)]);
    let asked = [request(0x101)];
    let seen = TaskSeen {
        accepted: &asked,
        ..task(&inputs, &idle[..layout.output_size()], &first)
    };
    assert_eq!(judge.task(1, seen, 100), Vec::<Breach>::new());
    // Inputs.TxCounter is still 0: the batch is not acknowledged.
    let second = outputs(2, &[request(0x101)]);
    let breach = judge
        .task(
            2,
            task(&inputs, &first[..layout.output_size()], &second),
            100,
        )
        .into_iter()
        .next()
        .unwrap();
    assert_eq!(breach.requirements, TX_UNTOUCHED);
}

#[test]
fn more_messages_than_requests_or_another_frame_than_asked_is_a_breach() {
    let layout = layout();
    let inputs = vec![0; layout.input_size()];
    let idle = outputs(0, &[]);
    let invented = outputs(1, &[request(0x7FF)]);
    let breach = Judge::new(layout, QueueMode::Standard, &Default::default())
        .task(
            1,
            task(&inputs, &idle[..layout.output_size()], &invented),
            100,
        )
        .into_iter()
        .next()
        .unwrap();
    assert_eq!(breach.requirements, TX_COUNT, "{breach:?}");
    let asked = [request(0x101)];
    let seen = TaskSeen {
        accepted: &asked,
        ..task(&inputs, &idle[..layout.output_size()], &invented)
    };
    let breach = Judge::new(layout, QueueMode::Standard, &Default::default())
        .task(1, seen, 100)
        .into_iter()
        .next()
        .unwrap();
    assert_eq!(breach.requirements, TX_ENCODING, "{breach:?}");
}

#[test]
fn writing_behind_the_image_or_reading_past_the_slots_breaks_its_bounds() {
    let layout = layout();
    let inputs = vec![0; layout.input_size()];
    let idle = outputs(0, &[]);
    let mut scribbled = idle.clone();
    *scribbled.last_mut().unwrap() = 0;
    let mut judge = Judge::new(layout, QueueMode::Standard, &Default::default());
    let breach = judge
        .task(
            1,
            task(&inputs, &idle[..layout.output_size()], &scribbled),
            100,
        )
        .into_iter()
        .next()
        .unwrap();
    assert_eq!(breach.requirements, IMAGE_BOUNDS);
    let three = [request(1), request(2), request(3)];
    let seen = TaskSeen {
        delivered: &three,
        ..task(&inputs, &idle[..layout.output_size()], &idle)
    };
    let breach = Judge::new(layout, QueueMode::Standard, &Default::default())
        .task(1, seen, 100)
        .into_iter()
        .next()
        .unwrap();
    assert_eq!(breach.requirements, IMAGE_BOUNDS);
    assert_eq!(breach.actual, "3");
}

#[test]
fn a_delivered_message_that_is_no_frame_is_a_decoding_breach() {
    let layout = layout();
    let inputs = vec![0; layout.input_size()];
    let idle = outputs(0, &[]);
    let not_frames = ["29-bit identifier without the flag".to_string()];
    let seen = TaskSeen {
        not_frames: &not_frames,
        ..task(&inputs, &idle[..layout.output_size()], &idle)
    };
    let breach = Judge::new(layout, QueueMode::Standard, &Default::default())
        .task(1, seen, 100)
        .into_iter()
        .next()
        .unwrap();
    assert_eq!(breach.requirements, RX_DECODING);
}

#[test]
fn a_byte_stream_is_cut_where_the_client_cut_it() {
    use canif_model::frame::{CanId, Frame};
    let message = |id: u16, data: &[u8]| MessageRepr {
        transaction_number: 0,
        frame: Frame::classic(CanId::Standard(id), data).unwrap(),
        time_stamp: 0,
    };
    let pending = vec![
        message(1, &[1, 2, 3]),
        message(2, &[9]),
        message(1, &[4, 5, 6, 7, 8, 9]),
    ];
    // Eight bytes of identifier 1 from two requests; the rest stays behind.
    let taken = message(1, &[1, 2, 3, 4, 5, 6, 7, 8]);
    assert_eq!(
        super::tx::cut(pending.clone(), &taken),
        vec![taken, message(2, &[9]), message(1, &[9])]
    );
    // Bytes that are not the next of their identifier change nothing.
    assert_eq!(super::tx::cut(pending.clone(), &message(1, &[2])), pending);
    assert_eq!(super::tx::cut(pending.clone(), &message(3, &[1])), pending);
}

/// An input image with RxCounter 1 and NoOfRxMessages 1, `ids` in its slots
/// from slot 0 (those past the first are stale).
fn batch_of_one(ids: &[u16]) -> Vec<u8> {
    let layout = layout();
    let mut inputs = vec![0; layout.input_size()];
    let mut image = InputImage::new_checked(&mut inputs[..], layout).unwrap();
    image.set_rx_counter(1);
    image.set_no_of_rx_messages(1);
    for (slot, id) in ids.iter().enumerate() {
        request(*id)
            .emit(&mut image.rx_message_mut(slot).unwrap())
            .unwrap();
    }
    inputs
}

/// Issue 36: in a restarted program's first batch, a message decoded
/// otherwise than the device wrote it is a decoding fault (CL-RX-003), not
/// the restart's (CL-RST-001 allows a batch twice or dropped, nothing else).
#[test]
fn a_wrong_decoding_after_a_plc_restart_is_charged_to_the_decoding() {
    let layout = layout();
    let mut judge = Judge::new(layout, QueueMode::Standard, &Default::default());
    let inputs = batch_of_one(&[0x181]);
    judge.device_cycle(&inputs);
    judge.plc_restarted(0);
    let idle = outputs(0, &[]);
    let mut acknowledged = idle.clone();
    OutputImage::new_checked(&mut acknowledged[..layout.output_size()], layout)
        .unwrap()
        .set_rx_counter(1);
    let wrongly_decoded = [request(0x182)];
    let twice = [request(0x181), request(0x181)];
    for (delivered, blamed) in [(&wrongly_decoded[..], RX_DECODING), (&twice, PLC_RESTART)] {
        let seen = TaskSeen {
            delivered,
            ..task(&inputs, &idle[..layout.output_size()], &acknowledged)
        };
        let breaches = judge.clone().task(1, seen, 100);
        assert_eq!(breaches.first().map(|b| b.requirements), Some(blamed));
    }
}

/// Issue 36: a client that reads a slot past NoOfRxMessages delivers no
/// message of the batch, however right its decoding: CL-RX-002, not the
/// decoding's CL-RX-003.
#[test]
fn a_stale_slot_read_is_charged_to_the_delivery_not_the_decoding() {
    let layout = layout();
    let mut judge = Judge::new(layout, QueueMode::Standard, &Default::default());
    // Slot 1, past NoOfRxMessages, holds what an earlier batch left there.
    let inputs = batch_of_one(&[0x181, 0x199]);
    judge.device_cycle(&inputs);
    let idle = outputs(0, &[]);
    let delivered = [request(0x199), request(0x181)];
    let seen = TaskSeen {
        delivered: &delivered,
        ..task(&inputs, &idle[..layout.output_size()], &idle)
    };
    let breach = judge.task(1, seen, 100).into_iter().next().unwrap();
    assert_eq!(breach.requirements, RX_ONCE, "{breach:?}");
}
