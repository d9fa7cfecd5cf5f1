//! Scripted stimulus: one scenario per requirement family, in the manual's terms.

use canif_model::config::{FrameFormat, InterfaceConfig, Synchronization};
use canif_model::dlc::FD_DATA_SIZES;
use canif_model::exchange::ExchangeMode;
use canif_model::filter::{manual_example, FilterRow};
use canif_model::frame::{CanId, Frame};
use canif_model::image::MessageRepr;
use canif_model::info_data::ControllerStatus;
use canif_model::timing::BitRates;
use canif_spec::ReqId;

use super::generated::random_frame;
use super::{scenario, Rng, Scenario, Step, Steps};

pub(super) fn message(frame: Frame, transaction_number: u16) -> MessageRepr {
    MessageRepr {
        transaction_number,
        frame,
        time_stamp: 0,
    }
}

pub(super) fn std(id: u16, data: &[u8]) -> Frame {
    Frame::classic(CanId::Standard(id), data).unwrap()
}

pub(super) fn idle(cycles: usize) -> Vec<Step> {
    vec![Step::default(); cycles]
}

/// PLC batches of every size around the slot count, with transaction numbers.
pub fn tx_batches(config: &InterfaceConfig, seed: u64) -> Scenario {
    let mut rng = Rng::new(seed ^ 0x7458);
    let slots = usize::from(config.tx_slots);
    let mut tn = 0u16;
    let mut steps = Vec::new();
    for cycle in 0..40 {
        let mut step = Step::default();
        for _ in 0..(cycle % (slots + 3)) {
            tn = tn.wrapping_add(1);
            step.send
                .push(message(random_frame(&mut rng, config.format), tn));
        }
        steps.push(step);
    }
    steps.extend(idle(60));
    let covers = [
        "HS-TX-001",
        "HS-TX-002",
        "HS-TX-004",
        "HS-TX-006",
        "HS-TX-007",
        "HS-TX-009",
        "HS-TX-011",
        "FD-LEN-001",
    ];
    scenario("tx-batches", config, &covers, Steps::Scripted(steps))
}

/// More to send than the bus carries: the send queue fills and acknowledges wait.
pub fn tx_backpressure(config: &InterfaceConfig) -> Scenario {
    let slots = usize::from(config.tx_slots);
    let mut rng = Rng::new(0x7B);
    let mut steps = Vec::new();
    let mut seq = 0u16;
    for _ in 0..30 {
        let mut step = Step::default();
        for _ in 0..slots {
            seq = seq.wrapping_add(1);
            // A distinct identifier per message (at most 30 x 32 of them).
            let data: Vec<u8> = (0..8).map(|_| rng.next_u64() as u8).collect();
            step.send.push(message(std(seq & 0x7FF, &data), seq));
        }
        steps.push(step);
    }
    steps.extend(idle(400));
    let mut scenario = scenario(
        "tx-backpressure",
        config,
        &["HS-TX-006", "HS-TX-008", "HS-TX-007", "HS-TX-012"],
        Steps::Scripted(steps),
    );
    scenario.bit_rates = BitRates {
        nominal: 125_000,
        data: scenario.bit_rates.data.min(2_000_000),
    };
    scenario
}

/// The PLC jumps its TxCounter to 0xFFFE, then counts on across the wrap.
pub fn tx_counter_jump(config: &InterfaceConfig) -> Scenario {
    let mut steps = Vec::new();
    for i in 0..8u16 {
        let mut step = Step {
            send: vec![message(std(0x100 + i, &[i as u8]), i)],
            ..Step::default()
        };
        if i == 0 {
            step.set_tx_counter = Some(0xFFFE);
        }
        steps.push(step);
        steps.push(Step::default());
    }
    steps.extend(idle(10));
    scenario(
        "tx-counter-jump",
        config,
        &["HS-TX-003", "HS-TX-005"],
        Steps::Scripted(steps),
    )
}

/// Confirmation delay with an LRW telegram (two cycles).
pub fn lrw_exchange(config: &InterfaceConfig) -> Scenario {
    let mut scenario = tx_batches(config, 7);
    scenario.name = "lrw-exchange".into();
    scenario.exchange = ExchangeMode::Lrw;
    scenario.check_confirmation_delay = true;
    scenario.covers.push(ReqId::new("PDX-001"));
    scenario
}

/// Separate input update: the confirmation comes one cycle later.
pub fn separate_input_update(config: &InterfaceConfig) -> Scenario {
    let mut scenario = tx_batches(config, 8);
    scenario.name = "separate-input-update".into();
    scenario.check_confirmation_delay = true;
    scenario.covers.push(ReqId::new("PDX-002"));
    scenario
}

