//! One contact with the others frozen, u = A r + c (A the contact's diagonal block of W):
//! the exact minimizer of the one-contact SOC-QP ([`solve_contact`]) and a solution of the
//! one-contact Coulomb law (2.9) ([`solve_contact_law`]), the building blocks of projected
//! Gauss–Seidel ([`super::pgs`]) and of the fused outer method ([`crate::outer::fused`]).
//!
//! # The one-contact solve is exact
//! [`solve_contact`] computes the minimizer exactly (to rounding), by cases:
//! - interior: the unconstrained minimizer −Wᵢᵢ⁻¹ cᵢ lies in K_μ;
//! - vertex: cᵢ ∈ K_μ* (then 0 satisfies the optimality condition K* ∋ Wᵢᵢ·0 + cᵢ ⊥ 0);
//! - boundary: rᵢ = t (1, μ cos α, μ sin α) with t = −cᵀd/(dᵀAd) > 0; the angle α maximizes
//!   ψ(α) = (cᵀd(α))² / (d(α)ᵀ A d(α)) among directions with cᵀd < 0, found by Newton's method
//!   on ψ' (from the previous iterate's direction, −c_T, the unconstrained minimizer's, or the
//!   best of a few sampled angles), and
//!   accepted only if the Lagrange multiplier is nonnegative (KKT of the convex problem, hence
//!   the global minimizer). In d = 2 the boundary is two rays, both tried.
//!
//! μ = 0 (the half-line) and μ = ∞ (the half-space) have their own closed forms.

use crate::cone;
use crate::linalg::sparse::CscMatrix;

// Tolerances of the one-contact solves. They run once per contact and sweep (projected
// Gauss–Seidel, the fused method), so they stay `const`s here rather than fields of
// [`crate::settings::InnerParams`] (whose doc lists them).

/// A d × d block counts as singular when a pivot (1 × 1: the entry; 2 × 2 and 3 × 3: the
/// determinant) is ≤ `PIVOT` · scaleᵈ (scale: the block's trace, or its regularized value).
pub(crate) const PIVOT: f64 = 1e-13;
/// A diagonal block Wᵢᵢ with trace ≤ `SINGULAR_TRACE` · ‖W‖ (‖W‖: the largest block trace)
/// counts as singular; its inversion scale is kept at least this.
pub(crate) const SINGULAR_TRACE: f64 = 1e-12;
/// A singular diagonal block gets `REGULARIZATION` · scale added to its diagonal.
pub(crate) const REGULARIZATION: f64 = 1e-8;
/// Newton on ψ'(α) (boundary case of the SOC-QP) has converged at a step below this angle
/// (the error left is its square).
pub(crate) const ANGLE_STEP: f64 = 1e-7;
/// Newton steps of one boundary-angle (ψ'(α) = 0) and one slip-angle (g(θ) = 0) run.
pub(crate) const ANGLE_NEWTON_STEPS: usize = 30;
/// Largest angle step (radians) of those Newton runs.
pub(crate) const MAX_ANGLE_STEP: f64 = 0.5;
/// Gradient step on ψ' (radians, times sign ψ') where ψ is not locally concave.
pub(crate) const ANGLE_GRADIENT_STEP: f64 = 0.1;
/// The KKT multiplier of the boundary point, y_N of y = A x + c, may be as low as
/// −`MULTIPLIER` (|c_N| + |c_T1| + |c_T2|) (rounding).
pub(crate) const MULTIPLIER: f64 = 1e-10;
/// Sampled angles of the boundary search when the three seeds fail …
pub(crate) const ANGLE_SAMPLES: usize = 32;
/// … of which the best (largest ψ) `ANGLE_SEEDS` start a Newton run.
pub(crate) const ANGLE_SEEDS: usize = 4;
/// Projected-gradient steps (step 1/‖A‖∞) of the last resort of the boundary case.
pub(crate) const FALLBACK_STEPS: usize = 500;
/// Newton on the slip equation g(θ) = 0 (2.9) has converged at a step below this angle.
pub(crate) const SLIP_STEP: f64 = 1e-8;
/// A sliding solution of (2.9) is kept when the law's residual is ≤ `LAW_RESIDUAL` ·
/// (‖A r‖ + ‖c‖).
pub(crate) const LAW_RESIDUAL: f64 = 1e-9;

