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
mod transport;

pub use ethercat::EthercatDoor;
pub use exec::ExecDoor;
pub use lib::{LibDoor, LibHost};
pub use timeouts::Timeouts;
pub use transport::{Settings, Transport};
// The survey capability's types (only the EtherCAT door has one today).
pub use ethercat::{Pace, TerminalFacts};

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::image::ImageLayout;

use crate::declare::client::ClientDeclaration;
use adapter::protocol::OwnedBus;
use client::Client;
use ethercat::EthercatLink;
use iut::{BuildError, Iut};

use crate::error::IutError;

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

/// How an implementation outside canif's own code is reached: one arm per
/// transport, each the type its module defines; everything a door does is
/// that module's [`Transport`], reached through [`Door::transport`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Door {
    /// Another process speaking the adapter protocol (docs/adapter-protocol.md).
    Exec(ExecDoor),
    /// A shared library built against include/canif.h (the C ABI).
    Lib(LibDoor),
    /// A terminal over EtherCAT (a device).
    Ethercat(EthercatDoor),
}

/// Asks a device, configuration after configuration, whether it accepts.
pub type Configurer = Box<dyn FnMut(&Capabilities, &InterfaceConfig) -> Result<(), BuildError>>;

impl Door {
    /// The transport behind the door: the one place a door is told apart.
    pub fn transport(&self) -> &dyn Transport {
        match self {
            Door::Exec(door) => door,
            Door::Lib(door) => door,
            Door::Ethercat(door) => door,
        }
    }

    fn transport_mut(&mut self) -> &mut dyn Transport {
        match self {
            Door::Exec(door) => door,
            Door::Lib(door) => door,
            Door::Ethercat(door) => door,
        }
    }

    /// The door an `--iut` argument names, with the default settings:
    /// `exec:COMMAND`, `lib:PATH` or `ethercat:LINK`; `None` for words that
    /// name no door.
    pub fn parse(text: &str) -> Option<Result<Door, String>> {
        if let Some(command) = text.strip_prefix("exec:") {
            return Some(match command.trim().is_empty() {
                true => Err("exec: needs a command, e.g. exec:'python3 my_iut.py'".into()),
                false => Ok(Door::Exec(ExecDoor::new(command))),
            });
        }
        if let Some(path) = text.strip_prefix("lib:") {
            return Some(match path.is_empty() {
                true => Err("lib: needs a path, e.g. lib:./libdevice.so".into()),
                false => Ok(Door::Lib(LibDoor::in_process(path))),
            });
        }
        let link = text.strip_prefix("ethercat:")?;
        Some(EthercatLink::parse(link).map(|link| Door::Ethercat(EthercatDoor::on(link))))
    }

    /// This door with the command line's settings, or why one does not apply.
    pub fn settled(mut self, settings: &Settings) -> Result<Door, String> {
        self.transport_mut().settle(settings)?;
        Ok(self)
    }

    pub fn name(&self) -> String {
        self.transport().name()
    }

    /// This door set for `profile` (a terminal checked against its identity).
    pub fn for_profile(&self, profile: &canif_spec::Profile) -> Door {
        self.transport()
            .for_profile(profile)
            .unwrap_or_else(|| self.clone())
    }

    /// Whether the device's CAN controller is out of the harness's reach: it
    /// opens its own socket, or it is a terminal on a real bus.
    pub fn owns_its_bus(&self) -> bool {
        self.transport().owns_its_bus()
    }

    /// The device behind the door for a configuration; with `bus`, an
    /// external device is told to open that interface itself.
    pub fn device(
        &self,
        caps: &Capabilities,
        config: &InterfaceConfig,
        bus: Option<&OwnedBus>,
    ) -> Result<Box<dyn Iut>, BuildError> {
        self.transport().device(caps, config, bus)
    }

    /// Something that answers configuration after configuration; for an
    /// external process, one process answers them all.
    pub fn configurer(&self) -> Configurer {
        self.transport().configurer()
    }

    /// Starts the implementation once in `role` (see [`Transport::starts`]).
    pub fn starts(&self, role: Role) -> Result<(), IutError> {
        self.transport().starts(role)
    }

    /// Ends the client processes kept idle between programs (see
    /// `exec::client`): what a run does when its last program has ended.
    pub fn release_idle_clients() {
        exec::client::release_idle();
    }

    /// What a client declares before any start (include/canif.h:
    /// `canif_client_declares` is asked first), in its host or in process;
    /// `None` for a door that tells it only once started.
    pub fn client_declares(&self) -> Option<Result<ClientDeclaration, IutError>> {
        self.transport().client_declares()
    }

    /// A fresh client (a new PLC program) behind the door for an interface.
    pub fn client(
        &self,
        config: &InterfaceConfig,
        layout: ImageLayout,
    ) -> Result<Box<dyn Client>, BuildError> {
        self.transport().client(config, layout)
    }
}
