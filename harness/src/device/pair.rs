//! The model and the implementation under test side by side: whatever
//! happens to one happens to the other, and whatever they do differently is a
//! [`Difference`]. Buses drive a `Pair`; they never touch the two devices
//! directly.

use canif_model::device::{Device, RxOutcome};
use canif_model::frame::Frame;
use canif_model::image::{ImageLayout, LengthField, OutputImage};
use canif_model::Nanos;
use canif_spec::ReqId;

use crate::bus::sim::Controller;
use crate::device::blame;
use crate::device::bounds::Bounds;
use crate::device::diff::{frame_difference, read_with_another_structure, Difference};
use crate::device::history::{History, Taken};
use crate::device::sync1_window::{Held, Moment, Sync1Window};
use crate::door::iut::{InvalidFrame, Iut};
use crate::outcome::{Failure, FrameDiff, Outcome};
use crate::run::Ring;
use crate::trace::TraceWriter;

/// How many recent batches a frame is looked for in, read at another stride.
const BATCHES: usize = 8;

/// The IUT broke: the scenario ends in error, whatever the model expected.
pub(crate) fn iut_broke(error: crate::error::IutError) -> Outcome {
    Outcome::Error(error.into())
}

/// The two devices of one scenario and what has been seen of them.
pub struct Pair {
    pub iut: Box<dyn Iut>,
    pub model: Device,
    pub layout: ImageLayout,
    /// The frame both devices handed to their controllers, not yet on the bus.
    pub iut_pending: Option<Frame>,
    /// The IUT's controller holds a frame, waiting or on the wire, until it
    /// completes: it is not idle, so it is not polled.
    iut_busy: bool,
    /// Bounds judging (G3) instead of the model's frames and images, when
    /// the scenario asks for it.
    pub bounds: Option<Bounds>,
    /// With Distributed Clocks, where the IUT's first Tx message may start.
    pub sync1: Sync1Window,
    /// When the IUT's last frame ended: a controller busy at SYNC1 starts later.
    own_frame_ended: Nanos,
    /// Scenario time.
    pub now: Nanos,
    pub cycle: u64,
    /// Frames that ended on the bus and were checked.
    pub frames: u64,
    /// Observations in which the IUT differed from the model only where the
    /// documents leave it open (see [`crate::ScenarioRun::tolerated`]).
    pub tolerated: u64,
    pub history: History,
    /// Every frame that ended on the bus (whether the IUT sent it, its end),
    /// kept only for a caller that reads them (a Gherkin world's steps).
    pub ended: Option<Vec<(Frame, bool, Nanos)>>,
    /// The output images of the last batches handed over, to tell a frame
    /// read at the wrong stride from another wrong frame.
    batches: Ring<Vec<u8>>,
    trace: Option<TraceWriter>,
    scenario: String,
    covers: Vec<ReqId>,
}

impl Pair {
    pub fn new(
        iut: Box<dyn Iut>,
        model: Device,
        (scenario, covers): (&str, &[ReqId]),
        trace: Option<TraceWriter>,
    ) -> Self {
        Pair {
            iut,
            layout: model.layout(),
            model,
            iut_pending: None,
            iut_busy: false,
            bounds: None,
            sync1: Sync1Window::default(),
            own_frame_ended: 0,
            now: 0,
            cycle: 0,
            frames: 0,
            tolerated: 0,
            history: History::default(),
            ended: None,
            batches: Ring::new(BATCHES),
            trace,
            scenario: scenario.to_string(),
            covers: covers.to_vec(),
        }
    }

    /// The PLC's output image of this cycle: kept when it hands over a new batch.
    pub fn outputs(&mut self, outputs: &[u8]) {
        let counter = |bytes: &[u8]| {
            OutputImage::new_checked(bytes, self.layout).map_or(None, |o| Some(o.tx_counter()))
        };
        let last = self.batches.iter().last().and_then(|b| counter(b));
        if counter(outputs).is_some() && counter(outputs) != last {
            self.batches.push(outputs.to_vec());
        }
    }

    /// Whether the IUT's frame is a slot of a recent batch read with another
    /// message structure's stride and offsets.
    fn misread(&self, expected: Option<&Frame>, frame: &Frame) -> bool {
        let batches: Vec<&[u8]> = self.batches.iter().map(Vec::as_slice).collect();
        read_with_another_structure(&self.layout, &batches, expected, frame)
    }

