//! The survey a report shows of each terminal: who it is, how canif's
//! master configured it, and how its exchange performs over idle cycles
//! (docs/ethercat.md, "Running it").

use canif_model::config::InterfaceConfig;

use super::{build, EthercatLink};
use crate::door::iut::{BuildError, Iut};
use crate::error::{IutCause, IutError};

/// An EtherCAT terminal as canif's master found it: the report's own entry.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct TerminalFacts {
    pub profile: String,
    pub name: String,
    pub vendor_id: u32,
    pub product_code: u32,
    pub revision: u32,
    pub serial: u32,
    /// `0x1C32:05` read back after setting `0x1C32:08` (000 §5); none where it did not answer.
    pub local_cycle_ns: Option<u32>,
    /// Idle cycles timed after bring-up, and one cycle's exchange (LRW and input read), wall clock.
    pub cycles: u64,
    pub mean_cycle_ns: u64,
    pub worst_cycle_ns: u64,
    /// A soak's real-time period (`--ethercat-soak-s`), and the cycles that
    /// ended after the next one was due; none when the cycles were not paced.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period_ns: Option<u64>,
    #[serde(default)]
    pub missed_cycles: u64,
    /// SyncManagers 0–3 as the master configured them from the terminal's
    /// SII: start, length, control byte.
    #[serde(default)]
    pub sync_managers: Vec<[u16; 3]>,
    /// The process data the terminal mapped, and how many of its input
    /// bytes lie behind the CAN interface's image (the CAN status, `0x1A85`).
    #[serde(default)]
    pub output_bytes: usize,
    #[serde(default)]
    pub input_bytes: usize,
    #[serde(default)]
    pub status_bytes: usize,
}

impl TerminalFacts {
    /// The SyncManagers as configured: `start/length` each, in hex.
    pub fn layout(&self) -> String {
        let each: Vec<String> = self
            .sync_managers
            .iter()
            .map(|[start, length, _]| format!("{start:#06x}/{length}"))
            .collect();
        match each.is_empty() {
            true => "not read".into(),
            false => each.join(", "),
        }
    }
}

/// How a survey exchanges its idle cycles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pace {
    /// This many cycles, one after the other.
    Unpaced(u32),
    /// One cycle every `period` for `soak`, as a real-time task would: a
    /// cycle that ends after the next one's start missed its deadline.
    Every {
        period: std::time::Duration,
        soak: std::time::Duration,
    },
}

impl Pace {
    /// Idle cycles an unpaced survey times.
    pub const SURVEY_CYCLES: u32 = 1_000;
}

impl Default for Pace {
    /// A burst of idle cycles, unpaced: what a run does unless a soak is asked for.
    fn default() -> Self {
        Pace::Unpaced(Self::SURVEY_CYCLES)
    }
}

/// Brings the terminal up once with the profile's first interface, runs
/// idle PLC cycles at `pace`, and reads `0x1C32:05`: who the terminal is and
/// how its exchange performs, for the run's report.
pub fn survey(
    profile: &canif_spec::Profile,
    link: &EthercatLink,
    pace: Pace,
) -> Result<TerminalFacts, BuildError> {
    use std::time::{Duration, Instant};
    let caps = &profile.model_capabilities();
    let identity = &profile.ethercat.ok_or_else(|| {
        BuildError::Failed(IutError::new(
            IutCause::NotStarted,
            format!(
                "{} is no EtherCAT terminal: it gives no identity",
                profile.name
            ),
        ))
    })?;
    let config = InterfaceConfig::new(caps.first_format(), 1);
    let mut iut = build(caps, &config, identity, link)?;
    let outputs = vec![0u8; iut.output_len()];
    let (period, cycles) = match pace {
        Pace::Unpaced(cycles) => (None, u64::from(cycles)),
        Pace::Every { period, soak } => (
            Some(period),
            (soak.as_nanos() / period.as_nanos().max(1)) as u64,
        ),
    };
    let (mut total, mut worst, mut missed) = (0u64, 0u64, 0u64);
    let started = Instant::now();
    for n in 0..cycles {
        if let Some(period) = period {
            let due = started + period * n as u32;
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
        }
        let began = Instant::now();
        iut.cycle(
            &outputs,
            n * period.map_or(1_000_000, |p| p.as_nanos() as u64),
        )
        .map_err(BuildError::Failed)?;
        let took = began.elapsed().as_nanos() as u64;
        total += took;
        worst = worst.max(took);
        if let Some(period) = period {
            let next = started + period * (n as u32 + 1);
            if Instant::now() > next + Duration::ZERO {
                missed += 1;
            }
        }
    }
    iut.read_local_cycle();
    let mut facts = iut.facts.clone();
    facts.profile = profile.name.clone();
    facts.cycles = cycles;
    facts.mean_cycle_ns = total / cycles.max(1);
    facts.worst_cycle_ns = worst;
    facts.period_ns = period.map(|p| p.as_nanos() as u64);
    facts.missed_cycles = missed;
    Ok(facts)
}

/// What a run over `link` needs before it starts, or why it cannot: a
/// terminal on a network interface has its CAN port on a real bus, and
/// only terminal profiles can be one.
pub fn preflight(
    link: &EthercatLink,
    profiles: &[&canif_spec::Profile],
    bus_is_sim: bool,
    terminals: &[&str],
) -> Result<(), String> {
    if let EthercatLink::Interface { name, .. } = link {
        if bus_is_sim {
            return Err(format!(
                "--iut ethercat:{name}: a terminal on a network interface has its CAN port on a real bus; \
                 add --bus socketcan:IFACE (the CAN adapter cabled to it), or use ethercat:emulated"
            ));
        }
    }
    let not_terminals: Vec<&str> = profiles
        .iter()
        .filter(|p| p.ethercat.is_none())
        .map(|p| p.name.as_str())
        .collect();
    match not_terminals.as_slice() {
        [] => Ok(()),
        names => Err(format!(
            "--iut ethercat: {} {} no EtherCAT terminal; name terminal profiles with --profile ({})",
            names.join(", "),
            if names.len() == 1 { "is" } else { "are" },
            terminals.join(", ")
        )),
    }
}
