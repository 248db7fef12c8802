//! Levenberg–Marquardt on the Alart–Curnier map: the end game for rigid, rank-deficient
//! problems (issue #11 item 4; measurements in docs/rigid.md).
//!
//! With a factor ρᵢ > 0 per contact, Coulomb's law (2.9) at contact i holds exactly when the
//! Alart–Curnier map (the paper's reference \[3\]) vanishes:
//!
//! ```text
//!     Φⁱ_ρ(r) = rⁱ − P_μ(yⁱ),     yⁱ = rⁱ − ρᵢ uⁱ,     u = W r + q,
//!     P_μ(y) = (max(0, y_N), projection of y_T onto the disc of radius μ max(0, y_N)).
//! ```
//!
//! Every ρ > 0 has the same zeros (the solutions of (2.10) in local form), but not the same
//! merit ½‖Φ_ρ‖²: its generalized Jacobian is
//!
//! ```text
//!     J = I − D + ρ D W,     D = blockdiag ∂P_μ(yⁱ),
//! ```
//!
//! singular where contacts stick when W is (more contact unknowns than degrees of freedom:
//! rigid piles and walls), so a monotone method (the semismooth Newton end game of
//! [`crate::newton`], Levenberg–Marquardt) can stop at a point where JᵀΦ ≈ 0 but Φ ≠ 0. This
//! end game takes Levenberg–Marquardt steps (JᵀJ + λI) δ = −JᵀΦ, λ = c min(‖Φ‖/‖r‖, 1), with
//! the trust-region update of c, in segments of [`LmParams::segment_steps`] steps counted from
//! the segment's first taken step (the rejections that open a segment only raise c; at most
//! [`LmParams::max_rejections`] in a row); a segment that
//! does not lower the error of docs/error.md enough is followed by an escape from the
//! stationary point: a watchdog (the next [`LmParams::watchdog_steps`] LM steps are taken
//! whatever the merit says, as Siconos' NSN takes the full step when its line search fails)
//! or a switch of every ρᵢ to the next factor of [`LmParams::rho_factors`] (the pieces of Φ_ρ
//! and the stationary points of its merit move, r and the zeros stay). The iterates need not
//! lie in the cones: each is judged as its projection onto L = Π K_μᵢ, and the projection of
//! lowest error (on the problem given, W as stored) is returned — the point a caller's verdict
//! on the stored problem sees.
//!
//! Its loop is its own, not the Newton driver `newton::drive` of the other
//! Newton-type methods: a step δ is taken or rejected whole, on the gain ratio (actual over
//! predicted decrease of ‖Φ_ρ‖², [`LmParams::accept_ratio`]) that also updates c, and never
//! backtracked along δ by the Armijo search (`line_search::armijo`); the watchdog
//! takes steps whatever the merit says.

use crate::deadline::Deadline;
use crate::linalg::normal::{Normal, NormalPattern};
use crate::linalg::pattern_lu::JacobianPattern;
use crate::problem::{projected, LocalProblem};

