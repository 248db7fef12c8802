//! A barrier for the threads of one parallel region (one `rayon::broadcast`) of the
//! Gauss–Seidel sweep ([`crate::nsgs`]): between two colours every thread must have finished
//! its updates before any starts the next colour.
//!
//! Written by hand because neither std nor rayon has what is needed: `std::sync::Barrier`
//! parks the waiting threads (a futex sleep and wake-up per colour, tens of µs: the cost that
//! one region per sweep removes, docs/scaling.md "Threads"), and rayon offers no barrier inside
//! a broadcast. Waiters spin briefly, then park until the last thread arrives: on a quiet
//! machine the colours meet within the spin, and on an oversubscribed one a waiter does not
//! take the core from the thread everyone waits for.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::thread::Thread;

/// Spins before a waiter parks (a `pause` is ≈ 10–40 ns: about 3–10 µs in all, longer than
/// the threads' usual difference in finishing a colour on a quiet machine).
const SPINS: u32 = 256;

/// A reusable barrier of a fixed number of threads (a generation counter).
pub(crate) struct SpinBarrier {
    threads: usize,
    arrived: AtomicUsize,
    generation: AtomicUsize,
    /// the waiters that stopped spinning, to be unparked by the last arrival
    parked: Mutex<Vec<Thread>>,
}

impl SpinBarrier {
    /// A barrier for `threads` threads (at least one).
    pub(crate) fn new(threads: usize) -> Self {
        Self {
            threads: threads.max(1),
            arrived: AtomicUsize::new(0),
            generation: AtomicUsize::new(0),
            parked: Mutex::new(Vec::new()),
        }
    }

    /// Returns once all `threads` threads have called `wait` for this generation; everything a
    /// thread wrote before its call is visible to every thread after theirs.
    pub(crate) fn wait(&self) {
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.threads {
            // the last one: reset for the next use, then release the others
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
            let parked = std::mem::take(&mut *self.waiters());
            parked.iter().for_each(Thread::unpark);
            return;
        }
        for _ in 0..SPINS {
            if self.generation.load(Ordering::Acquire) != generation {
                return;
            }
            std::hint::spin_loop();
        }
        {
            // checked under the lock: the last arrival bumps the generation before it takes
            // the lock to unpark, so either it sees this thread in the list or this thread
            // sees the new generation
            let mut waiters = self.waiters();
            if self.generation.load(Ordering::Acquire) != generation {
                return;
            }
            waiters.push(std::thread::current());
        }
        while self.generation.load(Ordering::Acquire) == generation {
            std::thread::park();
        }
    }

    /// The list of parked waiters (a poisoned lock only means a thread panicked while holding
    /// it; the list is still valid).
    fn waiters(&self) -> std::sync::MutexGuard<'_, Vec<Thread>> {
        self.parked.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicU64;

    #[test]
    fn no_thread_passes_a_round_before_all_finished_it() {
        let threads = 3;
        let rounds = 200;
        let barrier = SpinBarrier::new(threads);
        let done = AtomicU64::new(0);
        std::thread::scope(|s| {
            for t in 0..threads {
                let (barrier, done) = (&barrier, &done);
                s.spawn(move || {
                    for round in 0..rounds {
                        // a late thread now and then: the others spin out and park
                        if t == 0 && round % 40 == 0 {
                            std::thread::sleep(std::time::Duration::from_millis(2));
                        }
                        done.fetch_add(1, Ordering::Relaxed);
                        barrier.wait();
                        // every thread's increment of this round is in
                        assert!(done.load(Ordering::Relaxed) >= (round + 1) * threads as u64);
                        barrier.wait();
                    }
                });
            }
        });
        assert_eq!(done.load(Ordering::Relaxed), rounds * threads as u64);
    }
}
