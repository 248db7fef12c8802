//! The outer method of §3.3 and the policy around it.
//!
//! The paper's algorithm is the loop of `stage`: s ← F(s) with F(s)ⁱ = ‖ũ_Tⁱ(s)‖ (3.19),
//! each F(s) the solution of the SOC-QP (3.15)/(4.7) by an inner solver ([`crate::inner`]),
//! stopped by the error of `docs/error.md` (and, if asked, by rule (6.1)). Its pieces, one
//! file each: [`fixed_point`] (F, the shift b = q + E s, rule (6.1), the update rule),
//! [`anderson`] (mixing on s), [`fused`] (Gauss–Seidel on Coulomb's law itself, the fused
//! outer method) and [`newton`] (the semismooth Newton end game).
//!
//! The policy ([`Solver::solve`]) is the plan of [`crate::plan`]: an optional warm-up of
//! Gauss–Seidel sweeps on Coulomb's law, on a cold solve of a rigid problem the interior
//! point and the method of multipliers, then the main method, then the fallback method when
//! the main one stops without converging; every status is decided on the problem as stored
//! (`form`).
//!
//! The setup/solve split: [`Solver::new`] checks the settings and builds the Delassus form of
//! a global problem (W = Hᵀ M⁻¹ H, q = Hᵀ M⁻¹ f + w, the factorization of M) once;
//! [`Solver::solve`] can be called many times (the inner solvers, owned by the solver, are set
//! up once for W: Lipschitz estimate, diagonal blocks, Clarabel setup), and [`Solver::update_q`] /
//! [`Solver::update_rhs`] / [`Solver::update_w`] change the data of a time step.

pub mod anderson;
pub mod fixed_point;
pub(crate) mod form;
pub mod fused;
pub mod newton;
mod stage;

use crate::deadline::Deadline;
use crate::delassus::Delassus;
use crate::inner::{
    apgd::ApgdSolver, faceted::FacetedSolver, ipm::IpmSolver, pgs::PgsSolver, InnerSolver,
};
use crate::linalg::sparse::CscMatrix;
use crate::plan::{Plan, Rigid, StepKind, Structure};
use crate::problem::{GlobalProblem, LocalProblem, Problem, ProblemError};
use crate::settings::{InnerKind, InnerParams, MethodParams, OuterKind, Settings};
use crate::solution::{Guess, OuterRecord, Solution, SolveError, Status};
use form::{Form, Stored};
use stage::{Best, Stage};
use std::borrow::Cow;
use std::time::Instant;

/// The [`Structure`] of the problem of `form` (the rigid-body limits from `settings`).
fn structure_of(form: &Form<'_>, settings: &Settings) -> Structure {
    let local = form.local();
    let m = local.q.len();
    let bp = &settings.params.tuning.barrier;
    let (dofs, rigid) = match &form.stored {
        Stored::Global(g, _) => {
            let n = g.m.nrows;
            let schur = n <= bp.max_schur_dofs && 2 * n <= m;
            (Some(n), if schur { Rigid::Schur } else { Rigid::No })
        }
        Stored::Local(_) => (
            None,
            if m <= bp.max_skeleton_unknowns {
                Rigid::SkeletonProbe
            } else {
                Rigid::No
            },
        ),
    };
    let mu = &local.mu;
    let mu_range = if mu.is_empty() {
        (f64::NAN, f64::NAN)
    } else {
        mu.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            })
    };
    Structure {
        dim: local.dim,
        contacts: mu.len(),
        unknowns: m,
        dofs,
        symmetric: form.symmetric,
        density: if m == 0 {
            0.0
        } else {
            local.w.nnz() as f64 / (m as f64 * m as f64)
        },
        mu_range,
        mu_positive: !mu.is_empty() && mu.iter().all(|&x| x > 0.0 && x.is_finite()),
        rigid,
    }
}

/// Names `kind` as the step that made every history record of `ran`.
fn label(ran: &mut Ran, kind: StepKind) {
    ran.0.history.iter_mut().for_each(|h| h.step = kind);
}

/// The inner solvers of a [`Solver`], each set up for the problem's (d, W, μ) when first
/// needed (a fallback never reached costs nothing) and kept across stages and solves: the
/// diagonal blocks of W (Gauss–Seidel), the λ_max(W) estimate and block form (APGD), the
/// Clarabel setups (interior point, faceted). [`Solver::update_w`] drops them.
pub(crate) struct InnerSolvers {
    /// one per [`InnerKind`], in the order of [`InnerKind::ALL`], on the QP matrix
    /// ([`Form::qp_w`])
    qp: [Option<Box<dyn InnerSolver + Send>>; 4],
    /// the Gauss–Seidel solver of the fused method, on the stored W
    fused: Option<PgsSolver>,
    facets: usize,
    params: InnerParams,
}

impl InnerSolvers {
    fn new(settings: &Settings) -> Self {
        Self {
            qp: [None, None, None, None],
            fused: None,
            facets: settings.params.facets,
            params: settings.params.tuning.inner,
        }
    }

    /// The solver of `kind` for the QP (4.7) of `form`.
    pub(crate) fn get(
        &mut self,
        kind: InnerKind,
        form: &Form<'_>,
    ) -> &mut (dyn InnerSolver + Send) {
        let (facets, params) = (self.facets, self.params);
        let slot = InnerKind::ALL
            .iter()
            .position(|&k| k == kind)
            .expect("every kind is in ALL");
        self.qp[slot]
            .get_or_insert_with(|| {
                let (dim, w) = (form.local().dim, form.qp_w());
                match kind {
                    InnerKind::Pgs => {
                        let mut s = PgsSolver::new(dim, w);
                        s.refresh = params.gs_refresh;
                        s.ray = params.infeasible_ray;
                        Box::new(s)
                    }
                    InnerKind::Apgd => {
                        let power = params.apgd_power_iterations;
                        let mut s = ApgdSolver::with_power_iterations(dim, w, power);
                        s.barzilai_borwein = params.apgd_barzilai_borwein;
                        s.params = params.apgd;
                        s.ray = params.infeasible_ray;
                        Box::new(s)
                    }
                    InnerKind::Ipm => Box::new(IpmSolver::with_polish(params.ipm_polish_steps)),
                    InnerKind::Faceted => Box::new(FacetedSolver::new(facets)),
                }
            })
            .as_mut()
    }

