//! Problem data of the incremental problem (2.10), in its global form (M, H, f, w, μ) and its
//! local (Delassus) form (W, q, μ).
//!
//! # The one internal convention
//! coulomb stores problems in the **FCLIB convention**:
//!
//! ```text
//!     M v = H r + f,     u = Hᵀ v + w,     (uⁱ, rⁱ) ∈ C(eⁱ, μⁱ)   (2.9)
//! ```
//!
//! with H of size n × m (n = dofs, m = d · contacts). The paper writes (2.8)
//! `M v + f_p = H_pᵀ r`, `u = H_p v + w`; the two are related by H = H_pᵀ and f = −f_p
//! ([`GlobalProblem::from_paper`] converts). Eliminating v gives the local form
//! `u = W r + q` with W = Hᵀ M⁻¹ H and q = Hᵀ M⁻¹ f + w (see [`crate::delassus`]).
//!
//! Every contact block is ordered normal first, uⁱ = (u_N, u_T), rⁱ = (r_N, r_T), so the
//! paper's eⁱ is the first basis vector of the block.

use crate::linalg::sparse::{CscMatrix, SparseError};
use thiserror::Error;

/// Relative asymmetry max|A − Aᵀ| / max|A| above which a W or M is reported as not symmetric
/// (by `coulomb info`, and by solvers that then work on ½(A + Aᵀ) internally). The problem
/// itself is always the one stored: a non-symmetric W or M is valid data.
pub const SYMMETRY_TOLERANCE: f64 = 1e-6;

/// Relative shift of the positive-semidefiniteness test of ½(W + Wᵀ): the Cholesky
/// factorization of ½(W + Wᵀ) + τ I with τ = `PSD_SHIFT` · max diag(W) must succeed, i.e. the
/// smallest eigenvalue of the symmetric part is ≥ −τ up to rounding. Real rank-deficient W
/// carry assembly round-off of that order: Confeti-ex13-4contact-Fc3D-SBM (rank 3 of 12)
/// has eigenvalues down to −1.2e-11 for a largest diagonal entry of 3.4e-4 (−3.5e-8
/// relative).
pub const PSD_SHIFT: f64 = 1e-6;

/// What is wrong with a problem's data.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ProblemError {
    /// The space dimension d is not 2 or 3.
    #[error("space dimension d = {0} is not 2 or 3")]
    Dimension(i64),
    /// Two pieces of data do not fit together.
    #[error("shape mismatch in {what}: expected {expected}, found {found}")]
    Shape {
        /// which array or matrix
        what: &'static str,
        /// the size it must have
        expected: String,
        /// the size it has
        found: String,
    },
    /// A matrix or vector entry is NaN or infinite.
    #[error("non-finite entry in {what} at {location}")]
    NonFinite {
        /// which array or matrix
        what: &'static str,
        /// index, or (row, col)
        location: String,
    },
    /// A friction coefficient is negative, NaN, or finite but above [`MU_MAX`] (the
    /// projection onto K_μ needs 1 + μ²; μ = ∞, the half-space, is accepted).
    #[error(
        "friction coefficient mu[{contact}] = {value} is not in [0, {MU_MAX:e}] or inf (a finite μ above {MU_MAX:e} overflows 1 + μ²; write inf for a half-space)"
    )]
    Friction {
        /// contact index
        contact: usize,
        /// the offending value
        value: f64,
    },
    /// M is not positive definite: its Cholesky factorization broke down.
    #[error("M is not positive definite: {0}")]
    NotPositiveDefinite(String),
    /// The symmetric part ½(W + Wᵀ) of W is not positive semidefinite: u = W r + q is then
    /// not the local form of any mechanical system, and Coulomb's law may have no solution
    /// or infinitely many for reasons that are not mechanical.
    #[error("{what} is not positive semidefinite: {detail}")]
    NotPositiveSemidefinite {
        /// which matrix
        what: &'static str,
        /// where it fails
        detail: String,
    },
    /// Sparse storage arrays are inconsistent.
    #[error("inconsistent sparse storage of {what}: {source}")]
    Sparse {
        /// which matrix
        what: &'static str,
        /// what is wrong with its arrays
        source: SparseError,
    },
}

