//! Compressed sparse column matrices: the one storage type for M, H and W.
//!
//! A plain CSC container is kept by hand because it is the exchange format between three
//! parties that each have their own type: FCLIB (CSC, CSR or triplets on disk), faer (sparse
//! Cholesky of M) and Clarabel (its own CSC type for the conic interior point). Converting at
//! those edges is a copy of three arrays; the hot loops (matrix–vector products, block
//! Gauss–Seidel sweeps) read the arrays directly.

use thiserror::Error;

/// Why a set of arrays does not describe a valid sparse matrix.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SparseError {
    /// `col_ptr` has the wrong length, does not start at 0, decreases, or does not end at nnz.
    #[error("column pointers are inconsistent: {0}")]
    BadPointers(String),
    /// A row (or column) index is outside the matrix.
    #[error("index {index} at entry {entry} is out of range (dimension {dim})")]
    IndexOutOfRange {
        /// position of the entry in the index array
        entry: usize,
        /// the offending index
        index: i64,
        /// the dimension it must stay below
        dim: usize,
    },
    /// Index and value arrays have different lengths.
    #[error("array lengths disagree: {0}")]
    LengthMismatch(String),
}

/// A real sparse matrix in compressed sparse column form, row indices sorted and unique
/// within each column.
#[derive(Debug, Clone, PartialEq)]
pub struct CscMatrix {
    /// number of rows
    pub nrows: usize,
    /// number of columns
    pub ncols: usize,
    /// `ncols + 1` column pointers into `row_idx` and `values`
    pub col_ptr: Vec<usize>,
    /// row index of each stored entry
    pub row_idx: Vec<usize>,
    /// value of each stored entry
    pub values: Vec<f64>,
}

impl CscMatrix {
    /// The `nrows × ncols` zero matrix.
    pub fn zeros(nrows: usize, ncols: usize) -> Self {
        Self {
            nrows,
            ncols,
            col_ptr: vec![0; ncols + 1],
            row_idx: Vec::new(),
            values: Vec::new(),
        }
    }

    /// The `n × n` identity scaled by `alpha`.
    pub fn identity(n: usize, alpha: f64) -> Self {
        Self {
            nrows: n,
            ncols: n,
            col_ptr: (0..=n).collect(),
            row_idx: (0..n).collect(),
            values: vec![alpha; n],
        }
    }

    /// Builds a matrix from `(row, col, value)` triplets; duplicates are summed, entries are
    /// sorted. Indices must be in range.
    pub fn from_triplets(
        nrows: usize,
        ncols: usize,
        rows: &[usize],
        cols: &[usize],
        vals: &[f64],
    ) -> Result<Self, SparseError> {
        if rows.len() != cols.len() || rows.len() != vals.len() {
            return Err(SparseError::LengthMismatch(format!(
                "{} row indices, {} column indices, {} values",
                rows.len(),
                cols.len(),
                vals.len()
            )));
        }
        for (k, (&r, &c)) in rows.iter().zip(cols).enumerate() {
            if r >= nrows {
                return Err(SparseError::IndexOutOfRange {
                    entry: k,
                    index: r as i64,
                    dim: nrows,
                });
            }
            if c >= ncols {
                return Err(SparseError::IndexOutOfRange {
                    entry: k,
                    index: c as i64,
                    dim: ncols,
                });
            }
        }
        let mut counts = vec![0usize; ncols + 1];
        for &c in cols {
            counts[c + 1] += 1;
        }
        for j in 0..ncols {
            counts[j + 1] += counts[j];
        }
        let mut next = counts.clone();
        let mut ri = vec![0usize; rows.len()];
        let mut vv = vec![0.0; rows.len()];
        for k in 0..rows.len() {
            let p = next[cols[k]];
            ri[p] = rows[k];
            vv[p] = vals[k];
            next[cols[k]] += 1;
        }
        Ok(Self::compress(nrows, ncols, &counts, &ri, &vv))
    }

