//! Existence diagnostics with certificates: "no solution can exist" versus "the solver failed".
//!
//! For the incremental problem (2.10) in FCLIB convention (`M v = H r + f`, `u = Hᵀ v + w`,
//! H of size n × m, L = ∏ K_{μⁱ}, L* = ∏ K_{1/μⁱ}) the paper's criteria read (the paper writes
//! H_p = Hᵀ, so its "Im H" is our Im Hᵀ and its "Ker(Hᵀ)" our Ker H):
//!
//! | criterion | statement | consequence |
//! |---|---|---|
//! | (4.5) | ∃ v: (Hᵀ v + w)ⁱ_N ≥ 0 for every contact | necessary; if it fails **no solution exists** |
//! | (4.1) | ∃ v: Hᵀ v + w ∈ 𝓛* (interior of K_{1/μ} where μ > 0, half-spaces where μ = 0) | existence, Thm 4.6 |
//! | (4.4) | w ∈ Im Hᵀ + L* | existence, Cadoux–Malick \[21\] (after Prop. 4.8); necessary and sufficient when all μ = 0 (§5.1) |
//! | (4.6) | wᵀ r ≥ 0 for all r ∈ L ∩ Ker H, i.e. w ∈ cl(Im Hᵀ + L*) | existence, Klarbring–Pang \[48\] via Prop. 4.8 |
//! | (5.1) | Ker H ∩ L = {0} | existence for every w, Thm 5.1 |
//!
//! For a local problem (W, q) the same holds with W in place of H (Ker W = Ker H,
//! Im W = Im Hᵀ) and q in place of w. For a global problem H is used directly (sparse); W is
//! never formed.
//!
//! # One conic problem decides each criterion
//! Every criterion is the sign of the optimal value of a *margin problem* (solved by Clarabel)
//!
//! ```text
//!     t* = max t   s.t.   Hᵀ v + w − t·e_S ∈ C,   t ≤ 1,
//! ```
//!
//! where C is a product of per-contact cones (L* for (4.1), (4.4), (4.6), (5.1); the half-spaces
//! {x_N ≥ 0} for (4.5)), e_S = (1, 0, 0) on the contacts of a set S and 0 elsewhere, and w is
//! replaced by 0 for (5.1). The per-contact margin of x ∈ ℝ^d is x_N − μ‖x_T‖ for K_{1/μ}
//! (x_N for a half-space), so t* is the best worst-contact margin. Its conic dual is
//!
//! ```text
//!     min wᵀ r + z   s.t.   H r = 0,   r ∈ C*,   Σ_{i∈S} rⁱ_N + z = 1,   z ≥ 0,
//! ```
//!
//! and the primal is strictly feasible (take t → −∞), so there is no duality gap:
//! t* = min(1, min{wᵀ r : r ∈ L ∩ Ker H, Σ_S r_N = 1}). Hence a primal point v is a certificate
//! that the criterion holds, and a dual point r ∈ L ∩ Ker H with wᵀ r < 0 (or, for (5.1), any
//! nonzero r ∈ L ∩ Ker H) a certificate that it fails: for every feasible (v, t),
//! `0 ≤ rᵀ(Hᵀ v + w − t e_S) = wᵀ r − t Σ_S r_N`, so t ≤ wᵀ r / Σ_S r_N. For (4.5) the dual
//! point is the Farkas vector y ≥ 0 with H_N y = 0 and w_Nᵀ y < 0.
//!
//! Certificates returned by Clarabel are never trusted as such: v is checked by recomputing
//! Hᵀ v + w and its cone margins; r is projected onto L, normalized, and its kernel residual
//! ‖H r‖ / Σⱼ |rⱼ| ‖H₍:,ⱼ₎‖ is recomputed. The verdict is taken from these verified numbers.
//!
//! # Tolerances and "undecided"
//! Margins are measured on w / ‖w‖∞ (the criteria are invariant under scaling of w), and
//! `CheckSettings::tol` separates the verdicts:
//! - a closed criterion ((4.4), (4.5), (4.6)) holds when a verified v has margin ≥ −tol;
//! - the strict ones hold when the margin is > tol ((4.1); for (5.1), relative to max‖xⁱ‖);
//! - a criterion fails when a verified r gives an upper bound on the margin below −tol
//!   (≤ tol for (4.1)); that bound is wᵀr plus a slack for the kernel residual of r, which
//!   grows like √residual for second-order cones (see `KERNEL_SLACK`), so that an r that
//!   is only approximately in Ker H cannot fake a failure;
//! - otherwise the verdict is undecided. This is what happens when w lies on the boundary of
//!   a non-closed Im Hᵀ + L* (d = 3): the supremum of the margin is 0 but is not attained, so
//!   (4.4) fails while (4.6) holds, and no finite computation can tell them apart; (4.4) is
//!   then reported undecided rather than holding.
//!
//! In d = 2 (and for μ ∈ {0, ∞}) every cone is polyhedral, Im Hᵀ + L* is closed and
//! (4.4) ⇔ (4.6).

use crate::problem::{GlobalProblem, LocalProblem, Problem, ProblemError};
use crate::sparse::CscMatrix;
use clarabel::algebra as ca;
use clarabel::solver::{self as cs, IPSolver};
use serde::{Serialize, Serializer};
use std::time::Instant;
use thiserror::Error;

/// The five criteria of §4–§5.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Criterion {
    /// (4.1): C(0) ≠ ∅, the strict version.
    C4_1,
    /// (4.4): w ∈ Im Hᵀ + L*.
    C4_4,
    /// (4.5): non-penetration is kinematically possible (necessary).
    C4_5,
    /// (4.6): w ∈ cl(Im Hᵀ + L*) (Klarbring–Pang, Prop. 4.8).
    C4_6,
    /// (5.1): Ker H ∩ L = {0}.
    C5_1,
}

impl Criterion {
    /// The paper's equation number, e.g. "4.4".
    pub fn label(self) -> &'static str {
        match self {
            Criterion::C4_1 => "4.1",
            Criterion::C4_4 => "4.4",
            Criterion::C4_5 => "4.5",
            Criterion::C4_6 => "4.6",
            Criterion::C5_1 => "5.1",
        }
    }
}

impl std::fmt::Display for Criterion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "({})", self.label())
    }
}

impl Serialize for Criterion {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.label())
    }
}

/// Outcome of one criterion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// the criterion holds, with a verified certificate (within tolerance)
    Holds,
    /// the criterion fails, with a verified certificate (within tolerance)
    Fails,
    /// neither certificate could be verified within tolerance
    Undecided,
}

