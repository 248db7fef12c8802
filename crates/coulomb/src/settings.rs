//! What a solve is asked to do. [`Settings`] holds what a user changes: the method (an inner
//! solver of F(s) and an outer iteration on s, §3.3 and §6 of the paper, and a fallback), the
//! stopping tolerance, the iteration and time limits and a cancel request. One level down,
//! [`MethodParams`] holds the method's parameters (warm-up and interior-point tries, inner
//! tolerance, Newton end game, rule (6.1), facets) and every tuning constant of the outer loop
//! in one typed, documented [`Tuning`] struct.
//!
//! # One meaning per tolerance
//! - [`Settings::tol`]: the bound on the error of `docs/error.md` of the returned r (and on
//!   the balance residual of a global problem); the only tolerance a status is decided by.
//! - [`MethodParams::fixed_point_tol`]: ε of the paper's rule (6.1), an extra stopping test on
//!   ‖F(s) − s‖ / (n (‖s‖ + 1)); it never makes a solve "converged".
//! - The inner tolerance (see [`Tuning::inner_tol`]): the tolerance handed to an inner solver
//!   in [`crate::inner::InnerLimits::tol`], on that solver's own relative optimality measure;
//!   it is derived from `tol` and the error of the current outer iterate, never set directly.
//! - [`MethodParams::newton_start`]: an error level (of `docs/error.md`) below which the
//!   Newton end game is tried; not a stopping test.

pub use crate::barrier::{BarrierParams, BARRIER_MAX_WORK};
pub use crate::inner::apgd::ApgdParams;
pub use crate::inner::RayParams;
pub use crate::levenberg::LmParams;
pub use crate::multiplier::{MultiplierParams, MULTIPLIER_MAX_FACTORIZATIONS};
pub use crate::newton::NewtonParams;
pub use crate::outer::anderson::AndersonParams;
pub use crate::proximal::{ProxParams, PROX_CAPPED_MAX_STEPS, PROX_MAX_STEPS};
use std::fmt;
use std::str::FromStr;
use std::time::Duration;

/// Which method computes F(s) (§6, options (i), (iv), (v)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum InnerKind {
    /// Clarabel interior point on the SOC-QP (primal (3.15) for global problems, dual (4.7) for local).
    Ipm,
    /// accelerated projected gradient (FISTA with adaptive restart) on (4.7)
    Apgd,
    /// projected block Gauss–Seidel on (4.7), exact one-contact solves
    Pgs,
    /// faceted cone: each K_μ replaced by a k-facet pyramid, QP solved by Clarabel
    Faceted,
}

/// How the fixed point s = F(s) is sought.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum OuterKind {
    /// successive approximation s ← F(s)
    FixedPoint,
    /// safeguarded Anderson mixing on s
    Anderson,
    /// no separate outer loop: Gauss–Seidel directly on Coulomb's law, contact i given a
    /// solution of its own law (2.9) with the others frozen (needs `InnerKind::Pgs`).
    /// Convergence is decided by the error measure like every other choice.
    Fused,
}

impl InnerKind {
    /// Every inner solver, in the order of reports.
    pub const ALL: [InnerKind; 4] = [
        InnerKind::Pgs,
        InnerKind::Apgd,
        InnerKind::Ipm,
        InnerKind::Faceted,
    ];

    /// The name used on command lines, in the Python bindings and in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            InnerKind::Ipm => "ipm",
            InnerKind::Apgd => "apgd",
            InnerKind::Pgs => "pgs",
            InnerKind::Faceted => "faceted",
        }
    }
}

impl OuterKind {
    /// Every outer iteration.
    pub const ALL: [OuterKind; 3] = [OuterKind::FixedPoint, OuterKind::Anderson, OuterKind::Fused];

    /// The name used on command lines, in the Python bindings and in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            OuterKind::FixedPoint => "fixed_point",
            OuterKind::Anderson => "anderson",
            OuterKind::Fused => "fused",
        }
    }
}

/// A name that is not one of the known solvers.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} {name:?}; expected one of {expected}")]
pub struct ParseMethodError {
    /// what was parsed ("inner solver", "outer iteration", "method")
    pub what: &'static str,
    /// the name given
    pub name: String,
    /// the accepted names, comma separated
    pub expected: String,
}

