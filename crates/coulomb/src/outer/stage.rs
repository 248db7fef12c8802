//! One stage of the outer iteration of §3.3 with one (inner, outer) method: the paper's
//! algorithm, step by step.
//!
//! ```text
//!     s₀ = 0 (or F at the guess);  for k = 0, 1, …:
//!         stop if err(r_k) ≤ tol (docs/error.md, on the problem as stored), or a cap is hit
//!         r_{k+1} = r(s_k):   solve (3.15)/(4.7) with b = q + E s_k      (inner_step)
//!         F(s_k)ⁱ = ‖ũ_Tⁱ‖,  ũ = W r_{k+1} + b  (3.19);  err, rule (6.1) (record)
//!         stop on err ≤ tol, an inner failure, rule (6.1) or a stall    (check_termination)
//!         Newton end game on the natural map when err is small          (try_end_game)
//!         s_{k+1} = F(s_k), or Anderson mixing of it                     (next_s)
//! ```
//!
//! With all μ = 0 the inner problem is the whole problem (§5.1) and s plays no role. With
//! [`OuterKind::Fused`] each "outer iteration" is one batch of Gauss–Seidel sweeps on
//! Coulomb's law ([`super::fused`]).

use super::fixed_point::{self, OuterUpdate};
use super::form::{Form, Stored, Verdict};
use super::method::{Ctx, Method, Outcome, Point, StartPoint, Work};
use super::newton::{EndGame, Iterate};
use super::InnerSolvers;
use crate::deadline::Deadline;
use crate::inner::{ipm, InnerLimits, InnerProblem, InnerReport, InnerStatus};
use crate::plan::Budget;
use crate::settings::{InnerKind, MethodParams, OuterKind, Settings};
use crate::solution::{Guess, OuterRecord, SolveError, Status};

/// The state of one stage: r, s, the history, and what the stopping tests remember.
pub(super) struct Stage<'f, 'a> {
    form: &'f Form<'a>,
    settings: &'f Settings,
    deadline: Deadline,
    /// end with [`Status::Stalled`] when the error no longer decreases (a stage with a fallback)
    stop_on_stall: bool,
    /// the warm-up try: the fused iteration may give up as soon as its rate says the
    /// tolerance is out of reach
    warmup: bool,
    frictionless: bool,
    r: Vec<f64>,
    s: Vec<f64>,
    /// b = q + E s
    b: Vec<f64>,
    update: OuterUpdate,
    history: Vec<OuterRecord>,
    inner_total: usize,
    verdict: Verdict,
    balance_stalls: usize,
    end_game: EndGame,
    /// the iterate of lowest [`Verdict::merit`] so far (None: the current one, or none yet)
    best: Option<Point>,
}

impl<'f, 'a> Stage<'f, 'a> {
    /// A stage from `guess` (projected onto L; zero when None), s = F(guess) or 0.
    pub(super) fn new(
        form: &'f Form<'a>,
        settings: &'f Settings,
        guess: Option<&Guess>,
        deadline: Deadline,
        stop_on_stall: bool,
        warmup: bool,
    ) -> Result<Self, SolveError> {
        let local = form.local();
        let r = start_point(form, guess)?;
        let s = if guess.is_some() {
            fixed_point::evaluate_f(local.dim, &local.velocity(&r))
        } else {
            vec![0.0; local.mu.len()]
        };
        let verdict = form.verdict(&r);
        let mut stage = Self {
            form,
            settings,
            deadline,
            stop_on_stall,
            warmup,
            frictionless: local.mu.iter().all(|&x| x == 0.0),
            r,
            s,
            b: Vec::with_capacity(local.q.len()),
            update: OuterUpdate::with_params(settings.outer, &settings.params.tuning.anderson),
            history: Vec::new(),
            inner_total: 0,
            verdict,
            balance_stalls: 0,
            end_game: EndGame::new(),
            best: None,
        };
        stage.remember_best();
        Ok(stage)
    }

    /// The outer loop of §3.3 until a status: the last iterate, and the iterate of lowest
    /// error visited before it when that one is lower.
    pub(super) fn run(mut self, solvers: &mut InnerSolvers) -> Outcome {
        let status = loop {
            if let Some(status) = self.check_start() {
                break status;
            }
            let Some(report) = self.inner_step(solvers) else {
                break Status::NumericalError;
            };
            let (report, fs) = self.record(report);
            if let Some(status) = self.check_termination(&report) {
                break status;
            }
            if self.try_end_game(&report, &fs) {
                continue;
            }
            self.next_s(&fs);
        };
        self.finish(status)
    }

    /// Before an outer iteration: converged, unbounded, iteration cap, time limit.
    fn check_start(&self) -> Option<Status> {
        let tol = self.settings.tol;
        if self.verdict.converged(tol) {
            Some(Status::Converged)
        } else if self.verdict.spurious(tol) {
            Some(Status::Unbounded)
        } else if self.history.len() >= self.settings.max_outer {
            Some(Status::MaxIterations)
        } else if self.deadline.cancelled() {
            Some(Status::Interrupted)
        } else if self.deadline.passed() {
            Some(Status::TimeLimit)
        } else {
            None
        }
    }

