//! Protocol 3's records: the requests and answers of versions 1 and 2 and of
//! the client role, as bytes in the shared mapping instead of JSON lines.
//! One encoder and one decoder each way, so both ends (the harness, and
//! `canif device --stdio` or `canif lib-host` serving) read and write the
//! same [`Request`] and [`Answer`] values the lines carry.

// A record's numbers are little-endian as the images' are: one codec.
use canif_model::image::le::{read as get, write as put};
use canif_model::info_data::ControllerStatus;

use super::layout::{entry, record, MAX_ENTRIES};
use crate::door::adapter::protocol::{
    Answer, BusEvent, FrameData, Request, Transmitted, WireFrame, WireMessage,
};

mod decode;

pub use decode::Decoded;

/// What a record is.
pub mod kind {
    pub const CYCLE: u32 = 1;
    pub const RECEIVE: u32 = 2;
    pub const POLL_TRANSMIT: u32 = 3;
    pub const TRANSMIT_COMPLETE: u32 = 4;
    pub const CONTROLLER_STATUS: u32 = 5;
    pub const STEP: u32 = 6;
    pub const TASK: u32 = 7;
    pub const PLAN: u32 = 8;
    pub const OK: u32 = 101;
    pub const ERROR: u32 = 102;
    pub const INPUTS: u32 = 103;
    pub const TRANSMIT: u32 = 104;
    pub const STEPPED: u32 = 105;
    pub const TASKED: u32 = 106;
}

/// What an entry is.
pub mod tag {
    pub const RECEIVED: u32 = 1;
    pub const STARTED: u32 = 2;
    pub const COMPLETED: u32 = 3;
    pub const STATUS: u32 = 4;
    pub const PLANNED: u32 = 5;
    pub const PLANNED_INVALID: u32 = 6;
    pub const FRAME: u32 = 7;
    pub const INVALID: u32 = 8;
    pub const MESSAGE: u32 = 9;
    pub const REFUSED: u32 = 10;
    pub const SENT: u32 = 11;
}

/// A record as bytes: its head and entries, and the images it carries
/// (borrowed from the request or answer: they are copied once, into the
/// mapping).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Encoded<'a> {
    pub record: Vec<u8>,
    pub outputs: Option<&'a [u8]>,
    pub inputs: Option<&'a [u8]>,
}

/// The head's count and image lengths, read where the record lies: how
/// much more there is to read.
pub fn head(bytes: &[u8]) -> (usize, usize, usize) {
    (
        get(bytes, record::COUNT) as usize,
        get(bytes, record::OUTPUTS_LEN) as usize,
        get(bytes, record::INPUTS_LEN) as usize,
    )
}

struct Builder<'a> {
    encoded: Encoded<'a>,
    count: usize,
}

/// Which image a record carries.
enum Image {
    Outputs,
    Inputs,
}

