//! A primal–dual interior-point method on Coulomb's law (2.9) itself (issue #11 item 4:
//! rigid, rank-deficient problems; measurements in docs/rigid.md).
//!
//! With ũ = u + μ‖u_T‖e (§3) the law at contact i is the complementarity
//! K_μ ∋ rⁱ ⊥ ũⁱ ∈ K_μ*, which in the scaled coordinates
//!
//! ```text
//!     aⁱ = (μ r_N, r_T),     bⁱ = (ũ_N / μ, u_T),     u = W r + q,
//! ```
//!
//! reads L ∋ aⁱ ⊥ bⁱ ∈ L on the Lorentz (ice-cream) cone L = {x : ‖x̄‖ ≤ x₀} (aᵀb = rᵀũ).
//! The method follows the central path aⁱ ∘ bⁱ = κ e (Jordan product, e = (1, 0, 0)) from an
//! interior point to κ → 0, with b kept as an unknown (b − T ũ(r) = 0 is one of the Newton
//! equations, T = diag(1/μ, 1, 1)). A Newton step with Nesterov–Todd scaling Θ (Θ b = Θ⁻¹ a = λ)
//! solves
//!
//! ```text
//!     (W + blockdiag((T C)⁻¹ Θ⁻² S)) δr = (T C)⁻¹ (Θ⁻¹ ξ + f),
//!     S = diag(μ, 1, 1),  C = ∂ũ/∂u = I + μ e t̂ᵀ (t̂ = u_T / ‖u_T‖),  f = b − T ũ(r),
//! ```
//!
//! with W as stored. Where contacts stick and W is singular (more contact unknowns than
//! degrees of freedom), the semismooth Jacobians of the Newton and Levenberg–Marquardt end
//! games are singular; here the barrier term Θ⁻² is positive definite at every interior point,
//! so the matrix stays regular along the path (in the frictionless case W + SΘ⁻²S is
//! positive definite). Steps are Mehrotra predictor–corrector steps, cut to stay in the
//! interior. The matrix is factored once per step ([`Setup`]): by a sparse LU on the block
//! pattern of W; or, for a global problem with few degrees of freedom (rigid bodies), through
//! its Schur complement on M; or, for a local problem whose W has low rank, through the
//! skeleton of W ([`crate::linalg::skeleton`]), each solve refined on W as stored and redone by the
//! sparse LU when the refinement falls short. The iterate of lowest error (docs/error.md, W
//! as stored) is returned.

use crate::deadline::Deadline;
use crate::linalg::blocks::{apply_blocks, invert_small};
use crate::linalg::pattern_lu::{JacobianPattern, PatternLu};
use crate::linalg::skeleton::Skeleton;
use crate::problem::{GlobalProblem, LocalProblem};

/// The default of [`BarrierParams::max_work`] (docs/solver-core.md: how it was calibrated).
pub const BARRIER_MAX_WORK: usize = 150;

/// Newton steps of one run of the interior-point try: the default of
/// [`crate::settings::MethodParams::barrier_steps`].
pub const BARRIER_STEPS: usize = 150;

/// Parameters of the interior-point method on Coulomb's law ([`crate::barrier`]) and of its
/// try in the default policy ([`crate::Solver::solve`]): after the warm-up of a cold solve
/// (no guess) with every μ > 0 of a global problem with at most half as many degrees of
/// freedom as contact unknowns (at most `max_schur_dofs`: rigid bodies touching at several
/// points per face, where W is rank-deficient and the Newton systems are of the size of M),
/// or of a local problem with at most `max_skeleton_unknowns` contact unknowns whose W has a
/// skeleton of rank ≤ min(`max_schur_dofs`, `skeleton_rank_ratio` · m) ([`crate::linalg::skeleton`]),
/// before the main
/// method. A try runs the method along each path of `paths` in turn (at most
/// [`crate::settings::MethodParams::barrier_steps`] Newton steps each), finishes a run with the
/// Levenberg–Marquardt end game when its error is ≤ [`crate::levenberg::LmParams::start`], keeps the best point
/// and stops once it converges (or is within `handover` · tol where the method of multipliers
/// follows) or has spent its work budget `max_work` (Newton and LM steps: a budget in work, so
/// that the same input takes the same path on any machine and under any load).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct BarrierParams {
    /// a run stops when its lowest error has not improved for this many steps; ≥ 1
    pub stall_steps: usize,
    /// once its lowest error is ≤ `settle_below`, a run stops after this many steps in a row
    /// cut below `settle_alpha` of the Newton step (jammed near the end of its path: the try's
    /// Levenberg–Marquardt finish, [`crate::levenberg::LmParams::start`], takes over from
    /// there); ≥ 1 (measured: docs/tuning.md, `tuning.barrier.settle_steps`)
    pub settle_steps: usize,
    /// see `settle_steps`; ≥ 0 (0: never)
    pub settle_below: f64,
    /// see `settle_steps`; in (0, 1)
    pub settle_alpha: f64,
    /// fraction of the step to the boundary of the cones that is taken; in (0, 1)
    pub boundary_fraction: f64,
    /// (smoothing, recentring) of the runs of a try, in order: on hard rigid problems the
    /// method is sensitive to them and different runs end at different points
    pub paths: [PathParams; 4],
    /// the start b = T ũ(r₀) is moved into the interior of L with this margin, relative to
    /// its largest entry; > 0
    pub start_margin: f64,
    /// … and by at least this multiple of ‖q‖/√contacts; > 0
    pub start_floor: f64,
    /// a try takes at most this many steps in all (the interior point's Newton steps and
    /// its LM finishes' steps, each a factorization): no new run or finish starts once they
    /// are spent, and a run or finish gets at most what is left: a budget in work so that
    /// the path does not depend on the machine's speed or load; ≥ 1
    /// (docs/tuning.md, `tuning.barrier`)
    pub max_work: usize,
    /// the LM finish of a run of the try stops when its lowest error has not dropped below
    /// [`crate::levenberg::LmParams::stall_gain`] times its value this many segments earlier (the try's own
    /// [`crate::levenberg::LmParams::stall_segments`]); ≥ 1
    pub lm_stall_segments: usize,
    /// where the method of multipliers follows the try ([`crate::settings::MultiplierParams`]), the try ends
    /// after a run whose end point has an error ≤ `handover` · tol (from such points the
    /// multipliers converge in a few Newton steps, where the LM finish crawls); ≥ 0 (0: the
    /// try ends only at the tolerance) (docs/tuning.md, `tuning.barrier`)
    pub handover: f64,
    /// a global problem with at most this many degrees of freedom (and fewer than contact
    /// unknowns) has its Newton systems solved on M + H G⁻¹ Hᵀ (dense LU) instead of W + G;
    /// the policy's try needs it; ≥ 1. Also the largest rank of the skeleton of a local W
    pub max_schur_dofs: usize,
    /// the dense LU factorizations of these Newton systems (Schur complement, skeleton, and
    /// the method of multipliers' J, [`crate::linalg::dense`]) run on all threads from this size on,
    /// on one thread below it; ≥ 1 (docs/tuning.md, `tuning.barrier`)
    pub dense_parallel_dim: usize,
    /// a local problem with at most this many contact unknowns is probed for a skeleton
    /// W ≈ W[:, P] W[P, P]⁻¹ W[P, :] of rank ≤ min(`max_schur_dofs`, `skeleton_rank_ratio` · m)
    /// ([`crate::linalg::skeleton`]; cost ≤ m · rank² flops); if it has one, its Newton systems are
    /// solved through it (dense LU of the size of the rank) and the policy's try runs on it
    pub max_skeleton_unknowns: usize,
    /// see `max_skeleton_unknowns`; in (0, 1]. A pile of rigid bodies has rank W ≤ 6 per body
    /// (docs/tuning.md, `tuning.barrier`)
    pub skeleton_rank_ratio: f64,
    /// the pivoting of the skeleton stops when every remaining diagonal entry of
    /// ½(W + Wᵀ) is ≤ this multiple of max Wᵢᵢ (its numerical rank); in (0, 1)
    pub rank_tol: f64,
    /// a solve through the skeleton is refined on W as stored at most this many times …
    pub refine_steps: usize,
    /// … until its residual (max norm) is ≤ this multiple of the right-hand side's; else the
    /// step is solved by the sparse LU of W + G; > 0
    pub refine_tol: f64,
    /// after this many steps in a row solved by the sparse LU that way, a run no longer tries
    /// the skeleton (every solve of a W with a large antisymmetric part falls back); ≥ 1
    pub skeleton_strikes: usize,
}