fn parse_named<T: Copy>(
    what: &'static str,
    s: &str,
    all: &[T],
    name: impl Fn(T) -> &'static str,
) -> Result<T, ParseMethodError> {
    let key = s.trim().to_ascii_lowercase().replace('-', "_");
    all.iter()
        .copied()
        .find(|&k| name(k) == key)
        .ok_or_else(|| ParseMethodError {
            what,
            name: s.trim().to_string(),
            expected: all.iter().map(|&k| name(k)).collect::<Vec<_>>().join(", "),
        })
}

impl FromStr for InnerKind {
    type Err = ParseMethodError;
    /// `ipm`, `apgd`, `pgs` or `faceted` (case-insensitive).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        parse_named("inner solver", s, &Self::ALL, Self::as_str)
    }
}

impl FromStr for OuterKind {
    type Err = ParseMethodError;
    /// `fixed_point` (or `fixed-point`), `anderson` or `fused` (case-insensitive).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        parse_named("outer iteration", s, &Self::ALL, Self::as_str)
    }
}

impl fmt::Display for InnerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.as_str())
    }
}

impl fmt::Display for OuterKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.as_str())
    }
}

/// One method: an inner solver of F(s) inside an outer iteration on s. Written `inner` (plain
/// fixed point s ← F(s)) or `inner+outer`, e.g. `apgd+anderson`, `pgs+fused`; the one
/// spelling of every CLI command and of the Python bindings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Method {
    /// the solver of the inner problem (3.15)/(4.7)
    pub inner: InnerKind,
    /// the outer iteration on s
    pub outer: OuterKind,
}

impl Method {
    /// The method (`inner`, `outer`).
    pub const fn new(inner: InnerKind, outer: OuterKind) -> Self {
        Self { inner, outer }
    }

    /// Whether the pair can run: the fused outer iteration needs the `pgs` inner solver.
    pub fn is_valid(self) -> bool {
        self.outer != OuterKind::Fused || self.inner == InnerKind::Pgs
    }
}

impl From<(InnerKind, OuterKind)> for Method {
    fn from((inner, outer): (InnerKind, OuterKind)) -> Self {
        Self { inner, outer }
    }
}

impl From<Method> for (InnerKind, OuterKind) {
    fn from(m: Method) -> Self {
        (m.inner, m.outer)
    }
}

impl fmt::Display for Method {
    /// `inner` for the plain fixed point, `inner+outer` otherwise.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.outer {
            OuterKind::FixedPoint => f.pad(self.inner.as_str()),
            outer => f.pad(&format!("{}+{}", self.inner, outer)),
        }
    }
}

impl FromStr for Method {
    type Err = ParseMethodError;
    /// `inner` or `inner+outer` (case-insensitive, blanks around the names ignored).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (inner, outer) = match s.split_once('+') {
            Some((i, o)) => (i.parse()?, o.parse()?),
            None => (s.parse()?, OuterKind::FixedPoint),
        };
        Ok(Self { inner, outer })
    }
}

/// Parameters of the inner solvers of (4.7): the constants each has always used, as
/// defaults. A [`crate::Solver`] builds its inner solvers with them.
///
/// The one-contact solves of projected Gauss–Seidel and of the fused method
/// ([`crate::inner::contact`]) run once per contact and sweep, so their tolerances stay
/// `const`s there (each documented where it is defined): `PIVOT` (a d × d block counts as
/// singular when its pivots fall below `PIVOT` · scale), `SINGULAR_TRACE` and
/// `REGULARIZATION` (a block of trace ≤ `SINGULAR_TRACE` · ‖W‖ gets
/// `REGULARIZATION` · trace added to its diagonal), `ANGLE_STEP` and `SLIP_STEP` (Newton on
/// the boundary angle of the SOC-QP and on the slip angle of (2.9) has converged at a step
/// below these), `ANGLE_NEWTON_STEPS`, `MAX_ANGLE_STEP`, `ANGLE_GRADIENT_STEP`,
/// `ANGLE_SAMPLES` and `ANGLE_SEEDS` (the boundary-angle search), `MULTIPLIER` (the KKT
/// multiplier may be −`MULTIPLIER` · ‖c‖ by rounding), `LAW_RESIDUAL` (a sliding solution
/// of (2.9) is kept when its residual is ≤ `LAW_RESIDUAL` (‖A r‖ + ‖c‖)) and
/// `FALLBACK_STEPS` (projected-gradient steps of the last resort).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct InnerParams {
    /// APGD: power iterations of the initial estimate L of λ_max(W) (the step is 1/L, raised
    /// by backtracking when too small); ≥ 1
    pub apgd_power_iterations: usize,
    /// APGD: a Barzilai–Borwein trial step ‖Δx‖²/(Δxᵀ W Δx) (backtracked) instead of the
    /// running 1/L
    pub apgd_barzilai_borwein: bool,
    /// projected Gauss–Seidel (inner solver and fused method): sweeps between exact
    /// recomputations of the maintained u = W r + b (against drift); ≥ 1
    pub gs_refresh: usize,
    /// fused method: sweeps between two Anderson steps of its Gauss–Seidel iteration, each kept
    /// only where it lowers the error ([`crate::outer::fused`]); 0: no mixing
    pub gs_anderson_period: usize,
    /// fused method: memory of that Anderson mixing; ≥ 1
    pub gs_anderson_memory: usize,
    /// interior point: semismooth Newton steps that polish Clarabel's r on the natural map
    /// (0: none; see [`crate::inner::ipm::DEFAULT_POLISH_STEPS`])
    pub ipm_polish_steps: usize,
    /// APGD's step-size control
    pub apgd: ApgdParams,
    /// the infeasible-ray test of (4.7) (stage, Gauss–Seidel, APGD)
    pub infeasible_ray: RayParams,
}

