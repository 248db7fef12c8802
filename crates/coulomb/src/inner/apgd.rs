//! Accelerated projected gradient on the dual inner problem (4.7) — the paper's option (v),
//! made fast:
//!
//! ```text
//!     min_{r ∈ L}  I(r) = ½ rᵀ W r + bᵀ r,      ∇I(r) = W r + b.
//! ```
//!
//! FISTA (Beck–Teboulle) with
//! - step 1/L, L from a few power iterations on W (an estimate of λ_max(W)), increased by
//!   backtracking whenever the quadratic upper bound
//!   I(x⁺) ≤ I(y) + ∇I(y)ᵀ(x⁺ − y) + L/2 ‖x⁺ − y‖² fails (for a quadratic I this is
//!   (x⁺ − y)ᵀ W (x⁺ − y) ≤ L ‖x⁺ − y‖²), and allowed to shrink slowly otherwise;
//! - adaptive restart (O'Donoghue–Candès): the momentum is reset when
//!   (y − x⁺)ᵀ(x⁺ − x) > 0 (gradient test) or I(x⁺) > I(x) (function test);
//! - optionally a Barzilai–Borwein trial step ‖Δx‖²/(Δxᵀ W Δx), capped by the backtracking.
//!
//! One product with W per iteration (W y is a combination of W x⁺ and W x). Stopping: the
//! natural-map residual ‖r − P_L(r − ∇I(r))‖ / max(‖b‖, ‖r‖, ‖∇I(r)‖) ≤ tol.
//!
//! The iteration is generic over [`LinearOperator`], implemented for the assembled W
//! ([`CscMatrix`], and [`BlockCsr`] — W by d × d blocks, which the solver uses whenever the
//! blocks are mostly nonzero) and for the matrix-free Delassus operator x ↦ Hᵀ M⁻¹ H x
//! ([`DelassusOperator`]).

use super::{InnerLimits, InnerProblem, InnerReport, InnerSolver, InnerStatus, RayParams};
use crate::cone;
use crate::delassus::DelassusOperator;
use crate::law::norm;
use crate::linalg::sparse::{BlockCsr, CscMatrix};
use crate::natural_map::dual_residual_shifted;

/// Parameters of APGD's step-size control on (4.7) ([`crate::inner::apgd`]): L estimates
/// λ_max(W), the step is 1/L.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ApgdParams {
    /// L is kept ≥ `lip_floor` · L₀ (L₀ the power-iteration estimate); in (0, 1]
    pub lip_floor: f64,
    /// after each accepted step L ← max(`lip_decay` · L, floor); in (0, 1]
    pub lip_decay: f64,
    /// backtracking: while (x⁺ − y)ᵀW(x⁺ − y) > ‖x⁺ − y‖²/step (+ rounding slack),
    /// L ← max(`backtrack_growth` · L, `backtrack_margin` · (x⁺ − y)ᵀW(x⁺ − y)/‖x⁺ − y‖²); > 1
    pub backtrack_growth: f64,
    /// see `backtrack_growth`; ≥ 1
    pub backtrack_margin: f64,
    /// the backtracking test allows `backtrack_slack` · ‖x⁺ − y‖ ‖W x⁺‖ of rounding; ≥ 0
    pub backtrack_slack: f64,
    /// at most this many trial steps per iteration (the last is taken); ≥ 1
    pub backtrack_tries: usize,
    /// the infeasible-ray test ([`crate::inner::RayParams`]) runs every `ray_period` iterations; ≥ 1
    pub ray_period: usize,
}

impl Default for ApgdParams {
    fn default() -> Self {
        Self {
            lip_floor: 1e-3,
            lip_decay: 0.97,
            backtrack_growth: 2.0,
            backtrack_margin: 1.1,
            backtrack_slack: 1e-12,
            backtrack_tries: 60,
            ray_period: 64,
        }
    }
}

/// A symmetric positive semi-definite operator x ↦ W x.
pub trait LinearOperator {
    /// Size of W.
    fn size(&self) -> usize;
    /// y ← W x.
    fn apply(&self, x: &[f64], y: &mut [f64]);
}

impl LinearOperator for CscMatrix {
    fn size(&self) -> usize {
        self.ncols
    }
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        self.gemv_acc(1.0, x, y);
    }
}

impl LinearOperator for BlockCsr {
    fn size(&self) -> usize {
        self.blocks * self.dim
    }
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.gemv(x, y);
    }
}

/// The matrix-free Delassus operator x ↦ Hᵀ M⁻¹ H x with its size m (columns of H).
pub struct MatrixFree<'a> {
    /// the operator
    pub op: DelassusOperator<'a>,
    /// m = d · contacts
    pub size: usize,
}

impl LinearOperator for MatrixFree<'_> {
    fn size(&self) -> usize {
        self.size
    }
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.op.apply(x, y);
    }
}

