//! The one evaluation of a candidate solution, shared by the solver (every status is decided
//! by it) and by [`crate::fclib::evaluate`] (stored solutions): the error of `docs/error.md`
//! with u recomputed from the problem data, the balance residual of a global problem, and
//! the equality residual of a global problem with equality constraints.

use crate::law::{error_measure, ErrorMeasure};
use crate::problem::{GlobalProblem, LocalProblem};

/// The error of `docs/error.md` of a candidate solution, with its parts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// the error measure, u recomputed from the problem data
    pub measure: ErrorMeasure,
    /// ‖M v − H r − f‖ / max(1, ‖f‖) for a global problem, `None` for a local one
    pub balance_residual: Option<f64>,
    /// ‖Gᵀ v + b‖ / max(1, ‖b‖) for a global problem with equality constraints, `None`
    /// otherwise
    pub equality_residual: Option<f64>,
}

impl Evaluation {
    /// Converged at `tol` (docs/error.md): err ≤ tol and, for a global problem, the
    /// balance residual ≤ tol and (with equality constraints) the equality residual ≤ tol.
    pub fn converged(&self, tol: f64) -> bool {
        self.measure.converged(tol)
            && self.balance_residual.is_none_or(|b| b <= tol)
            && self.equality_residual.is_none_or(|e| e <= tol)
    }
}

/// Local problem: u = W r + q and the error with scale max(‖q‖, ‖r‖, ‖u‖) (`q_norm` = ‖q‖).
pub fn local(p: &LocalProblem, r: &[f64], q_norm: f64) -> (Vec<f64>, Evaluation) {
    let u = p.velocity(r);
    let measure = error_measure(p.dim, &p.mu, r, &u, q_norm);
    let e = Evaluation {
        measure,
        balance_residual: None,
        equality_residual: None,
    };
    (u, e)
}

/// Global problem at (v, r): u = Hᵀ v + w, the error with scale max(‖q‖, ‖r‖, ‖u‖) where
/// `q_norm` is ‖q‖ of the Delassus vector q = Hᵀ M⁻¹ f + w, and the balance residual.
/// (With equality constraints use [`global_with`]: here λ is taken as zero.)
pub fn global(p: &GlobalProblem, v: &[f64], r: &[f64], q_norm: f64) -> (Vec<f64>, Evaluation) {
    global_with(p, v, r, None, q_norm)
}

/// Global problem at (v, r, λ): as [`global`], the balance residual
/// ‖M v − H r − G λ − f‖ / max(1, ‖f‖) with the multipliers `l` = λ of the equality
/// constraints, and their residual ‖Gᵀ v + b‖ / max(1, ‖b‖). For a problem with equality
/// constraints `q_norm` is ‖q̃‖ of the reduced Delassus vector ([`crate::equality`]): the
/// u of r = 0 with the constraints satisfied.
pub fn global_with(
    p: &GlobalProblem,
    v: &[f64],
    r: &[f64],
    l: Option<&[f64]>,
    q_norm: f64,
) -> (Vec<f64>, Evaluation) {
    let u = p.velocity(v);
    let measure = error_measure(p.dim, &p.mu, r, &u, q_norm);
    let e = Evaluation {
        measure,
        balance_residual: Some(p.balance_residual_with(v, r, l)),
        equality_residual: p.equality_residual(v),
    };
    (u, e)
}
