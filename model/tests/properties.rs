//! Properties for what examples cannot cover: round trips, robustness on any
//! input, and the queue guarantees under any protocol-following traffic.

mod common;

use canif_model::client::PlcClient;
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode};
use canif_model::device::{Device, RxOutcome};
use canif_model::dlc::{fd_round_up, FD_DATA_SIZES};
use canif_model::filter::{accepts, FilterAction, FilterMatch, FilterRow};
use canif_model::frame::{CanId, Frame};
use canif_model::image::{LengthField, MessageLayout, MessageRepr, MessageView};
use common::*;
use proptest::prelude::*;

fn arb_id(extended_allowed: bool) -> BoxedStrategy<CanId> {
    if extended_allowed {
        prop_oneof![
            (0u32..=0x7FF).prop_map(|id| CanId::Standard(id as u16)),
            (0u32..=0x1FFF_FFFF).prop_map(CanId::Extended)
        ]
        .boxed()
    } else {
        (0u16..=0x7FF).prop_map(CanId::Standard).boxed()
    }
}

fn arb_classic(extended_allowed: bool) -> BoxedStrategy<Frame> {
    (
        arb_id(extended_allowed),
        any::<bool>(),
        proptest::collection::vec(any::<u8>(), 0..=8),
    )
        .prop_map(|(id, rtr, data)| {
            if rtr {
                Frame::remote(id, data.len() as u8).unwrap()
            } else {
                Frame::classic(id, &data).unwrap()
            }
        })
        .boxed()
}

fn arb_fd() -> BoxedStrategy<Frame> {
    (
        arb_id(true),
        any::<bool>(),
        any::<bool>(),
        0usize..16,
        proptest::collection::vec(any::<u8>(), 64),
    )
        .prop_map(|(id, brs, esi, dlc, data)| {
            Frame::fd(id, brs, esi, &data[..usize::from(FD_DATA_SIZES[dlc])]).unwrap()
        })
        .boxed()
}

fn arb_message(layout: &'static MessageLayout) -> BoxedStrategy<MessageRepr> {
    let frame = match layout.length {
        LengthField::InCobIdWord => arb_classic(false),
        LengthField::Word(_) => arb_classic(true),
        LengthField::Byte(_) => prop_oneof![arb_classic(true), arb_fd()].boxed(),
    };
    let has_tn = layout.transaction_number.is_some();
    let has_ts = layout.time_stamp.is_some();
    (frame, any::<u16>(), any::<u64>())
        .prop_map(move |(frame, tn, ts)| MessageRepr {
            transaction_number: if has_tn { tn } else { 0 },
            frame,
            time_stamp: if has_ts { ts } else { 0 },
        })
        .boxed()
}

fn arb_layout_and_message() -> impl Strategy<Value = (&'static MessageLayout, MessageRepr)> {
    (0..MessageLayout::ALL.len()).prop_flat_map(|i| {
        (
            Just(MessageLayout::ALL[i]),
            arb_message(MessageLayout::ALL[i]),
        )
    })
}

fn seq_frame(seq: u32) -> Frame {
    Frame::classic(CanId::Standard((seq & 0x7FF) as u16), &seq.to_le_bytes()).unwrap()
}

