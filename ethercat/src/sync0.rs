//! Distributed Clocks: the SYNC0 events that start the application's cycle
//! when the master activated them (ETG.1000.4 §9.3 "SYNC0/SYNC1"; 003 "Synchronization
//! with SYNC0/SYNC1 event": SYNC0 starts the CAN interface cycle).
//!
//! The first event comes at the start time the master wrote to 0x0990, in
//! system time; the next every SYNC0 cycle (0x09A0) after. The ESC's local
//! clock is the system time less the offset the master wrote (0x0920).

/// The SYNC0 events still to come, in system time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sync0Schedule {
    next: u64,
    cycle: u64,
    /// Events that came while the host was not asking (a stalled host): the
    /// application ran once for all of them.
    pub missed: u64,
}

impl Sync0Schedule {
    /// Events from `start` every `cycle` ns; a start already past `now`
    /// (both system time; a master that wrote none leaves 0) begins at the
    /// next whole cycle after `now`.
    pub fn new(start: u64, cycle: u32, now: u64) -> Option<Sync0Schedule> {
        let cycle = u64::from(cycle);
        if cycle == 0 {
            return None;
        }
        let next = if start < now {
            (now / cycle + 1) * cycle
        } else {
            start
        };
        Some(Sync0Schedule {
            next,
            cycle,
            missed: 0,
        })
    }

    /// When the next event comes, in system time.
    pub fn next(&self) -> u64 {
        self.next
    }

    /// The event due before system time `before` (or at it, `inclusive`):
    /// its time, the schedule moved on past it. Events further overdue are
    /// folded into this one and counted as missed.
    pub fn take_due(&mut self, before: u64, inclusive: bool) -> Option<u64> {
        let due = if inclusive {
            self.next <= before
        } else {
            self.next < before
        };
        if !due {
            return None;
        }
        // The last event due, counted, not walked to: a master may set the
        // clock so far off (an offset of 2^62 ns) that walking event by
        // event never ends.
        let span = before - self.next - u64::from(!inclusive);
        let skipped = span / self.cycle;
        self.missed = self.missed.saturating_add(skipped);
        let at = self.next + skipped * self.cycle;
        self.next = at.saturating_add(self.cycle);
        Some(at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_come_every_cycle_from_the_start_time_and_a_frame_at_an_event_comes_first() {
        let mut schedule = Sync0Schedule::new(5_000, 1_000, 1_000).unwrap();
        assert_eq!(schedule.next(), 5_000);
        assert_eq!(
            schedule.take_due(5_000, false),
            None,
            "a frame at the event"
        );
        assert_eq!(schedule.take_due(5_000, true), Some(5_000), "a timer at it");
        assert_eq!(schedule.take_due(6_001, false), Some(6_000));
        assert_eq!(schedule.next(), 7_000);
        assert_eq!(schedule.missed, 0);
    }

    #[test]
    fn a_stalled_host_runs_the_cycle_once_and_counts_the_missed_events() {
        let mut schedule = Sync0Schedule::new(1_000, 1_000, 0).unwrap();
        assert_eq!(schedule.take_due(4_500, false), Some(4_000));
        assert_eq!(schedule.missed, 3);
        assert_eq!(schedule.next(), 5_000);
    }

    /// A master that set the system time 2^62 ns ahead, with SYNC0 at 1 ms:
    /// 4.6e12 events overdue are counted in one step (they were walked one
    /// by one, and `canif device --ethercat` hung at 100 % CPU).
    #[test]
    fn a_clock_set_far_ahead_is_one_step_however_many_events_it_skips() {
        let mut schedule = Sync0Schedule::new(0, 1_000_000, 0).unwrap();
        let far = 1u64 << 62;
        let last = far / 1_000_000;
        assert_eq!(schedule.take_due(far, true), Some(last * 1_000_000));
        assert_eq!(schedule.missed, last);
        assert_eq!(schedule.next(), (last + 1) * 1_000_000);
        // At the very end of time the schedule stops instead of wrapping.
        let mut schedule = Sync0Schedule::new(0, 1_000, 0).unwrap();
        assert!(schedule.take_due(u64::MAX, false).is_some());
        assert_eq!(schedule.next(), u64::MAX);
        assert_eq!(schedule.take_due(u64::MAX, false), None);
    }

    #[test]
    fn a_start_time_in_the_past_or_none_begins_at_the_next_whole_cycle() {
        assert_eq!(Sync0Schedule::new(0, 1_000, 2_500).unwrap().next(), 3_000);
        assert_eq!(
            Sync0Schedule::new(0, 1_000, 0).unwrap().next(),
            0,
            "at the clock's origin"
        );
        assert_eq!(
            Sync0Schedule::new(1_000, 1_000, 2_500).unwrap().next(),
            3_000
        );
        assert_eq!(Sync0Schedule::new(1_000, 0, 0), None);
    }
}
