//! `configure`: the interface, the profile's capabilities, the bus; and the
//! controller status.

use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode, Synchronization};
use canif_model::filter::{FilterAction, FilterMatch, FilterRow};
use canif_model::image::ImageLayout;
use canif_model::info_data::{BitTiming, ControllerStatus};
use canif_model::Nanos;
use serde::{Deserialize, Serialize};

/// `configure.config`: the interface as the PLC configured it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    pub format: Format,
    pub queue: Queue,
    pub transaction_number: bool,
    pub time_stamp: bool,
    pub tx_slots: u8,
    pub rx_slots: u8,
    // Every field is required, as the schema says: a default here once took
    // a `configure` without its data bit timing as one with 0.
    pub filters: Vec<Filter>,
    #[serde(deserialize_with = "present")]
    pub sync1_shift_ns: Option<Nanos>,
    pub nominal_timing: u32,
    pub data_timing: u32,
    pub output_size: usize,
    pub input_size: usize,
}

/// An `Option` field that must be there, `null` or not (serde would take a
/// missing one as `None`).
fn present<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(
    deserializer: D,
) -> Result<Option<T>, D::Error> {
    Option::<T>::deserialize(deserializer)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Format {
    #[serde(rename = "11-bit")]
    Base11,
    #[serde(rename = "29-bit")]
    Extended29,
    #[serde(rename = "fd")]
    Fd,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Queue {
    Standard,
    Optimized,
    Fast,
}

/// One row of the filter table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Filter {
    Range {
        action: Action,
        from: u32,
        to: u32,
    },
    Mask {
        action: Action,
        code: u32,
        mask: u32,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Action {
    Accept,
    Reject,
}

/// `configure.capabilities`: what the profile offers, the model's
/// [`Capabilities`] on the wire field for field (serde's remote derive lists
/// the fields once, in `CapsFields`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Caps(#[serde(with = "CapsFields")] pub Capabilities);

#[derive(Serialize, Deserialize)]
#[serde(remote = "Capabilities", deny_unknown_fields)]
struct CapsFields {
    base11: bool,
    ext29: bool,
    fd: bool,
    fast_queue: bool,
    optimized_queue: bool,
    transaction_number: bool,
    transaction_number_only_ext29: bool,
    #[serde(rename = "timestamp")]
    time_stamp: bool,
    filters: bool,
    info_data: bool,
    distributed_clocks: bool,
    max_slots: u8,
    rx_queue_depth: usize,
    tx_queue_depth: usize,
    /// The device's own choice, declared to canif, never sent to it.
    #[serde(skip)]
    tx_queue_accounting: canif_model::config::TxQueueAccounting,
    #[serde(skip)]
    sync1_output_delay: Option<canif_model::Nanos>,
    #[serde(skip)]
    freedoms: canif_model::freedoms::Freedoms,
}

/// `configure.bus`: a SocketCAN interface an external IUT opens itself; its
/// time stamps count from `epoch_ns` of CLOCK_REALTIME.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OwnedBus {
    pub epoch_ns: u64,
    #[serde(rename = "socketcan")]
    pub interface: String,
}

/// `controller_status.status`: the model's [`ControllerStatus`] on the wire,
/// field for field (serde's remote derive lists the fields once, in `StatusFields`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub struct Status(#[serde(with = "StatusFields")] pub ControllerStatus);

impl<'de> Deserialize<'de> for Status {
    /// From an object only: serde's derive also takes a struct from an
    /// array of its fields, and an empty one (`"status": []`) as all defaults.
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let object = serde_json::Map::deserialize(deserializer)?;
        StatusFields::deserialize(serde_json::Value::Object(object))
            .map(Status)
            .map_err(serde::de::Error::custom)
    }
}

#[derive(Serialize, Deserialize)]
#[serde(
    remote = "ControllerStatus",
    default = "ControllerStatus::default",
    deny_unknown_fields
)]
struct StatusFields {
    bus_off: bool,
    error_passive: bool,
    node_active: bool,
    warning_limit: bool,
    overload: bool,
    bus_idle: bool,
    transceiver_delay: u32,
    ack_errors: u32,
    bit_errors: u32,
    crc_errors: u32,
    form_errors: u32,
    stuff_errors: u32,
    receive_error_counter: u32,
    transmit_error_counter: u32,
    core_running: bool,
}

impl From<&ControllerStatus> for Status {
    fn from(status: &ControllerStatus) -> Self {
        Status(*status)
    }
}

impl From<&Status> for ControllerStatus {
    fn from(status: &Status) -> Self {
        status.0
    }
}

