//! The step library. Every step is documented in features/README.md.

use canif_harness::check::hex;
use canif_model::canopen::cob_id::{default_cob_id, Channel};
use canif_model::canopen::guarding::GuardResponder;
use canif_model::canopen::heartbeat;
use canif_model::canopen::nmt::{self, NmtCommand, NmtState};
use canif_model::canopen::sdo::{abort_code, SdoRequest, SdoResponse};
use canif_model::canopen::NodeId;
use canif_model::cia_table;
use canif_model::config::{FrameFormat, QueueMode, Synchronization};
use canif_model::dlc;
use canif_model::exchange::ExchangeMode;
use canif_model::filter::{FilterAction, FilterMatch, FilterRow};
use canif_model::frame::{CanId, Frame, FrameKind};
use canif_model::info_data::ControllerStatus;
use canif_model::sizing;
use canif_model::timing::{classic_bits, BitCount};
use canif_model::Nanos;
use cucumber::gherkin::Step;
use cucumber::{given, then, when};

use crate::world::CanWorld;

type StepResult = Result<(), String>;

fn num(text: &str) -> u32 {
    let text = text.trim();
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => {
            u32::from_str_radix(hex, 16).unwrap_or_else(|_| panic!("not a hex number: {text}"))
        }
        None => text
            .parse()
            .unwrap_or_else(|_| panic!("not a number: {text}")),
    }
}

fn bytes(text: &str) -> Vec<u8> {
    text.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap_or_else(|_| panic!("not a hex byte: {b}")))
        .collect()
}

fn id(text: &str, extended: bool) -> CanId {
    if extended {
        CanId::Extended(num(text))
    } else {
        CanId::Standard(num(text) as u16)
    }
}

/// The identifier a step names: 29-bit when the value needs more than 11 bits.
fn id_of(cob: &str) -> CanId {
    id(cob, num(cob) > 0x7FF)
}

fn check(condition: bool, message: impl FnOnce() -> String) -> StepResult {
    if condition {
        Ok(())
    } else {
        Err(message())
    }
}

// ---------------------------------------------------------------- Given

#[given(regex = r"^the interface is set up for (11-bit|29-bit|CAN FD) messages with (\d+) slots$")]
fn interface(world: &mut CanWorld, format: String, slots: u32) {
    let format = match format.as_str() {
        "11-bit" => FrameFormat::Base11,
        "29-bit" => FrameFormat::Extended29,
        _ => FrameFormat::Fd,
    };
    let queue = world.config.queue;
    world.config = canif_model::config::InterfaceConfig::new(format, slots as u8);
    world.config.queue = queue;
}

#[given(regex = r"^the (Fast|Optimized) CAN Queue$")]
fn queue(world: &mut CanWorld, mode: String) {
    world.config.queue = if mode == "Fast" {
        QueueMode::Fast
    } else {
        QueueMode::Optimized
    };
}

#[given("transaction numbers are on")]
fn transaction_numbers(world: &mut CanWorld) {
    world.config.transaction_number = true;
}

#[given("time stamps are on")]
fn time_stamps(world: &mut CanWorld) {
    world.config.time_stamp = true;
}

#[given(regex = r"^the device profile (\S+)$")]
fn device_profile(world: &mut CanWorld, name: String) -> StepResult {
    let catalogue = canif_spec::Catalogue::embedded().map_err(|e| e.to_string())?;
    let profile = catalogue
        .profile(&name)
        .ok_or_else(|| format!("no profile {name}"))?;
    world.target.caps = profile.model_capabilities();
    world.target.profile = name;
    Ok(())
}

#[given(regex = r"^(\d+) Rx slots and (\d+) Tx slots$")]
fn slot_counts(world: &mut CanWorld, rx: u32, tx: u32) {
    world.config.rx_slots = rx as u8;
    world.config.tx_slots = tx as u8;
}

#[given("the filter table")]
fn filter_table(world: &mut CanWorld, step: &Step) {
    let table = step.table.as_ref().expect("a table under the step");
    world.config.filters = table
        .rows
        .iter()
        .skip(1)
        .map(|row| {
            let action = if row[0].trim() == "accept" {
                FilterAction::Accept
            } else {
                FilterAction::Reject
            };
            let matches = match row[1].trim() {
                "range" => FilterMatch::Range {
                    from: num(&row[2]),
                    to: num(&row[3]),
                },
                _ => FilterMatch::CodeMask {
                    code: num(&row[2]),
                    mask: num(&row[3]),
                },
            };
            FilterRow { action, matches }
        })
        .collect();
}

#[given(regex = r"^the local Rx queue holds (\d+) messages$")]
fn rx_queue_depth(world: &mut CanWorld, depth: usize) {
    world.target.caps.rx_queue_depth = depth;
}

#[given(regex = r"^the local send queue holds (\d+) messages$")]
fn tx_queue_depth(world: &mut CanWorld, depth: usize) {
    world.target.caps.tx_queue_depth = depth;
}

#[given("the bus is blocked")]
fn bus_blocked(world: &mut CanWorld) {
    world.bus_blocked = true;
}

#[given(regex = r"^distributed clocks with SYNC1 (\d+) µs after SYNC0$")]
fn distributed_clocks(world: &mut CanWorld, shift: u64) {
    world.config.synchronization = Synchronization::DistributedClocks {
        sync1_shift: shift * 1_000,
    };
}

