//! The client requirements (`spec/requirements/client.yaml`, rulings P1–P5),
//! judged task by task from what the harness sees: the input image the task
//! was handed, the output image it left, what it delivered to its
//! application, the batches the device entered and the frames the device
//! sent. Pure: the rig feeds it, time is the task's number.

use std::collections::VecDeque;

use canif_model::config::QueueMode;
use canif_model::frame::Frame;
use canif_model::handshake;
use canif_model::image::{ImageLayout, InputImage, MessageRepr, OutputImage};
use canif_spec::{req_ids, ReqId};

use super::master::NEIGHBOUR_PATTERN;
use crate::declare::client::{Application, ClientDeclaration, RestartChoice};

mod rx;
mod tx;

use rx::RxBatch;
use tx::TxBatch;

pub(super) const TX_REQUEST: &[ReqId] = req_ids!["CL-TX-001"];
pub(super) const TX_UNTOUCHED: &[ReqId] = req_ids!["CL-TX-002"];
pub(super) const TX_ONCE: &[ReqId] = req_ids!["CL-TX-003"];
pub(super) const TX_ENCODING: &[ReqId] = req_ids!["CL-TX-004"];
pub(super) const TX_COUNT: &[ReqId] = req_ids!["CL-TX-005"];
pub(super) const RX_ACKNOWLEDGE: &[ReqId] = req_ids!["CL-RX-001"];
pub(super) const RX_READ_ALL: &[ReqId] = req_ids!["CL-RX-004"];
pub(super) const RX_ONCE: &[ReqId] = req_ids!["CL-RX-002"];
pub(super) const RX_DECODING: &[ReqId] = req_ids!["CL-RX-003"];
pub(super) const IMAGE_BOUNDS: &[ReqId] = req_ids!["CL-IMG-001"];
pub(super) const FAST_QUEUE: &[ReqId] = req_ids!["CL-FQ-001"];
pub(super) const PLC_RESTART: &[ReqId] = req_ids!["CL-RST-001"];
pub(super) const DEVICE_RESTART: &[ReqId] = req_ids!["CL-RST-002"];
pub(super) const TRANSACTION_NUMBERS: &[ReqId] = req_ids!["CL-TN-001"];
pub(super) const SENT_REPORTS: &[ReqId] = req_ids!["CL-TN-002"];

/// How many of the messages the device entered last the judge remembers:
/// more than the slots of many batches, which a stale slot can hold.
const ENTERED_KEPT: usize = 1024;

/// The row of a client's diagram a breach of `requirements` is about.
pub(super) fn row_of(requirements: &[ReqId]) -> crate::outcome::TaskRow {
    use crate::outcome::TaskRow;
    let about = |ids: &[ReqId]| requirements.iter().any(|id| ids.contains(id));
    if about(TX_REQUEST) || about(TX_UNTOUCHED) {
        TaskRow::TxCounter
    } else if about(RX_ACKNOWLEDGE) || about(RX_READ_ALL) {
        TaskRow::RxCounter
    } else if about(TX_COUNT) || about(IMAGE_BOUNDS) {
        TaskRow::NoOfTxMessages
    } else if about(TX_ONCE) || about(TX_ENCODING) || about(DEVICE_RESTART) {
        TaskRow::Bus
    } else {
        TaskRow::Application
    }
}

/// What a client did wrong, before the rig adds where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Breach {
    pub requirements: &'static [ReqId],
    pub what: String,
    pub expected: String,
    pub actual: String,
}

/// A client its host stopped at an image's end (`canif lib-host`'s guard page).
pub(super) fn outside_image(what: &str) -> Breach {
    Breach {
        requirements: IMAGE_BOUNDS,
        what: "an access of the process image".into(),
        expected: "within the image".into(),
        actual: what.into(),
    }
}

fn breach(
    requirements: &'static [ReqId],
    what: impl Into<String>,
    expected: impl Into<String>,
    actual: impl Into<String>,
) -> Result<(), Breach> {
    Err(Breach {
        requirements,
        what: what.into(),
        expected: expected.into(),
        actual: actual.into(),
    })
}

