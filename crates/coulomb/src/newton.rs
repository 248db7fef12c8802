//! Semismooth Newton on the natural map of Coulomb's law.
//!
//! With ũ = u + μ‖u_T‖e the De Saxcé velocity (3.7), Coulomb's law (2.9) at contact i is the
//! complementarity K_μ ∋ rⁱ ⊥ ũⁱ ∈ K_μ* (Lemma 3.1, (3.9)), i.e. the zero of the natural map
//!
//! ```text
//!     Gⁱ(r) = rⁱ − P_{K_μ}(rⁱ − ũⁱ),      u = W r + q,
//! ```
//!
//! whose norm, divided by max(‖q‖, ‖r‖, ‖u‖), is exactly the error of docs/error.md. This
//! module drives ‖G‖ to zero by semismooth Newton steps with a backtracking line search on ‖G‖:
//! the generalized Jacobian is
//!
//! ```text
//!     J = I − D + D A W,     D = blockdiag ∂P_{K_μ}(rⁱ − ũⁱ),
//!     A = blockdiag ∂ũⁱ/∂uⁱ = [1  μ û_Tᵀ; 0  I],  û_T = u_T / ‖u_T‖,
//! ```
//!
//! solved by faer's sparse LU with a diagonal shift λ I that vanishes with ‖G‖ (and grows when
//! a direction gives no descent, as happens when J is singular: sticking contacts and more
//! contact unknowns than degrees of freedom). It is
//! the end game of [`crate::solver`]: the fixed point s = F(s) of §3.3 converges linearly, a
//! Newton step from an r with error ~1e-5 converges quadratically. The same pieces
//! (projection Jacobian, sparse LU) polish the interior-point solutions of the inner
//! problems (3.15) and (4.7) in [`crate::inner::ipm`].

use crate::deadline::Deadline;
use crate::linalg::normal::{Normal, NormalPattern};
use crate::linalg::pattern_lu::JacobianPattern;
/// At its former path: the size from which the sparse factorizations run on all threads.
pub use crate::linalg::pattern_lu::SPARSE_PARALLEL_DIM;
use crate::line_search::{armijo, Search};
use crate::natural_map::de_saxce_map;
use crate::problem::LocalProblem;

/// Parameters of the semismooth Newton end game ([`crate::outer::newton`]); the budget and
/// the starting level are [`crate::settings::MethodParams::newton_steps`] and
/// [`crate::settings::MethodParams::newton_start`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct NewtonParams {
    /// Newton steps one end-game try may take (all tries of a stage share
    /// [`crate::settings::MethodParams::newton_steps`])
    pub try_steps: usize,
    /// a failed try is tried again once the error is below this fraction of the error it
    /// started from
    pub retry: f64,
    /// outer iterations without a new lowest error after which the fixed point counts as
    /// stagnating (the end game is then tried again whatever its gate)
    pub stagnation: usize,
    /// a new lowest error counts as progress only below this fraction of the previous lowest
    pub stagnation_gain: f64,
    /// the natural map is driven below this fraction of tol · ‖q‖
    pub target_fraction: f64,
    /// first shift of a step: λ = `lambda_factor` · min(‖G‖/‖q‖, 1e-2) · max diag(W)
    /// (see [`crate::newton::LAMBDA_FACTOR`])
    pub lambda_factor: f64,
    /// a try stops after this many consecutive slow steps (see [`crate::newton::SLOW_STEPS`]); ≥ 1
    pub slow_steps: usize,
    /// a step with ‖G⁺‖ > `slow_ratio` ‖G‖ is slow (see [`crate::newton::SLOW_RATIO`]); in (0, 1]
    pub slow_ratio: f64,
    /// the first shift λ uses min(‖G‖/‖q‖, `shift_ratio_cap`) (see `lambda_factor`); > 0
    pub shift_ratio_cap: f64,
    /// directions (shifts λ) tried per step before the step counts as giving no descent; ≥ 1
    pub shift_tries: usize,
    /// after a direction without descent λ ← max(`shift_growth` · λ, `shift_floor` · max diag(W));
    /// > 1
    pub shift_growth: f64,
    /// see `shift_growth`; > 0
    pub shift_floor: f64,
    /// line search on the step δ: t = 1, then up to this many halvings of t
    pub halvings: usize,
    /// a trial point r + t δ is accepted when ‖G(r + t δ)‖ < ‖G(r)‖ and
    /// ‖G(r + t δ)‖ ≤ (1 − `sufficient_decrease` · t) ‖G(r)‖ (Armijo); in [0, 1)
    pub sufficient_decrease: f64,
    /// on a non-symmetric W, a try whose error fell to at most this fraction of the error it
    /// started from is followed by another try from its point (above it the end game stops
    /// and the fixed point goes on); in (0, 1]
    pub continue_gain: f64,
}