#[given(regex = r"^the process data is exchanged with (LRW|separate input update)$")]
fn exchange(world: &mut CanWorld, mode: String) {
    world.exchange_mode = if mode == "LRW" {
        ExchangeMode::Lrw
    } else {
        ExchangeMode::SeparateInputUpdate
    };
}

#[given(
    regex = r"^the arbitration bit timing jump width (\d+), time A (\d+), time B (\d+), prescaler (\d+)$"
)]
fn bit_timing(world: &mut CanWorld, jump_width: u8, time_a: u8, time_b: u8, prescaler: u8) {
    world.config.nominal_timing = canif_model::info_data::BitTiming {
        jump_width,
        time_a,
        time_b,
        prescaler,
    };
}

// ---------------------------------------------------------------- When

#[when(regex = r"^the PLC sends (\d+) messages?$")]
fn plc_sends_n(world: &mut CanWorld, n: u32) -> StepResult {
    for i in 0..n {
        world.plc_sends(Frame::classic(CanId::Standard(0x100 + i as u16), &[i as u8]).unwrap())?;
    }
    Ok(())
}

#[when(regex = r"^the PLC sends (0x[0-9A-Fa-f]+) with data ?([0-9A-Fa-f ]*)$")]
fn plc_sends(world: &mut CanWorld, cob: String, data: String) -> StepResult {
    let frame = Frame::classic(id_of(&cob), &bytes(&data)).map_err(|e| e.to_string())?;
    world.plc_sends(frame)
}

#[when(regex = r"^the PLC sends the 29-bit (0x[0-9A-Fa-f]+) with data ?([0-9A-Fa-f ]*)$")]
fn plc_sends_extended(world: &mut CanWorld, cob: String, data: String) -> StepResult {
    world.plc_sends(Frame::classic(id(&cob, true), &bytes(&data)).map_err(|e| e.to_string())?)
}

#[when(regex = r"^the PLC sends a remote request for (0x[0-9A-Fa-f]+) with length (\d+)$")]
fn plc_sends_remote(world: &mut CanWorld, cob: String, len: u8) -> StepResult {
    world.plc_sends(Frame::remote(id_of(&cob), len).map_err(|e| e.to_string())?)
}

#[when(
    regex = r"^the PLC sends an FD message (0x[0-9A-Fa-f]+) with (\d+) bytes ?( ?with BRS)?( and ESI)?$"
)]
fn plc_sends_fd(
    world: &mut CanWorld,
    cob: String,
    len: u8,
    brs: String,
    esi: String,
) -> StepResult {
    let size = dlc::fd_round_up(len).ok_or("more than 64 bytes")?;
    let mut data: Vec<u8> = (0..len).map(|i| i ^ 0x5A).collect();
    data.resize(usize::from(size), 0);
    let frame = Frame::fd(id_of(&cob), !brs.is_empty(), !esi.is_empty(), &data)
        .map_err(|e| e.to_string())?;
    // The PLC gives the real byte count; the bytes past it are stale junk.
    world.declared_lengths.push((world.next_tn, len));
    world.plc_sends(frame)
}

#[when(regex = r"^the PLC writes Outputs.TxCounter = (\d+)$")]
fn plc_writes_tx_counter(world: &mut CanWorld, value: u32) {
    world.tx_counter_override = Some(value as u16);
}

#[when("a cycle passes")]
fn one_cycle(world: &mut CanWorld) -> StepResult {
    world.cycle(false)
}

#[when(regex = r"^(\d+) cycles pass$")]
fn cycles(world: &mut CanWorld, n: u32) -> StepResult {
    (0..n).try_for_each(|_| world.cycle(false))
}

#[when(regex = r"^the PLC is busy for (\d+) cycles?$")]
fn plc_busy(world: &mut CanWorld, n: u32) -> StepResult {
    (0..n).try_for_each(|_| world.cycle(true))
}

#[when(regex = r"^node (0x[0-9A-Fa-f]+) transmits (0x[0-9A-Fa-f]+) with data ?([0-9A-Fa-f ]*)$")]
fn node_transmits(world: &mut CanWorld, _node: String, cob: String, data: String) -> StepResult {
    world.node_sends(Frame::classic(id_of(&cob), &bytes(&data)).map_err(|e| e.to_string())?)
}

#[when(regex = r"^a node transmits the 29-bit (0x[0-9A-Fa-f]+) with data ?([0-9A-Fa-f ]*)$")]
fn node_transmits_extended(world: &mut CanWorld, cob: String, data: String) -> StepResult {
    world.node_sends(Frame::classic(id(&cob, true), &bytes(&data)).map_err(|e| e.to_string())?)
}

#[when(regex = r"^a node transmits a remote request for (0x[0-9A-Fa-f]+) with length (\d+)$")]
fn node_transmits_remote(world: &mut CanWorld, cob: String, len: u8) -> StepResult {
    world.node_sends(Frame::remote(id_of(&cob), len).map_err(|e| e.to_string())?)
}

