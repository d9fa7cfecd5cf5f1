//! Protocol 3 (docs/adapter-protocol.md, "Protocol 3"): the requests and
//! answers of every cycle as records in memory both processes map, one
//! wake-up each way, and the lines only for `configure`, `start` and `bye`.
//!
//! - [`layout`]: where everything lies in the mapping.
//! - [`record`]: the records, read and written as the lines' own types.
//!
//! Each side writes its record, then its sequence word, then wakes the other
//! if that one said it sleeps. A waiter spins a moment first (when it may run
//! on another CPU than the poster), then says it sleeps, looks once more, and
//! sleeps on its eventfd; a wake-up that finds nothing new is harmless.

pub mod layout;
pub mod record;

use std::os::fd::BorrowedFd;
use std::sync::atomic::Ordering::SeqCst;
use std::time::{Duration, Instant};

use canif_cabi::shared::{SharedMap, Wake, Woken};

use super::protocol::{Answer, BusEvent, Request, SharedOffer};
use layout::header;
use record::{Decoded, Encoded};

/// The descriptors protocol 3 is handed on: the mapping's memfd, the
/// implementation's eventfd (woken for a request), the harness's (woken for
/// an answer).
pub const SHARED_FDS: [u32; 3] = [5, 6, 7];

/// How long a waiter spins before it sleeps, where spinning can help.
const SPIN: Duration = Duration::from_micros(50);

/// How long to spin on this thread: not at all where it runs on one CPU.
fn spin_time() -> Duration {
    if let Some(us) = std::env::var("CANIF_SPIN_US")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        return Duration::from_micros(us);
    }
    if canif_cabi::shared::cpus_allowed() > 1 {
        SPIN
    } else {
        Duration::ZERO
    }
}

/// Spins up to `spin` for `done`: looks after every pause (a pause is a
/// hundred cycles or more on recent CPUs), at the clock every 256.
fn spin_for(spin: Duration, done: impl Fn() -> bool) -> bool {
    if done() {
        return true;
    }
    if spin.is_zero() {
        return false;
    }
    let started = Instant::now();
    loop {
        for _ in 0..256 {
            std::hint::spin_loop();
            if done() {
                return true;
            }
        }
        if started.elapsed() >= spin {
            return false;
        }
    }
}

/// How a side's wait for the other's record ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Turn {
    /// The record came.
    Came,
    /// The other descriptor waited on is readable (or closed).
    Other,
    /// Neither within the time given.
    TimedOut,
}

/// One side's wait for the other's record, the same on both sides: spin a
/// moment, then set its asleep word, look once more, and sleep on its
/// eventfd (watching `other` too) until `slice` has passed.
fn wait_turn(
    asleep: &std::sync::atomic::AtomicU32,
    wake: &Wake,
    spin: Duration,
    came: impl Fn() -> bool,
    other: Option<BorrowedFd<'_>>,
    slice: Duration,
) -> std::io::Result<Turn> {
    if spin_for(spin.min(slice), &came) {
        return Ok(Turn::Came);
    }
    asleep.store(1, SeqCst);
    let woken = match came() {
        true => Ok(Woken::Signalled),
        false => wake.wait(other, slice),
    };
    asleep.store(0, SeqCst);
    Ok(match woken? {
        _ if came() => Turn::Came,
        Woken::Other => Turn::Other,
        Woken::Signalled | Woken::TimedOut => Turn::TimedOut,
    })
}

/// Writes an encoded record at `at`, its images in their regions.
fn store(map: &SharedMap, at: usize, encoded: &Encoded) -> Result<(), String> {
    if encoded.record.len() > layout::RECORD_ROOM {
        return Err(format!(
            "a record of {} bytes does not fit its {} bytes",
            encoded.record.len(),
            layout::RECORD_ROOM
        ));
    }
    for (image, region) in [
        (&encoded.outputs, layout::OUTPUTS_AT),
        (&encoded.inputs, layout::INPUTS_AT),
    ] {
        if let Some(image) = image {
            if image.len() > layout::IMAGE_ROOM {
                return Err(format!("an image of {} bytes", image.len()));
            }
            map.write(region, image);
        }
    }
    map.write(at, &encoded.record);
    Ok(())
}

