//! Where two input images, or two frames, differ, and which requirements that
//! difference breaks. Images are read only through the model's views; what the
//! documents call don't-care is skipped: Rx slots at and past NoOfRxMessages
//! (HS-RX-008, FQ-005) and data bytes past the length.

use canif_model::dlc;
use canif_model::filter::{self, FilterRow};
use canif_model::frame::Frame;
use canif_model::image::{
    field, ImageLayout, InputImage, LengthField, MessageLayout, MessageRepr, MessageView,
    OutputImage,
};
use canif_model::Nanos;
use canif_spec::ReqId;

use crate::device::blame;
use crate::device::history::Taken;
use crate::outcome::FrameDiff;

/// A difference found, before it becomes a [`crate::Failure`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Difference {
    pub candidates: &'static [ReqId],
    pub what: String,
    pub expected: String,
    pub actual: String,
    /// The frames themselves, when a frame differs: drawn byte by byte.
    pub frames: Option<Box<FrameDiff>>,
}

/// A difference in `region` whose bytes are the model's moved by 2 or 4:
/// the layout put the region at the wrong offset, which `candidates` name.
fn shifted(
    (expected, actual): (&[u8], &[u8]),
    region: std::ops::Range<usize>,
    candidates: &'static [ReqId],
    difference: Difference,
) -> Difference {
    let moved_by = |by: isize| {
        let (mut same, mut meaningful) = (true, 0);
        for i in region.clone() {
            let Some(a) = i.checked_add_signed(by).and_then(|j| actual.get(j)) else {
                continue;
            };
            same &= expected[i] == *a;
            meaningful += usize::from(expected[i] != 0);
        }
        same && meaningful > 0
    };
    if [-4, -2, 2, 4].into_iter().any(moved_by) {
        Difference {
            candidates,
            what: format!("{} (the region is shifted)", difference.what),
            ..difference
        }
    } else {
        difference
    }
}

/// An input image of the wrong size.
pub fn image_size(expected: usize, actual: usize) -> Difference {
    Difference {
        frames: None,
        candidates: blame::INPUT_IMAGE_SIZE,
        what: "input image size".into(),
        expected: format!("{expected} bytes"),
        actual: format!("{actual} bytes"),
    }
}

/// Bytes as `01 02 0A`.
pub fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn describe_slot(view: &MessageView<&[u8]>) -> String {
    match MessageRepr::parse(view) {
        Ok(m) => format!("{} ts={} [{}]", m.frame, m.time_stamp, hex(view.as_bytes())),
        Err(e) => format!("invalid ({e}) [{}]", hex(view.as_bytes())),
    }
}

/// What the handshake looked like going into the cycle (both devices agreed
/// until now, so one previous RxCounter and TxCounter serve both).
#[derive(Debug, Clone, Copy)]
pub struct Handshake {
    /// Inputs.RxCounter going into the cycle.
    pub rx_before: u16,
    pub plc_released: u16,
    pub fast: bool,
    /// NoOfTxMessages of the output image the cycle ran on.
    pub no_of_tx_messages: u16,
    /// Inputs.TxCounter going into the cycle, and the Outputs.TxCounter
    /// the cycle ran on: an acknowledge is the one copied to the other.
    pub tx_before: u16,
    pub tx_requested: u16,
}

/// How an input image is judged against the model's.
pub struct InputCheck<'a> {
    pub layout: &'a ImageLayout,
    /// What the model's Rx queue did with a frame another node sent lately;
    /// `None`: no node did. A slot holding such a frame carries a real, wrong
    /// frame; anything else is a frame the IUT encoded wrongly.
    pub received: &'a dyn Fn(&Frame) -> Option<Taken>,
    /// The model's local Rx queue overflowed lately.
    pub overflowed: bool,
    /// The configuration's filter table: a frame let through or held back
    /// otherwise than it says is charged to the statement deciding it.
    pub filters: &'a [FilterRow],
    /// Whether a transaction number is of a message the model has accepted
    /// and not yet completed on the bus.
    pub waiting_to_send: &'a dyn Fn(u16) -> bool,
    pub time_stamp_tolerance: Nanos,
    /// The controller has reported a status to the model (else InfoData
    /// holds INFO-009's initial words).
    pub controller_reported: bool,
    pub handshake: Handshake,
    /// What the device declared of the freedoms the checks otherwise skip.
    pub declared: DeclaredRx,
}