impl Default for BarrierParams {
    fn default() -> Self {
        Self {
            stall_steps: 30,
            settle_steps: 5,
            settle_below: 1e-6,
            settle_alpha: 0.1,
            boundary_fraction: 0.99,
            paths: [
                PathParams {
                    smoothing: 0.1,
                    recentre: 0.05,
                },
                PathParams {
                    smoothing: 0.1,
                    recentre: 0.0,
                },
                PathParams {
                    smoothing: 0.3,
                    recentre: 0.0,
                },
                PathParams {
                    smoothing: 0.03,
                    recentre: 0.0,
                },
            ],
            start_margin: 1e-2,
            start_floor: 1e-3,
            max_work: BARRIER_MAX_WORK,
            lm_stall_segments: 2,
            handover: 10.0,
            max_schur_dofs: 1500,
            dense_parallel_dim: 1500,
            max_skeleton_unknowns: 4000,
            skeleton_rank_ratio: 0.6,
            rank_tol: 1e-10,
            refine_steps: 4,
            refine_tol: 1e-10,
            skeleton_strikes: 3,
        }
    }
}

impl BarrierParams {
    pub(crate) fn validate(&self) -> Result<(), String> {
        let fraction = |x: f64| x.is_finite() && x > 0.0 && x < 1.0;
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if self.stall_steps == 0
            || self.settle_steps == 0
            || self.max_schur_dofs == 0
            || self.dense_parallel_dim == 0
            || self.skeleton_strikes == 0
            || self.lm_stall_segments == 0
            || self.max_work == 0
        {
            return Err(
                "tuning.barrier: stall_steps, settle_steps, max_schur_dofs, \
                 dense_parallel_dim, skeleton_strikes, lm_stall_segments and max_work must be ≥ 1"
                    .into(),
            );
        }
        let paths_ok = self.paths.iter().all(|p| {
            p.smoothing.is_finite()
                && p.smoothing >= 0.0
                && p.recentre.is_finite()
                && (0.0..1.0).contains(&p.recentre)
        });
        let ok = fraction(self.boundary_fraction)
            && paths_ok
            && self.settle_below.is_finite()
            && self.settle_below >= 0.0
            && fraction(self.settle_alpha)
            && positive(self.start_margin)
            && positive(self.start_floor)
            && self.handover.is_finite()
            && self.handover >= 0.0
            && fraction(self.rank_tol)
            && positive(self.skeleton_rank_ratio)
            && self.skeleton_rank_ratio <= 1.0
            && positive(self.refine_tol);
        if !ok {
            return Err(format!(
                "tuning.barrier: a parameter is out of range: {self:?}"
            ));
        }
        Ok(())
    }
}

/// The two constants that shape the path of one run of [`solve`] (the policy tries several:
/// [`BarrierParams::paths`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PathParams {
    /// ‖u_T‖ is smoothed to √(‖u_T‖² + δᵢ²) with δᵢ = `smoothing` · κ / aᵢ₀ (κ = aᵀb /
    /// contacts, so δ → 0 along the path); ≥ 0
    pub smoothing: f64,
    /// after a step cut below this fraction of the Newton step, the next one is a pure
    /// centring step (σ = 1); in [0, 1)
    pub recentre: f64,
}

/// Why [`solve`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BarrierStatus {
    /// the error of docs/error.md is ≤ the target
    Reached,
    /// `max_steps` steps were taken above the target
    MaxSteps,
    /// the deadline passed
    TimeLimit,
    /// the lowest error did not improve for [`BarrierParams::stall_steps`] steps, or, once
    /// ≤ [`BarrierParams::settle_below`], [`BarrierParams::settle_steps`] steps in a row were
    /// cut below [`BarrierParams::settle_alpha`] of the Newton step
    Stalled,
    /// the LU factorization of the Newton matrix failed (also with a diagonal shift up to
    /// 1e-6 max Wᵢᵢ) or gave a non-finite direction, or no step along it stays inside the
    /// cones
    LinearSolve,
    /// a contact has μ = 0 (the scaled coordinates need μ > 0), there is no contact, the
    /// sizes disagree (also with the [`Setup`]'s problem), or the symbolic LU of the pattern
    /// of W failed: no step taken
    NotApplicable,
}

/// The outcome of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarrierReport {
    /// how it stopped
    pub status: BarrierStatus,
    /// Newton steps (LU factorizations)
    pub steps: usize,
    /// the error of docs/error.md at the returned r (W r + q recomputed)
    pub error: f64,
    /// the complementarity aᵀb / contacts at the last iterate
    pub gap: f64,
    /// steps whose Newton systems were solved by the sparse LU of W + G although the setup
    /// has a skeleton (its refinement fell short of [`BarrierParams::refine_tol`])
    pub exact_steps: usize,
}

/// x₀² − ‖x̄‖² (positive in the interior of L).
fn det(x: &[f64]) -> f64 {
    // (x₀ − ‖x̄‖)(x₀ + ‖x̄‖): no cancellation of the squares near the boundary
    let t = crate::law::norm(&x[1..]);
    (x[0] - t) * (x[0] + t)
}

/// Jordan product x ∘ y = (xᵀy, x₀ȳ + y₀x̄).
fn jordan(x: &[f64], y: &[f64], out: &mut [f64]) {
    out[0] = x.iter().zip(y).map(|(a, b)| a * b).sum();
    for k in 1..x.len() {
        out[k] = x[0] * y[k] + y[0] * x[k];
    }
}

/// The z with λ ∘ z = v (λ in the interior of L).
fn jordan_div(l: &[f64], v: &[f64], out: &mut [f64]) {
    let dot: f64 = l[1..].iter().zip(&v[1..]).map(|(a, b)| a * b).sum();
    let z0 = (l[0] * v[0] - dot) / det(l);
    out[0] = z0;
    for k in 1..l.len() {
        out[k] = (v[k] - z0 * l[k]) / l[0];
    }
}

/// The Nesterov–Todd scaling of an interior pair (a, b) of L: Θ = η B_w̄, B_w̄ the Lorentz
/// boost [w̄₀, w̄ᵀ; w̄, I + w̄w̄ᵀ/(1 + w̄₀)] (B_w̄ e = w̄, B_w̄² = 2w̄w̄ᵀ − J, J = diag(1, −1, …)),
/// w̄ = (ā + J b̄)/(2γ) with ā = a/√det a, b̄ = b/√det b, γ = √((1 + āᵀb̄)/2), and
/// η = (det a / det b)^¼: symmetric positive definite with Θ b = Θ⁻¹ a. Returns (η, w̄).
fn nt_scaling(a: &[f64], b: &[f64]) -> (f64, [f64; 3]) {
    let (da, db) = (det(a).sqrt(), det(b).sqrt());
    let d = a.len();
    let mut abar = [0.0; 3];
    let mut bbar = [0.0; 3];
    for k in 0..d {
        abar[k] = a[k] / da;
        bbar[k] = b[k] / db;
    }
    let dot: f64 = (0..d).map(|k| abar[k] * bbar[k]).sum();
    let gamma = ((1.0 + dot) / 2.0).sqrt();
    let mut w = [0.0; 3];
    w[0] = (abar[0] + bbar[0]) / (2.0 * gamma);
    for k in 1..d {
        w[k] = (abar[k] - bbar[k]) / (2.0 * gamma);
    }
    ((da / db).sqrt(), w)
}

