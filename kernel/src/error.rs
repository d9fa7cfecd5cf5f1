//! What went wrong with the kernel's CAN stack, as a value: the harness and
//! the tests decide by the variant, never by the text.

use std::fmt;
use std::io;

/// An operating-system error, kept as its kind and its words (so that the
/// error can be cloned into every skip reason and report that names it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OsError {
    pub kind: io::ErrorKind,
    pub message: String,
}

impl From<io::Error> for OsError {
    fn from(error: io::Error) -> Self {
        OsError {
            kind: error.kind(),
            message: error.to_string(),
        }
    }
}

impl fmt::Display for OsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// What an interface operation was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Operation {
    /// Opening and configuring a socket on it (CAN_RAW, or AF_PACKET for EtherCAT).
    Open,
    /// Finding it over netlink.
    Find,
    /// `ip link set … up` (true) or `down` (false).
    SetLink(bool),
}

/// Why SocketCAN cannot be used here or now.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum KernelError {
    /// `socket(AF_CAN, SOCK_RAW, CAN_RAW)` fails: this kernel has no SocketCAN.
    NoCan { release: String, error: OsError },
    /// No network interface of this name on this machine.
    NoInterface { name: String },
    /// The environment variable that names a test's interfaces is unset
    /// (`value` none) or not `IFACE,IFACE`.
    NotNamed {
        variable: String,
        value: Option<String>,
    },
    /// An operation on an interface failed.
    Interface {
        interface: String,
        operation: Operation,
        error: OsError,
    },
}

impl fmt::Display for KernelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            KernelError::NoCan { release, error } => write!(
                f,
                "socket(AF_CAN, SOCK_RAW, CAN_RAW) fails on this kernel ({release}): {error}"
            ),
            KernelError::NoInterface { name } => {
                write!(
                    f,
                    "no interface {name} (scripts/kernel-can-lane creates it)"
                )
            }
            KernelError::NotNamed {
                variable,
                value: None,
            } => write!(
                f,
                "no interface pair ({variable}=IFACE,IFACE; scripts/kernel-can-lane sets it)"
            ),
            KernelError::NotNamed {
                variable,
                value: Some(value),
            } => write!(f, "{variable}={value:?} is not IFACE,IFACE"),
            KernelError::Interface {
                interface,
                operation: Operation::SetLink(up),
                error,
            } => write!(
                f,
                "{interface}: set {}: {error}",
                if *up { "up" } else { "down" }
            ),
            KernelError::Interface {
                interface, error, ..
            } => write!(f, "{interface}: {error}"),
        }
    }
}

impl std::error::Error for KernelError {}

impl From<KernelError> for String {
    fn from(error: KernelError) -> String {
        error.to_string()
    }
}
