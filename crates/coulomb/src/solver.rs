//! The public entry point: `solve(&problem, &settings)` runs the outer fixed-point iteration
//! s ← F(s) of §3.3 around an inner solver of (3.15)/(4.7), and reports the error of
//! `docs/error.md` recomputed from the returned r (and v).
//!
//! # The problem solved is the problem stored
//! W (local) or M (global) need not be symmetric: real files carry assembly round-off
//! (relative asymmetry 1e-16 … 1.3e-3), and the problem is the one stored. When W is not
//! symmetric the inner problem of §3.3 is no longer the QP (4.7) but the variational
//! inequality: find r ∈ L with ⟨W r + q + E s, r′ − r⟩ ≥ 0 for all r′ ∈ L, strongly
//! monotone when ½(W + Wᵀ) is positive definite. The QP inner solvers (APGD, projected
//! Gauss–Seidel, interior point, faceted) see only the quadratic form, i.e. the surrogate
//! ½(W + Wᵀ); they are a stage. What finishes on the stored W: the error measure and every
//! status (always on the stored data), F(s) (3.19) (from u = W r + q), the fused
//! Gauss–Seidel on Coulomb's law (each contact's law solved with its own stored diagonal
//! block, u maintained through the stored columns), and the semismooth Newton end game
//! ([`crate::newton`], J = I − D + D A W with W as stored). With the default settings
//! every run on a non-symmetric W ends with the error of the stored problem; the Newton end
//! game or the fused fallback brings it below tol.

use crate::delassus::Delassus;
use crate::fixed_point::{self, OuterUpdate};
use crate::inner::{
    apgd::ApgdSolver, faceted::FacetedSolver, ipm, ipm::IpmSolver, pgs, pgs::PgsSolver,
    InnerLimits, InnerProblem, InnerReport, InnerSolver, InnerStatus,
};
use crate::law;
use crate::newton;
use crate::problem::{GlobalProblem, LocalProblem, Problem, ProblemError};
use serde::Serialize;
use std::time::{Duration, Instant};

/// Which method computes F(s) (§6, options (i), (iv), (v)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InnerKind {
    /// Clarabel interior point on the SOC-QP (primal (3.15) for global problems, dual (4.7) for local).
    Ipm,
    /// accelerated projected gradient (FISTA with adaptive restart) on (4.7)
    Apgd,
    /// projected block Gauss–Seidel on (4.7), exact one-contact solves
    Pgs,
    /// faceted cone: each K_μ replaced by a k-facet pyramid, QP solved by Clarabel
    Faceted,
}

/// How the fixed point s = F(s) is sought.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OuterKind {
    /// successive approximation s ← F(s)
    FixedPoint,
    /// safeguarded Anderson mixing on s
    Anderson,
    /// no separate outer loop: Gauss–Seidel directly on Coulomb's law, contact i given a
    /// solution of its own law (2.9) with the others frozen (needs `InnerKind::Pgs`).
    /// Convergence is decided by the error measure like every other choice.
    Fused,
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// the error of docs/error.md (and, for global problems, the balance residual) is ≤ tol
    Converged,
    /// the outer iteration cap was reached with the error above tol
    MaxIterations,
    /// the time limit was reached with the error above tol
    TimeLimit,
    /// the error stopped decreasing in a first stage that has a fallback (see
    /// [`Settings::fallback`]); the fallback then runs
    Stalled,
    /// an inner solve failed (iteration cap, numerical breakdown)
    InnerFailure,
    /// an inner problem (3.15) was infeasible: C̄(s) = ∅
    InnerInfeasible,
    /// the iterates became non-finite
    NumericalError,
    /// the paper's rule (6.1) held (`Settings::fixed_point_tol`) but the error is above tol
    FixedPointRule,
    /// the error is ≤ tol only because r is unbounded: ‖W‖ ‖r‖ > [`UNBOUNDED_RATIO`] ·
    /// max(‖q‖, ‖u‖), so the scale max(‖q‖, ‖r‖, ‖u‖) of the relative error is ‖r‖ while u
    /// still violates the law (e.g. penetrates). The iterates diverge, the mark of a problem
    /// without a solution (Painlevé's paradox, §5.3); never reported as converged
    Unbounded,
    /// the error is ≤ tol but the balance residual of the global problem stays above tol
    /// (v = M⁻¹(H r + f) from the Cholesky factor of one triangle of M does not balance the
    /// whole M: M ill-conditioned or not quite symmetric, as in some FEM files)
    BalanceResidual,
}

