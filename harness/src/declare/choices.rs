//! The choices the documents leave, as a device declares them (issue 26).
//! A declared choice is judged as declared. Where a device declares nothing,
//! every documented choice is accepted: the first scenario that tells the send
//! queue's accountings apart shows which one the device takes, and the rest of
//! the profile holds it to that one; the freedoms of G3 are judged by their
//! bounds, and what Rx slots and an idle NoOfRxMessages hold is not judged.

use std::fmt;

use super::{Declaration, DeclarationError};

use canif_model::config::{Capabilities, TxQueueAccounting};
use canif_model::exchange::SYNC1_TX_JITTER;
use canif_model::freedoms::{BadTxLength, Named, OversizeBatch, RxIdleCount, StaleRxSlots};
use canif_model::Nanos;
use canif_spec::{req_ids, ReqId};

/// What a device says it does where the documents leave a choice; `None`: it
/// says nothing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Declared {
    /// HS-TX-012: whether the frame on the wire counts against the send queue.
    pub tx_queue_accounting: Option<TxQueueAccounting>,
    /// HS-TX-008: how many messages the local send queue holds. No document
    /// gives it; undeclared, the profile's assumed depth is judged.
    pub tx_queue_depth: Option<usize>,
    /// PDX-004 (ruling R10): the time from SYNC1 to the start of the first Tx
    /// message, in ns. Undeclared, each scenario measures it and holds every
    /// batch to within the 500 ns jitter of the others.
    pub sync1_output_delay: Option<Nanos>,
    /// PDX-004: the most the start lies after SYNC1 + the output delay, in ns
    /// (at most 003's 500); undeclared, 500.
    pub sync1_jitter: Option<Nanos>,
    /// HS-TX-010 (G3): what a batch beyond the slots sends.
    pub oversize_batch: Option<OversizeBatch>,
    /// LAY-GEN-008 (G3): what a message with its length out of range sends.
    pub bad_tx_length: Option<BadTxLength>,
    /// HS-RX-009: NoOfRxMessages once the PLC acknowledged and nothing new came.
    pub rx_idle_count: Option<RxIdleCount>,
    /// HS-RX-008: what a delivery leaves in the slots past its NoOfRxMessages.
    pub stale_rx_slots: Option<StaleRxSlots>,
}

/// A choice the documents leave, by the name it is declared with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Choice {
    TxQueueAccounting,
    TxQueueDepth,
    Sync1OutputDelay,
    Sync1Jitter,
    OversizeBatch,
    BadTxLength,
    RxIdleCount,
    StaleRxSlots,
}

/// The values of a named choice, joined for a message.
fn values<T: Named>() -> String {
    T::NAMES.join(" or ")
}

fn named<T: Named>(value: &str) -> Option<T> {
    T::from_name(value)
}

