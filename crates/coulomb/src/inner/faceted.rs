//! Faceted cones (the paper's §6 option (iv)): each K_μ replaced by a pyramid with k facets, the
//! inner problem (4.7) becoming an ordinary QP, solved by Clarabel with nonnegative (and zero)
//! cones only.
//!
//! # The pyramid
//! For d = 3 and 0 < μ < ∞ the disc {‖r_T‖ ≤ μ r_N} of the cross-section is replaced by the
//! **inscribed** regular k-gon whose vertices lie at angles θ_j = 2πj/k on the circle of
//! radius μ r_N. Its facets are the half-spaces
//!
//! ```text
//!     cos φ_j r_T1 + sin φ_j r_T2 ≤ μ cos(π/k) r_N,    φ_j = (2j + 1) π / k,  j = 0..k−1,
//! ```
//!
//! passed to Clarabel as rows `A_i r_i + s = 0`, s ≥ 0. (For k ≥ 3 they imply r_N ≥ 0.)
//! For d = 2 the cone is already polyhedral: the two rows ±r_T ≤ μ r_N are exact, whatever k.
//! μ = 0 gives r_N ≥ 0, r_T = 0 and μ = ∞ gives r_N ≥ 0, exactly as in the SOC solver.
//!
//! **Why inscribed.** The inscribed pyramid K_k lies inside K_μ, so every faceted r lies in
//! L = ∏ K_{μⁱ}: the returned impulses are admissible Coulomb forces (never more friction than
//! μ allows), the objective of (4.7) at the faceted solution is an upper bound of the exact
//! optimum, and the outer loop's error measures only the complementarity defect caused by the
//! smaller cone. A circumscribed pyramid would allow r outside K_μ (up to a factor
//! 1/cos(π/k) of friction) in the maximal-friction directions.
//!
//! # Accuracy
//! The result solves the **faceted** problem, not (4.7): it approaches the exact solution only
//! as k grows (the cross-section's inscribed polygon misses the disc by a relative gap
//! 1 − cos(π/k) ≈ π²/(2k²)), and the artificial anisotropy of the pyramid remains for any
//! finite k. The outer loop reports the true error of docs/error.md, which therefore stalls at
//! a level set by k for d = 3. As for [`super::ipm::IpmSolver`], Clarabel offers no warm
//! start (the incoming r is ignored); a [`FacetedSolver`] serves one (d, W, μ) and k, its
//! setup built at the first solve and reused by the later ones.

use super::clarabel::{solve_dual_qp, triplets_to_clarabel, QpSetup};
use super::{InnerLimits, InnerProblem, InnerReport, InnerSolver};
use clarabel::algebra::CscMatrix as ClarabelCsc;
use clarabel::solver::SupportedConeT;

/// Default number of facets of each pyramid in 3-D.
pub const DEFAULT_FACETS: usize = 8;

/// Clarabel on the faceted dual QP.
#[derive(Debug)]
pub struct FacetedSolver {
    /// number of facets of each pyramid (d = 3; values below 3 are raised to 3;
    /// d = 2 is exact with 2 whatever this is)
    facets: usize,
    /// the Clarabel setup, built at the first solve and reused by the later ones (on the same
    /// (d, W, μ): only b changes)
    setup: Option<QpSetup>,
}

impl Clone for FacetedSolver {
    /// A clone starts without the Clarabel setup (it is built at its first solve).
    fn clone(&self) -> Self {
        Self::new(self.facets)
    }
}

impl Default for FacetedSolver {
    /// [`DEFAULT_FACETS`] facets.
    fn default() -> Self {
        Self::new(DEFAULT_FACETS)
    }
}

impl FacetedSolver {
    /// A faceted solver with `facets` facets per cone (d = 3; raised to 3 if smaller).
    pub fn new(facets: usize) -> Self {
        Self {
            facets,
            setup: None,
        }
    }

    /// The number of facets actually used in 3-D: max(facets, 3).
    pub fn effective_facets(&self) -> usize {
        self.facets.max(3)
    }
}

impl InnerSolver for FacetedSolver {
    fn name(&self) -> &'static str {
        "faceted"
    }

    /// Solves (4.7) with every K_{μⁱ} replaced by its inscribed k-facet pyramid (see module
    /// docs); `r` on entry is ignored.
    fn solve(
        &mut self,
        problem: &InnerProblem<'_>,
        limits: &InnerLimits,
        r: &mut [f64],
    ) -> InnerReport {
        let k = self.effective_facets();
        solve_dual_qp(&mut self.setup, 0, problem, limits, r, || {
            pyramid_constraints(problem.dim, problem.mu, k)
        })
    }
}