/// The record at `at`, with the images its head names.
fn load(map: &SharedMap, at: usize, buffer: &mut Vec<u8>) -> Result<(Vec<u8>, Vec<u8>), String> {
    buffer.resize(layout::record::ENTRIES, 0);
    map.read(at, buffer);
    let (count, outputs_len, inputs_len) = record::head(buffer);
    let body = count
        .saturating_mul(layout::entry::SIZE)
        .min(layout::RECORD_ROOM - layout::record::ENTRIES);
    buffer.resize(layout::record::ENTRIES + body, 0);
    map.read(
        at + layout::record::ENTRIES,
        &mut buffer[layout::record::ENTRIES..],
    );
    let image = |region: usize, len: usize| {
        if len > layout::IMAGE_ROOM {
            return Err(format!(
                "an image of {len} bytes (room for {})",
                layout::IMAGE_ROOM
            ));
        }
        let mut bytes = vec![0; len];
        map.read(region, &mut bytes);
        Ok(bytes)
    };
    Ok((
        image(layout::OUTPUTS_AT, outputs_len)?,
        image(layout::INPUTS_AT, inputs_len)?,
    ))
}

/// The harness's end: it makes the mapping and the eventfds, hands them to
/// the process it starts, posts requests and waits for answers.
pub(crate) struct HarnessEnd {
    map: SharedMap,
    wake_iut: Wake,
    wake_harness: Wake,
    seq: u32,
    spin: Duration,
    /// The last answer read back, and the last request written: kept for
    /// the next, so that a cycle's exchange allocates nothing for them.
    buffer: Vec<u8>,
    record: Vec<u8>,
}

impl HarnessEnd {
    pub(crate) fn new() -> std::io::Result<HarnessEnd> {
        let map = SharedMap::create("canif-protocol-3", layout::SIZE)?;
        map.word(header::MAGIC).store(layout::MAGIC, SeqCst);
        Ok(HarnessEnd {
            map,
            wake_iut: Wake::new()?,
            wake_harness: Wake::new()?,
            seq: 0,
            spin: spin_time(),
            buffer: Vec::new(),
            record: Vec::new(),
        })
    }

