//! Equality (bilateral) constraints of a global problem, eliminated before the contact solve.
//!
//! The incremental problem (2.10) with equality rows (FCLIB's `/fclib_global/G`, `b`):
//!
//! ```text
//!     M v = H r + G λ + f,     u = Hᵀ v + w,     Gᵀ v + b = 0,     (uⁱ, rⁱ) ∈ C(eⁱ, μⁱ)   (2.9)
//! ```
//!
//! The equality rows extend (2.10) with constraints that carry no friction and no sign: λ is
//! free. For a given r the first and third lines are a saddle-point system in (v, λ); with
//! X = M⁻¹ G and the Schur complement S = Gᵀ M⁻¹ G (p × p, positive semidefinite),
//!
//! ```text
//!     S λ = −(b + Gᵀ M⁻¹ (H r + f)),     v = M⁻¹ (H r + f + G λ),
//! ```
//!
//! so u = W̃ r + q̃ is again a local problem of the form (4.7), with
//! W̃ = Hᵀ (M⁻¹ − M⁻¹ G S⁺ Gᵀ M⁻¹) H (positive semidefinite: the Delassus operator of the
//! motions the constraints allow) and q̃ = w + Hᵀ M⁻¹ f − Hᵀ M⁻¹ G S⁺ (b + Gᵀ M⁻¹ f).
//! The solver solves that local problem with its default plan, recovers λ and v, and reports
//! the error of `docs/error.md` on the problem as stored.
//!
//! # Redundant constraints
//! S is singular when constraint rows are dependent (a door on two hinges, a closed loop):
//! null(S) = null(G). S is factored by a Cholesky with diagonal pivoting that stops at the
//! first pivot below [`PIVOT_TOLERANCE`] · max diag(S): the k accepted rows K span range(Gᵀ)
//! in the M⁻¹ metric, and Hᵀ M⁻¹ G S⁺ Gᵀ M⁻¹ H = B_Kᵀ S_KK⁻¹ B_K (B = Gᵀ M⁻¹ H) exactly, so
//! the dropped rows change neither W̃ nor v. The multipliers are the minimum-norm solution
//! (two identical rows share their load equally). When b is not in range(Gᵀ) no v satisfies
//! Gᵀ v + b = 0 (inconsistent constraints); the equality residual on the stored problem
//! then stays above tol and the solve ends with [`crate::Status::EqualityResidual`], never
//! "converged".
//!
//! # Cost
//! S and the factor are dense (p × p, at most [`MAX_EQUALITY_ROWS`] rows), and the correction
//! Yᵀ Y of W (Y = L⁻¹ B_K) is dense over the contacts whose bodies the constraints connect:
//! meant for problems of up to a few thousand equality rows, as FCLIB files carry.

use crate::delassus::Delassus;
use crate::linalg::sparse::CscMatrix;
use crate::problem::{GlobalProblem, LocalProblem, ProblemError};

/// Relative pivot threshold of the pivoted Cholesky of S = Gᵀ M⁻¹ G: a row whose remaining
/// pivot is ≤ `PIVOT_TOLERANCE` · max diag(S) is treated as dependent on the accepted ones.
/// The pivots are squared lengths (of M^{-1/2} G's columns orthogonal to the accepted ones),
/// so this drops rows at an angle below about 3e-6 rad from the span of the others; rounding
/// leaves identical rows a pivot of order p · ε · max diag(S), far below it.
pub const PIVOT_TOLERANCE: f64 = 1e-11;

/// Largest number of equality rows p the dense reduction accepts.
pub const MAX_EQUALITY_ROWS: usize = 4096;

/// C = A B for CSC matrices (rows of each column sorted).
fn product(a: &CscMatrix, b: &CscMatrix) -> CscMatrix {
    let mut acc = vec![0.0; a.nrows];
    let mut mark = vec![usize::MAX; a.nrows];
    let mut touched = Vec::new();
    let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
    for j in 0..b.ncols {
        touched.clear();
        for p in b.col_ptr[j]..b.col_ptr[j + 1] {
            let (k, bv) = (b.row_idx[p], b.values[p]);
            for q in a.col_ptr[k]..a.col_ptr[k + 1] {
                let i = a.row_idx[q];
                if mark[i] != j {
                    mark[i] = j;
                    acc[i] = 0.0;
                    touched.push(i);
                }
                acc[i] += a.values[q] * bv;
            }
        }
        touched.sort_unstable();
        for &i in &touched {
            row_idx.push(i);
            values.push(acc[i]);
        }
        col_ptr.push(row_idx.len());
    }
    CscMatrix {
        nrows: a.nrows,
        ncols: b.ncols,
        col_ptr,
        row_idx,
        values,
    }
}

