//! ethercrab's timers, kept by the thread that drives the master.
//!
//! Every PDU ethercrab sends arms a timeout. With its `std` feature each was
//! an async-io timer, and inserting one always wakes async-io's reactor
//! thread: an eventfd write per frame, a fifth of the in-memory run's main
//! thread, and on a veth pair a third busy thread beside master and terminal
//! on two cores (perf, issue 35). Built without `std`, ethercrab keeps time
//! through embassy-time's driver interface; this is that driver. A timer is
//! an entry in one list, which the driving thread ([`block_on`]) looks at
//! between polls and sleeps on until the earliest is due: no thread of its
//! own, nothing to wake.

use std::future::Future;
use std::pin::pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};
use std::task::{Context, Poll, Wake, Waker};
use std::thread::{self, Thread};
use std::time::{Duration, Instant};

// Ticks are microseconds (embassy-time's default rate), as `now` counts them.
const _: () = assert!(embassy_time_driver::TICK_HZ == 1_000_000);

/// The longest a driving thread sleeps without looking again: a bound, not
/// a timer, in case a wake-up comes from somewhere that forgot to wake it.
const LONGEST_SLEEP: Duration = Duration::from_millis(10);

/// The timers waiting, one per waker: all of a drive's PDUs wake the same
/// task, so only its earliest deadline matters (a later one is set again by
/// the timer itself when the task polls it after an early wake-up).
struct Timers {
    due: Mutex<Vec<(u64, Waker)>>,
}

embassy_time_driver::time_driver_impl!(static TIMERS: Timers = Timers { due: Mutex::new(Vec::new()) });

fn since_start() -> Duration {
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed()
}

impl Timers {
    fn due(&self) -> MutexGuard<'_, Vec<(u64, Waker)>> {
        // A panic while the list was held left it whole: each change is one push or retain.
        self.due.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl embassy_time_driver::Driver for Timers {
    fn now(&self) -> u64 {
        since_start().as_micros() as u64
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        let mut due = self.due();
        match due.iter_mut().find(|(_, w)| w.will_wake(waker)) {
            Some(entry) => entry.0 = entry.0.min(at),
            None => due.push((at, waker.clone())),
        }
    }
}

/// Wakes every task whose time has come; the earliest time still ahead.
fn wake_due() -> Option<u64> {
    let now = embassy_time_driver::Driver::now(&TIMERS);
    let mut woken = Vec::new();
    let next = {
        let mut due = TIMERS.due();
        due.retain(|(at, waker)| {
            let waiting = *at > now;
            if !waiting {
                woken.push(waker.clone());
            }
            waiting
        });
        due.iter().map(|(at, _)| *at).min()
    };
    // Outside the list's lock: a waker may run code that arms a timer.
    woken.into_iter().for_each(Waker::wake);
    next
}

/// The driving thread, and whether it was woken since it last polled.
struct Unpark {
    thread: Thread,
    woken: AtomicBool,
}

impl Wake for Unpark {
    fn wake(self: Arc<Self>) {
        self.wake_by_ref();
    }