    /// The descriptors to hand to the process, at [`SHARED_FDS`].
    pub(crate) fn handed(&self) -> [(BorrowedFd<'_>, i32); 3] {
        let [memfd, wake_iut, wake_harness] = SHARED_FDS.map(|fd| fd as i32);
        [
            (self.map.fd(), memfd),
            (self.wake_iut.fd(), wake_iut),
            (self.wake_harness.fd(), wake_harness),
        ]
    }

    pub(crate) fn offer() -> SharedOffer {
        SharedOffer {
            memfd: SHARED_FDS[0],
            wake_iut: SHARED_FDS[1],
            wake_harness: SHARED_FDS[2],
            size: layout::SIZE as u64,
        }
    }

    /// Writes `request`, after the bus events `events` of a polled device,
    /// and wakes the implementation.
    pub(crate) fn post(&mut self, events: &[BusEvent], request: &Request) -> Result<(), String> {
        let buffer = std::mem::take(&mut self.record);
        let encoded = match events {
            [] => record::encode_request(buffer, request)?,
            events => record::encode_batch(buffer, events, request)?,
        };
        store(&self.map, layout::REQUEST_AT, &encoded)?;
        self.record = encoded.record;
        self.seq = self.seq.wrapping_add(1);
        self.map.word(header::REQUEST_SEQ).store(self.seq, SeqCst);
        if self.map.word(header::IUT_ASLEEP).load(SeqCst) != 0 {
            self.wake_iut.signal();
        }
        Ok(())
    }

    fn answered(&self) -> bool {
        self.map.word(header::ANSWER_SEQ).load(SeqCst) == self.seq
    }

    /// Waits up to `slice` for the answer to the last request (spinning
    /// first where that can help); whether it came.
    pub(crate) fn wait(&self, slice: Duration) -> bool {
        let turn = wait_turn(
            self.map.word(header::HARNESS_ASLEEP),
            &self.wake_harness,
            self.spin,
            || self.answered(),
            None,
            slice,
        );
        // A failed poll(2) is a wait that saw nothing: the caller looks again.
        matches!(turn, Ok(Turn::Came))
    }

    /// The answer, once [`Self::wait`] said it came.
    pub(crate) fn answer(&mut self) -> Result<Answer, String> {
        let (outputs, inputs) = load(&self.map, layout::ANSWER_AT, &mut self.buffer)?;
        Decoded::new(&self.buffer, outputs, inputs)?.answer()
    }
}

/// What an implementation's end found.
pub enum Next {
    /// A request in the mapping, after the bus events before it (a polled
    /// device's), to answer with [`IutEnd::answer`].
    Request(Vec<BusEvent>, Request),
    /// A record that is none (its answer is the error to give).
    Broken(String),
    /// The line channel has something (a line, or its end): read it there.
    Line,
}

/// An implementation's end (canif's own servers): waits for requests in the
/// mapping, or for the line channel, and writes answers.
pub struct IutEnd {
    map: SharedMap,
    wake_iut: Wake,
    wake_harness: Wake,
    seen: u32,
    spin: Duration,
    /// The last request read back and the last answer written (as
    /// [`HarnessEnd`]'s).
    buffer: Vec<u8>,
    record: Vec<u8>,
}

impl IutEnd {
    /// Opens what `offer` names (descriptors this process was started with).
    pub fn open(offer: &SharedOffer) -> std::io::Result<IutEnd> {
        let inherited = |fd: u32| {
            let fd = i32::try_from(fd).map_err(std::io::Error::other)?;
            canif_cabi::shared::inherited(fd)
        };
        let map = SharedMap::open(inherited(offer.memfd)?)?;
        if map.len() < layout::SIZE || map.word(header::MAGIC).load(SeqCst) != layout::MAGIC {
            return Err(std::io::Error::other(format!(
                "descriptor {} is no protocol 3 mapping (\"CNF3\", {} bytes)",
                offer.memfd,
                layout::SIZE
            )));
        }
        let seen = map.word(header::REQUEST_SEQ).load(SeqCst);
        Ok(IutEnd {
            map,
            wake_iut: Wake::from_fd(inherited(offer.wake_iut)?),
            wake_harness: Wake::from_fd(inherited(offer.wake_harness)?),
            seen,
            spin: spin_time(),
            buffer: Vec::new(),
            record: Vec::new(),
        })
    }

    fn posted(&self) -> bool {
        self.map.word(header::REQUEST_SEQ).load(SeqCst) != self.seen
    }

    /// Waits for the next request, or for `line` (the line channel) to
    /// become readable or close.
    pub fn next(&mut self, line: BorrowedFd<'_>) -> std::io::Result<Next> {
        loop {
            let turn = wait_turn(
                self.map.word(header::IUT_ASLEEP),
                &self.wake_iut,
                self.spin,
                || self.posted(),
                Some(line),
                Duration::from_secs(1),
            )?;
            match turn {
                Turn::Came => {}
                Turn::Other => return Ok(Next::Line),
                Turn::TimedOut => continue,
            }
            self.seen = self.map.word(header::REQUEST_SEQ).load(SeqCst);
            let request = load(&self.map, layout::REQUEST_AT, &mut self.buffer)
                .and_then(|(outputs, inputs)| Decoded::new(&self.buffer, outputs, inputs))
                .and_then(Decoded::batch);
            return Ok(match request {
                Ok((events, request)) => Next::Request(events, request),
                Err(why) => Next::Broken(why),
            });
        }
    }

    /// Writes the answer to the request [`Self::next`] gave, and wakes the harness.
    pub fn answer(&mut self, answer: &Answer) {
        let buffer = std::mem::take(&mut self.record);
        let stored = record::encode_answer(buffer, answer).and_then(|encoded| {
            store(&self.map, layout::ANSWER_AT, &encoded)?;
            Ok(encoded.record)
        });
        match stored {
            Ok(record) => self.record = record,
            Err(why) => {
                // An answer no record holds is answered as the error it is.
                let error = Answer::error(why);
                let encoded =
                    record::encode_answer(Vec::new(), &error).expect("an error answer encodes");
                let _ = store(&self.map, layout::ANSWER_AT, &encoded);
            }
        }
        self.map.word(header::ANSWER_SEQ).store(self.seen, SeqCst);
        if self.map.word(header::HARNESS_ASLEEP).load(SeqCst) != 0 {
            self.wake_harness.signal();
        }
    }
}