impl Default for InnerParams {
    fn default() -> Self {
        Self {
            apgd_power_iterations: crate::inner::apgd::POWER_ITERATIONS,
            apgd_barzilai_borwein: false,
            gs_refresh: crate::inner::pgs::REFRESH,
            gs_anderson_period: crate::outer::fused::ANDERSON_PERIOD,
            gs_anderson_memory: crate::outer::fused::ANDERSON_MEMORY,
            ipm_polish_steps: crate::inner::ipm::DEFAULT_POLISH_STEPS,
            apgd: ApgdParams::default(),
            infeasible_ray: RayParams::default(),
        }
    }
}

/// Every tuning constant of the outer loop, in one place; not meant to be changed per problem.
/// What each field does, its range and how its default was measured (or that it was not
/// recorded): docs/tuning.md.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Tuning {
    /// the inner tolerance is kept at least `inner_tol_floor` × tol (see [`Tuning::inner_tol`])
    pub inner_tol_floor: f64,
    /// … and at most this (absolute, on the inner solver's relative measure)
    pub inner_tol_ceiling: f64,
    /// the fused Gauss–Seidel stops its batch of sweeps at this fraction of tol
    pub fused_tol_fraction: f64,
    /// outer iterations over which the error must halve for a first stage that has a fallback
    /// to be considered progressing ([`crate::Status::Stalled`] otherwise)
    pub stall_window: usize,
    /// outer iterations with error ≤ tol but balance residual > tol after which the stage ends
    /// with [`crate::Status::BalanceResidual`]
    pub balance_stalls: usize,
    /// impulses with ‖W‖ ‖r‖ above this multiple of max(‖q‖, ‖u‖) count as unbounded
    /// ([`crate::Status::Unbounded`])
    pub unbounded_ratio: f64,
    /// Anderson mixing
    pub anderson: AndersonParams,
    /// Newton end game
    pub newton: NewtonParams,
    /// Levenberg–Marquardt end game after the Newton end game's budget is spent
    pub lm: LmParams,
    /// proximal-point end game after a stalled Levenberg–Marquardt run
    pub prox: ProxParams,
    /// the method of multipliers in the velocities (global rigid problems)
    pub multiplier: MultiplierParams,
    /// the interior-point try on Coulomb's law
    pub barrier: BarrierParams,
    /// the inner solvers' parameters
    pub inner: InnerParams,
}

impl Default for Tuning {
    fn default() -> Self {
        Self {
            inner_tol_floor: 0.2,
            inner_tol_ceiling: 1e-2,
            fused_tol_fraction: crate::outer::fused::TOL_FRACTION,
            stall_window: STALL_WINDOW,
            balance_stalls: 3,
            unbounded_ratio: UNBOUNDED_RATIO,
            anderson: AndersonParams::default(),
            newton: NewtonParams::default(),
            lm: LmParams::default(),
            prox: ProxParams::default(),
            multiplier: MultiplierParams::default(),
            barrier: BarrierParams::default(),
            inner: InnerParams::default(),
        }
    }
}

