//! The proximal point on Coulomb's law (2.9)–(2.10), local form: r_{k+1} solves the law for
//! the regularized data (W + σ_k I, q − σ_k r_k), i.e. u = W r + q + σ_k (r − r_k), by a
//! semismooth Newton method on the Alart–Curnier map
//! Φ_ρ(r) = r − P_μ(r − ρ u) (P_μ: projection onto the cone K_μᵢ of each contact, (2.9)),
//! J = I − D + ρ D (W + σ I) with D = ∂P_μ, solved by a sparse LU of J (W as stored: J is
//! not symmetric anyway). A regularized problem counts as solved once ‖Φ_ρ‖ is
//! [`ProxParams::inner_ratio`] times below its value at the centre r_k. σ follows the rule of
//! Siconos' PROX solver: σ_k = `sigma_factor` · err(r_k) · max Wᵢᵢ (err of docs/error.md on
//! the stored problem, so σ → 0 as the iterates converge) after a solved step; after one not
//! solved within [`ProxParams::inner_steps`] Newton steps, the centre stays and σ grows by
//! [`ProxParams::sigma_growth`]. A zero of the regularized map at r_{k+1} = r_k is a solution
//! of the law itself.
//!
//! The Newton steps on Φ_ρ are those of the crate's one semismooth Newton driver
//! (`newton::drive_from`, as the end game on (3.9)): J δ = −Φ_ρ, the Armijo search on ‖Φ_ρ‖
//! (`line_search::armijo`, c = 1e-4, [`ProxParams::line_search_steps`] trials) and, where it
//! is exhausted, the full step δ (a non-monotone escape from a stationary point of the merit).
//!
//! It is an end game of the outer method ([`crate::outer::newton`]) on problems where the law
//! is far from monotone (granular heaps and drums, docs/rigid.md): after a Newton try that
//! did not converge, and after a stalled Levenberg–Marquardt run ([`crate::levenberg`]); the
//! regularization moves the kinks where LM's merit ½‖Φ_ρ‖² has stationary points that are
//! not zeros.
//!
//! Every iterate is judged as its projection onto L = Π K_μᵢ, and the best one is returned.

use crate::deadline::Deadline;
use crate::linalg::pattern_lu::JacobianPattern;
use crate::newton::{drive_from, NewtonRule, OnExhausted, SemismoothMap};
use crate::problem::LocalProblem;

/// The proximal-point end game ([`crate::proximal`]) of a stage. It runs (a) after a Newton
/// try of the end game that did not converge, from an error ≤ `try_start`, with a budget of
/// `max_steps` Newton steps (`capped_max_steps` after an inner solve at its iteration cap),
/// and again only once the error is below `retry` times the end of its last such run; (b)
/// after a Levenberg–Marquardt run of the stage that stalled, from LM's best point when that
/// error is ≤ `start`, with a budget of `max_steps` Newton steps.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ProxParams {
    /// cap on proximal steps per run; 0: no proximal end game
    pub max_outer: usize,
    /// semismooth Newton steps (sparse LU of J) per proximal step; ≥ 1
    pub inner_steps: usize,
    /// halvings of the Armijo search before the full Newton step is taken; ≥ 1
    pub line_search_steps: usize,
    /// σ = `sigma_factor` · err · max Wᵢᵢ after a regularized problem that was solved
    /// (Siconos' PROX rule: 5); > 0
    pub sigma_factor: f64,
    /// σ is multiplied by this after a regularized problem that was not solved within
    /// `inner_steps` (Siconos' PROX rule: 10); ≥ 1
    pub sigma_growth: f64,
    /// a regularized problem is solved once ‖Φ_ρ‖ is ≤ its value at the centre r_k divided
    /// by this (Siconos: the inner tolerance is the outer error / 10); > 1
    pub inner_ratio: f64,
    /// a run stops after this many proximal steps in a row without a lower error; ≥ 1
    pub stall_steps: usize,
    /// (b) starts only from an error ≤ this (LM's best point); ≥ 0 (docs/tuning.md, `tuning.prox`)
    pub start: f64,
    /// (a) starts only from an error ≤ this (LM's own start, [`crate::levenberg::LmParams::start`]); ≥ 0
    pub try_start: f64,
    /// a run takes at most this many Newton steps (sparse LU factorizations of J) in all its
    /// proximal steps, a budget in work so that the path does not depend on the machine's
    /// speed or load; ≥ 1 (docs/tuning.md, `tuning.prox`)
    pub max_steps: usize,
    /// the budget of (a) after an inner solve that hit its iteration cap (the fixed point does
    /// not solve its subproblems); ≥ 1 (docs/tuning.md, `tuning.prox`)
    pub capped_max_steps: usize,
    /// (a) runs again once the error is below `retry` times the lowest error of its previous
    /// run; in (0, 1]
    pub retry: f64,
}

