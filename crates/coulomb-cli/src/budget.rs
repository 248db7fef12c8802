//! A wall-clock budget for work that cannot be interrupted from inside: the existence
//! check's conic solves have a time cap each, but not their setup (an LDL factorization of a
//! large KKT matrix can take minutes).

use std::time::Duration;

/// `f()` run on its own thread, or None if it has not returned within `budget`: the work is
/// then abandoned, and its thread ends with the process.
pub fn within<T: Send + 'static>(
    budget: Duration,
    f: impl FnOnce() -> T + Send + 'static,
) -> Option<T> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        // the receiver may be gone (time is up): nothing to report then
        let _ = tx.send(f());
    });
    rx.recv_timeout(budget).ok()
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
}
