//! Receive filters: which identifiers reach the CAN interface.
//!
//! Source: 000/001 §7 "Benutzung eines Filters", ruling G7: rows are evaluated in
//! table order and the first matching row decides; with no matching row a frame
//! is rejected if the table has any acceptance row and accepted otherwise.

use crate::frame::{CanId, EXTENDED_ID_MAX};

/// Whether a row lets frames through ("+") or holds them back ("-").
///
/// Requirements: FLT-001, FLT-002.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FilterAction {
    Accept,
    Reject,
}

/// Which identifiers a row matches.
///
/// Requirements: FLT-003, FLT-004.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FilterMatch {
    /// `from ..= to`, inclusive.
    Range { from: u32, to: u32 },
    /// Identifiers with `(id & mask) == (code & mask)` ("acceptance mask").
    CodeMask { code: u32, mask: u32 },
}

/// One row of the filter table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FilterRow {
    pub action: FilterAction,
    pub matches: FilterMatch,
}

impl FilterRow {
    pub fn accept_range(from: u32, to: u32) -> Self {
        FilterRow {
            action: FilterAction::Accept,
            matches: FilterMatch::Range { from, to },
        }
    }

    pub fn reject_range(from: u32, to: u32) -> Self {
        FilterRow {
            action: FilterAction::Reject,
            matches: FilterMatch::Range { from, to },
        }
    }

    pub fn accept_code_mask(code: u32, mask: u32) -> Self {
        FilterRow {
            action: FilterAction::Accept,
            matches: FilterMatch::CodeMask { code, mask },
        }
    }

    /// Does this row match the identifier? Rows compare the identifier's value:
    /// an 11-bit and a 29-bit identifier of the same value match alike (FLT-007).
    ///
    /// Requirements: FLT-003, FLT-004, FLT-007.
    pub fn matches(&self, id: CanId) -> bool {
        let id = id.raw();
        match self.matches {
            FilterMatch::Range { from, to } => from <= id && id <= to,
            FilterMatch::CodeMask { code, mask } => id & mask == code & mask,
        }
    }

    /// A row names identifiers within 29 bits, and a range runs upwards.
    pub fn check(&self) -> Result<(), String> {
        match self.matches {
            FilterMatch::Range { from, to } if from > to => {
                Err(format!("range 0x{from:X}..0x{to:X} runs backwards"))
            }
            FilterMatch::Range { to, .. } if to > EXTENDED_ID_MAX => {
                Err(format!("0x{to:X} is beyond 29 bits"))
            }
            FilterMatch::CodeMask { code, mask } if (code | mask) > EXTENDED_ID_MAX => Err(
                format!("code 0x{code:X} / mask 0x{mask:X} is beyond 29 bits"),
            ),
            _ => Ok(()),
        }
    }
}

/// Does the table let a frame with this identifier into the interface?
///
/// Requirements: FLT-005, FLT-006, FLT-008.
pub fn accepts(table: &[FilterRow], id: CanId) -> bool {
    match table.iter().find(|row| row.matches(id)) {
        Some(row) => row.action == FilterAction::Accept,
        None => !table.iter().any(|row| row.action == FilterAction::Accept),
    }
}

/// The filter table of 001 §7: reject 0x0–0x3FF, accept 0x400–0x700, reject
/// 0x701–0x1FFFFFFF.
///
/// Requirements: FLT-009.
pub fn manual_example() -> [FilterRow; 3] {
    [
        FilterRow::reject_range(0x0000_0000, 0x0000_03FF),
        FilterRow::accept_range(0x0000_0400, 0x0000_0700),
        FilterRow::reject_range(0x0000_0701, 0x1FFF_FFFF),
    ]
}
