//! What an interface is configured as, what a device can offer, and which
//! combinations are refused.
//!
//! Source: 000/001 §2 (feature matrix and footnotes), §3 (choose only modes the
//! hardware supports), §5.1 (queue modes), §5.1.2 (no filters in Fast/Optimized),
//! 003 (Distributed Clocks only in Fast CAN Queue mode), ruling R2 (1..=32 slots).

use crate::filter::FilterRow;
use crate::freedoms::Freedoms;
use crate::info_data::BitTiming;
use crate::Nanos;

/// The message format the interface is set up with ("Frame-Format", §3).
///
/// Requirements: PROF-006, PROF-007.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameFormat {
    /// 11-bit identifiers, COB ID word (CAN 2.0A).
    Base11,
    /// 29-bit message structure; carries 11-bit and 29-bit frames (CAN 2.0B).
    Extended29,
    /// CAN FD structures (FC532x, CX-M530).
    Fd,
}

/// How received messages travel from the controller to the input image.
///
/// Requirements: BQ-001, FQ-001, BQ-005.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum QueueMode {
    /// The plain CAN interface: buffered, with the Rx handshake.
    Standard,
    /// Optimized CAN Queue: buffered (1-buffer mode), 11-bit only, no filters.
    Optimized,
    /// Fast CAN Queue: unbuffered (3-buffer mode), no Rx acknowledge.
    Fast,
}

impl QueueMode {
    pub fn is_buffered(self) -> bool {
        !matches!(self, QueueMode::Fast)
    }
}

/// What starts the CAN interface cycle.
///
/// Requirements: PDX-004, PDX-005.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Synchronization {
    /// The Sync Manager 2 event of the process-data telegram (default).
    Sm2,
    /// SYNC0 starts the cycle; the first Tx message waits for SYNC1, which comes
    /// `sync1_shift` after SYNC0.
    DistributedClocks { sync1_shift: Nanos },
}

/// One interface as configured in TwinCAT.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InterfaceConfig {
    pub format: FrameFormat,
    pub queue: QueueMode,
    pub transaction_number: bool,
    pub time_stamp: bool,
    /// Number of Tx message slots in the output image (1..=32).
    pub tx_slots: u8,
    /// Number of Rx message slots in the input image (1..=32).
    pub rx_slots: u8,
    pub filters: Vec<FilterRow>,
    pub synchronization: Synchronization,
    /// Arbitration phase bit timing, reported in `InfoData[1]`.
    pub nominal_timing: BitTiming,
    /// Data phase bit timing, reported in `InfoData[2]` (CAN FD).
    pub data_timing: BitTiming,
}

impl InterfaceConfig {
    /// A plain buffered interface with `slots` slots each way and nothing else.
    pub fn new(format: FrameFormat, slots: u8) -> Self {
        InterfaceConfig {
            format,
            queue: QueueMode::Standard,
            transaction_number: format == FrameFormat::Fd,
            time_stamp: format == FrameFormat::Fd,
            tx_slots: slots,
            rx_slots: slots,
            filters: Vec::new(),
            synchronization: Synchronization::Sm2,
            nominal_timing: BitTiming::default(),
            data_timing: BitTiming::default(),
        }
    }
}

/// What a device offers: the data of a device profile that the model needs.
///
/// Requirements: PROF-001, RXQ-001, RXQ-002.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Capabilities {
    pub base11: bool,
    pub ext29: bool,
    pub fd: bool,
    pub fast_queue: bool,
    pub optimized_queue: bool,
    pub transaction_number: bool,
    /// Footnote 3: transaction numbers only in 29-bit mode (EL6751 legacy mapping).
    pub transaction_number_only_ext29: bool,
    pub time_stamp: bool,
    pub filters: bool,
    pub info_data: bool,
    pub distributed_clocks: bool,
    /// Largest slot count per direction.
    pub max_slots: u8,
    /// Local Rx queue depth in messages (EL6751 150, CCAT 512).
    pub rx_queue_depth: usize,
    /// Local send queue depth in messages (assumption HS-TX-008).
    pub tx_queue_depth: usize,
    /// Whether the frame on the wire counts against `tx_queue_depth`: a
    /// choice the documents leave (HS-TX-012), which a device declares.
    pub tx_queue_accounting: TxQueueAccounting,
    /// With Distributed Clocks, the time from SYNC1 to the start of the first
    /// Tx message (003's output delay; ruling R10: the device's constant, no
    /// document gives it): declared, or `None` and measured at the first batch.
    pub sync1_output_delay: Option<Nanos>,
    /// What the device does where G3 and HS-RX-008/009 leave it free.
    pub freedoms: Freedoms,
}

