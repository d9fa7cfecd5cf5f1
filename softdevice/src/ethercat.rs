//! The soft device as an EtherCAT terminal: its CoE objects and the cycle
//! behind the SyncManager 2 event (003; the object numbers of Beckhoff's
//! EL6751 documentation, their sub-indices as docs/ethercat.md assumes them).
//!
//! In PREOP the master downloads `0xF800` (bus parameters), `0x8000` (the
//! interface) and `0x8001` (the filter table); the terminal computes its PDO
//! mapping (`0x1600`, `0x1A00`) from them; SAFEOP starts the soft device.

use canif_ethercat::mailbox::abort;
use canif_ethercat::subdevice::al_status;
use canif_ethercat::{Application, Entry, ObjectDictionary, Start, Synchronization};

use crate::geometry::MsgGeometry;
use crate::{Choice, Fault, FilterRule, Format, Offer, Queue, Settings, SoftDevice};

/// The objects, numbered as the EL6751 documentation numbers them.
pub mod object {
    pub const DEVICE_NAME: u16 = 0x1008;
    pub const IDENTITY: u16 = 0x1018;
    pub const RX_PDO_MAP: u16 = 0x1600;
    pub const TX_PDO_MAP: u16 = 0x1A00;
    pub const SYNC_MANAGER_TYPES: u16 = 0x1C00;
    pub const RX_PDO_ASSIGN: u16 = 0x1C12;
    pub const TX_PDO_ASSIGN: u16 = 0x1C13;
    pub const SYNC_OUTPUTS: u16 = 0x1C32;
    pub const INTERFACE: u16 = 0x8000;
    pub const FILTERS: u16 = 0x8001;
    pub const BUS_PARAMETERS: u16 = 0xF800;
}

/// Sub-indices of `0x8000`.
pub mod interface {
    pub const FLAGS: u8 = 0x20;
    pub const RX_SLOTS: u8 = 0x21;
    pub const TX_SLOTS: u8 = 0x22;
    pub const RX_QUEUE: u8 = 0x23;
    pub const TX_QUEUE: u8 = 0x24;
    pub const FLAG_29_BIT: u16 = 1 << 0;
    pub const FLAG_FD: u16 = 1 << 1;
    pub const FLAG_TRANSACTION_NUMBER: u16 = 1 << 2;
    pub const FLAG_OPTIMIZED_QUEUE: u16 = 1 << 3;
    pub const FLAG_FAST_QUEUE: u16 = 1 << 4;
    pub const FLAG_TIME_STAMP: u16 = 1 << 5;
}

/// Rows the filter table holds (an assumption: the documents give no number).
pub const FILTER_ROWS: u8 = 32;
/// A filter row: flags (bit 0 accept, bit 1 code/mask), a reserved byte, two UDINTs.
const FILTER_ROW: usize = 10;

/// What `0x1018` says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TerminalIdentity {
    pub vendor_id: u32,
    pub product_code: u32,
    pub revision: u32,
    pub serial: u32,
}

/// The terminal: its configuration as downloaded, and the soft device once in SAFEOP.
#[derive(Debug, Clone)]
pub struct Terminal {
    identity: TerminalIdentity,
    name: String,
    draft: Settings,
    faults: Vec<Fault>,
    choices: Vec<Choice>,
    sync_mode: u16,
    measure_cycle: u16,
    longest_cycle: u32,
    device: Option<SoftDevice>,
    /// A firmware fault for the harness's tests: SAFEOP refused with this AL status code.
    refuses_start: Option<u16>,
}

fn u16_of(bytes: &[u8]) -> u16 {
    u16::from_le_bytes([bytes[0], bytes[1]])
}

fn u32_of(bytes: &[u8]) -> u32 {
    u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])
}