/// The local (Delassus) problem: find r, u with u = W r + q and (uⁱ, rⁱ) ∈ C(eⁱ, μⁱ).
/// The dual inner problem (4.7) is posed on it.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalProblem {
    /// space dimension d ∈ {2, 3}
    pub dim: usize,
    /// Delassus matrix W (m × m, symmetric positive semi-definite), m = d · contacts
    pub w: CscMatrix,
    /// free velocity q (m)
    pub q: Vec<f64>,
    /// friction coefficient of each contact
    pub mu: Vec<f64>,
}

/// Bilateral (equality) constraints of a global problem, FCLIB's `/fclib_global/G` and
/// `/fclib_global/vectors/b`: the problem becomes M v = H r + G λ + f, Gᵀ v + b = 0 with
/// multipliers λ ∈ ℝᵖ (joints: each row of Gᵀ is one constrained velocity component).
#[derive(Debug, Clone, PartialEq)]
pub struct Equality {
    /// G (n × p): column k is the generalized direction of constraint k
    pub g: CscMatrix,
    /// b (p)
    pub b: Vec<f64>,
}

impl Equality {
    /// Number of equality rows p.
    pub fn rows(&self) -> usize {
        self.b.len()
    }
}

/// The global problem (2.10) in FCLIB convention: M v = H r + f, u = Hᵀ v + w; with
/// [`Equality`] constraints, M v = H r + G λ + f and Gᵀ v + b = 0 in addition (the equality
/// rows extend (2.10); they carry no friction).
#[derive(Debug, Clone, PartialEq)]
pub struct GlobalProblem {
    /// space dimension d ∈ {2, 3}
    pub dim: usize,
    /// mass matrix M (n × n, symmetric positive definite)
    pub m: CscMatrix,
    /// H (n × m), m = d · contacts
    pub h: CscMatrix,
    /// f (n)
    pub f: Vec<f64>,
    /// w (m)
    pub w: Vec<f64>,
    /// friction coefficient of each contact
    pub mu: Vec<f64>,
    /// equality constraints Gᵀ v + b = 0 (None: the problem has none; boxed so that a
    /// problem without them stays small)
    pub equality: Option<Box<Equality>>,
}

/// Either form of the incremental problem.
#[derive(Debug, Clone, PartialEq)]
pub enum Problem {
    /// local form (W, q, μ)
    Local(LocalProblem),
    /// global form (M, H, f, w, μ)
    Global(GlobalProblem),
}

impl From<crate::mass::MassError> for ProblemError {
    fn from(e: crate::mass::MassError) -> Self {
        match e {
            crate::mass::MassError::NotPositiveDefinite(detail) => {
                ProblemError::NotPositiveDefinite(detail)
            }
        }
    }
}

impl Problem {
    /// Space dimension d.
    pub fn dim(&self) -> usize {
        match self {
            Problem::Local(p) => p.dim,
            Problem::Global(p) => p.dim,
        }
    }
    /// Number of contacts.
    pub fn contacts(&self) -> usize {
        self.mu().len()
    }
    /// Friction coefficients.
    pub fn mu(&self) -> &[f64] {
        match self {
            Problem::Local(p) => &p.mu,
            Problem::Global(p) => &p.mu,
        }
    }
    /// Number of degrees of freedom n (None for a local problem).
    pub fn dofs(&self) -> Option<usize> {
        match self {
            Problem::Local(_) => None,
            Problem::Global(p) => Some(p.m.nrows),
        }
    }
    /// Relative asymmetry max|A − Aᵀ| / max|A| of W (local) or M (global), as stored.
    pub fn asymmetry(&self) -> f64 {
        match self {
            Problem::Local(p) => p.w.asymmetry(),
            Problem::Global(p) => p.m.asymmetry(),
        }
    }
    /// "local" or "global".
    pub fn kind(&self) -> &'static str {
        match self {
            Problem::Local(_) => "local",
            Problem::Global(_) => "global",
        }
    }
}

fn check_dim(dim: i64) -> Result<usize, ProblemError> {
    if dim == 2 || dim == 3 {
        Ok(dim as usize)
    } else {
        Err(ProblemError::Dimension(dim))
    }
}