    /// The Gauss–Seidel solver of the fused method on the stored W of `form`.
    pub(crate) fn fused(&mut self, form: &Form<'_>) -> &mut PgsSolver {
        let p = self.params;
        self.fused.get_or_insert_with(|| {
            let local = form.local();
            let mut s = PgsSolver::new(local.dim, &local.w);
            s.refresh = p.gs_refresh;
            s.ray = p.infeasible_ray;
            s.anderson_period = p.gs_anderson_period;
            s.anderson_memory = p.gs_anderson_memory;
            s
        })
    }
}

/// A solver set up for one problem: the stored data, its Delassus form, the inner solvers.
pub struct Solver<'a> {
    form: Form<'a>,
    settings: Settings,
    solvers: InnerSolvers,
    /// what the solver knows of the problem ([`crate::plan::Structure`]), computed once
    structure: Structure,
}

impl<'a> Solver<'a> {
    /// Checks `settings` and builds what every solve of `problem` needs: for a global problem
    /// the factorization of M and the Delassus form (W, q).
    pub fn new(problem: &'a Problem, settings: Settings) -> Result<Self, SolveError> {
        match problem {
            Problem::Local(p) => Self::with_stored(Stored::Local(Cow::Borrowed(p)), settings),
            Problem::Global(g) => Self::global(Cow::Borrowed(g), settings),
        }
    }

    /// [`Solver::new`] taking ownership of the problem (no borrow to keep alive).
    pub fn new_owned(problem: Problem, settings: Settings) -> Result<Solver<'static>, SolveError> {
        match problem {
            Problem::Local(p) => Solver::with_stored(Stored::Local(Cow::Owned(p)), settings),
            Problem::Global(g) => Solver::global(Cow::Owned(g), settings),
        }
    }

    fn global(g: Cow<'a, GlobalProblem>, settings: Settings) -> Result<Self, SolveError> {
        settings.validate()?;
        let delassus = Box::new(Delassus::new(&g)?);
        Self::with_stored(Stored::Global(g, delassus), settings)
    }

    fn with_stored(stored: Stored<'a>, settings: Settings) -> Result<Self, SolveError> {
        settings.validate()?;
        let form = Form::new(stored, settings.params.tuning.unbounded_ratio);
        Ok(Self {
            structure: structure_of(&form, &settings),
            form,
            solvers: InnerSolvers::new(&settings),
            settings,
        })
    }

    /// What the solver knows of the problem: local or global, contacts, symmetry and density
    /// of W, the range of μ, whether the rigid-body steps apply ([`crate::plan`]).
    pub fn structure(&self) -> &Structure {
        &self.structure
    }

    /// The steps a solve from `guess` runs ([`crate::plan::choose`]): printed by
    /// `coulomb solve --explain`.
    pub fn plan(&self, guess: Option<&Guess>) -> Plan {
        crate::plan::choose(&self.structure, &self.settings, guess.is_none())
    }

    /// The settings of the next solves.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Replaces the settings (checked); the set-up data are kept.
    pub fn set_settings(&mut self, settings: Settings) -> Result<(), SolveError> {
        settings.validate()?;
        if settings.params.facets != self.settings.params.facets
            || settings.params.tuning.inner != self.settings.params.tuning.inner
        {
            self.solvers = InnerSolvers::new(&settings);
        }
        self.form.unbounded_ratio = settings.params.tuning.unbounded_ratio;
        self.structure = structure_of(&self.form, &settings);
        self.settings = settings;
        Ok(())
    }

    /// The local form (W, q, μ) the solver works on: the problem itself, or the Delassus form
    /// of a global problem.
    pub fn local(&self) -> &LocalProblem {
        self.form.local()
    }

    /// New free velocity q of a local problem (same W and μ), e.g. the next time step.
    pub fn update_q(&mut self, q: Vec<f64>) -> Result<(), SolveError> {
        let Stored::Local(p) = &mut self.form.stored else {
            return Err(SolveError::Problem(ProblemError::Shape {
                what: "q",
                expected: "a local problem (use update_rhs for a global one)".into(),
                found: "a global problem".into(),
            }));
        };
        crate::problem::check_len("q", &q, p.q.len())?;
        p.to_mut().q = q;
        self.form.refresh();
        Ok(())
    }

    /// New f and w of a global problem (same M, H and μ: the factorization and W are kept);
    /// q = Hᵀ M⁻¹ f + w is recomputed.
    pub fn update_rhs(&mut self, f: Vec<f64>, w: Vec<f64>) -> Result<(), SolveError> {
        let Stored::Global(g, d) = &mut self.form.stored else {
            return Err(SolveError::Problem(ProblemError::Shape {
                what: "f",
                expected: "a global problem (use update_q for a local one)".into(),
                found: "a local problem".into(),
            }));
        };
        crate::problem::check_len("f", &f, g.f.len())?;
        crate::problem::check_len("w", &w, g.w.len())?;
        let g = g.to_mut();
        (g.f, g.w) = (f, w);
        d.update_rhs(g);
        self.form.refresh();
        Ok(())
    }

    /// New Delassus matrix W of a local problem (same size; checked as
    /// [`LocalProblem::new`] checks it). The inner solvers' data are rebuilt for it at their
    /// next use.
    pub fn update_w(&mut self, w: CscMatrix) -> Result<(), SolveError> {
        let Stored::Local(p) = &mut self.form.stored else {
            return Err(SolveError::Problem(ProblemError::Shape {
                what: "W",
                expected: "a local problem".into(),
                found: "a global problem".into(),
            }));
        };
        let checked = LocalProblem::new(p.dim as i64, w, p.q.clone(), p.mu.clone())?;
        *p = Cow::Owned(checked);
        self.form.refresh();
        self.structure = structure_of(&self.form, &self.settings);
        self.solvers = InnerSolvers::new(&self.settings);
        Ok(())
    }

    /// Solves the problem from `guess` (a cold start when None) by the steps of
    /// [`Solver::plan`] ([`crate::plan::choose`]): warm-up sweeps, on a cold solve of a rigid
    /// problem the interior point on Coulomb's law and the method of multipliers, the main
    /// method, the fallback; each with a budget in work. The time limit covers all of them
    /// and only truncates. A solve stopped by
    /// [`Settings::cancel`] before it converged ends with [`Status::Interrupted`] (rather than
    /// the cap or time limit that the stop looked like inside a stage).
    pub fn solve(&mut self, guess: Option<&Guess>) -> Result<Solution, SolveError> {
        let mut sol = self.solve_stages(guess)?;
        let cancelled = self.settings.cancel.is_some_and(|c| c.requested());
        if cancelled
            && matches!(
                sol.status,
                Status::TimeLimit | Status::MaxIterations | Status::Stalled
            )
        {
            sol.status = Status::Interrupted;
        }
        Ok(sol)
    }

    /// [`Solver::solve`] before the status of an interrupted solve is set: the steps of
    /// [`Solver::plan`] in order, until one converges, the deadline passes, or the main step
    /// ends in a way its fallback cannot improve.
    fn solve_stages(&mut self, guess: Option<&Guess>) -> Result<Solution, SolveError> {
        let start = Instant::now();
        let deadline =
            Deadline::after(start, self.settings.time_limit).with_cancel(self.settings.cancel);
        let settings = &self.settings.clone();
        let plan = self.plan(guess);
        let has_fallback = plan.steps.iter().any(|s| s.kind == StepKind::Fallback);
        let mut stages: Vec<Ran> = Vec::new();
        // the interior point's result and end points, waiting for the multipliers
        let mut tried: Option<(Ran, Ends)> = None;
        // the main step's result, waiting for the fallback
        let mut main: Option<Ran> = None;
        for step in &plan.steps {
            match step.kind {
                StepKind::Warmup => {
                    let mut warm =
                        self.run(&warmup_settings(settings), guess, deadline, false, true)?;
                    label(&mut warm, StepKind::Warmup);
                    if warm.0.converged() || deadline.passed() {
                        return Ok(merge(Vec::new(), warm, start));
                    }
                    stages.push(warm);
                }
                StepKind::InteriorPoint => {
                    if let Some((mut t, ends)) = self.barrier_try(deadline)? {
                        label(&mut t, StepKind::InteriorPoint);
                        if t.0.converged() || deadline.passed() {
                            return Ok(merge(stages, t, start));
                        }
                        tried = Some((t, ends));
                    }
                }
                StepKind::Multipliers => {
                    // runs only after an interior point that ran and did not converge
                    // (the history in the order the steps ran: the try's record first)
                    if let Some((t, ends)) = tried.take() {
                        let m = self.multiplier_try(&t, ends, deadline)?;
                        stages.push(t);
                        if let Some(mut m) = m {
                            label(&mut m, StepKind::Multipliers);
                            if m.0.converged() || deadline.passed() {
                                return Ok(merge(stages, m, start));
                            }
                            stages.push(m);
                        }
                    }
                }
                StepKind::Main => {
                    if let Some((t, _)) = tried.take() {
                        stages.push(t);
                    }
                    // the main method starts from the caller's point, not from the
                    // warm-up's r: on hard problems Gauss–Seidel's r leads the fixed point
                    // of the main method astray
                    let mut first = self.run(settings, guess, deadline, has_fallback, false)?;
                    label(&mut first, StepKind::Main);
                    let handover = matches!(
                        first.0.status,
                        Status::MaxIterations
                            | Status::Stalled
                            | Status::InnerFailure
                            | Status::NumericalError
                    );
                    if !has_fallback || first.0.converged() || !handover || deadline.passed() {
                        return Ok(merge(stages, first, start));
                    }
                    main = Some(first);
                }
                StepKind::Fallback => {
                    let (Some(first), Some(method)) = (main.take(), step.method) else {
                        continue;
                    };
                    // the fallback goes on from the main step's last iterate, not its best
                    // one: that is where its own iteration stood
                    let from_first = Guess {
                        r: first.0.r.clone(),
                        v: first.0.v.clone(),
                    };
                    let second_settings = Settings {
                        inner: method.inner,
                        outer: method.outer,
                        fallback: None,
                        ..settings.clone()
                    };
                    let warm = if first.0.r.iter().all(|x| x.is_finite()) {
                        Some(&from_first)
                    } else {
                        guess
                    };
                    stages.push(first);
                    let mut second = self.run(&second_settings, warm, deadline, false, false)?;
                    label(&mut second, StepKind::Fallback);
                    return Ok(merge(stages, second, start));
                }
            }
        }
        Err(SolveError::Settings(
            "the plan of this solve has no main step".into(),
        ))
    }
}

