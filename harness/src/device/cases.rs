//! The scenarios a device's profile runs: each interface it offers, with the
//! scripted scenarios that fit it and generated ones from the seed.

use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode};
use canif_model::filter::FilterRow;

use super::scenario::{self, Scenario};
use crate::run::interface;

/// What the generated part of a profile's scenarios is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Generation {
    pub seed: u64,
    /// Generated scenarios per interface.
    pub cases: u64,
    /// Cycles of each generated scenario.
    pub generated_cycles: u64,
    /// Include the 65,540-cycle RxCounter wrap.
    pub counter_wrap: bool,
}

/// The scenarios for a profile: each interface it offers with what fits it.
pub fn scenarios(caps: &Capabilities, options: &Generation) -> Vec<Scenario> {
    let mut list = Vec::new();
    let seed = options.seed;
    let generated = |list: &mut Vec<Scenario>, config: &InterfaceConfig, salt: u64| {
        for case in 0..options.cases {
            list.push(scenario::generated(
                config,
                seed.wrapping_mul(1_000).wrapping_add(salt * 100 + case),
                options.generated_cycles,
                95,
            ));
        }
    };
    let classic = if caps.base11 {
        Some(FrameFormat::Base11)
    } else if caps.ext29 {
        Some(FrameFormat::Extended29)
    } else {
        None
    };
    if let Some(format) = classic {
        let config = interface(format, QueueMode::Standard, caps);
        list.extend([
            scenario::tx_batches(&config, seed),
            scenario::tx_backpressure(&config),
            scenario::tx_counter_jump(&config),
            scenario::separate_input_update(&config),
            scenario::lrw_exchange(&config),
            scenario::rx_handshake(&config, seed),
            scenario::rx_overflow(&config),
            scenario::remote_frames(&config),
            scenario::tx_batch_of_nothing(&config),
            scenario::tx_batch_beyond_the_slots(&config),
            scenario::tx_length_out_of_range(&config),
            scenario::random_output_images(&config, seed),
        ]);
        if caps.max_slots > config.tx_slots {
            let mut all = config.clone();
            (all.tx_slots, all.rx_slots) = (caps.max_slots, caps.max_slots);
            list.push(scenario::full_slots(&all));
        }
        if options.counter_wrap {
            list.push(scenario::rx_wrap(&config));
        }
        generated(&mut list, &config, 1);
    }
    if caps.ext29 && classic != Some(FrameFormat::Extended29) {
        let config = interface(FrameFormat::Extended29, QueueMode::Standard, caps);
        list.extend([
            scenario::tx_batches(&config, seed + 1),
            scenario::rx_handshake(&config, seed + 1),
            scenario::remote_frames(&config),
            scenario::tx_length_out_of_range(&config),
        ]);
        generated(&mut list, &config, 2);
    }
    if caps.ext29 {
        let config = interface(FrameFormat::Extended29, QueueMode::Standard, caps);
        list.push(scenario::reserved_cob_id_bits(&config));
    }
    if caps.filters {
        let format = if caps.ext29 {
            FrameFormat::Extended29
        } else {
            FrameFormat::Base11
        };
        let config = interface(format, QueueMode::Standard, caps);
        list.push(scenario::filters(
            &config,
            scenario::first_match_table(),
            "filters-first-match",
        ));
        list.push(scenario::filters(
            &config,
            Vec::<FilterRow>::new(),
            "filters-none",
        ));
        if caps.ext29 {
            list.push(scenario::filters(
                &config,
                scenario::manual_table(),
                "filters-manual-example",
            ));
        }
    }
    if caps.fd {
        let config = interface(FrameFormat::Fd, QueueMode::Standard, caps);
        list.extend([
            scenario::tx_batches(&config, seed + 2),
            scenario::fd_lengths(&config),
            scenario::rx_handshake(&config, seed + 2),
            scenario::classic_frame_with_fd_bits(&config),
            scenario::tx_length_out_of_range(&config),
            scenario::random_output_images(&config, seed + 2),
        ]);
        if caps.info_data {
            list.push(scenario::info_data(&config));
        }
        generated(&mut list, &config, 3);
    }
    if caps.optimized_queue {
        let config = interface(FrameFormat::Base11, QueueMode::Optimized, caps);
        list.extend([
            scenario::tx_batches(&config, seed + 3),
            scenario::rx_handshake(&config, seed + 3),
            scenario::rx_overflow(&config),
        ]);
        generated(&mut list, &config, 4);
    }
    if caps.fast_queue {
        let config = interface(FrameFormat::Base11, QueueMode::Fast, caps);
        list.extend([
            scenario::tx_batches(&config, seed + 4),
            scenario::fast_queue(&config),
        ]);
        if caps.distributed_clocks {
            list.push(scenario::distributed_clocks(&config));
        }
        generated(&mut list, &config, 5);
    }
    for scenario in &mut list {
        scenario.name = format!("{} [{}]", scenario.name, scenario.interface.describe());
    }
    list
}