/// The diagonal blocks of W, with what the one-contact solve needs.
#[derive(Debug, Clone)]
pub struct DiagonalBlocks {
    pub(crate) dim: usize,
    /// row-major d × d blocks, regularized when singular
    pub(crate) blocks: Vec<[f64; 9]>,
    /// inverses of `blocks`
    pub(crate) inverses: Vec<[f64; 9]>,
    /// estimate of ‖W‖ (largest block trace)
    pub w_scale: f64,
}

/// Inverse of a d × d (d ≤ 3) row-major matrix by cofactors; None if its determinant is not
/// positive relative to `scale` (a block with a positive definite symmetric part has a
/// positive determinant).
pub(crate) fn invert(a: &[f64; 9], d: usize, scale: f64) -> Option<[f64; 9]> {
    let mut inv = [0.0; 9];
    match d {
        1 => {
            if a[0].abs() <= PIVOT * scale {
                return None;
            }
            inv[0] = 1.0 / a[0];
        }
        2 => {
            let det = a[0] * a[3] - a[1] * a[2];
            if det.is_nan() || det <= PIVOT * scale * scale {
                return None;
            }
            inv[0] = a[3] / det;
            inv[1] = -a[1] / det;
            inv[2] = -a[2] / det;
            inv[3] = a[0] / det;
        }
        _ => {
            let c00 = a[4] * a[8] - a[5] * a[7];
            let c01 = a[5] * a[6] - a[3] * a[8];
            let c02 = a[3] * a[7] - a[4] * a[6];
            let det = a[0] * c00 + a[1] * c01 + a[2] * c02;
            if det.is_nan() || det <= PIVOT * scale * scale * scale {
                return None;
            }
            inv[0] = c00 / det;
            inv[1] = (a[2] * a[7] - a[1] * a[8]) / det;
            inv[2] = (a[1] * a[5] - a[2] * a[4]) / det;
            inv[3] = c01 / det;
            inv[4] = (a[0] * a[8] - a[2] * a[6]) / det;
            inv[5] = (a[2] * a[3] - a[0] * a[5]) / det;
            inv[6] = c02 / det;
            inv[7] = (a[1] * a[6] - a[0] * a[7]) / det;
            inv[8] = (a[0] * a[4] - a[1] * a[3]) / det;
        }
    }
    Some(inv)
}

