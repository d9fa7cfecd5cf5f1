//! Device profiles: which device offers what, as data.

use std::collections::BTreeSet;

use serde::Deserialize;

use crate::error::SpecError;
use crate::lines::line_of;
use crate::source::Source;
use canif_model::config::Capabilities;

/// One device (or firmware range) of the feature matrix in 000/001 §2.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    pub name: String,
    pub device: String,
    pub source: Source,
    pub capabilities: Vec<String>,
    /// Footnote 3: the transaction number only in 29-bit mode.
    #[serde(default)]
    pub transaction_number_only_ext29: bool,
    pub max_slots: u8,
    pub rx_queue_depth: usize,
    pub tx_queue_depth: usize,
    pub timestamp_tolerance_ns: u64,
    #[serde(default)]
    pub notes: Option<String>,
    /// Where the device is an EtherCAT terminal: the identity it must show.
    #[serde(default)]
    pub ethercat: Option<EthercatIdentity>,
    #[serde(skip)]
    pub file: String,
}

/// The identity object (0x1018) and SII words of an EtherCAT terminal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EthercatIdentity {
    pub vendor_id: u32,
    pub product_code: u32,
    pub revision: u32,
}

impl Profile {
    pub fn has(&self, capability: &str) -> bool {
        self.capabilities.iter().any(|c| c == capability)
    }

    /// The capabilities of `needed` this profile does not offer.
    pub fn lacks<'a>(&self, needed: &'a [String]) -> Vec<&'a str> {
        needed
            .iter()
            .filter(|c| !self.has(c))
            .map(String::as_str)
            .collect()
    }

    /// The capabilities the model needs, from this profile's data.
    pub fn model_capabilities(&self) -> Capabilities {
        Capabilities {
            base11: self.has("base11"),
            ext29: self.has("ext29"),
            fd: self.has("fd"),
            fast_queue: self.has("fast_queue"),
            optimized_queue: self.has("optimized_queue"),
            transaction_number: self.has("transaction_number"),
            transaction_number_only_ext29: self.transaction_number_only_ext29,
            time_stamp: self.has("timestamp"),
            filters: self.has("filters"),
            info_data: self.has("info_data"),
            distributed_clocks: self.has("distributed_clocks"),
            max_slots: self.max_slots,
            rx_queue_depth: self.rx_queue_depth,
            tx_queue_depth: self.tx_queue_depth,
            // A device's choice, not the profile's: declared per run.
            tx_queue_accounting: Default::default(),
            freedoms: Default::default(),
            sync1_output_delay: None,
        }
    }

    pub(crate) fn validate(
        &self,
        text: &str,
        known_capabilities: &BTreeSet<&str>,
        known_sources: &BTreeSet<&str>,
        errors: &mut Vec<SpecError>,
    ) {
        let mut error = |field: &str, needle: &str, message: String| {
            errors.push(SpecError {
                file: self.file.clone(),
                line: line_of(text, needle, 1).or_else(|| line_of(text, field, 1)),
                field: field.to_string(),
                message,
            })
        };
        for capability in &self.capabilities {
            if !known_capabilities.contains(capability.as_str()) {
                error(
                    "capabilities",
                    capability,
                    format!("unknown capability `{capability}` (see capabilities.yaml)"),
                );
            }
        }
        let mut seen = BTreeSet::new();
        for capability in &self.capabilities {
            if !seen.insert(capability) {
                error(
                    "capabilities",
                    capability,
                    format!("`{capability}` is listed twice"),
                );
            }
        }
        if !known_sources.contains(self.source.file.as_str()) {
            error(
                "source.file",
                &self.source.file,
                format!("`{}` is not in sources.yaml", self.source.file),
            );
        }
        if !(1..=32).contains(&self.max_slots) {
            error(
                "max_slots",
                "max_slots:",
                format!("{} is outside 1..=32 (ruling R2)", self.max_slots),
            );
        }
        if self.rx_queue_depth == 0 {
            error(
                "rx_queue_depth",
                "rx_queue_depth:",
                "must be at least 1".into(),
            );
        }
        if self.tx_queue_depth < usize::from(self.max_slots) {
            error(
                "tx_queue_depth",
                "tx_queue_depth:",
                format!(
                    "{} is less than max_slots {}: a full batch could never be accepted",
                    self.tx_queue_depth, self.max_slots
                ),
            );
        }
        if !(self.has("base11") || self.has("ext29") || self.has("fd")) {
            error(
                "capabilities",
                "capabilities:",
                "names no frame format (base11, ext29 or fd)".into(),
            );
        }
        if self.transaction_number_only_ext29
            && !(self.has("transaction_number") && self.has("ext29"))
        {
            error(
                "transaction_number_only_ext29",
                "transaction_number_only_ext29:",
                "needs the capabilities transaction_number and ext29".into(),
            );
        }
    }
}