impl Default for ProxParams {
    fn default() -> Self {
        Self {
            max_outer: 100,
            inner_steps: 20,
            line_search_steps: 30,
            sigma_factor: 5.0,
            sigma_growth: 10.0,
            inner_ratio: 10.0,
            stall_steps: 5,
            start: 1e-6,
            try_start: 2e-5,
            max_steps: PROX_MAX_STEPS,
            capped_max_steps: PROX_CAPPED_MAX_STEPS,
            retry: 0.1,
        }
    }
}

impl ProxParams {
    pub(crate) fn validate(&self) -> Result<(), String> {
        if self.inner_steps == 0 || self.line_search_steps == 0 || self.stall_steps == 0 {
            return Err(
                "tuning.prox: inner_steps, line_search_steps and stall_steps must be ≥ 1".into(),
            );
        }
        if !(self.sigma_factor.is_finite() && self.sigma_factor > 0.0) {
            return Err("tuning.prox.sigma_factor must be positive".into());
        }
        if !(self.sigma_growth.is_finite() && self.sigma_growth >= 1.0) {
            return Err("tuning.prox.sigma_growth must be finite and ≥ 1".into());
        }
        if !(self.inner_ratio.is_finite() && self.inner_ratio > 1.0) {
            return Err("tuning.prox.inner_ratio must be finite and > 1".into());
        }
        let level = |x: f64| x.is_finite() && x >= 0.0;
        if !level(self.start) || !level(self.try_start) {
            return Err("tuning.prox: start and try_start must be finite and ≥ 0".into());
        }
        if self.max_steps == 0 || self.capped_max_steps == 0 {
            return Err("tuning.prox: max_steps and capped_max_steps must be ≥ 1".into());
        }
        if !(self.retry > 0.0 && self.retry <= 1.0) {
            return Err("tuning.prox.retry must be in (0, 1]".into());
        }
        Ok(())
    }
}

/// The default of [`ProxParams::max_steps`] (docs/solver-core.md).
pub const PROX_MAX_STEPS: usize = 40;

/// The default of [`ProxParams::capped_max_steps`] (docs/solver-core.md).
pub const PROX_CAPPED_MAX_STEPS: usize = 200;

/// Armijo's constant c of the search on ‖Φ_ρ‖ ([`crate::line_search::armijo`]).
const SUFFICIENT_DECREASE: f64 = 1e-4;

/// Why [`solve`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProxStatus {
    /// the error of docs/error.md is ≤ the target
    Reached,
    /// [`ProxParams::max_outer`] proximal steps, or [`ProxParams::max_steps`] Newton steps,
    /// were taken above the target
    MaxSteps,
    /// the deadline passed
    TimeLimit,
    /// [`ProxParams::stall_steps`] proximal steps in a row did not lower the lowest error
    Stalled,
    /// the sizes of the problem and r disagree, r is not finite, or the symbolic LU of the
    /// pattern of J failed: no step taken
    Inconsistent,
}