impl Tuning {
    /// The tolerance of the next inner solve, on the inner solver's own relative measure:
    /// `inner_tol_factor` × (error of the current outer iterate), kept in
    /// [`Tuning::inner_tol_floor`] · tol … [`Tuning::inner_tol_ceiling`]; solvers that start
    /// cold at each outer iteration (interior point, faceted), and frictionless problems
    /// (where the inner problem is the whole problem, §5.1), get the floor at once.
    pub fn inner_tol(&self, settings: &Settings, error: f64, cold_or_frictionless: bool) -> f64 {
        let floor = self.inner_tol_floor * settings.tol;
        if cold_or_frictionless {
            floor
        } else {
            (settings.params.inner_tol_factor * error)
                .min(self.inner_tol_ceiling)
                .max(floor)
        }
    }

    fn validate(&self) -> Result<(), String> {
        let frac = |x: f64| x.is_finite() && x > 0.0 && x <= 1.0;
        if !frac(self.inner_tol_floor)
            || !frac(self.fused_tol_fraction)
            || !frac(self.newton.retry)
            || !frac(self.newton.stagnation_gain)
            || !frac(self.newton.target_fraction)
            || !frac(self.newton.continue_gain)
            || !frac(self.newton.slow_ratio)
            || !frac(self.inner.apgd.lip_floor)
            || !frac(self.inner.apgd.lip_decay)
        {
            return Err("tuning fractions must be in (0, 1]".into());
        }
        if !(self.inner_tol_ceiling.is_finite() && self.inner_tol_ceiling > 0.0) {
            return Err("tuning.inner_tol_ceiling must be positive".into());
        }
        if !(self.unbounded_ratio.is_finite() && self.unbounded_ratio > 1.0) {
            return Err("tuning.unbounded_ratio must be finite and above 1".into());
        }
        if self.stall_window == 0
            || self.balance_stalls == 0
            || self.anderson.memory == 0
            || self.newton.try_steps == 0
            || self.newton.stagnation == 0
            || self.inner.apgd_power_iterations == 0
            || self.inner.gs_refresh == 0
            || self.inner.gs_anderson_memory == 0
            || self.newton.slow_steps == 0
            || self.newton.shift_tries == 0
            || self.inner.apgd.backtrack_tries == 0
            || self.inner.apgd.ray_period == 0
        {
            return Err("tuning counts must be at least 1".into());
        }
        if !(self.newton.lambda_factor.is_finite() && self.newton.lambda_factor >= 0.0) {
            return Err("tuning.newton.lambda_factor must be finite and ≥ 0".into());
        }
        let positive = |x: f64| x.is_finite() && x > 0.0;
        let n = &self.newton;
        let above_one = |x: f64| x.is_finite() && x > 1.0;
        if !(positive(n.shift_ratio_cap) && positive(n.shift_floor) && above_one(n.shift_growth)) {
            return Err("tuning.newton shift parameters: cap, floor > 0, growth > 1".into());
        }
        if !(n.sufficient_decrease.is_finite() && (0.0..1.0).contains(&n.sufficient_decrease)) {
            return Err("tuning.newton.sufficient_decrease must be in [0, 1)".into());
        }
        let a = &self.inner.apgd;
        let at_least = |x: f64, lo: f64| x.is_finite() && x >= lo;
        if !(above_one(a.backtrack_growth)
            && at_least(a.backtrack_margin, 1.0)
            && at_least(a.backtrack_slack, 0.0))
        {
            return Err("tuning.inner.apgd: backtrack growth > 1, margin ≥ 1, slack ≥ 0".into());
        }
        let ray = &self.inner.infeasible_ray;
        if !(positive(ray.residual) && positive(ray.descent)) {
            return Err("tuning.inner.infeasible_ray thresholds must be positive".into());
        }
        self.barrier.validate()?;
        self.prox.validate()?;
        self.multiplier.validate()?;
        self.lm.validate()
    }
}

/// Impulses with ‖W‖ ‖r‖ above this multiple of max(‖q‖, ‖u‖) count as unbounded
/// ([`crate::Status::Unbounded`]): for a bounded solution W r = u − q is of the order of the
/// data (docs/tuning.md, `Tuning`). The default of [`Tuning::unbounded_ratio`].
pub const UNBOUNDED_RATIO: f64 = 1e6;