impl Default for NewtonParams {
    fn default() -> Self {
        NewtonParams {
            try_steps: 15,
            retry: 0.1,
            stagnation: 3,
            stagnation_gain: 0.5,
            target_fraction: 0.5,
            lambda_factor: LAMBDA_FACTOR,
            slow_steps: SLOW_STEPS,
            slow_ratio: SLOW_RATIO,
            shift_ratio_cap: 1e-2,
            shift_tries: 4,
            shift_growth: 100.0,
            shift_floor: 1e-10,
            halvings: 10,
            sufficient_decrease: 1e-4,
            continue_gain: 0.5,
        }
    }
}

/// Consecutive slow steps (‖G‖ reduced by less than 1 − [`SLOW_RATIO`]) after which
/// [`polish`] gives up.
pub const SLOW_STEPS: usize = 4;

/// The first shift of a step is λ = `LAMBDA_FACTOR` · (‖G‖ / ‖q‖) · max diag(W): small enough
/// to keep the quadratic convergence of the exact step where J is regular, large enough to
/// give a direction where it is singular (docs/tuning.md, `tuning.newton`).
pub const LAMBDA_FACTOR: f64 = 1e-2;

/// A step with ‖G⁺‖ > `SLOW_RATIO` ‖G‖ counts as slow.
pub const SLOW_RATIO: f64 = 0.9;

/// Newton steps of the end game per stage: the default of
/// [`crate::settings::MethodParams::newton_steps`].
pub const END_GAME_STEPS: usize = 30;

/// The end game is tried once the error of docs/error.md is ≤ this: the default of
/// [`crate::settings::MethodParams::newton_start`].
pub const END_GAME_START: f64 = 1e-3;

/// Why a semismooth Newton run ([`polish`], and the polish steps of the interior-point inner
/// solvers) stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewtonStatus {
    /// ‖G(r)‖ ≤ `target`
    Reached,
    /// the step cap was reached above the target
    MaxSteps,
    /// no step along the Newton direction decreased ‖G‖ (or the linear solve failed)
    NoDescent,
    /// [`SLOW_STEPS`] steps in a row were slow: far from the region of fast convergence
    Slow,
    /// the deadline passed
    TimeLimit,
}

/// The outcome of a semismooth Newton run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonReport {
    /// how it stopped
    pub status: NewtonStatus,
    /// Newton steps taken (accepted)
    pub steps: usize,
    /// ‖G(r)‖ at the returned r
    pub residual: f64,
}

/// A nonsmooth map G: ℝⁿ → ℝⁿ whose zero [`drive`] seeks, with its generalized Jacobian J.
/// The map keeps two slots (current point, trial point) of G and of what J is built from.
pub(crate) trait SemismoothMap {
    /// Evaluates G at `x` into the trial slot; returns the merit ‖G(x)‖ (in the map's own,
    /// possibly scaled, norm).
    fn eval_trial(&mut self, x: &[f64]) -> f64;
    /// Makes the trial slot the current one.
    fn accept_trial(&mut self);
    /// G at the current point.
    fn current(&self) -> &[f64];
    /// Builds J at the current point (once per step).
    fn build_jacobian(&mut self);
    /// Solves (J + λ I) δ = rhs in place (λ = 0: the plain Newton system); None if the
    /// factorization fails or δ is not finite.
    fn solve_shifted(&mut self, lambda: f64, rhs: &mut [f64]) -> Option<()>;
}