/// The Cholesky factorization with diagonal pivoting of a dense symmetric positive
/// semidefinite p × p matrix: P S Pᵀ ≈ F Fᵀ with F (p × k) lower trapezoidal.
struct PivotedCholesky {
    p: usize,
    /// rank k: the number of accepted pivots
    k: usize,
    /// perm[i]: the row of S in position i
    perm: Vec<usize>,
    /// F, p × k column-major (rows in permuted order)
    f: Vec<f64>,
}

impl PivotedCholesky {
    /// Factors `s` (p × p column-major, symmetric).
    fn new(s: &[f64], p: usize) -> Self {
        let mut perm: Vec<usize> = (0..p).collect();
        let mut d: Vec<f64> = (0..p).map(|i| s[i * p + i]).collect();
        let dmax = d.iter().fold(0.0f64, |m, &x| m.max(x));
        let threshold = PIVOT_TOLERANCE * dmax;
        let mut f = vec![0.0; p * p];
        let mut k = 0;
        while k < p {
            // largest remaining pivot, the first one on ties
            let mut q = k;
            for i in k + 1..p {
                if d[i] > d[q] {
                    q = i;
                }
            }
            if d[q].is_nan() || d[q] <= threshold || dmax <= 0.0 {
                break;
            }
            perm.swap(k, q);
            d.swap(k, q);
            for t in 0..k {
                f.swap(t * p + k, t * p + q);
            }
            let pivot = d[k].sqrt();
            f[k * p + k] = pivot;
            for i in k + 1..p {
                let mut x = s[perm[k] * p + perm[i]];
                for t in 0..k {
                    x -= f[t * p + i] * f[t * p + k];
                }
                let l = x / pivot;
                f[k * p + i] = l;
                d[i] -= l * l;
            }
            k += 1;
        }
        f.truncate(p * k);
        Self { p, k, perm, f }
    }

    /// y ← L⁻¹ y with L = F[0..k, 0..k].
    fn forward(&self, y: &mut [f64]) {
        for j in 0..self.k {
            y[j] /= self.f[j * self.p + j];
            let yj = y[j];
            for (i, yi) in y.iter_mut().enumerate().take(self.k).skip(j + 1) {
                *yi -= self.f[j * self.p + i] * yj;
            }
        }
    }

    /// y ← L⁻ᵀ y.
    fn backward(&self, y: &mut [f64]) {
        for j in (0..self.k).rev() {
            let mut x = y[j];
            for (i, yi) in y.iter().enumerate().take(self.k).skip(j + 1) {
                x -= self.f[j * self.p + i] * yi;
            }
            y[j] = x / self.f[j * self.p + j];
        }
    }
}

/// A global problem's equality constraints eliminated: the reduced local problem (W̃, q̃, μ)
/// of the module documentation and what recovers (v, λ) from any r.
pub struct Reduction {
    /// the Delassus form of (M, H, f, w) without the constraints, and the factor of M
    delassus: Delassus,
    /// the pivoted Cholesky of S = Gᵀ M⁻¹ G
    chol: PivotedCholesky,
    /// Y = L⁻¹ B_K (k × m), B = Gᵀ M⁻¹ H
    y: CscMatrix,
    /// L⁻¹ (b + Gᵀ M⁻¹ f)_K
    z0: Vec<f64>,
    /// the null-space basis of S in permuted order, Z = [Z_K; I] with Z_K = −L⁻ᵀ L₂₁ᵀ
    /// (k × (p − k), column-major), and the Cholesky factor of Zᵀ Z ((p − k)², lower)
    z_k: Vec<f64>,
    ztz: Vec<f64>,
    /// the reduced local problem (W̃, q̃, μ)
    pub local: LocalProblem,
}

