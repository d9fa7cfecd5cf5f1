//! The situation a scenario starts from: the interface, the device, the bus.

use canif_model::config::{FrameFormat, QueueMode, Synchronization};
use canif_model::exchange::ExchangeMode;
use canif_model::filter::{FilterAction, FilterMatch, FilterRow};
use cucumber::gherkin::Step;
use cucumber::given;

use crate::world::CanWorld;

use super::{num, StepResult};

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