    /// A difference as the failure of this scenario, with its history. The
    /// IUT's differing frame goes into the trace, which so ends with it.
    pub fn fail(&mut self, difference: Difference) -> Outcome {
        if let (
            Some(trace),
            Some(FrameDiff {
                actual: Some(frame),
                ..
            }),
        ) = (self.trace.as_mut(), difference.frames.as_deref())
        {
            let requirements = blame::narrow(&self.covers, difference.candidates);
            let comment = format!(
                "canif FAIL {}: cycle {}: {}: expected {}, actual {}",
                ReqId::join(&requirements, ", "),
                self.cycle,
                difference.what,
                difference.expected,
                difference.actual
            );
            let _ = trace.failing_frame(self.now, frame, &comment);
        }
        Outcome::Fail(Box::new(Failure {
            requirements: blame::narrow(&self.covers, difference.candidates),
            scenario: self.scenario.clone(),
            cycle: self.cycle,
            time: self.now,
            what: difference.what,
            expected: difference.expected,
            actual: difference.actual,
            context: {
                // The PLC side judges on after a breach; a device cannot be.
                let mut context = self.history.context();
                context.push(
                    "(the scenario stops here: the model's state has left the IUT's, so what the IUT does next cannot be judged against it)"
                        .into(),
                );
                context
            },
            timeline: crate::outcome::Timeline::Cycles(self.history.timeline()),
            frames: difference.frames.map(|f| *f),
            images: None,
            rest: crate::verdict::Rest::Stopped,
            further: Vec::new(),
        }))
    }

    /// Asks both devices for their next frame when the controller is free.
    pub fn poll(&mut self) -> Result<(), Outcome> {
        if self.iut_busy {
            return Ok(());
        }
        let actual = self.iut.poll_transmit(self.now).map_err(iut_broke)?;
        let judged = match self.bounds.as_mut() {
            Some(bounds) => bounds.transmit(actual, self.layout.is_fd()),
            None => {
                // Distributed Clocks: the first message of a batch waits for
                // SYNC1 and the device's output delay (003, R10).
                let sync1 = self.model.poll_timeout();
                let expected = match sync1 {
                    Some(due) => match self.held_for_sync1(due, actual.is_some()) {
                        Ok(expected) => expected,
                        Err(difference) => return Err(self.fail(difference)),
                    },
                    None => self.model.poll_transmit(self.now),
                };
                let nothing_sent = actual.is_none();
                self.transmit_difference(expected, actual)
                    .map_err(|d| self.at_sync1(sync1.is_some(), nothing_sent, d))
            }
        };
        match judged {
            Ok(frame) => {
                self.iut_busy = frame.is_some();
                self.iut_pending = frame;
                Ok(())
            }
            Err(difference) => Err(self.fail(difference)),
        }
    }

    /// What the model hands its controller of a batch held for SYNC1 at
    /// `due`, now that the IUT has `sent` its first frame or not
    /// ([`Sync1Window`]).
    fn held_for_sync1(&mut self, due: Nanos, sent: bool) -> Result<Option<Frame>, Difference> {
        let moment = Moment {
            now: self.now,
            due,
            sent,
            iut_holds: self.iut.poll_timeout().is_some(),
            controller_was_free: self.own_frame_ended <= due,
        };
        match self.sync1.decide(moment)? {
            Held::Wait => Ok(None),
            Held::Release { exact } => {
                self.tolerated += u64::from(!exact);
                Ok(self.model.poll_transmit(self.now))
            }
        }
    }

    /// The output delay the IUT is judged by: declared, or the shortest
    /// measured so far (R10); `None` before any batch was held for SYNC1.
    pub fn sync1_output_delay(&self) -> Option<Nanos> {
        self.sync1.output_delay()
    }

