//! A terminal from the segment's scan to OP: found and identified, left in
//! PREOP (`open`), given its start-up list, then SyncManagers and FMMUs,
//! SAFEOP and OP (`bring_up`); `build` is all of it.

use std::cell::Cell;
use std::sync::{Arc, Mutex};

use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::exchange::ExchangeMode;
use canif_model::image::ImageLayout;
use canif_spec::EthercatIdentity;
use ethercrab::subdevice_group::PreOp;
use ethercrab::{DefaultLock, SubDeviceGroup};

use super::coe::Mailboxes;
use super::link::{self, InterfaceMaster, MemoryMaster, Peer, SharedTerminal};
use super::start_up::{self, configure, master_error, request_safe_op, Sync0Clock};
#[cfg(feature = "socketcan")]
use super::veth;
use super::{
    emulated_terminal, exchange, EthercatIut, EthercatLink, Master, TerminalFacts, MAX_PDI,
    MAX_SUBDEVICES,
};
use crate::door::iut::BuildError;
use crate::error::{IutCause, IutError};

/// Finds the terminal `link` names, scans the segment and checks the
/// terminal's identity: it is left in PREOP.
pub(super) fn open(
    caps: &Capabilities,
    identity: &EthercatIdentity,
    link: &EthercatLink,
) -> Result<Opened, BuildError> {
    // Each terminal starts its virtual clock at 0, where the first cycle
    // (and, with Distributed Clocks, the first SYNC0) is.
    link::set_now(0);
    #[cfg(feature = "socketcan")]
    let mut serving = None;
    let (master, terminal, position) = match link {
        EthercatLink::Emulated(emulated) => {
            let master = MemoryMaster::of_this_thread();
            let terminal = Arc::new(Mutex::new(emulated_terminal(caps, identity, emulated)));
            *master.peer.borrow_mut() = Some(Peer {
                terminal: Arc::clone(&terminal),
                fault: emulated.link_fault,
                frames: Cell::new(0),
            });
            (Master::Memory(master), Some(terminal), 0)
        }
        EthercatLink::Interface { name, position } => {
            let master = InterfaceMaster::on(name).map_err(|e| {
                BuildError::Failed(IutError::new(
                    IutCause::NotStarted,
                    format!("EtherCAT master on {name}: {e} (a raw socket needs CAP_NET_RAW)"),
                ))
            })?;
            (Master::Interface(master), None, *position)
        }
        #[cfg(feature = "socketcan")]
        EthercatLink::Veth {
            master: master_side,
            terminal: terminal_side,
            emulated,
        } => {
            let terminal = Arc::new(Mutex::new(emulated_terminal(caps, identity, emulated)));
            let not_started =
                |what: String| BuildError::Failed(IutError::new(IutCause::NotStarted, what));
            serving = Some(
                veth::Serving::start(terminal_side, &terminal)
                    .map_err(|e| not_started(format!("the terminal on {terminal_side}: {e}")))?,
            );
            let master = InterfaceMaster::on(master_side).map_err(|e| {
                not_started(format!(
                    "EtherCAT master on {master_side}: {e} (a raw socket needs CAP_NET_RAW)"
                ))
            })?;
            (Master::Interface(master), Some(terminal), 0)
        }
        #[cfg(not(feature = "socketcan"))]
        EthercatLink::Veth { .. } => {
            return Err(BuildError::Failed(IutError::new(
                IutCause::NotStarted,
                "a veth pair needs Linux sockets (cargo feature `socketcan`)",
            )))
        }
    };
    let md = master.maindevice();
    let group = master
        .drive(md.init_single_group::<MAX_SUBDEVICES, MAX_PDI>(link::now))
        .map_err(|e| BuildError::Failed(master_error(e, "scanning the segment")))?;
    let (station, facts) = {
        let sub = group
            .subdevice(md, position)
            .map_err(|e| BuildError::Failed(master_error(e, "finding the terminal")))?;
        let seen = sub.identity();
        let facts = TerminalFacts {
            name: sub.name().to_string(),
            vendor_id: seen.vendor_id,
            product_code: seen.product_id,
            revision: seen.revision,
            serial: seen.serial,
            ..TerminalFacts::default()
        };
        if (seen.vendor_id, seen.product_id, seen.revision)
            != (identity.vendor_id, identity.product_code, identity.revision)
        {
            return Err(BuildError::Failed(IutError::new(
                IutCause::Impossible,
                format!(
                    "the terminal at position {position} is vendor {:#010x} product {:#010x} revision {:#010x}; the profile's is {:#010x}/{:#010x}/{:#010x}",
                    seen.vendor_id, seen.product_id, seen.revision,
                    identity.vendor_id, identity.product_code, identity.revision
                ),
            )));
        }
        (sub.configured_address(), facts)
    };
    Ok(Opened {
        master,
        terminal,
        position,
        #[cfg(feature = "socketcan")]
        serving,
        group,
        station,
        facts,
        mailboxes: None,
    })
}