    /// Builds a matrix from CSC arrays that may be unsorted or hold duplicates (summed).
    pub fn from_csc_arrays(
        nrows: usize,
        ncols: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
    ) -> Result<Self, SparseError> {
        check_pointers(col_ptr, ncols, row_idx.len().min(values.len()))?;
        let nnz = col_ptr[ncols];
        for (k, &r) in row_idx[..nnz].iter().enumerate() {
            if r >= nrows {
                return Err(SparseError::IndexOutOfRange {
                    entry: k,
                    index: r as i64,
                    dim: nrows,
                });
            }
        }
        Ok(Self::compress(
            nrows,
            ncols,
            col_ptr,
            &row_idx[..nnz],
            &values[..nnz],
        ))
    }

    /// Builds a matrix from CSR arrays (row pointers, column indices), unsorted or with
    /// duplicates allowed.
    pub fn from_csr_arrays(
        nrows: usize,
        ncols: usize,
        row_ptr: &[usize],
        col_idx: &[usize],
        values: &[f64],
    ) -> Result<Self, SparseError> {
        check_pointers(row_ptr, nrows, col_idx.len().min(values.len()))?;
        let nnz = row_ptr[nrows];
        let mut rows = Vec::with_capacity(nnz);
        for i in 0..nrows {
            for _ in row_ptr[i]..row_ptr[i + 1] {
                rows.push(i);
            }
        }
        Self::from_triplets(nrows, ncols, &rows, &col_idx[..nnz], &values[..nnz])
    }

    /// Sorts each column by row index and sums duplicates. `col_ptr` delimits the columns of
    /// `row_idx`/`values`.
    fn compress(
        nrows: usize,
        ncols: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
    ) -> Self {
        let mut out_ptr = Vec::with_capacity(ncols + 1);
        let mut out_rows = Vec::with_capacity(row_idx.len());
        let mut out_vals = Vec::with_capacity(values.len());
        out_ptr.push(0);
        let mut col: Vec<(usize, f64)> = Vec::new();
        for j in 0..ncols {
            col.clear();
            col.extend((col_ptr[j]..col_ptr[j + 1]).map(|p| (row_idx[p], values[p])));
            col.sort_by_key(|e| e.0);
            for &(r, v) in &col {
                if out_rows.len() > out_ptr[j] && out_rows.last() == Some(&r) {
                    *out_vals.last_mut().expect("non-empty") += v;
                } else {
                    out_rows.push(r);
                    out_vals.push(v);
                }
            }
            out_ptr.push(out_rows.len());
        }
        Self {
            nrows,
            ncols,
            col_ptr: out_ptr,
            row_idx: out_rows,
            values: out_vals,
        }
    }

    /// Builds a sparse matrix from a dense row-major array, dropping exact zeros.
    pub fn from_dense(nrows: usize, ncols: usize, data: &[f64]) -> Self {
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for j in 0..ncols {
            for i in 0..nrows {
                let v = data[i * ncols + j];
                if v != 0.0 {
                    row_idx.push(i);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        Self {
            nrows,
            ncols,
            col_ptr,
            row_idx,
            values,
        }
    }

    /// Dense row-major copy.
    pub fn to_dense(&self) -> Vec<f64> {
        let mut d = vec![0.0; self.nrows * self.ncols];
        for j in 0..self.ncols {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                d[self.row_idx[p] * self.ncols + j] += self.values[p];
            }
        }
        d
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.col_ptr[self.ncols]
    }

    /// Iterates over the stored `(row, col, value)` entries, column by column.
    pub fn triplets(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..self.ncols).flat_map(move |j| {
            (self.col_ptr[j]..self.col_ptr[j + 1])
                .map(move |p| (self.row_idx[p], j, self.values[p]))
        })
    }

    /// The transpose, in CSC form.
    pub fn transpose(&self) -> Self {
        let mut counts = vec![0usize; self.nrows + 1];
        for &r in &self.row_idx[..self.nnz()] {
            counts[r + 1] += 1;
        }
        for i in 0..self.nrows {
            counts[i + 1] += counts[i];
        }
        let mut next = counts.clone();
        let mut ri = vec![0; self.nnz()];
        let mut vv = vec![0.0; self.nnz()];
        for j in 0..self.ncols {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let r = self.row_idx[p];
                ri[next[r]] = j;
                vv[next[r]] = self.values[p];
                next[r] += 1;
            }
        }
        Self {
            nrows: self.ncols,
            ncols: self.nrows,
            col_ptr: counts,
            row_idx: ri,
            values: vv,
        }
    }

