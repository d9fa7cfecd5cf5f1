//! The start-up downloads that configure a terminal's CAN interface in PREOP
//! (EL6751 documentation: 0xF800 first, then 0x8000, then 0x8001, each with
//! complete access), their values as docs/ethercat.md lays them out.

use canif_model::config::Capabilities;
use canif_model::config::{FrameFormat, InterfaceConfig, QueueMode};
use canif_model::filter::{FilterAction, FilterMatch};

/// One download: object, and its bytes with complete access from sub-index 0.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Download {
    pub index: u16,
    pub name: &'static str,
    pub data: Vec<u8>,
}

pub const BUS_PARAMETERS: u16 = 0xF800;
pub const INTERFACE: u16 = 0x8000;
pub const FILTERS: u16 = 0x8001;
pub const SYNC_OUTPUTS: u16 = 0x1C32;
/// `0x1C32:05`, the longest local cycle the terminal measured once `:08` is set (000 §5).
pub const CYCLE_TIME_SUB: u8 = 5;
pub const MEASURE_SUB: u8 = 8;

/// Sub-index 0 as complete access sends it: the count, then a padding byte.
fn count(n: u8) -> Vec<u8> {
    vec![n, 0]
}

/// `0x8000:20` as docs/ethercat.md lays it out: one bit per frame format
/// of TwinCAT's dialog (the public example's 0x0008 is 29-bit with
/// transaction numbers), the queue, the time stamp.
fn flags(config: &InterfaceConfig) -> u16 {
    let format = match (config.format, config.transaction_number) {
        (FrameFormat::Base11, false) => 0,
        (FrameFormat::Extended29, false) => 1 << 2,
        (FrameFormat::Extended29, true) => 1 << 3,
        (FrameFormat::Base11, true) => 1 << 4,
        (FrameFormat::Fd, _) => 1 << 5,
    };
    let queue = match config.queue {
        QueueMode::Standard => 0,
        QueueMode::Optimized => 1 << 0,
        QueueMode::Fast => 1 << 1,
    };
    let stamp = if config.time_stamp { 1 << 6 } else { 0 };
    format | queue | stamp
}

/// The three downloads, in the order the documentation gives.
pub fn downloads(caps: &Capabilities, config: &InterfaceConfig) -> Vec<Download> {
    let mut bus = count(2);
    bus.extend_from_slice(&config.nominal_timing.to_word().to_le_bytes());
    bus.extend_from_slice(&config.data_timing.to_word().to_le_bytes());

    let mut interface = count(0x24);
    interface.extend_from_slice(&flags(config).to_le_bytes());
    interface.extend_from_slice(&u16::from(config.rx_slots).to_le_bytes());
    interface.extend_from_slice(&u16::from(config.tx_slots).to_le_bytes());
    interface.extend_from_slice(&(caps.rx_queue_depth as u16).to_le_bytes());
    interface.extend_from_slice(&(caps.tx_queue_depth as u16).to_le_bytes());

    let mut filters = count(config.filters.len() as u8);
    for row in &config.filters {
        let accept = u8::from(row.action == FilterAction::Accept);
        let (kind, a, b) = match row.matches {
            FilterMatch::Range { from, to } => (0, from, to),
            FilterMatch::CodeMask { code, mask } => (2, code, mask),
        };
        filters.extend_from_slice(&[accept | kind, 0]);
        filters.extend_from_slice(&a.to_le_bytes());
        filters.extend_from_slice(&b.to_le_bytes());
    }
    vec![
        Download {
            index: BUS_PARAMETERS,
            name: "CAN bus parameters",
            data: bus,
        },
        Download {
            index: INTERFACE,
            name: "CAN interface configuration",
            data: interface,
        },
        Download {
            index: FILTERS,
            name: "CAN filter table",
            data: filters,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use canif_model::filter::FilterRow;

    #[test]
    fn the_documented_example_row_is_accept_everything() {
        // ETHERCAT.md: an open-source master writes 0x8001 with one entry
        // 01 00 00 00 00 00 FF FF FF 1F — read here as "accept 0 to 0x1FFFFFFF".
        let mut config = InterfaceConfig::new(FrameFormat::Extended29, 10);
        config.filters.push(FilterRow {
            action: FilterAction::Accept,
            matches: FilterMatch::Range {
                from: 0,
                to: 0x1FFF_FFFF,
            },
        });
        let caps = Capabilities::everything();
        let filters = &downloads(&caps, &config)[2];
        assert_eq!(
            filters.data,
            [1, 0, 0x01, 0x00, 0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0x1F]
        );
    }

    #[test]
    fn the_interface_record_reads_the_public_example() {
        // ETHERCAT.md's example: flags 0x0008 (29-bit with transaction
        // numbers), 10 and 10 slots, queues of 150.
        let mut config = InterfaceConfig::new(FrameFormat::Extended29, 10);
        config.transaction_number = true;
        let caps = Capabilities {
            rx_queue_depth: 150,
            tx_queue_depth: 150,
            ..Capabilities::everything()
        };
        let interface = &downloads(&caps, &config)[1];
        assert_eq!(
            interface.data,
            [0x24, 0, 0x08, 0, 10, 0, 10, 0, 150, 0, 150, 0]
        );
    }
}
