//! What the bus, the PLC and the images must show.

use canif_harness::device::blame;
use canif_harness::device::diff::hex;
use canif_model::dlc;
use canif_model::frame::FrameKind;
use canif_model::image::field;
use cucumber::then;

use crate::world::CanWorld;

use super::{bytes, check, check_as, num, StepResult, Witness};

// What each kind of check witnesses: the blame sets of the harness
// (canif_harness::device::blame) for the fields the check reads. A failing scenario
// blames only its tags among them, or all its tags when none is.

/// Inputs.TxCounter: the acknowledgement of a batch, when it comes and
/// whether it fits the queue (not the order on the bus).
const TX_ACKNOWLEDGEMENT: Witness = &[blame::TX_COUNTER, blame::TX_EMPTY_BATCH];
/// What the bus carries: which messages of which batches, in what order, how
/// many per cycle, when, and with which identifier, length and flags.
const TX_PATH: Witness = &[
    blame::TX_MISSING,
    blame::TX_EXTRA,
    blame::TX_OTHER_FRAME,
    blame::TX_DATA,
    blame::TX_REMOTE,
    blame::TX_FORMAT,
    blame::TX_ID_WORD,
    blame::TX_ID_29,
    blame::TX_ID_RESERVED,
    blame::TX_LENGTH,
    blame::TX_FD_FLAGS,
    blame::SYNC1_EARLY,
    blame::SYNC1_LATE,
];
/// Inputs.RxCounter, NoOfRxMessages and what the PLC received: the Rx
/// handshake, the Rx queue, the filters and the message layouts.
const RX_PATH: Witness = &[
    blame::RX_UNRELEASED,
    blame::RX_EMPTY_DELIVERY,
    blame::RX_ADMISSION,
    blame::RX_WITHHELD_FAST,
    blame::RX_WITHHELD,
    blame::RX_COUNTING,
    blame::RX_SET,
    blame::COB_WORD,
    blame::COB_LOW,
    blame::COB_RTR,
    blame::COB_FORMAT,
    blame::LENGTH,
    blame::FLAGS,
];
/// The transaction number and when the PLC saw its confirmation.
const TRANSACTION: Witness = &[blame::TRANSACTION_NUMBER, blame::CONFIRMATION];
/// Which identifier format and RTR a frame or message has.
const ID_FORMAT: Witness = &[
    blame::COB_WORD,
    blame::COB_LOW,
    blame::COB_RTR,
    blame::COB_FORMAT,
    blame::TX_REMOTE,
    blame::TX_FORMAT,
    blame::TX_ID_WORD,
    blame::TX_ID_29,
];
/// Lengths, DLCs and padding.
const LENGTH: Witness = &[
    blame::LENGTH,
    blame::TX_LENGTH,
    blame::TX_PADDING,
    blame::TX_INVALID,
];
/// EDL, BRS and ESI.
const FD_BITS: Witness = &[blame::FLAGS, blame::TX_FD_FLAGS, blame::TX_FORMAT];
/// Time stamps of received messages.
const TIME_STAMPS: Witness = &[blame::TIME_STAMP];
/// The bytes of a message in the image: every field of it, and where the
/// messages start.
const MESSAGE_BYTES: Witness = &[
    blame::COB_WORD,
    blame::COB_LOW,
    blame::COB_RTR,
    blame::COB_FORMAT,
    blame::LENGTH,
    blame::FLAGS,
    blame::TIME_STAMP,
    blame::BYTE_ORDER,
    blame::RX_MESSAGES_OFFSET,
    blame::RX_MESSAGES_OFFSET_TN,
];
/// The sizes of the images and where their regions start.
const IMAGE_SIZES: Witness = &[
    blame::INPUT_IMAGE_SIZE,
    blame::RX_MESSAGES_OFFSET,
    blame::RX_MESSAGES_OFFSET_TN,
    blame::INFO_DATA_OFFSET,
];
/// When the first frame of a cycle starts.
const SEND_TIME: Witness = &[blame::SYNC1_EARLY, blame::SYNC1_LATE];

