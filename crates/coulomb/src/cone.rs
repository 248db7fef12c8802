//! The second-order (Coulomb) cone K_{e,μ} of (3.2)–(3.3), its dual K_{e,1/μ} and the
//! Euclidean projections onto both.
//!
//! Vectors are local contact vectors ordered normal first: x = (x_N, x_T), so e is the first
//! basis vector. The same code serves d = 2 and d = 3 (and any d ≥ 1).

/// Norm of the tangential part x_T = (x₁, …, x_{d−1}).
#[inline]
pub fn tangent_norm(x: &[f64]) -> f64 {
    x[1..].iter().map(|t| t * t).sum::<f64>().sqrt()
}

/// Whether x ∈ K_μ = {‖x_T‖ ≤ μ x_N} (μ ∈ [0, ∞]), with an absolute slack `tol`.
pub fn contains(mu: f64, x: &[f64], tol: f64) -> bool {
    let t = tangent_norm(x);
    if mu.is_infinite() {
        x[0] >= -tol
    } else {
        t <= mu * x[0] + tol && x[0] >= -tol
    }
}

/// Projects x in place onto K_μ (3.2), with the extreme cases (3.3): μ = 0 gives the
/// half-line {x_T = 0, x_N ≥ 0}, μ = ∞ the half-space {x_N ≥ 0}.
///
/// For 0 < μ < ∞: x if ‖x_T‖ ≤ μ x_N; 0 if μ‖x_T‖ ≤ −x_N; otherwise
/// a = (x_N + μ‖x_T‖)/(1 + μ²) and the projection is (a, μ a x_T/‖x_T‖).
#[inline]
pub fn project(mu: f64, x: &mut [f64]) {
    if mu.is_infinite() {
        x[0] = x[0].max(0.0);
        return;
    }
    let n = x[0];
    let t = tangent_norm(x);
    // n ≥ 0 too: with μ = 0 and x_T = 0, t ≤ μ n reads 0 ≤ −0 for every n < 0
    if t <= mu * n && n >= 0.0 {
        return;
    }
    if mu * t <= -n {
        x.iter_mut().for_each(|v| *v = 0.0);
        return;
    }
    let a = (n + mu * t) / (1.0 + mu * mu);
    x[0] = a;
    let scale = if t > 0.0 { mu * a / t } else { 0.0 };
    x[1..].iter_mut().for_each(|v| *v *= scale);
}

/// Projects x in place onto the dual cone K_μ* = K_{1/μ} (with 1/0 = ∞ and 1/∞ = 0).
#[inline]
pub fn project_dual(mu: f64, x: &mut [f64]) {
    project(dual_coefficient(mu), x);
}

/// The coefficient 1/μ of the dual cone, with the conventions 1/0 = ∞ and 1/∞ = 0.
#[inline]
pub fn dual_coefficient(mu: f64) -> f64 {
    if mu == 0.0 {
        f64::INFINITY
    } else if mu.is_infinite() {
        0.0
    } else {
        1.0 / mu
    }
}

/// Projects every d-block of `x` onto its own K_{μⁱ}: the projection onto L = ∏ K_{μⁱ}.
pub fn project_product(dim: usize, mu: &[f64], x: &mut [f64]) {
    for (xi, &m) in x.chunks_exact_mut(dim).zip(mu) {
        project(m, xi);
    }
}

/// Projects every d-block of `x` onto K_{μⁱ}* : the projection onto L* (3.12).
pub fn project_product_dual(dim: usize, mu: &[f64], x: &mut [f64]) {
    for (xi, &m) in x.chunks_exact_mut(dim).zip(mu) {
        project_dual(m, xi);
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use proptest::prelude::*;

    fn dot(a: &[f64], b: &[f64]) -> f64 {
        a.iter().zip(b).map(|(x, y)| x * y).sum()
    }
    fn dist(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt()
    }
    fn mu_strategy() -> impl Strategy<Value = f64> {
        prop_oneof![Just(0.0), Just(f64::INFINITY), 0.01f64..5.0]
    }
    fn vec_strategy() -> impl Strategy<Value = Vec<f64>> {
        prop_oneof![
            proptest::collection::vec(-10.0f64..10.0, 2),
            proptest::collection::vec(-10.0f64..10.0, 3)
        ]
    }

    pub fn known_projections() {
        let mut x = [-1.0, 0.5, 0.0];
        project(1.0, &mut x);
        assert_eq!(x, [0.0, 0.0, 0.0]);
        let mut x = [0.0, 2.0];
        project(1.0, &mut x);
        assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
        let mut x = [-3.0, 2.0];
        project(f64::INFINITY, &mut x);
        assert_eq!(x, [0.0, 2.0]);
        let mut x = [3.0, 2.0, -1.0];
        project(0.0, &mut x);
        assert_eq!(x, [3.0, 0.0, 0.0]);
        let mut x = [3.0, 2.0, -1.0];
        project_dual(0.0, &mut x);
        assert_eq!(x, [3.0, 2.0, -1.0]);
    }

    proptest! {
        fn prop_projection_is_idempotent_and_in_cone(mu in mu_strategy(), x in vec_strategy()) {
            let mut p = x.clone();
            project(mu, &mut p);
            prop_assert!(contains(mu, &p, 1e-9));
            let mut pp = p.clone();
            project(mu, &mut pp);
            prop_assert!(dist(&p, &pp) <= 1e-12 * (1.0 + dot(&p, &p).sqrt()));
        }

        fn prop_projection_is_nonexpansive(mu in mu_strategy(), x in proptest::collection::vec(-10.0f64..10.0, 3), y in proptest::collection::vec(-10.0f64..10.0, 3)) {
            let (mut px, mut py) = (x.clone(), y.clone());
            project(mu, &mut px);
            project(mu, &mut py);
            prop_assert!(dist(&px, &py) <= dist(&x, &y) + 1e-12);
            let (mut dx, mut dy) = (x.clone(), y.clone());
            project_dual(mu, &mut dx);
            project_dual(mu, &mut dy);
            prop_assert!(dist(&dx, &dy) <= dist(&x, &y) + 1e-12);
        }

        /// Moreau: x = P_K(x) − P_{K*}(−x), the two parts orthogonal.
        fn prop_moreau_decomposition(mu in mu_strategy(), x in vec_strategy()) {
            let mut p = x.clone();
            project(mu, &mut p);
            let mut d: Vec<f64> = x.iter().map(|v| -v).collect();
            project_dual(mu, &mut d);
            let recomposed: Vec<f64> = p.iter().zip(&d).map(|(a, b)| a - b).collect();
            prop_assert!(dist(&recomposed, &x) <= 1e-9 * (1.0 + dot(&x, &x).sqrt()));
            prop_assert!(dot(&p, &d).abs() <= 1e-9 * (1.0 + dot(&x, &x)));
        }
    }

    // proptest! writes private functions: the tests are these, which run them
    pub fn projection_is_idempotent_and_in_cone() {
        prop_projection_is_idempotent_and_in_cone()
    }

    pub fn projection_is_nonexpansive() {
        prop_projection_is_nonexpansive()
    }

    pub fn moreau_decomposition() {
        prop_moreau_decomposition()
    }
}
