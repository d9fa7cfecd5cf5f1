//! The Tx half of the judge: what the client wrote in the output image
//! against what its application asked to send, in order and once
//! (CL-TX-*), and what it told its application was sent (CL-TN-*).

use super::*;

/// A batch the client wrote and the device has not acknowledged in its view.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct TxBatch {
    pub(super) counter: u16,
    pub(super) count: u16,
    slots: Vec<u8>,
}

impl Judge {
    pub(super) fn judge_tx(
        &mut self,
        inputs: &InputImage<&[u8]>,
        before: &OutputImage<&[u8]>,
        after: &OutputImage<&[u8]>,
    ) -> Result<(), Breach> {
        if self
            .pending
            .as_ref()
            .is_some_and(|p| p.counter == inputs.tx_counter())
        {
            self.pending = None;
        }
        // A restarted program may write a new batch under the counter the
        // last one had: a new batch all the same, if one the device cannot see.
        let changed = after.tx_counter() != before.tx_counter()
            || (self.after_plc_restart && tx_batch(after) != tx_batch(before));
        if let Some(pending) = &self.pending {
            if !pending.is_in(after) {
                let now = tx_batch(after);
                let what = if changed {
                    "a new batch before the last was acknowledged"
                } else {
                    "the Tx messages or NoOfTxMessages of an unacknowledged batch"
                };
                return breach(
                    TX_UNTOUCHED,
                    what,
                    format!("TxCounter {} unchanged", pending.counter),
                    format!("TxCounter {}, NoOfTxMessages {}", now.counter, now.count),
                );
            }
            return Ok(());
        }
        if !changed {
            return Ok(());
        }
        let count = after.no_of_tx_messages();
        if self.restarted && count == 0 {
            return Ok(()); // a restarted program's first image: a batch of nothing
        }
        if !handshake::ready_to_send(before.tx_counter(), inputs.tx_counter()) && !self.restarted {
            return breach(
                TX_REQUEST,
                "a new batch while the counters differ",
                format!(
                    "Outputs.TxCounter {} = Inputs.TxCounter {}",
                    before.tx_counter(),
                    inputs.tx_counter()
                ),
                "a new batch",
            );
        }
        let next = handshake::next(inputs.tx_counter());
        if after.tx_counter() != next {
            return breach(
                TX_REQUEST,
                "Outputs.TxCounter of a new batch",
                format!("Inputs.TxCounter + 1 = {next}"),
                after.tx_counter().to_string(),
            );
        }
        if usize::from(count) > self.layout.tx_slots {
            return breach(
                TX_COUNT,
                "NoOfTxMessages",
                format!("at most the {} Tx slots", self.layout.tx_slots),
                count.to_string(),
            );
        }
        let mut numbers = Vec::new();
        for slot in 0..usize::from(count) {
            let view = after.tx_message(slot).expect("slot within the slots");
            let written = MessageRepr::parse(&view);
            if let Ok(written) = &written {
                self.next_of_its_stream(self.batched + slot, written);
            }
            let request = self.requests.get(self.batched + slot);
            match (written, request) {
                (Ok(written), Some(request)) if written.frame == request.frame => {
                    numbers.push(written.transaction_number)
                }
                (_, None) => {
                    return breach(
                        TX_COUNT,
                        format!("Tx message {slot}"),
                        format!("{} requests to send", self.requests.len() - self.batched),
                        format!("NoOfTxMessages {count}"),
                    )
                }
                (written, Some(request)) => {
                    // A frame asked for before or after this one: the order
                    // or the once is broken, not the encoding.
                    let asked = written
                        .as_ref()
                        .is_ok_and(|w| self.requests.iter().any(|r| r.frame == w.frame));
                    let actual = match &written {
                        Ok(w) => w.frame.to_string(),
                        Err(e) => e.to_string(),
                    };
                    let ids = if asked { TX_ONCE } else { TX_ENCODING };
                    return breach(
                        ids,
                        format!("Tx message {slot}"),
                        request.frame.to_string(),
                        actual,
                    );
                }
            }
        }
        if self.layout.transaction_number && !self.numbers_free {
            self.judge_numbers(&numbers)?;
        }
        self.on_bus.resize(self.on_bus.len() + numbers.len(), false);
        self.numbers.extend(numbers);
        if self.after_plc_restart && after.tx_counter() == self.device_tx {
            // A restarted program cannot know the counter the device last
            // took; a batch with that counter shows the device no change
            // (G1), so it may never be sent (P3, an assumption).
            self.may_lose
                .extend(self.batched..self.batched + usize::from(count));
        } else {
            self.after_plc_restart = false;
        }
        self.batched += usize::from(count);
        self.pending = Some(tx_batch(after));
        Ok(())
    }