/// Θ x, or Θ⁻¹ x = (1/η) J B_w̄ J x when `inverse`.
fn nt_apply(eta: f64, w: &[f64; 3], inverse: bool, x: &[f64], out: &mut [f64]) {
    let d = x.len();
    let sign = if inverse { -1.0 } else { 1.0 };
    let wx: f64 = (1..d).map(|k| w[k] * x[k]).sum();
    let scale = if inverse { 1.0 / eta } else { eta };
    out[0] = scale * (w[0] * x[0] + sign * wx);
    let c = sign * x[0] + wx / (1.0 + w[0]);
    for k in 1..d {
        out[k] = scale * (x[k] + c * w[k]);
    }
}

/// The largest α ∈ (0, 1] with x + α δx in L (not cut by a fraction).
fn max_step(x: &[f64], dx: &[f64]) -> f64 {
    // det(x + α δx) = det x + 2α xᵀJδx + α² det δx, and x₀ + α δx₀ ≥ 0
    let c = det(x);
    let b = x[0] * dx[0] - x[1..].iter().zip(&dx[1..]).map(|(a, b)| a * b).sum::<f64>();
    let a = det(dx);
    let mut alpha = 1.0f64;
    if dx[0] < 0.0 {
        alpha = alpha.min(-x[0] / dx[0]);
    }
    // smallest positive root of a α² + 2b α + c
    if a.abs() < 1e-300 {
        if b < 0.0 {
            alpha = alpha.min(-c / (2.0 * b));
        }
    } else {
        let disc = b * b - a * c;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            for root in [(-b - sq) / a, (-b + sq) / a] {
                if root > 0.0 {
                    alpha = alpha.min(root);
                }
            }
        }
    }
    alpha.max(0.0)
}

/// At r: u = W r + q, the target T ũ(r) of b (with ‖u_T‖ smoothed to √(‖u_T‖² + δᵢ²)) and t̂ = ∂‖u_T‖/∂u_T
/// per contact (u = W r + q, W as stored).
struct Point {
    u: Vec<f64>,
    target: Vec<f64>,
    that: Vec<f64>,
}

fn point(p: &LocalProblem, r: &[f64], smooth: &[f64]) -> Point {
    let d = p.dim;
    let u = p.velocity(r);
    let mut target = vec![0.0; u.len()];
    let mut that = vec![0.0; u.len()];
    for (i, &mu) in p.mu.iter().enumerate() {
        let at = i * d;
        let ut = crate::law::norm(&u[at + 1..at + d]).hypot(smooth[i]);
        target[at] = (u[at] + mu * ut) / mu;
        for k in 1..d {
            target[at + k] = u[at + k];
            if ut > 0.0 {
                that[at + k] = u[at + k] / ut;
            }
        }
    }
    Point { u, target, that }
}

/// The state of the method: r, its scaled form a = S r, and b (both in the interior of L).
struct State {
    r: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
}

impl State {
    /// The cold start: r_N = ‖q‖/(√n max Wᵢᵢ μᵢ), r_T = 0 (a = e · ‖q‖/(√n max Wᵢᵢ)), and
    /// b = T ũ(r₀) moved into the interior of L by a common multiple of e.
    fn cold(p: &LocalProblem, params: &BarrierParams) -> Self {
        let (d, n) = (p.dim, p.mu.len());
        let m = n * d;
        let diag_max = p.w.diagonal().iter().fold(0.0f64, |x, &y| x.max(y.abs()));
        let q_scale = crate::law::norm(&p.q) / (n as f64).sqrt();
        let unit = if q_scale > 0.0 { q_scale } else { 1.0 };
        let an = if diag_max > 0.0 { unit / diag_max } else { 1.0 };
        let mut r = vec![0.0; m];
        let mut a = vec![0.0; m];
        for i in 0..n {
            a[i * d] = an;
            r[i * d] = an / p.mu[i];
        }
        let mut b = point(p, &r, &vec![0.0; n]).target;
        // b ends as far inside L as the farthest block of T ũ(r₀) was outside (plus margins)
        let shift = 2.0 * push_interior(d, &mut b, params.start_margin);
        let shift = shift.max(params.start_floor * unit);
        for blk in b.chunks_mut(d) {
            blk[0] += shift;
        }
        Self { r, a, b }
    }

    /// aᵀb / contacts.
    fn gap(&self, n: usize) -> f64 {
        self.a.iter().zip(&self.b).map(|(x, y)| x * y).sum::<f64>() / n as f64
    }
}

/// How the Newton systems (W + G) δr = ρ, G = blockdiag((T C)⁻¹ Θ⁻² S), of [`solve_with`] are
/// solved; chosen once per problem (the runs of the policy's try share it).
pub struct Setup<'g> {
    linear: Linear<'g>,
    /// m, the number of contact unknowns of the problem it was set up for
    unknowns: usize,
}

/// The factorization a [`Setup`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinearKind {
    /// sparse LU of W + G on the block pattern of W
    SparseLu,
    /// dense LU of the Schur complement M + H G⁻¹ Hᵀ of a global problem
    Schur {
        /// the size of M
        dofs: usize,
    },
    /// dense LU of A + R G⁻¹ C for the skeleton W ≈ C A⁻¹ R of [`crate::linalg::skeleton`]
    Skeleton {
        /// the size of A
        rank: usize,
    },
}

impl<'g> Setup<'g> {
    /// For a global problem `global` (`p` its Delassus form: W = Hᵀ M⁻¹ H, q = Hᵀ M⁻¹ f + w)
    /// with fewer degrees of freedom than contact unknowns, at most
    /// [`BarrierParams::max_schur_dofs`]: the Schur complement on M. Else, for at most
    /// [`BarrierParams::max_skeleton_unknowns`] contact unknowns, the skeleton of W when its
    /// symmetric part has rank ≤ min(`max_schur_dofs`, [`BarrierParams::skeleton_rank_ratio`]
    /// · m). None if neither applies (or the
    /// deadline passes while probing the rank).
    pub fn structured(
        p: &LocalProblem,
        global: Option<&'g GlobalProblem>,
        params: &BarrierParams,
        deadline: Deadline,
    ) -> Option<Self> {
        let m = p.q.len();
        let schur = global.filter(|g| {
            let n_dofs = g.m.nrows;
            n_dofs <= params.max_schur_dofs
                && n_dofs < m
                && g.h.ncols == m
                && g.h.nrows == n_dofs
                && p.w.nrows == m
        });
        if let Some(g) = schur {
            return Some(Self {
                linear: Linear::Schur(g),
                unknowns: m,
            });
        }
        if m > params.max_skeleton_unknowns || p.w.nrows != m {
            return None;
        }
        let max_rank = params
            .max_schur_dofs
            .min((params.skeleton_rank_ratio * m as f64) as usize);
        Skeleton::new(&p.w, p.dim, max_rank, params.rank_tol, deadline).map(|s| Self {
            linear: Linear::Skeleton(Box::new(s), std::cell::OnceCell::new()),
            unknowns: m,
        })
    }

    /// [`Setup::structured`], else a sparse LU on the block pattern of W (None if its
    /// symbolic factorization fails).
    pub fn new(
        p: &LocalProblem,
        global: Option<&'g GlobalProblem>,
        params: &BarrierParams,
        deadline: Deadline,
    ) -> Option<Self> {
        Self::structured(p, global, params, deadline).or_else(|| {
            JacobianPattern::new(p).map(|pattern| Self {
                linear: Linear::Pattern(pattern),
                unknowns: p.q.len(),
            })
        })
    }

