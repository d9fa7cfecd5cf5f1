//! EtherCAT frames on Ethernet II (EtherType 0x88A4, ETG.1000.4 §5): an
//! EtherCAT header, then datagrams, each with its working counter.

use std::fmt;

/// The EtherType of EtherCAT frames.
pub const ETHERTYPE: u16 = 0x88A4;

/// Byte ranges of the frame, written once.
mod field {
    use std::ops::Range;
    pub(super) const DESTINATION: Range<usize> = 0..6;
    pub(super) const SOURCE: Range<usize> = 6..12;
    pub(super) const ETHERTYPE: Range<usize> = 12..14;
    /// Length (11 bits) and type (4 bits, 1 = datagrams).
    pub(super) const HEADER: Range<usize> = 14..16;
    pub(super) const DATAGRAMS: usize = 16;

    /// Within a datagram.
    pub(super) const COMMAND: usize = 0;
    pub(super) const INDEX: usize = 1;
    pub(super) const ADDRESS: Range<usize> = 2..6;
    /// Length (11 bits), circulating (bit 14), more follows (bit 15).
    pub(super) const LENGTH: Range<usize> = 6..8;
    pub(super) const IRQ: Range<usize> = 8..10;
    pub(super) const DATA: usize = 10;
    /// Header and working counter around the data.
    pub(super) const OVERHEAD: usize = 12;
}

const LENGTH_MASK: u16 = 0x07FF;
const MORE_FOLLOWS: u16 = 0x8000;
const TYPE_DATAGRAMS: u16 = 1;

/// The datagram commands (ETG.1000.4 Table 14).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    Nop,
    Aprd,
    Apwr,
    Aprw,
    Fprd,
    Fpwr,
    Fprw,
    Brd,
    Bwr,
    Brw,
    Lrd,
    Lwr,
    Lrw,
    Armw,
    Frmw,
}

impl Command {
    pub fn from_code(code: u8) -> Option<Command> {
        use Command::*;
        Some(match code {
            0 => Nop,
            1 => Aprd,
            2 => Apwr,
            3 => Aprw,
            4 => Fprd,
            5 => Fpwr,
            6 => Fprw,
            7 => Brd,
            8 => Bwr,
            9 => Brw,
            10 => Lrd,
            11 => Lwr,
            12 => Lrw,
            13 => Armw,
            14 => Frmw,
            _ => return None,
        })
    }

    pub fn code(self) -> u8 {
        self as u8
    }

    /// Whether the command reads the addressed memory into the datagram.
    pub fn reads(self) -> bool {
        use Command::*;
        matches!(
            self,
            Aprd | Aprw | Fprd | Fprw | Brd | Brw | Lrd | Lrw | Armw | Frmw
        )
    }

    /// Whether the command writes the datagram into the addressed memory.
    pub fn writes(self) -> bool {
        use Command::*;
        matches!(
            self,
            Apwr | Aprw | Fpwr | Fprw | Bwr | Brw | Lwr | Lrw | Armw | Frmw
        )
    }
}

/// Why bytes are no EtherCAT frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum WireError {
    /// Shorter than the part being read.
    Truncated { needed: usize, have: usize },
    /// Another EtherType.
    NotEthercat(u16),
    /// An EtherCAT header of another type than datagrams.
    HeaderType(u16),
    /// A datagram with a command code ETG.1000.4 does not define.
    UnknownCommand(u8),
    /// The header's length disagrees with the datagrams.
    Length { header: usize, datagrams: usize },
}

impl fmt::Display for WireError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WireError::Truncated { needed, have } => {
                write!(f, "truncated frame: {needed} bytes needed, {have} present")
            }
            WireError::NotEthercat(t) => write!(f, "EtherType {t:#06x}, not EtherCAT (0x88a4)"),
            WireError::HeaderType(t) => write!(f, "EtherCAT header type {t}, not datagrams (1)"),
            WireError::UnknownCommand(c) => write!(f, "datagram command {c}, not in ETG.1000.4"),
            WireError::Length { header, datagrams } => write!(
                f,
                "EtherCAT header says {header} bytes, its datagrams take {datagrams}"
            ),
        }
    }
}

impl std::error::Error for WireError {}

/// One datagram as it travels: the slaves read and write `data` and count.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Datagram {
    pub command: Command,
    pub index: u8,
    /// ADP (low 16 bits) and ADO (high 16 bits), or a logical address.
    pub address: u32,
    pub irq: u16,
    pub data: Vec<u8>,
    pub working_counter: u16,
}

impl Datagram {
    /// Position or station address (ADP).
    pub fn station(&self) -> u16 {
        self.address as u16
    }

    /// Register offset (ADO).
    pub fn register(&self) -> u16 {
        (self.address >> 16) as u16
    }