/// Which don't-care fields a device declared what it writes into (HS-RX-008,
/// HS-RX-009): then they are judged against the model taking that choice.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DeclaredRx {
    pub idle_count: bool,
    pub stale_slots: bool,
}

impl InputCheck<'_> {
    /// The first difference between the model's and the IUT's input image.
    pub fn compare(&self, expected: &[u8], actual: &[u8]) -> Option<Difference> {
        let (Ok(e), Ok(a)) = (
            InputImage::new_checked(expected, *self.layout),
            InputImage::new_checked(actual, *self.layout),
        ) else {
            return Some(image_size(expected.len(), actual.len()));
        };
        // The PLC reads NoOfRxMessages and the messages only when
        // Inputs.RxCounter differs from its Outputs.RxCounter (001 §6): in
        // Buffered mode they are don't-care otherwise (HS-RX-008).
        let unread = !self.handshake.fast && e.rx_counter() == self.handshake.plc_released;
        let layout = self.layout;
        let bytes = (expected, actual);
        self.header(&e, &a, unread)
            .or_else(|| {
                let d = if unread { None } else { self.messages(&e, &a) }?;
                let region = layout.rx_slot(0).start..layout.rx_slot(layout.rx_slots - 1).end;
                let candidates = if layout.transaction_number {
                    blame::RX_MESSAGES_OFFSET_TN
                } else {
                    blame::RX_MESSAGES_OFFSET
                };
                Some(shifted(bytes, region, candidates, d))
            })
            .or_else(|| {
                let d = self.info_data(&e, &a)?;
                let region = layout.info_data_start()..expected.len();
                Some(shifted(bytes, region, blame::INFO_DATA_OFFSET, d))
            })
    }

    fn header(
        &self,
        e: &InputImage<&[u8]>,
        a: &InputImage<&[u8]>,
        unread: bool,
    ) -> Option<Difference> {
        let (e_image, a_image) = (e, a);
        let (e, a) = (e.header(), a.header());
        let handshake = self.handshake;
        if e.tx_counter != a.tx_counter {
            return Some(Difference {
                frames: None,
                candidates: if handshake.no_of_tx_messages == 0 {
                    blame::TX_EMPTY_BATCH
                } else if a.tx_counter != handshake.tx_before
                    && a.tx_counter != handshake.tx_requested
                {
                    blame::TX_ACKNOWLEDGE_VALUE
                } else {
                    blame::TX_COUNTER
                },
                what: "Inputs.TxCounter".into(),
                expected: e.tx_counter.to_string(),
                actual: a.tx_counter.to_string(),
            });
        }
        if e.rx_counter != a.rx_counter {
            let (model_moved, iut_moved) = (
                e.rx_counter != handshake.rx_before,
                a.rx_counter != handshake.rx_before,
            );
            let released = handshake.fast || handshake.plc_released == handshake.rx_before;
            let candidates = match (model_moved, iut_moved) {
                (false, true) if !released => blame::RX_UNRELEASED,
                (false, true) if a.no_of_rx_messages == 0 => blame::RX_EMPTY_DELIVERY,
                (false, true) => self
                    .filter_statement_of(a_image)
                    .unwrap_or(blame::RX_ADMISSION),
                (true, false) if handshake.rx_before == u16::MAX => blame::RX_COUNTING,
                (true, false) if handshake.fast => blame::RX_WITHHELD_FAST,
                (true, false) => self
                    .filter_statement_of(e_image)
                    .unwrap_or(blame::RX_WITHHELD),
                _ => blame::RX_COUNTING,
            };
            return Some(Difference {
                frames: None,
                candidates,
                what: "Inputs.RxCounter".into(),
                expected: format!(
                    "{} (was {}, Outputs.RxCounter {})",
                    e.rx_counter, handshake.rx_before, handshake.plc_released
                ),
                actual: a.rx_counter.to_string(),
            });
        }
        if unread && self.declared.idle_count && e.no_of_rx_messages != a.no_of_rx_messages {
            return Some(Difference {
                frames: None,
                candidates: blame::RX_IDLE_COUNT,
                what: "Inputs.NoOfRxMessages with nothing new (rx-idle-count as declared)".into(),
                expected: e.no_of_rx_messages.to_string(),
                actual: a.no_of_rx_messages.to_string(),
            });
        }
        if !unread && e.no_of_rx_messages != a.no_of_rx_messages {
            return Some(Difference {
                frames: None,
                candidates: blame::RX_SET,
                what: "Inputs.NoOfRxMessages".into(),
                expected: e.no_of_rx_messages.to_string(),
                actual: a.no_of_rx_messages.to_string(),
            });
        }
        if e.transaction_number != a.transaction_number {
            return Some(Difference {
                frames: None,
                // A message handed over and not yet complete on the bus:
                // "sent" read as G6 does not read it (TN-003 alone).
                candidates: match a.transaction_number {
                    Some(n) if (self.waiting_to_send)(n) => blame::TRANSACTION_NUMBER_EARLY,
                    _ => blame::TRANSACTION_NUMBER,
                },
                what: "Inputs.TransactionNumber".into(),
                expected: e.transaction_number.unwrap_or(0).to_string(),
                actual: a.transaction_number.unwrap_or(0).to_string(),
            });
        }
        None
    }

    /// The filter statement deciding the messages `image` delivers, all
    /// taken or all held back: the narrowest that decides every one of them
    /// (an edge that is also an overlap names both, and the others say
    /// which), else the first message's.
    fn filter_statement_of(&self, image: &InputImage<&[u8]>) -> Option<&'static [ReqId]> {
        let count = usize::from(image.no_of_rx_messages()).min(self.layout.rx_slots);
        let statements: Vec<&'static [ReqId]> = (0..count)
            .filter_map(|slot| image.rx_message(slot))
            .filter_map(|view| MessageRepr::parse(&view).ok())
            .filter_map(|message| blame::filter_statement(self.filters, message.frame.id))
            .collect();
        let in_all = |s: &&[ReqId]| {
            statements
                .iter()
                .all(|other| s.iter().all(|id| other.contains(id)))
        };
        statements
            .iter()
            .copied()
            .filter(in_all)
            .min_by_key(|s| s.len())
            .or_else(|| statements.first().copied())
    }

    fn messages(&self, e: &InputImage<&[u8]>, a: &InputImage<&[u8]>) -> Option<Difference> {
        let in_use = usize::from(e.no_of_rx_messages());
        for slot in 0..in_use.min(self.layout.rx_slots) {
            let (Some(es), Some(as_)) = (e.rx_message(slot), a.rx_message(slot)) else {
                continue;
            };
            if es.as_bytes() == as_.as_bytes() {
                continue;
            }
            let Some(candidates) = self.slot_difference(&es, &as_) else {
                continue; // only don't-care bytes (data past the length) differ
            };
            return Some(Difference {
                frames: None,
                candidates,
                what: format!("Inputs.RxMessage[{slot}]"),
                expected: describe_slot(&es),
                actual: describe_slot(&as_),
            });
        }
        // Past NoOfRxMessages only what the device declared is judged (and
        // never in the Fast CAN Queue's 3-buffer mode, G5).
        if !self.declared.stale_slots || self.handshake.fast {
            return None;
        }
        (in_use..self.layout.rx_slots).find_map(|slot| {
            let (es, as_) = (e.rx_message(slot)?, a.rx_message(slot)?);
            (es.as_bytes() != as_.as_bytes() && self.slot_difference(&es, &as_).is_some()).then(
                || Difference {
                    frames: None,
                    candidates: blame::RX_STALE_SLOTS,
                    what: format!(
                        "Inputs.RxMessage[{slot}] past NoOfRxMessages (stale-rx-slots as declared)"
                    ),
                    expected: hex(es.as_bytes()),
                    actual: hex(as_.as_bytes()),
                },
            )
        })
    }

    /// The requirements of the first field in which two slots differ; `None`
    /// when only don't-care bytes do.
    fn slot_difference(
        &self,
        e: &MessageView<&[u8]>,
        a: &MessageView<&[u8]>,
    ) -> Option<&'static [ReqId]> {
        let message = e.layout();
        let parsed = |v: &MessageView<&[u8]>| MessageRepr::parse(v).ok().map(|m| m.frame);
        let data_len = parsed(e).map_or(0, |f| f.data().len());
        let different_frame = match (parsed(e), parsed(a)) {
            (Some(expected), Some(actual)) => {
                expected != actual && (self.received)(&actual).is_some()
            }
            _ => false,
        };
        // Which frames a full queue loses (with the Fast CAN Queue a loss is
        // a cycle's overflow, not a queue's order): the device kept one the
        // model's tail drop lost, or, after an overflow, misses one the model
        // queued with places to spare - which no queue a place shorter drops
        // on arrival, so the device evicted it later.
        let taken = |frame: Option<Frame>| frame.and_then(|f| (self.received)(&f));
        let kept_what_the_model_dropped = different_frame
            && !self.handshake.fast
            && (taken(parsed(a)) == Some(Taken::Lost)
                || (self.overflowed && taken(parsed(e)) == Some(Taken::WithRoom)));
        // A frame the table holds back, let through; else one it lets
        // through, missing: the filter statement deciding it.
        let filtered = match (parsed(e), parsed(a)) {
            (Some(expected), Some(actual)) if different_frame => {
                match filter::accepts(self.filters, actual.id) {
                    false => blame::filter_statement(self.filters, actual.id),
                    true => blame::filter_statement(self.filters, expected.id),
                }
            }
            _ => None,
        };
        let has_own_length = !matches!(message.length, LengthField::InCobIdWord);
        Some(if kept_what_the_model_dropped {
            blame::RX_DROP_POLICY
        } else if let Some(statement) = filtered {
            statement
        } else if different_frame {
            blame::RX_SET
        } else if message.cob_id.len() == 2 && e.cob_id_word() != a.cob_id_word() {
            if e.cob_id_word().0.swap_bytes() == a.cob_id_word().0 {
                blame::BYTE_ORDER
            } else {
                blame::COB_WORD
            }
        } else if message.cob_id.len() == 4 && e.cob_id32() != a.cob_id32() {
            let diff = e.cob_id32().0 ^ a.cob_id32().0;
            if diff & 0x8000_0000 != 0 {
                blame::COB_FORMAT
            } else if diff & 0x4000_0000 != 0 {
                blame::COB_RTR
            } else {
                blame::COB_LOW
            }
        } else if has_own_length && e.raw_length() != a.raw_length() {
            let dlc = u8::try_from(e.raw_length()).ok().and_then(dlc::fd_dlc);
            if message.flags.is_some() && dlc.map(u16::from) == Some(a.raw_length()) {
                blame::RX_LENGTH_AS_DLC
            } else {
                blame::LENGTH
            }
        } else if message.flags.is_some() && e.flags() != a.flags() {
            blame::FLAGS
        } else if e.data_field()[..data_len] != a.data_field()[..data_len] {
            blame::RX_SET
        } else if message.time_stamp.is_some()
            && e.time_stamp().abs_diff(a.time_stamp()) > self.time_stamp_tolerance
        {
            blame::TIME_STAMP
        } else {
            return None;
        })
    }

    fn info_data(&self, e: &InputImage<&[u8]>, a: &InputImage<&[u8]>) -> Option<Difference> {
        (0..field::INFO_DATA_WORDS).find_map(|index| {
            let (expected, actual) = (e.info_data(index)?, a.info_data(index)?);
            (expected != actual).then(|| Difference {
                frames: None,
                candidates: blame::info_data(index, self.controller_reported),
                what: format!("InfoData[{index}]"),
                expected: format!("0x{expected:08X}"),
                actual: format!("0x{actual:08X}"),
            })
        })
    }
}

