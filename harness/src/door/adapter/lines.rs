//! An implementation's answers, line by line, read on the harness's own
//! thread with poll(2): waiting there instead of handing lines over from a
//! reader thread saves a context switch per exchange, which is most of an
//! exchange's cost.

use std::fs::File;
use std::time::Duration;

/// The longest line an IUT may print: far above any answer the protocol has
/// (an input image of 32 FD slots is about 5 KB of hex), far below what could
/// exhaust the harness's memory.
const MAX_LINE: usize = 1 << 20;

/// What reading the IUT's next line gave.
pub(crate) enum Line {
    Text(String),
    /// The IUT printed what no line of the protocol can be.
    Broken(String),
    /// Nothing within the timeout.
    Silent,
    /// Its stdout closed.
    Closed,
}

/// The IUT's stdout, read on the harness's own thread: waiting with poll(2)
/// instead of handing lines over from a reader thread saves a context switch
/// per exchange, which is most of an exchange's cost.
pub(crate) struct LineReader {
    source: File,
    buffer: Vec<u8>,
    /// What one read fills, allocated once (not zeroed again per read).
    chunk: Box<[u8]>,
    /// Bytes of `buffer` already handed out.
    used: usize,
}

impl LineReader {
    pub(crate) fn new(source: File) -> Self {
        LineReader {
            source,
            buffer: Vec::with_capacity(1 << 16),
            chunk: vec![0; 1 << 16].into_boxed_slice(),
            used: 0,
        }
    }

    /// The next line (without its newline), waiting at most `timeout` in all.
    pub(crate) fn next(&mut self, timeout: Duration) -> Line {
        use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
        use std::io::Read;
        use std::os::fd::AsFd;
        let deadline = std::time::Instant::now() + timeout;
        let mut searched = self.used;
        loop {
            if let Some(at) = self.buffer[searched..].iter().position(|b| *b == b'\n') {
                let end = searched + at;
                let bytes = &self.buffer[self.used..end];
                let line = match std::str::from_utf8(bytes) {
                    Ok(text) => Line::Text(text.to_string()),
                    Err(e) => Line::Broken(format!(
                        "printed a line that is not UTF-8 (byte {} of {:02X?}…)",
                        e.valid_up_to(),
                        &bytes[..bytes.len().min(16)]
                    )),
                };
                self.used = end + 1;
                if self.used == self.buffer.len() {
                    self.buffer.clear();
                    self.used = 0;
                }
                return line;
            }
            searched = self.buffer.len();
            if self.buffer.len() - self.used > MAX_LINE {
                return Line::Broken(format!("printed a line longer than {MAX_LINE} bytes"));
            }
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            let wait = PollTimeout::try_from(left).unwrap_or(PollTimeout::MAX);
            let mut fds = [PollFd::new(self.source.as_fd(), PollFlags::POLLIN)];
            match poll(&mut fds, wait) {
                Ok(0) => return Line::Silent,
                Ok(_) => {}
                Err(nix::errno::Errno::EINTR) => continue,
                Err(e) => return Line::Broken(format!("its stdout failed: {e}")),
            }
            if self.used > 0 {
                self.buffer.drain(..self.used);
                searched -= self.used;
                self.used = 0;
            }
            match self.source.read(&mut self.chunk) {
                Ok(0) => return Line::Closed,
                Ok(n) => self.buffer.extend_from_slice(&self.chunk[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Line::Broken(format!("its stdout failed: {e}")),
            }
        }
    }
}