impl Solver<'_> {
    /// One stage of `settings`' method from `guess`.
    fn run(
        &mut self,
        settings: &Settings,
        guess: Option<&Guess>,
        deadline: Deadline,
        stop_on_stall: bool,
        warmup: bool,
    ) -> Result<Ran, SolveError> {
        let stage = Stage::new(&self.form, settings, guess, deadline, stop_on_stall, warmup)?;
        Ok(stage.run(&mut self.solvers))
    }

    /// The interior-point try on Coulomb's law ([`crate::barrier`], policy and parameters
    /// [`crate::settings::BarrierParams`]): cold-started runs along each path of
    /// `paths` in turn, each finished by the Levenberg–Marquardt end game when its error is
    /// ≤ [`crate::settings::LmParams::start`] (its stall rule
    /// [`crate::settings::BarrierParams::lm_stall_segments`]), until one reaches the
    /// tolerance — or [`crate::settings::BarrierParams::handover`] · tol where the method of
    /// multipliers follows ([`Solver::multipliers_apply`]) — or the try's budget of steps
    /// ([`crate::settings::BarrierParams::max_work`]) is spent. Its best point is judged on the problem as stored like
    /// every iterate (status `converged`, `unbounded` or `max_iterations`; one outer record
    /// whose inner iterations are all its Newton and LM steps); with it, the end points of
    /// all its runs, lowest error first (the starts of [`Solver::multiplier_try`]). None
    /// (nothing run) when the Newton systems have neither a Schur complement nor a skeleton
    /// ([`crate::barrier::Setup::structured`]).
    fn barrier_try(&mut self, deadline: Deadline) -> Result<Option<(Ran, Ends)>, SolveError> {
        let settings = &self.settings;
        let (bp, lm) = (settings.params.tuning.barrier, settings.params.tuning.lm);
        let local = self.form.local();
        let target = settings.params.tuning.newton.target_fraction * settings.tol;
        let global = match &self.form.stored {
            Stored::Global(g, _) => Some(&**g),
            Stored::Local(_) => None,
        };
        let Some(setup) = crate::barrier::Setup::structured(local, global, &bp, deadline) else {
            return Ok(None);
        };
        let try_lm = crate::settings::LmParams {
            stall_segments: bp.lm_stall_segments,
            ..lm
        };
        // the try hands over to the method of multipliers from an end point this close
        let handover = if self.multipliers_follow(&setup) {
            target.max(bp.handover * settings.tol)
        } else {
            target
        };
        let mut ends: Vec<(Vec<f64>, f64)> = Vec::new();
        let mut steps = 0;
        // the budget in steps (not in time: the same path on any machine and under any load)
        for path in bp.paths {
            if steps >= bp.max_work || deadline.passed() {
                break;
            }
            let (mut r, report) = crate::barrier::solve_with(
                local,
                &setup,
                target,
                settings.params.barrier_steps.min(bp.max_work - steps),
                &bp,
                path,
                deadline,
            );
            steps += report.steps;
            let mut error = report.error;
            let left = bp.max_work.saturating_sub(steps);
            if error > target && error <= lm.start && lm.max_steps > 0 && left > 0 {
                let mut trial = r.clone();
                let finish_lm = crate::settings::LmParams {
                    max_steps: try_lm.max_steps.min(left),
                    ..try_lm
                };
                let lr = crate::levenberg::solve(local, &mut trial, target, &finish_lm, deadline);
                steps += lr.steps;
                if lr.error < error {
                    (r, error) = (trial, lr.error);
                }
            }
            ends.push((r, error));
            if error <= handover {
                break;
            }
        }
        // lowest error first (a NaN last); the sort is stable: equal errors keep path order
        ends.sort_by(|a, b| match (a.1.is_nan(), b.1.is_nan()) {
            (false, false) => a.1.total_cmp(&b.1),
            (x, y) => x.cmp(&y),
        });
        let ends: Vec<Vec<f64>> = ends.into_iter().map(|(r, _)| r).collect();
        let r = ends
            .first()
            .cloned()
            .unwrap_or_else(|| vec![0.0; local.q.len()]);
        // the skeleton goes on to the method of multipliers (built once per solve)
        let ends = Ends {
            points: ends,
            skeleton: setup.into_skeleton(),
        };
        let ran = self.judged(r, steps, deadline)?;
        Ok(Some((ran, ends)))
    }

    /// The point `r` that a method outside the stage loop reached in `steps` inner steps,
    /// judged on the problem as stored like every iterate (a stage of no outer iteration),
    /// with one outer record (no fixed-point residual) counting those steps.
    fn judged(&mut self, r: Vec<f64>, steps: usize, deadline: Deadline) -> Result<Ran, SolveError> {
        let judge = Settings {
            max_outer: 0,
            fallback: None,
            ..self.settings.clone()
        };
        let guess = Guess { r, v: None };
        let (mut solution, best) = self.run(&judge, Some(&guess), deadline, false, false)?;
        solution.history.push(OuterRecord {
            error: solution.error,
            fixed_point_residual: f64::NAN,
            rule_6_1: f64::NAN,
            inner_iterations: steps,
            step: crate::plan::StepKind::Main,
        });
        solution.outer_iterations += 1;
        solution.inner_iterations += steps;
        Ok((solution, best))
    }
}