    /// r ← r(s): the inner problem (3.15)/(4.7) with b = q + E s, warm-started from r, to the
    /// inner tolerance of [`crate::settings::Tuning::inner_tol`]; None if r became
    /// non-finite.
    fn inner_step(&mut self, solvers: &mut InnerSolvers) -> Option<InnerReport> {
        let (settings, form) = (self.settings, self.form);
        let local = form.local();
        let (dim, mu) = (local.dim, &local.mu[..]);
        // Interior point and faceted QPs start cold at every outer iteration: a loose inner
        // tolerance would never tighten through warm starts, so they solve to the final one.
        let cold = matches!(settings.inner, InnerKind::Ipm | InnerKind::Faceted);
        let limits = InnerLimits {
            tol: settings.params.tuning.inner_tol(
                settings,
                self.verdict.error,
                cold || self.frictionless,
            ),
            max_iterations: settings.max_inner,
            deadline: self.deadline,
        };
        fixed_point::shifted(dim, &local.q, mu, &self.s, &mut self.b);
        let report = match (&form.stored, settings.inner, settings.outer) {
            (_, _, OuterKind::Fused) => {
                let limits = InnerLimits {
                    tol: settings.params.tuning.fused_tol_fraction * settings.tol,
                    ..limits
                };
                let (w, q) = (&local.w, &local.q);
                let pgs = solvers.fused(form);
                super::fused::solve_fused(pgs, dim, w, q, mu, &limits, self.warmup, &mut self.r)
            }
            (Stored::Global(g, _), InnerKind::Ipm, _) => {
                let mut shift = Vec::with_capacity(self.r.len());
                fixed_point::shifted(dim, &g.w, mu, &self.s, &mut shift);
                let out = ipm::solve_primal(g, &shift, &limits);
                if out.r.len() == self.r.len() {
                    self.r = out.r;
                }
                out.report
            }
            _ => {
                let inner = InnerProblem {
                    dim,
                    w: form.qp_w(),
                    b: &self.b,
                    mu,
                };
                solvers
                    .get(settings.inner, form)
                    .solve(&inner, &limits, &mut self.r)
            }
        };
        self.inner_total += report.iterations;
        self.r.iter().all(|x| x.is_finite()).then_some(report)
    }

    /// F(s) (3.19) from ũ = W r + b (its tangential part is that of u = W r + q), the
    /// infeasible-ray test of (3.15), the error of docs/error.md and the (6.1) measure, one
    /// history record. Returns the report (status `Infeasible` if r is a ray) and F(s).
    fn record(&mut self, mut report: InnerReport) -> (InnerReport, Vec<f64>) {
        let local = self.form.local();
        let u = local.velocity(&self.r);
        let fs = fixed_point::evaluate_f(local.dim, &u);
        if self.settings.outer == OuterKind::Fused {
            fixed_point::shifted(local.dim, &local.q, &local.mu, &fs, &mut self.b);
        }
        let wr: Vec<f64> = u.iter().zip(&local.q).map(|(a, c)| a - c).collect();
        if crate::inner::unbounded_ray(
            &self.r,
            &wr,
            &self.b,
            self.form.w_scale,
            &self.settings.params.tuning.inner.infeasible_ray,
        ) {
            report.status = InnerStatus::Infeasible;
        }
        self.verdict = self.form.verdict(&self.r);
        self.remember_best();
        let (fixed_point_residual, rule_6_1) = fixed_point::residuals(&self.s, &fs);
        self.push_record(fixed_point_residual, rule_6_1, report.iterations);
        (report, fs)
    }

    /// Appends the record of an iteration: the current error, ‖F(s) − s‖ and (6.1).
    pub(super) fn push_record(
        &mut self,
        fixed_point_residual: f64,
        rule_6_1: f64,
        inner_iterations: usize,
    ) {
        self.history.push(OuterRecord {
            error: self.verdict.error,
            fixed_point_residual,
            rule_6_1,
            inner_iterations,
            step: crate::plan::StepKind::Main,
        });
    }

    /// After an outer iteration: a balance residual that does not follow the error, an inner
    /// failure, the paper's rule (6.1), a stall.
    fn check_termination(&mut self, report: &InnerReport) -> Option<Status> {
        let (settings, tol) = (self.settings, self.settings.tol);
        let converged = self.verdict.converged(tol);
        if self.verdict.error <= tol && !converged && !self.verdict.spurious(tol) {
            self.balance_stalls += 1;
            if self.balance_stalls >= settings.params.tuning.balance_stalls {
                return Some(Status::BalanceResidual);
            }
        }
        if let Some(status) = inner_failure(report) {
            // an unbounded (4.7) is never reported as converged, whatever the relative error
            if report.status == InnerStatus::Infeasible || !converged {
                return Some(status);
            }
        }
        let rule = self.history.last().map_or(f64::INFINITY, |h| h.rule_6_1);
        if settings
            .params
            .fixed_point_tol
            .is_some_and(|eps| rule <= eps)
            && !converged
            && !self.frictionless
        {
            return Some(Status::FixedPointRule);
        }
        (self.stop_on_stall && self.stalled()).then_some(Status::Stalled)
    }

