//! Doors: how an implementation under test is reached, below both sides.
//!
//! A door is a transport — a process over the adapter protocol, a shared
//! library (in canif's process or hosted in a `canif lib-host` of its own),
//! a terminal over EtherCAT — and serves whichever role the implementation
//! plays: a device ([`iut::Iut`]) or a PLC-side client ([`client::Client`]).
//! The sides above (`crate::device`, `crate::client`) import doors, never
//! each other; no door imports a side.
//!
//! - [`iut`], [`client`]: the two roles' traits, and the in-process devices.
//! - [`adapter`]: the adapter protocol and the process that speaks it.
//! - [`exec`], `lib`, [`ethercat`]: one module per transport, each with
//!   both roles it serves.
//! - [`serve`]: the other end of the protocol, canif serving an in-process
//!   implementation to another process (`canif device --stdio`, `canif lib-host`).
//!
//! A new transport is one module here and one arm of [`Door`] (CONTRIBUTING.md).

pub mod adapter;
pub mod client;
pub mod ethercat;
pub mod exec;
pub mod iut;
pub(crate) mod lib;
pub mod serve;
mod timeouts;

pub use timeouts::Timeouts;

use std::path::{Path, PathBuf};

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::image::ImageLayout;

use crate::declare::client::ClientDeclaration;
use adapter::process::Channel;
use adapter::protocol::OwnedBus;
use client::Client;
use ethercat::EthercatLink;
use exec::{Configured, ExecIut};
use iut::{BuildError, Iut};

use crate::error::{IutCause, IutError};

/// The role an implementation plays behind a door.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    Device,
    Client,
}

impl Role {
    /// The name `canif lib-host --role` takes.
    pub fn name(self) -> &'static str {
        match self {
            Role::Device => "device",
            Role::Client => "client",
        }
    }
}

/// The canif executable that hosts a library (`canif lib-host`), and how
/// long the host may take.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LibHost {
    pub canif: PathBuf,
    pub timeouts: Timeouts,
}

impl LibHost {
    /// The host of the library at `path` in `role`, as a command for `sh`.
    pub fn command(&self, role: Role, path: &Path) -> String {
        let quoted = |p: &Path| format!("'{}'", p.display().to_string().replace('\'', "'\\''"));
        format!(
            "exec {} lib-host --control --role {} {}",
            quoted(&self.canif),
            role.name(),
            quoted(path)
        )
    }
}

/// How an implementation outside canif's own code is reached.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Door {
    /// Another process speaking the adapter protocol (docs/adapter-protocol.md).
    Exec {
        command: String,
        timeouts: Timeouts,
        /// Run the IUT on the CPU of the harness's thread: the exchange strictly
        /// alternates, and a wake-up across CPUs costs ten times one on the same
        /// CPU on a virtual machine (measured in benches/external_iut.rs).
        same_cpu: bool,
    },
    /// A shared library built against include/canif.h (the C ABI): in
    /// canif's process, or with `host` in a `canif lib-host` of its own,
    /// where a crash or an access past its images ends that process only.
    Lib {
        path: PathBuf,
        host: Option<LibHost>,
    },
    /// A terminal over EtherCAT (a device): canif's master (ethercrab) and,
    /// in memory or on a veth pair, the soft device behind an emulated ESC.
    Ethercat {
        /// The identity the profile gives (set per profile by the suite).
        identity: Option<canif_spec::EthercatIdentity>,
        link: EthercatLink,
    },
}

/// Offers a device process a configuration: a refusal is its answer, judged
/// by the refusal grid; a broken exchange is a failure to build.
fn offer(
    iut: &mut ExecIut,
    caps: &Capabilities,
    config: &InterfaceConfig,
    bus: Option<&OwnedBus>,
) -> Result<(), BuildError> {
    match iut
        .configure(caps, config, bus)
        .map_err(BuildError::Failed)?
    {
        Configured::Accepted => Ok(()),
        Configured::Refused(reason) => Err(BuildError::Refused(reason)),
    }
}

/// Asks a device, configuration after configuration, whether it accepts.
pub type Configurer = Box<dyn FnMut(&Capabilities, &InterfaceConfig) -> Result<(), BuildError>>;