impl Solver<'_> {
    /// Whether [`Solver::multiplier_try`] applies, short of the skeleton of a local W: the
    /// stage is on, every μ is finite, and the problem is a global one with at most
    /// [`crate::settings::BarrierParams::max_schur_dofs`] degrees of freedom and at most half
    /// as many as contact unknowns, or a local one with at most
    /// [`crate::settings::BarrierParams::max_skeleton_unknowns`] contact unknowns (whose
    /// skeleton [`Solver::multiplier_try`] then checks: it must reproduce W, symmetric or
    /// not).
    fn multipliers_apply(&self) -> bool {
        let settings = &self.settings;
        let (mp, bp) = (
            settings.params.tuning.multiplier,
            settings.params.tuning.barrier,
        );
        let local = self.form.local();
        let m = local.q.len();
        if mp.max_steps == 0 || !local.mu.iter().all(|mu| mu.is_finite()) {
            return false;
        }
        match &self.form.stored {
            Stored::Global(g, _) => {
                let n = g.m.nrows;
                n <= bp.max_schur_dofs && 2 * n <= m
            }
            Stored::Local(_) => m <= bp.max_skeleton_unknowns,
        }
    }

    /// Whether the method of multipliers' stage will follow an interior-point try run on
    /// `setup`: [`Solver::multipliers_apply`], and on a local problem a skeleton that
    /// reproduces W within [`crate::settings::MultiplierParams::skeleton_residual`] · tol (as
    /// [`Solver::exact_skeleton`] requires; a W with an antisymmetric part outside its range
    /// has none: its try then goes on to tol instead of handing over at
    /// [`crate::settings::BarrierParams::handover`] · tol).
    fn multipliers_follow(&self, setup: &crate::barrier::Setup<'_>) -> bool {
        let settings = &self.settings;
        let limit = settings.params.tuning.multiplier.skeleton_residual * settings.tol;
        let parallel_dim = settings.params.tuning.barrier.dense_parallel_dim;
        self.multipliers_apply()
            && match (&self.form.stored, setup.skeleton()) {
                (Stored::Global(..), _) => true,
                (Stored::Local(p), Some(sk)) => {
                    sk.residual(&p.w, parallel_dim).is_some_and(|x| x <= limit)
                }
                (Stored::Local(_), None) => false,
            }
    }

    /// The skeleton W ≈ C A⁻¹ R of the local problem `p` ([`crate::linalg::skeleton`]) of rank at
    /// most min([`crate::settings::BarrierParams::max_schur_dofs`],
    /// [`crate::settings::BarrierParams::skeleton_rank_ratio`] · m), when it reproduces W
    /// (symmetric or not) within [`crate::settings::MultiplierParams::skeleton_residual`] · tol
    /// ([`crate::linalg::skeleton::Skeleton::residual`]); None otherwise or when `deadline` passes.
    #[cfg(test)]
    fn exact_skeleton(
        &self,
        p: &LocalProblem,
        deadline: Deadline,
    ) -> Option<crate::linalg::skeleton::Skeleton> {
        let bp = &self.settings.params.tuning.barrier;
        let m = p.q.len();
        let max_rank = bp
            .max_schur_dofs
            .min((bp.skeleton_rank_ratio * m as f64) as usize);
        let skeleton =
            crate::linalg::skeleton::Skeleton::new(&p.w, p.dim, max_rank, bp.rank_tol, deadline)?;
        self.reproduces(&skeleton, p).then_some(skeleton)
    }

    /// Whether `skeleton` reproduces the W of `p` within
    /// [`crate::settings::MultiplierParams::skeleton_residual`] · tol.
    fn reproduces(&self, skeleton: &crate::linalg::skeleton::Skeleton, p: &LocalProblem) -> bool {
        let (mp, bp) = (
            &self.settings.params.tuning.multiplier,
            &self.settings.params.tuning.barrier,
        );
        skeleton
            .residual(&p.w, bp.dense_parallel_dim)
            .is_some_and(|r| r <= mp.skeleton_residual * self.settings.tol)
    }

    /// The method of multipliers in the velocities ([`crate::multiplier`], parameters
    /// [`crate::settings::MultiplierParams`]) from the best point of the interior-point try
    /// `tried` and, at once, from the end points `ends` of its other runs, on a local problem
    /// through the skeleton of W the try built (at most
    /// [`crate::settings::MultiplierParams::starts`] runs in all, [`crate::multiplier::solve_from`]),
    /// within its budget of factorizations
    /// ([`crate::settings::MultiplierParams::max_factorizations`]). It applies where the try did: a global
    /// problem with at most [`crate::settings::BarrierParams::max_schur_dofs`] degrees of
    /// freedom and at most half as many as contact unknowns (rigid bodies touching at several
    /// points per face), or a local one whose W has a skeleton W ≈ C A⁻¹ R of rank at most
    /// that and [`crate::settings::BarrierParams::skeleton_rank_ratio`] · m
    /// ([`crate::linalg::skeleton`]) equal to W within
    /// [`crate::settings::MultiplierParams::skeleton_residual`] · tol (W symmetric or not:
    /// the method then runs on the velocity form A v = R r, u = C v + q; a W whose
    /// antisymmetric part is not of W's rank, as the corpus' nonsym class, has no such
    /// skeleton). Its point is judged on the
    /// problem as stored like every iterate (one outer record whose inner iterations are its
    /// Newton steps). None when it does not apply.
    fn multiplier_try(
        &mut self,
        tried: &Ran,
        ends: Ends,
        deadline: Deadline,
    ) -> Result<Option<Ran>, SolveError> {
        if !self.multipliers_apply() {
            return Ok(None);
        }
        let settings = &self.settings;
        let mp = settings.params.tuning.multiplier;
        let bp = settings.params.tuning.barrier;
        let local = self.form.local();
        let m = local.q.len();
        let skeleton_form;
        let (g, hu, mass): (&GlobalProblem, Option<&CscMatrix>, &crate::mass::MassFactor) =
            match &self.form.stored {
                Stored::Global(g, delassus) => (g, None, &delassus.factor),
                Stored::Local(p) => {
                    let Some(skeleton) = ends.skeleton.filter(|sk| self.reproduces(sk, p)) else {
                        return Ok(None);
                    };
                    let (a, a_sym, h, hu) = skeleton.velocity_form();
                    let Ok(mass) = crate::mass::MassFactor::new(&a_sym) else {
                        return Ok(None);
                    };
                    let Ok(g) = GlobalProblem::new_unfactored(
                        p.dim as i64,
                        a,
                        h,
                        vec![0.0; skeleton.rank()],
                        p.q.clone(),
                        p.mu.clone(),
                    ) else {
                        return Ok(None);
                    };
                    skeleton_form = (g, hu, mass);
                    (&skeleton_form.0, Some(&skeleton_form.1), &skeleton_form.2)
                }
            };
        let r = match &tried.1 {
            Some(best)
                if best.merit() < tried.0.error.max(tried.0.balance_residual.unwrap_or(0.0)) =>
            {
                best.r().to_vec()
            }
            _ => tried.0.r.clone(),
        };
        if r.len() != m || !r.iter().all(|x| x.is_finite()) {
            return Ok(None);
        }
        // the try's best point, then the end points of its other runs (distinct, finite)
        let mut starts = vec![r];
        for end in ends.points {
            if starts.len() >= mp.starts {
                break;
            }
            if end.len() == m && end.iter().all(|x| x.is_finite()) && !starts.contains(&end) {
                starts.push(end);
            }
        }
        let par = crate::linalg::dense::parallelism(g.m.nrows, bp.dense_parallel_dim);
        let diag = local.w.diagonal();
        let w_mean = diag.iter().sum::<f64>() / diag.len().max(1) as f64;
        let form = &self.form;
        // the finish's steps stop at tol: its point is then judged by the same error on the
        // stored problem (each step costs sparse factorizations; the runs wait for none)
        let least_squares = |r: &mut [f64], until: Deadline| {
            crate::newton::least_squares(
                local,
                r,
                settings.tol,
                mp.finish_steps,
                mp.finish_slow_steps,
                settings.params.tuning.lm.max_normal_nonzeros,
                until,
            )
        };
        let finish = |r: &[f64]| {
            let mut trial = r.to_vec();
            least_squares(&mut trial, deadline);
            let v = form.verdict(&trial);
            (v.error <= settings.tol && v.balance.unwrap_or(0.0) <= settings.tol).then_some(trial)
        };
        let report = crate::multiplier::solve_from(
            g,
            hu,
            mass,
            w_mean,
            &mut starts,
            settings.tol,
            &mp,
            par,
            deadline,
            |r| {
                let v = form.verdict(r);
                (v.error, v.balance.unwrap_or(0.0))
            },
            finish,
        );
        let mut r = starts.swap_remove(0);
        let mut steps = report.newton_steps;
        // the least-squares finish from the stage's end point, if close to the tolerance
        let merit = report.error.max(report.balance);
        if report.status != crate::multiplier::MultiplierStatus::Converged
            && merit <= mp.finish_below * settings.tol
            && m <= mp.finish_max_unknowns
            && mp.finish_steps > 0
        {
            let mut trial = r.clone();
            let last = least_squares(&mut trial, deadline);
            steps += last.steps;
            if last.residual < report.error {
                r = trial;
            }
        }
        self.judged(r, steps, deadline).map(Some)
    }
}