/// What counts against the local send queue's depth when the device decides
/// whether a batch fits (HS-TX-012). 003 says the first message goes out at
/// once when the controller is idle and is queued otherwise, but not whether
/// the frame being sent still takes a place: either reading is documented.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum TxQueueAccounting {
    /// The frame on the wire has left the queue (canif's reading of 003).
    #[default]
    WireOutsideQueue,
    /// The frame on the wire still takes its place until it is sent.
    WireInQueue,
}

impl crate::freedoms::Named for TxQueueAccounting {
    const ALL: &'static [Self] = &[
        TxQueueAccounting::WireOutsideQueue,
        TxQueueAccounting::WireInQueue,
    ];
    const NAMES: &'static [&'static str] = &["wire-outside-queue", "wire-in-queue"];

    /// The choice's name, as declared (`--declare tx-queue-accounting=NAME`).
    fn name(self) -> &'static str {
        match self {
            TxQueueAccounting::WireOutsideQueue => "wire-outside-queue",
            TxQueueAccounting::WireInQueue => "wire-in-queue",
        }
    }
}

impl TxQueueAccounting {
    /// How many places the queue takes with `waiting` messages queued and,
    /// perhaps, one on the wire.
    pub fn taken(self, waiting: usize, on_wire: bool) -> usize {
        match self {
            TxQueueAccounting::WireOutsideQueue => waiting,
            TxQueueAccounting::WireInQueue => waiting + usize::from(on_wire),
        }
    }
}

impl Capabilities {
    /// The frame format of the profile's first interface: 11-bit where it has
    /// it, else 29-bit, else CAN FD.
    pub fn first_format(&self) -> FrameFormat {
        if self.base11 {
            FrameFormat::Base11
        } else if self.ext29 {
            FrameFormat::Extended29
        } else {
            FrameFormat::Fd
        }
    }

    /// Everything on, 32 slots, EL6751 queue depths: for tests of single features.
    pub fn everything() -> Self {
        Capabilities {
            base11: true,
            ext29: true,
            fd: true,
            fast_queue: true,
            optimized_queue: true,
            transaction_number: true,
            transaction_number_only_ext29: false,
            time_stamp: true,
            filters: true,
            info_data: true,
            distributed_clocks: true,
            max_slots: 32,
            rx_queue_depth: 150,
            tx_queue_depth: 64,
            tx_queue_accounting: TxQueueAccounting::default(),
            sync1_output_delay: None,
            freedoms: Freedoms::default(),
        }
    }
}

/// A configuration the device refuses, with the reason.
///
/// Requirements: PROF-002..PROF-005, PROF-008..PROF-012, FLT-010.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ConfigError {
    FormatNotOffered(FrameFormat),
    QueueModeNotOffered(QueueMode),
    QueueModeNeedsBase11(QueueMode),
    QueueModeWithoutTransactionNumber(QueueMode),
    FiltersNotAllowed(QueueMode),
    FiltersNotOffered,
    InvalidFilter {
        row: usize,
        reason: String,
    },
    TransactionNumberNotOffered,
    TransactionNumberOnlyExt29,
    TimeStampNotOffered,
    TimeStampNeedsExt29WithTransactionNumber,
    FdStructuresCarryTransactionNumberAndTimeStamp,
    SlotCount {
        direction: &'static str,
        slots: u8,
        max: u8,
    },
    DistributedClocksNotOffered,
    DistributedClocksNeedsFastQueue,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        use ConfigError::*;
        match self {
            FormatNotOffered(format) => write!(f, "the device does not offer the {format:?} frame format (000 §2)"),
            QueueModeNotOffered(mode) => write!(f, "the device does not offer the {mode:?} CAN queue (000 §2)"),
            QueueModeNeedsBase11(mode) => write!(f, "the {mode:?} CAN queue supports only 11-bit identifiers (000 §5.1.2, §2 footnote 1)"),
            QueueModeWithoutTransactionNumber(mode) => write!(f, "the {mode:?} CAN queue has no transaction number (000 §2 footnote 1)"),
            FiltersNotAllowed(mode) => write!(f, "filters cannot be used with the {mode:?} CAN queue (000 §5.1.2)"),
            FiltersNotOffered => write!(f, "the device offers no receive filters"),
            InvalidFilter { row, reason } => write!(f, "filter row {}: {reason}", row + 1),
            TransactionNumberNotOffered => write!(f, "the device offers no transaction number (000 §2)"),
            TransactionNumberOnlyExt29 => write!(f, "this device offers the transaction number only in 29-bit mode (000 §2 footnote 3)"),
            TimeStampNotOffered => write!(f, "the device offers no time stamp (000 §2)"),
            TimeStampNeedsExt29WithTransactionNumber => write!(f, "the time stamp exists only in 29-bit mode with transaction number (000 §2 footnote 2)"),
            FdStructuresCarryTransactionNumberAndTimeStamp => write!(f, "the CAN FD structures always carry transactionNumber and timeStamp (000 §8.3): enable both"),
            SlotCount { direction, slots, max } => write!(f, "{direction} slot count {slots} is outside 1..={max} (ruling R2)"),
            DistributedClocksNotOffered => write!(f, "the device cannot synchronise with Distributed Clocks (003)"),
            DistributedClocksNeedsFastQueue => write!(f, "Distributed Clocks synchronisation exists only in Fast CAN Queue mode (003)"),
        }
    }
}