impl Door {
    pub fn name(&self) -> String {
        match self {
            Door::Exec { command, .. } => format!("exec:{command}"),
            Door::Lib { path, .. } => format!("lib:{}", path.display()),
            Door::Ethercat { link, .. } => link.name(),
        }
    }

    /// A hosted library as the process it runs in: its command, and how
    /// long it may take. The host speaks on its control channel, so that
    /// what the library prints is its output, never a broken exchange.
    fn hosted(&self, role: Role) -> Option<(String, Timeouts)> {
        let Door::Lib {
            path,
            host: Some(host),
        } = self
        else {
            return None;
        };
        Some((host.command(role, path), host.timeouts))
    }

    /// What a device run through this door needs before it starts, or why
    /// it cannot: `terminals` names the catalogue's terminal profiles.
    pub fn preflight(
        &self,
        profiles: &[&canif_spec::Profile],
        bus_is_sim: bool,
        terminals: &[&str],
    ) -> Result<(), String> {
        match self {
            Door::Ethercat { link, .. } => {
                ethercat::preflight(link, profiles, bus_is_sim, terminals)
            }
            Door::Exec { .. } | Door::Lib { .. } => Ok(()),
        }
    }

    /// A capability of the EtherCAT door alone: the terminal of `profile`
    /// brought up once before the run, for the report; `None` behind a
    /// door that has no terminal to survey.
    pub fn survey(
        &self,
        profile: &canif_spec::Profile,
        pace: ethercat::Pace,
    ) -> Option<Result<ethercat::TerminalFacts, BuildError>> {
        match self {
            Door::Ethercat { link, .. } if profile.ethercat.is_some() => {
                Some(ethercat::survey(profile, link, pace))
            }
            _ => None,
        }
    }

    /// Whether the device's CAN controller is out of the harness's reach: it
    /// opens its own socket, or it is a terminal on a real bus.
    pub fn owns_its_bus(&self) -> bool {
        matches!(
            self,
            Door::Exec { .. }
                | Door::Ethercat {
                    link: EthercatLink::Interface { .. },
                    ..
                }
        )
    }

    /// The device behind the door for a configuration; with `bus`, an
    /// external device is told to open that interface itself.
    pub fn device(
        &self,
        caps: &Capabilities,
        config: &InterfaceConfig,
        bus: Option<&OwnedBus>,
    ) -> Result<Box<dyn Iut>, BuildError> {
        if let Some((command, timeouts, same_cpu, channel)) = self.device_process() {
            // A hosted library's CAN side the harness drives through the
            // protocol; an exec IUT's is on `bus` where it opens its own.
            let bus = bus.filter(|_| channel == Channel::Stdio);
            let mut iut = ExecIut::spawn_on(&command, timeouts, same_cpu, channel)
                .map_err(BuildError::Failed)?;
            offer(&mut iut, caps, config, bus)?;
            return Ok(Box::new(iut));
        }
        match self {
            Door::Lib { path, .. } => Ok(Box::new(lib::build(path, caps, config)?)),
            Door::Ethercat { identity, link } => {
                let identity = identity.as_ref().ok_or_else(|| {
                    BuildError::Failed(IutError::new(
                        IutCause::NotStarted,
                        "this profile is no EtherCAT terminal: it gives no identity to check",
                    ))
                })?;
                Ok(Box::new(ethercat::build(caps, config, identity, link)?))
            }
            Door::Exec { .. } => unreachable!("a process, started above"),
        }
    }

    /// The process a device behind this door runs in, and how it speaks:
    /// an exec IUT on its stdio, a hosted library on the host's control channel.
    fn device_process(&self) -> Option<(String, Timeouts, bool, Channel)> {
        match (self.hosted(Role::Device), self) {
            // A host speaks protocol 3: on a CPU of its own, each side spins
            // a moment for the other's record instead of sleeping.
            (Some((command, timeouts)), _) => Some((command, timeouts, false, Channel::Control)),
            (
                None,
                Door::Exec {
                    command,
                    timeouts,
                    same_cpu,
                },
            ) => Some((command.clone(), *timeouts, *same_cpu, Channel::Stdio)),
            _ => None,
        }
    }

