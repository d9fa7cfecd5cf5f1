//! A software EL6751: the device side of the CAN interface, firmware style.
//!
//! * [`SoftDevice::sync_manager_event`] — the CAN interface cycle, run when the
//!   process-data telegram arrives (003).
//! * [`SoftDevice::rx_interrupt`] — the controller received a frame.
//! * [`SoftDevice::controller_idle`] — the controller may start the next frame.
//! * [`SoftDevice::tx_done_interrupt`] — the frame it started is on the bus.
//!
//! Written from the manual (000/001 §6, 003) independently of `canif-model`.

#![forbid(unsafe_code)]

mod fault;
pub mod field;
mod frame;
mod freedom;
mod geometry;
mod settings;

pub use fault::Fault;
pub use frame::CanFrame;
pub use freedom::Freedom;
pub use settings::{FilterRule, Format, Offer, Queue, Settings, SettingsError};

use std::collections::VecDeque;

use field::{header, info};
use geometry::{get16, get32, put16, put32, MsgGeometry};

#[derive(Clone, Copy, Debug)]
struct TxJob {
    frame: CanFrame,
    tn: u16,
    release_at: u64,
    first_in_batch: bool,
}

#[derive(Clone, Copy, Debug)]
struct RxJob {
    frame: CanFrame,
    stamp: u64,
}

/// Why the cycle task could not run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImageSizeError {
    pub expected: usize,
    pub got: usize,
}

impl std::fmt::Display for ImageSizeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "output image of {} bytes, expected {}",
            self.got, self.expected
        )
    }
}

impl std::error::Error for ImageSizeError {}

/// The soft device.
#[derive(Debug, Clone)]
pub struct SoftDevice {
    settings: Settings,
    faults: Vec<Fault>,
    choices: Vec<Freedom>,
    tx_geo: MsgGeometry,
    /// The structure Tx slots are read with: `tx_geo` but for a fault.
    tx_read: MsgGeometry,
    rx_geo: MsgGeometry,
    rx_base: usize,
    info_base: usize,
    input: Vec<u8>,
    send_fifo: VecDeque<TxJob>,
    on_wire: Option<TxJob>,
    last_tn: u16,
    recv_fifo: VecDeque<RxJob>,
    deferred_tx: Option<u16>,
    controller: [u32; 16],
}

impl SoftDevice {
    /// Starts the device with `settings`; refuses what the device does not offer.
    pub fn new(settings: Settings) -> Result<Self, SettingsError> {
        Self::with_faults(settings, &[])
    }

    /// [`Self::new`] with `faults` switched on from the start, those of the
    /// configuration's check among them.
    pub fn with_faults(settings: Settings, faults: &[Fault]) -> Result<Self, SettingsError> {
        settings.check(faults)?;
        let has_tn = settings.transaction_number || settings.format == Format::Fd;
        let tx_geo = MsgGeometry::tx(settings.format, has_tn);
        let skips_tn = faults.contains(&Fault::TxReadWithoutTransactionNumber);
        let tx_read = MsgGeometry::tx(settings.format, has_tn && !skips_tn);
        let rx_geo = MsgGeometry::rx(
            settings.format,
            settings.time_stamp || settings.format == Format::Fd,
        );
        let rx_base = if has_tn {
            header::MESSAGES_AFTER_TRANSACTION_NUMBER
        } else {
            header::MESSAGES
        };
        let info_base = rx_base + usize::from(settings.rx_slots) * rx_geo.size;
        let input_len = info_base
            + if settings.offer.info_data {
                4 * info::WORDS
            } else {
                0
            };
        let mut controller = [0u32; info::WORDS];
        if !faults.contains(&Fault::InfoDataStartsZero) {
            controller[info::STATUS] = info::NODE_ACTIVE;
            controller[info::CORE_RUNNING] = 1;
        }
        Ok(SoftDevice {
            tx_geo,
            tx_read,
            rx_geo,
            rx_base,
            info_base,
            input: vec![0; input_len],
            send_fifo: VecDeque::new(),
            on_wire: None,
            last_tn: 0,
            recv_fifo: VecDeque::new(),
            deferred_tx: None,
            controller,
            faults: faults.to_vec(),
            choices: Vec::new(),
            settings,
        })
    }

