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
    /// Frames other nodes sent lately, and what the model's Rx queue did
    /// with each.
    recent_rx: Ring<(Frame, Taken)>,
}

/// What the model's local Rx queue did with a frame another node sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Taken {
    /// Queued with more than its last place free: a queue one place
    /// shorter keeps it too.
    WithRoom,
    /// Queued into its last free place.
    LastPlace,
    /// Lost to the full queue (tail drop, G4).
    Lost,
    /// Not for the queue: filtered, or a format the interface cannot carry.
    Held,
}

impl Default for History {
    fn default() -> Self {
        History {
            cycles: Ring::context(),
            bus: Ring::new(BUS_LOG),
            recent_rx: Ring::new(RECENT_RX),
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

    /// A frame ended on the bus during `cycle`: the IUT's (`taken` `None`),
    /// or another node's, which the model's queue `taken`.
    pub fn frame(&mut self, cycle: u64, frame: Frame, end: Nanos, taken: Option<Taken>) {
        self.bus.push(Logged {
            cycle,
            from_iut: taken.is_none(),
            frame,
            end,
        });
        if let Some(taken) = taken {
            self.recent_rx.push((frame, taken));
        }
    }

    /// What the model's queue did with `frame`, if another node sent it
    /// lately (its latest time).
    pub fn taken(&self, frame: &Frame) -> Option<Taken> {
        self.recent_rx
            .iter()
            .rev()
            .find(|(f, _)| f == frame)
            .map(|(_, taken)| *taken)
    }

    /// The model's local Rx queue overflowed lately.
    pub fn overflowed(&self) -> bool {
        self.recent_rx.iter().any(|(_, t)| *t == Taken::Lost)
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
                history.frame(cycle, frame, cycle * 1_000 + 500, Some(Taken::WithRoom));
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
        assert_eq!(history.taken(&frame), Some(Taken::WithRoom));
        let other = Frame::classic(CanId::Standard(1), &[]).unwrap();
        assert_eq!(history.taken(&other), None);
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
            history.frame(0, frame, 10 + u64::from(id), Some(Taken::WithRoom));
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
