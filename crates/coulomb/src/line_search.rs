//! The Armijo line search of every Newton-type method: semismooth Newton on the natural map
//! ([`crate::newton`], ‖G‖ of (3.9)), the method of multipliers ([`crate::multiplier`],
//! ‖G(v)‖²) and the proximal point ([`crate::proximal`], ‖Φ_ρ‖ of the Alart–Curnier map).
//!
//! From a point x with merit θ(0) and a direction δ, θ(t) = merit(x + t δ) is tried at
//! t = 1, ½, ¼, … and the first t with
//!
//! ```text
//!     θ(t) finite,   θ(t) < θ(0),   θ(t) ≤ (1 − c t) θ(0)
//! ```
//!
//! is accepted (sufficient decrease, c ∈ [0, 1); c = 0 asks for a decrease only). What to do
//! when no tried t passes is the caller's policy: a larger shift of J (Newton), the end of
//! the run (multipliers), the full step (proximal point).

/// What [`armijo`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Search {
    /// the first tried step t that passed the test, and θ(t)
    Accepted {
        /// the step length
        t: f64,
        /// the merit at x + t δ
        merit: f64,
    },
    /// no tried step passed
    Exhausted,
}

/// Backtracking from the full step: evaluates `merit_at(t)` = θ(t) at t = 1, ½, …,
/// 2^{1 − trials} and returns the first t with θ(t) finite, θ(t) < `merit0` and
/// θ(t) ≤ (1 − `c` t) `merit0`, or [`Search::Exhausted`]. The last call of `merit_at` is
/// the accepted trial's (callers keep the state it evaluated).
pub(crate) fn armijo(
    merit0: f64,
    c: f64,
    trials: usize,
    mut merit_at: impl FnMut(f64) -> f64,
) -> Search {
    let mut t = 1.0;
    for _ in 0..trials {
        let merit = merit_at(t);
        if merit.is_finite() && merit < merit0 && merit <= (1.0 - c * t) * merit0 {
            return Search::Accepted { t, merit };
        }
        t *= 0.5;
    }
    Search::Exhausted
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    pub fn the_first_sufficient_halving_is_accepted() {
        // θ(t) = (1 − t)² + 0.5 from θ(0) = 1.5: with c = 0.6, θ(1) = 0.5 ≤ 0.6 passes; with
        // c = 0.9, θ(1) fails (needs ≤ 0.15) and θ(½) = 0.75 passes (needs ≤ 0.825)
        let mut calls = Vec::new();
        let found = armijo(1.5, 0.6, 10, |t| {
            calls.push(t);
            (1.0 - t) * (1.0 - t) + 0.5
        });
        assert_eq!(found, Search::Accepted { t: 1.0, merit: 0.5 });
        let found = armijo(1.5, 0.9, 10, |t| {
            calls.push(t);
            (1.0 - t) * (1.0 - t) + 0.5
        });
        assert_eq!(
            found,
            Search::Accepted {
                t: 0.5,
                merit: 0.75
            }
        );
        assert_eq!(calls, [1.0, 1.0, 0.5]);
    }

    pub fn no_decrease_a_nan_or_no_trial_exhausts() {
        assert_eq!(armijo(1.0, 0.0, 5, |_| 1.0), Search::Exhausted);
        assert_eq!(armijo(1.0, 1e-4, 5, |_| f64::NAN), Search::Exhausted);
        assert_eq!(armijo(1.0, 1e-4, 0, |_| 0.0), Search::Exhausted);
    }
}
