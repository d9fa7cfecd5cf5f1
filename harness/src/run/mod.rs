//! What both sides share: the selection, one profile's run of either side
//! ([`Cases`], [`run_profile`]), the kill matrix that proves each side's
//! power on its own faults, and the bounded ring a failure's history is kept in.
//!
//! A side says what its cases are and how one runs; everything around a
//! case — selection, fail-fast, interrupts, progress, the reach of the
//! verdicts — is written once here.

mod interface;
mod kill;
mod profile;
mod ring;
mod rng;
mod selection;

pub use interface::interface;
pub use kill::{kill_matrix, unreached, KillRow, SelfCheck};
pub use profile::{checked_ids, run_profile, Cases, ProfileRun};
pub use ring::{Ring, CONTEXT};
pub use rng::Rng;
pub use selection::{Selection, Shard};
