//! The instant at which a time-limited solve stops, computed without overflow: one
//! [`Deadline`] type, made once per solve from [`crate::Settings::time_limit`] and
//! [`crate::Settings::cancel`]. A deadline only truncates a solve (status `time_limit` or
//! `interrupted`): no decision of the solver's path reads the clock, every stage's budget is
//! in work (iterations, factorizations), so that the same input and settings give the same
//! iterates on any machine and under any load (docs/solver-core.md).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A request to stop a solve early, from outside it (a signal handler, another thread): a
/// flag that the solve reads wherever it reads the clock for its time limit. Once the flag is
/// set, the deadline counts as passed; the solve returns its best iterate with
/// [`crate::Status::Interrupted`] (the error recomputed as for any other ending).
#[derive(Clone, Copy)]
pub struct Cancel(&'static AtomicBool);

impl Cancel {
    /// A request read from `flag` (set it to true to stop the solves that carry it).
    pub fn new(flag: &'static AtomicBool) -> Self {
        Self(flag)
    }

    /// Whether the stop was requested.
    pub fn requested(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

impl std::fmt::Debug for Cancel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Cancel({})", self.requested())
    }
}

/// Two requests are the same when they read the same flag.
impl PartialEq for Cancel {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.0, other.0)
    }
}

impl Eq for Cancel {}

/// When a solve must stop: an instant, or never; and earlier when its [`Cancel`] is
/// requested.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Deadline(Option<Instant>, Option<Cancel>);

impl Deadline {
    /// No deadline.
    pub const NEVER: Deadline = Deadline(None, None);

    /// `start + limit` ([`deadline`]): never when there is no limit or when the sum is beyond
    /// what [`Instant`] can represent.
    pub fn after(start: Instant, limit: Option<Duration>) -> Self {
        Self(deadline(start, limit), None)
    }

    /// The same deadline, passed as soon as `cancel` (when some) is requested.
    pub fn with_cancel(self, cancel: Option<Cancel>) -> Self {
        Self(self.0, cancel)
    }

    /// Whether the deadline has passed (reads the clock; never for [`Deadline::NEVER`]) or a
    /// stop was requested ([`Deadline::cancelled`]).
    pub fn passed(&self) -> bool {
        self.cancelled() || self.0.is_some_and(|t| Instant::now() >= t)
    }

    /// Whether the solve was asked to stop by its [`Cancel`].
    pub fn cancelled(&self) -> bool {
        self.1.is_some_and(|c| c.requested())
    }

    /// The instant, None for no deadline (for the time left, e.g. Clarabel's time limit).
    pub fn instant(&self) -> Option<Instant> {
        self.0
    }
}

impl From<Option<Instant>> for Deadline {
    fn from(t: Option<Instant>) -> Self {
        Self(t, None)
    }
}

impl From<Instant> for Deadline {
    fn from(t: Instant) -> Self {
        Self(Some(t), None)
    }
}

/// The deadline `start + limit`, or `None` (no deadline) when there is no limit or when
/// `start + limit` is beyond what [`Instant`] can represent (e.g. `Duration::MAX`, or 10¹⁹ s
/// on platforms whose clock counts nanoseconds in 64 bits): a limit that far away can never
/// be reached, so the solve simply runs to its iteration caps.
pub fn deadline(start: Instant, limit: Option<Duration>) -> Option<Instant> {
    limit.and_then(|t| start.checked_add(t))
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    pub fn huge_limits_mean_no_deadline_and_never_panic() {
        let now = Instant::now();
        assert_eq!(deadline(now, None), None);
        assert_eq!(deadline(now, Some(Duration::MAX)), None);
        // 1e19 s and 1e30 s (the latter saturates in Duration's own conversion)
        for secs in [1e19, 1e30] {
            let t = Duration::try_from_secs_f64(secs).unwrap_or(Duration::MAX);
            if let Some(d) = deadline(now, Some(t)) {
                assert!(d > now);
            }
        }
        let d = deadline(now, Some(Duration::from_millis(5))).unwrap();
        assert_eq!(d - now, Duration::from_millis(5));
    }

    pub fn a_cancelled_deadline_has_passed() {
        static FLAG: AtomicBool = AtomicBool::new(false);
        let d = Deadline::NEVER.with_cancel(Some(Cancel::new(&FLAG)));
        assert!(!d.passed() && !d.cancelled());
        FLAG.store(true, Ordering::Relaxed);
        assert!(d.passed() && d.cancelled());
        assert_eq!(d.instant(), None);
        assert!(!Deadline::NEVER.passed());
    }
}
