//! Work on up to `--jobs` threads, results in the items' order: a parallel
//! run reports exactly what a serial one would.

/// `work` on each item, on up to `jobs` threads, in the items' order: `None`
/// for an item a SIGINT kept from starting.
pub(crate) fn in_parallel<T: Sync, R: Send>(
    items: &[T],
    jobs: usize,
    work: impl Fn(usize, &T) -> R + Sync,
) -> Vec<Option<R>> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;
    if jobs <= 1 {
        let mut results = Vec::new();
        for (n, item) in items.iter().enumerate() {
            if canif_harness::interrupt::requested() {
                break;
            }
            results.push(Some(work(n, item)));
        }
        return results;
    }
    let next = AtomicUsize::new(0);
    let results: Vec<Mutex<Option<R>>> = items.iter().map(|_| Mutex::new(None)).collect();
    let worker = || loop {
        let n = next.fetch_add(1, Ordering::SeqCst);
        let Some(item) = items.get(n) else { break };
        if canif_harness::interrupt::requested() {
            break;
        }
        let result = work(n, item);
        *results[n].lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
    };
    std::thread::scope(|scope| {
        let mut spawned = 0;
        for _ in 0..jobs.min(items.len()) {
            // A Gherkin world and the model's state machines want the
            // stack a main thread has, not a spawned thread's 2 MiB.
            let thread = std::thread::Builder::new()
                .stack_size(16 << 20)
                .spawn_scoped(scope, worker);
            spawned += usize::from(thread.is_ok());
        }
        if spawned == 0 {
            // No thread to be had: the work is done here, one at a time.
            worker();
        }
    });
    results
        .into_iter()
        .map(|slot| slot.into_inner().unwrap_or_else(|e| e.into_inner()))
        .collect()
}
