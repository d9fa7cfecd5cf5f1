//! A simulated CAN bus in virtual time: frames take the time the model's bit
//! timing gives them, and among frames waiting when the bus goes idle the
//! lowest arbitration field wins.

use canif_model::frame::{CanId, Frame, FrameKind};
use canif_model::timing::{frame_duration, BitRates, Stuffing};
use canif_model::Nanos;

/// The bits a frame sends during arbitration, as a number: lower wins.
/// Standard: id(11) RTR IDE=0; extended: base(11) SRR=1 IDE=1 ext(18) RTR.
pub fn arbitration_key(frame: &Frame) -> u64 {
    let rtr = u64::from(matches!(frame.kind, FrameKind::Classic { rtr: true }));
    match frame.id {
        CanId::Standard(id) => (u64::from(id) << 21) | (rtr << 20),
        CanId::Extended(id) => {
            let base = u64::from(id >> 18);
            let ext = u64::from(id & 0x3_FFFF);
            (base << 21) | (1 << 20) | (1 << 19) | (ext << 1) | rtr
        }
    }
}

/// How long `frame` occupies the bus (nominal bit count, intermission included).
pub fn duration(frame: &Frame, rates: BitRates) -> Nanos {
    frame_duration(frame, rates, Stuffing::Nominal)
}

/// Other nodes' frames waiting for the bus, each ready from a given time.
#[derive(Debug, Default)]
pub struct Nodes {
    waiting: Vec<(Nanos, Frame)>,
}

impl Nodes {
    pub fn schedule(&mut self, ready_at: Nanos, frame: Frame) {
        self.waiting.push((ready_at, frame));
    }

    /// The frame that wins arbitration among those ready at `now`.
    pub fn best_ready(&self, now: Nanos) -> Option<(usize, &Frame)> {
        self.waiting
            .iter()
            .enumerate()
            .filter(|(_, (ready, _))| *ready <= now)
            .min_by_key(|(i, (_, frame))| (arbitration_key(frame), *i))
            .map(|(i, (_, frame))| (i, frame))
    }

    pub fn take(&mut self, index: usize) -> Frame {
        self.waiting.remove(index).1
    }

    pub fn next_ready_after(&self, now: Nanos) -> Option<Nanos> {
        self.waiting
            .iter()
            .map(|(ready, _)| *ready)
            .filter(|ready| *ready > now)
            .min()
    }

    pub fn is_empty(&self) -> bool {
        self.waiting.is_empty()
    }
}
