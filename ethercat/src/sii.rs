//! The SII EEPROM image (ETG.1000.6 §5.4, ETG.2010): the fixed words with the
//! identity and the mailbox, then categories: strings, general, FMMU, SyncM.

/// Who the SubDevice says it is (SII words 0x0008–0x000F, and object 0x1018).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    pub vendor_id: u32,
    pub product_code: u32,
    pub revision: u32,
    pub serial: u32,
    pub name: String,
}

/// Where the SyncManagers sit; the process-data lengths are set by the master.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    pub mailbox_out: u16,
    pub mailbox_in: u16,
    pub mailbox_size: u16,
    pub outputs: u16,
    pub inputs: u16,
    /// Process data in 1-buffer (mailbox) mode, else in 3-buffer mode.
    pub one_buffer: bool,
}

impl Layout {
    /// The real EL6751's (its public object and register description):
    /// mailboxes of 1024 bytes at 0x1000 and 0x1400, process data at 0x1800
    /// and 0x2400 in 1-buffer mode, as the EL6751 runs its buffered queues
    /// (000 §5.1.2: "Die EL6751 arbeitet im 1-Buffer-Betrieb").
    pub const EL6751: Layout = Layout {
        mailbox_out: 0x1000,
        mailbox_in: 0x1400,
        mailbox_size: 1024,
        outputs: 0x1800,
        inputs: 0x2400,
        one_buffer: true,
    };

    /// A second layout, for proving that no master assumes the first:
    /// 128-byte mailboxes, then outputs and inputs in 3-buffer mode.
    pub const COMPACT: Layout = Layout {
        mailbox_out: 0x1000,
        mailbox_in: 0x1080,
        mailbox_size: 128,
        outputs: 0x1100,
        inputs: 0x1D00,
        one_buffer: false,
    };

    /// SM0..SM3 as (start, length, control, type) of the SyncM category.
    /// Control: mode (bits 0–1, 10 = 1-buffer), direction (bits 2–3),
    /// the PDI event (bit 5) and, for the outputs, the watchdog (bit 6).
    pub fn sync_managers(&self) -> [(u16, u16, u8, u8); 4] {
        let mode = if self.one_buffer { 0b10 } else { 0b00 };
        [
            (self.mailbox_out, self.mailbox_size, 0x26, 1),
            (self.mailbox_in, self.mailbox_size, 0x22, 2),
            (self.outputs, 0, 0x64 | mode, 3),
            (self.inputs, 0, 0x20 | mode, 4),
        ]
    }
}

mod category {
    pub(super) const STRINGS: u16 = 10;
    pub(super) const GENERAL: u16 = 30;
    pub(super) const FMMU: u16 = 40;
    pub(super) const SYNC_MANAGER: u16 = 41;
    pub(super) const END: u16 = 0xFFFF;
}

/// CoE details of the general category: SDO, SDO information, PDO assignment, complete access.
const COE_DETAILS: u8 = 0b10_0111;
/// Mailbox protocols word: CoE.
const MAILBOX_COE: u16 = 0x0004;

/// The CRC-8 of the ESC configuration area (polynomial 0x07, start 0xFF).
fn crc8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0xFF, |mut crc, byte| {
        crc ^= byte;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
        }
        crc
    })
}

fn push16(out: &mut Vec<u8>, value: u16) {
    out.extend_from_slice(&value.to_le_bytes());
}

fn push_category(out: &mut Vec<u8>, kind: u16, mut data: Vec<u8>) {
    if data.len() % 2 == 1 {
        data.push(0);
    }
    push16(out, kind);
    push16(out, (data.len() / 2) as u16);
    out.extend_from_slice(&data);
}

