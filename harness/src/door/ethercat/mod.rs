//! A terminal under test over EtherCAT (`--iut ethercat:…`): canif is the
//! MainDevice (ethercrab). It scans, checks the identity against the profile,
//! configures the CAN interface in PREOP by CoE downloads, brings the terminal
//! to OP and runs each harness cycle as EtherCAT telegrams: one LRW carrying
//! the outputs (the SyncManager 2 event), then a read of the input
//! SyncManager for what that cycle produced. The LRW's own inputs are those
//! of the cycle before — 003's confirmation two task cycles later — and are
//! checked to be exactly those.

mod bring_up;
mod coe;
pub mod esi;
mod exchange;
mod link;
pub mod objects;
#[cfg(feature = "socketcan")]
pub mod served;
mod session;
mod start_up;
mod survey;
mod timer;
mod transport;
#[cfg(feature = "socketcan")]
mod veth;

use canif_ethercat::sii::Layout;
use canif_ethercat::{Identity, SubDevice};
use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::exchange::ExchangeMode;
use canif_model::frame::Frame;
use canif_model::info_data::ControllerStatus;
use canif_model::Nanos;
use canif_softdevice::ethercat::{Terminal, TerminalIdentity};
use canif_softdevice::{Fault, Freedom, SoftDevice};
use canif_spec::EthercatIdentity;
use ethercrab::subdevice_group::Op;
use ethercrab::{DefaultLock, SubDeviceGroup};

use crate::door::iut::{soft_controller, soft_settings, Iut, Planned, Telegrams, Transmit};
use crate::error::{IutCause, IutError};
pub use bring_up::build;
use bring_up::{bring_up, open, Opened};
use coe::Mailboxes;
pub use link::LinkFault;
use link::{lock, InterfaceMaster, MemoryMaster, SharedTerminal};
pub use session::Configurer;
use start_up::SYNC0_CYCLE_NS;
pub use survey::{preflight, survey, Pace, TerminalFacts};
pub use transport::EthercatDoor;

const MAX_SUBDEVICES: usize = 16;
const MAX_PDI: usize = 4096;
/// The working counter of an LRW that read a terminal's inputs and wrote its outputs.
const LRW_WORKING_COUNTER: u16 = 3;
/// Input SyncManager (SM3) registers.
const SM3: u16 = canif_ethercat::register::SYNC_MANAGER_BASE + 3 * 8;

/// An emulated terminal: the soft device behind an emulated ESC, in memory.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Emulated {
    pub faults: Vec<Fault>,
    pub choices: Vec<Freedom>,
    /// A fault of the link or of the ESC, for canif's own tests.
    pub link_fault: Option<LinkFault>,
    /// The SyncManager layout its SII advertises: the real EL6751's, or a
    /// second one to show that canif's master assumes none.
    pub layout: Layout,
}

impl Default for Emulated {
    fn default() -> Self {
        Emulated {
            faults: Vec::new(),
            choices: Vec::new(),
            link_fault: None,
            layout: Layout::EL6751,
        }
    }
}

/// Where canif's master finds the terminal.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EthercatLink {
    /// In memory, with the soft device's CAN controller driven by the harness.
    Emulated(Emulated),
    /// On a network interface, at this position of the segment; its CAN side
    /// is on a real bus the harness shares (`--bus socketcan:`).
    Interface { name: String, position: usize },
    /// The emulated terminal served on `terminal`, canif's master on `master`,
    /// two ends of a veth pair: frames cross the kernel's packet path.
    Veth {
        master: String,
        terminal: String,
        emulated: Emulated,
    },
}

impl EthercatLink {
    /// `emulated`, `emulated@MASTER_IFACE,TERMINAL_IFACE` or `IFACE[@POSITION]`.
    pub fn parse(text: &str) -> Result<EthercatLink, String> {
        let emulated = Emulated::default();
        if text == "emulated" {
            return Ok(EthercatLink::Emulated(emulated));
        }
        if let Some(pair) = text.strip_prefix("emulated@") {
            return match pair.split_once(',') {
                Some((master, terminal)) if !master.is_empty() && !terminal.is_empty() => {
                    Ok(EthercatLink::Veth {
                        master: master.to_string(),
                        terminal: terminal.to_string(),
                        emulated,
                    })
                }
                _ => Err(format!(
                    "`{pair}`: the two ends of a veth pair, MASTER_IFACE,TERMINAL_IFACE"
                )),
            };
        }
        let (name, position) = match text.split_once('@') {
            Some((name, position)) => (
                name,
                position.parse().map_err(|_| {
                    format!("`{position}`: a terminal's position is a number from 0")
                })?,
            ),
            None => (text, 0),
        };
        if name.is_empty() {
            return Err(
                "ethercat: needs `emulated` or a network interface, e.g. ethercat:eth1@1".into(),
            );
        }
        Ok(EthercatLink::Interface {
            name: name.to_string(),
            position,
        })
    }

