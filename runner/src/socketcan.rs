//! The SocketCAN interfaces a run uses, opened once before it: a bus that
//! cannot be opened at all is one error, not one per scenario, on either side.

use crate::error::PlanError;

/// Opens each of `interfaces` once (the bus `described` names), or says why not.
#[cfg(feature = "socketcan")]
pub(crate) fn opens(described: &str, interfaces: &[&str]) -> Result<(), PlanError> {
    let opened = canif_kernel::probe().and_then(|()| {
        interfaces
            .iter()
            .try_for_each(|name| canif_kernel::KernelSocket::open(name, false).map(|_| ()))
    });
    opened.map_err(|error| PlanError::Preflight(format!("error: --bus {described}: {error}")))
}

/// What a simulated bus shares between profiles run side by side: nothing;
/// a SocketCAN bus is one interface.
pub(crate) const ONE_INTERFACE: &str = "a SocketCAN bus: one interface";
