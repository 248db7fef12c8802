//! The rigid-body steps of the plan as [`Method`]s: the interior point on Coulomb's law
//! ([`crate::barrier`], with its Levenberg–Marquardt finishes) and the method of multipliers
//! in the velocities ([`crate::multiplier`]), each judged on the problem as stored like every
//! iterate of the stage loop (a stage of no outer iteration, `judged`).

use super::form::{Form, Stored};
use super::method::{Ctx, Handover, Method, Outcome, StartPoint};
use super::stage::Stage;
use crate::deadline::Deadline;
use crate::linalg::skeleton::Skeleton;
use crate::linalg::sparse::CscMatrix;
use crate::plan::Budget;
use crate::problem::{GlobalProblem, LocalProblem};
use crate::settings::Settings;
use crate::solution::{Guess, OuterRecord, SolveError};

/// The interior point on Coulomb's law as a step: the try ([`crate::barrier`], policy and parameters
/// [`crate::settings::BarrierParams`]): cold-started runs along each path of
/// `paths` in turn, each finished by the Levenberg–Marquardt end game when its error is
/// ≤ [`crate::settings::LmParams::start`] (its stall rule
/// [`crate::settings::BarrierParams::lm_stall_segments`]), until one reaches the
/// tolerance — or [`crate::settings::BarrierParams::handover`] · tol where the method of
/// multipliers follows (`multipliers_apply`) — or the try's budget of steps
/// (the step's [`Budget::Steps`]: `total` =
/// [`crate::settings::BarrierParams::max_work`], `per_run` =
/// [`crate::settings::MethodParams::barrier_steps`]) is spent. Its best point is judged on the problem as stored like
/// every iterate (status `converged`, `unbounded` or `max_iterations`; one outer record
/// whose inner iterations are all its Newton and LM steps); with it, the end points of
/// all its runs, lowest error first (the starts of [`Multipliers`]). None
/// (nothing run) when the Newton systems have neither a Schur complement nor a skeleton
/// ([`crate::barrier::Setup::structured`]).
pub(super) struct InteriorPoint;