impl Config {
    pub fn new(config: &InterfaceConfig, layout: &ImageLayout) -> Self {
        Config {
            format: match config.format {
                FrameFormat::Base11 => Format::Base11,
                FrameFormat::Extended29 => Format::Extended29,
                FrameFormat::Fd => Format::Fd,
            },
            queue: match config.queue {
                QueueMode::Standard => Queue::Standard,
                QueueMode::Optimized => Queue::Optimized,
                QueueMode::Fast => Queue::Fast,
            },
            transaction_number: config.transaction_number,
            time_stamp: config.time_stamp,
            tx_slots: config.tx_slots,
            rx_slots: config.rx_slots,
            filters: config
                .filters
                .iter()
                .map(|row| {
                    let action = match row.action {
                        FilterAction::Accept => Action::Accept,
                        FilterAction::Reject => Action::Reject,
                    };
                    match row.matches {
                        FilterMatch::Range { from, to } => Filter::Range { action, from, to },
                        FilterMatch::CodeMask { code, mask } => Filter::Mask { action, code, mask },
                    }
                })
                .collect(),
            sync1_shift_ns: match config.synchronization {
                Synchronization::Sm2 => None,
                Synchronization::DistributedClocks { sync1_shift } => Some(sync1_shift),
            },
            nominal_timing: config.nominal_timing.to_word(),
            data_timing: config.data_timing.to_word(),
            output_size: layout.output_size(),
            input_size: layout.input_size(),
        }
    }

    /// The model's configuration.
    pub fn interface(&self) -> InterfaceConfig {
        let format = match self.format {
            Format::Base11 => FrameFormat::Base11,
            Format::Extended29 => FrameFormat::Extended29,
            Format::Fd => FrameFormat::Fd,
        };
        let mut interface = InterfaceConfig::new(format, self.tx_slots);
        interface.queue = match self.queue {
            Queue::Standard => QueueMode::Standard,
            Queue::Optimized => QueueMode::Optimized,
            Queue::Fast => QueueMode::Fast,
        };
        interface.rx_slots = self.rx_slots;
        interface.transaction_number = self.transaction_number;
        interface.time_stamp = self.time_stamp;
        interface.synchronization = match self.sync1_shift_ns {
            Some(sync1_shift) => Synchronization::DistributedClocks { sync1_shift },
            None => Synchronization::Sm2,
        };
        interface.nominal_timing = BitTiming::from_word(self.nominal_timing);
        interface.data_timing = BitTiming::from_word(self.data_timing);
        interface.filters = self
            .filters
            .iter()
            .map(|row| {
                let (action, matches) = match *row {
                    Filter::Range { action, from, to } => (action, FilterMatch::Range { from, to }),
                    Filter::Mask { action, code, mask } => {
                        (action, FilterMatch::CodeMask { code, mask })
                    }
                };
                FilterRow {
                    action: match action {
                        Action::Accept => FilterAction::Accept,
                        Action::Reject => FilterAction::Reject,
                    },
                    matches,
                }
            })
            .collect();
        interface
    }
}

impl From<&Capabilities> for Caps {
    fn from(caps: &Capabilities) -> Self {
        Caps(caps.clone())
    }
}

impl From<&Caps> for Capabilities {
    fn from(caps: &Caps) -> Self {
        caps.0.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_status_is_a_flat_object_with_defaults_and_no_unknown_fields() {
        let status = Status(ControllerStatus {
            bus_off: true,
            crc_errors: 7,
            ..ControllerStatus::default()
        });
        let text = serde_json::to_string(&status).unwrap();
        assert!(text.starts_with("{\"bus_off\":true,") && text.contains("\"crc_errors\":7"));
        assert_eq!(serde_json::from_str::<Status>(&text).unwrap(), status);
        let sparse: Status = serde_json::from_str(r#"{"crc_errors": 7, "bus_off": true}"#).unwrap();
        assert_eq!(sparse, status);
        assert!(serde_json::from_str::<Status>(r#"{"bus_of": true}"#).is_err());
    }
}

/// `configure`'s and `start`'s `shared` field: the harness offers protocol 3
/// on these descriptors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SharedOffer {
    pub memfd: u32,
    pub wake_iut: u32,
    pub wake_harness: u32,
    pub size: u64,
}

impl SharedOffer {
    /// The field as it must come when it comes: an object, never `null`
    /// (the schema's word; serde would take `null` as absent).
    pub fn not_null<'de, D: serde::Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Option<SharedOffer>, D::Error> {
        SharedOffer::deserialize(deserializer).map(Some)
    }
}