/// A terminal found on its link and checked, in PREOP: what a start-up
/// list is written to.
pub(super) struct Opened {
    pub(super) master: Master,
    /// In memory or on a veth pair: the emulated terminal.
    pub(super) terminal: Option<SharedTerminal>,
    pub(super) position: usize,
    #[cfg(feature = "socketcan")]
    pub(super) serving: Option<veth::Serving>,
    pub(super) group: SubDeviceGroup<MAX_SUBDEVICES, MAX_PDI, DefaultLock, PreOp>,
    pub(super) station: u16,
    pub(super) facts: TerminalFacts,
    /// Its mailbox SyncManagers, once a start-up list has read them.
    pub(super) mailboxes: Option<Mailboxes>,
}

impl Opened {
    /// Where the first SYNC0 lies: at the harness's virtual time 0 for an
    /// emulated terminal, ahead of the terminal's own time for a real one.
    pub(super) fn clock(&self) -> Sync0Clock {
        match &self.terminal {
            Some(_) => Sync0Clock::Virtual {
                now: link::now(),
                first_sync0: 0,
            },
            None => Sync0Clock::Real,
        }
    }

    /// Writes the start-up list of `config` (and the DC registers) in PREOP.
    pub(super) fn configure(
        &mut self,
        caps: &Capabilities,
        config: &InterfaceConfig,
    ) -> Result<(), BuildError> {
        let md = self.master.maindevice();
        let clock = self.clock();
        self.master.drive(configure(
            md,
            self.station,
            &mut self.mailboxes,
            (caps, config),
            clock,
        ))
    }
}

/// Brings up the terminal `link` names and configures it as `config`.
pub fn build(
    caps: &Capabilities,
    config: &InterfaceConfig,
    identity: &EthercatIdentity,
    link: &EthercatLink,
) -> Result<EthercatIut, BuildError> {
    let mut opened = open(caps, identity, link)?;
    opened.configure(caps, config)?;
    bring_up(opened, caps, config)
}

/// A terminal in PREOP that took its start-up list, to OP: SyncManagers and
/// FMMUs, SAFEOP, OP.
pub(super) fn bring_up(
    opened: Opened,
    caps: &Capabilities,
    config: &InterfaceConfig,
) -> Result<EthercatIut, BuildError> {
    let (master, station, position) = (&opened.master, opened.station, opened.position);
    let md = master.maindevice();
    let group = master
        .drive(opened.group.into_pre_op_pdi(md))
        .map_err(|e| BuildError::Failed(master_error(e, "configuring SyncManagers and FMMUs")))?;
    master.drive(request_safe_op(md, station))?;
    let group = master
        .drive(group.into_op(md))
        .map_err(|e| BuildError::Failed(master_error(e, "SAFEOP → OP")))?;
    let interface_inputs = ImageLayout::new(config, caps.info_data).input_size();
    let mut facts = opened.facts;
    facts.sync_managers = master.drive(start_up::sync_managers(md, station));
    if let Ok(sub) = group.subdevice(md, position) {
        facts.output_bytes = sub.outputs_raw().len();
        facts.input_bytes = sub.inputs_raw().len();
    }
    facts.status_bytes = facts.input_bytes.saturating_sub(interface_inputs);
    if facts.input_bytes < interface_inputs {
        return Err(BuildError::Failed(IutError::new(
            IutCause::Impossible,
            format!(
                "the terminal mapped {} input bytes; the configuration's image has {interface_inputs}",
                facts.input_bytes
            ),
        )));
    }
    Ok(EthercatIut {
        interface_inputs,
        master: opened.master,
        group,
        position,
        station,
        terminal: opened.terminal,
        #[cfg(feature = "socketcan")]
        serving: opened.serving,
        previous_inputs: None,
        telegrams: ExchangeMode::Lrw,
        deviation: None,
        windows: None,
        input_sync_manager: None,
        dc: matches!(
            config.synchronization,
            canif_model::config::Synchronization::DistributedClocks { .. }
        )
        .then(exchange::DcMaster::default),
        facts,
    })
}