/// The rows A r + s = 0, s ∈ {0}ᵃ × ℝ₊ᵇ of the faceted cone product (module docs), with
/// zero rows first.
fn pyramid_constraints(
    dim: usize,
    mu: &[f64],
    facets: usize,
) -> (ClarabelCsc<f64>, Vec<SupportedConeT<f64>>) {
    // (row, col, value) of A, zero-cone rows and nonnegative rows kept apart, numbered later
    let mut zero: Vec<(usize, f64)> = Vec::new();
    let mut nonneg: Vec<Vec<(usize, f64)>> = Vec::new();
    let half = std::f64::consts::PI / facets as f64;
    for (i, &m) in mu.iter().enumerate() {
        let n = dim * i;
        if m == 0.0 {
            nonneg.push(vec![(n, -1.0)]);
            zero.extend((1..dim).map(|t| (n + t, -1.0)));
        } else if m.is_infinite() {
            nonneg.push(vec![(n, -1.0)]);
        } else if dim == 2 {
            // ±r_T ≤ μ r_N as A r + s = 0 with A = (−μ, ±1): s = μ r_N ∓ r_T ≥ 0
            nonneg.push(vec![(n, -m), (n + 1, 1.0)]);
            nonneg.push(vec![(n, -m), (n + 1, -1.0)]);
        } else {
            // s = μ cos(π/k) r_N − cos φ_j r_T1 − sin φ_j r_T2 ≥ 0
            let radius = m * half.cos();
            for j in 0..facets {
                let phi = (2 * j + 1) as f64 * half;
                nonneg.push(vec![(n, -radius), (n + 1, phi.cos()), (n + 2, phi.sin())]);
            }
        }
    }
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for (row, &(col, val)) in zero.iter().enumerate() {
        rows.push(row);
        cols.push(col);
        vals.push(val);
    }
    for (k, entries) in nonneg.iter().enumerate() {
        for &(col, val) in entries {
            rows.push(zero.len() + k);
            cols.push(col);
            vals.push(val);
        }
    }
    let nrows = zero.len() + nonneg.len();
    let a = triplets_to_clarabel(nrows, dim * mu.len(), &rows, &cols, &vals);
    let mut cones = Vec::new();
    if !zero.is_empty() {
        cones.push(SupportedConeT::ZeroConeT(zero.len()));
    }
    if !nonneg.is_empty() {
        cones.push(SupportedConeT::NonnegativeConeT(nonneg.len()));
    }
    (a, cones)
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use crate::inner::InnerStatus;
    use crate::linalg::sparse::CscMatrix;

    fn limits() -> InnerLimits {
        InnerLimits {
            tol: 1e-9,
            max_iterations: 100,
            deadline: crate::deadline::Deadline::NEVER,
        }
    }

    /// The rows of each 3-D pyramid are satisfied with equality at its vertices
    /// (1, μ cos θ_j, μ sin θ_j) by exactly two facets, and strictly by the others.
    pub fn pyramid_vertices_lie_on_the_cone() {
        let (mu, k) = (0.7, 8);
        let (a, cones) = pyramid_constraints(3, &[mu], k);
        assert_eq!(cones.len(), 1);
        let dense = CscMatrix::from_csc_arrays(a.m, a.n, &a.colptr, &a.rowval, &a.nzval)
            .expect("valid")
            .to_dense();
        for j in 0..k {
            let th = 2.0 * std::f64::consts::PI * j as f64 / k as f64;
            let v = [1.0, mu * th.cos(), mu * th.sin()];
            let mut active = 0;
            for row in 0..a.m {
                // s = −A v ≥ 0 (dense is row-major)
                let s: f64 = -(0..3).map(|c| dense[row * 3 + c] * v[c]).sum::<f64>();
                assert!(s > -1e-12);
                if s.abs() < 1e-12 {
                    active += 1;
                }
            }
            assert_eq!(active, 2);
        }
    }

    /// Sliding along a vertex direction is represented exactly: with W = I and
    /// b = (−1, −2, 0) the solution is the projection of −b onto K_μ, which lies on the
    /// edge θ = 0 of the pyramid.
    pub fn vertex_direction_is_exact() {
        let w = CscMatrix::identity(3, 1.0);
        let b = [-1.0, -2.0, 0.0];
        let mu = [0.5];
        let mut r = vec![0.0; 3];
        let rep = FacetedSolver::new(8).solve(
            &InnerProblem {
                dim: 3,
                w: &w,
                b: &b,
                mu: &mu,
            },
            &limits(),
            &mut r,
        );
        assert_eq!(rep.status, InnerStatus::Solved);
        let mut expected = [1.0, 2.0, 0.0];
        crate::cone::project(0.5, &mut expected);
        for (x, y) in r.iter().zip(expected) {
            assert!((x - y).abs() < 1e-7, "{r:?} vs {expected:?}");
        }
    }
}
