//! Coulomb's law (2.9) at one contact, the De Saxcé change (3.7), per-contact status and the
//! error measure every result is reported in (the natural map with ρ = 1).
//!
//! Local vectors are ordered normal first: u = (u_N, u_T), r = (r_N, r_T).

use crate::cone;

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
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
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

/// The natural-map residual of one contact, from its home [`crate::natural_map`] (re-exported
/// here, where callers have always found it).
pub use crate::natural_map::contact_residual_sq;

/// The error measure of `docs/error.md`, split into its parts.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ErrorMeasure {
    /// sqrt(Σᵢ ‖eᵢ‖²) (+∞ when it exceeds the largest f64, NaN when r or u holds a NaN)
    pub absolute: f64,
    /// max(‖q‖, ‖r‖, ‖u‖) (+∞ when it exceeds the largest f64 or an entry is infinite)
    pub scale: f64,
    /// absolute / scale when scale > ε, else absolute: the number that is reported and
    /// compared. Computed from scaled norms, so it is finite whenever r, u and ‖q‖ are
    /// finite, even when ‖r‖ or ‖u‖ themselves overflow; +∞ (or NaN) otherwise, so that a
    /// non-finite input is never "converged" ([`ErrorMeasure::converged`]).
    pub error: f64,
}

impl ErrorMeasure {
    /// Whether the error is a finite number ≤ `tol` (the definition of "converged" of
    /// docs/error.md, balance residual aside).
    pub fn converged(&self, tol: f64) -> bool {
        self.error.is_finite() && self.error <= tol
    }
}

/// Multiplier 2⁻ᵏ (exact) that brings `max_abs` (finite, > 2¹⁰⁰) to at most 4, so that the
/// squares of the scaled entries cannot overflow; 1 for smaller values.
fn down_scale(max_abs: f64) -> f64 {
    if max_abs.is_finite() && max_abs > 2f64.powi(100) {
        // log2 rounds, so add one: 2^-(e+1) · max_abs ≤ 1; at most 2^-1022 (a normal
        // number: entries then stay ≤ 4)
        let e = max_abs.log2().ceil() as i32 + 1;
        2f64.powi(-e.min(1022))
    } else {
        1.0
    }
}

/// Computes the error measure from (r, u), the friction coefficients and ‖q‖ (computed with
/// [`norm`]). The caller is responsible for u being recomputed from the problem data
/// (u = W r + q or u = Hᵀ v + w).
///
/// The natural map eᵢ(u, r) = r − P_{K_μ}(r − ũ) is positively homogeneous (eᵢ(αu, αr) =
/// α eᵢ(u, r) for α > 0), and so is every norm: all of r, u and ‖q‖ are first multiplied by a
/// power of two α (exact) that brings the largest entry below 4, the ratio is taken on the
/// scaled values, and `absolute` and `scale` are reported divided by α. Nothing overflows on
/// finite input; a NaN or ±∞ in r, u or ‖q‖ gives error NaN or +∞, never a small number.
pub fn error_measure(dim: usize, mu: &[f64], r: &[f64], u: &[f64], q_norm: f64) -> ErrorMeasure {
    if let Some(m) = error_measure_plain(dim, mu, r, u, q_norm) {
        return m;
    }
    let nan = r.iter().chain(u).any(|x| x.is_nan()) || q_norm.is_nan();
    let max_abs = r
        .iter()
        .chain(u)
        .fold(q_norm.abs(), |m, x| if x.abs() > m { x.abs() } else { m });
    if nan || !max_abs.is_finite() {
        let bad = if nan { f64::NAN } else { f64::INFINITY };
        return ErrorMeasure {
            absolute: bad,
            scale: f64::INFINITY,
            error: bad,
        };
    }
    let alpha = down_scale(max_abs);
    let mut sum = 0.0;
    let mut rs = [0.0; 3];
    let mut us = [0.0; 3];
    for ((ri, ui), &m) in r.chunks_exact(dim).zip(u.chunks_exact(dim)).zip(mu) {
        let d = ri.len().min(3);
        for k in 0..d {
            rs[k] = ri[k] * alpha;
            us[k] = ui[k] * alpha;
        }
        sum += contact_residual_sq(m, &us[..d], &rs[..d]);
    }
    let abs_scaled = sum.sqrt();
    let scaled_norm = |x: &[f64]| {
        x.iter()
            .map(|v| (v * alpha) * (v * alpha))
            .sum::<f64>()
            .sqrt()
    };
    let scale_scaled = (q_norm * alpha).max(scaled_norm(r)).max(scaled_norm(u));
    let absolute = abs_scaled / alpha;
    let scale = scale_scaled / alpha;
    let error = if !abs_scaled.is_finite() || !scale_scaled.is_finite() {
        // a friction coefficient of ±∞ or NaN in the projection: no number to report
        f64::NAN
    } else if scale > f64::EPSILON {
        abs_scaled / scale_scaled
    } else {
        abs_scaled / alpha
    };
    ErrorMeasure {
        absolute,
        scale,
        error,
    }
}