impl<'a> Builder<'a> {
    /// A record written into `buffer` (what it held is dropped): an end that
    /// hands back the last record's buffer writes every record without an
    /// allocation.
    fn new(mut record: Vec<u8>, kind: u32, time: u64) -> Builder<'a> {
        record.clear();
        record.resize(record::ENTRIES, 0);
        put(&mut record, record::KIND, kind.into());
        put(&mut record, record::TIME, time);
        Builder {
            encoded: Encoded {
                record,
                ..Encoded::default()
            },
            count: 0,
        }
    }

    fn image(mut self, which: Image, image: &'a [u8]) -> Self {
        let (length, slot) = match which {
            Image::Outputs => (record::OUTPUTS_LEN, &mut self.encoded.outputs),
            Image::Inputs => (record::INPUTS_LEN, &mut self.encoded.inputs),
        };
        *slot = Some(image);
        put(&mut self.encoded.record, length, image.len() as u64);
        self
    }

    /// A new entry with `tag`, to fill in.
    fn entry(&mut self, tag: u32) -> &mut [u8] {
        self.count += 1;
        let start = self.encoded.record.len();
        self.encoded.record.resize(start + entry::SIZE, 0);
        let slot = &mut self.encoded.record[start..];
        put(slot, entry::TAG, tag.into());
        slot
    }

    fn event(&mut self, event: &BusEvent) {
        match event {
            BusEvent::Received { frame, end_ns } => {
                let slot = self.entry(tag::RECEIVED);
                put_frame(slot, frame);
                put(slot, entry::TIME, *end_ns);
            }
            BusEvent::Started { at_ns } => put(self.entry(tag::STARTED), entry::TIME, *at_ns),
            BusEvent::Completed => {
                self.entry(tag::COMPLETED);
            }
            BusEvent::Status { status } => put_status(self.entry(tag::STATUS), &status.0),
        }
    }

    /// Text where an entry's data goes (at most its 64 bytes, cut at a character).
    fn text(slot: &mut [u8], text: &str) {
        let mut end = text.len().min(entry::DATA.len());
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        put(slot, entry::AUX, end as u64);
        slot[entry::DATA.start..entry::DATA.start + end].copy_from_slice(&text.as_bytes()[..end]);
    }

    fn done(mut self) -> Result<Encoded<'a>, String> {
        if self.count > MAX_ENTRIES {
            return Err(format!(
                "{} entries do not fit a record ({MAX_ENTRIES} at most)",
                self.count
            ));
        }
        put(&mut self.encoded.record, record::COUNT, self.count as u64);
        Ok(self.encoded)
    }
}

fn put_frame(slot: &mut [u8], frame: &WireFrame) {
    put(slot, entry::ID, frame.id.into());
    slot[entry::FLAGS] = [frame.extended, frame.rtr, frame.fd, frame.brs, frame.esi]
        .iter()
        .enumerate()
        .fold(0u8, |flags, (bit, on)| flags | (u8::from(*on) << bit));
    slot[entry::LEN] = frame.len;
    let data = frame.data.as_slice();
    let data = &data[..data.len().min(entry::DATA.len())];
    slot[entry::DATA.start..entry::DATA.start + data.len()].copy_from_slice(data);
    // The data's own length, where the frame's `len` (a DLC-rounded FD length,
    // or a remote frame's) does not say it.
    put(slot, entry::AUX, data.len() as u64);
}

fn get_frame(slot: &[u8]) -> WireFrame {
    let flags = slot[entry::FLAGS];
    let bit = |n: u8| flags & (1 << n) != 0;
    let data_len = (get(slot, entry::AUX) as usize).min(entry::DATA.len());
    WireFrame {
        id: get(slot, entry::ID) as u32,
        extended: bit(0),
        rtr: bit(1),
        fd: bit(2),
        brs: bit(3),
        esi: bit(4),
        len: slot[entry::LEN],
        data: FrameData::from(&slot[entry::DATA.start..entry::DATA.start + data_len]),
    }
}

fn put_status(slot: &mut [u8], status: &ControllerStatus) {
    let flags = [
        status.bus_off,
        status.error_passive,
        status.node_active,
        status.warning_limit,
        status.overload,
        status.bus_idle,
        status.core_running,
    ]
    .iter()
    .enumerate()
    .fold(0u64, |flags, (bit, on)| flags | (u64::from(*on) << bit));
    put(slot, entry::AUX, flags);
    let words = [
        status.transceiver_delay,
        status.ack_errors,
        status.bit_errors,
        status.crc_errors,
        status.form_errors,
        status.stuff_errors,
        status.receive_error_counter,
        status.transmit_error_counter,
    ];
    for (n, word) in words.iter().enumerate() {
        let at = entry::DATA.start + 4 * n;
        put(slot, at..at + 4, (*word).into());
    }
}

