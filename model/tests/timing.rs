//! Frame timing, the CiA table and buffer sizing (000 §4, R3, R4).

use canif_model::cia_table::{self, FLAGGED_CELL};
use canif_model::frame::{CanId, Frame};
use canif_model::sizing::{self, FrameTimeBasis};
use canif_model::timing::{classic_bits, fd_bits, frame_duration, BitCount, BitRates, Stuffing};

/// Covers: TIM-001, TIM-002
#[test]
fn classic_bit_counts() {
    assert_eq!(
        classic_bits(false, 0),
        BitCount {
            nominal: 47,
            worst_case: 55
        }
    );
    assert_eq!(
        classic_bits(false, 8),
        BitCount {
            nominal: 111,
            worst_case: 135
        }
    );
    assert_eq!(
        classic_bits(true, 0),
        BitCount {
            nominal: 67,
            worst_case: 80
        }
    );
    assert_eq!(
        classic_bits(true, 8),
        BitCount {
            nominal: 131,
            worst_case: 160
        }
    );
    let frame = Frame::classic(CanId::Standard(0x123), &[0; 8]).unwrap();
    assert_eq!(
        frame_duration(&frame, BitRates::classic(500_000), Stuffing::Nominal),
        222_000
    );
    assert_eq!(
        frame_duration(&frame, BitRates::classic(500_000), Stuffing::WorstCase),
        270_000
    );
    // A remote frame carries no data bytes, whatever it requests.
    let remote = Frame::remote(CanId::Standard(0x123), 8).unwrap();
    assert_eq!(
        frame_duration(&remote, BitRates::classic(1_000_000), Stuffing::Nominal),
        47_000
    );
}

/// Covers: TIM-003, FD-BIT-004, FD-BIT-002
#[test]
fn fd_bit_counts_and_the_two_bit_rates() {
    let empty = fd_bits(false, 0, false);
    assert_eq!(empty.arbitration.nominal + empty.data.nominal, 62);
    let full = fd_bits(false, 64, true);
    assert_eq!(
        full.arbitration,
        BitCount {
            nominal: 30,
            worst_case: 33
        },
        "the 4th worst-case stuff bit follows BRS and is sent at the data rate"
    );
    assert_eq!(
        full.data,
        BitCount {
            nominal: 549,
            worst_case: 679
        }
    );
    assert_eq!(
        fd_bits(false, 20, true).data.nominal,
        5 + 160 + 4 + 21 + 7,
        "CRC-21 above 16 bytes"
    );

    let switched = Frame::fd(CanId::Standard(1), true, false, &[0; 64]).unwrap();
    let plain = Frame::fd(CanId::Standard(1), false, false, &[0; 64]).unwrap();
    let rates = BitRates {
        nominal: 500_000,
        data: 2_000_000,
    };
    assert_eq!(
        frame_duration(&switched, rates, Stuffing::Nominal),
        30 * 2_000 + 549 * 500
    );
    assert_eq!(
        frame_duration(&plain, rates, Stuffing::Nominal),
        579 * 2_000
    );
    // Equal rates: switching changes nothing.
    let same = BitRates::classic(500_000);
    assert_eq!(
        frame_duration(&switched, same, Stuffing::Nominal),
        frame_duration(&plain, same, Stuffing::Nominal)
    );
}

/// Covers: TIM-004
#[test]
fn the_cia_table_as_data() {
    assert_eq!(cia_table::cells().count(), 45);
    assert_eq!(cia_table::frame_time(500_000, 8), Some(260_000), "≈ 260 µs");
    assert_eq!(cia_table::frame_time(1_000_000, 0), Some(50_000), "≈ 50 µs");
    assert_eq!(cia_table::frame_time(800_000, 8), None);
    assert_eq!(cia_table::frame_time(50_000, 9), None);
}

/// Covers: TIM-005, ERR-R3
#[test]
fn every_cell_lies_between_nominal_and_worst_case() {
    for cell in cia_table::cells() {
        assert!(cia_table::within_model_bounds(&cell), "{cell:?}");
    }
    // The bound is real: a cell 10 % above the worst case would fail it.
    let too_slow = cia_table::Cell {
        bitrate: 500_000,
        data_len: 8,
        printed: 297_000,
    };
    assert!(!cia_table::within_model_bounds(&too_slow));
}

/// Covers: TIM-006, ERR-R3
#[test]
fn only_the_50_kbit_7_byte_cell_breaks_its_row() {
    let flagged: Vec<_> = cia_table::inconsistent_cells()
        .iter()
        .map(|c| (c.bitrate, c.data_len, c.printed))
        .collect();
    assert_eq!(flagged, [(50_000, 7, 2_340_000)]);
    assert_eq!(FLAGGED_CELL, (50_000, 7, 243));
    assert_eq!(
        cia_table::frame_time(50_000, 7),
        Some(2_430_000),
        "the corrected value is used"
    );
}