impl DiagonalBlocks {
    /// Extracts and inverts the d × d diagonal blocks of W (d ∈ {2, 3}).
    pub fn new(dim: usize, w: &CscMatrix) -> Self {
        let nc = w.ncols / dim;
        let mut blocks = vec![[0.0; 9]; nc];
        for (i, blk) in blocks.iter_mut().enumerate() {
            for k in 0..dim {
                let col = i * dim + k;
                for p in w.col_ptr[col]..w.col_ptr[col + 1] {
                    let row = w.row_idx[p];
                    if row >= i * dim && row < (i + 1) * dim {
                        blk[(row - i * dim) * dim + k] += w.values[p];
                    }
                }
            }
        }
        let global_scale = blocks
            .iter()
            .map(|b| (0..dim).map(|k| b[k * dim + k].abs()).sum::<f64>())
            .fold(0.0f64, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut inverses = Vec::with_capacity(nc);
        for blk in blocks.iter_mut() {
            let trace: f64 = (0..dim).map(|k| blk[k * dim + k]).sum();
            let scale = trace.max(SINGULAR_TRACE * global_scale);
            match invert(blk, dim, scale) {
                Some(inv) if trace > SINGULAR_TRACE * global_scale => {
                    inverses.push(inv);
                }
                _ => {
                    let eps = REGULARIZATION * scale;
                    for k in 0..dim {
                        blk[k * dim + k] += eps;
                    }
                    let inv = invert(blk, dim, 0.0).unwrap_or([0.0; 9]);
                    inverses.push(inv);
                }
            }
        }
        Self {
            dim,
            blocks,
            inverses,
            w_scale: global_scale,
        }
    }

    /// Whether these are the blocks of a d-dimensional problem with `contacts` contacts.
    pub(crate) fn fits(&self, dim: usize, contacts: usize) -> bool {
        self.dim == dim && self.blocks.len() == contacts
    }
}

#[inline]
pub(crate) fn matvec(a: &[f64; 9], d: usize, x: &[f64; 3]) -> [f64; 3] {
    let mut y = [0.0; 3];
    for i in 0..d {
        let mut s = 0.0;
        for j in 0..d {
            s += a[i * d + j] * x[j];
        }
        y[i] = s;
    }
    y
}

#[inline]
fn dot3(a: &[f64; 3], b: &[f64; 3], d: usize) -> f64 {
    (0..d).map(|k| a[k] * b[k]).sum()
}

/// Minimizer of ½ xᵀ A x + cᵀ x along the ray t·dir, t ≥ 0: (t, value).
#[inline]
fn ray_minimizer(a: &[f64; 9], d: usize, c: &[f64; 3], dir: &[f64; 3]) -> (f64, f64) {
    let cd = dot3(c, dir, d);
    let dad = dot3(dir, &matvec(a, d, dir), d);
    if cd >= 0.0 || dad <= 0.0 {
        return (0.0, 0.0);
    }
    let t = -cd / dad;
    (t, 0.5 * cd * t)
}

/// ψ(α) = log((cᵀd)² / dᵀAd) and its first two derivatives in α, for d(α) = (1, μ cos α,
/// μ sin α) (d = 3), at the unit vector e = (cos α, sin α). Returns (cᵀd, ψ', ψ'', dᵀAd).
#[inline]
fn psi(a: &[f64; 9], c: &[f64; 3], mu: f64, e: (f64, f64)) -> (f64, f64, f64, f64) {
    let (co, s) = e;
    let (s2, c2) = (2.0 * s * co, co * co - s * s);
    let n = c[0] + mu * (c[1] * co + c[2] * s);
    let n1 = mu * (-c[1] * s + c[2] * co);
    let n2 = -mu * (c[1] * co + c[2] * s);
    let den = a[0]
        + 2.0 * mu * (a[1] * co + a[2] * s)
        + mu * mu * (a[4] * co * co + 2.0 * a[5] * co * s + a[8] * s * s);
    let den1 =
        2.0 * mu * (-a[1] * s + a[2] * co) + mu * mu * ((a[8] - a[4]) * s2 + 2.0 * a[5] * c2);
    let den2 =
        2.0 * mu * (-a[1] * co - a[2] * s) + mu * mu * (2.0 * (a[8] - a[4]) * c2 - 4.0 * a[5] * s2);
    let p1 = 2.0 * n1 / n - den1 / den;
    let p2 = 2.0 * (n2 * n - n1 * n1) / (n * n) - (den2 * den - den1 * den1) / (den * den);
    (n, p1, p2, den)
}

/// The unit vector e rotated by the angle δ (|δ| ≤ 1/2): cos δ and sin δ by their Taylor
/// polynomials (relative error < 3·10⁻⁵ there), then renormalized, so the result is a unit
/// vector at angle α + δ + O(δ⁷).
#[inline]
fn rotate(e: (f64, f64), delta: f64) -> (f64, f64) {
    let d2 = delta * delta;
    let cd = 1.0 - d2 * (0.5 - d2 / 24.0);
    let sd = delta * (1.0 - d2 * (1.0 / 6.0 - d2 / 120.0));
    let (co, s) = (e.0 * cd - e.1 * sd, e.1 * cd + e.0 * sd);
    let norm = (co * co + s * s).sqrt();
    (co / norm, s / norm)
}

/// The unit vector along (x, y), if that is a finite nonzero vector.
#[inline]
fn unit(x: f64, y: f64) -> Option<(f64, f64)> {
    let norm = (x * x + y * y).sqrt();
    (norm > 0.0 && norm.is_finite()).then(|| (x / norm, y / norm))
}

/// Newton on ψ'(α) = 0 from the direction e₀ = (cos α₀, sin α₀) (d = 3, boundary case);
/// returns the boundary point if the iteration reaches a stationary point with cᵀd < 0 and a
/// nonnegative multiplier.
fn boundary_newton(a: &[f64; 9], c: &[f64; 3], mu: f64, e0: (f64, f64)) -> Option<[f64; 3]> {
    let mut e = e0;
    let mut converged = false;
    for _ in 0..ANGLE_NEWTON_STEPS {
        let (n, p1, p2, _) = psi(a, c, mu, e);
        if n.is_nan() || n >= 0.0 {
            return None;
        }
        // Newton step on ψ' when ψ is locally concave, a gradient step otherwise
        let step = if p2 < 0.0 {
            -p1 / p2
        } else {
            ANGLE_GRADIENT_STEP * p1.signum()
        };
        let step = step.clamp(-MAX_ANGLE_STEP, MAX_ANGLE_STEP);
        e = rotate(e, step);
        if p2 < 0.0 && step.abs() <= ANGLE_STEP {
            converged = true;
            break;
        }
    }
    if !converged {
        return None;
    }
    let (co, s) = e;
    let n = c[0] + mu * (c[1] * co + c[2] * s);
    let den = a[0]
        + 2.0 * mu * (a[1] * co + a[2] * s)
        + mu * mu * (a[4] * co * co + 2.0 * a[5] * co * s + a[8] * s * s);
    if n.is_nan() || n >= 0.0 || den.is_nan() || den <= 0.0 {
        return None;
    }
    let t = -n / den;
    let x = [t, t * mu * co, t * mu * s];
    // multiplier: y = A x + c must be λ (μ² x_N, −x_T) with λ ≥ 0, i.e. y_N ≥ 0 (up to rounding)
    let y = matvec(a, 3, &x);
    let yn = y[0] + c[0];
    let scale = c[0].abs() + c[1].abs() + c[2].abs();
    if yn < -MULTIPLIER * scale {
        return None;
    }
    Some(x)
}

/// One contact with the others frozen: u = A r + c, r ∈ K_μ (d ∈ {2, 3}; A symmetric positive
/// definite, row-major d × d, with inverse `ainv`).
#[derive(Debug, Clone, Copy)]
pub struct OneContact<'a> {
    /// the diagonal block A = Wᵢᵢ
    pub a: &'a [f64; 9],
    /// A⁻¹
    pub ainv: &'a [f64; 9],
    /// d
    pub d: usize,
    /// μ
    pub mu: f64,
    /// c = uᵢ − Wᵢᵢ rᵢ (the other contacts' part of u)
    pub c: [f64; 3],
}