/// What a certificate vector is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CertificateKind {
    /// generalized velocities v (length n; length m for a local problem) with Hᵀ v + w in the
    /// criterion's cone
    Velocity,
    /// impulses r ∈ L ∩ Ker H (length m), normalized so that the Σ r_N over the margin's
    /// contacts is 1
    Impulse,
    /// Farkas vector y ≥ 0 (one entry per contact) with H_N y = 0 and w_Nᵀ y < 0, Σ y = 1
    Farkas,
}

/// The verdict on one criterion, with its verified certificate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CriterionReport {
    /// holds, fails or undecided
    pub verdict: Verdict,
    /// the verified residual of the certificate backing the verdict (relative; see
    /// [`CertificateKind`]): for a velocity, the largest cone violation of Hᵀ v + w divided by
    /// ‖w‖∞; for impulses or a Farkas vector, the relative kernel residual
    /// ‖H r‖ / Σⱼ |rⱼ| ‖H₍:,ⱼ₎‖ (r is exactly in L after projection). None when undecided.
    pub certificate_residual: Option<f64>,
    /// what `certificate` holds
    pub certificate_kind: Option<CertificateKind>,
    /// the certificate vector (v, r or y)
    pub certificate: Option<Vec<f64>>,
    /// the verified margin of the best velocity found: min over the criterion's contacts of
    /// (x_N − μ‖x_T‖) / ‖w‖∞ with x = Hᵀ v + w (relative to max ‖xⁱ‖ for (5.1), where w = 0)
    pub margin: Option<f64>,
    /// the verified dual bound: wᵀ r / ‖w‖∞ for the normalized impulse certificate (an upper
    /// bound on the margin)
    pub dual_bound: Option<f64>,
    /// what was found, in words
    pub detail: String,
}

/// The five verdicts, serialized under the paper's equation numbers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Criteria {
    /// (4.1)
    #[serde(rename = "4.1")]
    pub c4_1: CriterionReport,
    /// (4.4)
    #[serde(rename = "4.4")]
    pub c4_4: CriterionReport,
    /// (4.5)
    #[serde(rename = "4.5")]
    pub c4_5: CriterionReport,
    /// (4.6)
    #[serde(rename = "4.6")]
    pub c4_6: CriterionReport,
    /// (5.1)
    #[serde(rename = "5.1")]
    pub c5_1: CriterionReport,
}

impl Criteria {
    /// The report of one criterion.
    pub fn get(&self, c: Criterion) -> &CriterionReport {
        match c {
            Criterion::C4_1 => &self.c4_1,
            Criterion::C4_4 => &self.c4_4,
            Criterion::C4_5 => &self.c4_5,
            Criterion::C4_6 => &self.c4_6,
            Criterion::C5_1 => &self.c5_1,
        }
    }
}

/// What the theory concludes from the verdicts.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Conclusion {
    /// a solution of (2.10) exists, by this criterion and this result of the paper
    Exists {
        /// the criterion that holds
        by: Criterion,
        /// the theorem that turns it into existence
        theorem: &'static str,
    },
    /// no solution of (2.10) can exist: this necessary criterion fails, with a certificate
    None {
        /// the necessary criterion that fails
        by: Criterion,
        /// why it is necessary
        theorem: &'static str,
    },
    /// none of the sufficient criteria holds and the necessary one does not fail: the theory
    /// says nothing (e.g. Painlevé's Example III, §5.3)
    Unknown,
}

impl Conclusion {
    /// "exists", "none" or "unknown".
    pub fn label(&self) -> &'static str {
        match self {
            Conclusion::Exists { .. } => "exists",
            Conclusion::None { .. } => "none",
            Conclusion::Unknown => "unknown",
        }
    }
}

/// The result of [`check`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExistenceReport {
    /// "local" or "global"
    pub kind: &'static str,
    /// space dimension d
    pub dim: usize,
    /// number of contacts
    pub contacts: usize,
    /// whether every μ = 0 (then (4.4) is necessary and sufficient, §5.1)
    pub frictionless: bool,
    /// the verdict on each criterion
    pub criteria: Criteria,
    /// what the theory concludes
    pub conclusion: Conclusion,
    /// why the conclusion is weaker than the criteria suggest, when it is (a local problem
    /// whose W is not symmetric: see [`check_local`])
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// wall-clock seconds spent
    pub seconds: f64,
}

/// Settings of [`check`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckSettings {
    /// decision tolerance on margins and dual bounds (relative to ‖w‖∞)
    pub tol: f64,
    /// largest accepted certificate residual
    pub certificate_tol: f64,
    /// iteration cap of each conic solve
    pub max_iter: u32,
    /// wall-clock cap (seconds) of each conic solve
    pub time_limit: f64,
}

impl Default for CheckSettings {
    fn default() -> Self {
        Self {
            tol: 1e-7,
            certificate_tol: 1e-6,
            max_iter: 200,
            time_limit: 30.0,
        }
    }
}

/// Why a check could not run.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CheckError {
    /// the problem data are invalid
    #[error(transparent)]
    Problem(#[from] ProblemError),
    /// the settings are invalid
    #[error("invalid check settings: {0}")]
    Settings(String),
}

/// A velocity norm beyond which a slightly negative (4.4) margin is treated as a supremum that
/// may not be attained (Im Hᵀ + L* not closed), relative to ‖w‖∞ / max|H|.
const UNATTAINED_V_NORM: f64 = 1e6;

/// Runs every criterion on a problem (global: with H and w; local: with W and q).
pub fn check(problem: &Problem, settings: &CheckSettings) -> Result<ExistenceReport, CheckError> {
    match problem {
        Problem::Global(g) => check_global(g, settings),
        Problem::Local(l) => check_local(l, settings),
    }
}

/// [`check`], calling `progress` with each criterion just before it is evaluated (for a
/// progress display: each criterion is one or two conic solves, long on huge problems).
pub fn check_with_progress(
    problem: &Problem,
    settings: &CheckSettings,
    progress: &mut dyn FnMut(Criterion),
) -> Result<ExistenceReport, CheckError> {
    match problem {
        Problem::Global(p) => check_global_with(p, settings, progress),
        Problem::Local(p) => check_local_with(p, settings, progress),
    }
}

/// [`check`] on a global problem: the criteria on (H, w). The theorems assume M symmetric
/// positive definite: for an M that is not symmetric beyond rounding
/// ([`ROUNDING_ASYMMETRY`]; CubeH8 and LMGC_GlobalFrictionContactProblem00046 store M with
/// relative asymmetry 1.5e-7) a criterion that holds leaves the conclusion unknown.
pub fn check_global(
    p: &GlobalProblem,
    settings: &CheckSettings,
) -> Result<ExistenceReport, CheckError> {
    check_global_with(p, settings, &mut |_| {})
}

