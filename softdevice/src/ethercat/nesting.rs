//! Consistency nesting (ETG.1020): Beckhoff's EL6751 manual configures the
//! CAN interface with start-up SDOs "with Complete Access or with
//! consistency nesting". Sub-index 0 written 0 opens an object, its entries
//! are written, sub-index 0 written back closes it, and the terminal judges
//! the whole object then: the refusal, if any, is the abort of that last
//! write. An array's count 0 (the filter table, a PDO assignment) is a
//! configuration of its own and stands at once; a record's sub-index 0 is
//! its highest sub-index, so a record left open cannot start (SAFEOP).

use super::objects::{interface, object};

/// The objects a master may configure with nesting.
const NESTED: [u16; 5] = [
    object::INTERFACE,
    object::FILTERS,
    object::BUS_PARAMETERS,
    object::RX_PDO_ASSIGN,
    object::TX_PDO_ASSIGN,
];

/// An object opened by its sub-index 0 written 0, and what was written to it since.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Nesting {
    pub index: u16,
    pub writes: Vec<(u8, Vec<u8>)>,
}

/// What one download does to the nesting.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum Step {
    /// Not nested: written and judged as it comes.
    Direct,
    /// Sub-index 0 written 0: the object opens (`count_now`: an array's
    /// count 0 is written at once).
    Open { count_now: bool },
    /// An entry of the open object: kept until it closes.
    Keep,
    /// Sub-index 0 written back: these entries, in this order, judged together.
    Close(Vec<(u8, Vec<u8>)>),
}

/// A record's sub-index 0: its highest sub-index, not a count.
pub(super) fn highest(index: u16) -> Option<u8> {
    match index {
        object::INTERFACE => Some(interface::TX_QUEUE),
        object::BUS_PARAMETERS => Some(2),
        _ => None,
    }
}

/// What the download `values` of `index` does, given the object open now
/// (taken; put back by the caller where it stays open).
pub(super) fn step(open: &mut Option<Nesting>, index: u16, values: &[(u8, Vec<u8>)]) -> Step {
    if !NESTED.contains(&index) {
        return Step::Direct;
    }
    let sub0 = match values {
        [(0, value)] => Some(value.first().copied().unwrap_or(0)),
        _ => None,
    };
    let this = open.as_ref().is_some_and(|n| n.index == index);
    match (this, sub0) {
        (false, Some(0)) => {
            *open = Some(Nesting {
                index,
                writes: Vec::new(),
            });
            Step::Open {
                count_now: highest(index).is_none(),
            }
        }
        // A complete access, or an object not opened: as it comes (a
        // complete access replaces what an open nesting had kept).
        (_, _) if values.len() > 1 && values.iter().any(|(sub, _)| *sub == 0) => {
            if this {
                *open = None;
            }
            Step::Direct
        }
        (false, _) => Step::Direct,
        (true, None) => {
            if let Some(nesting) = open.as_mut() {
                nesting.writes.extend(values.iter().cloned());
            }
            Step::Keep
        }
        (true, Some(_)) => {
            let nesting = open.take().expect("open");
            // An array's new count first, then its entries; a record's
            // sub-index 0 sets nothing, and is checked by the caller.
            let mut all = Vec::with_capacity(nesting.writes.len() + 1);
            if highest(index).is_none() {
                all.extend(values.iter().cloned());
            }
            all.extend(nesting.writes);
            Step::Close(all)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sub_index_zero_written_zero_opens_and_written_back_closes_with_every_entry() {
        let mut open = None;
        let interface = object::INTERFACE;
        assert_eq!(
            step(&mut open, interface, &[(0, vec![0])]),
            Step::Open { count_now: false }
        );
        assert_eq!(step(&mut open, interface, &[(1, vec![8, 0])]), Step::Keep);
        assert_eq!(step(&mut open, interface, &[(2, vec![4, 0])]), Step::Keep);
        assert_eq!(
            step(&mut open, interface, &[(0, vec![interface::TX_QUEUE])]),
            Step::Close(vec![(1, vec![8, 0]), (2, vec![4, 0])])
        );
        assert_eq!(open, None);
    }

    #[test]
    fn an_array_takes_its_count_first_and_its_zero_count_at_once() {
        let mut open = None;
        let filters = object::FILTERS;
        assert_eq!(
            step(&mut open, filters, &[(0, vec![0])]),
            Step::Open { count_now: true }
        );
        assert_eq!(step(&mut open, filters, &[(1, vec![1; 10])]), Step::Keep);
        assert_eq!(
            step(&mut open, filters, &[(0, vec![1])]),
            Step::Close(vec![(0, vec![1]), (1, vec![1; 10])])
        );
    }

    #[test]
    fn what_is_not_nested_is_written_as_it_comes() {
        let mut open = None;
        // Another object, an entry without an opening, a complete access.
        assert_eq!(step(&mut open, 0x1C32, &[(0, vec![0])]), Step::Direct);
        assert_eq!(
            step(&mut open, object::INTERFACE, &[(1, vec![0, 0])]),
            Step::Direct
        );
        step(&mut open, object::FILTERS, &[(0, vec![0])]);
        let complete = [(0, vec![1]), (1, vec![0; 10])];
        assert_eq!(step(&mut open, object::FILTERS, &complete), Step::Direct);
        assert_eq!(open, None, "a complete access replaces the nesting");
    }
}