    pub fn set_station(&mut self, station: u16) {
        self.address = (self.address & 0xFFFF_0000) | u32::from(station);
    }

    /// A datagram for `command` at ADP `station` and ADO `register`.
    pub fn physical(command: Command, station: u16, register: u16, data: Vec<u8>) -> Datagram {
        Datagram {
            command,
            index: 0,
            address: u32::from(station) | (u32::from(register) << 16),
            irq: 0,
            data,
            working_counter: 0,
        }
    }
}

/// A whole frame: the Ethernet addresses and the datagrams.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame {
    pub destination: [u8; 6],
    pub source: [u8; 6],
    pub datagrams: Vec<Datagram>,
}

fn read16(bytes: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([bytes[at], bytes[at + 1]])
}

impl Frame {
    /// No addresses, no datagrams: what [`Frame::parse_from`] fills.
    pub const EMPTY: Frame = Frame {
        destination: [0; 6],
        source: [0; 6],
        datagrams: Vec::new(),
    };

    /// Parses one Ethernet frame; padding after the datagrams is allowed.
    pub fn parse(bytes: &[u8]) -> Result<Frame, WireError> {
        let mut frame = Frame::EMPTY;
        frame.parse_from(bytes)?;
        Ok(frame)
    }

    /// As [`Frame::parse`], into this frame: its datagrams' buffers are
    /// reused (a terminal answers frame after frame without allocating).
    /// On an error the frame holds no datagrams.
    pub fn parse_from(&mut self, bytes: &[u8]) -> Result<(), WireError> {
        let parsed = self.parse_datagrams(bytes);
        if parsed.is_err() {
            self.datagrams.clear();
        }
        parsed
    }

    fn parse_datagrams(&mut self, bytes: &[u8]) -> Result<(), WireError> {
        let need = |needed: usize| {
            if bytes.len() < needed {
                Err(WireError::Truncated {
                    needed,
                    have: bytes.len(),
                })
            } else {
                Ok(())
            }
        };
        need(field::DATAGRAMS)?;
        let ethertype = u16::from_be_bytes([
            bytes[field::ETHERTYPE.start],
            bytes[field::ETHERTYPE.start + 1],
        ]);
        if ethertype != ETHERTYPE {
            return Err(WireError::NotEthercat(ethertype));
        }
        let header = read16(bytes, field::HEADER.start);
        if header >> 12 != TYPE_DATAGRAMS {
            return Err(WireError::HeaderType(header >> 12));
        }
        let declared = usize::from(header & LENGTH_MASK);
        need(field::DATAGRAMS + declared)?;
        let mut count = 0;
        let mut at = field::DATAGRAMS;
        loop {
            need(at + field::OVERHEAD)?;
            let length_word = read16(bytes, at + field::LENGTH.start);
            let len = usize::from(length_word & LENGTH_MASK);
            need(at + field::OVERHEAD + len)?;
            let code = bytes[at + field::COMMAND];
            let address = &bytes[at + field::ADDRESS.start..at + field::ADDRESS.end];
            let command = Command::from_code(code).ok_or(WireError::UnknownCommand(code))?;
            if count == self.datagrams.len() {
                self.datagrams
                    .push(Datagram::physical(command, 0, 0, Vec::new()));
            }
            let datagram = &mut self.datagrams[count];
            datagram.command = command;
            datagram.index = bytes[at + field::INDEX];
            datagram.address = u32::from_le_bytes([address[0], address[1], address[2], address[3]]);
            datagram.irq = read16(bytes, at + field::IRQ.start);
            datagram.data.clear();
            datagram
                .data
                .extend_from_slice(&bytes[at + field::DATA..at + field::DATA + len]);
            datagram.working_counter = read16(bytes, at + field::DATA + len);
            count += 1;
            at += field::OVERHEAD + len;
            if length_word & MORE_FOLLOWS == 0 {
                break;
            }
        }
        if at - field::DATAGRAMS != declared {
            return Err(WireError::Length {
                header: declared,
                datagrams: at - field::DATAGRAMS,
            });
        }
        self.datagrams.truncate(count);
        self.destination.copy_from_slice(&bytes[field::DESTINATION]);
        self.source.copy_from_slice(&bytes[field::SOURCE]);
        Ok(())
    }