    /// With a stream per identifier, the request `written` may stand for is
    /// the first not handed over of its identifier: it moves to `at`, the
    /// others keep their order (one stream: nothing moves).
    fn next_of_its_stream(&mut self, at: usize, written: &MessageRepr) {
        if self.byte_stream {
            let pending = self.requests.split_off(at);
            self.requests.extend(cut(pending, written));
            return;
        }
        if !self.streams {
            return;
        }
        let id = written.frame.id;
        let first = (at..self.requests.len()).find(|&i| self.requests[i].frame.id == id);
        if let Some(first) = first {
            self.requests[at..=first].rotate_right(1);
        }
    }

    /// CL-TN-002: a message is told sent once it is on the bus, once, in
    /// the order sent. Skipping some is no breach: the client may tell only
    /// of the last one Inputs.TransactionNumber names.
    pub(super) fn judge_sent(&mut self, sent: &[u16]) -> Result<(), Breach> {
        for number in sent {
            let at = (self.reported..self.numbers.len()).find(|&i| self.numbers[i] == *number);
            let Some(at) = at else {
                let actual = if self.numbers[..self.reported].contains(number) {
                    "told again, or out of order"
                } else {
                    "no message handed over carries it"
                };
                return breach(
                    SENT_REPORTS,
                    format!("the message with transaction number {number} told sent"),
                    "a message handed over and not yet told sent",
                    actual,
                );
            };
            if !self.on_bus[at] && !self.lost_in_restart.contains(&at) {
                return breach(
                    SENT_REPORTS,
                    format!("the message with transaction number {number} told sent"),
                    "on the bus: Inputs.TransactionNumber names it or a later message",
                    format!(
                        "not sent yet ({} of {} handed over are on the bus)",
                        self.sent, self.batched
                    ),
                );
            }
            self.reported = at + 1;
        }
        Ok(())
    }

    /// CL-TN-001: numbers other than 0, unique among the messages in flight.
    fn judge_numbers(&self, numbers: &[u16]) -> Result<(), Breach> {
        let in_flight = &self.numbers[self.sent.min(self.batched)..];
        for (slot, number) in numbers.iter().enumerate() {
            if *number == 0 || in_flight.contains(number) || numbers[..slot].contains(number) {
                return breach(
                    TRANSACTION_NUMBERS,
                    format!("the transaction number of Tx message {slot}"),
                    "not 0 and not carried by another message in flight",
                    number.to_string(),
                );
            }
        }
        Ok(())
    }
}

impl TxBatch {
    /// The image still holds this batch: counter, count and slots unchanged.
    fn is_in(&self, image: &OutputImage<&[u8]>) -> bool {
        let mut slots = self.slots.chunks(image.layout().tx_message.size);
        image.tx_counter() == self.counter
            && image.no_of_tx_messages() == self.count
            && (0..usize::from(self.count)).all(|slot| {
                match (image.tx_message(slot), slots.next()) {
                    (Some(view), Some(kept)) => view.as_bytes() == kept,
                    (None, None) => true,
                    _ => false,
                }
            })
    }
}

pub(super) fn tx_batch(image: &OutputImage<&[u8]>) -> TxBatch {
    let count = image.no_of_tx_messages();
    let slots = (0..usize::from(count))
        .filter_map(|slot| image.tx_message(slot))
        .flat_map(|view| view.as_bytes().to_vec())
        .collect();
    TxBatch {
        counter: image.tx_counter(),
        count,
        slots,
    }
}

/// A byte stream's `pending` messages, oldest first, with `taken`'s bytes
/// cut from its identifier's: `taken` first, the bytes it carried gone from
/// those it came from (a message partly taken keeps the rest), the other
/// identifiers' untouched. Unchanged where `taken` is not the next bytes of
/// its identifier (the ordinary comparison then says what is wrong).
pub(super) fn cut(pending: Vec<MessageRepr>, taken: &MessageRepr) -> Vec<MessageRepr> {
    let id = taken.frame.id;
    let want = taken.frame.data();
    let next: Vec<u8> = pending
        .iter()
        .filter(|m| m.frame.id == id)
        .flat_map(|m| m.frame.data().iter().copied())
        .take(want.len())
        .collect();
    if want.is_empty() || taken.frame.is_remote() || next != want {
        return pending;
    }
    let mut left = want.len();
    let mut rest = Vec::with_capacity(pending.len());
    for message in pending {
        if left == 0 || message.frame.id != id {
            rest.push(message);
            continue;
        }
        let data = message.frame.data();
        if data.len() <= left {
            left -= data.len();
            continue;
        }
        let frame = Frame::classic(id, &data[left..]).expect("fewer bytes than it had");
        left = 0;
        rest.push(MessageRepr { frame, ..message });
    }
    std::iter::once(*taken).chain(rest).collect()
}