/// Exact minimizer of ½ xᵀ A x + cᵀ x over K_μ for one contact. `warm` (the previous value)
/// only seeds the angle search of the boundary case. Returns x.
pub fn solve_contact(contact: &OneContact<'_>, warm: &[f64; 3]) -> [f64; 3] {
    let OneContact { a, ainv, d, mu, c } = *contact;
    let c = &c;
    let mut x0 = matvec(ainv, d, c);
    x0.iter_mut().for_each(|v| *v = -*v);
    // interior
    if cone::contains(mu, &x0[..d], 0.0) {
        return x0;
    }
    // vertex: c ∈ K_μ* = K_{1/μ}, i.e. μ‖c_T‖ ≤ c_N
    let ct = cone::tangent_norm(&c[..d]);
    if mu.is_finite() && mu * ct <= c[0] {
        return [0.0; 3];
    }
    if mu == 0.0 {
        // half-line: x = (t, 0), t = max(0, −c_N / A_NN)
        let t = if a[0] > 0.0 {
            (-c[0] / a[0]).max(0.0)
        } else {
            0.0
        };
        return [t, 0.0, 0.0];
    }
    if mu.is_infinite() {
        // half-space x_N ≥ 0 and the unconstrained minimizer has x_N < 0: x_N = 0,
        // x_T minimizes the tangential block
        let mut x = [0.0; 3];
        if d == 2 {
            if a[3] > 0.0 {
                x[1] = -c[1] / a[3];
            }
        } else {
            let (p, q, r) = (a[4], a[5], a[8]);
            let det = p * r - q * q;
            if det > 0.0 {
                x[1] = -(r * c[1] - q * c[2]) / det;
                x[2] = -(p * c[2] - q * c[1]) / det;
            }
        }
        return x;
    }
    if d == 2 {
        let (t1, v1) = ray_minimizer(a, 2, c, &[1.0, mu, 0.0]);
        let (t2, v2) = ray_minimizer(a, 2, c, &[1.0, -mu, 0.0]);
        return if v1 <= v2 {
            [t1, mu * t1, 0.0]
        } else {
            [t2, -mu * t2, 0.0]
        };
    }
    // d = 3 boundary: seed the angle from the previous iterate, then from −c_T and x0_T,
    // then from sampled angles.
    // (each angle is computed only when needed: the first seed usually succeeds)
    for k in 0..3 {
        let seed = match k {
            0 => unit(warm[1], warm[2]),
            1 => unit(-c[1], -c[2]),
            _ => unit(x0[1], x0[2]),
        };
        if let Some(x) = seed.and_then(|e| boundary_newton(a, c, mu, e)) {
            return x;
        }
    }
    let mut cands: Vec<(f64, (f64, f64))> = (0..ANGLE_SAMPLES)
        .filter_map(|k| {
            let e = (2.0 * std::f64::consts::PI * k as f64 / ANGLE_SAMPLES as f64).sin_cos();
            let e = (e.1, e.0);
            let (n, _, _, den) = psi(a, c, mu, e);
            (n < 0.0 && den > 0.0).then_some((n * n / den, e))
        })
        .collect();
    cands.sort_by(|p, q| q.0.total_cmp(&p.0));
    for &(_, e) in cands.iter().take(ANGLE_SEEDS) {
        if let Some(x) = boundary_newton(a, c, mu, e) {
            return x;
        }
    }
    // last resort (never observed): many projected-gradient steps with step 1/‖A‖
    let lip = (0..3)
        .map(|i| (0..3).map(|j| a[i * 3 + j].abs()).sum::<f64>())
        .fold(0.0f64, f64::max);
    let mut x = *warm;
    for _ in 0..FALLBACK_STEPS {
        let g = matvec(a, 3, &x);
        for k in 0..3 {
            x[k] -= (g[k] + c[k]) / lip;
        }
        cone::project(mu, &mut x);
    }
    x
}

