//! Generated stimulus: random PLC and bus behaviour from a seed, offered no
//! faster than the bus carries it.

use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::dlc::FD_DATA_SIZES;
use canif_model::frame::{CanId, Frame};
use canif_model::image::MessageRepr;
use canif_model::timing::BitRates;
use canif_model::Nanos;

use super::{scenario, Rng, Scenario, Step, Steps};

/// A message the interface can carry, from the generator.
pub(super) fn random_frame(rng: &mut Rng, format: FrameFormat) -> Frame {
    let extended = format != FrameFormat::Base11 && rng.chance(50);
    let id = if extended {
        CanId::Extended(rng.below(0x2000_0000) as u32)
    } else {
        CanId::Standard(rng.below(0x800) as u16)
    };
    if format == FrameFormat::Fd && rng.chance(60) {
        let size = usize::from(FD_DATA_SIZES[rng.below(16) as usize]);
        let data: Vec<u8> = (0..size).map(|_| rng.next_u64() as u8).collect();
        return Frame::fd(id, rng.chance(50), rng.chance(20), &data).unwrap();
    }
    if rng.chance(10) {
        return Frame::remote(id, rng.below(9) as u8).unwrap();
    }
    let len = rng.below(9) as usize;
    let data: Vec<u8> = (0..len).map(|_| rng.next_u64() as u8).collect();
    Frame::classic(id, &data).unwrap()
}

pub(super) struct Generator {
    rng: Rng,
    format: FrameFormat,
    slots: u64,
    cycle_time: Nanos,
    bit_rates: BitRates,
    load_percent: u64,
    /// Bus time still free to offer: a cycle's share of the load is added each
    /// cycle, every frame offered (PLC or node) spends its duration. Offering
    /// no more than the bus carries keeps every backlog, and memory, bounded.
    budget: Nanos,
    tn: u16,
}

impl Generator {
    pub(super) fn new(scenario: &Scenario, seed: u64, load_percent: u64) -> Self {
        Generator {
            rng: Rng::new(seed),
            format: scenario.interface.format,
            slots: u64::from(scenario.interface.tx_slots),
            cycle_time: scenario.cycle_time,
            bit_rates: scenario.bit_rates,
            load_percent,
            budget: 0,
            tn: 0,
        }
    }

    fn affordable(&mut self, frame: &Frame) -> bool {
        let cost = crate::bus::sim::duration(frame, self.bit_rates);
        if cost > self.budget {
            return false;
        }
        self.budget -= cost;
        true
    }

    pub(super) fn step(&mut self) -> Step {
        let share = self.cycle_time * self.load_percent / 100;
        // Quiet cycles save up for a burst of at most four cycles' worth.
        self.budget = (self.budget + share).min(4 * share);
        let mut step = Step {
            plc_busy: self.rng.chance(15),
            ..Step::default()
        };
        for _ in 0..self.rng.below(self.slots + 3) {
            let frame = random_frame(&mut self.rng, self.format);
            if !self.affordable(&frame) {
                break;
            }
            self.tn = self.tn.wrapping_add(1);
            step.send.push(MessageRepr {
                transaction_number: self.tn,
                frame,
                time_stamp: 0,
            });
        }
        for _ in 0..self.rng.below(2 * self.slots) {
            let frame = random_frame(&mut self.rng, self.format);
            if !self.affordable(&frame) {
                break;
            }
            let at = self.rng.below(self.cycle_time);
            step.bus.push((at, frame));
        }
        step
    }
}

/// Random PLC behaviour and bus load from a seed.
pub fn generated(config: &InterfaceConfig, seed: u64, cycles: u64, load_percent: u64) -> Scenario {
    let covers = [
        "HS-TX-001",
        "HS-TX-002",
        "HS-TX-004",
        "HS-TX-006",
        "HS-TX-007",
        "HS-TX-008",
        "HS-TX-009",
        "HS-TX-011",
        "HS-RX-001",
        "HS-RX-002",
        "HS-RX-003",
        "HS-RX-004",
        "HS-RX-006",
        "HS-RX-007",
        "BQ-002",
        "FQ-001",
        "FQ-002",
        "FQ-004",
        "RXQ-003",
        "RXQ-004",
        "FD-LEN-005",
    ];
    scenario(
        &format!("generated-{seed}"),
        config,
        &covers,
        Steps::Generated {
            cycles,
            seed,
            load_percent,
        },
    )
}