#[when(
    regex = r"^a node transmits an FD frame (0x[0-9A-Fa-f]+) with (\d+) bytes ?( ?with BRS)?( ?(?:and|with) ESI)?$"
)]
fn node_transmits_fd(
    world: &mut CanWorld,
    cob: String,
    len: usize,
    brs: String,
    esi: String,
) -> StepResult {
    let data: Vec<u8> = (0..len).map(|i| (i as u8).wrapping_mul(3)).collect();
    world.node_sends(
        Frame::fd(id_of(&cob), !brs.is_empty(), !esi.is_empty(), &data)
            .map_err(|e| e.to_string())?,
    )
}

#[when(regex = r"^other nodes transmit (\d+) frames$")]
fn nodes_transmit(world: &mut CanWorld, n: u32) -> StepResult {
    for i in 0..n {
        let frame = Frame::classic(
            CanId::Standard(((world.sent_by_nodes.len() as u32) % 0x7FF) as u16 + 1),
            &[i as u8],
        )
        .unwrap();
        world.node_sends(frame)?;
    }
    Ok(())
}

#[when(regex = r"^a node transmits one frame in each of the next (\d+) cycles$")]
fn one_frame_per_cycle(world: &mut CanWorld, cycles: u32) -> StepResult {
    world.one_frame_per_cycle(cycles)
}

#[when("the bus is released")]
fn bus_released(world: &mut CanWorld) -> StepResult {
    world.bus_blocked = false;
    world.run_bus()
}

#[when(
    regex = r"^the controller reports (bus off|error passive|warning limit|bus idle) with (\d+) CRC errors and a transmit error counter of (\d+)$"
)]
fn controller_reports(world: &mut CanWorld, state: String, crc: u32, tec: u32) {
    world.status = Some(ControllerStatus {
        bus_off: state == "bus off",
        error_passive: state == "error passive",
        warning_limit: state == "warning limit",
        bus_idle: state == "bus idle",
        node_active: state != "bus off",
        crc_errors: crc,
        transmit_error_counter: tec,
        core_running: state != "bus off",
        ..ControllerStatus::default()
    });
}

#[when(regex = r"^the controller reports a transceiver delay of (\d+) time quanta$")]
fn transceiver_delay(world: &mut CanWorld, quanta: u32) {
    world.status = Some(ControllerStatus {
        transceiver_delay: quanta,
        node_active: true,
        core_running: true,
        ..ControllerStatus::default()
    });
}

// ---------------------------------------------------------------- Then

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
    check(u32::from(actual) == value, || {
        format!("Inputs.{field}: expected {value}, actual {actual}")
    })
}

#[then(regex = r"^the bus carries (0x[0-9A-Fa-f]+(?:, 0x[0-9A-Fa-f]+)*) in that order$")]
fn bus_carries(world: &mut CanWorld, ids: String) -> StepResult {
    let expected: Vec<u32> = ids.split(", ").map(num).collect();
    let actual: Vec<u32> = world.on_bus.iter().map(|f| f.id.raw()).collect();
    check(actual == expected, || {
        format!("on the bus: expected {expected:X?}, actual {actual:X?}")
    })
}

