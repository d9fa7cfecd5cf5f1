//! The CANopen bus coupler of the quick start (002) as a node on a Gherkin
//! world's simulated bus: the steps set its inputs and stop it, the bus lets
//! it answer the frames the IUT sends.

use std::cell::RefCell;
use std::rc::Rc;

use canif_harness::bus::sim::Answering;
use canif_model::canopen::coupler::Coupler;
use canif_model::canopen::NodeId;
use canif_model::frame::Frame;
use canif_model::Nanos;

/// The coupler, shared by the world's steps and the bus it answers on.
#[derive(Clone)]
pub struct BusCoupler(Rc<RefCell<Node>>);

struct Node {
    coupler: Coupler,
    /// A failed coupler neither answers nor sends (heartbeat and guarding loss).
    alive: bool,
}

impl BusCoupler {
    /// A coupler with two digital input bytes and four analog inputs.
    pub fn new(node: NodeId) -> Self {
        BusCoupler(Rc::new(RefCell::new(Node {
            coupler: Coupler::new(node, 2, 4),
            alive: true,
        })))
    }

    pub fn node(&self) -> NodeId {
        self.0.borrow().coupler.node()
    }

    pub fn alive(&self) -> bool {
        self.0.borrow().alive
    }

    pub fn fail(&self) {
        self.0.borrow_mut().alive = false;
    }

    /// The frames a changed digital input byte makes it send (none once failed).
    pub fn set_digital_input(&self, byte: usize, value: u8) -> Vec<Frame> {
        self.while_alive(|c| c.set_digital_input(byte, value))
    }

    /// The frames a changed analog input makes it send (none once failed).
    pub fn set_analog_input(&self, channel: usize, value: i16) -> Vec<Frame> {
        self.while_alive(|c| c.set_analog_input(channel, value))
    }

    /// What it sends by itself by `now` (heartbeats, event timers).
    pub fn poll(&self, now: Nanos) -> Vec<Frame> {
        self.while_alive(|c| c.poll(now))
    }

    fn while_alive(&self, f: impl FnOnce(&mut Coupler) -> Vec<Frame>) -> Vec<Frame> {
        let mut node = self.0.borrow_mut();
        match node.alive {
            true => f(&mut node.coupler),
            false => Vec::new(),
        }
    }
}

impl Answering for BusCoupler {
    fn answer(&mut self, frame: &Frame, end: Nanos) -> Vec<Frame> {
        self.while_alive(|c| c.handle(frame, end))
    }
}

impl std::fmt::Debug for BusCoupler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let node = self.0.borrow();
        write!(
            f,
            "coupler {} ({})",
            node.coupler.node().get(),
            if node.alive { "running" } else { "failed" }
        )
    }
}
