//! The configuration-refusal grid: every configuration in a grid of formats,
//! queue modes, options, filters and slot counts, and the IUT must accept
//! exactly what the model accepts (the profile's capabilities, 000 §3).

use canif_model::config::{
    Capabilities, ConfigError, FrameFormat, InterfaceConfig, QueueMode, Synchronization,
};
use canif_model::filter::FilterRow;
use canif_spec::{req_ids, ReqId};

use super::iut_kind::IutKind;
use crate::door::iut::BuildError;
use crate::outcome::{Failure, Outcome, ScenarioRun};
use crate::verdict::{NotRunReason, Rest};

fn refusal_ids(error: &ConfigError) -> &'static [ReqId] {
    use ConfigError::*;
    match error {
        // Each format's own statement of who lacks it.
        FormatNotOffered(FrameFormat::Base11) => req_ids!["PROF-002", "PROF-006"],
        FormatNotOffered(FrameFormat::Extended29) => req_ids!["PROF-002", "PROF-009"],
        FormatNotOffered(FrameFormat::Fd) => req_ids!["PROF-002", "PROF-007"],
        QueueModeNotOffered(_) => req_ids!["PROF-002"],
        QueueModeNeedsBase11(_) => req_ids!["BQ-003", "PROF-003"],
        QueueModeWithoutTransactionNumber(_) => req_ids!["BQ-005", "PROF-003"],
        FiltersNotAllowed(_) => req_ids!["BQ-004"],
        FiltersNotOffered => req_ids!["PROF-002"],
        InvalidFilter { .. } => req_ids!["FLT-010"],
        TransactionNumberNotOffered => req_ids!["PROF-002", "PROF-008"],
        TransactionNumberOnlyExt29 => req_ids!["PROF-005", "TN-004"],
        TimeStampNotOffered => req_ids!["PROF-004", "PROF-008"],
        TimeStampNeedsExt29WithTransactionNumber => req_ids!["PROF-004", "TS-002"],
        FdStructuresCarryTransactionNumberAndTimeStamp => req_ids!["LAY-FD-001", "LAY-FD-004"],
        SlotCount { .. } => req_ids!["PROF-011", "LAY-GEN-007"],
        DistributedClocksNotOffered | DistributedClocksNeedsFastQueue => req_ids!["PDX-005"],
    }
}

/// What a device breaks when it refuses a configuration its profile offers:
/// it does not offer what the feature matrix says (PROF-001).
pub const OFFERED_REFUSED: &[ReqId] = req_ids!["PROF-001"];

/// What a device breaks when it refuses an offered configuration at one slot
/// count and takes it at another: the slot range first, then PROF-001.
const SLOT_COUNT_REFUSED: &[ReqId] = req_ids!["LAY-GEN-007", "PROF-011", "PROF-001"];

/// A scenario that could not start because the IUT refused its interface,
/// which the profile offers: a failure of [`OFFERED_REFUSED`], and the rest
/// of what the scenario covers not run, with the IUT's words.
pub fn refused(scenario: &str, config: &InterfaceConfig, reason: String) -> Failure {
    let interface = config.describe();
    let failure = Failure::stopped(
        (OFFERED_REFUSED.to_vec(), scenario.into()),
        format!("configuration {interface}, which the profile offers"),
        ("accepted".into(), format!("refused: {reason}")),
    );
    Failure {
        rest: Rest::NotRun(NotRunReason::Refused { interface, reason }),
        ..failure
    }
}

/// The refusal check's name.
pub const REFUSALS: &str = "configuration refusals";

/// Requirements the refusal check exercises.
pub(super) const REFUSAL_IDS: &[ReqId] = req_ids![
    "PROF-001",
    "PROF-002",
    "PROF-003",
    "PROF-004",
    "PROF-005",
    "PROF-006",
    "PROF-007",
    "PROF-008",
    "PROF-009",
    "PROF-011",
    "PROF-012",
    "BQ-003",
    "BQ-004",
    "BQ-005",
    "FLT-010",
    "TN-004",
    "TS-002",
    "LAY-FD-001",
    "LAY-FD-004",
    "LAY-GEN-007",
    "PDX-005",
];

