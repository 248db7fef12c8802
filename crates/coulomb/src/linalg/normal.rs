//! The normal equations (JᵀJ + λ I) δ = −JᵀΦ of the Levenberg–Marquardt steps
//! ([`crate::levenberg`], [`crate::newton::least_squares`]): the block pattern of JᵀJ from the
//! pattern of J (`pattern_lu::JacobianPattern`), its symbolic Cholesky factorization
//! computed once per run, and a numeric Cholesky per step.

use super::pattern_lu::JacobianPattern;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::Side;

/// The pattern of JᵀJ (every d × d block (a, b) such that block columns a and b of J share a
/// block row) and its symbolic Cholesky factorization, computed once per run.
pub(crate) struct NormalPattern {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    /// the numeric factorizations' parallelism ([`super::pattern_lu::SPARSE_PARALLEL_DIM`])
    par: faer::Par,
}

impl NormalPattern {
    pub(crate) fn new(jac: &JacobianPattern, dim: usize, max_nonzeros: usize) -> Option<Self> {
        let contacts = jac.neighbors.len();
        // rows[k]: the block columns of J with a block in block row k
        let mut rows: Vec<Vec<usize>> = vec![Vec::new(); contacts];
        for (b, nb) in jac.neighbors.iter().enumerate() {
            for &k in nb {
                rows[k].push(b);
            }
        }
        let mut blocks: Vec<Vec<usize>> = Vec::with_capacity(contacts);
        let mut total = 0usize;
        let mut mark = vec![usize::MAX; contacts];
        for (b, nb) in jac.neighbors.iter().enumerate() {
            let mut list = Vec::new();
            for &k in nb {
                for &a in &rows[k] {
                    if mark[a] != b {
                        mark[a] = b;
                        list.push(a);
                    }
                }
            }
            list.sort_unstable();
            total = total.saturating_add(list.len() * dim * dim);
            if total > max_nonzeros {
                return None;
            }
            blocks.push(list);
        }
        let m = contacts * dim;
        let mut col_ptr = Vec::with_capacity(m + 1);
        let mut row_idx = Vec::with_capacity(total);
        col_ptr.push(0);
        for j in 0..m {
            for &a in &blocks[j / dim] {
                row_idx.extend(a * dim..(a + 1) * dim);
            }
            col_ptr.push(row_idx.len());
        }
        let sym = SymbolicSparseColMatRef::new_checked(m, m, &col_ptr, None, &row_idx);
        let symbolic =
            factorize_symbolic_cholesky(sym, Side::Lower, Default::default(), Default::default())
                .ok()?;
        Some(Self {
            col_ptr,
            row_idx,
            symbolic,
            par: super::pattern_lu::sparse_parallelism(m),
        })
    }
}

/// J (values on `jac`'s pattern, column-major) with its row-major copy, and JᵀJ + λI.
pub(crate) struct Normal<'p> {
    jac: &'p JacobianPattern,
    pattern: NormalPattern,
    /// J by rows: for each row, (column, value)
    row_ptr: Vec<usize>,
    row_entries: Vec<(usize, f64)>,
    acc: Vec<f64>,
    values: Vec<f64>,
}

impl<'p> Normal<'p> {
    pub(crate) fn new(jac: &'p JacobianPattern, pattern: NormalPattern, m: usize) -> Self {
        Self {
            jac,
            pattern,
            row_ptr: vec![0; m + 1],
            row_entries: Vec::new(),
            acc: vec![0.0; m],
            values: Vec::new(),
        }
    }

    /// Solves (JᵀJ + λI) δ = −JᵀΦ for J given by its values `jv` on the pattern; None if the
    /// Cholesky factorization fails or δ is not finite.
    pub(crate) fn direction(&mut self, jv: &[f64], lambda: f64, phi: &[f64]) -> Option<Vec<f64>> {
        let m = phi.len();
        let (cp, ri) = (&self.jac.col_ptr, &self.jac.row_idx);
        // J by rows
        self.row_ptr.iter_mut().for_each(|x| *x = 0);
        for &i in ri.iter() {
            self.row_ptr[i + 1] += 1;
        }
        for i in 0..m {
            self.row_ptr[i + 1] += self.row_ptr[i];
        }
        self.row_entries.clear();
        self.row_entries.resize(ri.len(), (0, 0.0));
        let mut next = self.row_ptr.clone();
        for c in 0..m {
            for k in cp[c]..cp[c + 1] {
                let i = ri[k];
                self.row_entries[next[i]] = (c, jv[k]);
                next[i] += 1;
            }
        }
        // JᵀJ + λI on its pattern, column by column
        self.values.clear();
        for c in 0..m {
            for k in cp[c]..cp[c + 1] {
                let (row, v) = (ri[k], jv[k]);
                for &(i, w) in &self.row_entries[self.row_ptr[row]..self.row_ptr[row + 1]] {
                    self.acc[i] += v * w;
                }
            }
            self.acc[c] += lambda;
            let (np, nr) = (&self.pattern.col_ptr, &self.pattern.row_idx);
            for &i in &nr[np[c]..np[c + 1]] {
                self.values.push(self.acc[i]);
                self.acc[i] = 0.0;
            }
        }
        // −JᵀΦ
        let mut delta: Vec<f64> = (0..m)
            .map(|c| -(cp[c]..cp[c + 1]).map(|k| jv[k] * phi[ri[k]]).sum::<f64>())
            .collect();
        let (np, nr) = (&self.pattern.col_ptr, &self.pattern.row_idx);
        let sym = SymbolicSparseColMatRef::new_checked(m, m, np, None, nr);
        let mat = SparseColMatRef::new(sym, &self.values);
        let (symbolic, par) = (&self.pattern.symbolic, self.pattern.par);
        let mut l_values = vec![0.0; symbolic.len_val()];
        let scratch = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]);
        let mut mem = MemBuffer::try_new(scratch).ok()?;
        let llt = symbolic
            .factorize_numeric_llt(
                &mut l_values,
                mat,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .ok()?;
        llt.solve_in_place_with_conj(
            faer::Conj::No,
            faer::MatMut::from_column_major_slice_mut(&mut delta, m, 1),
            par,
            MemStack::new(&mut mem),
        );
        delta.iter().all(|x| x.is_finite()).then_some(delta)
    }
}