/// What a stage returns: its last iterate's solution, and its lowest-error iterate when
/// that one is lower.
type Ran = (Solution, Option<Best>);

/// What the interior-point try hands to the method of multipliers: the end points of its
/// runs, lowest error first, and the skeleton of a local W its Newton systems were solved
/// through (None for a global problem: the Schur complement).
struct Ends {
    points: Vec<Vec<f64>>,
    skeleton: Option<crate::linalg::skeleton::Skeleton>,
}

/// The warm-up try: at most `warmup_sweeps` fused Gauss–Seidel sweeps, one outer iteration,
/// no end game.
fn warmup_settings(settings: &Settings) -> Settings {
    Settings {
        inner: InnerKind::Pgs,
        outer: OuterKind::Fused,
        fallback: None,
        max_outer: 1,
        max_inner: settings.params.warmup_sweeps,
        params: MethodParams {
            newton_steps: 0,
            ..settings.params
        },
        ..settings.clone()
    }
}

/// The last stage's solution with the histories and iteration counts of the earlier ones
/// prepended, and the total time. When the last stage ends without converging on a cap, a
/// stall or an inner failure, the returned iterate (r, u, v, s, error) is the one of lowest
/// error ([`form::Verdict::merit`]) visited by any stage: a solve never returns a worse point
/// than one it found. Its status and history stay those of the solve.
fn merge(earlier: Vec<Ran>, (mut last, last_best): Ran, start: Instant) -> Solution {
    let replaceable = matches!(
        last.status,
        Status::MaxIterations
            | Status::TimeLimit
            | Status::Interrupted
            | Status::Stalled
            | Status::InnerFailure
            | Status::NumericalError
            | Status::FixedPointRule
    );
    let mut history = Vec::new();
    let mut best = last_best;
    for (mut stage, stage_best) in earlier {
        history.append(&mut stage.history);
        last.outer_iterations += stage.outer_iterations;
        last.inner_iterations += stage.inner_iterations;
        let candidate = stage_best.unwrap_or_else(|| Best::of(stage));
        if candidate.merit() < best.as_ref().map_or(f64::INFINITY, Best::merit) {
            best = Some(candidate);
        }
    }
    history.append(&mut last.history);
    last.history = history;
    last.solve_time = start.elapsed();
    let last_merit = last.error.max(last.balance_residual.unwrap_or(0.0));
    match best {
        Some(b) if replaceable && b.merit() < last_merit => b.into_solution(last),
        _ => last,
    }
}

