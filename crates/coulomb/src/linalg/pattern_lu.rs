//! The patterned sparse LU of the Newton systems on the block pattern of W: the pattern of
//! J + λ I (every d × d block (i, j) with i = j or with a nonzero of W in block (i, j)) with its
//! symbolic LU computed once, numeric LUs on it (`PatternLu`), and a one-off sparse LU of
//! summed triplets (`sparse_lu_solve`). Used by semismooth Newton ([`crate::newton`]), the
//! interior point on the law ([`crate::barrier`]), the proximal point ([`crate::proximal`]),
//! the polish of the inner interior point ([`crate::inner::ipm`]) and, for its pattern, the
//! normal equations of Levenberg–Marquardt ([`super::normal`]).

use crate::linalg::sparse::CscMatrix;
use crate::problem::LocalProblem;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};

/// Solves J x = rhs for a square sparse J given as summed triplets, by faer's sparse LU.
/// None if the factorization fails or the solution is not finite.
pub(crate) fn sparse_lu_solve(
    n: usize,
    rows: &[usize],
    cols: &[usize],
    vals: &[f64],
    rhs: &mut [f64],
) -> Option<()> {
    let csc = CscMatrix::from_triplets(n, n, rows, cols, vals).ok()?;
    let trip: Vec<faer::sparse::Triplet<usize, usize, f64>> = csc
        .triplets()
        .map(|(i, j, v)| faer::sparse::Triplet::new(i, j, v))
        .collect();
    let mat = faer::sparse::SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip).ok()?;
    let lu = mat.sp_lu().ok()?;
    lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(rhs, n, 1));
    rhs.iter().all(|x| x.is_finite()).then_some(())
}

/// The sparsity pattern of J + λ I: every d × d block (i, j) with i = j or with a nonzero of
/// W in block (i, j), and its symbolic LU factorization, computed once per [`crate::newton::polish`] call
/// (the values change at every step, the pattern does not). Also the pattern of the
/// Alart–Curnier Jacobian of [`crate::levenberg`] (same blocks), which needs no LU.
pub(crate) struct JacobianPattern {
    dim: usize,
    pub(crate) col_ptr: Vec<usize>,
    pub(crate) row_idx: Vec<usize>,
    /// for each contact (block column), the contacts of its block rows, ascending
    pub(crate) neighbors: Vec<Vec<usize>>,
    /// position of each diagonal entry in `row_idx`
    diagonal: Vec<usize>,
    /// None when built by [`JacobianPattern::without_lu`]
    symbolic: Option<std::sync::Arc<SymbolicLu<usize>>>,
    /// the numeric factorizations' parallelism ([`SPARSE_PARALLEL_DIM`])
    par: faer::Par,
}

/// The sparse factorizations of the Newton and Levenberg–Marquardt systems (LU of J on
/// the block pattern of J, Cholesky of JᵀJ + λI) run on all threads from this many unknowns on,
/// on one thread below: faer's supernodal factorizations spend more on synchronising their
/// threads than they gain on the small supernodes of such problems. Measured on 2 cores
/// (docs/bench.md, "Threads"): the box files of the corpus (m ≤ 2 000) take 0.75× the time
/// with this and the dense LU on one thread; a 5 000-bead granular file (m = 21 183) the
/// same time either way.
pub const SPARSE_PARALLEL_DIM: usize = 20_000;
/// The parallelism of a sparse factorization of n unknowns ([`SPARSE_PARALLEL_DIM`]).
pub(crate) fn sparse_parallelism(n: usize) -> faer::Par {
    super::dense::parallelism(n, SPARSE_PARALLEL_DIM)
}

/// A numeric LU of J on a [`JacobianPattern`] (its symbolic factorization shared).
pub(crate) struct PatternLu {
    symbolic: std::sync::Arc<SymbolicLu<usize>>,
    numeric: NumericLu<usize, f64>,
    par: faer::Par,
}

impl PatternLu {
    /// x = J⁻¹ rhs in place; false (nothing changed) if the length of `rhs` is not J's size.
    pub(crate) fn solve_in_place(&self, rhs: &mut [f64]) -> bool {
        let n = self.symbolic.nrows();
        if rhs.len() != n {
            return false;
        }
        let scratch = self.symbolic.solve_in_place_scratch::<f64>(1, self.par);
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            faer::Conj::No,
            faer::MatMut::from_column_major_slice_mut(rhs, n, 1),
            self.par,
            MemStack::new(&mut MemBuffer::new(scratch)),
        );
        true
    }
}