    /// y ← y + alpha · A x.
    pub fn gemv_acc(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!(x.len(), self.ncols);
        debug_assert_eq!(y.len(), self.nrows);
        for (j, &xv) in x.iter().enumerate() {
            let xj = alpha * xv;
            if xj == 0.0 {
                continue;
            }
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                y[self.row_idx[p]] += self.values[p] * xj;
            }
        }
    }

    /// y ← y + alpha · Aᵀ x.
    pub fn gemv_t_acc(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!(x.len(), self.nrows);
        debug_assert_eq!(y.len(), self.ncols);
        for (j, yj) in y.iter_mut().enumerate() {
            let mut s = 0.0;
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                s += self.values[p] * x[self.row_idx[p]];
            }
            *yj += alpha * s;
        }
    }

    /// A x as a new vector.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.nrows];
        self.gemv_acc(1.0, x, &mut y);
        y
    }

    /// Aᵀ x as a new vector.
    pub fn mul_t_vec(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.ncols];
        self.gemv_t_acc(1.0, x, &mut y);
        y
    }

    /// Largest |A − Aᵀ| entry relative to the largest |A| entry (0 for a symmetric matrix).
    pub fn asymmetry(&self) -> f64 {
        if self.nrows != self.ncols {
            return f64::INFINITY;
        }
        let t = self.transpose();
        let scale = self.values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let diff = self.add_scaled(-1.0, &t);
        let d = diff.values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if scale > 0.0 {
            d / scale
        } else {
            d
        }
    }

    /// Whether A is square and every stored entry equals its transposed entry exactly (an
    /// entry whose transposed partner is not stored must be zero).
    /// Needs no allocation: each entry's partner is found by binary search in its column (rows
    /// are sorted).
    pub fn is_exactly_symmetric(&self) -> bool {
        if self.nrows != self.ncols {
            return false;
        }
        let partner = |i: usize, j: usize| -> f64 {
            // A_ij from column j
            let rows = &self.row_idx[self.col_ptr[j]..self.col_ptr[j + 1]];
            rows.binary_search(&i)
                .map_or(0.0, |k| self.values[self.col_ptr[j] + k])
        };
        (0..self.ncols).all(|j| {
            (self.col_ptr[j]..self.col_ptr[j + 1])
                .all(|p| self.row_idx[p] == j || partner(j, self.row_idx[p]) == self.values[p])
        })
    }

    /// The symmetric part ½(A + Aᵀ) of a square matrix.
    pub fn symmetric_part(&self) -> CscMatrix {
        let mut s = self.add_scaled(1.0, &self.transpose());
        s.values.iter_mut().for_each(|v| *v *= 0.5);
        s
    }

    /// A + alpha · B (same shape).
    pub fn add_scaled(&self, alpha: f64, other: &CscMatrix) -> CscMatrix {
        let mut rows = Vec::with_capacity(self.nnz() + other.nnz());
        let mut cols = Vec::with_capacity(self.nnz() + other.nnz());
        let mut vals = Vec::with_capacity(self.nnz() + other.nnz());
        for (r, c, v) in self.triplets() {
            rows.push(r);
            cols.push(c);
            vals.push(v);
        }
        for (r, c, v) in other.triplets() {
            rows.push(r);
            cols.push(c);
            vals.push(alpha * v);
        }
        Self::from_triplets(self.nrows, self.ncols, &rows, &cols, &vals)
            .expect("indices of valid matrices are in range")
    }

    /// The upper triangle (diagonal included), as Clarabel and faer's Cholesky expect.
    pub fn upper_triangle(&self) -> CscMatrix {
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for j in 0..self.ncols {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                if self.row_idx[p] <= j {
                    row_idx.push(self.row_idx[p]);
                    values.push(self.values[p]);
                }
            }
            col_ptr.push(row_idx.len());
        }
        Self {
            nrows: self.nrows,
            ncols: self.ncols,
            col_ptr,
            row_idx,
            values,
        }
    }

    /// Whether every stored value is finite; returns the first bad `(row, col)` otherwise.
    pub fn first_non_finite(&self) -> Option<(usize, usize)> {
        self.triplets()
            .find(|(_, _, v)| !v.is_finite())
            .map(|(r, c, _)| (r, c))
    }

    /// Diagonal entries (zero where not stored).
    pub fn diagonal(&self) -> Vec<f64> {
        let n = self.nrows.min(self.ncols);
        let mut d = vec![0.0; n];
        for (j, dj) in d.iter_mut().enumerate() {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                if self.row_idx[p] == j {
                    *dj += self.values[p];
                }
            }
        }
        d
    }

    /// Checks the structural invariants (pointer monotonicity, sorted unique in-range rows).
    pub fn check(&self) -> Result<(), SparseError> {
        check_pointers(
            &self.col_ptr,
            self.ncols,
            self.row_idx.len().min(self.values.len()),
        )?;
        for j in 0..self.ncols {
            let mut last: Option<usize> = None;
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let r = self.row_idx[p];
                if r >= self.nrows {
                    return Err(SparseError::IndexOutOfRange {
                        entry: p,
                        index: r as i64,
                        dim: self.nrows,
                    });
                }
                if last.is_some_and(|l| l >= r) {
                    return Err(SparseError::BadPointers(format!(
                        "row indices of column {j} are not sorted and unique"
                    )));
                }
                last = Some(r);
            }
        }
        Ok(())
    }
}

