//! The ESC registers a MainDevice touches (EtherCAT Slave Controller register
//! description, section II), and the SyncManager and FMMU records.

pub const TYPE: u16 = 0x0000;
pub const FMMUS_SUPPORTED: u16 = 0x0004;
pub const SYNC_MANAGERS_SUPPORTED: u16 = 0x0005;
pub const RAM_SIZE: u16 = 0x0006;
pub const PORT_DESCRIPTOR: u16 = 0x0007;
/// ESC features supported: bit 2 Distributed Clocks, bit 3 64-bit system time.
pub const FEATURES: u16 = 0x0008;
pub const STATION_ADDRESS: u16 = 0x0010;
pub const STATION_ALIAS: u16 = 0x0012;
pub const DL_STATUS: u16 = 0x0110;
pub const AL_CONTROL: u16 = 0x0120;
pub const AL_STATUS: u16 = 0x0130;
pub const AL_STATUS_CODE: u16 = 0x0134;
/// SII: configuration/access (0x0500), control/status (0x0502), address (0x0504), data (0x0508).
pub const SII_ACCESS: u16 = 0x0500;
pub const SII_CONTROL: u16 = 0x0502;
pub const SII_ADDRESS: u16 = 0x0504;
pub const SII_DATA: u16 = 0x0508;
/// Watchdog divider (0x0400, in 40 ns units less 2) and the process-data
/// watchdog time (0x0420, in divider units), and its status (0x0440, bit 0
/// clear once it expired).
pub const WATCHDOG_DIVIDER: u16 = 0x0400;
pub const WATCHDOG_TIME_PROCESS_DATA: u16 = 0x0420;
pub const WATCHDOG_STATUS_PROCESS_DATA: u16 = 0x0440;
pub const FMMU_BASE: u16 = 0x0600;
pub const SYNC_MANAGER_BASE: u16 = 0x0800;
/// Receive time on port 0: a write to it latches the local time.
pub const DC_RECEIVE_TIME_PORT0: u16 = 0x0900;
pub const DC_SYSTEM_TIME: u16 = 0x0910;
pub const DC_RECEIVE_TIME_ECAT: u16 = 0x0918;
pub const DC_SYSTEM_TIME_OFFSET: u16 = 0x0920;
pub const DC_SYNC_ACTIVATION: u16 = 0x0981;
/// Start time of cyclic operation: the first SYNC0 event, in system time.
pub const DC_START_TIME: u16 = 0x0990;
pub const DC_SYNC0_CYCLE: u16 = 0x09A0;
pub const DC_SYNC1_CYCLE: u16 = 0x09A4;
/// Where process RAM starts; below are registers.
pub const PROCESS_RAM: u16 = 0x1000;

pub const FMMU_LEN: u16 = 16;
pub const SYNC_MANAGER_LEN: u16 = 8;

/// The SII control word's bits (0x0502).
pub mod sii {
    /// Read size: 1 = the data register holds 8 bytes.
    pub const READ_8_BYTES: u16 = 1 << 6;
    pub const COMMAND_READ: u16 = 1 << 8;
    pub const COMMAND_WRITE: u16 = 1 << 9;
    pub const COMMAND_RELOAD: u16 = 1 << 10;
    pub const COMMAND_MASK: u16 = 0x0700;
    pub const COMMAND_ERROR: u16 = 1 << 13;
}

/// A SyncManager channel as its 8 register bytes hold it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SyncManager {
    pub start: u16,
    pub length: u16,
    pub control: u8,
    pub status: u8,
    pub activate: u8,
}

impl SyncManager {
    pub const MODE_MAILBOX: u8 = 0b10;
    pub const WRITTEN_BY_MASTER: u8 = 0b0100;
    pub const STATUS_MAILBOX_FULL: u8 = 1 << 3;

    pub fn parse(bytes: &[u8]) -> SyncManager {
        SyncManager {
            start: u16::from_le_bytes([bytes[0], bytes[1]]),
            length: u16::from_le_bytes([bytes[2], bytes[3]]),
            control: bytes[4],
            status: bytes[5],
            activate: bytes[6],
        }
    }

    pub fn enabled(&self) -> bool {
        self.activate & 1 == 1 && self.length > 0
    }

    pub fn mailbox(&self) -> bool {
        self.control & 0b11 == Self::MODE_MAILBOX
    }

    /// Written by the master (outputs, the master's mailbox).
    pub fn written_by_master(&self) -> bool {
        self.control & 0b1100 == Self::WRITTEN_BY_MASTER
    }

    pub fn range(&self) -> std::ops::Range<usize> {
        usize::from(self.start)..usize::from(self.start) + usize::from(self.length)
    }
}

/// An FMMU: a byte-aligned window from logical to physical memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Fmmu {
    pub logical_start: u32,
    pub length: u16,
    pub physical_start: u16,
    /// Bit 0: read (inputs), bit 1: write (outputs).
    pub kind: u8,
    pub active: bool,
}

impl Fmmu {
    pub fn parse(bytes: &[u8]) -> Fmmu {
        Fmmu {
            logical_start: u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
            length: u16::from_le_bytes([bytes[4], bytes[5]]),
            physical_start: u16::from_le_bytes([bytes[8], bytes[9]]),
            kind: bytes[11],
            active: bytes[12] & 1 == 1,
        }
    }

    pub fn reads(&self) -> bool {
        self.kind & 1 == 1
    }

    pub fn writes(&self) -> bool {
        self.kind & 2 == 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sync_manager_record_reads_as_the_register_description_lays_it_out() {
        // SM0 of a typical terminal: 0x1000, 128 bytes, mailbox written by the master, enabled.
        let sm = SyncManager::parse(&[0x00, 0x10, 0x80, 0x00, 0x26, 0x00, 0x01, 0x00]);
        assert_eq!((sm.start, sm.length), (0x1000, 128));
        assert!(sm.mailbox() && sm.written_by_master() && sm.enabled());
        assert_eq!(sm.range(), 0x1000..0x1080);
    }

    #[test]
    fn an_fmmu_record_reads_its_window() {
        let fmmu = Fmmu::parse(&[
            0x00, 0x00, 0x01, 0x00, 0x06, 0x00, 0x00, 0x07, 0x00, 0x11, 0x00, 0x02, 0x01, 0, 0, 0,
        ]);
        assert_eq!(fmmu.logical_start, 0x0001_0000);
        assert_eq!((fmmu.length, fmmu.physical_start), (6, 0x1100));
        assert!(fmmu.writes() && !fmmu.reads() && fmmu.active);
    }
}
