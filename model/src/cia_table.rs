//! The frame-time table of 000/001 §4 ("Daten von CiA"), held as data.
//!
//! Source: 000 §4 "Tabelle für die Telegrammlaufzeiten bei 11 Bit Ident \[ms\]",
//! ruling R3: informative; the model's worst case bounds every cell, and the
//! 50 kbit/s, 7-byte cell (2.34) breaks its row (2.43 fits).

use crate::timing::{bits_duration, classic_bits};
use crate::Nanos;

/// The table's bit rates in bit/s, one row each.
pub const BIT_RATES: [u32; 5] = [50_000, 125_000, 250_000, 500_000, 1_000_000];

/// Cells in hundredths of a millisecond (10 µs), as printed; row by bit rate,
/// column by data length 0..=8.
///
/// Requirements: TIM-004.
pub const PRINTED: [[u32; 9]; 5] = [
    [109, 128, 147, 166, 186, 205, 224, 234, 262],
    [44, 51, 59, 67, 74, 82, 90, 97, 105],
    [22, 26, 29, 33, 37, 41, 45, 49, 52],
    [11, 13, 15, 17, 19, 21, 22, 24, 26],
    [5, 6, 7, 8, 9, 10, 11, 12, 13],
];

/// The printed cell that ruling R3 flags, and the value that fits its row.
pub const FLAGGED_CELL: (u32, u8, u32) = (50_000, 7, 243);

/// One cell of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cell {
    pub bitrate: u32,
    pub data_len: u8,
    /// As printed, in nanoseconds.
    pub printed: Nanos,
}

/// Every cell as printed.
pub fn cells() -> impl Iterator<Item = Cell> {
    BIT_RATES
        .iter()
        .zip(PRINTED.iter())
        .flat_map(|(&bitrate, row)| {
            row.iter().enumerate().map(move |(len, &hundredths)| Cell {
                bitrate,
                data_len: len as u8,
                printed: Nanos::from(hundredths) * 10_000,
            })
        })
}

/// The frame time the manual uses for buffer sizing: the cell, with the flagged
/// cell corrected (R3). `None` outside the table.
///
/// Requirements: TIM-004, ERR-R3.
pub fn frame_time(bitrate: u32, data_len: u8) -> Option<Nanos> {
    let row = BIT_RATES.iter().position(|&rate| rate == bitrate)?;
    let hundredths = *PRINTED[row].get(usize::from(data_len))?;
    let hundredths = if (bitrate, data_len) == (FLAGGED_CELL.0, FLAGGED_CELL.1) {
        FLAGGED_CELL.2
    } else {
        hundredths
    };
    Some(Nanos::from(hundredths) * 10_000)
}

/// Half a printed unit: the rounding of a cell.
pub const ROUNDING: Nanos = 5_000;

/// Is a printed cell within [nominal, worst case] of the bit model, allowing for
/// the table's rounding to 0.01 ms?
///
/// Requirements: TIM-005, ERR-R3.
pub fn within_model_bounds(cell: &Cell) -> bool {
    let bits = classic_bits(false, cell.data_len);
    let nominal = bits_duration(bits.nominal, cell.bitrate);
    let worst = bits_duration(bits.worst_case, cell.bitrate);
    cell.printed + ROUNDING >= nominal && cell.printed <= worst + ROUNDING
}

/// Interior cells that break their row: further from the mean of their two
/// neighbours than the table's rounding (three cells' worth) plus two bit times
/// (the stuff bits' step) can explain.
///
/// Requirements: TIM-006, ERR-R3.
pub fn inconsistent_cells() -> Vec<Cell> {
    let all: Vec<Cell> = cells().collect();
    all.windows(3)
        .filter(|w| w[0].bitrate == w[2].bitrate)
        .filter(|w| {
            let mean_twice = w[0].printed + w[2].printed;
            let deviation_twice = (2 * w[1].printed).abs_diff(mean_twice);
            let allowance = 2 * (2 * ROUNDING + bits_duration(2, w[1].bitrate));
            deviation_twice > allowance
        })
        .map(|w| w[1])
        .collect()
}
