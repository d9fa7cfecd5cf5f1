//! The soft device as an EtherCAT terminal: the EL6751's CoE objects and the
//! cycle behind the SyncManager 2 event (003; the objects of Beckhoff's
//! public EL6751 description, what it leaves open as docs/ethercat.md
//! assumes it).
//!
//! In PREOP a master downloads `0xF800` (bus parameters), `0x8000` (the
//! interface) and `0x8001` (the filter table), and may set the PDO
//! assignment and the sync parameters; the terminal computes its PDO
//! mapping (`0x1600`, `0x1A00`, `0x1A85`) from them; SAFEOP starts the soft
//! device. The inputs are the interface's image, then the CAN status.

mod dictionary;
mod nesting;
pub mod objects;

use canif_ethercat::subdevice::al_status;
use canif_ethercat::{Application, Entry, Start, Synchronization};

use crate::field::info;
use crate::geometry::MsgGeometry;
use crate::{Fault, Format, Freedom, Offer, Queue, Settings, SoftDevice};
use objects::{object, status};

/// What `0x1018` says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TerminalIdentity {
    pub vendor_id: u32,
    pub product_code: u32,
    pub revision: u32,
    pub serial: u32,
}

/// One SyncManager's parameters (`0x1C32` outputs, `0x1C33` inputs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct SyncParameters {
    mode: u16,
    cycle_time: u32,
    sync0_cycle: u32,
}

/// The terminal: its configuration as downloaded, and the soft device once in SAFEOP.
#[derive(Debug, Clone)]
pub struct Terminal {
    identity: TerminalIdentity,
    name: String,
    draft: Settings,
    faults: Vec<Fault>,
    choices: Vec<Freedom>,
    /// `0x1C12` and `0x1C13`: the PDOs a master assigned.
    rx_assign: Vec<u16>,
    tx_assign: Vec<u16>,
    sync: [SyncParameters; 2],
    measure_cycle: u16,
    longest_cycle: u32,
    /// The outputs of the last cycle (what `0x700z` reads).
    last_outputs: Vec<u8>,
    device: Option<SoftDevice>,
    /// A firmware fault for the harness's tests: SAFEOP refused with this AL status code.
    refuses_start: Option<u16>,
    /// The object a master opened by consistency nesting, not yet closed.
    nesting: Option<nesting::Nesting>,
}

impl Terminal {
    /// A terminal offering `offer`, with queues of these depths; configured as
    /// it leaves the factory (11-bit, one slot each way, the CAN status
    /// assigned beside the interface).
    pub fn new(
        identity: TerminalIdentity,
        name: &str,
        offer: Offer,
        rx_fifo_depth: usize,
        tx_fifo_depth: usize,
    ) -> Terminal {
        let sync = SyncParameters {
            mode: 1,
            cycle_time: 0,
            sync0_cycle: 0,
        };
        Terminal {
            identity,
            name: name.to_string(),
            draft: Settings {
                offer,
                format: Format::Std11,
                queue: Queue::Buffered,
                transaction_number: false,
                time_stamp: false,
                tx_slots: 1,
                rx_slots: 1,
                filters: Vec::new(),
                dc_sync1_shift: None,
                rx_fifo_depth,
                tx_fifo_depth,
                nominal_timing: 0,
                data_timing: 0,
            },
            faults: Vec::new(),
            choices: Vec::new(),
            rx_assign: vec![object::RX_PDO_MAP],
            tx_assign: vec![object::TX_PDO_MAP, object::STATUS_PDO_MAP],
            sync: [sync, SyncParameters { mode: 0x22, ..sync }],
            measure_cycle: 0,
            longest_cycle: 0,
            last_outputs: Vec::new(),
            device: None,
            refuses_start: None,
            nesting: None,
        }
    }

    pub fn inject(&mut self, fault: Fault) {
        self.faults.push(fault);
    }

    pub fn choose(&mut self, choice: Freedom) {
        self.choices.push(choice);
    }

