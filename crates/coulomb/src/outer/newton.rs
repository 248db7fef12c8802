//! The Newton end game of a stage: once the error of `docs/error.md` is ≤
//! [`crate::MethodParams::newton_start`], semismooth Newton steps on the natural map of (3.9)
//! for all contacts ([`crate::newton::polish`]) are tried from r; they are kept if they lower
//! the error (one history record per kept try; s then restarts from F at the new r).
//!
//! A failed try is repeated only after the error has dropped below
//! [`crate::settings::NewtonParams::retry`] times its starting value, when an inner solve hits
//! its iteration cap, or when the fixed point stagnates
//! ([`crate::settings::NewtonParams::stagnation`] iterations without a new lowest error); a
//! try takes at most [`crate::settings::NewtonParams::try_steps`] steps and all tries of a
//! stage at most [`crate::MethodParams::newton_steps`], so that the iteration is deterministic.
//!
//! A try that did not converge at err ≤ [`crate::settings::ProxParams::try_start`] hands its
//! best point to the proximal point ([`crate::proximal`]) with a budget of Newton steps of its
//! own ([`crate::settings::ProxParams::max_steps`]);
//! once the Newton budget is spent on a stagnating iterate, Levenberg–Marquardt
//! ([`crate::levenberg`]) runs, and the proximal point again after an LM run that stalled.

use super::fixed_point;
use super::form::{Form, Verdict};
use crate::deadline::Deadline;
use crate::inner::{InnerReport, InnerStatus};
use crate::settings::{NewtonParams, Settings};
use crate::solution::OuterRecord;

/// What the end game of a stage remembers between outer iterations.
#[derive(Debug, Clone, Copy)]
pub(super) struct EndGame {
    /// a failed try is repeated once the error is below this
    gate: f64,
    /// Newton steps spent by this stage
    used: usize,
    /// the Levenberg–Marquardt end game ([`crate::levenberg`]) runs again only once the
    /// error is below this
    lm_gate: f64,
    /// LM steps spent by this stage
    lm_used: usize,
    /// the proximal point after a Newton try runs again only once the error is below this
    prox_gate: f64,
}

impl EndGame {
    pub(super) fn new() -> Self {
        Self {
            gate: f64::INFINITY,
            used: 0,
            lm_gate: f64::INFINITY,
            lm_used: 0,
            prox_gate: f64::INFINITY,
        }
    }
}

/// Whether the last `p.stagnation` outer iterations all failed to lower the best error to
/// `p.stagnation_gain` times its previous value.
fn stagnating(history: &[OuterRecord], p: &NewtonParams) -> bool {
    let n = history.len();
    if n <= p.stagnation {
        return false;
    }
    let best_before = history[..n - p.stagnation]
        .iter()
        .map(|h| h.error)
        .fold(f64::INFINITY, f64::min);
    history[n - p.stagnation..]
        .iter()
        .all(|h| h.error > p.stagnation_gain * best_before)
}

/// What a kept end game produced: the new r and its verdict, one history record per kept
/// try, and F at the new r (the next s).
pub(super) struct Improved {
    pub(super) r: Vec<f64>,
    pub(super) verdict: Verdict,
    pub(super) records: Vec<OuterRecord>,
    pub(super) fs: Vec<f64>,
}

/// The state of the outer iterate the end game starts from.
pub(super) struct Iterate<'x> {
    pub(super) r: &'x [f64],
    pub(super) verdict: &'x Verdict,
    pub(super) history: &'x [OuterRecord],
    /// F(s) of the last outer iteration
    pub(super) fs: &'x [f64],
}

impl Iterate<'_> {
    /// The point an end game starts from: r, its error and F(s) of `best` when there is one,
    /// else of the outer iterate.
    fn or_best<'a>(&'a self, best: &'a Option<Improved>) -> (&'a [f64], f64, &'a [f64]) {
        match best {
            Some(b) => (&b.r, b.verdict.error, &b.fs),
            None => (self.r, self.verdict.error, self.fs),
        }
    }
}