/// Outer iterations over which the error must halve for a first stage to be considered
/// progressing (see [`Settings::fallback`]). The default of [`Tuning::stall_window`].
pub const STALL_WINDOW: usize = 25;

/// The parameters of the method, one level below the choices a user makes in [`Settings`]:
/// the warm-up and interior-point tries before the main method, the inner tolerance, the
/// Newton end game, the paper's rule (6.1), the faceted cone, and every tuning constant of
/// the outer loop ([`Tuning`]). The defaults suit rigid-body problems; what each field does,
/// its range and how its default was chosen: docs/tuning.md.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MethodParams {
    /// quick first try: at most this many Gauss–Seidel sweeps on Coulomb's law itself
    /// before the main method (0: none); small problems are solved there, and otherwise the
    /// main method starts from the caller's point as if the try had not happened
    pub warmup_sweeps: usize,
    /// the interior-point try on Coulomb's law ([`crate::barrier`]) before the main method of
    /// a cold solve of a rigid problem (policy and parameters: [`Tuning::barrier`]): at
    /// most this many Newton steps per run; 0 turns it off
    pub barrier_steps: usize,
    /// ε of the paper's stopping rule (6.1) ‖F(s) − s‖ / (n (‖s‖ + 1)) ≤ ε, used as an
    /// additional internal stopping test when set (the reported status still requires err ≤ tol)
    pub fixed_point_tol: Option<f64>,
    /// number of facets of the pyramid replacing each K_μ (faceted inner solver, d = 3)
    pub facets: usize,
    /// the inner tolerance is `inner_tol_factor` × (error of the previous outer iterate),
    /// kept between [`Tuning::inner_tol_floor`] · tol and [`Tuning::inner_tol_ceiling`]
    pub inner_tol_factor: f64,
    /// end game: once the error is ≤ [`MethodParams::newton_start`], semismooth Newton steps
    /// on the natural map of the whole law ([`crate::newton::polish`]) are tried after an
    /// outer iteration and kept if they lower the error; this many steps at most per stage;
    /// 0 turns it off
    pub newton_steps: usize,
    /// error (docs/error.md) below which the Newton end game is tried
    pub newton_start: f64,
    /// the tuning constants of the outer loop
    pub tuning: Tuning,
}

impl Default for MethodParams {
    fn default() -> Self {
        Self {
            warmup_sweeps: 50,
            barrier_steps: crate::barrier::BARRIER_STEPS,
            fixed_point_tol: None,
            facets: crate::inner::faceted::DEFAULT_FACETS,
            inner_tol_factor: 0.1,
            newton_steps: crate::newton::END_GAME_STEPS,
            newton_start: crate::newton::END_GAME_START,
            tuning: Tuning::default(),
        }
    }
}

/// Typed settings: what a user changes — the tolerance, the method (main and fallback), the
/// iteration and time limits, a cancel request — with the method's parameters one level down
/// in [`Settings::params`]. The defaults suit rigid-body problems: a warm-up of at most 50
/// Gauss–Seidel sweeps on Coulomb's law, then APGD inside Anderson-mixed fixed-point
/// iterations, a semismooth Newton end game on the whole law once the error is
/// ≤ [`MethodParams::newton_start`] (1e-3), and fused Gauss–Seidel as fallback when the first
/// stage stalls; on a step of granular matter ([`crate::plan::Structure::granular`]) the plan
/// runs the fused Gauss–Seidel first and APGD + Anderson as its fallback
/// ([`crate::plan::choose`]). [`Settings::paper`] is the paper's algorithm.
///
/// With the `serde` feature its JSON keeps every field of [`MethodParams`] at the top level,
/// next to `tol` and the limits, in the order of the layout before the parameters moved down
/// (a sphere checkpoint's `/json/solver` is this JSON).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(from = "SettingsRecord", into = "SettingsRecord")
)]
pub struct Settings {
    /// tolerance on the reported error (docs/error.md); also on the balance residual
    pub tol: f64,
    /// inner solver of the main method
    pub inner: InnerKind,
    /// outer iteration of the main method
    pub outer: OuterKind,
    /// a second (inner, outer) method, warm-started from the first one's r, run when the first
    /// stops without converging (pgs + fused here and another main method: the two change
    /// places on a granular step, [`crate::plan::choose`]) (iteration cap, inner failure, or stalled: the error no longer
    /// halves over [`Tuning::stall_window`] outer iterations); the time limit covers both
    pub fallback: Option<(InnerKind, OuterKind)>,
    /// cap on outer iterations (subproblems)
    pub max_outer: usize,
    /// cap on iterations of each inner solve
    pub max_inner: usize,
    /// wall-clock limit for the whole solve (None: no limit), turned into one
    /// [`crate::deadline::Deadline`] when the solve starts
    pub time_limit: Option<Duration>,
    /// a request to stop early from outside the solve (e.g. a signal handler; None: none),
    /// read wherever the time limit is: the solve then ends with
    /// [`crate::Status::Interrupted`] and its best iterate; not serialized
    pub cancel: Option<crate::deadline::Cancel>,
    /// the parameters of the method: its tries, end game and tuning constants
    pub params: MethodParams,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            tol: 1e-8,
            inner: InnerKind::Apgd,
            outer: OuterKind::Anderson,
            fallback: Some((InnerKind::Pgs, OuterKind::Fused)),
            max_outer: 200,
            max_inner: 10_000,
            time_limit: Some(Duration::from_secs(60)),
            cancel: None,
            params: MethodParams::default(),
        }
    }
}

