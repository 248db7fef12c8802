//! Coulomb's law (2.9) at one contact, the De Saxcé change (3.7), per-contact status and the
//! error measure every result is reported in (the natural map with ρ = 1).
//!
//! Local vectors are ordered normal first: u = (u_N, u_T), r = (r_N, r_T).

use crate::cone;
use serde::Serialize;

/// De Saxcé's change (3.7): ũ = u + μ‖u_T‖ e, written into `out`.
#[inline]
pub fn de_saxce(mu: f64, u: &[f64], out: &mut [f64]) {
    out.copy_from_slice(u);
    out[0] += mu * cone::tangent_norm(u);
}

/// Applies (3.7) to every d-block of `u`: the whole-problem ũ = u + E s with s = ‖u_T‖.
pub fn de_saxce_all(dim: usize, mu: &[f64], u: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; u.len()];
    for ((ui, oi), &m) in u.chunks_exact(dim).zip(out.chunks_exact_mut(dim)).zip(mu) {
        de_saxce(m, ui, oi);
    }
    out
}

/// The three branches of Coulomb's law (2.9), as read off a pair (u, r).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactStatus {
    /// r = 0 and u_N ≥ 0.
    TakeOff,
    /// u = 0 and r ∈ K_μ.
    Stick,
    /// u_N = 0, ‖r_T‖ = μ r_N > 0 and r_T = −α u_T with α > 0.
    Slide,
    /// (u, r) is in none of the three branches within the tolerance.
    Violated,
}

/// Classifies one contact with absolute tolerance `tol` on velocities and impulses.
pub fn status(mu: f64, u: &[f64], r: &[f64], tol: f64) -> ContactStatus {
    let rn = cone::tangent_norm(r).hypot(r[0]);
    let un = cone::tangent_norm(u).hypot(u[0]);
    let r_in_cone = cone::contains(mu, r, tol);
    if rn <= tol && u[0] >= -tol {
        return ContactStatus::TakeOff;
    }
    if un <= tol && r_in_cone {
        return ContactStatus::Stick;
    }
    let ut = cone::tangent_norm(u);
    let rt = cone::tangent_norm(r);
    if u[0].abs() <= tol && r_in_cone && (rt - mu * r[0]).abs() <= tol * (1.0 + mu) && ut > tol {
        // r_T must point against u_T: r_T + (‖r_T‖/‖u_T‖) u_T ≈ 0.
        let alpha = rt / ut;
        let dev: f64 = r[1..]
            .iter()
            .zip(&u[1..])
            .map(|(a, b)| (a + alpha * b).powi(2))
            .sum::<f64>()
            .sqrt();
        if dev <= tol * (1.0 + rt) {
            return ContactStatus::Slide;
        }
    }
    ContactStatus::Violated
}

/// The natural-map residual of one contact: eᵢ = r − P_{K_μ}(r − ũ) with ũ = (u_N + μ‖u_T‖, u_T).
/// Returns ‖eᵢ‖²; eᵢ = 0 exactly when (u, r) satisfies (2.9) (Lemma 3.1).
#[inline]
pub fn contact_residual_sq(mu: f64, u: &[f64], r: &[f64]) -> f64 {
    debug_assert!(u.len() == r.len() && u.len() <= 3);
    let mut x = [0.0; 3];
    let d = u.len();
    let ut = cone::tangent_norm(u);
    for k in 0..d {
        x[k] = r[k] - u[k];
    }
    x[0] -= mu * ut;
    cone::project(mu, &mut x[..d]);
    (0..d).map(|k| (r[k] - x[k]).powi(2)).sum()
}

/// The error measure of `docs/error.md`, split into its parts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ErrorMeasure {
    /// sqrt(Σᵢ ‖eᵢ‖²)
    pub absolute: f64,
    /// max(‖q‖, ‖r‖, ‖u‖)
    pub scale: f64,
    /// absolute / scale when scale > ε, else absolute: the number that is reported and compared
    pub error: f64,
}

/// Computes the error measure from (r, u), the friction coefficients and ‖q‖. The caller is
/// responsible for u being recomputed from the problem data (u = W r + q or u = Hᵀ v + w).
pub fn error_measure(dim: usize, mu: &[f64], r: &[f64], u: &[f64], q_norm: f64) -> ErrorMeasure {
    let mut sum = 0.0;
    for ((ri, ui), &m) in r.chunks_exact(dim).zip(u.chunks_exact(dim)).zip(mu) {
        sum += contact_residual_sq(m, ui, ri);
    }
    let absolute = sum.sqrt();
    let scale = q_norm.max(norm(r)).max(norm(u));
    let error = if scale > f64::EPSILON {
        absolute / scale
    } else {
        absolute
    };
    ErrorMeasure {
        absolute,
        scale,
        error,
    }
}