/// Covers: TIM-007, ERR-R4
#[test]
fn the_manuals_sizing_examples() {
    let slots = |bitrate: u32, cycle_us: u64, payload: u8| {
        sizing::manual_figure(bitrate, cycle_us * 1_000, payload)
            .unwrap()
            .slots
    };
    assert_eq!(slots(500_000, 1_000, 8), 4);
    assert_eq!(slots(500_000, 5_000, 8), 20);
    assert_eq!(slots(1_000_000, 1_000, 0), 20);
    assert_eq!(sizing::slots_needed(1_000, 1_000), 1);
    assert_eq!(sizing::slots_needed(1_001, 1_000), 2);
}

/// R4 amended: the shortest 11-bit frame of 8 bytes at 500 kbit/s is 222 µs,
/// so 5 frames can end in a 1 ms cycle and the manual's 4 slots can overflow.
/// The advisor gives both figures and recommends the safe one.
///
/// Covers: TIM-008, ERR-R4
#[test]
fn the_advisor_recommends_the_figure_that_cannot_overflow() {
    let advice = sizing::advise(500_000, 1_000_000, 8).unwrap();
    assert_eq!(advice.manual.unwrap().slots, 4);
    assert_eq!(advice.safe.frame_time, 222_000);
    assert_eq!(advice.safe.slots, 5);
    assert_eq!(advice.recommended(), advice.safe);
    assert!(advice.manual_can_overflow());
    // Where the manual's figure is already safe, both agree.
    let roomy = sizing::advise(1_000_000, 1_000_000, 0).unwrap();
    assert_eq!((roomy.manual.unwrap().slots, roomy.safe.slots), (20, 22));
    // Outside the CiA table there is only the safe figure.
    let outside = sizing::advise(800_000, 1_000_000, 8).unwrap();
    assert_eq!(outside.manual, None);
    assert_eq!(
        (
            outside.safe.basis,
            outside.safe.frame_time,
            outside.safe.slots
        ),
        (FrameTimeBasis::Nominal, 138_750, 8)
    );
    // The safe figure never gives fewer slots than the worst case would.
    let worst = sizing::size(800_000, 1_000_000, 8, FrameTimeBasis::WorstCase).unwrap();
    assert!(outside.safe.slots >= worst.slots);
    assert_eq!(sizing::advise(500_000, 1_000_000, 9), None);
}

/// An independent count: ISO 11898-1 bit stuffing run on the densest bit
/// pattern of the dynamically stuffed region (SOF … BRS, then ESI, DLC and
/// data), each stuff bit charged to the phase it is sent in: one inserted
/// after the BRS bit goes out after the switch, at the data rate. For every FD
/// size and both identifier lengths the model's worst-case split must agree.
///
/// Covers: TIM-003
#[test]
fn fd_worst_case_stuffing_agrees_with_a_bit_level_count() {
    /// Stuff bits inserted after each raw bit, for the pattern that makes the
    /// most: five equal bits, then runs of four that each merge with the stuff
    /// bit before them (Davis et al.'s worst case).
    fn stuffed_after(raw_bits: u32) -> Vec<u32> {
        let mut after = Vec::new();
        // Equal bits on the wire so far; each raw bit repeats the level, and a
        // stuff bit (the other level) starts a run the next raw bits continue.
        let mut run = 0;
        for position in 1..=raw_bits {
            run += 1;
            if run == 5 {
                after.push(position);
                run = 1;
            }
        }
        after
    }
    for extended in [false, true] {
        let arbitration_bits: u32 = if extended { 36 } else { 17 };
        for &len in canif_model::dlc::FD_DATA_SIZES.iter() {
            let data_bits = 1 + 4 + 8 * u32::from(len); // ESI, DLC, data
            let stuffs = stuffed_after(arbitration_bits + data_bits);
            let in_arbitration = stuffs.iter().filter(|p| **p < arbitration_bits).count() as u32;
            let in_data = stuffs.len() as u32 - in_arbitration;
            let model = fd_bits(extended, len, true);
            assert_eq!(
                model.arbitration.worst_case - model.arbitration.nominal,
                in_arbitration,
                "{} id, {len} bytes: arbitration-phase stuff bits",
                if extended { "29-bit" } else { "11-bit" }
            );
            assert_eq!(
                model.data.worst_case - model.data.nominal,
                in_data,
                "{} id, {len} bytes: data-phase stuff bits",
                if extended { "29-bit" } else { "11-bit" }
            );
        }
    }
    // The figures: 11-bit, 0 bytes, (arbitration nominal/worst, data nominal/worst).
    let empty = fd_bits(false, 0, true);
    assert_eq!(
        (
            empty.arbitration.nominal,
            empty.arbitration.worst_case,
            empty.data.nominal,
            empty.data.worst_case
        ),
        (30, 33, 32, 34)
    );
}