impl JacobianPattern {
    pub(crate) fn new(p: &LocalProblem) -> Option<Self> {
        let mut pattern = Self::without_lu(p);
        let sym = SymbolicSparseColMatRef::new_checked(
            pattern.col_ptr.len() - 1,
            pattern.col_ptr.len() - 1,
            &pattern.col_ptr,
            None,
            &pattern.row_idx,
        );
        pattern.symbolic = Some(std::sync::Arc::new(
            factorize_symbolic_lu(sym, Default::default()).ok()?,
        ));
        Some(pattern)
    }

    /// The pattern alone (no symbolic LU; [`JacobianPattern::solve`] then fails).
    pub(crate) fn without_lu(p: &LocalProblem) -> Self {
        let d = p.dim;
        let contacts = p.mu.len();
        let mut neighbors: Vec<Vec<usize>> = (0..contacts).map(|c| vec![c]).collect();
        for (i, j, _) in p.w.triplets() {
            neighbors[j / d].push(i / d);
        }
        for n in &mut neighbors {
            n.sort_unstable();
            n.dedup();
        }
        let m = contacts * d;
        let mut col_ptr = Vec::with_capacity(m + 1);
        let mut row_idx = Vec::new();
        let mut diagonal = vec![0; m];
        col_ptr.push(0);
        for j in 0..m {
            for &ci in &neighbors[j / d] {
                for a in 0..d {
                    if ci * d + a == j {
                        diagonal[j] = row_idx.len();
                    }
                    row_idx.push(ci * d + a);
                }
            }
            col_ptr.push(row_idx.len());
        }
        Self {
            dim: d,
            col_ptr,
            row_idx,
            neighbors,
            diagonal,
            symbolic: None,
            par: sparse_parallelism(p.q.len()),
        }
    }

    /// The values of J = I − D + B W on the pattern (B = D A), column by column.
    pub(crate) fn fill(
        &self,
        p: &LocalProblem,
        dblocks: &[f64],
        blocks: &[f64],
        wcol: &mut [f64],
        vals: &mut Vec<f64>,
    ) {
        let d = self.dim;
        vals.clear();
        for j in 0..p.w.ncols {
            let (cj, b) = (j / d, j % d);
            for k in p.w.col_ptr[j]..p.w.col_ptr[j + 1] {
                wcol[p.w.row_idx[k]] += p.w.values[k];
            }
            for &ci in &self.neighbors[cj] {
                let bl = &blocks[ci * d * d..(ci + 1) * d * d];
                let dl = &dblocks[ci * d * d..(ci + 1) * d * d];
                for a in 0..d {
                    let mut v: f64 = (0..d).map(|k| bl[a * d + k] * wcol[ci * d + k]).sum();
                    if ci == cj {
                        v += if a == b { 1.0 } else { 0.0 } - dl[a * d + b];
                    }
                    vals.push(v);
                }
            }
            for k in p.w.col_ptr[j]..p.w.col_ptr[j + 1] {
                wcol[p.w.row_idx[k]] = 0.0;
            }
        }
    }

    pub(crate) fn shift_diagonal(&self, vals: &mut [f64], lambda: f64) {
        for &k in &self.diagonal {
            vals[k] += lambda;
        }
    }

    /// The LU of the matrix with these values on the pattern, from the cached symbolic
    /// factorization; None if it fails.
    pub(crate) fn factor(&self, vals: &[f64]) -> Option<PatternLu> {
        let n = self.col_ptr.len() - 1;
        let symbolic = self.symbolic.clone()?;
        if vals.len() != self.row_idx.len() {
            return None;
        }
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let mat = SparseColMatRef::new(sym, vals);
        let mut numeric = NumericLu::new();
        let scratch = symbolic.factorize_numeric_lu_scratch::<f64>(self.par, Default::default());
        symbolic
            .factorize_numeric_lu(
                &mut numeric,
                mat,
                self.par,
                MemStack::new(&mut MemBuffer::try_new(scratch).ok()?),
                Default::default(),
            )
            .ok()?;
        Some(PatternLu {
            symbolic,
            numeric,
            par: self.par,
        })
    }

    /// Solves (J + λ I) x = rhs in place by LU with the cached symbolic factorization; None
    /// if the factorization fails or x is not finite.
    pub(crate) fn solve(&self, vals: &[f64], rhs: &mut [f64]) -> Option<()> {
        let lu = self.factor(vals)?;
        (lu.solve_in_place(rhs) && rhs.iter().all(|x| x.is_finite())).then_some(())
    }
}