/// The regularization of the Newton system, J + λ I: the first λ of a step is
/// `factor` · min(‖G‖ / `residual_scale`, `ratio_cap`) · `diag_scale`, and it becomes
/// max(`growth` · λ, `floor` · `diag_scale`) for each of at most `tries` directions that give
/// no descent (a Levenberg–Marquardt-like direction where J is singular); the defaults
/// (cap 1e-2, growth 100, floor 1e-10, 4 tries) are in [`crate::settings::NewtonParams`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Shift {
    pub(crate) factor: f64,
    pub(crate) residual_scale: f64,
    pub(crate) diag_scale: f64,
    pub(crate) tries: usize,
    pub(crate) ratio_cap: f64,
    pub(crate) growth: f64,
    pub(crate) floor: f64,
}

/// What [`drive`] does when no direction of a step passes the Armijo search
/// ([`crate::line_search::armijo`]): each method's own policy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum OnExhausted {
    /// the run ends ([`NewtonStatus::NoDescent`]): the end game of (3.9) and the polish of
    /// the inner problems (4.7), (3.15)
    Stop,
    /// the full step x + δ of the last direction solved is taken (a non-monotone escape from
    /// a stationary point of the merit: the proximal point's Φ_ρ); a full step to a point
    /// that is not finite ends the run ([`NewtonStatus::NoDescent`])
    FullStep,
}

/// Caps and rules of one [`drive`] run.
#[derive(Debug, Clone, Copy)]
pub(crate) struct NewtonRule {
    /// stop once the merit is ≤ this
    pub(crate) target: f64,
    /// at most this many steps
    pub(crate) max_steps: usize,
    /// line search: the merit is tried at t = 1, ½, … , 2^{1 − `trials`} (1: the full step
    /// only; 0: no trial, every search is exhausted)
    pub(crate) trials: usize,
    /// a trial is accepted when its merit is < ‖G‖ and ≤ (1 − c t) ‖G‖ (c = this; 0: any
    /// decrease)
    pub(crate) sufficient_decrease: f64,
    /// None: λ = 0, one direction per step
    pub(crate) shift: Option<Shift>,
    /// when every direction of a step exhausts its search
    pub(crate) on_exhausted: OnExhausted,
    /// stop (`Slow`) after this many consecutive steps with merit > `slow_ratio` · before
    pub(crate) slow_steps: usize,
    /// see `slow_steps`
    pub(crate) slow_ratio: f64,
    /// no step starts after it
    pub(crate) deadline: Deadline,
}

/// The one damped semismooth Newton driver of the crate: the end game on the natural map
/// (3.9) ([`polish`]), the interior-point polish steps (dual (4.7) and primal (3.15) natural
/// maps) and the inner loop of the proximal point on Φ_ρ ([`crate::proximal`]). From `x`
/// (overwritten by the last iterate), steps δ from (J + λ I) δ = −G(x), each followed by the
/// Armijo search of `rule` and, where it is exhausted, `rule.on_exhausted`, until the merit
/// is ≤ `rule.target`, the step cap, no descent, too many slow steps, or the deadline.
/// Evaluates G at x first ([`drive_from`] when it is evaluated).
pub(crate) fn drive<M: SemismoothMap>(
    map: &mut M,
    x: &mut [f64],
    rule: &NewtonRule,
) -> NewtonReport {
    let merit = map.eval_trial(x);
    map.accept_trial();
    drive_from(map, x, merit, rule)
}