fn check_global_with(
    p: &GlobalProblem,
    settings: &CheckSettings,
    progress: &mut dyn FnMut(Criterion),
) -> Result<ExistenceReport, CheckError> {
    let data = KinematicData::new(p.dim, &p.h, &p.w, &p.mu)?;
    let mut report = run_all_with(&data, "global", settings, progress)?;
    let asymmetry = p.m.asymmetry();
    if asymmetry > ROUNDING_ASYMMETRY {
        downgrade(&mut report, "M", asymmetry);
    }
    Ok(report)
}

/// A sufficient criterion proves existence only for a symmetric W (or M): for a matrix that
/// is not symmetric beyond rounding the conclusion becomes [`Conclusion::Unknown`], and the
/// note says which criterion held.
fn downgrade(report: &mut ExistenceReport, what: &str, asymmetry: f64) {
    if let Conclusion::Exists { by, theorem } = report.conclusion {
        report.note = Some(format!(
            "{by} holds, which proves existence by {theorem} for a symmetric {what}; this {what} \
             is not symmetric (relative asymmetry {asymmetry:.2e}), for which the theorem is \
             not established"
        ));
        report.conclusion = Conclusion::Unknown;
    }
}

/// Relative asymmetry max|W − Wᵀ| / max|W| up to which W counts as symmetric for the
/// theorems of [`check_local`]: the round-off of assembling Hᵀ M⁻¹ H in floating point
/// (BoxesStack1-i100000-32: 1.6e-16).
pub const ROUNDING_ASYMMETRY: f64 = 1e-12;

/// [`check`] on a local problem: the criteria on x(v) = W v + q.
///
/// The sufficient criteria are theorems for W = Hᵀ M⁻¹ H, which is symmetric. When the
/// stored W is not symmetric beyond rounding ([`ROUNDING_ASYMMETRY`]), (4.5) is still necessary (u = W r + q with u_N ≥ 0
/// is such an x) and its failure still proves that no solution exists; but a sufficient
/// criterion that holds proves existence only for a symmetric W, so the conclusion is then
/// [`Conclusion::Unknown`], with the criterion that held named in
/// [`ExistenceReport::note`].
pub fn check_local(
    p: &LocalProblem,
    settings: &CheckSettings,
) -> Result<ExistenceReport, CheckError> {
    check_local_with(p, settings, &mut |_| {})
}

fn check_local_with(
    p: &LocalProblem,
    settings: &CheckSettings,
    progress: &mut dyn FnMut(Criterion),
) -> Result<ExistenceReport, CheckError> {
    if p.w.asymmetry() <= ROUNDING_ASYMMETRY {
        let data = KinematicData::new(p.dim, &p.w, &p.q, &p.mu)?;
        return run_all_with(&data, "local", settings, progress);
    }
    // B = Wᵀ, so that Bᵀ v + q = W v + q
    let wt = p.w.transpose();
    let data = KinematicData::new(p.dim, &wt, &p.q, &p.mu)?;
    let mut report = run_all_with(&data, "local", settings, progress)?;
    downgrade(&mut report, "W", p.w.asymmetry());
    Ok(report)
}

/// The purely kinematic data the criteria depend on (§5.5): x(v) = Bᵀ v + w with B = H
/// (global) or W (local).
struct KinematicData<'a> {
    dim: usize,
    b: &'a CscMatrix,
    w: &'a [f64],
    mu: &'a [f64],
    /// ‖B₍:,ⱼ₎‖ for each column j
    col_norms: Vec<f64>,
    /// ‖w‖∞, or 1 when w = 0
    w_scale: f64,
    /// max |Bᵢⱼ|, or 1 when B = 0
    b_scale: f64,
}

impl<'a> KinematicData<'a> {
    fn new(
        dim: usize,
        b: &'a CscMatrix,
        w: &'a [f64],
        mu: &'a [f64],
    ) -> Result<Self, ProblemError> {
        b.check()
            .map_err(|source| ProblemError::Sparse { what: "H", source })?;
        let m = dim * mu.len();
        if b.ncols != m || w.len() != m {
            return Err(ProblemError::Shape {
                what: "H / w",
                expected: format!("{m} columns and entries (d · contacts)"),
                found: format!("{} columns, {} entries", b.ncols, w.len()),
            });
        }
        if let Some(i) = mu.iter().position(|x| x.is_nan() || *x < 0.0) {
            return Err(ProblemError::Friction {
                contact: i,
                value: mu[i],
            });
        }
        if let Some((r, c)) = b.first_non_finite() {
            return Err(ProblemError::NonFinite {
                what: "H",
                location: format!("({r}, {c})"),
            });
        }
        if let Some(i) = w.iter().position(|x| !x.is_finite()) {
            return Err(ProblemError::NonFinite {
                what: "w",
                location: format!("index {i}"),
            });
        }
        let col_norms = (0..b.ncols)
            .map(|j| {
                b.values[b.col_ptr[j]..b.col_ptr[j + 1]]
                    .iter()
                    .map(|x| x * x)
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let w_inf = w.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let b_inf = b.values[..b.nnz()]
            .iter()
            .fold(0.0f64, |a, x| a.max(x.abs()));
        Ok(Self {
            dim,
            b,
            w,
            mu,
            col_norms,
            w_scale: if w_inf > 0.0 { w_inf } else { 1.0 },
            b_scale: if b_inf > 0.0 { b_inf } else { 1.0 },
        })
    }

    fn contacts(&self) -> usize {
        self.mu.len()
    }

    /// The cone of contact i in (4.4): K_{μ}* = K_{1/μ}.
    fn dual_block(&self, i: usize) -> Block {
        let mu = self.mu[i];
        if mu == 0.0 {
            Block::HalfSpace
        } else if mu.is_infinite() {
            Block::Ray
        } else {
            Block::Soc(mu)
        }
    }
}

/// One contact's cone in the margin problem, written for x = (x_N, x_T).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Block {
    /// {x_N ≥ 0} = K_∞ = K_0*: frictionless contacts in L*, every contact in (4.5)
    HalfSpace,
    /// K_{1/μ} = K_μ* = {μ‖x_T‖ ≤ x_N}, 0 < μ < ∞
    Soc(f64),
    /// K_0 = K_∞* = {x_T = 0, x_N ≥ 0} (μ = ∞)
    Ray,
}

impl Block {
    /// Margin of x: the largest t with x − t e in the cone (−∞ … for a ray with x_T ≠ 0, the
    /// negative tangential size is returned instead).
    fn margin(self, x: &[f64]) -> f64 {
        let n = x[0];
        let t = crate::cone::tangent_norm(x);
        match self {
            Block::HalfSpace => n,
            Block::Soc(mu) => n - mu * t,
            Block::Ray => {
                if t > 0.0 {
                    n.min(-t)
                } else {
                    n
                }
            }
        }
    }

