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
//! # Warm start
//! Clarabel is a primal-dual interior-point method started from its own central point; it
//! offers no warm start, so the incoming r of [`InnerSolver::solve`] is ignored. What *is*
//! reused is the setup: [`IpmSolver`] keeps the Clarabel solver of its last call and, when the
//! next call has the same W and μ (as in the fixed-point iteration s ↦ F(s) of (3.19), where
//! only b = q + E s changes), only overwrites the linear term through Clarabel's data-update
//! API (`update_q`), skipping equilibration and the symbolic factorization of the KKT matrix.

use super::{InnerLimits, InnerProblem, InnerReport, InnerSolver, InnerStatus};
use crate::problem::GlobalProblem;
use crate::sparse::CscMatrix;
use clarabel::algebra::CscMatrix as ClarabelCsc;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use std::time::Instant;

/// Clarabel on the dual (4.7): min over r ∈ L = ∏ K_{μⁱ} of ½ rᵀ W r + bᵀ r.
///
/// The returned r is Clarabel's primal solution x; W r + b is then ũ ∈ L* up to the
/// tolerance (the multiplier z of the cone rows, rescaled, equals ũ).
#[derive(Debug, Default)]
pub struct IpmSolver {
    /// the Clarabel solver of the last call, reused while (d, μ, W) stay the same
    cache: Option<QpCache>,
}

impl Clone for IpmSolver {
    /// A clone starts without the cached Clarabel setup (it is rebuilt on first use).
    fn clone(&self) -> Self {
        Self::new()
    }
}

impl IpmSolver {
    /// A solver with default Clarabel settings (`verbose = false`; tolerances, iteration cap
    /// and time limit come from the [`InnerLimits`] of each call).
    pub fn new() -> Self {
        Self { cache: None }
    }
}