impl EndGame {
    /// Tries the end game from `at` after an outer iteration whose inner solve ended with
    /// `report`: None if the gate is closed, otherwise the Newton steps spent and, if the
    /// error dropped, what replaces the iterate (s then restarts from F at the new r).
    ///
    /// When the inner solver works on the surrogate ½(W + Wᵀ), a try that more than halved
    /// the error is followed by another one at once: an inner solve would pull r back towards
    /// the surrogate's solution.
    pub(super) fn attempt(
        &mut self,
        form: &Form<'_>,
        settings: &Settings,
        deadline: Deadline,
        at: Iterate<'_>,
        report: &InnerReport,
    ) -> Option<(usize, Option<Improved>)> {
        let (tol, p) = (settings.tol, settings.params.tuning.newton);
        let gate_open = at.verdict.error <= self.gate
            || report.status == InnerStatus::MaxIterations
            || stagnating(at.history, &p);
        if settings.params.newton_steps == 0
            || at.verdict.error > settings.params.newton_start
            || at.verdict.converged(tol)
        {
            return None;
        }
        if self.used >= settings.params.newton_steps {
            // the Newton budget is spent: only the Levenberg–Marquardt end game, behind its gate
            if at.verdict.error > self.lm_gate || !stagnating(at.history, &p) {
                return None;
            }
            return self.levenberg(form, settings, deadline, &at, &None);
        }
        if !gate_open {
            return None;
        }
        let local = form.local();
        let mut spent = 0;
        let mut best: Option<Improved> = None;
        while self.used < settings.params.newton_steps {
            let (r, error, fs) = at.or_best(&best);
            let mut trial = r.to_vec();
            let nr = crate::newton::polish_with(
                local,
                &mut trial,
                p.target_fraction * tol * form.q_norm,
                p.try_steps.min(settings.params.newton_steps - self.used),
                deadline,
                &p,
            );
            self.used += nr.steps.max(1);
            let candidate = form.verdict(&trial);
            spent += nr.steps;
            if nr.steps == 0 || candidate.error >= error {
                break;
            }
            let gain = candidate.error / error;
            let fs_new = fixed_point::evaluate_f(local.dim, &local.velocity(&trial));
            let (fixed_point_residual, rule_6_1) = fixed_point::residuals(fs, &fs_new);
            let record = OuterRecord {
                error: candidate.error,
                fixed_point_residual,
                rule_6_1,
                inner_iterations: nr.steps,
                step: crate::plan::StepKind::Main,
            };
            let mut records = best.map_or_else(Vec::new, |b| b.records);
            records.push(record);
            let done = candidate.converged(tol)
                || form.symmetric
                || gain > p.continue_gain
                || deadline.passed();
            best = Some(Improved {
                r: trial,
                verdict: candidate,
                records,
                fs: fs_new,
            });
            if done {
                break;
            }
        }
        match &best {
            Some(b) if !b.verdict.converged(tol) => self.gate = p.retry * b.verdict.error,
            Some(_) => {}
            None => self.gate = p.retry * at.verdict.error,
        }
        let mut converged = best.as_ref().is_some_and(|b| b.verdict.converged(tol));
        if !converged {
            let run = self.proximal(form, settings, deadline, &at, &best, report);
            if let Some((steps, improved)) = run {
                spent += steps;
                best = improved.or(best);
                converged = best.as_ref().is_some_and(|b| b.verdict.converged(tol));
            }
        }
        if self.used >= settings.params.newton_steps && !converged && stagnating(at.history, &p) {
            if let Some((steps, improved)) = self.levenberg(form, settings, deadline, &at, &best) {
                spent += steps;
                best = improved.or(best);
            }
        }
        Some((spent, best))
    }

    /// The Levenberg–Marquardt end game ([`crate::levenberg`]) from the best point so far
    /// (`best`, or the outer iterate): None when its step budget
    /// ([`crate::settings::LmParams::max_steps`]) is spent or the error is above
    /// [`crate::settings::LmParams::start`]; otherwise its steps and, if it lowered
    /// the error (of the problem as stored), the new iterate with one history record.
    fn levenberg(
        &mut self,
        form: &Form<'_>,
        settings: &Settings,
        deadline: Deadline,
        at: &Iterate<'_>,
        best: &Option<Improved>,
    ) -> Option<(usize, Option<Improved>)> {
        let (tol, mut lm) = (settings.tol, settings.params.tuning.lm);
        if self.lm_used >= lm.max_steps || deadline.passed() {
            return None;
        }
        // what is left of the stage's budget of LM steps (a budget in work: the path does
        // not depend on the machine's speed)
        lm.max_steps -= self.lm_used;
        let (r, error, fs) = at.or_best(best);
        if error > lm.start {
            return None;
        }
        let local = form.local();
        let mut trial = r.to_vec();
        let target = settings.params.tuning.newton.target_fraction * tol;
        let mut report = crate::levenberg::solve(local, &mut trial, target, &lm, deadline);
        let lm_steps = report.steps;
        // a stalled LM hands its best point to the proximal point (its own budget of Newton
        // steps, [`crate::settings::ProxParams::max_steps`])
        let prox = &settings.params.tuning.prox;
        let stalled = matches!(
            report.status,
            crate::levenberg::LmStatus::Stalled | crate::levenberg::LmStatus::MaxSteps
        );
        if stalled
            && report.error > target
            && report.error <= prox.start
            && prox.max_outer > 0
            && !deadline.passed()
        {
            let mut point = trial.clone();
            let pr = crate::proximal::solve(local, &mut point, target, prox, deadline);
            report.steps += pr.steps;
            // a proximal point that followed a ray of diverging r (no solution: the
            // relative error falls only because ‖r‖ grows) is not kept
            if pr.error < report.error && !form.verdict(&point).unbounded {
                trial = point;
                report.error = pr.error;
            }
        }
        self.lm_used += lm_steps.max(1);
        self.lm_gate = lm.retry * report.error.min(error);
        let candidate = form.verdict(&trial);
        // a run that did not converge is kept only if it cut the error by `keep_gain`: a small
        // gain is lost again once the fixed point goes on from an unrelated point
        let kept = candidate.converged(tol) || candidate.error <= lm.keep_gain * error;
        let moved = report.steps > 0 && kept;
        let improved =
            moved.then(|| Improved::after(form, trial, candidate, fs, best, report.steps));
        Some((report.steps, improved))
    }

