//! The PLC side's steps: the client under test, the master, the application
//! and the device around it (docs/plc-side.md).

use canif_harness::client::application::Event;
use canif_harness::client::master::Master;
use canif_harness::Outcome;
use canif_model::config::{FrameFormat, QueueMode};
use canif_spec::req_ids;
use cucumber::{given, then, when};

use super::{check_as, StepResult};
use crate::client_world::ClientWorld;

fn format(text: &str) -> FrameFormat {
    match text {
        "11-bit" => FrameFormat::Base11,
        "29-bit" => FrameFormat::Extended29,
        _ => FrameFormat::Fd,
    }
}

#[given(
    regex = r"^the client's interface is set up for (11-bit|29-bit|CAN FD) messages with (\d+) slots$"
)]
fn set_up(world: &mut ClientWorld, text: String, slots: u8) {
    world.set_up(format(&text), QueueMode::Standard, slots);
}

#[given(regex = r"^the client's interface uses the Fast CAN Queue with (\d+) slots$")]
fn fast_queue(world: &mut ClientWorld, slots: u8) {
    let format = world.config.format;
    world.set_up(format, QueueMode::Fast, slots);
}

#[given(regex = r#"^the master is "([a-z-]+)"$"#)]
fn master(world: &mut ClientWorld, name: String) -> StepResult {
    world.master = Master::by_name(&name).ok_or(format!("no master model {name}"))?;
    Ok(())
}

#[when(regex = r"^the application asks the client to send (\d+) messages?$")]
fn application_sends(world: &mut ClientWorld, n: u32) {
    world.application_sends(n);
}

#[when(regex = r"^other nodes send (\d+) frames?$")]
fn nodes_send(world: &mut ClientWorld, n: u32) {
    world.nodes_send(n);
}

#[when(regex = r"^(\d+) cycles? pass(?:es)?$")]
fn cycles_pass(world: &mut ClientWorld, n: u64) {
    world.cycle += n;
}

#[when("the PLC restarts")]
fn plc_restarts(world: &mut ClientWorld) {
    world.at_this_cycle(Event::PlcRestart);
}

#[when("the device restarts")]
fn device_restarts(world: &mut ClientWorld) {
    world.at_this_cycle(Event::DeviceRestart);
}

#[when("the device reports NoOfRxMessages 65535 with its next batch")]
fn overstated(world: &mut ClientWorld) {
    world.at_this_cycle(Event::OverstateRxCount);
}

#[then("the client broke no requirement in any task")]
fn no_breach(world: &mut ClientWorld) -> StepResult {
    let (run, _) = world.run();
    match &run.outcome {
        Outcome::Pass => Ok(()),
        Outcome::Fail(failure) => {
            let ids: Vec<_> = failure.requirements.clone();
            crate::world::record_witness(&[&ids]);
            Err(failure.details())
        }
        Outcome::Error(error) => {
            crate::world::record_iut_error(&error.to_string());
            Err(error.to_string())
        }
    }
}

#[then("the bus carries every message the application asked for, once and in order")]
fn bus_carries(world: &mut ClientWorld) -> StepResult {
    let asked = world.asked.clone();
    let (_, record) = world.run();
    check_as(&[req_ids!["CL-TX-003"]], record.sent == asked, || {
        format!("asked {asked:?}, the bus carried {:?}", record.sent)
    })
}

#[then("the application received every frame the other nodes sent, once and in order")]
fn application_received(world: &mut ClientWorld) -> StepResult {
    let arrived = world.arrived.clone();
    let (_, record) = world.run();
    let received: Vec<_> = record.delivered.iter().map(|m| m.frame).collect();
    check_as(&[req_ids!["CL-RX-002"]], received == arrived, || {
        format!("the nodes sent {arrived:?}, the application received {received:?}")
    })
}

#[then(
    regex = r"^the application received every frame the other nodes sent, and at most (\d+) twice$"
)]
fn application_received_again(world: &mut ClientWorld, most: usize) -> StepResult {
    let arrived = world.arrived.clone();
    let (_, record) = world.run();
    let received: Vec<_> = record.delivered.iter().map(|m| m.frame).collect();
    let distinct: std::collections::BTreeSet<String> =
        received.iter().map(|f| f.to_string()).collect();
    let repeated = received.len() - distinct.len();
    let all = arrived.iter().all(|f| received.contains(f));
    check_as(&[req_ids!["CL-RST-001"]], all && repeated <= most, || {
        format!("{repeated} frames delivered twice (at most {most}); all delivered: {all}")
    })
}