#[then(regex = r"^Inputs\.(TxCounter|RxCounter|NoOfRxMessages|TransactionNumber) is (\d+)$")]
fn input_field(world: &mut CanWorld, field: String, value: u32) -> StepResult {
    world.start()?;
    let image = world.input_image();
    let actual = match field.as_str() {
        "TxCounter" => image.tx_counter(),
        "RxCounter" => image.rx_counter(),
        "NoOfRxMessages" => image.no_of_rx_messages(),
        _ => image
            .transaction_number()
            .ok_or("the image has no TransactionNumber")?,
    };
    let witness = match field.as_str() {
        "TxCounter" => TX_ACKNOWLEDGEMENT,
        "TransactionNumber" => TRANSACTION,
        _ => RX_PATH,
    };
    check_as(witness, u32::from(actual) == value, || {
        format!("Inputs.{field}: expected {value}, actual {actual}")
    })
}

#[then(regex = r"^the bus carries (0x[0-9A-Fa-f]+(?:, 0x[0-9A-Fa-f]+)*) in that order$")]
fn bus_carries(world: &mut CanWorld, ids: String) -> StepResult {
    let expected: Vec<u32> = ids.split(", ").map(num).collect();
    let actual: Vec<u32> = world.on_bus.iter().map(|f| f.id.raw()).collect();
    check_as(TX_PATH, actual == expected, || {
        format!("on the bus: expected {expected:X?}, actual {actual:X?}")
    })
}

#[then(regex = r"^the bus carries (\d+) frames?$")]
fn bus_carries_n(world: &mut CanWorld, n: usize) -> StepResult {
    check_as(TX_PATH, world.on_bus.len() == n, || {
        format!(
            "expected {n} frames on the bus, saw {}: {:?}",
            world.on_bus.len(),
            world.on_bus
        )
    })
}

#[then("the bus carries nothing")]
fn bus_carries_nothing(world: &mut CanWorld) -> StepResult {
    bus_carries_n(world, 0)
}

#[then(regex = r"^the bus carries (0x[0-9A-Fa-f]+) with data ?([0-9A-Fa-f ]*)$")]
fn bus_carries_frame(world: &mut CanWorld, cob: String, data: String) -> StepResult {
    let wanted = bytes(&data);
    check_as(
        TX_PATH,
        world
            .on_bus
            .iter()
            .any(|f| f.id.raw() == num(&cob) && f.data() == wanted),
        || {
            format!(
                "no frame {cob} with data {} on the bus: {:?}",
                hex(&wanted),
                world.on_bus
            )
        },
    )
}

#[then(
    regex = r"^the last frame on the bus is (extended|standard)( and a remote request for (\d+) bytes)?$"
)]
fn last_frame_format(
    world: &mut CanWorld,
    format: String,
    remote: String,
    len: String,
) -> StepResult {
    let frame = world.on_bus.last().ok_or("nothing on the bus")?;
    check_as(
        ID_FORMAT,
        frame.id.is_extended() == (format == "extended"),
        || format!("{frame} is not {format}"),
    )?;
    if !remote.is_empty() {
        check_as(
            ID_FORMAT,
            frame.is_remote() && u32::from(frame.len()) == num(&len),
            || format!("{frame} is not a remote request for {len} bytes"),
        )?;
    }
    Ok(())
}

#[then(regex = r"^the last frame on the bus has (\d+) data bytes and DLC (\d+)$")]
fn last_frame_length(world: &mut CanWorld, len: u8, dlc_value: u8) -> StepResult {
    let frame = world.on_bus.last().ok_or("nothing on the bus")?;
    let actual_dlc = if frame.is_fd() {
        dlc::fd_dlc(frame.len())
    } else {
        Some(frame.len())
    };
    check_as(
        LENGTH,
        frame.len() == len && actual_dlc == Some(dlc_value),
        || format!("{frame}: {} bytes, DLC {actual_dlc:?}", frame.len()),
    )
}

#[then(regex = r"^the bytes after the first (\d+) are 00$")]
fn padding(world: &mut CanWorld, n: usize) -> StepResult {
    let frame = world.on_bus.last().ok_or("nothing on the bus")?;
    let data = frame.data();
    check_as(
        LENGTH,
        data[..n]
            .iter()
            .enumerate()
            .all(|(i, b)| *b == (i as u8) ^ 0x5A),
        || format!("data bytes changed: {frame}"),
    )?;
    check_as(LENGTH, data[n..].iter().all(|b| *b == 0), || {
        format!("padding is not 00: {}", hex(&data[n..]))
    })
}

