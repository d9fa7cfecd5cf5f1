//! Process-data exchange and synchronisation (003, G10).

mod common;

use canif_model::client::PlcClient;
use canif_model::config::{ConfigError, FrameFormat, QueueMode, Synchronization};
use canif_model::device::Device;
use canif_model::exchange::{ExchangeMode, ProcessDataExchange, SYNC1_TX_JITTER};
use canif_model::image::InputImage;
use common::*;

fn cycles_until_confirmed(mode: ExchangeMode) -> u32 {
    let mut device = device(FrameFormat::Base11, QueueMode::Standard, 4);
    let mut plc = PlcClient::new(device.layout());
    let mut exchange = ProcessDataExchange::new(mode, device.inputs());
    plc.send(message(std_frame(0x181, &[1]), 0)).unwrap();
    for task in 0..10 {
        let seen = InputImage::new_checked(exchange.plc_inputs(), device.layout())
            .unwrap()
            .tx_counter();
        if seen == 1 {
            return task;
        }
        let outputs = plc.task(exchange.plc_inputs()).unwrap().to_vec(); // task 0 writes TxCounter 1
        device.cycle(&outputs, 0).unwrap();
        exchange.device_cycle_done(device.inputs());
    }
    panic!("never confirmed");
}

/// Covers: PDX-001, PDX-002
#[test]
fn confirmation_delay_of_lrw_and_separate_input_update() {
    assert_eq!(cycles_until_confirmed(ExchangeMode::Lrw), 2);
    assert_eq!(cycles_until_confirmed(ExchangeMode::SeparateInputUpdate), 1);
    assert_eq!(ExchangeMode::Lrw.confirmation_cycles(), 2);
    assert_eq!(ExchangeMode::SeparateInputUpdate.confirmation_cycles(), 1);
}

/// Covers: PDX-003
#[test]
fn by_default_the_cycle_runs_on_the_process_data_telegram() {
    let mut device = device(FrameFormat::Base11, QueueMode::Standard, 4);
    assert_eq!(device.config().synchronization, Synchronization::Sm2);
    let outputs = outputs_with(&device, 1, 0, &[message(std_frame(1, &[]), 0)], 1);
    device.cycle(&outputs, 5_000).unwrap();
    assert!(
        device.poll_transmit(5_000).is_some(),
        "sent in the cycle the telegram started"
    );
}

/// Covers: PDX-004, PDX-005
#[test]
fn distributed_clocks_hold_the_first_frame_until_sync1() {
    let mut config = config(FrameFormat::Base11, QueueMode::Fast, 4);
    config.synchronization = Synchronization::DistributedClocks {
        sync1_shift: 250_000,
    };
    let mut device = Device::new(&caps(), config.clone()).unwrap();
    let batch: Vec<_> = (0..2).map(|i| message(std_frame(i, &[]), 0)).collect();
    device
        .cycle(&outputs_with(&device, 1, 0, &batch, 2), 1_000_000)
        .unwrap(); // SYNC0
    assert_eq!(device.poll_transmit(1_000_000), None);
    assert_eq!(device.poll_timeout(), Some(1_250_000));
    assert_eq!(device.poll_transmit(1_250_000 - 1), None);
    assert!(
        device.poll_transmit(1_250_000).is_some(),
        "at SYNC1, within {SYNC1_TX_JITTER} ns"
    );
    device.handle_transmit_complete();
    assert!(
        device.poll_transmit(1_250_000).is_some(),
        "the rest follow at once"
    );

    let mut buffered = config.clone();
    buffered.queue = QueueMode::Standard;
    assert_eq!(
        buffered.validate(&caps()),
        Err(ConfigError::DistributedClocksNeedsFastQueue)
    );
    let mut no_dc = caps();
    no_dc.distributed_clocks = false;
    assert_eq!(
        config.validate(&no_dc),
        Err(ConfigError::DistributedClocksNotOffered)
    );
}