    /// The proximal point ([`crate::proximal`]) after a Newton try that did not converge,
    /// from the best point so far: None when the error is above
    /// [`crate::settings::ProxParams::try_start`] or its gate is closed; otherwise its Newton
    /// steps and, if it lowered the error (of the problem as stored) to at most
    /// [`crate::settings::LmParams::keep_gain`] times its start (or converged), the new
    /// iterate with one history record. A run takes at most
    /// [`crate::settings::ProxParams::max_steps`] Newton steps, or
    /// [`crate::settings::ProxParams::capped_max_steps`] after an inner solve (`inner`) that
    /// hit its iteration cap.
    fn proximal(
        &mut self,
        form: &Form<'_>,
        settings: &Settings,
        deadline: Deadline,
        at: &Iterate<'_>,
        best: &Option<Improved>,
        inner: &InnerReport,
    ) -> Option<(usize, Option<Improved>)> {
        let (tol, prox) = (settings.tol, &settings.params.tuning.prox);
        let (r, error, fs) = at.or_best(best);
        if prox.max_outer == 0
            || error > prox.try_start
            || error > self.prox_gate
            || deadline.passed()
        {
            return None;
        }
        // an inner solve at its iteration cap: the fixed point does not solve its subproblems
        // (the granular drums of the corpus), and the proximal point gets the larger budget
        let budget = crate::settings::ProxParams {
            max_steps: if inner.status == InnerStatus::MaxIterations {
                prox.capped_max_steps
            } else {
                prox.max_steps
            },
            ..*prox
        };
        let mut trial = r.to_vec();
        let target = settings.params.tuning.newton.target_fraction * tol;
        let report = crate::proximal::solve(form.local(), &mut trial, target, &budget, deadline);
        self.prox_gate = prox.retry * report.error.min(error);
        let candidate = form.verdict(&trial);
        // as for LM: a small gain is lost again once the fixed point goes on; a result on a
        // ray of diverging r is not kept
        let kept = candidate.converged(tol)
            || (candidate.error <= settings.params.tuning.lm.keep_gain * error
                && !candidate.unbounded);
        let moved = report.steps > 0 && kept;
        let improved =
            moved.then(|| Improved::after(form, trial, candidate, fs, best, report.steps));
        Some((report.steps, improved))
    }
}

impl Improved {
    /// What an end game that moved r to `r` (with its verdict) leaves: the records of `best`
    /// plus one for this run (`steps` inner iterations), and F at the new r.
    fn after(
        form: &Form<'_>,
        r: Vec<f64>,
        verdict: Verdict,
        fs: &[f64],
        best: &Option<Improved>,
        steps: usize,
    ) -> Self {
        let local = form.local();
        let fs_new = fixed_point::evaluate_f(local.dim, &local.velocity(&r));
        let (fixed_point_residual, rule_6_1) = fixed_point::residuals(fs, &fs_new);
        let mut records = best.as_ref().map_or_else(Vec::new, |b| b.records.clone());
        records.push(OuterRecord {
            error: verdict.error,
            fixed_point_residual,
            rule_6_1,
            inner_iterations: steps,
            step: crate::plan::StepKind::Main,
        });
        Self {
            r,
            verdict,
            records,
            fs: fs_new,
        }
    }
}
