//! One profile's run of a PLC-side client: every interface the profile
//! offers, every life cycle under every master, and a verdict per client
//! requirement. The mirror of [`crate::device::suite`] for the other side.

use std::time::Duration;

use canif_model::config::{Capabilities, InterfaceConfig, QueueMode};
use canif_model::image::ImageLayout;
use canif_model::timing::BitRates;
use canif_spec::{Profile, ReqId, Scope, Side, Suite};

use super::application::{self, ClientScenario};
use super::exec::ExecClient;
use super::faulty::{ClientFault, FaultyClient};
use super::lib_client::LibClient;
use super::master::Master;
use super::{judge, rig, Client, ReferenceClient};
use crate::client::played_device::PlayedDevice;
use crate::device::iut::BuildError;
use crate::error::RunError;
use crate::outcome::{Outcome, ScenarioRun};

use crate::run::{Selection, SelfCheck, Side as RunSide};
use crate::verdict::{NotRunReason, Reach, Unobserved};

/// The client under test, as the harness builds it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ClientKind {
    /// The reference client of 001 §6 (`canif_model::client`).
    Reference,
    /// The independent client of [`super::faulty`], with at most one fault.
    Faulty(Option<ClientFault>),
    /// A process speaking the adapter protocol's client role.
    Exec { command: String, timeout_ms: u64 },
    /// A shared library of the C ABI's client role: in canif's process, or
    /// with `host` in a `canif lib-host` of its own.
    Lib {
        path: std::path::PathBuf,
        host: Option<crate::device::iut_kind::LibHost>,
    },
}

impl ClientKind {
    pub fn name(&self) -> String {
        match self {
            ClientKind::Reference => "reference client".into(),
            ClientKind::Faulty(None) => "soft client".into(),
            ClientKind::Faulty(Some(fault)) => format!("soft client with fault {fault}"),
            ClientKind::Exec { command, .. } => format!("exec:{command}"),
            ClientKind::Lib { path, .. } => format!("lib:{}", path.display()),
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
            ClientKind::Lib { path, host: None } => {
                Box::new(LibClient::start(path, config, layout).map_err(BuildError::Failed)?)
            }
            ClientKind::Lib {
                path,
                host: Some(host),
            } => Box::new(
                ExecClient::start(
                    &host.command("client", path),
                    Duration::from_millis(host.timeout_ms),
                    config,
                    layout,
                )
                .map_err(BuildError::Failed)?,
            ),
            ClientKind::Exec {
                command,
                timeout_ms,
            } => Box::new(
                ExecClient::start(command, Duration::from_millis(*timeout_ms), config, layout)
                    .map_err(BuildError::Failed)?,
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
                crate::client::played_device::kernel::KernelDeviceSide::open(
                    caps, config, interface, *timeout,
                )
                .map(|d| Box::new(d) as Box<dyn PlayedDevice>)
                .map_err(|e| {
                    use crate::error::{BusCause, BusError};
                    RunError::Bus(BusError::new(BusCause::Unavailable, e))
                })
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

/// One case of a client's run: a life cycle under one master model.
#[derive(Debug, Clone)]
pub struct ClientCase {
    pub scenario: ClientScenario,
    pub master: Master,
}

impl RunSide for ClientOptions {
    type UnderTest = ClientKind;
    type Case = ClientCase;
    const UNDER_TEST: &'static str = "the client";
    const SIDE: Side = Side::Plc;

    fn cases(&self, profile: &Profile) -> Vec<ClientCase> {
        scenarios(&profile.model_capabilities(), self)
            .into_iter()
            .map(|(scenario, master)| ClientCase { scenario, master })
            .collect()
    }

    fn name(case: &ClientCase) -> String {
        run_name(&case.scenario, case.master)
    }

    fn covers(case: &ClientCase) -> &[ReqId] {
        &case.scenario.covers
    }

    fn run(&self, kind: &ClientKind, profile: &Profile, case: ClientCase) -> ScenarioRun {
        let build = |layout| kind.build(&case.scenario.config, layout);
        let open = |caps: &Capabilities, config, rates| self.bus.open(caps, config, rates);
        rig::run(
            &profile.model_capabilities(),
            &case.scenario,
            case.master,
            &build,
            &open,
        )
    }

    fn selection(&self) -> &Selection {
        &self.selection
    }

    fn fail_fast(&self) -> bool {
        true
    }

    fn reach(&self, profile: &Profile, runs: &[ScenarioRun]) -> Reach {
        let mut reach = reach(&profile.model_capabilities(), self);
        let declared_nothing = runs.iter().any(|r| {
            r.iut_declares
                .iter()
                .any(|d| d == super::TELLS_NOTHING_SENT)
        });
        if declared_nothing {
            let why = "the client declares it tells its application nothing of which Tx messages were sent: its transaction numbers may be anything (000 §5.2, \"z. B. eine fortlaufende Nummer\")";
            for id in judge::TRANSACTION_NUMBERS.iter().chain(judge::SENT_REPORTS) {
                reach.not_applicable.insert(id.to_string(), why.to_string());
            }
        } else if told_nothing_sent(runs) {
            for told in judge::SENT_REPORTS {
                reach.unobserved.insert(
                    told.to_string(),
                    NotRunReason::NothingToJudge(Unobserved::SentMessages),
                );
            }
        }
        reach
    }
}

/// CL-TN-002 judges what a client tells its application was sent: where a
/// run with transaction numbers passed and the client told nothing (a run
/// that told something and broke CL-TN-002 fails it), there was nothing to judge.
fn told_nothing_sent(runs: &[ScenarioRun]) -> bool {
    runs.iter().any(|r| {
        matches!(r.outcome, Outcome::Pass)
            && r.covers
                .iter()
                .any(|id| judge::TRANSACTION_NUMBERS.contains(id))
    })
}

/// What a client run can judge: the PLC side's requirements its cases exercise.
pub fn reach(caps: &Capabilities, options: &ClientOptions) -> Reach {
    Reach {
        scope: Scope {
            side: Side::Plc,
            suite: Suite::Interface,
        },
        here: checked_ids(caps, options).into_iter().collect(),
        left_out: options.selection.not_run(),
        ..Reach::default()
    }
}

/// The soft client's faults, each alone.
impl SelfCheck for ClientOptions {
    type Fault = ClientFault;

    fn faults() -> Vec<ClientFault> {
        ClientFault::ALL.to_vec()
    }

    fn fault_name(fault: ClientFault) -> &'static str {
        fault.name()
    }

    fn with_fault(&self, fault: ClientFault) -> (Self, ClientKind) {
        let options = ClientOptions {
            counter_wrap: fault == ClientFault::IgnoresWrap,
            ..self.clone()
        };
        (options, ClientKind::Faulty(Some(fault)))
    }
}