#[then(regex = r"^the bus carries (\d+) frames?$")]
fn bus_carries_n(world: &mut CanWorld, n: usize) -> StepResult {
    check(world.on_bus.len() == n, || {
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
    check(
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
    check(frame.id.is_extended() == (format == "extended"), || {
        format!("{frame} is not {format}")
    })?;
    if !remote.is_empty() {
        check(
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
    check(frame.len() == len && actual_dlc == Some(dlc_value), || {
        format!("{frame}: {} bytes, DLC {actual_dlc:?}", frame.len())
    })
}

#[then(regex = r"^the bytes after the first (\d+) are 00$")]
fn padding(world: &mut CanWorld, n: usize) -> StepResult {
    let frame = world.on_bus.last().ok_or("nothing on the bus")?;
    let data = frame.data();
    check(
        data[..n]
            .iter()
            .enumerate()
            .all(|(i, b)| *b == (i as u8) ^ 0x5A),
        || format!("data bytes changed: {frame}"),
    )?;
    check(data[n..].iter().all(|b| *b == 0), || {
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
    check(expected == actual, || {
        format!("{frame}: expected {expected:?} (BRS, ESI), actual {actual:?}")
    })
}

#[then(regex = r"^the PLC has received (\d+) messages?$")]
fn plc_received_n(world: &mut CanWorld, n: usize) -> StepResult {
    check(world.received.len() == n, || {
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
    check(actual == expected, || {
        format!("the PLC received {actual:X?}, expected {expected:X?}")
    })
}

#[then(regex = r"^the PLC has received (0x[0-9A-Fa-f]+) with data ?([0-9A-Fa-f ]*)$")]
fn plc_received_frame(world: &mut CanWorld, cob: String, data: String) -> StepResult {
    let wanted = bytes(&data);
    check(
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
    check(frame.id.is_extended() == (format == "extended"), || {
        format!("{frame} is not {format}")
    })?;
    if !remote.is_empty() {
        check(
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
    check(
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
        check(message.frame == *frame, || {
            format!("{} received for {}", message.frame, frame)
        })?;
        check(message.time_stamp.abs_diff(*end) <= tolerance, || {
            format!(
                "time stamp {} ns, reception ended at {end} ns",
                message.time_stamp
            )
        })?;
    }
    check(world.received.len() == world.sent_by_nodes.len(), || {
        "not every frame was received".into()
    })
}

#[then(regex = r"^Inputs\.RxMessage\[(\d+)\] begins with ([0-9A-Fa-f ]+)$")]
fn rx_message_bytes(world: &mut CanWorld, slot: usize, expected: String) -> StepResult {
    world.start()?;
    let range = world.layout().rx_slot(slot);
    let wanted = bytes(&expected);
    let actual = &world.inputs[range.start..range.start + wanted.len()];
    check(actual == wanted, || {
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
    world.start()?;
    let layout = world.layout();
    let actual = if before_info.is_empty() {
        world.inputs.len()
    } else {
        layout.info_data_start()
    };
    check(layout.output_size() == outputs && actual == inputs, || {
        format!(
            "output {} bytes, input {actual} bytes",
            layout.output_size()
        )
    })
}

#[then(regex = r"^the device (refuses|accepts) the configuration$")]
fn configuration(world: &mut CanWorld, verdict: String) -> StepResult {
    let result = world.start();
    check(result.is_ok() == (verdict == "accepts"), || {
        format!("expected the device to {verdict} it: {result:?}")
    })
}

#[then(regex = r"^InfoData\[(\d+)\] is (0x[0-9A-Fa-f]+|\d+)$")]
fn info_data(world: &mut CanWorld, index: usize, value: String) -> StepResult {
    let actual = world.input_image().info_data(index).ok_or("no InfoData")?;
    check(actual == num(&value), || {
        format!("InfoData[{index}] = 0x{actual:X}, expected {value}")
    })
}

#[then(regex = r"^the PLC saw the confirmation (\d+) cycles? after its increment$")]
fn confirmation(world: &mut CanWorld, cycles: u64) -> StepResult {
    check(world.confirmation_delay == Some(cycles), || {
        format!("confirmation after {:?} cycles", world.confirmation_delay)
    })
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
    // 003: the first Tx message starts at SYNC1 with a jitter of at most 500 ns.
    check(
        offset.abs_diff(micros * 1_000) <= canif_model::exchange::SYNC1_TX_JITTER,
        || format!("the first frame started {offset} ns after the cycle began, not {micros} µs"),
    )
}

// ------------------------------------------------------- the model's tables

#[then(regex = r"^DLC (\d+) means (\d+) data bytes$")]
fn dlc_means(_world: &mut CanWorld, code: u8, len: u8) -> StepResult {
    check(dlc::fd_data_size(code) == Some(len), || {
        format!("DLC {code} means {:?} bytes", dlc::fd_data_size(code))
    })
}

#[then(regex = r"^a length of (\d+) is sent as (\d+) bytes with DLC (\d+)$")]
fn length_rounds(_world: &mut CanWorld, len: u8, size: u8, code: u8) -> StepResult {
    let actual = (dlc::fd_round_up(len), dlc::fd_dlc_for_length(len));
    check(actual == (Some(size), Some(code)), || {
        format!("length {len}: sent as {actual:?}")
    })
}

#[then(
    regex = r"^(\d+) data bytes at (\d+) kbit/s, printed as ([0-9.]+) ms, lie between the nominal and the worst-case frame time$"
)]
fn cia_cell(_world: &mut CanWorld, len: u8, kbit: u32, printed: String) -> StepResult {
    let printed_ns = (printed.parse::<f64>().map_err(|e| e.to_string())? * 1e6).round() as u64;
    let cell = cia_table::Cell {
        bitrate: kbit * 1000,
        data_len: len,
        printed: printed_ns,
    };
    let BitCount {
        nominal,
        worst_case,
    } = classic_bits(false, len);
    check(cia_table::within_model_bounds(&cell), || {
        format!("{printed} ms is outside {nominal}..{worst_case} bits at {kbit} kbit/s")
    })
}

#[then(regex = r"^the cell for (\d+) bytes at (\d+) kbit/s is (flagged|consistent)$")]
fn cia_flag(_world: &mut CanWorld, len: u8, kbit: u32, verdict: String) -> StepResult {
    let flagged = cia_table::inconsistent_cells()
        .iter()
        .any(|c| c.data_len == len && c.bitrate == kbit * 1000);
    check(flagged == (verdict == "flagged"), || {
        format!("the cell is flagged: {flagged}")
    })
}

#[then(regex = r"^at (\d+) kbit/s with (\d+)-byte frames a (\d+) µs cycle needs (\d+) slots$")]
fn sizing_example(
    _world: &mut CanWorld,
    kbit: u32,
    payload: u8,
    cycle_us: u64,
    slots: u64,
) -> StepResult {
    let sizing = sizing::recommend(kbit * 1000, cycle_us * 1000, payload).ok_or("no sizing")?;
    check(sizing.slots == slots, || {
        format!(
            "{} slots ({:?}, frame time {} ns)",
            sizing.slots, sizing.basis, sizing.frame_time
        )
    })
}

/// The NMT state a step names (its regex allows only these three).
fn nmt_state_named(name: &str) -> NmtState {
    match name {
        "operational" => NmtState::Operational,
        "pre-operational" => NmtState::PreOperational,
        _ => NmtState::Stopped,
    }
}

fn nmt_command(name: &str) -> NmtCommand {
    match name {
        "start" => NmtCommand::StartRemoteNode,
        "stop" => NmtCommand::StopRemoteNode,
        "enter pre-operational" => NmtCommand::EnterPreOperational,
        "reset node" => NmtCommand::ResetNode,
        _ => NmtCommand::ResetCommunication,
    }
}

#[then(
    regex = r"^the NMT command (start|stop|enter pre-operational|reset node|reset communication) for (all nodes|node \d+) is 0x000 with data ([0-9A-Fa-f ]+)$"
)]
fn nmt_telegram(
    _world: &mut CanWorld,
    command: String,
    target: String,
    data: String,
) -> StepResult {
    let node = target
        .strip_prefix("node ")
        .map(|n| NodeId::new(num(n) as u8).expect("node 1..63"));
    let frame = nmt::command_frame(nmt_command(&command), node);
    check(
        frame.id == CanId::Standard(0) && frame.data() == bytes(&data),
        || format!("the telegram is {frame}"),
    )
}

#[then(
    regex = r"^a node in state (pre-operational|operational|stopped) that receives (start|stop|enter pre-operational|reset node|reset communication) is (pre-operational|operational|stopped) and guarding reports (0x[0-9A-Fa-f]+)$"
)]
fn nmt_state(
    _world: &mut CanWorld,
    from: String,
    command: String,
    to: String,
    code: String,
) -> StepResult {
    let after = nmt_state_named(&from).apply(nmt_command(&command));
    check(
        after == nmt_state_named(&to) && u32::from(after.code()) == num(&code),
        || format!("the node is {after:?} (0x{:02X})", after.code()),
    )
}

fn channel(name: &str) -> Channel {
    match name {
        "digital inputs" => Channel::DigitalInputs,
        "digital outputs" => Channel::DigitalOutputs,
        "analog inputs 1-4" => Channel::AnalogInputs1To4,
        "analog outputs 1-4" => Channel::AnalogOutputs1To4,
        "analog inputs 5-8" => Channel::AnalogInputs5To8,
        "analog outputs 5-8" => Channel::AnalogOutputs5To8,
        "analog inputs 9-12" => Channel::AnalogInputs9To12,
        "analog outputs 9-12" => Channel::AnalogOutputs9To12,
        "SDO requests" => Channel::SdoRequest,
        "SDO responses" => Channel::SdoResponse,
        _ => Channel::ErrorControl,
    }
}

#[then(regex = r"^the default identifier of (.+) for node (\d+) is (0x[0-9A-Fa-f]+)$")]
fn default_identifier(
    _world: &mut CanWorld,
    name: String,
    node: u8,
    expected: String,
) -> StepResult {
    let actual = default_cob_id(channel(&name), NodeId::new(node).ok_or("node 1..63")?);
    check(u32::from(actual) == num(&expected), || {
        format!("0x{actual:03X}")
    })
}

#[then(
    regex = r"^an expedited (upload response|download request) of (\d+) bytes? starts with (0x[0-9A-Fa-f]+)$"
)]
fn sdo_command(_world: &mut CanWorld, kind: String, n: u8, command: String) -> StepResult {
    let first = if kind == "upload response" {
        SdoResponse::Upload {
            index: 0x1000,
            sub_index: 0,
            data: [0; 4],
            size: n,
        }
        .to_bytes()[0]
    } else {
        SdoRequest::Download {
            index: 0x1000,
            sub_index: 0,
            data: [0; 4],
            size: Some(n),
        }
        .to_bytes()[0]
    };
    check(u32::from(first) == num(&command), || {
        format!("0x{first:02X}")
    })
}

#[then(
    regex = r"^writing (0x[0-9A-Fa-f]+):(\d+) = (0x[0-9A-Fa-f]+) to node (\d+) is (0x[0-9A-Fa-f]+) with data ([0-9A-Fa-f ]+)$"
)]
fn sdo_download(
    _world: &mut CanWorld,
    index: String,
    sub: u8,
    value: String,
    node: u8,
    cob: String,
    data: String,
) -> StepResult {
    let request = SdoRequest::Download {
        index: num(&index) as u16,
        sub_index: sub,
        data: num(&value).to_le_bytes(),
        size: None,
    };
    let id = default_cob_id(Channel::SdoRequest, NodeId::new(node).ok_or("node")?);
    check(
        u32::from(id) == num(&cob) && request.to_bytes().to_vec() == bytes(&data),
        || format!("0x{id:03X} with {}", hex(&request.to_bytes())),
    )
}

#[then(regex = r"^the answer confirming it is ([0-9A-Fa-f ]+)$")]
fn sdo_confirmation(_world: &mut CanWorld, data: String) -> StepResult {
    let answer = bytes(&data);
    check(
        matches!(
            SdoResponse::parse(&answer),
            Ok(SdoResponse::DownloadAck { .. })
        ),
        || format!("{data} is no download response"),
    )
}

#[then(
    regex = r"^aborting (0x[0-9A-Fa-f]+):(\d+) because the (object|sub-index) does not exist is ([0-9A-Fa-f ]+)$"
)]
fn sdo_abort(
    _world: &mut CanWorld,
    index: String,
    sub: u8,
    what: String,
    data: String,
) -> StepResult {
    let code = if what == "object" {
        abort_code::OBJECT_DOES_NOT_EXIST
    } else {
        abort_code::SUB_INDEX_DOES_NOT_EXIST
    };
    let abort = SdoResponse::Abort {
        index: num(&index) as u16,
        sub_index: sub,
        code,
    };
    check(abort.to_bytes().to_vec() == bytes(&data), || {
        hex(&abort.to_bytes())
    })
}

#[then(
    regex = r"^node (\d+) answers (\d+) guarding requests in state (operational|pre-operational|stopped) with ([0-9A-Fa-f ]+)$"
)]
fn guarding(
    _world: &mut CanWorld,
    node: u8,
    n: usize,
    state: String,
    answers: String,
) -> StepResult {
    let state = nmt_state_named(&state);
    let node = NodeId::new(node).ok_or("node")?;
    let mut responder = GuardResponder::default();
    let actual: Vec<u8> = (0..n)
        .map(|_| responder.respond(node, state).data()[0])
        .collect();
    check(actual == bytes(&answers), || hex(&actual))
}