/// Parameters of the Levenberg–Marquardt end game on the Alart–Curnier map
/// ([`crate::levenberg`]), the finish for rigid, rank-deficient problems on which the
/// semismooth Newton end game stops at a stationary point (docs/rigid.md). A stage runs it
/// from its best iterate once the Newton end game has spent its whole budget
/// ([`crate::settings::MethodParams::newton_steps`]) without converging, the fixed point stagnates (see
/// [`crate::newton::NewtonParams::stagnation`]) and the error is ≤ `start`, and again whenever the error has dropped below `retry` times
/// the lowest error of the previous run; `max_steps = 0` turns it off.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LmParams {
    /// cap on LM steps (factorizations of JᵀJ + λI) of all runs of a stage; 0: no LM end game
    pub max_steps: usize,
    /// the end game starts only from an error (docs/error.md) ≤ this; ≥ 0
    /// (docs/tuning.md, `tuning.lm`)
    pub start: f64,
    /// a run stops (stalled) when its lowest error has not dropped below `stall_gain` times
    /// its value `stall_segments` segments earlier; ≥ 1
    pub stall_segments: usize,
    /// see `stall_segments`; in (0, 1]
    pub stall_gain: f64,
    /// the end game runs again once the error is below `retry` times the lowest error of its
    /// previous run; in (0, 1]
    pub retry: f64,
    /// a run that does not converge replaces the stage's iterate only if it lowered the error
    /// to at most `keep_gain` times its starting value; in (0, 1]
    pub keep_gain: f64,
    /// LM steps per segment; a segment that does not lower the error to `segment_gain` times
    /// its starting value is followed by an escape; ≥ 1
    pub segment_steps: usize,
    /// see `segment_steps`; in (0, 1]
    pub segment_gain: f64,
    /// a segment's `segment_steps` count from its first taken step (the rejected steps that
    /// open it only raise the damping factor, ×4 each); this many rejected steps in a row end
    /// a segment on their own; ≥ 1
    pub max_rejections: usize,
    /// a watchdog escape takes this many LM steps whatever the merit says (non-monotone;
    /// the best r is kept); 0: no watchdog, every escape switches ρ
    pub watchdog_steps: usize,
    /// watchdog escapes between two switches of ρ (the escapes cycle: this many watchdogs,
    /// then one switch)
    pub watchdogs_per_switch: usize,
    /// ρᵢ = factor / ‖Wᵢᵢ‖_F, the factor taken in turn from this list at each switch; each
    /// factor > 0 (the first one is used first)
    pub rho_factors: [f64; 7],
    /// first damping factor c: λ = c · min(‖Φ‖ / ‖r‖, 1); > 0
    pub damping: f64,
    /// the damping factor is never lowered below this; > 0
    pub damping_floor: f64,
    /// damping factor after a watchdog escape; > 0
    pub escape_damping: f64,
    /// a step is accepted when ‖Φ‖ decreases and (actual / predicted decrease of ‖Φ‖²) is
    /// above this; in [0, 1)
    pub accept_ratio: f64,
    /// skip the end game when JᵀJ has more stored entries than this (memory and time of its
    /// Cholesky factorization); ≥ 1
    pub max_normal_nonzeros: usize,
}

impl Default for LmParams {
    fn default() -> Self {
        Self {
            max_steps: 400,
            start: 2e-5,
            stall_segments: 6,
            stall_gain: 0.5,
            retry: 0.1,
            keep_gain: 0.5,
            segment_steps: 8,
            segment_gain: 0.7,
            max_rejections: 12,
            watchdog_steps: 2,
            watchdogs_per_switch: 1,
            rho_factors: [1.0, 0.1, 10.0, 0.3, 3.0, 0.03, 30.0],
            damping: 1e-2,
            damping_floor: 1e-8,
            escape_damping: 1e-6,
            accept_ratio: 1e-4,
            max_normal_nonzeros: 40_000_000,
        }
    }
}

impl LmParams {
    pub(crate) fn validate(&self) -> Result<(), String> {
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if self.segment_steps == 0
            || self.stall_segments == 0
            || self.max_rejections == 0
            || self.max_normal_nonzeros == 0
        {
            return Err(
                "tuning.lm: segment_steps, stall_segments, max_rejections and max_normal_nonzeros must be ≥ 1"
                    .into(),
            );
        }
        let fraction = |x: f64| positive(x) && x <= 1.0;
        if ![
            self.segment_gain,
            self.stall_gain,
            self.retry,
            self.keep_gain,
        ]
        .into_iter()
        .all(fraction)
        {
            return Err(
                "tuning.lm: segment_gain, stall_gain, retry, keep_gain must be in (0, 1]".into(),
            );
        }
        if !(self.rho_factors.iter().all(|&f| positive(f))
            && positive(self.damping)
            && positive(self.damping_floor)
            && positive(self.escape_damping))
        {
            return Err("tuning.lm: rho factors and damping factors must be positive".into());
        }
        if !(self.start.is_finite() && self.start >= 0.0) {
            return Err("tuning.lm.start must be finite and ≥ 0".into());
        }
        if !(self.accept_ratio.is_finite() && (0.0..1.0).contains(&self.accept_ratio)) {
            return Err("tuning.lm.accept_ratio must be in [0, 1)".into());
        }
        Ok(())
    }
}

/// Why [`solve`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LmStatus {
    /// the error of docs/error.md is ≤ the target
    Reached,
    /// [`LmParams::max_steps`] steps were taken above the target
    MaxSteps,
    /// the deadline passed
    TimeLimit,
    /// the lowest error did not drop below [`LmParams::stall_gain`] times its value
    /// [`LmParams::stall_segments`] segments earlier
    Stalled,
    /// JᵀJ would have more than [`LmParams::max_normal_nonzeros`] entries, or its symbolic
    /// factorization failed: no step taken
    TooLarge,
    /// the sizes of the problem and r disagree, or r is not finite: no step taken
    Inconsistent,
}