/// Typed settings with defaults suited to rigid-body problems: a warm-up of at most 50
/// Gauss–Seidel sweeps on Coulomb's law, then APGD inside Anderson-mixed fixed-point
/// iterations, a semismooth Newton end game on the whole law once the error is
/// ≤ [`Settings::newton_start`] (1e-3), and fused Gauss–Seidel as fallback when the first
/// stage stalls.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Settings {
    /// tolerance on the reported error (docs/error.md); also on the balance residual
    pub tol: f64,
    /// inner solver
    pub inner: InnerKind,
    /// outer iteration
    pub outer: OuterKind,
    /// a second (inner, outer) method, warm-started from the first one's r, run when the first
    /// stops without converging (iteration cap, inner failure, or stalled: the error no longer
    /// halves over [`STALL_WINDOW`] outer iterations); the time limit covers both
    pub fallback: Option<(InnerKind, OuterKind)>,
    /// quick first try: at most this many Gauss–Seidel sweeps on Coulomb's law itself
    /// before the main method (0: none); small problems are solved there, and otherwise the
    /// main method starts from the caller's point as if the try had not happened
    pub warmup_sweeps: usize,
    /// cap on outer iterations (subproblems)
    pub max_outer: usize,
    /// cap on iterations of each inner solve
    pub max_inner: usize,
    /// wall-clock limit for the whole solve
    pub time_limit: Option<Duration>,
    /// ε of the paper's stopping rule (6.1) ‖F(s) − s‖ / (n (‖s‖ + 1)) ≤ ε, used as an
    /// additional internal stopping test when set (the reported status still requires err ≤ tol)
    pub fixed_point_tol: Option<f64>,
    /// number of facets of the pyramid replacing each K_μ (faceted inner solver, d = 3)
    pub facets: usize,
    /// the inner tolerance is `inner_tol_factor` × (error of the previous outer iterate),
    /// kept between `tol`/5 and 1e-2
    pub inner_tol_factor: f64,
    /// end game: once the error is ≤ [`Settings::newton_start`], semismooth Newton steps on
    /// the natural map of the whole law ([`crate::newton::polish`]) are tried after an outer
    /// iteration and kept if they lower the error; this many steps at most per stage (see
    /// [`solve_with_guess`]); 0 turns it off
    pub newton_steps: usize,
    /// error below which the Newton end game is tried
    pub newton_start: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            tol: 1e-8,
            inner: InnerKind::Apgd,
            outer: OuterKind::Anderson,
            fallback: Some((InnerKind::Pgs, OuterKind::Fused)),
            warmup_sweeps: 50,
            max_outer: 200,
            max_inner: 10_000,
            time_limit: Some(Duration::from_secs(60)),
            fixed_point_tol: None,
            facets: 8,
            inner_tol_factor: 0.1,
            newton_steps: 30,
            newton_start: 1e-3,
        }
    }
}

/// One outer iteration of the history.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OuterRecord {
    /// the error of docs/error.md after this iteration
    pub error: f64,
    /// ‖F(s) − s‖
    pub fixed_point_residual: f64,
    /// the paper's (6.1) measure ‖F(s) − s‖ / (n (‖s‖ + 1))
    pub rule_6_1: f64,
    /// inner iterations spent in this outer iteration
    pub inner_iterations: usize,
}

/// A starting point: impulses r, and velocities v for global problems.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Guess {
    /// impulses r (length d · contacts)
    pub r: Vec<f64>,
    /// velocities v (global problems; ignored for local ones)
    pub v: Option<Vec<f64>>,
}

