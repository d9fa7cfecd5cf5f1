//! The terminal's object dictionary: what each object reads, and what a
//! download may change (in PREOP; `0x1C32:08`/`0x1C33:08` at any time, as
//! 000 §5 has the measurement started and stopped).

use canif_ethercat::mailbox::abort;
use canif_ethercat::{Entry, ObjectDictionary};

use super::nesting::{self, Step};
use super::objects::{self, flags, interface, object, status, sync, FILTER_ROW, FILTER_ROWS};
use super::Terminal;
use crate::field::{header, info};
use crate::geometry::MsgGeometry;
use crate::{FilterRule, Format, Queue};

fn u16_of(bytes: &[u8]) -> u16 {
    u16::from_le_bytes([bytes[0], bytes[1]])
}

fn u32_of(bytes: &[u8]) -> u32 {
    u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])
}

fn ro(sub: u8, value: Vec<u8>) -> Entry {
    Entry::new(sub, value, false)
}

/// The bytes `range` of `image`, zeros where it is shorter.
fn slice(image: &[u8], at: usize, len: usize) -> Vec<u8> {
    let mut out = image.get(at..).unwrap_or_default().to_vec();
    out.resize(len, 0);
    out.truncate(len);
    out
}

impl Terminal {
    fn flags(&self) -> u16 {
        let d = &self.draft;
        let format = match (d.format, d.transaction_number) {
            (Format::Std11, false) => 0,
            (Format::Std11, true) => flags::STD11_TRANSACTION_NUMBER,
            (Format::Ext29, false) => flags::EXT29,
            (Format::Ext29, true) => flags::EXT29_TRANSACTION_NUMBER,
            (Format::Fd, _) => flags::FD,
        };
        let queue = match d.queue {
            Queue::Buffered => 0,
            Queue::Optimized => flags::OPTIMIZED_QUEUE,
            Queue::Fast => flags::FAST_QUEUE,
        };
        let stamp = if d.time_stamp { flags::TIME_STAMP } else { 0 };
        format | queue | stamp
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

    /// A record's sub-index 0: its highest sub-index, written 0 and back by
    /// consistency nesting (it reads 0 while the record is open).
    fn record_sub0(&self, index: u16, writable: bool) -> Entry {
        let open = self.nesting.as_ref().is_some_and(|n| n.index == index);
        let highest = nesting::highest(index).unwrap_or(0);
        Entry::new(0, vec![if open { 0 } else { highest }], writable)
    }

    /// `0x1C12`/`0x1C13`: the count, then two places.
    fn assignment(assigned: &[u16], writable: bool) -> Vec<Entry> {
        let mut out = vec![Entry::new(0, vec![assigned.len() as u8], writable)];
        for place in 0..2u8 {
            let pdo = assigned.get(usize::from(place)).copied().unwrap_or(0);
            out.push(Entry::new(place + 1, pdo.to_le_bytes().to_vec(), writable));
        }
        out
    }

    fn sync_parameters(&self, inputs: bool, writable: bool) -> Vec<Entry> {
        let p = self.sync[usize::from(inputs)];
        let longest = if inputs { 0 } else { self.longest_cycle };
        vec![
            ro(0, vec![sync::SYNC_ERROR]),
            Entry::new(sync::MODE, p.mode.to_le_bytes().to_vec(), writable).named("Sync mode"),
            Entry::new(
                sync::CYCLE_TIME,
                p.cycle_time.to_le_bytes().to_vec(),
                writable,
            )
            .named("Cycle time"),
            ro(sync::SHIFT_TIME, vec![0; 4]).named("Shift time"),
            ro(
                sync::MODES_SUPPORTED,
                sync::SUPPORTED.to_le_bytes().to_vec(),
            )
            .named("Sync modes supported"),
            ro(sync::MINIMUM_CYCLE_TIME, longest.to_le_bytes().to_vec())
                .named("Minimum cycle time"),
            ro(sync::CALC_AND_COPY_TIME, vec![0; 4]).named("Calc and copy time"),
            Entry::new(
                sync::GET_CYCLE_TIME,
                self.measure_cycle.to_le_bytes().to_vec(),
                true,
            )
            .named("Get cycle time"),
            ro(sync::DELAY_TIME, vec![0; 4]).named("Delay time"),
            Entry::new(
                sync::SYNC0_CYCLE_TIME,
                p.sync0_cycle.to_le_bytes().to_vec(),
                writable,
            )
            .named("Sync0 cycle time"),
            ro(sync::SM_EVENT_MISSED, vec![0; 2]).named("SM-Event Missed"),
            ro(sync::CYCLE_TIME_TOO_SMALL, vec![0; 2]).named("Cycle time too small"),
            ro(sync::SYNC_ERROR, vec![0]).named("Sync error"),
        ]
    }

    /// `0x700z` (outputs) and `0x600z` (inputs): the image as the last
    /// cycle left it (zeros for the format not configured): the three
    /// counters, for the inputs the transaction number, then one message per slot.
    fn image_object(&self, index: u16, inputs: bool) -> Vec<Entry> {
        let (outputs_object, inputs_object) = self.image_objects();
        let current = index
            == if inputs {
                inputs_object
            } else {
                outputs_object
            };
        let image: &[u8] = match (current, inputs, &self.device) {
            (true, false, _) => &self.last_outputs,
            (true, true, Some(device)) => &device.input,
            _ => &[],
        };
        let (tx, rx) = self.geometries();
        let size = match (current, inputs) {
            (true, false) => tx.size,
            (true, true) => rx.size,
            (false, _) => {
                let format = match index {
                    object::OUTPUTS_11 | object::INPUTS_11 => Format::Std11,
                    _ => Format::Ext29,
                };
                match inputs {
                    false => MsgGeometry::tx(format, false).size,
                    true => MsgGeometry::rx(format, false).size,
                }
            }
        };
        let with_tn = current && self.has_tn();
        let (first_sub, first_at, slots, count_name) = match inputs {
            false => (
                4,
                header::MESSAGES,
                self.draft.tx_slots,
                "Number of TX Messages",
            ),
            true if with_tn => (
                5,
                header::MESSAGES_AFTER_TRANSACTION_NUMBER,
                self.draft.rx_slots,
                "Number of RX Messages",
            ),
            true => (
                5,
                header::MESSAGES,
                self.draft.rx_slots,
                "Number of RX Messages",
            ),
        };
        let mut out = vec![ro(0, vec![first_sub - 1 + slots])];
        for (sub, at, name) in [
            (1, header::TX_COUNTER, "TX Counter"),
            (2, header::RX_COUNTER, "RX Counter"),
            (3, header::NO_OF_MESSAGES, count_name),
        ] {
            out.push(ro(sub, slice(image, at, 2)).named(name));
        }
        if inputs {
            let tn: &[u8] = if with_tn { image } else { &[] };
            out.push(
                ro(4, slice(tn, header::TRANSACTION_NUMBER, 2)).named("TX Transaction Number"),
            );
        }
        for n in 0..slots {
            let at = first_at + usize::from(n) * size;
            out.push(ro(first_sub + n, slice(image, at, size)));
        }
        out
    }

    /// Applies one download to a copy of the terminal, which must stay acceptable.
    fn configure(&mut self, index: u16, values: &[(u8, Vec<u8>)]) -> Result<(), u32> {
        // What `set` changes, put back when the download is refused (the
        // whole terminal was cloned for this once: a fifth of the time the
        // refusal grid spent in the terminal).
        let before = (
            self.draft.clone(),
            self.rx_assign.clone(),
            self.tx_assign.clone(),
            self.sync,
            self.measure_cycle,
        );
        let written = values
            .iter()
            .try_for_each(|(sub, value)| self.set(index, *sub, value))
            .and_then(|()| self.judge(index));
        if written.is_err() {
            (
                self.draft,
                self.rx_assign,
                self.tx_assign,
                self.sync,
                self.measure_cycle,
            ) = before;
        }
        written
    }

    /// Whether the soft device takes the settings as written so far (what
    /// `SoftDevice::new` checks, without building one).
    fn judge(&self, index: u16) -> Result<(), u32> {
        let refused = |_| abort::VALUE_RANGE;
        // 0x8000 comes before 0x8001: the interface is judged without the old filter table.
        if index == object::INTERFACE && !self.draft.filters.is_empty() {
            let mut judged = self.draft.clone();
            judged.filters.clear();
            return judged.check(&[]).map_err(refused);
        }
        self.draft.check(&[]).map_err(refused)
    }

    fn set(&mut self, index: u16, sub: u8, value: &[u8]) -> Result<(), u32> {
        let d = &mut self.draft;
        match (index, sub) {
            // Sub-index 0 of a record is its highest sub-index: nothing to set.
            (
                object::INTERFACE
                | object::BUS_PARAMETERS
                | object::SYNC_OUTPUTS
                | object::SYNC_INPUTS,
                0,
            ) => {}
            (object::BUS_PARAMETERS, 1) => d.nominal_timing = u32_of(value),
            (object::BUS_PARAMETERS, 2) => d.data_timing = u32_of(value),
            (object::INTERFACE, interface::FLAGS) => {
                let bits = u16_of(value);
                let formats = bits & flags::FORMATS;
                if bits & !flags::KNOWN != 0 || formats.count_ones() > 1 {
                    return Err(abort::VALUE_RANGE);
                }
                (d.format, d.transaction_number) = match formats {
                    flags::EXT29 => (Format::Ext29, false),
                    flags::EXT29_TRANSACTION_NUMBER => (Format::Ext29, true),
                    flags::STD11_TRANSACTION_NUMBER => (Format::Std11, true),
                    flags::FD => (Format::Fd, false),
                    _ => (Format::Std11, false),
                };
                d.queue = match bits & (flags::OPTIMIZED_QUEUE | flags::FAST_QUEUE) {
                    0 => Queue::Buffered,
                    flags::OPTIMIZED_QUEUE => Queue::Optimized,
                    flags::FAST_QUEUE => Queue::Fast,
                    _ => return Err(abort::VALUE_RANGE),
                };
                d.time_stamp = bits & flags::TIME_STAMP != 0;
            }
            (object::INTERFACE, interface::RX_SLOTS) => {
                d.rx_slots = u8::try_from(u16_of(value)).map_err(|_| abort::VALUE_RANGE)?
            }
            (object::INTERFACE, interface::TX_SLOTS) => {
                d.tx_slots = u8::try_from(u16_of(value)).map_err(|_| abort::VALUE_RANGE)?
            }
            (object::INTERFACE, interface::RX_QUEUE | interface::TX_QUEUE) => {
                let depth = u16_of(value);
                if !(1..=interface::MAX_QUEUE_DEPTH).contains(&depth) {
                    return Err(abort::VALUE_RANGE);
                }
                match sub {
                    interface::RX_QUEUE => d.rx_fifo_depth = usize::from(depth),
                    _ => d.tx_fifo_depth = usize::from(depth),
                }
            }
            (object::FILTERS, 0) => {
                let rows = usize::from(value[0]);
                if rows > usize::from(FILTER_ROWS) {
                    return Err(abort::VALUE_RANGE);
                }
                let blank = FilterRule::Range {
                    accept: false,
                    low: 0,
                    high: 0,
                };
                d.filters.resize(rows, blank);
            }
            (object::FILTERS, row) => {
                let n = usize::from(row) - 1;
                if n >= d.filters.len() {
                    return Ok(()); // rows past sub-index 0 are kept, not used
                }
                let (a, b) = (u32_of(&value[2..6]), u32_of(&value[6..10]));
                let accept = value[0] & 1 == 1;
                d.filters[n] = if value[0] & 2 == 2 {
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
            (object::RX_PDO_ASSIGN | object::TX_PDO_ASSIGN, 0) => {
                let assigned = self.assigned_mut(index);
                if value[0] > 2 {
                    return Err(abort::VALUE_RANGE);
                }
                assigned.resize(usize::from(value[0]), 0);
            }
            (object::RX_PDO_ASSIGN | object::TX_PDO_ASSIGN, place @ 1..=2) => {
                let pdo = u16_of(value);
                let known: &[u16] = match index {
                    object::RX_PDO_ASSIGN => &[object::RX_PDO_MAP],
                    _ => &[object::TX_PDO_MAP, object::STATUS_PDO_MAP],
                };
                let assigned = self.assigned_mut(index);
                let at = usize::from(place) - 1;
                let elsewhere = assigned
                    .iter()
                    .enumerate()
                    .any(|(i, &p)| i != at && p == pdo);
                if !known.contains(&pdo) || elsewhere {
                    return Err(abort::VALUE_RANGE);
                }
                if assigned.len() <= at {
                    assigned.resize(at + 1, 0);
                }
                assigned[at] = pdo;
            }
            (object::SYNC_OUTPUTS | object::SYNC_INPUTS, _) => {
                let inputs = index == object::SYNC_INPUTS;
                let p = &mut self.sync[usize::from(inputs)];
                match sub {
                    sync::MODE if sync::mode_known(inputs, u16_of(value)) => p.mode = u16_of(value),
                    sync::MODE => return Err(abort::VALUE_RANGE),
                    sync::CYCLE_TIME => p.cycle_time = u32_of(value),
                    sync::SYNC0_CYCLE_TIME => p.sync0_cycle = u32_of(value),
                    sync::GET_CYCLE_TIME => self.measure_cycle = u16_of(value),
                    _ => return Err(abort::READ_ONLY),
                }
            }
            _ => return Err(abort::READ_ONLY),
        }
        Ok(())
    }

    fn assigned_mut(&mut self, index: u16) -> &mut Vec<u16> {
        match index {
            object::RX_PDO_ASSIGN => &mut self.rx_assign,
            _ => &mut self.tx_assign,
        }
    }
}

impl ObjectDictionary for Terminal {
    fn entry(&self, index: u16, sub: u8) -> Result<Entry, u32> {
        let mapped = match index {
            object::RX_PDO_MAP => self.outputs_mapped(),
            object::TX_PDO_MAP => self.inputs_mapped(),
            _ => return canif_ethercat::sdo::entry_of(self.object(index), sub),
        };
        Terminal::mapping_entry(&mapped, sub).ok_or(abort::NO_SUBINDEX)
    }

    fn object(&self, index: u16) -> Option<Vec<Entry>> {
        let text = |value: &str| vec![ro(0, value.as_bytes().to_vec()).text()];
        let configurable = self.device.is_none();
        let u16s = |values: &[u16]| {
            let mut out = vec![ro(0, vec![values.len() as u8])];
            for (i, v) in values.iter().enumerate() {
                out.push(ro(i as u8 + 1, v.to_le_bytes().to_vec()));
            }
            out
        };
        Some(match index {
            object::DEVICE_TYPE => vec![ro(0, objects::DEVICE_TYPE.to_le_bytes().to_vec())],
            object::DEVICE_NAME => text(&self.name),
            object::HARDWARE_VERSION => text("00"),
            object::SOFTWARE_VERSION => text(env!("CARGO_PKG_VERSION")),
            object::IDENTITY => vec![
                ro(0, vec![4]),
                ro(1, self.identity.vendor_id.to_le_bytes().to_vec()).named("Vendor ID"),
                ro(2, self.identity.product_code.to_le_bytes().to_vec()).named("Product code"),
                ro(3, self.identity.revision.to_le_bytes().to_vec()).named("Revision"),
                ro(4, self.identity.serial.to_le_bytes().to_vec()).named("Serial number"),
            ],
            // Mailbox out, mailbox in, outputs, inputs (ETG.1000.6 Table 67).
            object::SYNC_MANAGER_TYPES => {
                let mut out = vec![ro(0, vec![4])];
                out.extend((1..=4).map(|n| ro(n, vec![n])));
                out
            }
            object::RX_PDO_ASSIGN => Terminal::assignment(&self.rx_assign, configurable),
            object::TX_PDO_ASSIGN => Terminal::assignment(&self.tx_assign, configurable),
            object::RX_PDO_MAP => Terminal::mapping(&self.outputs_mapped()),
            object::TX_PDO_MAP => Terminal::mapping(&self.inputs_mapped()),
            object::STATUS_PDO_MAP => Terminal::status_mapping(),
            object::SYNC_OUTPUTS => self.sync_parameters(false, configurable),
            object::SYNC_INPUTS => self.sync_parameters(true, configurable),
            object::OUTPUTS_11 | object::OUTPUTS_29 => self.image_object(index, false),
            object::INPUTS_11 | object::INPUTS_29 => self.image_object(index, true),
            object::INTERFACE => {
                let d = &self.draft;
                let rw = |sub, value: u16, name| {
                    Entry::new(sub, value.to_le_bytes().to_vec(), configurable).named(name)
                };
                vec![
                    self.record_sub0(index, configurable),
                    rw(interface::FLAGS, self.flags(), "Flags"),
                    rw(interface::RX_SLOTS, u16::from(d.rx_slots), "Rx slots"),
                    rw(interface::TX_SLOTS, u16::from(d.tx_slots), "Tx slots"),
                    rw(interface::RX_QUEUE, d.rx_fifo_depth as u16, "Rx queue size"),
                    rw(interface::TX_QUEUE, d.tx_fifo_depth as u16, "Tx queue size"),
                ]
            }
            object::FILTERS => self
                .filter_rows()
                .into_iter()
                .map(|e| Entry {
                    writable: configurable,
                    ..e
                })
                .collect(),
            object::MODULAR_DEVICE => u16s(&[0x0010, 1]),
            object::CAN_STATUS => {
                let mut out = u16s(&self.can_status());
                out[usize::from(status::STATE)].name = "CAN state";
                out[usize::from(status::RX_ERROR_COUNTER)].name = "Rx error counter";
                out[usize::from(status::TX_ERROR_COUNTER)].name = "Tx error counter";
                out
            }
            object::INFO_DATA if self.draft.offer.info_data => {
                let words = self.device.as_ref().map_or(vec![0; info::WORDS * 4], |d| {
                    (0..info::WORDS)
                        .flat_map(|i| d.controller_word(i).to_le_bytes())
                        .collect()
                });
                vec![ro(0, vec![1]), ro(1, words)]
            }
            object::BUS_PARAMETERS => {
                let d = &self.draft;
                vec![
                    self.record_sub0(index, configurable),
                    Entry::new(1, d.nominal_timing.to_le_bytes().to_vec(), configurable)
                        .named("Nominal bit timing"),
                    Entry::new(2, d.data_timing.to_le_bytes().to_vec(), configurable)
                        .named("Data bit timing"),
                ]
            }
            _ => return None,
        })
    }

    fn write(&mut self, index: u16, values: &[(u8, Vec<u8>)]) -> Result<(), u32> {
        let measurement = matches!(index, object::SYNC_OUTPUTS | object::SYNC_INPUTS)
            && values.iter().all(|(sub, _)| *sub == sync::GET_CYCLE_TIME);
        if self.device.is_some() && !measurement {
            return Err(abort::DEVICE_STATE);
        }
        match nesting::step(&mut self.nesting, index, values) {
            Step::Direct => self.configure(index, values),
            Step::Keep => Ok(()),
            Step::Open { count_now: true } => self.configure(index, values),
            Step::Open { count_now: false } => Ok(()),
            Step::Close(all) => {
                let closed_as_opened = match (nesting::highest(index), values) {
                    (Some(highest), [(0, value)]) => value.first() == Some(&highest),
                    _ => true,
                };
                match closed_as_opened {
                    true => self.configure(index, &all),
                    false => Err(abort::VALUE_RANGE),
                }
            }
        }
    }

    fn indices(&self) -> Vec<u16> {
        object::ALL
            .into_iter()
            .filter(|&i| i != object::INFO_DATA || self.draft.offer.info_data)
            .collect()
    }

    fn name(&self, index: u16) -> String {
        object::name(index).to_string()
    }
}