/// Slip equation of a sliding contact (d = 3) at the slip direction τ = (cos θ, sin θ):
/// with r = r_N (1, −μτ) and r_N fixed by u_N = 0, u = A r + c, returns
/// (g, g', r_N, β) where g(θ) = u_T × τ (zero when u_T ∥ τ) and β = u_T · τ.
#[inline]
fn slip_equation(a: &[f64; 9], c: &[f64; 3], mu: f64, tau: (f64, f64)) -> (f64, f64, f64, f64) {
    let (co, s) = tau;
    let p = a[0] - mu * (a[1] * co + a[2] * s);
    let dp = -mu * (a[2] * co - a[1] * s);
    let rn = -c[0] / p;
    let drn = c[0] * dp / (p * p);
    let t1 = a[3] - mu * (a[4] * co + a[5] * s);
    let dt1 = -mu * (a[5] * co - a[4] * s);
    let t2 = a[6] - mu * (a[7] * co + a[8] * s);
    let dt2 = -mu * (a[8] * co - a[7] * s);
    let u1 = rn * t1 + c[1];
    let u2 = rn * t2 + c[2];
    let du1 = drn * t1 + rn * dt1;
    let du2 = drn * t2 + rn * dt2;
    let g = u1 * s - u2 * co;
    let dg = du1 * s + u1 * co - du2 * co + u2 * s;
    (g, dg, rn, u1 * co + u2 * s)
}