    /// Makes the firmware refuse every PREOP → SAFEOP with this AL status
    /// code (for the harness's tests of a terminal in error).
    pub fn refuse_start_with(&mut self, code: u16) {
        self.refuses_start = Some(code);
    }

    /// The soft device, from SAFEOP on: the CAN controller's side is driven here.
    pub fn device_mut(&mut self) -> Option<&mut SoftDevice> {
        self.device.as_mut()
    }

    pub fn device(&self) -> Option<&SoftDevice> {
        self.device.as_ref()
    }

    fn has_tn(&self) -> bool {
        self.draft.transaction_number || self.draft.format == Format::Fd
    }

    fn geometries(&self) -> (MsgGeometry, MsgGeometry) {
        let ts = self.draft.time_stamp || self.draft.format == Format::Fd;
        (
            MsgGeometry::tx(self.draft.format, self.has_tn()),
            MsgGeometry::rx(self.draft.format, ts),
        )
    }

    /// The images' objects: 0x7000/0x6000 for 11-bit, 0x7001/0x6001 for 29-bit and FD.
    fn image_objects(&self) -> (u16, u16) {
        match self.draft.format {
            Format::Std11 => (object::OUTPUTS_11, object::INPUTS_11),
            _ => (object::OUTPUTS_29, object::INPUTS_29),
        }
    }

    /// A PDO mapping: sub 0 the count, then (index, sub, bits) per entry; a
    /// slot wider than a mapping entry's 255 bits is mapped as gaps after it.
    fn mapping(entries: &[(u16, u8, usize)]) -> Vec<Entry> {
        let mapped: Vec<u32> = Terminal::mapping_words(entries).collect();
        let mut out = vec![Entry::new(0, vec![mapped.len() as u8], false)];
        out.extend(
            mapped
                .into_iter()
                .enumerate()
                .map(|(i, word)| Entry::new(i as u8 + 1, word.to_le_bytes().to_vec(), false)),
        );
        out
    }

    /// One entry of a mapping, as [`Terminal::mapping`] lists it, without
    /// building the others: a master uploads a mapping entry by entry.
    fn mapping_entry(entries: &[(u16, u8, usize)], sub: u8) -> Option<Entry> {
        let mut words = Terminal::mapping_words(entries);
        match sub {
            0 => Some(Entry::new(0, vec![words.count() as u8], false)),
            _ => words
                .nth(usize::from(sub) - 1)
                .map(|word| Entry::new(sub, word.to_le_bytes().to_vec(), false)),
        }
    }

    /// The mapping's words: (index << 16) | (sub << 8) | bits, a slot wider
    /// than 248 bits followed by gaps (index 0) for the rest.
    fn mapping_words(entries: &[(u16, u8, usize)]) -> impl Iterator<Item = u32> + '_ {
        entries.iter().flat_map(|&(index, sub, bits)| {
            (0..bits.div_ceil(248)).map(move |n| {
                let now = (bits - n * 248).min(248);
                let (i, s) = if n == 0 { (index, sub) } else { (0, 0) };
                (u32::from(i) << 16) | (u32::from(s) << 8) | now as u32
            })
        })
    }

    /// What the outputs' mapping (0x1600) lists: the header words, then a
    /// slot per Tx slot.
    fn outputs_mapped(&self) -> Vec<(u16, u8, usize)> {
        let (tx, _) = self.geometries();
        let (object, _) = self.image_objects();
        let mut entries = vec![(object, 1, 16), (object, 2, 16), (object, 3, 16)];
        for n in 0..self.draft.tx_slots {
            entries.push((object, 4 + n, tx.size * 8));
        }
        entries
    }

    /// What the inputs' mapping (0x1A00) lists: the header words, the
    /// transaction number where there is one, a slot per Rx slot, InfoData.
    fn inputs_mapped(&self) -> Vec<(u16, u8, usize)> {
        let (_, rx) = self.geometries();
        let (_, object) = self.image_objects();
        let mut entries = vec![(object, 1, 16), (object, 2, 16), (object, 3, 16)];
        if self.has_tn() {
            entries.push((object, 4, 16));
        }
        for n in 0..self.draft.rx_slots {
            entries.push((object, 5 + n, rx.size * 8));
        }
        if self.draft.offer.info_data {
            entries.push((object::INFO_DATA, 1, info::WORDS * 32));
        }
        entries
    }

    fn status_mapping() -> Vec<Entry> {
        Terminal::mapping(&[
            (object::CAN_STATUS, status::STATE, 16),
            (object::CAN_STATUS, status::RX_ERROR_COUNTER, 16),
            (object::CAN_STATUS, status::TX_ERROR_COUNTER, 16),
        ])
    }

    /// `0xF108`: the controller's status bits and error counters (zeros before SAFEOP).
    fn can_status(&self) -> [u16; 3] {
        let word = |i| {
            self.device
                .as_ref()
                .map_or(0, |d| d.controller_word(i) as u16)
        };
        [
            word(info::STATUS),
            word(info::RECEIVE_ERROR_COUNTER),
            word(info::TRANSMIT_ERROR_COUNTER),
        ]
    }

    fn status_assigned(&self) -> bool {
        self.tx_assign.contains(&object::STATUS_PDO_MAP)
    }
}