impl Choice {
    pub const ALL: [Choice; 8] = [
        Choice::TxQueueAccounting,
        Choice::TxQueueDepth,
        Choice::Sync1OutputDelay,
        Choice::Sync1Jitter,
        Choice::OversizeBatch,
        Choice::BadTxLength,
        Choice::RxIdleCount,
        Choice::StaleRxSlots,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Choice::TxQueueAccounting => "tx-queue-accounting",
            Choice::TxQueueDepth => "tx-queue-depth",
            Choice::Sync1OutputDelay => "sync1-output-delay-ns",
            Choice::Sync1Jitter => "sync1-jitter-ns",
            Choice::OversizeBatch => "oversize-batch",
            Choice::BadTxLength => "bad-tx-length",
            Choice::RxIdleCount => "rx-idle-count",
            Choice::StaleRxSlots => "stale-rx-slots",
        }
    }

    pub fn from_name(name: &str) -> Option<Choice> {
        Choice::ALL.into_iter().find(|c| c.name() == name)
    }

    /// What the choice decides, and the requirement that leaves it.
    pub fn description(self) -> &'static str {
        match self {
            Choice::TxQueueAccounting => "whether the frame on the wire counts against the send queue's depth (HS-TX-012)",
            Choice::TxQueueDepth => "messages the local send queue holds (HS-TX-008; no document gives it, the profiles assume 64)",
            Choice::Sync1OutputDelay => "with Distributed Clocks, ns from SYNC1 to the start of the first Tx message (PDX-004, ruling R10)",
            Choice::Sync1Jitter => "with Distributed Clocks, the most ns the first Tx message starts after SYNC1 + the output delay (PDX-004; 003 allows 500)",
            Choice::OversizeBatch => "what a batch whose NoOfTxMessages exceeds the slots sends (HS-TX-010, G3)",
            Choice::BadTxLength => "what a Tx message whose length is out of range sends (LAY-GEN-008, G3)",
            Choice::RxIdleCount => "NoOfRxMessages once the PLC has acknowledged and nothing new was entered (HS-RX-009)",
            Choice::StaleRxSlots => "what a delivery leaves in the Rx slots past its NoOfRxMessages (HS-RX-008)",
        }
    }

    /// What a value must be, in words.
    pub fn expects(self) -> String {
        match self {
            Choice::TxQueueAccounting => values::<TxQueueAccounting>(),
            Choice::TxQueueDepth => "a number of messages, at least 1".into(),
            Choice::Sync1OutputDelay => "a number of nanoseconds".into(),
            Choice::Sync1Jitter => format!("a number of nanoseconds, at most {SYNC1_TX_JITTER}"),
            Choice::OversizeBatch => values::<OversizeBatch>(),
            Choice::BadTxLength => values::<BadTxLength>(),
            Choice::RxIdleCount => values::<RxIdleCount>(),
            Choice::StaleRxSlots => values::<StaleRxSlots>(),
        }
    }

    /// The values a probe tries, for the choices that have a few.
    pub fn named_values(self) -> &'static [&'static str] {
        match self {
            Choice::TxQueueAccounting => TxQueueAccounting::NAMES,
            Choice::OversizeBatch => OversizeBatch::NAMES,
            Choice::BadTxLength => BadTxLength::NAMES,
            Choice::RxIdleCount => RxIdleCount::NAMES,
            Choice::StaleRxSlots => StaleRxSlots::NAMES,
            Choice::TxQueueDepth | Choice::Sync1OutputDelay | Choice::Sync1Jitter => &[],
        }
    }

    /// The requirement whose scenarios tell this choice's values apart.
    pub fn settled_by(self) -> Option<ReqId> {
        match self {
            Choice::TxQueueAccounting => Some(TX_QUEUE_ACCOUNTING_SETTLED_BY),
            Choice::OversizeBatch => Some(ReqId::new("HS-TX-010")),
            Choice::BadTxLength => Some(ReqId::new("LAY-GEN-008")),
            Choice::RxIdleCount => Some(ReqId::new("HS-RX-009")),
            Choice::StaleRxSlots => Some(ReqId::new("HS-RX-008")),
            Choice::TxQueueDepth | Choice::Sync1OutputDelay | Choice::Sync1Jitter => None,
        }
    }
}

impl fmt::Display for Choice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The requirements the send queue's accounting decides: a failure blamed on
/// one of them, while the device declared none, is tried under the other.
pub(crate) const TX_QUEUE_ACCOUNTING_IDS: &[ReqId] =
    req_ids!["HS-TX-007", "HS-TX-008", "HS-TX-012"];

/// The requirement whose scenarios tell the accountings apart.
pub(crate) const TX_QUEUE_ACCOUNTING_SETTLED_BY: ReqId = ReqId::new("HS-TX-012");

impl Declaration for Declared {
    /// Adds one `NAME=VALUE` (the command line's `--declare`, a line of a
    /// probe's file).
    fn declare(&mut self, text: &str) -> Result<(), DeclarationError> {
        let (name, value) = text
            .split_once('=')
            .map(|(n, v)| (n.trim(), v.trim()))
            .ok_or_else(|| DeclarationError::Malformed {
                line: text.to_string(),
            })?;
        let choice = Choice::from_name(name).ok_or_else(|| DeclarationError::UnknownName {
            name: name.to_string(),
            what: "choice",
            known: Choice::ALL.iter().map(|c| c.name()).collect(),
        })?;
        let unknown = || DeclarationError::BadValue {
            name: choice.name(),
            value: value.to_string(),
            expected: choice.expects(),
        };
        let number = || value.parse::<u64>().ok();
        match choice {
            Choice::TxQueueAccounting => {
                self.tx_queue_accounting = Some(named(value).ok_or_else(unknown)?)
            }
            Choice::TxQueueDepth => {
                let depth = number().filter(|d| *d > 0).ok_or_else(unknown)?;
                self.tx_queue_depth = Some(usize::try_from(depth).map_err(|_| unknown())?);
            }
            Choice::Sync1OutputDelay => {
                self.sync1_output_delay = Some(number().ok_or_else(unknown)?)
            }
            Choice::Sync1Jitter => {
                let jitter = number().filter(|ns| *ns <= SYNC1_TX_JITTER);
                self.sync1_jitter = Some(jitter.ok_or_else(unknown)?);
            }
            Choice::OversizeBatch => self.oversize_batch = Some(named(value).ok_or_else(unknown)?),
            Choice::BadTxLength => self.bad_tx_length = Some(named(value).ok_or_else(unknown)?),
            Choice::RxIdleCount => self.rx_idle_count = Some(named(value).ok_or_else(unknown)?),
            Choice::StaleRxSlots => self.stale_rx_slots = Some(named(value).ok_or_else(unknown)?),
        }
        Ok(())
    }