/// Frames from other nodes; the PLC is busy now and then.
pub fn rx_handshake(config: &InterfaceConfig, seed: u64) -> Scenario {
    let mut rng = Rng::new(seed ^ 0x5278);
    let slots = u64::from(config.rx_slots);
    let mut steps = Vec::new();
    for cycle in 0..50u64 {
        let mut step = Step {
            plc_busy: cycle % 7 == 3 || cycle % 11 == 5,
            ..Step::default()
        };
        for _ in 0..rng.below(2 * slots + 1).min(3) {
            let mut frame = random_frame(&mut rng, config.format);
            if config.format == FrameFormat::Base11 && rng.chance(10) {
                frame = Frame::classic(CanId::Extended(0x1234_5678), &[1]).unwrap();
                // RXQ-005
            }
            step.bus.push((rng.below(800_000), frame));
        }
        steps.push(step);
    }
    steps.extend(idle(30));
    let covers = [
        "HS-RX-001",
        "HS-RX-002",
        "HS-RX-003",
        "HS-RX-004",
        "HS-RX-006",
        "HS-RX-007",
        "BQ-002",
        "RXQ-005",
        "FQ-001",
        "FQ-002",
        "FD-LEN-005",
    ];
    scenario("rx-handshake", config, &covers, Steps::Scripted(steps))
}

/// The PLC stops reading while the bus is full: the local queue overflows.
pub fn rx_overflow(config: &InterfaceConfig) -> Scenario {
    let mut steps = Vec::new();
    let mut seq = 0u32;
    for cycle in 0..100u64 {
        let mut step = Step {
            plc_busy: cycle < 40,
            ..Step::default()
        };
        if cycle < 40 {
            for i in 0..25u64 {
                seq += 1;
                step.bus.push((i * 40_000, std((seq % 0x7FF) as u16, &[])));
            }
        }
        steps.push(step);
    }
    let mut scenario = scenario(
        "rx-overflow",
        config,
        &["RXQ-003", "RXQ-004", "RXQ-006", "HS-RX-007", "FQ-004"],
        Steps::Scripted(steps),
    );
    scenario.bit_rates = BitRates {
        nominal: 1_000_000,
        data: 2_000_000,
    };
    scenario
}

/// 65,540 deliveries: RxCounter passes 0xFFFF → 0.
pub fn rx_wrap(config: &InterfaceConfig) -> Scenario {
    scenario(
        "rx-counter-wrap",
        config,
        &["HS-RX-005", "HS-TX-005"],
        Steps::RxWrap { cycles: 65_540 },
    )
}

/// Remote frames both ways.
pub fn remote_frames(config: &InterfaceConfig) -> Scenario {
    let ext = config.format != FrameFormat::Base11;
    let mut steps = Vec::new();
    for len in 0..=8u8 {
        let id = if ext && len % 2 == 1 {
            CanId::Extended(0x0ABC_0000 | u32::from(len))
        } else {
            CanId::Standard(0x700 + u16::from(len))
        };
        let frame = Frame::remote(id, len).unwrap();
        steps.push(Step {
            send: vec![message(frame, u16::from(len))],
            bus: vec![(100_000, frame)],
            ..Step::default()
        });
    }
    steps.extend(idle(10));
    scenario(
        "remote-frames",
        config,
        &["LAY-11-003", "LAY-29-004"],
        Steps::Scripted(steps),
    )
}

/// Filters: first match, default by kind, and 001 §7's table.
pub fn filters(config: &InterfaceConfig, table: Vec<FilterRow>, name: &str) -> Scenario {
    let mut config = config.clone();
    config.filters = table;
    // An identifier inside an overlap before those at a row's edge: there
    // a device taking the order wrongly shows it apart from one whose range
    // ends early (blame::filter_statement).
    let ids: [u32; 14] = [
        0x000,
        0x0FF,
        0x150,
        0x100,
        0x1FF,
        0x200,
        0x3FF,
        0x400,
        0x450,
        0x4FF,
        0x700,
        0x701,
        0x900,
        0x1FFF_FFFF,
    ];
    let mut steps = Vec::new();
    for (i, id) in ids.iter().enumerate() {
        let id = if *id > 0x7FF || (config.format != FrameFormat::Base11 && i % 2 == 1) {
            CanId::Extended(*id)
        } else {
            CanId::Standard(*id as u16)
        };
        if config.format == FrameFormat::Base11 && id.is_extended() {
            continue;
        }
        steps.push(Step {
            bus: vec![(50_000, Frame::classic(id, &[i as u8]).unwrap())],
            ..Step::default()
        });
    }
    steps.extend(idle(10));
    let covers = [
        "FLT-001", "FLT-002", "FLT-003", "FLT-004", "FLT-005", "FLT-006", "FLT-007", "FLT-008",
        "FLT-009",
    ];
    scenario(name, &config, &covers, Steps::Scripted(steps))
}

/// A table where first-match and last-match disagree.
pub fn first_match_table() -> Vec<FilterRow> {
    vec![
        FilterRow::accept_range(0x100, 0x1FF),
        FilterRow::reject_range(0x000, 0x7FF),
        FilterRow::accept_code_mask(0x400, 0x700),
    ]
}

pub fn manual_table() -> Vec<FilterRow> {
    manual_example().to_vec()
}

