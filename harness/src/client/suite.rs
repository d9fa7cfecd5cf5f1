//! One profile's run of a PLC-side client: every interface the profile
//! offers, every life cycle under every master, and a verdict per client
//! requirement. The mirror of [`crate::device::suite`] for the other side.

#[cfg(feature = "socketcan")]
use std::time::Duration;

use canif_model::config::{Capabilities, InterfaceConfig, QueueMode};
use canif_model::image::ImageLayout;
use canif_model::timing::BitRates;
use canif_spec::{Profile, ReqId, Scope, Side, Suite};

use super::application::{self, ClientScenario};
use super::master::Master;
use super::soft_client::{ClientFault, ClientShape, FaultyClient};
use super::{judge, rig, Client, ReferenceClient};
use crate::client::played_device::PlayedDevice;
use crate::declare::client::ClientDeclaration;
use crate::declare::Declares;
use crate::door::iut::BuildError;
use crate::door::Door;
use crate::error::{IutCause, IutError, Refusal, RunError};
use crate::outcome::{Outcome, ScenarioRun};

use crate::run::{Cases, Selection, SelfCheck};
use crate::verdict::{NotRunReason, Reach, Unobserved};

/// The client under test, as the harness builds it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ClientKind {
    /// The reference client of 001 §6 (`canif_model::client`).
    Reference,
    /// The independent client of [`super::soft_client`], with at most one fault.
    Faulty(Option<ClientFault>),
    /// The independent client taking a way of working the documents allow
    /// only where declared, declaring it or not.
    Shaped { shape: ClientShape, declared: bool },
    /// A client behind a door: a process speaking the adapter protocol's
    /// client role, or a library of the C ABI's client role.
    Door(Door),
}

impl ClientKind {
    pub fn name(&self) -> String {
        match self {
            ClientKind::Reference => "reference client".into(),
            ClientKind::Faulty(None) => "soft client".into(),
            ClientKind::Faulty(Some(fault)) => format!("soft client with fault {fault}"),
            ClientKind::Shaped { shape, declared } => format!(
                "soft client taking {}{}",
                shape.name(),
                if *declared {
                    ", declared"
                } else {
                    ", undeclared"
                }
            ),
            ClientKind::Door(door) => door.name(),
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
            ClientKind::Shaped { shape, .. }
                if *shape == ClientShape::Only11Bit
                    && config.format != canif_model::config::FrameFormat::Base11 =>
            {
                return Err(BuildError::Failed(IutError::new(
                    IutCause::NotStarted,
                    "the soft client serves 11-bit interfaces only",
                )))
            }
            ClientKind::Shaped { shape, declared } => {
                Box::new(FaultyClient::new(layout, config.queue, None).shaped(*shape, *declared))
            }
            ClientKind::Door(door) => return door.client(config, layout),
        })
    }
}

impl ClientKind {
    /// What the client declares: a library before any start, as
    /// include/canif.h promises; any other client as a program started on
    /// the first of `interfaces` it starts on (it need not serve one to
    /// declare), and stopped.
    pub fn declaration(
        &self,
        caps: &Capabilities,
        interfaces: &[InterfaceConfig],
    ) -> Result<ClientDeclaration, BuildError> {
        if let ClientKind::Door(door) = self {
            if let Some(declared) = door.client_declares() {
                return declared.map_err(BuildError::Failed);
            }
        }
        let mut failed = BuildError::Refused("no interface to start it on".into());
        for config in interfaces {
            let layout = ImageLayout::new(config, caps.info_data);
            match self.build(config, layout) {
                Ok(client) => return Ok(client.declaration()),
                Err(error) => failed = error,
            }
        }
        Err(failed)
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
    /// What the client declares (the command line's and its own together),
    /// or why it could not be read: then every case is that error.
    pub declared: Result<ClientDeclaration, RunError>,
}

impl ClientOptions {
    pub fn new(seed: u64) -> Self {
        ClientOptions {
            seed,
            bus: ClientBus::Sim,
            counter_wrap: true,
            masters: Master::ALL.to_vec(),
            selection: Selection::default(),
            declared: Ok(ClientDeclaration::default()),
        }
    }

    /// These options with what `kind` declares added to what they declare
    /// already (the command line's), asked once of a program started on the
    /// first interface (11-bit, 29-bit, FD, …) the client starts on and the
    /// command line leaves it: the declaration is the client's, not a profile's.
    pub fn declared_by(self, kind: &ClientKind) -> Self {
        let caps = &Capabilities::everything();
        let declared = self.declared.clone().and_then(|ours| {
            let interfaces: Vec<InterfaceConfig> = application::interfaces(caps)
                .iter()
                .filter_map(|offered| ours.serve(offered).ok())
                .collect();
            let theirs = kind
                .declaration(caps, &interfaces)
                .map_err(|error| match error {
                    BuildError::Failed(error) => RunError::Iut(IutError {
                        what: format!("while its declaration was read: {}", error.what),
                        ..error
                    }),
                    BuildError::Refused(reason) => RunError::Configuration(Refusal::Iut(format!(
                        "while its declaration was read: {reason}"
                    ))),
                })?;
            ours.merged(&theirs).map_err(|error| {
                RunError::Iut(IutError::new(
                    IutCause::Protocol,
                    format!("its declaration and the command line's: {error}"),
                ))
            })
        });
        ClientOptions { declared, ..self }
    }