    /// Each declared choice as `NAME=VALUE`.
    fn lines(&self) -> Vec<String> {
        Choice::ALL
            .into_iter()
            .filter_map(|c| Some(format!("{}={}", c.name(), self.value(c)?)))
            .collect()
    }
}

impl Declared {
    /// The declared value of `choice`, as it is written.
    pub fn value(&self, choice: Choice) -> Option<String> {
        let name = |v: Option<&'static str>| v.map(str::to_string);
        match choice {
            Choice::TxQueueAccounting => name(self.tx_queue_accounting.map(Named::name)),
            Choice::TxQueueDepth => self.tx_queue_depth.map(|n| n.to_string()),
            Choice::Sync1OutputDelay => self.sync1_output_delay.map(|ns| ns.to_string()),
            Choice::Sync1Jitter => self.sync1_jitter.map(|ns| ns.to_string()),
            Choice::OversizeBatch => name(self.oversize_batch.map(Named::name)),
            Choice::BadTxLength => name(self.bad_tx_length.map(Named::name)),
            Choice::RxIdleCount => name(self.rx_idle_count.map(Named::name)),
            Choice::StaleRxSlots => name(self.stale_rx_slots.map(Named::name)),
        }
    }

    /// Forgets what was declared of `choice`.
    pub fn forget(&mut self, choice: Choice) {
        match choice {
            Choice::TxQueueAccounting => self.tx_queue_accounting = None,
            Choice::TxQueueDepth => self.tx_queue_depth = None,
            Choice::Sync1OutputDelay => self.sync1_output_delay = None,
            Choice::Sync1Jitter => self.sync1_jitter = None,
            Choice::OversizeBatch => self.oversize_batch = None,
            Choice::BadTxLength => self.bad_tx_length = None,
            Choice::RxIdleCount => self.rx_idle_count = None,
            Choice::StaleRxSlots => self.stale_rx_slots = None,
        }
    }

    /// These declarations, and `fallback`'s where these say nothing.
    pub fn or(self, fallback: Declared) -> Declared {
        let mut both = fallback;
        for line in self.lines() {
            let _ = both.declare(&line);
        }
        both
    }

    /// The first choice these and `other` both declare, with different
    /// values: this one's and the other's.
    pub fn contradiction(&self, other: &Declared) -> Option<(Choice, String, String)> {
        Choice::ALL.into_iter().find_map(|choice| {
            let (mine, theirs) = (self.value(choice)?, other.value(choice)?);
            (mine != theirs).then_some((choice, mine, theirs))
        })
    }

    /// These declarations, less those `told` makes (what an IUT declared that
    /// the command line did not declare already).
    pub fn except(self, told: &Declared) -> Declared {
        let mut left = self;
        for choice in Choice::ALL {
            if told.value(choice).is_some() {
                left.forget(choice);
            }
        }
        left
    }

    /// The capabilities the model judges by: `caps` with these choices.
    pub fn apply(&self, caps: &Capabilities) -> Capabilities {
        let freedoms = caps.freedoms;
        Capabilities {
            tx_queue_accounting: self.tx_queue_accounting.unwrap_or(caps.tx_queue_accounting),
            tx_queue_depth: self.tx_queue_depth.unwrap_or(caps.tx_queue_depth),
            sync1_output_delay: self.sync1_output_delay.or(caps.sync1_output_delay),
            freedoms: canif_model::freedoms::Freedoms {
                oversize_batch: self.oversize_batch.unwrap_or(freedoms.oversize_batch),
                bad_tx_length: self.bad_tx_length.unwrap_or(freedoms.bad_tx_length),
                rx_idle_count: self.rx_idle_count.unwrap_or(freedoms.rx_idle_count),
                stale_rx_slots: self.stale_rx_slots.unwrap_or(freedoms.stale_rx_slots),
            },
            ..caps.clone()
        }
    }

    /// Each declared choice by name, as a probe's file and the protocol's
    /// `declares` carry them.
    pub fn entries(&self) -> std::collections::BTreeMap<String, String> {
        Choice::ALL
            .into_iter()
            .filter_map(|c| Some((c.name().to_string(), self.value(c)?)))
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
        let choice = Choice::TxQueueAccounting;
        format!("{choice}={}", self.tx_queue_accounting.name())
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
        assert_eq!(Declared::parse(&declared.lines()), Ok(declared));
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
            ..Declared::default()
        };
        let outside = Declared {
            tx_queue_accounting: Some(TxQueueAccounting::WireOutsideQueue),
            sync1_output_delay: None,
            tx_queue_depth: Some(8),
            ..Declared::default()
        };
        assert_eq!(wire_in.or(outside).tx_queue_depth, Some(8));
        assert_eq!(
            wire_in.or(outside).tx_queue_accounting,
            wire_in.tx_queue_accounting
        );
        assert_eq!(Declared::default().or(outside), outside);
    }
}