#[then(regex = r"^setting the heartbeat to (0x[0-9A-Fa-f]+) ms is the SDO ([0-9A-Fa-f ]+)$")]
fn heartbeat_sdo(_world: &mut CanWorld, period: String, data: String) -> StepResult {
    let actual = heartbeat::set_producer_time(num(&period) as u16).to_bytes();
    check(actual.to_vec() == bytes(&data), || hex(&actual))
}

#[then(
    regex = r"^node (\d+) in state (operational|pre-operational|stopped) beats (0x[0-9A-Fa-f]+) with data ([0-9A-Fa-f ]+)$"
)]
fn heartbeat_frame(
    _world: &mut CanWorld,
    node: u8,
    state: String,
    cob: String,
    data: String,
) -> StepResult {
    let state = nmt_state_named(&state);
    let frame = heartbeat::heartbeat(NodeId::new(node).ok_or("node")?, state);
    check(
        frame.id.raw() == num(&cob) && frame.data() == bytes(&data),
        || frame.to_string(),
    )
}

#[then(
    regex = r"^a CAN FD frame of (\d+) bytes at (\d+)/(\d+) kbit/s takes ([0-9.]+) µs with BRS and ([0-9.]+) µs without, not counting stuff bits$"
)]
fn fd_duration(
    _world: &mut CanWorld,
    len: usize,
    nominal: u32,
    data: u32,
    with_brs: f64,
    without: f64,
) -> StepResult {
    use canif_model::timing::{frame_duration, BitRates, Stuffing};
    let rates = BitRates {
        nominal: nominal * 1000,
        data: data * 1000,
    };
    let frame = |brs| {
        Frame::fd(CanId::Standard(0x123), brs, false, &vec![0; len]).map_err(|e| e.to_string())
    };
    let switched = frame_duration(&frame(true)?, rates, Stuffing::Nominal) as f64 / 1000.0;
    let plain = frame_duration(&frame(false)?, rates, Stuffing::Nominal) as f64 / 1000.0;
    check(
        (switched - with_brs).abs() < 0.01 && (plain - without).abs() < 0.01,
        || format!("{switched} µs with BRS, {plain} µs without"),
    )
}

