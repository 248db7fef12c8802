//! The proximal point on r solved in the velocities of a global problem: a method of
//! multipliers for the incremental problem (2.10) of rigid bodies whose W = Hᵀ M⁻¹ H (4.7) is
//! rank-deficient.
//!
//! With multipliers λ = r_k and a penalty ρᵢ > 0 per contact, step k solves for v
//!
//! ```text
//!     G(v) = M v − f − H P_L(λ − ρ ũ(Hᵀ v + w)) = 0,    ũ = u + μ‖u_T‖ e  (3.7),
//! ```
//!
//! and sets r_{k+1} = P_L(λ − ρ ũ). A fixed point r = P_L(r − ρ ũ) is Coulomb's law (2.9) in
//! De Saxcé's form (3.8) with M v = H r + f: a solution of (2.10). Step k is the proximal
//! point of Siconos' PROX, r_{k+1} solving the law for (W + I/ρ, q − r_k/ρ) (with ũ of the
//! unregularized u), but its unknowns are the n velocities, which are unique where the m ≫ n
//! impulses are not (the convex problem (3.15) is strongly convex in v). Each step is a
//! semismooth Newton method on G with
//!
//! ```text
//!     J = M + H B Hᵀ,    Bᵢ = ρᵢ ∂P_{K_μ}(yᵢ) (I + μ e t̂ᵀ),    t̂ = u_T / ‖u_T‖ (0 at u_T = 0),
//! ```
//!
//! a dense LU of size n (the problems it applies to have n ≤
//! [`crate::settings::BarrierParams::max_schur_dofs`]; J and the products with H and H_u are
//! formed contact by contact from the d columns of each contact, gathered once per solve
//! into one dense block) and a backtracking search on ‖G‖,
//! stopped at its target, at a cap, or after a few steps in a row that barely lower ‖G‖
//! ([`MultiplierParams::slow_steps`]; measured: docs/tuning.md,
//! `tuning.multiplier.slow_steps`). A step first
//! tries the factors of the run's last J (a chord step, v ← v − J_old⁻¹ G(v)), kept when it
//! lowers ‖G‖ by the factor [`MultiplierParams::chord_ratio`]: near the solution of a
//! subproblem J changes little from step to step and the LU costs O(n³) against O(n²).
//! This Newton loop is its own, not the driver `newton::drive` of the end game and the
//! proximal point: its steps try the chord direction before J is built, and take it on that
//! ratio test without a search; only a step that factors J ends with the Armijo search (on
//! ‖G‖², `line_search::armijo`), whose exhaustion ends the run.
//! ρᵢ starts at ρ_f / w̄ with w̄ the mean of trace(Wᵢᵢ)/d: a penalty of the order of 1/‖W‖
//! keeps the Newton systems regular and the outer iteration moving (how ρ_f was measured:
//! docs/tuning.md, `tuning.multiplier.rho_factor`).
//! ρ then follows the subproblems: it grows after a step whose Newton run was easy (the
//! proximal point converges faster as ρ grows), up to a cap, and is halved after a step whose
//! Newton run failed and whose r is worse (its error above
//! [`MultiplierParams::reject_growth`] times the current one).
//!
//! Every iterate is judged like the solver's iterates: v = M⁻¹(H r + f) recomputed from r,
//! u = Hᵀ v + w, the error of docs/error.md and the balance residual on the stored data.
//!
//! Where the iteration goes depends on where it starts (the law with μ = 1 is not monotone):
//! [`solve_from`] runs it from several starts at once and keeps the first run that
//! converges.

use rayon::prelude::*;

use crate::deadline::Deadline;
use crate::linalg::sparse::CscMatrix;
use crate::line_search::{armijo, Search};
use crate::mass::MassFactor;
use crate::problem::GlobalProblem;

/// Parameters of the method of multipliers in the velocities ([`crate::multiplier`]): a
/// stage of the default for problems of rigid bodies — global ones with at most
/// [`crate::barrier::BarrierParams::max_schur_dofs`] degrees of freedom and at most half as
/// many as contact unknowns, local ones whose W has a skeleton
/// ([`crate::barrier::BarrierParams::skeleton_rank_ratio`]) that reproduces it
/// (`skeleton_residual`) — run after the interior-point try, from its lowest-error point and
/// the end points of its other runs.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MultiplierParams {
    /// cap on outer (multiplier) steps per run; 0: no such stage
    pub max_steps: usize,
    /// ρᵢ = `rho_factor` / w̄, w̄ the mean of trace(Wᵢᵢ)/d; > 0
    /// (docs/tuning.md, `tuning.multiplier`)
    pub rho_factor: f64,
    /// Newton steps per outer step; ≥ 1
    pub newton_steps: usize,
    /// a Newton run also stops after this many steps in a row that each lowered ‖G‖ by less
    /// than the factor `slow_ratio` (a damped crawl: the outer step goes on from where it
    /// stands, [`MultiplierParams::reject_growth`]); ≥ 1 (docs/tuning.md, `tuning.multiplier`)
    pub slow_steps: usize,
    /// see `slow_steps`; in (0, 1]
    pub slow_ratio: f64,
    /// a Newton step first tries the step of the factors of the last J factored in the same
    /// Newton run (a chord step: two triangular solves instead of an LU of size n); it is
    /// taken if ‖G‖ falls to at most `chord_ratio` times its value, else J is factored at
    /// the current v; at most `newton_steps` chord steps per Newton run; in [0, 1) (0: every
    /// step factors J) (docs/tuning.md, `tuning.multiplier`)
    pub chord_ratio: f64,
    /// halvings of the backtracking search on ‖G‖ before a Newton run gives up; ≥ 1
    pub halvings: usize,
    /// Armijo's constant of that search; in (0, 1)
    pub sufficient_decrease: f64,
    /// Newton on G stops at ‖G‖ ≤ `inner_ratio` · err · max(1, ‖f‖), err the error at the
    /// outer step's start; > 0
    pub inner_ratio: f64,
    /// an outer step whose Newton run did not reach its target and whose r has an error above
    /// `reject_growth` times the current one is taken again from the same multipliers with
    /// every ρᵢ multiplied by `penalty_cut`; ≥ 1. With 1 an unsolved step is kept only when
    /// its error is at most the current one (docs/tuning.md, `tuning.multiplier`)
    pub reject_growth: f64,
    /// see `reject_growth`; in (0, 1)
    pub penalty_cut: f64,
    /// after an outer step whose Newton run reached its target in more than
    /// `easy_newton_steps`, a ρᵢ below its first value grows by this factor, up to that
    /// value; ≥ 1
    pub penalty_regrowth: f64,
    /// after an outer step whose Newton run reached its target in at most this many steps
    /// that factored J (its chord steps not counted, `chord_ratio`), every ρᵢ grows by
    /// `penalty_growth`, up to `penalty_cap` times its first value (the
    /// proximal point converges faster as ρ grows: Rockafellar 1976)
    /// (docs/tuning.md, `tuning.multiplier`)
    pub easy_newton_steps: usize,
    /// see `easy_newton_steps`; ≥ 1 (1: ρ never grows above its first value)
    /// (docs/tuning.md, `tuning.multiplier`)
    pub penalty_growth: f64,
    /// see `easy_newton_steps`; ≥ 1
    pub penalty_cap: f64,
    /// a run stops after this many outer steps without the lowest merit falling to
    /// `stall_gain` times its value at the last such fall; ≥ 1
    pub stall_steps: usize,
    /// see `stall_steps`; in (0, 1)
    pub stall_gain: f64,
    /// the stage factors J at most this many times in all its runs (chord steps not
    /// counted); its runs take their steps in lock-step rounds and the budget is checked
    /// between rounds, a budget in work so that the path does not depend on the machine's
    /// speed or load; ≥ 1 (docs/tuning.md, `tuning.multiplier`)
    pub max_factorizations: usize,
    /// the stage runs the method from at most this many starts at once, the best point of
    /// the interior-point try and the end points of its other runs
    /// ([`crate::multiplier::solve_from`]); ≥ 1 (1: from the best point only)
    /// (docs/tuning.md, `tuning.multiplier`)
    pub starts: usize,
    /// on a local problem the stage runs on the velocity form of W's skeleton C A⁻¹ R
    /// ([`crate::linalg::skeleton`]), symmetric or not, and only where
    /// [`crate::linalg::skeleton::Skeleton::residual`] ≤ `skeleton_residual` · tol (W = C A⁻¹ R holds
    /// to rounding when rank W equals the skeleton's rank: the stage then solves the stored
    /// W's law; else it could not reach tol on it); ≥ 0
    pub skeleton_residual: f64,
    /// where the stage ends unconverged at an error (max with the balance residual) ≤
    /// `finish_below` · tol, at most `finish_steps` Levenberg–Marquardt steps on the natural
    /// map itself follow from its point ([`crate::newton::least_squares`]: sparse, for at most
    /// `finish_max_unknowns` contact unknowns), kept where they lower the error; ≥ 0
    /// (docs/tuning.md, `tuning.multiplier`)
    pub finish_below: f64,
    /// see `finish_below`; 0: no finish
    pub finish_steps: usize,
    /// the finish stops after this many steps in a row that each leave more than 90 % of the
    /// error (the floor of the point's active set: [`crate::newton::least_squares`]); 0: no
    /// such stop (docs/tuning.md, `tuning.multiplier`)
    pub finish_slow_steps: usize,
    /// see `finish_below`
    pub finish_max_unknowns: usize,
    /// the finish is also tried while the stage runs ([`crate::multiplier::solve_from`]):
    /// on a run whose lowest merit falls to at most `finish_crawl` · tol and below this
    /// factor times the merit from which that run last tried it, at most `finish_attempts`
    /// times per stage (a step costs sparse Cholesky factorizations of JᵀJ + λνI); in (0, 1]
    /// (docs/tuning.md, `tuning.multiplier`)
    pub finish_gain: f64,
    /// see `finish_gain`; ≥ 0
    pub finish_crawl: f64,
    /// see `finish_gain`
    pub finish_attempts: usize,
}

