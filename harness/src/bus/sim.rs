//! A simulated CAN bus in virtual time: frames take the time the model's bit
//! timing gives them, and among frames waiting when the bus goes idle the
//! lowest arbitration field wins (ISO 11898-1 arbitration).

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::hash::{BuildHasherDefault, Hasher};

use canif_model::frame::{CanId, Frame, FrameKind};
use canif_model::timing::{frame_duration, BitRates, Stuffing};
use canif_model::Nanos;

/// The bits a frame sends during arbitration, as a number: lower wins.
/// Standard: id(11) RTR IDE=0; extended: base(11) SRR=1 IDE=1 ext(18) RTR.
pub(crate) fn arbitration_key(frame: &Frame) -> u64 {
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
pub(crate) fn duration(frame: &Frame, rates: BitRates) -> Nanos {
    frame_duration(frame, rates, Stuffing::Nominal)
}

/// Hashes a sequence number as itself: the numbers are unique and dense, and
/// SipHash cost a measurable share of a long scenario's time.
#[derive(Default)]
struct SequenceHasher(u64);

impl Hasher for SequenceHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for byte in bytes {
            self.0 = (self.0 << 8) | u64::from(*byte);
        }
    }
    fn write_u64(&mut self, n: u64) {
        self.0 = n;
    }
}

/// Other nodes' frames waiting for the bus, each ready from a given time.
/// Frames not yet ready wait by time; ready ones by arbitration key (then by
/// order of scheduling), so each arbitration costs O(log n).
#[derive(Debug, Default)]
pub(crate) struct Nodes {
    later: BinaryHeap<Reverse<(Nanos, u64)>>,
    ready: BinaryHeap<Reverse<(u64, u64)>>,
    frames: HashMap<u64, Frame, BuildHasherDefault<SequenceHasher>>,
    sequence: u64,
}

impl Nodes {
    pub(crate) fn schedule(&mut self, ready_at: Nanos, frame: Frame) {
        self.sequence += 1;
        self.frames.insert(self.sequence, frame);
        self.later.push(Reverse((ready_at, self.sequence)));
    }

    fn mature(&mut self, now: Nanos) {
        while let Some(Reverse((ready_at, sequence))) = self.later.peek().copied() {
            if ready_at > now {
                break;
            }
            self.later.pop();
            let key = self.frames.get(&sequence).map_or(u64::MAX, arbitration_key);
            self.ready.push(Reverse((key, sequence)));
        }
    }

    /// The arbitration key of the frame that would win at `now`, if any is ready.
    pub(crate) fn best_key(&mut self, now: Nanos) -> Option<u64> {
        self.mature(now);
        self.ready.peek().map(|Reverse((key, _))| *key)
    }

    /// Takes the winner at `now`.
    pub(crate) fn take_best(&mut self, now: Nanos) -> Option<Frame> {
        self.mature(now);
        let Reverse((_, sequence)) = self.ready.pop()?;
        self.frames.remove(&sequence)
    }

    pub(crate) fn next_ready_after(&self, now: Nanos) -> Option<Nanos> {
        self.later
            .peek()
            .map(|Reverse((ready_at, _))| *ready_at)
            .filter(|t| *t > now)
    }
}

/// What the simulated bus needs of the node whose controller it serves: the
/// device under test beside the model (the device side's pair), or the model
/// device alone (the played device, when a PLC-side client is under test).
pub(crate) trait Controller {
    /// Why the run cannot go on.
    type Error;
    /// Scenario time.
    fn now(&mut self) -> &mut Nanos;
    /// The frame handed to the controller and not yet on the bus.
    fn pending(&mut self) -> &mut Option<Frame>;
    /// Asks the device for its next frame when the controller is free.
    fn poll(&mut self) -> Result<(), Self::Error>;
    /// When a held frame becomes due (Distributed Clocks).
    fn due(&self) -> Option<Nanos>;
    /// A frame ended on the bus; `own`: the controller sent it.
    fn ended(&mut self, frame: Frame, own: bool, end: Nanos) -> Result<(), Self::Error>;
    /// The bus took `steps` events without reaching the end of the cycle: the
    /// device keeps asking to be polled again (time does not advance).
    fn stalled(&self, steps: usize) -> Self::Error;
}

