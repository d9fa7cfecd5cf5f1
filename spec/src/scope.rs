//! Where a requirement is judged: which side of the interface it binds, and
//! which suite checks it. A run lists the verdicts of its own side and suite
//! only; what another side or suite judges is not its to report.

use serde::Deserialize;

/// Which side of the interface a requirement binds: the device (EL6751,
/// FC51xx, CCAT, FC532x and what behaves like them) or the PLC-side client
/// that fills and reads the image.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Deserialize, serde::Serialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    #[default]
    Device,
    Plc,
}

impl Side {
    /// As the command line and the reports spell it.
    pub fn as_str(self) -> &'static str {
        match self {
            Side::Device => "device",
            Side::Plc => "plc",
        }
    }
}

impl std::fmt::Display for Side {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Which suite judges a requirement: the CAN interface of a device or a
/// client (`canif run`), or a CANopen node on the bus (`canif run --suite canopen`).
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Deserialize, serde::Serialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Suite {
    #[default]
    Interface,
    Canopen,
}

/// What one run judges: a side under one suite.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Scope {
    pub side: Side,
    pub suite: Suite,
}

impl Scope {
    /// Does the run of this scope report on `requirement`? Its side's, and its
    /// suite's, and what it exercises of another suite (the interface suite's
    /// Gherkin scenarios reach a few CANopen requirements).
    pub fn reports(&self, requirement: &crate::Requirement, exercised: bool) -> bool {
        requirement.side == self.side && (requirement.suite == self.suite || exercised)
    }
}