    /// Something that answers configuration after configuration; for an
    /// external process, one process answers them all.
    pub fn configurer(&self) -> Configurer {
        match self.device_process() {
            Some((command, timeouts, same_cpu, channel)) => {
                let mut process: Option<ExecIut> = None;
                Box::new(move |caps, config| {
                    let iut = match process.as_mut() {
                        Some(iut) => iut,
                        None => process.insert(
                            ExecIut::spawn_on(&command, timeouts, same_cpu, channel)
                                .map_err(BuildError::Failed)?,
                        ),
                    };
                    offer(iut, caps, config, None)
                })
            }
            None => match self {
                Door::Ethercat {
                    identity: Some(identity),
                    link,
                } => {
                    let mut terminal = ethercat::Configurer::new(*identity, link.clone());
                    Box::new(move |caps, config| terminal.offer(caps, config))
                }
                _ => {
                    let door = self.clone();
                    Box::new(move |caps, config| door.device(caps, config, None).map(|_| ()))
                }
            },
        }
    }

    /// Starts the implementation once in `role`, on an 11-bit interface of
    /// 8 slots, and ends it. `Err` only where it cannot start at all — its
    /// command is not found or cannot run, its library is no file — which
    /// no run could judge; whatever else it does is the run's to judge.
    pub fn starts(&self, role: Role) -> Result<(), IutError> {
        match self {
            Door::Ethercat { .. } => return Ok(()),
            // Loading it here would run its code in canif's process: a
            // hosted library is only looked for.
            Door::Lib { path, .. } if !path.is_file() => {
                return Err(IutError::new(
                    IutCause::NotStarted,
                    format!("cannot load `{}`: no such file", path.display()),
                ))
            }
            Door::Lib { host: Some(_), .. } => return Ok(()),
            Door::Lib { .. } | Door::Exec { .. } => {}
        }
        let caps = Capabilities::everything();
        let config = InterfaceConfig::new(canif_model::config::FrameFormat::Base11, 8);
        let failed = match role {
            Role::Device => self.device(&caps, &config, None).err(),
            Role::Client => self
                .client(&config, ImageLayout::new(&config, caps.info_data))
                .err(),
        };
        match failed {
            Some(BuildError::Failed(error)) if error.cause == IutCause::NotStarted => Err(error),
            _ => Ok(()),
        }
    }

    /// Ends the client processes kept idle between programs (see
    /// `exec::client`): what a run does when its last program has ended.
    pub fn release_idle_clients() {
        exec::client::release_idle();
    }

    /// A fresh client (a new PLC program) behind the door for an interface.
    /// What a library client declares before any start (include/canif.h:
    /// `canif_client_declares` is asked first), in its host or in process;
    /// `None` for a door that tells it only once started.
    pub fn client_declares(&self) -> Option<Result<ClientDeclaration, IutError>> {
        if let Some((command, timeouts)) = self.hosted(Role::Client) {
            return Some(exec::client::declares_before_start(&command, timeouts));
        }
        match self {
            Door::Lib { path, host: None } => Some(lib::client::LibClient::declares(path)),
            _ => None,
        }
    }

    pub fn client(
        &self,
        config: &InterfaceConfig,
        layout: ImageLayout,
    ) -> Result<Box<dyn Client>, BuildError> {
        if let Some((command, timeouts)) = self.hosted(Role::Client) {
            return Ok(Box::new(
                exec::client::ExecClient::start(
                    &command,
                    timeouts,
                    Channel::Control,
                    config,
                    layout,
                )
                .map_err(BuildError::Failed)?,
            ));
        }
        Ok(match self {
            Door::Lib { path, .. } => Box::new(
                lib::client::LibClient::start(path, config, layout).map_err(BuildError::Failed)?,
            ),
            Door::Exec {
                command, timeouts, ..
            } => Box::new(
                exec::client::ExecClient::start(command, *timeouts, Channel::Stdio, config, layout)
                    .map_err(BuildError::Failed)?,
            ),
            Door::Ethercat { .. } => {
                return Err(BuildError::Failed(IutError::new(
                    IutCause::NotStarted,
                    "an EtherCAT terminal is a device: it cannot be a PLC-side client",
                )))
            }
        })
    }
}
