//! One profile's conformance run: the interfaces it offers, the scenarios on
//! each, the configurations it must refuse, and a verdict per requirement.

use std::collections::BTreeMap;

use canif_model::config::{
    Capabilities, ConfigError, FrameFormat, InterfaceConfig, QueueMode, Synchronization,
};
use canif_model::filter::FilterRow;
use canif_model::Nanos;
use canif_spec::{req_ids, Catalogue, Profile, ReqId};

use crate::bus::BusChoice;
use crate::error::RunError;
use crate::iut::BuildError;
use crate::iut_kind::IutKind;
use crate::lockstep::run_scenario;
use crate::outcome::{Failure, Outcome, ScenarioRun};
use crate::scenario::{self, Scenario};
use crate::verdict::{self, Check, CheckResult, Evidence, Finding, Reach, Verdict, VerdictKind};

/// What to run.
#[derive(Debug, Clone)]
pub struct Options {
    pub seed: u64,
    /// Generated scenarios per interface.
    pub cases: u64,
    /// Cycles of each generated scenario.
    pub generated_cycles: u64,
    /// Include the 65,540-cycle RxCounter wrap.
    pub counter_wrap: bool,
    /// Write each scenario's bus trace under this folder (`PROFILE/SCENARIO.{log,pcapng}`).
    pub trace_dir: Option<std::path::PathBuf>,
    /// What a trace stamps scenario time 0 with, in ns since the Unix epoch.
    pub trace_epoch: Nanos,
    /// The bus the scenarios run on.
    pub bus: BusChoice,
    /// Which scenarios run (all by default).
    pub selection: Selection,
    /// After the IUT breaks in a profile, report the profile's remaining
    /// scenarios as skipped instead of starting the broken IUT again.
    pub fail_fast: bool,
}

impl Options {
    /// A short run for tests: one generated case of 100 cycles, no counter wrap.
    pub fn quick(seed: u64) -> Self {
        Options {
            seed,
            cases: 1,
            generated_cycles: 100,
            counter_wrap: false,
            trace_dir: None,
            trace_epoch: 0,
            bus: BusChoice::Sim,
            fail_fast: true,
            selection: Selection::default(),
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            cases: 4,
            generated_cycles: 200,
            counter_wrap: true,
            ..Options::quick(1)
        }
    }
}

/// What a run is asked to run: everything, or the checks whose name contains
/// one of `scenarios` or that exercise one of `requirements`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Selection {
    pub scenarios: Vec<String>,
    pub requirements: Vec<String>,
}

impl Selection {
    pub fn is_everything(&self) -> bool {
        self.scenarios.is_empty() && self.requirements.is_empty()
    }

    /// Does the selection take a check of this name that exercises `covers`?
    pub fn admits<'a>(&self, name: &str, mut covers: impl Iterator<Item = &'a str>) -> bool {
        self.is_everything()
            || self.scenarios.iter().any(|s| name.contains(s.as_str()))
            || covers.any(|id| self.requirements.iter().any(|r| r == id))
    }

    /// The options that made it: `--scenario X --requirement Y`.
    pub fn flags(&self) -> String {
        let scenarios = self.scenarios.iter().map(|s| format!("--scenario {s}"));
        let requirements = self
            .requirements
            .iter()
            .map(|r| format!("--requirement {r}"));
        scenarios.chain(requirements).collect::<Vec<_>>().join(" ")
    }

    /// Why a requirement it leaves out was not run.
    pub fn describe(&self) -> String {
        if self.is_everything() {
            "not selected".into()
        } else {
            format!("left out by the selection ({})", self.flags())
        }
    }
}

/// Everything one profile's run produced.
#[derive(Debug, Clone)]
pub struct ProfileRun {
    pub profile: String,
    pub runs: Vec<ScenarioRun>,
    pub failures: Vec<Failure>,
    pub verdicts: BTreeMap<String, Verdict>,
}

impl ProfileRun {
    /// A profile on which no lockstep scenario ran (the CANopen suite's node).
    pub fn none(profile: &str) -> Self {
        ProfileRun {
            profile: profile.to_string(),
            runs: Vec::new(),
            failures: Vec::new(),
            verdicts: BTreeMap::new(),
        }
    }

