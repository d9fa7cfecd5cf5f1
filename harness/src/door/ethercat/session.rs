//! Configuration after configuration to one terminal held in PREOP, as a
//! configurator rewrites a terminal's start-up list: the refusal grid's
//! thousands of configurations cost a start-up list each, not a scan of the
//! segment each (which reads the whole SII: four fifths of the grid's time
//! over the in-memory link, measured). A real terminal keeps what it was
//! written between configurations in either case; so does this one.
//!
//! A start-up list the terminal takes is then brought up from there as a
//! run brings one up (SyncManagers, FMMUs, SAFEOP, OP), and the next list
//! goes to a fresh scan: taken back to PREOP instead, the emulated terminal
//! judges the next list against the settings the last one left, where a
//! fresh bring-up starts from its defaults (the test that compares the two
//! said so).

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_spec::EthercatIdentity;

use super::{bring_up, open, EthercatLink, Opened};
use crate::door::iut::BuildError;

/// Offers configurations to the terminal `link` names, one after another.
pub struct Configurer {
    identity: EthercatIdentity,
    link: EthercatLink,
    /// The terminal in PREOP, for the capabilities it was opened with.
    held: Option<(Capabilities, Opened)>,
}

impl Configurer {
    pub fn new(identity: EthercatIdentity, link: EthercatLink) -> Self {
        Configurer {
            identity,
            link,
            held: None,
        }
    }

    /// Whether the terminal takes `config`: refused by an SDO abort of its
    /// start-up list, or by an AL status code on the way to OP.
    pub fn offer(
        &mut self,
        caps: &Capabilities,
        config: &InterfaceConfig,
    ) -> Result<(), BuildError> {
        if self
            .held
            .as_ref()
            .is_some_and(|(held_for, _)| held_for != caps)
        {
            self.held = None;
        }
        let mut opened = match self.held.take() {
            Some((_, opened)) => opened,
            // The held terminal, if any, is gone before a scan takes its link.
            None => open(caps, &self.identity, &self.link)?,
        };
        match opened.configure(caps, config) {
            // Still in PREOP: the next list is written over this one.
            Err(BuildError::Refused(why)) => {
                self.held = Some((caps.clone(), opened));
                Err(BuildError::Refused(why))
            }
            Err(failed) => Err(failed),
            Ok(()) => bring_up(opened, caps, config).map(|_| ()),
        }
    }
}
