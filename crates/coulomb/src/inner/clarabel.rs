//! Clarabel plumbing shared by the interior-point ([`super::ipm`]) and faceted
//! ([`super::faceted`]) inner solvers: matrices in Clarabel's CSC type, settings from
//! [`InnerLimits`], status mapping, and the dual QP (4.7) solve on a setup built once.

use super::polish::polish_dual;
use super::{InnerLimits, InnerProblem, InnerReport, InnerStatus};
use crate::linalg::sparse::CscMatrix;
use crate::natural_map::dual_natural_residual;
use clarabel::algebra::CscMatrix as ClarabelCsc;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use std::time::Instant;

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
    if let Some(deadline) = limits.deadline.instant() {
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

/// A Clarabel solver set up for min ½ rᵀ W r + bᵀ r s.t. A r + s = 0, s ∈ K, built at the
/// first solve of an inner solver (Clarabel's setup equilibrates with the first b, so it is
/// built with it) and kept for all later ones: only b changes between the inner solves on
/// one (d, W, μ), so a later solve needs just `update_q`.
pub(crate) struct QpSetup {
    /// the size of r it was built for
    size: usize,
    solver: DefaultSolver<f64>,
}

impl std::fmt::Debug for QpSetup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("QpSetup").field("size", &self.size).finish()
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

/// Solves min ½ rᵀ W r + bᵀ r s.t. A r + s = 0, s ∈ K with Clarabel: with the solver of
/// `setup` (built by its first call, `constraints` building (A, K); the (d, W, μ) of every
/// later call are those of the first). Writes Clarabel's x into `r` (left untouched when no
/// solve took place).
pub(crate) fn solve_dual_qp(
    setup: &mut Option<QpSetup>,
    polish: usize,
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
    let reused = match setup.as_mut() {
        Some(c) if c.size == r.len() => {
            c.solver.update_q(&problem.b.to_vec()).is_ok()
                && c.solver.update_settings(settings.clone()).is_ok()
        }
        Some(_) => return fail(InnerStatus::NumericalError),
        None => false,
    };
    if !reused {
        *setup = None;
        let (a, cones) = constraints();
        let p = to_clarabel(&problem.w.upper_triangle());
        let zeros = vec![0.0; a.m];
        match DefaultSolver::new(&p, problem.b, &a, &zeros, &cones, settings) {
            Ok(solver) => {
                *setup = Some(QpSetup {
                    size: r.len(),
                    solver,
                })
            }
            Err(_) => return fail(InnerStatus::NumericalError),
        }
    }
    let Some(c) = setup.as_mut() else {
        return fail(InnerStatus::NumericalError);
    };
    c.solver.solve();
    let x = &c.solver.solution.x;
    let finite = x.len() == r.len() && x.iter().all(|v| v.is_finite());
    if finite {
        r.copy_from_slice(x);
    }
    let mut report = report_of(&c.solver);
    if !finite {
        if report.status != InnerStatus::Infeasible {
            report.status = InnerStatus::NumericalError;
        }
        return report;
    }
    if polish > 0 {
        let raw = c.solver.info.status;
        let stalled = matches!(
            raw,
            SolverStatus::AlmostSolved | SolverStatus::InsufficientProgress
        );
        let residual = if raw == SolverStatus::Solved || stalled {
            polish_dual(problem, r, polish, limits.deadline)
        } else {
            dual_natural_residual(problem.dim, problem.mu, problem.w, problem.b, r)
        };
        report.residual = residual;
        if stalled && residual <= limits.tol {
            report.status = InnerStatus::Solved;
        }
    }
    report
}
