//! The choices the documents leave, as a device declares them (issue 26).
//! A declared choice is judged as declared. Where a device declares nothing,
//! every documented choice is accepted: the first scenario that tells them
//! apart shows which one the device takes, and the rest of the profile holds
//! it to that one.

use std::fmt;

use canif_model::config::TxQueueAccounting;
use canif_spec::{req_ids, ReqId};

/// What a device says it does where the documents leave a choice; `None`: it
/// says nothing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Declared {
    /// HS-TX-012: whether the frame on the wire counts against the send queue.
    pub tx_queue_accounting: Option<TxQueueAccounting>,
}

/// The choices a device can declare, by name.
pub const CHOICES: &[(&str, &str)] = &[(
    TX_QUEUE_ACCOUNTING,
    "whether the frame on the wire counts against the send queue's depth (HS-TX-012): wire-outside-queue | wire-in-queue",
)];

const TX_QUEUE_ACCOUNTING: &str = "tx-queue-accounting";

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
            other => Err(DeclareError::UnknownChoice(other.to_string())),
        }
    }

    /// These declarations, and `fallback`'s where these say nothing.
    pub fn or(self, fallback: Declared) -> Declared {
        Declared {
            tx_queue_accounting: self.tx_queue_accounting.or(fallback.tx_queue_accounting),
        }
    }

    /// Each declared choice as `NAME=VALUE`.
    pub fn lines(&self) -> Vec<String> {
        self.tx_queue_accounting
            .map(|a| format!("{TX_QUEUE_ACCOUNTING}={}", a.name()))
            .into_iter()
            .collect()
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
    }

    #[test]
    fn what_is_declared_wins_over_the_fallback() {
        let wire_in = Declared {
            tx_queue_accounting: Some(TxQueueAccounting::WireInQueue),
        };
        let outside = Declared {
            tx_queue_accounting: Some(TxQueueAccounting::WireOutsideQueue),
        };
        assert_eq!(wire_in.or(outside), wire_in);
        assert_eq!(Declared::default().or(outside), outside);
    }
}
