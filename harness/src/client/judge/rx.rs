//! The Rx half of the judge: which batches the device entered, which the
//! client was shown, and whether what it delivered is each of them once and
//! in order (CL-RX-*, CL-FQ-001, the restarts' allowances of P3).

use std::collections::VecDeque;

use canif_model::config::QueueMode;
use canif_model::image::{InputImage, MessageRepr, OutputImage};

use super::{
    breach, Breach, Judge, RestartChoice, FAST_QUEUE, PLC_RESTART, RX_ACKNOWLEDGE, RX_DECODING,
    RX_ONCE, RX_READ_ALL,
};

/// A batch the device entered in the input image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct RxBatch {
    pub(super) counter: u16,
    pub(super) messages: VecDeque<MessageRepr>,
    /// The client was handed an image showing it (in a task it ran).
    pub(super) shown: bool,
    /// The device restarted after entering it: if the client never saw it,
    /// it is lost with the device's memory (CL-RST-002).
    pub(super) before_device_restart: bool,
    /// Messages of it delivered so far.
    taken: usize,
    /// The first batch a restarted program was shown (P3's one batch with
    /// the Fast CAN Queue, where the device does not wait for it).
    at_plc_restart: bool,
}

impl RxBatch {
    pub(super) fn new(counter: u16, messages: VecDeque<MessageRepr>) -> Self {
        RxBatch {
            counter,
            messages,
            shown: false,
            before_device_restart: false,
            taken: 0,
            at_plc_restart: false,
        }
    }
}

impl Judge {
    pub(super) fn judge_rx(
        &mut self,
        inputs: &InputImage<&[u8]>,
        before: &OutputImage<&[u8]>,
        after: &OutputImage<&[u8]>,
        delivered: &[MessageRepr],
    ) -> Result<(), Breach> {
        let counter = inputs.rx_counter();
        let fresh = counter != self.seen_rx_counter;
        self.seen_rx_counter = counter;
        if fresh {
            self.skip_unshown(counter)?;
        }
        let restart_batch = self.restart_batch.take();
        if restart_batch.is_some() && self.queue == QueueMode::Fast {
            if let Some(front) = self.rx.front_mut().filter(|b| b.counter == counter) {
                front.at_plc_restart = true;
            }
        }
        let mut delivered = delivered;
        // P3: a restarted client may deliver the batch it finds once more.
        if let (Some(again), Some(last)) = (restart_batch, &self.last_delivered) {
            let n = last.messages.len();
            if last.counter == again
                && delivered.len() >= n
                && delivered[..n].iter().eq(last.messages.iter())
            {
                if self.restart_choice == Some(RestartChoice::DropsOnce) {
                    return breach(
                        PLC_RESTART,
                        format!("the batch of RxCounter {again} in the image at the restart"),
                        "acknowledged unread: the client declares restart=drops-once",
                        "delivered again",
                    );
                }
                delivered = &delivered[n..];
            }
        }
        for message in delivered {
            // P3 allows one batch: a message delivered twice, out of order,
            // from a stale slot or never entered beyond it is the restart's
            // fault; a message decoded wrongly is a decoding fault, restart
            // or not.
            self.take_delivered(message, inputs)
                .map_err(|breach| match restart_batch {
                    Some(_) if [RX_ONCE, FAST_QUEUE].contains(&breach.requirements) => Breach {
                        requirements: PLC_RESTART,
                        ..breach
                    },
                    _ => breach,
                })?;
        }
        // P1: out of step after a restart, a counter of the client's own
        // acknowledges nothing; what it then does to the deliveries is judged.
        let acknowledges = self.out_of_step.is_none() || after.rx_counter() == counter;
        if self.queue != QueueMode::Fast
            && after.rx_counter() != before.rx_counter()
            && acknowledges
        {
            if after.rx_counter() != counter {
                return breach(
                    RX_ACKNOWLEDGE,
                    "Outputs.RxCounter",
                    format!("Inputs.RxCounter {counter}"),
                    after.rx_counter().to_string(),
                );
            }
            let undelivered = self.rx.front().is_some_and(|b| b.counter == counter);
            if undelivered && restart_batch.is_none() {
                return breach(
                    RX_READ_ALL,
                    "messages read before the acknowledge",
                    format!("NoOfRxMessages = {}", inputs.no_of_rx_messages()),
                    format!(
                        "{} left unread",
                        self.rx.front().map_or(0, |b| b.messages.len())
                    ),
                );
            }
            if undelivered {
                if self.restart_choice == Some(RestartChoice::DeliversTwice) {
                    return breach(
                        PLC_RESTART,
                        format!("the batch of RxCounter {counter} in the image at the restart"),
                        "delivered: the client declares restart=delivers-twice",
                        "acknowledged unread",
                    );
                }
                self.rx.pop_front(); // P3: dropped once
            }
        }
        Ok(())
    }

