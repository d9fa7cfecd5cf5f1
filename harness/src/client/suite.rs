//! One profile's run of a PLC-side client: every interface the profile
//! offers, every life cycle under every master, and a verdict per client
//! requirement. The mirror of [`crate::suite`] for the other side.

use std::collections::BTreeMap;

use std::time::Duration;

use canif_model::config::{Capabilities, InterfaceConfig, QueueMode};
use canif_model::image::ImageLayout;
use canif_model::timing::BitRates;
use canif_spec::{Catalogue, Profile, ReqId, Side};

use super::application::{self, ClientScenario};
use super::exec::ExecClient;
use super::faulty::{ClientFault, FaultyClient};
use super::lib_client::LibClient;
use super::master::Master;
use super::{rig, Client, ReferenceClient};
use crate::device_side::PlayedDevice;
use crate::error::RunError;
use crate::iut::BuildError;
use crate::outcome::{Outcome, ScenarioRun};
use crate::suite::{ProfileRun, Selection};
use crate::verdict::{self, Reach};

/// The client under test, as the harness builds it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ClientKind {
    /// The reference client of 001 §6 (`canif_model::client`).
    Reference,
    /// The independent client of [`super::faulty`], with at most one fault.
    Faulty(Option<ClientFault>),
    /// A process speaking the adapter protocol's client role.
    Exec { command: String, timeout_ms: u64 },
    /// A shared library of the C ABI's client role.
    Lib { path: std::path::PathBuf },
}

impl ClientKind {
    pub fn name(&self) -> String {
        match self {
            ClientKind::Reference => "reference client".into(),
            ClientKind::Faulty(None) => "soft client".into(),
            ClientKind::Faulty(Some(fault)) => format!("soft client with fault {fault}"),
            ClientKind::Exec { command, .. } => format!("exec:{command}"),
            ClientKind::Lib { path } => format!("lib:{}", path.display()),
        }
    }

    /// A fresh client (a new PLC program) for an interface.
    pub fn build(
        &self,
        config: &InterfaceConfig,
        layout: ImageLayout,
    ) -> Result<Box<dyn Client>, BuildError> {
        Ok(match self {
            ClientKind::Reference => Box::new(ReferenceClient::new(layout)),
            ClientKind::Faulty(fault) => Box::new(FaultyClient::new(layout, config.queue, *fault)),
            ClientKind::Lib { path } => Box::new(
                LibClient::start(path, config, layout).map_err(|e| BuildError::Failed(e.0))?,
            ),
            ClientKind::Exec {
                command,
                timeout_ms,
            } => Box::new(
                ExecClient::start(command, Duration::from_millis(*timeout_ms), config, layout)
                    .map_err(|e| BuildError::Failed(e.0))?,
            ),
        })
    }
}

/// Where the device the harness plays sends and receives its frames.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ClientBus {
    /// The simulated bus, virtual time.
    Sim,
    /// The device's controller and the other nodes on a SocketCAN interface;
    /// `timeout`: how long a frame may take to cross the kernel.
    #[cfg(feature = "socketcan")]
    SocketCan {
        interface: String,
        timeout: Duration,
    },
}

impl ClientBus {
    /// The bus, as a report names it.
    pub fn describe(&self) -> String {
        match self {
            ClientBus::Sim => "simulated bus (virtual time), the reference model as the device".into(),
            #[cfg(feature = "socketcan")]
            ClientBus::SocketCan { interface, .. } => format!(
                "the reference model as the device, its controller and the other nodes on {interface} (Linux {}); frames cross the kernel",
                canif_kernel::kernel_release()
            ),
        }
    }

    fn open(
        &self,
        caps: &Capabilities,
        config: InterfaceConfig,
        bit_rates: BitRates,
    ) -> Result<Box<dyn PlayedDevice>, RunError> {
        match self {
            ClientBus::Sim => rig::simulated(caps, config, bit_rates),
            #[cfg(feature = "socketcan")]
            ClientBus::SocketCan { interface, timeout } => {
                crate::bus::kernel_device::KernelDeviceSide::open(caps, config, interface, *timeout)
                    .map(|d| Box::new(d) as Box<dyn PlayedDevice>)
                    .map_err(|e| RunError::Bus(crate::error::BusError(e)))
            }
        }
    }
}

/// What a client run runs.
#[derive(Debug, Clone)]
pub struct ClientOptions {
    pub seed: u64,
    pub bus: ClientBus,
    /// Include the 65,600-cycle counter wrap.
    pub counter_wrap: bool,
    /// The master models (all by default).
    pub masters: Vec<Master>,
    pub selection: Selection,
}

impl ClientOptions {
    pub fn new(seed: u64) -> Self {
        ClientOptions {
            seed,
            bus: ClientBus::Sim,
            counter_wrap: true,
            masters: Master::ALL.to_vec(),
            selection: Selection::default(),
        }
    }
}

/// The masters a profile's device can work with (Distributed Clocks only
/// where it offers them).
pub fn masters_for(caps: &Capabilities, options: &ClientOptions) -> Vec<Master> {
    options
        .masters
        .iter()
        .copied()
        .filter(|m| !m.distributed_clocks || caps.distributed_clocks)
        .collect()
}

