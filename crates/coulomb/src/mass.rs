//! The factorization of the mass matrix M of a global problem (2.10), used to check that M is
//! positive definite ([`crate::problem::GlobalProblem::new`]) and to form the Delassus form
//! ([`crate::delassus`]).
//!
//! M is factored by Cholesky block by block: the dofs are split into the connected components
//! of M's sparsity graph (one per rigid body for a multibody system, one for a finite-element
//! mesh), so a block-diagonal M costs a few small dense factorizations and M⁻¹ H keeps the
//! sparsity of H. Large blocks use faer's sparse supernodal Cholesky; M⁻¹ is never formed.

use crate::linalg::sparse::CscMatrix;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{SparseColMat, Triplet};
use faer::{MatMut, Side};

/// Why M could not be factored.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MassError {
    /// M (or the symmetric part of a block) is not positive definite: the Cholesky
    /// factorization broke down, or a sparse factorization failed
    #[error("{0}")]
    NotPositiveDefinite(String),
}

/// Blocks up to this size are factored densely.
const DENSE_BLOCK_MAX: usize = 48;

enum Factor {
    /// Lower-triangular dense Cholesky factor, row-major k × k. A hand-written kernel:
    /// calling a general dense factorization per 6 × 6 rigid-body block costs more in setup
    /// than the factorization itself.
    Dense(Vec<f64>),
    /// faer sparse LLᵀ.
    Sparse(Box<Llt<usize, f64>>),
    /// faer sparse LU with partial pivoting of a block that is not exactly symmetric: solves
    /// then hold for M_b itself, not for its symmetric part.
    Lu(Box<Lu<usize, f64>>),
}

struct Block {
    dofs: Vec<usize>,
    /// Cholesky factor of M_b, or LU factors when M_b is not exactly symmetric
    factor: Factor,
    /// the block M_b itself when it is not exactly symmetric: solves are then refined
    /// iteratively against it, so that M v = b holds for the M of the problem
    raw: Option<CscMatrix>,
}

/// Cap on iterative-refinement steps against a non-symmetric block.
const MAX_REFINEMENT: usize = 10;

/// Cholesky factorization of a symmetric positive definite M, split along the connected
/// components of its sparsity graph. Files in the wild store M with rounding-level asymmetry;
/// then positive definiteness is checked on the symmetric part, the block itself is solved by
/// LU and each solve is refined against it (for an ill-conditioned M, a relative asymmetry of
/// 1e-7 already moves M⁻¹ b by tens of percent, so the symmetric part is not a substitute).
pub struct MassFactor {
    n: usize,
    blocks: Vec<Block>,
    /// for each dof, (block index, position within the block)
    place: Vec<(usize, usize)>,
}

impl std::fmt::Debug for MassFactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MassFactor")
            .field("n", &self.n)
            .field("blocks", &self.blocks.len())
            .finish()
    }
}