/// The JSON layout of [`Settings`]: the fields of [`MethodParams`] at the top level, in the
/// order the fields had before they moved into [`Settings::params`], so that stored settings
/// read and write unchanged. [`Settings::cancel`] is not stored (read back as None).
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct SettingsRecord {
    tol: f64,
    inner: InnerKind,
    outer: OuterKind,
    fallback: Option<(InnerKind, OuterKind)>,
    warmup_sweeps: usize,
    barrier_steps: usize,
    max_outer: usize,
    max_inner: usize,
    time_limit: Option<Duration>,
    fixed_point_tol: Option<f64>,
    facets: usize,
    inner_tol_factor: f64,
    newton_steps: usize,
    newton_start: f64,
    tuning: Tuning,
}

#[cfg(feature = "serde")]
impl From<Settings> for SettingsRecord {
    fn from(s: Settings) -> Self {
        let p = s.params;
        Self {
            tol: s.tol,
            inner: s.inner,
            outer: s.outer,
            fallback: s.fallback,
            warmup_sweeps: p.warmup_sweeps,
            barrier_steps: p.barrier_steps,
            max_outer: s.max_outer,
            max_inner: s.max_inner,
            time_limit: s.time_limit,
            fixed_point_tol: p.fixed_point_tol,
            facets: p.facets,
            inner_tol_factor: p.inner_tol_factor,
            newton_steps: p.newton_steps,
            newton_start: p.newton_start,
            tuning: p.tuning,
        }
    }
}

#[cfg(feature = "serde")]
impl From<SettingsRecord> for Settings {
    fn from(r: SettingsRecord) -> Self {
        Self {
            tol: r.tol,
            inner: r.inner,
            outer: r.outer,
            fallback: r.fallback,
            max_outer: r.max_outer,
            max_inner: r.max_inner,
            time_limit: r.time_limit,
            cancel: None,
            params: MethodParams {
                warmup_sweeps: r.warmup_sweeps,
                barrier_steps: r.barrier_steps,
                fixed_point_tol: r.fixed_point_tol,
                facets: r.facets,
                inner_tol_factor: r.inner_tol_factor,
                newton_steps: r.newton_steps,
                newton_start: r.newton_start,
                tuning: r.tuning,
            },
        }
    }
}

/// Inner iterations of the paper's Table 1 runs for the iterative inner solvers (APGD, PGS).
pub const PAPER_MAX_INNER: usize = 250;

impl Settings {
    /// The default settings with (`inner`, `outer`) as the only method: no warm-up try, no
    /// interior-point try and no fallback, so that the result describes that method.
    pub fn method(inner: InnerKind, outer: OuterKind) -> Self {
        Self {
            inner,
            outer,
            fallback: None,
            params: MethodParams {
                warmup_sweeps: 0,
                barrier_steps: 0,
                ..MethodParams::default()
            },
            ..Self::default()
        }
    }