    /// Projects an impulse block onto the dual of this cone (the block of L, or of the
    /// normal ray for a half-space).
    fn project_dual(self, r: &mut [f64]) {
        match self {
            Block::HalfSpace => {
                r[0] = r[0].max(0.0);
                r[1..].iter_mut().for_each(|x| *x = 0.0);
            }
            Block::Soc(mu) => crate::cone::project(mu, r),
            Block::Ray => r[0] = r[0].max(0.0),
        }
    }
}

/// The data of one margin problem.
struct MarginProblem<'d, 'a> {
    data: &'d KinematicData<'a>,
    blocks: Vec<Block>,
    /// contacts whose margin is maximized (the set S)
    mask: Vec<bool>,
    /// use w = 0 (for (5.1))
    homogeneous: bool,
}

/// How a Clarabel solve ended, in the terms the verdicts need.
#[derive(Debug, Clone, Copy, PartialEq)]
enum ConicStatus {
    Solved,
    Infeasible,
    Failed,
}

/// The raw output of a margin solve (before verification).
struct MarginSolve {
    /// primal velocities (original scaling)
    v: Option<Vec<f64>>,
    /// dual impulses (optimal dual or infeasibility certificate), unnormalized
    r: Option<Vec<f64>>,
    clarabel_status: String,
}

/// A verified velocity certificate.
struct VelocityCheck {
    /// min over S of the margin / ‖w‖∞ (+∞ when S is empty)
    masked: f64,
    /// min over the other contacts of the margin / ‖w‖∞ (+∞ when none)
    unmasked: f64,
    /// max ‖xⁱ‖ / ‖w‖∞
    size: f64,
}

/// A verified impulse certificate.
struct ImpulseCheck {
    /// r projected onto L and normalized (Σ_S r_N = 1, or ‖r‖ = 1 if that sum vanishes)
    r: Vec<f64>,
    /// wᵀ r / ‖w‖∞ for the normalized r
    value: f64,
    /// whether Σ_S r_N > 0 (else r lives on contacts outside S and `value` < 0 means the
    /// cone constraint itself is infeasible)
    on_mask: bool,
    /// ‖H r‖ / Σⱼ |rⱼ| ‖H₍:,ⱼ₎‖
    residual: f64,
    /// `value` plus the uncertainty the kernel residual leaves on it (see [`KERNEL_SLACK`]):
    /// the verified upper bound on the margin
    bound: f64,
}

/// How far wᵀr may move when an approximate r ∈ L (residual ε = ‖H r‖ relative) is replaced
/// by a point of L ∩ Ker H: |Δ(wᵀr)| ≤ κ ‖ŵ‖ ‖r‖ ε for polyhedral cones (Hoffman) and
/// κ ‖ŵ‖ ‖r‖ √ε for second-order cones (Hölderian error bound with exponent ½, which is
/// attained when Ker H runs along the boundary of L). κ = KERNEL_SLACK.
const KERNEL_SLACK: f64 = 10.0;

impl<'d, 'a> MarginProblem<'d, 'a> {
    fn w_hat(&self, j: usize) -> f64 {
        if self.homogeneous {
            0.0
        } else {
            self.data.w[j] / self.data.w_scale
        }
    }