    /// Which factorization the Newton systems get.
    pub fn kind(&self) -> LinearKind {
        match &self.linear {
            Linear::Pattern(_) => LinearKind::SparseLu,
            Linear::Schur(g) => LinearKind::Schur { dofs: g.m.nrows },
            Linear::Skeleton(s, _) => LinearKind::Skeleton { rank: s.rank() },
        }
    }

    /// The skeleton of W the Newton systems were solved through, if they were, taken out of
    /// the setup (for the method of multipliers: the skeleton is built once per solve).
    pub fn into_skeleton(self) -> Option<Skeleton> {
        match self.linear {
            Linear::Skeleton(s, _) => Some(*s),
            _ => None,
        }
    }

    /// The skeleton of W the Newton systems are solved through, if they are.
    pub fn skeleton(&self) -> Option<&Skeleton> {
        match &self.linear {
            Linear::Skeleton(s, _) => Some(s),
            _ => None,
        }
    }
}

/// [`solve_with`] on [`Setup::new`] (status `NotApplicable` when it is None).
pub fn solve(
    p: &LocalProblem,
    global: Option<&GlobalProblem>,
    tol: f64,
    max_steps: usize,
    params: &BarrierParams,
    path: PathParams,
    deadline: Deadline,
) -> (Vec<f64>, BarrierReport) {
    match Setup::new(p, global, params, deadline) {
        Some(setup) => solve_with(p, &setup, tol, max_steps, params, path, deadline),
        None => not_applicable(p),
    }
}

/// r = 0 with status `NotApplicable`.
fn not_applicable(p: &LocalProblem) -> (Vec<f64>, BarrierReport) {
    let r = vec![0.0; p.q.len()];
    let error = p.error(&r).error;
    let report = BarrierReport {
        status: BarrierStatus::NotApplicable,
        steps: 0,
        error,
        gap: f64::NAN,
        exact_steps: 0,
    };
    (r, report)
}

/// Runs the interior-point method on the local problem `p` from a cold start along the path
/// shaped by `path`, until the error of docs/error.md is ≤ `tol`, for at most `max_steps`
/// Newton steps, the Newton systems solved as `setup` says. Returns the r of lowest error
/// visited (W as stored) and the report.
pub fn solve_with(
    p: &LocalProblem,
    setup: &Setup<'_>,
    tol: f64,
    max_steps: usize,
    params: &BarrierParams,
    path: PathParams,
    deadline: Deadline,
) -> (Vec<f64>, BarrierReport) {
    let d = p.dim;
    let n = p.mu.len();
    let m = n * d;
    let report = |status, steps, error, gap, exact_steps| BarrierReport {
        status,
        steps,
        error,
        gap,
        exact_steps,
    };
    if n == 0
        || p.q.len() != m
        || setup.unknowns != m
        || p.w.nrows != m
        || p.w.ncols != m
        || p.mu.iter().any(|&mu| !(mu > 0.0 && mu.is_finite()))
    {
        return not_applicable(p);
    }
    let linear = &setup.linear;
    let mut x = State::cold(p, params);
    let mut best_r = x.r.clone();
    let mut best = f64::INFINITY;
    let mut best_step = 0;
    // consecutive steps cut below `settle_alpha` of the Newton step
    let mut short_steps = 0;
    let mut steps = 0;
    let mut alpha = 1.0;
    let mut smooth = vec![0.0; n];
    let mut newton = NewtonSystem::new(p, params);
    let q_norm = crate::law::norm(&p.q);
    let status = loop {
        // smoothing of ‖u_T‖ tied to the path: δᵢ = c κ / aᵢ₀
        let gap = x.gap(n);
        for (delta, a) in smooth.iter_mut().zip(x.a.chunks(d)) {
            *delta = path.smoothing * gap / a[0];
        }
        let pt = point(p, &x.r, &smooth);
        // the error of docs/error.md, u = W r + q with W as stored (= p.error(r))
        let e = crate::law::error_measure(d, &p.mu, &x.r, &pt.u, q_norm).error;
        if e < best {
            best = e;
            best_r.copy_from_slice(&x.r);
            best_step = steps;
        }
        if best <= tol {
            break BarrierStatus::Reached;
        }
        if steps >= max_steps {
            break BarrierStatus::MaxSteps;
        }
        if deadline.passed() {
            break BarrierStatus::TimeLimit;
        }
        let jammed = best <= params.settle_below && short_steps >= params.settle_steps;
        if steps - best_step >= params.stall_steps || jammed {
            break BarrierStatus::Stalled;
        }
        steps += 1;
        let f: Vec<f64> = (0..m).map(|k| x.b[k] - pt.target[k]).collect();
        newton.assemble(p, linear, &x, &pt);
        // predictor: σ = 0
        let affine = |_: usize, l: &[f64], out: &mut [f64]| {
            jordan(l, l, out);
            out.iter_mut().for_each(|v| *v = -*v);
        };
        let Some((_, da, db)) = newton.direction(p, linear, &pt, &f, &affine) else {
            break BarrierStatus::LinearSolve;
        };
        let alpha_aff = step_length(d, &x.a, &da, &x.b, &db);
        let gap_aff = (0..m)
            .map(|k| (x.a[k] + alpha_aff * da[k]) * (x.b[k] + alpha_aff * db[k]))
            .sum::<f64>()
            / n as f64;
        // corrector: σκe − λ∘λ − (Θ⁻¹δa) ∘ (Θδb); a pure centring step (σ = 1, no
        // second-order term) after a step cut below `recentre`
        let recentre = alpha < path.recentre && steps > 1;
        let sigma = if recentre {
            1.0
        } else {
            (gap_aff / gap).clamp(0.0, 1.0).powi(3)
        };
        let mut corr = vec![0.0; m];
        if !recentre {
            newton.second_order(&da, &db, &mut corr);
        }
        let target_gap = sigma * gap;
        let combined = |i: usize, l: &[f64], out: &mut [f64]| {
            jordan(l, l, out);
            for k in 0..out.len() {
                out[k] = -out[k] - corr[i * d + k];
            }
            out[0] += target_gap;
        };
        let Some((dr, da, db)) = newton.direction(p, linear, &pt, &f, &combined) else {
            break BarrierStatus::LinearSolve;
        };
        alpha = (params.boundary_fraction * step_length(d, &x.a, &da, &x.b, &db)).min(1.0);
        short_steps = if alpha < params.settle_alpha {
            short_steps + 1
        } else {
            0
        };
        // the roots of det(x + α δx) are computed with rounding: halve α until every block
        // is strictly inside as det() evaluates it (the scalings need det > 0)
        let inside = |alpha: f64| {
            let moved = |v: &[f64], dv: &[f64]| -> bool {
                let mut y = [0.0; 3];
                v.chunks(d).zip(dv.chunks(d)).all(|(v, dv)| {
                    for k in 0..d {
                        y[k] = v[k] + alpha * dv[k];
                    }
                    y[0] > 0.0 && det(&y[..d]) > 0.0
                })
            };
            moved(&x.a, &da) && moved(&x.b, &db)
        };
        let mut halvings = 0;
        while !inside(alpha) {
            alpha *= 0.5;
            halvings += 1;
            if halvings > 60 {
                break;
            }
        }
        if halvings > 60 {
            break BarrierStatus::LinearSolve;
        }
        for k in 0..m {
            x.r[k] += alpha * dr[k];
            x.a[k] += alpha * da[k];
            x.b[k] += alpha * db[k];
        }
    };
    let gap = x.gap(n);
    let error = p.error(&best_r).error;
    (
        best_r,
        report(status, steps, error, gap, newton.exact_steps),
    )
}