    /// The requirements that failed on this profile.
    pub fn failed_requirements(&self) -> Vec<String> {
        self.verdicts
            .iter()
            .filter(|(_, v)| v.kind() == VerdictKind::Fail)
            .map(|(id, _)| id.clone())
            .collect()
    }

    /// The lockstep scenarios as checks for [`verdict::judge`].
    pub fn checks(&self) -> Vec<Check> {
        let mut failures = 0;
        self.runs
            .iter()
            .map(|run| Check {
                evidence: Evidence::Scenario(run.scenario.clone()),
                covers: run.covers.iter().map(|id| id.to_string()).collect(),
                result: match &run.outcome {
                    Outcome::Pass => CheckResult::Pass,
                    Outcome::Fail(failure) => {
                        failures += 1;
                        CheckResult::Fail(Finding {
                            requirements: failure
                                .requirements
                                .iter()
                                .map(|id| id.to_string())
                                .collect(),
                            cause: failure.cause(),
                            details: failure.details(),
                            failure: Some(failures - 1),
                        })
                    }
                    Outcome::Error(error) => CheckResult::Error(error.to_string()),
                },
                elapsed: run.elapsed,
            })
            .collect()
    }

    pub fn frames_checked(&self) -> u64 {
        self.runs.iter().map(|r| r.frames_checked).sum()
    }
    pub fn cycles(&self) -> u64 {
        self.runs.iter().map(|r| r.cycles).sum()
    }
}

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

/// The scenarios for a profile: each interface it offers with what fits it.
pub fn scenarios(caps: &Capabilities, options: &Options) -> Vec<Scenario> {
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
        scenario.name = format!("{} [{}]", scenario.name, describe(&scenario.interface));
    }
    list
}

/// A short name for an interface configuration.
pub fn describe(config: &InterfaceConfig) -> String {
    let mut parts = vec![match config.format {
        FrameFormat::Base11 => "11-bit",
        FrameFormat::Extended29 => "29-bit",
        FrameFormat::Fd => "FD",
    }
    .to_string()];
    match config.queue {
        QueueMode::Standard => {}
        QueueMode::Optimized => parts.push("optimized".into()),
        QueueMode::Fast => parts.push("fast".into()),
    }
    if config.transaction_number && config.format != FrameFormat::Fd {
        parts.push("TN".into());
    }
    if config.time_stamp && config.format != FrameFormat::Fd {
        parts.push("TS".into());
    }
    if !config.filters.is_empty() {
        parts.push("filters".into());
    }
    if let Synchronization::DistributedClocks { .. } = config.synchronization {
        parts.push("DC".into());
    }
    parts.join(", ")
}

