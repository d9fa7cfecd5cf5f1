//! Why a scenario could not be judged: the IUT broke, the bus broke, the
//! configuration cannot run, or the harness itself is wrong. None of these is a
//! non-conformance; each becomes an `error` verdict that says which it was.
//! Each carries its cause as a value: nothing reads an error's text back.

use std::fmt;

use canif_model::config::ConfigError;
use canif_model::frame::FrameError;

/// What an implementation under test (a device or a client) did that broke
/// the exchange with it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IutCause {
    /// It could not be started or loaded, or never answered its first
    /// request within the start limit: no run of it can judge anything.
    NotStarted,
    /// It exited, closed its output or its input, or died.
    Gone,
    /// It did not answer within the timeout.
    Silent,
    /// It answered what the protocol does not allow: no JSON, an unknown
    /// answer, an answer out of turn, a version it does not speak.
    Protocol,
    /// It answered that it failed.
    Reported,
    /// It answered what no device or client can: an image of the wrong size,
    /// a frame that is not one, a due time that never advances.
    Impossible,
    /// An implementation in canif's own process panicked.
    Panicked,
    /// The harness broke the protocol with it (a bug in canif, found at the boundary).
    HarnessBug,
    /// A library in `canif lib-host` read or wrote past one of its images and
    /// was stopped there: well-formed evidence of what it did (CL-IMG-001,
    /// G3), judged as a failure, not an error.
    OutsideImage,
}

/// Something went wrong with the IUT itself: it could not start, broke the
/// adapter protocol, or answered what no device can (an image of the wrong size).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IutError {
    pub cause: IutCause,
    /// What happened, in one line.
    pub what: String,
    /// What the implementation said about it (the last lines of its stderr).
    pub log: Option<String>,
}

impl IutError {
    pub fn new(cause: IutCause, what: impl Into<String>) -> Self {
        IutError {
            cause,
            what: what.into(),
            log: None,
        }
    }

    /// What happened, without the implementation's own output after it.
    pub fn headline(&self) -> &str {
        &self.what
    }
}

impl fmt::Display for IutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.log {
            Some(log) => write!(f, "{}; {log}", self.what),
            None => f.write_str(&self.what),
        }
    }
}

impl std::error::Error for IutError {}

/// A frame a device's controller started that is no valid CAN frame: judged
/// as the device's non-conformance, never an error of the exchange.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum InvalidFrame {
    /// The identifier does not fit its format (11 or 29 bits).
    Identifier { id: u32, extended: bool },
    /// The length, the data or the FD bits make no frame.
    Parts(FrameError),
    /// BRS or ESI on a classic frame: they exist only in CAN FD frames.
    FdBitsOnClassic { brs: bool, esi: bool },
    /// A remote frame in CAN FD, which has none.
    RemoteFd,
    /// The implementation said so itself (the adapter protocol's `invalid`), in its words.
    Declared(String),
}

impl InvalidFrame {
    /// The FD bits of a frame that no controller sends: a remote FD frame
    /// (CAN FD has none), BRS or ESI on a classic one.
    pub fn of_fd_bits(fd: bool, remote: bool, brs: bool, esi: bool) -> Result<(), InvalidFrame> {
        match (fd, remote) {
            (true, true) => Err(InvalidFrame::RemoteFd),
            (false, _) if brs || esi => Err(InvalidFrame::FdBitsOnClassic { brs, esi }),
            _ => Ok(()),
        }
    }
}

impl fmt::Display for InvalidFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InvalidFrame::Identifier { id, extended } => write!(
                f,
                "identifier 0x{id:X} does not fit {}",
                if *extended {
                    "a 29-bit identifier"
                } else {
                    "an 11-bit identifier"
                }
            ),
            InvalidFrame::Parts(error) => error.fmt(f),
            InvalidFrame::FdBitsOnClassic { brs, esi } => write!(
                f,
                "{} on a classic frame (they exist only in CAN FD frames)",
                match (brs, esi) {
                    (true, true) => "BRS and ESI",
                    (true, false) => "BRS",
                    _ => "ESI",
                }
            ),
            InvalidFrame::RemoteFd => f.write_str("a remote frame in CAN FD, which has none"),
            InvalidFrame::Declared(words) => f.write_str(words),
        }
    }
}

/// What failed on the bus under the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BusCause {
    /// The interface could not be opened or configured.
    Unavailable,
    /// A send or receive on it failed (the interface went down, a buffer stayed full).
    Io,
    /// The device the harness plays on it broke.
    PlayedDevice,
}

/// The bus under the run failed: a SocketCAN interface went down, a frame did
/// not arrive, a send buffer stayed full.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusError {
    pub cause: BusCause,
    pub what: String,
}

impl BusError {
    pub fn new(cause: BusCause, what: impl Into<String>) -> Self {
        BusError {
            cause,
            what: what.into(),
        }
    }
}

impl fmt::Display for BusError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.what)
    }
}

impl std::error::Error for BusError {}

/// Who refused a scenario's configuration.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Refusal {
    /// The model refuses it: the scenario does not fit the profile (a bug in canif's scenarios).
    Model(ConfigError),
    /// The IUT refuses a configuration the profile allows.
    Iut(String),
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::Model(error) => {
                write!(f, "the model refuses the scenario's configuration: {error}")
            }
            Refusal::Iut(reason) => write!(
                f,
                "the IUT refuses a configuration the profile allows: {reason}"
            ),
        }
    }
}

/// What in the harness or its scenarios is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HarnessError {
    /// A scenario asks for what its interface cannot carry.
    Scenario(String),
    /// The model or the played side failed where it cannot.
    Model(String),
}

impl fmt::Display for HarnessError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            HarnessError::Scenario(what) => write!(f, "scenario bug: {what}"),
            HarnessError::Model(what) => write!(f, "harness bug: {what}"),
        }
    }
}

/// What an earlier case of the profile broke, that later ones are skipped after.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Broke {
    /// "the IUT", "the client".
    pub under_test: &'static str,
    pub scenario: String,
    pub error: IutError,
}

impl fmt::Display for Broke {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} broke in `{}`: {}",
            self.under_test,
            self.scenario,
            self.error.headline()
        )
    }
}

/// Why a scenario ended in `error`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RunError {
    Iut(IutError),
    Bus(BusError),
    /// The model or the IUT refuses the scenario's configuration.
    Configuration(Refusal),
    /// The harness or a scenario is wrong (a bug in canif).
    Harness(HarnessError),
    /// Not run: what is under test had already broken in an earlier scenario
    /// of the profile (fail-fast).
    Skipped(Box<Broke>),
    /// The run was asked to stop (SIGINT, SIGTERM) before this scenario ended.
    Interrupted,
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Iut(e) => e.fmt(f),
            RunError::Bus(e) => e.fmt(f),
            RunError::Configuration(refusal) => refusal.fmt(f),
            RunError::Harness(error) => error.fmt(f),
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