/// [`error_measure`] in one pass without scaling, when that is exact: every entry of r and u
/// and ‖q‖ finite with magnitude at most 2¹⁰⁰ (no square can overflow). None otherwise.
#[inline]
fn error_measure_plain(
    dim: usize,
    mu: &[f64],
    r: &[f64],
    u: &[f64],
    q_norm: f64,
) -> Option<ErrorMeasure> {
    const LIMIT: f64 = 1.2676506002282294e30; // 2¹⁰⁰
    if q_norm.is_nan() || q_norm.abs() > LIMIT {
        return None;
    }
    let (mut sum, mut r2, mut u2) = (0.0, 0.0, 0.0);
    let mut bounded = true;
    for ((ri, ui), &m) in r.chunks_exact(dim).zip(u.chunks_exact(dim)).zip(mu) {
        for k in 0..ri.len() {
            r2 += ri[k] * ri[k];
            u2 += ui[k] * ui[k];
            // false for NaN and for entries beyond the limit
            bounded &= ri[k].abs() <= LIMIT && ui[k].abs() <= LIMIT;
        }
        sum += contact_residual_sq(m, ui, ri);
    }
    if !bounded || !sum.is_finite() {
        return None;
    }
    let absolute = sum.sqrt();
    let scale = q_norm.max(r2.sqrt()).max(u2.sqrt());
    let error = if scale > f64::EPSILON {
        absolute / scale
    } else {
        absolute
    };
    Some(ErrorMeasure {
        absolute,
        scale,
        error,
    })
}

pub use crate::linalg::vector::norm;

/// ‖a‖ / max(1, ‖b‖) (e.g. the balance residual ‖M v − H r − f‖ / max(1, ‖f‖) of
/// docs/error.md), computed on entries scaled by a common power of two, so that it is finite
/// whenever a and b are, even when ‖b‖ itself would overflow; NaN or +∞ otherwise.
pub fn relative_norm(a: &[f64], b: &[f64]) -> f64 {
    let mut max = 0.0f64;
    for x in a.iter().chain(b) {
        if !x.is_finite() {
            return if x.is_nan() { f64::NAN } else { f64::INFINITY };
        }
        max = max.max(x.abs());
    }
    let alpha = down_scale(max);
    let scaled = |x: &[f64]| {
        x.iter()
            .map(|v| (v * alpha) * (v * alpha))
            .sum::<f64>()
            .sqrt()
    };
    scaled(a) / scaled(b).max(alpha)
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
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
        fn prop_lemma_3_1_on_each_branch(case in 0u8..3, mu in 0.05f64..3.0, a in -5.0f64..5.0, b in -3.0f64..3.0, c in -5.0f64..5.0, d3 in any::<bool>()) {
            let (u, r) = pair(case, mu, a, b, c, d3);
            prop_assert!(lemma31(mu, &u, &r));
            prop_assert!(contact_residual_sq(mu, &u, &r) <= 1e-20 * (1.0 + dot(&u, &u) + dot(&r, &r)));
            let s = status(mu, &u, &r, 1e-9);
            prop_assert_ne!(s, ContactStatus::Violated);
        }

        /// Conversely, a pair violating (2.9) (penetrating, or friction not opposing sliding)
        /// fails (3.10) and has a nonzero error.
        fn prop_violations_are_detected(mu in 0.05f64..3.0, a in 0.1f64..5.0, c in 0.1f64..5.0) {
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

    // proptest! writes private functions: the tests are these, which run them
    pub fn lemma_3_1_on_each_branch() {
        prop_lemma_3_1_on_each_branch()
    }

    pub fn violations_are_detected() {
        prop_violations_are_detected()
    }

    pub fn error_scale_rule() {
        let e = error_measure(2, &[0.5], &[0.0, 0.0], &[0.0, 0.0], 0.0);
        assert_eq!(e.error, 0.0);
        let e = error_measure(2, &[0.5], &[1.0, 0.0], &[-1.0, 0.0], 2.0);
        assert!(e.absolute > 0.0);
        assert!((e.error - e.absolute / 2.0).abs() < 1e-15);
    }
}