/// Whether the IUT decoded `frame` from the output image at another message
/// structure's stride and offsets (LAY-GEN-006, LAY-GEN-002): it is the slot
/// the model sent `expected` from, read with another structure; or, where
/// the model sent nothing, a slot of one of `batches` read so that no slot
/// holds with the interface's own structure. A frame a slot holds as it is
/// (one past NoOfTxMessages, say) is another fault.
pub fn read_with_another_structure(
    layout: &ImageLayout,
    batches: &[&[u8]],
    expected: Option<&Frame>,
    frame: &Frame,
) -> bool {
    let Some(first) = (layout.tx_slots > 0).then(|| layout.tx_slot(0).start) else {
        return false;
    };
    // Read as a device that trusts the fields would.
    let read = |outputs: &[u8], structure: &'static MessageLayout, slot: usize| {
        let at = first + slot * structure.size;
        outputs
            .get(at..at + structure.size)
            .and_then(|bytes| MessageView::new_checked(bytes, structure).ok())
            .map(|view| MessageRepr::parse_clamped(&view).0.frame)
    };
    let own = layout.tx_message;
    let others = || {
        MessageLayout::ALL
            .iter()
            .filter(move |other| other.name != own.name)
    };
    if let Some(expected) = expected {
        return batches.iter().any(|outputs| {
            (0..layout.tx_slots).any(|slot| {
                read(outputs, own, slot) == Some(*expected)
                    && others().any(|other| read(outputs, other, slot) == Some(*frame))
            })
        });
    }
    // Only the slots a batch asks for: a zeroed slot past them reads as a
    // frame with every structure, and so does an empty frame on identifier 0.
    let asked = |outputs: &[u8]| {
        OutputImage::new_checked(outputs, *layout).map_or(0, |o| {
            usize::from(o.no_of_tx_messages()).min(layout.tx_slots)
        })
    };
    let holds = |structure: &'static MessageLayout| {
        batches.iter().any(|outputs| {
            (0..asked(outputs)).any(|slot| read(outputs, structure, slot) == Some(*frame))
        })
    };
    let zeroes = frame.id.raw() == 0 && frame.data().is_empty() && !frame.is_remote();
    !zeroes && !holds(own) && others().any(|other| holds(other))
}

