//! How long an implementation in another process may take, and where the
//! start limit comes from: every door that starts a process shares it.

use std::time::Duration;

/// How long an implementation in another process may take: to start (the
/// process, an interpreter, a library's load, up to its first answer), and
/// to answer each request after that. Only the second says it hung: a slow
/// start on a busy machine is not a hang.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timeouts {
    pub start: Duration,
    pub request: Duration,
}

impl Timeouts {
    /// The environment variable that sets the start limit in ms, for every
    /// run and test that does not set it on the command line.
    pub const START_VARIABLE: &'static str = "CANIF_START_TIMEOUT_MS";
    /// The start limit when nothing sets it.
    pub const DEFAULT_START_MS: u64 = 60_000;
    /// The per-request limit when nothing sets it.
    pub const DEFAULT_REQUEST_MS: u64 = 5_000;

    /// `request` per request, and the start limit of [`Self::START_VARIABLE`]
    /// (or [`Self::DEFAULT_START_MS`]); never less than `request`.
    pub fn with_request(request: Duration) -> Self {
        let start = std::env::var(Self::START_VARIABLE)
            .ok()
            .and_then(|ms| ms.trim().parse::<u64>().ok())
            .filter(|ms| *ms > 0)
            .unwrap_or(Self::DEFAULT_START_MS);
        Timeouts {
            start: Duration::from_millis(start).max(request),
            request,
        }
    }
}

impl Default for Timeouts {
    fn default() -> Self {
        Timeouts::with_request(Duration::from_millis(Self::DEFAULT_REQUEST_MS))
    }
}
