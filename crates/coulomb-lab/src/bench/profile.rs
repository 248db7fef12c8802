//! Dolan–Moré performance profiles (Dolan & Moré, *Benchmarking optimization software with
//! performance profiles*, Math. Program. 91, 2002), the way frictional-contact solvers are
//! compared over FCLIB collections (Acary, Brémond & Huber).
//!
//! For problems p ∈ P and solvers s ∈ S, let t_{p,s} be the time solver s needs on problem p
//! (∞ when it failed). The performance ratio is
//!
//! ```text
//! r_{p,s} = t_{p,s} / min_{s'} t_{p,s'}        (∞ when s failed, or when no solver succeeded on p)
//! ```
//!
//! and the profile of solver s is the fraction of problems it solves within a factor τ ≥ 1 of the
//! best solver:
//!
//! ```text
//! ρ_s(τ) = |{p ∈ P : r_{p,s} ≤ τ}| / |P|.
//! ```
//!
//! ρ_s(1) is the fraction of problems on which s was fastest (ties count as a win for every tied
//! solver), and lim_{τ→∞} ρ_s(τ) is the fraction it solved at all. Problems nobody solved stay
//! in the denominator |P|.
//!
//! Everything here is pure: no I/O, no clock.

/// Times at or below this (seconds) are treated as equal to it before ratios are formed, so that
/// a zero time never gives 0/0.
pub const TIME_FLOOR: f64 = 1e-9;

/// Why a profile could not be formed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProfileError {
    /// a row of the time table has a different number of solvers than the first row
    #[error("problem {problem} has {found} solver times, expected {expected}")]
    Ragged {
        /// index of the offending problem (row)
        problem: usize,
        /// number of entries in that row
        found: usize,
        /// number of entries in the first row
        expected: usize,
    },
    /// a time is negative, NaN or infinite
    #[error("time of solver {solver} on problem {problem} is {time}, expected a finite non-negative number")]
    BadTime {
        /// problem index
        problem: usize,
        /// solver index
        solver: usize,
        /// the offending value
        time: f64,
    },
}

/// The performance profile of a set of solvers over a set of problems.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// |P|, the number of problems (including those no solver solved)
    n_problems: usize,
    /// for each solver, its finite ratios r_{p,s} sorted increasingly (one per problem it solved)
    ratios: Vec<Vec<f64>>,
}

/// Forms the performance profile from a table `times[p][s]` = time of solver s on problem p, or
/// `None` when s did not converge on p. Every row must have the same length (the number of
/// solvers); an empty table gives a profile with no problems.
pub fn performance_profile(times: &[Vec<Option<f64>>]) -> Result<Profile, ProfileError> {
    let n_solvers = times.first().map_or(0, Vec::len);
    let mut ratios = vec![Vec::new(); n_solvers];
    for (p, row) in times.iter().enumerate() {
        if row.len() != n_solvers {
            return Err(ProfileError::Ragged {
                problem: p,
                found: row.len(),
                expected: n_solvers,
            });
        }
        for (s, t) in row.iter().enumerate() {
            if let Some(t) = *t {
                if !t.is_finite() || t < 0.0 {
                    return Err(ProfileError::BadTime {
                        problem: p,
                        solver: s,
                        time: t,
                    });
                }
            }
        }
        // best time over the solvers that converged on p; none → every ratio is ∞
        let best = row
            .iter()
            .flatten()
            .map(|t| t.max(TIME_FLOOR))
            .fold(f64::INFINITY, f64::min);
        if !best.is_finite() {
            continue;
        }
        for (s, t) in row.iter().enumerate() {
            if let (Some(t), Some(list)) = (*t, ratios.get_mut(s)) {
                list.push(t.max(TIME_FLOOR) / best);
            }
        }
    }
    for list in &mut ratios {
        list.sort_by(f64::total_cmp);
    }
    Ok(Profile {
        n_problems: times.len(),
        ratios,
    })
}

impl Profile {
    /// |P|, the number of problems.
    pub fn n_problems(&self) -> usize {
        self.n_problems
    }

    /// The number of solvers.
    pub fn n_solvers(&self) -> usize {
        self.ratios.len()
    }

    /// The finite performance ratios r_{p,s} of `solver`, sorted increasingly (empty for an
    /// unknown solver index).
    pub fn ratios(&self, solver: usize) -> &[f64] {
        self.ratios.get(solver).map_or(&[], Vec::as_slice)
    }

    /// ρ_s(τ) = |{p : r_{p,s} ≤ τ}| / |P| (0 when there are no problems or the index is unknown).
    pub fn rho(&self, solver: usize, tau: f64) -> f64 {
        if self.n_problems == 0 {
            return 0.0;
        }
        let r = self.ratios(solver);
        let count = r.partition_point(|&x| x <= tau);
        count as f64 / self.n_problems as f64
    }

    /// lim_{τ→∞} ρ_s(τ): the fraction of problems `solver` solved.
    pub fn rho_max(&self, solver: usize) -> f64 {
        self.rho(solver, f64::INFINITY)
    }

    /// The smallest τ with ρ_s(τ) = ρ_s(∞), i.e. the largest finite ratio of `solver`;
    /// `None` when it solved nothing.
    pub fn tau_at_max(&self, solver: usize) -> Option<f64> {
        self.ratios(solver).last().copied()
    }