    fn wake_by_ref(self: &Arc<Self>) {
        if !self.woken.swap(true, Ordering::AcqRel) {
            self.thread.unpark();
        }
    }
}

/// Runs `future` to its end on this thread, sleeping while it waits and
/// waking it when one of its timers is due.
pub(super) fn block_on<F: Future>(future: F) -> F::Output {
    thread_local! {
        // One waker per thread, whatever it drives: the timer list keeps
        // one entry per waker, so it stays as short as the threads are few.
        static UNPARK: Arc<Unpark> = Arc::new(Unpark {
            thread: thread::current(),
            woken: AtomicBool::new(false),
        });
    }
    let unpark = UNPARK.with(Arc::clone);
    let waker = Waker::from(Arc::clone(&unpark));
    let mut cx = Context::from_waker(&waker);
    let mut future = pin!(future);
    loop {
        unpark.woken.store(false, Ordering::Release);
        if let Poll::Ready(output) = future.as_mut().poll(&mut cx) {
            return output;
        }
        // Woken while it ran (a frame came back): polled again at once,
        // without the list (a clock reading and a lock per frame): a timer
        // reads the clock itself when polled, and the whole task is. The
        // list matters only to a task about to sleep.
        if unpark.woken.load(Ordering::Acquire) {
            continue;
        }
        let next = wake_due();
        if unpark.woken.load(Ordering::Acquire) {
            continue;
        }
        let sleep = next.map_or(LONGEST_SLEEP, |at| {
            Duration::from_micros(at.saturating_sub(embassy_time_driver::Driver::now(&TIMERS)))
        });
        thread::park_timeout(sleep.min(LONGEST_SLEEP));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The driver's tick: `now` is whole microseconds since the first reading.
    const TICK: Duration = Duration::from_micros(1);

    #[test]
    fn a_timer_ends_a_wait_no_sooner_than_its_time() {
        let began = Instant::now();
        block_on(embassy_time::Timer::after(
            embassy_time::Duration::from_millis(3),
        ));
        assert!(began.elapsed() + TICK >= Duration::from_millis(3));
    }

    #[test]
    fn a_timer_fires_for_a_task_that_keeps_waking_itself() {
        // Woken on every poll, as a pump with frames in flight is, so never
        // put to sleep on the timer list: the timer is still polled. On a
        // thread of its own, so that a timer that never fires fails
        // the test (a bound far beyond any busy machine's delay), not hangs it.
        let (done, waited) = std::sync::mpsc::channel();
        thread::spawn(move || {
            let busy = std::future::poll_fn(|cx| {
                cx.waker().wake_by_ref();
                Poll::<()>::Pending
            });
            let began = Instant::now();
            let timer = embassy_time::Timer::after(embassy_time::Duration::from_millis(3));
            block_on(futures_lite::future::or(timer, busy));
            let _ = done.send(began.elapsed());
        });
        let waited = waited
            .recv_timeout(Duration::from_secs(60))
            .expect("the timer fired");
        // The driver counts whole microseconds: one may be cut off.
        assert!(waited + TICK >= Duration::from_millis(3));
    }

    /// A waker that counts its wake-ups.
    struct Count(std::sync::atomic::AtomicUsize);

    impl Wake for Count {
        fn wake(self: Arc<Self>) {
            self.0.fetch_add(1, Ordering::SeqCst);
        }
    }

    #[test]
    fn only_the_timers_due_are_woken() {
        let (due, later) = (
            Arc::new(Count(Default::default())),
            Arc::new(Count(Default::default())),
        );
        let (due_waker, later_waker) = (
            Waker::from(Arc::clone(&due)),
            Waker::from(Arc::clone(&later)),
        );
        use embassy_time_driver::Driver;
        TIMERS.schedule_wake(0, &due_waker);
        TIMERS.schedule_wake(u64::MAX, &later_waker);
        let next = wake_due();
        assert_eq!(due.0.load(Ordering::SeqCst), 1);
        assert_eq!(later.0.load(Ordering::SeqCst), 0);
        assert!(next.is_some(), "the later timer is still waiting");
        TIMERS.due().retain(|(_, w)| !w.will_wake(&later_waker));
    }

    #[test]
    fn one_entry_per_waker_at_its_earliest_time() {
        let waker = Waker::from(Arc::new(Unpark {
            thread: thread::current(),
            woken: AtomicBool::new(false),
        }));
        let driver = Timers {
            due: Mutex::new(Vec::new()),
        };
        use embassy_time_driver::Driver;
        driver.schedule_wake(500, &waker);
        driver.schedule_wake(900, &waker);
        driver.schedule_wake(300, &waker);
        let due = driver.due();
        assert_eq!(due.len(), 1);
        assert_eq!(due[0].0, 300);
    }
}
