//! Interior point (Clarabel) on the inner SOC-QP: the dual (4.7) on W, and the primal (3.15)
//! on (M, H) for global problems (the paper's §6 option (i)).
//!
//! # Cone conventions
//! Clarabel solves `min ½ xᵀ P x + qᵀ x  s.t.  A x + s = b, s ∈ K` and returns the dual
//! variable z ∈ K* with `P x + q + Aᵀ z = 0`. Each contact's Coulomb cone is passed as a
//! second-order cone `{(t, y) : ‖y‖ ≤ t}` after a diagonal scaling of its rows:
//!
//! | cone of the contact | scaled slack s of the contact | Clarabel cones |
//! |---|---|---|
//! | r ∈ K_μ, 0 < μ < ∞ (dual (4.7)) | s = (μ r_N, r_T) | `SecondOrderConeT(d)` |
//! | r ∈ K_0 (μ = 0) | s_N = r_N, s_T = r_T | `NonnegativeConeT(1)`, `ZeroConeT(d − 1)` |
//! | r ∈ K_∞ (μ = ∞) | s_N = r_N | `NonnegativeConeT(1)` (r_T free) |
//! | u ∈ K_{1/μ} = K_μ*, 0 < μ < ∞ (primal (3.15)) | s = (u_N, μ u_T) | `SecondOrderConeT(d)` |
//! | u ∈ K_0* (μ = 0, half-space) | s_N = u_N | `NonnegativeConeT(1)` (u_T free) |
//! | u ∈ K_∞* (μ = ∞) | s_N = u_N, s_T = u_T | `NonnegativeConeT(1)`, `ZeroConeT(d − 1)` |
//!
//! The rows are ordered zero-cone rows first, then nonnegative rows, then one SOC block per
//! frictional contact, so that Clarabel sees few, large cones.
//!
//! # Polish
//! Clarabel stops on its duality gap. For a sliding contact (r and ũ on the boundaries of K_μ
//! and K_μ*) the gap rᵀũ is quadratic in their angular misalignment, so in 3-D Clarabel's
//! answer at gap 1e-12 still has a natural-map residual ‖r − P_L(r − ũ)‖ (what the error of
//! docs/error.md measures) near 1e-7, and Clarabel stalls if asked for much less. Both
//! solvers therefore finish with a few semismooth Newton steps on the natural map of (3.14)
//! (Jacobian via the B-derivative of the SOC projection, faer sparse LU, a step kept only if
//! it reduces the residual), which converge quadratically from Clarabel's point to rounding
//! level. [`IpmSolver::with_polish`] / [`solve_primal_polished`] with 0 steps turn it off.
//!
//! # Warm start
//! Clarabel is a primal-dual interior-point method started from its own central point; it
//! offers no warm start, so the incoming r of [`InnerSolver::solve`] is ignored. What *is*
//! reused is the setup: an [`IpmSolver`] serves one (d, W, μ); it builds the Clarabel solver at
//! its first call and, at every later call (as in the fixed-point iteration s ↦ F(s) of (3.19),
//! where only b = q + E s changes), only overwrites the linear term through Clarabel's
//! data-update API (`update_q`), skipping equilibration and the symbolic factorization of the
//! KKT matrix.

use super::clarabel::{clarabel_settings, report_of, to_clarabel};
pub(crate) use super::clarabel::{solve_dual_qp, triplets_to_clarabel, QpSetup};
use super::polish::{polish_rule, shifted_lu_solve};
use super::{InnerLimits, InnerProblem, InnerReport, InnerSolver, InnerStatus};
use crate::deadline::Deadline;
use crate::linalg::sparse::CscMatrix;
use crate::natural_map::{natural_map, push_d_times, push_identity_minus_d};
use crate::newton::{drive, SemismoothMap};
use crate::problem::GlobalProblem;
use clarabel::algebra::CscMatrix as ClarabelCsc;
use clarabel::solver::{DefaultSolver, IPSolver, SolverStatus, SupportedConeT};

