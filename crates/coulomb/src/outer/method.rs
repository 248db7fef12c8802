//! The methods of a plan behind one trait, and the one outcome type they return.
//!
//! Every step of a [`crate::plan::Plan`] is a [`Method`]: the fixed-point stage of §3.3
//! (`stage::FixedPoint`: the paper's loop s ← F(s) (3.19) with its inner solvers of the
//! SOC-QP (3.15)/(4.7), or the fused Gauss–Seidel on the law (2.9), with the Newton end
//! game; the warm-up, the main step and the fallback), the interior point on the law and the
//! method of multipliers (`rigid::InteriorPoint`, `rigid::Multipliers`). Each is run from a
//! [`StartPoint`] with the step's [`Budget`] and returns an [`Outcome`]: its status, its last
//! and best points with their verdicts on the problem as stored ([`Form::verdict`]: u, v, the
//! error of docs/error.md, the balance residual; never a surrogate's), what the next step
//! needs (the end points of its runs), its history records and its work.
//!
//! [`checkpoint`] is the one place where a solve decides to stop after a step.

use super::form::{Form, Verdict};
use super::InnerSolvers;
use crate::deadline::Deadline;
use crate::linalg::skeleton::Skeleton;
use crate::plan::{Budget, Start, Step, StepKind};
use crate::settings::Settings;
use crate::solution::{Guess, OuterRecord, SolveError, Status};
use std::borrow::Cow;

/// An iterate with its verdict on the problem as stored: r, the outer variable s of §3.3
/// (s = 0 for the methods without one), u (and v) recomputed from r, the error, the balance
/// residual.
pub(crate) struct Point {
    pub(crate) r: Vec<f64>,
    pub(crate) s: Vec<f64>,
    pub(crate) verdict: Verdict,
}

impl Point {
    /// The merit ([`Verdict::merit`]) of this iterate.
    pub(crate) fn merit(&self) -> f64 {
        self.verdict.merit()
    }

    /// The error of docs/error.md, or the balance residual when larger (the merit without
    /// the divergence test).
    pub(crate) fn error_or_balance(&self) -> f64 {
        self.verdict.error.max(self.verdict.balance.unwrap_or(0.0))
    }
}

/// The work a method did, as the solution counts it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Work {
    /// outer iterations of §3.3 (sweep batches of the fused method, Newton end-game steps
    /// counted as records); one for a method outside the stage loop
    pub(crate) outer_iterations: usize,
    /// inner iterations: of the QP solvers, Gauss–Seidel sweeps, and the Newton and
    /// Levenberg–Marquardt steps of the end game, the interior point and the multipliers
    pub(crate) inner_iterations: usize,
}

/// What the interior point hands to the method of multipliers: the end points of its runs,
/// lowest error first, and the skeleton of a local W its Newton systems were solved through
/// (None for a global problem: the Schur complement).
pub(crate) struct Handover {
    pub(crate) points: Vec<Vec<f64>>,
    pub(crate) skeleton: Option<Skeleton>,
}

/// The result of one method run from one start, decided on the problem as stored.
pub(crate) struct Outcome {
    /// how it ended
    pub(crate) status: Status,
    /// its last iterate
    pub(crate) last: Point,
    /// the iterate of lowest merit visited, when lower than the last one's
    pub(crate) best: Option<Point>,
    /// what the next step starts from besides the best point (the interior point's runs)
    pub(crate) handover: Option<Handover>,
    /// one record per outer iteration (one for a method outside the stage loop)
    pub(crate) history: Vec<OuterRecord>,
    /// its work
    pub(crate) work: Work,
}

impl Outcome {
    /// Whether the status is [`Status::Converged`].
    pub(crate) fn converged(&self) -> bool {
        self.status == Status::Converged
    }

    /// Marks every history record as made by the step `kind`.
    pub(crate) fn label(&mut self, kind: StepKind) {
        self.history.iter_mut().for_each(|h| h.step = kind);
    }