    /// The paper's algorithm (§3.3, §6) with the inner solver `inner`: the plain fixed point
    /// s ← F(s), each subproblem (3.15)/(4.7) solved accurately (inner tolerance 1e-6 × the
    /// current error, down to the floor), no warm-up, no fallback, no Newton end game; the
    /// iterative inner solvers capped at [`PAPER_MAX_INNER`] iterations as in Table 1. Set
    /// [`MethodParams::fixed_point_tol`] to stop by rule (6.1) as the paper does.
    pub fn paper(inner: InnerKind) -> Self {
        let mut s = Self::time_stepping(Method::new(inner, OuterKind::FixedPoint));
        if matches!(inner, InnerKind::Apgd | InnerKind::Pgs) {
            s.max_inner = PAPER_MAX_INNER;
        }
        s.params.newton_steps = 0;
        s
    }

    /// `method` alone, each subproblem solved accurately (inner tolerance 1e-6 × the current
    /// error, down to the floor): the preset of time stepping, where the loose rule (6.1)
    /// often stops the outer loop after one subproblem, whose accuracy is then the step's.
    pub fn time_stepping(method: Method) -> Self {
        let mut s = Self::method(method.inner, method.outer);
        s.params.inner_tol_factor = 1e-6;
        s
    }

    /// The (inner, outer) pair of the main method.
    pub fn main_method(&self) -> Method {
        Method::new(self.inner, self.outer)
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), crate::solution::SolveError> {
        let bad = |m: &str| Err(crate::solution::SolveError::Settings(m.to_string()));
        if let Err(m) = check_tol(self.tol) {
            return bad(&m);
        }
        if self.max_outer == 0 || self.max_inner == 0 {
            return bad("max_outer and max_inner must be at least 1");
        }
        let p = &self.params;
        if p.inner_tol_factor.is_nan() || p.inner_tol_factor <= 0.0 || p.inner_tol_factor > 1.0 {
            return bad("inner_tol_factor must be in (0, 1]");
        }
        if p.fixed_point_tol.is_some_and(|e| e.is_nan() || e <= 0.0) {
            return bad("fixed_point_tol must be positive");
        }
        if p.newton_start.is_nan() || p.newton_start < 0.0 {
            return bad("newton_start must be nonnegative");
        }
        if p.facets < 3 {
            return bad("facets must be at least 3");
        }
        if !self.main_method().is_valid() {
            return bad("the fused outer iteration needs the pgs inner solver");
        }
        if let Some(fallback) = self.fallback {
            if !Method::from(fallback).is_valid() {
                return bad("the fused outer iteration needs the pgs inner solver (fallback)");
            }
        }
        p.tuning
            .validate()
            .map_err(crate::solution::SolveError::Settings)
    }
}