    /// The client sees RxCounter `counter`: batches before it it never saw.
    fn skip_unshown(&mut self, counter: u16) -> Result<(), Breach> {
        let Some(at) = self.rx.iter().position(|b| b.counter == counter) else {
            return Ok(());
        };
        for batch in self.rx.drain(..at).collect::<Vec<_>>() {
            if batch.at_plc_restart && self.restart_choice == Some(RestartChoice::DeliversTwice) {
                return breach(
                    PLC_RESTART,
                    format!(
                        "the batch of RxCounter {} a restarted program was shown",
                        batch.counter
                    ),
                    "delivered: the client declares restart=delivers-twice",
                    format!("{} never delivered", batch.messages.len()),
                );
            }
            let lost_with_restart = self.restart_batch == Some(batch.counter)
                || batch.at_plc_restart
                || (batch.before_device_restart && !batch.shown);
            match self.queue {
                QueueMode::Fast if batch.shown && !lost_with_restart => {
                    return breach(
                        FAST_QUEUE,
                        format!("the messages of RxCounter {}", batch.counter),
                        "read in the task that saw the new RxCounter",
                        format!("{} never delivered", batch.messages.len()),
                    )
                }
                QueueMode::Fast => {} // P4: a missed task cycle loses them
                _ if lost_with_restart => {}
                _ => {
                    return breach(
                        RX_ONCE,
                        format!("the messages of RxCounter {}", batch.counter),
                        "delivered before the next batch",
                        format!("{} never delivered", batch.messages.len()),
                    )
                }
            }
        }
        if let Some(front) = self.rx.front_mut() {
            front.shown = true;
        }
        Ok(())
    }

    fn take_delivered(
        &mut self,
        message: &MessageRepr,
        inputs: &InputImage<&[u8]>,
    ) -> Result<(), Breach> {
        if self.byte_stream {
            // The next bytes of its identifier, however the client cut them.
            if let Some(batch) = self.rx.front_mut() {
                let pending = std::mem::take(&mut batch.messages).into();
                batch.messages = super::tx::cut(pending, message).into();
            }
        } else if self.streams {
            // Its stream's next message comes first; the others keep their order.
            if let Some(batch) = self.rx.front_mut() {
                let id = message.frame.id;
                if let Some(at) = batch.messages.iter().position(|m| m.frame.id == id) {
                    batch.messages.make_contiguous()[..=at].rotate_right(1);
                }
            }
        }
        let expected = self.rx.front().and_then(|b| b.messages.front()).copied();
        if expected.as_ref() == Some(message) {
            let batch = self.rx.front_mut().expect("a front message has a batch");
            let repr = batch.messages.pop_front().expect("checked above");
            let done = batch.messages.is_empty();
            if batch.taken == 0 {
                self.last_delivered = Some(RxBatch::new(batch.counter, VecDeque::new()));
            }
            batch.taken += 1;
            let entry = self
                .last_delivered
                .as_mut()
                .expect("set at the batch's first message");
            entry.messages.push_back(repr);
            if done {
                self.rx.pop_front();
            }
            return Ok(());
        }
        let described = expected.map_or("no message (all were delivered)".into(), |m| {
            m.frame.to_string()
        });
        let again = self
            .last_delivered
            .as_ref()
            .is_some_and(|b| b.messages.contains(message));
        let later = self
            .rx
            .iter()
            .flat_map(|b| b.messages.iter())
            .any(|m| m == message);
        // A slot past NoOfRxMessages, or an earlier batch's message: no
        // message of this batch, however right its decoding.
        let in_use = usize::from(inputs.no_of_rx_messages()).min(self.layout.rx_slots);
        let earlier = self.entered_lately.contains(message)
            || (in_use..self.layout.rx_slots)
                .filter_map(|slot| inputs.rx_message(slot))
                .any(|view| MessageRepr::parse_clamped(&view).0 == *message);
        let once = match self.queue {
            QueueMode::Fast => FAST_QUEUE,
            _ => RX_ONCE,
        };
        let (ids, what) = match (again, later, expected) {
            (true, _, _) => (once, "a message delivered twice"),
            (_, true, _) => (RX_ONCE, "a message delivered out of order"),
            _ if earlier => (
                once,
                "a slot past NoOfRxMessages or of an earlier batch read",
            ),
            (_, _, None) => (RX_ONCE, "a message the device never entered"),
            _ => (
                RX_DECODING,
                "a message decoded otherwise than the device wrote it",
            ),
        };
        breach(ids, what, described, format!("{}", message.frame))
    }
}