#[then(
    regex = r"^a guarding answer (0x[0-9A-Fa-f]+) after (0x[0-9A-Fa-f]+) is (accepted|a toggle error)$"
)]
fn guarding_toggle(
    _world: &mut CanWorld,
    second: String,
    first: String,
    verdict: String,
) -> StepResult {
    let mut checker = canif_model::canopen::guarding::GuardChecker::default();
    let answer =
        |byte: String| Frame::classic(CanId::Standard(0x703), &[num(&byte) as u8]).expect("1 byte");
    checker.check(&answer(first))?;
    let result = checker.check(&answer(second));
    check(result.is_ok() == (verdict == "accepted"), || {
        format!("the checker says {result:?}")
    })
}

#[then(
    regex = r"^a guard time of (\d+) ms with life time factor (\d+) gives (a reaction time of (\d+) ms|no life guarding)$"
)]
fn life_time(
    _world: &mut CanWorld,
    guard: u16,
    factor: u8,
    _text: String,
    ms: String,
) -> StepResult {
    let actual = canif_model::canopen::guarding::life_time(guard, factor);
    let expected = if ms.is_empty() {
        None
    } else {
        Some(u64::from(num(&ms)) * 1_000_000)
    };
    check(actual == expected, || format!("{actual:?} ns"))
}

#[then(
    regex = r"^with a producer time of (\d+) ms a heartbeat sent at (\d+) ms is followed (at (\d+) ms|by none)$"
)]
fn heartbeat_period(
    _world: &mut CanWorld,
    period: u16,
    sent: u64,
    _text: String,
    next: String,
) -> StepResult {
    let actual = heartbeat::next_due(sent * 1_000_000, period);
    let expected = if next.is_empty() {
        None
    } else {
        Some(u64::from(num(&next)) * 1_000_000)
    };
    check(actual == expected, || format!("{actual:?} ns"))
}