/// Every configuration of the grid, with its slot counts in the name.
pub fn grid() -> impl Iterator<Item = InterfaceConfig> {
    let filter_tables = || {
        [
            vec![],
            vec![FilterRow::accept_range(0x100, 0x1FF)],
            vec![FilterRow::accept_range(0x200, 0x100)],
            // The edges of FLT-010: one identifier, all 29 bits, and
            // code/mask rows at and beyond them.
            vec![
                FilterRow::accept_range(0x123, 0x123),
                FilterRow::accept_range(0, 0x1FFF_FFFF),
                FilterRow::accept_code_mask(0x1FFF_FFFF, 0),
            ],
            vec![FilterRow::accept_code_mask(0x2000_0000, 0)],
            vec![FilterRow::accept_code_mask(0x2000_0000, 0x2000_0000)],
        ]
    };
    let formats = [
        FrameFormat::Base11,
        FrameFormat::Extended29,
        FrameFormat::Fd,
    ];
    let queues = [QueueMode::Standard, QueueMode::Optimized, QueueMode::Fast];
    let options = [(false, false), (true, false), (false, true), (true, true)];
    let slots = [(0u8, 0u8), (1, 1), (32, 32), (33, 33), (8, 33), (0, 8)];
    formats.into_iter().flat_map(move |format| {
        queues.into_iter().flat_map(move |queue| {
            options.into_iter().flat_map(move |(tn, ts)| {
                filter_tables().into_iter().flat_map(move |filters| {
                    slots.into_iter().flat_map(move |(tx_slots, rx_slots)| {
                        let filters = filters.clone();
                        [false, true].into_iter().map(move |dc| {
                            let mut config = InterfaceConfig::new(format, tx_slots);
                            config.rx_slots = rx_slots;
                            config.queue = queue;
                            config.transaction_number = tn;
                            config.time_stamp = ts;
                            config.filters = filters.clone();
                            if dc {
                                config.synchronization = Synchronization::DistributedClocks {
                                    sync1_shift: 100_000,
                                };
                            }
                            config
                        })
                    })
                })
            })
        })
    })
}

/// Every configuration in the grid: the IUT must accept exactly what the
/// model accepts. The whole grid is tried: every mismatch is blamed (the
/// first shown), and what no mismatch touched held.
pub fn check_refusals(kind: &IutKind, caps: &Capabilities) -> ScenarioRun {
    let mut checked = 0;
    let mut configure = kind.configurer();
    let mut mismatches: Vec<(InterfaceConfig, Failure)> = Vec::new();
    // The configurations the IUT took, to tell a refused slot count apart.
    let mut taken: Vec<InterfaceConfig> = Vec::new();
    let mut outcome = None;
    for config in grid() {
        checked += 1;
        let expected = config.validate(caps);
        let actual = match configure(caps, &config) {
            Ok(()) => Ok(()),
            Err(BuildError::Refused(reason)) => Err(reason),
            Err(BuildError::Failed(reason)) => {
                outcome = Some(Outcome::Error(reason.into()));
                break;
            }
        };
        if actual.is_ok() {
            taken.push(config.clone());
        }
        if expected.is_ok() != actual.is_ok() {
            mismatches.push((config.clone(), mismatch(&config, expected, actual)));
        }
    }
    let same_but_slots = |a: &InterfaceConfig, b: &InterfaceConfig| {
        InterfaceConfig {
            tx_slots: b.tx_slots,
            rx_slots: b.rx_slots,
            ..a.clone()
        } == *b
    };
    let mismatches: Vec<Failure> = mismatches
        .into_iter()
        .map(|(config, mut failure)| {
            let offered = failure.requirements == OFFERED_REFUSED;
            if offered && taken.iter().any(|t| same_but_slots(&config, t)) {
                failure.requirements = SLOT_COUNT_REFUSED.to_vec();
            }
            failure
        })
        .collect();
    let outcome = outcome.unwrap_or_else(|| {
        let Some(mut first) = mismatches.first().cloned() else {
            return Outcome::Pass;
        };
        let mut blamed: Vec<ReqId> = mismatches
            .iter()
            .flat_map(|m| m.requirements.iter().copied())
            .collect();
        // In the order blamed (the statement before PROF-001), each once.
        let mut seen = std::collections::BTreeSet::new();
        blamed.retain(|id| seen.insert(*id));
        first.requirements = blamed;
        if mismatches.len() > 1 {
            first.what = format!(
                "{} (and {} more of the {checked} configurations)",
                first.what,
                mismatches.len() - 1
            );
        }
        first.context = mismatches
            .iter()
            .skip(1)
            .take(20)
            .map(|m| format!("{}: expected {}, actual {}", m.what, m.expected, m.actual))
            .collect();
        first.rest = Rest::Held;
        Outcome::Fail(Box::new(first))
    });
    ScenarioRun {
        cycles: checked,
        ..ScenarioRun::ended(REFUSALS.into(), REFUSAL_IDS.to_vec(), outcome)
    }
}

/// The IUT accepted what the model refuses, or refused what it accepts.
fn mismatch(
    config: &InterfaceConfig,
    expected: Result<(), ConfigError>,
    actual: Result<(), String>,
) -> Failure {
    let said = |result: Result<(), String>| match result {
        Ok(()) => "accepted".to_string(),
        Err(e) => format!("refused: {e}"),
    };
    let requirements = match &expected {
        Err(e) => refusal_ids(e).to_vec(),
        Ok(()) => OFFERED_REFUSED.to_vec(),
    };
    Failure::stopped(
        (requirements, REFUSALS.into()),
        format!(
            "configuration {} with {} Tx and {} Rx slots",
            config.describe(),
            config.tx_slots,
            config.rx_slots
        ),
        (said(expected.map_err(|e| e.to_string())), said(actual)),
    )
}