impl Terminal {
    /// A terminal offering `offer`, with queues of these depths; configured as
    /// it leaves the factory (11-bit, one slot each way).
    pub fn new(
        identity: TerminalIdentity,
        name: &str,
        offer: Offer,
        rx_fifo_depth: usize,
        tx_fifo_depth: usize,
    ) -> Terminal {
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
            sync_mode: 1,
            measure_cycle: 0,
            longest_cycle: 0,
            device: None,
            refuses_start: None,
        }
    }

    pub fn inject(&mut self, fault: Fault) {
        self.faults.push(fault);
    }

    pub fn choose(&mut self, choice: Choice) {
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
            Format::Std11 => (0x7000, 0x6000),
            _ => (0x7001, 0x6001),
        }
    }

    /// A PDO mapping: sub 0 the count, then (index, sub, bits) per entry; a
    /// slot wider than a mapping entry's 255 bits is mapped as gaps after it.
    fn mapping(entries: &[(u16, u8, usize)]) -> Vec<Entry> {
        let mut mapped = Vec::new();
        for &(index, sub, bits) in entries {
            let mut left = bits;
            let mut first = true;
            while left > 0 {
                let now = left.min(248);
                let (i, s) = if first { (index, sub) } else { (0, 0) };
                let word = (u32::from(i) << 16) | (u32::from(s) << 8) | now as u32;
                mapped.push(word.to_le_bytes().to_vec());
                left -= now;
                first = false;
            }
        }
        let mut out = vec![Entry::new(0, vec![mapped.len() as u8], false)];
        out.extend(
            mapped
                .into_iter()
                .enumerate()
                .map(|(i, v)| Entry::new(i as u8 + 1, v, false)),
        );
        out
    }

    fn outputs_mapping(&self) -> Vec<Entry> {
        let (tx, _) = self.geometries();
        let (object, _) = self.image_objects();
        let mut entries = vec![(object, 1, 16), (object, 2, 16), (object, 3, 16)];
        for n in 0..self.draft.tx_slots {
            entries.push((object, 4 + n, tx.size * 8));
        }
        Terminal::mapping(&entries)
    }

    fn inputs_mapping(&self) -> Vec<Entry> {
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
            entries.push((0xF108, 1, crate::field::info::WORDS * 32));
        }
        Terminal::mapping(&entries)
    }

    fn flags(&self) -> u16 {
        use interface::*;
        let d = &self.draft;
        let mut flags = 0;
        for (on, flag) in [
            (d.format == Format::Ext29, FLAG_29_BIT),
            (d.format == Format::Fd, FLAG_FD),
            (d.transaction_number, FLAG_TRANSACTION_NUMBER),
            (d.queue == Queue::Optimized, FLAG_OPTIMIZED_QUEUE),
            (d.queue == Queue::Fast, FLAG_FAST_QUEUE),
            (d.time_stamp, FLAG_TIME_STAMP),
        ] {
            if on {
                flags |= flag;
            }
        }
        flags
    }

    fn filter_rows(&self) -> Vec<Entry> {
        let mut out = vec![Entry::new(0, vec![self.draft.filters.len() as u8], true)];
        for n in 0..FILTER_ROWS {
            let mut row = vec![0u8; FILTER_ROW];
            if let Some(rule) = self.draft.filters.get(usize::from(n)) {
                let (accept, mask, a, b) = match *rule {
                    FilterRule::Range { accept, low, high } => (accept, false, low, high),
                    FilterRule::Mask { accept, code, mask } => (accept, true, code, mask),
                };
                row[0] = u8::from(accept) | u8::from(mask) << 1;
                row[2..6].copy_from_slice(&a.to_le_bytes());
                row[6..10].copy_from_slice(&b.to_le_bytes());
            }
            out.push(Entry::new(n + 1, row, true));
        }
        out
    }

    /// Applies one download to a copy of the configuration, which must stay acceptable.
    fn configure(&mut self, index: u16, values: &[(u8, Vec<u8>)]) -> Result<(), u32> {
        use interface::*;
        let mut next = self.draft.clone();
        for (sub, value) in values {
            match (index, *sub) {
                (object::BUS_PARAMETERS, 1) => next.nominal_timing = u32_of(value),
                (object::BUS_PARAMETERS, 2) => next.data_timing = u32_of(value),
                (object::INTERFACE, FLAGS) => {
                    let flags = u16_of(value);
                    next.format = match (flags & FLAG_29_BIT != 0, flags & FLAG_FD != 0) {
                        (false, false) => Format::Std11,
                        (true, false) => Format::Ext29,
                        (false, true) => Format::Fd,
                        (true, true) => return Err(abort::VALUE_RANGE),
                    };
                    next.queue = match (
                        flags & FLAG_OPTIMIZED_QUEUE != 0,
                        flags & FLAG_FAST_QUEUE != 0,
                    ) {
                        (false, false) => Queue::Buffered,
                        (true, false) => Queue::Optimized,
                        (false, true) => Queue::Fast,
                        (true, true) => return Err(abort::VALUE_RANGE),
                    };
                    next.transaction_number = flags & FLAG_TRANSACTION_NUMBER != 0;
                    next.time_stamp = flags & FLAG_TIME_STAMP != 0;
                }
                (object::INTERFACE, RX_SLOTS) => {
                    next.rx_slots = u8::try_from(u16_of(value)).map_err(|_| abort::VALUE_RANGE)?
                }
                (object::INTERFACE, TX_SLOTS) => {
                    next.tx_slots = u8::try_from(u16_of(value)).map_err(|_| abort::VALUE_RANGE)?
                }
                (object::INTERFACE, RX_QUEUE | TX_QUEUE) => {
                    // The queue depths are the terminal's: only they may be written back.
                    let depth = if *sub == RX_QUEUE {
                        self.draft.rx_fifo_depth
                    } else {
                        self.draft.tx_fifo_depth
                    };
                    if usize::from(u16_of(value)) != depth {
                        return Err(abort::VALUE_RANGE);
                    }
                }
                // Sub-index 0 of a record is its highest sub-index: nothing to set.
                (object::INTERFACE | object::BUS_PARAMETERS, 0) => {}
                (object::FILTERS, 0) => {
                    let rows = usize::from(value[0]);
                    if rows > usize::from(FILTER_ROWS) {
                        return Err(abort::VALUE_RANGE);
                    }
                    next.filters.resize(
                        rows,
                        FilterRule::Range {
                            accept: false,
                            low: 0,
                            high: 0,
                        },
                    );
                }
                (object::FILTERS, row) => {
                    let n = usize::from(row) - 1;
                    if n >= next.filters.len() {
                        continue; // rows past sub-index 0 are kept, not used
                    }
                    let (a, b) = (u32_of(&value[2..6]), u32_of(&value[6..10]));
                    let accept = value[0] & 1 == 1;
                    next.filters[n] = if value[0] & 2 == 2 {
                        FilterRule::Mask {
                            accept,
                            code: a,
                            mask: b,
                        }
                    } else {
                        FilterRule::Range {
                            accept,
                            low: a,
                            high: b,
                        }
                    };
                }
                (object::SYNC_OUTPUTS, 1) => self.sync_mode = u16_of(value),
                (object::SYNC_OUTPUTS, 8) => self.measure_cycle = u16_of(value),
                _ => return Err(abort::READ_ONLY),
            }
        }
        // 0x8000 comes before 0x8001: the interface is judged without the old filter table.
        let mut judged = next.clone();
        if index == object::INTERFACE {
            judged.filters.clear();
        }
        SoftDevice::new(judged).map_err(|_| abort::VALUE_RANGE)?;
        self.draft = next;
        Ok(())
    }
}