    /// Solves max t s.t. B̂ᵀ v̂ + ŵ − t e_S ∈ C, t ≤ 1 with Clarabel, on B̂ = B / max|B|,
    /// ŵ = w / ‖w‖∞. Only the dofs that some contact sees are variables.
    fn solve(&self, settings: &CheckSettings) -> MarginSolve {
        let d = self.data;
        let dim = d.dim;
        let b = d.b;
        // Compact the dofs: rows of B with at least one entry.
        let mut dof_index = vec![usize::MAX; b.nrows];
        let mut nv = 0usize;
        for &row in &b.row_idx[..b.nnz()] {
            if dof_index[row] == usize::MAX {
                dof_index[row] = nv;
                nv += 1;
            }
        }
        let t_col = nv;
        let mut rows = Vec::new();
        let mut cols = Vec::new();
        let mut vals = Vec::new();
        let mut rhs = Vec::new();
        let mut cones: Vec<cs::SupportedConeT<f64>> = Vec::new();
        // Row of the Clarabel system holding contact component j, and its scale factor.
        let mut push_row = |j: usize, scale: f64, shift: bool, rhs: &mut Vec<f64>| {
            let row = rhs.len();
            for p in b.col_ptr[j]..b.col_ptr[j + 1] {
                rows.push(row);
                cols.push(dof_index[b.row_idx[p]]);
                vals.push(-scale * b.values[p] / d.b_scale);
            }
            if shift {
                rows.push(row);
                cols.push(t_col);
                vals.push(1.0);
            }
            rhs.push(scale * self.w_hat(j));
        };
        for (i, block) in self.blocks.iter().enumerate() {
            let j0 = i * dim;
            let shift = self.mask[i];
            match *block {
                Block::HalfSpace => {
                    push_row(j0, 1.0, shift, &mut rhs);
                    cones.push(cs::NonnegativeConeT(1));
                }
                Block::Soc(mu) => {
                    push_row(j0, 1.0, shift, &mut rhs);
                    for k in 1..dim {
                        push_row(j0 + k, mu, false, &mut rhs);
                    }
                    cones.push(cs::SecondOrderConeT(dim));
                }
                Block::Ray => {
                    push_row(j0, 1.0, shift, &mut rhs);
                    cones.push(cs::NonnegativeConeT(1));
                    for k in 1..dim {
                        push_row(j0 + k, 1.0, false, &mut rhs);
                    }
                    cones.push(cs::ZeroConeT(dim - 1));
                }
            }
        }
        // t ≤ 1
        rows.push(rhs.len());
        cols.push(t_col);
        vals.push(1.0);
        rhs.push(1.0);
        cones.push(cs::NonnegativeConeT(1));

        let nx = nv + 1;
        let a = ca::CscMatrix::new_from_triplets(rhs.len(), nx, rows, cols, vals);
        let p = ca::CscMatrix::zeros((nx, nx));
        let mut q = vec![0.0; nx];
        q[t_col] = -1.0;
        let csettings = cs::DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(settings.max_iter)
            .time_limit(settings.time_limit)
            .build();
        let Ok(csettings) = csettings else {
            return MarginSolve::failed("Clarabel settings rejected");
        };
        let mut solver = match cs::DefaultSolver::new(&p, &q, &a, &rhs, &cones, csettings) {
            Ok(s) => s,
            Err(e) => return MarginSolve::failed(&format!("Clarabel setup failed: {e}")),
        };
        solver.solve();
        let sol = &solver.solution;
        let status = match sol.status {
            cs::SolverStatus::Solved | cs::SolverStatus::AlmostSolved => ConicStatus::Solved,
            cs::SolverStatus::PrimalInfeasible | cs::SolverStatus::AlmostPrimalInfeasible => {
                ConicStatus::Infeasible
            }
            _ => ConicStatus::Failed,
        };
        let all_finite = sol.x.iter().chain(&sol.z).all(|x| x.is_finite());
        // Map back: v = (‖w‖∞ / max|B|) v̂ (v̂ is the solution on scaled data; for (5.1) w = 0
        // and only the direction matters).
        let v_factor = if self.homogeneous {
            1.0 / d.b_scale
        } else {
            d.w_scale / d.b_scale
        };
        let mut v = vec![0.0; b.nrows];
        for (k, &idx) in dof_index.iter().enumerate() {
            if idx != usize::MAX {
                v[k] = sol.x.get(idx).copied().unwrap_or(0.0) * v_factor;
            }
        }
        // Dual z → impulses r (z in C*, r = D z with D the tangential scaling).
        let mut r = vec![0.0; dim * d.contacts()];
        let mut row = 0usize;
        for (i, block) in self.blocks.iter().enumerate() {
            let j0 = i * dim;
            let z = |k: usize| sol.z.get(k).copied().unwrap_or(0.0);
            match *block {
                Block::HalfSpace => {
                    r[j0] = z(row);
                    row += 1;
                }
                Block::Soc(mu) => {
                    r[j0] = z(row);
                    for k in 1..dim {
                        r[j0 + k] = mu * z(row + k);
                    }
                    row += dim;
                }
                Block::Ray => {
                    for k in 0..dim {
                        r[j0 + k] = z(row + k);
                    }
                    row += dim;
                }
            }
        }
        let t_opt =
            (status == ConicStatus::Solved).then(|| sol.x.get(t_col).copied().unwrap_or(0.0));
        let clarabel_status = match t_opt {
            Some(t) => format!("{:?}, t* = {t:.3e}", sol.status),
            None => format!("{:?}", sol.status),
        };
        if !all_finite {
            return MarginSolve::failed(&format!("Clarabel {clarabel_status}: non-finite output"));
        }
        MarginSolve {
            v: (status == ConicStatus::Solved || status == ConicStatus::Failed).then_some(v),
            r: Some(r),
            clarabel_status,
        }
    }

    /// Recomputes x = Hᵀ v + w (w = 0 when homogeneous) and its margins.
    fn check_velocity(&self, v: &[f64]) -> VelocityCheck {
        let d = self.data;
        let mut x = if self.homogeneous {
            vec![0.0; d.w.len()]
        } else {
            d.w.to_vec()
        };
        d.b.gemv_t_acc(1.0, v, &mut x);
        let mut masked = f64::INFINITY;
        let mut unmasked = f64::INFINITY;
        let mut size = 0.0f64;
        for (i, xi) in x.chunks_exact(d.dim).enumerate() {
            let m = self.blocks[i].margin(xi) / d.w_scale;
            size = size.max(crate::law::norm(xi) / d.w_scale);
            if self.mask[i] {
                masked = masked.min(m);
            } else {
                unmasked = unmasked.min(m);
            }
        }
        VelocityCheck {
            masked,
            unmasked,
            size,
        }
    }

    /// Projects r onto the dual cones, normalizes it and recomputes wᵀ r and ‖H r‖.
    fn check_impulse(&self, r: &[f64]) -> Option<ImpulseCheck> {
        let d = self.data;
        let mut r = r.to_vec();
        for (i, ri) in r.chunks_exact_mut(d.dim).enumerate() {
            self.blocks[i].project_dual(ri);
        }
        let on_mask_sum: f64 = (0..d.contacts())
            .filter(|&i| self.mask[i])
            .map(|i| r[i * d.dim])
            .sum();
        let norm = crate::law::norm(&r);
        if norm == 0.0 || !norm.is_finite() {
            return None;
        }
        let on_mask = on_mask_sum > 1e-9 * norm;
        let scale = if on_mask { on_mask_sum } else { norm };
        r.iter_mut().for_each(|x| *x /= scale);
        let value = if self.homogeneous {
            0.0
        } else {
            r.iter().zip(d.w).map(|(a, b)| a * b).sum::<f64>() / d.w_scale
        };
        let hr = d.b.mul_vec(&r);
        let denom: f64 = r.iter().zip(&d.col_norms).map(|(a, c)| a.abs() * c).sum();
        let residual = if denom > 0.0 {
            crate::law::norm(&hr) / denom
        } else {
            // H r = 0 trivially: every column r touches is zero.
            0.0
        };
        let polyhedral = d.dim == 2 || self.blocks.iter().all(|b| !matches!(b, Block::Soc(_)));
        let w_hat_norm = if self.homogeneous {
            0.0
        } else {
            crate::law::norm(d.w) / d.w_scale
        };
        let spread = if polyhedral {
            residual
        } else {
            residual.sqrt()
        };
        let bound = value + KERNEL_SLACK * w_hat_norm * crate::law::norm(&r) * spread;
        Some(ImpulseCheck {
            r,
            value,
            on_mask,
            residual,
            bound,
        })
    }
}

impl MarginSolve {
    fn failed(msg: &str) -> Self {
        Self {
            v: None,
            r: None,
            clarabel_status: msg.to_string(),
        }
    }
}

fn undecided(detail: String, margin: Option<f64>, dual_bound: Option<f64>) -> CriterionReport {
    CriterionReport {
        verdict: Verdict::Undecided,
        certificate_residual: None,
        certificate_kind: None,
        certificate: None,
        margin,
        dual_bound,
        detail,
    }
}

/// Everything one margin solve yields, verified.
struct Verified {
    solve: MarginSolve,
    vel: Option<(Vec<f64>, VelocityCheck)>,
    imp: Option<ImpulseCheck>,
}

fn solve_and_verify(mp: &MarginProblem, settings: &CheckSettings) -> Verified {
    let solve = mp.solve(settings);
    let vel = solve.v.as_ref().map(|v| (v.clone(), mp.check_velocity(v)));
    let imp = solve.r.as_ref().and_then(|r| mp.check_impulse(r));
    Verified { solve, vel, imp }
}

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "n/a".to_string(), |v| format!("{v:.3e}"))
}

