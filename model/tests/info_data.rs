//! InfoData (001 §8.3.3).

mod common;

use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::device::Device;
use canif_model::info_data::{index, status, BitTiming, ControllerStatus};
use common::*;

/// Covers: INFO-001, INFO-002, INFO-003, INFO-004, INFO-005, INFO-006, INFO-007
#[test]
fn info_data_reports_the_controller() {
    let mut config = InterfaceConfig::new(FrameFormat::Fd, 4);
    config.nominal_timing = BitTiming {
        jump_width: 1,
        time_a: 13,
        time_b: 2,
        prescaler: 5,
    };
    config.data_timing = BitTiming {
        jump_width: 2,
        time_a: 7,
        time_b: 2,
        prescaler: 1,
    };
    let mut device = Device::new(&caps(), config).unwrap();
    device.handle_controller_status(ControllerStatus {
        error_passive: true,
        warning_limit: true,
        bus_idle: true,
        transceiver_delay: 9,
        ack_errors: 1,
        bit_errors: 2,
        crc_errors: 3,
        form_errors: 4,
        stuff_errors: 5,
        receive_error_counter: 96,
        transmit_error_counter: 128,
        core_running: true,
        ..ControllerStatus::default()
    });
    let batch: Vec<_> = (0..3).map(|i| message(std_frame(i, &[]), 0)).collect();
    for i in 0..2 {
        device.handle_received(std_frame(0x700 + i, &[]), 0);
    }
    device
        .cycle(&outputs_with(&device, 1, 0, &batch, 3), 0)
        .unwrap();
    let inputs = inputs_of(&device);
    let word = |i| inputs.info_data(i).unwrap();
    assert_eq!(
        word(index::CAN_STATUS),
        status::ERROR_PASSIVE | status::WARNING_LIMIT | status::BUS_IDLE
    );
    assert_eq!(word(index::CAN_STATUS), 0b0100_1010);
    assert_eq!(
        word(index::ARBITRATION_BAUDRATE).to_le_bytes(),
        [1, 13, 2, 5]
    );
    assert_eq!(word(index::DATA_BAUDRATE).to_le_bytes(), [2, 7, 2, 1]);
    assert_eq!(word(index::TRANSCEIVER_DELAY), 9);
    assert_eq!(
        (
            word(index::SEND_FIFO_HIGH_PRIO),
            word(index::SEND_FIFO_LOW_PRIO)
        ),
        (0, 3)
    );
    assert_eq!(
        word(index::RECEIVE_FIFO),
        0,
        "both received messages went into the image"
    );
    assert_eq!(
        [word(7), word(8), word(9), word(10), word(12)],
        [1, 2, 3, 4, 5]
    );
    assert_eq!(
        (
            word(index::RECEIVE_ERROR_COUNTER),
            word(index::TRANSMIT_ERROR_COUNTER)
        ),
        (96, 128)
    );
    assert_eq!((word(index::CAN_CORE), word(index::UNUSED)), (1, 0));

    device.handle_controller_status(ControllerStatus {
        bus_off: true,
        ..ControllerStatus::default()
    });
    device
        .cycle(&outputs_with(&device, 1, 0, &batch, 3), 0)
        .unwrap();
    let inputs = inputs_of(&device);
    assert_eq!(inputs.info_data(index::CAN_STATUS), Some(status::BUS_OFF));
    assert_eq!(inputs.info_data(index::CAN_CORE), Some(0));
}

/// Covers: PROF-012, INFO-001
#[test]
fn devices_without_info_data_have_none_in_the_image() {
    let mut caps = caps();
    caps.info_data = false;
    let device = Device::new(&caps, InterfaceConfig::new(FrameFormat::Fd, 4)).unwrap();
    assert_eq!(
        device.layout().input_size(),
        device.layout().info_data_start()
    );
    assert_eq!(inputs_of(&device).info_data(0), None);
}