/// One task as the judge sees it.
#[derive(Debug, Clone, Copy)]
pub(super) struct TaskSeen<'a> {
    /// The input image the task was handed (without the neighbour bytes).
    pub inputs: &'a [u8],
    /// The output image the device held before the task.
    pub before: &'a [u8],
    /// The output buffer the task left, neighbour bytes behind.
    pub after: &'a [u8],
    /// The requests the client took (those it refused are left out).
    pub accepted: &'a [MessageRepr],
    pub delivered: &'a [MessageRepr],
    /// What it delivered after those that is no frame.
    pub not_frames: &'a [String],
    /// The transaction numbers it told its application were sent.
    pub sent: &'a [u16],
}

/// The judge of one client run.
#[derive(Debug, Clone)]
pub(super) struct Judge {
    layout: ImageLayout,
    queue: QueueMode,
    /// Accepted requests, in order.
    requests: Vec<MessageRepr>,
    /// How many of them the client handed over in batches.
    batched: usize,
    /// The transaction number the client wrote for each request handed over.
    numbers: Vec<u16>,
    /// How many of them reached the bus.
    sent: usize,
    /// Which of those handed over are on the bus (a device restart skips some).
    on_bus: Vec<bool>,
    /// Handed over, lost in a device restart, and sent in no client's view:
    /// a client inferring "sent" from a later number cannot tell (CL-TN-002).
    lost_in_restart: std::collections::BTreeSet<usize>,
    /// Of those handed over, how many the client has told it knows the fate of.
    reported: usize,
    /// Frames the device may send once more (a device restart re-takes the
    /// batch in the image, G1).
    may_repeat: VecDeque<Frame>,
    pending: Option<TxBatch>,
    /// Batches the device entered and the client has not delivered, oldest first.
    rx: VecDeque<RxBatch>,
    /// The batch delivered last, to tell a duplicate from a wrong message.
    last_delivered: Option<RxBatch>,
    /// The messages the device entered lately, to tell a message of an
    /// earlier batch (a stale slot read, CL-RX-002) from a wrong decoding
    /// (CL-RX-003).
    entered_lately: VecDeque<MessageRepr>,
    /// The device's RxCounter after its last cycle.
    device_rx_counter: u16,
    /// The RxCounter of the last input image the client was handed.
    seen_rx_counter: u16,
    /// P3: the one batch a restarted client may deliver again or drop.
    restart_batch: Option<u16>,
    /// The first task after a PLC restart.
    restarted: bool,
    /// A device restart happened at this task, and requests were waiting.
    device_restart: Option<u64>,
    /// A device restart happened in this run.
    device_restarted: bool,
    /// The task of the last device restart: after it, no image the client
    /// sees comes from the device before.
    last_device_restart: Option<u64>,
    /// The Outputs.TxCounter the device's last cycle saw.
    device_tx: u16,
    /// From a PLC restart to the first batch the device takes.
    after_plc_restart: bool,
    /// Requests (by index) the device may never see (P3, CL-RST-001).
    may_lose: std::collections::BTreeSet<usize>,
    /// The client declares it tells its application nothing of what was
    /// sent: its transaction numbers are free (000 §5.2), CL-TN-001 is not judged.
    numbers_free: bool,
    /// The application has a stream per identifier: frames of different
    /// identifiers may pass each other, those of one identifier not.
    streams: bool,
    /// The application's streams are bytes: a frame may carry the next
    /// bytes of its identifier however the client cut them.
    byte_stream: bool,
    /// P3 as the client declares it; `None`: either.
    restart_choice: Option<RestartChoice>,
    /// A restart put the client's Outputs.RxCounter out of step with the
    /// device's, this many tasks ago: until the images it is handed come from
    /// after the restart (the exchange's dead time) and it copies
    /// Inputs.RxCounter again, a value of its own is judged by what its
    /// application sees (P1), not as such.
    out_of_step: Option<u64>,
    /// A part of the judge that found a breach stops judging: its state has
    /// left the client's, and what it would say next follows from the
    /// breach (the Tx part: batches, frames on the bus, what was told sent,
    /// the device restart; the Rx part: deliveries). The other part goes on.
    tx_broken: bool,
    rx_broken: bool,
}