fn components(m: &CscMatrix) -> Vec<Vec<usize>> {
    let n = m.ncols;
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for (r, c, _) in m.triplets() {
        let (a, b) = (find(&mut parent, r), find(&mut parent, c));
        if a != b {
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut index = vec![usize::MAX; n];
    let mut comps: Vec<Vec<usize>> = Vec::new();
    for i in 0..n {
        let root = find(&mut parent, i);
        if index[root] == usize::MAX {
            index[root] = comps.len();
            comps.push(Vec::new());
        }
        comps[index[root]].push(i);
    }
    comps
}

fn dense_cholesky(a: &mut [f64], k: usize) -> Result<(), String> {
    for j in 0..k {
        let mut d = a[j * k + j];
        for p in 0..j {
            d -= a[j * k + p] * a[j * k + p];
        }
        if d.is_nan() || d <= 0.0 || !d.is_finite() {
            return Err(format!("non-positive pivot {d:.3e}"));
        }
        let d = d.sqrt();
        a[j * k + j] = d;
        for i in j + 1..k {
            let mut s = a[i * k + j];
            for p in 0..j {
                s -= a[i * k + p] * a[j * k + p];
            }
            a[i * k + j] = s / d;
        }
        for i in 0..j {
            a[i * k + j] = 0.0;
        }
    }
    Ok(())
}

fn dense_solve(l: &[f64], k: usize, x: &mut [f64]) {
    for i in 0..k {
        let mut s = x[i];
        for p in 0..i {
            s -= l[i * k + p] * x[p];
        }
        x[i] = s / l[i * k + i];
    }
    for i in (0..k).rev() {
        let mut s = x[i];
        for p in i + 1..k {
            s -= l[p * k + i] * x[p];
        }
        x[i] = s / l[i * k + i];
    }
}

impl MassFactor {
    /// Factors M (symmetric; only checked for positive definiteness here).
    pub fn new(m: &CscMatrix) -> Result<Self, MassError> {
        let n = m.nrows;
        let comps = components(m);
        let mut place = vec![(0, 0); n];
        for (b, dofs) in comps.iter().enumerate() {
            for (k, &d) in dofs.iter().enumerate() {
                place[d] = (b, k);
            }
        }
        let mut blocks = Vec::with_capacity(comps.len());
        for (b, dofs) in comps.into_iter().enumerate() {
            let k = dofs.len();
            let (factor, raw) = if k <= DENSE_BLOCK_MAX {
                // small block: straight into a dense array, no sparse intermediates
                let mut a = vec![0.0; k * k];
                for &d in &dofs {
                    for p in m.col_ptr[d]..m.col_ptr[d + 1] {
                        a[place[m.row_idx[p]].1 * k + place[d].1] += m.values[p];
                    }
                }
                let symmetric = (0..k).all(|i| (0..i).all(|j| a[i * k + j] == a[j * k + i]));
                let raw = (!symmetric).then(|| CscMatrix::from_dense(k, k, &a));
                for i in 0..k {
                    for j in 0..i {
                        let mean = 0.5 * (a[i * k + j] + a[j * k + i]);
                        a[i * k + j] = mean;
                        a[j * k + i] = mean;
                    }
                }
                dense_cholesky(&mut a, k).map_err(|e| {
                    MassError::NotPositiveDefinite(format!(
                        "{e} in the block of dofs {}..{}",
                        dofs[0],
                        dofs[k - 1]
                    ))
                })?;
                (Factor::Dense(a), raw)
            } else {
                let mut local = Vec::new();
                for &d in &dofs {
                    for p in m.col_ptr[d]..m.col_ptr[d + 1] {
                        local.push((place[m.row_idx[p]].1, place[d].1, m.values[p]));
                    }
                }
                let (ri, ci, vi): (Vec<usize>, Vec<usize>, Vec<f64>) = (
                    local.iter().map(|e| e.0).collect(),
                    local.iter().map(|e| e.1).collect(),
                    local.iter().map(|e| e.2).collect(),
                );
                let block_matrix = CscMatrix::from_triplets(k, k, &ri, &ci, &vi)
                    .map_err(|e| MassError::NotPositiveDefinite(format!("{e}")))?;
                let sym = {
                    let mut s = block_matrix.add_scaled(1.0, &block_matrix.transpose());
                    s.values.iter_mut().for_each(|v| *v *= 0.5);
                    s
                };
                let raw = (sym != block_matrix).then_some(block_matrix);
                let trip: Vec<_> = sym
                    .triplets()
                    .filter(|&(i, j, _)| i <= j)
                    .map(|(i, j, v)| Triplet::new(i, j, v))
                    .collect();
                let mat = SparseColMat::<usize, f64>::try_new_from_triplets(k, k, &trip)
                    .map_err(|e| MassError::NotPositiveDefinite(format!("{e:?}")))?;
                let symbolic = SymbolicLlt::try_new(mat.symbolic(), Side::Upper)
                    .map_err(|e| MassError::NotPositiveDefinite(format!("{e:?}")))?;
                let llt = Llt::try_new_with_symbolic(symbolic, mat.as_ref(), Side::Upper)
                    .map_err(|e| MassError::NotPositiveDefinite(format!("{e:?} in block {b}")))?;
                (Factor::Sparse(Box::new(llt)), raw)
            };
            // the Cholesky factor of the symmetric part certified positive definiteness; a
            // block that is not exactly symmetric is solved with its own LU factors
            let factor =
                match &raw {
                    Some(a) => Factor::Lu(Box::new(lu_factor(a).map_err(|e| {
                        MassError::NotPositiveDefinite(format!("{e} in block {b}"))
                    })?)),
                    None => factor,
                };
            blocks.push(Block { dofs, factor, raw });
        }
        Ok(Self { n, blocks, place })
    }

    /// Dimension n of M.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Whether every block of M is exactly symmetric (factored by Cholesky, no refinement).
    pub fn exactly_symmetric(&self) -> bool {
        self.blocks.iter().all(|b| b.raw.is_none())
    }

    /// x ← M_b⁻¹ x for block b, refined against M_b when it is not exactly symmetric.
    fn solve_block(&self, b: usize, x: &mut [f64]) {
        let block = &self.blocks[b];
        let Some(a) = &block.raw else {
            Self::solve_symmetric(block, x);
            return;
        };
        let rhs = x.to_vec();
        let rhs_norm = crate::law::norm(&rhs);
        Self::solve_symmetric(block, x);
        let mut res = vec![0.0; x.len()];
        let mut last = f64::INFINITY;
        for _ in 0..MAX_REFINEMENT {
            res.copy_from_slice(&rhs);
            a.gemv_acc(-1.0, x, &mut res);
            let rn = crate::law::norm(&res);
            if rn <= 1e-15 * rhs_norm || rn >= last {
                break;
            }
            last = rn;
            Self::solve_symmetric(block, &mut res);
            x.iter_mut().zip(&res).for_each(|(xi, ri)| *xi += ri);
        }
    }

    fn solve_symmetric(block: &Block, x: &mut [f64]) {
        match &block.factor {
            Factor::Dense(l) => dense_solve(l, block.dofs.len(), x),
            Factor::Sparse(llt) => {
                let k = block.dofs.len();
                llt.solve_in_place(MatMut::from_column_major_slice_mut(x, k, 1));
            }
            Factor::Lu(lu) => {
                let k = block.dofs.len();
                lu.solve_in_place(MatMut::from_column_major_slice_mut(x, k, 1));
            }
        }
    }

    /// x ← M⁻¹ x.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        let mut buf = Vec::new();
        for b in 0..self.blocks.len() {
            let dofs = &self.blocks[b].dofs;
            buf.clear();
            buf.extend(dofs.iter().map(|&d| x[d]));
            self.solve_block(b, &mut buf);
            for (&d, &v) in dofs.iter().zip(&buf) {
                x[d] = v;
            }
        }
    }

    /// M⁻¹ b for a sparse right-hand side given as (dof, value) pairs; the result is returned
    /// as (dof, value) pairs over the blocks that b touches.
    pub(crate) fn solve_sparse(&self, rhs: &[(usize, f64)], out: &mut Vec<(usize, f64)>) {
        out.clear();
        let mut touched: Vec<usize> = rhs.iter().map(|&(d, _)| self.place[d].0).collect();
        touched.sort_unstable();
        touched.dedup();
        let mut buf = Vec::new();
        for b in touched {
            let dofs = &self.blocks[b].dofs;
            buf.clear();
            buf.resize(dofs.len(), 0.0);
            for &(d, v) in rhs {
                let (bb, k) = self.place[d];
                if bb == b {
                    buf[k] += v;
                }
            }
            self.solve_block(b, &mut buf);
            out.extend(dofs.iter().copied().zip(buf.iter().copied()));
        }
    }
}

/// Sparse LU factors of a square block.
fn lu_factor(a: &CscMatrix) -> Result<Lu<usize, f64>, String> {
    let trip: Vec<_> = a
        .triplets()
        .map(|(i, j, v)| Triplet::new(i, j, v))
        .collect();
    let mat = SparseColMat::<usize, f64>::try_new_from_triplets(a.nrows, a.ncols, &trip)
        .map_err(|e| format!("{e:?}"))?;
    let symbolic = SymbolicLu::try_new(mat.symbolic()).map_err(|e| format!("{e:?}"))?;
    Lu::try_new_with_symbolic(symbolic, mat.as_ref()).map_err(|e| format!("LU: {e:?}"))
}