/// The tolerances accepted everywhere (the CLI's `--tol`, a scene file's `step.tol`, Python's
/// `set_solver(tol=…)` and `Simulation(tol=…)`, [`Settings::validate`]): finite, above 0 and
/// below 1. The error of `docs/error.md` is relative (abs_err / max(‖q‖, ‖r‖, ‖u‖)), so a
/// tolerance of 1 or more accepts any r — "converged" would mean nothing (issue 55: `tol =
/// 1e300` was accepted).
pub fn check_tol(tol: f64) -> Result<(), String> {
    if tol.is_finite() && tol > 0.0 && tol < 1.0 {
        Ok(())
    } else {
        Err(format!(
            "tol = {tol} must be above 0 and below 1 (the error of docs/error.md is relative: 1 accepts any answer)"
        ))
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    pub fn a_zero_stagnation_window_is_refused() {
        let mut s = Settings::default();
        assert!(s.validate().is_ok());
        s.params.tuning.newton.stagnation = 0;
        assert!(s.validate().is_err());
    }

    pub fn method_names_round_trip() {
        for inner in InnerKind::ALL {
            assert_eq!(inner.as_str().parse::<InnerKind>(), Ok(inner));
            for outer in OuterKind::ALL {
                let m = Method::new(inner, outer);
                assert_eq!(m.to_string().parse::<Method>(), Ok(m));
            }
        }
        assert_eq!(
            " APGD+Anderson ".parse::<Method>(),
            Ok(Method::new(InnerKind::Apgd, OuterKind::Anderson))
        );
        assert_eq!("fixed-point".parse(), Ok(OuterKind::FixedPoint));
        let e = "newton".parse::<InnerKind>().unwrap_err();
        assert!(e.to_string().contains("ipm, apgd, pgs, faceted") || e.to_string().contains("pgs"));
        assert!("pgs+".parse::<Method>().is_err());
    }

    pub fn presets_validate_and_bad_tuning_is_refused() {
        Settings::default().validate().unwrap();
        for inner in InnerKind::ALL {
            let p = Settings::paper(inner);
            p.validate().unwrap();
            assert_eq!(
                (p.outer, p.fallback, p.params.newton_steps),
                (OuterKind::FixedPoint, None, 0)
            );
        }
        let mut s = Settings::default();
        s.params.tuning.newton.retry = 0.0;
        assert!(s.validate().is_err());
        let mut s = Settings::default();
        s.params.tuning.anderson.memory = 0;
        assert!(s.validate().is_err());
        let refused: [fn(&mut Tuning); 50] = [
            |t| t.multiplier.newton_steps = 0,
            |t| t.multiplier.chord_ratio = 1.0,
            |t| t.multiplier.chord_ratio = f64::NAN,
            |t| t.multiplier.slow_steps = 0,
            |t| t.multiplier.slow_ratio = 0.0,
            |t| t.multiplier.slow_ratio = f64::NAN,
            |t| t.multiplier.starts = 0,
            |t| t.multiplier.skeleton_residual = f64::NAN,
            |t| t.multiplier.skeleton_residual = -1.0,
            |t| t.multiplier.finish_below = f64::NAN,
            |t| t.multiplier.finish_below = f64::INFINITY,
            |t| t.multiplier.finish_gain = 0.0,
            |t| t.multiplier.finish_gain = 1.5,
            |t| t.multiplier.finish_crawl = -1.0,
            |t| t.barrier.skeleton_rank_ratio = 0.0,
            |t| t.barrier.skeleton_rank_ratio = 1.5,
            |t| t.barrier.dense_parallel_dim = 0,
            |t| t.barrier.lm_stall_segments = 0,
            |t| t.barrier.handover = -1.0,
            |t| t.barrier.handover = f64::INFINITY,
            |t| t.multiplier.rho_factor = 0.0,
            |t| t.multiplier.inner_ratio = f64::NAN,
            |t| t.multiplier.stall_gain = 1.0,
            |t| t.multiplier.max_factorizations = 0,
            |t| t.barrier.max_work = 0,
            |t| t.multiplier.penalty_growth = 0.5,
            |t| t.multiplier.penalty_cap = f64::INFINITY,
            |t| t.inner.gs_anderson_memory = 0,
            |t| t.prox.inner_steps = 0,
            |t| t.prox.line_search_steps = 0,
            |t| t.prox.stall_steps = 0,
            |t| t.prox.sigma_factor = 0.0,
            |t| t.prox.start = f64::NAN,
            |t| t.prox.try_start = -1.0,
            |t| t.prox.max_steps = 0,
            |t| t.prox.capped_max_steps = 0,
            |t| t.prox.retry = 1.5,
            |t| t.prox.sigma_growth = 0.5,
            |t| t.prox.inner_ratio = 1.0,
            |t| t.lm.segment_steps = 0,
            |t| t.lm.max_rejections = 0,
            |t| t.lm.stall_gain = 0.0,
            |t| t.lm.rho_factors[3] = -1.0,
            |t| t.lm.accept_ratio = 1.0,
            |t| t.newton.shift_tries = 0,
            |t| t.newton.shift_growth = 1.0,
            |t| t.newton.sufficient_decrease = 1.0,
            |t| t.inner.apgd.backtrack_margin = 0.5,
            |t| t.inner.apgd.ray_period = 0,
            |t| t.inner.infeasible_ray.descent = f64::NAN,
        ];
        for spoil in refused {
            let mut s = Settings::default();
            spoil(&mut s.params.tuning);
            assert!(s.validate().is_err());
        }
        assert!(Settings::method(InnerKind::Apgd, OuterKind::Fused)
            .validate()
            .is_err());
    }

    pub fn inner_tolerance_stays_between_floor_and_ceiling() {
        let s = Settings::default();
        let t = s.params.tuning;
        assert_eq!(t.inner_tol(&s, 1.0, false), 1e-2);
        assert_eq!(t.inner_tol(&s, 1e-20, false), 0.2 * s.tol);
        assert_eq!(t.inner_tol(&s, 1e-4, true), 0.2 * s.tol);
        assert!((t.inner_tol(&s, 1e-4, false) - 1e-5).abs() < 1e-18);
    }
}
