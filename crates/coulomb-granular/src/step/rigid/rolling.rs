//! Rolling resistance in the rigid step (docs/granular.md, "Rolling resistance"; the law of
//! [`crate::rolling`], "model A"): a contact whose pair of materials has μ_r > 0 and that
//! involves a ball carries, besides r, a resisting impulse y ∈ ℝ³ on the axes (t₁, t₂, n), the
//! torque impulse R_e (y₁ t₁ + y₂ t₂ + y₃ n) on A and its opposite on B, with ‖y‖ ≤ μ_r r_N and
//! maximal dissipation on ω_R = R_e (t₁, t₂, n)·(ω_A − ω_B): y = P_{B(μ_r r_N)}(y − ω_R).
//! R_e = R_A R_B / (R_A + R_B) between two balls, the ball's radius against any other body or
//! an obstacle; pairs with no ball are refused when the world is built.
//!
//! The step alternates ([`super::RigidWorld::step`]): the problem (2.10) with the rolling
//! impulses y as given impulses (f + J_Rᵀ y, the problem stored, as the sphere engine's) is
//! solved by the step's method; then one Gauss–Seidel pass over the rolling rows, each y_i the
//! exact minimizer over its ball with r frozen ([`crate::rolling::ball_qp`]); until the error
//! of the 6-component law ([`Rolling::error`]) is ≤ the tolerance.

use super::nsgs::{Problem, Row};
use coulomb::law;

/// Passes of the alternation at most in one step (each a solve of (2.10)).
pub const MAX_PASSES: usize = 500;

/// The rolling rows of a step: per contact with μ_r > 0, J_R on its bodies' rotational dofs,
/// w_R (a rotating obstacle's −R_e t·ω_B) and μ_r in a [`Row`], and W_R = J_R M⁻¹ J_Rᵀ.
#[derive(Debug, Clone, Default)]
pub struct Rolling {
    /// (index of the contact, its rolling row)
    pub rows: Vec<(usize, Row)>,
    w: Vec<[f64; 9]>,
}

/// J v + w of a row (3 components).
fn velocity(row: &Row, v: &[[f64; 6]]) -> [f64; 3] {
    let mut u = row.w;
    for (blk, j) in row.a.iter().chain(row.b.iter()) {
        for k in 0..3 {
            u[k] += (0..6).map(|d| j[k][d] * v[*blk][d]).sum::<f64>();
        }
    }
    u
}

impl Rolling {
    /// The rows with their W_R for the diagonal masses `mass`.
    pub fn new(rows: Vec<(usize, Row)>, mass: &[[f64; 6]]) -> Self {
        let w = rows
            .iter()
            .map(|(_, row)| {
                let mut w = [0.0; 9];
                for (blk, j) in row.a.iter().chain(row.b.iter()) {
                    let m = &mass[*blk];
                    for r in 0..3 {
                        for c in 0..3 {
                            w[3 * r + c] += (0..6).map(|d| j[r][d] * j[c][d] / m[d]).sum::<f64>();
                        }
                    }
                }
                w
            })
            .collect();
        Self { rows, w }
    }

    /// Whether no contact has rolling resistance.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// f + J_Rᵀ y.
    pub fn momenta(&self, f: &[[f64; 6]], y: &[[f64; 3]]) -> Vec<[f64; 6]> {
        let mut p = f.to_vec();
        for ((_, row), yi) in self.rows.iter().zip(y) {
            for (blk, j) in row.a.iter().chain(row.b.iter()) {
                for d in 0..6 {
                    p[*blk][d] += (0..3).map(|k| j[k][d] * yi[k]).sum::<f64>();
                }
            }
        }
        p
    }

    /// One Gauss–Seidel pass over the rolling rows with the contacts' impulses r frozen: y_i
    /// the minimizer of ½ yᵀ W_R y + (ω_R − W_R y_i)ᵀ y over B(μ_r r_N), v = M⁻¹(…) updated.
    pub fn sweep(&self, mass: &[[f64; 6]], v: &mut [[f64; 6]], r: &[f64], y: &mut [[f64; 3]]) {
        for (((i, row), w), yi) in self.rows.iter().zip(&self.w).zip(y.iter_mut()) {
            let om = velocity(row, v);
            let g: [f64; 3] =
                std::array::from_fn(|k| om[k] - (0..3).map(|c| w[3 * k + c] * yi[c]).sum::<f64>());
            let rho = row.mu * r[3 * i].max(0.0);
            let Some(new) = crate::rolling::ball_qp(w, &g, rho) else {
                continue;
            };
            if !new.iter().all(|x| x.is_finite()) {
                continue;
            }
            let delta: [f64; 3] = std::array::from_fn(|k| new[k] - yi[k]);
            for (blk, j) in row.a.iter().chain(row.b.iter()) {
                for d in 0..6 {
                    v[*blk][d] += (0..3).map(|k| j[k][d] * delta[k]).sum::<f64>() / mass[*blk][d];
                }
            }
            *yi = new;
        }
    }

    /// The error of (r, λ, y) on `problem` (whose f holds J_Rᵀ y), v = M⁻¹(f + H r + G λ)
    /// recomputed: the larger of the joints' residual ([`Problem::error_parts`]) and the
    /// measure of the 6-component law of [`crate::rolling`],
    /// sqrt(Σᵢ ‖eᵢ‖² + ‖e_R,ᵢ‖²) / max(‖q‖, ‖(r, y)‖, ‖(u, ω_R)‖), q that of `problem`.
    pub fn error(&self, problem: &Problem, r: &[f64], lambda: &[f64], y: &[[f64; 3]]) -> f64 {
        let v = problem.velocities_with(r, lambda);
        let u = problem.u_all(&v);
        let mu: Vec<f64> = problem.rows.iter().map(|row| row.mu).collect();
        let m = law::error_measure(3, &mu, r, &u, problem.q_norm());
        let (mut e2, mut y2, mut w2) = (0.0, 0.0, 0.0);
        for ((i, row), yi) in self.rows.iter().zip(y) {
            let om = velocity(row, &v);
            e2 += crate::rolling::rolling_residual_sq(row.mu, r[3 * i], *yi, om);
            y2 += yi.iter().map(|x| x * x).sum::<f64>();
            w2 += om.iter().map(|x| x * x).sum::<f64>();
        }
        let sq = |x: &[f64]| x.iter().map(|a| a * a).sum::<f64>();
        let scale = problem
            .q_norm()
            .max((sq(r) + y2).sqrt())
            .max((sq(&u) + w2).sqrt());
        let absolute = (m.absolute * m.absolute + e2).sqrt();
        let err = if scale > 0.0 {
            absolute / scale
        } else {
            absolute
        };
        let (_, joint) = problem.error_parts(r, lambda);
        if joint.is_nan() || err.is_nan() {
            return f64::NAN;
        }
        err.max(joint)
    }
}