/// The outcome of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmReport {
    /// how it stopped
    pub status: LmStatus,
    /// LM steps (factorizations of JᵀJ + λI), accepted or not
    pub steps: usize,
    /// watchdog escapes
    pub watchdogs: usize,
    /// switches of ρ
    pub switches: usize,
    /// the error of docs/error.md at the returned r (W r + q recomputed)
    pub error: f64,
}

/// Φ_ρ(r) into `g` and the blocks of D = ∂P_μ(y) (row-major d × d per contact) into
/// `dblocks`, for u = W r + q given; returns ‖Φ_ρ‖.
pub(crate) fn alart_curnier(
    dim: usize,
    mu: &[f64],
    rho: &[f64],
    r: &[f64],
    u: &[f64],
    g: &mut [f64],
    dblocks: &mut [f64],
) -> f64 {
    let d = dim;
    for (i, &mu) in mu.iter().enumerate() {
        let at = i * d;
        let dj = &mut dblocks[i * d * d..(i + 1) * d * d];
        dj.iter_mut().for_each(|x| *x = 0.0);
        let mut y = [0.0; 3];
        for k in 0..d {
            y[k] = r[at + k] - rho[i] * u[at + k];
        }
        let pn = y[0].max(0.0);
        if y[0] > 0.0 {
            dj[0] = 1.0;
        }
        let t = y[1..d].iter().map(|x| x * x).sum::<f64>().sqrt();
        let radius = mu * pn;
        let mut pt = [0.0; 2];
        if t <= radius {
            for k in 1..d {
                pt[k - 1] = y[k];
                dj[k * d + k] = 1.0;
            }
        } else if t > 0.0 {
            // P_T = radius ŷ, ŷ = y_T / t: ∂/∂y_T = (radius / t)(I − ŷŷᵀ), ∂/∂y_N = μ ŷ
            let s = radius / t;
            for a in 1..d {
                pt[a - 1] = s * y[a];
                for b in 1..d {
                    let e = if a == b { 1.0 } else { 0.0 };
                    dj[a * d + b] = s * (e - y[a] * y[b] / (t * t));
                }
                if y[0] > 0.0 {
                    dj[a * d] = mu * y[a] / t;
                }
            }
        }
        g[at] = r[at] - pn;
        for k in 1..d {
            g[at + k] = r[at + k] - pt[k - 1];
        }
    }
    crate::law::norm(g)
}

/// ρᵢ = 1 / ‖Wᵢᵢ‖_F (1 where the diagonal block is zero or not finite).
pub(crate) fn base_rho(p: &LocalProblem) -> Vec<f64> {
    let d = p.dim;
    let mut sq = vec![0.0; p.mu.len()];
    for (i, j, v) in p.w.triplets() {
        if i / d == j / d {
            sq[i / d] += v * v;
        }
    }
    sq.iter()
        .map(|&s| {
            if s > 0.0 && s.is_finite() {
                1.0 / s.sqrt()
            } else {
                1.0
            }
        })
        .collect()
}

/// Where the segments of [`solve`] end: after [`LmParams::segment_steps`] steps counted from
/// the segment's first taken step (the rejected steps that open a segment only raise the
/// damping: the trust region's search for the radius of a useful step), or after
/// [`LmParams::max_rejections`] rejected steps in a row.
struct SegmentClock {
    counted: usize,
    rejections: usize,
    steps: usize,
    max_rejections: usize,
}

impl SegmentClock {
    fn new(params: &LmParams) -> Self {
        Self {
            counted: 0,
            rejections: 0,
            steps: params.segment_steps,
            max_rejections: params.max_rejections,
        }
    }

    /// Records one step, taken or rejected; true when the segment ends with it.
    fn tick(&mut self, taken: bool) -> bool {
        if taken {
            self.rejections = 0;
            self.counted += 1;
        } else {
            self.rejections += 1;
            if self.counted > 0 {
                self.counted += 1;
            }
        }
        let end = self.counted >= self.steps || self.rejections >= self.max_rejections;
        if end {
            (self.counted, self.rejections) = (0, 0);
        }
        end
    }
}