/// The Newton matrix W + blockdiag((T C)⁻¹ Θ⁻² S) on the pattern of W (values), the
/// Nesterov–Todd scalings and λ = Θ b of the current iterate.
struct NewtonSystem {
    d: usize,
    scal: Vec<(f64, [f64; 3])>,
    lam: Vec<f64>,
    vals: Vec<f64>,
    wcol: Vec<f64>,
    /// I − (T C)⁻¹ Θ⁻² S per contact (the form [`JacobianPattern::fill`] takes: J = I − D + B W)
    dblocks: Vec<f64>,
    /// G = (T C)⁻¹ Θ⁻² S per contact (row-major d × d)
    gblocks: Vec<f64>,
    /// identity blocks (B = I)
    blocks: Vec<f64>,
    /// max |Wᵢᵢ| (the scale of the diagonal shift of a failed factorization)
    diag_max: f64,
    /// this step's factorization (None until the first solve after `assemble`)
    factor: Option<Factor>,
    /// the diagonal shift of the sparse LU of this step
    shift: f64,
    /// [`BarrierParams::refine_steps`], [`BarrierParams::refine_tol`]
    refine_steps: usize,
    refine_tol: f64,
    /// steps solved by the sparse LU although a skeleton was set up
    exact_steps: usize,
    /// [`BarrierParams::skeleton_strikes`]
    skeleton_strikes: usize,
    /// [`BarrierParams::dense_parallel_dim`]
    dense_parallel_dim: usize,
    /// the exact steps in a row up to this one (the current step counts once it falls back)
    exact_run: usize,
    /// whether the current step fell back to the sparse LU
    step_exact: bool,
}

impl NewtonSystem {
    fn new(p: &LocalProblem, params: &BarrierParams) -> Self {
        let (n, d) = (p.mu.len(), p.dim);
        let mut blocks = vec![0.0; n * d * d];
        for i in 0..n {
            for k in 0..d {
                blocks[i * d * d + k * d + k] = 1.0;
            }
        }
        Self {
            d,
            scal: vec![(1.0, [1.0, 0.0, 0.0]); n],
            lam: vec![0.0; n * d],
            vals: Vec::new(),
            wcol: vec![0.0; n * d],
            dblocks: vec![0.0; n * d * d],
            gblocks: vec![0.0; n * d * d],
            blocks,
            diag_max: p.w.diagonal().iter().fold(0.0f64, |x, &y| x.max(y.abs())),
            factor: None,
            shift: 0.0,
            refine_steps: params.refine_steps,
            refine_tol: params.refine_tol,
            exact_steps: 0,
            skeleton_strikes: params.skeleton_strikes,
            dense_parallel_dim: params.dense_parallel_dim,
            exact_run: 0,
            step_exact: false,
        }
    }

    fn assemble(&mut self, p: &LocalProblem, linear: &Linear<'_>, x: &State, pt: &Point) {
        let d = self.d;
        self.factor = None;
        self.shift = 0.0;
        self.exact_run = if self.step_exact {
            self.exact_run + 1
        } else {
            0
        };
        self.step_exact = false;
        for (i, &mu) in p.mu.iter().enumerate() {
            let at = i * d;
            let (ai, bi) = (&x.a[at..at + d], &x.b[at..at + d]);
            self.scal[i] = nt_scaling(ai, bi);
            let (eta, w) = self.scal[i];
            nt_apply(eta, &w, false, bi, &mut self.lam[at..at + d]);
            let th = &pt.that[at..at + d];
            let dj = &mut self.dblocks[i * d * d..(i + 1) * d * d];
            let gj = &mut self.gblocks[i * d * d..(i + 1) * d * d];
            for c in 0..d {
                // column c of (T C)⁻¹ Θ⁻² S
                let mut col = [0.0; 3];
                let mut tmp = [0.0; 3];
                col[c] = if c == 0 { mu } else { 1.0 };
                nt_apply(eta, &w, true, &col[..d], &mut tmp[..d]);
                nt_apply(eta, &w, true, &tmp[..d], &mut col[..d]);
                tc_inverse(mu, th, &mut col[..d]);
                for rr in 0..d {
                    let id = if rr == c { 1.0 } else { 0.0 };
                    dj[rr * d + c] = id - col[rr];
                    gj[rr * d + c] = col[rr];
                }
            }
        }
        if let Linear::Pattern(pattern) = linear {
            pattern.fill(
                p,
                &self.dblocks,
                &self.blocks,
                &mut self.wcol,
                &mut self.vals,
            );
        }
    }