/// Whether the sparse Cholesky factorization of S + τ I succeeds, where S is the symmetric
/// part ½(A + Aᵀ) scaled on both sides by `scale` (S_ij = ½(A_ij + A_ji) scale_i scale_j):
/// the test that S is positive semidefinite up to τ. Err with faer's reason otherwise.
pub fn shifted_cholesky_succeeds(a: &CscMatrix, scale: &[f64], tau: f64) -> Result<(), String> {
    use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
    use faer::sparse::{SparseColMat, Triplet};
    use faer::Side;
    let n = a.nrows;
    let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(a.nnz() + n);
    for (i, j, v) in a.triplets() {
        let x = 0.5 * v * scale[i] * scale[j];
        // upper triangle of ½(A + Aᵀ): (i, j) and (j, i) both land on (min, max)
        trip.push(Triplet::new(
            i.min(j),
            i.max(j),
            if i == j { 2.0 * x } else { x },
        ));
    }
    for i in 0..n {
        trip.push(Triplet::new(i, i, tau));
    }
    let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
        .map_err(|e| format!("{e:?}"))?;
    let symbolic =
        SymbolicLlt::try_new(mat.symbolic(), Side::Upper).map_err(|e| format!("{e:?}"))?;
    Llt::try_new_with_symbolic(symbolic, mat.as_ref(), Side::Upper)
        .map(|_| ())
        .map_err(|_| "its Cholesky factorization broke down".to_string())
}

