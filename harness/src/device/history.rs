//! The last cycles and frames of a run, kept in bounded rings (memory does not
//! grow with run length) and formatted only when a failure shows them.

use canif_model::frame::Frame;
use canif_model::image::{ImageLayout, InputHeader, InputImage, OutputHeader, OutputImage};
use canif_model::Nanos;

use crate::outcome::{BusFrame, CycleView};
use crate::run::Ring;

/// How many frames of bus history a failure can show.
const BUS_LOG: usize = 256;

/// How many frames of one cycle a failure's context lists.
const SHOWN_FRAMES: usize = 8;

/// How many received frames the oracle remembers.
const RECENT_RX: usize = 4_096;

/// What one cycle looked like.
#[derive(Debug, Clone, Copy)]
struct CycleRecord {
    cycle: u64,
    now: Nanos,
    outputs: OutputHeader,
    expected: InputHeader,
    actual: InputHeader,
}

/// A frame that ended on the bus during a cycle.
#[derive(Debug, Clone, Copy)]
struct Logged {
    cycle: u64,
    from_iut: bool,
    frame: Frame,
    end: Nanos,
}

/// The bounded history of one scenario.
#[derive(Debug)]
pub struct History {
    cycles: Ring<CycleRecord>,
    bus: Ring<Logged>,
    /// Frames other nodes sent lately.
    recent_rx: Ring<Frame>,
    /// Of those, the frames the model lost to a full local Rx queue.
    recent_lost: Ring<Frame>,
    /// Of those, the frames the model queued with more than its last place
    /// free: a device with one place less keeps them too.
    recent_with_room: Ring<Frame>,
}

impl Default for History {
    fn default() -> Self {
        History {
            cycles: Ring::context(),
            bus: Ring::new(BUS_LOG),
            recent_rx: Ring::new(RECENT_RX),
            recent_lost: Ring::new(RECENT_RX),
            recent_with_room: Ring::new(RECENT_RX),
        }
    }
}

impl History {
    /// Remembers one cycle's images (headers only). Images of the wrong size
    /// are remembered as empty headers: the size itself is the failure.
    pub fn cycle(
        &mut self,
        layout: ImageLayout,
        (cycle, now): (u64, Nanos),
        outputs: &[u8],
        expected: &[u8],
        actual: &[u8],
    ) {
        let input = |b: &[u8]| InputImage::new_checked(b, layout).map(|i| i.header());
        self.cycles.push(CycleRecord {
            cycle,
            now,
            outputs: OutputImage::new_checked(outputs, layout)
                .map(|o| o.header())
                .unwrap_or_default(),
            expected: input(expected).unwrap_or_default(),
            actual: input(actual).unwrap_or_default(),
        });
    }

    /// A frame ended on the bus during `cycle`.
    pub fn frame(&mut self, cycle: u64, from_iut: bool, frame: Frame, end: Nanos) {
        self.bus.push(Logged {
            cycle,
            from_iut,
            frame,
            end,
        });
        if !from_iut {
            self.recent_rx.push(frame);
        }
    }

    /// The model lost `frame`, received from another node, to its full
    /// local Rx queue (tail drop, G4).
    pub fn model_lost(&mut self, frame: Frame) {
        self.recent_lost.push(frame);
    }

    /// The model queued `frame` with more than its last place free.
    pub fn queued_with_room(&mut self, frame: Frame) {
        self.recent_with_room.push(frame);
    }

    /// Whether `frame` is one a full queue lost only by the order it drops
    /// in: the model lost frames lately, and queued `frame` with places to
    /// spare, so no shorter queue drops it on arrival - a device without it
    /// evicted it later (a head drop, not a depth).
    pub fn evicted_by_the_drop_order(&self, frame: &Frame) -> bool {
        self.recent_lost.iter().len() > 0 && self.recent_with_room.iter().any(|f| f == frame)
    }

    /// Whether the model lately lost `frame` to its full local Rx queue.
    pub fn lost_by_model_lately(&self, frame: &Frame) -> bool {
        self.recent_lost.iter().any(|f| f == frame)
    }

    /// Whether another node sent `frame` lately.
    pub fn received_lately(&self, frame: &Frame) -> bool {
        self.recent_rx.iter().any(|f| f == frame)
    }

    /// Frames that ended since the cycle before `cycle`.
    fn frames_before(&self, cycle: u64) -> impl Iterator<Item = &Logged> {
        self.bus.iter().filter(move |l| l.cycle + 1 == cycle)
    }