/// The whole EEPROM, as bytes (two per word).
pub fn image(identity: &Identity, layout: &Layout) -> Vec<u8> {
    let mut out = vec![0u8; 0x80];
    // The ESC configuration area (PDI settings) means nothing to an emulated
    // ESC: zeros, sealed with their checksum in word 7 as a master checks it.
    out[14] = crc8(&out[0..14]);
    let words = [
        (0x08, identity.vendor_id),
        (0x0A, identity.product_code),
        (0x0C, identity.revision),
        (0x0E, identity.serial),
    ];
    for (word, value) in words {
        out[word * 2..word * 2 + 4].copy_from_slice(&value.to_le_bytes());
    }
    for (word, value) in [
        // Bootstrap mailbox = standard mailbox.
        (0x14, layout.mailbox_out),
        (0x15, layout.mailbox_size),
        (0x16, layout.mailbox_in),
        (0x17, layout.mailbox_size),
        (0x18, layout.mailbox_out),
        (0x19, layout.mailbox_size),
        (0x1A, layout.mailbox_in),
        (0x1B, layout.mailbox_size),
        (0x1C, MAILBOX_COE),
        // EEPROM size in KiBit - 1, version 1.
        (0x3E, 15),
        (0x3F, 1),
    ] {
        out[word * 2..word * 2 + 2].copy_from_slice(&value.to_le_bytes());
    }

    let mut strings = vec![1u8, identity.name.len() as u8];
    strings.extend_from_slice(identity.name.as_bytes());
    push_category(&mut out, category::STRINGS, strings);

    let mut general = vec![0u8; 32];
    general[2] = 1; // order number: string 1 (what masters show as the name)
    general[3] = 1; // name: string 1
    general[5] = COE_DETAILS;
    push_category(&mut out, category::GENERAL, general);

    // FMMU0 outputs, FMMU1 inputs, FMMU2 mailbox status.
    push_category(&mut out, category::FMMU, vec![1, 2, 3, 0xFF]);

    let mut sync = Vec::new();
    for (start, length, control, kind) in layout.sync_managers() {
        push16(&mut sync, start);
        push16(&mut sync, length);
        sync.extend_from_slice(&[control, 0, 1, kind]);
    }
    push_category(&mut out, category::SYNC_MANAGER, sync);
    push16(&mut out, category::END);
    push16(&mut out, 0);
    out.resize(2048, 0xFF);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn el6751() -> Identity {
        Identity {
            vendor_id: 2,
            product_code: 0x1A5F_3052,
            revision: 0x0011_0000,
            serial: 7,
            name: "EL6751".into(),
        }
    }

    fn word(image: &[u8], w: usize) -> u16 {
        u16::from_le_bytes([image[w * 2], image[w * 2 + 1]])
    }

    #[test]
    fn the_configuration_area_is_sealed_with_its_crc() {
        // Check values of CRC-8, polynomial 0x07, start 0xFF, not reflected,
        // computed apart by a bit-by-bit script: a changed polynomial or start shows.
        assert_eq!(crc8(b"123456789"), 0xFB);
        assert_eq!(crc8(&[0; 14]), 0x30);
        assert_eq!(image(&el6751(), &Layout::COMPACT)[14], 0x30);
    }

    #[test]
    fn identity_and_mailbox_sit_in_their_words() {
        let image = image(&el6751(), &Layout::COMPACT);
        assert_eq!(word(&image, 0x08), 2);
        assert_eq!((word(&image, 0x0A), word(&image, 0x0B)), (0x3052, 0x1A5F));
        assert_eq!((word(&image, 0x18), word(&image, 0x19)), (0x1000, 128));
        assert_eq!(word(&image, 0x1C), MAILBOX_COE);
    }

    #[test]
    fn categories_follow_one_another_to_the_end_marker() {
        let image = image(&el6751(), &Layout::COMPACT);
        let mut at = 0x40;
        let mut kinds = Vec::new();
        loop {
            let kind = word(&image, at);
            if kind == category::END {
                break;
            }
            kinds.push(kind);
            at += 2 + usize::from(word(&image, at + 1));
        }
        assert_eq!(kinds, [10, 30, 40, 41]);
    }
}