    /// (δr, δa, δb) for the complementarity right-hand side `rc` (per contact, from λ):
    /// λ ∘ (Θ⁻¹δa + Θδb) = rc, δb = T C W δr − f, δa = S δr. None if the LU fails.
    #[allow(clippy::type_complexity)]
    fn direction(
        &mut self,
        p: &LocalProblem,
        linear: &Linear<'_>,
        pt: &Point,
        f: &[f64],
        rc: &dyn Fn(usize, &[f64], &mut [f64]),
    ) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let d = self.d;
        let m = f.len();
        let mut dr = vec![0.0; m];
        let mut c = [0.0; 3];
        let mut xi = [0.0; 3];
        for (i, &mu) in p.mu.iter().enumerate() {
            let at = i * d;
            let l = &self.lam[at..at + d];
            rc(i, l, &mut c[..d]);
            jordan_div(l, &c[..d], &mut xi[..d]);
            let (eta, w) = self.scal[i];
            nt_apply(eta, &w, true, &xi[..d], &mut dr[at..at + d]);
            for k in 0..d {
                dr[at + k] += f[at + k];
            }
            tc_inverse(mu, &pt.that[at..at + d], &mut dr[at..at + d]);
        }
        self.linear_solve(p, linear, &mut dr)?;
        let mut wd = vec![0.0; m];
        p.w.gemv_acc(1.0, &dr, &mut wd);
        let mut da = vec![0.0; m];
        let mut db = vec![0.0; m];
        for (i, &mu) in p.mu.iter().enumerate() {
            let at = i * d;
            da[at] = mu * dr[at];
            let tdot: f64 = (1..d).map(|k| pt.that[at + k] * wd[at + k]).sum();
            db[at] = (wd[at] + mu * tdot) / mu - f[at];
            for k in 1..d {
                da[at + k] = dr[at + k];
                db[at + k] = wd[at + k] - f[at + k];
            }
        }
        Some((dr, da, db))
    }

    /// Solves (W + G) x = rhs in place with this step's factorization, computed at the first
    /// call after [`NewtonSystem::assemble`] (the predictor and the corrector share it). None
    /// if the factorization fails (also with the largest diagonal shift) or x is not finite.
    /// Through a skeleton, a solve whose refinement on W does not reach
    /// [`BarrierParams::refine_tol`] is redone, for the rest of the step, by a sparse LU of
    /// W + G (the skeleton only approximates a W with an antisymmetric part, and near the end
    /// of the path G is small); after [`BarrierParams::skeleton_strikes`] such steps in a row,
    /// every later step of the run goes to the sparse LU directly.
    fn linear_solve(
        &mut self,
        p: &LocalProblem,
        linear: &Linear<'_>,
        rhs: &mut [f64],
    ) -> Option<()> {
        match linear {
            Linear::Pattern(pattern) => self.sparse_solve(pattern, rhs),
            Linear::Schur(g) => {
                if self.factor.is_none() {
                    self.factor = Some(self.schur_factor(g)?);
                }
                let Some(Factor::Schur(ginv, lu)) = &self.factor else {
                    return None;
                };
                schur_apply(self.d, g, ginv, lu, rhs)
            }
            Linear::Skeleton(sk, exact) => {
                // after `skeleton_strikes` steps in a row that fell back, the run keeps to the
                // sparse LU (W far from symmetric, or the end of the path)
                let skip = self.exact_run >= self.skeleton_strikes;
                if self.factor.is_none() && !skip {
                    self.factor = self
                        .inverse_blocks()
                        .and_then(|ginv| sk.factor(&ginv, self.dense_parallel_dim))
                        .map(Factor::Skeleton);
                }
                if let Some(Factor::Skeleton(f)) = &self.factor {
                    let b = rhs.to_vec();
                    if self.refined(p, sk, f, &b, rhs).is_some() {
                        return Some(());
                    }
                    rhs.copy_from_slice(&b);
                    self.factor = None;
                }
                let pattern = exact.get_or_init(|| JacobianPattern::new(p)).as_ref()?;
                if self.factor.is_none() {
                    self.exact_steps += 1;
                    self.step_exact = true;
                    pattern.fill(
                        p,
                        &self.dblocks,
                        &self.blocks,
                        &mut self.wcol,
                        &mut self.vals,
                    );
                }
                self.sparse_solve(pattern, rhs)
            }
        }
    }

    /// x = (W + G)⁻¹ rhs through the skeleton, refined on W as stored (x ← x + M⁻¹(b −
    /// (W + G) x), M the skeleton's W + G) at most [`BarrierParams::refine_steps`] times;
    /// None unless the residual (max norm) reaches [`BarrierParams::refine_tol`] times the
    /// right-hand side's. (Near the end of the path G has tiny blocks and the Woodbury
    /// formula cancels large terms: there the refinement stalls, see docs/rigid.md.)
    /// (`rhs` holds b on entry, x on return.)
    fn refined(
        &self,
        p: &LocalProblem,
        sk: &Skeleton,
        f: &crate::linalg::skeleton::SkeletonLu,
        b: &[f64],
        rhs: &mut [f64],
    ) -> Option<()> {
        let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let goal = self.refine_tol * max_abs(b);
        sk.solve(f, rhs)?;
        let mut res = self.residual(p, b, rhs);
        for _ in 0..self.refine_steps {
            if max_abs(&res) <= goal {
                break;
            }
            sk.solve(f, &mut res)?;
            for (x, dx) in rhs.iter_mut().zip(&res) {
                *x += dx;
            }
            res = self.residual(p, b, rhs);
        }
        (max_abs(&res) <= goal && rhs.iter().all(|x| x.is_finite())).then_some(())
    }

    /// G⁻¹ by blocks; None if a block is singular (to working precision).
    fn inverse_blocks(&self) -> Option<Vec<f64>> {
        let d = self.d;
        let mut ginv = vec![0.0; self.gblocks.len()];
        for (blk, inv) in self.gblocks.chunks(d * d).zip(ginv.chunks_mut(d * d)) {
            invert_small(d, blk, inv)?;
        }
        Some(ginv)
    }

    /// x = (W + G)⁻¹ rhs by the sparse LU of W + G (values in `vals`) on the pattern; near the
    /// end of the path W + G can be singular to working precision: then the diagonal is
    /// shifted (static regularization, a slightly damped step).
    fn sparse_solve(&mut self, pattern: &JacobianPattern, rhs: &mut [f64]) -> Option<()> {
        let b = rhs.to_vec();
        loop {
            if self.factor.is_none() {
                self.factor = Some(Factor::Sparse(Box::new(self.sparse_factor(pattern)?)));
            }
            if let Some(Factor::Sparse(lu)) = &self.factor {
                if lu.solve_in_place(rhs) && rhs.iter().all(|x| x.is_finite()) {
                    return Some(());
                }
            }
            self.factor = None;
            self.shift = self.next_shift()?;
            rhs.copy_from_slice(&b);
        }
    }

    /// b − (W + G) x (W as stored).
    fn residual(&self, p: &LocalProblem, b: &[f64], x: &[f64]) -> Vec<f64> {
        let mut gx = vec![0.0; x.len()];
        apply_blocks(self.d, &self.gblocks, x, &mut gx);
        let mut res: Vec<f64> = b.iter().zip(&gx).map(|(bi, gi)| bi - gi).collect();
        p.w.gemv_acc(-1.0, x, &mut res);
        res
    }

    /// The sparse LU of W + G + shift · I on the pattern, the shift raised until it succeeds.
    fn sparse_factor(&mut self, pattern: &JacobianPattern) -> Option<PatternLu> {
        loop {
            if let Some(lu) = pattern.factor(&self.vals_shifted(pattern, self.shift)) {
                return Some(lu);
            }
            self.shift = self.next_shift()?;
        }
    }

    /// The diagonal shift after a failed one: 1e-12 max |Wᵢᵢ|, then × 100, up to 1e-6 max |Wᵢᵢ|.
    fn next_shift(&self) -> Option<f64> {
        let shift = if self.shift == 0.0 {
            1e-12 * self.diag_max
        } else {
            100.0 * self.shift
        };
        (shift <= 1e-6 * self.diag_max && shift.is_finite() && shift > 0.0).then_some(shift)
    }

    /// G⁻¹ and the LU of the Schur complement M + H G⁻¹ Hᵀ (for W = Hᵀ M⁻¹ H).
    fn schur_factor(&self, g: &GlobalProblem) -> Option<Factor> {
        let d = self.d;
        let n = g.m.nrows;
        let contacts = self.gblocks.len() / (d * d);
        let ginv = self.inverse_blocks()?;
        let mut k = faer::Mat::<f64>::zeros(n, n);
        for (i, j, v) in g.m.triplets() {
            k[(i, j)] += v;
        }
        // H G⁻¹ Hᵀ, contact by contact (the columns of H of contact i times its block)
        let col = |c: usize| {
            (g.h.col_ptr[c]..g.h.col_ptr[c + 1]).map(move |t| (g.h.row_idx[t], g.h.values[t]))
        };
        for i in 0..contacts {
            let inv = &ginv[i * d * d..(i + 1) * d * d];
            for c1 in 0..d {
                for c2 in 0..d {
                    let gv = inv[c1 * d + c2];
                    if gv == 0.0 {
                        continue;
                    }
                    for (ra, va) in col(i * d + c1) {
                        for (rb, vb) in col(i * d + c2) {
                            k[(ra, rb)] += va * gv * vb;
                        }
                    }
                }
            }
        }
        let lu = crate::linalg::dense::Lu::new(
            k,
            crate::linalg::dense::parallelism(n, self.dense_parallel_dim),
        )?;
        Some(Factor::Schur(ginv, lu))
    }

    /// The matrix values with λ added to the diagonal (borrowed unchanged when λ = 0).
    fn vals_shifted(&self, pattern: &JacobianPattern, lambda: f64) -> std::borrow::Cow<'_, [f64]> {
        if lambda == 0.0 {
            return std::borrow::Cow::Borrowed(&self.vals);
        }
        let mut v = self.vals.clone();
        pattern.shift_diagonal(&mut v, lambda);
        std::borrow::Cow::Owned(v)
    }

    /// (Θ⁻¹δa) ∘ (Θδb) per contact, Mehrotra's second-order term.
    fn second_order(&self, da: &[f64], db: &[f64], out: &mut [f64]) {
        let d = self.d;
        for (i, &(eta, w)) in self.scal.iter().enumerate() {
            let at = i * d;
            let mut x = [0.0; 3];
            let mut y = [0.0; 3];
            nt_apply(eta, &w, true, &da[at..at + d], &mut x[..d]);
            nt_apply(eta, &w, false, &db[at..at + d], &mut y[..d]);
            jordan(&x[..d], &y[..d], &mut out[at..at + d]);
        }
    }
}

/// How the Newton systems are solved: sparse LU of W + G on the block pattern of W, or the
/// Schur complement on M of a global problem.
enum Linear<'g> {
    Pattern(JacobianPattern),
    Schur(&'g GlobalProblem),
    /// the skeleton, and the pattern of W for the exact solves (built at the first need)
    Skeleton(Box<Skeleton>, std::cell::OnceCell<Option<JacobianPattern>>),
}

