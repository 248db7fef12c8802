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

mod criteria;
mod margin;

use crate::linalg::sparse::CscMatrix;
use crate::problem::{GlobalProblem, LocalProblem, Problem, ProblemError};
use clarabel::algebra as ca;
use clarabel::solver::{self as cs, IPSolver};
use criteria::run_all_with;
use margin::KinematicData;
use std::time::{Duration, Instant};
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

#[cfg(feature = "serde")]
impl serde::Serialize for Criterion {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.label())
    }
}

/// Outcome of one criterion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Verdict {
    /// the criterion holds, with a verified certificate (within tolerance)
    Holds,
    /// the criterion fails, with a verified certificate (within tolerance)
    Fails,
    /// neither certificate could be verified within tolerance
    Undecided,
}

/// What a certificate vector is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
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
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
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
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Criteria {
    /// (4.1)
    #[cfg_attr(feature = "serde", serde(rename = "4.1"))]
    pub c4_1: CriterionReport,
    /// (4.4)
    #[cfg_attr(feature = "serde", serde(rename = "4.4"))]
    pub c4_4: CriterionReport,
    /// (4.5)
    #[cfg_attr(feature = "serde", serde(rename = "4.5"))]
    pub c4_5: CriterionReport,
    /// (4.6)
    #[cfg_attr(feature = "serde", serde(rename = "4.6"))]
    pub c4_6: CriterionReport,
    /// (5.1)
    #[cfg_attr(feature = "serde", serde(rename = "5.1"))]
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
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(tag = "kind", rename_all = "snake_case"))]
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
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
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
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub note: Option<String>,
    /// wall-clock seconds spent
    pub seconds: f64,
}

/// Settings of [`check`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct CheckSettings {
    /// decision tolerance on margins and dual bounds (relative to ‖w‖∞)
    pub tol: f64,
    /// largest accepted certificate residual
    pub certificate_tol: f64,
    /// iteration cap of each conic solve
    pub max_iter: u32,
    /// wall-clock cap of each conic solve (> 0)
    pub time_limit: Duration,
}

impl Default for CheckSettings {
    fn default() -> Self {
        Self {
            tol: 1e-7,
            certificate_tol: 1e-6,
            max_iter: 200,
            time_limit: Duration::from_secs(30),
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
    if p.equality.is_some() {
        return check_equality(p, settings, progress);
    }
    let data = KinematicData::new(p.dim, &p.h, &p.w, &p.mu)?;
    let mut report = run_all_with(&data, "global", settings, progress)?;
    let asymmetry = p.m.asymmetry();
    if asymmetry > ROUNDING_ASYMMETRY {
        downgrade(&mut report, "M", asymmetry);
    }
    Ok(report)
}

/// A global problem with equality constraints (G, b): the criteria on its reduced local
/// problem (W̃, q̃) of [`crate::equality`] (W̃ = Hᵀ (M⁻¹ − M⁻¹ G S⁺ Gᵀ M⁻¹) H is the Delassus
/// operator of the motions the constraints allow, symmetric when M is). That equivalence needs
/// constraints some v satisfies: when the velocity of r = 0 leaves an equality residual above
/// `settings.tol` (b not in the range of Gᵀ), an "exists" becomes [`Conclusion::Unknown`]
/// with a note.
fn check_equality(
    p: &GlobalProblem,
    settings: &CheckSettings,
    progress: &mut dyn FnMut(Criterion),
) -> Result<ExistenceReport, CheckError> {
    let reduction = crate::equality::Reduction::new(p)?;
    let mut report = check_local_with(&reduction.local, settings, progress)?;
    report.kind = "global";
    let asymmetry = p.m.asymmetry();
    if asymmetry > ROUNDING_ASYMMETRY {
        downgrade(&mut report, "M", asymmetry);
    }
    let r0 = vec![0.0; p.h.ncols];
    let (v0, _) = reduction.recover(p, &r0);
    let residual = p.equality_residual(&v0).unwrap_or(0.0);
    if residual.is_nan() || residual > settings.tol {
        if let Conclusion::Exists { by, .. } = report.conclusion {
            report.note = Some(format!(
                "{by} holds on the problem reduced by the equality constraints, but no velocity \
                 satisfies them: the equality residual ‖Gᵀ v + b‖ / max(1, ‖b‖) stays at \
                 {residual:.2e} (b is not in the range of Gᵀ)"
            ));
            report.conclusion = Conclusion::Unknown;
        }
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
    if s.time_limit.is_zero() {
        return Err(CheckError::Settings("time_limit = 0 s is not > 0".into()));
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

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    fn local(dim: i64, w: &[f64], q: Vec<f64>, mu: Vec<f64>) -> Problem {
        let m = q.len();
        let w = CscMatrix::from_dense(m, m, w);
        Problem::Local(LocalProblem::new(dim, w, q, mu).unwrap())
    }

    pub fn single_contact_local_pushing_apart_exists() {
        // W = I, q = (1, 0): (4.1) holds with v = 0.
        let p = local(2, &[1.0, 0.0, 0.0, 1.0], vec![1.0, 0.0], vec![0.5]);
        let rep = check(&p, &CheckSettings::default()).unwrap();
        assert_eq!(rep.criteria.c4_1.verdict, Verdict::Holds);
        assert_eq!(rep.criteria.c5_1.verdict, Verdict::Holds);
        assert!(matches!(rep.conclusion, Conclusion::Exists { .. }));
    }

    pub fn zero_contacts_exist() {
        let p = local(3, &[], vec![], vec![]);
        let rep = check(&p, &CheckSettings::default()).unwrap();
        assert!(matches!(rep.conclusion, Conclusion::Exists { .. }));
    }

    pub fn zero_delassus_and_infinite_friction_do_not_break() {
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

    pub fn bad_settings_are_rejected() {
        let p = local(2, &[1.0, 0.0, 0.0, 1.0], vec![1.0, 0.0], vec![0.5]);
        let s = CheckSettings {
            tol: f64::NAN,
            ..CheckSettings::default()
        };
        assert!(matches!(check(&p, &s), Err(CheckError::Settings(_))));
    }

    pub fn existence_check_sees_the_constraints() {
        let settings = CheckSettings::default();
        // a solution exists (found above): the check of the reduced problem cannot say none
        let ok = check(
            &Problem::Global(crate::test_problems::equality_ball(1, None)),
            &settings,
        )
        .unwrap();
        assert!(!matches!(ok.conclusion, Conclusion::None { .. }), "{ok:?}");
        // inconsistent rows: no solution, so never "exists"
        let bad = check(
            &Problem::Global(crate::test_problems::equality_ball(
                2,
                Some(vec![-0.5, -0.4]),
            )),
            &settings,
        )
        .unwrap();
        assert!(
            !matches!(bad.conclusion, Conclusion::Exists { .. }),
            "{bad:?}"
        );
    }
}