impl std::error::Error for ConfigError {}

impl InterfaceConfig {
    /// The interface's short name, as every report and both sides name it:
    /// its frame format, then what it adds (queue, transaction numbers, time
    /// stamps, filters, Distributed Clocks), e.g. `11-bit, optimized, TN`.
    pub fn describe(&self) -> String {
        let mut parts = vec![match self.format {
            FrameFormat::Base11 => "11-bit",
            FrameFormat::Extended29 => "29-bit",
            FrameFormat::Fd => "FD",
        }];
        match self.queue {
            QueueMode::Standard => {}
            QueueMode::Optimized => parts.push("optimized"),
            QueueMode::Fast => parts.push("fast"),
        }
        // An FD image has both, always: naming them would say nothing.
        if self.transaction_number && self.format != FrameFormat::Fd {
            parts.push("TN");
        }
        if self.time_stamp && self.format != FrameFormat::Fd {
            parts.push("TS");
        }
        if !self.filters.is_empty() {
            parts.push("filters");
        }
        if let Synchronization::DistributedClocks { .. } = self.synchronization {
            parts.push("DC");
        }
        parts.join(", ")
    }

    /// Checks the configuration against what the device offers.
    pub fn validate(&self, caps: &Capabilities) -> Result<(), ConfigError> {
        use ConfigError::*;
        let offered = match self.format {
            FrameFormat::Base11 => caps.base11,
            FrameFormat::Extended29 => caps.ext29,
            FrameFormat::Fd => caps.fd,
        };
        if !offered {
            return Err(FormatNotOffered(self.format));
        }
        match self.queue {
            QueueMode::Standard => {}
            QueueMode::Optimized if !caps.optimized_queue => {
                return Err(QueueModeNotOffered(self.queue))
            }
            QueueMode::Fast if !caps.fast_queue => return Err(QueueModeNotOffered(self.queue)),
            mode => {
                if self.format != FrameFormat::Base11 {
                    return Err(QueueModeNeedsBase11(mode));
                }
                if self.transaction_number {
                    return Err(QueueModeWithoutTransactionNumber(mode));
                }
                if !self.filters.is_empty() {
                    return Err(FiltersNotAllowed(mode));
                }
            }
        }
        if !self.filters.is_empty() && !caps.filters {
            return Err(FiltersNotOffered);
        }
        for (row, filter) in self.filters.iter().enumerate() {
            filter
                .check()
                .map_err(|reason| InvalidFilter { row, reason })?;
        }
        if self.transaction_number {
            if !caps.transaction_number {
                return Err(TransactionNumberNotOffered);
            }
            if caps.transaction_number_only_ext29 && self.format == FrameFormat::Base11 {
                return Err(TransactionNumberOnlyExt29);
            }
        }
        if self.time_stamp {
            if !caps.time_stamp {
                return Err(TimeStampNotOffered);
            }
            if self.format == FrameFormat::Base11 || !self.transaction_number {
                return Err(TimeStampNeedsExt29WithTransactionNumber);
            }
        }
        if self.format == FrameFormat::Fd && !(self.transaction_number && self.time_stamp) {
            return Err(FdStructuresCarryTransactionNumberAndTimeStamp);
        }
        for (direction, slots) in [("Tx", self.tx_slots), ("Rx", self.rx_slots)] {
            if slots == 0 || slots > caps.max_slots {
                return Err(SlotCount {
                    direction,
                    slots,
                    max: caps.max_slots,
                });
            }
        }
        if let Synchronization::DistributedClocks { .. } = self.synchronization {
            if !caps.distributed_clocks {
                return Err(DistributedClocksNotOffered);
            }
            if self.queue != QueueMode::Fast {
                return Err(DistributedClocksNeedsFastQueue);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn tx_queue_accounting_reads_back_by_its_name_and_the_reference_comes_first() {
        crate::freedoms::tests::round_trip::<super::TxQueueAccounting>();
    }
}
