//! The simulated coupler behind socketcand's text protocol on loopback TCP, so
//! that CANopen tools written by others (python-can's `socketcand` interface,
//! the `canopen` package) can talk to it. Real time drives its heartbeat.

use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::time::{Duration, Instant};

use canif_model::canopen::coupler::Coupler;
use canif_model::frame::{CanId, Frame};
use canif_model::Nanos;

/// A frame as socketcand writes it in raw mode.
fn frame_text(frame: &Frame, at: Nanos) -> String {
    let id = match frame.id {
        CanId::Standard(id) => format!("{id:03X}"),
        CanId::Extended(id) => format!("{id:08X}"),
    };
    let data: String = frame.data().iter().map(|b| format!("{b:02X}")).collect();
    format!(
        "< frame {id} {}.{:06} {data} >",
        at / 1_000_000_000,
        (at % 1_000_000_000) / 1_000
    )
}

/// A `< send ID LEN B0 B1 … >` command's frame.
fn sent_frame(command: &[String]) -> Option<Frame> {
    let raw = u32::from_str_radix(&command[1], 16).unwrap_or(0);
    let id = if command[1].len() > 3 {
        CanId::extended(raw)
    } else {
        CanId::standard(raw)
    };
    let data: Vec<u8> = command[3..]
        .iter()
        .filter_map(|b| u8::from_str_radix(b, 16).ok())
        .collect();
    id.and_then(|id| Frame::classic(id, &data).ok())
}

/// Serves `coupler` to one client on `listener` until the client leaves.
pub fn serve(listener: &TcpListener, coupler: &mut Coupler) -> std::io::Result<()> {
    let (stream, _) = listener.accept()?;
    stream.set_read_timeout(Some(Duration::from_millis(5)))?;
    let mut writer = stream.try_clone()?;
    let started = Instant::now();
    let now = || started.elapsed().as_nanos() as Nanos;
    let mut reader = BufReader::new(stream);
    let mut pending = String::new();
    writer.write_all(b"< hi >")?;
    loop {
        let mut chunk = Vec::new();
        match reader.read_until(b'>', &mut chunk) {
            Ok(0) => return Ok(()), // the client left
            Ok(_) => pending.push_str(&String::from_utf8_lossy(&chunk)),
            Err(error)
                if matches!(
                    error.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                pending.push_str(&String::from_utf8_lossy(&chunk));
            }
            Err(_) => return Ok(()),
        }
        let mut out = Vec::new();
        while let (Some(start), Some(end)) = (pending.find('<'), pending.find('>')) {
            if end < start {
                pending.drain(..=end);
                continue;
            }
            let command: Vec<String> = pending[start + 1..end]
                .split_whitespace()
                .map(String::from)
                .collect();
            pending.drain(..=end);
            match command.first().map(String::as_str) {
                Some("open") | Some("rawmode") => out.push("< ok >".to_string()),
                Some("send") if command.len() >= 3 => {
                    if let Some(frame) = sent_frame(&command) {
                        let at = now();
                        out.extend(coupler.handle(&frame, at).iter().map(|f| frame_text(f, at)));
                    }
                }
                _ => out.push("< error unknown command >".to_string()),
            }
        }
        let at = now();
        out.extend(coupler.poll(at).iter().map(|f| frame_text(f, at)));
        if !out.is_empty() && writer.write_all(out.concat().as_bytes()).is_err() {
            return Ok(());
        }
    }
}
