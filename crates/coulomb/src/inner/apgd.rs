//! Accelerated projected gradient on (4.7) (under construction).

use super::{InnerLimits, InnerProblem, InnerReport, InnerSolver, InnerStatus};

/// FISTA with adaptive restart on (4.7).
#[derive(Debug, Clone, Default)]
pub struct ApgdSolver {}

impl ApgdSolver {
    /// A solver with default parameters.
    pub fn new() -> Self {
        Self {}
    }
}

impl InnerSolver for ApgdSolver {
    fn name(&self) -> &'static str {
        "apgd"
    }
    fn solve(&mut self, _p: &InnerProblem<'_>, _l: &InnerLimits, _r: &mut [f64]) -> InnerReport {
        InnerReport {
            status: InnerStatus::NumericalError,
            iterations: 0,
            residual: f64::INFINITY,
        }
    }
}
