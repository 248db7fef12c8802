//! Progress of one Gauss–Seidel sweep over its colours, shared by the threads that sweep it
//! as one parallel region ([`crate::nsgs`]): each colour's chunks are claimed one by one, and
//! a thread starts on colour c only once every chunk of colour c − 1 is done.
//!
//! Written by hand because neither std nor rayon has it: rayon's per-colour parallel call
//! puts its idle workers to sleep between colours (a futex wake-up per colour, the cost this
//! removes, docs/scaling.md "Threads"), and `std::sync::Barrier` would make every thread wait
//! for every other one at every colour, a descheduled one included. Here a thread waits only
//! for chunks that another thread is running: a late thread finds its colours done and skips
//! them. Waiters spin briefly, then park until the colour is done (on an oversubscribed
//! machine a waiter does not take the core from the thread it waits for).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};
use std::thread::Thread;

/// Spins before a waiter parks (a `pause` is ≈ 10–40 ns: a few µs in all, longer than the
/// threads' usual difference in finishing a colour on a quiet machine).
const SPINS: u32 = 256;

/// Claimed and done chunks of every colour of one sweep.
pub(crate) struct ColourProgress<'a> {
    /// chunks of each colour
    chunks: &'a [usize],
    claimed: Vec<AtomicUsize>,
    done: Vec<AtomicUsize>,
    /// the threads parked in [`ColourProgress::wait_done`]
    parked: Mutex<Vec<Thread>>,
}

impl<'a> ColourProgress<'a> {
    /// A sweep of colours with `chunks[c]` chunks each, nothing claimed.
    pub(crate) fn new(chunks: &'a [usize]) -> Self {
        Self {
            chunks,
            claimed: chunks.iter().map(|_| AtomicUsize::new(0)).collect(),
            done: chunks.iter().map(|_| AtomicUsize::new(0)).collect(),
            parked: Mutex::new(Vec::new()),
        }
    }

    /// The next unclaimed chunk of colour c (None: all claimed). Each chunk is handed out once.
    pub(crate) fn claim(&self, c: usize) -> Option<usize> {
        let k = self.claimed[c].fetch_add(1, Ordering::Relaxed);
        (k < self.chunks[c]).then_some(k)
    }

    /// Records a claimed chunk of colour c as done; what the thread wrote before is visible to
    /// every thread that [`ColourProgress::wait_done`] releases for this colour.
    pub(crate) fn finish(&self, c: usize) {
        if self.done[c].fetch_add(1, Ordering::AcqRel) + 1 == self.chunks[c] {
            // the colour's last chunk: wake the parked waiters (they check again)
            let parked = std::mem::take(&mut *self.waiters());
            parked.iter().for_each(Thread::unpark);
        }
    }

    /// Returns once every chunk of colour c is done.
    pub(crate) fn wait_done(&self, c: usize) {
        let complete = || self.done[c].load(Ordering::Acquire) == self.chunks[c];
        for _ in 0..SPINS {
            if complete() {
                return;
            }
            std::hint::spin_loop();
        }
        loop {
            {
                // checked under the lock: the last chunk's `finish` counts it done before it
                // takes the lock to unpark, so either it finds this thread in the list or this
                // thread sees the colour complete
                let mut waiters = self.waiters();
                if complete() {
                    return;
                }
                waiters.push(std::thread::current());
            }
            std::thread::park();
            if complete() {
                return;
            }
        }
    }

    /// The list of parked waiters (a poisoned lock only means a thread panicked holding it;
    /// the list is still valid).
    fn waiters(&self) -> MutexGuard<'_, Vec<Thread>> {
        self.parked.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use std::sync::atomic::AtomicU64;

    /// Three threads over 50 colours: every chunk runs once, and no chunk of colour c starts
    /// before all of colour c − 1 are done (each chunk adds to its colour's counter and checks
    /// the previous colour's total); one thread is late now and then, so others park.
    pub fn colours_run_in_order_and_every_chunk_once() {
        let chunks: Vec<usize> = (0..50).map(|c| 1 + c % 7).collect();
        let progress = ColourProgress::new(&chunks);
        let counts: Vec<AtomicU64> = chunks.iter().map(|_| AtomicU64::new(0)).collect();
        std::thread::scope(|s| {
            for t in 0..3 {
                let (progress, counts, chunks) = (&progress, &counts, &chunks);
                s.spawn(move || {
                    for c in 0..chunks.len() {
                        if c > 0 {
                            progress.wait_done(c - 1);
                        }
                        if t == 0 && c % 10 == 0 {
                            std::thread::sleep(std::time::Duration::from_millis(2));
                        }
                        while progress.claim(c).is_some() {
                            if c > 0 {
                                let before = counts[c - 1].load(Ordering::Relaxed);
                                assert_eq!(before, chunks[c - 1] as u64, "colour {c}");
                            }
                            counts[c].fetch_add(1, Ordering::Relaxed);
                            progress.finish(c);
                        }
                    }
                });
            }
        });
        for (c, n) in counts.iter().enumerate() {
            assert_eq!(n.load(Ordering::Relaxed), chunks[c] as u64);
        }
    }
}