/// [`drive`] from an x whose G the map holds as its current point, `merit` its norm.
/// A NaN merit ends the run (`NoDescent`); an infinite one goes on to the linear solve,
/// which fails on the infinite right-hand side.
pub(crate) fn drive_from<M: SemismoothMap>(
    map: &mut M,
    x: &mut [f64],
    merit: f64,
    rule: &NewtonRule,
) -> NewtonReport {
    let n = x.len();
    let mut norm = merit;
    let mut trial = vec![0.0; n];
    let mut steps = 0;
    let mut slow_steps = 0;
    let status = loop {
        if norm.is_nan() {
            break NewtonStatus::NoDescent;
        }
        if norm <= rule.target {
            break NewtonStatus::Reached;
        }
        if steps >= rule.max_steps {
            break NewtonStatus::MaxSteps;
        }
        if rule.deadline.passed() {
            break NewtonStatus::TimeLimit;
        }
        map.build_jacobian();
        let before = norm;
        let (mut lambda, tries) = match rule.shift {
            Some(s) => (
                s.factor * (norm / s.residual_scale).min(s.ratio_cap) * s.diag_scale,
                s.tries,
            ),
            None => (0.0, 1),
        };
        let mut accepted = false;
        // the last direction solved whose search was exhausted
        let mut exhausted = None;
        for _ in 0..tries {
            if rule.deadline.passed() {
                break;
            }
            let mut delta: Vec<f64> = map.current().iter().map(|g| -g).collect();
            if map.solve_shifted(lambda, &mut delta).is_some() {
                let c = rule.sufficient_decrease;
                let search = armijo(norm, c, rule.trials, |t| {
                    for k in 0..n {
                        trial[k] = x[k] + t * delta[k];
                    }
                    map.eval_trial(&trial)
                });
                if let Search::Accepted { merit, .. } = search {
                    x.copy_from_slice(&trial);
                    map.accept_trial();
                    norm = merit;
                    accepted = true;
                } else {
                    exhausted = Some(delta);
                }
            }
            if accepted {
                break;
            }
            if let Some(s) = rule.shift {
                lambda = (lambda * s.growth).max(s.floor * s.diag_scale);
            }
        }
        if !accepted {
            match (rule.on_exhausted, exhausted) {
                (OnExhausted::FullStep, Some(delta)) => {
                    for (xk, dk) in x.iter_mut().zip(&delta) {
                        *xk += dk;
                    }
                    norm = map.eval_trial(x);
                    map.accept_trial();
                    if !x.iter().all(|v| v.is_finite()) {
                        steps += 1;
                        break NewtonStatus::NoDescent;
                    }
                }
                _ if rule.deadline.passed() => break NewtonStatus::TimeLimit,
                _ => break NewtonStatus::NoDescent,
            }
        }
        steps += 1;
        slow_steps = if norm > rule.slow_ratio * before {
            slow_steps + 1
        } else {
            0
        };
        if slow_steps >= rule.slow_steps && norm > rule.target {
            break NewtonStatus::Slow;
        }
    };
    NewtonReport {
        status,
        steps,
        residual: norm,
    }
}

/// ‖G(r)‖ of the De Saxcé natural map of `p` at r ([`de_saxce_map`] with u = W r + q; G, D
/// and B = D A written as there).
fn de_saxce_map_norm(
    p: &LocalProblem,
    r: &[f64],
    g: &mut [f64],
    dblocks: &mut [f64],
    blocks: &mut [f64],
) -> f64 {
    let mut u = p.q.clone();
    p.w.gemv_acc(1.0, r, &mut u);
    de_saxce_map(p.dim, &p.mu, r, &u, g, dblocks, blocks);
    crate::law::norm(g)
}

/// The De Saxcé natural map G(r) = r − P_L(r − ũ(W r + q)) of a local problem, with the
/// data of its Jacobian J = I − D + D A W on a fixed pattern.
struct DeSaxceMap<'a> {
    p: &'a LocalProblem,
    pattern: JacobianPattern,
    /// G, D blocks, B = D A blocks: current and trial
    g: [Vec<f64>; 2],
    dblocks: [Vec<f64>; 2],
    blocks: [Vec<f64>; 2],
    vals: Vec<f64>,
    wcol: Vec<f64>,
}

impl SemismoothMap for DeSaxceMap<'_> {
    fn eval_trial(&mut self, r: &[f64]) -> f64 {
        let (g, dblocks, blocks) = (&mut self.g[1], &mut self.dblocks[1], &mut self.blocks[1]);
        de_saxce_map_norm(self.p, r, g, dblocks, blocks)
    }

    fn accept_trial(&mut self) {
        self.g.swap(0, 1);
        self.dblocks.swap(0, 1);
        self.blocks.swap(0, 1);
    }

    fn current(&self) -> &[f64] {
        &self.g[0]
    }

    fn build_jacobian(&mut self) {
        let (dblocks, blocks) = (&self.dblocks[0], &self.blocks[0]);
        self.pattern
            .fill(self.p, dblocks, blocks, &mut self.wcol, &mut self.vals);
    }

    fn solve_shifted(&mut self, lambda: f64, rhs: &mut [f64]) -> Option<()> {
        let mut shifted = self.vals.clone();
        self.pattern.shift_diagonal(&mut shifted, lambda);
        self.pattern.solve(&shifted, rhs)
    }
}