    /// The remembered cycles as data.
    pub fn timeline(&self) -> Vec<CycleView> {
        self.cycles
            .iter()
            .map(|r| CycleView {
                cycle: r.cycle,
                time: r.now,
                outputs: r.outputs,
                expected: r.expected,
                actual: r.actual,
                frames: self
                    .frames_before(r.cycle)
                    .map(|l| BusFrame {
                        end: l.end,
                        from_iut: l.from_iut,
                        text: l.frame.to_string(),
                    })
                    .collect(),
            })
            .collect()
    }

    /// The remembered cycles as text, each with the frames that ended on the bus
    /// since the cycle before.
    pub fn context(&self) -> Vec<String> {
        self.cycles
            .iter()
            .map(|r| {
                let o = r.outputs;
                let i = r.actual;
                let tn = i.transaction_number.map_or(String::new(), |tn| format!(" tn={tn}"));
                let frames: Vec<&Logged> = self.frames_before(r.cycle).collect();
                let shown = &frames[frames.len().saturating_sub(SHOWN_FRAMES)..];
                let listed: Vec<String> = shown
                    .iter()
                    .map(|l| format!("{} {}", if l.from_iut { "tx" } else { "rx" }, l.frame))
                    .collect();
                // A flood must not bury the cause: its count and its last frames.
                let bus = match frames.len() - shown.len() {
                    _ if frames.is_empty() => String::new(),
                    0 => format!(" | bus: {}", listed.join(", ")),
                    more => format!(
                        " | bus: {} frames, the last: … {more} more, {}",
                        frames.len(),
                        listed.join(", ")
                    ),
                };
                format!(
                    "cycle {:>5} t={:>9.3} ms  out[tx={} rx={} n={}]  in[tx={} rx={} n={}{tn}]{bus}",
                    r.cycle,
                    r.now as f64 / 1e6,
                    o.tx_counter,
                    o.rx_counter,
                    o.no_of_tx_messages,
                    i.tx_counter,
                    i.rx_counter,
                    i.no_of_rx_messages
                )
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use canif_model::config::{FrameFormat, InterfaceConfig};
    use canif_model::frame::CanId;

    use super::*;
    use crate::run::CONTEXT;

    #[test]
    fn a_failure_shows_the_last_cycles_with_the_frames_that_ended_before_each() {
        let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Base11, 2), false);
        let (outputs, inputs) = (vec![0; layout.output_size()], vec![0; layout.input_size()]);
        let mut history = History::default();
        let frame = Frame::classic(CanId::Standard(0x321), &[7]).unwrap();
        for cycle in 0..10u64 {
            history.cycle(layout, (cycle, cycle * 1_000), &outputs, &inputs, &inputs);
            if cycle == 8 {
                history.frame(cycle, false, frame, cycle * 1_000 + 500);
            }
        }
        let timeline = history.timeline();
        assert_eq!(timeline.len(), CONTEXT);
        assert_eq!(timeline.first().map(|c| c.cycle), Some(10 - CONTEXT as u64));
        let cycle9 = timeline.iter().find(|c| c.cycle == 9).unwrap();
        assert_eq!(
            cycle9.frames.len(),
            1,
            "the frame of cycle 8 shows before cycle 9"
        );
        assert!(!cycle9.frames[0].from_iut);
        let context = history.context();
        assert_eq!(context.len(), CONTEXT);
        assert!(context.last().unwrap().contains("rx"), "{context:?}");
        assert!(history.received_lately(&frame));
        assert!(!history.received_lately(&Frame::classic(CanId::Standard(1), &[]).unwrap()));
    }

    #[test]
    fn an_image_of_the_wrong_size_is_remembered_as_an_empty_header() {
        let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Base11, 2), false);
        let mut history = History::default();
        history.cycle(layout, (0, 0), &[1, 2], &[3], &[4]);
        assert_eq!(history.timeline()[0].actual, InputHeader::default());
    }

    #[test]
    fn a_flood_shows_its_count_and_its_last_frames() {
        let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Base11, 2), false);
        let (outputs, inputs) = (vec![0; layout.output_size()], vec![0; layout.input_size()]);
        let mut history = History::default();
        history.cycle(layout, (0, 0), &outputs, &inputs, &inputs);
        for id in 0..200u16 {
            let frame = Frame::classic(CanId::Standard(id), &[]).unwrap();
            history.frame(0, false, frame, 10 + u64::from(id));
        }
        history.cycle(layout, (1, 1_000), &outputs, &inputs, &inputs);
        let context = history.context();
        let last = context.last().unwrap();
        assert!(
            last.contains("bus: 200 frames, the last: … 192 more, rx 0C0#"),
            "{last}"
        );
        assert_eq!(last.matches("rx ").count(), SHOWN_FRAMES, "{last}");
    }
}