/// Solves (W + G) x = rhs in place for W = Hᵀ M⁻¹ H: x = G⁻¹ (rhs − Hᵀ y) with
/// (M + H G⁻¹ Hᵀ) y = H G⁻¹ rhs, from G⁻¹ and the LU of the Schur complement. None if x is not
/// finite.
fn schur_apply(
    d: usize,
    g: &GlobalProblem,
    ginv: &[f64],
    lu: &crate::linalg::dense::Lu,
    rhs: &mut [f64],
) -> Option<()> {
    let mut z = vec![0.0; rhs.len()];
    apply_blocks(d, ginv, rhs, &mut z);
    let mut yv = g.h.mul_vec(&z);
    if !lu.solve_in_place(&mut yv) {
        return None;
    }
    let mut res = rhs.to_vec();
    g.h.gemv_t_acc(-1.0, &yv, &mut res);
    apply_blocks(d, ginv, &res, rhs);
    rhs.iter().all(|x| x.is_finite()).then_some(())
}

/// The factorization of one step's Newton matrix W + G.
enum Factor {
    /// sparse LU of W + G (+ shift) on the block pattern of W
    Sparse(Box<PatternLu>),
    /// G⁻¹ and the dense LU of M + H G⁻¹ Hᵀ
    Schur(Vec<f64>, crate::linalg::dense::Lu),
    /// G⁻¹ and the dense LU of A + R G⁻¹ C ([`crate::linalg::skeleton`])
    Skeleton(crate::linalg::skeleton::SkeletonLu),
}

/// x ← (T C)⁻¹ x = (μ (x₀ − t̂ᵀx̄), x̄) for one contact.
fn tc_inverse(mu: f64, that: &[f64], x: &mut [f64]) {
    let dot: f64 = (1..x.len()).map(|k| that[k] * x[k]).sum();
    x[0] = mu * (x[0] - dot);
}

/// The largest α ≤ 1 keeping every a + α δa and b + α δb in L.
fn step_length(d: usize, a: &[f64], da: &[f64], b: &[f64], db: &[f64]) -> f64 {
    let mut alpha = 1.0f64;
    for (((a, da), b), db) in a
        .chunks(d)
        .zip(da.chunks(d))
        .zip(b.chunks(d))
        .zip(db.chunks(d))
    {
        alpha = alpha.min(max_step(a, da)).min(max_step(b, db));
    }
    alpha
}

