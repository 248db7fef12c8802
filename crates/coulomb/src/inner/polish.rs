//! Semismooth Newton polish of an approximate solution of the dual inner problem (4.7), on
//! its natural map ([`crate::natural_map`]).

use super::InnerProblem;
use crate::deadline::Deadline;
use crate::natural_map::{natural_map, push_d_times, push_identity_minus_d};
use crate::newton::sparse_lu_solve;

/// Whether `deadline` has passed.
pub(crate) fn past(deadline: Deadline) -> bool {
    deadline.passed()
}

/// Polishes an approximate solution r of (4.7) by at most `steps` semismooth Newton steps on
/// F(r) = r − P_L(r − (W r + b)), whose Jacobian is I − D + D W (D = ∂P_L), solved by faer's
/// sparse LU. A step is kept only if it decreases ‖F‖; no step starts after `deadline`; returns the final relative residual ‖F(r)‖ / max(1, ‖b‖).
///
/// Why: an interior-point method stops on the duality gap rᵀũ, and for a sliding contact
/// (r and ũ on the boundaries of K_μ and K_μ*) rᵀũ is *quadratic* in their misalignment, so a
/// gap of 1e-12 leaves a natural residual (the error measure of docs/error.md) near 1e-7.
/// Newton on F converges quadratically from there.
pub(crate) fn polish_dual(
    problem: &InnerProblem<'_>,
    r: &mut [f64],
    steps: usize,
    deadline: Deadline,
) -> f64 {
    let (dim, m) = (problem.dim, r.len());
    let scale = crate::law::norm(problem.b).max(1.0);
    let mut f = vec![0.0; m];
    let mut jac = vec![0.0; problem.mu.len() * dim * dim];
    let eval = |r: &[f64], f: &mut [f64], jac: &mut [f64]| {
        let mut u = problem.b.to_vec();
        problem.w.gemv_acc(1.0, r, &mut u);
        natural_map(dim, problem.mu, r, &u, f, jac);
        crate::law::norm(f)
    };
    let mut norm_f = eval(r, &mut f, &mut jac);
    let mut trial = vec![0.0; m];
    let mut f_trial = vec![0.0; m];
    let mut jac_trial = vec![0.0; jac.len()];
    for _ in 0..steps {
        if norm_f.is_nan() || norm_f <= 1e-15 * scale || past(deadline) {
            break;
        }
        // J = I − D + D W
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        push_identity_minus_d(dim, &jac, 0, &mut rows, &mut cols, &mut vals);
        push_d_times(
            dim,
            &jac,
            1.0,
            problem.w.triplets(),
            0,
            &mut rows,
            &mut cols,
            &mut vals,
        );
        let mut delta: Vec<f64> = f.iter().map(|x| -x).collect();
        if sparse_lu_solve(m, &rows, &cols, &vals, &mut delta).is_none() {
            break;
        }
        for k in 0..m {
            trial[k] = r[k] + delta[k];
        }
        let norm_trial = eval(&trial, &mut f_trial, &mut jac_trial);
        if norm_trial.is_nan() || norm_trial >= norm_f {
            break;
        }
        r.copy_from_slice(&trial);
        std::mem::swap(&mut f, &mut f_trial);
        std::mem::swap(&mut jac, &mut jac_trial);
        norm_f = norm_trial;
    }
    norm_f / scale
}