proptest! {
    /// Covers: LAY-11-001, LAY-29-001, LAY-FD-001, LAY-GEN-006
    #[test]
    fn every_message_round_trips((layout, message) in arb_layout_and_message()) {
        let mut bytes = vec![0xA5u8; layout.size];
        let mut view = MessageView::new_checked(&mut bytes[..], layout).unwrap();
        message.emit(&mut view).unwrap();
        prop_assert_eq!(MessageRepr::parse(&view).unwrap(), message);
    }

    /// Covers: LAY-GEN-008, FD-LEN-006
    #[test]
    fn decoding_any_bytes_never_panics_and_stays_in_bounds(layout in 0..MessageLayout::ALL.len(), bytes in proptest::collection::vec(any::<u8>(), 78)) {
        let layout = MessageLayout::ALL[layout];
        let view = MessageView::new_checked(&bytes[..layout.size], layout).unwrap();
        let _ = MessageRepr::parse(&view);
        let (message, _) = MessageRepr::parse_clamped(&view);
        let limit = if message.frame.is_fd() { 64 } else { 8 };
        prop_assert!(message.frame.data().len() <= limit);
        prop_assert!(!message.frame.is_fd() || fd_round_up(message.frame.len()) == Some(message.frame.len()));
    }

    /// Covers: HS-TX-010, HS-TX-011, LAY-GEN-008
    #[test]
    fn any_output_image_keeps_the_device_cycling(
        format in prop_oneof![Just(FrameFormat::Base11), Just(FrameFormat::Extended29), Just(FrameFormat::Fd)],
        slots in 1u8..=8,
        images in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..700), 1..6),
    ) {
        let mut device = Device::new(&Capabilities::everything(), InterfaceConfig::new(format, slots)).unwrap();
        let size = device.layout().output_size();
        for image in images {
            let wrong_size = image.len() != size;
            let before = device.queued_tx();
            let mut exact = image.clone();
            exact.resize(size, 0);
            prop_assert_eq!(device.cycle(&image, 0).is_err(), wrong_size);
            device.cycle(&exact, 0).unwrap();
            prop_assert!(device.queued_tx() <= before + usize::from(slots));
            prop_assert_eq!(device.inputs().len(), device.layout().input_size());
            if let Some(frame) = device.poll_transmit(0) {
                let limit = if frame.is_fd() { 64 } else { 8 };
                prop_assert!(frame.data().len() <= limit);
                device.handle_transmit_complete();
            }
        }
    }

    /// Covers: HS-TX-006, HS-TX-004, FQ-003, HS-TX-008
    #[test]
    fn no_tx_message_is_lost_duplicated_or_reordered(
        queue in prop_oneof![Just(QueueMode::Standard), Just(QueueMode::Optimized), Just(QueueMode::Fast)],
        slots in 1u8..=8,
        extra_depth in 0usize..10,
        steps in proptest::collection::vec((0u32..=12, 0usize..=6), 1..60),
    ) {
        let mut caps = Capabilities::everything();
        caps.tx_queue_depth = usize::from(slots) + extra_depth;
        let mut rig = Rig::new(Device::new(&caps, config(FrameFormat::Base11, queue, slots)).unwrap());
        let mut sent = Vec::new();
        for (new_messages, completions) in steps {
            for _ in 0..new_messages {
                let frame = seq_frame(sent.len() as u32);
                rig.plc.send(message(frame, 0)).unwrap();
                sent.push(frame);
            }
            rig.cycle(completions);
        }
        for _ in 0..2_000 {
            // Done when nothing waits in the PLC, in the output image (unacknowledged) or in the device.
            let acknowledged = rig.plc.outputs()[..2] == rig.device.inputs()[..2];
            if rig.plc.pending() == 0 && acknowledged && rig.device.queued_tx() == 0 {
                break;
            }
            rig.cycle(64);
        }
        prop_assert_eq!(rig.on_bus, sent);
    }

    /// Covers: HS-RX-007, RXQ-003, RXQ-004, HS-RX-001, BQ-002
    #[test]
    fn buffered_rx_loses_exactly_the_frames_that_find_the_queue_full(
        slots in 1u8..=8,
        depth in 1usize..=20,
        steps in proptest::collection::vec((0u32..=10, any::<bool>()), 1..60),
    ) {
        let mut caps = Capabilities::everything();
        caps.rx_queue_depth = depth;
        let mut device = Device::new(&caps, config(FrameFormat::Base11, QueueMode::Standard, slots)).unwrap();
        let mut plc = PlcClient::new(device.layout());
        // The reference: occupancy of the local queue and whether the image awaits the PLC.
        let (mut occupancy, mut awaiting_ack) = (0usize, false);
        let mut expected = Vec::new();
        let mut seq = 0u32;
        let run = |arrivals: u32, plc_runs: bool, device: &mut Device, plc: &mut PlcClient, seq: &mut u32,
                   occupancy: &mut usize, awaiting_ack: &mut bool, expected: &mut Vec<Frame>| -> Result<(), TestCaseError> {
            for _ in 0..arrivals {
                let frame = seq_frame(*seq);
                *seq += 1;
                let outcome = device.handle_received(frame, 0);
                if *occupancy < depth {
                    prop_assert_eq!(outcome, RxOutcome::Queued);
                    *occupancy += 1;
                    expected.push(frame);
                } else {
                    prop_assert_eq!(outcome, RxOutcome::Lost);
                }
            }
            let outputs = plc.outputs().to_vec();
            device.cycle(&outputs, 0).unwrap();
            if !*awaiting_ack && *occupancy > 0 {
                *occupancy -= (*occupancy).min(usize::from(slots));
                *awaiting_ack = true;
            }
            if plc_runs {
                plc.task(device.inputs()).unwrap();
                *awaiting_ack = false;
            }
            Ok(())
        };
        for (arrivals, plc_runs) in steps {
            run(arrivals, plc_runs, &mut device, &mut plc, &mut seq, &mut occupancy, &mut awaiting_ack, &mut expected)?;
        }
        for _ in 0..(depth + 2) * 2 {
            run(0, true, &mut device, &mut plc, &mut seq, &mut occupancy, &mut awaiting_ack, &mut expected)?;
        }
        let received: Vec<Frame> = plc.take_received().into_iter().map(|m| m.frame).collect();
        prop_assert_eq!(device.lost(), u64::from(seq) - expected.len() as u64);
        prop_assert_eq!(received, expected);
    }

    /// Covers: FQ-004, FQ-002, FQ-001
    #[test]
    fn fast_queue_delivers_the_first_slots_of_each_cycle(
        slots in 1u8..=8,
        steps in proptest::collection::vec(0u32..=12, 1..40),
    ) {
        let mut device = Device::new(&Capabilities::everything(), config(FrameFormat::Base11, QueueMode::Fast, slots)).unwrap();
        let mut plc = PlcClient::new(device.layout());
        let mut expected = Vec::new();
        let mut seq = 0u32;
        for arrivals in steps {
            for i in 0..arrivals {
                let frame = seq_frame(seq);
                seq += 1;
                device.handle_received(frame, 0);
                if i < u32::from(slots) {
                    expected.push(frame);
                }
            }
            let outputs = plc.outputs().to_vec();
            device.cycle(&outputs, 0).unwrap();
            plc.task(device.inputs()).unwrap();
        }
        let received: Vec<Frame> = plc.take_received().into_iter().map(|m| m.frame).collect();
        prop_assert_eq!(received, expected);
    }

    /// Covers: FD-LEN-003, ERR-R1
    #[test]
    fn fd_rounding_is_the_least_valid_length_at_least_n(n in 0u8..=255) {
        let brute_force = FD_DATA_SIZES.iter().copied().filter(|&size| size >= n).min();
        prop_assert_eq!(fd_round_up(n), brute_force);
    }

    /// Covers: FLT-003, FLT-004, FLT-005, FLT-006, FLT-008
    #[test]
    fn filters_agree_with_a_brute_force_reading_of_the_table(
        rows in proptest::collection::vec((any::<bool>(), any::<bool>(), 0u32..0x800, 0u32..0x800), 0..6),
        id in 0u32..0x800,
    ) {
        let table: Vec<FilterRow> = rows.iter().map(|&(accept, range, a, b)| FilterRow {
            action: if accept { FilterAction::Accept } else { FilterAction::Reject },
            matches: if range { FilterMatch::Range { from: a.min(b), to: a.max(b) } } else { FilterMatch::CodeMask { code: a, mask: b } },
        }).collect();
        // Brute force: every row's match decided bit by bit or by enumeration, then the lowest index.
        let row_matches = |row: &FilterRow| match row.matches {
            FilterMatch::Range { from, to } => (from..=to).any(|candidate| candidate == id),
            FilterMatch::CodeMask { code, mask } => (0..29).all(|bit| mask & (1 << bit) == 0 || (id >> bit) & 1 == (code >> bit) & 1),
        };
        let decision = match table.iter().position(row_matches) {
            Some(first) => table[first].action == FilterAction::Accept,
            None => table.iter().all(|row| row.action == FilterAction::Reject),
        };
        prop_assert_eq!(accepts(&table, CanId::Extended(id)), decision);
    }

    /// Covers: TS-003
    #[test]
    fn time_stamps_do_not_decrease_in_delivery_order(gaps in proptest::collection::vec((0u64..1_000_000, any::<bool>()), 1..80)) {
        let mut config = config(FrameFormat::Extended29, QueueMode::Standard, 3);
        config.transaction_number = true;
        config.time_stamp = true;
        let mut rig = Rig::new(Device::new(&Capabilities::everything(), config).unwrap());
        let mut now = 0;
        for (i, (gap, cycle)) in gaps.iter().enumerate() {
            now += gap;
            rig.device.handle_received(seq_frame(i as u32), now);
            if *cycle {
                rig.cycle(0);
            }
        }
        for _ in 0..60 {
            rig.cycle(0);
        }
        let stamps: Vec<u64> = rig.plc.take_received().iter().map(|m| m.time_stamp).collect();
        prop_assert_eq!(stamps.len(), gaps.len());
        prop_assert!(stamps.windows(2).all(|w| w[0] <= w[1]));
    }
}