fn check_pointers(ptr: &[usize], n: usize, avail: usize) -> Result<(), SparseError> {
    if ptr.len() != n + 1 {
        return Err(SparseError::BadPointers(format!(
            "expected {} pointers, found {}",
            n + 1,
            ptr.len()
        )));
    }
    if ptr[0] != 0 {
        return Err(SparseError::BadPointers(format!(
            "first pointer is {}, not 0",
            ptr[0]
        )));
    }
    if let Some(k) = ptr.windows(2).position(|w| w[1] < w[0]) {
        return Err(SparseError::BadPointers(format!(
            "pointers decrease at position {}",
            k + 1
        )));
    }
    if ptr[n] > avail {
        return Err(SparseError::BadPointers(format!(
            "last pointer {} exceeds the {} stored entries",
            ptr[n], avail
        )));
    }
    Ok(())
}

/// A square matrix stored by dense d × d blocks in compressed block rows (d ∈ {2, 3}: one
/// block per pair of contacts). W = H M⁻¹ Hᵀ is made of such blocks, and a product touching a
/// block at a time (one index, d² multiply–adds on contiguous values, d outputs kept in
/// registers) runs several times faster than the entry-wise CSC product. Neither faer nor
/// sprs has block sparse storage, hence this type.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockCsr {
    /// block size d
    pub dim: usize,
    /// number of block rows (= block columns)
    pub blocks: usize,
    /// `blocks + 1` pointers into `block_col` and the block values
    pub row_ptr: Vec<usize>,
    /// block column of each stored block, increasing within a block row
    pub block_col: Vec<usize>,
    /// d² values per stored block, row-major
    pub values: Vec<f64>,
}

