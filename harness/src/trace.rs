//! Bus traces for the tools people already use: a candump log
//! (`(sec.usec) iface ID#DATA`, `##` for FD) and pcapng with link type
//! CAN_SOCKETCAN (227), nanosecond time stamps (if_tsresol = 9). Both are
//! written as the run goes, so a long run holds no trace in memory.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use canif_model::frame::{Frame, FrameKind};
use canif_model::Nanos;

/// The interface name the traces give the simulated bus.
pub const INTERFACE: &str = "sim0";
/// pcapng link type of SocketCAN frames.
pub const LINKTYPE_CAN_SOCKETCAN: u16 = 227;

const SECTION_HEADER: u32 = 0x0A0D_0D0A;
const INTERFACE_DESCRIPTION: u32 = 0x0000_0001;
const ENHANCED_PACKET: u32 = 0x0000_0006;

/// Writes one scenario's bus to `NAME.log` and `NAME.pcapng`.
pub struct TraceWriter {
    candump: BufWriter<File>,
    pcapng: BufWriter<File>,
}

fn block(out: &mut impl Write, kind: u32, body: &[u8]) -> io::Result<()> {
    let padded = body.len().div_ceil(4) * 4;
    let total = (12 + padded) as u32;
    out.write_all(&kind.to_le_bytes())?;
    out.write_all(&total.to_le_bytes())?;
    out.write_all(body)?;
    out.write_all(&vec![0; padded - body.len()])?;
    out.write_all(&total.to_le_bytes())
}

impl TraceWriter {
    pub fn create(dir: &Path, name: &str) -> io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let mut pcapng = BufWriter::new(File::create(dir.join(format!("{name}.pcapng")))?);
        let mut section = Vec::new();
        section.extend_from_slice(&0x1A2B_3C4Du32.to_le_bytes());
        section.extend_from_slice(&1u16.to_le_bytes());
        section.extend_from_slice(&0u16.to_le_bytes());
        section.extend_from_slice(&(-1i64).to_le_bytes());
        block(&mut pcapng, SECTION_HEADER, &section)?;
        let mut interface = Vec::new();
        interface.extend_from_slice(&LINKTYPE_CAN_SOCKETCAN.to_le_bytes());
        interface.extend_from_slice(&0u16.to_le_bytes());
        interface.extend_from_slice(&0u32.to_le_bytes()); // no snap length limit
        interface.extend_from_slice(&[9, 0, 1, 0, 9, 0, 0, 0]); // if_tsresol = 10^-9, padded
        interface.extend_from_slice(&[0, 0, 0, 0]); // opt_endofopt
        block(&mut pcapng, INTERFACE_DESCRIPTION, &interface)?;
        let candump = BufWriter::new(File::create(dir.join(format!("{name}.log")))?);
        Ok(TraceWriter { candump, pcapng })
    }

    /// A frame that ended on the bus at `at`.
    pub fn frame(&mut self, at: Nanos, frame: &Frame) -> io::Result<()> {
        writeln!(
            self.candump,
            "({}.{:06}) {INTERFACE} {frame}",
            at / 1_000_000_000,
            (at % 1_000_000_000) / 1_000
        )?;
        let mut can_id = frame.id.raw();
        if frame.id.is_extended() {
            can_id |= 0x8000_0000;
        }
        if frame.is_remote() {
            can_id |= 0x4000_0000;
        }
        let (flags, room) = match frame.kind {
            FrameKind::Fd { brs, esi } => (0x04 | u8::from(brs) | (u8::from(esi) << 1), 64),
            FrameKind::Classic { .. } => (0, 8),
        };
        let mut packet = Vec::with_capacity(8 + room);
        packet.extend_from_slice(&can_id.to_be_bytes()); // the CAN id is big-endian in this link type
        packet.push(frame.len());
        packet.extend_from_slice(&[flags, 0, 0]);
        packet.extend_from_slice(frame.data());
        packet.resize(8 + room, 0);
        let mut body = Vec::with_capacity(20 + packet.len());
        body.extend_from_slice(&0u32.to_le_bytes());
        body.extend_from_slice(&((at >> 32) as u32).to_le_bytes());
        body.extend_from_slice(&(at as u32).to_le_bytes());
        body.extend_from_slice(&(packet.len() as u32).to_le_bytes());
        body.extend_from_slice(&(packet.len() as u32).to_le_bytes());
        body.extend_from_slice(&packet);
        block(&mut self.pcapng, ENHANCED_PACKET, &body)
    }

    pub fn finish(mut self) -> io::Result<()> {
        self.candump.flush()?;
        self.pcapng.flush()
    }
}
