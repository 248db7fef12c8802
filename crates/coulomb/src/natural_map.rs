//! The natural map of Coulomb's law and of the inner problems, in one place.
//!
//! With ũ = u + μ‖u_T‖e the De Saxcé velocity (3.7), Coulomb's law (2.9) at contact i is the
//! complementarity K_μ ∋ rⁱ ⊥ ũⁱ ∈ K_μ* (Lemma 3.1, (3.9)), i.e. the zero of
//!
//! ```text
//!     Gⁱ(r) = rⁱ − P_{K_μ}(rⁱ − ũⁱ),
//! ```
//!
//! and the inner problem (4.7) for a fixed s is the complementarity L* ∋ W r + b ⊥ r ∈ L
//! (3.14), the zero of r − P_L(r − (W r + b)). Everything that evaluates these maps or their
//! generalized Jacobians lives here: the error measure of `docs/error.md`
//! ([`contact_residual_sq`], used by [`crate::law`]), the stopping measures of the inner
//! solvers (`dual_residual`, `dual_residual_shifted`, `dual_natural_residual`), and the
//! Newton systems of [`crate::newton`] and of the interior-point polish
//! (`natural_map`, `de_saxce_map`, [`projection_jacobian`], `push_d_times`,
//! `push_identity_minus_d`).
//!
//! # Normalisations
//! One map, three documented scalings of its norm: the error of `docs/error.md` divides by
//! max(‖q‖, ‖r‖, ‖u‖) ([`crate::law::error_measure`]); the first-order inner solvers (PGS,
//! APGD) stop on ‖r − P_L(r − ũ)‖ / max(‖b‖, ‖r‖, ‖ũ‖) (`dual_residual`, the same rule
//! with b in the place of q); the interior-point polish on ‖·‖ / max(1, ‖b‖)
//! (`dual_natural_residual`). `InnerLimits::tol` is compared with the solver's own one.

use crate::cone;
use crate::linalg::sparse::CscMatrix;
use crate::linalg::vector::norm;

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
    // μ‖u_T‖ with the convention ∞ · 0 = 0 (μ = ∞ and u_T = 0: ũ = u)
    if ut != 0.0 {
        x[0] -= mu * ut;
    }
    cone::project(mu, &mut x[..d]);
    (0..d).map(|k| (r[k] - x[k]).powi(2)).sum()
}

/// Projection of y onto K_μ (written into `p`) and its Jacobian ∂P_{K_μ}(y) (row-major d × d
/// into `jac`). On the boundary piece (0 < μ < ∞, neither y ∈ K_μ nor −y ∈ K_μ*), with
/// t = ‖y_T‖, ŷ = y_T / t and a = (y_N + μ t)/(1 + μ²):
///
/// ```text
///     ∂P = (1/(1 + μ²)) (1, μ ŷ)(1, μ ŷ)ᵀ + (μ a / t) [0 0; 0 I − ŷ ŷᵀ].
/// ```
///
/// Inside K_μ it is I, inside −K_μ* it is 0 (a B-subdifferential element on the kinks).
pub fn projection_jacobian(mu: f64, y: &[f64], p: &mut [f64], jac: &mut [f64]) {
    let d = y.len();
    p.copy_from_slice(y);
    crate::cone::project(mu, p);
    jac.iter_mut().for_each(|x| *x = 0.0);
    let t = crate::cone::tangent_norm(y);
    if mu == 0.0 {
        jac[0] = if y[0] > 0.0 { 1.0 } else { 0.0 };
    } else if mu.is_infinite() {
        jac[0] = if y[0] > 0.0 { 1.0 } else { 0.0 };
        (1..d).for_each(|k| jac[k * d + k] = 1.0);
    } else if t <= mu * y[0] {
        (0..d).for_each(|k| jac[k * d + k] = 1.0);
    } else if mu * t <= -y[0] || t == 0.0 {
        // polar cone: P = 0
    } else {
        let a = (y[0] + mu * t) / (1.0 + mu * mu);
        let mut g = [0.0; 3];
        g[0] = 1.0;
        for k in 1..d {
            g[k] = mu * y[k] / t;
        }
        for i in 0..d {
            for j in 0..d {
                jac[i * d + j] = g[i] * g[j] / (1.0 + mu * mu);
            }
        }
        let c = mu * a / t;
        for i in 1..d {
            for j in 1..d {
                let e = if i == j { 1.0 } else { 0.0 };
                jac[i * d + j] += c * (e - (y[i] / t) * (y[j] / t));
            }
        }
    }
}

/// Natural-map residual F(r) = r − P_L(r − u) of the complementarity L* ∋ u ⊥ r ∈ L (3.14),
/// with the Jacobians ∂P of every contact (row-major d × d blocks) in `jac`.
pub(crate) fn natural_map(
    dim: usize,
    mu: &[f64],
    r: &[f64],
    u: &[f64],
    f: &mut [f64],
    jac: &mut [f64],
) {
    let mut y = [0.0; 3];
    let mut p = [0.0; 3];
    for (i, &m) in mu.iter().enumerate() {
        let block = i * dim..(i + 1) * dim;
        for k in 0..dim {
            y[k] = r[block.start + k] - u[block.start + k];
        }
        projection_jacobian(
            m,
            &y[..dim],
            &mut p[..dim],
            &mut jac[i * dim * dim..(i + 1) * dim * dim],
        );
        for k in 0..dim {
            f[block.start + k] = r[block.start + k] - p[k];
        }
    }
}

