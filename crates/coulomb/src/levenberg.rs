//! Levenberg–Marquardt on the Alart–Curnier map: the end game for rigid, rank-deficient
//! problems (issue #11 item 4; measurements in docs/rigid.md).
//!
//! With a factor ρᵢ > 0 per contact, Coulomb's law (2.9) at contact i holds exactly when the
//! Alart–Curnier map (the paper's reference [3]) vanishes:
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

use crate::deadline::Deadline;
use crate::linalg::normal::{Normal, NormalPattern};
use crate::linalg::pattern_lu::JacobianPattern;
use crate::problem::LocalProblem;
use crate::settings::LmParams;

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

/// x projected onto L = Π K_μᵢ.
pub(crate) fn projected(p: &LocalProblem, x: &[f64]) -> Vec<f64> {
    let mut y = x.to_vec();
    crate::cone::project_product(p.dim, &p.mu, &mut y);
    y
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_problems::problem;

    #[test]
    fn levenberg_marquardt_solves_a_regular_problem_from_zero() {
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
    #[test]
    fn the_escapes_solve_a_rank_deficient_problem_where_newton_stalls() {
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
    #[test]
    fn a_point_outside_the_cones_is_judged_and_returned_as_its_projection() {
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
    #[test]
    fn a_segment_counts_from_its_first_taken_step() {
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

    #[test]
    fn bad_sizes_and_caps_give_typed_statuses() {
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

    /// A stage whose fixed point crawls (one APGD iteration per inner solve) and whose Newton
    /// budget is one step: without the LM end game it ends at its iteration cap; with it, it
    /// converges, and the reported error is the one recomputed from r on the stored W. A run
    /// that converges without spending its Newton budget is unchanged.
    #[test]
    fn a_stage_hands_its_stall_to_the_lm_end_game() {
        use crate::settings::{InnerKind, OuterKind, Settings};
        let crawl = Settings {
            max_inner: 1,
            newton_steps: 1,
            newton_start: 1.0,
            max_outer: 60,
            ..Settings::method(InnerKind::Apgd, OuterKind::FixedPoint)
        };
        let mut crawl = crawl;
        crawl.tuning.lm.start = 1.0;
        let mut off = crawl.clone();
        off.tuning.lm.max_steps = 0;
        let p = problem(6, 2811, 0.0, 0.0);
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
        let p = problem(6, 2902, 0.0, 0.0);
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