impl ObjectDictionary for Terminal {
    fn object(&self, index: u16) -> Option<Vec<Entry>> {
        use interface::*;
        let ro = |sub: u8, value: Vec<u8>| Entry::new(sub, value, false);
        let rw = |sub: u8, value: Vec<u8>| Entry::new(sub, value, true);
        let configurable = self.device.is_none();
        Some(match index {
            object::DEVICE_NAME => vec![ro(0, self.name.as_bytes().to_vec())],
            object::IDENTITY => vec![
                ro(0, vec![4]),
                ro(1, self.identity.vendor_id.to_le_bytes().to_vec()),
                ro(2, self.identity.product_code.to_le_bytes().to_vec()),
                ro(3, self.identity.revision.to_le_bytes().to_vec()),
                ro(4, self.identity.serial.to_le_bytes().to_vec()),
            ],
            // Mailbox out, mailbox in, outputs, inputs (ETG.1000.6 Table 67).
            object::SYNC_MANAGER_TYPES => vec![
                ro(0, vec![4]),
                ro(1, vec![1]),
                ro(2, vec![2]),
                ro(3, vec![3]),
                ro(4, vec![4]),
            ],
            object::RX_PDO_ASSIGN => vec![
                ro(0, vec![1]),
                ro(1, object::RX_PDO_MAP.to_le_bytes().to_vec()),
            ],
            object::TX_PDO_ASSIGN => vec![
                ro(0, vec![1]),
                ro(1, object::TX_PDO_MAP.to_le_bytes().to_vec()),
            ],
            object::RX_PDO_MAP => self.outputs_mapping(),
            object::TX_PDO_MAP => self.inputs_mapping(),
            object::SYNC_OUTPUTS => vec![
                ro(0, vec![8]),
                rw(1, self.sync_mode.to_le_bytes().to_vec()),
                ro(5, self.longest_cycle.to_le_bytes().to_vec()),
                rw(8, self.measure_cycle.to_le_bytes().to_vec()),
            ],
            object::BUS_PARAMETERS => vec![
                ro(0, vec![2]),
                Entry::new(
                    1,
                    self.draft.nominal_timing.to_le_bytes().to_vec(),
                    configurable,
                ),
                Entry::new(
                    2,
                    self.draft.data_timing.to_le_bytes().to_vec(),
                    configurable,
                ),
            ],
            object::INTERFACE => vec![
                ro(0, vec![TX_QUEUE]),
                Entry::new(FLAGS, self.flags().to_le_bytes().to_vec(), configurable),
                Entry::new(
                    RX_SLOTS,
                    u16::from(self.draft.rx_slots).to_le_bytes().to_vec(),
                    configurable,
                ),
                Entry::new(
                    TX_SLOTS,
                    u16::from(self.draft.tx_slots).to_le_bytes().to_vec(),
                    configurable,
                ),
                Entry::new(
                    RX_QUEUE,
                    (self.draft.rx_fifo_depth as u16).to_le_bytes().to_vec(),
                    configurable,
                ),
                Entry::new(
                    TX_QUEUE,
                    (self.draft.tx_fifo_depth as u16).to_le_bytes().to_vec(),
                    configurable,
                ),
            ],
            object::FILTERS => self
                .filter_rows()
                .into_iter()
                .map(|e| Entry {
                    writable: configurable,
                    ..e
                })
                .collect(),
            _ => return None,
        })
    }