/// The result of [`solve`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Solution {
    /// impulses r
    pub r: Vec<f64>,
    /// relative velocities u, recomputed from the problem data (W r + q or Hᵀ v + w)
    pub u: Vec<f64>,
    /// velocities v (global problems)
    pub v: Option<Vec<f64>>,
    /// the final fixed-point variable s (one entry per contact)
    pub s: Vec<f64>,
    /// how the solve ended
    pub status: Status,
    /// the error of docs/error.md, recomputed from r (and v)
    pub error: f64,
    /// ‖M v − H r − f‖ / max(1, ‖f‖) for global problems
    pub balance_residual: Option<f64>,
    /// outer iterations (subproblems solved)
    pub outer_iterations: usize,
    /// inner iterations, summed
    pub inner_iterations: usize,
    /// per outer iteration
    pub history: Vec<OuterRecord>,
    /// wall-clock time of the solve (excluding file reading)
    pub solve_time: Duration,
}

impl Solution {
    /// Whether the status is [`Status::Converged`].
    pub fn converged(&self) -> bool {
        self.status == Status::Converged
    }
}

/// Why a solve could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// the problem data are invalid
    #[error(transparent)]
    Problem(#[from] ProblemError),
    /// the settings are invalid
    #[error("invalid settings: {0}")]
    Settings(String),
    /// the guess has the wrong size
    #[error("invalid guess: {0}")]
    Guess(String),
}