/// How many bus events one cycle may take: a 1 ms cycle at 1 Mbit/s carries
/// about 20 frames, so only a device whose due times do not advance reaches it.
pub(crate) const MOST_EVENTS_PER_CYCLE: usize = 10_000;

/// A node on the bus that answers the frames the controller sends (a
/// CANopen slave answering the PLC's requests): its answers wait for the bus
/// from the end of the frame they answer.
pub trait Answering {
    fn answer(&mut self, frame: &Frame, end: Nanos) -> Vec<Frame>;
}

/// The simulated bus of one scenario: the other nodes, and the frame on the wire.
pub struct SimBus {
    nodes: Nodes,
    bit_rates: BitRates,
    /// The frame on the bus: its end, whether the controller sent it.
    on_bus: Option<(Nanos, Frame, bool)>,
    /// The controller loses every arbitration (a dominant node holds the
    /// bus): its frame waits; the other nodes' frames still pass.
    own_held: bool,
    answering: Option<Box<dyn Answering>>,
}

impl std::fmt::Debug for SimBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimBus")
            .field("bit_rates", &self.bit_rates)
            .field("on_bus", &self.on_bus)
            .field("own_held", &self.own_held)
            .finish_non_exhaustive()
    }
}

impl SimBus {
    pub fn new(bit_rates: BitRates) -> Self {
        SimBus {
            nodes: Nodes::default(),
            bit_rates,
            on_bus: None,
            own_held: false,
            answering: None,
        }
    }

    /// Another node's frame, ready to send from `at`.
    pub fn schedule(&mut self, at: Nanos, frame: Frame) {
        self.nodes.schedule(at, frame);
    }

    /// Other nodes' frames, ready from `at` in this order.
    pub fn schedule_all(&mut self, at: Nanos, frames: Vec<Frame>) {
        for (k, frame) in frames.into_iter().enumerate() {
            self.nodes.schedule(at + k as Nanos, frame);
        }
    }

    /// Holds (or releases) the controller's frames: see `SimBus::own_held`.
    pub fn hold_own(&mut self, held: bool) {
        self.own_held = held;
    }

    /// Puts a node on the bus that answers the controller's frames.
    pub fn answer_with(&mut self, node: Box<dyn Answering>) {
        self.answering = Some(node);
    }

    /// How long `frame` occupies this bus.
    pub fn duration(&self, frame: &Frame) -> Nanos {
        duration(frame, self.bit_rates)
    }

    /// The controller resets (a device restart): its frame on the wire, if
    /// any, is destroyed and never ends.
    pub(crate) fn abort_own(&mut self) {
        if self.on_bus.as_ref().is_some_and(|(_, _, own)| *own) {
            self.on_bus = None;
        }
    }