impl Default for MultiplierParams {
    fn default() -> Self {
        Self {
            max_steps: 20_000,
            rho_factor: 300.0,
            newton_steps: 50,
            slow_steps: 4,
            slow_ratio: 0.9,
            chord_ratio: 0.5,
            halvings: 30,
            sufficient_decrease: 1e-4,
            inner_ratio: 1e-2,
            reject_growth: 1.0,
            penalty_cut: 0.5,
            penalty_regrowth: 1.2,
            easy_newton_steps: 6,
            penalty_growth: 1.5,
            penalty_cap: 100.0,
            stall_steps: 1000,
            stall_gain: 0.5,
            max_factorizations: MULTIPLIER_MAX_FACTORIZATIONS,
            starts: 4,
            skeleton_residual: 0.01,
            finish_below: 10.0,
            finish_steps: 8,
            finish_slow_steps: 2,
            finish_max_unknowns: 2000,
            finish_gain: 0.5,
            finish_crawl: 2.0,
            finish_attempts: 8,
        }
    }
}

impl MultiplierParams {
    pub(crate) fn validate(&self) -> Result<(), String> {
        if self.newton_steps == 0
            || self.slow_steps == 0
            || self.halvings == 0
            || self.stall_steps == 0
            || self.starts == 0
        {
            return Err(
                "tuning.multiplier: newton_steps, slow_steps, halvings, stall_steps and starts must \
                 be ≥ 1"
                    .into(),
            );
        }
        if !(self.slow_ratio > 0.0 && self.slow_ratio <= 1.0) {
            return Err("tuning.multiplier: slow_ratio must be in (0, 1]".into());
        }
        if !(self.chord_ratio >= 0.0 && self.chord_ratio < 1.0) {
            return Err("tuning.multiplier: chord_ratio must be in [0, 1)".into());
        }
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(self.rho_factor) || !positive(self.inner_ratio) {
            return Err("tuning.multiplier: rho_factor and inner_ratio must be positive".into());
        }
        let open = |x: f64| x > 0.0 && x < 1.0;
        if !open(self.sufficient_decrease) || !open(self.stall_gain) || !open(self.penalty_cut) {
            return Err(
                "tuning.multiplier: sufficient_decrease, stall_gain and penalty_cut must be in (0, 1)"
                    .into(),
            );
        }
        let at_least_one = |x: f64| x.is_finite() && x >= 1.0;
        if ![
            self.reject_growth,
            self.penalty_regrowth,
            self.penalty_growth,
            self.penalty_cap,
        ]
        .into_iter()
        .all(at_least_one)
        {
            return Err(
                "tuning.multiplier: reject_growth, penalty_regrowth, penalty_growth and \
                 penalty_cap must be finite and ≥ 1"
                    .into(),
            );
        }
        if self.max_factorizations == 0 {
            return Err("tuning.multiplier.max_factorizations must be ≥ 1".into());
        }
        if !(self.skeleton_residual.is_finite() && self.skeleton_residual >= 0.0) {
            return Err("tuning.multiplier.skeleton_residual must be finite and ≥ 0".into());
        }
        let nonnegative = |x: f64| x.is_finite() && x >= 0.0;
        if !nonnegative(self.finish_below) || !nonnegative(self.finish_crawl) {
            return Err(
                "tuning.multiplier.finish_below and finish_crawl must be finite and ≥ 0".into(),
            );
        }
        if !(self.finish_gain > 0.0 && self.finish_gain <= 1.0) {
            return Err("tuning.multiplier.finish_gain must be in (0, 1]".into());
        }
        Ok(())
    }
}

/// The default of [`MultiplierParams::max_factorizations`] (docs/solver-core.md).
pub const MULTIPLIER_MAX_FACTORIZATIONS: usize = 2000;

/// The largest n [`solve`] takes: its Newton systems are dense n × n (8 n² bytes, O(n³)
/// flops per step; the default's stage stays at or below
/// [`crate::settings::BarrierParams::max_schur_dofs`]).
pub const MAX_DENSE_DOFS: usize = 5_000;

/// How a run of [`solve`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MultiplierStatus {
    /// error and balance residual ≤ tol at the returned r
    Converged,
    /// [`MultiplierParams::max_steps`] outer steps
    MaxSteps,
    /// [`MultiplierParams::stall_steps`] outer steps without halving the lowest merit
    Stalled,
    /// the deadline passed
    TimeLimit,
    /// a non-finite start, G or error, or sizes that disagree
    NumericalError,
    /// more than [`MAX_DENSE_DOFS`] degrees of freedom: nothing run
    TooLarge,
}

/// The outcome of [`solve`]: r holds the lowest-merit iterate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultiplierReport {
    /// how it ended
    pub status: MultiplierStatus,
    /// outer (multiplier) steps
    pub steps: usize,
    /// Newton steps (chord steps included), summed over the outer steps
    pub newton_steps: usize,
    /// of those, the chord steps ([`MultiplierParams::chord_ratio`]): J not factored
    pub chord_steps: usize,
    /// the error of docs/error.md at the returned r
    pub error: f64,
    /// the balance residual ‖M v − H r − f‖ / max(1, ‖f‖) at the returned r, v = M⁻¹(H r + f)
    pub balance: f64,
}

/// The data every run of the method shares: the problem in its velocity form (with the
/// columns of H and H_u gathered by contact), the parameters, ρ's first value and the
/// parallelism of the dense LUs.
struct Shared<'a> {
    p: &'a GlobalProblem,
    h_cols: ContactColumns,
    hu_cols: ContactColumns,
    params: &'a MultiplierParams,
    rho_i: f64,
    f_norm: f64,
    tol: f64,
    par: faer::Par,
}

/// Runs the method of multipliers (module docs) on `p` from `r` (replaced by the iterate of
/// lowest merit max(error, balance residual)) until both are ≤ `tol`, a cap, a stall or the
/// deadline. `mass` is the factor of p's M; `w_mean` the mean of the diagonal of the W
/// whose law is solved (ρ = [`MultiplierParams::rho_factor`] / `w_mean`); `judge` returns
/// (error, balance residual) of an r on the problem as stored (it may be another form of the
/// same law: a local problem whose W has the skeleton p, [`crate::linalg::skeleton`]). With `hu`,
/// u = `hu`ᵀ v + w instead of Hᵀ v + w (a skeleton W ≈ C A⁻¹ R of a W that is not
/// symmetric: H = R, `hu` = Cᵀ); `mass` is then a factor of the symmetric part of M, used
/// for the start v only. `par`: the parallelism of the dense LU of each Newton step
/// ([`crate::linalg::dense::parallelism`]).
#[allow(clippy::too_many_arguments)]
pub fn solve(
    p: &GlobalProblem,
    hu: Option<&CscMatrix>,
    mass: &MassFactor,
    w_mean: f64,
    r: &mut [f64],
    tol: f64,
    params: &MultiplierParams,
    par: faer::Par,
    deadline: Deadline,
    judge: impl Fn(&[f64]) -> (f64, f64) + Sync,
) -> MultiplierReport {
    let mut starts = [r.to_vec()];
    let report = solve_from(
        p,
        hu,
        mass,
        w_mean,
        &mut starts,
        tol,
        params,
        par,
        deadline,
        judge,
        |_| None,
    );
    r.copy_from_slice(&starts[0]);
    report
}

