//! The choices the documents leave, as a device declares them (issue 26).
//! A declared choice is judged as declared. Where a device declares nothing,
//! every documented choice is accepted: the first scenario that tells them
//! apart shows which one the device takes, and the rest of the profile holds
//! it to that one.

use std::fmt;

use canif_model::config::TxQueueAccounting;
use canif_model::Nanos;
use canif_spec::{req_ids, ReqId};

/// What a device says it does where the documents leave a choice; `None`: it
/// says nothing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Declared {
    /// HS-TX-012: whether the frame on the wire counts against the send queue.
    pub tx_queue_accounting: Option<TxQueueAccounting>,
    /// PDX-004 (ruling R10): the time from SYNC1 to the start of the first Tx
    /// message, in ns. Undeclared, each scenario measures it and holds every
    /// batch to within the 500 ns jitter of the others.
    pub sync1_output_delay: Option<Nanos>,
    /// HS-TX-008: how many messages the local send queue holds. No document
    /// gives it; undeclared, the profile's assumed depth is judged.
    pub tx_queue_depth: Option<usize>,
}

/// The choices a device can declare, by name.
pub const CHOICES: &[(&str, &str)] = &[
    (
        TX_QUEUE_ACCOUNTING,
        "whether the frame on the wire counts against the send queue's depth (HS-TX-012): wire-outside-queue | wire-in-queue",
    ),
    (
        SYNC1_OUTPUT_DELAY,
        "with Distributed Clocks, ns from SYNC1 to the start of the first Tx message (PDX-004, ruling R10)",
    ),
    (
        TX_QUEUE_DEPTH,
        "messages the local send queue holds (HS-TX-008; no document gives it, the profiles assume 64)",
    ),
];

/// The name the send queue's accounting is declared by.
pub const TX_QUEUE_ACCOUNTING: &str = "tx-queue-accounting";
const SYNC1_OUTPUT_DELAY: &str = "sync1-output-delay-ns";
const TX_QUEUE_DEPTH: &str = "tx-queue-depth";

/// The requirements the send queue's accounting decides: a failure blamed on
/// one of them, while the device declared none, is tried under the other.
pub(crate) const TX_QUEUE_ACCOUNTING_IDS: &[ReqId] =
    req_ids!["HS-TX-007", "HS-TX-008", "HS-TX-012"];

/// The requirement whose scenarios tell the accountings apart.
pub(crate) const TX_QUEUE_ACCOUNTING_SETTLED_BY: ReqId = ReqId::new("HS-TX-012");

/// A declaration that cannot be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DeclareError {
    /// Not `NAME=VALUE`.
    Form(String),
    UnknownChoice(String),
    UnknownValue {
        choice: String,
        value: String,
    },
}

impl fmt::Display for DeclareError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = CHOICES.iter().map(|(name, _)| *name).collect();
        match self {
            DeclareError::Form(text) => write!(f, "`{text}` is not NAME=VALUE"),
            DeclareError::UnknownChoice(name) => write!(
                f,
                "no choice is called `{name}`; the choices are {}",
                names.join(", ")
            ),
            DeclareError::UnknownValue { choice, value } if choice == SYNC1_OUTPUT_DELAY => write!(
                f,
                "{choice} cannot be `{value}`; it is a number of nanoseconds"
            ),
            DeclareError::UnknownValue { choice, value } if choice == TX_QUEUE_DEPTH => write!(
                f,
                "{choice} cannot be `{value}`; it is a number of messages, at least 1"
            ),
            DeclareError::UnknownValue { choice, value } => {
                let values: Vec<&str> = TxQueueAccounting::ALL.iter().map(|a| a.name()).collect();
                write!(
                    f,
                    "{choice} cannot be `{value}`; it is {}",
                    values.join(" or ")
                )
            }
        }
    }
}

impl std::error::Error for DeclareError {}

impl Declared {
    /// Adds one `NAME=VALUE` (the command line's `--declare`, a line of a
    /// probe's file).
    pub fn declare(&mut self, text: &str) -> Result<(), DeclareError> {
        let (name, value) = text
            .split_once('=')
            .map(|(n, v)| (n.trim(), v.trim()))
            .ok_or_else(|| DeclareError::Form(text.to_string()))?;
        match name {
            TX_QUEUE_ACCOUNTING => {
                let accounting = TxQueueAccounting::from_name(value).ok_or_else(|| {
                    DeclareError::UnknownValue {
                        choice: name.to_string(),
                        value: value.to_string(),
                    }
                })?;
                self.tx_queue_accounting = Some(accounting);
                Ok(())
            }
            SYNC1_OUTPUT_DELAY => {
                let delay = value.parse().map_err(|_| DeclareError::UnknownValue {
                    choice: name.to_string(),
                    value: value.to_string(),
                })?;
                self.sync1_output_delay = Some(delay);
                Ok(())
            }
            TX_QUEUE_DEPTH => {
                let depth = value.parse().ok().filter(|d| *d > 0).ok_or_else(|| {
                    DeclareError::UnknownValue {
                        choice: name.to_string(),
                        value: value.to_string(),
                    }
                })?;
                self.tx_queue_depth = Some(depth);
                Ok(())
            }
            other => Err(DeclareError::UnknownChoice(other.to_string())),
        }
    }

