//! The slot geometry a client declares: `slots` for both directions, or
//! `tx-slots` and `rx-slots` apart, as a terminal's settings hold the Tx and
//! Rx slot counts apart (issue 36). The geometries a client is run at follow
//! from the two ranges.

use std::fmt;

/// The most slots an image has each way (ruling R2).
pub const MAX_SLOTS: u8 = 32;

/// The slot counts a client's code runs with, one way (1..=32, R2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlotRange {
    pub min: u8,
    pub max: u8,
}

impl SlotRange {
    /// Every count an image may have.
    pub const ANY: SlotRange = SlotRange {
        min: 1,
        max: MAX_SLOTS,
    };

    pub fn contains(self, slots: u8) -> bool {
        (self.min..=self.max).contains(&slots)
    }

    /// `N` or `MIN..MAX`, each within 1..=32; `None` for anything else.
    pub(super) fn parse(value: &str) -> Option<SlotRange> {
        let count = |s: &str| {
            s.trim()
                .parse::<u8>()
                .ok()
                .filter(|n| (1..=MAX_SLOTS).contains(n))
        };
        let (min, max) = match value.split_once("..") {
            Some((min, max)) => (count(min)?, count(max)?),
            None => (count(value)?, count(value)?),
        };
        (min <= max).then_some(SlotRange { min, max })
    }

    /// The part of the range a profile with `max_slots` offers, if any.
    fn within(self, max_slots: u8) -> Option<(u8, u8)> {
        let high = self.max.min(max_slots);
        (self.min <= high).then_some((self.min, high))
    }
}

impl fmt::Display for SlotRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.min == self.max {
            true => write!(f, "{}", self.min),
            false => write!(f, "{}..{}", self.min, self.max),
        }
    }
}

/// The (Tx, Rx) slot counts a client taking `tx` and `rx` is run at on a
/// profile with `max_slots`: the default 8 each way (or the nearest it
/// takes) first, then the edges of both ranges together, then the edges
/// apart (the most Tx slots with the fewest Rx slots and the other way
/// round), where a client that sizes one direction by the other's count
/// shows it. Empty where the profile offers a direction none of its counts.
pub(super) fn geometries(tx: SlotRange, rx: SlotRange, max_slots: u8) -> Vec<(u8, u8)> {
    let (Some((tx_low, tx_high)), Some((rx_low, rx_high))) =
        (tx.within(max_slots), rx.within(max_slots))
    else {
        return Vec::new();
    };
    let mut list = Vec::new();
    for geometry in [
        (8.clamp(tx_low, tx_high), 8.clamp(rx_low, rx_high)),
        (tx_low, rx_low),
        (tx_high, rx_high),
        (tx_high, rx_low),
        (tx_low, rx_high),
    ] {
        if !list.contains(&geometry) {
            list.push(geometry);
        }
    }
    list
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_range_reads_as_written_and_refuses_what_no_image_has() {
        assert_eq!(SlotRange::parse("10"), Some(SlotRange { min: 10, max: 10 }));
        assert_eq!(SlotRange::parse("4..16").unwrap().to_string(), "4..16");
        for bad in ["0", "33", "12..4", "x", "1..40"] {
            assert_eq!(SlotRange::parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn geometries_are_the_default_the_edges_and_the_edges_apart() {
        let any = SlotRange::ANY;
        assert_eq!(
            geometries(any, any, 32),
            [(8, 8), (1, 1), (32, 32), (32, 1), (1, 32)]
        );
        let ten = SlotRange { min: 10, max: 10 };
        assert_eq!(geometries(ten, ten, 32), [(10, 10)]);
        assert!(geometries(ten, ten, 8).is_empty());
        let twenty = SlotRange { min: 20, max: 20 };
        assert_eq!(geometries(ten, twenty, 32), [(10, 20)]);
        let range = SlotRange { min: 4, max: 16 };
        assert_eq!(
            geometries(range, range, 32),
            [(8, 8), (4, 4), (16, 16), (16, 4), (4, 16)]
        );
    }
}
