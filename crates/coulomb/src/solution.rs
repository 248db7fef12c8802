//! What a solve returns: the [`Solution`] (r, u, v, s, the error of `docs/error.md` recomputed
//! on the problem as stored, the history of the outer iteration), its [`Status`], and the
//! [`SolveError`] of a solve that could not start.

use crate::problem::ProblemError;
use std::fmt;
use std::time::Duration;

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Status {
    /// the error of docs/error.md (and, for global problems, the balance residual) is ≤ tol
    Converged,
    /// the outer iteration cap was reached with the error above tol
    MaxIterations,
    /// the time limit was reached with the error above tol
    TimeLimit,
    /// the error stopped decreasing in a first stage that has a fallback (see
    /// [`crate::Settings::fallback`]); the fallback then runs
    Stalled,
    /// an inner solve failed (iteration cap, numerical breakdown)
    InnerFailure,
    /// an inner problem (3.15) was infeasible: C̄(s) = ∅
    InnerInfeasible,
    /// the iterates became non-finite
    NumericalError,
    /// the paper's rule (6.1) held (`MethodParams::fixed_point_tol`) but the error is above tol
    FixedPointRule,
    /// the error is ≤ tol only because r is unbounded: ‖W‖ ‖r‖ >
    /// [`crate::settings::Tuning::unbounded_ratio`] · max(‖q‖, ‖u‖), so the scale
    /// max(‖q‖, ‖r‖, ‖u‖) of the relative error is ‖r‖ while u still violates the law (e.g.
    /// penetrates). The iterates diverge, the mark of a problem without a solution
    /// (Painlevé's paradox, §5.3); never reported as converged
    Unbounded,
    /// the error is ≤ tol but the balance residual of the global problem stays above tol
    /// (v = M⁻¹(H r + f) from the Cholesky factor of one triangle of M does not balance the
    /// whole M: M ill-conditioned or not quite symmetric, as in some FEM files)
    BalanceResidual,
    /// the solve was asked to stop ([`crate::Settings::cancel`], e.g. on SIGINT) before the
    /// error reached tol; the returned iterate is the best one found so far
    Interrupted,
    /// a global problem with equality constraints ([`crate::equality`]): the reduced contact
    /// problem was solved, but on the problem as stored the equality residual
    /// ‖Gᵀ v + b‖ / max(1, ‖b‖) (or the error or balance residual after recovering v and λ)
    /// stays above tol: b is not in the range of Gᵀ (inconsistent constraints, no v satisfies
    /// them) or the constraints are too ill-conditioned for the elimination
    EqualityResidual,
}

impl Status {
    /// The snake_case name used in reports, JSON and the Python bindings.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Converged => "converged",
            Status::MaxIterations => "max_iterations",
            Status::TimeLimit => "time_limit",
            Status::Stalled => "stalled",
            Status::InnerFailure => "inner_failure",
            Status::InnerInfeasible => "inner_infeasible",
            Status::NumericalError => "numerical_error",
            Status::FixedPointRule => "fixed_point_rule",
            Status::Unbounded => "unbounded",
            Status::BalanceResidual => "balance_residual",
            Status::Interrupted => "interrupted",
            Status::EqualityResidual => "equality_residual",
        }
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.as_str())
    }
}

/// One outer iteration of the history.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct OuterRecord {
    /// the error of docs/error.md after this iteration
    pub error: f64,
    /// ‖F(s) − s‖
    pub fixed_point_residual: f64,
    /// the paper's (6.1) measure ‖F(s) − s‖ / (n (‖s‖ + 1))
    pub rule_6_1: f64,
    /// inner iterations spent in this outer iteration
    pub inner_iterations: usize,
    /// the step of the solve's plan that made this record ([`crate::plan`]); the records of
    /// the interior point and the multipliers have no fixed-point residual (NaN)
    pub step: StepKind,
}

/// A starting point: impulses r, and velocities v for global problems.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Guess {
    /// impulses r (length d · contacts)
    pub r: Vec<f64>,
    /// velocities v (global problems; ignored for local ones)
    pub v: Option<Vec<f64>>,
}

/// The result of a solve.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Solution {
    /// impulses r. A solve that stops without converging on a cap (iterations, time), a
    /// stall or an inner failure returns the iterate of lowest error (docs/error.md; for
    /// global problems the larger of error and balance residual) that any of its stages
    /// visited, not merely the last one; `u`, `v`, `s`, `error` and `balance_residual` are
    /// those of that iterate, `status` and `history` those of the solve
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
    /// ‖M v − H r − G λ − f‖ / max(1, ‖f‖) for global problems
    pub balance_residual: Option<f64>,
    /// multipliers λ of the equality constraints (global problems that have them)
    pub l: Option<Vec<f64>>,
    /// ‖Gᵀ v + b‖ / max(1, ‖b‖) for global problems with equality constraints
    pub equality_residual: Option<f64>,
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

/// Which step of a solve's plan ([`crate::plan::Plan`]) a history record comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum StepKind {
    /// Gauss–Seidel sweeps on Coulomb's law itself (fused), one outer iteration
    Warmup,
    /// the interior-point method on Coulomb's law ([`crate::barrier`]) with its
    /// Levenberg–Marquardt finishes, from r = 0
    InteriorPoint,
    /// the method of multipliers in the velocities ([`crate::multiplier`]) from the
    /// interior point's end points
    Multipliers,
    /// the main (inner, outer) method with its end game (Newton, proximal point, LM)
    Main,
    /// the fallback (inner, outer) method
    Fallback,
}

impl std::fmt::Display for StepKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StepKind::Warmup => "warm-up",
            StepKind::InteriorPoint => "interior point",
            StepKind::Multipliers => "multipliers",
            StepKind::Main => "main",
            StepKind::Fallback => "fallback",
        })
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    #[cfg(feature = "serde")]
    pub fn status_names_match_their_serialization() {
        for s in [
            Status::Converged,
            Status::MaxIterations,
            Status::TimeLimit,
            Status::Stalled,
            Status::InnerFailure,
            Status::InnerInfeasible,
            Status::NumericalError,
            Status::FixedPointRule,
            Status::Unbounded,
            Status::BalanceResidual,
            Status::Interrupted,
            Status::EqualityResidual,
        ] {
            let json = serde_json::to_string(&s).unwrap();
            assert_eq!(json, format!("\"{s}\""));
        }
    }
}