#[then(regex = r"^the analog PDO of the channel values (-?\d+) and (-?\d+) is ([0-9A-Fa-f ]+)$")]
fn analog_pdo(_world: &mut CanWorld, first: i16, second: i16, data: String) -> StepResult {
    let payload = canif_model::canopen::pdo::analog_payload(&[first, second]);
    check(payload == bytes(&data), || hex(&payload))
}

#[then(regex = r"^a digital PDO of (\d+) bytes is (valid|invalid)$")]
fn digital_pdo(_world: &mut CanWorld, n: usize, verdict: String) -> StepResult {
    let valid = canif_model::canopen::pdo::digital_payload(&vec![0; n]).is_some();
    check(valid == (verdict == "valid"), || {
        format!("{n} bytes valid: {valid}")
    })
}

#[then(
    regex = r"^uploading (0x[0-9A-Fa-f]+):(\d+) = (\d+) as Unsigned(8|16|32) is ([0-9A-Fa-f ]+)$"
)]
fn sdo_upload(
    _world: &mut CanWorld,
    index: String,
    sub: u8,
    value: u32,
    bits: u32,
    data: String,
) -> StepResult {
    let response = SdoResponse::Upload {
        index: num(&index) as u16,
        sub_index: sub,
        data: value.to_le_bytes(),
        size: (bits / 8) as u8,
    };
    check(response.to_bytes().to_vec() == bytes(&data), || {
        hex(&response.to_bytes())
    })
}

#[then(
    regex = r"^reading (0x[0-9A-Fa-f]+):(\d+) from node (\d+) is (0x[0-9A-Fa-f]+) with data ([0-9A-Fa-f ]+)$"
)]
fn sdo_upload_request(
    _world: &mut CanWorld,
    index: String,
    sub: u8,
    node: u8,
    cob: String,
    data: String,
) -> StepResult {
    let request = SdoRequest::Upload {
        index: num(&index) as u16,
        sub_index: sub,
    };
    let id = default_cob_id(Channel::SdoRequest, NodeId::new(node).ok_or("node")?);
    check(
        u32::from(id) == num(&cob) && request.to_bytes().to_vec() == bytes(&data),
        || format!("0x{id:03X} with {}", hex(&request.to_bytes())),
    )
}

// ------------------------------------------- CANopen through the CAN interface

#[given(regex = r"^the profile's CAN interface with (\d+) slots$")]
fn profile_interface(world: &mut CanWorld, slots: u8) {
    let caps = &world.target.caps;
    world.config = canif_model::config::InterfaceConfig::new(caps.first_format(), slots);
}

#[given(regex = r"^a Beckhoff bus coupler with node id (\d+) on the bus$")]
fn coupler_on_bus(world: &mut CanWorld, node: u8) -> StepResult {
    let node = NodeId::new(node).ok_or("node ids are 1..63")?;
    world.coupler = Some(canif_model::canopen::coupler::Coupler::new(node, 2, 4));
    Ok(())
}

fn coupler_node(world: &CanWorld) -> Result<NodeId, String> {
    world
        .coupler
        .as_ref()
        .map(|c| c.node())
        .ok_or_else(|| "no coupler on the bus".into())
}

#[when(
    regex = r"^the PLC sends the NMT command (start|stop|enter pre-operational|reset node|reset communication) to (all nodes|the coupler)$"
)]
fn plc_nmt(world: &mut CanWorld, command: String, target: String) -> StepResult {
    let node = if target == "all nodes" {
        None
    } else {
        Some(coupler_node(world)?)
    };
    world.plc_sends(nmt::command_frame(nmt_command(&command), node))
}

#[when(regex = r"^the PLC writes (0x[0-9A-Fa-f]+):(\d+) = (\d+) to the coupler by SDO$")]
fn plc_sdo_download(world: &mut CanWorld, index: String, sub: u8, value: u32) -> StepResult {
    let node = coupler_node(world)?;
    let request = SdoRequest::Download {
        index: num(&index) as u16,
        sub_index: sub,
        data: value.to_le_bytes(),
        size: None,
    };
    world.plc_sends(
        Frame::classic(
            CanId::Standard(default_cob_id(Channel::SdoRequest, node)),
            &request.to_bytes(),
        )
        .expect("8 bytes"),
    )
}

#[when(regex = r"^the PLC reads (0x[0-9A-Fa-f]+):(\d+) from the coupler by SDO$")]
fn plc_sdo_upload(world: &mut CanWorld, index: String, sub: u8) -> StepResult {
    let node = coupler_node(world)?;
    let request = SdoRequest::Upload {
        index: num(&index) as u16,
        sub_index: sub,
    };
    world.plc_sends(
        Frame::classic(
            CanId::Standard(default_cob_id(Channel::SdoRequest, node)),
            &request.to_bytes(),
        )
        .expect("8 bytes"),
    )
}

#[when("the PLC guards the coupler")]
fn plc_guards(world: &mut CanWorld) -> StepResult {
    let node = coupler_node(world)?;
    world.plc_sends(canif_model::canopen::guarding::request(node))
}

#[when("the PLC requests the analog inputs")]
fn plc_requests_analog(world: &mut CanWorld) -> StepResult {
    let node = coupler_node(world)?;
    world.plc_sends(
        Frame::remote(
            CanId::Standard(default_cob_id(Channel::AnalogInputs1To4, node)),
            8,
        )
        .expect("rtr"),
    )
}

