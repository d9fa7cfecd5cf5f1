//! The interface a profile offers for a frame format and queue mode, the
//! same for both sides: 8 slots (or fewer where the profile has fewer), and
//! the transaction number and time stamp wherever the profile has them.

use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode};

/// The interface of `format` and `queue` a profile of `caps` offers.
pub fn interface(format: FrameFormat, queue: QueueMode, caps: &Capabilities) -> InterfaceConfig {
    let mut config = InterfaceConfig::new(format, 8.min(caps.max_slots));
    config.queue = queue;
    let tn_allowed = caps.transaction_number
        && queue == QueueMode::Standard
        && !(caps.transaction_number_only_ext29 && format == FrameFormat::Base11);
    config.transaction_number = format == FrameFormat::Fd || tn_allowed;
    config.time_stamp = format == FrameFormat::Fd
        || (config.transaction_number && caps.time_stamp && format == FrameFormat::Extended29);
    config
}