    /// The candidate of this outcome for the lowest-error point of a solve: its best point,
    /// or its last one judged as its status says (a diverging last iterate whose run did not
    /// stop as [`Status::Unbounded`] counts by its error).
    pub(crate) fn candidate(self) -> Point {
        let unbounded = self.status == Status::Unbounded;
        self.best.unwrap_or(Point {
            verdict: Verdict {
                unbounded,
                ..self.last.verdict
            },
            ..self.last
        })
    }
}

/// Where a method starts, built from the step's [`Start`] by [`start_point`].
pub(crate) enum StartPoint<'g> {
    /// one point (its r projected onto L by the stage), or r = 0 when None
    One(Option<Cow<'g, Guess>>),
    /// several points, the first the previous step's best, and the skeleton of W it built
    Several(Handover),
}

/// What a method runs with: the problem as stored, the settings, the inner solvers.
pub(crate) struct Ctx<'s, 'a> {
    pub(crate) form: &'s Form<'a>,
    pub(crate) settings: &'s Settings,
    pub(crate) solvers: &'s mut InnerSolvers,
}

/// A method of the plan: runs from `start` with `budget` until its own stopping rules, the
/// budget or `deadline`. None: it does not apply to this problem (nothing run).
pub(crate) trait Method {
    fn run(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        start: StartPoint<'_>,
        budget: Budget,
        deadline: Deadline,
    ) -> Result<Option<Outcome>, SolveError>;
}

/// The start of a step: the caller's `guess` ([`Start::Caller`]), r = 0 ([`Start::Cold`]),
/// the best point and run end points of the step before ([`Start::PreviousBest`], its
/// handover taken), or its last iterate ([`Start::PreviousLast`]; the caller's guess when that
/// is not finite). None when the start needs a step before that did not run.
pub(crate) fn start_point<'g>(
    start: Start,
    guess: Option<&'g Guess>,
    previous: Option<&mut Outcome>,
) -> Option<StartPoint<'g>> {
    match start {
        Start::Caller => Some(StartPoint::One(guess.map(Cow::Borrowed))),
        Start::Cold => Some(StartPoint::One(None)),
        Start::PreviousBest => {
            let previous = previous?;
            let first = match &previous.best {
                Some(best) if best.merit() < previous.last.error_or_balance() => best.r.clone(),
                _ => previous.last.r.clone(),
            };
            let handover = previous.handover.take()?;
            let mut points = vec![first];
            points.extend(handover.points);
            Some(StartPoint::Several(Handover {
                points,
                skeleton: handover.skeleton,
            }))
        }
        Start::PreviousLast => {
            let previous = previous?;
            let last = &previous.last;
            Some(StartPoint::One(if last.r.iter().all(|x| x.is_finite()) {
                Some(Cow::Owned(Guess {
                    r: last.r.clone(),
                    v: last.verdict.v.clone(),
                }))
            } else {
                guess.map(Cow::Borrowed)
            }))
        }
    }
}

/// What a solve does after a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Checkpoint {
    /// run the next step
    Continue,
    /// return (the lowest-error point of all steps when this one did not converge)
    Stop,
}

/// The termination of a solve, in one place: after a step with `outcome`, stop when it
/// converged, when `deadline` passed, when no step follows, or when the next step goes on
/// from this one's last iterate (the fallback) and the status is not one it can improve (a
/// cap, a stall, an inner or numerical failure).
pub(crate) fn checkpoint(outcome: &Outcome, next: Option<&Step>, deadline: Deadline) -> Checkpoint {
    let handover = matches!(
        outcome.status,
        Status::MaxIterations | Status::Stalled | Status::InnerFailure | Status::NumericalError
    );
    let stop = match next {
        _ if outcome.converged() || deadline.passed() => true,
        None => true,
        Some(step) => step.start == Start::PreviousLast && !handover,
    };
    if stop {
        Checkpoint::Stop
    } else {
        Checkpoint::Continue
    }
}