impl BlockCsr {
    /// The block form of a valid square CSC matrix whose size is a multiple of d
    /// (d ∈ {2, 3}); None otherwise. Entries absent from a stored block are zeros.
    pub fn from_csc(a: &CscMatrix, dim: usize) -> Option<Self> {
        if !(2..=3).contains(&dim) || a.nrows != a.ncols || a.ncols % dim != 0 || a.check().is_err()
        {
            return None;
        }
        let blocks = a.ncols / dim;
        // Columns are visited in increasing order, so for a fixed block row the block columns
        // of its entries come in nondecreasing order: one marker per block row finds each
        // new block (pass 1 counts them, pass 2 places them). Linear in nnz, no sort.
        let mut last = vec![usize::MAX; blocks];
        let mut row_ptr = vec![0; blocks + 1];
        for j in 0..a.ncols {
            let bj = j / dim;
            for &i in &a.row_idx[a.col_ptr[j]..a.col_ptr[j + 1]] {
                let bi = i / dim;
                if last[bi] != bj {
                    last[bi] = bj;
                    row_ptr[bi + 1] += 1;
                }
            }
        }
        for k in 0..blocks {
            row_ptr[k + 1] += row_ptr[k];
        }
        let stored = row_ptr[blocks];
        let mut block_col = vec![0; stored];
        let mut values = vec![0.0; stored * dim * dim];
        let mut next = row_ptr[..blocks].to_vec();
        let mut slot = vec![0; blocks];
        last.iter_mut().for_each(|v| *v = usize::MAX);
        for j in 0..a.ncols {
            let bj = j / dim;
            for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                let i = a.row_idx[p];
                let bi = i / dim;
                if last[bi] != bj {
                    last[bi] = bj;
                    slot[bi] = next[bi];
                    block_col[next[bi]] = bj;
                    next[bi] += 1;
                }
                values[slot[bi] * dim * dim + (i % dim) * dim + j % dim] += a.values[p];
            }
        }
        Some(Self {
            dim,
            blocks,
            row_ptr,
            block_col,
            values,
        })
    }

    /// Number of stored blocks.
    pub fn stored_blocks(&self) -> usize {
        self.block_col.len()
    }

    /// y ← A x (x and y of length `blocks · dim`).
    pub fn gemv(&self, x: &[f64], y: &mut [f64]) {
        match self.dim {
            2 => self.gemv_d::<2>(x, y),
            _ => self.gemv_d::<3>(x, y),
        }
    }

    fn gemv_d<const D: usize>(&self, x: &[f64], y: &mut [f64]) {
        for (bi, out) in y.chunks_exact_mut(D).enumerate().take(self.blocks) {
            let mut acc = [0.0; D];
            let range = self.row_ptr[bi]..self.row_ptr[bi + 1];
            let vals = &self.values[range.start * D * D..range.end * D * D];
            for (&bj, blk) in self.block_col[range].iter().zip(vals.chunks_exact(D * D)) {
                let xj = &x[bj * D..bj * D + D];
                for a in 0..D {
                    for b in 0..D {
                        acc[a] += blk[a * D + b] * xj[b];
                    }
                }
            }
            out.copy_from_slice(&acc);
        }
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    pub fn triplets_sum_duplicates_and_sort() {
        let a = CscMatrix::from_triplets(2, 2, &[1, 0, 1], &[0, 0, 0], &[1.0, 2.0, 3.0]).unwrap();
        assert_eq!(a.col_ptr, vec![0, 2, 2]);
        assert_eq!(a.row_idx, vec![0, 1]);
        assert_eq!(a.values, vec![2.0, 4.0]);
        a.check().unwrap();
    }

    pub fn csr_and_transpose_agree_with_dense() {
        // [[1, 0, 2], [0, 3, 0]]
        let a = CscMatrix::from_csr_arrays(2, 3, &[0, 2, 3], &[0, 2, 1], &[1.0, 2.0, 3.0]).unwrap();
        assert_eq!(a.to_dense(), vec![1.0, 0.0, 2.0, 0.0, 3.0, 0.0]);
        let t = a.transpose();
        assert_eq!(t.to_dense(), vec![1.0, 0.0, 0.0, 3.0, 2.0, 0.0]);
        assert_eq!(a.mul_vec(&[1.0, 1.0, 1.0]), vec![3.0, 3.0]);
        assert_eq!(a.mul_t_vec(&[1.0, 2.0]), vec![1.0, 6.0, 2.0]);
    }

    pub fn bad_arrays_are_reported() {
        assert!(matches!(
            CscMatrix::from_csc_arrays(2, 2, &[0, 1], &[0], &[1.0]),
            Err(SparseError::BadPointers(_))
        ));
        assert!(matches!(
            CscMatrix::from_csc_arrays(2, 2, &[0, 2, 1], &[0, 1], &[1.0, 1.0]),
            Err(SparseError::BadPointers(_))
        ));
        assert!(matches!(
            CscMatrix::from_triplets(2, 2, &[5], &[0], &[1.0]),
            Err(SparseError::IndexOutOfRange { .. })
        ));
    }

    pub fn block_product_equals_entrywise_product() {
        for dim in [2usize, 3] {
            let n = 4 * dim;
            let mut dense = vec![0.0; n * n];
            for (k, v) in dense.iter_mut().enumerate() {
                // a pattern with empty blocks, full blocks and partly filled ones
                if (k * 7) % 5 != 0 && (k / n + k % n) % 3 != 1 {
                    *v = ((k * 37) % 11) as f64 - 5.0;
                }
            }
            let a = CscMatrix::from_dense(n, n, &dense);
            let b = BlockCsr::from_csc(&a, dim).unwrap();
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
            let mut y = vec![f64::NAN; n];
            b.gemv(&x, &mut y);
            let expected = a.mul_vec(&x);
            for (p, q) in y.iter().zip(&expected) {
                assert!(
                    (p - q).abs() <= 1e-12 * (1.0 + q.abs()),
                    "{y:?} vs {expected:?}"
                );
            }
        }
        assert!(BlockCsr::from_csc(&CscMatrix::zeros(5, 5), 3).is_none());
        // arrays that do not describe a matrix: refused, not indexed out of range
        let mut bad = CscMatrix::identity(6, 1.0);
        bad.row_idx[2] = 99;
        assert!(BlockCsr::from_csc(&bad, 3).is_none());
    }
}