impl Reduction {
    /// Factors M and S and forms the reduced problem of `problem` (which has equality
    /// constraints; without them the reduction is the plain Delassus form).
    pub fn new(problem: &GlobalProblem) -> Result<Self, ProblemError> {
        let p = problem.equality_rows();
        if p > MAX_EQUALITY_ROWS {
            return Err(ProblemError::Shape {
                what: "G",
                expected: format!(
                    "at most {MAX_EQUALITY_ROWS} columns (equality rows are eliminated through a dense p × p Schur complement Gᵀ M⁻¹ G)"
                ),
                found: format!("{p} columns"),
            });
        }
        let delassus = Delassus::new(problem)?;
        let empty = CscMatrix::zeros(problem.m.nrows, 0);
        let g = problem.equality.as_ref().map_or(&empty, |e| &e.g);
        // X = M⁻¹ G, column by column on the blocks of M each column touches
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        let (mut rhs, mut out) = (Vec::new(), Vec::new());
        for j in 0..p {
            rhs.clear();
            rhs.extend((g.col_ptr[j]..g.col_ptr[j + 1]).map(|t| (g.row_idx[t], g.values[t])));
            delassus.factor.solve_sparse(&rhs, &mut out);
            for &(i, x) in &out {
                rows.push(i);
                cols.push(j);
                vals.push(x);
            }
        }
        let x = CscMatrix::from_triplets(problem.m.nrows, p, &rows, &cols, &vals)
            .expect("indices of M⁻¹ G are in range");
        let xt = x.transpose();
        // S = Gᵀ X, dense and symmetrized (M, and so S, may carry rounding asymmetry)
        let s_sparse = product(&g.transpose(), &x);
        let mut s = vec![0.0; p * p];
        for (i, j, v) in s_sparse.triplets() {
            s[j * p + i] += 0.5 * v;
            s[i * p + j] += 0.5 * v;
        }
        let chol = PivotedCholesky::new(&s, p);
        let k = chol.k;
        // Y = L⁻¹ B_K, B = Xᵀ H (p × m)
        let b_full = product(&xt, &problem.h);
        let m = problem.h.ncols;
        let mut position = vec![usize::MAX; p];
        for (i, &row) in chol.perm[..k].iter().enumerate() {
            position[row] = i;
        }
        let mut col = vec![0.0; k];
        let (mut y_ptr, mut y_idx, mut y_val) = (vec![0], Vec::new(), Vec::new());
        for j in 0..m {
            col.iter_mut().for_each(|c| *c = 0.0);
            let mut any = false;
            for t in b_full.col_ptr[j]..b_full.col_ptr[j + 1] {
                let i = position[b_full.row_idx[t]];
                if i != usize::MAX {
                    col[i] = b_full.values[t];
                    any = true;
                }
            }
            if any {
                chol.forward(&mut col);
                for (i, &c) in col.iter().enumerate() {
                    if c != 0.0 {
                        y_idx.push(i);
                        y_val.push(c);
                    }
                }
            }
            y_ptr.push(y_idx.len());
        }
        let y = CscMatrix {
            nrows: k,
            ncols: m,
            col_ptr: y_ptr,
            row_idx: y_idx,
            values: y_val,
        };
        // W̃ = W − Yᵀ Y (exactly symmetric when W is: each entry sums the same products in
        // the same order as its transpose)
        let correction = product(&y.transpose(), &y);
        let w = delassus.local.w.add_scaled(-1.0, &correction);
        // null-space basis of S and the Cholesky factor of Zᵀ Z (for minimum-norm λ)
        let nd = p - k;
        let mut z_k = vec![0.0; k * nd];
        for t in 0..nd {
            let zc = &mut z_k[t * k..(t + 1) * k];
            for (i, z) in zc.iter_mut().enumerate() {
                *z = chol.f[i * p + k + t];
            }
            chol.backward(zc);
            zc.iter_mut().for_each(|z| *z = -*z);
        }
        let mut ztz = vec![0.0; nd * nd];
        for a in 0..nd {
            for c in 0..=a {
                let dot: f64 = (0..k).map(|i| z_k[a * k + i] * z_k[c * k + i]).sum();
                ztz[c * nd + a] = dot + if a == c { 1.0 } else { 0.0 };
            }
        }
        dense_cholesky_lower(&mut ztz, nd);
        let mut red = Self {
            delassus,
            chol,
            y,
            z0: Vec::new(),
            z_k,
            ztz,
            local: LocalProblem {
                dim: problem.dim,
                w,
                q: Vec::new(),
                mu: problem.mu.clone(),
            },
        };
        red.update_rhs(problem);
        Ok(red)
    }