/// (4.5): margin problem on the half-spaces {x_N ≥ 0}, all contacts shifted.
fn criterion_4_5(data: &KinematicData, settings: &CheckSettings) -> CriterionReport {
    let n = data.contacts();
    let mp = MarginProblem {
        data,
        blocks: vec![Block::HalfSpace; n],
        mask: vec![true; n],
        homogeneous: false,
    };
    let ver = solve_and_verify(&mp, settings);
    let margin = ver.vel.as_ref().map(|(_, c)| c.masked.min(c.unmasked));
    if let (Some((v, _)), Some(m)) = (&ver.vel, margin) {
        if m >= -settings.tol {
            return CriterionReport {
                verdict: Verdict::Holds,
                certificate_residual: Some((-m).max(0.0)),
                certificate_kind: Some(CertificateKind::Velocity),
                certificate: Some(v.clone()),
                margin: Some(m),
                dual_bound: None,
                detail: format!(
                    "v found with (Hᵀv + w)_N ≥ {m:.3e}·‖w‖∞ at every contact: non-penetration is kinematically possible"
                ),
            };
        }
    }
    if let Some(imp) = &ver.imp {
        if imp.bound < -settings.tol && imp.residual <= settings.certificate_tol {
            let y: Vec<f64> = imp.r.chunks_exact(data.dim).map(|c| c[0]).collect();
            return CriterionReport {
                verdict: Verdict::Fails,
                certificate_residual: Some(imp.residual),
                certificate_kind: Some(CertificateKind::Farkas),
                certificate: Some(y),
                margin,
                dual_bound: Some(imp.bound),
                detail: format!(
                    "Farkas certificate y ≥ 0, Σy = 1, H_N y ≈ 0 (relative residual {:.2e}), w_Nᵀy = {:.3e}·‖w‖∞ (upper bound with the kernel-residual slack: {:.3e}) < 0: \
                     penetration cannot be prevented, no solution exists",
                    imp.residual, imp.value, imp.bound
                ),
            };
        }
    }
    undecided(
        format!(
            "no certificate verified (Clarabel: {}; best margin {}, dual bound {})",
            ver.solve.clarabel_status,
            fmt_opt(margin),
            fmt_opt(ver.imp.as_ref().map(|i| i.bound))
        ),
        margin,
        ver.imp.as_ref().map(|i| i.bound),
    )
}

/// (4.4) and (4.6) from one margin problem on L* with every contact shifted: t* ≥ 0 ⇔ (4.6);
/// an attained t* ≥ 0 ⇔ (4.4).
fn criteria_4_4_and_4_6(
    data: &KinematicData,
    settings: &CheckSettings,
) -> (CriterionReport, CriterionReport) {
    let n = data.contacts();
    let blocks: Vec<Block> = (0..n).map(|i| data.dual_block(i)).collect();
    let polyhedral = data.dim == 2 || blocks.iter().all(|b| !matches!(b, Block::Soc(_)));
    let mp = MarginProblem {
        data,
        blocks,
        mask: vec![true; n],
        homogeneous: false,
    };
    let ver = solve_and_verify(&mp, settings);
    let margin = ver.vel.as_ref().map(|(_, c)| c.masked.min(c.unmasked));
    let dual_bound = ver.imp.as_ref().map(|i| i.bound);
    if let (Some((v, c)), Some(m)) = (&ver.vel, margin) {
        if m >= -settings.tol {
            let v_rel = crate::law::norm(v) * data.b_scale / data.w_scale;
            let r46 = CriterionReport {
                verdict: Verdict::Holds,
                certificate_residual: Some((-m).max(0.0)),
                certificate_kind: Some(CertificateKind::Velocity),
                certificate: Some(v.clone()),
                margin: Some(m),
                dual_bound,
                detail: format!(
                    "v found with worst margin x_N − μ‖x_T‖ = {m:.3e}·‖w‖∞ of Hᵀv + w: w ∈ cl(Im Hᵀ + L*) \
                     within tolerance, i.e. wᵀr ≥ 0 on L ∩ Ker H"
                ),
            };
            let unattained = m < 0.0 && !polyhedral && v_rel > UNATTAINED_V_NORM;
            let r44 = if unattained {
                undecided(
                    format!(
                        "margin sup ≈ 0 ({m:.3e}) reached only with ‖v‖ ≈ {v_rel:.1e}·‖w‖∞/max|H|: \
                         w lies on the boundary of Im Hᵀ + L*, which may not be closed (d = 3)"
                    ),
                    Some(m),
                    dual_bound,
                )
            } else {
                CriterionReport {
                    detail: format!(
                        "v found with Hᵀv + w ∈ L* (worst margin x_N − μ‖x_T‖ = {m:.3e}·‖w‖∞, max ‖xⁱ‖ = {:.3e}·‖w‖∞)",
                        c.size
                    ),
                    ..r46.clone()
                }
            };
            return (r44, r46);
        }
    }
    if let Some(imp) = &ver.imp {
        if imp.bound < -settings.tol && imp.residual <= settings.certificate_tol {
            let rep = CriterionReport {
                verdict: Verdict::Fails,
                certificate_residual: Some(imp.residual),
                certificate_kind: Some(CertificateKind::Impulse),
                certificate: Some(imp.r.clone()),
                margin,
                dual_bound: Some(imp.bound),
                detail: format!(
                    "r ∈ L with Σ r_N = 1, ‖H r‖ relative residual {:.2e}, wᵀr = {:.3e}·‖w‖∞ (upper bound with the kernel-residual slack: {:.3e}) < 0: \
                     w ∉ cl(Im Hᵀ + L*)",
                    imp.residual, imp.value, imp.bound
                ),
            };
            return (rep.clone(), rep);
        }
    }
    let detail = format!(
        "no certificate verified (Clarabel: {}; best margin {}, dual bound {})",
        ver.solve.clarabel_status,
        fmt_opt(margin),
        fmt_opt(dual_bound)
    );
    (
        undecided(detail.clone(), margin, dual_bound),
        undecided(detail, margin, dual_bound),
    )
}

