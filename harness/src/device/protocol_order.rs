//! The promises docs/adapter-protocol.md makes to an IUT about the harness's
//! own requests, held on every request: times never go back, and
//! `poll_transmit` is asked only of an idle controller (a frame handed out is
//! completed before the next is asked for). A device written from the
//! document may rely on both, so a harness that breaks them would fail a
//! conforming device; [`Ordered`] turns such a harness bug into an error that
//! names it instead.

use canif_model::frame::Frame;
use canif_model::info_data::ControllerStatus;
use canif_model::Nanos;

use crate::door::iut::{Iut, Planned, Transmit};
use crate::error::{IutCause, IutError};

/// An IUT whose requests are checked against the protocol's promises before
/// they reach it.
pub struct Ordered {
    inner: Box<dyn Iut>,
    /// The latest time any request carried.
    latest: Nanos,
    /// A frame was handed out and not yet completed.
    busy: bool,
}

impl Ordered {
    pub fn new(inner: Box<dyn Iut>) -> Self {
        Ordered {
            inner,
            latest: 0,
            busy: false,
        }
    }

    fn at(&mut self, request: &str, time: Nanos) -> Result<(), IutError> {
        if time < self.latest {
            return Err(broken(format!(
                "{request} at {time} ns after a request at {} ns (times are non-decreasing)",
                self.latest
            )));
        }
        self.latest = time;
        Ok(())
    }
}

fn broken(what: String) -> IutError {
    IutError::new(
        IutCause::HarnessBug,
        format!("harness bug: the harness broke docs/adapter-protocol.md: {what}"),
    )
}

impl Iut for Ordered {
    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        self.at("cycle", now)?;
        self.inner.cycle(outputs, now)
    }

    fn announce_cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<(), IutError> {
        // Held to the promises by `cycle`, which collects it.
        self.inner.announce_cycle(outputs, now)
    }

    fn receive(&mut self, frame: &Frame, end_of_reception: Nanos) -> Result<(), IutError> {
        self.at("receive", end_of_reception)?;
        self.inner.receive(frame, end_of_reception)
    }

    fn poll_transmit(&mut self, now: Nanos) -> Result<Transmit, IutError> {
        if self.busy {
            return Err(broken(format!(
                "poll_transmit at {now} ns while the controller's frame is still on the \
                 wire (poll means the controller is idle)"
            )));
        }
        self.at("poll_transmit", now)?;
        let transmit = self.inner.poll_transmit(now)?;
        self.busy = transmit.is_some();
        Ok(transmit)
    }

    fn poll_timeout(&self) -> Option<Nanos> {
        self.inner.poll_timeout()
    }

    fn transmit_complete(&mut self) -> Result<(), IutError> {
        if !self.busy {
            return Err(broken(
                "transmit_complete with no frame handed out".to_string(),
            ));
        }
        self.busy = false;
        self.inner.transmit_complete()
    }

    fn controller_status(&mut self, status: &ControllerStatus) -> Result<(), IutError> {
        self.inner.controller_status(status)
    }

    fn transmit_plan(&self, now: Nanos, most: usize) -> Option<Vec<Planned>> {
        self.inner.transmit_plan(now, most)
    }
    fn telegrams(&mut self) -> Option<&mut dyn crate::door::iut::Telegrams> {
        self.inner.telegrams()
    }
    fn declared(&self) -> crate::declare::choices::Declared {
        self.inner.declared()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::IutKind;
    use canif_model::client::PlcClient;
    use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig};
    use canif_model::frame::CanId;
    use canif_model::image::{ImageLayout, MessageRepr};

    fn config() -> InterfaceConfig {
        InterfaceConfig::new(FrameFormat::Base11, 4)
    }

    fn ordered() -> Ordered {
        Ordered::new(
            IutKind::Model
                .build(&Capabilities::everything(), &config())
                .unwrap(),
        )
    }

    fn one_frame_to_send() -> Vec<u8> {
        let layout = ImageLayout::new(&config(), false);
        let mut client = PlcClient::new(layout);
        let frame = Frame::classic(CanId::Standard(1), &[]).unwrap();
        client
            .send(MessageRepr {
                transaction_number: 0,
                frame,
                time_stamp: 0,
            })
            .unwrap();
        client.task(&vec![0; layout.input_size()]).unwrap().to_vec()
    }

    #[test]
    fn a_time_that_goes_back_is_a_harness_bug() {
        let mut iut = ordered();
        let frame = Frame::classic(CanId::Standard(1), &[]).unwrap();
        iut.receive(&frame, 10_000).unwrap();
        let error = iut.cycle(&one_frame_to_send(), 0).unwrap_err();
        assert!(error.what.contains("non-decreasing"), "{}", error.what);
    }

    #[test]
    fn polling_a_busy_controller_is_a_harness_bug() {
        let mut iut = ordered();
        iut.cycle(&one_frame_to_send(), 0).unwrap();
        assert!(iut.poll_transmit(0).unwrap().is_some());
        let error = iut.poll_transmit(100).unwrap_err();
        assert!(error.what.contains("idle"), "{}", error.what);
        iut.transmit_complete().unwrap();
        assert!(iut.poll_transmit(200).unwrap().is_none());
    }

    #[test]
    fn completing_with_no_frame_handed_out_is_a_harness_bug() {
        let mut iut = ordered();
        assert!(iut.poll_transmit(0).unwrap().is_none());
        assert!(iut.transmit_complete().is_err());
    }
}