    /// Recomputes q̃ for new f, w (and b) of `problem` (same M, H, G).
    pub fn update_rhs(&mut self, problem: &GlobalProblem) {
        self.delassus.update_rhs(problem);
        let k = self.chol.k;
        // c0 = b + Gᵀ M⁻¹ f, restricted to the accepted rows
        let mut z0 = vec![0.0; k];
        if let Some(e) = &problem.equality {
            let mut c0 = e.b.clone();
            e.g.gemv_t_acc(1.0, &self.delassus.free_velocity, &mut c0);
            for (i, z) in z0.iter_mut().enumerate() {
                *z = c0[self.chol.perm[i]];
            }
        }
        self.chol.forward(&mut z0);
        let mut q = self.delassus.local.q.clone();
        self.y.gemv_t_acc(-1.0, &z0, &mut q);
        self.local.q = q;
        self.z0 = z0;
    }

    /// Number of equality rows kept after the pivoted Cholesky of S (the rank of G).
    pub fn rank(&self) -> usize {
        self.chol.k
    }

    /// The multipliers λ (minimum norm) and the velocities v = M⁻¹ (H r + f + G λ) of
    /// impulses r.
    pub fn recover(&self, problem: &GlobalProblem, r: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (p, k) = (self.chol.p, self.chol.k);
        let nd = p - k;
        // λ_K = −L⁻ᵀ (Y r + z0)
        let mut lk = self.z0.clone();
        self.y.gemv_acc(1.0, r, &mut lk);
        self.chol.backward(&mut lk);
        lk.iter_mut().for_each(|x| *x = -*x);
        // minimum norm: λ − Z (Zᵀ Z)⁻¹ Zᵀ λ with λ = (λ_K, 0) in permuted order
        let mut a: Vec<f64> = (0..nd)
            .map(|t| (0..k).map(|i| self.z_k[t * k + i] * lk[i]).sum())
            .collect();
        dense_cholesky_solve(&self.ztz, nd, &mut a);
        let mut lperm = lk;
        lperm.resize(p, 0.0);
        for (t, &at) in a.iter().enumerate() {
            for (i, li) in lperm.iter_mut().enumerate().take(k) {
                *li -= self.z_k[t * k + i] * at;
            }
            lperm[k + t] -= at;
        }
        let mut l = vec![0.0; p];
        for (i, &x) in lperm.iter().enumerate() {
            l[self.chol.perm[i]] = x;
        }
        // v = M⁻¹ (H r + f + G λ)
        let mut v = problem.h.mul_vec(r);
        for (a, b) in v.iter_mut().zip(&problem.f) {
            *a += b;
        }
        if let Some(e) = &problem.equality {
            e.g.gemv_acc(1.0, &l, &mut v);
        }
        self.delassus.factor.solve_in_place(&mut v);
        (v, l)
    }
}

/// In-place Cholesky of a dense SPD n × n matrix (column-major, lower triangle read and
/// written). Zᵀ Z = I + Z_Kᵀ Z_K has eigenvalues ≥ 1, so no pivot can vanish.
fn dense_cholesky_lower(a: &mut [f64], n: usize) {
    for j in 0..n {
        let mut d = a[j * n + j];
        for t in 0..j {
            d -= a[t * n + j] * a[t * n + j];
        }
        let d = d.max(f64::MIN_POSITIVE).sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut x = a[j * n + i];
            for t in 0..j {
                x -= a[t * n + i] * a[t * n + j];
            }
            a[j * n + i] = x / d;
        }
    }
}

/// x ← (L Lᵀ)⁻¹ x with L from [`dense_cholesky_lower`].
fn dense_cholesky_solve(l: &[f64], n: usize, x: &mut [f64]) {
    for j in 0..n {
        x[j] /= l[j * n + j];
        let xj = x[j];
        for i in j + 1..n {
            x[i] -= l[j * n + i] * xj;
        }
    }
    for j in (0..n).rev() {
        let mut s = x[j];
        for i in j + 1..n {
            s -= l[j * n + i] * x[i];
        }
        x[j] = s / l[j * n + j];
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests;