/// Levenberg–Marquardt on the natural map G(r) = r − P_L(r − ũ(W r + q)) itself, whose norm
/// over max(‖q‖, ‖r‖, ‖u‖) is the error of docs/error.md: from `r` projected onto
/// L = Π K_μᵢ (overwritten by the iterate of lowest error), each step solves the
/// least-squares system
///
/// ```text
///     (JᵀJ + λ ν I) δ = −Jᵀ G,     J = I − D + D A W,   ν = trace(JᵀJ) / m,
/// ```
///
/// with J on W's block pattern (as [`polish`] builds it) and a sparse Cholesky factorization of
/// JᵀJ + λνI on its block pattern (symbolic once per call, [`crate::levenberg`]'s), and takes
/// P_L(r + δ) where it lowers the error (then λ ← λ/10), else tries λ ← 10 λ (at most 6
/// times): every iterate lies in L, as a solver's starting point does (an r outside L can
/// have a small natural-map residual that its projection does not have).
/// Where J is singular and G(r) is not in its range — an active set that no r satisfies
/// exactly, as on rigid piles (docs/rigid.md) — the semismooth Newton step of [`polish`] has
/// no descent, while this step goes to the least-squares point of the linearization: the
/// error there is the floor of that active set, which may lie below the tolerance. At most
/// `max_steps` accepted steps; stops once the error is ≤ `target`, when no λ gives a
/// decrease, after `slow_steps` steps in a row that each leave more than [`SLOW_RATIO`] of
/// the error (at that floor: `Slow`; 0: no such stop), or at `deadline`. A problem whose
/// sizes disagree, or whose JᵀJ would have more than `max_normal_nonzeros` entries (or fails
/// its symbolic factorization), takes no step (`NoDescent`; residual NaN for the former, r
/// untouched). `residual` reports the error of docs/error.md at the returned r (not ‖G‖).
pub fn least_squares(
    p: &LocalProblem,
    r: &mut [f64],
    target: f64,
    max_steps: usize,
    slow_steps: usize,
    max_normal_nonzeros: usize,
    deadline: Deadline,
) -> NewtonReport {
    let (d, m) = (p.dim, r.len());
    let mut report = NewtonReport {
        status: NewtonStatus::NoDescent,
        steps: 0,
        residual: f64::NAN,
    };
    if !p.fits(r) || !r.iter().all(|x| x.is_finite()) || d == 0 {
        return report;
    }
    crate::cone::project_product(d, &p.mu, r);
    let mut err = p.error(r).error;
    report.residual = err;
    if err <= target {
        report.status = NewtonStatus::Reached;
        return report;
    }
    let jac = JacobianPattern::without_lu(p);
    let Some(normal) = NormalPattern::new(&jac, d, max_normal_nonzeros) else {
        return report;
    };
    let mut normal = Normal::new(&jac, normal, m);
    let (mut g, mut dblocks, mut blocks) = (vec![0.0; m], vec![0.0; m * d], vec![0.0; m * d]);
    let (mut wcol, mut jv) = (vec![0.0; m], Vec::new());
    let mut lambda = 1e-8;
    let mut trial = vec![0.0; m];
    let mut slow = 0;
    while err > target && report.steps < max_steps {
        if deadline.passed() {
            report.status = NewtonStatus::TimeLimit;
            return report;
        }
        let mut u = p.q.clone();
        p.w.gemv_acc(1.0, r, &mut u);
        de_saxce_map(d, &p.mu, r, &u, &mut g, &mut dblocks, &mut blocks);
        jac.fill(p, &dblocks, &blocks, &mut wcol, &mut jv);
        // trace(JᵀJ) = ‖J‖²_F
        let nu = jv.iter().map(|x| x * x).sum::<f64>() / m as f64;
        if !(nu.is_finite() && nu > 0.0) {
            return report;
        }
        let mut accepted = false;
        let before = err;
        for _ in 0..6 {
            if deadline.passed() {
                report.status = NewtonStatus::TimeLimit;
                return report;
            }
            if let Some(step) = normal.direction(&jv, lambda * nu, &g) {
                for ((t, x), s) in trial.iter_mut().zip(r.iter()).zip(&step) {
                    *t = x + s;
                }
                crate::cone::project_product(d, &p.mu, &mut trial);
                let e = p.error(&trial).error;
                if e < err {
                    r.copy_from_slice(&trial);
                    err = e;
                    lambda = (lambda / 10.0).max(1e-14);
                    accepted = true;
                    break;
                }
            }
            lambda *= 10.0;
        }
        report.residual = err;
        if !accepted {
            return report;
        }
        report.steps += 1;
        slow = if err > SLOW_RATIO * before {
            slow + 1
        } else {
            0
        };
        if slow_steps > 0 && slow >= slow_steps && err > target {
            report.status = NewtonStatus::Slow;
            return report;
        }
    }
    report.status = if err <= target {
        NewtonStatus::Reached
    } else {
        NewtonStatus::MaxSteps
    };
    report
}

