//! The documents' tables: DLC, the CiA frame times, buffer sizing.

use canif_model::cia_table;
use canif_model::dlc;
use canif_model::sizing;
use canif_model::timing::{classic_bits, BitCount};
use cucumber::then;

use crate::world::CanWorld;

use super::{check, StepResult};

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
    let sizing = sizing::manual_figure(kbit * 1000, cycle_us * 1000, payload).ok_or("no sizing")?;
    check(sizing.slots == slots, || {
        format!(
            "{} slots ({:?}, frame time {} ns)",
            sizing.slots, sizing.basis, sizing.frame_time
        )
    })
}

#[then(
    regex = r"^at (\d+) kbit/s with (\d+)-byte frames the advisor recommends (\d+) slots for a (\d+) µs cycle$"
)]
fn safe_sizing(
    _world: &mut CanWorld,
    kbit: u32,
    payload: u8,
    slots: u64,
    cycle_us: u64,
) -> StepResult {
    let advice = sizing::advise(kbit * 1000, cycle_us * 1000, payload).ok_or("no sizing")?;
    let recommended = advice.recommended();
    check(recommended.slots == slots, || {
        format!(
            "{} slots ({:?}, frame time {} ns)",
            recommended.slots, recommended.basis, recommended.frame_time
        )
    })
}
