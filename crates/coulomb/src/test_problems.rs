//! Deterministic problem builders shared by the unit tests of several modules (test builds
//! only).

use crate::linalg::sparse::CscMatrix;
use crate::problem::{GlobalProblem, LocalProblem};

/// Deterministic pseudo-random numbers in [−1, 1) (a linear congruential generator; the
/// stream is fixed by `seed` and `salt`), for the tests' problem builders.
pub(crate) fn uniform(seed: u64, salt: u64) -> impl FnMut() -> f64 {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(salt);
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// A deterministic pseudo-random local problem: W = AᵀA (+ `delta` I), A with m/2 rows
/// (rank-deficient when δ = 0), μ in [0.3, 1]; `skew` adds a small antisymmetric part to W
/// (as stored in real files).
pub(crate) fn problem(contacts: usize, seed: u64, delta: f64, skew: f64) -> LocalProblem {
    let mut next = uniform(seed, 1);
    let m = 3 * contacts;
    let k = m / 2;
    let a: Vec<f64> = (0..k * m).map(|_| next()).collect();
    let mut w = vec![0.0; m * m];
    for i in 0..m {
        for j in 0..m {
            w[i * m + j] = (0..k).map(|l| a[l * m + i] * a[l * m + j]).sum::<f64>()
                + if i == j { delta } else { 0.0 }
                + skew * (i as f64 - j as f64) / m as f64;
        }
    }
    LocalProblem {
        dim: 3,
        w: CscMatrix::from_dense(m, m, &w),
        q: (0..m).map(|_| next()).collect(),
        mu: (0..contacts).map(|_| 0.3 + 0.7 * next().abs()).collect(),
    }
}

/// A ball (3 translational dofs, mass 2) pressed onto the floor (free velocity
/// (1, 0, −1)), contact normal z, tangents x, y, μ = 0.3, its x velocity held at 0.5 by
/// `rows` copies of the constraint v_x − 0.5 = 0 (G = e_x, b = −0.5), or with b given.
pub(crate) fn equality_ball(rows: usize, b: Option<Vec<f64>>) -> GlobalProblem {
    let m = CscMatrix::identity(3, 2.0);
    let h = CscMatrix::from_dense(3, 3, &[0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0]);
    let f = vec![2.0, 0.0, -2.0];
    let g = CscMatrix::from_dense(
        3,
        rows,
        &(0..3 * rows)
            .map(|k| if k < rows { 1.0 } else { 0.0 })
            .collect::<Vec<_>>(),
    );
    let b = b.unwrap_or(vec![-0.5; rows]);
    GlobalProblem::new(3, m, h, f, vec![0.0; 3], vec![0.3])
        .unwrap()
        .with_equality(g, b)
        .unwrap()
}