/// The shift t ≥ 0 such that every block of x + t e is in the interior of L with a margin
/// of `margin` times the largest entry (0 when all are already inside).
fn push_interior(d: usize, x: &mut [f64], margin: f64) -> f64 {
    let mut worst = 0.0f64;
    let mut size = 0.0f64;
    for blk in x.chunks(d) {
        let t = crate::law::norm(&blk[1..]);
        worst = worst.max(t - blk[0]);
        size = size.max(blk[0].abs()).max(t);
    }
    if worst >= 0.0 {
        worst + margin * size
    } else {
        0.0
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    /// One run with the default parameters and first path, to 1e-8, at most 150 steps.
    fn run_default(p: &LocalProblem) -> (Vec<f64>, BarrierReport) {
        let params = BarrierParams::default();
        solve(
            p,
            None,
            1e-8,
            150,
            &params,
            params.paths[0],
            Deadline::NEVER,
        )
    }

    pub fn nt_scaling_maps_b_and_a_to_the_same_point() {
        let pairs = [
            ([2.0, 0.5, -0.3], [1.5, -0.2, 0.9]),
            ([1.0, 0.0, 0.0], [3.0, 1.0, 1.0]),
            ([5.0, 4.0, 2.9], [0.7, 0.1, -0.6]),
        ];
        for (a, b) in pairs {
            let (eta, w) = nt_scaling(&a, &b);
            let mut tb = [0.0; 3];
            let mut ta = [0.0; 3];
            nt_apply(eta, &w, false, &b, &mut tb);
            nt_apply(eta, &w, true, &a, &mut ta);
            for k in 0..3 {
                assert!(
                    (tb[k] - ta[k]).abs() < 1e-12 * (1.0 + ta[k].abs()),
                    "{tb:?} {ta:?}"
                );
            }
            // Θ Θ⁻¹ = I
            let x = [0.3, -1.2, 0.4];
            let mut y = [0.0; 3];
            let mut z = [0.0; 3];
            nt_apply(eta, &w, true, &x, &mut y);
            nt_apply(eta, &w, false, &y, &mut z);
            for k in 0..3 {
                assert!((z[k] - x[k]).abs() < 1e-12, "{z:?}");
            }
        }
    }

    pub fn solves_rank_deficient_problems_and_reports_the_stored_error() {
        // W = AᵀA + skew with A of m/2 rows: more contact unknowns than the rank of W (the
        // rigid case), μ ∈ [0.3, 1], W symmetric or not; the returned r's error is the one
        // recomputed on the problem given. Newton systems by the sparse LU of W + G, no stop
        // for the end game (`settle_below` = 0): the method alone reaches 1e-8; through the
        // skeleton of W with the default parameters (the policy's setup here, rank m/2) it
        // reaches it or stops jammed near it (below `settle_below`), where the LM end game
        // finishes
        let mut reached = [0, 0];
        let mut finished = 0;
        let mut runs = 0;
        let params = BarrierParams::default();
        let no_skeleton = BarrierParams {
            max_skeleton_unknowns: 0,
            settle_below: 0.0,
            ..params
        };
        for seed in 0..12 {
            for skew in [0.0, 1e-3] {
                let p = crate::test_problems::problem(8, seed, 0.0, skew);
                runs += 1;
                for (k, bp) in [no_skeleton, params].iter().enumerate() {
                    let setup = Setup::new(&p, None, bp, Deadline::NEVER).unwrap();
                    let skeleton = matches!(setup.kind(), LinearKind::Skeleton { .. });
                    assert_eq!(skeleton, k == 1);
                    let (mut r, rep) =
                        solve_with(&p, &setup, 1e-8, 150, bp, bp.paths[0], Deadline::NEVER);
                    let recomputed = p.error(&r).error;
                    assert_eq!(recomputed, rep.error, "seed {seed} skew {skew}");
                    assert!(rep.steps <= 150);
                    if rep.status == BarrierStatus::Reached {
                        assert!(recomputed <= 1e-8, "seed {seed}: {recomputed}");
                        reached[k] += 1;
                    }
                    if k == 1 {
                        assert!(
                            recomputed <= bp.settle_below,
                            "seed {seed} skew {skew}: {recomputed}"
                        );
                        let lm = crate::levenberg::LmParams::default();
                        crate::levenberg::solve(&p, &mut r, 1e-8, &lm, Deadline::NEVER);
                        finished += usize::from(p.error(&r).error <= 1e-8);
                    } else {
                        assert_eq!(rep.exact_steps, 0);
                    }
                }
            }
        }
        assert!(
            reached[0] >= runs - 2,
            "LU: reached 1e-8 on {} of {runs}",
            reached[0]
        );
        assert_eq!(
            finished, runs,
            "skeleton + LM: 1e-8 on {finished} of {runs}"
        );
    }

    pub fn a_run_jammed_near_the_end_of_its_path_stops_for_the_end_game() {
        // `settle_steps` steps in a row cut below `settle_alpha`, with the lowest error ≤
        // `settle_below`, end a run (status Stalled) with its best point, judged on the
        // stored W; with `settle_below` = 0 the same run goes on to the tolerance
        let p = crate::test_problems::problem(8, 3, 0.0, 1e-3);
        let base = BarrierParams::default();
        let run = |bp: &BarrierParams| {
            let setup = Setup::new(&p, None, bp, Deadline::NEVER).unwrap();
            solve_with(&p, &setup, 1e-8, 150, bp, bp.paths[0], Deadline::NEVER)
        };
        let never = BarrierParams {
            settle_below: 0.0,
            max_skeleton_unknowns: 0,
            ..base
        };
        let eager = BarrierParams {
            settle_steps: 2,
            settle_below: f64::MAX,
            settle_alpha: 0.999,
            ..never
        };
        let (_, whole) = run(&never);
        assert_eq!(whole.status, BarrierStatus::Reached, "{whole:?}");
        let (r, cut) = run(&eager);
        assert_eq!(cut.status, BarrierStatus::Stalled, "{cut:?}");
        assert!(cut.steps < whole.steps, "{cut:?} {whole:?}");
        assert_eq!(p.error(&r).error, cut.error);
    }

    pub fn the_skeleton_gives_the_steps_of_the_sparse_lu() {
        // a local problem with W = AᵀA of rank m/2: the same iterates whether the Newton
        // systems are solved through the skeleton of W (Woodbury) or by a sparse LU of W + G;
        // with an antisymmetric part in W (the skeleton then only approximates W, the solves
        // are refined on W as stored) the same too
        for skew in [0.0, 1e-4] {
            let p = crate::test_problems::problem(8, 5, 0.0, skew);
            let params = BarrierParams::default();
            let deadline = Deadline::NEVER;
            let skeleton = Setup::new(&p, None, &params, deadline).unwrap();
            assert_eq!(skeleton.kind(), LinearKind::Skeleton { rank: 12 });
            let no_skeleton = BarrierParams {
                max_skeleton_unknowns: 0,
                ..params
            };
            let sparse = Setup::new(&p, None, &no_skeleton, deadline).unwrap();
            assert_eq!(sparse.kind(), LinearKind::SparseLu);
            assert!(Setup::structured(&p, None, &no_skeleton, deadline).is_none());
            // a setup used on another problem takes no step
            let other = crate::test_problems::problem(5, 5, 0.0, skew);
            for setup in [&skeleton, &sparse] {
                let (_, rep) =
                    solve_with(&other, setup, 0.0, 3, &params, params.paths[0], deadline);
                assert_eq!(rep.status, BarrierStatus::NotApplicable);
            }
            for steps in [3, 8] {
                let run =
                    |setup| solve_with(&p, setup, 0.0, steps, &params, params.paths[0], deadline);
                let ((r1, a), (r2, b)) = (run(&sparse), run(&skeleton));
                assert_eq!((a.steps, b.steps), (steps, steps));
                assert_same_iterates(&r1, &r2, &format!("skew {skew}, {steps} steps"));
            }
        }
    }

    pub fn a_run_gives_up_the_skeleton_after_its_strikes() {
        // W with a large antisymmetric part: the refined skeleton solves fall short and those
        // steps are solved by the sparse LU; after `skeleton_strikes` such steps in a row the
        // run goes to the sparse LU directly. Where every step falls back (skew 0.3) the same
        // sparse LU solves every step either way: the same iterates; where some would not
        // (skew 0.1) the run has more exact steps and the same iterates to rounding
        let deadline = Deadline::NEVER;
        let base = BarrierParams::default();
        let never = BarrierParams {
            skeleton_strikes: usize::MAX,
            ..base
        };
        for skew in [0.3, 0.1] {
            let p = crate::test_problems::problem(8, 2, 0.0, skew);
            let setup = Setup::new(&p, None, &base, deadline).unwrap();
            assert!(matches!(setup.kind(), LinearKind::Skeleton { .. }));
            let run =
                |bp: &BarrierParams| solve_with(&p, &setup, 0.0, 12, bp, bp.paths[0], deadline);
            let ((r1, a), (r2, b)) = (run(&never), run(&base));
            assert_eq!((a.steps, b.steps), (12, 12));
            if skew == 0.3 {
                assert_eq!((a.exact_steps, b.exact_steps), (12, 12), "{a:?} {b:?}");
                assert_eq!(r1, r2);
            } else {
                assert!(
                    a.exact_steps < 12 && b.exact_steps > a.exact_steps,
                    "{a:?} {b:?}"
                );
                assert_same_iterates(&r1, &r2, "skew 0.1");
            }
        }
    }

    pub fn the_schur_complement_gives_the_steps_of_the_sparse_lu() {
        // a global problem (M = 2I, n = m/4) and its Delassus form: the same iterates whether
        // the Newton systems are solved on M + H G⁻¹ Hᵀ or on W + G
        let (m, n) = (24, 6);
        let lp = crate::test_problems::problem(8, 5, 0.0, 0.0);
        let h: Vec<f64> = (0..n * m)
            .map(|k| ((k * 7919) % 23) as f64 / 11.0 - 1.0)
            .collect();
        let g = GlobalProblem::new(
            3,
            crate::linalg::sparse::CscMatrix::identity(n, 2.0),
            crate::linalg::sparse::CscMatrix::from_dense(n, m, &h),
            vec![0.3; n],
            lp.q.clone(),
            lp.mu.clone(),
        )
        .unwrap();
        let local = crate::delassus::Delassus::new(&g).unwrap().local;
        let params = BarrierParams::default();
        for steps in [3, 8] {
            let run = |global| {
                solve(
                    &local,
                    global,
                    0.0,
                    steps,
                    &params,
                    params.paths[0],
                    Deadline::NEVER,
                )
            };
            let ((r1, a), (r2, b)) = (run(None), run(Some(&g)));
            assert_eq!((a.steps, b.steps), (steps, steps));
            assert_same_iterates(&r1, &r2, &format!("{steps} steps"));
        }
    }

    /// Two runs' iterates are equal up to rounding (amplified as the iterates near the
    /// boundary of the cones); a wrong elimination would differ at the first step.
    fn assert_same_iterates(r1: &[f64], r2: &[f64], what: &str) {
        let diff = r1
            .iter()
            .zip(r2)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        let size = r1.iter().fold(0.0f64, |s, x| s.max(x.abs()));
        assert!(
            diff <= 1e-6 * size,
            "{what}: differ by {diff} (size {size})"
        );
    }

    pub fn solves_two_dimensional_problems() {
        // d = 2 (the Lorentz cone of R²): W = AᵀA + I/10 with A of m/2 rows, 6 contacts
        let mut reached = 0;
        for seed in 0..8u64 {
            let mut next = crate::test_problems::uniform(seed, 3);
            let (contacts, m) = (6, 12);
            let a: Vec<f64> = (0..m / 2 * m).map(|_| next()).collect();
            let w: Vec<f64> = (0..m * m)
                .map(|k| {
                    let (i, j) = (k / m, k % m);
                    let aa: f64 = (0..m / 2).map(|l| a[l * m + i] * a[l * m + j]).sum();
                    aa + if i == j { 0.1 } else { 0.0 }
                })
                .collect();
            let p = LocalProblem::new(
                2,
                crate::linalg::sparse::CscMatrix::from_dense(m, m, &w),
                (0..m).map(|_| next()).collect(),
                (0..contacts).map(|_| 0.2 + 0.8 * next().abs()).collect(),
            )
            .unwrap();
            let (r, rep) = run_default(&p);
            assert_eq!(p.error(&r).error, rep.error, "seed {seed}");
            if rep.status == BarrierStatus::Reached {
                assert!(rep.error <= 1e-8);
                reached += 1;
            }
        }
        assert!(reached >= 6, "reached 1e-8 on {reached} of 8");
    }

    pub fn a_frictionless_contact_or_an_empty_problem_takes_no_step() {
        let mut p = crate::test_problems::problem(3, 1, 0.1, 0.0);
        p.mu[1] = 0.0;
        let (r, rep) = run_default(&p);
        assert_eq!(rep.status, BarrierStatus::NotApplicable);
        assert_eq!(rep.steps, 0);
        assert_eq!(rep.error, p.error(&r).error);
    }

    pub fn max_step_stops_at_the_boundary() {
        let x = [1.0, 0.0, 0.0];
        let dx = [0.0, 2.0, 0.0];
        let a = max_step(&x, &dx);
        assert!((a - 0.5).abs() < 1e-14);
        let mut y = [0.0; 3];
        for k in 0..3 {
            y[k] = x[k] + a * dx[k];
        }
        assert!(det(&y).abs() < 1e-12);
        assert_eq!(max_step(&x, &[1.0, 0.5, 0.0]), 1.0);
    }
}
