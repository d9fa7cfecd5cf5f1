//! What every transport offers, once: a door module implements
//! [`Transport`] for its own type, and [`super::Door`] dispatches to it in
//! one place. What only one transport can do (an EtherCAT terminal's
//! survey) is a method whose default says "not behind this door".

use std::path::PathBuf;

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::image::ImageLayout;
use canif_softdevice::{Fault, Freedom};
use canif_spec::Profile;

use super::adapter::protocol::OwnedBus;
use super::client::Client;
use super::iut::{BuildError, Iut};
use super::{Configurer, Door, Role, Timeouts};
use super::{Pace, TerminalFacts};
use crate::declare::client::ClientDeclaration;
use crate::error::{IutCause, IutError};

/// How the command line asks an implementation behind a door to be run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Settings {
    /// The start and per-request limits of a process.
    pub timeouts: Timeouts,
    /// Run a device process on the harness's CPU (docs/adapter-protocol.md).
    pub same_cpu: bool,
    /// The canif executable that hosts a library (`canif lib-host`); `None`:
    /// the library runs in canif's own process.
    pub host: Option<PathBuf>,
    /// The soft device's faults and choices, where the door has the soft
    /// device behind it (an emulated terminal).
    pub faults: Vec<Fault>,
    pub choices: Vec<Freedom>,
}

/// What a transport offers both roles; every door module has one.
pub trait Transport {
    /// How reports and `--rerun-failed` name what is behind the door.
    fn name(&self) -> String;

    /// The device behind the door for a configuration; with `bus`, an
    /// external device is told to open that interface itself.
    fn device(
        &self,
        caps: &Capabilities,
        config: &InterfaceConfig,
        bus: Option<&OwnedBus>,
    ) -> Result<Box<dyn Iut>, BuildError>;

    /// A fresh client (a new PLC program) behind the door for an interface.
    fn client(
        &self,
        config: &InterfaceConfig,
        layout: ImageLayout,
    ) -> Result<Box<dyn Client>, BuildError>;

    /// Something that answers configuration after configuration (the
    /// refusal grid); a process answers them all.
    fn configurer(&self) -> Configurer;

    /// Starts what is behind the door once in `role`, and ends it: `Err`
    /// only where it cannot start at all (its command is not found, its
    /// library is no file), which no run could judge.
    fn starts(&self, role: Role) -> Result<(), IutError>;

    /// Whether the device's CAN controller is out of the harness's reach:
    /// it opens its own socket, or it is on a real bus.
    fn owns_its_bus(&self) -> bool;

    /// Takes the command line's settings: an error names one that does not
    /// apply behind this door.
    fn settle(&mut self, settings: &Settings) -> Result<(), String>;

    /// This door set for `profile` (a terminal is checked against its
    /// identity); `None` where a door is the same for every profile.
    fn for_profile(&self, profile: &Profile) -> Option<Door> {
        let _ = profile;
        None
    }

    /// Whether a PLC-side client can be behind this door.
    fn serves_clients(&self) -> bool {
        true
    }

    /// Whether this door can run `profile` at all (a terminal only a
    /// terminal profile).
    fn serves(&self, profile: &Profile) -> bool {
        let _ = profile;
        true
    }

    /// What profiles running side by side (`--jobs`) would share that
    /// cannot be shared; `None` when they share nothing.
    fn shared_between_profiles(&self) -> Option<&'static str> {
        None
    }

    /// What a device run through this door needs before it starts, or why
    /// it cannot: `terminals` names the catalogue's terminal profiles.
    fn preflight(
        &self,
        profiles: &[&Profile],
        bus_is_sim: bool,
        terminals: &[&str],
    ) -> Result<(), String> {
        let _ = (profiles, bus_is_sim, terminals);
        Ok(())
    }

    /// What a client declares before any start; `None` for a door that
    /// tells it only once started.
    fn client_declares(&self) -> Option<Result<ClientDeclaration, IutError>> {
        None
    }

    /// The soft device's choices, where the soft device is behind the door.
    fn soft_device_choices(&self) -> Option<&[Freedom]> {
        None
    }

    /// An EtherCAT terminal's capability: the terminal of `profile` brought
    /// up once before the run, for the report. `None` behind other doors.
    fn survey(&self, profile: &Profile, pace: Pace) -> Option<Result<TerminalFacts, BuildError>> {
        let _ = (profile, pace);
        None
    }
}

/// [`Transport::starts`] for a door that can only tell by building: once,
/// on an 11-bit interface of 8 slots.
pub(super) fn starts_by_building(door: &dyn Transport, role: Role) -> Result<(), IutError> {
    let caps = Capabilities::everything();
    let config = InterfaceConfig::new(canif_model::config::FrameFormat::Base11, 8);
    let failed = match role {
        Role::Device => door.device(&caps, &config, None).err(),
        Role::Client => door
            .client(&config, ImageLayout::new(&config, caps.info_data))
            .err(),
    };
    match failed {
        Some(BuildError::Failed(error)) if error.cause == IutCause::NotStarted => Err(error),
        _ => Ok(()),
    }
}

/// [`Transport::configurer`] for a door that answers each configuration
/// by opening what is behind it afresh.
pub(super) fn configurer_by_building(door: impl Transport + 'static) -> Configurer {
    Box::new(move |caps, config| door.device(caps, config, None).map(|_| ()))
}

impl Settings {
    /// The refusal of soft-device settings where no soft device is behind
    /// what is run (a door's process, library or real terminal; the model).
    pub fn no_soft_device(&self) -> Result<(), String> {
        match (self.faults.is_empty(), self.choices.is_empty()) {
            (true, true) => Ok(()),
            (false, _) => Err(
                "--fault applies to the soft device only (pass it to the IUT's own command)".into(),
            ),
            (_, false) => Err("--choice applies to the soft device only".into()),
        }
    }
}