#[then(regex = r"^the last frame on the bus is (an FD|a classic) frame ?( ?with BRS)?( and ESI)?$")]
fn last_frame_kind(world: &mut CanWorld, kind: String, brs: String, esi: String) -> StepResult {
    let frame = world.on_bus.last().ok_or("nothing on the bus")?;
    let expected = if kind == "an FD" {
        Some((!brs.is_empty(), !esi.is_empty()))
    } else {
        None
    };
    let actual = match frame.kind {
        FrameKind::Fd { brs, esi } => Some((brs, esi)),
        FrameKind::Classic { .. } => None,
    };
    check_as(FD_BITS, expected == actual, || {
        format!("{frame}: expected {expected:?} (BRS, ESI), actual {actual:?}")
    })
}

#[then(regex = r"^the PLC has received (\d+) messages?$")]
fn plc_received_n(world: &mut CanWorld, n: usize) -> StepResult {
    check_as(RX_PATH, world.received.len() == n, || {
        format!(
            "the PLC received {}: {:?}",
            world.received.len(),
            world.received.iter().map(|m| m.frame).collect::<Vec<_>>()
        )
    })
}

#[then(regex = r"^the PLC has received (0x[0-9A-Fa-f]+(?:, 0x[0-9A-Fa-f]+)*)$")]
fn plc_received_ids(world: &mut CanWorld, ids: String) -> StepResult {
    let expected: Vec<u32> = ids.split(", ").map(num).collect();
    let actual: Vec<u32> = world.received.iter().map(|m| m.frame.id.raw()).collect();
    check_as(RX_PATH, actual == expected, || {
        format!("the PLC received {actual:X?}, expected {expected:X?}")
    })
}

#[then(regex = r"^the PLC has received (0x[0-9A-Fa-f]+) with data ?([0-9A-Fa-f ]*)$")]
fn plc_received_frame(world: &mut CanWorld, cob: String, data: String) -> StepResult {
    let wanted = bytes(&data);
    check_as(
        RX_PATH,
        world
            .received
            .iter()
            .any(|m| m.frame.id.raw() == num(&cob) && m.frame.data() == wanted),
        || {
            format!(
                "no message {cob} with {} among {:?}",
                hex(&wanted),
                world.received.iter().map(|m| m.frame).collect::<Vec<_>>()
            )
        },
    )
}

#[then(
    regex = r"^the PLC's message (\d+) is (extended|standard)( and a remote request for (\d+) bytes)?$"
)]
fn plc_message_format(
    world: &mut CanWorld,
    index: usize,
    format: String,
    remote: String,
    len: String,
) -> StepResult {
    let frame = world.received.get(index).ok_or("no such message")?.frame;
    check_as(
        ID_FORMAT,
        frame.id.is_extended() == (format == "extended"),
        || format!("{frame} is not {format}"),
    )?;
    if !remote.is_empty() {
        check_as(
            ID_FORMAT,
            frame.is_remote() && u32::from(frame.len()) == num(&len),
            || format!("{frame} is not a remote request for {len} bytes"),
        )?;
    }
    Ok(())
}

#[then(
    regex = r"^the PLC's message (\d+) is an FD frame of (\d+) bytes ?( ?with BRS)?( ?(?:and|with) ESI)?$"
)]
fn plc_message_fd(
    world: &mut CanWorld,
    index: usize,
    len: u8,
    brs: String,
    esi: String,
) -> StepResult {
    let frame = world.received.get(index).ok_or("no such message")?.frame;
    check_as(
        FD_BITS,
        frame.kind
            == FrameKind::Fd {
                brs: !brs.is_empty(),
                esi: !esi.is_empty(),
            }
            && frame.len() == len,
        || {
            format!(
                "{frame} is not an FD frame of {len} bytes with BRS {} ESI {}",
                !brs.is_empty(),
                !esi.is_empty()
            )
        },
    )
}

#[then("each message's time stamp is the end of its reception")]
fn time_stamps_match(world: &mut CanWorld) -> StepResult {
    let tolerance = 1_000;
    for (message, (frame, end)) in world.received.iter().zip(&world.sent_by_nodes) {
        check_as(TIME_STAMPS, message.frame == *frame, || {
            format!("{} received for {}", message.frame, frame)
        })?;
        check_as(
            TIME_STAMPS,
            message.time_stamp.abs_diff(*end) <= tolerance,
            || {
                format!(
                    "time stamp {} ns, reception ended at {end} ns",
                    message.time_stamp
                )
            },
        )?;
    }
    check_as(
        TIME_STAMPS,
        world.received.len() == world.sent_by_nodes.len(),
        || "not every frame was received".into(),
    )
}