    /// Whether the lowest error of the last [`crate::settings::Tuning::stall_window`]
    /// iterations is above half the lowest one before them.
    fn stalled(&self) -> bool {
        let window = self.settings.params.tuning.stall_window;
        let n = self.history.len();
        if n <= window {
            return false;
        }
        let min = |h: &[OuterRecord]| h.iter().map(|h| h.error).fold(f64::INFINITY, f64::min);
        min(&self.history[n - window..]) > 0.5 * min(&self.history[..n - window])
    }

    /// The Newton end game ([`super::newton`]) when its gate is open; true if it moved r
    /// (s then restarts from F at the new r).
    fn try_end_game(&mut self, report: &InnerReport, fs: &[f64]) -> bool {
        let at = Iterate {
            r: &self.r,
            verdict: &self.verdict,
            history: &self.history,
            fs,
        };
        let attempt = self
            .end_game
            .attempt(self.form, self.settings, self.deadline, at, report);
        let Some((steps, improved)) = attempt else {
            return false;
        };
        self.inner_total += steps;
        let Some(better) = improved else {
            return false;
        };
        self.r = better.r;
        self.verdict = better.verdict;
        self.history.extend(better.records);
        self.s = better.fs;
        self.remember_best();
        self.update =
            OuterUpdate::with_params(self.settings.outer, &self.settings.params.tuning.anderson);
        true
    }

    /// s ← F(s), or Anderson mixing of it.
    pub(super) fn next_s(&mut self, fs: &[f64]) {
        self.s = self.update.next(&self.s, fs);
    }

    /// Keeps the current iterate if its merit is the lowest so far.
    fn remember_best(&mut self) {
        let merit = self.verdict.merit();
        if merit < self.best.as_ref().map_or(f64::INFINITY, Point::merit) {
            self.best = Some(Point {
                r: self.r.clone(),
                s: self.s.clone(),
                verdict: self.verdict.clone(),
            });
        }
    }

    fn finish(self, status: Status) -> Outcome {
        let current = self.verdict.merit();
        Outcome {
            status,
            best: self.best.filter(|b| b.merit() < current),
            last: Point {
                r: self.r,
                s: self.s,
                verdict: self.verdict,
            },
            handover: None,
            work: Work {
                outer_iterations: self.history.len(),
                inner_iterations: self.inner_total,
            },
            history: self.history,
        }
    }
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

/// The outer status an inner failure forces (None: keep iterating, warm-started).
fn inner_failure(report: &InnerReport) -> Option<Status> {
    match report.status {
        InnerStatus::Solved | InnerStatus::MaxIterations => None,
        InnerStatus::TimeLimit => Some(Status::TimeLimit),
        InnerStatus::Infeasible => Some(Status::InnerInfeasible),
        InnerStatus::NumericalError => Some(Status::InnerFailure),
    }
}

/// The fixed-point stage as a step of the plan: the warm-up (a budget of sweeps: one outer
/// iteration of the fused method, no end game) and the main and fallback steps (a budget of
/// outer and inner iterations and end-game Newton steps) with the (inner, outer) pair `pair`.
pub(super) struct FixedPoint {
    pub(super) pair: crate::settings::Method,
    /// end with [`Status::Stalled`] when the error no longer decreases (a step that a
    /// fallback follows)
    pub(super) stop_on_stall: bool,
}

impl Method for FixedPoint {
    fn run(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        start: StartPoint<'_>,
        budget: Budget,
        deadline: Deadline,
    ) -> Result<Option<Outcome>, SolveError> {
        let (max_outer, max_inner, newton_steps, warmup) = match budget {
            Budget::Sweeps(n) => (1, n, 0, true),
            Budget::Iterations {
                outer,
                inner,
                newton,
            } => (outer, inner, newton, false),
            _ => {
                return Err(SolveError::Settings(format!(
                    "a fixed-point step cannot run on a budget of {budget}"
                )))
            }
        };
        let StartPoint::One(guess) = start else {
            return Err(SolveError::Settings(
                "a fixed-point step starts from one point".into(),
            ));
        };
        let settings = Settings {
            inner: self.pair.inner,
            outer: self.pair.outer,
            fallback: None,
            max_outer,
            max_inner,
            params: MethodParams {
                newton_steps,
                ..ctx.settings.params
            },
            ..ctx.settings.clone()
        };
        let stage = Stage::new(
            ctx.form,
            &settings,
            guess.as_deref(),
            deadline,
            self.stop_on_stall,
            warmup,
        )?;
        Ok(Some(stage.run(ctx.solvers)))
    }
}