/// λ_max(W) estimated by `iterations` power iterations from a fixed start vector.
pub fn lipschitz_estimate<A: LinearOperator + ?Sized>(op: &A, iterations: usize) -> f64 {
    let n = op.size();
    if n == 0 {
        return 0.0;
    }
    let mut x: Vec<f64> = (0..n)
        .map(|i| 1.0 + 0.1 * ((i * 7919) % 13) as f64)
        .collect();
    let mut y = vec![0.0; n];
    let mut lambda = 0.0;
    for _ in 0..iterations.max(1) {
        let nx = norm(&x);
        if nx.is_nan() || nx <= 0.0 {
            break;
        }
        x.iter_mut().for_each(|v| *v /= nx);
        op.apply(&x, &mut y);
        lambda = norm(&y);
        std::mem::swap(&mut x, &mut y);
    }
    lambda
}

/// FISTA with adaptive restart on (4.7), set up for one (d, W) by [`ApgdSolver::new`]: the
/// λ_max(W) estimate and W stored by d × d blocks are computed there, once.
#[derive(Debug, Clone)]
pub struct ApgdSolver {
    /// use a Barzilai–Borwein trial step (backtracked) instead of the running 1/L
    pub barzilai_borwein: bool,
    /// step-size control ([`crate::settings::InnerParams::apgd`])
    pub params: ApgdParams,
    /// thresholds of the infeasible-ray test ([`crate::settings::InnerParams::infeasible_ray`])
    pub ray: RayParams,
    /// the λ_max(W) estimate of [`lipschitz_estimate`]
    lip: f64,
    /// W by d × d blocks (None where blocks would be mostly padding: W is used as stored)
    blocks: Option<BlockCsr>,
    /// d
    dim: usize,
}

/// Power iterations of the initial λ_max(W) estimate of [`ApgdSolver::new`].
pub const POWER_ITERATIONS: usize = 20;

impl ApgdSolver {
    /// A solver for the d-dimensional problems on `w` with plain FISTA steps: W by blocks
    /// (when that does not more than double the stored entries) and λ_max(W) estimated by
    /// [`POWER_ITERATIONS`] power iterations.
    pub fn new(dim: usize, w: &CscMatrix) -> Self {
        Self::with_power_iterations(dim, w, POWER_ITERATIONS)
    }

    /// [`ApgdSolver::new`] with `power_iterations` power iterations for λ_max(W).
    pub fn with_power_iterations(dim: usize, w: &CscMatrix, power_iterations: usize) -> Self {
        let blocks = BlockCsr::from_csc(w, dim).filter(|b| b.values.len() <= 2 * w.nnz().max(1));
        let lip = match &blocks {
            Some(b) => lipschitz_estimate(b, power_iterations),
            None => lipschitz_estimate(w, power_iterations),
        };
        Self {
            barzilai_borwein: false,
            params: ApgdParams::default(),
            ray: RayParams::default(),
            lip,
            blocks,
            dim,
        }
    }
}

impl InnerSolver for ApgdSolver {
    fn name(&self) -> &'static str {
        "apgd"
    }

    fn solve(
        &mut self,
        problem: &InnerProblem<'_>,
        limits: &InnerLimits,
        r: &mut [f64],
    ) -> InnerReport {
        let w = problem.w;
        let m = problem.dim * problem.mu.len();
        let blocks_fit = self.blocks.as_ref().is_none_or(|b| b.blocks * b.dim == m);
        if problem.dim != self.dim || w.ncols != m || r.len() != m || !blocks_fit {
            return InnerReport {
                status: InnerStatus::NumericalError,
                iterations: 0,
                residual: f64::INFINITY,
            };
        }
        let op: &dyn LinearOperator = match &self.blocks {
            Some(b) => b,
            None => w,
        };
        solve_operator(
            op,
            problem.dim,
            problem.b,
            problem.mu,
            self.lip,
            self.barzilai_borwein,
            &self.params,
            &self.ray,
            limits,
            r,
        )
    }
}