/// Clarabel on the dual (4.7): min over r ∈ L = ∏ K_{μⁱ} of ½ rᵀ W r + bᵀ r.
///
/// The returned r is Clarabel's primal solution x; W r + b is then ũ ∈ L* up to the
/// tolerance (the multiplier z of the cone rows, rescaled, equals ũ).
#[derive(Debug)]
pub struct IpmSolver {
    /// at most this many semismooth Newton steps polish Clarabel's r (0: none); see
    /// [`DEFAULT_POLISH_STEPS`]
    pub polish_steps: usize,
    /// the Clarabel setup, built at the first solve and reused by the later ones (on the same
    /// (d, W, μ): only b changes)
    setup: Option<QpSetup>,
}

/// Default number of semismooth Newton polish steps after an interior-point solve.
///
/// Clarabel stops on the duality gap; for sliding contacts the gap is quadratic in the
/// misalignment of r and ũ, so its r has a natural-map residual (the error of
/// docs/error.md) of about the square root of the gap, e.g. 1e-7 for a gap of 1e-13 in 3-D.
/// A few Newton steps on the natural map F(r) = r − P_L(r − ũ), each kept only if it
/// reduces ‖F‖, bring it to rounding level.
pub const DEFAULT_POLISH_STEPS: usize = 3;

impl Default for IpmSolver {
    fn default() -> Self {
        Self::new()
    }
}

impl Clone for IpmSolver {
    /// A clone starts without the Clarabel setup (it is built at its first solve).
    fn clone(&self) -> Self {
        Self::with_polish(self.polish_steps)
    }
}

impl IpmSolver {
    /// A solver with default Clarabel settings (`verbose = false`; tolerances, iteration cap
    /// and time limit come from the [`InnerLimits`] of each call) and
    /// [`DEFAULT_POLISH_STEPS`] polish steps.
    pub fn new() -> Self {
        Self::with_polish(DEFAULT_POLISH_STEPS)
    }

    /// Like [`IpmSolver::new`] with at most `polish_steps` Newton polish steps (0: plain
    /// Clarabel).
    pub fn with_polish(polish_steps: usize) -> Self {
        Self {
            polish_steps,
            setup: None,
        }
    }
}