/// The outcome of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProxReport {
    /// how it stopped
    pub status: ProxStatus,
    /// proximal steps (regularized problems solved)
    pub outer: usize,
    /// Newton steps (sparse LU factorizations of J) of all proximal steps
    pub steps: usize,
    /// proximal steps whose regularized problem was not solved within
    /// [`ProxParams::inner_steps`] (the centre stayed, σ grew)
    pub rejected: usize,
    /// the error of docs/error.md at the returned r (W r + q recomputed)
    pub error: f64,
}

/// Runs the proximal point from `r` (projected onto the cones first) until the error of
/// docs/error.md on the problem as stored is ≤ `target`, a cap, a stall or the deadline;
/// `r` becomes the lowest-error iterate (in the cones).
pub fn solve(
    p: &LocalProblem,
    r: &mut [f64],
    target: f64,
    params: &ProxParams,
    deadline: Deadline,
) -> ProxReport {
    let (d, m) = (p.dim, r.len());
    let consistent = p.fits(r) && r.iter().all(|x| x.is_finite());
    let mut report = ProxReport {
        status: ProxStatus::Inconsistent,
        outer: 0,
        steps: 0,
        rejected: 0,
        error: f64::NAN,
    };
    if !consistent {
        return report;
    }
    crate::cone::project_product(d, &p.mu, r);
    let mut best_err = p.error(r).error;
    report.error = best_err;
    if best_err <= target {
        report.status = ProxStatus::Reached;
        return report;
    }
    let Some(jac) = JacobianPattern::new(p) else {
        return report;
    };
    let nb = p.mu.len() * d * d;
    let mut map = RegularizedMap {
        p,
        jac,
        rho: crate::levenberg::base_rho(p),
        center: vec![0.0; m],
        sigma: 0.0,
        g: [vec![0.0; m], vec![0.0; m]],
        dbl: [vec![0.0; nb], vec![0.0; nb]],
        shifted: vec![0.0; nb],
        blocks: vec![0.0; nb],
        jv: Vec::new(),
        wcol: vec![0.0; m],
        factorizations: 0,
    };
    let w_max = p.w.diagonal().iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let mut x = r.to_vec();
    let mut error = best_err;
    let mut since_best = 0;
    let mut sigma = params.sigma_factor * error * w_max;
    report.status = loop {
        if best_err <= target {
            break ProxStatus::Reached;
        }
        if report.outer >= params.max_outer || report.steps >= params.max_steps {
            break ProxStatus::MaxSteps;
        }
        if deadline.passed() {
            break ProxStatus::TimeLimit;
        }
        if since_best >= params.stall_steps {
            break ProxStatus::Stalled;
        }
        report.outer += 1;
        map.center.copy_from_slice(&x);
        map.sigma = sigma;
        let center_error = error;
        let phi = map.eval_trial(&x);
        map.accept_trial();
        // the regularized problem is solved once ‖Φ‖ ≤ ‖Φ(centre)‖ / inner_ratio (at the
        // centre Φ of the regularized problem is that of the law itself): Newton on Φ with
        // Armijo on ‖Φ‖ and, when no step decreases it, the full step (a non-monotone escape
        // from a stationary point of the merit)
        let inner_target = phi / params.inner_ratio;
        let rule = NewtonRule {
            target: inner_target,
            max_steps: params
                .inner_steps
                .min(params.max_steps.saturating_sub(report.steps)),
            trials: params.line_search_steps,
            sufficient_decrease: SUFFICIENT_DECREASE,
            shift: None,
            on_exhausted: OnExhausted::FullStep,
            slow_steps: usize::MAX,
            slow_ratio: 1.0,
            deadline,
        };
        let factorizations = map.factorizations;
        let newton = drive_from(&mut map, &mut x, phi, &rule);
        report.steps += map.factorizations - factorizations;
        if !x.iter().all(|v| v.is_finite()) {
            x.copy_from_slice(r);
        }
        let mut solved = newton.residual <= inner_target;
        let y = crate::problem::projected(p, &x);
        error = p.error(&y).error;
        if error < best_err {
            best_err = error;
            r.copy_from_slice(&y);
            since_best = 0;
        } else {
            since_best += 1;
        }
        if !error.is_finite() {
            x.copy_from_slice(r);
            error = best_err;
            solved = false;
        } else if !solved {
            // a regularized problem that was not solved does not move the centre: its
            // Newton iterate can be far off (the full steps that escape a stationary point
            // of the merit), and the next try, with a larger σ, starts from the centre again
            x.copy_from_slice(&map.center);
            error = center_error;
            report.rejected += 1;
        }
        // σ follows the error after a solved regularized problem and grows after one that
        // was not solved (Siconos' PROX rule)
        sigma = if solved {
            params.sigma_factor * error * w_max
        } else {
            sigma * params.sigma_growth
        };
    };
    report.error = best_err;
    report
}

