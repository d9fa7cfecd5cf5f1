//! Why a scenario could not be judged: the IUT broke, the bus broke, the
//! configuration cannot run, or the harness itself is wrong. None of these is a
//! non-conformance; each becomes an `error` verdict that says which it was.

use std::fmt;

/// Something went wrong with the IUT itself: it could not start, broke the
/// adapter protocol, or answered what no device can (an image of the wrong size).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IutError(pub String);

impl IutError {
    /// The first line: what broke, without the IUT's own output after it.
    pub fn headline(&self) -> &str {
        self.0.lines().next().unwrap_or_default()
    }
}

impl fmt::Display for IutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for IutError {}

/// The bus under the run failed: a SocketCAN interface went down, a frame did
/// not arrive, a send buffer stayed full.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusError(pub String);

impl fmt::Display for BusError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BusError {}

/// Why a scenario ended in `error`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RunError {
    Iut(IutError),
    Bus(BusError),
    /// The model or the IUT refuses the scenario's configuration.
    Configuration(String),
    /// The harness or a scenario is wrong (a bug in canif).
    Harness(String),
    /// Not run: the IUT had already broken in an earlier scenario of the
    /// profile (fail-fast), named here.
    Skipped(String),
    /// The run was asked to stop (SIGINT, SIGTERM) before this scenario ended.
    Interrupted,
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Iut(e) => e.fmt(f),
            RunError::Bus(e) => e.fmt(f),
            RunError::Configuration(reason) | RunError::Harness(reason) => f.write_str(reason),
            RunError::Skipped(after) => write!(f, "skipped after {after}"),
            RunError::Interrupted => f.write_str("interrupted (SIGINT or SIGTERM)"),
        }
    }
}

impl std::error::Error for RunError {}

impl From<IutError> for RunError {
    fn from(error: IutError) -> Self {
        RunError::Iut(error)
    }
}

impl From<BusError> for RunError {
    fn from(error: BusError) -> Self {
        RunError::Bus(error)
    }
}