/// CAN FD: every Tx length 0..=64, every Rx size, with BRS and ESI.
pub fn fd_lengths(config: &InterfaceConfig) -> Scenario {
    let mut steps = Vec::new();
    for len in 0..=64u8 {
        let data: Vec<u8> = (0..len).map(|i| i ^ 0x5A).collect();
        let size = canif_model::dlc::fd_round_up(len).unwrap();
        let mut padded = data.clone();
        padded.resize(usize::from(size), 0);
        let id = if len % 3 == 0 {
            CanId::Extended(0x1000 + u32::from(len))
        } else {
            CanId::Standard(u16::from(len))
        };
        let tx = Frame::fd(id, len % 2 == 0, len % 5 == 0, &padded).unwrap();
        let mut step = Step {
            send: vec![message(tx, u16::from(len) + 1)],
            ..Step::default()
        };
        if let Some(&rx_size) = FD_DATA_SIZES.get(usize::from(len % 16)) {
            let rx_data: Vec<u8> = (0..rx_size).map(|i| i.wrapping_mul(7)).collect();
            step.bus.push((
                300_000,
                Frame::fd(
                    CanId::Standard(0x300 + u16::from(len)),
                    len % 2 == 1,
                    len % 4 == 0,
                    &rx_data,
                )
                .unwrap(),
            ));
        }
        steps.push(step);
    }
    steps.extend(idle(20));
    let covers = [
        "FD-LEN-001",
        "FD-LEN-003",
        "FD-LEN-004",
        "FD-LEN-005",
        "ERR-R1",
        "FD-LEN-002",
        "TS-001",
    ];
    let mut scenario = scenario("fd-lengths", config, &covers, Steps::Scripted(steps));
    // The PLC gives the real byte count (000 §8.3.1); the device rounds up.
    scenario.declared_lengths = (0..=64u8).map(|len| (u16::from(len) + 1, len)).collect();
    scenario
}

/// InfoData: controller status changes while frames wait in the receive FIFO.
pub fn info_data(config: &InterfaceConfig) -> Scenario {
    let mut steps = Vec::new();
    for cycle in 0..30u32 {
        let status = ControllerStatus {
            bus_off: cycle % 10 == 9,
            error_passive: cycle % 4 == 1,
            node_active: cycle % 10 != 9,
            warning_limit: cycle % 3 == 0,
            overload: cycle % 7 == 0,
            bus_idle: cycle % 2 == 0,
            transceiver_delay: cycle,
            ack_errors: cycle,
            bit_errors: cycle * 2,
            crc_errors: cycle * 3,
            form_errors: cycle * 4,
            stuff_errors: cycle * 5,
            receive_error_counter: cycle % 128,
            transmit_error_counter: (cycle * 9) % 256,
            core_running: cycle % 10 != 9,
        };
        let bus = (0..3u16)
            .map(|i| (u64::from(i) * 200_000, std(0x400 + i, &[cycle as u8])))
            .collect();
        let send = if cycle % 3 == 0 {
            vec![message(std(0x10, &[1, 2, 3]), cycle as u16)]
        } else {
            Vec::new()
        };
        steps.push(Step {
            status: Some(status),
            bus,
            send,
            plc_busy: cycle % 5 < 3,
            ..Step::default()
        });
    }
    steps.extend(idle(20));
    let covers = [
        "INFO-001", "INFO-002", "INFO-003", "INFO-004", "INFO-005", "INFO-006", "INFO-007",
        "INFO-008", "INFO-009",
    ];
    scenario("info-data", config, &covers, Steps::Scripted(steps))
}

/// Fast CAN Queue: bursts past the slot count, the PLC sometimes late.
pub fn fast_queue(config: &InterfaceConfig) -> Scenario {
    let slots = u64::from(config.rx_slots);
    let mut steps = Vec::new();
    for cycle in 0..40u64 {
        let burst = (cycle % (2 * slots + 2)).min(18);
        let bus = (0..burst)
            .map(|i| (i * 50_000, std(((cycle * 32 + i) % 0x7FF) as u16, &[])))
            .collect();
        steps.push(Step {
            bus,
            plc_busy: cycle % 6 == 2,
            ..Step::default()
        });
    }
    steps.extend(idle(10));
    let mut scenario = scenario(
        "fast-queue",
        config,
        &["FQ-001", "FQ-002", "FQ-004", "HS-RX-002", "HS-RX-007"],
        Steps::Scripted(steps),
    );
    scenario.bit_rates = BitRates::classic(1_000_000);
    scenario
}

/// Distributed Clocks: the first Tx message of each batch waits for SYNC1.
pub fn distributed_clocks(config: &InterfaceConfig) -> Scenario {
    let mut config = config.clone();
    config.synchronization = Synchronization::DistributedClocks {
        sync1_shift: 300_000,
    };
    let mut steps = Vec::new();
    for cycle in 0..20u16 {
        let send = (0..(cycle % 4))
            .map(|i| message(std(0x200 + i, &[cycle as u8]), 0))
            .collect();
        steps.push(Step {
            send,
            ..Step::default()
        });
    }
    steps.extend(idle(10));
    scenario(
        "distributed-clocks",
        &config,
        &["PDX-004", "PDX-005"],
        Steps::Scripted(steps),
    )
}