/// FISTA with restart on (4.7) for any operator W; `lip` is an estimate of λ_max(W) (it is
/// increased by backtracking when too small, under the rules of `params`); every
/// `params.ray_period` iterations the iterate is tested for an infeasible ray with the
/// thresholds of `ray`. `r` holds the warm start on entry.
#[allow(clippy::too_many_arguments)]
pub fn solve_operator<A: LinearOperator + ?Sized>(
    op: &A,
    dim: usize,
    b: &[f64],
    mu: &[f64],
    lip: f64,
    barzilai_borwein: bool,
    params: &ApgdParams,
    ray: &RayParams,
    limits: &InnerLimits,
    r: &mut [f64],
) -> InnerReport {
    let n = r.len();
    let b_norm = norm(b);
    cone::project_product(dim, mu, r);
    // iterates: x (current), y (extrapolated), with W x, W y kept
    let mut x = r.to_vec();
    let mut wx = vec![0.0; n];
    op.apply(&x, &mut wx);
    let mut y = x.clone();
    let mut wy = wx.clone();
    let mut xn = vec![0.0; n];
    let mut wxn = vec![0.0; n];
    let mut grad = vec![0.0; n];
    let mut l = if lip > 0.0 && lip.is_finite() {
        lip
    } else {
        1.0
    };
    let l_floor = params.lip_floor * l;
    // the ‖W‖ of the ray test: the starting L, as l_floor · (1 / floor) (for the default
    // floor 1e-3, 1 / floor is exactly 1e3: the product the test has always used)
    let ray_scale = 1.0 / params.lip_floor;
    let mut t = 1.0f64;
    let mut fx = objective(&x, &wx, b);
    let mut bb_step: Option<f64> = None;
    let residual_of = |x: &[f64], wx: &[f64]| dual_residual_shifted(dim, mu, x, wx, b, b_norm);
    let mut residual = residual_of(&x, &wx);
    let mut iterations = 0;
    let status = loop {
        if !residual.is_finite() {
            break InnerStatus::NumericalError;
        }
        if residual <= limits.tol {
            break InnerStatus::Solved;
        }
        if iterations >= limits.max_iterations {
            break InnerStatus::MaxIterations;
        }
        if limits.deadline.passed() {
            break InnerStatus::TimeLimit;
        }
        if iterations % params.ray_period == params.ray_period - 1
            && super::unbounded_ray(&x, &wx, b, l_floor * ray_scale, ray)
        {
            break InnerStatus::Infeasible;
        }
        iterations += 1;
        for ((g, a), c) in grad.iter_mut().zip(&wy).zip(b) {
            *g = a + c;
        }
        // projected step from y, backtracking on L
        let mut step = bb_step.take().unwrap_or(1.0 / l).min(1.0 / l_floor);
        let mut tries = 0;
        loop {
            for ((p, yi), g) in xn.iter_mut().zip(&y).zip(&grad) {
                *p = yi - step * g;
            }
            cone::project_product(dim, mu, &mut xn);
            op.apply(&xn, &mut wxn);
            // (x⁺ − y)ᵀ W (x⁺ − y) ≤ ‖x⁺ − y‖² / step
            // up to the rounding in W x⁺ − W y (relative 1e-12 of ‖W x⁺‖ ‖x⁺ − y‖)
            let (mut dwd, mut dd, mut wn) = (0.0, 0.0, 0.0);
            for i in 0..n {
                let d = xn[i] - y[i];
                dwd += d * (wxn[i] - wy[i]);
                dd += d * d;
                wn += wxn[i] * wxn[i];
            }
            tries += 1;
            let slack = params.backtrack_slack * (dd * wn).sqrt();
            if dwd * step <= dd + slack * step || tries > params.backtrack_tries {
                break;
            }
            l = (params.backtrack_growth * l).max(params.backtrack_margin * dwd / dd);
            step = 1.0 / l;
        }
        let fxn = objective(&xn, &wxn, b);
        // adaptive restart: function or gradient test
        let mut momentum_dot = 0.0;
        for i in 0..n {
            momentum_dot += (y[i] - xn[i]) * (xn[i] - x[i]);
        }
        let restart = fxn > fx || momentum_dot > 0.0;
        let t_next = if restart {
            1.0
        } else {
            0.5 * (1.0 + (1.0 + 4.0 * t * t).sqrt())
        };
        let beta = if restart { 0.0 } else { (t - 1.0) / t_next };
        if barzilai_borwein {
            let (mut sy, mut ss) = (0.0, 0.0);
            for i in 0..n {
                let s = xn[i] - x[i];
                sy += s * (wxn[i] - wx[i]);
                ss += s * s;
            }
            if sy > 0.0 && ss > 0.0 {
                bb_step = Some(ss / sy);
            }
        }
        for i in 0..n {
            y[i] = xn[i] + beta * (xn[i] - x[i]);
            wy[i] = wxn[i] + beta * (wxn[i] - wx[i]);
        }
        std::mem::swap(&mut x, &mut xn);
        std::mem::swap(&mut wx, &mut wxn);
        t = t_next;
        fx = fxn;
        l = (params.lip_decay * l).max(l_floor);
        residual = residual_of(&x, &wx);
    };
    r.copy_from_slice(&x);
    InnerReport {
        status,
        iterations,
        residual,
    }
}

/// I(x) = ½ xᵀ W x + bᵀ x from x and W x.
fn objective(x: &[f64], wx: &[f64], b: &[f64]) -> f64 {
    x.iter()
        .zip(wx)
        .zip(b)
        .map(|((xi, wi), bi)| xi * (0.5 * wi + bi))
        .sum()
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    pub fn power_iteration_estimates_the_largest_eigenvalue() {
        let w = CscMatrix::from_dense(3, 3, &[4.0, 1.0, 0.0, 1.0, 3.0, 0.0, 0.0, 0.0, 1.0]);
        let l = lipschitz_estimate(&w, 50);
        let exact = 3.5 + 0.5 * 5.0f64.sqrt();
        assert!((l - exact).abs() < 1e-6 * exact, "{l} vs {exact}");
    }
}
