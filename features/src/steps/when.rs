//! What the PLC and the other nodes do.

use canif_model::dlc;
use canif_model::frame::{CanId, Frame};
use canif_model::info_data::ControllerStatus;
use cucumber::when;

use crate::world::CanWorld;

use super::{bytes, id, id_of, StepResult};

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
            CanId::Standard(((world.frames_from_nodes() as u32) % 0x7FF) as u16 + 1),
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
    world.release_bus()
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
