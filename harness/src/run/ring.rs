//! The last few items of a run, kept in a bounded ring: memory does not grow
//! with the run's length, and a failure shows what came just before it.

use std::collections::VecDeque;

/// How many cycles (device side) or tasks (PLC side) of history a failure shows.
pub const CONTEXT: usize = 6;

/// At most `capacity` items, the oldest dropped first.
#[derive(Debug, Clone)]
pub struct Ring<T> {
    items: VecDeque<T>,
    capacity: usize,
}

impl<T> Ring<T> {
    pub fn new(capacity: usize) -> Self {
        Ring {
            items: VecDeque::with_capacity(capacity + 1),
            capacity,
        }
    }

    /// A ring of a failure's history: [`CONTEXT`] items.
    pub fn context() -> Self {
        Ring::new(CONTEXT)
    }

    pub fn push(&mut self, item: T) {
        self.items.push_back(item);
        if self.items.len() > self.capacity {
            self.items.pop_front();
        }
    }

    /// Oldest first.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = &T> + ExactSizeIterator {
        self.items.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::Ring;

    #[test]
    fn a_ring_keeps_the_newest_items_in_order() {
        let mut ring = Ring::new(3);
        for n in 0..5 {
            ring.push(n);
        }
        assert_eq!(ring.iter().copied().collect::<Vec<_>>(), [2, 3, 4]);
        assert_eq!(Ring::<u8>::context().capacity, super::CONTEXT);
    }
}