/// G(r) of the De Saxcé natural map into `g`, the projection Jacobians D into `dblocks` and
/// the blocks B = D A into `blocks` (row-major d × d per contact), at r with u = W r + q.
pub(crate) fn de_saxce_map(
    d: usize,
    mus: &[f64],
    r: &[f64],
    u: &[f64],
    g: &mut [f64],
    dblocks: &mut [f64],
    blocks: &mut [f64],
) {
    let mut y = [0.0; 3];
    let mut proj = [0.0; 3];
    for (i, &mu) in mus.iter().enumerate() {
        let dj = &mut dblocks[i * d * d..(i + 1) * d * d];
        let at = i * d;
        let ui = &u[at..at + d];
        let t = crate::cone::tangent_norm(ui);
        let slide = mu.is_finite() && mu > 0.0 && t > 0.0;
        for k in 0..d {
            y[k] = r[at + k] - ui[k];
        }
        if slide {
            y[0] -= mu * t;
        }
        projection_jacobian(mu, &y[..d], &mut proj[..d], dj);
        for k in 0..d {
            g[at + k] = r[at + k] - proj[k];
        }
        // B = D A: column 0 of A is e_N, column k ≥ 1 is μ û_k e_N + e_k
        let b = &mut blocks[i * d * d..(i + 1) * d * d];
        for a in 0..d {
            b[a * d] = dj[a * d];
            for k in 1..d {
                let extra = if slide { mu * ui[k] / t } else { 0.0 };
                b[a * d + k] = dj[a * d] * extra + dj[a * d + k];
            }
        }
    }
}

/// Appends the triplets of `sign`·D·B (rows offset by `row0`) where D is the block diagonal
/// of the d × d projection Jacobians and B is given by `(row k, column j, value)` entries;
/// row k of B belongs to contact k / d.
#[allow(clippy::too_many_arguments)]
pub(crate) fn push_d_times(
    dim: usize,
    jac: &[f64],
    sign: f64,
    entries: impl Iterator<Item = (usize, usize, f64)>,
    row0: usize,
    rows: &mut Vec<usize>,
    cols: &mut Vec<usize>,
    vals: &mut Vec<f64>,
) {
    for (k, j, v) in entries {
        let (c, a) = (k / dim, k % dim);
        for a2 in 0..dim {
            let dv = jac[c * dim * dim + a2 * dim + a];
            if dv != 0.0 {
                rows.push(row0 + c * dim + a2);
                cols.push(j);
                vals.push(sign * dv * v);
            }
        }
    }
}

/// Appends the triplets of I − D (rows and columns offset by `off`).
pub(crate) fn push_identity_minus_d(
    dim: usize,
    jac: &[f64],
    off: usize,
    rows: &mut Vec<usize>,
    cols: &mut Vec<usize>,
    vals: &mut Vec<f64>,
) {
    let contacts = jac.len() / (dim * dim);
    for c in 0..contacts {
        for a in 0..dim {
            for b in 0..dim {
                let e = if a == b { 1.0 } else { 0.0 };
                rows.push(off + c * dim + a);
                cols.push(off + c * dim + b);
                vals.push(e - jac[c * dim * dim + a * dim + b]);
            }
        }
    }
}

/// The natural-map residual of (4.7), ‖r − P_L(r − u)‖ / max(‖b‖, ‖r‖, ‖u‖) with u = W r + b.
pub(crate) fn dual_residual(dim: usize, mu: &[f64], r: &[f64], u: &[f64], b_norm: f64) -> f64 {
    dual_residual_parts(dim, mu, r, u, None, b_norm)
}

/// [`dual_residual`] with u = `wr` + `b` formed on the fly (one pass over r, W r and b).
pub(crate) fn dual_residual_shifted(
    dim: usize,
    mu: &[f64],
    r: &[f64],
    wr: &[f64],
    b: &[f64],
    b_norm: f64,
) -> f64 {
    dual_residual_parts(dim, mu, r, wr, Some(b), b_norm)
}

#[inline]
fn dual_residual_parts(
    dim: usize,
    mu: &[f64],
    r: &[f64],
    wr: &[f64],
    b: Option<&[f64]>,
    b_norm: f64,
) -> f64 {
    let (mut sum, mut r_sq, mut u_sq) = (0.0, 0.0, 0.0);
    let mut x = [0.0; 3];
    for (i, &m) in mu.iter().enumerate() {
        let j0 = i * dim;
        for k in 0..dim {
            let rk = r[j0 + k];
            let uk = wr[j0 + k] + b.map_or(0.0, |b| b[j0 + k]);
            x[k] = rk - uk;
            r_sq += rk * rk;
            u_sq += uk * uk;
        }
        cone::project(m, &mut x[..dim]);
        sum += (0..dim).map(|k| (r[j0 + k] - x[k]).powi(2)).sum::<f64>();
    }
    let scale = b_norm.max(r_sq.sqrt()).max(u_sq.sqrt());
    if scale > f64::EPSILON {
        sum.sqrt() / scale
    } else {
        sum.sqrt()
    }
}

/// Relative natural-map residual ‖r − P_L(r − (W r + b))‖ / max(1, ‖b‖) of (4.7).
pub(crate) fn dual_natural_residual(
    dim: usize,
    mu: &[f64],
    w: &CscMatrix,
    b: &[f64],
    r: &[f64],
) -> f64 {
    let m = r.len();
    let mut u = b.to_vec();
    w.gemv_acc(1.0, r, &mut u);
    let mut f = vec![0.0; m];
    let mut jac = vec![0.0; mu.len() * dim * dim];
    natural_map(dim, mu, r, &u, &mut f, &mut jac);
    norm(&f) / norm(b).max(1.0)
}