    fn has(&self, fault: Fault) -> bool {
        self.faults.contains(&fault)
    }

    /// Takes one of the freedoms the documents leave (the device still conforms).
    pub fn choose(&mut self, choice: Freedom) {
        if !self.choices.contains(&choice) {
            self.choices.push(choice);
        }
    }

    fn chose(&self, choice: Freedom) -> bool {
        self.choices.contains(&choice)
    }

    fn output_len(&self) -> usize {
        6 + usize::from(self.settings.tx_slots) * self.tx_geo.size
    }

    fn bump(&self, counter: u16) -> u16 {
        if self.has(Fault::CounterDoesNotWrap) {
            counter.saturating_add(1)
        } else {
            counter.wrapping_add(1)
        }
    }

    /// The CAN interface cycle (003): Tx, then Rx, then transaction number, then status.
    pub fn sync_manager_event(&mut self, output: &[u8], now: u64) -> Result<&[u8], ImageSizeError> {
        if output.len() != self.output_len() {
            return Err(ImageSizeError {
                expected: self.output_len(),
                got: output.len(),
            });
        }
        self.transmit_side(output, now);
        self.receive_side(get16(output, header::RX_COUNTER));
        let tn = self.last_tn;
        if self.rx_base == header::MESSAGES_AFTER_TRANSACTION_NUMBER {
            put16(&mut self.input, header::TRANSACTION_NUMBER, tn);
        }
        if self.settings.offer.info_data {
            self.controller[info::NOMINAL_TIMING] = self.settings.nominal_timing;
            self.controller[info::DATA_TIMING] = self.settings.data_timing;
            self.controller[info::TX_ERROR_FRAMES] = 0;
            self.controller[info::TX_FIFO_LEVEL] =
                (self.send_fifo.len() + usize::from(self.on_wire.is_some())) as u32;
            self.controller[info::RX_FIFO_LEVEL] = if self.has(Fault::ReceiveFifoNotReported) {
                0
            } else {
                self.recv_fifo.len() as u32
            };
            let base = self.info_base
                + if self.has(Fault::InfoDataTwoBytesLate) {
                    2
                } else {
                    0
                };
            for (i, word) in self.controller.iter().enumerate() {
                let at = base + 4 * i;
                if at + 4 <= self.input.len() {
                    put32(&mut self.input, at, *word);
                }
            }
        }
        Ok(&self.input)
    }

    fn transmit_side(&mut self, output: &[u8], now: u64) {
        if self.deferred_tx.take().is_some() {
            // Fault AckBeforeAccept: the batch acknowledged last cycle is only read now.
            self.copy_batch(output, now);
        }
        let requested = get16(output, header::TX_COUNTER);
        let acknowledged = get16(&self.input, header::TX_COUNTER);
        if requested == acknowledged {
            return;
        }
        let asked = usize::from(get16(output, header::NO_OF_MESSAGES));
        if asked == 0 && self.has(Fault::ZeroBatchNotAcknowledged) {
            return;
        }
        let slots = usize::from(self.settings.tx_slots);
        let mut count = if self.has(Fault::TrustsNoOfTxMessages) {
            asked.min(64)
        } else if asked > slots && self.chose(Freedom::RefusesOversizeBatch) {
            0
        } else {
            asked.min(slots)
        };
        if self.has(Fault::BatchCappedAt31) {
            count = count.min(31);
        }
        if self.has(Fault::SendsOneMoreThanAsked) {
            count = (count + 1).min(usize::from(self.settings.tx_slots));
        }
        // HS-TX-012, a choice: does the frame on the wire still count?
        let busy = self.queue_places_taken();
        if self.has(Fault::AckBeforeAccept) {
            put16(&mut self.input, header::TX_COUNTER, requested);
            self.deferred_tx = Some(requested);
            return;
        }
        if busy > 0 && busy + count > self.settings.tx_fifo_depth {
            if !self.has(Fault::DropsWhatDoesNotFit) {
                return; // no room: acknowledge later
            }
            count = self.settings.tx_fifo_depth.saturating_sub(busy);
        }
        self.copy_batch_n(output, now, count);
        let acknowledge = if self.has(Fault::AcknowledgesByIncrement) {
            acknowledged.wrapping_add(1)
        } else {
            requested
        };
        put16(&mut self.input, header::TX_COUNTER, acknowledge);
    }

