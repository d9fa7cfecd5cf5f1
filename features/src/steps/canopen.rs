//! CANopen over the CAN interface (002, 004): telegrams and the node.

use canif_harness::device::diff::hex;
use canif_model::canopen::cob_id::{default_cob_id, Channel};
use canif_model::canopen::guarding::GuardResponder;
use canif_model::canopen::heartbeat;
use canif_model::canopen::nmt::{self, NmtCommand, NmtState};
use canif_model::canopen::sdo::{abort_code, SdoRequest, SdoResponse};
use canif_model::canopen::NodeId;
use canif_model::frame::{CanId, Frame};
use canif_model::Nanos;
use cucumber::{given, then, when};

use crate::world::CanWorld;

use super::{bytes, check, num, StepResult};

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
    let request = SdoRequest::download(num(&index) as u16, sub, num(&value));
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
    let response = SdoResponse::upload(num(&index) as u16, sub, value, (bits / 8) as u8);
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
    world.put_coupler(crate::bus_coupler::BusCoupler::new(node));
    Ok(())
}

fn coupler_node(world: &CanWorld) -> Result<NodeId, String> {
    world
        .coupler
        .as_ref()
        .map(crate::bus_coupler::BusCoupler::node)
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
    let request = SdoRequest::download(num(&index) as u16, sub, value);
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
        .as_ref()
        .ok_or("no coupler")?
        .set_digital_input(byte, num(&value) as u8);
    world.coupler_sends(frames)
}

#[when(regex = r"^analog input (\d+) of the coupler becomes (-?\d+)$")]
fn coupler_analog(world: &mut CanWorld, channel: usize, value: i16) -> StepResult {
    world.start()?;
    let frames = world
        .coupler
        .as_ref()
        .ok_or("no coupler")?
        .set_analog_input(channel, value);
    world.coupler_sends(frames)
}

#[when("the coupler fails")]
fn coupler_fails(world: &mut CanWorld) {
    world.coupler_fails();
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
