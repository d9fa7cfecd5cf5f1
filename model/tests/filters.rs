//! Filters (000/001 §7, G7).

mod common;

use canif_model::config::{ConfigError, FrameFormat, QueueMode};
use canif_model::device::RxOutcome;
use canif_model::filter::{accepts, manual_example, FilterRow};
use canif_model::frame::CanId;
use common::*;

fn ext(id: u32) -> CanId {
    CanId::Extended(id)
}

/// Covers: FLT-009, FLT-001, FLT-002, FLT-004
#[test]
fn the_manual_example_forwards_exactly_0x400_to_0x700() {
    let table = manual_example();
    for (id, expected) in [
        (0x0, false),
        (0x3FF, false),
        (0x400, true),
        (0x555, true),
        (0x700, true),
        (0x701, false),
        (0x1FFF_FFFF, false),
    ] {
        assert_eq!(accepts(&table, ext(id)), expected, "0x{id:X}");
    }
}

/// Covers: FLT-003
#[test]
fn code_and_mask_select_bit_by_bit() {
    let table = [FilterRow::accept_code_mask(0x180, 0x780)]; // 0x180..=0x1FF
    assert!(accepts(&table, ext(0x180)));
    assert!(accepts(&table, ext(0x1FF)));
    assert!(!accepts(&table, ext(0x200)));
    assert!(!accepts(&table, ext(0x17F)));
    assert!(
        accepts(&table, ext(0x0180_0180)),
        "bits outside the mask do not matter"
    );
}

/// Covers: FLT-005
#[test]
fn the_first_matching_row_decides() {
    let accept_then_reject = [
        FilterRow::accept_range(0x100, 0x1FF),
        FilterRow::reject_range(0, 0x7FF),
    ];
    let reject_then_accept = [
        FilterRow::reject_range(0, 0x7FF),
        FilterRow::accept_range(0x100, 0x1FF),
    ];
    assert!(accepts(&accept_then_reject, ext(0x150)));
    assert!(!accepts(&reject_then_accept, ext(0x150)));
}

/// Covers: FLT-006, FLT-008
#[test]
fn unmatched_frames_follow_the_kind_of_table() {
    assert!(accepts(&[], ext(0x123)), "no filters: everything");
    assert!(
        accepts(&[FilterRow::reject_range(0, 0xFF)], ext(0x123)),
        "only rejections: the rest passes"
    );
    assert!(
        !accepts(&[FilterRow::accept_range(0, 0xFF)], ext(0x123)),
        "an acceptance row: the rest is held back"
    );
}

/// Covers: FLT-007
#[test]
fn both_identifier_formats_are_filtered_by_value() {
    let table = manual_example();
    assert_eq!(
        accepts(&table, CanId::Standard(0x400)),
        accepts(&table, ext(0x400))
    );
    assert_eq!(
        accepts(&table, CanId::Standard(0x3FF)),
        accepts(&table, ext(0x3FF))
    );
}

/// Covers: FLT-010
#[test]
fn malformed_rows_are_configuration_errors() {
    let caps = caps();
    for row in [
        FilterRow::accept_range(0x700, 0x400),
        FilterRow::accept_range(0, 0x2000_0000),
        FilterRow::accept_code_mask(0x4000_0000, 0),
    ] {
        let mut config = config(FrameFormat::Extended29, QueueMode::Standard, 4);
        config.filters = vec![FilterRow::reject_range(0, 1), row];
        assert!(
            matches!(
                config.validate(&caps),
                Err(ConfigError::InvalidFilter { row: 1, .. })
            ),
            "{row:?}"
        );
    }
    let mut no_filters = caps.clone();
    no_filters.filters = false;
    let mut config = config(FrameFormat::Extended29, QueueMode::Standard, 4);
    config.filters = manual_example().to_vec();
    assert_eq!(
        config.validate(&no_filters),
        Err(ConfigError::FiltersNotOffered)
    );
}

/// Covers: FLT-001, FLT-002, FLT-009
#[test]
fn the_device_delivers_only_accepted_frames() {
    let mut config = config(FrameFormat::Extended29, QueueMode::Standard, 8);
    config.filters = manual_example().to_vec();
    let mut rig = Rig::new(canif_model::device::Device::new(&caps(), config).unwrap());
    let mut outcomes = Vec::new();
    for id in [0x3FFu32, 0x400, 0x700, 0x701] {
        let frame = canif_model::frame::Frame::classic(ext(id), &[]).unwrap();
        outcomes.push(rig.device.handle_received(frame, 0));
    }
    assert_eq!(
        outcomes,
        [
            RxOutcome::Filtered,
            RxOutcome::Queued,
            RxOutcome::Queued,
            RxOutcome::Filtered
        ]
    );
    rig.cycle(0);
    rig.cycle(0);
    let ids = rig.received_ids();
    assert_eq!(ids, [0x400, 0x700]);
}
