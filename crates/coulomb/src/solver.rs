//! The public entry point: `solve(&problem, &settings)` runs the outer fixed-point iteration
//! s ← F(s) of §3.3 around an inner solver of (3.15)/(4.7), and reports the error of
//! `docs/error.md` recomputed from the returned r (and v).

use crate::problem::{Problem, ProblemError};
use serde::Serialize;
use std::time::Duration;

/// Which method computes F(s) (§6, options (i), (iv), (v)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InnerKind {
    /// Clarabel interior point on the SOC-QP (primal (3.15) for global problems, dual (4.7) for local).
    Ipm,
    /// accelerated projected gradient (FISTA with adaptive restart) on (4.7)
    Apgd,
    /// projected block Gauss–Seidel on (4.7), exact one-contact solves
    Pgs,
    /// faceted cone: each K_μ replaced by a k-facet pyramid, QP solved by Clarabel
    Faceted,
}

/// How the fixed point s = F(s) is sought.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OuterKind {
    /// successive approximation s ← F(s)
    FixedPoint,
    /// safeguarded Anderson mixing on s
    Anderson,
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// the error of docs/error.md (and, for global problems, the balance residual) is ≤ tol
    Converged,
    /// the outer iteration cap was reached with the error above tol
    MaxIterations,
    /// the time limit was reached with the error above tol
    TimeLimit,
    /// an inner solve failed (iteration cap, numerical breakdown)
    InnerFailure,
    /// an inner problem (3.15) was infeasible: C̄(s) = ∅
    InnerInfeasible,
    /// the iterates became non-finite
    NumericalError,
}

/// Typed settings with defaults suited to rigid-body problems.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Settings {
    /// tolerance on the reported error (docs/error.md); also on the balance residual
    pub tol: f64,
    /// inner solver
    pub inner: InnerKind,
    /// outer iteration
    pub outer: OuterKind,
    /// cap on outer iterations (subproblems)
    pub max_outer: usize,
    /// cap on iterations of each inner solve
    pub max_inner: usize,
    /// wall-clock limit for the whole solve
    pub time_limit: Option<Duration>,
    /// ε of the paper's stopping rule (6.1) ‖F(s) − s‖ / (n (‖s‖ + 1)) ≤ ε, used as an
    /// additional internal stopping test when set (the reported status still requires err ≤ tol)
    pub fixed_point_tol: Option<f64>,
    /// number of facets of the pyramid replacing each K_μ (faceted inner solver, d = 3)
    pub facets: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            tol: 1e-8,
            inner: InnerKind::Pgs,
            outer: OuterKind::FixedPoint,
            max_outer: 200,
            max_inner: 10_000,
            time_limit: Some(Duration::from_secs(60)),
            fixed_point_tol: None,
            facets: 8,
        }
    }
}

/// One outer iteration of the history.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OuterRecord {
    /// the error of docs/error.md after this iteration
    pub error: f64,
    /// ‖F(s) − s‖
    pub fixed_point_residual: f64,
    /// the paper's (6.1) measure ‖F(s) − s‖ / (n (‖s‖ + 1))
    pub rule_6_1: f64,
    /// inner iterations spent in this outer iteration
    pub inner_iterations: usize,
}

/// A starting point: impulses r, and velocities v for global problems.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Guess {
    /// impulses r (length d · contacts)
    pub r: Vec<f64>,
    /// velocities v (global problems; ignored for local ones)
    pub v: Option<Vec<f64>>,
}

/// The result of [`solve`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Solution {
    /// impulses r
    pub r: Vec<f64>,
    /// relative velocities u, recomputed from the problem data (W r + q or Hᵀ v + w)
    pub u: Vec<f64>,
    /// velocities v (global problems)
    pub v: Option<Vec<f64>>,
    /// the final fixed-point variable s (one entry per contact)
    pub s: Vec<f64>,
    /// how the solve ended
    pub status: Status,
    /// the error of docs/error.md, recomputed from r (and v)
    pub error: f64,
    /// ‖M v − H r − f‖ / max(1, ‖f‖) for global problems
    pub balance_residual: Option<f64>,
    /// outer iterations (subproblems solved)
    pub outer_iterations: usize,
    /// inner iterations, summed
    pub inner_iterations: usize,
    /// per outer iteration
    pub history: Vec<OuterRecord>,
    /// wall-clock time of the solve (excluding file reading)
    pub solve_time: Duration,
}

impl Solution {
    /// Whether the status is [`Status::Converged`].
    pub fn converged(&self) -> bool {
        self.status == Status::Converged
    }
}

/// Why a solve could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// the problem data are invalid
    #[error(transparent)]
    Problem(#[from] ProblemError),
    /// the settings are invalid
    #[error("invalid settings: {0}")]
    Settings(String),
    /// the guess has the wrong size
    #[error("invalid guess: {0}")]
    Guess(String),
}

/// Solves the incremental problem (2.10) from a cold start.
pub fn solve(problem: &Problem, settings: &Settings) -> Result<Solution, SolveError> {
    solve_with_guess(problem, settings, None)
}

/// Solves the incremental problem (2.10), warm-started from `guess` when given.
pub fn solve_with_guess(
    problem: &Problem,
    settings: &Settings,
    guess: Option<&Guess>,
) -> Result<Solution, SolveError> {
    let _ = (problem, settings, guess);
    Err(SolveError::Settings("solver under construction".into()))
}
