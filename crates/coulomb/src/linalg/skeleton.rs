//! A skeleton (low-rank) form of a rank-deficient Delassus matrix, for the Newton systems of
//! the interior-point method on Coulomb's law ([`crate::barrier`]) on local problems.
//!
//! For rigid bodies touching at several points per face, W = H M⁻¹ Hᵀ (4.7) has rank k at most
//! the number of degrees of freedom, often a fraction of the m contact unknowns, but a local
//! problem stores W alone (no H, no M). With P the k pivots of a Cholesky factorization of the
//! symmetric part ½(W + Wᵀ) with diagonal pivoting (stopped when the largest remaining
//! diagonal entry is ≤ `rank_tol` · max Wᵢᵢ), the skeleton
//!
//! ```text
//!     W ≈ C A⁻¹ R,     C = W[:, P],  A = W[P, P],  R = W[P, :],
//! ```
//!
//! is exact when rank W = k (A is then regular). A system (G + W) x = b with G block-diagonal
//! and regular is solved by the Sherman–Morrison–Woodbury identity
//!
//! ```text
//!     x = G⁻¹ b − G⁻¹ C (A + R G⁻¹ C)⁻¹ R G⁻¹ b,
//! ```
//!
//! a dense LU of size k (the analogue of the Schur complement M + H G⁻¹ Hᵀ of a global
//! problem), C and R being as sparse as the columns and rows of W. Where W is only close to
//! the skeleton (the antisymmetric part of a non-symmetric W, rounding), the caller refines x
//! on the stored W ([`crate::barrier`]). Written here because no crate of the stack offers a
//! pivoted partial Cholesky of a sparse matrix that stops at its numerical rank.

use crate::deadline::Deadline;
use crate::linalg::sparse::CscMatrix;

/// The skeleton C A⁻¹ R of W on the pivots P (module docs).
pub struct Skeleton {
    dim: usize,
    /// W[P, P] (k × k)
    a: faer::Mat<f64>,
    /// R = W[P, :] by columns: for column j of W, its entries in the rows of P as (index in
    /// P, value), at `r_idx[r_ptr[j]..r_ptr[j + 1]]`
    r_ptr: Vec<usize>,
    r_idx: Vec<usize>,
    r_val: Vec<f64>,
    /// C = W[:, P] by rows: for row l of W, its entries in the columns of P
    c_ptr: Vec<usize>,
    c_idx: Vec<usize>,
    c_val: Vec<f64>,
}

/// The factored form of (G + C A⁻¹ R) for one block-diagonal G ([`Skeleton::factor`]).
pub struct SkeletonLu {
    /// the rank of the skeleton it was factored for
    rank: usize,
    /// G⁻¹ by blocks (row-major d × d)
    ginv: Vec<f64>,
    lu: crate::linalg::dense::Lu,
}