impl InnerSolver for IpmSolver {
    fn name(&self) -> &'static str {
        "ipm"
    }

    /// Solves (4.7) with Clarabel, then polishes r (see [`DEFAULT_POLISH_STEPS`]); `r` on
    /// entry is ignored (no warm start, see module docs).
    ///
    /// The report's residual is the relative natural-map residual
    /// ‖r − P_L(r − (W r + b))‖ / max(1, ‖b‖) of the returned r (Clarabel's own
    /// max(res_primal, res_dual, min(gap_abs, gap_rel)) when polishing is off).
    ///
    /// Clarabel's status maps to: `Solved` → Solved; primal or dual infeasibility
    /// certificates (full or reduced accuracy) → Infeasible ((4.7) unbounded, i.e. (3.15)
    /// infeasible); `MaxIterations` → MaxIterations; `MaxTime` → TimeLimit; anything else
    /// (`AlmostSolved`, `InsufficientProgress`, `NumericalError`) → NumericalError, except
    /// that a stalled solve whose polished r has residual ≤ `limits.tol` is Solved.
    fn solve(
        &mut self,
        problem: &InnerProblem<'_>,
        limits: &InnerLimits,
        r: &mut [f64],
    ) -> InnerReport {
        let polish = self.polish_steps;
        solve_dual_qp(&mut self.setup, polish, problem, limits, r, || {
            let layout = ConeLayout::dual_exact(problem.dim, problem.mu);
            let a = layout.a_matrix(None);
            (a, layout.cones())
        })
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
///
/// (In the paper's notation (2.8) this is min ½ vᵀ M v + f_pᵀ v s.t. H_p v + w + E s ∈ L*.)
/// M (upper triangle) and H go to Clarabel as sparse matrices; the constraint is posed as
/// `−S Hᵀ v + s = S shift`, s ∈ K, with S the row scaling of the module docs (μ u_T for the
/// tangential rows). Clarabel's stationarity `M v − f − H S z = 0` shows that the multiplier of
/// (3.14) is r = S z: componentwise r_N = z_N and r_T = μ z_T, which lies in K_μ because z lies
/// in the self-dual SOC. Hence `M v = H r + f` and L* ∋ Hᵀ v + shift ⊥ r ∈ L at the solution.
///
/// An empty feasible set C̄(s) (3.17) is reported as [`InnerStatus::Infeasible`]; v and r
/// then hold Clarabel's last iterate (its infeasibility certificate), not a solution.
/// Inconsistent sizes give [`InnerStatus::NumericalError`] with empty v and r.
pub fn solve_primal(problem: &GlobalProblem, shift: &[f64], limits: &InnerLimits) -> PrimalOutcome {
    solve_primal_polished(problem, shift, limits, DEFAULT_POLISH_STEPS)
}

/// [`solve_primal`] with at most `polish_steps` semismooth Newton steps on (3.14) after
/// Clarabel (0: plain Clarabel): F₁ = M v − H r − f = 0, F₂ = r − P_L(r − (Hᵀ v + shift)) = 0.
/// When polishing, the report's residual is max(‖F₁‖ / max(1, ‖f‖), ‖F₂‖ / max(1, ‖shift‖));
/// a stalled Clarabel solve whose polished residual is ≤ `limits.tol` is `Solved`.
pub fn solve_primal_polished(
    problem: &GlobalProblem,
    shift: &[f64],
    limits: &InnerLimits,
    polish_steps: usize,
) -> PrimalOutcome {
    let fail = |status| PrimalOutcome {
        v: Vec::new(),
        r: Vec::new(),
        report: InnerReport {
            status,
            iterations: 0,
            residual: f64::INFINITY,
        },
    };
    let dim = problem.dim;
    let n = problem.m.nrows;
    let nr = problem.h.ncols;
    let consistent = (dim == 2 || dim == 3)
        && problem.mu.len() * dim == nr
        && shift.len() == nr
        && problem.m.ncols == n
        && problem.h.nrows == n
        && problem.f.len() == n
        && problem.m.check().is_ok()
        && problem.h.check().is_ok()
        && problem.m.first_non_finite().is_none()
        && problem.h.first_non_finite().is_none()
        && problem.f.iter().chain(shift).all(|x| x.is_finite())
        && problem.mu.iter().all(|m| *m >= 0.0);
    if !consistent {
        return fail(InnerStatus::NumericalError);
    }
    let settings = match clarabel_settings(limits) {
        Ok(s) => s,
        Err(status) => return fail(status),
    };
    let layout = ConeLayout::primal(dim, &problem.mu);
    let a = layout.a_matrix(Some(&problem.h));
    let mut b = vec![0.0; layout.rows];
    for (k, &sh) in shift.iter().enumerate() {
        if let Some((row, scale)) = layout.map[k] {
            b[row] = scale * sh;
        }
    }
    let p = to_clarabel(&problem.m.upper_triangle());
    let q: Vec<f64> = problem.f.iter().map(|x| -x).collect();
    let mut solver = match DefaultSolver::new(&p, &q, &a, &b, &layout.cones(), settings) {
        Ok(s) => s,
        Err(_) => return fail(InnerStatus::NumericalError),
    };
    solver.solve();
    let mut v = solver.solution.x.clone();
    let z = &solver.solution.z;
    let mut r: Vec<f64> = (0..nr)
        .map(|k| layout.map[k].map_or(0.0, |(row, scale)| scale * z[row]))
        .collect();
    let mut report = report_of(&solver);
    let finite = v.iter().chain(&r).all(|x| x.is_finite());
    if !finite {
        if report.status != InnerStatus::Infeasible {
            report.status = InnerStatus::NumericalError;
        }
    } else if polish_steps > 0 {
        let raw = solver.info.status;
        let stalled = matches!(
            raw,
            SolverStatus::AlmostSolved | SolverStatus::InsufficientProgress
        );
        if raw == SolverStatus::Solved || stalled {
            report.residual = polish_primal(
                problem,
                shift,
                &mut v,
                &mut r,
                polish_steps,
                limits.deadline,
            );
            if stalled && report.residual <= limits.tol {
                report.status = InnerStatus::Solved;
            }
        }
    }
    PrimalOutcome { v, r, report }
}

// ---------------------------------------------------------------------------------------------
// Shared Clarabel plumbing (also used by the faceted solver)
// ---------------------------------------------------------------------------------------------

/// Row layout of a product of per-contact cones in Clarabel's form: component k of the
/// contact vector (r for the dual, u = Hᵀ v + shift for the primal) goes to slack row
/// `map[k] = Some((row, scale))` with s_row = scale · x_k, or to no row at all (free).
#[derive(Debug, Clone)]
pub(crate) struct ConeLayout {
    /// number of `ZeroConeT` rows (first)
    zero: usize,
    /// number of `NonnegativeConeT` rows (after the zero rows)
    nonneg: usize,
    /// sizes of the SOC blocks (after the nonnegative rows)
    soc: Vec<usize>,
    /// total number of rows
    rows: usize,
    /// row and scale of each component
    map: Vec<Option<(usize, f64)>>,
}

/// Which row class a component is assigned to, before rows are numbered.
#[derive(Clone, Copy)]
enum RowClass {
    Free,
    Zero,
    Nonneg,
    Soc { block: usize },
}

impl ConeLayout {
    /// Layout for r ∈ L = ∏ K_{μⁱ} of the dual (4.7): s = (μ r_N, r_T) ∈ SOC for
    /// 0 < μ < ∞; r_N ≥ 0, r_T = 0 for μ = 0; r_N ≥ 0, r_T free for μ = ∞.
    pub(crate) fn dual_exact(dim: usize, mu: &[f64]) -> Self {
        Self::build(dim, mu, |m, tangential| {
            if m == 0.0 {
                (
                    if tangential {
                        RowClass::Zero
                    } else {
                        RowClass::Nonneg
                    },
                    1.0,
                )
            } else if m.is_infinite() {
                (
                    if tangential {
                        RowClass::Free
                    } else {
                        RowClass::Nonneg
                    },
                    1.0,
                )
            } else {
                (RowClass::Soc { block: 0 }, if tangential { 1.0 } else { m })
            }
        })
    }

    /// Layout for u ∈ L* = ∏ K_{1/μⁱ} of the primal (3.15): s = (u_N, μ u_T) ∈ SOC for
    /// 0 < μ < ∞; u_N ≥ 0, u_T free for μ = 0; u_N ≥ 0, u_T = 0 for μ = ∞.
    pub(crate) fn primal(dim: usize, mu: &[f64]) -> Self {
        Self::build(dim, mu, |m, tangential| {
            if m == 0.0 {
                (
                    if tangential {
                        RowClass::Free
                    } else {
                        RowClass::Nonneg
                    },
                    1.0,
                )
            } else if m.is_infinite() {
                (
                    if tangential {
                        RowClass::Zero
                    } else {
                        RowClass::Nonneg
                    },
                    1.0,
                )
            } else {
                (RowClass::Soc { block: 0 }, if tangential { m } else { 1.0 })
            }
        })
    }

    /// Numbers the rows: `class(μ, tangential)` says where each component goes.
    fn build(dim: usize, mu: &[f64], class: impl Fn(f64, bool) -> (RowClass, f64)) -> Self {
        let mut classes = Vec::with_capacity(dim * mu.len());
        let mut soc = Vec::new();
        for &m in mu {
            let mut block_size = 0;
            for k in 0..dim {
                let (mut c, scale) = class(m, k > 0);
                if let RowClass::Soc { .. } = c {
                    c = RowClass::Soc { block: soc.len() };
                    block_size += 1;
                }
                classes.push((c, scale));
            }
            if block_size > 0 {
                soc.push(block_size);
            }
        }
        let zero = classes
            .iter()
            .filter(|(c, _)| matches!(c, RowClass::Zero))
            .count();
        let nonneg = classes
            .iter()
            .filter(|(c, _)| matches!(c, RowClass::Nonneg))
            .count();
        let mut soc_start = Vec::with_capacity(soc.len());
        let mut next = zero + nonneg;
        for &size in &soc {
            soc_start.push(next);
            next += size;
        }
        let rows = next;
        let (mut next_zero, mut next_nonneg) = (0, zero);
        let mut soc_fill = vec![0; soc.len()];
        let map = classes
            .iter()
            .map(|&(c, scale)| match c {
                RowClass::Free => None,
                RowClass::Zero => {
                    next_zero += 1;
                    Some((next_zero - 1, scale))
                }
                RowClass::Nonneg => {
                    next_nonneg += 1;
                    Some((next_nonneg - 1, scale))
                }
                RowClass::Soc { block } => {
                    let row = soc_start[block] + soc_fill[block];
                    soc_fill[block] += 1;
                    Some((row, scale))
                }
            })
            .collect();
        Self {
            zero,
            nonneg,
            soc,
            rows,
            map,
        }
    }

    /// Clarabel's cone list for this layout.
    pub(crate) fn cones(&self) -> Vec<SupportedConeT<f64>> {
        let mut cones = Vec::with_capacity(2 + self.soc.len());
        if self.zero > 0 {
            cones.push(SupportedConeT::ZeroConeT(self.zero));
        }
        if self.nonneg > 0 {
            cones.push(SupportedConeT::NonnegativeConeT(self.nonneg));
        }
        cones.extend(
            self.soc
                .iter()
                .map(|&d| SupportedConeT::SecondOrderConeT(d)),
        );
        cones
    }

    /// The constraint matrix A = −S (dual, `h = None`) or A = −S Hᵀ (primal), where S maps
    /// component k to its row with its scale.
    fn a_matrix(&self, h: Option<&CscMatrix>) -> ClarabelCsc<f64> {
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        match h {
            None => {
                for (k, entry) in self.map.iter().enumerate() {
                    if let Some((row, scale)) = *entry {
                        rows.push(row);
                        cols.push(k);
                        vals.push(-scale);
                    }
                }
                let ncols = self.map.len();
                triplets_to_clarabel(self.rows, ncols, &rows, &cols, &vals)
            }
            Some(h) => {
                // (S Hᵀ)[row(k), j] = scale_k · H[j, k]
                for k in 0..h.ncols {
                    if let Some(Some((row, scale))) = self.map.get(k) {
                        for p in h.col_ptr[k]..h.col_ptr[k + 1] {
                            rows.push(*row);
                            cols.push(h.row_idx[p]);
                            vals.push(-scale * h.values[p]);
                        }
                    }
                }
                triplets_to_clarabel(self.rows, h.nrows, &rows, &cols, &vals)
            }
        }
    }
}

/// Residuals of (3.14) for the primal unknowns (v, r): F₁ = M v − H r − f (into `f[..n]`) and
/// F₂ = r − P_L(r − (Hᵀ v + shift)) (into `f[n..]`, Jacobians ∂P into `jac`); returns
/// max(‖F₁‖ / max(1, ‖f‖), ‖F₂‖ / max(1, ‖shift‖)).
fn primal_map(
    problem: &GlobalProblem,
    shift: &[f64],
    x: &[f64],
    f: &mut [f64],
    jac: &mut [f64],
) -> f64 {
    let n = problem.m.nrows;
    let (v, r) = x.split_at(n);
    let (f1, f2) = f.split_at_mut(n);
    f1.iter_mut().zip(&problem.f).for_each(|(a, b)| *a = -b);
    problem.m.gemv_acc(1.0, v, f1);
    problem.h.gemv_acc(-1.0, r, f1);
    let mut u = shift.to_vec();
    problem.h.gemv_t_acc(1.0, v, &mut u);
    natural_map(problem.dim, &problem.mu, r, &u, f2, jac);
    let s1 = crate::law::norm(&problem.f).max(1.0);
    let s2 = crate::law::norm(shift).max(1.0);
    (crate::law::norm(f1) / s1).max(crate::law::norm(f2) / s2)
}

/// The map (F₁, F₂) of [`primal_map`] on x = (v, r), with Jacobian
/// [[M, −H], [D Hᵀ, I − D]] assembled as triplets.
struct PrimalMap<'a> {
    problem: &'a GlobalProblem,
    shift: &'a [f64],
    /// (F₁, F₂) and the D blocks: current and trial
    f: [Vec<f64>; 2],
    jac: [Vec<f64>; 2],
    triplets: (Vec<usize>, Vec<usize>, Vec<f64>),
}