    /// The largest finite ratio over all solvers (1 when no solver solved anything).
    pub fn largest_ratio(&self) -> f64 {
        (0..self.n_solvers())
            .filter_map(|s| self.tau_at_max(s))
            .fold(1.0, f64::max)
    }

    /// The vertices of the step function τ ↦ ρ_s(τ) on [1, `tau_end`], ready to draw as a
    /// polyline: starts at (1, ρ_s(1)), rises vertically at each ratio in (1, tau_end], and ends
    /// at (tau_end, ρ_s(tau_end)).
    pub fn steps(&self, solver: usize, tau_end: f64) -> Vec<(f64, f64)> {
        let mut points = vec![(1.0, self.rho(solver, 1.0))];
        let mut level = self.rho(solver, 1.0);
        for &r in self.ratios(solver) {
            if r <= 1.0 || r > tau_end {
                continue;
            }
            let next = self.rho(solver, r);
            if next > level {
                points.push((r, level));
                points.push((r, next));
                level = next;
            }
        }
        if tau_end > 1.0 {
            points.push((tau_end, level));
        }
        points
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 3 problems × 2 solvers (A, B):
    /// p0: A 1.0, B 2.0   → r_A = 1, r_B = 2
    /// p1: A 3.0, B 3.0   → tie: r_A = r_B = 1
    /// p2: A failed, B 0.5 → r_A = ∞, r_B = 1
    fn hand_made() -> Vec<Vec<Option<f64>>> {
        vec![
            vec![Some(1.0), Some(2.0)],
            vec![Some(3.0), Some(3.0)],
            vec![None, Some(0.5)],
        ]
    }

    #[test]
    fn hand_made_profile_is_exact() {
        let p = performance_profile(&hand_made()).unwrap();
        assert_eq!(p.n_problems(), 3);
        assert_eq!(p.n_solvers(), 2);
        assert_eq!(p.ratios(0), &[1.0, 1.0]);
        assert_eq!(p.ratios(1), &[1.0, 1.0, 2.0]);
        // below 1 nobody is within the factor
        assert_eq!(p.rho(0, 0.99), 0.0);
        assert_eq!(p.rho(1, 0.99), 0.0);
        // ρ(1) = wins, the tie on p1 counted for both
        assert_eq!(p.rho(0, 1.0), 2.0 / 3.0);
        assert_eq!(p.rho(1, 1.0), 2.0 / 3.0);
        // between 1 and 2 nothing changes
        assert_eq!(p.rho(0, 1.5), 2.0 / 3.0);
        assert_eq!(p.rho(1, 1.999), 2.0 / 3.0);
        // B reaches its maximum exactly at τ = 2
        assert_eq!(p.rho(1, 2.0), 1.0);
        assert_eq!(p.tau_at_max(1), Some(2.0));
        assert_eq!(p.rho_max(1), 1.0);
        // A never solves p2: capped at 2/3, reached at τ = 1
        assert_eq!(p.rho(0, 1e12), 2.0 / 3.0);
        assert_eq!(p.rho_max(0), 2.0 / 3.0);
        assert_eq!(p.tau_at_max(0), Some(1.0));
        assert_eq!(p.largest_ratio(), 2.0);
    }

    #[test]
    fn unsolved_problem_stays_in_denominator() {
        let mut t = hand_made();
        t.push(vec![None, None]);
        let p = performance_profile(&t).unwrap();
        assert_eq!(p.n_problems(), 4);
        assert_eq!(p.rho(0, 1.0), 0.5);
        assert_eq!(p.rho(1, 1.0), 0.5);
        assert_eq!(p.rho_max(0), 0.5);
        assert_eq!(p.rho_max(1), 0.75);
    }

    #[test]
    fn steps_trace_the_step_function() {
        let p = performance_profile(&hand_made()).unwrap();
        let two3 = 2.0 / 3.0;
        assert_eq!(
            p.steps(1, 4.0),
            vec![(1.0, two3), (2.0, two3), (2.0, 1.0), (4.0, 1.0)]
        );
        assert_eq!(p.steps(0, 4.0), vec![(1.0, two3), (4.0, two3)]);
        // a step beyond tau_end is not drawn
        assert_eq!(p.steps(1, 1.5), vec![(1.0, two3), (1.5, two3)]);
    }

    #[test]
    fn zero_times_are_floored_not_divided_by_zero() {
        let p = performance_profile(&[vec![Some(0.0), Some(0.0)], vec![Some(0.0), None]]).unwrap();
        assert_eq!(p.rho(0, 1.0), 1.0);
        assert_eq!(p.rho(1, 1.0), 0.5);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        assert_eq!(
            performance_profile(&[vec![Some(1.0), None], vec![Some(1.0)]]),
            Err(ProfileError::Ragged {
                problem: 1,
                found: 1,
                expected: 2
            })
        );
        assert!(matches!(
            performance_profile(&[vec![Some(f64::NAN)]]),
            Err(ProfileError::BadTime {
                problem: 0,
                solver: 0,
                ..
            })
        ));
        assert!(matches!(
            performance_profile(&[vec![Some(-1.0)]]),
            Err(ProfileError::BadTime { .. })
        ));
        let empty = performance_profile(&[]).unwrap();
        assert_eq!(empty.n_problems(), 0);
        assert_eq!(empty.rho(0, 1.0), 0.0);
        assert_eq!(empty.largest_ratio(), 1.0);
    }
}