    fn write(&mut self, index: u16, values: &[(u8, Vec<u8>)]) -> Result<(), u32> {
        if self.device.is_some() && index != object::SYNC_OUTPUTS {
            return Err(abort::DEVICE_STATE);
        }
        self.configure(index, values)
    }
}

impl Application for Terminal {
    fn process_data(&self) -> (usize, usize) {
        match SoftDevice::new(self.draft.clone()) {
            Ok(device) => (device.output_len(), device.input.len()),
            Err(_) => (0, 0),
        }
    }

    fn start(&mut self, start: Start) -> Result<(), u16> {
        if let Some(code) = self.refuses_start {
            return Err(code);
        }
        let mut settings = self.draft.clone();
        settings.dc_sync1_shift = match start.synchronization {
            Synchronization::SyncManager2 => None,
            Synchronization::DistributedClocks { sync1_shift, .. } => Some(u64::from(sync1_shift)),
        };
        let mut device =
            SoftDevice::new(settings).map_err(|_| al_status::INVALID_SYNC_CONFIGURATION)?;
        for fault in &self.faults {
            device.inject(*fault);
        }
        for choice in &self.choices {
            device.choose(*choice);
        }
        self.device = Some(device);
        Ok(())
    }

    fn stop(&mut self) {
        self.device = None;
    }

    fn cycle(&mut self, outputs: &[u8], now: u64) -> Vec<u8> {
        let began = std::time::Instant::now();
        let inputs = match self.device.as_mut() {
            Some(device) => device
                .sync_manager_event(outputs, now)
                .map(<[u8]>::to_vec)
                .unwrap_or_default(),
            None => Vec::new(),
        };
        if self.measure_cycle != 0 {
            let took = began.elapsed().as_nanos().min(u128::from(u32::MAX)) as u32;
            self.longest_cycle = self.longest_cycle.max(took);
        }
        inputs
    }
}
