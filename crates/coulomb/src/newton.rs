//! Semismooth Newton on the natural map of Coulomb's law.
//!
//! With ũ = u + μ‖u_T‖e the De Saxcé velocity (3.7), Coulomb's law (2.9) at contact i is the
//! complementarity K_μ ∋ rⁱ ⊥ ũⁱ ∈ K_μ* (Lemma 3.1, (3.9)), i.e. the zero of the natural map
//!
//! ```text
//!     Gⁱ(r) = rⁱ − P_{K_μ}(rⁱ − ũⁱ),      u = W r + q,
//! ```
//!
//! whose norm, divided by max(‖q‖, ‖r‖, ‖u‖), is exactly the error of docs/error.md. This
//! module drives ‖G‖ to zero by semismooth Newton steps with a backtracking line search on ‖G‖:
//! the generalized Jacobian is
//!
//! ```text
//!     J = I − D + D A W,     D = blockdiag ∂P_{K_μ}(rⁱ − ũⁱ),
//!     A = blockdiag ∂ũⁱ/∂uⁱ = [1  μ û_Tᵀ; 0  I],  û_T = u_T / ‖u_T‖,
//! ```
//!
//! solved by faer's sparse LU with a diagonal shift λ I that vanishes with ‖G‖ (and grows when
//! a direction gives no descent, as happens when J is singular: sticking contacts and more
//! contact unknowns than degrees of freedom). It is
//! the end game of [`crate::solver`]: the fixed point s = F(s) of §3.3 converges linearly, a
//! Newton step from an r with error ~1e-5 converges quadratically. The same pieces
//! (projection Jacobian, sparse LU) polish the interior-point solutions of the inner
//! problems (3.15) and (4.7) in [`crate::inner::ipm`].

use crate::deadline::Deadline;
use crate::natural_map::de_saxce_map;
use crate::problem::LocalProblem;
use crate::sparse::CscMatrix;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
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
/// W in block (i, j), and its symbolic LU factorization, computed once per [`polish`] call
/// (the values change at every step, the pattern does not).
struct JacobianPattern {
    dim: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// for each contact (block column), the contacts of its block rows, ascending
    neighbors: Vec<Vec<usize>>,
    /// position of each diagonal entry in `row_idx`
    diagonal: Vec<usize>,
    symbolic: SymbolicLu<usize>,
}

impl JacobianPattern {
    fn new(p: &LocalProblem) -> Option<Self> {
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
        let sym = SymbolicSparseColMatRef::new_checked(m, m, &col_ptr, None, &row_idx);
        let symbolic = SymbolicLu::try_new(sym).ok()?;
        Some(Self {
            dim: d,
            col_ptr,
            row_idx,
            neighbors,
            diagonal,
            symbolic,
        })
    }

    /// The values of J = I − D + B W on the pattern (B = D A), column by column.
    fn fill(
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

    fn shift_diagonal(&self, vals: &mut [f64], lambda: f64) {
        for &k in &self.diagonal {
            vals[k] += lambda;
        }
    }

    /// Solves (J + λ I) x = rhs in place by LU with the cached symbolic factorization; None
    /// if the factorization fails or x is not finite.
    fn solve(&self, vals: &[f64], rhs: &mut [f64]) -> Option<()> {
        let n = rhs.len();
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let mat = SparseColMatRef::new(sym, vals);
        let lu = Lu::try_new_with_symbolic(self.symbolic.clone(), mat).ok()?;
        lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(rhs, n, 1));
        rhs.iter().all(|x| x.is_finite()).then_some(())
    }
}

/// Consecutive slow steps (‖G‖ reduced by less than 1 − [`SLOW_RATIO`]) after which
/// [`polish`] gives up.
pub const SLOW_STEPS: usize = 4;

/// The first shift of a step is λ = `LAMBDA_FACTOR` · (‖G‖ / ‖q‖) · max diag(W): small enough
/// to keep the quadratic convergence of the exact step where J is regular, large enough to
/// give a direction where it is singular (tuned on the FCLIB problems of ../shared/fclib).
pub const LAMBDA_FACTOR: f64 = 1e-2;

/// A step with ‖G⁺‖ > `SLOW_RATIO` ‖G‖ counts as slow.
pub const SLOW_RATIO: f64 = 0.9;

/// Why [`polish`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewtonStatus {
    /// ‖G(r)‖ ≤ `target`
    Reached,
    /// the step cap was reached above the target
    MaxSteps,
    /// no step along the Newton direction decreased ‖G‖ (or the linear solve failed)
    NoDescent,
    /// [`SLOW_STEPS`] steps in a row were slow: far from the region of fast convergence
    Slow,
    /// the deadline passed
    TimeLimit,
}

