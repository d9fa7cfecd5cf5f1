//! The ESC's memory, datagram by datagram (ETG.1000.4 §5.4, ESC register
//! description): which datagrams address it, what they read and write
//! through registers and FMMUs, and the working counter.

use crate::register::{self, Fmmu, SyncManager};
use crate::wire::{Command, Datagram};

/// Registers and process RAM.
pub const MEMORY: usize = 0x3000;
const FMMUS: u16 = 8;
const SYNC_MANAGERS: u16 = 8;
/// Port 0 with a link and communication; ports 1–3 closed (the end of the line).
const DL_STATUS: u16 = 0x5611;

/// What a datagram touched, for the SubDevice to act on after the frame.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Touched {
    /// Physical byte ranges written and read.
    pub written: Vec<std::ops::Range<usize>>,
    pub read: Vec<std::ops::Range<usize>>,
}

impl Touched {
    pub fn wrote(&self, address: u16) -> bool {
        self.written
            .iter()
            .any(|r| r.contains(&usize::from(address)))
    }

    /// Whether the last byte of `range` was written (a buffer is complete).
    pub fn completed(&self, range: &std::ops::Range<usize>) -> bool {
        !range.is_empty() && self.written.iter().any(|r| r.contains(&(range.end - 1)))
    }

    pub fn read_end_of(&self, range: &std::ops::Range<usize>) -> bool {
        !range.is_empty() && self.read.iter().any(|r| r.contains(&(range.end - 1)))
    }
}

/// The memory of one ESC.
#[derive(Clone)]
pub struct Esc {
    pub memory: Vec<u8>,
    /// The local clock at the frame being processed (ns), and the time latched by a write to 0x0900.
    pub local_time: u64,
}

impl Default for Esc {
    fn default() -> Self {
        Esc::new()
    }
}

impl Esc {
    pub fn new() -> Esc {
        let mut esc = Esc {
            memory: vec![0; MEMORY],
            local_time: 0,
        };
        esc.memory[0] = 0x11; // ESC type
        esc.memory[1] = 0x02; // revision
        esc.memory[usize::from(register::FMMUS_SUPPORTED)] = FMMUS as u8;
        esc.memory[usize::from(register::SYNC_MANAGERS_SUPPORTED)] = SYNC_MANAGERS as u8;
        esc.memory[usize::from(register::RAM_SIZE)] = ((MEMORY - 0x1000) / 1024) as u8;
        esc.memory[usize::from(register::PORT_DESCRIPTOR)] = 0x0F;
        esc.set16(register::FEATURES, 0b1100); // DC, 64-bit system time
        esc.set16(register::DL_STATUS, DL_STATUS);
        // The ESC's reset values: 100 µs units, 100 ms without process data.
        esc.set16(register::WATCHDOG_DIVIDER, 0x09C2);
        esc.set16(register::WATCHDOG_TIME_PROCESS_DATA, 1000);
        esc.set16(register::WATCHDOG_STATUS_PROCESS_DATA, 1);
        esc
    }

    pub fn get16(&self, at: u16) -> u16 {
        let at = usize::from(at);
        u16::from_le_bytes([self.memory[at], self.memory[at + 1]])
    }

    pub fn set16(&mut self, at: u16, value: u16) {
        let at = usize::from(at);
        self.memory[at..at + 2].copy_from_slice(&value.to_le_bytes());
    }

    pub fn get32(&self, at: u16) -> u32 {
        let at = usize::from(at);
        u32::from_le_bytes(self.memory[at..at + 4].try_into().expect("4 bytes"))
    }

    pub fn get64(&self, at: u16) -> u64 {
        let at = usize::from(at);
        u64::from_le_bytes(self.memory[at..at + 8].try_into().expect("8 bytes"))
    }

    pub fn set64(&mut self, at: u16, value: u64) {
        let at = usize::from(at);
        self.memory[at..at + 8].copy_from_slice(&value.to_le_bytes());
    }

    pub fn station_address(&self) -> u16 {
        self.get16(register::STATION_ADDRESS)
    }

    pub fn sync_manager(&self, n: u16) -> SyncManager {
        let at = usize::from(register::SYNC_MANAGER_BASE + n * register::SYNC_MANAGER_LEN);
        SyncManager::parse(&self.memory[at..at + 8])
    }

    pub fn set_sync_manager_status(&mut self, n: u16, status: u8) {
        let at = register::SYNC_MANAGER_BASE + n * register::SYNC_MANAGER_LEN + 5;
        self.memory[usize::from(at)] = status;
    }

