//! Inner solvers: for a fixed s ≥ 0, compute F(s) of (3.19) by solving the strongly convex
//! second-order-cone QP, either in its dual form (4.7) on the Delassus matrix,
//!
//! ```text
//!     min_{r ∈ L}  ½ rᵀ W r + bᵀ r,      b = q + E s,
//! ```
//!
//! whose optimality conditions are L* ∋ ũ = W r + b ⊥ r ∈ L (3.14), or in its primal form
//! (3.15) on (M, H) for global problems.

pub mod apgd;
pub(crate) mod clarabel;
pub mod contact;
pub mod faceted;
pub mod ipm;
pub mod pgs;
pub(crate) mod polish;

pub use crate::deadline::Deadline;
use crate::linalg::sparse::CscMatrix;

/// Thresholds of the test that an iterate r of (4.7) is a ray certifying that (4.7) is
/// unbounded below, so that the primal (3.15) is infeasible (C̄(s) = ∅): with d = r/‖r‖,
/// ‖W d‖ ≤ `residual` · ‖W‖ and bᵀd ≤ −`descent` · ‖b‖ (see [`crate::inner::unbounded_ray`]).
/// Used by the outer stage after each inner solve, by projected Gauss–Seidel and by APGD.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RayParams {
    /// bound on ‖W d‖ / ‖W‖ (d in the recession directions: W d ≈ 0); > 0
    pub residual: f64,
    /// bound on −bᵀd / ‖b‖ (d a descent direction of the objective ½ rᵀW r + bᵀr); > 0
    pub descent: f64,
}

impl Default for RayParams {
    fn default() -> Self {
        Self {
            residual: 1e-7,
            descent: 1e-3,
        }
    }
}

/// The dual inner problem (4.7): min over r ∈ L = ∏ K_{μⁱ} of ½ rᵀ W r + bᵀ r.
#[derive(Debug, Clone, Copy)]
pub struct InnerProblem<'a> {
    /// space dimension d
    pub dim: usize,
    /// Delassus matrix W (symmetric positive semi-definite)
    pub w: &'a CscMatrix,
    /// linear term b = q + E s
    pub b: &'a [f64],
    /// friction coefficients μⁱ (the cone of contact i is K_{μⁱ})
    pub mu: &'a [f64],
}

/// How an inner solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum InnerStatus {
    /// the inner stopping criterion was met
    Solved,
    /// the iteration cap was reached first
    MaxIterations,
    /// the deadline passed first
    TimeLimit,
    /// the problem was detected infeasible or unbounded (e.g. (3.15) has an empty feasible set)
    Infeasible,
    /// numerical breakdown (non-finite iterates, factorization failure, solver error)
    NumericalError,
}

/// What an inner solve returns besides r.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InnerReport {
    /// how it ended
    pub status: InnerStatus,
    /// iterations spent
    pub iterations: usize,
    /// final value of the solver's own stopping measure
    pub residual: f64,
}

/// Limits and tolerance for one inner solve.
#[derive(Debug, Clone, Copy)]
pub struct InnerLimits {
    /// Stopping tolerance ε of the inner solve. Its meaning: a bound on the relative natural-map
    /// residual of (4.7),
    /// ρ(r) = ‖r − P_L(r − ũ)‖ / max(‖b‖, ‖r‖, ‖ũ‖), ũ = W r + b ((3.14) with b in the place
    /// of q: the error of docs/error.md for the inner problem). Projected Gauss–Seidel and
    /// APGD stop on ρ(r) ≤ ε exactly. The interior-point and faceted solvers convert it once,
    /// into Clarabel's gap and feasibility tolerances (`tol_gap_abs = tol_gap_rel = tol_feas
    /// = ε`, `clarabel_settings` in inner/clarabel.rs), whose stopping test is Clarabel's own; a
    /// stalled interior-point solve is still accepted when its polished r has
    /// ‖r − P_L(r − ũ)‖ / max(1, ‖b‖) ≤ ε. The fused method ([`crate::outer::fused`]) reads
    /// it as a bound on the error of docs/error.md of the whole law (on q).
    pub tol: f64,
    /// iteration cap
    pub max_iterations: usize,
    /// wall-clock deadline ([`Deadline::NEVER`] for none)
    pub deadline: Deadline,
}

impl InnerLimits {
    /// Whether the deadline has passed, before iteration `iteration` of a loop whose
    /// iterations each touch about `work` nonzeros: the clock is read only every
    /// 20 000 / work iterations (rounded down, between 1 and 64), so that on the smallest problems reading it
    /// does not cost more than the iteration, and a deadline is overrun by at most ~20 000
    /// nonzeros' worth of work.
    pub fn past_deadline(&self, iteration: usize, work: usize) -> bool {
        let every = (20_000 / work.max(1)).clamp(1, 64);
        iteration % every == 0 && self.deadline.passed()
    }
}

/// A solver of the dual inner problem (4.7), set up for one (d, W, μ): its per-matrix data
/// (diagonal blocks, Lipschitz estimate, Clarabel setup) are built once, by its constructor or
/// at its first solve, and every later solve changes only b = q + E s. [`crate::Solver`] owns
/// one per inner kind and makes a new one when W changes ([`crate::Solver::update_w`]).
/// `r` holds the warm start on entry (zeros for a cold start) and the solution on exit;
/// solvers that cannot use a warm start ignore it.
pub trait InnerSolver {
    /// Short name for reports ("pgs", "apgd", "ipm", "faceted").
    fn name(&self) -> &'static str;
    /// Solves (4.7) for `problem`, writing r. `problem` must carry the (d, W, μ) the solver
    /// was set up for (only b may change); sizes that disagree with the setup give
    /// [`InnerStatus::NumericalError`] without an iteration.
    fn solve(
        &mut self,
        problem: &InnerProblem<'_>,
        limits: &InnerLimits,
        r: &mut [f64],
    ) -> InnerReport;
}

/// Whether r certifies that (4.7) is unbounded below (so that the primal (3.15) is
/// infeasible, C̄(s) = ∅): with d = r/‖r‖ ∈ L, W d ≈ 0 and bᵀd < 0 (Farkas: for feasible v,
/// (Hᵀv + w + E s)ᵀd ≥ 0, while H d = 0 makes it (w + E s)ᵀd = bᵀd). `wr` is W r and
/// `w_scale` an estimate of ‖W‖. Thresholds ([`RayParams`], defaults 1e-7 and 1e-3):
/// ‖W d‖ ≤ `ray.residual` ‖W‖ and bᵀd ≤ −`ray.descent` ‖b‖.
pub fn unbounded_ray(r: &[f64], wr: &[f64], b: &[f64], w_scale: f64, ray: &RayParams) -> bool {
    let rn = crate::law::norm(r);
    if rn.is_nan() || rn <= 0.0 || !rn.is_finite() {
        return false;
    }
    let wd = crate::law::norm(wr) / rn;
    let bd = r.iter().zip(b).map(|(x, y)| x * y).sum::<f64>() / rn;
    wd <= ray.residual * w_scale && bd <= -ray.descent * crate::law::norm(b)
}

/// An estimate of ‖W‖: the largest trace of a diagonal d × d block (≥ λ_max of each block).
pub fn w_scale(dim: usize, w: &CscMatrix) -> f64 {
    let diag = w.diagonal();
    diag.chunks(dim.max(1))
        .map(|c| c.iter().sum::<f64>())
        .fold(0.0f64, f64::max)
}