/// The outcome of [`polish`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonReport {
    /// how it stopped
    pub status: NewtonStatus,
    /// Newton steps taken (accepted)
    pub steps: usize,
    /// ‖G(r)‖ at the returned r
    pub residual: f64,
}

/// ‖G(r)‖ of the De Saxcé natural map of `p` at r ([`de_saxce_map`] with u = W r + q; G, D
/// and B = D A written as there).
fn de_saxce_map_norm(
    p: &LocalProblem,
    r: &[f64],
    g: &mut [f64],
    dblocks: &mut [f64],
    blocks: &mut [f64],
) -> f64 {
    let mut u = p.q.clone();
    p.w.gemv_acc(1.0, r, &mut u);
    de_saxce_map(p.dim, &p.mu, r, &u, g, dblocks, blocks);
    crate::law::norm(g)
}

/// Semismooth Newton on G(r) = r − P_L(r − ũ(W r + q)) from `r` (overwritten by the best
/// iterate): at most `max_steps` steps, each a direction from (J + λ I) δ = −G followed by a
/// backtracking line search that accepts the first t ∈ {1, ½, ¼, …} (≥ 2⁻¹⁰) with
/// ‖G(r + t δ)‖ ≤ (1 − 10⁻⁴ t) ‖G(r)‖. Stops once ‖G‖ ≤ `target`, when no step decreases ‖G‖,
/// after [`SLOW_STEPS`] slow steps in a row, or at `deadline`. A problem whose sizes disagree
/// (d, μ, q, W, r) takes no step (`NoDescent`, residual NaN).
pub fn polish(
    p: &LocalProblem,
    r: &mut [f64],
    target: f64,
    max_steps: usize,
    deadline: Deadline,
) -> NewtonReport {
    let (d, m) = (p.dim, r.len());
    let consistent = (d == 2 || d == 3)
        && m == p.mu.len() * d
        && p.q.len() == m
        && p.w.nrows == m
        && p.w.ncols == m
        && p.w.check().is_ok();
    if !consistent {
        // inconsistent sizes (a hand-built problem that skipped validation): no step is taken
        return NewtonReport {
            status: NewtonStatus::NoDescent,
            steps: 0,
            residual: f64::NAN,
        };
    }
    let mut g = vec![0.0; m];
    let mut blocks = vec![0.0; p.mu.len() * d * d];
    let mut dblocks = blocks.clone();
    let mut norm = de_saxce_map_norm(p, r, &mut g, &mut dblocks, &mut blocks);
    let mut trial = vec![0.0; m];
    let mut g_trial = vec![0.0; m];
    let mut blocks_trial = vec![0.0; blocks.len()];
    let mut dblocks_trial = blocks_trial.clone();
    let diag_scale = (0..m)
        .map(|j| {
            (p.w.col_ptr[j]..p.w.col_ptr[j + 1])
                .filter(|&k| p.w.row_idx[k] == j)
                .map(|k| p.w.values[k].abs())
                .sum::<f64>()
        })
        .fold(0.0f64, f64::max)
        .max(1.0);
    let q_scale = crate::law::norm(&p.q).max(f64::MIN_POSITIVE);
    let Some(pattern) = JacobianPattern::new(p) else {
        return NewtonReport {
            status: NewtonStatus::NoDescent,
            steps: 0,
            residual: norm,
        };
    };
    let mut vals = Vec::new();
    let mut wcol = vec![0.0; m];
    let mut steps = 0;
    let mut slow_steps = 0;
    let status = loop {
        if !norm.is_finite() {
            break NewtonStatus::NoDescent;
        }
        if norm <= target {
            break NewtonStatus::Reached;
        }
        if steps >= max_steps {
            break NewtonStatus::MaxSteps;
        }
        if deadline.passed() {
            break NewtonStatus::TimeLimit;
        }
        // J + λ I with J = I − D + (D A) W; λ starts at a fraction of the relative residual (a regularized
        // semismooth Newton step, exact in the limit) and grows a hundredfold whenever the
        // direction gives no descent: a singular J (more contact unknowns than degrees of
        // freedom) then still yields a Levenberg–Marquardt-like direction.
        pattern.fill(p, &dblocks, &blocks, &mut wcol, &mut vals);
        let before = norm;
        let mut lambda = LAMBDA_FACTOR * (norm / q_scale).min(1e-2) * diag_scale;
        let mut accepted = false;
        for _ in 0..4 {
            if deadline.passed() {
                break;
            }
            let mut shifted = vals.clone();
            pattern.shift_diagonal(&mut shifted, lambda);
            let mut delta: Vec<f64> = g.iter().map(|x| -x).collect();
            if pattern.solve(&shifted, &mut delta).is_some() {
                let mut t = 1.0;
                for _ in 0..=10 {
                    for k in 0..m {
                        trial[k] = r[k] + t * delta[k];
                    }
                    let n_trial = de_saxce_map_norm(
                        p,
                        &trial,
                        &mut g_trial,
                        &mut dblocks_trial,
                        &mut blocks_trial,
                    );
                    if n_trial.is_finite() && n_trial <= (1.0 - 1e-4 * t) * norm {
                        r.copy_from_slice(&trial);
                        std::mem::swap(&mut g, &mut g_trial);
                        std::mem::swap(&mut blocks, &mut blocks_trial);
                        std::mem::swap(&mut dblocks, &mut dblocks_trial);
                        norm = n_trial;
                        accepted = true;
                        break;
                    }
                    t *= 0.5;
                }
            }
            if accepted {
                break;
            }
            lambda = (lambda * 100.0).max(1e-10 * diag_scale);
        }
        if !accepted {
            if deadline.passed() {
                break NewtonStatus::TimeLimit;
            }
            break NewtonStatus::NoDescent;
        }
        steps += 1;
        slow_steps = if norm > SLOW_RATIO * before {
            slow_steps + 1
        } else {
            0
        };
        if slow_steps >= SLOW_STEPS && norm > target {
            break NewtonStatus::Slow;
        }
    };
    NewtonReport {
        status,
        steps,
        residual: norm,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::natural_map::{push_d_times, push_identity_minus_d};
    use crate::sparse::CscMatrix;

    /// A deterministic pseudo-random local problem with W = AᵀA + δI (d = 3).
    fn problem(contacts: usize, seed: u64, delta: f64) -> LocalProblem {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let m = 3 * contacts;
        let k = m.saturating_sub(2).max(1);
        let a: Vec<f64> = (0..k * m).map(|_| next()).collect();
        let mut w = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                w[i * m + j] = (0..k).map(|l| a[l * m + i] * a[l * m + j]).sum::<f64>()
                    + if i == j { delta } else { 0.0 };
            }
        }
        LocalProblem {
            dim: 3,
            w: CscMatrix::from_dense(m, m, &w),
            q: (0..m).map(|_| next()).collect(),
            mu: (0..contacts).map(|_| 0.2 + 0.5 * next().abs()).collect(),
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let p = problem(4, 7, 0.1);
        let m = 12;
        for trial in 0..20u64 {
            let r: Vec<f64> = (0..m)
                .map(|k| ((k as f64 + 1.0) * (trial as f64 + 0.37)).sin())
                .collect();
            let dir: Vec<f64> = (0..m).map(|k| ((k * 7 + 3) as f64).cos()).collect();
            let mut g = vec![0.0; m];
            let mut db = vec![0.0; 36];
            let mut b = vec![0.0; 36];
            de_saxce_map_norm(&p, &r, &mut g, &mut db, &mut b);
            let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
            push_identity_minus_d(3, &db, 0, &mut rows, &mut cols, &mut vals);
            push_d_times(
                3,
                &b,
                1.0,
                p.w.triplets(),
                0,
                &mut rows,
                &mut cols,
                &mut vals,
            );
            let j = CscMatrix::from_triplets(m, m, &rows, &cols, &vals).unwrap();
            let jd = j.mul_vec(&dir);
            let eps = 1e-7;
            let rp: Vec<f64> = r.iter().zip(&dir).map(|(x, d)| x + eps * d).collect();
            let mut gp = vec![0.0; m];
            de_saxce_map_norm(&p, &rp, &mut gp, &mut db, &mut b);
            for k in 0..m {
                let fd = (gp[k] - g[k]) / eps;
                assert!(
                    (fd - jd[k]).abs() <= 1e-4 * (1.0 + fd.abs()),
                    "trial {trial} row {k}: J δ = {} but finite difference {fd}",
                    jd[k]
                );
            }
        }
    }

    #[test]
    fn inconsistent_sizes_take_no_step_instead_of_panicking() {
        let mut p = problem(2, 1, 0.5);
        p.mu.push(0.3); // three friction coefficients for two contacts
        let mut r = vec![0.0; 6];
        let out = polish(&p, &mut r, 0.0, 5, Deadline::NEVER);
        assert_eq!((out.status, out.steps), (NewtonStatus::NoDescent, 0));
        assert!(r.iter().all(|&x| x == 0.0));
        let p = problem(2, 1, 0.5);
        let mut short = vec![0.0; 5];
        assert_eq!(polish(&p, &mut short, 0.0, 5, Deadline::NEVER).steps, 0);
    }

    #[test]
    fn newton_reaches_rounding_level_from_a_rough_point() {
        let p = problem(5, 3, 0.5);
        let mut r = vec![0.0; 15];
        let out = polish(&p, &mut r, 0.0, 50, Deadline::NEVER);
        let u = p.velocity(&r);
        let err = crate::law::error_measure(3, &p.mu, &r, &u, crate::law::norm(&p.q)).error;
        assert!(err < 1e-12, "error {err:.3e} after {out:?}");
    }
}