    /// What the client declares, or nothing where it could not be read.
    pub fn declaration(&self) -> ClientDeclaration {
        self.declared.clone().unwrap_or_default()
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

/// Every scenario of a profile, each with the master it runs under, as the
/// client's declaration shapes them: on the interfaces it serves, at its
/// geometry and the edges of the profile's range, in its direction.
pub fn scenarios(caps: &Capabilities, options: &ClientOptions) -> Vec<(ClientScenario, Master)> {
    let declared = options.declaration();
    let mut list = Vec::new();
    let masters = masters_for(caps, options);
    for (n, offered) in application::interfaces(caps).iter().enumerate() {
        let Ok(served) = declared.serve(offered) else {
            continue;
        };
        for (g, slots) in declared.geometries(caps.max_slots).into_iter().enumerate() {
            let mut config = served.clone();
            (config.tx_slots, config.rx_slots) = slots;
            for &master in &masters {
                // DC works only with the Fast CAN Queue (PDX-005).
                if master.distributed_clocks && config.queue != QueueMode::Fast {
                    continue;
                }
                // The edges of the range: the traffic life cycles, under one master.
                if g > 0 && master != masters[0] {
                    continue;
                }
                let wrap = options.counter_wrap && n == 0 && g == 0;
                let life_cycles = match g {
                    0 => application::scenarios(&config, master, options.seed, wrap),
                    _ => application::traffic(&config, options.seed),
                };
                for scenario in life_cycles {
                    if let Some(scenario) = scenario.for_client(&declared) {
                        list.push((scenario, master));
                    }
                }
            }
        }
    }
    list
}

/// What the profile offers and the client declares it does not serve, each
/// with the declaration's reason.
pub fn not_served(caps: &Capabilities, options: &ClientOptions) -> Vec<(String, String)> {
    let declared = options.declaration();
    let mut list = Vec::new();
    for offered in application::interfaces(caps) {
        if let Err(why) = declared.serve(&offered) {
            list.push((application::describe(&offered), why));
        }
    }
    if declared.geometries(caps.max_slots).is_empty() {
        list.push((
            format!("every slot count of the profile (1..{})", caps.max_slots),
            declared.declined_slots(caps.max_slots),
        ));
    }
    for (way, does) in [
        (
            "frames the application asks to send",
            declared.direction().sends(),
        ),
        ("frames from the bus", declared.direction().receives()),
    ] {
        if !does {
            list.push((way.to_string(), declared.declined_direction()));
        }
    }
    list
}

/// The name a scenario runs under.
pub fn run_name(scenario: &ClientScenario, master: Master) -> String {
    format!("{} under {}", scenario.name, master.name)
}

/// Every client requirement a run on these capabilities exercises.
pub fn exercised(caps: &Capabilities, options: &ClientOptions) -> Vec<String> {
    crate::run::checked_ids::<ClientOptions>(&client_cases(caps, options))
}

/// A client run's cases on these capabilities: every life cycle under
/// every master model.
fn client_cases(caps: &Capabilities, options: &ClientOptions) -> Vec<ClientCase> {
    scenarios(caps, options)
        .into_iter()
        .map(|(scenario, master)| ClientCase { scenario, master })
        .collect()
}

/// One case of a client's run: a life cycle under one master model.
#[derive(Debug, Clone)]
pub struct ClientCase {
    pub scenario: ClientScenario,
    pub master: Master,
}

impl Cases for ClientOptions {
    type UnderTest = ClientKind;
    type Case = ClientCase;
    const UNDER_TEST: &'static str = "the client";
    const SIDE: Side = Side::Plc;
    /// Nothing carries from one case to the next: each starts afresh.
    type Learned = ();

    fn choices((): ()) -> Vec<crate::declare::ChoiceEntry> {
        Vec::new()
    }

    fn cases(&self, profile: &Profile) -> Vec<ClientCase> {
        client_cases(&profile.model_capabilities(), self)
    }

    fn name(case: &ClientCase) -> String {
        run_name(&case.scenario, case.master)
    }

    fn covers(case: &ClientCase) -> &[ReqId] {
        &case.scenario.covers
    }

    fn run(
        &self,
        kind: &ClientKind,
        profile: &Profile,
        case: ClientCase,
        (): &mut (),
    ) -> ScenarioRun {
        if let Err(error) = &self.declared {
            return ScenarioRun::ended(
                run_name(&case.scenario, case.master),
                case.scenario.covers.clone(),
                Outcome::Error(error.clone()),
            );
        }
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
        let declared = runs
            .iter()
            .filter_map(|r| match &r.iut_declares {
                Declares::Client(declared) => Some(declared),
                _ => None,
            })
            .fold(self.declaration(), |all, run| {
                all.merged(run).unwrap_or(all)
            });
        let declared_nothing = declared.tells_sent == Some(false);
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

/// What a client run can judge: the PLC side's requirements its cases
/// exercise. What only the interfaces, slot counts or direction the client
/// declines would exercise is not applicable, the declaration the reason.
pub fn reach(caps: &Capabilities, options: &ClientOptions) -> Reach {
    let here: std::collections::BTreeSet<String> = exercised(caps, options).into_iter().collect();
    let not_served = not_served(caps, options);
    let undeclared = ClientOptions {
        declared: Ok(ClientDeclaration::default()),
        ..options.clone()
    };
    let why = not_served
        .iter()
        .map(|(what, why)| format!("{what}: {why}"))
        .collect::<Vec<_>>()
        .join("; ");
    let not_applicable = exercised(caps, &undeclared)
        .into_iter()
        .filter(|id| !here.contains(id))
        .map(|id| {
            (
                id,
                format!("only what the client does not serve exercises it ({why})"),
            )
        })
        .collect();
    Reach {
        scope: Scope {
            side: Side::Plc,
            suite: Suite::Interface,
        },
        here,
        not_applicable,
        not_served,
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
