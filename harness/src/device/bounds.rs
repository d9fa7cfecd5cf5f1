//! Judging by the bounds of G3, for input whose treatment the documents leave
//! to the implementer (NoOfTxMessages beyond the slots, a classic length above
//! 8, random output images): whatever the device does with it, it never puts
//! more frames on the bus than the slots of the batches it acknowledged
//! (HS-TX-010), never a frame that is no valid CAN frame (LAY-GEN-008,
//! FD-LEN-006), keeps its image's size, and still acknowledges what the PLC
//! writes afterwards.

use canif_model::frame::Frame;
use canif_model::image::{ImageLayout, InputImage, OutputImage};
use canif_spec::{req_ids, ReqId};

use crate::device::blame;
use crate::device::diff::{image_size, Difference};
use crate::door::iut::Transmit;

/// More frames than the acknowledged slots, or no acknowledge at the end.
const BEYOND_THE_SLOTS: &[ReqId] = req_ids!["HS-TX-010"];

/// The bounds a scenario's IUT is held to.
#[derive(Debug, Clone, Default)]
pub struct Bounds {
    /// Frames the acknowledged batches still allow on the bus.
    allowance: usize,
    /// The TxCounter the IUT acknowledged last, and the one the PLC wrote.
    acknowledged: u16,
    requested: u16,
}

impl Bounds {
    /// After a cycle: the image keeps its size, and a batch the IUT has just
    /// acknowledged allows at most the slots' number of frames.
    pub fn cycle(
        &mut self,
        layout: &ImageLayout,
        outputs: &[u8],
        actual: &[u8],
    ) -> Option<Difference> {
        let Ok(inputs) = InputImage::new_checked(actual, *layout) else {
            return Some(image_size(layout.input_size(), actual.len()));
        };
        let acknowledged = inputs.tx_counter();
        if let Ok(outputs) = OutputImage::new_checked(outputs, *layout) {
            self.requested = outputs.tx_counter();
        }
        if acknowledged != self.acknowledged {
            self.allowance += layout.tx_slots;
            self.acknowledged = acknowledged;
            // Whatever the device made of the batch, its acknowledge is a copy.
            if acknowledged != self.requested {
                return Some(Difference {
                    frames: None,
                    candidates: blame::TX_ACKNOWLEDGE_VALUE,
                    what: "Inputs.TxCounter".into(),
                    expected: format!("{} (Outputs.TxCounter) or unchanged", self.requested),
                    actual: acknowledged.to_string(),
                });
            }
        }
        None
    }

    /// A frame the IUT hands its controller: within the bounds, or how not.
    pub fn transmit(
        &mut self,
        actual: Transmit,
        fd_interface: bool,
    ) -> Result<Option<Frame>, Difference> {
        match actual {
            None => Ok(None),
            Some(Err(invalid)) => Err(Difference {
                frames: None,
                candidates: blame::invalid_frame(&invalid, fd_interface),
                what: "frame handed to the controller".into(),
                expected: "a valid CAN frame (at most 8 classic, 64 FD data bytes)".into(),
                actual: format!("invalid frame: {invalid}"),
            }),
            Some(Ok(frame)) if self.allowance == 0 => Err(Difference {
                frames: None,
                candidates: BEYOND_THE_SLOTS,
                what: "frames on the bus".into(),
                expected: "no more than the slots of the batches acknowledged".into(),
                actual: format!("one more: {frame}"),
            }),
            Some(Ok(frame)) => {
                self.allowance -= 1;
                Ok(Some(frame))
            }
        }
    }

    /// At the end: the last batch the PLC wrote was acknowledged (the
    /// interface kept cycling).
    pub fn still_cycling(&self) -> Option<Difference> {
        (self.requested != self.acknowledged).then(|| Difference {
            frames: None,
            candidates: BEYOND_THE_SLOTS,
            what: "Inputs.TxCounter at the end".into(),
            expected: format!("{} (the PLC's last batch acknowledged)", self.requested),
            actual: self.acknowledged.to_string(),
        })
    }
}
