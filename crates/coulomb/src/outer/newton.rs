//! The Newton end game of a stage: once the error of `docs/error.md` is ≤
//! [`crate::Settings::newton_start`], semismooth Newton steps on the natural map of (3.9)
//! for all contacts ([`crate::newton::polish`]) are tried from r; they are kept if they lower
//! the error (one history record per kept try; s then restarts from F at the new r).
//!
//! A failed try is repeated only after the error has dropped below
//! [`crate::settings::NewtonParams::retry`] times its starting value, when an inner solve hits
//! its iteration cap, or when the fixed point stagnates
//! ([`crate::settings::NewtonParams::stagnation`] iterations without a new lowest error); a
//! try takes at most [`crate::settings::NewtonParams::try_steps`] steps and all tries of a
//! stage at most [`crate::Settings::newton_steps`], so that the iteration is deterministic.

use super::fixed_point::{self, OuterUpdate};
use super::stage::Stage;
use crate::inner::{InnerReport, InnerStatus};
use crate::settings::NewtonParams;
use crate::solution::OuterRecord;

/// What the end game of a stage remembers between outer iterations.
#[derive(Debug, Clone, Copy)]
pub(super) struct EndGame {
    /// a failed try is repeated once the error is below this
    gate: f64,
    /// Newton steps spent by this stage
    used: usize,
}

impl EndGame {
    pub(super) fn new() -> Self {
        Self {
            gate: f64::INFINITY,
            used: 0,
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

/// Tries the end game after an outer iteration that produced F(s) = `fs`; true if r moved
/// (s is then F at the new r and the outer update restarts), false if the caller should take
/// its usual step s ← F(s).
///
/// When the inner solver works on the surrogate ½(W + Wᵀ), a try that more than halved the
/// error is followed by another one at once: an inner solve would pull r back towards the
/// surrogate's solution.
pub(super) fn try_end_game(stage: &mut Stage<'_, '_>, report: &InnerReport, fs: &[f64]) -> bool {
    let settings = stage.settings;
    let (tol, p) = (settings.tol, settings.tuning.newton);
    let gate_open = stage.verdict.error <= stage.end_game.gate
        || report.status == InnerStatus::MaxIterations
        || stagnating(&stage.history, &p);
    if settings.newton_steps == 0
        || stage.verdict.error > settings.newton_start
        || !gate_open
        || stage.verdict.converged(tol)
        || stage.end_game.used >= settings.newton_steps
    {
        return false;
    }
    let local = stage.form.local();
    let mut improved = false;
    let mut fs = fs.to_vec();
    while stage.end_game.used < settings.newton_steps {
        let mut trial = stage.r.clone();
        let nr = crate::newton::polish(
            local,
            &mut trial,
            p.target_fraction * tol * stage.form.q_norm,
            p.try_steps.min(settings.newton_steps - stage.end_game.used),
            stage.deadline.instant(),
        );
        stage.end_game.used += nr.steps.max(1);
        let candidate = stage.form.verdict(&trial);
        stage.inner_total += nr.steps;
        if nr.steps == 0 || candidate.error >= stage.verdict.error {
            break;
        }
        let gain = candidate.error / stage.verdict.error;
        stage.r = trial;
        stage.verdict = candidate;
        let fs_new = fixed_point::evaluate_f(local.dim, &local.velocity(&stage.r));
        let (fp_residual, rule) = fixed_point::residuals(&fs, &fs_new);
        stage.push_record(fp_residual, rule, nr.steps);
        fs = fs_new;
        improved = true;
        if stage.verdict.converged(tol)
            || stage.form.symmetric
            || gain > 0.5
            || stage.deadline.passed()
        {
            break;
        }
    }
    if improved {
        stage.s = fs;
        stage.update = OuterUpdate::with_params(settings.outer, &settings.tuning.anderson);
        if !stage.verdict.converged(tol) {
            stage.end_game.gate = p.retry * stage.verdict.error;
        }
        return true;
    }
    stage.end_game.gate = p.retry * stage.verdict.error;
    false
}