impl SoftDevice {
    /// A controller status word as InfoData numbers them (`field::info`),
    /// for the CAN status (here, beside the only objects that read it).
    fn controller_word(&self, index: usize) -> u32 {
        self.controller.get(index).copied().unwrap_or(0)
    }
}

impl Application for Terminal {
    fn process_data(&self) -> (usize, usize) {
        match SoftDevice::new(self.draft.clone()) {
            Ok(device) => {
                let status = if self.status_assigned() {
                    status::BYTES
                } else {
                    0
                };
                (device.output_len(), device.input.len() + status)
            }
            Err(_) => (0, 0),
        }
    }

    fn start(&mut self, start: Start) -> Result<(), u16> {
        if let Some(code) = self.refuses_start {
            return Err(code);
        }
        // A record opened by consistency nesting and never closed holds no
        // configuration the terminal has judged.
        if let Some(open) = &self.nesting {
            if nesting::highest(open.index).is_some() {
                return Err(al_status::INCONSISTENT_SETTINGS);
            }
        }
        self.nesting = None;
        // The CAN interface's PDOs are mandatory in their assignments.
        if !self.rx_assign.contains(&object::RX_PDO_MAP) {
            return Err(al_status::INVALID_OUTPUT_CONFIGURATION);
        }
        if !self.tx_assign.contains(&object::TX_PDO_MAP) {
            return Err(al_status::INVALID_INPUT_CONFIGURATION);
        }
        let mut settings = self.draft.clone();
        settings.dc_sync1_shift = match start.synchronization {
            Synchronization::SyncManager2 => None,
            Synchronization::DistributedClocks { sync1_shift, .. } => Some(u64::from(sync1_shift)),
        };
        let mut device = SoftDevice::with_faults(settings, &self.faults)
            .map_err(|_| al_status::INVALID_SYNC_CONFIGURATION)?;
        for choice in &self.choices {
            device.choose(*choice);
        }
        self.last_outputs = vec![0; device.output_len()];
        self.device = Some(device);
        Ok(())
    }

    fn stop(&mut self) {
        self.device = None;
    }

    fn cycle(&mut self, outputs: &[u8], now: u64) -> Vec<u8> {
        let began = std::time::Instant::now();
        let mut inputs = match self.device.as_mut() {
            Some(device) => device
                .sync_manager_event(outputs, now)
                .map(<[u8]>::to_vec)
                .unwrap_or_default(),
            None => Vec::new(),
        };
        self.last_outputs.clear();
        self.last_outputs.extend_from_slice(outputs);
        if self.status_assigned() && !inputs.is_empty() {
            for word in self.can_status() {
                inputs.extend_from_slice(&word.to_le_bytes());
            }
        }
        if self.measure_cycle != 0 {
            let took = began.elapsed().as_nanos().min(u128::from(u32::MAX)) as u32;
            self.longest_cycle = self.longest_cycle.max(took);
        }
        inputs
    }
}
