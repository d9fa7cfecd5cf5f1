//! CANopen as a conformance target: the telegrams of the quick start (002) and
//! the SDO page (004) sent to a node, and its answers checked. Any node that
//! takes frames and time works: the simulated coupler of the model, or a node
//! on a SocketCAN interface (`socketcan::SocketCanNode`, real time).
//!
//! - `checks`: the node checks; [`side`]: they as a side of the suite (what
//!   `canif run canopen` runs); `socketcand` and `on_bus`: the
//!   simulated coupler served to other tools. (`device::quick_start` sends the
//!   same telegrams through an IUT's process image.)

mod checks;
#[cfg(feature = "socketcan")]
pub mod on_bus;
pub mod side;
#[cfg(feature = "socketcan")]
mod socketcan;
pub mod socketcand;

pub use checks::{check_node, node_check_ids, sdo_request, NodeCheck};
#[cfg(feature = "socketcan")]
pub use socketcan::SocketCanNode;

use canif_model::canopen::coupler::Coupler;
use canif_model::frame::Frame;
use canif_model::Nanos;

/// A CANopen node under test.
pub trait CanNode {
    /// A frame reaches the node at `now`; what it answers.
    fn handle(&mut self, frame: &Frame, now: Nanos) -> Vec<Frame>;
    /// Time passes; what it sends by itself.
    fn poll(&mut self, now: Nanos) -> Vec<Frame>;
}

impl CanNode for Coupler {
    fn handle(&mut self, frame: &Frame, now: Nanos) -> Vec<Frame> {
        Coupler::handle(self, frame, now)
    }
    fn poll(&mut self, now: Nanos) -> Vec<Frame> {
        Coupler::poll(self, now)
    }
}
