//! The lib door: a shared library built against include/canif.h (the C
//! ABI), in canif's process or hosted in a `canif lib-host` of its own,
//! where a crash or an access past its images ends that process only.

use std::path::{Path, PathBuf};

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::image::ImageLayout;

use super::client::LibClient;
use crate::declare::client::ClientDeclaration;
use crate::door::adapter::process::Channel;
use crate::door::adapter::protocol::OwnedBus;
use crate::door::client::Client;
use crate::door::exec::client::{declares_before_start, ExecClient};
use crate::door::exec::spawned_device;
use crate::door::iut::{BuildError, Iut};
use crate::door::transport::{configurer_by_building, starts_by_building, Settings, Transport};
use crate::door::{Configurer, Role, Timeouts};
use crate::error::{IutCause, IutError};

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

/// `lib:PATH`: the library, in process (`host: None`) or hosted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LibDoor {
    pub path: PathBuf,
    pub host: Option<LibHost>,
}

impl LibDoor {
    /// The library at `path`, in canif's process.
    pub fn in_process(path: impl Into<PathBuf>) -> Self {
        LibDoor {
            path: path.into(),
            host: None,
        }
    }

    /// A hosted library as the process it runs in: its command, and how
    /// long it may take. The host speaks on its control channel, so that
    /// what the library prints is its output, never a broken exchange.
    fn hosted(&self, role: Role) -> Option<(String, Timeouts)> {
        let host = self.host.as_ref()?;
        Some((host.command(role, &self.path), host.timeouts))
    }
}

impl Transport for LibDoor {
    fn name(&self) -> String {
        format!("lib:{}", self.path.display())
    }

    fn device(
        &self,
        caps: &Capabilities,
        config: &InterfaceConfig,
        _: Option<&OwnedBus>,
    ) -> Result<Box<dyn Iut>, BuildError> {
        match self.hosted(Role::Device) {
            // A host speaks protocol 3: on a CPU of its own, each side spins
            // a moment for the other's record instead of sleeping. Its CAN
            // side the harness drives through the protocol.
            Some((command, timeouts)) => spawned_device(
                (&command, timeouts, false, Channel::Control),
                caps,
                config,
                None,
            ),
            None => Ok(Box::new(super::build(&self.path, caps, config)?)),
        }
    }

    fn client(
        &self,
        config: &InterfaceConfig,
        layout: ImageLayout,
    ) -> Result<Box<dyn Client>, BuildError> {
        let client: Box<dyn Client> = match self.hosted(Role::Client) {
            Some((command, timeouts)) => Box::new(
                ExecClient::start(&command, timeouts, Channel::Control, config, layout)
                    .map_err(BuildError::Failed)?,
            ),
            None => {
                Box::new(LibClient::start(&self.path, config, layout).map_err(BuildError::Failed)?)
            }
        };
        Ok(client)
    }

    fn configurer(&self) -> Configurer {
        match self.hosted(Role::Device) {
            Some((command, timeouts)) => {
                crate::door::exec::configurer(command, timeouts, false, Channel::Control)
            }
            None => configurer_by_building(self.clone()),
        }
    }

    fn starts(&self, role: Role) -> Result<(), IutError> {
        if !self.path.is_file() {
            return Err(IutError::new(
                IutCause::NotStarted,
                format!("cannot load `{}`: no such file", self.path.display()),
            ));
        }
        // Loading it here would run its code in canif's process: a hosted
        // library is only looked for.
        match self.host {
            Some(_) => Ok(()),
            None => starts_by_building(self, role),
        }
    }

    fn owns_its_bus(&self) -> bool {
        false
    }

    fn settle(&mut self, settings: &Settings) -> Result<(), String> {
        settings.no_soft_device()?;
        self.host = settings.host.clone().map(|canif| LibHost {
            canif,
            timeouts: settings.timeouts,
        });
        Ok(())
    }

    fn shared_between_profiles(&self) -> Option<&'static str> {
        match self.host {
            None => Some("--lib-in-process: one library in canif's process"),
            Some(_) => None,
        }
    }

    fn client_declares(&self) -> Option<Result<ClientDeclaration, IutError>> {
        Some(match self.hosted(Role::Client) {
            Some((command, timeouts)) => declares_before_start(&command, timeouts),
            None => LibClient::declares(&self.path),
        })
    }
}