    pub fn name(&self) -> String {
        match self {
            EthercatLink::Emulated(emulated) => std::iter::once("ethercat:emulated")
                .chain(emulated.faults.iter().map(|f| f.name()))
                .chain(emulated.choices.iter().map(|c| c.name()))
                .collect::<Vec<_>>()
                .join("+"),
            EthercatLink::Interface { name, position } => format!("ethercat:{name}@{position}"),
            EthercatLink::Veth {
                master,
                terminal,
                emulated,
            } => std::iter::once(format!("ethercat:emulated@{master},{terminal}"))
                .chain(emulated.faults.iter().map(|f| f.name().to_string()))
                .chain(emulated.choices.iter().map(|c| c.name().to_string()))
                .collect::<Vec<_>>()
                .join("+"),
        }
    }

    /// The soft device's faults and choices behind an emulated terminal.
    pub fn emulated_mut(&mut self) -> Option<&mut Emulated> {
        match self {
            EthercatLink::Emulated(emulated) | EthercatLink::Veth { emulated, .. } => {
                Some(emulated)
            }
            EthercatLink::Interface { .. } => None,
        }
    }
}

/// The master, on either link, holding one terminal: dropped, it lets the
/// in-memory link's terminal go (one link per thread, the next bring-up's).
/// It moves from a terminal opened in PREOP to the one brought up.
enum Master {
    Memory(&'static MemoryMaster),
    Interface(&'static InterfaceMaster),
}

impl Master {
    fn maindevice(&self) -> &'static ethercrab::MainDevice<'static> {
        match self {
            Master::Memory(m) => &m.maindevice,
            Master::Interface(m) => &m.maindevice,
        }
    }

    fn drive<T>(&self, operation: impl std::future::Future<Output = T>) -> T {
        match self {
            Master::Memory(m) => m.drive(operation),
            Master::Interface(m) => m.drive(operation),
        }
    }
}

impl Drop for Master {
    fn drop(&mut self) {
        if let Master::Memory(master) = self {
            *master.peer.borrow_mut() = None;
        }
    }
}

/// The terminal on the other end of canif's master.
pub struct EthercatIut {
    master: Master,
    group: SubDeviceGroup<MAX_SUBDEVICES, MAX_PDI, DefaultLock, Op>,
    position: usize,
    station: u16,
    /// In memory: the terminal, whose CAN controller the harness drives.
    terminal: Option<SharedTerminal>,
    /// On a veth pair: the thread serving the terminal, stopped on drop.
    #[cfg(feature = "socketcan")]
    serving: Option<veth::Serving>,
    /// What the previous cycle's SyncManager 2 event left in the inputs.
    previous_inputs: Option<Vec<u8>>,
    /// The CAN interface's share of the inputs: what follows (the CAN
    /// status, 003: "the cycle ends with the CAN status") is the terminal's own.
    interface_inputs: usize,
    /// How the played master exchanges the process data (LRW by default).
    telegrams: ExchangeMode,
    /// What the last LRW showed the terminal doing wrong, for the lockstep.
    deviation: Option<crate::door::iut::Deviation>,
    /// Where the logical image maps the terminal (read once, for LWR and LRD).
    windows: Option<exchange::Windows>,
    /// Where the input SyncManager lies, start and length (read once).
    input_sync_manager: Option<(u16, u16)>,
    /// With Distributed Clocks: the master's telegrams around each SYNC0.
    dc: Option<exchange::DcMaster>,
    pub facts: TerminalFacts,
}

/// The emulated terminal of a profile: its identity, the soft device's offer.
pub fn emulated_terminal(
    caps: &Capabilities,
    identity: &EthercatIdentity,
    emulated: &Emulated,
) -> SubDevice<Terminal> {
    let offer = soft_settings(caps, &InterfaceConfig::new(caps.first_format(), 1)).offer;
    let mut terminal = Terminal::new(
        TerminalIdentity {
            vendor_id: identity.vendor_id,
            product_code: identity.product_code,
            revision: identity.revision,
            serial: 1,
        },
        "EL6751",
        offer,
        caps.rx_queue_depth,
        caps.tx_queue_depth,
    );
    for fault in &emulated.faults {
        terminal.inject(*fault);
    }
    for choice in &emulated.choices {
        terminal.choose(*choice);
    }
    if let Some(LinkFault::AlError(code)) = emulated.link_fault {
        terminal.refuse_start_with(code);
    }
    let mut subdevice = SubDevice::with_layout(
        &Identity {
            vendor_id: identity.vendor_id,
            product_code: identity.product_code,
            revision: identity.revision,
            serial: 1,
            name: "EL6751".into(),
        },
        emulated.layout,
        terminal,
    );
    subdevice.cycles_on_frames = emulated.link_fault == Some(LinkFault::CyclesOnFrames);
    subdevice
}

impl EthercatIut {
    /// The CAN controller of a terminal in memory. On a network interface the
    /// terminal's controller is on the real bus, which the harness reads as
    /// another node (`--bus socketcan:`): it never asks for it.
    fn controller<T>(&self, act: impl FnOnce(&mut SoftDevice) -> T) -> Result<T, IutError> {
        let Some(terminal) = &self.terminal else {
            return Err(IutError::new(
                IutCause::HarnessBug,
                "a terminal on a network interface has its CAN controller on the real bus",
            ));
        };
        let mut terminal = lock(terminal);
        let device = terminal.application.device_mut().ok_or_else(|| {
            IutError::new(
                IutCause::Impossible,
                "the terminal left SAFEOP/OP during the run",
            )
        })?;
        Ok(act(device))
    }

    fn output_len(&self) -> usize {
        let md = self.master.maindevice();
        self.group
            .subdevice(md, self.position)
            .map_or(0, |sub| sub.outputs_raw().len())
    }

    /// The terminal's virtual clock (in memory, or the veth terminal's).
    fn set_clock(&self, now: Nanos) {
        link::set_now(now);
        #[cfg(feature = "socketcan")]
        if let Some(serving) = &self.serving {
            serving
                .clock
                .store(now, std::sync::atomic::Ordering::SeqCst);
        }
    }

    /// Reads `0x1C32:05` for the report.
    pub fn read_local_cycle(&mut self) {
        let md = self.master.maindevice();
        let station = self.station;
        let value = self.master.drive(async {
            let mut mailboxes = Mailboxes::of(md, station).await.ok()?;
            mailboxes
                .upload(md, objects::SYNC_OUTPUTS, objects::CYCLE_TIME_SUB)
                .await
                .ok()
        });
        if let Some(bytes) = value.filter(|b| b.len() == 4) {
            self.facts.local_cycle_ns =
                <u32 as ethercrab::EtherCrabWireRead>::unpack_from_slice(&bytes).ok();
        }
    }
}

impl Iut for EthercatIut {
    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        self.set_clock(now);
        let mapped = self.output_len();
        if mapped != outputs.len() {
            return Err(IutError::new(
                IutCause::Impossible,
                format!(
                    "the terminal mapped {mapped} output bytes; the configuration's image has {}",
                    outputs.len()
                ),
            ));
        }
        let mut inputs = match self.dc.is_some() {
            true => self.exchange_around_sync0(outputs, now),
            false => self.exchange(self.telegrams, outputs, now),
        }?;
        inputs.truncate(self.interface_inputs);
        Ok(inputs)
    }

    fn receive(&mut self, frame: &Frame, end_of_reception: Nanos) -> Result<(), IutError> {
        self.controller(|d| soft_controller::receive(d, frame, end_of_reception))
    }

    fn poll_transmit(&mut self, now: Nanos) -> Result<Transmit, IutError> {
        self.controller(|d| soft_controller::poll_transmit(d, now))
    }

    fn poll_timeout(&self) -> Option<Nanos> {
        let terminal = lock(self.terminal.as_ref()?);
        terminal
            .application
            .device()
            .and_then(SoftDevice::next_release)
    }

    fn transmit_complete(&mut self) -> Result<(), IutError> {
        self.controller(SoftDevice::tx_done_interrupt)
    }

    fn controller_status(&mut self, status: &ControllerStatus) -> Result<(), IutError> {
        self.controller(|d| soft_controller::status(d, status))
    }

    fn transmit_plan(&self, now: Nanos, most: usize) -> Option<Vec<Planned>> {
        let terminal = lock(self.terminal.as_ref()?);
        terminal
            .application
            .device()
            .map(|d| soft_controller::plan(d, now, most))
    }

    fn telegrams(&mut self) -> Option<&mut dyn Telegrams> {
        Some(self)
    }
}

impl Telegrams for EthercatIut {
    fn exchange_with(&mut self, mode: ExchangeMode) {
        self.telegrams = mode;
    }

    fn take_deviation(&mut self) -> Option<crate::door::iut::Deviation> {
        self.deviation.take()
    }
}
