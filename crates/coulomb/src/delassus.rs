//! The Delassus form of a global problem: W = Hᵀ M⁻¹ H and q = Hᵀ M⁻¹ f + w, which turns
//! the primal inner problem (3.15) into its dual (4.7), and the matrix-free operator x ↦ W x.
//!
//! M is factored by Cholesky block by block: the dofs are split into the connected components
//! of M's sparsity graph (one per rigid body for a multibody system, one for a finite-element
//! mesh), so a block-diagonal M costs a few small dense factorizations and M⁻¹ H keeps the
//! sparsity of H. Large blocks use faer's sparse supernodal Cholesky; M⁻¹ is never formed.

use crate::linalg::sparse::CscMatrix;
/// The factorization of M has its own module; re-exported here, where callers have always
/// found it.
pub use crate::mass::{MassError, MassFactor};
use crate::problem::{GlobalProblem, LocalProblem, ProblemError};

/// The Delassus operator x ↦ W x = Hᵀ M⁻¹ H x, without forming W.
pub struct DelassusOperator<'a> {
    h: &'a CscMatrix,
    factor: &'a MassFactor,
}

impl<'a> DelassusOperator<'a> {
    /// Wraps H and a factorization of M.
    pub fn new(h: &'a CscMatrix, factor: &'a MassFactor) -> Self {
        Self { h, factor }
    }

    /// y ← W x.
    pub fn apply(&self, x: &[f64], y: &mut [f64]) {
        let mut z = self.h.mul_vec(x);
        self.factor.solve_in_place(&mut z);
        y.iter_mut().for_each(|v| *v = 0.0);
        self.h.gemv_t_acc(1.0, &z, y);
    }
}

/// A global problem together with its Delassus form and the factorization of M that links
/// them: v = M⁻¹ (H r + f) recovers the velocities from any r.
pub struct Delassus {
    /// the local problem (W, q, μ)
    pub local: LocalProblem,
    /// Cholesky factorization of M
    pub factor: MassFactor,
    /// M⁻¹ f (the velocity when r = 0)
    pub free_velocity: Vec<f64>,
}

impl Delassus {
    /// Factors M and forms W = Hᵀ M⁻¹ H, q = Hᵀ M⁻¹ f + w.
    pub fn new(problem: &GlobalProblem) -> Result<Self, ProblemError> {
        let factor = MassFactor::new(&problem.m)?;
        let w = assemble_w(&problem.h, &factor);
        let mut free_velocity = problem.f.clone();
        factor.solve_in_place(&mut free_velocity);
        let mut q = problem.w.clone();
        problem.h.gemv_t_acc(1.0, &free_velocity, &mut q);
        // W is symmetric up to rounding when M is; store it exactly symmetric then. When M
        // itself is not exactly symmetric, W = Hᵀ M⁻¹ H is kept as computed so that the local
        // form stays equivalent to the global one.
        let mut w = w;
        if factor.exactly_symmetric() && !symmetrize_in_place(&mut w) {
            w = symmetrize(&w);
        }
        let local = LocalProblem {
            dim: problem.dim,
            w,
            q,
            mu: problem.mu.clone(),
        };
        Ok(Self {
            local,
            factor,
            free_velocity,
        })
    }

    /// Recomputes M⁻¹ f and q = Hᵀ M⁻¹ f + w for new f and w of `problem` (same M and H:
    /// the factorization and W are kept), as a time step needs.
    pub fn update_rhs(&mut self, problem: &GlobalProblem) {
        self.free_velocity.clone_from(&problem.f);
        self.factor.solve_in_place(&mut self.free_velocity);
        self.local.q.clone_from(&problem.w);
        problem
            .h
            .gemv_t_acc(1.0, &self.free_velocity, &mut self.local.q);
    }

    /// v = M⁻¹ (H r + f).
    pub fn velocity(&self, h: &CscMatrix, r: &[f64]) -> Vec<f64> {
        let mut v = h.mul_vec(r);
        self.factor.solve_in_place(&mut v);
        for (a, b) in v.iter_mut().zip(&self.free_velocity) {
            *a += b;
        }
        v
    }
}

/// ½ (W + Wᵀ).
fn symmetrize(w: &CscMatrix) -> CscMatrix {
    let t = w.transpose();
    let mut s = w.add_scaled(1.0, &t);
    s.values.iter_mut().for_each(|v| *v *= 0.5);
    s
}