    /// The message in slot `i` (beyond the slots: a device that trusts
    /// NoOfTxMessages starts over at slot 0).
    fn tx_slot<'a>(&self, output: &'a [u8], i: usize) -> &'a [u8] {
        let at = 6 + (i % usize::from(self.settings.tx_slots)) * self.tx_read.size;
        &output[at..at + self.tx_read.size]
    }

    fn copy_batch(&mut self, output: &[u8], now: u64) {
        let count = usize::from(get16(output, header::NO_OF_MESSAGES))
            .min(usize::from(self.settings.tx_slots));
        self.copy_batch_n(output, now, count);
    }

    fn copy_batch_n(&mut self, output: &[u8], now: u64, count: usize) {
        let late = if self.has(Fault::Sync1Late) {
            2_000
        } else if self.chose(Freedom::Sync1Jitter) {
            400
        } else {
            0
        };
        let release_at = self
            .settings
            .dc_sync1_shift
            .map_or(0, |shift| now + shift + late);
        let mut batch: Vec<TxJob> = (0..count)
            .filter_map(|i| {
                let slot = self.tx_slot(output, i);
                let tn = self.tx_read.tn.map_or(0, |o| get16(slot, o));
                Some(TxJob {
                    frame: self.decode_tx(slot)?,
                    tn,
                    release_at: 0,
                    first_in_batch: false,
                })
            })
            .collect();
        if let Some(first) = batch.first_mut() {
            first.release_at = release_at;
            first.first_in_batch = true;
        }
        if self.has(Fault::SendsBatchReversed) {
            batch.reverse();
        }
        self.send_fifo.extend(batch);
    }

    /// The frame a Tx slot asks for; `None` when the device drops it (a
    /// length out of range, with [`Freedom::DropsMessageWithBadLength`]).
    fn decode_tx(&self, slot: &[u8]) -> Option<CanFrame> {
        let g = self.tx_read;
        let mut frame = CanFrame::default();
        if g.cob_wide {
            let cob = get32(slot, g.cob);
            frame.extended = cob & 0x8000_0000 != 0
                || (self.has(Fault::StandardIdKeepsHighBits) && cob & 0x1FFF_F800 != 0);
            frame.remote = cob & 0x4000_0000 != 0;
            frame.id = if frame.extended {
                cob & 0x1FFF_FFFF
            } else {
                cob & 0x7FF
            };
        } else {
            let word = get16(slot, g.cob);
            frame.id = u32::from(word >> 5);
            let rtr_bit = if self.has(Fault::RtrBitMisplaced) {
                3
            } else {
                4
            };
            frame.remote = word & (1 << rtr_bit) != 0;
            frame.len = (word & 0xF) as usize;
        }
        if let Some(o) = g.len16 {
            frame.len = usize::from(get16(slot, o));
        }
        if let Some(o) = g.len8 {
            frame.len = usize::from(slot[o]);
        }
        let flags = g.flags.map_or(0, |o| slot[o]);
        let fd_mask = if self.has(Fault::BrsWithoutEdlSendsFd) {
            3
        } else {
            1
        };
        frame.fd = flags & fd_mask != 0;
        let cap = if frame.fd { 64 } else { 8 };
        if frame.len > cap && self.chose(Freedom::DropsMessageWithBadLength) {
            return None;
        }
        if frame.fd {
            frame.brs = flags & 2 != 0;
            frame.esi = flags & 4 != 0;
            frame.remote &= self.has(Fault::FdKeepsRemote);
            let wanted = frame.len.min(64);
            let wire = if self.has(Fault::FdLengthRoundsDown) {
                frame::FD_SIZES
                    .iter()
                    .rev()
                    .copied()
                    .find(|&s| s <= wanted)
                    .unwrap_or(0)
            } else if self.has(Fault::FdLength32As36) && (25..=32).contains(&wanted) {
                36
            } else {
                frame::FD_SIZES
                    .iter()
                    .copied()
                    .find(|&s| s >= wanted)
                    .unwrap_or(64)
            };
            let pad = if self.has(Fault::FdPaddingFf) {
                0xFF
            } else {
                0x00
            };
            for i in 0..wire {
                frame.data[i] = if i < wanted { slot[g.data + i] } else { pad };
            }
            frame.len = wire;
        } else {
            let most = if self.has(Fault::ClassicLengthUnbounded) {
                15
            } else {
                8
            };
            frame.len = frame.len.min(most);
            if !frame.remote {
                let n = frame.len.min(slot.len() - g.data);
                frame.data[..n].copy_from_slice(&slot[g.data..g.data + n]);
            }
        }
        Some(frame)
    }

    fn receive_side(&mut self, plc_rx_counter: u16) {
        let fast = self.settings.queue == Queue::Fast;
        let free = plc_rx_counter == get16(&self.input, header::RX_COUNTER);
        let may_fill = if fast {
            !self.has(Fault::FastQueueWaitsForAck) || free
        } else {
            free || self.has(Fault::OverwritesUnacknowledgedRx)
        };
        if !may_fill {
            return;
        }
        if self.recv_fifo.is_empty() {
            if !fast && self.chose(Freedom::ClearsRxCountWhenIdle) {
                put16(&mut self.input, header::NO_OF_MESSAGES, 0);
            }
            if self.has(Fault::RxCounterCountsEmptyCycles) {
                put16(&mut self.input, header::NO_OF_MESSAGES, 0);
                let next = self.bump(get16(&self.input, header::RX_COUNTER));
                put16(&mut self.input, header::RX_COUNTER, next);
            }
            return;
        }
        let mut count = self
            .recv_fifo
            .len()
            .min(usize::from(self.settings.rx_slots));
        if self.has(Fault::RxCountCappedAt31) {
            count = count.min(31);
        }
        for i in 0..usize::from(self.settings.rx_slots) {
            let at = self.rx_start() + i * self.rx_geo.size;
            let size = self.rx_geo.size.min(self.input.len().saturating_sub(at));
            let job = if i < count {
                self.recv_fifo.pop_front()
            } else {
                None
            };
            let slot_bytes = match job {
                Some(job) => self.encode_rx(&job),
                None if self.chose(Freedom::KeepsStaleRxSlots) => continue,
                None => vec![0; size],
            };
            self.input[at..at + size].copy_from_slice(&slot_bytes[..size]);
        }
        if fast {
            self.recv_fifo.clear();
        }
        put16(&mut self.input, header::NO_OF_MESSAGES, count as u16);
        let next = self.bump(get16(&self.input, header::RX_COUNTER));
        put16(&mut self.input, header::RX_COUNTER, next);
    }

    /// Where the Rx messages start in the input image.
    fn rx_start(&self) -> usize {
        if self.has(Fault::RxMessagesAfterReservedWord) {
            header::MESSAGES_AFTER_TRANSACTION_NUMBER
        } else {
            self.rx_base
        }
    }

    fn encode_rx(&self, job: &RxJob) -> Vec<u8> {
        let g = self.rx_geo;
        let f = &job.frame;
        let mut slot = vec![0u8; g.size];
        if g.cob_wide {
            let mut cob = f.id;
            if f.extended && !self.has(Fault::ExtendedFlagMissing) {
                cob |= 0x8000_0000;
            }
            if f.remote {
                cob |= 0x4000_0000;
            }
            put32(&mut slot, g.cob, cob);
        } else {
            let word =
                ((f.id as u16) << 5) | if f.remote { 1 << 4 } else { 0 } | (f.len as u16 & 0xF);
            if self.has(Fault::CobIdWordBigEndian) {
                slot[g.cob..g.cob + 2].copy_from_slice(&word.to_be_bytes());
            } else {
                put16(&mut slot, g.cob, word);
            }
        }
        if let Some(o) = g.len16 {
            put16(&mut slot, o, f.len as u16);
        }
        if let Some(o) = g.len8 {
            slot[o] = match frame::FD_SIZES.iter().position(|&size| size == f.len) {
                Some(dlc) if f.fd && self.has(Fault::FdLengthAsDlc) => dlc as u8,
                _ => f.len as u8,
            };
        }
        if let Some(o) = g.flags {
            let (brs, esi) = if self.has(Fault::BrsEsiSwapped) {
                (f.esi, f.brs)
            } else {
                (f.brs, f.esi)
            };
            slot[o] = u8::from(f.fd) | (u8::from(brs) << 1) | (u8::from(esi) << 2);
        }
        if !f.remote {
            let n = f.len.min(g.data_cap);
            slot[g.data..g.data + n].copy_from_slice(&f.data[..n]);
        }
        if let Some(o) = g.ts {
            let stamp = if self.has(Fault::TimeStampInMicroseconds) {
                job.stamp / 1_000
            } else {
                job.stamp
            };
            slot[o..o + 8].copy_from_slice(&stamp.to_le_bytes());
        }
        slot
    }

    /// Receive interrupt: a frame ended at `stamp` (device clock, ns).
    /// Returns whether it was stored.
    pub fn rx_interrupt(&mut self, frame: CanFrame, stamp: u64) -> bool {
        let fits = match self.settings.format {
            Format::Std11 => !frame.extended && !frame.fd,
            Format::Ext29 => !frame.fd,
            Format::Fd => true,
        };
        if !fits
            || !settings::filter_passes(&self.settings.filters, frame.id, |fault| self.has(fault))
        {
            return false;
        }
        let room = if self.settings.queue == Queue::Fast {
            usize::from(self.settings.rx_slots)
        } else if self.has(Fault::RxQueueOneShort) {
            self.settings.rx_fifo_depth - 1
        } else {
            self.settings.rx_fifo_depth
        };
        if self.recv_fifo.len() >= room {
            if self.has(Fault::HeadDropWhenFull) && self.settings.queue != Queue::Fast {
                self.recv_fifo.pop_front();
            } else {
                return false;
            }
        }
        self.recv_fifo.push_back(RxJob { frame, stamp });
        true
    }

    /// The controller is idle at `now`: the next frame to put on the bus, if any.
    pub fn controller_idle(&mut self, now: u64) -> Option<CanFrame> {
        if self.on_wire.is_some() {
            return None;
        }
        let job = *self.send_fifo.front()?;
        if job.release_at > now {
            return None;
        }
        self.send_fifo.pop_front();
        self.on_wire = Some(job);
        if self.has(Fault::TransactionNumberOnHandover) {
            self.last_tn = job.tn;
        }
        Some(job.frame)
    }

    /// When the first frame of a batch may go (Distributed Clocks, SYNC1).
    pub fn next_release(&self) -> Option<u64> {
        match (&self.on_wire, self.send_fifo.front()) {
            (None, Some(job)) if job.release_at > 0 => Some(job.release_at),
            _ => None,
        }
    }

    /// The frames waiting to be sent, in order (not the one on the wire), each
    /// with the time it is released at (0: at once).
    pub fn waiting(&self) -> impl Iterator<Item = (&CanFrame, u64)> {
        self.send_fifo
            .iter()
            .map(|job| (&job.frame, job.release_at))
    }

    /// Transmit-done interrupt: the frame on the wire was acknowledged.
    pub fn tx_done_interrupt(&mut self) {
        if let Some(job) = self.on_wire.take() {
            let keep_first = self.has(Fault::TransactionNumberOfFirstFrame) && !job.first_in_batch;
            if !keep_first && !self.has(Fault::TransactionNumberOnHandover) {
                self.last_tn = job.tn;
            }
        }
    }

    /// Controller status words for InfoData (0: status bits, 3: transceiver delay,
    /// 7-10, 12-14: error counters, 11: core running).
    pub fn set_controller_word(&mut self, index: usize, value: u32) {
        if let Some(word) = self.controller.get_mut(index) {
            *word = value;
        }
    }

    /// The places of the send queue a batch must find room beside: the
    /// frames waiting, and the one on the wire where the device counts it
    /// (003 leaves it open; by default it has left the queue).
    fn queue_places_taken(&self) -> usize {
        let on_wire = self.chose(Freedom::CountsFrameOnWire) && self.on_wire.is_some();
        self.send_fifo.len() + usize::from(on_wire)
    }
}

// Last in the file: the mutation exclusions name lines above.
pub mod ethercat;