#[then(regex = r"^Inputs\.RxMessage\[(\d+)\] begins with ([0-9A-Fa-f ]+)$")]
fn rx_message_bytes(world: &mut CanWorld, slot: usize, expected: String) -> StepResult {
    world.start()?;
    let wanted = bytes(&expected);
    let image = world.input_image();
    let message = image.rx_message(slot).ok_or("no such slot")?;
    let actual = &message.as_bytes()[..wanted.len()];
    check_as(MESSAGE_BYTES, actual == wanted, || {
        format!(
            "Inputs.RxMessage[{slot}] begins with {}, expected {}",
            hex(actual),
            hex(&wanted)
        )
    })
}

#[then(regex = r"^the output image has (\d+) bytes and the input image (\d+)( before InfoData)?$")]
fn image_sizes(
    world: &mut CanWorld,
    outputs: usize,
    inputs: usize,
    before_info: String,
) -> StepResult {
    // The IUT's own input image: one cycle if none has run yet (until then
    // the world holds zeros of the model's size). Its output image has the
    // model's size, or the IUT breaks at that cycle.
    if world.cycle == 0 {
        world.cycle(false)?;
    }
    let layout = world.layout();
    let info_data = if layout.info_data {
        4 * field::INFO_DATA_WORDS
    } else {
        0
    };
    let actual = if before_info.is_empty() {
        world.inputs.len()
    } else {
        world.inputs.len().saturating_sub(info_data)
    };
    check_as(
        IMAGE_SIZES,
        layout.output_size() == outputs && actual == inputs,
        || {
            format!(
                "output {} bytes, input {actual} bytes",
                layout.output_size()
            )
        },
    )
}

#[then(regex = r"^the device (refuses|accepts) the configuration$")]
fn configuration(world: &mut CanWorld, verdict: String) -> StepResult {
    let result = world.start();
    // A refusal scenario is tagged with the rule that refuses: all its tags.
    check(result.is_ok() == (verdict == "accepts"), || {
        format!("expected the device to {verdict} it: {result:?}")
    })
}

#[then(regex = r"^InfoData\[(\d+)\] is (0x[0-9A-Fa-f]+|\d+)$")]
fn info_data(world: &mut CanWorld, index: usize, value: String) -> StepResult {
    let actual = world.input_image().info_data(index).ok_or("no InfoData")?;
    check_as(
        &[blame::info_data(index, world.status.is_some())],
        actual == num(&value),
        || format!("InfoData[{index}] = 0x{actual:X}, expected {value}"),
    )
}

#[then(regex = r"^the PLC saw the confirmation (\d+) cycles? after its increment$")]
fn confirmation(world: &mut CanWorld, cycles: u64) -> StepResult {
    check_as(
        TRANSACTION,
        world.confirmation_delay == Some(cycles),
        || format!("confirmation after {:?} cycles", world.confirmation_delay),
    )
}

#[then(regex = r"^the first frame of the last cycle started (\d+) µs after the cycle began$")]
fn first_frame_at(world: &mut CanWorld, micros: u64) -> StepResult {
    let cycle_start = world.now.saturating_sub(crate::world::CYCLE);
    let started = world
        .bus_times
        .iter()
        .copied()
        .find(|t| *t >= cycle_start)
        .ok_or("nothing went on the bus in the last cycle")?;
    let offset = started - cycle_start;
    // 003 and R10: the first Tx message starts the device's output delay
    // after SYNC1 (declared, or measured by the lockstep), within 500 ns.
    let delay = world.sync1_output_delay().unwrap_or(0);
    let earliest = micros * 1_000 + delay;
    let jitter = canif_model::exchange::SYNC1_TX_JITTER;
    check_as(
        SEND_TIME,
        (earliest..=earliest + jitter).contains(&offset),
        || {
            format!(
                "the first frame started {offset} ns after the cycle began, not {micros} µs \
                 and an output delay of {delay} ns"
            )
        },
    )
}
