//! Semismooth Newton polish of an approximate solution of the dual inner problem (4.7), on
//! its natural map ([`crate::natural_map`]).

use super::InnerProblem;
use crate::deadline::Deadline;
use crate::linalg::pattern_lu::sparse_lu_solve;
use crate::natural_map::{natural_map, push_d_times, push_identity_minus_d};
use crate::newton::{drive, NewtonRule, OnExhausted, SemismoothMap};

/// The natural map F(r) = r − P_L(r − (W r + b)) of (4.7), its Jacobian I − D + D W
/// (D = ∂P_L) assembled as triplets for faer's sparse LU.
struct DualMap<'a, 'b> {
    problem: &'a InnerProblem<'b>,
    /// F and the D blocks: current and trial
    f: [Vec<f64>; 2],
    jac: [Vec<f64>; 2],
    /// J as triplets
    triplets: (Vec<usize>, Vec<usize>, Vec<f64>),
}

impl SemismoothMap for DualMap<'_, '_> {
    fn eval_trial(&mut self, r: &[f64]) -> f64 {
        let problem = self.problem;
        let mut u = problem.b.to_vec();
        problem.w.gemv_acc(1.0, r, &mut u);
        natural_map(
            problem.dim,
            problem.mu,
            r,
            &u,
            &mut self.f[1],
            &mut self.jac[1],
        );
        crate::law::norm(&self.f[1])
    }

    fn accept_trial(&mut self) {
        self.f.swap(0, 1);
        self.jac.swap(0, 1);
    }

    fn current(&self) -> &[f64] {
        &self.f[0]
    }

    fn build_jacobian(&mut self) {
        // J = I − D + D W
        let (dim, jac) = (self.problem.dim, &self.jac[0]);
        let (rows, cols, vals) = &mut self.triplets;
        rows.clear();
        cols.clear();
        vals.clear();
        push_identity_minus_d(dim, jac, 0, rows, cols, vals);
        push_d_times(
            dim,
            jac,
            1.0,
            self.problem.w.triplets(),
            0,
            rows,
            cols,
            vals,
        );
    }

    fn solve_shifted(&mut self, lambda: f64, rhs: &mut [f64]) -> Option<()> {
        let m = rhs.len();
        let (rows, cols, vals) = &self.triplets;
        shifted_lu_solve(m, rows, cols, vals, lambda, rhs)
    }
}

/// Solves (J + λ I) x = rhs for J given as summed triplets (λ = 0: J itself).
pub(crate) fn shifted_lu_solve(
    m: usize,
    rows: &[usize],
    cols: &[usize],
    vals: &[f64],
    lambda: f64,
    rhs: &mut [f64],
) -> Option<()> {
    if lambda == 0.0 {
        return sparse_lu_solve(m, rows, cols, vals, rhs);
    }
    let (mut rows, mut cols, mut vals) = (rows.to_vec(), cols.to_vec(), vals.to_vec());
    for k in 0..m {
        rows.push(k);
        cols.push(k);
        vals.push(lambda);
    }
    sparse_lu_solve(m, &rows, &cols, &vals, rhs)
}

/// The rule of the polish steps of the interior-point solvers: full Newton steps (no shift,
/// no line search), each kept only if it decreases the merit, at most `steps` of them, none
/// after `deadline`, until the merit is ≤ `target`.
pub(crate) fn polish_rule(target: f64, steps: usize, deadline: Deadline) -> NewtonRule {
    NewtonRule {
        target,
        max_steps: steps,
        trials: 1,
        sufficient_decrease: 0.0,
        shift: None,
        on_exhausted: OnExhausted::Stop,
        slow_steps: usize::MAX,
        slow_ratio: 1.0,
        deadline,
    }
}

/// Polishes an approximate solution r of (4.7) by at most `steps` semismooth Newton steps on
/// F(r) = r − P_L(r − (W r + b)), whose Jacobian is I − D + D W (D = ∂P_L), solved by faer's
/// sparse LU, with the driver of [`crate::newton::drive`] and [`polish_rule`] (a step is kept
/// only if it decreases ‖F‖; no step starts after `deadline`; target 1e-15 max(1, ‖b‖));
/// returns the final relative residual ‖F(r)‖ / max(1, ‖b‖).
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
    let jac = vec![0.0; problem.mu.len() * dim * dim];
    let mut map = DualMap {
        problem,
        f: [vec![0.0; m], vec![0.0; m]],
        jac: [jac.clone(), jac],
        triplets: (Vec::new(), Vec::new(), Vec::new()),
    };
    let report = drive(&mut map, r, &polish_rule(1e-15 * scale, steps, deadline));
    report.residual / scale
}