impl Judge {
    /// The judge of a client declaring `declared`: one that tells its
    /// application nothing of what was sent may enter any transaction number
    /// (000 §5.2); one with a stream per identifier keeps each in order; a
    /// declared restart choice (P3) is the only one it may take.
    pub(super) fn new(layout: ImageLayout, queue: QueueMode, declared: &ClientDeclaration) -> Self {
        Judge {
            numbers_free: declared.tells_sent == Some(false),
            streams: declared.application() != Application::OneStream,
            byte_stream: declared.application() == Application::ByteStream,
            restart_choice: declared.restart,
            out_of_step: None,
            tx_broken: false,
            rx_broken: false,
            layout,
            queue,
            requests: Vec::new(),
            batched: 0,
            numbers: Vec::new(),
            sent: 0,
            on_bus: Vec::new(),
            lost_in_restart: std::collections::BTreeSet::new(),
            reported: 0,
            may_repeat: VecDeque::new(),
            pending: None,
            rx: VecDeque::new(),
            last_delivered: None,
            entered_lately: VecDeque::new(),
            device_rx_counter: 0,
            seen_rx_counter: 0,
            restart_batch: None,
            restarted: false,
            device_restart: None,
            device_restarted: false,
            last_device_restart: None,
            device_tx: 0,
            after_plc_restart: false,
            may_lose: std::collections::BTreeSet::new(),
        }
    }

    /// The device's RxCounter after its last cycle.
    pub(super) fn device_rx_counter(&self) -> u16 {
        self.device_rx_counter
    }

    /// Requests accepted and not yet handed over (what a restart loses).
    pub(super) fn waiting(&self) -> usize {
        self.requests.len() - self.batched
    }

    /// The device's cycle left this input image.
    pub(super) fn device_cycle(&mut self, inputs: &[u8]) {
        let Ok(image) = InputImage::new_checked(inputs, self.layout) else {
            return;
        };
        let counter = image.rx_counter();
        if counter == self.device_rx_counter {
            return;
        }
        self.device_rx_counter = counter;
        let count = usize::from(image.no_of_rx_messages()).min(self.layout.rx_slots);
        let messages = (0..count)
            .filter_map(|slot| image.rx_message(slot))
            .map(|view| MessageRepr::parse_clamped(&view).0)
            .collect::<VecDeque<_>>();
        self.entered_lately.extend(messages.iter().copied());
        let excess = self.entered_lately.len().saturating_sub(ENTERED_KEPT);
        self.entered_lately.drain(..excess);
        self.rx.push_back(RxBatch::new(counter, messages));
    }

    /// The device sent a frame on the bus.
    /// The device's cycle saw Outputs.TxCounter `counter`.
    pub(super) fn device_saw(&mut self, counter: u16) {
        self.device_tx = counter;
    }

    pub(super) fn device_sent(&mut self, frame: &Frame) -> Result<(), Breach> {
        if self.tx_broken {
            return Ok(());
        }
        let judged = self.judge_device_sent(frame);
        self.tx_broken |= judged.is_err();
        judged
    }

    fn judge_device_sent(&mut self, frame: &Frame) -> Result<(), Breach> {
        while self.may_lose.contains(&self.sent)
            && self.requests.get(self.sent).map(|r| &r.frame) != Some(frame)
        {
            self.sent += 1;
        }
        if self.requests.get(self.sent).map(|r| &r.frame) == Some(frame) {
            if let Some(on_bus) = self.on_bus.get_mut(self.sent) {
                *on_bus = true;
            }
            self.sent += 1;
            return Ok(());
        }
        if self.may_repeat.front() == Some(frame) {
            self.may_repeat.pop_front();
            // The batch in the image at the restart, taken once more.
            let again = (0..self.batched.min(self.on_bus.len()))
                .rev()
                .find(|&i| !self.on_bus[i] && self.requests[i].frame == *frame);
            if let Some(i) = again {
                self.on_bus[i] = true;
                self.lost_in_restart.remove(&i);
            }
            return Ok(());
        }
        let expected = match self.requests.get(self.sent) {
            Some(next) => format!("request #{} {}", self.sent, next.frame),
            None => "no frame (every request was sent)".into(),
        };
        // After an earlier breach the count may run past the requests.
        let (before, after) = self.requests.split_at(self.sent.min(self.requests.len()));
        let what = if before.iter().any(|r| r.frame == *frame) {
            "a frame sent twice"
        } else if after.iter().any(|r| r.frame == *frame) {
            "a frame sent out of order"
        } else {
            "a frame the application never asked for"
        };
        breach(TX_ONCE, what, expected, frame.to_string())
    }