impl Settings {
    /// The default settings with (`inner`, `outer`) as the only method: no warm-up try and
    /// no fallback, so that the result describes that method.
    pub fn method(inner: InnerKind, outer: OuterKind) -> Self {
        Self {
            inner,
            outer,
            fallback: None,
            warmup_sweeps: 0,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<(), SolveError> {
        let bad = |m: &str| Err(SolveError::Settings(m.to_string()));
        if self.tol.is_nan() || self.tol <= 0.0 || self.tol.is_infinite() {
            return bad("tol must be positive and finite");
        }
        if self.max_outer == 0 || self.max_inner == 0 {
            return bad("max_outer and max_inner must be at least 1");
        }
        if self.inner_tol_factor.is_nan()
            || self.inner_tol_factor <= 0.0
            || self.inner_tol_factor > 1.0
        {
            return bad("inner_tol_factor must be in (0, 1]");
        }
        if self.fixed_point_tol.is_some_and(|e| e.is_nan() || e <= 0.0) {
            return bad("fixed_point_tol must be positive");
        }
        if self.newton_start.is_nan() || self.newton_start < 0.0 {
            return bad("newton_start must be nonnegative");
        }
        if self.facets < 3 {
            return bad("facets must be at least 3");
        }
        if self.outer == OuterKind::Fused && self.inner != InnerKind::Pgs {
            return bad("the fused outer iteration needs the pgs inner solver");
        }
        if let Some((inner, outer)) = self.fallback {
            if outer == OuterKind::Fused && inner != InnerKind::Pgs {
                return bad("the fused outer iteration needs the pgs inner solver (fallback)");
            }
        }
        Ok(())
    }
}

/// Solves the incremental problem (2.10) from a cold start.
pub fn solve(problem: &Problem, settings: &Settings) -> Result<Solution, SolveError> {
    solve_with_guess(problem, settings, None)
}

/// The problem as stored, in the local form the solver works on.
enum Stored<'a> {
    Local(&'a LocalProblem),
    Global(&'a GlobalProblem, Box<Delassus>),
}

/// The stored problem, and the surrogate matrix of the SOC-QP inner solvers.
///
/// A quadratic form has no antisymmetric part: the inner problems (3.15)/(4.7) solved as
/// QPs (APGD, projected Gauss–Seidel, interior point, faceted) see ½(W + Wᵀ) when the
/// stored W is not exactly symmetric. Everything else — u = W r + q, F(s) (3.19), the error
/// of docs/error.md, the fused Gauss–Seidel on Coulomb's law and the Newton end game — uses
/// the stored W.
struct Form<'a> {
    stored: Stored<'a>,
    /// ½(W + Wᵀ), formed at the first use of a QP inner solver when W is not exactly
    /// symmetric (a fused Gauss–Seidel or Newton run never needs it)
    surrogate: std::cell::OnceCell<crate::sparse::CscMatrix>,
    /// whether W is exactly symmetric
    symmetric: bool,
    /// ‖W‖ estimated by the largest trace of a diagonal block
    w_scale: f64,
}

impl<'a> Form<'a> {
    fn new(stored: Stored<'a>) -> Self {
        let mut form = Self {
            stored,
            surrogate: std::cell::OnceCell::new(),
            symmetric: true,
            w_scale: 0.0,
        };
        form.w_scale = crate::inner::w_scale(form.local().dim, &form.local().w);
        form.symmetric = form.local().w.is_exactly_symmetric();
        form
    }

    fn local(&self) -> &LocalProblem {
        match &self.stored {
            Stored::Local(p) => p,
            Stored::Global(_, d) => &d.local,
        }
    }

    /// Whether ‖W‖ ‖r‖ > [`UNBOUNDED_RATIO`] · max(‖q‖, ‖u‖) (‖W‖ estimated by the largest
    /// trace of a diagonal block).
    fn unbounded(&self, r: &[f64], u: &[f64], q_norm: f64) -> bool {
        let data = q_norm.max(law::norm(u)).max(f64::MIN_POSITIVE);
        self.w_scale * law::norm(r) > UNBOUNDED_RATIO * data
    }

    /// The matrix of the SOC-QP inner problems: W, or ½(W + Wᵀ) when W is not symmetric.
    fn qp_w(&self) -> &crate::sparse::CscMatrix {
        if self.symmetric {
            &self.local().w
        } else {
            self.surrogate
                .get_or_init(|| self.local().w.symmetric_part())
        }
    }
}

/// The checked outcome for impulses r: (u, v, error, balance residual, divergence).
struct Verdict {
    u: Vec<f64>,
    v: Option<Vec<f64>>,
    error: f64,
    balance: Option<f64>,
    /// ‖W‖ ‖r‖ > [`UNBOUNDED_RATIO`] · max(‖q‖, ‖u‖)
    unbounded: bool,
}

/// Impulses with ‖W‖ ‖r‖ above this multiple of max(‖q‖, ‖u‖) count as unbounded
/// ([`Status::Unbounded`]): for a bounded solution W r = u − q is of the order of the data;
/// divergent iterates (a singular diagonal block regularized by 1e-8, Painlevé without a
/// solution) reach 1e7 and more.
pub const UNBOUNDED_RATIO: f64 = 1e6;

impl Verdict {
    /// Recomputes u (and v) from r and evaluates the error of docs/error.md: u = W r + q for a
    /// local problem; v = M⁻¹(H r + f), u = Hᵀ v + w and the balance residual for a global one.
    fn of(form: &Form<'_>, r: &[f64]) -> Self {
        let local = form.local();
        let q_norm = law::norm(&local.q);
        match &form.stored {
            Stored::Local(p) => {
                let u = p.velocity(r);
                let error = law::error_measure(p.dim, &p.mu, r, &u, q_norm).error;
                let unbounded = form.unbounded(r, &u, q_norm);
                Verdict {
                    u,
                    v: None,
                    error,
                    balance: None,
                    unbounded,
                }
            }
            Stored::Global(g, d) => {
                // v = M⁻¹(H r + f); the Cholesky factor reads one triangle of M, so for an M
                // that is only nearly symmetric the balance residual (computed with the whole
                // M) can stay above tol: Status::BalanceResidual
                let v = d.velocity(&g.h, r);
                let u = g.velocity(&v);
                let error = law::error_measure(g.dim, &g.mu, r, &u, q_norm).error;
                let balance = g.balance_residual(&v, r);
                let unbounded = form.unbounded(r, &u, q_norm);
                Verdict {
                    u,
                    v: Some(v),
                    error,
                    balance: Some(balance),
                    unbounded,
                }
            }
        }
    }

    fn converged(&self, tol: f64) -> bool {
        self.error <= tol && self.balance.is_none_or(|b| b <= tol) && !self.unbounded
    }

    /// The error is ≤ tol only because r diverges.
    fn spurious(&self, tol: f64) -> bool {
        self.unbounded && self.error <= tol
    }
}

fn inner_solver(settings: &Settings) -> Box<dyn InnerSolver> {
    match settings.inner {
        InnerKind::Pgs => Box::new(PgsSolver::new()),
        InnerKind::Apgd => Box::new(ApgdSolver::new()),
        InnerKind::Ipm => Box::new(IpmSolver::new()),
        InnerKind::Faceted => Box::new(FacetedSolver::new(settings.facets)),
    }
}

/// Solves the incremental problem (2.10), warm-started from `guess` when given.
///
/// The outer loop (§3.3): with b = q + E s, solve the inner problem (4.7) for r(s) (warm
/// started from the previous r, tolerance tied to the current error), evaluate
/// ũ = W r + b and F(s)ⁱ = ‖ũ_Tⁱ‖ (3.19), compute the error of docs/error.md from r, and stop
/// when it is ≤ tol; otherwise s ← F(s) (or Anderson mixing). With all μ = 0 the inner
/// problem is the whole problem (§5.1) and s plays no role. With [`OuterKind::Fused`] each
/// "outer iteration" is one batch of Gauss–Seidel sweeps on Coulomb's law.
///
/// End game ([`Settings::newton_steps`]): once the error is ≤ [`Settings::newton_start`],
/// semismooth Newton steps on the natural map of (3.9) for all contacts ([`crate::newton`])
/// are tried from r; they are kept if they lower the error (one extra history record, s then
/// restarts from F at the new r). A failed try is repeated only after the error has dropped
/// below [`NEWTON_RETRY`] times its starting value, when an inner solve hits its iteration
/// cap, or when the fixed point stagnates ([`STAGNATION`] iterations without a new lowest
/// error); a try takes at most [`NEWTON_TRY_STEPS`] steps and all tries of a stage at most
/// [`Settings::newton_steps`], so that the iteration is deterministic.
pub fn solve_with_guess(
    problem: &Problem,
    settings: &Settings,
    guess: Option<&Guess>,
) -> Result<Solution, SolveError> {
    settings.validate()?;
    let start = Instant::now();
    let deadline = crate::deadline::deadline(start, settings.time_limit);
    let form = Form::new(match problem {
        Problem::Local(p) => Stored::Local(p),
        Problem::Global(g) => Stored::Global(g, Box::new(Delassus::new(g)?)),
    });
    let mut stages: Vec<Solution> = Vec::new();
    if settings.warmup_sweeps > 0 {
        let warm_settings = Settings {
            inner: InnerKind::Pgs,
            outer: OuterKind::Fused,
            fallback: None,
            max_outer: 1,
            max_inner: settings.warmup_sweeps,
            newton_steps: 0,
            ..settings.clone()
        };
        let warm = solve_stage(&form, &warm_settings, guess, start, deadline, false, true)?;
        if warm.converged() || deadline.is_some_and(|t| Instant::now() >= t) {
            return Ok(merge(Vec::new(), warm, start));
        }
        stages.push(warm);
    }
    // the main method starts from the caller's point, not from the warm-up's r: on hard
    // problems Gauss–Seidel's r leads the fixed point of the main method astray
    let Some((inner, outer)) = settings.fallback else {
        let main = solve_stage(&form, settings, guess, start, deadline, false, false)?;
        return Ok(merge(stages, main, start));
    };
    let first = solve_stage(&form, settings, guess, start, deadline, true, false)?;
    let handover = matches!(
        first.status,
        Status::MaxIterations | Status::Stalled | Status::InnerFailure | Status::NumericalError
    );
    if first.converged() || !handover || deadline.is_some_and(|t| Instant::now() >= t) {
        return Ok(merge(stages, first, start));
    }
    let warm = Guess {
        r: first.r.clone(),
        v: first.v.clone(),
    };
    let second_settings = Settings {
        inner,
        outer,
        fallback: None,
        ..settings.clone()
    };
    let warm = if first.r.iter().all(|x| x.is_finite()) {
        Some(&warm)
    } else {
        guess
    };
    let second = solve_stage(&form, &second_settings, warm, start, deadline, false, false)?;
    stages.push(first);
    Ok(merge(stages, second, start))
}

/// The last stage's solution with the histories and iteration counts of the earlier ones
/// prepended, and the total time.
fn merge(earlier: Vec<Solution>, mut last: Solution, start: Instant) -> Solution {
    let mut history = Vec::new();
    for stage in earlier {
        history.extend(stage.history);
        last.outer_iterations += stage.outer_iterations;
        last.inner_iterations += stage.inner_iterations;
    }
    history.append(&mut last.history);
    last.history = history;
    last.solve_time = start.elapsed();
    last
}

/// The checked starting impulses: the guess (projected onto L) or zero.
fn start_point(form: &Form<'_>, guess: Option<&Guess>) -> Result<Vec<f64>, SolveError> {
    let local = form.local();
    let m = local.q.len();
    let mut r = match guess {
        Some(gs) if gs.r.len() != m => {
            return Err(SolveError::Guess(format!(
                "r has length {}, expected {m}",
                gs.r.len()
            )))
        }
        Some(gs) if gs.r.iter().any(|x| !x.is_finite()) => {
            return Err(SolveError::Guess("r has non-finite entries".into()))
        }
        Some(gs) => gs.r.clone(),
        None => vec![0.0; m],
    };
    crate::cone::project_product(local.dim, &local.mu, &mut r);
    Ok(r)
}

/// Newton steps one end-game try may take (all tries of a stage share
/// [`Settings::newton_steps`]).
const NEWTON_TRY_STEPS: usize = 15;

/// A failed Newton end game is tried again once the error is below this fraction of the error
/// it started from.
const NEWTON_RETRY: f64 = 0.1;

/// Outer iterations over which the error must halve for a first stage to be considered
/// progressing (see [`Settings::fallback`]).
pub const STALL_WINDOW: usize = 25;

/// One run of the outer loop with `settings.inner` / `settings.outer`; `stop_on_stall` ends it
/// with [`Status::Stalled`] when the error no longer decreases; `warmup` lets the fused
/// iteration give up as soon as its rate says the tolerance is out of reach.
fn solve_stage(
    form: &Form<'_>,
    settings: &Settings,
    guess: Option<&Guess>,
    start: Instant,
    deadline: Option<Instant>,
    stop_on_stall: bool,
    warmup: bool,
) -> Result<Solution, SolveError> {
    let local = form.local();
    let (dim, mu) = (local.dim, &local.mu[..]);
    let m = local.q.len();
    let mut r = start_point(form, guess)?;
    let frictionless = mu.iter().all(|&x| x == 0.0);
    // s from the guess (F at the guess), zero for a cold start
    let mut s = if guess.is_some() {
        fixed_point::evaluate_f(dim, &local.velocity(&r))
    } else {
        vec![0.0; mu.len()]
    };
    let mut solver = inner_solver(settings);
    let mut pgs_fused = PgsSolver::new();
    let mut update = OuterUpdate::new(settings.outer);
    let mut history = Vec::new();
    let mut inner_total = 0;
    let mut b = Vec::with_capacity(m);
    let w_scale = crate::inner::w_scale(dim, &local.w);
    let mut verdict = Verdict::of(form, &r);
    let mut last_error = verdict.error;
    let mut balance_stalls = 0;
    let mut newton_gate = f64::INFINITY;
    let mut newton_used = 0;
    let q_norm = law::norm(&local.q);
    let status = loop {
        if verdict.converged(settings.tol) {
            break Status::Converged;
        }
        if verdict.spurious(settings.tol) {
            break Status::Unbounded;
        }
        if history.len() >= settings.max_outer {
            break Status::MaxIterations;
        }
        if deadline.is_some_and(|t| Instant::now() >= t) {
            break Status::TimeLimit;
        }
        // inner solve for r(s), warm-started
        // Interior point and faceted QPs start cold at every outer iteration: a loose inner
        // tolerance would never tighten through warm starts, so they solve to the final one.
        let cold_inner = matches!(settings.inner, InnerKind::Ipm | InnerKind::Faceted);
        let inner_tol = if frictionless || cold_inner {
            0.2 * settings.tol
        } else {
            (settings.inner_tol_factor * last_error)
                .min(1e-2)
                .max(0.2 * settings.tol)
        };
        let limits = InnerLimits {
            tol: inner_tol,
            max_iterations: settings.max_inner,
            deadline,
        };
        fixed_point::shifted(dim, &local.q, mu, &s, &mut b);
        let mut report = match (&form.stored, settings.inner, settings.outer) {
            (_, _, OuterKind::Fused) => {
                let limits = InnerLimits {
                    tol: 0.9 * settings.tol,
                    ..limits
                };
                pgs::solve_fused(
                    &mut pgs_fused,
                    dim,
                    &local.w,
                    &local.q,
                    mu,
                    &limits,
                    warmup,
                    &mut r,
                )
            }
            (Stored::Global(g, _), InnerKind::Ipm, _) => {
                let mut shift = Vec::with_capacity(m);
                fixed_point::shifted(dim, &g.w, mu, &s, &mut shift);
                let out = ipm::solve_primal(g, &shift, &limits);
                if out.r.len() == m {
                    r = out.r;
                }
                out.report
            }
            _ => {
                let inner = InnerProblem {
                    dim,
                    w: form.qp_w(),
                    b: &b,
                    mu,
                };
                solver.solve(&inner, &limits, &mut r)
            }
        };
        inner_total += report.iterations;
        if r.iter().any(|x| !x.is_finite()) {
            break Status::NumericalError;
        }
        // F(s) from ũ = W r + b (its tangential part is that of u = W r + q)
        let u_local = local.velocity(&r);
        let fs = fixed_point::evaluate_f(dim, &u_local);
        if settings.outer == OuterKind::Fused {
            fixed_point::shifted(dim, &local.q, mu, &fs, &mut b);
        }
        let wr: Vec<f64> = u_local.iter().zip(&local.q).map(|(a, c)| a - c).collect();
        if crate::inner::unbounded_ray(&r, &wr, &b, w_scale) {
            report.status = InnerStatus::Infeasible;
        }
        verdict = Verdict::of(form, &r);
        let (fp_residual, rule) = fixed_point::residuals(&s, &fs);
        history.push(OuterRecord {
            error: verdict.error,
            fixed_point_residual: fp_residual,
            rule_6_1: rule,
            inner_iterations: report.iterations,
        });
        last_error = verdict.error;
        if verdict.error <= settings.tol
            && !verdict.converged(settings.tol)
            && !verdict.spurious(settings.tol)
        {
            balance_stalls += 1;
            if balance_stalls >= 3 {
                break Status::BalanceResidual;
            }
        }
        if let Some(status) = inner_failure(&report) {
            // an unbounded (4.7) is never reported as converged, whatever the relative error
            if report.status == InnerStatus::Infeasible || !verdict.converged(settings.tol) {
                break status;
            }
        }
        if settings.fixed_point_tol.is_some_and(|eps| rule <= eps)
            && !verdict.converged(settings.tol)
            && !frictionless
        {
            break Status::FixedPointRule;
        }
        if stop_on_stall && history.len() > STALL_WINDOW {
            let recent = history[history.len() - STALL_WINDOW..]
                .iter()
                .map(|h| h.error)
                .fold(f64::INFINITY, f64::min);
            let before = history[..history.len() - STALL_WINDOW]
                .iter()
                .map(|h| h.error)
                .fold(f64::INFINITY, f64::min);
            if recent > 0.5 * before {
                break Status::Stalled;
            }
        }
        if settings.newton_steps > 0
            && verdict.error <= settings.newton_start
            && (verdict.error <= newton_gate
                || report.status == InnerStatus::MaxIterations
                || stagnating(&history))
            && !verdict.converged(settings.tol)
            && newton_used < settings.newton_steps
        {
            // Newton end game from r, kept only if the error of docs/error.md drops; all the
            // tries of a stage share `newton_steps` steps. When the inner solver works on the
            // surrogate ½(W + Wᵀ), a try that more than halved the error is followed by
            // another one at once: an inner solve would pull r back towards the surrogate's
            // solution.
            let mut improved = false;
            let mut fs = fs;
            while newton_used < settings.newton_steps {
                let mut trial = r.clone();
                let nr = newton::polish(
                    local,
                    &mut trial,
                    0.5 * settings.tol * q_norm,
                    NEWTON_TRY_STEPS.min(settings.newton_steps - newton_used),
                    deadline,
                );
                newton_used += nr.steps.max(1);
                let candidate = Verdict::of(form, &trial);
                inner_total += nr.steps;
                if nr.steps == 0 || candidate.error >= verdict.error {
                    break;
                }
                let gain = candidate.error / verdict.error;
                r = trial;
                verdict = candidate;
                let fs_new = fixed_point::evaluate_f(dim, &local.velocity(&r));
                let (fp_residual, rule) = fixed_point::residuals(&fs, &fs_new);
                history.push(OuterRecord {
                    error: verdict.error,
                    fixed_point_residual: fp_residual,
                    rule_6_1: rule,
                    inner_iterations: nr.steps,
                });
                last_error = verdict.error;
                fs = fs_new;
                improved = true;
                if verdict.converged(settings.tol)
                    || form.symmetric
                    || gain > 0.5
                    || deadline.is_some_and(|t| Instant::now() >= t)
                {
                    break;
                }
            }
            if improved {
                s = fs;
                update = OuterUpdate::new(settings.outer);
                if !verdict.converged(settings.tol) {
                    newton_gate = NEWTON_RETRY * verdict.error;
                }
                continue;
            }
            newton_gate = NEWTON_RETRY * verdict.error;
            s = update.next(&s, &fs);
            continue;
        }
        s = update.next(&s, &fs);
    };
    let (inner_iterations, outer_iterations) = (inner_total, history.len());
    Ok(Solution {
        r,
        u: verdict.u,
        v: verdict.v,
        s,
        status,
        error: verdict.error,
        balance_residual: verdict.balance,
        outer_iterations,
        inner_iterations,
        history,
        solve_time: start.elapsed(),
    })
}

/// Outer iterations without a new lowest error after which the fixed point counts as
/// stagnating (the Newton end game is then tried again whatever its gate).
const STAGNATION: usize = 3;

/// A new lowest error counts as progress only below this fraction of the previous lowest.
const STAGNATION_GAIN: f64 = 0.5;

/// Whether the last [`STAGNATION`] outer iterations all failed to lower the best error to
/// [`STAGNATION_GAIN`] times its previous value.
fn stagnating(history: &[OuterRecord]) -> bool {
    let n = history.len();
    if n <= STAGNATION {
        return false;
    }
    let best_before = history[..n - STAGNATION]
        .iter()
        .map(|h| h.error)
        .fold(f64::INFINITY, f64::min);
    history[n - STAGNATION..]
        .iter()
        .all(|h| h.error > STAGNATION_GAIN * best_before)
}

/// The outer status an inner failure forces (None: keep iterating, warm-started).
fn inner_failure(report: &InnerReport) -> Option<Status> {
    match report.status {
        InnerStatus::Solved | InnerStatus::MaxIterations => None,
        InnerStatus::TimeLimit => Some(Status::TimeLimit),
        InnerStatus::Infeasible => Some(Status::InnerInfeasible),
        InnerStatus::NumericalError => Some(Status::InnerFailure),
    }
}