impl Skeleton {
    /// The skeleton of the m × m matrix `w` (contacts of dimension `dim`), or None when its
    /// symmetric part has more than `max_rank` pivots above `rank_tol` · max Wᵢᵢ (not
    /// rank-deficient enough), is not positive on its diagonal, has a non-finite entry, or the
    /// deadline passes during the pivoting (cost ≤ m · max_rank² flops).
    pub fn new(
        w: &CscMatrix,
        dim: usize,
        max_rank: usize,
        rank_tol: f64,
        deadline: Deadline,
    ) -> Option<Self> {
        let m = w.nrows;
        if m == 0 || w.ncols != m || dim == 0 || m % dim != 0 || w.first_non_finite().is_some() {
            return None;
        }
        let wt = w.transpose();
        let mut residual = w.diagonal();
        let dmax = residual.iter().fold(0.0f64, |x, &y| x.max(y));
        if !(dmax > 0.0 && dmax.is_finite()) {
            return None;
        }
        // columns of L (column-major, m per pivot), pivots in order
        let mut l: Vec<f64> = Vec::new();
        let mut pivots: Vec<usize> = Vec::new();
        let mut col = vec![0.0; m];
        let mut taken = vec![false; m];
        loop {
            let mut piv = usize::MAX;
            let mut best = rank_tol * dmax;
            for (i, &v) in residual.iter().enumerate() {
                if !taken[i] && v > best {
                    (piv, best) = (i, v);
                }
            }
            if piv == usize::MAX {
                break;
            }
            if pivots.len() >= max_rank || deadline.passed() {
                return None;
            }
            // column piv of ½(W + Wᵀ) minus L Lᵀ
            col.fill(0.0);
            for (src, half) in [(w, 0.5), (&wt, 0.5)] {
                for t in src.col_ptr[piv]..src.col_ptr[piv + 1] {
                    col[src.row_idx[t]] += half * src.values[t];
                }
            }
            for lt in l.chunks(m) {
                let f = lt[piv];
                if f != 0.0 {
                    for (c, &x) in col.iter_mut().zip(lt) {
                        *c -= f * x;
                    }
                }
            }
            let pivot = col[piv];
            if pivot.is_nan() || pivot <= rank_tol * dmax {
                // rounding: the remaining diagonal was overestimated; skip this index
                taken[piv] = true;
                continue;
            }
            let scale = 1.0 / pivot.sqrt();
            for (i, c) in col.iter_mut().enumerate() {
                *c *= scale;
                residual[i] -= *c * *c;
            }
            taken[piv] = true;
            l.extend_from_slice(&col);
            pivots.push(piv);
        }
        Some(Self::on_pivots(w, &wt, dim, &pivots))
    }

    /// C, A, R of `w` on the given pivots (`wt` = wᵀ).
    fn on_pivots(w: &CscMatrix, wt: &CscMatrix, dim: usize, pivots: &[usize]) -> Self {
        let m = w.nrows;
        let k = pivots.len();
        let mut pos = vec![usize::MAX; m];
        for (a, &p) in pivots.iter().enumerate() {
            pos[p] = a;
        }
        // entries of the columns of `src` in the rows of P
        let gather = |src: &CscMatrix| {
            let (mut ptr, mut idx, mut val) = (vec![0], Vec::new(), Vec::new());
            for j in 0..m {
                for t in src.col_ptr[j]..src.col_ptr[j + 1] {
                    let a = pos[src.row_idx[t]];
                    if a != usize::MAX {
                        idx.push(a);
                        val.push(src.values[t]);
                    }
                }
                ptr.push(idx.len());
            }
            (ptr, idx, val)
        };
        let (r_ptr, r_idx, r_val) = gather(w);
        let (c_ptr, c_idx, c_val) = gather(wt);
        let mut a = faer::Mat::<f64>::zeros(k, k);
        for (b, &p) in pivots.iter().enumerate() {
            for t in r_ptr[p]..r_ptr[p + 1] {
                a[(r_idx[t], b)] += r_val[t];
            }
        }
        Self {
            dim,
            a,
            r_ptr,
            r_idx,
            r_val,
            c_ptr,
            c_idx,
            c_val,
        }
    }

    /// k, the number of pivots.
    pub fn rank(&self) -> usize {
        self.a.nrows()
    }

    /// m, the size of W.
    pub fn unknowns(&self) -> usize {
        self.r_ptr.len() - 1
    }