#[when(regex = r"^digital input byte (\d+) of the coupler becomes (0x[0-9A-Fa-f]+)$")]
fn coupler_digital(world: &mut CanWorld, byte: usize, value: String) -> StepResult {
    world.start()?;
    let frames = world
        .coupler
        .as_mut()
        .ok_or("no coupler")?
        .set_digital_input(byte, num(&value) as u8);
    world.coupler_sends(frames)
}

#[when(regex = r"^analog input (\d+) of the coupler becomes (-?\d+)$")]
fn coupler_analog(world: &mut CanWorld, channel: usize, value: i16) -> StepResult {
    world.start()?;
    let frames = world
        .coupler
        .as_mut()
        .ok_or("no coupler")?
        .set_analog_input(channel, value);
    world.coupler_sends(frames)
}

#[when("the coupler fails")]
fn coupler_fails(world: &mut CanWorld) {
    world.coupler_alive = false;
    world.coupler_failed_at = Some(world.now);
}

#[then(regex = r"^the PLC has received the SDO answer ([0-9A-Fa-f ]+)$")]
fn plc_sdo_answer(world: &mut CanWorld, data: String) -> StepResult {
    let node = coupler_node(world)?;
    let id = default_cob_id(Channel::SdoResponse, node);
    let wanted = bytes(&data);
    check(
        world
            .received
            .iter()
            .any(|m| m.frame.id == CanId::Standard(id) && m.frame.data() == wanted),
        || {
            format!(
                "no answer {} on 0x{id:03X} among {:?}",
                hex(&wanted),
                world.received.iter().map(|m| m.frame).collect::<Vec<_>>()
            )
        },
    )
}

#[then(regex = r"^the last guarding answer says (operational|pre-operational|stopped)$")]
fn guarding_answer(world: &mut CanWorld, state: String) -> StepResult {
    let node = coupler_node(world)?;
    let id = CanId::Standard(default_cob_id(Channel::ErrorControl, node));
    let answer = world
        .received
        .iter()
        .rev()
        .find(|m| m.frame.id == id && m.frame.data().len() == 1)
        .ok_or("no guarding answer received")?;
    let wanted = nmt_state_named(&state);
    check(answer.frame.data()[0] & 0x7F == wanted.code(), || {
        format!("status byte 0x{:02X}", answer.frame.data()[0])
    })
}

/// Heartbeats the PLC received from the coupler, with the cycle time it read them.
fn heartbeats(world: &CanWorld) -> Result<Vec<Nanos>, String> {
    let id = CanId::Standard(default_cob_id(Channel::ErrorControl, coupler_node(world)?));
    Ok(world
        .received_at
        .iter()
        .filter(|(_, f)| f.id == id && !f.is_remote())
        .map(|(at, _)| *at)
        .collect())
}

#[then(regex = r"^the PLC receives a heartbeat every (\d+) ms$")]
fn heartbeat_every(world: &mut CanWorld, period: u64) -> StepResult {
    let times = heartbeats(world)?;
    let gaps: Vec<u64> = times
        .windows(2)
        .map(|w| (w[1] - w[0]) / 1_000_000)
        .collect();
    check(
        gaps.len() >= 3 && gaps.iter().all(|g| g.abs_diff(period) <= 2),
        || format!("heartbeat gaps {gaps:?} ms"),
    )
}

/// Covers the master's view (HB-004): no heartbeat for twice the producer time.
#[then(
    regex = r"^by heartbeat the PLC notices the coupler's loss within (\d+) ms of (\d+) ms heartbeats$"
)]
fn heartbeat_loss(world: &mut CanWorld, within: u64, period: u64) -> StepResult {
    let failed = world
        .coupler_failed_at
        .ok_or("the coupler has not failed")?;
    let last = heartbeats(world)?
        .into_iter()
        .filter(|t| *t <= failed + 2_000_000)
        .max()
        .ok_or("no heartbeat before the failure")?;
    // The master's rule: lost when no heartbeat for twice the producer time.
    let noticed = last + 2 * period * 1_000_000;
    let late = heartbeats(world)?
        .into_iter()
        .any(|t| t > failed + 2_000_000);
    check(
        !late && noticed.saturating_sub(failed) <= within * 1_000_000,
        || {
            format!(
                "last heartbeat at {} ms, noticed at {} ms, failure at {} ms",
                last / 1_000_000,
                noticed / 1_000_000,
                failed / 1_000_000
            )
        },
    )
}

#[then("by guarding the PLC notices the coupler's loss at the next request")]
fn guarding_loss(world: &mut CanWorld) -> StepResult {
    let failed = world
        .coupler_failed_at
        .ok_or("the coupler has not failed")?;
    let node = coupler_node(world)?;
    let id = CanId::Standard(default_cob_id(Channel::ErrorControl, node));
    let answered_after = world
        .received_at
        .iter()
        .any(|(at, f)| *at > failed + 2_000_000 && f.id == id);
    let asked_after = world
        .on_bus
        .iter()
        .filter(|f| f.id == id && f.is_remote())
        .count()
        >= 2;
    check(asked_after && !answered_after, || {
        format!("asked again: {asked_after}, answered after the failure: {answered_after}")
    })
}
