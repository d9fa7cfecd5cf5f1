//! Stimulus: what the PLC does and what the other nodes send, cycle by cycle.
//! Scripted scenarios target requirement families; generated ones mix
//! everything from a seed. Steps are produced lazily, so a long run holds
//! bounded memory.

mod generated;
mod scripted;
mod untrusted;

pub use generated::generated;
pub use scripted::*;
pub use untrusted::*;

pub use crate::run::Rng;
use canif_model::config::{FrameFormat, InterfaceConfig, QueueMode};
use canif_model::exchange::ExchangeMode;
use canif_model::frame::{CanId, Frame};
use canif_model::image::MessageRepr;
use canif_model::info_data::ControllerStatus;
use canif_model::timing::BitRates;
use canif_model::Nanos;
use canif_spec::ReqId;

use crate::device::medium::BusChoice;
pub use crate::device::played_plc::OutputEdit;

/// One PLC task cycle of stimulus.
#[derive(Debug, Clone, Default)]
pub struct Step {
    /// Messages the PLC program queues before its task.
    pub send: Vec<MessageRepr>,
    /// The PLC skips its task (outputs stay as they were).
    pub plc_busy: bool,
    /// After its task the PLC writes this TxCounter (a jump: any change counts, G1).
    pub set_tx_counter: Option<u16>,
    /// Frames other nodes want to send, ready at this offset into the cycle.
    pub bus: Vec<(Nanos, Frame)>,
    pub status: Option<ControllerStatus>,
    /// Fields the PLC's program writes itself after the sample code (unusual
    /// or invalid input).
    pub edits: Vec<OutputEdit>,
    /// A whole output image the PLC writes instead of the sample code's.
    pub raw_outputs: Option<Vec<u8>>,
}

/// How a scenario judges the IUT.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Judgement {
    /// Field by field and frame by frame against the model.
    #[default]
    Exact,
    /// Only by the bounds of G3, for input whose treatment the documents leave
    /// to the implementer: never more frames on the bus than the slots of the
    /// batches it acknowledged (HS-TX-010), no invalid frame (LAY-GEN-008),
    /// the image's size kept, and the interface still cycling afterwards.
    /// Where the device declared each of `decided_by` (and there is one),
    /// the model judges it taking those choices, exactly.
    Bounds {
        decided_by: &'static [crate::declare::choices::Choice],
    },
}

/// How a scenario's steps come about.
#[derive(Debug, Clone)]
pub enum Steps {
    Scripted(Vec<Step>),
    /// Random PLC and bus behaviour for `cycles` cycles from `seed`, then a drain.
    Generated {
        cycles: u64,
        seed: u64,
        load_percent: u64,
    },
    /// One frame received and read every cycle, long enough for RxCounter to wrap.
    RxWrap {
        cycles: u64,
    },
}

/// A scenario: an interface, the exchange and bus timing, and the stimulus.
#[derive(Debug, Clone)]
pub struct Scenario {
    pub name: String,
    /// The requirements it exercises; failures are attributed within these.
    pub covers: Vec<ReqId>,
    pub interface: InterfaceConfig,
    pub exchange: ExchangeMode,
    pub bit_rates: BitRates,
    pub cycle_time: Nanos,
    pub check_confirmation_delay: bool,
    /// FD Tx messages whose dataLength the PLC writes as this (not a valid
    /// size), keyed by transaction number; the bytes past it hold junk.
    pub declared_lengths: Vec<(u16, u8)>,
    /// How far a receive time stamp may be from the end of reception (the
    /// profile's timestamp_tolerance_ns, TS-004).
    pub time_stamp_tolerance: Nanos,
    /// Write the bus as `DIR/NAME.log` (candump) and `DIR/NAME.pcapng`.
    pub trace: Option<(std::path::PathBuf, String, canif_model::Nanos)>,
    /// The bus it runs on.
    pub bus: BusChoice,
    pub judgement: Judgement,
    /// What the command line or the IUT's kind declared of the device's
    /// choices; where it says nothing, the IUT's own declaration counts.
    pub declared: crate::declare::choices::Declared,
    pub steps: Steps,
}

impl Scenario {
    /// Whether it delivers received messages through a buffered Rx queue
    /// (where what a delivery leaves, and an idle NoOfRxMessages, are the
    /// device's declared choices: HS-RX-008, HS-RX-009).
    pub fn delivers_buffered(&self) -> bool {
        self.interface.queue.is_buffered()
            && self
                .covers
                .iter()
                .any(|id| crate::device::blame::RX_SET.contains(id))
    }

