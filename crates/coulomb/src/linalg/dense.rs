//! Dense LU factorizations with partial pivoting of the small Newton systems of rigid
//! problems — the Schur complement M + H G⁻¹ Hᵀ ([`crate::barrier`]), A + R G⁻¹ C of a skeleton
//! ([`crate::linalg::skeleton`]), J = M + H B Hᵀ of the method of multipliers ([`crate::multiplier`]) —
//! on as many threads as their size pays for.
//!
//! faer's `PartialPivLu` always runs on faer's global parallelism; this type calls faer's
//! factorization and triangular solves with a parallelism chosen per matrix instead
//! ([`parallelism`]), without touching the global setting, which belongs to the application.
//! Measured (`cargo bench -p coulomb-bench --bench dense_lu`, 2 cores): on all threads a factor
//! and solve takes 4.8× as long as on one at n = 100, 2.3× at n = 384, 1.13× at 1 000, and
//! 0.93× at 1 500, 0.78× at 3 000; the box piles of the corpus spend most of their time in
//! such systems of size 100–400, where the threads' synchronisation costs more than it
//! saves.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::{Mat, MatMut, Par};

/// The parallelism for a dense factorization of size `n`: one thread below `parallel_dim`
/// ([`crate::settings::BarrierParams::dense_parallel_dim`]), all of rayon's from there on.
pub fn parallelism(n: usize, parallel_dim: usize) -> Par {
    if n >= parallel_dim {
        Par::rayon(0)
    } else {
        Par::Seq
    }
}

/// P A = L U of a square A (L unit lower and U upper, stored in one matrix).
pub struct Lu {
    lu: Mat<f64>,
    fwd: Vec<usize>,
    bwd: Vec<usize>,
    par: Par,
}

impl Lu {
    /// Factors the square matrix `a` (consumed) with parallelism `par`. The factorization of a
    /// singular or non-finite matrix completes; its solves then give non-finite entries,
    /// which the callers test for. `a` that is not square gives None.
    pub fn new(mut a: Mat<f64>, par: Par) -> Option<Self> {
        let n = a.nrows();
        if a.ncols() != n {
            return None;
        }
        let mut fwd = vec![0usize; n];
        let mut bwd = vec![0usize; n];
        let mut mem = MemBuffer::new(factor::lu_in_place_scratch::<usize, f64>(
            n,
            n,
            par,
            Default::default(),
        ));
        factor::lu_in_place(
            a.as_mut(),
            &mut fwd,
            &mut bwd,
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        Some(Self {
            lu: a,
            fwd,
            bwd,
            par,
        })
    }

    /// The storage of the factors, to be filled with the next matrix of the same size and
    /// factored by [`Lu::new`] without a new allocation.
    pub fn into_matrix(self) -> Mat<f64> {
        self.lu
    }

    /// The size n.
    pub fn dim(&self) -> usize {
        self.lu.nrows()
    }

    /// x = A⁻¹ b in place for the n-vector `rhs`; false (and nothing changed) if its length is
    /// not n.
    pub fn solve_in_place(&self, rhs: &mut [f64]) -> bool {
        let n = self.dim();
        if rhs.len() != n {
            return false;
        }
        self.solve_columns(MatMut::from_column_major_slice_mut(rhs, n, 1));
        true
    }

    /// X = A⁻¹ B in place for the n × k matrix `rhs` (its row count is checked by faer).
    fn solve_columns(&self, rhs: MatMut<'_, f64>) {
        let n = self.dim();
        // `fwd` and `bwd` are the inverse permutations that `lu_in_place` wrote (checked, O(n))
        let perm = faer::perm::PermRef::new_checked(&self.fwd, &self.bwd, n);
        let mut mem = MemBuffer::new(solve::solve_in_place_scratch::<usize, f64>(
            n,
            rhs.ncols(),
            self.par,
        ));
        solve::solve_in_place_with_conj(
            self.lu.as_ref(),
            self.lu.as_ref(),
            perm,
            faer::Conj::No,
            rhs,
            self.par,
            MemStack::new(&mut mem),
        );
    }
}

/// Ridge added to the normal equations of [`least_squares`], relative to their trace (a
/// numerical safeguard of a k × k solve, k ≤ memory, not a tuning parameter).
const RIDGE: f64 = 1e-10;

/// A pivot of at most this fraction of the trace makes [`least_squares`] give up (the
/// differences are numerically dependent; the step is then the plain fixed point).
const PIVOT: f64 = 1e-14;

/// γ = argmin ‖g − Σ γⱼ aⱼ‖ by the normal equations with a small ridge (k ≤ 10 columns);
/// None if the system is singular or the coefficients are huge.
pub fn least_squares(a: &[Vec<f64>], g: &[f64]) -> Option<Vec<f64>> {
    let k = a.len();
    if k == 0 {
        return Some(Vec::new());
    }
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    let mut n = vec![0.0; k * k];
    let mut rhs = vec![0.0; k];
    for i in 0..k {
        for j in 0..=i {
            let v = dot(&a[i], &a[j]);
            n[i * k + j] = v;
            n[j * k + i] = v;
        }
        rhs[i] = dot(&a[i], g);
    }
    let trace: f64 = (0..k).map(|i| n[i * k + i]).sum();
    if trace.is_nan() || trace <= 0.0 {
        return None;
    }
    for i in 0..k {
        n[i * k + i] += RIDGE * trace;
    }
    // Gaussian elimination with partial pivoting
    for c in 0..k {
        let p = (c..k).max_by(|&x, &y| n[x * k + c].abs().total_cmp(&n[y * k + c].abs()))?;
        if n[p * k + c].abs() <= PIVOT * trace {
            return None;
        }
        if p != c {
            for j in 0..k {
                n.swap(c * k + j, p * k + j);
            }
            rhs.swap(c, p);
        }
        for row in c + 1..k {
            let f = n[row * k + c] / n[c * k + c];
            for j in c..k {
                n[row * k + j] -= f * n[c * k + j];
            }
            rhs[row] -= f * rhs[c];
        }
    }
    let mut x = vec![0.0; k];
    for c in (0..k).rev() {
        let s: f64 = (c + 1..k).map(|j| n[c * k + j] * x[j]).sum();
        x[c] = (rhs[c] - s) / n[c * k + c];
    }
    (x.iter().all(|v| v.is_finite() && v.abs() < 1e4)).then_some(x)
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    /// A well-conditioned non-symmetric matrix that needs pivoting (zero first diagonal).
    fn matrix(n: usize) -> Mat<f64> {
        Mat::from_fn(n, n, |i, j| {
            if i == j {
                if i == 0 {
                    0.0
                } else {
                    4.0 + i as f64
                }
            } else {
                ((3 * i + 5 * j) % 7) as f64 / 7.0 - 0.3
            }
        })
    }

    /// max |A⁻¹ b − x| for the LU of A and b = A x (the solve must succeed).
    fn solve_error(lu: &Lu, b: &[f64], x: &[f64]) -> f64 {
        let mut y = b.to_vec();
        assert!(lu.solve_in_place(&mut y));
        y.iter()
            .zip(x)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max)
    }