impl Method for InteriorPoint {
    fn run(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        start: StartPoint<'_>,
        budget: Budget,
        deadline: Deadline,
    ) -> Result<Option<Outcome>, SolveError> {
        let (Budget::Steps { per_run, total }, StartPoint::One(None)) = (budget, start) else {
            return Err(SolveError::Settings(
                "the interior point starts cold on a budget of Newton steps".into(),
            ));
        };
        let settings = ctx.settings;
        let (bp, lm) = (settings.params.tuning.barrier, settings.params.tuning.lm);
        let local = ctx.form.local();
        let target = settings.params.tuning.newton.target_fraction * settings.tol;
        let global = match &ctx.form.stored {
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
        let hand_at = if multipliers_follow(ctx.form, settings, &setup) {
            target.max(bp.handover * settings.tol)
        } else {
            target
        };
        let mut ends: Vec<(Vec<f64>, f64)> = Vec::new();
        let mut steps = 0;
        // the budget in steps (not in time: the same path on any machine and under any load)
        for path in bp.paths {
            if steps >= total || deadline.passed() {
                break;
            }
            let (mut r, report) = crate::barrier::solve_with(
                local,
                &setup,
                target,
                per_run.min(total - steps),
                &bp,
                path,
                deadline,
            );
            steps += report.steps;
            let mut error = report.error;
            let left = total.saturating_sub(steps);
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
            if error <= hand_at {
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
        let handover = Handover {
            points: ends,
            skeleton: setup.into_skeleton(),
        };
        let mut outcome = judged(ctx, r, steps, deadline)?;
        outcome.handover = Some(handover);
        Ok(Some(outcome))
    }
}

/// The point `r` that a method outside the stage loop reached in `steps` inner steps,
/// judged on the problem as stored like every iterate (a stage of no outer iteration),
/// with one outer record (no fixed-point residual) counting those steps.
fn judged(
    ctx: &mut Ctx<'_, '_>,
    r: Vec<f64>,
    steps: usize,
    deadline: Deadline,
) -> Result<Outcome, SolveError> {
    let judge = Settings {
        max_outer: 0,
        fallback: None,
        ..ctx.settings.clone()
    };
    let guess = Guess { r, v: None };
    let stage = Stage::new(ctx.form, &judge, Some(&guess), deadline, false, false)?;
    let mut outcome = stage.run(ctx.solvers);
    outcome.history.push(OuterRecord {
        error: outcome.last.verdict.error,
        fixed_point_residual: f64::NAN,
        rule_6_1: f64::NAN,
        inner_iterations: steps,
        step: crate::plan::StepKind::Main,
    });
    outcome.work.outer_iterations += 1;
    outcome.work.inner_iterations += steps;
    Ok(outcome)
}

/// Whether [`Multipliers`] applies, short of the skeleton of a local W: the
/// stage is on, every μ is finite, and the problem is a global one with at most
/// [`crate::settings::BarrierParams::max_schur_dofs`] degrees of freedom and at most half
/// as many as contact unknowns, or a local one with at most
/// [`crate::settings::BarrierParams::max_skeleton_unknowns`] contact unknowns (whose
/// skeleton [`Multipliers`] then checks: it must reproduce W, symmetric or
/// not).
pub(super) fn multipliers_apply(form: &Form<'_>, settings: &Settings) -> bool {
    let (mp, bp) = (
        settings.params.tuning.multiplier,
        settings.params.tuning.barrier,
    );
    let local = form.local();
    let m = local.q.len();
    if mp.max_steps == 0 || !local.mu.iter().all(|mu| mu.is_finite()) {
        return false;
    }
    match &form.stored {
        Stored::Global(g, _) => {
            let n = g.m.nrows;
            n <= bp.max_schur_dofs && 2 * n <= m
        }
        Stored::Local(_) => m <= bp.max_skeleton_unknowns,
    }
}

/// Whether the method of multipliers' stage will follow an interior-point try run on
/// `setup`: `multipliers_apply`, and on a local problem a skeleton that
/// reproduces W within [`crate::settings::MultiplierParams::skeleton_residual`] · tol (as
/// `exact_skeleton` requires; a W with an antisymmetric part outside its range
/// has none: its try then goes on to tol instead of handing over at
/// [`crate::settings::BarrierParams::handover`] · tol).
pub(super) fn multipliers_follow(
    form: &Form<'_>,
    settings: &Settings,
    setup: &crate::barrier::Setup<'_>,
) -> bool {
    let limit = settings.params.tuning.multiplier.skeleton_residual * settings.tol;
    let parallel_dim = settings.params.tuning.barrier.dense_parallel_dim;
    multipliers_apply(form, settings)
        && match (&form.stored, setup.skeleton()) {
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
#[cfg(feature = "unit-tests")]
pub(super) fn exact_skeleton(
    settings: &Settings,
    p: &LocalProblem,
    deadline: Deadline,
) -> Option<Skeleton> {
    let bp = &settings.params.tuning.barrier;
    let m = p.q.len();
    let max_rank = bp
        .max_schur_dofs
        .min((bp.skeleton_rank_ratio * m as f64) as usize);
    let skeleton = Skeleton::new(&p.w, p.dim, max_rank, bp.rank_tol, deadline)?;
    reproduces(settings, &skeleton, p).then_some(skeleton)
}

/// Whether `skeleton` reproduces the W of `p` within
/// [`crate::settings::MultiplierParams::skeleton_residual`] · tol.
fn reproduces(settings: &Settings, skeleton: &Skeleton, p: &LocalProblem) -> bool {
    let (mp, bp) = (
        &settings.params.tuning.multiplier,
        &settings.params.tuning.barrier,
    );
    skeleton
        .residual(&p.w, bp.dense_parallel_dim)
        .is_some_and(|r| r <= mp.skeleton_residual * settings.tol)
}

/// The method of multipliers in the velocities as a step ([`crate::multiplier`], parameters
/// [`crate::settings::MultiplierParams`]) from the best point of the interior-point try
/// and, at once, from the end points of its other runs ([`StartPoint::Several`]), on a local problem
/// through the skeleton of W the try built (at most
/// [`crate::settings::MultiplierParams::starts`] runs in all, [`crate::multiplier::solve_from`]),
/// within the step's [`Budget::Factorizations`] (`total` =
/// [`crate::settings::MultiplierParams::max_factorizations`], `starts` =
/// [`crate::settings::MultiplierParams::starts`]). It applies where the try did: a global
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
pub(super) struct Multipliers;

impl Method for Multipliers {
    fn run(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        start: StartPoint<'_>,
        budget: Budget,
        deadline: Deadline,
    ) -> Result<Option<Outcome>, SolveError> {
        let (Budget::Factorizations { total, starts }, StartPoint::Several(handover)) =
            (budget, start)
        else {
            return Err(SolveError::Settings(
                "the multipliers start from the interior point's points on a budget of \
                 factorizations"
                    .into(),
            ));
        };
        let settings = ctx.settings;
        if !multipliers_apply(ctx.form, settings) {
            return Ok(None);
        }
        let mp = crate::settings::MultiplierParams {
            max_factorizations: total,
            starts,
            ..settings.params.tuning.multiplier
        };
        let bp = settings.params.tuning.barrier;
        let local = ctx.form.local();
        let m = local.q.len();
        let skeleton_form;
        let (g, hu, mass): (&GlobalProblem, Option<&CscMatrix>, &crate::mass::MassFactor) =
            match &ctx.form.stored {
                Stored::Global(g, delassus) => (g, None, &delassus.factor),
                Stored::Local(p) => {
                    let Some(skeleton) = handover.skeleton.filter(|sk| reproduces(settings, sk, p))
                    else {
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
        // the try's best point, then the end points of its other runs (distinct, finite)
        let mut points = handover.points.into_iter();
        let r = points.next().unwrap_or_default();
        if r.len() != m || !r.iter().all(|x| x.is_finite()) {
            return Ok(None);
        }
        let mut starts = vec![r];
        for end in points {
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
        let form = ctx.form;
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
        judged(ctx, r, steps, deadline).map(Some)
    }
}