    pub fn steps(&self) -> Box<dyn Iterator<Item = Step> + '_> {
        match &self.steps {
            Steps::Scripted(steps) => Box::new(steps.iter().cloned()),
            Steps::Generated {
                cycles,
                seed,
                load_percent,
            } => {
                let mut gen = generated::Generator::new(self, *seed, *load_percent);
                let cycles = *cycles;
                Box::new((0..cycles + 200).map(move |k| {
                    if k < cycles {
                        gen.step()
                    } else {
                        Step::default()
                    }
                }))
            }
            Steps::RxWrap { cycles } => {
                let offset = self.cycle_time / 2;
                Box::new((0..*cycles).map(move |k| Step {
                    bus: vec![(
                        offset,
                        Frame::classic(CanId::Standard((k % 0x7FF) as u16), &[k as u8]).unwrap(),
                    )],
                    ..Step::default()
                }))
            }
        }
    }
}

/// Ids every scenario on an interface of this shape exercises.
fn layout_ids(config: &InterfaceConfig) -> Vec<&'static str> {
    let mut ids = vec![
        "LAY-GEN-001",
        "LAY-GEN-002",
        "LAY-GEN-003",
        "LAY-GEN-004",
        "LAY-GEN-007",
        "PDX-003",
    ];
    match config.format {
        FrameFormat::Base11 => ids.extend([
            "LAY-11-001",
            "LAY-11-002",
            "LAY-11-003",
            "LAY-11-004",
            "LAY-GEN-005",
        ]),
        FrameFormat::Extended29 => ids.extend([
            "LAY-29-001",
            "LAY-29-002",
            "LAY-29-003",
            "LAY-29-004",
            "LAY-29-005",
        ]),
        FrameFormat::Fd => ids.extend([
            "LAY-FD-001",
            "LAY-FD-002",
            "FD-001",
            "FD-BIT-001",
            "FD-BIT-002",
            "FD-BIT-003",
        ]),
    }
    if config.transaction_number || config.format == FrameFormat::Fd {
        ids.extend(["LAY-GEN-006", "TN-001", "TN-002", "TN-003"]);
    } else if config.format != FrameFormat::Fd {
        ids.push("LAY-GEN-005");
    }
    if config.time_stamp {
        ids.extend(["TS-001", "TS-003", "TS-004"]);
    }
    match config.queue {
        QueueMode::Fast => ids.extend(["FQ-003"]),
        QueueMode::Optimized => ids.extend(["BQ-001"]),
        QueueMode::Standard => {}
    }
    ids
}

/// Can a scenario on this interface exercise the requirement at all?
fn exercisable(id: &str, config: &InterfaceConfig) -> bool {
    let buffered = config.queue != QueueMode::Fast;
    let fd = config.format == FrameFormat::Fd;
    let tn = config.transaction_number || fd;
    match id {
        _ if id.starts_with("FQ-") => config.queue == QueueMode::Fast,
        "BQ-001" => config.queue == QueueMode::Optimized,
        "BQ-002" | "HS-RX-001" | "HS-RX-004" | "RXQ-003" | "RXQ-004" | "RXQ-006" => buffered,
        _ if id.starts_with("FD-") || id.starts_with("LAY-FD-") || id == "ERR-R1" => fd,
        _ if id.starts_with("TN-") || id == "LAY-GEN-006" => tn,
        _ if id.starts_with("TS-") => config.time_stamp,
        "FLT-008" => config.filters.is_empty(),
        "FLT-009" => config.filters == scripted::manual_table(),
        _ if id.starts_with("FLT-") => !config.filters.is_empty(),
        _ if id.starts_with("LAY-11-") => config.format == FrameFormat::Base11,
        _ if id.starts_with("LAY-29-") => config.format == FrameFormat::Extended29,
        "RXQ-005" => config.format == FrameFormat::Base11,
        _ => true,
    }
}

pub(crate) fn scenario(
    name: &str,
    config: &InterfaceConfig,
    covers: &[&'static str],
    steps: Steps,
) -> Scenario {
    let mut ids: Vec<ReqId> = layout_ids(config)
        .into_iter()
        .chain(covers.iter().copied())
        .filter(|id| exercisable(id, config))
        .map(ReqId::new)
        .collect();
    ids.sort();
    ids.dedup();
    let fd = config.format == FrameFormat::Fd;
    Scenario {
        name: name.to_string(),
        covers: ids,
        interface: config.clone(),
        exchange: ExchangeMode::SeparateInputUpdate,
        bit_rates: if fd {
            BitRates {
                nominal: 500_000,
                data: 2_000_000,
            }
        } else {
            BitRates::classic(500_000)
        },
        cycle_time: 1_000_000,
        check_confirmation_delay: false,
        declared_lengths: Vec::new(),
        time_stamp_tolerance: 0,
        trace: None,
        bus: BusChoice::Sim,
        judgement: Judgement::Exact,
        declared: Default::default(),
        steps,
    }
}