    /// How far W is from its skeleton: max over two fixed probe vectors x of
    /// ‖W x − C A⁻¹ R x‖∞ / ‖W x‖∞ (0 when W = C A⁻¹ R, which holds when rank W = k and A
    /// is regular, symmetric or not). None when A is singular to working precision or `w` is
    /// not the matrix of the skeleton. Cost: one dense LU of A (k³ · ⅔ flops, on all threads
    /// when k ≥ `parallel_dim`, [`crate::linalg::dense::parallelism`]) and four products.
    pub fn residual(&self, w: &CscMatrix, parallel_dim: usize) -> Option<f64> {
        let (m, k) = (self.unknowns(), self.rank());
        if w.nrows != m || w.ncols != m {
            return None;
        }
        let par = crate::linalg::dense::parallelism(k, parallel_dim);
        let lu = crate::linalg::dense::Lu::new(self.a.clone(), par)?;
        let mut worst = 0.0f64;
        for probe in 0..2 {
            // an irregular probe: no structure of W's rows can cancel it
            let x: Vec<f64> = (0..m)
                .map(|j| ((j * (2 * probe + 3) + probe) as f64 * 0.618_033_988_75).sin() + 0.1)
                .collect();
            let wx = w.mul_vec(&x);
            let mut y = vec![0.0; k];
            for (j, &xj) in x.iter().enumerate() {
                for t in self.r_ptr[j]..self.r_ptr[j + 1] {
                    y[self.r_idx[t]] += self.r_val[t] * xj;
                }
            }
            lu.solve_in_place(&mut y);
            let (mut diff, mut scale) = (0.0f64, 0.0f64);
            for (l, &wxl) in wx.iter().enumerate() {
                let cy: f64 = (self.c_ptr[l]..self.c_ptr[l + 1])
                    .map(|t| self.c_val[t] * y[self.c_idx[t]])
                    .sum();
                diff = diff.max((wxl - cy).abs());
                scale = scale.max(wxl.abs());
            }
            let rel = diff / scale;
            if !rel.is_finite() {
                return None;
            }
            worst = worst.max(rel);
        }
        Some(worst)
    }

    /// W ≈ C A⁻¹ R as the velocity form of a global problem with k degrees of freedom:
    /// M v = R r (M = A, H = R, k × m) and u = (Cᵀ)ᵀ v + q, so that u = W r + q on the
    /// skeleton, also for a W that is not symmetric. Returns (A, ½(A + Aᵀ), R, Cᵀ).
    pub fn velocity_form(&self) -> (CscMatrix, CscMatrix, CscMatrix, CscMatrix) {
        let k = self.rank();
        let mut a = vec![0.0; k * k];
        let mut a_sym = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                a[i * k + j] = self.a[(i, j)];
                a_sym[i * k + j] = 0.5 * (self.a[(i, j)] + self.a[(j, i)]);
            }
        }
        let m = self.unknowns();
        // R by columns and C by rows (= Cᵀ by columns); their indices (positions in P) need
        // not be sorted: compress them
        let compress = |ptr: &[usize], idx: &[usize], val: &[f64]| {
            CscMatrix::from_csc_arrays(k, m, ptr, idx, val)
                .unwrap_or_else(|_| CscMatrix::zeros(k, m))
        };
        (
            CscMatrix::from_dense(k, k, &a),
            CscMatrix::from_dense(k, k, &a_sym),
            compress(&self.r_ptr, &self.r_idx, &self.r_val),
            compress(&self.c_ptr, &self.c_idx, &self.c_val),
        )
    }

    /// The factored G + C A⁻¹ R for the block-diagonal regular G given by the row-major
    /// d × d blocks of G⁻¹; None if A + R G⁻¹ C has a non-finite entry. Its dense LU runs
    /// on all threads when the rank is ≥ `parallel_dim`, else on one ([`crate::linalg::dense`]).
    pub fn factor(&self, ginv: &[f64], parallel_dim: usize) -> Option<SkeletonLu> {
        let d = self.dim;
        if ginv.len() != self.unknowns() * d {
            return None;
        }
        let ginv = ginv.to_vec();
        let mut k = self.a.clone();
        // R G⁻¹ C, contact by contact
        for (i, inv) in ginv.chunks(d * d).enumerate() {
            for c1 in 0..d {
                let j = i * d + c1;
                for c2 in 0..d {
                    let gv = inv[c1 * d + c2];
                    if gv == 0.0 {
                        continue;
                    }
                    let l = i * d + c2;
                    for t in self.r_ptr[j]..self.r_ptr[j + 1] {
                        let ra = self.r_val[t] * gv;
                        let a = self.r_idx[t];
                        for s in self.c_ptr[l]..self.c_ptr[l + 1] {
                            k[(a, self.c_idx[s])] += ra * self.c_val[s];
                        }
                    }
                }
            }
        }
        if (0..k.ncols()).any(|j| k.col(j).iter().any(|v| !v.is_finite())) {
            return None;
        }
        let rank = self.rank();
        Some(SkeletonLu {
            rank,
            ginv,
            lu: crate::linalg::dense::Lu::new(
                k,
                crate::linalg::dense::parallelism(rank, parallel_dim),
            )?,
        })
    }
}

