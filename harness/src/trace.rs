//! Bus traces for the tools people already use: a candump log
//! (`(sec.usec) iface ID#DATA`, `##` for FD) and pcapng (written by the
//! `pcap-file` crate) with link type CAN_SOCKETCAN (227), the interface named,
//! nanosecond time stamps, and each frame's direction as the IUT sees it
//! (EPB flags: outbound = the IUT sent it, inbound = another node did), and
//! the frame a failure is about carrying the failure as its comment. Both
//! are written as the run goes, so a long run holds no trace in memory. The
//! candump log has no place for a comment, so a failing frame is marked in
//! `NAME.failing.txt` beside it, by its line in the log.

use std::borrow::Cow;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::time::Duration;

use canif_model::frame::{Frame, FrameKind};
use canif_model::Nanos;
use pcap_file::pcapng::blocks::enhanced_packet::{EnhancedPacketBlock, EnhancedPacketOption};
use pcap_file::pcapng::blocks::interface_description::{
    InterfaceDescriptionBlock, InterfaceDescriptionOption,
};
use pcap_file::pcapng::PcapNgWriter;
use pcap_file::DataLink;

/// Removes what an earlier run left at `path`, if anything.
pub(crate) fn remove_stale(path: &Path) -> io::Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

/// The interface name the traces give the simulated bus.
pub(crate) const SIM_INTERFACE: &str = "canif-sim";

/// EPB flags, bits 0-1: the direction of the packet (pcapng §4.3.1).
mod direction {
    pub(super) const INBOUND: u32 = 0b01;
    pub(super) const OUTBOUND: u32 = 0b10;
}

/// Writes one scenario's bus to `NAME.log` and `NAME.pcapng` (and, when
/// it fails at a frame, `NAME.failing.txt`).
pub struct TraceWriter {
    epoch: Nanos,
    interface: String,
    candump: BufWriter<File>,
    /// Lines written to the candump log.
    lines: usize,
    /// Where the failing-frame marks go, and the log's name they refer to.
    failing: (std::path::PathBuf, String),
    pcapng: PcapNgWriter<BufWriter<File>>,
}

/// One line of a candump log: `(SECONDS.MICROS) IFACE ID#DATA`, `at` in ns.
pub(crate) fn candump_line(at: Nanos, interface: &str, frame: &Frame) -> String {
    format!(
        "({}.{:06}) {interface} {frame}",
        at / 1_000_000_000,
        (at % 1_000_000_000) / 1_000
    )
}

fn pcap_error(error: pcap_file::PcapError) -> io::Error {
    match error {
        pcap_file::PcapError::IoError(error) => error,
        other => io::Error::other(other.to_string()),
    }
}

/// A frame as the CAN_SOCKETCAN link type carries it: `struct can_frame` or
/// `struct canfd_frame`, the CAN id big-endian.
fn socketcan_packet(frame: &Frame) -> Vec<u8> {
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
    packet.extend_from_slice(&can_id.to_be_bytes());
    packet.push(frame.len());
    packet.extend_from_slice(&[flags, 0, 0]);
    packet.extend_from_slice(frame.data());
    packet.resize(8 + room, 0);
    packet
}

impl TraceWriter {
    /// Starts `DIR/NAME.log` and `DIR/NAME.pcapng` for a bus called
    /// `interface`; scenario time 0 is stamped `epoch` (ns since the Unix epoch),
    /// so that tools such as `log2asc` see one real start time.
    pub fn create(dir: &Path, name: &str, interface: &str, epoch: Nanos) -> io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let file = BufWriter::new(File::create(dir.join(format!("{name}.pcapng")))?);
        let mut pcapng = PcapNgWriter::new(file).map_err(pcap_error)?;
        pcapng
            .write_pcapng_block(InterfaceDescriptionBlock {
                linktype: DataLink::CAN_SOCKETCAN,
                snaplen: 0,
                options: vec![
                    InterfaceDescriptionOption::IfName(Cow::Borrowed(interface)),
                    // pcap-file writes nanoseconds; without this readers assume µs.
                    InterfaceDescriptionOption::IfTsResol(9),
                ],
            })
            .map_err(pcap_error)?;
        let candump = BufWriter::new(File::create(dir.join(format!("{name}.log")))?);
        let failing = dir.join(format!("{name}.failing.txt"));
        // Marks of an earlier run of this scenario are not this run's.
        remove_stale(&failing)?;
        Ok(TraceWriter {
            epoch,
            interface: interface.to_string(),
            candump,
            lines: 0,
            failing: (failing, format!("{name}.log")),
            pcapng,
        })
    }

    /// A frame that ended on the bus at `at`; `from_iut`: the IUT sent it.
    pub fn frame(&mut self, at: Nanos, frame: &Frame, from_iut: bool) -> io::Result<()> {
        self.packet(at, frame, from_iut, None).map(drop)
    }

    /// The IUT's frame a failure is about, with the failure as its packet
    /// comment (Wireshark shows it, `frame.comment` finds it). The candump
    /// log stays as candump writes it: its readers (canplayer, python-can)
    /// take every line for a frame, so the mark is `NAME.failing.txt`:
    /// `NAME.log:LINE: the line  <- the failure`.
    pub fn failing_frame(&mut self, at: Nanos, frame: &Frame, comment: &str) -> io::Result<()> {
        let line = self.packet(at, frame, true, Some(comment))?;
        let (path, log) = &self.failing;
        let mut marks = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)?;
        writeln!(marks, "{log}:{}: {line}  <- {comment}", self.lines)
    }

    fn packet(
        &mut self,
        at: Nanos,
        frame: &Frame,
        from_iut: bool,
        comment: Option<&str>,
    ) -> io::Result<String> {
        let at = self.epoch.saturating_add(at);
        let line = candump_line(at, &self.interface, frame);
        writeln!(self.candump, "{line}")?;
        self.lines += 1;
        let packet = socketcan_packet(frame);
        let flags = if from_iut {
            direction::OUTBOUND
        } else {
            direction::INBOUND
        };
        self.pcapng
            .write_pcapng_block(EnhancedPacketBlock {
                interface_id: 0,
                timestamp: Duration::from_nanos(at),
                original_len: packet.len() as u32,
                data: Cow::Owned(packet),
                options: std::iter::once(EnhancedPacketOption::Flags(flags))
                    .chain(comment.map(|c| EnhancedPacketOption::Comment(Cow::Borrowed(c))))
                    .collect(),
            })
            .map_err(pcap_error)?;
        Ok(line)
    }

    pub fn finish(mut self) -> io::Result<()> {
        self.candump.flush()?;
        self.pcapng.get_mut().flush()
    }
}