    /// Completes frames and starts the next winner of arbitration, until `until`.
    pub(crate) fn drive<C: Controller>(
        &mut self,
        node: &mut C,
        until: Nanos,
    ) -> Result<(), C::Error> {
        for _ in 0..MOST_EVENTS_PER_CYCLE {
            node.poll()?;
            let now = *node.now();
            if self.on_bus.is_none() {
                let other = self.nodes.best_key(now);
                let own = match self.own_held {
                    true => None,
                    false => node.pending().as_ref().map(arbitration_key),
                };
                let start = match (other, own) {
                    (Some(o), Some(k)) if o < k => self.nodes.take_best(now).map(|f| (f, false)),
                    (Some(_), None) => self.nodes.take_best(now).map(|f| (f, false)),
                    (_, Some(_)) => node.pending().take().map(|f| (f, true)),
                    (None, None) => None,
                };
                if let Some((frame, own)) = start {
                    let end = now + duration(&frame, self.bit_rates);
                    self.on_bus = Some((end, frame, own));
                }
            }
            let next = [
                self.on_bus.as_ref().map(|(end, _, _)| *end),
                self.nodes.next_ready_after(now),
                node.due().filter(|t| *t > now),
            ]
            .into_iter()
            .flatten()
            .min();
            match next {
                Some(t) if t <= until => {
                    *node.now() = t;
                    if let Some((end, frame, own)) = self.on_bus.take() {
                        if end == t {
                            node.ended(frame, own, end)?;
                            if let (true, Some(answering)) = (own, self.answering.as_mut()) {
                                for answer in answering.answer(&frame, end) {
                                    self.nodes.schedule(end, answer);
                                }
                            }
                        } else {
                            self.on_bus = Some((end, frame, own));
                        }
                    }
                }
                _ => {
                    *node.now() = until;
                    return Ok(());
                }
            }
        }
        Err(node.stalled(MOST_EVENTS_PER_CYCLE))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn classic(id: CanId) -> Frame {
        Frame::classic(id, &[1, 2]).unwrap()
    }

    fn standard(id: u16) -> Frame {
        classic(CanId::Standard(id))
    }

    #[test]
    fn arbitration_follows_the_bits_on_the_wire() {
        let key = arbitration_key;
        assert!(key(&standard(0x100)) < key(&standard(0x101)));
        // A data frame wins over a remote frame of the same identifier (RTR is recessive).
        assert!(key(&standard(0x100)) < key(&Frame::remote(CanId::Standard(0x100), 2).unwrap()));
        // A standard frame wins over an extended one with the same base identifier (SRR, IDE).
        let extended = classic(CanId::Extended(0x100 << 18));
        assert!(key(&standard(0x100)) < key(&extended));
        // An extended frame with a lower base identifier wins over a standard one.
        assert!(key(&classic(CanId::Extended(0x0FF << 18))) < key(&standard(0x100)));
    }

    #[test]
    fn nodes_release_frames_when_ready_and_lowest_key_first() {
        let mut nodes = Nodes::default();
        nodes.schedule(10, standard(0x300));
        nodes.schedule(0, standard(0x200));
        nodes.schedule(0, standard(0x100));
        assert_eq!(nodes.take_best(5), Some(standard(0x100)));
        assert_eq!(nodes.next_ready_after(5), Some(10));
        assert_eq!(nodes.take_best(5), Some(standard(0x200)));
        assert_eq!(nodes.take_best(5), None, "0x300 is not ready before 10 ns");
        assert_eq!(nodes.take_best(10), Some(standard(0x300)));
        assert_eq!(nodes.take_best(u64::MAX), None);
    }

    /// A controller with one frame to send, recording what ended on the bus.
    #[derive(Default)]
    struct Node {
        now: Nanos,
        pending: Option<Frame>,
        to_send: Vec<Frame>,
        ended: Vec<(Frame, bool, Nanos)>,
        due: Option<Nanos>,
    }

    impl Controller for Node {
        type Error = String;
        fn now(&mut self) -> &mut Nanos {
            &mut self.now
        }
        fn pending(&mut self) -> &mut Option<Frame> {
            &mut self.pending
        }
        fn poll(&mut self) -> Result<(), String> {
            if self.pending.is_none() {
                self.pending = self.to_send.pop();
            }
            Ok(())
        }
        fn due(&self) -> Option<Nanos> {
            self.due
        }
        fn ended(&mut self, frame: Frame, own: bool, end: Nanos) -> Result<(), String> {
            self.ended.push((frame, own, end));
            Ok(())
        }
        fn stalled(&self, steps: usize) -> String {
            format!("stalled after {steps}")
        }
    }

    #[test]
    fn the_lower_identifier_takes_the_bus_and_the_other_follows_back_to_back() {
        let rates = BitRates::classic(500_000);
        let mut bus = SimBus::new(rates);
        bus.schedule(0, standard(0x100));
        let mut node = Node {
            to_send: vec![standard(0x200)],
            ..Node::default()
        };
        bus.drive(&mut node, 1_000_000).unwrap();
        let first = duration(&standard(0x100), rates);
        let second = duration(&standard(0x200), rates);
        assert_eq!(
            node.ended,
            [
                (standard(0x100), false, first),
                (standard(0x200), true, first + second)
            ]
        );
        assert_eq!(node.now, 1_000_000, "the bus runs to the end of the cycle");
    }

    #[test]
    fn a_frame_still_on_the_wire_at_the_end_of_the_cycle_ends_in_the_next() {
        let rates = BitRates::classic(125_000);
        let mut bus = SimBus::new(rates);
        let mut node = Node {
            to_send: vec![standard(0x123)],
            ..Node::default()
        };
        bus.drive(&mut node, 10_000).unwrap();
        assert!(node.ended.is_empty());
        bus.drive(&mut node, 1_000_000).unwrap();
        assert_eq!(node.ended.len(), 1);
        assert_eq!(node.ended[0].2, duration(&standard(0x123), rates));
    }

    #[test]
    fn a_node_whose_due_time_never_advances_stalls_the_bus() {
        let mut bus = SimBus::new(BitRates::classic(500_000));
        // A due time always just ahead of now: polled again and again.
        struct Stuck(Node);
        impl Controller for Stuck {
            type Error = String;
            fn now(&mut self) -> &mut Nanos {
                self.0.now()
            }
            fn pending(&mut self) -> &mut Option<Frame> {
                self.0.pending()
            }
            fn poll(&mut self) -> Result<(), String> {
                Ok(())
            }
            fn due(&self) -> Option<Nanos> {
                Some(self.0.now + 1)
            }
            fn ended(&mut self, frame: Frame, own: bool, end: Nanos) -> Result<(), String> {
                self.0.ended(frame, own, end)
            }
            fn stalled(&self, steps: usize) -> String {
                self.0.stalled(steps)
            }
        }
        let error = bus
            .drive(&mut Stuck(Node::default()), 1_000_000_000)
            .unwrap_err();
        assert_eq!(error, format!("stalled after {MOST_EVENTS_PER_CYCLE}"));
    }

    #[test]
    fn a_held_controller_loses_every_arbitration_until_released() {
        let rates = BitRates::classic(500_000);
        let mut bus = SimBus::new(rates);
        bus.hold_own(true);
        bus.schedule(0, standard(0x700));
        let mut node = Node {
            to_send: vec![standard(0x001)],
            ..Node::default()
        };
        bus.drive(&mut node, 1_000_000).unwrap();
        assert_eq!(
            node.ended,
            [(standard(0x700), false, duration(&standard(0x700), rates))]
        );
        assert_eq!(node.pending, Some(standard(0x001)), "still waiting");
        bus.hold_own(false);
        bus.drive(&mut node, 2_000_000).unwrap();
        assert_eq!(node.ended.len(), 2);
        assert_eq!(node.ended[1].0, standard(0x001));
        assert!(node.ended[1].1, "the controller's own frame");
    }

    /// Answers every frame with the frame's identifier plus one.
    struct Echo;

    impl Answering for Echo {
        fn answer(&mut self, frame: &Frame, _: Nanos) -> Vec<Frame> {
            vec![standard(frame.id.raw() as u16 + 1)]
        }
    }

    #[test]
    fn an_answering_node_answers_the_controllers_frames_once_they_end() {
        let rates = BitRates::classic(500_000);
        let mut bus = SimBus::new(rates);
        bus.answer_with(Box::new(Echo));
        bus.schedule(0, standard(0x300));
        let mut node = Node {
            to_send: vec![standard(0x100)],
            ..Node::default()
        };
        bus.drive(&mut node, 1_000_000).unwrap();
        let ended: Vec<(u32, bool)> = node
            .ended
            .iter()
            .map(|(f, own, _)| (f.id.raw(), *own))
            .collect();
        // The other node's frame is not answered, the controller's is, after it.
        assert_eq!(ended, [(0x100, true), (0x101, false), (0x300, false)]);
        let (first_end, answer_end) = (node.ended[0].2, node.ended[1].2);
        assert_eq!(answer_end, first_end + duration(&standard(0x101), rates));
    }

    #[test]
    fn frames_scheduled_together_keep_their_order_only_if_ready_one_after_another() {
        let rates = BitRates::classic(500_000);
        let mut bus = SimBus::new(rates);
        bus.schedule_all(0, vec![standard(0x200), standard(0x100)]);
        let mut node = Node::default();
        bus.drive(&mut node, 1_000_000).unwrap();
        let ids: Vec<u32> = node.ended.iter().map(|(f, _, _)| f.id.raw()).collect();
        // 0x200 is ready a nanosecond earlier and takes the idle bus.
        assert_eq!(ids, [0x200, 0x100]);
    }
}