impl Skeleton {
    /// x = (G + C A⁻¹ R)⁻¹ rhs in place, with G as factored in `f`; None if x is not finite
    /// or the sizes disagree.
    pub fn solve(&self, f: &SkeletonLu, rhs: &mut [f64]) -> Option<()> {
        let s = self;
        let d = s.dim;
        let k = s.rank();
        if rhs.len() != s.unknowns() || f.ginv.len() != rhs.len() * d || f.rank != k {
            return None;
        }
        let mut z = vec![0.0; rhs.len()];
        crate::linalg::blocks::apply_blocks(d, &f.ginv, rhs, &mut z);
        let mut y = vec![0.0; k];
        for (j, &zj) in z.iter().enumerate() {
            for u in s.r_ptr[j]..s.r_ptr[j + 1] {
                y[s.r_idx[u]] += s.r_val[u] * zj;
            }
        }
        if !f.lu.solve_in_place(&mut y) {
            return None;
        }
        let cy: Vec<f64> = (0..rhs.len())
            .map(|l| {
                (s.c_ptr[l]..s.c_ptr[l + 1])
                    .map(|u| s.c_val[u] * y[s.c_idx[u]])
                    .sum()
            })
            .collect();
        apply_blocks_sub(d, &f.ginv, &cy, &z, rhs);
        rhs.iter().all(|x| x.is_finite()).then_some(())
    }
}