/// W ← ½ (W + Wᵀ) in place, for a structurally symmetric W (sorted rows): each pair of
/// entries (i, j), (j, i) gets (W_ij + W_ji)/2. Returns false, leaving W unchanged, when the
/// pattern is not symmetric.
fn symmetrize_in_place(w: &mut CscMatrix) -> bool {
    let m = w.ncols;
    // partner[p]: position of the transposed entry of entry p
    let mut partner = vec![usize::MAX; w.nnz()];
    // next[i]: the next entry of column i below the diagonal not yet paired; rows below the
    // diagonal of column i are met in increasing order as the columns j > i are visited
    let mut next: Vec<usize> = (0..m)
        .map(|i| {
            let col = &w.row_idx[w.col_ptr[i]..w.col_ptr[i + 1]];
            w.col_ptr[i] + col.partition_point(|&r| r <= i)
        })
        .collect();
    for j in 0..m {
        for p in w.col_ptr[j]..w.col_ptr[j + 1] {
            let i = w.row_idx[p];
            if i >= j {
                break;
            }
            let q = next[i];
            if q >= w.col_ptr[i + 1] || w.row_idx[q] != j {
                return false;
            }
            partner[p] = q;
            partner[q] = p;
            next[i] += 1;
        }
    }
    // every entry below the diagonal must have been paired
    if (0..m).any(|i| next[i] != w.col_ptr[i + 1]) {
        return false;
    }
    for (p, &q) in partner.iter().enumerate() {
        if q != usize::MAX && q > p {
            let mean = (w.values[p] + w.values[q]) * 0.5;
            w.values[p] = mean;
            w.values[q] = mean;
        }
    }
    true
}