/// Newton on the slip equation g(θ) = 0 from the direction τ₀ (d = 3); returns the sliding
/// solution r = r_N (1, −μτ) if the iteration converges to a root with r_N > 0 and u_T = βτ,
/// β ≥ 0.
fn slide_newton(a: &[f64; 9], c: &[f64; 3], mu: f64, tau0: (f64, f64)) -> Option<[f64; 3]> {
    let mut tau = tau0;
    for _ in 0..ANGLE_NEWTON_STEPS {
        let (g, dg, rn, beta) = slip_equation(a, c, mu, tau);
        // away from a root with β > 0 the derivative g' ≈ β is positive
        if dg.is_nan() || rn.is_nan() || dg <= 0.0 || rn <= 0.0 {
            return None;
        }
        let step = (-g / dg).clamp(-MAX_ANGLE_STEP, MAX_ANGLE_STEP);
        tau = rotate(tau, step);
        if step.abs() <= SLIP_STEP && beta >= 0.0 {
            let (_, _, rn, beta) = slip_equation(a, c, mu, tau);
            if !(rn > 0.0 && rn.is_finite()) || beta < 0.0 {
                return None;
            }
            return Some([rn, -mu * rn * tau.0, -mu * rn * tau.1]);
        }
    }
    None
}

/// A solution r of Coulomb's law (2.9) for one contact with u = A r + c, by cases: take-off r = 0 when c_N ≥ 0;
/// stick r = −A⁻¹c when it lies in K_μ; slide r = r_N (1, −μτ) with u_N = 0 and u_T = βτ,
/// β ≥ 0 — in d = 2 both directions τ = ±1 are tried, in d = 3 the slip equation is solved by
/// Newton's method from the directions of −r_T (`warm`, the previous value) and of u_T
/// (`u_seed`), and the result is kept if its residual of (2.9) is ≤ 1e-9 (‖A r‖ + ‖c‖).
/// None when no case applies (μ infinite, or the slip iteration fails); the caller then takes
/// a step of the convex problem with s frozen instead.
pub fn solve_contact_law(
    contact: &OneContact<'_>,
    warm: &[f64; 3],
    u_seed: &[f64; 3],
) -> Option<[f64; 3]> {
    let OneContact { a, ainv, d, mu, c } = *contact;
    let c = &c;
    if c[0] >= 0.0 {
        return Some([0.0; 3]);
    }
    if !mu.is_finite() {
        return None;
    }
    let mut x0 = matvec(ainv, d, c);
    x0.iter_mut().for_each(|v| *v = -*v);
    if cone::contains(mu, &x0[..d], 0.0) {
        return Some(x0);
    }
    if mu == 0.0 {
        return (a[0] > 0.0).then(|| [-c[0] / a[0], 0.0, 0.0]);
    }
    if d == 2 {
        for tau in [1.0, -1.0] {
            let p = a[0] - mu * tau * a[1];
            let rn = -c[0] / p;
            if p > 0.0 && rn > 0.0 && rn.is_finite() {
                let ut = rn * (a[2] - mu * tau * a[3]) + c[1];
                if ut * tau >= 0.0 {
                    return Some([rn, -mu * tau * rn, 0.0]);
                }
            }
        }
        return None;
    }
    [
        unit(-warm[1], -warm[2]),
        unit(u_seed[1], u_seed[2]),
        unit(-x0[1], -x0[2]),
    ]
    .into_iter()
    .flatten()
    .find_map(|tau| slide_newton(a, c, mu, tau))
    .filter(|r| {
        // the slip equation is solved to rounding; where A is so ill-conditioned that the
        // law's residual is still above 1e-9 (relative), the caller's convex step is used
        let ar = matvec(a, 3, r);
        let u = [ar[0] + c[0], ar[1] + c[1], ar[2] + c[2]];
        let scale = dot3(&ar, &ar, 3).sqrt() + dot3(c, c, 3).sqrt();
        crate::law::contact_residual_sq(mu, &u, r) <= (LAW_RESIDUAL * scale).powi(2)
    })
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    /// KKT residual of the one-contact problem: x ∈ K, y = A x + c ∈ K*, x ⊥ y.
    fn kkt(a: &[f64; 9], d: usize, mu: f64, c: &[f64; 3], x: &[f64; 3]) -> f64 {
        let mut y = matvec(a, d, x);
        for k in 0..d {
            y[k] += c[k];
        }
        let mut z = [0.0; 3];
        for k in 0..d {
            z[k] = x[k] - y[k];
        }
        cone::project(mu, &mut z[..d]);
        (0..d).map(|k| (x[k] - z[k]).powi(2)).sum::<f64>().sqrt()
    }

    /// A random d × d block A = G Gᵀ + 0.05 I (row-major) and its inverse.
    fn random_block(rng: &mut impl rand::Rng, d: usize) -> ([f64; 9], [f64; 9]) {
        let mut g = [0.0; 9];
        for v in g.iter_mut().take(d * d) {
            *v = rng.random_range(-1.0..1.0);
        }
        let mut a = [0.0; 9];
        for i in 0..d {
            for j in 0..d {
                a[i * d + j] = (0..d).map(|k| g[i * d + k] * g[j * d + k]).sum::<f64>()
                    + if i == j { 0.05 } else { 0.0 };
            }
        }
        (a, invert(&a, d, 1.0).unwrap())
    }

    pub fn one_contact_solve_satisfies_kkt() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for trial in 0..20_000 {
            let d = if trial % 3 == 0 { 2 } else { 3 };
            let (a, ainv) = random_block(&mut rng, d);
            let mut c = [0.0; 3];
            for v in c.iter_mut().take(d) {
                *v = rng.random_range(-2.0..2.0);
            }
            let mu = match trial % 7 {
                0 => 0.0,
                1 => f64::INFINITY,
                _ => rng.random_range(0.05..2.0),
            };
            let contact = OneContact {
                a: &a,
                ainv: &ainv,
                d,
                mu,
                c,
            };
            let x = solve_contact(&contact, &[0.0; 3]);
            let scale = 1.0 + c.iter().map(|v| v.abs()).sum::<f64>() * 20.0;
            let e = kkt(&a, d, mu, &c, &x);
            assert!(
                e <= 1e-9 * scale,
                "trial {trial}: d={d} mu={mu} kkt={e} x={x:?}"
            );
        }
    }

    /// Solutions of the one-contact law from [`solve_contact_law`] satisfy (2.9) (their error
    /// of docs/error.md vanishes), and the slip equation finds one in nearly every case.
    pub fn one_contact_law_solve_satisfies_coulombs_law() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let (mut found, mut tried) = (0, 0);
        for trial in 0..20_000 {
            let d = if trial % 3 == 0 { 2 } else { 3 };
            let (a, ainv) = random_block(&mut rng, d);
            let (mut c, mut warm, mut seed) = ([0.0; 3], [0.0; 3], [0.0; 3]);
            for k in 0..d {
                c[k] = rng.random_range(-2.0..2.0);
                warm[k] = rng.random_range(-1.0..1.0);
                seed[k] = rng.random_range(-1.0..1.0);
            }
            let mu = if trial % 11 == 0 {
                0.0
            } else {
                rng.random_range(0.05..2.0)
            };
            tried += 1;
            let contact = OneContact {
                a: &a,
                ainv: &ainv,
                d,
                mu,
                c,
            };
            let Some(r) = solve_contact_law(&contact, &warm, &seed) else {
                continue;
            };
            found += 1;
            let mut u = matvec(&a, d, &r);
            for k in 0..d {
                u[k] += c[k];
            }
            let res = crate::law::contact_residual_sq(mu, &u[..d], &r[..d]).sqrt();
            let scale = 1.0 + dot3(&r, &r, d).sqrt() + dot3(&u, &u, d).sqrt();
            assert!(
                res <= 1e-9 * scale,
                "trial {trial}: d={d} mu={mu} residual={res} r={r:?} u={u:?}"
            );
        }
        assert!(found * 100 >= tried * 99, "found {found} of {tried}");
    }
}