/// out = z − blockdiag(blocks) x.
fn apply_blocks_sub(d: usize, blocks: &[f64], x: &[f64], z: &[f64], out: &mut [f64]) {
    let mut tmp = vec![0.0; x.len()];
    crate::linalg::blocks::apply_blocks(d, blocks, x, &mut tmp);
    for ((o, zi), ti) in out.iter_mut().zip(z).zip(&tmp) {
        *o = zi - ti;
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use crate::test_problems::uniform;

    /// W = Bᵀ B + δ K (B: k × m, K antisymmetric on the pattern): rank k symmetric part.
    fn low_rank(m: usize, k: usize, asym: f64, seed: u64) -> CscMatrix {
        let mut next = uniform(seed, 11);
        let b: Vec<f64> = (0..k * m).map(|_| next()).collect();
        let mut dense = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                dense[i * m + j] = (0..k).map(|t| b[t * m + i] * b[t * m + j]).sum();
            }
        }
        for i in 0..m {
            for j in 0..i {
                let x = asym * next();
                dense[i * m + j] += x;
                dense[j * m + i] -= x;
            }
        }
        CscMatrix::from_dense(m, m, &dense)
    }

    fn block_diag(m: usize, d: usize, seed: u64) -> Vec<f64> {
        let mut next = uniform(seed, 13);
        let mut g = vec![0.0; m * d];
        for blk in g.chunks_mut(d * d) {
            for a in 0..d {
                for b in 0..d {
                    blk[a * d + b] = 0.05 * next();
                }
                blk[a * d + a] += 1.0;
            }
        }
        g
    }

    fn inverse(d: usize, g: &[f64]) -> Vec<f64> {
        let mut inv = vec![0.0; g.len()];
        for (blk, out) in g.chunks(d * d).zip(inv.chunks_mut(d * d)) {
            crate::linalg::blocks::invert_small(d, blk, out).expect("regular block");
        }
        inv
    }

    fn residual(w: &CscMatrix, d: usize, g: &[f64], x: &[f64], b: &[f64]) -> f64 {
        let mut r = b.to_vec();
        w.gemv_acc(-1.0, x, &mut r);
        let mut gx = vec![0.0; x.len()];
        crate::linalg::blocks::apply_blocks(d, g, x, &mut gx);
        r.iter()
            .zip(&gx)
            .map(|(a, c)| (a - c).abs())
            .fold(0.0, f64::max)
    }

    pub fn a_low_rank_matrix_has_its_rank_found_and_the_woodbury_solve_follows_its_symmetry() {
        // symmetric part of rank 12: exact solves for W symmetric; for W with an
        // antisymmetric part of 1e-6, the skeleton only approximates W (the caller refines)
        let (m, k, d) = (48, 12, 3);
        for (asym, bound) in [(0.0, 1e-10), (1e-6, 1e-3)] {
            let w = low_rank(m, k, asym, 3);
            let s = Skeleton::new(&w, d, m / 2, 1e-10, Deadline::NEVER).expect("rank 12 ≤ 24");
            assert_eq!(s.rank(), k);
            let g = block_diag(m, d, 5);
            let b: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7).sin()).collect();
            let mut x = b.clone();
            s.solve(&s.factor(&inverse(d, &g), 1500).expect("regular"), &mut x)
                .expect("finite");
            let res = residual(&w, d, &g, &x, &b);
            let bmax = b.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(res < bound * bmax, "asym {asym}: residual {res:e}");
            // sizes that disagree are refused, not indexed
            assert!(s.factor(&g[..g.len() - 9], 1500).is_none());
            let f = s.factor(&inverse(d, &g), 1500).expect("regular");
            assert!(s.solve(&f, &mut vec![1.0; m + 3]).is_none());
        }
    }

    pub fn the_skeleton_is_exact_for_a_low_rank_w_symmetric_or_not() {
        // W = Bᵀ N B with N = I + (a non-symmetric perturbation), B: k × m: rank k, not
        // symmetric (as W = Hᵀ M⁻¹ H with a non-symmetric M); then W = C A⁻¹ R exactly
        let (m, k, d) = (48, 14, 3);
        let mut next = uniform(21, 17);
        let b: Vec<f64> = (0..k * m).map(|_| next()).collect();
        let nmat: Vec<f64> = (0..k * k)
            .map(|t| if t % (k + 1) == 0 { 1.0 } else { 0.0 } + 0.05 * next())
            .collect();
        let mut dense = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                dense[i * m + j] = (0..k)
                    .flat_map(|s| (0..k).map(move |t| (s, t)))
                    .map(|(s, t)| b[s * m + i] * nmat[s * k + t] * b[t * m + j])
                    .sum();
            }
        }
        let w = CscMatrix::from_dense(m, m, &dense);
        assert!(w.asymmetry() > 1e-3, "the test matrix is not symmetric");
        let s = Skeleton::new(&w, d, m / 2, 1e-10, Deadline::NEVER).expect("rank 14 ≤ 24");
        assert_eq!(s.rank(), k);
        let res = s.residual(&w, 1500).expect("regular A");
        assert!(
            res < 1e-10,
            "non-symmetric rank-k W: skeleton residual {res:e}"
        );
        // symmetric rank k: exact too
        let sym = low_rank(m, 12, 0.0, 3);
        let s = Skeleton::new(&sym, d, m / 2, 1e-10, Deadline::NEVER).expect("rank 12");
        assert!(s.residual(&sym, 1500).expect("regular") < 1e-10);
        // a full-rank antisymmetric part of 1e-4: the skeleton of the symmetric part misses it
        let off = low_rank(m, 12, 1e-4, 3);
        let s = Skeleton::new(&off, d, m / 2, 1e-10, Deadline::NEVER).expect("rank 12");
        let res = s.residual(&off, 1500).expect("regular");
        assert!(
            res > 1e-7,
            "the skeleton of a full-rank W is not exact: {res:e}"
        );
        // another matrix's size is refused
        assert!(s.residual(&CscMatrix::zeros(m + 3, m + 3), 1500).is_none());
    }

    pub fn a_full_rank_matrix_has_no_skeleton() {
        let (m, d) = (30, 3);
        let w = low_rank(m, m, 0.0, 9);
        assert!(Skeleton::new(&w, d, m / 2, 1e-10, Deadline::NEVER).is_none());
        // nor does a zero or non-finite one
        assert!(Skeleton::new(&CscMatrix::zeros(m, m), d, m / 2, 1e-10, Deadline::NEVER).is_none());
        let mut bad = low_rank(m, 4, 0.0, 9);
        bad.values[0] = f64::NAN;
        assert!(Skeleton::new(&bad, d, m / 2, 1e-10, Deadline::NEVER).is_none());
    }
}