pub(crate) fn check_len(what: &'static str, v: &[f64], n: usize) -> Result<(), ProblemError> {
    if v.len() != n {
        return Err(ProblemError::Shape {
            what,
            expected: format!("length {n}"),
            found: format!("length {}", v.len()),
        });
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(ProblemError::NonFinite {
            what,
            location: format!("index {i}"),
        });
    }
    Ok(())
}

fn check_matrix(
    what: &'static str,
    a: &CscMatrix,
    nrows: usize,
    ncols: usize,
) -> Result<(), ProblemError> {
    a.check()
        .map_err(|source| ProblemError::Sparse { what, source })?;
    if a.nrows != nrows || a.ncols != ncols {
        return Err(ProblemError::Shape {
            what,
            expected: format!("{nrows} x {ncols}"),
            found: format!("{} x {}", a.nrows, a.ncols),
        });
    }
    if let Some((r, c)) = a.first_non_finite() {
        return Err(ProblemError::NonFinite {
            what,
            location: format!("({r}, {c})"),
        });
    }
    Ok(())
}

/// Checks that ½(A + Aᵀ) is positive semidefinite up to rounding (A square, finite): first
/// each d × d diagonal block (which locates the common failures: a negative diagonal entry,
/// an indefinite contact block), then the whole matrix by a sparse Cholesky factorization of
/// ½(A + Aᵀ) + τ I with τ = [`PSD_SHIFT`] · max diag(A).
fn check_psd(what: &'static str, dim: usize, a: &CscMatrix) -> Result<(), ProblemError> {
    let n = a.nrows;
    let diag = a.diagonal();
    if let Some(i) = diag.iter().position(|&x| x < 0.0) {
        return Err(ProblemError::NotPositiveSemidefinite {
            what,
            detail: format!("diagonal entry ({i}, {i}) = {:e} < 0", diag[i]),
        });
    }
    let max_diag = diag.iter().fold(0.0f64, |m, &x| m.max(x));
    if max_diag == 0.0 {
        // a positive semidefinite matrix with a zero diagonal is zero
        let sym = a.add_scaled(1.0, &a.transpose());
        return match sym.triplets().find(|&(_, _, v)| v != 0.0) {
            None => Ok(()),
            Some((i, j, _)) => Err(ProblemError::NotPositiveSemidefinite {
                what,
                detail: format!(
                    "its diagonal is zero but ½({what} + {what}ᵀ) has entry ({i}, {j}) ≠ 0"
                ),
            }),
        };
    }
    let tau = PSD_SHIFT * max_diag;
    // diagonal blocks of the symmetric part
    let contacts = n / dim.max(1);
    let mut blocks = vec![[0.0f64; 9]; contacts];
    for (i, j, v) in a.triplets() {
        let (ci, cj) = (i / dim, j / dim);
        if ci == cj && ci < contacts {
            let x = 0.5 * v;
            blocks[ci][(i % dim) * dim + j % dim] += x;
            blocks[ci][(j % dim) * dim + i % dim] += x;
        }
    }
    for (c, b) in blocks.iter().enumerate() {
        if !dense_psd(b, dim, tau) {
            return Err(ProblemError::NotPositiveSemidefinite {
                what,
                detail: format!(
                    "the symmetric part of its diagonal block of contact {c} (rows {}..={}) is indefinite",
                    c * dim,
                    c * dim + dim - 1
                ),
            });
        }
    }
    let ones = vec![1.0; n];
    crate::linalg::sparse::shifted_cholesky_succeeds(a, &ones, tau).map_err(|detail| {
        ProblemError::NotPositiveSemidefinite {
            what,
            detail: format!("½({what} + {what}ᵀ) has a negative eigenvalue ({detail})"),
        }
    })
}