/// Euclidean norm.
#[inline]
pub fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn dot(a: &[f64], b: &[f64]) -> f64 {
        a.iter().zip(b).map(|(x, y)| x * y).sum()
    }

    /// Lemma 3.1's conic complementarity K* ∋ ũ ⊥ r ∈ K, checked with tolerance.
    fn lemma31(mu: f64, u: &[f64], r: &[f64]) -> bool {
        let mut ut = vec![0.0; u.len()];
        de_saxce(mu, u, &mut ut);
        let scale = 1.0 + norm(u) * norm(r);
        cone::contains(mu, r, 1e-9)
            && cone::contains(cone::dual_coefficient(mu), &ut, 1e-9)
            && dot(&ut, r).abs() <= 1e-9 * scale
    }

    /// A random pair from one branch of (2.9): 0 take-off, 1 stick, 2 slide.
    fn pair(case: u8, mu: f64, a: f64, b: f64, c: f64, d3: bool) -> (Vec<f64>, Vec<f64>) {
        let dim = if d3 { 3 } else { 2 };
        let dir: Vec<f64> = if d3 {
            vec![b.cos(), b.sin()]
        } else {
            vec![if b >= 0.0 { 1.0 } else { -1.0 }]
        };
        let mut u = vec![0.0; dim];
        let mut r = vec![0.0; dim];
        match case {
            0 => {
                u[0] = a.abs();
                for k in 1..dim {
                    u[k] = c * dir[k - 1];
                }
            }
            1 => {
                r[0] = a.abs();
                let t = mu * a.abs() * (c.abs() / (1.0 + c.abs()));
                for k in 1..dim {
                    r[k] = t * dir[k - 1];
                }
            }
            _ => {
                r[0] = a.abs() + 0.1;
                let ut = c.abs() + 0.1;
                for k in 1..dim {
                    u[k] = ut * dir[k - 1];
                    r[k] = -mu * r[0] * dir[k - 1];
                }
            }
        }
        (u, r)
    }

    proptest! {
        /// Lemma 3.1: pairs built from each branch of (2.9) satisfy (3.10), have zero error
        /// and the right status.
        #[test]
        fn lemma_3_1_on_each_branch(case in 0u8..3, mu in 0.05f64..3.0, a in -5.0f64..5.0, b in -3.0f64..3.0, c in -5.0f64..5.0, d3 in any::<bool>()) {
            let (u, r) = pair(case, mu, a, b, c, d3);
            prop_assert!(lemma31(mu, &u, &r));
            prop_assert!(contact_residual_sq(mu, &u, &r) <= 1e-20 * (1.0 + dot(&u, &u) + dot(&r, &r)));
            let s = status(mu, &u, &r, 1e-9);
            prop_assert_ne!(s, ContactStatus::Violated);
        }

        /// Conversely, a pair violating (2.9) (penetrating, or friction not opposing sliding)
        /// fails (3.10) and has a nonzero error.
        #[test]
        fn violations_are_detected(mu in 0.05f64..3.0, a in 0.1f64..5.0, c in 0.1f64..5.0) {
            let u = vec![-a, 0.0, 0.0];
            let r = vec![c, 0.0, 0.0];
            prop_assert!(!lemma31(mu, &u, &r));
            prop_assert!(contact_residual_sq(mu, &u, &r) > 0.0);
            let u = vec![0.0, a, 0.0];
            let r = vec![c, mu * c, 0.0];
            prop_assert!(!lemma31(mu, &u, &r));
            prop_assert!(contact_residual_sq(mu, &u, &r) > 0.0);
            prop_assert_eq!(status(mu, &u, &r, 1e-9), ContactStatus::Violated);
        }
    }

    #[test]
    fn error_scale_rule() {
        let e = error_measure(2, &[0.5], &[0.0, 0.0], &[0.0, 0.0], 0.0);
        assert_eq!(e.error, 0.0);
        let e = error_measure(2, &[0.5], &[1.0, 0.0], &[-1.0, 0.0], 2.0);
        assert!(e.absolute > 0.0);
        assert!((e.error - e.absolute / 2.0).abs() < 1e-15);
    }
}