impl InnerSolver for IpmSolver {
    fn name(&self) -> &'static str {
        "ipm"
    }

    /// Solves (4.7) with Clarabel; `r` on entry is ignored (no warm start, see module docs).
    fn solve(
        &mut self,
        problem: &InnerProblem<'_>,
        limits: &InnerLimits,
        r: &mut [f64],
    ) -> InnerReport {
        solve_dual_qp(&mut self.cache, 0, problem, limits, r, || {
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
    let v = solver.solution.x.clone();
    let z = &solver.solution.z;
    let r = (0..nr)
        .map(|k| layout.map[k].map_or(0.0, |(row, scale)| scale * z[row]))
        .collect();
    PrimalOutcome {
        v,
        r,
        report: report_of(&solver),
    }
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

/// Builds a Clarabel CSC matrix from in-range triplets (sorted, duplicates summed).
pub(crate) fn triplets_to_clarabel(
    nrows: usize,
    ncols: usize,
    rows: &[usize],
    cols: &[usize],
    vals: &[f64],
) -> ClarabelCsc<f64> {
    match CscMatrix::from_triplets(nrows, ncols, rows, cols, vals) {
        Ok(a) => to_clarabel(&a),
        // all indices are produced in range by the callers; an empty matrix keeps Clarabel's
        // dimension check (and our status mapping) in charge if that ever failed
        Err(_) => ClarabelCsc::zeros((nrows, ncols)),
    }
}

/// Copies a (checked, sorted) [`CscMatrix`] into Clarabel's CSC type.
pub(crate) fn to_clarabel(a: &CscMatrix) -> ClarabelCsc<f64> {
    ClarabelCsc::new(
        a.nrows,
        a.ncols,
        a.col_ptr.clone(),
        a.row_idx.clone(),
        a.values.clone(),
    )
}

/// Clarabel's default settings with `verbose = false`, the tolerance `limits.tol` as
/// `tol_gap_abs`, `tol_gap_rel` and `tol_feas` (Clarabel's defaults if it is not a positive
/// finite number), `limits.max_iterations` as `max_iter` and the time left before
/// `limits.deadline` as `time_limit`. A deadline already passed gives `Err(TimeLimit)`.
pub(crate) fn clarabel_settings(limits: &InnerLimits) -> Result<DefaultSettings<f64>, InnerStatus> {
    let mut settings = DefaultSettings::<f64> {
        verbose: false,
        max_iter: u32::try_from(limits.max_iterations).unwrap_or(u32::MAX),
        ..DefaultSettings::default()
    };
    if limits.tol.is_finite() && limits.tol > 0.0 {
        settings.tol_gap_abs = limits.tol;
        settings.tol_gap_rel = limits.tol;
        settings.tol_feas = limits.tol;
    }
    if let Some(deadline) = limits.deadline {
        let left = deadline
            .saturating_duration_since(Instant::now())
            .as_secs_f64();
        if left <= 0.0 {
            return Err(InnerStatus::TimeLimit);
        }
        settings.time_limit = left;
    }
    Ok(settings)
}

/// Maps Clarabel's termination status to [`InnerStatus`].
///
/// `AlmostSolved` (Clarabel stalled short of the requested tolerance but met its reduced
/// ones) is reported as [`InnerStatus::NumericalError`]: the iterate is written and usually
/// usable, but the inner criterion was not met. Certificates of primal or dual infeasibility
/// (full or reduced accuracy) are [`InnerStatus::Infeasible`].
pub(crate) fn map_status(status: SolverStatus) -> InnerStatus {
    match status {
        SolverStatus::Solved => InnerStatus::Solved,
        SolverStatus::PrimalInfeasible
        | SolverStatus::DualInfeasible
        | SolverStatus::AlmostPrimalInfeasible
        | SolverStatus::AlmostDualInfeasible => InnerStatus::Infeasible,
        SolverStatus::MaxIterations => InnerStatus::MaxIterations,
        SolverStatus::MaxTime => InnerStatus::TimeLimit,
        SolverStatus::AlmostSolved
        | SolverStatus::Unsolved
        | SolverStatus::NumericalError
        | SolverStatus::InsufficientProgress
        | SolverStatus::CallbackTerminated => InnerStatus::NumericalError,
    }
}

/// The report of a finished Clarabel solve: mapped status, iterations and Clarabel's own
/// stopping measure max(res_primal, res_dual, min(gap_abs, gap_rel)).
pub(crate) fn report_of(solver: &DefaultSolver<f64>) -> InnerReport {
    let info = &solver.info;
    let residual = info
        .res_primal
        .max(info.res_dual)
        .max(info.gap_abs.min(info.gap_rel));
    InnerReport {
        status: map_status(info.status),
        iterations: info.iterations as usize,
        residual,
    }
}

/// A Clarabel solver set up for min ½ rᵀ W r + bᵀ r s.t. A r + s = 0, s ∈ K, with the data
/// that determine P, A and K: (d, μ, W) and a variant tag (e.g. the number of facets).
/// Only b changes between the inner solves of one fixed-point run, so a cached solver needs
/// just `update_q`.
pub(crate) struct QpCache {
    dim: usize,
    variant: usize,
    mu: Vec<f64>,
    w: CscMatrix,
    solver: DefaultSolver<f64>,
}

impl std::fmt::Debug for QpCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("QpCache")
            .field("dim", &self.dim)
            .field("variant", &self.variant)
            .field("contacts", &self.mu.len())
            .field("w_nnz", &self.w.nnz())
            .finish()
    }
}

impl QpCache {
    fn matches(&self, variant: usize, problem: &InnerProblem<'_>) -> bool {
        self.dim == problem.dim
            && self.variant == variant
            && self.mu.len() == problem.mu.len()
            && self
                .mu
                .iter()
                .zip(problem.mu)
                .all(|(a, b)| a.to_bits() == b.to_bits())
            && self.w == *problem.w
    }
}

/// Whether an [`InnerProblem`] and the output slice fit together and hold finite data.
pub(crate) fn valid_inner(problem: &InnerProblem<'_>, r: &[f64]) -> bool {
    let m = problem.mu.len() * problem.dim;
    (problem.dim == 2 || problem.dim == 3)
        && problem.w.nrows == m
        && problem.w.ncols == m
        && problem.b.len() == m
        && r.len() == m
        && problem.w.check().is_ok()
        && problem.w.first_non_finite().is_none()
        && problem.b.iter().all(|x| x.is_finite())
        && problem.mu.iter().all(|x| *x >= 0.0)
}

/// Solves min ½ rᵀ W r + bᵀ r s.t. A r + s = 0, s ∈ K with Clarabel, where `constraints`
/// builds (A, K) for a new setup. Reuses `cache` when (d, μ, W, variant) are unchanged.
/// Writes Clarabel's x into `r` (left untouched when no solve took place).
pub(crate) fn solve_dual_qp(
    cache: &mut Option<QpCache>,
    variant: usize,
    problem: &InnerProblem<'_>,
    limits: &InnerLimits,
    r: &mut [f64],
    constraints: impl FnOnce() -> (ClarabelCsc<f64>, Vec<SupportedConeT<f64>>),
) -> InnerReport {
    let fail = |status| InnerReport {
        status,
        iterations: 0,
        residual: f64::INFINITY,
    };
    if !valid_inner(problem, r) {
        return fail(InnerStatus::NumericalError);
    }
    let settings = match clarabel_settings(limits) {
        Ok(s) => s,
        Err(status) => return fail(status),
    };
    let reused = match cache.as_mut() {
        Some(c) if c.matches(variant, problem) => {
            c.solver.update_q(&problem.b.to_vec()).is_ok()
                && c.solver.update_settings(settings.clone()).is_ok()
        }
        _ => false,
    };
    if !reused {
        *cache = None;
        let (a, cones) = constraints();
        let p = to_clarabel(&problem.w.upper_triangle());
        let zeros = vec![0.0; a.m];
        match DefaultSolver::new(&p, problem.b, &a, &zeros, &cones, settings) {
            Ok(solver) => {
                *cache = Some(QpCache {
                    dim: problem.dim,
                    variant,
                    mu: problem.mu.to_vec(),
                    w: problem.w.clone(),
                    solver,
                })
            }
            Err(_) => return fail(InnerStatus::NumericalError),
        }
    }
    let Some(c) = cache.as_mut() else {
        return fail(InnerStatus::NumericalError);
    };
    c.solver.solve();
    let x = &c.solver.solution.x;
    if x.len() == r.len() && x.iter().all(|v| v.is_finite()) {
        r.copy_from_slice(x);
    }
    let report = report_of(&c.solver);
    if x.iter().any(|v| !v.is_finite()) && report.status == InnerStatus::Solved {
        return InnerReport {
            status: InnerStatus::NumericalError,
            ..report
        };
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> InnerLimits {
        InnerLimits {
            tol: 1e-9,
            max_iterations: 100,
            deadline: None,
        }
    }

    #[test]
    fn solver_is_send() {
        fn assert_send<T: Send>() {}
        assert_send::<IpmSolver>();
    }

    #[test]
    fn layouts_order_rows_and_scale() {
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

    #[test]
    fn single_contact_take_off_and_stick() {
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
        assert!(s.cache.is_some());
    }

    #[test]
    fn cached_solver_matches_fresh_solve() {
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

    #[test]
    fn bad_sizes_and_past_deadline() {
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
            deadline: Some(Instant::now()),
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
}