/// Whether the symmetric k × k (k ≤ 3, row-major) matrix `b` + τ I is positive definite
/// (Cholesky without square roots).
fn dense_psd(b: &[f64; 9], k: usize, tau: f64) -> bool {
    let mut a = *b;
    for i in 0..k {
        a[i * k + i] += tau;
    }
    for j in 0..k {
        let mut djj = a[j * k + j];
        for p in 0..j {
            djj -= a[j * k + p] * a[j * k + p] * a[p * k + p];
        }
        if djj.is_nan() || djj <= 0.0 {
            return false;
        }
        a[j * k + j] = djj;
        for i in j + 1..k {
            let mut lij = a[i * k + j];
            for p in 0..j {
                lij -= a[i * k + p] * a[j * k + p] * a[p * k + p];
            }
            a[i * k + j] = lij / djj;
        }
    }
    true
}

/// Largest finite friction coefficient accepted: the projection onto K_μ divides by 1 + μ²,
/// which must stay finite (found by the fuzz harness: μ = f64::MAX gave a wrong error).
pub const MU_MAX: f64 = 1e150;

fn check_mu(mu: &[f64]) -> Result<(), ProblemError> {
    let bad = |m: &f64| m.is_nan() || *m < 0.0 || (m.is_finite() && *m > MU_MAX);
    if let Some(i) = mu.iter().position(bad) {
        return Err(ProblemError::Friction {
            contact: i,
            value: mu[i],
        });
    }
    Ok(())
}

fn contact_count(dim: usize, m: usize, what: &'static str) -> Result<usize, ProblemError> {
    if m % dim != 0 {
        return Err(ProblemError::Shape {
            what,
            expected: format!("a multiple of d = {dim}"),
            found: format!("{m}"),
        });
    }
    Ok(m / dim)
}

impl LocalProblem {
    /// Builds and validates a local problem (W, q, μ) with d = `dim`: W square of size
    /// m = d · contacts with a positive semidefinite symmetric part ½(W + Wᵀ) (W itself need
    /// not be symmetric: real files store W with assembly round-off, and the problem is the
    /// one stored), all data finite, μ ≥ 0.
    pub fn new(dim: i64, w: CscMatrix, q: Vec<f64>, mu: Vec<f64>) -> Result<Self, ProblemError> {
        let dim = check_dim(dim)?;
        let m = mu.len() * dim;
        check_mu(&mu)?;
        check_len("q", &q, m)?;
        check_matrix("W", &w, m, m)?;
        check_psd("W", dim, &w)?;
        Ok(Self { dim, w, q, mu })
    }

    /// Whether W is exactly symmetric (every stored entry equals its transposed entry).
    pub fn is_symmetric(&self) -> bool {
        self.w.is_exactly_symmetric()
    }

    /// Number of contacts.
    pub fn contacts(&self) -> usize {
        self.mu.len()
    }

    /// Whether the sizes agree (d ∈ {2, 3}, m = d · contacts, q of length m, W m × m with
    /// valid storage) and r has length m: what the end games check before any step on a
    /// problem that may have been built by hand without [`LocalProblem::new`].
    pub fn fits(&self, r: &[f64]) -> bool {
        let (d, m) = (self.dim, r.len());
        (d == 2 || d == 3)
            && m == self.mu.len() * d
            && self.q.len() == m
            && self.w.nrows == m
            && self.w.ncols == m
            && self.w.check().is_ok()
    }

    /// u = W r + q.
    pub fn velocity(&self, r: &[f64]) -> Vec<f64> {
        let mut u = self.q.clone();
        self.w.gemv_acc(1.0, r, &mut u);
        u
    }

    /// The error of `docs/error.md` for impulses r, with u recomputed as W r + q.
    pub fn error(&self, r: &[f64]) -> crate::law::ErrorMeasure {
        let u = self.velocity(r);
        crate::law::error_measure(self.dim, &self.mu, r, &u, crate::law::norm(&self.q))
    }
}

impl GlobalProblem {
    /// Builds and validates a global problem in FCLIB convention (M v = H r + f,
    /// u = Hᵀ v + w). M must be symmetric and positive definite; positive definiteness is
    /// established by a Cholesky factorization.
    pub fn new(
        dim: i64,
        m: CscMatrix,
        h: CscMatrix,
        f: Vec<f64>,
        w: Vec<f64>,
        mu: Vec<f64>,
    ) -> Result<Self, ProblemError> {
        let p = Self::new_unfactored(dim, m, h, f, w, mu)?;
        crate::mass::MassFactor::new(&p.m)?;
        Ok(p)
    }