/// [`solve`] from each point of `starts` at once (at least one): one run per start, the
/// runs taking their outer steps in turn on rayon's threads, none waiting for another (each
/// Newton run on one thread when `par` is [`faer::Par::Seq`]).
/// The law with μ > 0 is not monotone: the limit of the iteration, if any, depends on its
/// start (measured: docs/tuning.md, `tuning.multiplier.starts`). It stops when a
/// run has converged, every run has stopped, or at the deadline. `starts[0]` is replaced by
/// the point returned: the first converged run's, else the lowest-merit iterate of all
/// runs. The report is that run's, with `steps` and `newton_steps` summed over all runs.
///
/// `finish` (`|_| None` for none): when a run's lowest merit falls to at most
/// [`MultiplierParams::finish_crawl`] · tol and below [`MultiplierParams::finish_gain`]
/// times the merit from which that run last called it, `finish` is called on its lowest-merit
/// r (at most [`MultiplierParams::finish_attempts`] times in all, for at most
/// [`MultiplierParams::finish_max_unknowns`] contact unknowns); a point it returns ends the
/// stage as converged (`finish` returns only points that the caller has judged converged on
/// the problem as stored).
#[allow(clippy::too_many_arguments)]
pub fn solve_from(
    p: &GlobalProblem,
    hu: Option<&CscMatrix>,
    mass: &MassFactor,
    w_mean: f64,
    starts: &mut [Vec<f64>],
    tol: f64,
    params: &MultiplierParams,
    par: faer::Par,
    deadline: Deadline,
    judge: impl Fn(&[f64]) -> (f64, f64) + Sync,
    finish: impl Fn(&[f64]) -> Option<Vec<f64>> + Sync,
) -> MultiplierReport {
    let n = p.dofs();
    let rho_i = if w_mean > 0.0 && w_mean.is_finite() {
        params.rho_factor / w_mean
    } else {
        1.0
    };
    let hu = hu.unwrap_or(&p.h);
    let shapes = hu.nrows == n && hu.ncols == p.w.len() && mass.dim() == n;
    let shared = Shared {
        p,
        h_cols: ContactColumns::new(&p.h, p.dim, p.contacts()),
        hu_cols: ContactColumns::new(hu, p.dim, p.contacts()),
        params,
        rho_i,
        f_norm: crate::law::norm(&p.f),
        tol,
        par,
    };
    let mut report = MultiplierReport {
        status: MultiplierStatus::NumericalError,
        steps: 0,
        newton_steps: 0,
        chord_steps: 0,
        error: f64::NAN,
        balance: f64::NAN,
    };
    let mut runs = Vec::with_capacity(starts.len());
    for r in starts.iter() {
        if r.len() != p.w.len() || !shapes {
            runs.push(Run::stopped(r, report, MultiplierStatus::NumericalError));
            continue;
        }
        let (e0, b0) = judge(r);
        let start = MultiplierReport {
            error: e0,
            balance: b0,
            ..report
        };
        if !(e0.is_finite() && b0.is_finite()) {
            runs.push(Run::stopped(r, start, MultiplierStatus::NumericalError));
        } else if e0 <= tol && b0 <= tol {
            runs.push(Run::stopped(r, start, MultiplierStatus::Converged));
        } else if n > MAX_DENSE_DOFS {
            runs.push(Run::stopped(r, start, MultiplierStatus::TooLarge));
        } else {
            runs.push(Run::new(&shared, mass, r, start));
        }
    }
    if runs.is_empty() {
        return report;
    }
    // Lock-step rounds: in each round every live run takes one outer step (Newton run, then
    // its conclusion), the runs on rayon's threads; between rounds the decisions are taken
    // in the runs' order (the first converged run by index, the finishes, the budget), so
    // that the result is the same on any number of threads and under any load. Each run's
    // iterates are those it would take alone.
    let mut attempts = 0;
    let mut point: Option<Vec<f64>> = None;
    loop {
        if runs
            .iter()
            .any(|run| run.done == Some(MultiplierStatus::Converged))
        {
            break;
        }
        let mut live: Vec<&mut Run> = runs.iter_mut().filter(|run| run.done.is_none()).collect();
        if live.is_empty() {
            break;
        }
        if deadline.passed() {
            live.iter_mut()
                .for_each(|run| run.done = Some(MultiplierStatus::TimeLimit));
            break;
        }
        live.par_iter_mut().for_each(|run| {
            run.newton(&shared, deadline);
            run.conclude(&shared, &judge);
        });
        if runs
            .iter()
            .any(|run| run.done == Some(MultiplierStatus::Converged))
        {
            continue;
        }
        // the finishes of this round: the runs close to tol, in index order, while attempts
        // are left; run at once, the first converged point by index kept
        let mut close = Vec::new();
        for (i, run) in runs.iter_mut().enumerate() {
            if attempts < params.finish_attempts && run.done.is_none() && wants_finish(&shared, run)
            {
                attempts += 1;
                run.finish_last = run.best_merit;
                close.push(i);
            }
        }
        if !close.is_empty() {
            let found: Vec<Option<Vec<f64>>> =
                close.par_iter().map(|&i| finish(&runs[i].best_r)).collect();
            if let Some(r) = found.into_iter().flatten().next() {
                point = Some(r);
                break;
            }
        }
        let factorizations: usize = runs
            .iter()
            .map(|run| run.report.newton_steps - run.report.chord_steps)
            .sum();
        if factorizations >= params.max_factorizations {
            runs.iter_mut()
                .filter(|run| run.done.is_none())
                .for_each(|run| run.done = Some(MultiplierStatus::MaxSteps));
            break;
        }
    }
    if let Some(r) = point {
        let (error, balance) = judge(&r);
        report = MultiplierReport {
            status: MultiplierStatus::Converged,
            steps: runs.iter().map(|run| run.report.steps).sum(),
            newton_steps: runs.iter().map(|run| run.report.newton_steps).sum(),
            chord_steps: runs.iter().map(|run| run.report.chord_steps).sum(),
            error,
            balance,
        };
        if let Some(r0) = starts.first_mut() {
            *r0 = r;
        }
        return report;
    }
    let chosen = runs
        .iter()
        .position(|run| run.done == Some(MultiplierStatus::Converged))
        .or_else(|| {
            (0..runs.len()).min_by(|&a, &b| runs[a].best_merit.total_cmp(&runs[b].best_merit))
        })
        .unwrap_or(0);
    let run = &runs[chosen];
    report = MultiplierReport {
        status: run.done.unwrap_or(MultiplierStatus::MaxSteps),
        steps: runs.iter().map(|run| run.report.steps).sum(),
        newton_steps: runs.iter().map(|run| run.report.newton_steps).sum(),
        chord_steps: runs.iter().map(|run| run.report.chord_steps).sum(),
        ..run.report
    };
    let best = run.best_r.clone();
    if let Some(r0) = starts.first_mut() {
        *r0 = best;
    }
    report
}

/// Whether [`solve_from`] calls the finish on `run`'s lowest-merit point: it has come to at
/// most [`MultiplierParams::finish_crawl`] · tol and below [`MultiplierParams::finish_gain`]
/// times the merit from which it last called it (for at most
/// [`MultiplierParams::finish_max_unknowns`] contact unknowns).
fn wants_finish(s: &Shared<'_>, run: &Run) -> bool {
    let params = s.params;
    params.finish_steps > 0
        && s.p.w.len() <= params.finish_max_unknowns
        && run.best_merit <= params.finish_crawl * s.tol
        && run.best_merit < params.finish_gain * run.finish_last
}

/// One run of the method of multipliers: its multipliers λ, penalties ρ, velocity v, the
/// lowest-merit iterate, the stall bookkeeping and the work space of its Newton steps.
struct Run {
    /// Some once it has stopped, with why
    done: Option<MultiplierStatus>,
    report: MultiplierReport,
    rho: Vec<f64>,
    lambda: Vec<f64>,
    v: Vec<f64>,
    best_r: Vec<f64>,
    best_merit: f64,
    stall_reference: f64,
    since_gain: usize,
    /// the lowest merit from which this run last called the finish ([`solve_from`])
    finish_last: f64,
    current_error: f64,
    /// the Newton run of the current outer step: its ‖G‖ target, steps that factored J (its
    /// chord steps not counted), and v at its start
    target: f64,
    newton: usize,
    v_start: Vec<f64>,
    blocks: Vec<f64>,
    jm: faer::Mat<f64>,
    /// the LU of J at an earlier point of the current Newton run (its chord steps,
    /// [`MultiplierParams::chord_ratio`])
    lu: Option<crate::linalg::dense::Lu>,
    /// Hᵢ Bᵢ of one contact (the assembly's work space)
    hb: Vec<f64>,
    dv: Vec<f64>,
    g: Residual,
    trial: Residual,
    vt: Vec<f64>,
}