/// (4.1): margin problem on L* with the contacts 0 < μ < ∞ shifted (interiors) and the
/// frictionless half-spaces kept closed.
fn criterion_4_1(data: &KinematicData, settings: &CheckSettings) -> CriterionReport {
    let n = data.contacts();
    if let Some(i) = data.mu.iter().position(|m| m.is_infinite()) {
        return CriterionReport {
            verdict: Verdict::Fails,
            certificate_residual: None,
            certificate_kind: None,
            certificate: None,
            margin: None,
            dual_bound: None,
            detail: format!(
                "contact {i} has μ = ∞: its dual cone K_0 has empty interior, so 𝓛* = ∅"
            ),
        };
    }
    let blocks: Vec<Block> = (0..n).map(|i| data.dual_block(i)).collect();
    let mask: Vec<bool> = blocks.iter().map(|b| matches!(b, Block::Soc(_))).collect();
    let mp = MarginProblem {
        data,
        blocks,
        mask,
        homogeneous: false,
    };
    let ver = solve_and_verify(&mp, settings);
    let margin = ver.vel.as_ref().map(|(_, c)| c.masked);
    let dual_bound = ver.imp.as_ref().map(|i| i.bound);
    if let Some((v, c)) = &ver.vel {
        if c.masked > settings.tol && c.unmasked >= -settings.tol {
            let shown = if c.masked.is_finite() {
                format!("{:.3e}·‖w‖∞", c.masked)
            } else {
                "∞ (no contact with μ > 0)".to_string()
            };
            return CriterionReport {
                verdict: Verdict::Holds,
                certificate_residual: Some(if c.unmasked < 0.0 { -c.unmasked } else { 0.0 }),
                certificate_kind: Some(CertificateKind::Velocity),
                certificate: Some(v.clone()),
                margin: c.masked.is_finite().then_some(c.masked),
                dual_bound,
                detail: format!(
                    "v found with Hᵀv + w ∈ 𝓛*: margin x_N − μ‖x_T‖ ≥ {shown} at contacts with μ > 0, \
                     frictionless contacts x_N ≥ {:.3e}·‖w‖∞",
                    if c.unmasked.is_finite() { c.unmasked } else { 0.0 }
                ),
            };
        }
    }
    if let Some(imp) = &ver.imp {
        let bound_ok = if imp.on_mask {
            imp.bound <= settings.tol
        } else {
            imp.bound < -settings.tol
        };
        if bound_ok && imp.residual <= settings.certificate_tol {
            return CriterionReport {
                verdict: Verdict::Fails,
                certificate_residual: Some(imp.residual),
                certificate_kind: Some(CertificateKind::Impulse),
                certificate: Some(imp.r.clone()),
                margin,
                dual_bound: Some(imp.bound),
                detail: if imp.on_mask {
                    format!(
                        "r ∈ L ∩ Ker H (relative residual {:.2e}) with Σ_{{μ>0}} r_N = 1 bounds every margin by wᵀr = {:.3e}·‖w‖∞ (upper bound with the kernel-residual slack: {:.3e}) ≤ tol",
                        imp.residual, imp.value, imp.bound
                    )
                } else {
                    format!(
                        "r ∈ L ∩ Ker H (relative residual {:.2e}) with wᵀr = {:.3e}·‖w‖∞ (upper bound with the kernel-residual slack: {:.3e}) < 0: even the closed cone constraint is infeasible",
                        imp.residual, imp.value, imp.bound
                    )
                },
            };
        }
    }
    undecided(
        format!(
            "no certificate verified (Clarabel: {}; best margin {}, dual bound {})",
            ver.solve.clarabel_status,
            fmt_opt(margin),
            fmt_opt(dual_bound)
        ),
        margin,
        dual_bound,
    )
}

/// (5.1): margin problem on L* with w = 0 and every contact shifted: t* = 1 ⇔ ∃ v with
/// Hᵀv ∈ int L* ⇔ Ker H ∩ L = {0}; t* = 0 ⇔ a nonzero r ∈ L ∩ Ker H.
fn criterion_5_1(data: &KinematicData, settings: &CheckSettings) -> CriterionReport {
    let n = data.contacts();
    let blocks: Vec<Block> = (0..n).map(|i| data.dual_block(i)).collect();
    let mp = MarginProblem {
        data,
        blocks,
        mask: vec![true; n],
        homogeneous: true,
    };
    let ver = solve_and_verify(&mp, settings);
    // Homogeneous: the margin is relative to the size of Hᵀ v.
    let margin = ver.vel.as_ref().map(|(_, c)| {
        if c.size > 0.0 {
            c.masked.min(c.unmasked) / c.size
        } else {
            0.0
        }
    });
    if let (Some((v, _)), Some(m)) = (&ver.vel, margin) {
        if m > settings.tol {
            return CriterionReport {
                verdict: Verdict::Holds,
                certificate_residual: Some(0.0),
                certificate_kind: Some(CertificateKind::Velocity),
                certificate: Some(v.clone()),
                margin: Some(m),
                dual_bound: None,
                detail: format!(
                    "v found with Hᵀv ∈ int L* (relative margin {m:.3e}): Ker H ∩ L = {{0}}, so every w satisfies (4.1), (4.4), (4.6)"
                ),
            };
        }
    }
    if let Some(imp) = &ver.imp {
        if imp.on_mask && imp.residual <= settings.certificate_tol {
            return CriterionReport {
                verdict: Verdict::Fails,
                certificate_residual: Some(imp.residual),
                certificate_kind: Some(CertificateKind::Impulse),
                certificate: Some(imp.r.clone()),
                margin,
                dual_bound: None,
                detail: format!(
                    "nonzero r ∈ L ∩ Ker H: Σ r_N = 1, ‖H r‖ relative residual {:.2e} (self-equilibrated contact impulses)",
                    imp.residual
                ),
            };
        }
    }
    undecided(
        format!(
            "no certificate verified (Clarabel: {}; relative margin {})",
            ver.solve.clarabel_status,
            fmt_opt(margin)
        ),
        margin,
        None,
    )
}

fn trivially_holds(detail: &str) -> CriterionReport {
    CriterionReport {
        verdict: Verdict::Holds,
        certificate_residual: Some(0.0),
        certificate_kind: None,
        certificate: None,
        margin: None,
        dual_bound: None,
        detail: detail.to_string(),
    }
}