/// The requirements of the first property in which a frame handed to the
/// controller differs from the model's; the frame is no real message sent
/// out of turn, so a different identifier was decoded from the wrong bits of
/// the Tx message's COB ID (`word`: the 11-bit COB ID word).
pub fn frame_difference(expected: &Frame, actual: &Frame, word: bool) -> &'static [ReqId] {
    if expected.id != actual.id {
        let (e, a) = (expected.id.raw(), actual.id.raw());
        return if e == a {
            blame::TX_FORMAT
        } else if expected.data() != actual.data() {
            blame::TX_OTHER_FRAME
        } else if word {
            blame::TX_ID_WORD
        } else if !expected.id.is_extended() && a & 0x7FF == e && a > 0x7FF {
            blame::TX_ID_RESERVED
        } else {
            blame::TX_ID_29
        };
    }
    if expected.is_remote() != actual.is_remote() {
        return blame::TX_REMOTE;
    }
    if expected.is_fd() != actual.is_fd() {
        return blame::TX_FORMAT;
    }
    if expected.kind != actual.kind {
        return blame::TX_FD_FLAGS;
    }
    if expected.len() != actual.len() {
        return blame::TX_LENGTH;
    }
    if expected.is_fd() {
        return blame::TX_PADDING;
    }
    blame::TX_DATA
}

#[cfg(test)]
mod tests;
