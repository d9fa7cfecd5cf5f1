//! Configuration after configuration to one terminal held in PREOP, as a
//! configurator rewrites a terminal's start-up list: the refusal grid's
//! thousands of configurations cost a start-up list each, not a scan of the
//! segment each (which reads the whole SII: four fifths of the grid's time
//! over the in-memory link, measured). A real terminal keeps what it was
//! written between configurations in either case; so does this one.
//!
//! A start-up list the terminal takes is then brought up from there as a
//! run brings one up (SyncManagers, FMMUs, SAFEOP, OP), and the next list
//! goes to a fresh scan, since ethercrab's group does not return from OP
//! to a PREOP it can configure again.

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_spec::EthercatIdentity;

use super::{bring_up, open, EthercatLink, Opened};
use crate::door::iut::BuildError;

/// Offers configurations to the terminal `link` names, one after another.
pub struct Configurer {
    identity: EthercatIdentity,
    link: EthercatLink,
    /// The terminal in PREOP, for the capabilities it was opened with.
    held: Option<(Capabilities, Held)>,
}

/// An opened terminal; the in-memory link lets go of it when it goes,
/// unless it was brought up (`None`: the running terminal lets go then).
struct Held(Option<Opened>);

impl Drop for Held {
    fn drop(&mut self) {
        if let Some(opened) = &self.0 {
            opened.master.let_go();
        }
    }
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
        let held = match &mut self.held {
            Some((_, held)) => held,
            None => {
                let opened = open(caps, &self.identity, &self.link)?;
                &mut self.held.insert((caps.clone(), Held(Some(opened)))).1
            }
        };
        let opened = held.0.as_mut().expect("a held terminal is opened");
        match opened.configure(caps, config) {
            // Still in PREOP: the next list is written over this one.
            Err(BuildError::Refused(why)) => Err(BuildError::Refused(why)),
            Err(failed) => {
                self.held = None;
                Err(failed)
            }
            Ok(()) => {
                let opened = held.0.take().expect("a held terminal is opened");
                self.held = None;
                bring_up(opened, caps, config).map(|_| ())
            }
        }
    }
}