impl Run {
    /// A run that does not start, ending with `status` at `r` (judged as `report`).
    fn stopped(r: &[f64], report: MultiplierReport, status: MultiplierStatus) -> Self {
        let merit = report.error.max(report.balance);
        Self {
            done: Some(status),
            report: MultiplierReport { status, ..report },
            rho: Vec::new(),
            lambda: Vec::new(),
            v: Vec::new(),
            best_r: r.to_vec(),
            best_merit: if merit.is_nan() { f64::INFINITY } else { merit },
            stall_reference: merit,
            since_gain: 0,
            finish_last: f64::INFINITY,
            current_error: report.error,
            target: 0.0,
            newton: 0,
            v_start: Vec::new(),
            blocks: Vec::new(),
            jm: faer::Mat::zeros(0, 0),
            lu: None,
            hb: Vec::new(),
            dv: Vec::new(),
            g: Residual::new(0, 0),
            trial: Residual::new(0, 0),
            vt: Vec::new(),
        }
    }

    /// A run from `r` (finite, judged as `report`), v = M⁻¹(H r + f).
    fn new(s: &Shared<'_>, mass: &MassFactor, r: &[f64], report: MultiplierReport) -> Self {
        let p = s.p;
        let (n, m, d) = (p.dofs(), p.w.len(), p.dim);
        let mut v = p.h.mul_vec(r);
        for (x, f) in v.iter_mut().zip(&p.f) {
            *x += f;
        }
        mass.solve_in_place(&mut v);
        let merit = report.error.max(report.balance);
        Self {
            done: None,
            report,
            rho: vec![s.rho_i; p.contacts()],
            lambda: r.to_vec(),
            v,
            best_r: r.to_vec(),
            best_merit: merit,
            stall_reference: merit,
            since_gain: 0,
            finish_last: f64::INFINITY,
            current_error: report.error,
            target: 0.0,
            newton: 0,
            v_start: vec![0.0; n],
            blocks: vec![0.0; p.contacts() * d * d],
            jm: faer::Mat::zeros(n, n),
            lu: None,
            hb: Vec::new(),
            dv: vec![0.0; n],
            g: Residual::new(n, m),
            trial: Residual::new(n, m),
            vt: vec![0.0; n],
        }
    }

    /// The Newton run of the next outer step: G(v) = 0 for the multipliers λ = r_k, from the
    /// current v, to ‖G‖ ≤ [`MultiplierParams::inner_ratio`] · error · max(‖f‖, ‖M v‖).
    fn newton(&mut self, s: &Shared<'_>, deadline: Deadline) {
        let (p, params) = (s.p, s.params);
        if self.report.steps >= params.max_steps {
            self.done = Some(MultiplierStatus::MaxSteps);
            return;
        }
        self.report.steps += 1;
        // relative to the size of the balance's terms, max(‖f‖, ‖M v‖)
        let mv = crate::law::norm(&p.m.mul_vec(&self.v));
        self.target = params.inner_ratio * self.current_error * s.f_norm.max(mv);
        self.g.evaluate(s, &self.lambda, &self.rho, &self.v);
        self.v_start.copy_from_slice(&self.v);
        self.newton = 0;
        if let Some(lu) = self.lu.take() {
            self.jm = lu.into_matrix();
        }
        // steps taken with the factors of an earlier step of this Newton run
        let mut chords = 0;
        // consecutive steps that lowered ‖G‖ by less than the factor `slow_ratio`
        let mut slow = 0;
        while self.g.norm > self.target
            && self.newton < params.newton_steps
            && slow < params.slow_steps
            && !deadline.passed()
        {
            let before = self.g.norm;
            // a chord step: the factors of an earlier J, kept if ‖G‖ falls by `chord_ratio`
            if let Some(lu) = self.lu.as_ref().filter(|_| chords < params.newton_steps) {
                self.dv
                    .iter_mut()
                    .zip(&self.g.g)
                    .for_each(|(x, gi)| *x = -gi);
                if lu.solve_in_place(&mut self.dv) && self.dv.iter().all(|x| x.is_finite()) {
                    for ((vt, v), dv) in self.vt.iter_mut().zip(&self.v).zip(&self.dv) {
                        *vt = v + dv;
                    }
                    self.trial.evaluate(s, &self.lambda, &self.rho, &self.vt);
                    if self.trial.norm <= params.chord_ratio * before {
                        chords += 1;
                        slow = 0;
                        std::mem::swap(&mut self.v, &mut self.vt);
                        std::mem::swap(&mut self.g, &mut self.trial);
                        continue;
                    }
                }
            }
            self.newton += 1;
            // `g` is G at the current v (evaluated before the loop or as the accepted trial)
            let g = &mut self.g;
            g.blocks(p, &self.lambda, &self.rho, &mut self.blocks);
            // J is assembled in the storage of the previous step's factors
            let mut jm = match self.lu.take() {
                Some(lu) => lu.into_matrix(),
                None => std::mem::replace(&mut self.jm, faer::Mat::zeros(0, 0)),
            };
            if jm.nrows() != p.dofs() || jm.ncols() != p.dofs() {
                jm = faer::Mat::zeros(p.dofs(), p.dofs());
            }
            assemble(p, s, &self.blocks, &mut jm, &mut self.hb);
            let Some(lu) = crate::linalg::dense::Lu::new(jm, s.par) else {
                break;
            };
            self.dv.iter_mut().zip(&g.g).for_each(|(x, gi)| *x = -gi);
            let solved = lu.solve_in_place(&mut self.dv);
            if params.chord_ratio > 0.0 {
                self.lu = Some(lu);
            } else {
                self.jm = lu.into_matrix();
            }
            if !solved || self.dv.iter().any(|x| !x.is_finite()) {
                break;
            }
            // Armijo on ‖G‖²; a direction without sufficient decrease ends the run
            let (v, vt, dv, trial) = (&self.v, &mut self.vt, &self.dv, &mut self.trial);
            let (lambda, rho) = (&self.lambda, &self.rho);
            let search = armijo(
                g.norm * g.norm,
                params.sufficient_decrease,
                params.halvings,
                |t| {
                    for ((vt, v), dv) in vt.iter_mut().zip(v).zip(dv) {
                        *vt = v + t * dv;
                    }
                    trial.evaluate(s, lambda, rho, vt);
                    trial.norm * trial.norm
                },
            );
            if search == Search::Exhausted {
                break;
            }
            std::mem::swap(&mut self.v, &mut self.vt);
            std::mem::swap(g, &mut self.trial);
            if self.g.norm > params.slow_ratio * before {
                slow += 1;
            } else {
                slow = 0;
            }
        }
        self.report.newton_steps += self.newton + chords;
        self.report.chord_steps += chords;
    }

    /// The rest of the outer step after [`Run::newton`]: r_{k+1} = P_L(λ − ρ ũ) judged on
    /// the stored data, the lowest-merit iterate, the new λ and ρ, and the stopping tests.
    fn conclude(&mut self, s: &Shared<'_>, judge: &impl Fn(&[f64]) -> (f64, f64)) {
        let params = s.params;
        if self.done.is_some() {
            return;
        }
        if !self.g.norm.is_finite() {
            self.done = Some(MultiplierStatus::NumericalError);
            return;
        }
        let (e, b) = judge(&self.g.r);
        if !(e.is_finite() && b.is_finite()) {
            self.done = Some(MultiplierStatus::NumericalError);
            return;
        }
        let merit = e.max(b);
        if merit < self.best_merit {
            self.best_merit = merit;
            self.best_r.copy_from_slice(&self.g.r);
            (self.report.error, self.report.balance) = (e, b);
        }
        let solved = self.g.norm <= self.target;
        let acceptable = e <= params.reject_growth * self.current_error;
        if !solved && !acceptable {
            // Newton did not solve step k and r_{k+1} is worse: step k again from λ with
            // a smaller penalty (a better conditioned subproblem)
            self.v.copy_from_slice(&self.v_start);
            self.rho.iter_mut().for_each(|x| *x *= params.penalty_cut);
        } else {
            self.lambda.copy_from_slice(&self.g.r);
            self.current_error = e;
            if solved && self.newton <= params.easy_newton_steps {
                // an easy subproblem: a larger penalty, a faster proximal point
                let cap = params.penalty_cap * s.rho_i;
                self.rho
                    .iter_mut()
                    .for_each(|x| *x = (*x * params.penalty_growth).min(cap));
            } else if solved {
                // a ρᵢ cut below its first value regrows towards it; one above it stays
                let rho_i = s.rho_i;
                self.rho
                    .iter_mut()
                    .for_each(|x| *x = (*x * params.penalty_regrowth).min(rho_i.max(*x)));
            }
        }
        if e <= s.tol && b <= s.tol {
            self.done = Some(MultiplierStatus::Converged);
            return;
        }
        if self.best_merit <= params.stall_gain * self.stall_reference {
            self.stall_reference = self.best_merit;
            self.since_gain = 0;
        } else {
            self.since_gain += 1;
            if self.since_gain >= params.stall_steps {
                self.done = Some(MultiplierStatus::Stalled);
            }
        }
    }
}