    /// The frame's bytes, padded to Ethernet's 60-byte minimum.
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::new();
        self.emit_into(&mut out);
        out
    }

    /// As [`Frame::emit`], into `out` (cleared first, its capacity kept).
    pub fn emit_into(&self, out: &mut Vec<u8>) {
        let length: usize = self
            .datagrams
            .iter()
            .map(|d| d.data.len() + field::OVERHEAD)
            .sum();
        // Sized once: a mailbox frame grown byte by byte was reallocated
        // several times (a twentieth of the in-memory link's run, perf).
        out.clear();
        out.reserve((field::DATAGRAMS + length).max(60));
        out.extend_from_slice(&self.destination);
        out.extend_from_slice(&self.source);
        out.extend_from_slice(&ETHERTYPE.to_be_bytes());
        out.extend_from_slice(
            &((length as u16 & LENGTH_MASK) | TYPE_DATAGRAMS << 12).to_le_bytes(),
        );
        for (i, d) in self.datagrams.iter().enumerate() {
            out.push(d.command.code());
            out.push(d.index);
            out.extend_from_slice(&d.address.to_le_bytes());
            let more = if i + 1 < self.datagrams.len() {
                MORE_FOLLOWS
            } else {
                0
            };
            out.extend_from_slice(&((d.data.len() as u16 & LENGTH_MASK) | more).to_le_bytes());
            out.extend_from_slice(&d.irq.to_le_bytes());
            out.extend_from_slice(&d.data);
            out.extend_from_slice(&d.working_counter.to_le_bytes());
        }
        out.resize(out.len().max(60), 0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A BRD of the ESC type register (2 bytes) as a master sends it, padded.
    static BRD_TYPE: [u8; 60] = {
        let mut f = [0u8; 60];
        let head: [u8; 30] = [
            0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, // broadcast
            0x10, 0x10, 0x10, 0x10, 0x10, 0x10, // source
            0x88, 0xA4, // EtherType
            0x0E, 0x10, // 14 bytes of datagrams, type 1
            0x07, 0x05, // BRD, index 5
            0x00, 0x00, 0x00, 0x00, // ADP 0, ADO 0x0000
            0x02, 0x00, // 2 bytes, last datagram
            0x00, 0x00, // IRQ
            0x00, 0x00, // data
            0x00, 0x00, // working counter
        ];
        let mut i = 0;
        while i < head.len() {
            f[i] = head[i];
            i += 1;
        }
        f
    };

    #[test]
    fn parses_a_broadcast_read() {
        let frame = Frame::parse(&BRD_TYPE).unwrap();
        assert_eq!(frame.destination, [0xFF; 6]);
        assert_eq!(frame.datagrams.len(), 1);
        let d = &frame.datagrams[0];
        assert_eq!((d.command, d.index, d.register()), (Command::Brd, 5, 0));
        assert_eq!(d.data, [0, 0]);
    }

    #[test]
    fn emits_what_it_parsed() {
        assert_eq!(Frame::parse(&BRD_TYPE).unwrap().emit(), BRD_TYPE);
    }

    #[test]
    fn refuses_what_is_no_frame() {
        assert_eq!(
            Frame::parse(&BRD_TYPE[..20]),
            Err(WireError::Truncated {
                needed: 30,
                have: 20
            })
        );
        let mut other = BRD_TYPE;
        other[12] = 0x08;
        other[13] = 0x00;
        assert_eq!(Frame::parse(&other), Err(WireError::NotEthercat(0x0800)));
        let mut command = BRD_TYPE;
        command[16] = 15;
        assert_eq!(Frame::parse(&command), Err(WireError::UnknownCommand(15)));
        let mut length = BRD_TYPE;
        length[14] = 0x10;
        assert_eq!(
            Frame::parse(&length),
            Err(WireError::Length {
                header: 16,
                datagrams: 14
            })
        );
    }

    #[test]
    fn a_frame_parsed_into_another_keeps_nothing_of_it() {
        let mut two = Frame::parse(&BRD_TYPE).unwrap();
        two.datagrams.push(Datagram::physical(
            Command::Fpwr,
            0x1000,
            0x1000,
            vec![7; 128],
        ));
        let mut reused = Frame::parse(&two.emit()).unwrap();
        reused.parse_from(&BRD_TYPE).unwrap();
        assert_eq!(reused, Frame::parse(&BRD_TYPE).unwrap());
        let mut out = two.emit();
        reused.emit_into(&mut out);
        assert_eq!(out, BRD_TYPE);
        // A frame that is none leaves no datagrams from the one before.
        assert!(reused.parse_from(&BRD_TYPE[..20]).is_err());
        assert!(reused.datagrams.is_empty());
    }

    #[test]
    fn several_datagrams_chain_by_more_follows() {
        let mut frame = Frame::parse(&BRD_TYPE).unwrap();
        frame.datagrams.push(Datagram::physical(
            Command::Fprd,
            0x1000,
            0x0130,
            vec![0; 2],
        ));
        let parsed = Frame::parse(&frame.emit()).unwrap();
        assert_eq!(parsed, frame);
    }
}