    /// The frame both devices agree to send (or none), or how they differ.
    pub fn transmit_difference(
        &self,
        expected: Option<Frame>,
        actual: Option<Result<Frame, InvalidFrame>>,
    ) -> Result<Option<Frame>, Difference> {
        // Called at every poll: agreement returns before anything is built.
        match (&expected, &actual) {
            (None, None) => return Ok(None),
            (Some(e), Some(Ok(a))) if e == a => return Ok(Some(*a)),
            _ => {}
        }
        let what = "frame handed to the controller".to_string();
        let frames = FrameDiff {
            expected,
            actual: actual.as_ref().and_then(|a| a.as_ref().ok().copied()),
        };
        let mut difference = match (expected, actual) {
            (None, None) => unreachable!("agreement returned above"),
            (Some(e), Some(Ok(a))) => {
                // A frame the model still holds is a real message sent out of turn.
                let queued_later = self.model.send_queue().any(|f| *f == a);
                Difference {
                    frames: None,
                    candidates: if queued_later {
                        blame::TX_OTHER_FRAME
                    } else if self.misread(Some(&e), &a) {
                        blame::TX_STRIDE
                    } else {
                        frame_difference(
                            &e,
                            &a,
                            matches!(self.layout.tx_message.length, LengthField::InCobIdWord),
                        )
                    },
                    what,
                    expected: e.to_string(),
                    actual: a.to_string(),
                }
            }
            (e, Some(Err(invalid))) => Difference {
                frames: None,
                candidates: blame::invalid_frame(&invalid, self.layout.is_fd()),
                what,
                expected: e.map_or("no frame".into(), |f| f.to_string()),
                actual: format!("invalid frame: {invalid}"),
            },
            (Some(e), None) => Difference {
                frames: None,
                candidates: blame::TX_MISSING,
                what,
                expected: e.to_string(),
                actual: "no frame".into(),
            },
            (None, Some(Ok(a))) => Difference {
                frames: None,
                candidates: if self.misread(None, &a) {
                    blame::TX_STRIDE
                } else {
                    blame::TX_EXTRA
                },
                what,
                expected: "no frame".into(),
                actual: a.to_string(),
            },
        };
        difference.frames = Some(Box::new(frames));
        Err(difference)
    }

    /// A Tx difference while the model holds a batch for SYNC1 is a timing
    /// one (PDX-004) when the IUT holds its first message past the jitter
    /// (it has a due time of its own) or sends the held message before it.
    fn at_sync1(&self, held: bool, nothing_sent: bool, d: Difference) -> Difference {
        let frames = d.frames.as_deref();
        let (candidates, what) = match frames {
            _ if !held => return d,
            Some(FrameDiff {
                expected: Some(_), ..
            }) if nothing_sent && self.iut.poll_timeout().is_some() => {
                (blame::SYNC1_LATE, "first frame of the batch after SYNC1")
            }
            Some(FrameDiff {
                expected: None,
                actual: Some(sent),
            }) if self.model.send_queue().next() == Some(sent) => {
                (blame::SYNC1_EARLY, "first frame of the batch before SYNC1")
            }
            _ => return d,
        };
        Difference {
            candidates,
            what: what.into(),
            ..d
        }
    }

    /// When the controller must be asked again: the IUT's own due time, or the
    /// latest the model's SYNC1 and the output delay allow, whichever comes first.
    pub fn due(&self) -> Option<Nanos> {
        let deadline = match self.bounds {
            Some(_) => None,
            None => self.model.poll_timeout().map(|t| self.sync1.deadline(t)),
        };
        [self.iut.poll_timeout(), deadline]
            .into_iter()
            .flatten()
            .min()
    }

    /// A frame ended on the bus, and the IUT's controller learns of it.
    pub fn complete(&mut self, frame: Frame, from_iut: bool, end: Nanos) -> Result<(), Outcome> {
        let told = if from_iut {
            self.iut_busy = false;
            self.own_frame_ended = end;
            self.iut.transmit_complete()
        } else {
            self.iut.receive(&frame, end)
        };
        told.map_err(iut_broke)?;
        self.observe(frame, from_iut, end);
        Ok(())
    }

    /// A frame ended on the bus: the model, the trace and the history learn of it.
    pub fn observe(&mut self, frame: Frame, from_iut: bool, end: Nanos) {
        self.frames += 1;
        if let Some(trace) = self.trace.as_mut() {
            if trace.frame(end, &frame, from_iut).is_err() {
                self.trace = None; // a full disk ends the trace, not the run
            }
        }
        let taken = if from_iut {
            self.model.handle_transmit_complete();
            None
        } else {
            let room = self.model.rx_room();
            Some(match self.model.handle_received(frame, end) {
                RxOutcome::Queued if room > 1 => Taken::WithRoom,
                RxOutcome::Queued => Taken::LastPlace,
                RxOutcome::Lost => Taken::Lost,
                RxOutcome::Filtered | RxOutcome::NotRepresentable => Taken::Held,
            })
        };
        self.history.frame(self.cycle, frame, end, taken);
        if let Some(ended) = self.ended.as_mut() {
            ended.push((frame, from_iut, end));
        }
    }