    fn fmmus(&self) -> impl Iterator<Item = Fmmu> + '_ {
        (0..FMMUS).map(|n| {
            let at = usize::from(register::FMMU_BASE + n * register::FMMU_LEN);
            Fmmu::parse(&self.memory[at..at + 16])
        })
    }

    /// The process-data watchdog's time in ns; `None` when a master set it to 0 (off).
    pub fn process_data_watchdog(&self) -> Option<u64> {
        let divider = u64::from(self.get16(register::WATCHDOG_DIVIDER)) + 2;
        let time = u64::from(self.get16(register::WATCHDOG_TIME_PROCESS_DATA));
        (time != 0).then_some(time * divider * 40)
    }

    /// The system time the ESC shows: its local time plus the offset the master wrote.
    fn system_time(&self) -> u64 {
        self.system_time_at(self.local_time)
    }

    /// The system time at local time `local`.
    pub fn system_time_at(&self, local: u64) -> u64 {
        local.wrapping_add(self.get64(register::DC_SYSTEM_TIME_OFFSET))
    }

    /// The local time at system time `system`.
    pub fn local_time_at(&self, system: u64) -> u64 {
        system.wrapping_sub(self.get64(register::DC_SYSTEM_TIME_OFFSET))
    }

    /// Whether `range` lies in the buffer of a mailbox the master reads
    /// that the ESC's firmware has not filled: the SyncManager denies the
    /// read, and the working counter does not count it (ESC technology,
    /// section I §2.4: the addressed memory must be accessible, "e.g.,
    /// protected SyncManager buffer"). A master may read the mailbox at
    /// once and poll its status only when told it is empty.
    ///
    /// Only the mailbox SyncManagers (0 and 1, ETG.2000's MBoxOut and
    /// MBoxIn): a real ESC guards a 1-buffer process-data SyncManager the
    /// same way, but the emulated firmware does not mark its inputs full,
    /// so those are read whatever their state (docs/ethercat.md).
    fn denies_read(&self, range: &std::ops::Range<usize>) -> bool {
        range.start >= usize::from(register::PROCESS_RAM)
            && (0..2).map(|n| self.sync_manager(n)).any(|sm| {
                let buffer = sm.range();
                sm.enabled()
                    && sm.mailbox()
                    && !sm.written_by_master()
                    && sm.status & SyncManager::STATUS_MAILBOX_FULL == 0
                    && buffer.start <= range.start
                    && range.end <= buffer.end
            })
    }

    /// Writes what a master may change of `bytes` at `start`: process RAM
    /// whole (a copy, not a look per byte: mailboxes and process data are
    /// most of what a master writes), registers byte by byte.
    fn write(&mut self, start: usize, bytes: &[u8]) {
        if start >= usize::from(register::PROCESS_RAM) {
            self.memory[start..start + bytes.len()].copy_from_slice(bytes);
            return;
        }
        for (i, value) in bytes.iter().enumerate() {
            if Esc::writable(start + i) {
                self.memory[start + i] = *value;
            }
        }
    }

    /// Whether a master may change this byte (read-only registers and the
    /// SyncManagers' status bytes are the ESC's own).
    fn writable(address: usize) -> bool {
        let read_only = [
            0x0000..0x0010,
            0x0110..0x0112,
            0x0130..0x0136,
            0x0440..0x0442,
            0x0900..0x0920,
        ];
        let sm_status = (0x0800..0x0880).contains(&address) && address % 8 == 5;
        !sm_status && !read_only.iter().any(|r| r.contains(&address))
    }

    /// Reads and writes `datagram` at physical `start`; the working-counter increment.
    fn access(&mut self, datagram: &mut Datagram, start: usize, touched: &mut Touched) -> u16 {
        let end = (start + datagram.data.len()).min(MEMORY);
        if start >= MEMORY {
            return 0;
        }
        let range = start..end;
        if range.contains(&usize::from(register::DC_SYSTEM_TIME)) {
            let time = self.system_time();
            self.set64(register::DC_SYSTEM_TIME, time);
        }
        let mut count = 0;
        let command = datagram.command;
        if command.reads() && !self.denies_read(&range) {
            let bytes = &self.memory[range.clone()];
            if matches!(command, Command::Brd | Command::Brw) {
                for (d, m) in datagram.data.iter_mut().zip(bytes) {
                    *d |= m;
                }
            } else {
                datagram.data[..range.len()].copy_from_slice(bytes);
            }
            touched.read.push(range.clone());
            count += 1;
        }
        if command.writes() {
            self.write(start, &datagram.data[..range.len()]);
            if range.contains(&usize::from(register::DC_RECEIVE_TIME_PORT0)) {
                // A write to the port-0 receive time latches the local time
                // the frame passed, there and in the processing unit's
                // register (0x0918 is local time, not system time: a master
                // that computes a new offset from it must not find the old
                // one inside).
                let time = self.local_time as u32;
                let at = usize::from(register::DC_RECEIVE_TIME_PORT0);
                self.memory[at..at + 4].copy_from_slice(&time.to_le_bytes());
                self.set64(register::DC_RECEIVE_TIME_ECAT, self.local_time);
            }
            touched.written.push(range);
            count += if command.reads() { 2 } else { 1 };
        }
        count
    }

    /// Logical addressing: each active FMMU overlapping the datagram moves
    /// its bytes. Writes take the datagram as it arrived and go before the
    /// reads, whatever order the FMMUs are in: an LRW whose read FMMU comes
    /// first must not write the inputs it just read into the outputs. An
    /// FMMU a master points at registers changes only what a master may.
    fn logical(&mut self, datagram: &mut Datagram, touched: &mut Touched) -> u16 {
        let (start, len) = (u64::from(datagram.address), datagram.data.len() as u64);
        let command = datagram.command;
        let mut windows = Vec::new();
        for fmmu in self.fmmus().filter(|f| f.active) {
            let (from, to) = (
                u64::from(fmmu.logical_start),
                u64::from(fmmu.logical_start) + u64::from(fmmu.length),
            );
            let (lo, hi) = (from.max(start), to.min(start + len));
            if lo >= hi {
                continue;
            }
            let in_datagram = (lo - start) as usize..(hi - start) as usize;
            let physical = usize::from(fmmu.physical_start) + (lo - from) as usize;
            let physical = physical..physical + in_datagram.len();
            if physical.end <= MEMORY {
                windows.push((fmmu, in_datagram, physical));
            }
        }
        let mut count = 0;
        if command.writes() {
            for (_, in_datagram, physical) in windows.iter().filter(|w| w.0.writes()) {
                self.write(physical.start, &datagram.data[in_datagram.clone()]);
                touched.written.push(physical.clone());
                count |= 2;
            }
        }
        if command.reads() {
            for (_, in_datagram, physical) in windows.iter().filter(|w| w.0.reads()) {
                datagram.data[in_datagram.clone()].copy_from_slice(&self.memory[physical.clone()]);
                touched.read.push(physical.clone());
                count |= 1;
            }
        }
        // An ESC counts a read and a write once each, however many FMMUs
        // served them: a read 1, a write 1 (LWR) or 2 beside a read (LRW).
        let write = match datagram.command {
            Command::Lrw => 2,
            _ => 1,
        };
        (count & 1) + (count >> 1) * write
    }

    /// A physically addressed datagram at its ESC. Of a read-multiple-write,
    /// the addressed ESC reads; there is no other ESC here to write.
    fn addressed(&mut self, datagram: &mut Datagram, touched: &mut Touched) -> u16 {
        let register = usize::from(datagram.register());
        if matches!(datagram.command, Command::Armw | Command::Frmw) {
            let mut read = datagram.clone();
            read.command = Command::Fprd;
            let count = self.access(&mut read, register, touched);
            datagram.data = read.data;
            count
        } else {
            self.access(datagram, register, touched)
        }
    }

    /// Processes one datagram at this ESC; `touched` gathers what it changed.
    pub fn process(&mut self, datagram: &mut Datagram, touched: &mut Touched) {
        use Command::*;
        let count = match datagram.command {
            Nop => 0,
            Aprd | Apwr | Aprw | Armw => {
                let addressed = datagram.station() == 0;
                datagram.set_station(datagram.station().wrapping_add(1));
                if addressed {
                    self.addressed(datagram, touched)
                } else {
                    0
                }
            }
            Fprd | Fpwr | Fprw | Frmw => {
                if datagram.station() == self.station_address() {
                    self.addressed(datagram, touched)
                } else {
                    0
                }
            }
            Brd | Bwr | Brw => self.access(datagram, usize::from(datagram.register()), touched),
            Lrd | Lwr | Lrw => self.logical(datagram, touched),
        };
        datagram.working_counter = datagram.working_counter.wrapping_add(count);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(esc: &mut Esc, mut datagram: Datagram) -> Datagram {
        esc.process(&mut datagram, &mut Touched::default());
        datagram
    }

    #[test]
    fn a_position_address_reaches_the_first_esc_and_moves_on() {
        let mut esc = Esc::new();
        let answer = run(
            &mut esc,
            Datagram::physical(
                Command::Apwr,
                0,
                register::STATION_ADDRESS,
                vec![0x00, 0x10],
            ),
        );
        assert_eq!((answer.working_counter, answer.station()), (1, 1));
        assert_eq!(esc.station_address(), 0x1000);
        // The next ESC's turn: position 0xFFFF (-1) passes this one by.
        let passed = run(
            &mut esc,
            Datagram::physical(Command::Aprd, 0xFFFF, register::TYPE, vec![0; 2]),
        );
        assert_eq!((passed.working_counter, passed.data[0]), (0, 0));
    }

    #[test]
    fn a_configured_address_reads_only_its_own_esc() {
        let mut esc = Esc::new();
        esc.set16(register::STATION_ADDRESS, 0x1001);
        let mine = run(
            &mut esc,
            Datagram::physical(Command::Fprd, 0x1001, register::DL_STATUS, vec![0; 2]),
        );
        assert_eq!(
            (mine.working_counter, mine.data.as_slice()),
            (1, &[0x11, 0x56][..])
        );
        let other = run(
            &mut esc,
            Datagram::physical(Command::Fprd, 0x1002, register::DL_STATUS, vec![0; 2]),
        );
        assert_eq!(other.working_counter, 0);
    }

    #[test]
    fn read_only_registers_keep_their_value() {
        let mut esc = Esc::new();
        let answer = run(
            &mut esc,
            Datagram::physical(Command::Bwr, 0, register::TYPE, vec![0xAA; 2]),
        );
        assert_eq!(answer.working_counter, 1);
        assert_eq!(esc.memory[0], 0x11);
    }

    #[test]
    fn lrw_reads_inputs_and_writes_outputs_through_the_fmmus_counting_three() {
        let mut esc = Esc::new();
        // FMMU0: logical 0..4 → 0x1100 (write); FMMU1: logical 4..6 → 0x1D00 (read).
        esc.memory[0x600..0x610].copy_from_slice(&fmmu_record(0, 4, 0x1100, 2));
        esc.memory[0x610..0x620].copy_from_slice(&fmmu_record(4, 2, 0x1D00, 1));
        esc.memory[0x1D00..0x1D02].copy_from_slice(&[7, 8]);
        let mut lrw = Datagram::physical(Command::Lrw, 0, 0, vec![1, 2, 3, 4, 0, 0]);
        lrw.address = 0;
        let mut touched = Touched::default();
        esc.process(&mut lrw, &mut touched);
        assert_eq!(lrw.working_counter, 3);
        assert_eq!(lrw.data, [1, 2, 3, 4, 7, 8]);
        assert_eq!(&esc.memory[0x1100..0x1104], &[1, 2, 3, 4]);
        assert!(touched.completed(&(0x1100..0x1104)));
    }

    #[test]
    fn logical_working_counters_follow_the_command() {
        let mut esc = Esc::new();
        // FMMU 0 writes logical 0..4 to 0x1000, FMMU 1 reads logical 4..8 from 0x1100.
        let base = usize::from(crate::register::FMMU_BASE);
        esc.memory[base..base + 16].copy_from_slice(&fmmu_record(0, 4, 0x1000, 2));
        esc.memory[base + 16..base + 32].copy_from_slice(&fmmu_record(4, 4, 0x1100, 1));
        let logical = |command, address, len| Datagram {
            address,
            ..Datagram::physical(command, 0, 0, vec![0; len])
        };
        assert_eq!(
            run(&mut esc, logical(Command::Lwr, 0, 4)).working_counter,
            1
        );
        assert_eq!(
            run(&mut esc, logical(Command::Lrd, 4, 4)).working_counter,
            1
        );
        assert_eq!(
            run(&mut esc, logical(Command::Lrw, 0, 8)).working_counter,
            3
        );
        // An LRD of the output window reads nothing the FMMUs allow.
        assert_eq!(
            run(&mut esc, logical(Command::Lrd, 0, 4)).working_counter,
            0
        );
    }

    #[test]
    fn an_lrw_writes_the_outputs_it_carried_even_when_the_read_fmmu_comes_first() {
        let mut esc = Esc::new();
        // FMMU 0 reads logical 0..4 from 0x1100, FMMU 1 writes the same
        // logical bytes to 0x1000: the outputs are what the master sent.
        let base = usize::from(crate::register::FMMU_BASE);
        esc.memory[base..base + 16].copy_from_slice(&fmmu_record(0, 4, 0x1100, 1));
        esc.memory[base + 16..base + 32].copy_from_slice(&fmmu_record(0, 4, 0x1000, 2));
        esc.memory[0x1100..0x1104].copy_from_slice(&[9, 9, 9, 9]);
        let mut lrw = Datagram::physical(Command::Lrw, 0, 0, vec![1, 2, 3, 4]);
        lrw.address = 0;
        esc.process(&mut lrw, &mut Touched::default());
        assert_eq!(&esc.memory[0x1000..0x1004], &[1, 2, 3, 4]);
        assert_eq!(lrw.data, [9, 9, 9, 9]);
    }

    #[test]
    fn an_fmmu_on_read_only_registers_changes_nothing_there() {
        let mut esc = Esc::new();
        let base = usize::from(crate::register::FMMU_BASE);
        // Logical 0..2 onto the ESC type register.
        esc.memory[base..base + 16].copy_from_slice(&fmmu_record(0, 2, 0x0000, 2));
        let mut lwr = Datagram::physical(Command::Lwr, 0, 0, vec![0xAA, 0xBB]);
        lwr.address = 0;
        esc.process(&mut lwr, &mut Touched::default());
        assert_eq!(&esc.memory[0..2], &[0x11, 0x02]);
    }

    #[test]
    fn the_processing_units_receive_time_is_local_time() {
        let mut esc = Esc::new();
        esc.set64(register::DC_SYSTEM_TIME_OFFSET, 1_000_000);
        esc.local_time = 5_000;
        run(
            &mut esc,
            Datagram::physical(Command::Bwr, 0, register::DC_RECEIVE_TIME_PORT0, vec![0; 4]),
        );
        // A master restarting reads the local time, not the old offset in it.
        assert_eq!(esc.get64(register::DC_RECEIVE_TIME_ECAT), 5_000);
    }

    #[test]
    fn the_watchdog_runs_on_the_reset_values_until_a_master_turns_it_off() {
        let mut esc = Esc::new();
        assert_eq!(esc.process_data_watchdog(), Some(100_000_000));
        run(
            &mut esc,
            Datagram::physical(
                Command::Bwr,
                0,
                register::WATCHDOG_TIME_PROCESS_DATA,
                vec![0; 2],
            ),
        );
        assert_eq!(esc.process_data_watchdog(), None);
    }

    #[test]
    fn an_empty_mailbox_is_not_read_and_not_counted() {
        let mut esc = Esc::new();
        esc.set16(register::STATION_ADDRESS, 0x1001);
        // SM1: the terminal's mailbox at 0x1400, 1024 bytes, read by the master.
        let sm1 = usize::from(register::SYNC_MANAGER_BASE + 8);
        esc.memory[sm1..sm1 + 8].copy_from_slice(&[0x00, 0x14, 0x00, 0x04, 0x02, 0, 1, 0]);
        esc.memory[0x1400] = 0xAB;
        let read = |esc: &mut Esc, len: usize| {
            run(
                esc,
                Datagram::physical(Command::Fprd, 0x1001, 0x1400, vec![0; len]),
            )
        };
        let empty = read(&mut esc, 1024);
        assert_eq!((empty.working_counter, empty.data[0]), (0, 0));
        // Filled by the firmware: read and counted.
        esc.set_sync_manager_status(1, SyncManager::STATUS_MAILBOX_FULL);
        let full = read(&mut esc, 1024);
        assert_eq!((full.working_counter, full.data[0]), (1, 0xAB));
        // A read reaching past the buffer is no read of the mailbox alone.
        esc.set_sync_manager_status(1, 0);
        assert_eq!(read(&mut esc, 1025).working_counter, 1);
    }

    /// An FMMU record: logical start, length, physical start, 1 read / 2 write, active.
    fn fmmu_record(logical: u32, len: u16, physical: u16, kind: u8) -> Vec<u8> {
        let mut record = vec![0u8; 16];
        record[0..4].copy_from_slice(&logical.to_le_bytes());
        record[4..6].copy_from_slice(&len.to_le_bytes());
        record[7] = 7;
        record[8..10].copy_from_slice(&physical.to_le_bytes());
        record[11] = kind;
        record[12] = 1;
        record
    }
}