impl SemismoothMap for PrimalMap<'_> {
    fn eval_trial(&mut self, x: &[f64]) -> f64 {
        primal_map(
            self.problem,
            self.shift,
            x,
            &mut self.f[1],
            &mut self.jac[1],
        )
    }

    fn accept_trial(&mut self) {
        self.f.swap(0, 1);
        self.jac.swap(0, 1);
    }

    fn current(&self) -> &[f64] {
        &self.f[0]
    }

    fn build_jacobian(&mut self) {
        let (problem, jac) = (self.problem, &self.jac[0]);
        let (dim, n) = (problem.dim, problem.m.nrows);
        let (rows, cols, vals) = &mut self.triplets;
        rows.clear();
        cols.clear();
        vals.clear();
        for (i, j, val) in problem.m.triplets() {
            rows.push(i);
            cols.push(j);
            vals.push(val);
        }
        for (i, k, val) in problem.h.triplets() {
            rows.push(i);
            cols.push(n + k);
            vals.push(-val);
        }
        // ∂F₂/∂v = D Hᵀ (y = r − Hᵀ v − shift): entry (k, j) of Hᵀ is H[j, k]
        push_d_times(
            dim,
            jac,
            1.0,
            problem.h.triplets().map(|(j, k, val)| (k, j, val)),
            n,
            rows,
            cols,
            vals,
        );
        push_identity_minus_d(dim, jac, n, rows, cols, vals);
    }

    fn solve_shifted(&mut self, lambda: f64, rhs: &mut [f64]) -> Option<()> {
        let (rows, cols, vals) = &self.triplets;
        shifted_lu_solve(rhs.len(), rows, cols, vals, lambda, rhs)
    }
}