    /// These declarations, and `fallback`'s where these say nothing.
    pub fn or(self, fallback: Declared) -> Declared {
        Declared {
            tx_queue_accounting: self.tx_queue_accounting.or(fallback.tx_queue_accounting),
            sync1_output_delay: self.sync1_output_delay.or(fallback.sync1_output_delay),
            tx_queue_depth: self.tx_queue_depth.or(fallback.tx_queue_depth),
        }
    }

    /// What these `NAME=VALUE` lines declare (as [`Declared::lines`] gave them;
    /// a line that is none is left out).
    pub fn from_lines(lines: &[String]) -> Declared {
        let mut declared = Declared::default();
        for line in lines {
            let _ = declared.declare(line);
        }
        declared
    }

    /// Each declared choice by name, as a probe's file and the protocol's
    /// `declares` carry them.
    pub fn entries(&self) -> std::collections::BTreeMap<String, String> {
        self.lines()
            .iter()
            .filter_map(|line| line.split_once('='))
            .map(|(name, value)| (name.to_string(), value.to_string()))
            .collect()
    }

    /// Each declared choice as `NAME=VALUE`.
    pub fn lines(&self) -> Vec<String> {
        let accounting = self
            .tx_queue_accounting
            .map(|a| format!("{TX_QUEUE_ACCOUNTING}={}", a.name()));
        let delay = self
            .sync1_output_delay
            .map(|ns| format!("{SYNC1_OUTPUT_DELAY}={ns}"));
        let depth = self.tx_queue_depth.map(|n| format!("{TX_QUEUE_DEPTH}={n}"));
        accounting.into_iter().chain(delay).chain(depth).collect()
    }
}

/// What a profile's run saw an undeclared device choose, and where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Observed {
    pub profile: String,
    pub tx_queue_accounting: TxQueueAccounting,
    /// The scenario that told the choices apart.
    pub scenario: String,
}

impl Observed {
    /// `NAME=VALUE`, as a declaration of it reads.
    pub fn line(&self) -> String {
        format!("{TX_QUEUE_ACCOUNTING}={}", self.tx_queue_accounting.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_declaration_is_read_by_name_and_value_and_says_what_is_wrong() {
        let mut declared = Declared::default();
        declared
            .declare("tx-queue-accounting=wire-in-queue")
            .unwrap();
        assert_eq!(
            declared.tx_queue_accounting,
            Some(TxQueueAccounting::WireInQueue)
        );
        assert_eq!(declared.lines(), ["tx-queue-accounting=wire-in-queue"]);
        assert_eq!(Declared::from_lines(&declared.lines()), declared);
        assert_eq!(declared.entries()["tx-queue-accounting"], "wire-in-queue");
        let form = declared.declare("wire-in-queue").unwrap_err();
        assert_eq!(form.to_string(), "`wire-in-queue` is not NAME=VALUE");
        let name = declared.declare("queue=x").unwrap_err().to_string();
        assert!(name.contains("tx-queue-accounting"), "{name}");
        let value = declared
            .declare("tx-queue-accounting=maybe")
            .unwrap_err()
            .to_string();
        assert!(
            value.contains("wire-outside-queue or wire-in-queue"),
            "{value}"
        );
        declared.declare("sync1-output-delay-ns=2500").unwrap();
        assert_eq!(declared.sync1_output_delay, Some(2_500));
        assert_eq!(
            declared.lines(),
            [
                "tx-queue-accounting=wire-in-queue",
                "sync1-output-delay-ns=2500"
            ]
        );
        let delay = declared
            .declare("sync1-output-delay-ns=-1")
            .unwrap_err()
            .to_string();
        assert!(delay.contains("a number of nanoseconds"), "{delay}");
    }

    #[test]
    fn what_is_declared_wins_over_the_fallback() {
        let wire_in = Declared {
            tx_queue_accounting: Some(TxQueueAccounting::WireInQueue),
            sync1_output_delay: Some(2_000),
            tx_queue_depth: None,
        };
        let outside = Declared {
            tx_queue_accounting: Some(TxQueueAccounting::WireOutsideQueue),
            sync1_output_delay: None,
            tx_queue_depth: Some(8),
        };
        assert_eq!(wire_in.or(outside).tx_queue_depth, Some(8));
        assert_eq!(
            wire_in.or(outside).tx_queue_accounting,
            wire_in.tx_queue_accounting
        );
        assert_eq!(Declared::default().or(outside), outside);
    }
}