    /// Closes the trace files.
    pub fn finish(&mut self) {
        if let Some(trace) = self.trace.take() {
            let _ = trace.finish();
        }
    }
}

impl Controller for Pair {
    type Error = Outcome;
    fn now(&mut self) -> &mut Nanos {
        &mut self.now
    }
    fn pending(&mut self) -> &mut Option<Frame> {
        &mut self.iut_pending
    }
    fn poll(&mut self) -> Result<(), Outcome> {
        Pair::poll(self)
    }
    fn due(&self) -> Option<Nanos> {
        Pair::due(self)
    }
    fn ended(&mut self, frame: Frame, own: bool, end: Nanos) -> Result<(), Outcome> {
        self.complete(frame, own, end)
    }
    fn stalled(&self, steps: usize) -> Outcome {
        Outcome::Error(
            crate::error::IutError::new(
                crate::error::IutCause::Impossible,
                format!(
                    "the IUT asked to be polled {steps} times within one cycle: its due time \
                 (next_ns {:?}) does not advance past {} ns",
                    self.iut.poll_timeout(),
                    self.now
                ),
            )
            .into(),
        )
    }
}

#[cfg(test)]
mod tests {
    use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig};
    use canif_model::frame::CanId;
    use canif_model::info_data::ControllerStatus;

    use canif_model::image::MessageRepr;

    use super::*;
    use crate::door::iut::Transmit;

    /// A device that offers one frame to its controller whenever polled.
    struct Babbler(Frame);

    impl Iut for Babbler {
        fn cycle(&mut self, _: &[u8], _: Nanos) -> Result<Vec<u8>, crate::error::IutError> {
            Ok(Vec::new())
        }
        fn receive(&mut self, _: &Frame, _: Nanos) -> Result<(), crate::error::IutError> {
            Ok(())
        }
        fn poll_transmit(&mut self, _: Nanos) -> Result<Transmit, crate::error::IutError> {
            Ok(Some(Ok(self.0)))
        }
        fn poll_timeout(&self) -> Option<Nanos> {
            None
        }
        fn transmit_complete(&mut self) -> Result<(), crate::error::IutError> {
            Ok(())
        }
        fn controller_status(
            &mut self,
            _: &ControllerStatus,
        ) -> Result<(), crate::error::IutError> {
            Ok(())
        }
    }

    /// A 29-bit interface with transaction numbers; its batch holds `message`
    /// in slot 0.
    fn pair_with_a_batch(message: MessageRepr) -> Pair {
        let mut config = InterfaceConfig::new(FrameFormat::Extended29, 4);
        config.transaction_number = true;
        let model = Device::new(&Capabilities::everything(), config).unwrap();
        let covers = canif_spec::req_ids!["HS-TX-006"];
        let mut pair = Pair::new(Box::new(Babbler(frame())), model, ("stride", covers), None);
        let mut outputs = vec![0; pair.layout.output_size()];
        let mut image = OutputImage::new_checked(&mut outputs[..], pair.layout).unwrap();
        image.set_tx_counter(1);
        image.set_no_of_tx_messages(1);
        message.emit(&mut image.tx_message_mut(0).unwrap()).unwrap();
        pair.outputs(&outputs);
        pair
    }

    #[test]
    fn a_frame_read_at_another_structures_stride_is_blamed_on_the_layout() {
        let sent = MessageRepr {
            transaction_number: 0x0102,
            frame: Frame::classic(CanId::Extended(0x0ABC_DEF0 & 0x1FFF_FFFF), &[1, 2, 3]).unwrap(),
            time_stamp: 0,
        };
        let pair = pair_with_a_batch(sent);
        // What an IUT that skips the transaction number reads from slot 0.
        let start = pair.layout.tx_slot(0).start;
        let mut outputs = vec![0; pair.layout.output_size()];
        let mut image = OutputImage::new_checked(&mut outputs[..], pair.layout).unwrap();
        sent.emit(&mut image.tx_message_mut(0).unwrap()).unwrap();
        let other = &canif_model::image::MessageLayout::EXT29;
        let view = canif_model::image::MessageView::new_checked(
            &outputs[start..start + other.size],
            other,
        )
        .unwrap();
        let misread = MessageRepr::parse_clamped(&view).0.frame;
        assert_ne!(misread, sent.frame);
        let difference = pair
            .transmit_difference(Some(sent.frame), Some(Ok(misread)))
            .unwrap_err();
        assert_eq!(difference.candidates, blame::TX_STRIDE);
        // Another wrong frame is not the layout's.
        let other_frame = Frame::classic(CanId::Extended(0x42), &[9]).unwrap();
        let difference = pair
            .transmit_difference(Some(sent.frame), Some(Ok(other_frame)))
            .unwrap_err();
        assert_ne!(difference.candidates, blame::TX_STRIDE);
    }

    fn pair(iut: Box<dyn Iut>) -> Pair {
        let config = InterfaceConfig::new(FrameFormat::Base11, 4);
        let model = Device::new(&Capabilities::everything(), config).unwrap();
        let covers = canif_spec::req_ids!["HS-TX-006"];
        Pair::new(iut, model, ("babble", covers), None)
    }

    fn frame() -> Frame {
        Frame::classic(CanId::Standard(0x55), &[1]).unwrap()
    }

    #[test]
    fn a_frame_the_model_does_not_send_fails_on_what_the_scenario_exercises_of_it() {
        let mut pair = pair(Box::new(Babbler(frame())));
        let Err(Outcome::Fail(failure)) = pair.poll() else {
            panic!("an extra frame passed")
        };
        assert_eq!(failure.requirements, canif_spec::req_ids!["HS-TX-006"]);
        assert_eq!(failure.what, "frame handed to the controller");
        assert_eq!(failure.expected, "no frame");
    }

    #[test]
    fn agreement_hands_the_frame_on_and_each_disagreement_has_its_blame() {
        let pair = pair(Box::new(Babbler(frame())));
        assert_eq!(pair.transmit_difference(None, None), Ok(None));
        assert_eq!(
            pair.transmit_difference(Some(frame()), Some(Ok(frame()))),
            Ok(Some(frame()))
        );
        let missing = pair.transmit_difference(Some(frame()), None).unwrap_err();
        assert_eq!(missing.candidates, blame::TX_MISSING);
        let invalid = pair
            .transmit_difference(None, Some(Err(InvalidFrame::Declared("36 bytes".into()))))
            .unwrap_err();
        assert_eq!(invalid.candidates, blame::TX_INVALID);
        assert_eq!(invalid.actual, "invalid frame: 36 bytes");
        // What no controller can send is blamed on where it came from.
        let brs = InvalidFrame::FdBitsOnClassic {
            brs: true,
            esi: false,
        };
        let flags = pair.transmit_difference(None, Some(Err(brs))).unwrap_err();
        assert_eq!(flags.candidates, blame::TX_FD_FLAGS);
        let too_wide = InvalidFrame::Identifier {
            id: 0x1234,
            extended: false,
        };
        let identifier = pair
            .transmit_difference(None, Some(Err(too_wide)))
            .unwrap_err();
        assert_eq!(identifier.candidates, blame::TX_ID_RESERVED);
    }

    /// R10 without a declared delay: the first start sets it, later starts
    /// the controller was free for must lie within 500 ns of it; a declared
    /// delay makes an earlier start early.
    #[test]
    fn an_undeclared_output_delay_is_measured_and_held_within_the_jitter() {
        let mut pair = pair(Box::new(Babbler(frame())));
        let sync1 = 1_000_000;
        pair.now = sync1 + 2_000;
        assert!(
            pair.held_for_sync1(sync1, true).is_ok(),
            "the first start sets 2 µs"
        );
        assert_eq!(pair.sync1_output_delay(), Some(2_000));
        pair.now = 2 * sync1 + 2_400;
        assert!(
            pair.held_for_sync1(2 * sync1, true).is_ok(),
            "400 ns later: jitter"
        );
        pair.now = 3 * sync1 + 2_600;
        let wide = pair.held_for_sync1(3 * sync1, true).unwrap_err();
        assert_eq!(wide.candidates, blame::SYNC1_LATE);
        assert_eq!(wide.actual, "2600 ns after SYNC1");
        // A controller still sending at SYNC1 starts later: that says nothing.
        pair.own_frame_ended = 4 * sync1 + 50_000;
        pair.now = 4 * sync1 + 50_000;
        assert!(pair.held_for_sync1(4 * sync1, true).is_ok());
        // Declared: before the delay is early, the frame not expected yet.
        pair.sync1.delay = Some(10_000);
        pair.own_frame_ended = 0;
        pair.now = 5 * sync1 + 1_000;
        assert_eq!(pair.held_for_sync1(5 * sync1, true), Ok(None));
    }
}