/// Semismooth Newton on G(r) = r − P_L(r − ũ(W r + q)) from `r` (overwritten by the best
/// iterate), by `drive`: at most `max_steps` steps, each a direction from (J + λ I) δ = −G
/// ([`LAMBDA_FACTOR`], up to 4 shifts) followed by a backtracking line search that accepts the
/// first t ∈ {1, ½, ¼, …} (≥ 2⁻¹⁰) with ‖G(r + t δ)‖ ≤ (1 − 10⁻⁴ t) ‖G(r)‖. Stops once
/// ‖G‖ ≤ `target`, when no step decreases ‖G‖, after [`SLOW_STEPS`] slow steps in a row, or
/// at `deadline`. A problem whose sizes disagree (d, μ, q, W, r) takes no step (`NoDescent`,
/// residual NaN).
pub fn polish(
    p: &LocalProblem,
    r: &mut [f64],
    target: f64,
    max_steps: usize,
    deadline: Deadline,
) -> NewtonReport {
    let params = NewtonParams::default();
    polish_with(p, r, target, max_steps, deadline, &params)
}

/// [`polish`] with the shift, line-search and slow-step constants of `params`
/// ([`crate::settings::NewtonParams`]: `lambda_factor`, `shift_ratio_cap`, `shift_tries`,
/// `shift_growth`, `shift_floor`, `halvings`, `sufficient_decrease`, `slow_steps`,
/// `slow_ratio`).
pub fn polish_with(
    p: &LocalProblem,
    r: &mut [f64],
    target: f64,
    max_steps: usize,
    deadline: Deadline,
    params: &NewtonParams,
) -> NewtonReport {
    let (d, m) = (p.dim, r.len());
    if !p.fits(r) {
        // inconsistent sizes (a hand-built problem that skipped validation): no step is taken
        return NewtonReport {
            status: NewtonStatus::NoDescent,
            steps: 0,
            residual: f64::NAN,
        };
    }
    let diag_scale = (0..m)
        .map(|j| {
            (p.w.col_ptr[j]..p.w.col_ptr[j + 1])
                .filter(|&k| p.w.row_idx[k] == j)
                .map(|k| p.w.values[k].abs())
                .sum::<f64>()
        })
        .fold(0.0f64, f64::max)
        .max(1.0);
    let q_scale = crate::law::norm(&p.q).max(f64::MIN_POSITIVE);
    let blocks = vec![0.0; p.mu.len() * d * d];
    let Some(pattern) = JacobianPattern::new(p) else {
        let mut g = vec![0.0; m];
        let (mut db, mut b) = (blocks.clone(), blocks);
        return NewtonReport {
            status: NewtonStatus::NoDescent,
            steps: 0,
            residual: de_saxce_map_norm(p, r, &mut g, &mut db, &mut b),
        };
    };
    let mut map = DeSaxceMap {
        p,
        pattern,
        g: [vec![0.0; m], vec![0.0; m]],
        dblocks: [blocks.clone(), blocks.clone()],
        blocks: [blocks.clone(), blocks],
        vals: Vec::new(),
        wcol: vec![0.0; m],
    };
    let rule = NewtonRule {
        target,
        max_steps,
        trials: params.halvings + 1,
        sufficient_decrease: params.sufficient_decrease,
        shift: Some(Shift {
            factor: params.lambda_factor,
            residual_scale: q_scale,
            diag_scale,
            tries: params.shift_tries,
            ratio_cap: params.shift_ratio_cap,
            growth: params.shift_growth,
            floor: params.shift_floor,
        }),
        on_exhausted: OnExhausted::Stop,
        slow_steps: params.slow_steps,
        slow_ratio: params.slow_ratio,
        deadline,
    };
    drive(&mut map, r, &rule)
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use crate::linalg::sparse::CscMatrix;
    use crate::natural_map::{push_d_times, push_identity_minus_d};

    /// G(x) = x with the Jacobian reported as −I: every direction δ = x is an ascent
    /// direction, so every Armijo search is exhausted.
    struct Ascent {
        g: [Vec<f64>; 2],
    }

    impl SemismoothMap for Ascent {
        fn eval_trial(&mut self, x: &[f64]) -> f64 {
            self.g[1].copy_from_slice(x);
            crate::law::norm(x)
        }
        fn accept_trial(&mut self) {
            self.g.swap(0, 1);
        }
        fn current(&self) -> &[f64] {
            &self.g[0]
        }
        fn build_jacobian(&mut self) {}
        fn solve_shifted(&mut self, lambda: f64, rhs: &mut [f64]) -> Option<()> {
            rhs.iter_mut().for_each(|v| *v /= lambda - 1.0);
            Some(())
        }
    }

    pub fn an_exhausted_search_stops_or_takes_the_full_step_as_the_rule_says() {
        let rule = |on_exhausted| NewtonRule {
            target: 0.0,
            max_steps: 3,
            trials: 5,
            sufficient_decrease: 1e-4,
            shift: None,
            on_exhausted,
            slow_steps: usize::MAX,
            slow_ratio: 1.0,
            deadline: Deadline::NEVER,
        };
        let mut map = Ascent {
            g: [vec![0.0; 2], vec![0.0; 2]],
        };
        let mut x = [1.0, -2.0];
        let report = drive(&mut map, &mut x, &rule(OnExhausted::Stop));
        assert_eq!((report.status, report.steps), (NewtonStatus::NoDescent, 0));
        assert_eq!(x, [1.0, -2.0]);
        // the full step x + δ = 2x, three times
        let report = drive(&mut map, &mut x, &rule(OnExhausted::FullStep));
        assert_eq!((report.status, report.steps), (NewtonStatus::MaxSteps, 3));
        assert_eq!(x, [8.0, -16.0]);
        assert_eq!(report.residual, crate::law::norm(&x));
        // a full step to a point that is not finite ends the run
        let mut x = [f64::MAX, 0.0];
        let report = drive(&mut map, &mut x, &rule(OnExhausted::FullStep));
        assert_eq!((report.status, report.steps), (NewtonStatus::NoDescent, 1));
        assert!(x[0].is_infinite());
    }

    pub fn least_squares_reaches_a_solution_nearby_and_never_raises_the_error() {
        // a regular problem: from a solution moved by 1e-6, the target in a few steps
        let p = problem(5, 3, 0.5);
        let mut sol = vec![0.0; 15];
        polish(&p, &mut sol, 1e-14, 100, Deadline::NEVER);
        assert!(p.error(&sol).error < 1e-12);
        let mut r: Vec<f64> = sol
            .iter()
            .enumerate()
            .map(|(i, x)| x + 1e-6 * ((i % 3) as f64 - 1.0))
            .collect();
        let start = p.error(&r).error;
        let rep = least_squares(&p, &mut r, 1e-11, 8, 0, NONZEROS, Deadline::NEVER);
        assert_eq!(rep.status, NewtonStatus::Reached, "{rep:?} from {start:e}");
        assert!(rep.steps <= 8 && rep.residual <= 1e-11);
        assert_eq!(rep.residual, p.error(&r).error);
        // rank-deficient, W not symmetric: whatever it reaches, the returned r is no worse
        // than the start and its error is the one reported
        let q = crate::test_problems::problem(6, 2811, 0.0, 1e-3);
        let mut r = vec![0.1; 18];
        let start = q.error(&crate::problem::projected(&q, &r)).error;
        let rep = least_squares(&q, &mut r, 1e-12, 5, 2, NONZEROS, Deadline::NEVER);
        assert!(
            rep.residual <= start && rep.residual == q.error(&r).error,
            "{rep:?}"
        );
        // every returned point lies in the cones: it is its own projection
        assert_eq!(r, crate::problem::projected(&q, &r));
        // sizes that disagree: no step
        let rep = least_squares(&q, &mut [0.0; 5], 1e-8, 5, 2, NONZEROS, Deadline::NEVER);
        assert_eq!(rep.status, NewtonStatus::NoDescent);
        assert!(rep.residual.is_nan());
        // a JᵀJ above the cap on its entries: no step, r projected, its error reported
        let mut r = vec![0.1; 18];
        let rep = least_squares(&q, &mut r, 1e-12, 5, 2, 10, Deadline::NEVER);
        assert_eq!((rep.status, rep.steps), (NewtonStatus::NoDescent, 0));
        assert_eq!(r, crate::problem::projected(&q, &[0.1; 18]));
        assert_eq!(rep.residual, q.error(&r).error);
    }

    /// The default cap on the entries of JᵀJ ([`crate::settings::LmParams::max_normal_nonzeros`]).
    const NONZEROS: usize = 40_000_000;

    /// A deterministic pseudo-random local problem with W = AᵀA + δI (d = 3).
    fn problem(contacts: usize, seed: u64, delta: f64) -> LocalProblem {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let m = 3 * contacts;
        let k = m.saturating_sub(2).max(1);
        let a: Vec<f64> = (0..k * m).map(|_| next()).collect();
        let mut w = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                w[i * m + j] = (0..k).map(|l| a[l * m + i] * a[l * m + j]).sum::<f64>()
                    + if i == j { delta } else { 0.0 };
            }
        }
        LocalProblem {
            dim: 3,
            w: CscMatrix::from_dense(m, m, &w),
            q: (0..m).map(|_| next()).collect(),
            mu: (0..contacts).map(|_| 0.2 + 0.5 * next().abs()).collect(),
        }
    }

    pub fn jacobian_matches_finite_differences() {
        let p = problem(4, 7, 0.1);
        let m = 12;
        for trial in 0..20u64 {
            let r: Vec<f64> = (0..m)
                .map(|k| ((k as f64 + 1.0) * (trial as f64 + 0.37)).sin())
                .collect();
            let dir: Vec<f64> = (0..m).map(|k| ((k * 7 + 3) as f64).cos()).collect();
            let mut g = vec![0.0; m];
            let mut db = vec![0.0; 36];
            let mut b = vec![0.0; 36];
            de_saxce_map_norm(&p, &r, &mut g, &mut db, &mut b);
            let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
            push_identity_minus_d(3, &db, 0, &mut rows, &mut cols, &mut vals);
            push_d_times(
                3,
                &b,
                1.0,
                p.w.triplets(),
                0,
                &mut rows,
                &mut cols,
                &mut vals,
            );
            let j = CscMatrix::from_triplets(m, m, &rows, &cols, &vals).unwrap();
            let jd = j.mul_vec(&dir);
            let eps = 1e-7;
            let rp: Vec<f64> = r.iter().zip(&dir).map(|(x, d)| x + eps * d).collect();
            let mut gp = vec![0.0; m];
            de_saxce_map_norm(&p, &rp, &mut gp, &mut db, &mut b);
            for k in 0..m {
                let fd = (gp[k] - g[k]) / eps;
                assert!(
                    (fd - jd[k]).abs() <= 1e-4 * (1.0 + fd.abs()),
                    "trial {trial} row {k}: J δ = {} but finite difference {fd}",
                    jd[k]
                );
            }
        }
    }

    pub fn inconsistent_sizes_take_no_step_instead_of_panicking() {
        let mut p = problem(2, 1, 0.5);
        p.mu.push(0.3); // three friction coefficients for two contacts
        let mut r = vec![0.0; 6];
        let out = polish(&p, &mut r, 0.0, 5, Deadline::NEVER);
        assert_eq!((out.status, out.steps), (NewtonStatus::NoDescent, 0));
        assert!(r.iter().all(|&x| x == 0.0));
        let p = problem(2, 1, 0.5);
        let mut short = vec![0.0; 5];
        assert_eq!(polish(&p, &mut short, 0.0, 5, Deadline::NEVER).steps, 0);
    }

    pub fn newton_reaches_rounding_level_from_a_rough_point() {
        let p = problem(5, 3, 0.5);
        let mut r = vec![0.0; 15];
        let out = polish(&p, &mut r, 0.0, 50, Deadline::NEVER);
        let u = p.velocity(&r);
        let err = crate::law::error_measure(3, &p.mu, &r, &u, crate::law::norm(&p.q)).error;
        assert!(err < 1e-12, "error {err:.3e} after {out:?}");
    }
}