fn run_all_with(
    data: &KinematicData,
    kind: &'static str,
    settings: &CheckSettings,
    progress: &mut dyn FnMut(Criterion),
) -> Result<ExistenceReport, CheckError> {
    validate_settings(settings)?;
    let start = Instant::now();
    let frictionless = data.mu.iter().all(|&m| m == 0.0);
    let criteria = if data.contacts() == 0 {
        let h = trivially_holds("no contacts");
        Criteria {
            c4_1: h.clone(),
            c4_4: h.clone(),
            c4_5: h.clone(),
            c4_6: h.clone(),
            c5_1: h,
        }
    } else {
        progress(Criterion::C4_5);
        let c4_5 = criterion_4_5(data, settings);
        progress(Criterion::C4_4);
        let (c4_4, c4_6) = criteria_4_4_and_4_6(data, settings);
        progress(Criterion::C4_1);
        let c4_1 = criterion_4_1(data, settings);
        progress(Criterion::C5_1);
        let c5_1 = criterion_5_1(data, settings);
        Criteria {
            c4_1,
            c4_4,
            c4_5,
            c4_6,
            c5_1,
        }
    };
    let conclusion = conclude(&criteria, frictionless);
    Ok(ExistenceReport {
        kind,
        dim: data.dim,
        contacts: data.contacts(),
        frictionless,
        criteria,
        conclusion,
        note: None,
        seconds: start.elapsed().as_secs_f64(),
    })
}

fn validate_settings(s: &CheckSettings) -> Result<(), CheckError> {
    if !s.tol.is_finite() || s.tol < 0.0 {
        return Err(CheckError::Settings(format!("tol = {} is not ≥ 0", s.tol)));
    }
    if !s.certificate_tol.is_finite() || s.certificate_tol < 0.0 {
        return Err(CheckError::Settings(format!(
            "certificate_tol = {} is not ≥ 0",
            s.certificate_tol
        )));
    }
    if s.max_iter == 0 {
        return Err(CheckError::Settings("max_iter = 0".into()));
    }
    if s.time_limit.is_nan() || s.time_limit <= 0.0 {
        return Err(CheckError::Settings(format!(
            "time_limit = {} is not > 0",
            s.time_limit
        )));
    }
    Ok(())
}

/// The theory's conclusion from the verdicts: (4.5) failing proves non-existence; in the
/// frictionless case (4.4) is necessary and sufficient (§5.1); otherwise the first sufficient
/// criterion that holds, in the order (4.1) Thm 4.6, (5.1) Thm 5.1, (4.4) \[21\], (4.6) \[48\].
pub fn conclude(c: &Criteria, frictionless: bool) -> Conclusion {
    if c.c4_5.verdict == Verdict::Fails {
        return Conclusion::None {
            by: Criterion::C4_5,
            theorem: "(4.5) is necessary: non-penetration must be kinematically possible (Fig. 3)",
        };
    }
    if frictionless {
        match c.c4_4.verdict {
            Verdict::Holds => {
                return Conclusion::Exists {
                    by: Criterion::C4_4,
                    theorem: "§5.1: frictionless, (4.4) is necessary and sufficient",
                }
            }
            Verdict::Fails => {
                return Conclusion::None {
                    by: Criterion::C4_4,
                    theorem: "§5.1: frictionless, (4.4) is necessary and sufficient",
                }
            }
            Verdict::Undecided => {}
        }
    }
    let sufficient = [
        (Criterion::C4_1, "Theorem 4.6"),
        (
            Criterion::C5_1,
            "Theorem 5.1 (a solution exists for every w)",
        ),
        (
            Criterion::C4_4,
            "Cadoux–Malick [21], generalizing Thm 4.6 (after Prop. 4.8)",
        ),
        (Criterion::C4_6, "Klarbring–Pang [48] via Prop. 4.8"),
    ];
    for (by, theorem) in sufficient {
        if c.get(by).verdict == Verdict::Holds {
            return Conclusion::Exists { by, theorem };
        }
    }
    Conclusion::Unknown
}

#[cfg(test)]
mod tests {
    use super::*;

    fn local(dim: i64, w: &[f64], q: Vec<f64>, mu: Vec<f64>) -> Problem {
        let m = q.len();
        let w = CscMatrix::from_dense(m, m, w);
        Problem::Local(LocalProblem::new(dim, w, q, mu).unwrap())
    }

    #[test]
    fn single_contact_local_pushing_apart_exists() {
        // W = I, q = (1, 0): (4.1) holds with v = 0.
        let p = local(2, &[1.0, 0.0, 0.0, 1.0], vec![1.0, 0.0], vec![0.5]);
        let rep = check(&p, &CheckSettings::default()).unwrap();
        assert_eq!(rep.criteria.c4_1.verdict, Verdict::Holds);
        assert_eq!(rep.criteria.c5_1.verdict, Verdict::Holds);
        assert!(matches!(rep.conclusion, Conclusion::Exists { .. }));
    }

    #[test]
    fn zero_contacts_exist() {
        let p = local(3, &[], vec![], vec![]);
        let rep = check(&p, &CheckSettings::default()).unwrap();
        assert!(matches!(rep.conclusion, Conclusion::Exists { .. }));
    }

    #[test]
    fn zero_delassus_and_infinite_friction_do_not_break() {
        // W = 0: u = q whatever r. q_N < 0 at contact 1: (4.5) fails with y = e₁.
        let p = local(
            3,
            &[0.0; 36],
            vec![1.0, 0.0, 0.0, -1.0, 0.5, 0.0],
            vec![0.3, 0.3],
        );
        let rep = check(&p, &CheckSettings::default()).unwrap();
        assert_eq!(rep.criteria.c4_5.verdict, Verdict::Fails);
        let y = rep.criteria.c4_5.certificate.clone().unwrap();
        assert!(
            y[0] >= 0.0 && y[0] < 1e-6 && (y[1] - 1.0).abs() < 1e-6,
            "{y:?}"
        );
        assert!(matches!(rep.conclusion, Conclusion::None { .. }));
        // μ = ∞ at one contact: K_0 has empty interior, (4.1) fails; nothing panics.
        let p = local(
            2,
            &[1.0, 0.0, 0.0, 1.0],
            vec![1.0, 0.0],
            vec![f64::INFINITY],
        );
        let rep = check(&p, &CheckSettings::default()).unwrap();
        assert_eq!(rep.criteria.c4_1.verdict, Verdict::Fails);
        assert_eq!(rep.criteria.c4_4.verdict, Verdict::Holds);
    }

    #[test]
    fn bad_settings_are_rejected() {
        let p = local(2, &[1.0, 0.0, 0.0, 1.0], vec![1.0, 0.0], vec![0.5]);
        let s = CheckSettings {
            tol: f64::NAN,
            ..CheckSettings::default()
        };
        assert!(matches!(check(&p, &s), Err(CheckError::Settings(_))));
    }
}