/// Levenberg–Marquardt with watchdog and ρ switching (module docs) on the local problem `p`
/// from `r` (overwritten by the projection onto L = Π K_μᵢ of the iterate whose projection has
/// the lowest error), until the error of docs/error.md at that projection
/// (W r + q recomputed from the W given, exactly as stored) is ≤ `target`, at most
/// [`LmParams::max_steps`] steps, or the deadline (checked before each step).
pub fn solve(
    p: &LocalProblem,
    r: &mut [f64],
    target: f64,
    params: &LmParams,
    deadline: Deadline,
) -> LmReport {
    let (d, m) = (p.dim, r.len());
    let consistent = p.fits(r) && r.iter().all(|x| x.is_finite());
    let mut report = LmReport {
        status: LmStatus::Inconsistent,
        steps: 0,
        watchdogs: 0,
        switches: 0,
        error: f64::NAN,
    };
    if !consistent {
        return report;
    }
    // the iterates of LM need not lie in the cones: each is judged, and returned, as its
    // projection onto L (what a solver's verdict on the stored problem sees)
    let error_of = |x: &[f64]| p.error(&projected(p, x)).error;
    crate::cone::project_product(d, &p.mu, r);
    let mut best_err = error_of(r);
    report.error = best_err;
    if best_err <= target {
        report.status = LmStatus::Reached;
        return report;
    }
    let jac = JacobianPattern::without_lu(p);
    let Some(normal) = NormalPattern::new(&jac, d, params.max_normal_nonzeros) else {
        report.status = LmStatus::TooLarge;
        return report;
    };
    let mut normal = Normal::new(&jac, normal, m);
    let base = base_rho(p);
    let nb = p.mu.len() * d * d;
    let (mut g, mut dbl) = (vec![0.0; m], vec![0.0; nb]);
    let (mut g2, mut dbl2) = (vec![0.0; m], vec![0.0; nb]);
    let mut blocks = vec![0.0; nb];
    let (mut jv, mut wcol) = (Vec::new(), vec![0.0; m]);
    let mut x = r.to_vec();
    let mut factor = 0;
    let mut rho: Vec<f64> = base.iter().map(|b| b * params.rho_factors[0]).collect();
    let mut damping = params.damping;
    let mut forced: usize = 0;
    let mut u = p.velocity(&x);
    let mut phi = alart_curnier(d, &p.mu, &rho, &x, &u, &mut g, &mut dbl);
    let mut segment_start = best_err;
    let mut clock = SegmentClock::new(params);
    let mut escapes = 0;
    // the lowest error at the end of each segment
    let mut segment_best = vec![best_err];
    report.status = loop {
        if best_err <= target {
            break LmStatus::Reached;
        }
        if report.steps >= params.max_steps {
            break LmStatus::MaxSteps;
        }
        if deadline.passed() {
            break LmStatus::TimeLimit;
        }
        report.steps += 1;
        let mut accepted = false;
        // J = I − D + (ρ D) W
        for (i, &ri) in rho.iter().enumerate() {
            for k in i * d * d..(i + 1) * d * d {
                blocks[k] = ri * dbl[k];
            }
        }
        jac.fill(p, &dbl, &blocks, &mut wcol, &mut jv);
        let xn = crate::law::norm(&x).max(f64::MIN_POSITIVE);
        let lambda = damping * (phi / xn).min(1.0);
        match normal.direction(&jv, lambda, &g) {
            None => damping *= 10.0,
            Some(delta) => {
                // predicted ‖Φ‖² decrease: ‖Φ‖² − ‖Φ + J δ‖²
                let mut jd = g.clone();
                for (c, &dc) in delta.iter().enumerate() {
                    for k in jac.col_ptr[c]..jac.col_ptr[c + 1] {
                        jd[jac.row_idx[k]] += jv[k] * dc;
                    }
                }
                let pred = phi * phi - jd.iter().map(|v| v * v).sum::<f64>();
                let trial: Vec<f64> = x.iter().zip(&delta).map(|(a, b)| a + b).collect();
                let u_trial = p.velocity(&trial);
                let phi2 = alart_curnier(d, &p.mu, &rho, &trial, &u_trial, &mut g2, &mut dbl2);
                let ratio = (phi * phi - phi2 * phi2) / pred.max(f64::MIN_POSITIVE);
                let take =
                    phi2.is_finite() && (forced > 0 || (ratio > params.accept_ratio && phi2 < phi));
                forced = forced.saturating_sub(1);
                if take {
                    accepted = true;
                    x = trial;
                    u = u_trial;
                    std::mem::swap(&mut g, &mut g2);
                    std::mem::swap(&mut dbl, &mut dbl2);
                    phi = phi2;
                    if ratio > 0.75 {
                        damping = (damping / 4.0).max(params.damping_floor);
                    }
                    let xp = projected(p, &x);
                    let e = if xp == x {
                        crate::law::error_measure(d, &p.mu, &x, &u, crate::law::norm(&p.q)).error
                    } else {
                        p.error(&xp).error
                    };
                    if e < best_err {
                        best_err = e;
                        r.copy_from_slice(&xp);
                    }
                } else {
                    damping *= 4.0;
                }
            }
        }
        if !clock.tick(accepted) {
            continue;
        }
        // end of a segment: escape from a stall
        let now = error_of(&x);
        if now > params.segment_gain * segment_start {
            let period = params.watchdogs_per_switch + 1;
            let watchdog =
                params.watchdog_steps > 0 && escapes % period < params.watchdogs_per_switch;
            escapes += 1;
            if watchdog {
                forced = params.watchdog_steps;
                damping = params.escape_damping;
                report.watchdogs += 1;
            } else {
                factor = (factor + 1) % params.rho_factors.len();
                rho = base
                    .iter()
                    .map(|b| b * params.rho_factors[factor])
                    .collect();
                damping = params.damping;
                phi = alart_curnier(d, &p.mu, &rho, &x, &u, &mut g, &mut dbl);
                report.switches += 1;
            }
        }
        segment_start = now;
        segment_best.push(best_err);
        let n = segment_best.len();
        if n > params.stall_segments
            && best_err > params.stall_gain * segment_best[n - 1 - params.stall_segments]
        {
            break LmStatus::Stalled;
        }
    };
    report.error = best_err;
    report
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use crate::test_problems::problem;

    pub fn levenberg_marquardt_solves_a_regular_problem_from_zero() {
        let p = problem(5, 3, 0.5, 0.0);
        let mut r = vec![0.0; 15];
        let out = solve(&p, &mut r, 1e-12, &LmParams::default(), Deadline::NEVER);
        let err = p.error(&r).error;
        assert!(err <= 1e-12, "error {err:.3e} after {out:?}");
        assert_eq!((out.status, out.error), (LmStatus::Reached, err));
    }

    /// Six contacts, W of rank 9 < 18: the Newton end game on the natural map stops (slow
    /// steps) far from the solution, Levenberg–Marquardt on the Alart–Curnier map needs its
    /// escapes (watchdog and ρ switch) and reaches 1e-8; the reported error is the one
    /// recomputed from the returned r on the W given, also when W is not symmetric.
    pub fn the_escapes_solve_a_rank_deficient_problem_where_newton_stalls() {
        for skew in [0.0, 1e-3] {
            let p = problem(6, 2811, 0.0, skew);
            let q_norm = crate::law::norm(&p.q);
            let mut r = vec![0.0; 18];
            let newton = crate::newton::polish(&p, &mut r, 0.5e-8 * q_norm, 200, Deadline::NEVER);
            let stalled = p.error(&r).error;
            assert!(
                stalled > 1e-4,
                "skew {skew}: Newton reached {stalled:.2e} ({newton:?})"
            );
            let mut r = vec![0.0; 18];
            let out = solve(&p, &mut r, 1e-8, &LmParams::default(), Deadline::NEVER);
            let u = p.velocity(&r);
            let err = crate::law::error_measure(3, &p.mu, &r, &u, crate::law::norm(&p.q)).error;
            assert!(err <= 1e-8, "skew {skew}: error {err:.3e} after {out:?}");
            assert_eq!((out.status, out.error), (LmStatus::Reached, err));
            assert!(out.watchdogs + out.switches >= 1, "{out:?}");
            // without escapes the same LM stops at a stationary point of ‖Φ‖²
            let plain = LmParams {
                watchdog_steps: 0,
                rho_factors: [1.0; 7],
                ..LmParams::default()
            };
            let mut r = vec![0.0; 18];
            let out = solve(&p, &mut r, 1e-8, &plain, Deadline::NEVER);
            assert!(
                out.error > 1e-8 && out.status != LmStatus::Reached,
                "{out:?}"
            );
        }
    }

    /// LM's iterates need not lie in the cones; what it returns, and the error it reports, is
    /// the projection onto L = Π K_μᵢ, so that a caller's verdict on the stored problem (which
    /// projects a guess) agrees with it.
    pub fn a_point_outside_the_cones_is_judged_and_returned_as_its_projection() {
        let p = problem(6, 2811, 0.0, 1e-3);
        let mut r = vec![0.0; 18];
        let out = solve(&p, &mut r, 1e-8, &LmParams::default(), Deadline::NEVER);
        assert_eq!(out.status, LmStatus::Reached, "{out:?}");
        // every returned block is in its cone, and the error is the one recomputed there
        for (ri, &mu) in r.chunks(3).zip(&p.mu) {
            let tol = 1e-12 * (1.0 + crate::law::norm(ri));
            assert!(crate::cone::contains(mu, ri, tol), "{ri:?} outside K_{mu}");
        }
        assert_eq!(out.error, p.error(&r).error);
        // the solution pushed outward: tangential impulses beyond μ r_N
        let mut outside = r.clone();
        for (ri, &mu) in outside.chunks_mut(3).zip(&p.mu) {
            (ri[1], ri[2]) = (1.1 * mu * ri[0] + 1e-3, 0.0);
        }
        let mut projected = outside.clone();
        crate::cone::project_product(3, &p.mu, &mut projected);
        assert_ne!(projected, outside);
        // a target met at the start: no step, the start is returned projected, with its error
        let mut start = outside.clone();
        let out = solve(&p, &mut start, 1.0, &LmParams::default(), Deadline::NEVER);
        assert_eq!((out.status, out.steps), (LmStatus::Reached, 0));
        assert_eq!(start, projected);
        assert_eq!(out.error, p.error(&projected).error);
    }

    /// A segment counts from its first taken step: the rejections that open it (the damping
    /// still growing) do not count, up to `max_rejections` in a row; once a step is taken,
    /// taken and rejected steps count alike.
    pub fn a_segment_counts_from_its_first_taken_step() {
        let params = LmParams {
            segment_steps: 3,
            max_rejections: 5,
            ..LmParams::default()
        };
        let ends = |steps: &[bool]| -> Vec<usize> {
            let mut clock = SegmentClock::new(&params);
            (0..steps.len()).filter(|&k| clock.tick(steps[k])).collect()
        };
        let (t, f) = (true, false);
        assert_eq!(ends(&[t, t, t, t, t, t]), [2, 5]);
        // four rejections open the segment, then three taken steps end it
        assert_eq!(ends(&[f, f, f, f, t, t, t]), [6]);
        // after a taken step, rejections count
        assert_eq!(ends(&[t, f, f, t, t, t]), [2, 5]);
        // five rejections in a row end a segment on their own, wherever they fall
        assert_eq!(ends(&[f, f, f, f, f, f, t, t, t]), [4, 8]);
    }

    pub fn bad_sizes_and_caps_give_typed_statuses() {
        let p = problem(3, 5, 0.0, 0.0);
        let mut short = vec![0.0; 8];
        let out = solve(&p, &mut short, 1e-8, &LmParams::default(), Deadline::NEVER);
        assert_eq!((out.status, out.steps), (LmStatus::Inconsistent, 0));
        let mut r = vec![f64::NAN; 9];
        let out = solve(&p, &mut r, 1e-8, &LmParams::default(), Deadline::NEVER);
        assert_eq!(out.status, LmStatus::Inconsistent);
        let tiny = LmParams {
            max_normal_nonzeros: 10,
            ..LmParams::default()
        };
        let mut r = vec![0.0; 9];
        let out = solve(&p, &mut r, 1e-8, &tiny, Deadline::NEVER);
        assert_eq!((out.status, out.steps), (LmStatus::TooLarge, 0));
        let one = LmParams {
            max_steps: 1,
            ..LmParams::default()
        };
        let out = solve(&p, &mut r, 0.0, &one, Deadline::NEVER);
        assert_eq!((out.status, out.steps), (LmStatus::MaxSteps, 1));
        let past = Deadline::from(std::time::Instant::now());
        let out = solve(&p, &mut r, 0.0, &LmParams::default(), past);
        assert_eq!((out.status, out.steps), (LmStatus::TimeLimit, 0));
    }
}