    /// Like [`GlobalProblem::new`] without the Cholesky test of M (every solver factors M
    /// anyway and reports [`ProblemError::NotPositiveDefinite`] then).
    pub fn new_unfactored(
        dim: i64,
        m: CscMatrix,
        h: CscMatrix,
        f: Vec<f64>,
        w: Vec<f64>,
        mu: Vec<f64>,
    ) -> Result<Self, ProblemError> {
        let dim = check_dim(dim)?;
        check_mu(&mu)?;
        let n = m.nrows;
        let nc = contact_count(dim, w.len(), "w")?;
        if nc != mu.len() {
            return Err(ProblemError::Shape {
                what: "mu",
                expected: format!("length {nc} (= len(w) / d)"),
                found: format!("length {}", mu.len()),
            });
        }
        check_matrix("M", &m, n, n)?;
        check_matrix("H", &h, n, w.len())?;
        check_len("f", &f, n)?;
        check_len("w", &w, nc * dim)?;
        Ok(Self {
            dim,
            m,
            h,
            f,
            w,
            mu,
            equality: None,
        })
    }

    /// The problem with equality constraints Gᵀ v + b = 0 added (G of size n × p, b of
    /// length p, finite; any rank: redundant rows are valid data), replacing any it had.
    pub fn with_equality(mut self, g: CscMatrix, b: Vec<f64>) -> Result<Self, ProblemError> {
        check_matrix("G", &g, self.m.nrows, b.len())?;
        check_len("b", &b, g.ncols)?;
        self.equality = Some(Box::new(Equality { g, b }));
        Ok(self)
    }

    /// Number of equality rows p (0 without equality constraints).
    pub fn equality_rows(&self) -> usize {
        self.equality.as_ref().map_or(0, |e| e.rows())
    }

    /// The equality residual ‖Gᵀ v + b‖ / max(1, ‖b‖) (docs/error.md); None without
    /// equality constraints.
    pub fn equality_residual(&self, v: &[f64]) -> Option<f64> {
        let e = self.equality.as_ref()?;
        let mut res = e.b.clone();
        e.g.gemv_t_acc(1.0, v, &mut res);
        Some(crate::law::relative_norm(&res, &e.b))
    }

    /// The balance residual ‖M v − H r − G λ − f‖ / max(1, ‖f‖), with the multipliers λ of
    /// the equality constraints (`l`; ignored without them, taken as zero when None).
    pub fn balance_residual_with(&self, v: &[f64], r: &[f64], l: Option<&[f64]>) -> f64 {
        let mut res = self.m.mul_vec(v);
        self.h.gemv_acc(-1.0, r, &mut res);
        if let (Some(e), Some(l)) = (&self.equality, l) {
            e.g.gemv_acc(-1.0, l, &mut res);
        }
        for (x, f) in res.iter_mut().zip(&self.f) {
            *x -= f;
        }
        crate::law::relative_norm(&res, &self.f)
    }

    /// Builds a problem from the paper's convention (2.8): `M v + f_p = H_pᵀ r`,
    /// `u = H_p v + w`, with H_p of size m × n. Stored as H = H_pᵀ, f = −f_p.
    pub fn from_paper(
        dim: i64,
        m: CscMatrix,
        h_p: &CscMatrix,
        f_p: &[f64],
        w: Vec<f64>,
        mu: Vec<f64>,
    ) -> Result<Self, ProblemError> {
        Self::new(
            dim,
            m,
            h_p.transpose(),
            f_p.iter().map(|x| -x).collect(),
            w,
            mu,
        )
    }

    /// The paper's (H_p, f_p) = (Hᵀ, −f) of (2.8).
    pub fn to_paper(&self) -> (CscMatrix, Vec<f64>) {
        (self.h.transpose(), self.f.iter().map(|x| -x).collect())
    }

    /// Number of contacts.
    pub fn contacts(&self) -> usize {
        self.mu.len()
    }

    /// Number of degrees of freedom n.
    pub fn dofs(&self) -> usize {
        self.m.nrows
    }

    /// u = Hᵀ v + w.
    pub fn velocity(&self, v: &[f64]) -> Vec<f64> {
        let mut u = self.w.clone();
        self.h.gemv_t_acc(1.0, v, &mut u);
        u
    }