/// G(v) = M v − f − H r, r = P_L(λ − ρ ũ(H_uᵀ v + w)), and ‖G‖.
struct Residual {
    g: Vec<f64>,
    r: Vec<f64>,
    u: Vec<f64>,
    norm: f64,
}

impl Residual {
    fn new(n: usize, m: usize) -> Self {
        Self {
            g: vec![0.0; n],
            r: vec![0.0; m],
            u: vec![0.0; m],
            norm: f64::INFINITY,
        }
    }

    /// Evaluates G, r and ‖G‖ at v (u = H_uᵀ v + w kept for [`Residual::blocks`]).
    fn evaluate(&mut self, s: &Shared<'_>, lambda: &[f64], rho: &[f64], v: &[f64]) {
        let p = s.p;
        let d = p.dim;
        self.u.copy_from_slice(&p.w);
        s.hu_cols.gemv_t_acc(v, &mut self.u);
        for i in 0..p.contacts() {
            let ui = &self.u[i * d..(i + 1) * d];
            let ri = &mut self.r[i * d..(i + 1) * d];
            prox_argument(p.mu[i], ui, &lambda[i * d..(i + 1) * d], rho[i], ri);
            crate::cone::project(p.mu[i], ri);
        }
        self.g.iter_mut().for_each(|x| *x = 0.0);
        p.m.gemv_acc(1.0, v, &mut self.g);
        for (gi, fi) in self.g.iter_mut().zip(&p.f) {
            *gi -= fi;
        }
        s.h_cols.gemv_sub(&self.r, &mut self.g);
        self.norm = crate::law::norm(&self.g);
    }

    /// Bᵢ = ρᵢ ∂P(yᵢ) (I + μ e t̂ᵀ) (row-major d × d) at the u of the last
    /// [`Residual::evaluate`], yᵢ = λᵢ − ρᵢ ũᵢ.
    fn blocks(&self, p: &GlobalProblem, lambda: &[f64], rho: &[f64], blocks: &mut [f64]) {
        let d = p.dim;
        let mut jac = [0.0; 9];
        let mut y = [0.0; 3];
        let mut proj = [0.0; 3];
        for i in 0..p.contacts() {
            let mu = p.mu[i];
            let ui = &self.u[i * d..(i + 1) * d];
            let t = crate::cone::tangent_norm(ui);
            prox_argument(mu, ui, &lambda[i * d..(i + 1) * d], rho[i], &mut y[..d]);
            crate::natural_map::projection_jacobian(mu, &y[..d], &mut proj[..d], &mut jac[..d * d]);
            // Bᵢ = ρ ∂P (I + μ e t̂ᵀ): column z of the product adds μ t̂_z ∂P[:, 0]
            let bi = &mut blocks[i * d * d..(i + 1) * d * d];
            for x in 0..d {
                for z in 0..d {
                    let mut s = jac[x * d + z];
                    if z > 0 && t > 0.0 && mu > 0.0 && mu.is_finite() {
                        s += jac[x * d] * mu * ui[z] / t;
                    }
                    bi[x * d + z] = rho[i] * s;
                }
            }
        }
    }
}

/// y = λ − ρ ũ(u) of one contact, ũ = u + μ‖u_T‖ e (3.7) (ũ = u where μ is 0 or infinite).
#[inline]
fn prox_argument(mu: f64, u: &[f64], lambda: &[f64], rho: f64, y: &mut [f64]) {
    let t = crate::cone::tangent_norm(u);
    for k in 0..u.len() {
        let ut = if k == 0 && mu > 0.0 && mu.is_finite() {
            u[0] + mu * t
        } else {
            u[k]
        };
        y[k] = lambda[k] - rho * ut;
    }
}

/// The d columns of a matrix (H or H_u) that belong to each contact, as one dense block per
/// contact: the union of their rows and the values on those rows (row-major, d per row).
struct ContactColumns {
    dim: usize,
    /// contact i's rows are `rows[ptr[i]..ptr[i + 1]]`
    ptr: Vec<usize>,
    rows: Vec<usize>,
    vals: Vec<f64>,
}

impl ContactColumns {
    fn new(a: &CscMatrix, dim: usize, contacts: usize) -> Self {
        let mut ptr = Vec::with_capacity(contacts + 1);
        let mut rows = Vec::new();
        let mut vals = Vec::new();
        ptr.push(0);
        for i in 0..contacts {
            let first = rows.len();
            let cols = (i * dim)..((i + 1) * dim).min(a.ncols);
            let mut mine: Vec<usize> = cols
                .clone()
                .flat_map(|j| a.row_idx[a.col_ptr[j]..a.col_ptr[j + 1]].iter().copied())
                .collect();
            mine.sort_unstable();
            mine.dedup();
            rows.extend_from_slice(&mine);
            vals.resize(rows.len() * dim, 0.0);
            for j in cols {
                for e in a.col_ptr[j]..a.col_ptr[j + 1] {
                    if let Ok(k) = rows[first..].binary_search(&a.row_idx[e]) {
                        vals[(first + k) * dim + j - i * dim] += a.values[e];
                    }
                }
            }
            ptr.push(rows.len());
        }
        Self {
            dim,
            ptr,
            rows,
            vals,
        }
    }

    /// y ← y + Aᵀ x (y of length d · contacts).
    fn gemv_t_acc(&self, x: &[f64], y: &mut [f64]) {
        if self.dim == 2 {
            self.gemv_t_acc_d::<2>(x, y);
        } else {
            self.gemv_t_acc_d::<3>(x, y);
        }
    }

    fn gemv_t_acc_d<const D: usize>(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.chunks_exact_mut(D).enumerate() {
            let (rows, vals) = self.contact(i);
            let mut acc = [0.0; D];
            for (&row, a) in rows.iter().zip(vals.chunks_exact(D)) {
                let xr = x[row];
                for z in 0..D {
                    acc[z] += a[z] * xr;
                }
            }
            for z in 0..D {
                yi[z] += acc[z];
            }
        }
    }

    /// y ← y − A x (x of length d · contacts).
    fn gemv_sub(&self, x: &[f64], y: &mut [f64]) {
        if self.dim == 2 {
            self.gemv_sub_d::<2>(x, y);
        } else {
            self.gemv_sub_d::<3>(x, y);
        }
    }

    fn gemv_sub_d<const D: usize>(&self, x: &[f64], y: &mut [f64]) {
        for (i, xi) in x.chunks_exact(D).enumerate() {
            if xi.iter().all(|v| *v == 0.0) {
                continue;
            }
            let (rows, vals) = self.contact(i);
            for (&row, a) in rows.iter().zip(vals.chunks_exact(D)) {
                y[row] -= (0..D).map(|z| a[z] * xi[z]).sum::<f64>();
            }
        }
    }

    /// Contact i's rows and their values (row-major, `dim` per row).
    fn contact(&self, i: usize) -> (&[usize], &[f64]) {
        let range = self.ptr[i]..self.ptr[i + 1];
        let d = self.dim;
        (
            &self.rows[range.clone()],
            &self.vals[range.start * d..range.end * d],
        )
    }
}