/// Φ_ρ(y) = y − P_μ(y − ρ u) of the law regularized at the centre c = r_k with σ = σ_k,
/// u = W y + q + σ (y − c), and its Jacobian J = I − D + ρ D (W + σ I), D = ∂P_μ, on W's
/// block pattern (a sparse LU; W as stored, J is not symmetric anyway); counts the Jacobians
/// it builds (one factorization each).
struct RegularizedMap<'a> {
    p: &'a LocalProblem,
    jac: JacobianPattern,
    /// ρᵢ of [`crate::levenberg::base_rho`]
    rho: Vec<f64>,
    center: Vec<f64>,
    sigma: f64,
    /// Φ_ρ and the D blocks: current and trial
    g: [Vec<f64>; 2],
    dbl: [Vec<f64>; 2],
    /// the diagonal blocks D − σ ρ D of I − (D − σ B) and B = ρ D, at the current point
    shifted: Vec<f64>,
    blocks: Vec<f64>,
    /// the values of J on its pattern
    jv: Vec<f64>,
    wcol: Vec<f64>,
    factorizations: usize,
}

impl SemismoothMap for RegularizedMap<'_> {
    fn eval_trial(&mut self, y: &[f64]) -> f64 {
        let p = self.p;
        let mut u = p.velocity(y);
        for (k, uk) in u.iter_mut().enumerate() {
            *uk += self.sigma * (y[k] - self.center[k]);
        }
        let (g, dbl) = (&mut self.g[1], &mut self.dbl[1]);
        crate::levenberg::alart_curnier(p.dim, &p.mu, &self.rho, y, &u, g, dbl)
    }

    fn accept_trial(&mut self) {
        self.g.swap(0, 1);
        self.dbl.swap(0, 1);
    }

    fn current(&self) -> &[f64] {
        &self.g[0]
    }

    fn build_jacobian(&mut self) {
        self.factorizations += 1;
        let (dd, sigma) = (self.p.dim * self.p.dim, self.sigma);
        // J = I − D + B (W + σ I), B = ρ D: the diagonal blocks of I − (D − σ B)
        let blocks = self.blocks.chunks_mut(dd).zip(self.shifted.chunks_mut(dd));
        for ((&ri, (b, shifted)), dbl) in self.rho.iter().zip(blocks).zip(self.dbl[0].chunks(dd)) {
            for ((bk, sk), &dk) in b.iter_mut().zip(shifted.iter_mut()).zip(dbl) {
                *bk = ri * dk;
                *sk = dk - sigma * *bk;
            }
        }
        self.jac.fill(
            self.p,
            &self.shifted,
            &self.blocks,
            &mut self.wcol,
            &mut self.jv,
        );
    }

    fn solve_shifted(&mut self, lambda: f64, rhs: &mut [f64]) -> Option<()> {
        if lambda == 0.0 {
            return self.jac.solve(&self.jv, rhs);
        }
        let mut shifted = self.jv.clone();
        self.jac.shift_diagonal(&mut shifted, lambda);
        self.jac.solve(&shifted, rhs)
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use crate::test_problems::problem;

    pub fn the_proximal_point_solves_a_rank_deficient_problem_and_reports_the_stored_error() {
        // rank-deficient W (more contact unknowns than rank), μ up to 1: from r = 0
        let mut solved = 0;
        for seed in 0..6 {
            let p = problem(12, seed, 0.0, 0.0);
            let mut r = vec![0.0; p.q.len()];
            let rep = solve(&p, &mut r, 1e-10, &ProxParams::default(), Deadline::NEVER);
            // the reported error is the one recomputed on the problem at the returned r,
            // which lies in the cones
            assert_eq!(rep.error, p.error(&r).error);
            for (c, mu) in r.chunks(3).zip(&p.mu) {
                let t = (c[1] * c[1] + c[2] * c[2]).sqrt();
                assert!(
                    t <= mu * c[0] * (1.0 + 1e-12) + 1e-300,
                    "{c:?} outside K_{mu}"
                );
            }
            if rep.status == ProxStatus::Reached {
                assert!(rep.error <= 1e-10);
                solved += 1;
            }
        }
        assert!(solved >= 4, "solved {solved} of 6");
    }

    pub fn a_regularized_problem_not_solved_leaves_the_centre_and_is_counted() {
        // one Newton step per proximal step and an unreachable inner ratio: no regularized
        // problem counts as solved, so every step is rejected (σ grows, the centre stays);
        // the run still returns its lowest-error point, in the cones, with its stored error
        let strict = ProxParams {
            inner_steps: 1,
            inner_ratio: 1e300,
            max_outer: 12,
            stall_steps: 12,
            ..ProxParams::default()
        };
        for seed in 0..4 {
            let p = problem(10, seed, 0.0, 0.0);
            let mut r = vec![0.0; p.q.len()];
            crate::cone::project_product(3, &p.mu, &mut r);
            let start = p.error(&r).error;
            let rep = solve(&p, &mut r, 1e-12, &strict, Deadline::NEVER);
            if rep.status == ProxStatus::Reached {
                continue;
            }
            assert!(rep.outer > 0);
            assert_eq!(rep.rejected, rep.outer, "{rep:?}");
            assert_eq!(rep.error, p.error(&r).error);
            assert!(rep.error <= start);
        }
        // with the defaults the same problems are solved with few or no rejections
        let p = problem(10, 0, 0.0, 0.0);
        let mut r = vec![0.0; p.q.len()];
        let rep = solve(&p, &mut r, 1e-10, &ProxParams::default(), Deadline::NEVER);
        assert!(rep.rejected < rep.outer.max(1), "{rep:?}");
    }

    pub fn bad_sizes_caps_and_deadlines_give_typed_statuses() {
        let p = problem(6, 1, 0.0, 0.0);
        let mut short = vec![0.0; 3];
        let rep = solve(
            &p,
            &mut short,
            1e-10,
            &ProxParams::default(),
            Deadline::NEVER,
        );
        assert_eq!(rep.status, ProxStatus::Inconsistent);
        let mut nan = vec![f64::NAN; p.q.len()];
        let rep = solve(&p, &mut nan, 1e-10, &ProxParams::default(), Deadline::NEVER);
        assert_eq!(rep.status, ProxStatus::Inconsistent);
        let mut r = vec![0.0; p.q.len()];
        let capped = ProxParams {
            max_outer: 0,
            ..ProxParams::default()
        };
        let rep = solve(&p, &mut r, 1e-30, &capped, Deadline::NEVER);
        assert_eq!(rep.status, ProxStatus::MaxSteps);
        assert_eq!(rep.outer, 0);
        let past = Deadline::after(std::time::Instant::now(), Some(std::time::Duration::ZERO));
        let rep = solve(&p, &mut r, 1e-30, &ProxParams::default(), past);
        assert_eq!(rep.status, ProxStatus::TimeLimit);
        assert!(rep.error.is_finite());
    }
}