fn get_status(slot: &[u8]) -> ControllerStatus {
    let flags = get(slot, entry::AUX);
    let bit = |n: u32| flags & (1 << n) != 0;
    let word = |n: usize| {
        let at = entry::DATA.start + 4 * n;
        get(slot, at..at + 4) as u32
    };
    ControllerStatus {
        bus_off: bit(0),
        error_passive: bit(1),
        node_active: bit(2),
        warning_limit: bit(3),
        overload: bit(4),
        bus_idle: bit(5),
        core_running: bit(6),
        transceiver_delay: word(0),
        ack_errors: word(1),
        bit_errors: word(2),
        crc_errors: word(3),
        form_errors: word(4),
        stuff_errors: word(5),
        receive_error_counter: word(6),
        transmit_error_counter: word(7),
    }
}

fn put_message(slot: &mut [u8], message: &WireMessage) {
    put_frame(slot, &message.frame);
    put(
        slot,
        entry::TRANSACTION_NUMBER,
        message.transaction_number.into(),
    );
    put(slot, entry::TIME_STAMP, message.time_stamp_ns);
}

fn get_message(slot: &[u8]) -> WireMessage {
    WireMessage {
        frame: get_frame(slot),
        transaction_number: get(slot, entry::TRANSACTION_NUMBER) as u16,
        time_stamp_ns: get(slot, entry::TIME_STAMP),
    }
}

fn get_text(slot: &[u8]) -> Result<String, String> {
    let len = (get(slot, entry::AUX) as usize).min(entry::DATA.len());
    String::from_utf8(slot[entry::DATA.start..entry::DATA.start + len].to_vec())
        .map_err(|_| "a text entry that is not UTF-8".to_string())
}

/// A `cycle` or `poll_transmit` of a device that is polled, after the bus
/// events since the last record: what version 1 would send as `receive`,
/// `transmit_complete` and `controller_status` requests first, each of them
/// answered `ok`, in one record.
pub fn encode_batch<'a>(
    buffer: Vec<u8>,
    events: &[BusEvent],
    request: &'a Request,
) -> Result<Encoded<'a>, String> {
    let mut record = match request {
        Request::Cycle { now_ns, outputs } => {
            Builder::new(buffer, kind::CYCLE, *now_ns).image(Image::Outputs, &outputs.0)
        }
        Request::PollTransmit { now_ns } => Builder::new(buffer, kind::POLL_TRANSMIT, *now_ns),
        other => return Err(format!("`{}` takes no bus events before it", other.name())),
    };
    for event in events {
        record.event(event);
    }
    record.done()
}

/// A request of the hot path as a record (written into `buffer`); `configure`, `start` and `bye`
/// stay on the line channel.
pub fn encode_request(buffer: Vec<u8>, request: &Request) -> Result<Encoded<'_>, String> {
    let record = match request {
        Request::Cycle { now_ns, outputs } => {
            Builder::new(buffer, kind::CYCLE, *now_ns).image(Image::Outputs, &outputs.0)
        }
        Request::Receive { frame, end_ns } => {
            let mut record = Builder::new(buffer, kind::RECEIVE, *end_ns);
            put_frame(record.entry(tag::RECEIVED), frame);
            record
        }
        Request::PollTransmit { now_ns } => Builder::new(buffer, kind::POLL_TRANSMIT, *now_ns),
        Request::TransmitComplete {} => Builder::new(buffer, kind::TRANSMIT_COMPLETE, 0),
        Request::ControllerStatus { status } => {
            let mut record = Builder::new(buffer, kind::CONTROLLER_STATUS, 0);
            put_status(record.entry(tag::STATUS), &status.0);
            record
        }
        Request::Step {
            now_ns,
            outputs,
            events,
        } => {
            let mut record =
                Builder::new(buffer, kind::STEP, *now_ns).image(Image::Outputs, &outputs.0);
            for event in events {
                match event {
                    BusEvent::Received { frame, end_ns } => {
                        let slot = record.entry(tag::RECEIVED);
                        put_frame(slot, frame);
                        put(slot, entry::TIME, *end_ns);
                    }
                    BusEvent::Started { at_ns } => {
                        put(record.entry(tag::STARTED), entry::TIME, *at_ns)
                    }
                    BusEvent::Completed => {
                        record.entry(tag::COMPLETED);
                    }
                    BusEvent::Status { status } => put_status(record.entry(tag::STATUS), &status.0),
                }
            }
            record
        }
        Request::Plan { now_ns, events } => {
            let mut record = Builder::new(buffer, kind::PLAN, *now_ns);
            for event in events {
                record.event(event);
            }
            record
        }
        Request::Task {
            inputs,
            outputs,
            requests,
        } => {
            let mut record = Builder::new(buffer, kind::TASK, 0)
                .image(Image::Inputs, &inputs.0)
                .image(Image::Outputs, &outputs.0);
            for message in requests {
                put_message(record.entry(tag::MESSAGE), message);
            }
            record
        }
        Request::Configure { .. }
        | Request::Start { .. }
        | Request::Declare {}
        | Request::Bye {} => return Err(format!("`{}` goes on the line channel", request.name())),
    };
    record.done()
}