/// Polishes (v, r) of (3.15) by at most `steps` semismooth Newton steps on
/// (F₁, F₂) of [`primal_map`], with Jacobian [[M, −H], [D Hᵀ, I − D]], by the driver of
/// [`crate::newton::drive`] with [`polish_rule`] (target 1e-15; a step is kept only if it
/// decreases the residual). Returns the final residual (see [`super::polish::polish_dual`] for why).
fn polish_primal(
    problem: &GlobalProblem,
    shift: &[f64],
    v: &mut [f64],
    r: &mut [f64],
    steps: usize,
    deadline: Deadline,
) -> f64 {
    let (dim, n, m) = (problem.dim, v.len(), r.len());
    let mut x: Vec<f64> = v.iter().chain(r.iter()).copied().collect();
    let jac = vec![0.0; problem.mu.len() * dim * dim];
    let mut map = PrimalMap {
        problem,
        shift,
        f: [vec![0.0; n + m], vec![0.0; n + m]],
        jac: [jac.clone(), jac],
        triplets: (Vec::new(), Vec::new(), Vec::new()),
    };
    let report = drive(&mut map, &mut x, &polish_rule(1e-15, steps, deadline));
    v.copy_from_slice(&x[..n]);
    r.copy_from_slice(&x[n..]);
    report.residual
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use crate::natural_map::dual_natural_residual;
    use crate::natural_map::projection_jacobian;

    fn limits() -> InnerLimits {
        InnerLimits {
            tol: 1e-9,
            max_iterations: 100,
            deadline: Deadline::NEVER,
        }
    }

    pub fn solver_is_send() {
        fn assert_send<T: Send>() {}
        assert_send::<IpmSolver>();
    }

    pub fn layouts_order_rows_and_scale() {
        let mu = [0.5, 0.0, f64::INFINITY];
        let d = ConeLayout::dual_exact(3, &mu);
        // μ = 0: 2 zero rows + 1 nonneg; μ = ∞: 1 nonneg; μ = 0.5: SOC(3)
        assert_eq!(
            (d.zero, d.nonneg, d.soc.clone(), d.rows),
            (2, 2, vec![3], 7)
        );
        assert_eq!(d.map[0], Some((4, 0.5)));
        assert_eq!(d.map[1], Some((5, 1.0)));
        assert_eq!(d.map[3], Some((2, 1.0)));
        assert_eq!(d.map[4], Some((0, 1.0)));
        assert_eq!(d.map[7], None);
        let p = ConeLayout::primal(3, &mu);
        assert_eq!(
            (p.zero, p.nonneg, p.soc.clone(), p.rows),
            (2, 2, vec![3], 7)
        );
        assert_eq!(p.map[1], Some((5, 0.5)));
        assert_eq!(p.map[4], None);
        assert_eq!(p.map[7], Some((0, 1.0)));
    }

    pub fn single_contact_take_off_and_stick() {
        // W = I, b = (1, 0, 0): take-off, r = 0.
        let w = CscMatrix::identity(3, 1.0);
        let mut r = vec![5.0; 3];
        let mut s = IpmSolver::new();
        let p = InnerProblem {
            dim: 3,
            w: &w,
            b: &[1.0, 0.0, 0.0],
            mu: &[0.3],
        };
        let rep = s.solve(&p, &limits(), &mut r);
        assert_eq!(rep.status, InnerStatus::Solved);
        assert!(r.iter().all(|x| x.abs() < 1e-7), "{r:?}");
        // b = (−1, 0.1, 0): stick, r = −b inside the cone (‖0.1‖ ≤ 0.3·1).
        let p = InnerProblem {
            b: &[-1.0, 0.1, 0.0],
            ..p
        };
        let rep = s.solve(&p, &limits(), &mut r);
        assert_eq!(rep.status, InnerStatus::Solved);
        for (x, y) in r.iter().zip([1.0, -0.1, 0.0]) {
            assert!((x - y).abs() < 1e-7, "{r:?}");
        }
        assert!(s.setup.is_some());
    }

    pub fn cached_solver_matches_fresh_solve() {
        let w = CscMatrix::from_dense(3, 3, &[2.0, 0.3, 0.1, 0.3, 1.5, -0.2, 0.1, -0.2, 1.0]);
        let mu = [0.4];
        let b1 = [-1.0, 2.0, 0.5];
        let b2 = [-2.0, -0.3, 1.0];
        let mut cached = IpmSolver::new();
        let mut r1 = vec![0.0; 3];
        cached.solve(
            &InnerProblem {
                dim: 3,
                w: &w,
                b: &b1,
                mu: &mu,
            },
            &limits(),
            &mut r1,
        );
        let mut r2 = vec![0.0; 3];
        let rep = cached.solve(
            &InnerProblem {
                dim: 3,
                w: &w,
                b: &b2,
                mu: &mu,
            },
            &limits(),
            &mut r2,
        );
        assert_eq!(rep.status, InnerStatus::Solved);
        let mut fresh = IpmSolver::new();
        let mut r3 = vec![0.0; 3];
        fresh.solve(
            &InnerProblem {
                dim: 3,
                w: &w,
                b: &b2,
                mu: &mu,
            },
            &limits(),
            &mut r3,
        );
        for (x, y) in r2.iter().zip(&r3) {
            // same problem, different equilibration history: equal to IPM accuracy
            assert!((x - y).abs() < 1e-6, "{r2:?} vs {r3:?}");
        }
        assert!(r1.iter().zip(&r2).any(|(x, y)| (x - y).abs() > 1e-3));
    }

    pub fn bad_sizes_and_past_deadline() {
        let w = CscMatrix::identity(3, 1.0);
        let mut s = IpmSolver::new();
        let mut r = vec![0.0; 2];
        let p = InnerProblem {
            dim: 3,
            w: &w,
            b: &[1.0, 0.0, 0.0],
            mu: &[0.3],
        };
        assert_eq!(
            s.solve(&p, &limits(), &mut r).status,
            InnerStatus::NumericalError
        );
        let mut r = vec![0.0; 3];
        let past = InnerLimits {
            deadline: std::time::Instant::now().into(),
            ..limits()
        };
        std::thread::sleep(std::time::Duration::from_millis(1));
        assert_eq!(s.solve(&p, &past, &mut r).status, InnerStatus::TimeLimit);
        let few = InnerLimits {
            max_iterations: 1,
            ..limits()
        };
        let p = InnerProblem {
            b: &[-1.0, 3.0, 2.0],
            ..p
        };
        assert_eq!(s.solve(&p, &few, &mut r).status, InnerStatus::MaxIterations);
    }

    /// ∂P_{K_μ} against central differences, at points of all three pieces.
    pub fn projection_jacobian_matches_finite_differences() {
        let points: [(f64, [f64; 3]); 6] = [
            (0.5, [1.0, 0.1, -0.2]),  // inside
            (0.5, [-1.0, 0.1, 0.2]),  // polar
            (0.5, [0.3, 1.0, -0.7]),  // boundary piece
            (0.8, [-0.2, -0.6, 0.9]), // boundary piece, y_N < 0
            (0.0, [0.7, 0.4, 0.1]),   // μ = 0
            (f64::INFINITY, [0.7, 0.4, 0.1]),
        ];
        for (mu, y) in points {
            for d in [2, 3] {
                let y = &y[..d];
                let mut p = vec![0.0; d];
                let mut jac = vec![0.0; d * d];
                projection_jacobian(mu, y, &mut p, &mut jac);
                let h = 1e-6;
                for j in 0..d {
                    let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
                    yp[j] += h;
                    ym[j] -= h;
                    crate::cone::project(mu, &mut yp);
                    crate::cone::project(mu, &mut ym);
                    for i in 0..d {
                        let fd = (yp[i] - ym[i]) / (2.0 * h);
                        assert!(
                            (fd - jac[i * d + j]).abs() < 1e-6,
                            "mu={mu} y={y:?} ({i},{j}): {fd} vs {}",
                            jac[i * d + j]
                        );
                    }
                }
            }
        }
    }

    pub fn polish_reaches_rounding_level_on_a_sliding_contact() {
        // W = [[2, .3, 0], [.3, 1, .1], [0, .1, 1.5]], b pushes into sliding
        let w = CscMatrix::from_dense(3, 3, &[2.0, 0.3, 0.0, 0.3, 1.0, 0.1, 0.0, 0.1, 1.5]);
        let p = InnerProblem {
            dim: 3,
            w: &w,
            b: &[-1.0, 2.0, -1.5],
            mu: &[0.3],
        };
        let mut plain = vec![0.0; 3];
        IpmSolver::with_polish(0).solve(&p, &limits(), &mut plain);
        let mut polished = vec![0.0; 3];
        let rep = IpmSolver::new().solve(&p, &limits(), &mut polished);
        assert_eq!(rep.status, InnerStatus::Solved);
        assert!(rep.residual < 1e-14, "{rep:?}");
        assert!(
            (dual_natural_residual(p.dim, p.mu, p.w, p.b, &polished) - rep.residual).abs() < 1e-15
        );
        assert!(dual_natural_residual(p.dim, p.mu, p.w, p.b, &plain) >= rep.residual);
    }
}
