//! A wall-clock budget for work that cannot be interrupted from inside: the existence
//! check's conic solves have a time cap each, but not their setup (an LDL factorization of a
//! large KKT matrix can take minutes).

use std::time::{Duration, Instant};

/// `f()` run on its own thread, or None if it has not returned within `budget` counted from
/// this call, or when SIGINT/SIGTERM arrives first (after [`crate::interrupt::install`]; looked
/// at every 100 ms): the work is then abandoned, and its thread ends with the process. A
/// result that arrives after the deadline is None too, so the answer does not depend on how
/// the two threads happened to be scheduled.
pub fn within<T: Send + 'static>(
    budget: Duration,
    f: impl FnOnce() -> T + Send + 'static,
) -> Option<T> {
    use std::sync::mpsc::RecvTimeoutError;
    let start = Instant::now();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        // the receiver may be gone (time is up): nothing to report then
        let _ = tx.send(f());
    });
    let value = loop {
        let left = budget.saturating_sub(start.elapsed());
        match rx.recv_timeout(left.min(Duration::from_millis(100))) {
            Ok(v) => break v,
            Err(RecvTimeoutError::Timeout)
                if !left.is_zero() && crate::interrupt::received().is_none() => {}
            Err(_) => return None,
        }
    };
    (start.elapsed() <= budget).then_some(value)
}

#[cfg(test)]
mod tests {
    use super::within;
    use std::time::{Duration, Instant};

    #[test]
    fn a_task_past_its_budget_is_abandoned() {
        let start = Instant::now();
        let late = within(Duration::from_millis(50), || {
            std::thread::sleep(Duration::from_secs(5));
            1
        });
        assert_eq!(late, None);
        assert!(start.elapsed() < Duration::from_secs(4));
        assert_eq!(within(Duration::from_secs(5), || 2), Some(2));
    }

    #[test]
    fn a_result_after_the_deadline_is_late_however_the_threads_ran() {
        // a budget shorter than starting a thread: never in time, even when the task's
        // value is waiting by the time the caller looks
        for _ in 0..200 {
            assert_eq!(within(Duration::from_nanos(1), || 3), None);
        }
    }
}