    /// The PLC restarted: its program and what it had not handed over are
    /// gone, and its last batch too if the device had not seen it yet (the
    /// device's last cycle saw Outputs.TxCounter `device_saw`).
    pub(super) fn plc_restarted(&mut self, device_saw: u16) {
        let unseen = self.pending.as_ref().filter(|p| p.counter != device_saw);
        if let Some(pending) = unseen {
            self.batched -= usize::from(pending.count);
            self.numbers.truncate(self.batched);
            self.on_bus.truncate(self.batched);
        }
        // A new program knows nothing of what the old one handed over.
        self.reported = self.batched;
        self.requests.truncate(self.batched);
        self.restarted = true;
        self.out_of_step = Some(0);
        self.after_plc_restart = true;
        self.restart_batch = Some(self.seen_rx_counter);
        // What it had handed over may still be in the image: the device takes
        // the next change of the counter as a batch (G1), and the new program
        // starts without a pending batch.
        self.pending = None;
    }

    /// The device restarted at `task`: what it had accepted and not sent is
    /// lost, and it takes the batch in the output image once more. Of the
    /// batches it had entered, the client can still see those up to the one
    /// with RxCounter `visible` (the master read it already); the others are lost.
    pub(super) fn device_restarted(&mut self, task: u64, outputs: &[u8], visible: u16) {
        self.lost_in_restart
            .extend((self.sent..self.batched).filter(|&i| self.on_bus.get(i) == Some(&false)));
        self.sent = self.batched;
        self.may_repeat = OutputImage::new_checked(outputs, self.layout)
            .map(|image| {
                let count = usize::from(image.no_of_tx_messages()).min(self.layout.tx_slots);
                (0..count)
                    .filter_map(|slot| image.tx_message(slot))
                    .map(|view| MessageRepr::parse_clamped(&view).0.frame)
                    .collect()
            })
            .unwrap_or_default();
        let keep = self
            .rx
            .iter()
            .position(|b| b.counter == visible)
            .map_or(0, |at| at + 1);
        self.rx.truncate(keep);
        for batch in &mut self.rx {
            batch.before_device_restart = true;
        }
        self.device_rx_counter = 0;
        self.pending = None;
        self.device_restart = Some(task);
        self.device_restarted = true;
        self.out_of_step = Some(0);
        self.last_device_restart = Some(task);
    }

