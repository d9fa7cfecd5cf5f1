//! The bus under a device's scenario: it carries the other nodes' frames and
//! the IUT's, decides when each ends, and tells the `Pair` — the lockstep
//! never knows which bus it runs on: the simulated bus in virtual time
//! ([`crate::bus::sim`], the default), or a Linux SocketCAN interface in real
//! time ([`kernel`], cargo feature `socketcan`, on by default).

#[cfg(feature = "socketcan")]
pub mod kernel;

use canif_model::frame::Frame;
use canif_model::timing::BitRates;
use canif_model::Nanos;

use crate::bus::sim::SimBus;
use crate::device::pair::Pair;
use crate::door::adapter::protocol::OwnedBus;
use crate::error::RunError;
use crate::outcome::Outcome;

/// What a bus does for the lockstep.
pub trait Bus {
    /// Another node's frame, ready to send from scenario time `at`.
    fn schedule(&mut self, at: Nanos, frame: Frame);

    /// Runs the bus up to scenario time `until`: frames end on it and the pair
    /// learns of them; a difference between the two devices ends the run.
    fn run_until(&mut self, pair: &mut Pair, until: Nanos) -> Result<(), Outcome>;

    /// The real length of a cycle, where the bus sets it (scenario offsets scale).
    fn cycle_time(&self) -> Option<Nanos> {
        None
    }

    /// How far receive time stamps may differ because of the bus.
    fn time_stamp_tolerance(&self) -> Nanos {
        0
    }

    /// Whether scenario time follows the wall clock.
    fn real_time(&self) -> bool {
        false
    }

    /// A frame as this bus can carry it.
    fn adapt(&self, frame: Frame) -> Frame {
        frame
    }

    /// The bus's name in traces: the simulated bus, or the IUT's interface.
    fn interface_name(&self) -> String {
        crate::trace::SIM_INTERFACE.to_string()
    }

    /// The interface an external IUT must open itself, if any.
    fn owned_bus(&self) -> Option<OwnedBus> {
        None
    }
}

/// Which bus scenarios run on.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum BusChoice {
    /// The simulated bus, in virtual time.
    #[default]
    Sim,
    /// A SocketCAN interface, in real time.
    #[cfg(feature = "socketcan")]
    SocketCan(kernel::KernelBusOptions),
}

impl BusChoice {
    /// Opens the bus for one scenario; `external_iut`: the IUT opens its own
    /// socket (it is another process).
    #[cfg_attr(not(feature = "socketcan"), allow(unused_variables))]
    pub fn open(&self, bit_rates: BitRates, external_iut: bool) -> Result<Box<dyn Bus>, RunError> {
        match self {
            BusChoice::Sim => Ok(Box::new(SimBus::new(bit_rates))),
            #[cfg(feature = "socketcan")]
            BusChoice::SocketCan(options) => {
                Ok(Box::new(kernel::KernelBus::open(options, external_iut)?))
            }
        }
    }

    pub fn is_sim(&self) -> bool {
        matches!(self, BusChoice::Sim)
    }
}

impl Bus for SimBus {
    fn schedule(&mut self, at: Nanos, frame: Frame) {
        SimBus::schedule(self, at, frame);
    }

    fn run_until(&mut self, pair: &mut Pair, until: Nanos) -> Result<(), Outcome> {
        self.drive(pair, until)
    }
}