/// J = M + Σᵢ Hᵢ Bᵢ H_{u,i}ᵀ (dense), Hᵢ and H_{u,i} the d columns of contact i
/// (gathered in `s`); `hb` is work space for Hᵢ Bᵢ.
fn assemble(
    p: &GlobalProblem,
    s: &Shared<'_>,
    blocks: &[f64],
    jm: &mut faer::Mat<f64>,
    hb: &mut Vec<f64>,
) {
    let d = p.dim;
    jm.fill(0.0);
    for j in 0..p.m.ncols {
        for e in p.m.col_ptr[j]..p.m.col_ptr[j + 1] {
            jm[(p.m.row_idx[e], j)] += p.m.values[e];
        }
    }
    for i in 0..p.contacts() {
        let b = &blocks[i * d * d..(i + 1) * d * d];
        if b.iter().all(|x| *x == 0.0) {
            continue;
        }
        let (h_rows, h_vals) = s.h_cols.contact(i);
        let (u_rows, u_vals) = s.hu_cols.contact(i);
        // d is 2 or 3 (checked by the problem's constructors)
        if d == 2 {
            add_contact::<2>(h_rows, h_vals, u_rows, u_vals, b, jm, hb);
        } else {
            add_contact::<3>(h_rows, h_vals, u_rows, u_vals, b, jm, hb);
        }
    }
}