/// Solves the incremental problem (2.10) from a cold start.
pub fn solve(problem: &Problem, settings: &Settings) -> Result<Solution, SolveError> {
    solve_with_guess(problem, settings, None)
}

/// Solves the incremental problem (2.10), warm-started from `guess` when given: a
/// [`Solver`] set up for this one solve (see `stage` for the loop and [`newton`] for the
/// end game).
pub fn solve_with_guess(
    problem: &Problem,
    settings: &Settings,
    guess: Option<&Guess>,
) -> Result<Solution, SolveError> {
    Solver::new(problem, settings.clone())?.solve(guess)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two 3-D contacts on an SPD W; q pushes both into contact with some sliding.
    fn local(q: Vec<f64>) -> LocalProblem {
        let mut w = vec![0.0; 36];
        for i in 0..6 {
            w[i * 6 + i] = 2.0 + i as f64 * 0.1;
            if i + 1 < 6 {
                w[i * 6 + i + 1] = 0.3;
                w[(i + 1) * 6 + i] = 0.3;
            }
        }
        LocalProblem::new(3, CscMatrix::from_dense(6, 6, &w), q, vec![0.3, 0.5]).unwrap()
    }

    /// A stop requested before or during a solve ends it with `Interrupted`, never with a
    /// claim of convergence, and with the iterate's own error; without the request the same
    /// settings converge.
    #[test]
    fn a_cancelled_solve_ends_interrupted_with_its_error() {
        use std::sync::atomic::{AtomicBool, Ordering};
        static STOP: AtomicBool = AtomicBool::new(false);
        let p = Problem::Local(local(vec![-1.0, 0.4, 0.1, -0.5, -0.2, 0.3]));
        for base in [
            Settings::default(),
            Settings::method(InnerKind::Apgd, OuterKind::FixedPoint),
        ] {
            let settings = Settings {
                cancel: Some(crate::deadline::Cancel::new(&STOP)),
                ..base
            };
            STOP.store(false, Ordering::Relaxed);
            assert!(solve(&p, &settings).unwrap().converged());
            STOP.store(true, Ordering::Relaxed);
            let sol = solve(&p, &settings).unwrap();
            assert_eq!(sol.status, Status::Interrupted);
            assert!(!sol.converged());
            assert!(
                sol.error.is_finite() && sol.error > settings.tol,
                "{}",
                sol.error
            );
        }
        STOP.store(false, Ordering::Relaxed);
    }

    #[test]
    fn a_solver_set_up_once_solves_like_fresh_solves() {
        let q1 = vec![-1.0, 0.4, 0.1, -0.5, -0.2, 0.3];
        let q2 = vec![-0.7, -0.1, 0.6, 0.2, 0.1, 0.0];
        let p1 = Problem::Local(local(q1));
        let p2 = Problem::Local(local(q2.clone()));
        for settings in [
            Settings::default(),
            Settings::paper(InnerKind::Apgd),
            Settings::method(InnerKind::Pgs, OuterKind::Fused),
        ] {
            let mut solver = Solver::new(&p1, settings.clone()).unwrap();
            let a = solver.solve(None).unwrap();
            let fresh = solve(&p1, &settings).unwrap();
            assert_eq!(
                (a.status, &a.r, a.error),
                (fresh.status, &fresh.r, fresh.error)
            );
            assert!(a.converged(), "{:?}", a.status);
            // the next step: new q, same W
            solver.update_q(q2.clone()).unwrap();
            let guess = Guess {
                r: a.r.clone(),
                v: None,
            };
            let b = solver.solve(Some(&guess)).unwrap();
            let fresh = solve_with_guess(&p2, &settings, Some(&guess)).unwrap();
            assert_eq!(
                (b.status, &b.r, b.error),
                (fresh.status, &fresh.r, fresh.error)
            );
            assert!(b.converged());
        }
        let mut solver = Solver::new(&p1, Settings::default()).unwrap();
        assert!(solver.update_q(vec![0.0; 5]).is_err());
        assert!(solver.update_q(vec![f64::NAN; 6]).is_err());
        assert!(solver.update_rhs(vec![], vec![]).is_err());
        let bad = Settings {
            tol: -1.0,
            ..Settings::default()
        };
        assert!(matches!(
            solver.set_settings(bad),
            Err(SolveError::Settings(_))
        ));
    }

    #[test]
    fn a_global_solver_updates_f_and_w_like_a_fresh_problem() {
        let g = crate::examples::crushed_ball(0.3, 1.0).unwrap();
        let mut g2 = g.clone();
        g2.f.iter_mut().for_each(|x| *x *= 0.5);
        g2.w.iter_mut().for_each(|x| *x += 0.1);
        let (p, p2) = (Problem::Global(g), Problem::Global(g2.clone()));
        let settings = Settings::default();
        let mut solver = Solver::new(&p, settings.clone()).unwrap();
        solver.solve(None).unwrap();
        solver.update_rhs(g2.f.clone(), g2.w.clone()).unwrap();
        let a = solver.solve(None).unwrap();
        let b = solve(&p2, &settings).unwrap();
        assert_eq!(a.status, b.status);
        assert!(
            (a.error - b.error).abs() <= 1e-12,
            "{} {}",
            a.error,
            b.error
        );
        let dr =
            a.r.iter()
                .zip(&b.r)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
        assert!(dr <= 1e-12, "{dr}");
        assert!(solver.update_q(vec![]).is_err());
    }

    /// The random problems of the LM tests (W = AᵀA + 0.05 I) with q pushing into contact
    /// and μ = 2 at every contact: the successive approximations often oscillate there.
    fn random_local(n: usize, seed: u64) -> LocalProblem {
        let mut p = crate::test_problems::problem(n, seed, 0.05, 0.0);
        p.q.iter_mut().step_by(3).for_each(|x| *x -= 0.5);
        p.mu = vec![2.0; n];
        p
    }

    #[test]
    fn a_rank_deficient_local_problem_tries_the_interior_point_method_first() {
        // W = AᵀA (rank m/2, the rigid multi-contact case), symmetric or with an antisymmetric
        // part as stored in real files: a cold solve tries the interior point on the skeleton
        // of W first (its record comes first, no warm-up); the verdict is on W as stored. With
        // W = AᵀA + 0.05 I (full rank) there is no skeleton and no try.
        for seed in 0..3 {
            for skew in [0.0, 1e-3] {
                let p = crate::test_problems::problem(8, seed, 0.0, skew);
                let mut settings = Settings {
                    time_limit: None,
                    ..Settings::default()
                };
                settings.params.warmup_sweeps = 0;
                let sol = solve(&Problem::Local(p.clone()), &settings).unwrap();
                assert_eq!(sol.history[0].step, StepKind::InteriorPoint, "seed {seed}");
                assert_eq!(barrier_records(&sol), 1, "seed {seed} skew {skew}");
                let recomputed = p.error(&sol.r).error;
                assert!(
                    (recomputed - sol.error).abs() <= 1e-12 * recomputed.max(1e-300),
                    "seed {seed} skew {skew}: reported {} recomputed {recomputed}",
                    sol.error
                );
                assert_eq!(sol.converged(), recomputed <= settings.tol);
                let full = crate::test_problems::problem(8, seed, 0.05, skew);
                let capped = Settings {
                    max_outer: 2,
                    ..settings.clone()
                };
                let sol = solve(&Problem::Local(full), &capped).unwrap();
                assert_eq!(barrier_records(&sol), 0, "seed {seed} skew {skew}");
            }
        }
    }

    /// History records of interior-point tries and of the method of multipliers that follows
    /// them (they have no fixed-point residual).
    fn barrier_records(sol: &Solution) -> usize {
        use crate::plan::StepKind::{InteriorPoint, Multipliers};
        sol.history
            .iter()
            .filter(|h| matches!(h.step, InteriorPoint | Multipliers))
            .count()
    }

    #[test]
    fn a_rigid_global_problem_tries_the_interior_point_method_first() {
        // M = I with n = m/4 degrees of freedom, H random (n × m): W = Hᵀ H has rank m/4 (the
        // rigid multi-contact case): a cold solve runs the try first (its record comes first,
        // no warm-up), a solve from a guess does not; the verdict is the global one, err and
        // balance residual recomputed from (v, r)
        let mut solved = 0;
        for seed in 0..8u64 {
            let lp = crate::test_problems::problem(8, seed, 0.0, 0.0);
            let (m, n) = (24, 6);
            let mut next = crate::test_problems::uniform(seed, 7);
            let h: Vec<f64> = (0..n * m).map(|_| next()).collect();
            let g = GlobalProblem::new(
                3,
                CscMatrix::identity(n, 1.0),
                CscMatrix::from_dense(n, m, &h),
                (0..n).map(|_| next()).collect(),
                lp.q.clone(),
                lp.mu.clone(),
            )
            .unwrap();
            let problem = Problem::Global(g.clone());
            let mut settings = Settings {
                time_limit: None,
                ..Settings::default()
            };
            settings.params.warmup_sweeps = 0;
            let sol = solve(&problem, &settings).unwrap();
            assert_eq!(sol.history[0].step, StepKind::InteriorPoint, "seed {seed}");
            // the try's record, and the method of multipliers' (also without a fixed-point
            // residual) right after it when the try did not converge
            let records = barrier_records(&sol);
            let tried_on = sol.history.len() > 1;
            assert_eq!(records, 1 + usize::from(tried_on), "seed {seed}");
            if tried_on {
                assert_eq!(sol.history[1].step, StepKind::Multipliers, "seed {seed}");
            }
            solved += usize::from(sol.converged() && sol.history.len() == 1);
            let mut off = settings.clone();
            off.params.barrier_steps = 0;
            assert_eq!(barrier_records(&solve(&problem, &off).unwrap()), 0);
            let v = sol.v.clone().unwrap();
            // ‖q‖ of the Delassus form q = Hᵀ M⁻¹ f + w (M = I), as docs/error.md scales it
            let mut q = g.w.clone();
            g.h.gemv_t_acc(1.0, &g.f, &mut q);
            let (_, ev) = crate::evaluation::global(&g, &v, &sol.r, crate::law::norm(&q));
            assert_eq!(sol.converged(), ev.converged(settings.tol), "seed {seed}");
            let guess = Guess {
                r: vec![0.0; m],
                v: None,
            };
            let warm = solve_with_guess(&problem, &settings, Some(&guess)).unwrap();
            assert_eq!(barrier_records(&warm), 0, "seed {seed}");
        }
        // the try itself converged (no later stage) on half of them at least
        eprintln!("the try alone converged on {solved} of 8");
        assert!(solved >= 4, "the try alone converged on {solved} of 8");
    }

    #[test]
    fn the_multipliers_apply_to_rigid_problems_whose_skeleton_reproduces_w() {
        // global: n = 6 degrees of freedom for m = 24 contact unknowns (n ≤ m/2) applies,
        // n = 18 (> m/2) does not; local W = AᵀA (rank m/2) applies and has an exact
        // skeleton; W = Aᵀ N A with N not symmetric (rank m/2, as a W = Hᵀ M⁻¹ H with a
        // non-symmetric M) too; W = AᵀA plus an antisymmetric part outside W's range
        // passes the first test but has no exact skeleton; the stage turned off applies
        // nowhere
        let lp = crate::test_problems::problem(8, 1, 0.0, 0.0);
        let global = |n: usize| {
            let mut next = crate::test_problems::uniform(1, 7);
            let h: Vec<f64> = (0..n * 24).map(|_| next()).collect();
            Problem::Global(
                GlobalProblem::new(
                    3,
                    CscMatrix::identity(n, 1.0),
                    CscMatrix::from_dense(n, 24, &h),
                    (0..n).map(|_| next()).collect(),
                    lp.q.clone(),
                    lp.mu.clone(),
                )
                .unwrap(),
            )
        };
        let skewed = crate::test_problems::problem(8, 1, 0.0, 1e-3);
        let nonsym = {
            // W = Aᵀ N A, A = the rows of lp's W's factor: take N = I + 0.1 K (K antisymmetric)
            let (m, k) = (24, 12);
            let mut next = crate::test_problems::uniform(5, 3);
            let a: Vec<f64> = (0..k * m).map(|_| next()).collect();
            let n: Vec<f64> = (0..k * k)
                .map(|t| {
                    let (s, u) = (t / k, t % k);
                    (if s == u { 1.0 } else { 0.0 }) + 0.1 * (s as f64 - u as f64) / k as f64
                })
                .collect();
            let mut w = vec![0.0; m * m];
            for i in 0..m {
                for j in 0..m {
                    for s in 0..k {
                        for u in 0..k {
                            w[i * m + j] += a[s * m + i] * n[s * k + u] * a[u * m + j];
                        }
                    }
                }
            }
            LocalProblem {
                w: CscMatrix::from_dense(m, m, &w),
                ..lp.clone()
            }
        };
        assert!(nonsym.w.asymmetry() > 1e-3);
        let on = Settings::default();
        let mut off = Settings::default();
        off.params.tuning.multiplier.max_steps = 0;
        for (problem, applies, exact) in [
            (global(6), true, false),
            (global(18), false, false),
            (Problem::Local(lp.clone()), true, true),
            (Problem::Local(nonsym), true, true),
            (Problem::Local(skewed), true, false),
        ] {
            let solver = Solver::new(&problem, on.clone()).unwrap();
            assert_eq!(
                solver.multipliers_apply(),
                applies,
                "{}",
                problem.contacts()
            );
            if let Problem::Local(p) = &problem {
                let found = solver.exact_skeleton(p, Deadline::NEVER);
                assert_eq!(found.is_some(), exact, "asymmetry {:e}", p.w.asymmetry());
                // the try hands over to the stage only where the stage will run
                let bp = on.params.tuning.barrier;
                let setup = crate::barrier::Setup::structured(p, None, &bp, Deadline::NEVER)
                    .expect("rank m/2: a skeleton");
                assert_eq!(solver.multipliers_follow(&setup), exact);
            }
            let solver = Solver::new(&problem, off.clone()).unwrap();
            assert!(!solver.multipliers_apply());
        }
    }

    #[test]
    fn an_unconverged_solve_returns_its_lowest_error_iterate() {
        // Outer iterations capped at 3 per stage: the paper's single stage, and the default
        // policy (warm-up, main method, fallback). Whatever the status, the returned r is the
        // iterate of lowest error visited, and its error is recomputed from r on the problem.
        let mut replaced = 0;
        for seed in 0..40 {
            let p = random_local(6, seed);
            for base in [Settings::paper(InnerKind::Apgd), Settings::default()] {
                let settings = Settings {
                    max_outer: 3,
                    time_limit: None,
                    ..base
                };
                let sol = solve(&Problem::Local(p.clone()), &settings).unwrap();
                let recomputed = p.error(&sol.r).error;
                assert!(
                    (recomputed - sol.error).abs() <= 1e-12 * recomputed.max(1e-300),
                    "seed {seed}: reported {} recomputed {recomputed}",
                    sol.error
                );
                if sol.converged() {
                    continue;
                }
                let lowest = sol
                    .history
                    .iter()
                    .map(|h| h.error)
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    sol.error <= lowest,
                    "seed {seed} {:?}: returned {} lowest visited {lowest}",
                    sol.status,
                    sol.error
                );
                let last = sol.history.last().map_or(f64::INFINITY, |h| h.error);
                if last > sol.error {
                    replaced += 1;
                }
            }
        }
        // the case the rule is for occurs in this family (15 of the 80 solves)
        assert!(replaced > 0, "no solve ended above its lowest error");
    }

    /// A stage whose fixed point crawls (one APGD iteration per inner solve) and whose Newton
    /// budget is one step: without the LM end game it ends at its iteration cap; with it, it
    /// converges, and the reported error is the one recomputed from r on the stored W. A run
    /// that converges without spending its Newton budget is unchanged.
    #[test]
    fn a_stage_hands_its_stall_to_the_lm_end_game() {
        use crate::settings::{InnerKind, OuterKind, Settings};
        let mut crawl = Settings {
            max_inner: 1,
            max_outer: 60,
            ..Settings::method(InnerKind::Apgd, OuterKind::FixedPoint)
        };
        crawl.params.newton_steps = 1;
        crawl.params.newton_start = 1.0;
        crawl.params.tuning.lm.start = 1.0;
        let mut off = crawl.clone();
        off.params.tuning.lm.max_steps = 0;
        let p = crate::test_problems::problem(6, 2811, 0.0, 0.0);
        let prob = crate::Problem::Local(p.clone());
        let without = crate::solve(&prob, &off).unwrap();
        assert_eq!(without.status, crate::Status::MaxIterations);
        let with = crate::solve(&prob, &crawl).unwrap();
        let err = p.error(&with.r).error;
        assert_eq!(with.status, crate::Status::Converged);
        assert!(
            err <= crawl.tol && with.error == err,
            "{err:.3e} vs {:.3e}",
            with.error
        );
        let p = crate::test_problems::problem(6, 2902, 0.0, 0.0);
        let prob = crate::Problem::Local(p);
        let (a, b) = (
            crate::solve(&prob, &off).unwrap(),
            crate::solve(&prob, &crawl).unwrap(),
        );
        assert_eq!(a.status, crate::Status::Converged);
        assert_eq!(
            (a.status, a.outer_iterations, a.inner_iterations, &a.r),
            (b.status, b.outer_iterations, b.inner_iterations, &b.r)
        );
    }
}