    pub fn solves_on_one_thread_and_on_all_to_the_same_answer() {
        for n in [1, 2, 7, 40] {
            let a = matrix(n);
            let x: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 * 0.25).collect();
            let b: Vec<f64> = (0..n)
                .map(|i| (0..n).map(|j| a[(i, j)] * x[j]).sum())
                .collect();
            for par in [Par::Seq, Par::rayon(2)] {
                let lu = Lu::new(a.clone(), par).expect("square");
                let err = solve_error(&lu, &b, &x);
                assert!(err < 1e-12, "n {n} {par:?}: error {err}");
            }
        }
    }

    pub fn bad_shapes_give_none_or_false_and_singular_gives_non_finite() {
        assert!(Lu::new(Mat::zeros(2, 3), Par::Seq).is_none());
        let lu = Lu::new(matrix(3), Par::Seq).expect("square");
        let mut short = vec![1.0; 2];
        assert!(!lu.solve_in_place(&mut short));
        assert_eq!(short, vec![1.0; 2]);
        let singular = Lu::new(Mat::zeros(3, 3), Par::Seq).expect("square");
        let mut b = vec![1.0; 3];
        assert!(singular.solve_in_place(&mut b));
        assert!(b.iter().any(|x| !x.is_finite()));
    }

    pub fn the_storage_of_factors_takes_the_next_matrix() {
        // factor A, take the storage back, fill it with 2 A + I and factor again: the solve
        // is that of the new matrix
        let n = 7;
        let a = matrix(n);
        let lu = Lu::new(a.clone(), Par::Seq).expect("square");
        let mut storage = lu.into_matrix();
        assert_eq!((storage.nrows(), storage.ncols()), (n, n));
        for j in 0..n {
            for i in 0..n {
                storage[(i, j)] = 2.0 * a[(i, j)] + if i == j { 1.0 } else { 0.0 };
            }
        }
        let x: Vec<f64> = (0..n).map(|i| 0.5 - i as f64).collect();
        let b: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| 2.0 * a[(i, j)] * x[j]).sum::<f64>() + x[i])
            .collect();
        let lu = Lu::new(storage, Par::Seq).expect("square");
        let err = solve_error(&lu, &b, &x);
        assert!(err < 1e-12, "error {err}");
    }

    pub fn the_parallelism_follows_the_size() {
        assert_eq!(parallelism(100, 1500), Par::Seq);
        assert_eq!(parallelism(1500, 1500), Par::rayon(0));
    }
}