    /// One task the client ran.
    pub(super) fn task(&mut self, task: u64, seen: TaskSeen<'_>, deadline: u64) -> Vec<Breach> {
        let layout = self.layout;
        let size = layout.output_size();
        let mut breaches = Vec::new();
        // Each part judges on after the other part's breach, so one defect
        // does not hide the next; a part stops at its own first breach.
        if seen.after[size..].iter().any(|b| *b != NEIGHBOUR_PATTERN) {
            breaches.extend(
                breach(
                    IMAGE_BOUNDS,
                    "the bytes behind the output image",
                    format!("untouched ({NEIGHBOUR_PATTERN:02X} …)"),
                    "written",
                )
                .err(),
            );
        }
        let read = seen.delivered.len() + seen.not_frames.len();
        if read > layout.rx_slots {
            breaches.extend(
                breach(
                    IMAGE_BOUNDS,
                    "messages read in one task",
                    format!("at most the {} Rx slots", layout.rx_slots),
                    read.to_string(),
                )
                .err(),
            );
        }
        if let Some(what) = seen.not_frames.first() {
            breaches.extend(
                breach(
                    RX_DECODING,
                    format!("delivered message {}", seen.delivered.len()),
                    "a frame, decoded per the message structure",
                    format!("no frame: {what}"),
                )
                .err(),
            );
        }
        let images = InputImage::new_checked(seen.inputs, layout)
            .and_then(|i| Ok((i, OutputImage::new_checked(seen.before, layout)?)))
            .and_then(|(i, b)| Ok((i, b, OutputImage::new_checked(&seen.after[..size], layout)?)));
        let (inputs, before, after) = match images {
            Ok(images) => images,
            Err(error) => {
                breaches.push(size_breach(error));
                return breaches;
            }
        };
        self.requests.extend_from_slice(seen.accepted);
        if self
            .last_device_restart
            .is_some_and(|restart| task > restart)
        {
            // What the device before its restart entered and the client did
            // not read by now is gone with its memory (inherent, CL-RST-002).
            self.rx.retain(|b| !b.before_device_restart);
        }
        if let Some(tasks) = self.out_of_step {
            let copied = after.rx_counter() == inputs.rx_counter();
            self.out_of_step = (tasks <= deadline || !copied).then_some(tasks + 1);
        }
        if !self.rx_broken {
            let judged = self.judge_rx(&inputs, &before, &after, seen.delivered);
            self.rx_broken |= judged.is_err();
            breaches.extend(judged.err());
        }
        if self.tx_broken {
            self.restarted = false;
            return breaches;
        }
        let judged = self
            .judge_sent(seen.sent)
            .and_then(|()| self.judge_tx(&inputs, &before, &after));
        self.tx_broken |= judged.is_err();
        breaches.extend(judged.err());
        if self.tx_broken {
            self.restarted = false;
            return breaches;
        }
        if let Some(restart) = self.device_restart {
            if self.pending.is_some() || self.waiting() == 0 {
                self.device_restart = None;
            } else if task > restart + deadline {
                self.tx_broken = true;
                breaches.extend(
                    breach(
                        DEVICE_RESTART,
                        "a new batch after the device restart",
                        format!("within {deadline} tasks of task {restart}"),
                        format!("none by task {task}, {} requests waiting", self.waiting()),
                    )
                    .err(),
                );
            }
        }
        self.restarted = false;
        breaches
    }

    /// After the last task: what never arrived. `device_queued_rx`: messages
    /// the device received and has not entered in the image.
    pub(super) fn finish(&self, device_queued_rx: usize) -> Result<(), Breach> {
        // What a device restart left stuck is the restart's (CL-RST-002).
        self.finish_unblamed(device_queued_rx)
            .map_err(|breach| match self.device_restarted {
                true => Breach {
                    requirements: DEVICE_RESTART,
                    ..breach
                },
                false => breach,
            })
    }

    fn finish_unblamed(&self, device_queued_rx: usize) -> Result<(), Breach> {
        let missing = (self.sent..self.requests.len())
            .filter(|i| !self.may_lose.contains(i))
            .count();
        if missing > 0 {
            return breach(
                TX_ONCE,
                "frames the application asked to send",
                format!(
                    "all {} on the bus",
                    self.requests.len() - self.may_lose.len()
                ),
                format!("{missing} never sent ({} handed over)", self.batched),
            );
        }
        if self.queue != QueueMode::Fast && device_queued_rx > 0 {
            return breach(
                RX_ACKNOWLEDGE,
                "messages the device received",
                "entered in the image once the client acknowledged the last batch",
                format!("{device_queued_rx} still waiting in the device: no acknowledge"),
            );
        }
        let undelivered: usize = self
            .rx
            .iter()
            .filter(|b| b.shown || (self.queue != QueueMode::Fast && !b.before_device_restart))
            .map(|b| b.messages.len())
            .sum();
        if undelivered > 0 {
            return breach(
                RX_ONCE,
                "messages the device entered",
                "all delivered",
                format!("{undelivered} never delivered"),
            );
        }
        Ok(())
    }
}

fn size_breach(error: canif_model::image::SizeError) -> Breach {
    Breach {
        requirements: IMAGE_BOUNDS,
        what: "the image size".into(),
        expected: error.expected.to_string(),
        actual: error.actual.to_string(),
    }
}

#[cfg(test)]
mod tests;
