//! The EtherCAT door: a terminal (a device) reached by canif's master
//! through real frames, in memory, on a veth pair or on a network interface.

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::image::ImageLayout;
use canif_softdevice::Freedom;
use canif_spec::{EthercatIdentity, Profile};

use super::{build, preflight, survey, Configurer as TerminalConfigurer, EthercatLink};
use super::{Pace, TerminalFacts};
use crate::door::adapter::protocol::OwnedBus;
use crate::door::client::Client;
use crate::door::iut::{BuildError, Iut};
use crate::door::transport::{configurer_by_building, Settings, Transport};
use crate::door::{Configurer, Door, Role};
use crate::error::{IutCause, IutError};

/// `ethercat:…`: a terminal on `link`, checked against `identity` (the
/// profile's, set per profile by the run).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EthercatDoor {
    pub identity: Option<EthercatIdentity>,
    pub link: EthercatLink,
}

impl EthercatDoor {
    /// The terminal on `link`, its identity not yet set.
    pub fn on(link: EthercatLink) -> Self {
        EthercatDoor {
            identity: None,
            link,
        }
    }

    fn identity(&self) -> Result<&EthercatIdentity, BuildError> {
        self.identity.as_ref().ok_or_else(|| {
            BuildError::Failed(IutError::new(
                IutCause::NotStarted,
                "this profile is no EtherCAT terminal: it gives no identity to check",
            ))
        })
    }
}

impl Transport for EthercatDoor {
    fn name(&self) -> String {
        self.link.name()
    }

    fn device(
        &self,
        caps: &Capabilities,
        config: &InterfaceConfig,
        _: Option<&OwnedBus>,
    ) -> Result<Box<dyn Iut>, BuildError> {
        Ok(Box::new(build(caps, config, self.identity()?, &self.link)?))
    }

    fn client(&self, _: &InterfaceConfig, _: ImageLayout) -> Result<Box<dyn Client>, BuildError> {
        Err(BuildError::Failed(IutError::new(
            IutCause::NotStarted,
            "an EtherCAT terminal is a device: it cannot be a PLC-side client",
        )))
    }

    fn configurer(&self) -> Configurer {
        match self.identity {
            Some(identity) => {
                let mut terminal = TerminalConfigurer::new(identity, self.link.clone());
                Box::new(move |caps, config| terminal.offer(caps, config))
            }
            None => configurer_by_building(self.clone()),
        }
    }

    /// A terminal is met by the run itself, which reports what broke.
    fn starts(&self, _: Role) -> Result<(), IutError> {
        Ok(())
    }

    /// A terminal on a network interface has its CAN port on a real bus.
    fn owns_its_bus(&self) -> bool {
        matches!(self.link, EthercatLink::Interface { .. })
    }

    fn settle(&mut self, settings: &Settings) -> Result<(), String> {
        match self.link.emulated_mut() {
            Some(emulated) => {
                emulated.faults = settings.faults.clone();
                emulated.choices = settings.choices.clone();
                Ok(())
            }
            None => settings.no_soft_device(),
        }
    }

    fn for_profile(&self, profile: &Profile) -> Option<Door> {
        Some(Door::Ethercat(EthercatDoor {
            identity: profile.ethercat,
            link: self.link.clone(),
        }))
    }

    /// A terminal is a device.
    fn serves_clients(&self) -> bool {
        false
    }

    fn serves(&self, profile: &Profile) -> bool {
        profile.ethercat.is_some()
    }

    fn shared_between_profiles(&self) -> Option<&'static str> {
        Some("an EtherCAT terminal: one link")
    }

    fn preflight(
        &self,
        profiles: &[&Profile],
        bus_is_sim: bool,
        terminals: &[&str],
    ) -> Result<(), String> {
        preflight(&self.link, profiles, bus_is_sim, terminals)
    }

    fn soft_device_choices(&self) -> Option<&[Freedom]> {
        match &self.link {
            EthercatLink::Emulated(emulated) | EthercatLink::Veth { emulated, .. } => {
                Some(&emulated.choices)
            }
            EthercatLink::Interface { .. } => None,
        }
    }

    fn survey(&self, profile: &Profile, pace: Pace) -> Option<Result<TerminalFacts, BuildError>> {
        profile
            .ethercat
            .is_some()
            .then(|| survey(profile, &self.link, pace))
    }
}