fn refusal_ids(error: &ConfigError) -> &'static [ReqId] {
    use ConfigError::*;
    match error {
        FormatNotOffered(_) => req_ids!["PROF-002", "PROF-006", "PROF-007", "PROF-009"],
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

/// The refusal check's name.
pub const REFUSALS: &str = "configuration refusals";

/// Requirements the refusal check exercises.
pub const REFUSAL_IDS: &[ReqId] = req_ids![
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

/// Every configuration in a grid: the IUT must accept exactly what the model accepts.
pub fn check_refusals(kind: &IutKind, caps: &Capabilities) -> ScenarioRun {
    let mut checked = 0;
    let mut configure = kind.configurer();
    for format in [
        FrameFormat::Base11,
        FrameFormat::Extended29,
        FrameFormat::Fd,
    ] {
        for queue in [QueueMode::Standard, QueueMode::Optimized, QueueMode::Fast] {
            for (tn, ts) in [(false, false), (true, false), (false, true), (true, true)] {
                for filters in [
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
                ] {
                    for (tx_slots, rx_slots) in
                        [(0u8, 0u8), (1, 1), (32, 32), (33, 33), (8, 33), (0, 8)]
                    {
                        for dc in [false, true] {
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
                            checked += 1;
                            let expected = config.validate(caps);
                            let actual = match configure(caps, &config) {
                                Ok(()) => Ok(()),
                                Err(BuildError::Refused(reason)) => Err(reason),
                                Err(BuildError::Failed(reason)) => {
                                    return ScenarioRun {
                                        scenario: REFUSALS.into(),
                                        covers: REFUSAL_IDS.to_vec(),
                                        outcome: Outcome::Error(
                                            crate::error::IutError(reason).into(),
                                        ),
                                        cycles: checked,
                                        frames_checked: 0,
                                        tolerated: 0,
                                        elapsed: std::time::Duration::ZERO,
                                    };
                                }
                            };
                            if expected.is_ok() != actual.is_ok() {
                                let requirements = match &expected {
                                    Err(e) => refusal_ids(e).to_vec(),
                                    Ok(()) => req_ids!["PROF-001", "PROF-002"].to_vec(),
                                };
                                let failure = Failure {
                                    requirements,
                                    scenario: REFUSALS.into(),
                                    cycle: 0,
                                    time: 0,
                                    what: format!(
                                        "configuration {} with {tx_slots} Tx and {rx_slots} Rx slots",
                                        describe(&config)
                                    ),
                                    expected: match expected {
                                        Ok(()) => "accepted".into(),
                                        Err(e) => format!("refused: {e}"),
                                    },
                                    actual: match actual {
                                        Ok(()) => "accepted".into(),
                                        Err(e) => format!("refused: {e}"),
                                    },
                                    context: Vec::new(),
                                    timeline: Vec::new(),
                                    frames: None,
                                };
                                return ScenarioRun {
                                    scenario: REFUSALS.into(),
                                    covers: REFUSAL_IDS.to_vec(),
                                    outcome: Outcome::Fail(Box::new(failure)),
                                    cycles: checked,
                                    frames_checked: 0,
                                    tolerated: 0,
                                    elapsed: std::time::Duration::ZERO,
                                };
                            }
                        }
                    }
                }
            }
        }
    }
    ScenarioRun {
        scenario: REFUSALS.into(),
        covers: REFUSAL_IDS.to_vec(),
        outcome: Outcome::Pass,
        cycles: checked,
        frames_checked: 0,
        tolerated: 0,
        elapsed: std::time::Duration::ZERO,
    }
}

/// Where and how the IUT broke in `run`, if it did: what the profile's later
/// scenarios are skipped after (fail-fast).
fn broke_in(run: &ScenarioRun) -> Option<String> {
    match &run.outcome {
        Outcome::Error(RunError::Iut(error)) => Some(format!(
            "the IUT broke in `{}`: {}",
            run.scenario,
            error.0.lines().next().unwrap_or("")
        )),
        _ => None,
    }
}

/// Runs every scenario of a profile against an IUT and judges each requirement.
pub fn run_profile(
    catalogue: &Catalogue,
    profile: &Profile,
    kind: &IutKind,
    options: &Options,
    mut progress: impl FnMut(&ScenarioRun),
) -> ProfileRun {
    let caps = profile.model_capabilities();
    let mut runs = Vec::new();
    if options
        .selection
        .admits(REFUSALS, REFUSAL_IDS.iter().map(ReqId::as_str))
    {
        let started = std::time::Instant::now();
        let mut run = check_refusals(kind, &caps);
        run.elapsed = started.elapsed();
        runs.push(run);
        progress(&runs[0]);
    }
    let mut broken = runs
        .first()
        .and_then(broke_in)
        .filter(|_| options.fail_fast);
    for mut scenario in scenarios(&caps, options) {
        if !options
            .selection
            .admits(&scenario.name, scenario.covers.iter().map(ReqId::as_str))
        {
            continue;
        }
        scenario.time_stamp_tolerance = profile.timestamp_tolerance_ns;
        scenario.bus = options.bus.clone();
        if let Some(dir) = &options.trace_dir {
            let name: String = scenario
                .name
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            scenario.trace = Some((dir.join(&profile.name), name, options.trace_epoch));
        }
        let run = match &broken {
            Some(after) => ScenarioRun {
                scenario: scenario.name.clone(),
                covers: scenario.covers.clone(),
                outcome: Outcome::Error(RunError::Skipped(after.clone())),
                cycles: 0,
                frames_checked: 0,
                tolerated: 0,
                elapsed: std::time::Duration::ZERO,
            },
            None if crate::interrupt::requested() => break,
            None => {
                let started = std::time::Instant::now();
                let mut run = run_scenario(kind, &caps, &scenario, scenario.steps());
                run.elapsed = started.elapsed();
                run
            }
        };
        if options.fail_fast && broken.is_none() {
            broken = broke_in(&run);
        }
        progress(&run);
        runs.push(run);
    }
    judge(catalogue, profile, runs, options)
}

/// The lockstep's own verdicts from its scenario runs (the report merges
/// them with the Gherkin scenarios' through [`verdict::judge`] again).
pub fn judge(
    catalogue: &Catalogue,
    profile: &Profile,
    runs: Vec<ScenarioRun>,
    options: &Options,
) -> ProfileRun {
    let failures = runs
        .iter()
        .filter_map(|run| match &run.outcome {
            Outcome::Fail(failure) => Some(failure.as_ref().clone()),
            _ => None,
        })
        .collect();
    let mut run = ProfileRun {
        profile: profile.name.clone(),
        runs,
        failures,
        verdicts: BTreeMap::new(),
    };
    let reach = Reach {
        here: checked_ids(&profile.model_capabilities(), options)
            .into_iter()
            .collect(),
        elsewhere: BTreeMap::new(),
        left_out: options.selection.describe(),
    };
    run.verdicts = verdict::judge(catalogue, profile, &run.checks(), &reach);
    run
}

/// Every requirement the scenarios and checks of a run exercise on a device
/// with these capabilities: exactly what [`judge`] can call pass or fail,
/// whatever the selection.
pub fn checked_ids(caps: &Capabilities, options: &Options) -> Vec<String> {
    let everything = Options {
        cases: options.cases.max(1),
        ..options.clone()
    };
    let mut ids: Vec<String> = scenarios(caps, &everything)
        .into_iter()
        .flat_map(|s| s.covers)
        .map(|id| id.to_string())
        .collect();
    ids.extend(REFUSAL_IDS.iter().map(|id| id.to_string()));
    ids.sort();
    ids.dedup();
    ids
}

/// A profile that has the feature `fault` breaks, for tests that need one.
pub fn profile_for(fault: canif_softdevice::Fault) -> &'static str {
    use canif_softdevice::Fault::*;
    match fault {
        FdLengthRoundsDown
        | FdLength32As36
        | FdPaddingFf
        | BrsEsiSwapped
        | ReceiveFifoNotReported
        | BrsWithoutEdlSendsFd
        | InfoDataTwoBytesLate => "fc532x",
        ExtendedFlagMissing
        | TransactionNumberOfFirstFrame
        | TransactionNumberOnHandover
        | TimeStampInMicroseconds
        | FilterLastMatchWins
        | StandardIdKeepsHighBits => "ccat",
        _ => "el6751-mdp",
    }
}

/// One row of the kill matrix: a fault and what it broke on each profile.
#[derive(Debug, Clone)]
pub struct KillRow {
    pub fault: canif_softdevice::Fault,
    /// Profile name → requirement ids that failed (empty: not caught there).
    pub caught: Vec<(String, Vec<String>)>,
}

/// Runs the soft device with each fault on every profile.
pub fn kill_matrix(
    catalogue: &Catalogue,
    options: &Options,
    mut progress: impl FnMut(&str),
) -> Vec<KillRow> {
    canif_softdevice::Fault::ALL
        .into_iter()
        .map(|fault| {
            progress(fault.name());
            let options = Options {
                counter_wrap: fault == canif_softdevice::Fault::CounterDoesNotWrap,
                ..options.clone()
            };
            let kind = IutKind::SoftDevice {
                faults: vec![fault],
                choices: vec![],
            };
            let caught = catalogue
                .profiles
                .iter()
                .map(|profile| {
                    let run = run_profile(catalogue, profile, &kind, &options, |_| {});
                    let failed = run.failed_requirements();
                    (profile.name.clone(), failed)
                })
                .collect();
            KillRow { fault, caught }
        })
        .collect()
}