/// J[rows of Hᵢ, rows of H_{u,i}] += Hᵢ Bᵢ H_{u,i}ᵀ for one contact of dimension D
/// ([`ContactColumns::contact`]'s layout); `hb` is work space for Hᵢ Bᵢ.
fn add_contact<const D: usize>(
    h_rows: &[usize],
    h_vals: &[f64],
    u_rows: &[usize],
    u_vals: &[f64],
    b: &[f64],
    jm: &mut faer::Mat<f64>,
    hb: &mut Vec<f64>,
) {
    hb.clear();
    for hr in h_vals.chunks_exact(D) {
        for z in 0..D {
            hb.push((0..D).map(|x| hr[x] * b[x * D + z]).sum());
        }
    }
    for (&col, ur) in u_rows.iter().zip(u_vals.chunks_exact(D)) {
        let column = jm.col_as_slice_mut(col);
        for (&row, hbr) in h_rows.iter().zip(hb.chunks_exact(D)) {
            column[row] += (0..D).map(|z| hbr[z] * ur[z]).sum::<f64>();
        }
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    /// A box (mass 1, half sizes a, b, c) on the plane z = 0 touching it at its four lower
    /// corners (12 contact unknowns, 6 degrees of freedom: W has rank ≤ 6), moving with
    /// `v0` (linear, angular) and pulled down by gravity over a step of 0.01 s; μ at every
    /// corner. FCLIB convention: M v = H r + f, u = Hᵀ v + w; column (i, k) of H is
    /// (t_k, p_i × t_k) for the contact frame t_0 = e_z (normal), t_1 = e_x, t_2 = e_y.
    fn box_on_plane(mu: f64, v0: [f64; 6]) -> GlobalProblem {
        let (a, b, c) = (0.5, 0.3, 0.2);
        let inertia = [
            (b * b + c * c) / 3.0,
            (a * a + c * c) / 3.0,
            (a * a + b * b) / 3.0,
        ];
        let mass_diag = [1.0, 1.0, 1.0, inertia[0], inertia[1], inertia[2]];
        let m = CscMatrix::from_dense(6, 6, &{
            let mut d = vec![0.0; 36];
            (0..6).for_each(|i| d[i * 7] = mass_diag[i]);
            d
        });
        let corners = [[a, b, -c], [-a, b, -c], [-a, -b, -c], [a, -b, -c]];
        let frame = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let mut h = vec![0.0; 6 * 12];
        for (i, p) in corners.iter().enumerate() {
            for (k, t) in frame.iter().enumerate() {
                let cross = [
                    p[1] * t[2] - p[2] * t[1],
                    p[2] * t[0] - p[0] * t[2],
                    p[0] * t[1] - p[1] * t[0],
                ];
                let col = 3 * i + k;
                for x in 0..3 {
                    h[x * 12 + col] = t[x];
                    h[(x + 3) * 12 + col] = cross[x];
                }
            }
        }
        let step = 0.01;
        let mut f: Vec<f64> = (0..6).map(|i| mass_diag[i] * v0[i]).collect();
        f[2] -= step * 9.81;
        GlobalProblem::new(
            3,
            m,
            CscMatrix::from_dense(6, 12, &h),
            f,
            vec![0.0; 12],
            vec![mu; 4],
        )
        .unwrap()
    }

    fn judged(p: &GlobalProblem, mass: &MassFactor, r: &[f64]) -> (f64, f64) {
        // v = M⁻¹(H r + f), u = Hᵀ v + w, the error of docs/error.md with ‖q‖ of the
        // Delassus vector, and the balance residual: independent of the method's own G
        let mut v = p.h.mul_vec(r);
        v.iter_mut().zip(&p.f).for_each(|(x, f)| *x += f);
        mass.solve_in_place(&mut v);
        let mut free = p.f.clone();
        mass.solve_in_place(&mut free);
        let q_norm = crate::law::norm(&p.velocity(&free));
        let (_, e) = crate::evaluation::global(p, &v, r, q_norm);
        (e.measure.error, e.balance_residual.unwrap())
    }

    fn w_mean(p: &GlobalProblem, mass: &MassFactor) -> f64 {
        let dense = p.h.to_dense();
        let (n, m) = (p.dofs(), p.w.len());
        (0..m)
            .map(|j| {
                let col: Vec<f64> = (0..n).map(|i| dense[i * m + j]).collect();
                let mut x = col.clone();
                mass.solve_in_place(&mut x);
                col.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>()
            })
            .sum::<f64>()
            / m as f64
    }

    /// [`solve`] from r = 0 to 1e-10, judged by [`judged`], with no deadline.
    fn from_zero(
        p: &GlobalProblem,
        mass: &MassFactor,
        wm: f64,
        params: &MultiplierParams,
    ) -> (Vec<f64>, MultiplierReport) {
        let mut r = vec![0.0; p.w.len()];
        let rep = solve(
            p,
            None,
            mass,
            wm,
            &mut r,
            1e-10,
            params,
            faer::Par::Seq,
            Deadline::NEVER,
            |r| judged(p, mass, r),
        );
        (r, rep)
    }

    pub fn the_method_of_multipliers_solves_a_sliding_box_on_four_corners() {
        // μ = 1 and 0.3, sliding, spinning and tilting: 12 impulses on 6 degrees of freedom,
        // from r = 0; the reported error is the one recomputed from the returned r
        let mut chords = 0;
        for (mu, v0) in [
            (1.0, [1.0, 0.3, -0.5, 0.2, -0.1, 0.7]),
            (0.3, [0.5, -0.2, -0.1, 0.0, 0.4, -1.0]),
            (1.0, [0.0, 0.0, -1.0, 0.0, 0.0, 0.0]),
        ] {
            let p = box_on_plane(mu, v0);
            let mass = MassFactor::new(&p.m).unwrap();
            let wm = w_mean(&p, &mass);
            let params = MultiplierParams::default();
            let (r, rep) = from_zero(&p, &mass, wm, &params);
            let (e, b) = judged(&p, &mass, &r);
            assert_eq!(rep.status, MultiplierStatus::Converged, "{rep:?}");
            assert!(e <= 1e-10 && b <= 1e-10, "{e:.2e} {b:.2e}");
            assert_eq!((rep.error, rep.balance), (e, b));
            for (c, mu) in r.chunks(3).zip(&p.mu) {
                let t = (c[1] * c[1] + c[2] * c[2]).sqrt();
                assert!(
                    t <= mu * c[0] * (1.0 + 1e-12) + 1e-300,
                    "{c:?} outside K_{mu}"
                );
            }
            // the box is pressed down: the normal impulses carry its weight and its fall
            let normal: f64 = r.chunks(3).map(|c| c[0]).sum();
            assert!(normal > 0.0);
            // a fixed penalty (no growth after easy steps) converges too, in no fewer steps
            let fixed = MultiplierParams {
                penalty_growth: 1.0,
                ..params
            };
            let (_, rep_fixed) = from_zero(&p, &mass, wm, &fixed);
            assert_eq!(rep_fixed.status, MultiplierStatus::Converged);
            assert!(rep.steps <= rep_fixed.steps, "{rep:?} {rep_fixed:?}");
            // every step with its own factors (no chord step) converges too
            let factored = MultiplierParams {
                chord_ratio: 0.0,
                ..params
            };
            let (r_f, rep_f) = from_zero(&p, &mass, wm, &factored);
            assert_eq!(rep_f.status, MultiplierStatus::Converged, "{rep_f:?}");
            assert_eq!(rep_f.chord_steps, 0);
            let (e, b) = judged(&p, &mass, &r_f);
            assert!(e <= 1e-10 && b <= 1e-10, "{e:.2e} {b:.2e}");
            assert!(rep.chord_steps <= rep.newton_steps);
            chords += rep.chord_steps;
        }
        // the default takes steps with earlier factors on these problems
        assert!(chords > 0);
    }

    pub fn a_finish_that_returns_a_point_ends_the_stage_and_is_tried_a_capped_number_of_times() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let p = box_on_plane(1.0, [1.0, 0.3, -0.5, 0.2, -0.1, 0.7]);
        let mass = MassFactor::new(&p.m).unwrap();
        let wm = w_mean(&p, &mass);
        let (solution, _) = from_zero(&p, &mass, wm, &MultiplierParams::default());
        // every new lowest merit is close enough for the finish
        let params = MultiplierParams {
            finish_crawl: 1e12,
            finish_gain: 1.0,
            finish_attempts: 2,
            ..MultiplierParams::default()
        };
        let run = |finish: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync)| {
            let mut starts = vec![vec![0.0; p.w.len()]];
            let rep = solve_from(
                &p,
                None,
                &mass,
                wm,
                &mut starts,
                1e-10,
                &params,
                faer::Par::Seq,
                Deadline::NEVER,
                |r| judged(&p, &mass, r),
                finish,
            );
            (starts.swap_remove(0), rep)
        };
        // a finish that returns the solution at its first call: the stage ends with it
        let calls = AtomicUsize::new(0);
        let (r, rep) = run(&|_| {
            calls.fetch_add(1, Ordering::Relaxed);
            Some(solution.clone())
        });
        assert_eq!(calls.load(Ordering::Relaxed), 1);
        assert_eq!(rep.status, MultiplierStatus::Converged);
        assert_eq!(r, solution);
        assert_eq!((rep.error, rep.balance), judged(&p, &mass, &solution));
        // a finish that never succeeds: called at most `finish_attempts` times, and the
        // stage converges by itself
        let calls = AtomicUsize::new(0);
        let (r, rep) = run(&|_| {
            calls.fetch_add(1, Ordering::Relaxed);
            None
        });
        let n = calls.load(Ordering::Relaxed);
        assert!((1..=2).contains(&n), "{n} calls");
        assert_eq!(rep.status, MultiplierStatus::Converged, "{rep:?}");
        let (e, b) = judged(&p, &mass, &r);
        assert!(e <= 1e-10 && b <= 1e-10);
    }

    pub fn several_starts_run_at_once_and_the_converged_run_is_returned() {
        let p = box_on_plane(1.0, [1.0, 0.3, -0.5, 0.2, -0.1, 0.7]);
        let mass = MassFactor::new(&p.m).unwrap();
        let wm = w_mean(&p, &mass);
        let params = MultiplierParams::default();
        let (r_alone, alone) = from_zero(&p, &mass, wm, &params);
        let solve_all = |starts: &mut [Vec<f64>]| {
            solve_from(
                &p,
                None,
                &mass,
                wm,
                starts,
                1e-10,
                &params,
                faer::Par::Seq,
                Deadline::NEVER,
                |r| judged(&p, &mass, r),
                |_| None,
            )
        };
        // a start that cannot run (not finite) beside one that converges: the converged
        // point is returned in starts[0], judged on the problem, with both runs' work summed
        let mut starts = vec![vec![f64::NAN; 12], vec![0.0; 12]];
        let rep = solve_all(&mut starts);
        assert_eq!(rep.status, MultiplierStatus::Converged, "{rep:?}");
        let (e, b) = judged(&p, &mass, &starts[0]);
        assert!(e <= 1e-10 && b <= 1e-10, "{e:.2e} {b:.2e}");
        assert_eq!((rep.error, rep.balance), (e, b));
        assert_eq!(
            (rep.steps, rep.newton_steps),
            (alone.steps, alone.newton_steps)
        );
        // two equal starts: each run takes the iterates it takes alone, so the point returned
        // is the one run alone returns; the other run stops once one has converged (its
        // steps so far are counted)
        let mut starts = vec![vec![0.0; 12], vec![0.0; 12]];
        let rep = solve_all(&mut starts);
        assert_eq!(rep.status, MultiplierStatus::Converged);
        assert_eq!(starts[0], r_alone);
        assert!(
            (alone.steps..=2 * alone.steps).contains(&rep.steps)
                && (alone.newton_steps..=2 * alone.newton_steps).contains(&rep.newton_steps),
            "{rep:?} {alone:?}"
        );
        // two different starts: the point returned is the one that one of them reaches alone
        let other: Vec<f64> = (0..12).map(|k| 0.5 + 0.1 * k as f64).collect();
        let mut r_other = other.clone();
        let rep_other = solve(
            &p,
            None,
            &mass,
            wm,
            &mut r_other,
            1e-10,
            &params,
            faer::Par::Seq,
            Deadline::NEVER,
            |r| judged(&p, &mass, r),
        );
        assert_eq!(rep_other.status, MultiplierStatus::Converged);
        for order in [
            [vec![0.0; 12], other.clone()],
            [other.clone(), vec![0.0; 12]],
        ] {
            let mut starts = order.to_vec();
            let rep = solve_all(&mut starts);
            assert_eq!(rep.status, MultiplierStatus::Converged);
            assert!(
                starts[0] == r_alone || starts[0] == r_other,
                "{:?}",
                starts[0]
            );
        }
        // no start: nothing run, a typed status
        let rep = solve_all(&mut []);
        assert_eq!(rep.status, MultiplierStatus::NumericalError);
        // only starts that cannot run: the status of the first
        let mut starts = vec![vec![f64::INFINITY; 12], vec![0.0; 5]];
        let rep = solve_all(&mut starts);
        assert_eq!(
            (rep.status, rep.steps),
            (MultiplierStatus::NumericalError, 0)
        );
    }

    /// A sparse n × (d · contacts) matrix with duplicate entries, an empty column and a
    /// contact whose columns have different rows (values from a fixed recurrence).
    fn scattered(n: usize, d: usize, contacts: usize) -> CscMatrix {
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        let mut x = 0.37_f64;
        for j in 0..d * contacts {
            if j == 1 {
                continue;
            }
            for k in 0..3 {
                x = (x * 7.3 + 0.11).fract();
                rows.push((j * 5 + k * 3 + (x * 4.0) as usize) % n);
                cols.push(j);
                vals.push(x - 0.5);
            }
        }
        rows.push(0);
        cols.push(d * contacts - 1);
        vals.push(0.25);
        CscMatrix::from_triplets(n, d * contacts, &rows, &cols, &vals).unwrap()
    }

    pub fn gathered_columns_give_the_products_of_the_sparse_matrix() {
        for d in [2, 3] {
            let (n, contacts) = (7, 5);
            let a = scattered(n, d, contacts);
            let cols = ContactColumns::new(&a, d, contacts);
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
            let mut want = vec![0.5; d * contacts];
            a.gemv_t_acc(1.0, &x, &mut want);
            let mut got = vec![0.5; d * contacts];
            cols.gemv_t_acc(&x, &mut got);
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() <= 1e-14, "d = {d}: Aᵀx {g} against {w}");
            }
            let mut r: Vec<f64> = (0..d * contacts).map(|i| (i as f64 * 1.3).cos()).collect();
            r[..d].iter_mut().for_each(|x| *x = 0.0);
            let mut want = vec![1.0; n];
            a.gemv_acc(-1.0, &r, &mut want);
            let mut got = vec![1.0; n];
            cols.gemv_sub(&r, &mut got);
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() <= 1e-14, "d = {d}: y − Ax {g} against {w}");
            }
        }
    }

    pub fn the_assembled_jacobian_is_m_plus_h_b_hu_transposed() {
        let p = box_on_plane(0.5, [0.0; 6]);
        let (n, m, d) = (p.dofs(), p.w.len(), p.dim);
        let hu = scattered(n, d, p.contacts());
        let params = MultiplierParams::default();
        let s = Shared {
            p: &p,
            h_cols: ContactColumns::new(&p.h, d, p.contacts()),
            hu_cols: ContactColumns::new(&hu, d, p.contacts()),
            params: &params,
            rho_i: 1.0,
            f_norm: 1.0,
            tol: 1e-8,
            par: faer::Par::Seq,
        };
        // contact 2 separated (Bᵢ = 0), the others full blocks
        let mut blocks: Vec<f64> = (0..p.contacts() * d * d)
            .map(|i| (i as f64 * 0.9).sin())
            .collect();
        blocks[2 * d * d..3 * d * d]
            .iter_mut()
            .for_each(|x| *x = 0.0);
        let mut jm = faer::Mat::zeros(n, n);
        assemble(&p, &s, &blocks, &mut jm, &mut Vec::new());
        // the same product densely: M + H B Huᵀ (row-major copies)
        let (md, hd, ud) = (p.m.to_dense(), p.h.to_dense(), hu.to_dense());
        for a in 0..n {
            for b in 0..n {
                let mut want = md[a * n + b];
                for i in 0..p.contacts() {
                    for x in 0..d {
                        for z in 0..d {
                            let bxz = blocks[i * d * d + x * d + z];
                            want += hd[a * m + i * d + x] * bxz * ud[b * m + i * d + z];
                        }
                    }
                }
                assert!(
                    (jm[(a, b)] - want).abs() <= 1e-13,
                    "J[{a}, {b}] = {} against {want}",
                    jm[(a, b)]
                );
            }
        }
    }

    /// An outer step whose Newton run missed its target: the run's current error before and
    /// after it, whether λ moved, ρ before and after.
    struct Unsolved {
        before: f64,
        after: f64,
        moved: bool,
        rho: Vec<f64>,
        rho_after: Vec<f64>,
    }

    /// The outer steps of one run from r = 0 with `params` whose Newton run missed its target.
    fn unsolved_steps(
        p: &GlobalProblem,
        mass: &MassFactor,
        params: &MultiplierParams,
    ) -> Vec<Unsolved> {
        let wm = w_mean(p, mass);
        let shared = Shared {
            p,
            h_cols: ContactColumns::new(&p.h, p.dim, p.contacts()),
            hu_cols: ContactColumns::new(&p.h, p.dim, p.contacts()),
            params,
            rho_i: params.rho_factor / wm,
            f_norm: crate::law::norm(&p.f),
            tol: 1e-14,
            par: faer::Par::Seq,
        };
        let r = vec![0.0; p.w.len()];
        let (error, balance) = judged(p, mass, &r);
        let start = MultiplierReport {
            status: MultiplierStatus::NumericalError,
            steps: 0,
            newton_steps: 0,
            chord_steps: 0,
            error,
            balance,
        };
        let mut run = Run::new(&shared, mass, &r, start);
        let judge = |r: &[f64]| judged(p, mass, r);
        let mut unsolved = Vec::new();
        while run.done.is_none() {
            let (lambda, rho, before) = (run.lambda.clone(), run.rho.clone(), run.current_error);
            run.newton(&shared, Deadline::NEVER);
            let solved = run.g.norm <= run.target;
            run.conclude(&shared, &judge);
            if !solved && run.done.is_none() {
                unsolved.push(Unsolved {
                    before,
                    after: run.current_error,
                    moved: run.lambda != lambda,
                    rho,
                    rho_after: run.rho.clone(),
                });
            }
        }
        unsolved
    }

    pub fn an_unsolved_step_is_kept_only_when_it_lowers_the_error() {
        // one Newton step per outer step (no chord step) leaves many subproblems unsolved;
        // with reject_growth = 1 (the default) such a step moves the multipliers only when
        // its r has a lower error, else λ stays and every ρᵢ is cut
        let p = box_on_plane(1.0, [1.0, 0.3, -0.5, 0.2, -0.1, 0.7]);
        let mass = MassFactor::new(&p.m).unwrap();
        let params = MultiplierParams {
            max_steps: 60,
            newton_steps: 1,
            chord_ratio: 0.0,
            ..MultiplierParams::default()
        };
        assert_eq!(params.reject_growth, 1.0);
        let steps = unsolved_steps(&p, &mass, &params);
        let (mut kept, mut cut) = (0, 0);
        for step in &steps {
            if step.moved {
                assert!(
                    step.after <= step.before,
                    "{:.3e} > {:.3e}",
                    step.after,
                    step.before
                );
                kept += 1;
            } else {
                assert_eq!(step.after, step.before);
                for (a, b) in step.rho.iter().zip(&step.rho_after) {
                    assert_eq!(*b, a * params.penalty_cut);
                }
                cut += 1;
            }
        }
        assert!(kept > 0 && cut > 0, "kept {kept}, cut {cut}");
        // with 10, unsolved steps that raise the error up to tenfold are kept
        let loose = MultiplierParams {
            reject_growth: 10.0,
            ..params
        };
        let rising = unsolved_steps(&p, &mass, &loose)
            .iter()
            .filter(|step| step.moved && step.after > step.before)
            .count();
        assert!(rising > 0);
    }

    pub fn bad_input_and_caps_give_typed_statuses() {
        let p = box_on_plane(1.0, [1.0, 0.3, -0.5, 0.2, -0.1, 0.7]);
        let mass = MassFactor::new(&p.m).unwrap();
        let wm = w_mean(&p, &mass);
        let params = MultiplierParams::default();
        // `solve` on p with w̄ = `wm` (0: no positive diagonal), tol, params and deadline
        let run = |r: &mut [f64], wm: f64, tol: f64, params: &MultiplierParams, deadline| {
            let judge = |r: &[f64]| judged(&p, &mass, r);
            solve(
                &p,
                None,
                &mass,
                wm,
                r,
                tol,
                params,
                faer::Par::Seq,
                deadline,
                judge,
            )
        };
        // a non-finite start
        let mut r = vec![f64::NAN; 12];
        let rep = run(&mut r, wm, 1e-10, &params, Deadline::NEVER);
        assert_eq!(rep.status, MultiplierStatus::NumericalError);
        // a past deadline: nothing run, r kept
        let mut r = vec![0.0; 12];
        let past = Deadline::after(std::time::Instant::now(), Some(std::time::Duration::ZERO));
        let rep = run(&mut r, wm, 1e-10, &params, past);
        assert_eq!((rep.status, rep.steps), (MultiplierStatus::TimeLimit, 0));
        assert!(r.iter().all(|&x| x == 0.0));
        // one outer step only: the cap, and the lowest-merit point returned
        let one = MultiplierParams {
            max_steps: 1,
            ..params
        };
        let mut r = vec![0.0; 12];
        let start = judged(&p, &mass, &r);
        let rep = run(&mut r, wm, 1e-14, &one, Deadline::NEVER);
        assert_eq!((rep.status, rep.steps), (MultiplierStatus::MaxSteps, 1));
        let (e, b) = judged(&p, &mass, &r);
        assert_eq!((rep.error, rep.balance), (e, b));
        assert!(e.max(b) <= start.0.max(start.1));
        // every Newton step counted slow (slow_ratio ~ 0) and one allowed: each outer step's
        // Newton run stops after one step, where the default takes several
        let crawl = MultiplierParams {
            max_steps: 20,
            slow_steps: 1,
            slow_ratio: 1e-300,
            ..params
        };
        let mut r = vec![0.0; 12];
        let rep = run(&mut r, wm, 1e-14, &crawl, Deadline::NEVER);
        assert!(rep.steps >= 1 && rep.newton_steps <= rep.steps, "{rep:?}");
        let (e, b) = judged(&p, &mass, &r);
        assert_eq!((rep.error, rep.balance), (e, b));
        let mut r = vec![0.0; 12];
        let full = run(
            &mut r,
            wm,
            1e-14,
            &MultiplierParams {
                max_steps: 20,
                ..params
            },
            Deadline::NEVER,
        );
        assert!(full.newton_steps > full.steps, "{full:?}");
        // more degrees of freedom than the dense Newton systems take: nothing run
        let n = MAX_DENSE_DOFS + 1;
        let big = GlobalProblem::new(
            3,
            CscMatrix::identity(n, 1.0),
            CscMatrix::zeros(n, 3),
            vec![1.0; n],
            vec![-1.0, 0.0, 0.0],
            vec![0.5],
        )
        .unwrap();
        let big_mass = MassFactor::new(&big.m).unwrap();
        let mut r = vec![0.0; 3];
        let rep = solve(
            &big,
            None,
            &big_mass,
            1.0,
            &mut r,
            1e-10,
            &params,
            faer::Par::Seq,
            Deadline::NEVER,
            |r| {
                let u = big.w.iter().zip(r).map(|(w, _)| *w).collect::<Vec<_>>();
                (crate::law::error_measure(3, &big.mu, r, &u, 1.0).error, 0.0)
            },
        );
        assert_eq!((rep.status, rep.steps), (MultiplierStatus::TooLarge, 0));
        // a W of no positive diagonal gives ρ = 1, still a typed outcome
        let mut r = vec![0.0; 12];
        let rep = run(&mut r, 0.0, 1e-10, &params, Deadline::NEVER);
        assert!(rep.error.is_finite());
    }
}