    /// The balance residual ‖M v − H r − f‖ / max(1, ‖f‖) (λ = 0 for a problem with
    /// equality constraints: see [`GlobalProblem::balance_residual_with`]).
    pub fn balance_residual(&self, v: &[f64], r: &[f64]) -> f64 {
        self.balance_residual_with(v, r, None)
    }
}

/// x projected onto L = Π K_μᵢ.
pub(crate) fn projected(p: &LocalProblem, x: &[f64]) -> Vec<f64> {
    let mut y = x.to_vec();
    crate::cone::project_product(p.dim, &p.mu, &mut y);
    y
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    fn small_global() -> GlobalProblem {
        let m = CscMatrix::from_dense(2, 2, &[2.0, 0.5, 0.5, 1.0]);
        let h = CscMatrix::from_dense(2, 2, &[1.0, 0.0, 0.3, 1.0]);
        GlobalProblem::new(2, m, h, vec![1.0, -2.0], vec![0.1, 0.0], vec![0.5]).unwrap()
    }

    pub fn paper_convention_round_trip() {
        let g = small_global();
        let (hp, fp) = g.to_paper();
        let back =
            GlobalProblem::from_paper(2, g.m.clone(), &hp, &fp, g.w.clone(), g.mu.clone()).unwrap();
        assert_eq!(back, g);
        // Same (v, r) satisfies both forms of the balance: M v + f_p = H_pᵀ r  ⇔  M v = H r + f.
        let v = [0.3, -0.7];
        let r = [1.0, 0.2];
        let mv = g.m.mul_vec(&v);
        let hpr = hp.mul_t_vec(&r);
        let hr = g.h.mul_vec(&r);
        for i in 0..2 {
            let paper = mv[i] + fp[i] - hpr[i];
            let fclib = mv[i] - hr[i] - g.f[i];
            assert!((paper - fclib).abs() < 1e-14);
        }
        // u = H_p v + w = Hᵀ v + w
        let u1 = g.velocity(&v);
        let mut u2 = hp.mul_vec(&v);
        u2.iter_mut().zip(&g.w).for_each(|(a, b)| *a += b);
        assert_eq!(u1, u2);
    }

    pub fn zero_contacts_is_valid() {
        let m = CscMatrix::identity(3, 1.0);
        let h = CscMatrix::zeros(3, 0);
        let g = GlobalProblem::new(3, m, h, vec![0.0; 3], vec![], vec![]).unwrap();
        assert_eq!(g.contacts(), 0);
        let l = LocalProblem::new(2, CscMatrix::zeros(0, 0), vec![], vec![]).unwrap();
        assert_eq!(l.contacts(), 0);
    }

    pub fn every_validation_error_is_reported() {
        let w = CscMatrix::identity(2, 1.0);
        assert_eq!(
            LocalProblem::new(4, w.clone(), vec![0.0; 2], vec![0.1]),
            Err(ProblemError::Dimension(4))
        );
        assert!(matches!(
            LocalProblem::new(2, w.clone(), vec![0.0; 3], vec![0.1]),
            Err(ProblemError::Shape { what: "q", .. })
        ));
        assert!(matches!(
            LocalProblem::new(2, w.clone(), vec![0.0, f64::NAN], vec![0.1]),
            Err(ProblemError::NonFinite { what: "q", .. })
        ));
        assert!(matches!(
            LocalProblem::new(2, w.clone(), vec![0.0; 2], vec![-0.1]),
            Err(ProblemError::Friction { contact: 0, .. })
        ));
        assert!(matches!(
            LocalProblem::new(2, w.clone(), vec![0.0; 2], vec![f64::NAN]),
            Err(ProblemError::Friction { .. })
        ));
        // a finite μ whose square overflows is refused; μ = ∞ (half-space) is accepted
        for huge in [f64::MAX, 1e200] {
            assert!(matches!(
                LocalProblem::new(2, w.clone(), vec![0.0; 2], vec![huge]),
                Err(ProblemError::Friction { contact: 0, .. })
            ));
        }
        LocalProblem::new(2, w.clone(), vec![0.0; 2], vec![f64::INFINITY]).unwrap();
        LocalProblem::new(2, w.clone(), vec![0.0; 2], vec![MU_MAX]).unwrap();
        // a non-symmetric W with a positive definite symmetric part is a valid problem
        let asym = CscMatrix::from_dense(2, 2, &[1.0, 1.0, 0.0, 1.0]);
        let p = LocalProblem::new(2, asym, vec![0.0; 2], vec![0.1]).unwrap();
        assert!(!p.is_symmetric());
        // W whose symmetric part is indefinite: −I, −0.01 I, diag(1, −1), [[1, 2], [2, 1]]
        for dense in [
            [-1.0, 0.0, 0.0, -1.0],
            [-0.01, 0.0, 0.0, -0.01],
            [1.0, 0.0, 0.0, -1.0],
            [1.0, 2.0, 2.0, 1.0],
            [1.0, 4.0, 0.0, 1.0],
        ] {
            let bad_w = CscMatrix::from_dense(2, 2, &dense);
            assert!(
                matches!(
                    LocalProblem::new(2, bad_w, vec![0.0; 2], vec![0.1]),
                    Err(ProblemError::NotPositiveSemidefinite { what: "W", .. })
                ),
                "{dense:?}"
            );
        }
        // diagonal blocks positive definite, the whole symmetric part indefinite (two
        // contacts coupled by 2 I): found by the sparse Cholesky test
        #[rustfmt::skip]
        let coupled = [
            1.0, 0.0, 2.0, 0.0,
            0.0, 1.0, 0.0, 2.0,
            2.0, 0.0, 1.0, 0.0,
            0.0, 2.0, 0.0, 1.0,
        ];
        let coupled = CscMatrix::from_dense(4, 4, &coupled);
        let err = LocalProblem::new(2, coupled, vec![0.0; 4], vec![0.1, 0.1]).unwrap_err();
        assert!(err.to_string().contains("negative eigenvalue"), "{err}");
        // a skew part of any size is fine; a singular symmetric part too
        let skew = CscMatrix::from_dense(2, 2, &[1.0, 30.0, -30.0, 1.0]);
        LocalProblem::new(2, skew, vec![0.0; 2], vec![0.1]).unwrap();
        let singular = CscMatrix::from_dense(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        LocalProblem::new(2, singular, vec![0.0; 2], vec![0.1]).unwrap();
        let mut bad = w.clone();
        bad.col_ptr = vec![0, 2, 1];
        assert!(matches!(
            LocalProblem::new(2, bad, vec![0.0; 2], vec![0.1]),
            Err(ProblemError::Sparse { what: "W", .. })
        ));
        let mut inf = w.clone();
        inf.values[1] = f64::INFINITY;
        assert!(matches!(
            LocalProblem::new(2, inf, vec![0.0; 2], vec![0.1]),
            Err(ProblemError::NonFinite { what: "W", .. })
        ));
        // Global: indefinite M, wrong H shape, wrong mu length.
        let m_indef = CscMatrix::from_dense(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let h = CscMatrix::identity(2, 1.0);
        assert!(matches!(
            GlobalProblem::new(2, m_indef, h.clone(), vec![0.0; 2], vec![0.0; 2], vec![0.1]),
            Err(ProblemError::NotPositiveDefinite(_))
        ));
        let m = CscMatrix::identity(2, 1.0);
        assert!(matches!(
            GlobalProblem::new(
                2,
                m.clone(),
                CscMatrix::identity(3, 1.0),
                vec![0.0; 2],
                vec![0.0; 2],
                vec![0.1]
            ),
            Err(ProblemError::Shape { what: "H", .. })
        ));
        assert!(matches!(
            GlobalProblem::new(
                2,
                m.clone(),
                h.clone(),
                vec![0.0; 2],
                vec![0.0; 2],
                vec![0.1, 0.2]
            ),
            Err(ProblemError::Shape { what: "mu", .. })
        ));
        assert!(matches!(
            GlobalProblem::new(2, m, h, vec![0.0; 2], vec![0.0; 3], vec![0.1]),
            Err(ProblemError::Shape { what: "w", .. })
        ));
    }
}