/// Every scenario of a profile, each with the master it runs under.
pub fn scenarios(caps: &Capabilities, options: &ClientOptions) -> Vec<(ClientScenario, Master)> {
    let mut list = Vec::new();
    for (n, config) in application::interfaces(caps).iter().enumerate() {
        for master in masters_for(caps, options) {
            // DC works only with the Fast CAN Queue (PDX-005).
            if master.distributed_clocks && config.queue != QueueMode::Fast {
                continue;
            }
            let wrap = options.counter_wrap && n == 0;
            for scenario in application::scenarios(config, master, options.seed, wrap) {
                list.push((scenario, master));
            }
        }
    }
    list
}

/// The name a scenario runs under.
pub fn run_name(scenario: &ClientScenario, master: Master) -> String {
    format!("{} under {}", scenario.name, master.name)
}

/// Every client requirement a run on these capabilities exercises.
pub fn checked_ids(caps: &Capabilities, options: &ClientOptions) -> Vec<String> {
    let mut ids: Vec<String> = scenarios(caps, options)
        .into_iter()
        .flat_map(|(s, _)| s.covers)
        .map(|id| id.to_string())
        .collect();
    ids.sort();
    ids.dedup();
    ids
}

/// Runs every scenario of a profile against a client and judges each requirement.
pub fn run_profile(
    catalogue: &Catalogue,
    profile: &Profile,
    kind: &ClientKind,
    options: &ClientOptions,
    mut progress: impl FnMut(&ScenarioRun),
) -> ProfileRun {
    let caps = profile.model_capabilities();
    let mut runs = Vec::new();
    let mut broken: Option<String> = None;
    for (scenario, master) in scenarios(&caps, options) {
        let name = run_name(&scenario, master);
        if !options
            .selection
            .admits(&name, scenario.covers.iter().map(ReqId::as_str))
        {
            continue;
        }
        if crate::interrupt::requested() {
            break;
        }
        let run = match &broken {
            // Fail fast: a client that broke is not started again and again.
            Some(after) => ScenarioRun {
                scenario: name,
                covers: scenario.covers.clone(),
                outcome: Outcome::Error(RunError::Skipped(after.clone())),
                cycles: 0,
                frames_checked: 0,
                tolerated: 0,
                elapsed: std::time::Duration::ZERO,
            },
            None => {
                let build = |layout| kind.build(&scenario.config, layout);
                let open =
                    |caps: &Capabilities, config, rates| options.bus.open(caps, config, rates);
                rig::run(&caps, &scenario, master, &build, &open)
            }
        };
        if let (None, Outcome::Error(RunError::Iut(error))) = (&broken, &run.outcome) {
            broken = Some(format!(
                "the client broke in `{}`: {}",
                run.scenario,
                error.0.lines().next().unwrap_or("")
            ));
        }
        progress(&run);
        runs.push(run);
    }
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
    run.verdicts = verdict::judge(
        catalogue,
        profile,
        &run.checks(),
        &reach(catalogue, &caps, options),
    );
    told_nothing_sent(&mut run);
    run
}

/// CL-TN-002 judges what a client tells its application was sent; where the
/// runs with transaction numbers passed and it told nothing, the verdict
/// says so rather than blaming the selection.
fn told_nothing_sent(run: &mut ProfileRun) {
    let [told] = super::judge::SENT_REPORTS else {
        return;
    };
    let ran = run.runs.iter().any(|r| {
        matches!(r.outcome, Outcome::Pass)
            && r.covers
                .iter()
                .any(|id| super::judge::TRANSACTION_NUMBERS.contains(id))
    });
    if let Some(verdict @ verdict::Verdict::NotRun(_)) = run.verdicts.get_mut(told.as_str()) {
        if ran {
            *verdict = verdict::Verdict::NotRun(
                "the client told its application of no Tx message sent (it does not use Inputs.TransactionNumber that way): nothing to judge".into(),
            );
        }
    }
}

/// What a client run can judge, and where the device's requirements are judged.
pub fn reach(catalogue: &Catalogue, caps: &Capabilities, options: &ClientOptions) -> Reach {
    Reach {
        here: checked_ids(caps, options).into_iter().collect(),
        elsewhere: catalogue
            .requirements()
            .filter(|r| r.side == Side::Device)
            .map(|r| {
                (
                    r.id.clone(),
                    "a device requirement: exercised by `canif run --side device`".into(),
                )
            })
            .collect(),
        left_out: options.selection.describe(),
    }
}

/// One row of the client kill matrix.
#[derive(Debug, Clone)]
pub struct ClientKillRow {
    pub fault: ClientFault,
    /// Profile name → requirement ids that failed (empty: not caught there).
    pub caught: Vec<(String, Vec<String>)>,
}

/// Runs the soft client with each fault on every profile.
pub fn kill_matrix(
    catalogue: &Catalogue,
    options: &ClientOptions,
    mut progress: impl FnMut(&str),
) -> Vec<ClientKillRow> {
    ClientFault::ALL
        .into_iter()
        .map(|fault| {
            progress(fault.name());
            let options = ClientOptions {
                counter_wrap: fault == ClientFault::IgnoresWrap,
                ..options.clone()
            };
            let kind = ClientKind::Faulty(Some(fault));
            let caught = catalogue
                .profiles
                .iter()
                .map(|profile| {
                    let run = run_profile(catalogue, profile, &kind, &options, |_| {});
                    (profile.name.clone(), run.failed_requirements())
                })
                .collect();
            ClientKillRow { fault, caught }
        })
        .collect()
}