/// An answer as a record.
pub fn encode_answer(buffer: Vec<u8>, answer: &Answer) -> Result<Encoded<'_>, String> {
    let record = match answer {
        Answer::Ok => Builder::new(buffer, kind::OK, 0),
        Answer::Error { message } => {
            // The text where the entries go, its length as the count.
            let mut record = Builder::new(buffer, kind::ERROR, 0);
            record.encoded.record.extend_from_slice(message.as_bytes());
            put(
                &mut record.encoded.record,
                record::COUNT,
                message.len() as u64,
            );
            return Ok(record.encoded);
        }
        Answer::Inputs { inputs } => {
            Builder::new(buffer, kind::INPUTS, 0).image(Image::Inputs, &inputs.0)
        }
        Answer::Transmit { frame, next_ns } => {
            let mut record = Builder::new(buffer, kind::TRANSMIT, next_ns.unwrap_or(u64::MAX));
            match frame {
                None => {}
                Some(Transmitted::Frame(frame)) => put_frame(record.entry(tag::FRAME), frame),
                Some(Transmitted::Invalid(invalid)) => {
                    Builder::text(record.entry(tag::INVALID), &invalid.invalid)
                }
            }
            record
        }
        Answer::Stepped { inputs, plan, more } => {
            let mut record = Builder::new(buffer, kind::STEPPED, u64::from(*more))
                .image(Image::Inputs, &inputs.0);
            for planned in plan {
                match (&planned.frame, &planned.invalid) {
                    (Some(frame), _) => {
                        let slot = record.entry(tag::PLANNED);
                        put_frame(slot, frame);
                        put(slot, entry::TIME, planned.not_before_ns);
                    }
                    (None, invalid) => {
                        let slot = record.entry(tag::PLANNED_INVALID);
                        Builder::text(slot, invalid.as_deref().unwrap_or_default());
                        put(slot, entry::TIME, planned.not_before_ns);
                    }
                }
            }
            record
        }
        Answer::Tasked {
            outputs,
            delivered,
            refused,
            sent,
        } => {
            let mut record =
                Builder::new(buffer, kind::TASKED, 0).image(Image::Outputs, &outputs.0);
            for message in delivered {
                put_message(record.entry(tag::MESSAGE), message);
            }
            for index in refused {
                put(record.entry(tag::REFUSED), entry::AUX, *index as u64);
            }
            for number in sent {
                put(
                    record.entry(tag::SENT),
                    entry::TRANSACTION_NUMBER,
                    (*number).into(),
                );
            }
            record
        }
        Answer::Configured { .. } | Answer::Started { .. } | Answer::Declared { .. } => {
            return Err(format!("`{}` goes on the line channel", answer.name()))
        }
    };
    record.done()
}

#[cfg(test)]
mod tests;
