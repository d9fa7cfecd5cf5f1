//! The exec door: an implementation in another process speaking the
//! adapter protocol on its stdio (docs/adapter-protocol.md), in either role.

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::image::ImageLayout;

use super::client::ExecClient;
use crate::door::adapter::process::Channel;
use crate::door::adapter::protocol::OwnedBus;
use crate::door::client::Client;
use crate::door::iut::{BuildError, Iut};
use crate::door::transport::{starts_by_building, Settings, Transport};
use crate::door::{Configurer, Role, Timeouts};

/// `exec:COMMAND`: a process started with `sh -c COMMAND`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExecDoor {
    pub command: String,
    pub timeouts: Timeouts,
    /// Run the IUT on the CPU of the harness's thread: the exchange strictly
    /// alternates, and a wake-up across CPUs costs ten times one on the same
    /// CPU on a virtual machine (measured in benches/external_iut.rs).
    pub same_cpu: bool,
}

impl ExecDoor {
    /// `COMMAND` with the default limits, on the harness's CPU.
    pub fn new(command: impl Into<String>) -> Self {
        ExecDoor {
            command: command.into(),
            timeouts: Timeouts::default(),
            same_cpu: true,
        }
    }
}

impl Transport for ExecDoor {
    fn name(&self) -> String {
        format!("exec:{}", self.command)
    }

    fn device(
        &self,
        caps: &Capabilities,
        config: &InterfaceConfig,
        bus: Option<&OwnedBus>,
    ) -> Result<Box<dyn Iut>, BuildError> {
        let process = (&*self.command, self.timeouts, self.same_cpu, Channel::Stdio);
        super::spawned_device(process, caps, config, bus)
    }

    fn client(
        &self,
        config: &InterfaceConfig,
        layout: ImageLayout,
    ) -> Result<Box<dyn Client>, BuildError> {
        let client =
            ExecClient::start(&self.command, self.timeouts, Channel::Stdio, config, layout)
                .map_err(BuildError::Failed)?;
        Ok(Box::new(client))
    }

    fn configurer(&self) -> Configurer {
        super::configurer(
            self.command.clone(),
            self.timeouts,
            self.same_cpu,
            Channel::Stdio,
        )
    }

    fn starts(&self, role: Role) -> Result<(), crate::error::IutError> {
        starts_by_building(self, role)
    }

    /// It opens its own socket on the bus it is told.
    fn owns_its_bus(&self) -> bool {
        true
    }

    fn settle(&mut self, settings: &Settings) -> Result<(), String> {
        settings.no_soft_device()?;
        self.timeouts = settings.timeouts;
        self.same_cpu = settings.same_cpu;
        Ok(())
    }
}