/// W = Hᵀ M⁻¹ H, column by column: X_j = M⁻¹ H_j on the blocks that H_j touches, then
/// W_j = Hᵀ X_j through the rows of H.
fn assemble_w(h: &CscMatrix, factor: &MassFactor) -> CscMatrix {
    let m = h.ncols;
    let ht = h.transpose(); // column k of Hᵀ = row k of H
    let mut acc = vec![0.0; m];
    let mut mark = vec![usize::MAX; m];
    let mut touched = Vec::new();
    let mut rhs = Vec::new();
    let mut x = Vec::new();
    let mut col_ptr = vec![0];
    let mut row_idx = Vec::new();
    let mut values = Vec::new();
    for j in 0..m {
        rhs.clear();
        rhs.extend((h.col_ptr[j]..h.col_ptr[j + 1]).map(|p| (h.row_idx[p], h.values[p])));
        factor.solve_sparse(&rhs, &mut x);
        touched.clear();
        for &(k, xv) in &x {
            if xv == 0.0 {
                continue;
            }
            for p in ht.col_ptr[k]..ht.col_ptr[k + 1] {
                let i = ht.row_idx[p];
                if mark[i] != j {
                    mark[i] = j;
                    acc[i] = 0.0;
                    touched.push(i);
                }
                acc[i] += ht.values[p] * xv;
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
        nrows: m,
        ncols: m,
        col_ptr,
        row_idx,
        values,
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    /// Dense reference: solve M X = H by Gaussian elimination, W = Hᵀ X.
    fn dense_reference(m: &[f64], h: &[f64], n: usize, k: usize) -> Vec<f64> {
        let mut a = m.to_vec();
        let mut x = h.to_vec(); // n × k row-major
        for c in 0..n {
            let piv = a[c * n + c];
            for r in c + 1..n {
                let f = a[r * n + c] / piv;
                for cc in 0..n {
                    a[r * n + cc] -= f * a[c * n + cc];
                }
                for cc in 0..k {
                    x[r * k + cc] -= f * x[c * k + cc];
                }
            }
        }
        for c in (0..n).rev() {
            for cc in 0..k {
                let mut s = x[c * k + cc];
                for r in c + 1..n {
                    s -= a[c * n + r] * x[r * k + cc];
                }
                x[c * k + cc] = s / a[c * n + c];
            }
        }
        let mut w = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                w[i * k + j] = (0..n).map(|p| h[p * k + i] * x[p * k + j]).sum();
            }
        }
        w
    }

    fn check_against_dense(n: usize, mdense: &[f64], hdense: &[f64], k: usize) {
        let m = CscMatrix::from_dense(n, n, mdense);
        let h = CscMatrix::from_dense(n, k, hdense);
        let f: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let wv: Vec<f64> = (0..k).map(|i| (i as f64 * 0.11).cos()).collect();
        let mu = vec![0.3; k / 3];
        let g = GlobalProblem::new(3, m, h.clone(), f.clone(), wv.clone(), mu).unwrap();
        let d = Delassus::new(&g).unwrap();
        let wref = dense_reference(mdense, hdense, n, k);
        assert!(d.local.w.check().is_ok(), "W is a valid CSC matrix");
        let m_symmetric = (0..n).all(|i| (0..n).all(|j| mdense[i * n + j] == mdense[j * n + i]));
        if m_symmetric {
            assert_eq!(d.local.w.asymmetry(), 0.0, "W is exactly symmetric");
        }
        let wd = d.local.w.to_dense();
        for (a, b) in wd.iter().zip(&wref) {
            assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "{a} vs {b}");
        }
        // q = Hᵀ M⁻¹ f + w: with f as a single extra column.
        let fref = dense_reference(mdense, &f, n, 1);
        let _ = fref; // (scalar fᵀM⁻¹f, not needed)
        let mut minvf = f.clone();
        d.factor.solve_in_place(&mut minvf);
        let mv = g.m.mul_vec(&minvf);
        for (a, b) in mv.iter().zip(&f) {
            assert!((a - b).abs() < 1e-10);
        }
        let mut qref = wv.clone();
        h.gemv_t_acc(1.0, &minvf, &mut qref);
        for (a, b) in d.local.q.iter().zip(&qref) {
            assert!((a - b).abs() < 1e-12);
        }
        // matrix-free operator
        let x: Vec<f64> = (0..k).map(|i| (i as f64).sqrt()).collect();
        let mut y = vec![0.0; k];
        DelassusOperator::new(&g.h, &d.factor).apply(&x, &mut y);
        let yref = d.local.w.mul_vec(&x);
        for (a, b) in y.iter().zip(&yref) {
            assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()));
        }
        // A global problem and its local form give the same error for the same (v, r).
        let r: Vec<f64> = (0..k).map(|i| 0.1 + (i as f64 * 0.7).sin().abs()).collect();
        let v = d.velocity(&g.h, &r);
        assert!(g.balance_residual(&v, &r) < 1e-12);
        let u_global = g.velocity(&v);
        let e_global =
            crate::law::error_measure(3, &g.mu, &r, &u_global, crate::law::norm(&d.local.q));
        let e_local = d.local.error(&r);
        assert!((e_global.error - e_local.error).abs() < 1e-12);
    }

    pub fn block_diagonal_mass_matches_dense() {
        // three 2×2 SPD blocks, 6 dofs, 2 contacts in 3-D
        let n = 6;
        let mut m = vec![0.0; n * n];
        for b in 0..3 {
            let i = 2 * b;
            m[i * n + i] = 2.0 + b as f64;
            m[(i + 1) * n + i + 1] = 1.5;
            m[i * n + i + 1] = 0.4;
            m[(i + 1) * n + i] = 0.4;
        }
        let k = 6;
        let h: Vec<f64> = (0..n * k)
            .map(|t| {
                if t % 4 == 0 {
                    0.0
                } else {
                    ((t * 7 % 11) as f64 - 5.0) / 5.0
                }
            })
            .collect();
        check_against_dense(n, &m, &h, k);
    }

    pub fn large_coupled_mass_matches_dense() {
        // one 60-dof tridiagonal block (sparse Cholesky path)
        let n = 60;
        let mut m = vec![0.0; n * n];
        for i in 0..n {
            m[i * n + i] = 4.0;
            if i + 1 < n {
                m[i * n + i + 1] = -1.0;
                m[(i + 1) * n + i] = -1.0;
            }
        }
        let k = 9;
        let h: Vec<f64> = (0..n * k)
            .map(|t| ((t * 13 % 17) as f64 - 8.0) / 8.0)
            .collect();
        check_against_dense(n, &m, &h, k);
    }

    pub fn slightly_asymmetric_ill_conditioned_mass_is_solved_exactly() {
        // cond ≈ 1e7 with a 1e-7 relative asymmetry, in a dense and a sparse block
        for n in [20usize, 80] {
            let mut m = vec![0.0; n * n];
            for i in 0..n {
                m[i * n + i] = 10f64.powf(7.0 * i as f64 / (n - 1) as f64);
                if i + 1 < n {
                    let c = 0.3 * m[i * n + i].min(1.0);
                    m[i * n + i + 1] = c * (1.0 + 1e-7);
                    m[(i + 1) * n + i] = c;
                }
            }
            let a = CscMatrix::from_dense(n, n, &m);
            let f = MassFactor::new(&a).unwrap();
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
            let mut x = b.clone();
            f.solve_in_place(&mut x);
            let ax = a.mul_vec(&x);
            let res: f64 = ax
                .iter()
                .zip(&b)
                .map(|(p, q)| (p - q).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(res < 1e-10, "n = {n}: residual {res}");
        }
    }

    pub fn symmetrize_in_place_equals_the_half_sum() {
        let n = 7;
        let mut dense = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                if (i * 3 + j * 3) % 4 != 1 {
                    dense[i * n + j] = ((i * 7 + j * 13) % 17) as f64 - 8.0 + 0.1 * i as f64;
                }
            }
        }
        let w = CscMatrix::from_dense(n, n, &dense);
        let mut v = w.clone();
        assert!(symmetrize_in_place(&mut v));
        assert_eq!(v, symmetrize(&w));
        // a pattern that is not symmetric is left alone
        dense[1] = 0.0;
        dense[n] = 5.0;
        let w = CscMatrix::from_dense(n, n, &dense);
        let mut v = w.clone();
        assert!(!symmetrize_in_place(&mut v));
        assert_eq!(v, w);
    }
}
