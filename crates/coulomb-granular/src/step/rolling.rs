//! Rolling resistance: the contact law (2.9) extended by a rolling-friction cone, and the
//! step's 6-component problem solved by a per-contact block Gauss–Seidel (docs/granular.md,
//! "Rolling resistance").
//!
//! # The law
//! Contact i between sphere A and B (sphere or obstacle) gets, besides r = (r_N, r_T) of
//! (2.9), a resisting impulse y ∈ ℝ³ on the axes (t₁, t₂, n): a torque impulse
//! R_e (y₁ t₁ + y₂ t₂ + y₃ n) on A and its opposite on a sphere B, with the effective radius
//! R_e = R_A R_B / (R_A + R_B) between two spheres and R_e = R_A against an obstacle (Ai et al.,
//! Powder Technol. 206, 2011, "model A"). y₁, y₂ resist rolling, y₃ spinning (without it a
//! sphere spinning about the normal on a floor never stops). Its velocity is the scaled
//! relative angular velocity
//!
//! ```text
//!     ω_R = R_e (t₁, t₂, n)·(ω_A − ω_B)        (ω_B: the obstacle's own rotation)
//! ```
//!
//! so that y is an impulse (N s) and ω_R a velocity (m/s), like r and u. With a dimensionless
//! rolling-friction coefficient μ_r the cone is the one of Siconos' rolling friction and
//! LMGC90 for the resisting torque, ‖torque‖ ≤ μ_r R_e r_N (one coefficient for rolling and
//! spinning), with maximal dissipation on ω_R at t_{k+1}:
//!
//! ```text
//!     ‖y‖ ≤ μ_r r_N,    y = −μ_r r_N ω_R / ‖ω_R‖ when ω_R ≠ 0
//!     ⇔  y = P_{B(μ_r r_N)}(y − ω_R)            (B(ρ): the ball of radius ρ)
//! ```
//!
//! μ_r = 0 is the law (2.9) alone (and [`crate::Simulation::step`] then does not call this
//! module).
//!
//! # The step
//! With the 6-component Jacobian J of a contact (the rows n, t₁, t₂ of H's columns, then the
//! three rolling rows), M v = f + Jᵀ(r, y), the step's unknowns satisfy (2.9) on (u, r) and
//! the rolling law on (ω_R, y). [`solve_step`] solves it by Gauss–Seidel over the contacts;
//! each contact's 6×6 block W₆ (with the others frozen: (u, ω_R) = W₆ x + c) is solved
//! exactly in the three common cases — take-off (c_N ≥ 0), stick without rotation
//! (x = −W₆⁻¹c inside both cones, W₆⁻¹ computed once per step) and stick with rolling
//! (u = 0, ‖y‖ = μ_r r_N: the ball-constrained QP on the Schur complement, see
//! `solve_stick_roll`) — and otherwise by alternating the exact one-contact solve of (2.9)
//! of `coulomb::inner::pgs::solve_contact_law` (y frozen) and the exact minimizer over the ball
//! (r frozen; the rolling block of W is β I₃ for spheres), at most `LOCAL` times (the global
//! sweeps refine the rest). Sweeps from the second on are over-relaxed (`RELAXATION`, with
//! a projection back onto the cones; ω halved when the error stops falling), and a step whose
//! plain sweeps do not halve the error in `WINDOW` sweeps continues in random order with
//! exact blocks (`STALLED_RELAXATION`). It stops when the error below is ≤ tol, else with a
//! typed status
//! after `Settings::max_inner` sweeps or `Settings::time_limit`.
//!
//! # Error
//! The measure of docs/error.md on the 6-component problem, computed from the returned (r, y)
//! with v = M⁻¹(f + Jᵀ(r, y)) recomputed:
//!
//! ```text
//!     err = sqrt(Σᵢ ‖eᵢ‖² + ‖e_R,ᵢ‖²) / max(‖q₆‖, ‖(r, y)‖, ‖(u, ω_R)‖)
//!     eᵢ   = r − P_{K_μ}(r − ũ)                    (docs/error.md)
//!     e_R,ᵢ = y − P_{B(μ_r max(r_N, 0))}(y − ω_R)
//! ```
//!
//! with q₆ = J M⁻¹ f + w₆. e_R,ᵢ = 0 exactly when the rolling law holds (given r_N ≥ 0, which
//! eᵢ = 0 enforces). A step is converged iff err ≤ tol.
//!
//! # Energy
//! With θ = ½ the rolling part adds ½ y·(ω_R,k+1 + ω_R,k) to the step's energy change
//! (docs/granular.md, "Energy"): y·ω_R,k+1 ≤ 0 by maximal dissipation, the midpoint term has no
//! sign only when ω_R turns within a step, as for Coulomb friction. Measured: no increase
//! (tests/rolling.rs, docs/validation.md).

use crate::contact::{Contact, Partner};
use crate::math::Vec3;
use crate::world::{Motion, World};
use coulomb::inner::pgs::{solve_contact, solve_contact_law, OneContact};
use coulomb::problem::GlobalProblem;
use coulomb::solver::{Settings, Solution, SolveError, Status};
use std::collections::HashMap;
use std::time::Instant;

/// Sweeps between two recomputations of v from scratch (round-off of the updates).
const REFRESH: usize = 25;
/// Over-relaxation ω of the sweeps from the second on: each contact's (r, y) is replaced by
/// the projection onto K_μ × B(μ_r r_N) of old + ω (new − old) (the fixed points are those of
/// plain Gauss–Seidel). Measured on the 150-bead box with e = 0.5, μ = 0.8, μ_r = 0.1
/// (`examples/rolling_bench.rs`; with damped stalled sweeps): mean sweeps per step 963 (ω = 1,
/// 300 steps: 1 592), 870 (ω = 1.5, 300 steps), 194 (ω = 1.8, 1 000 steps); docs/granular.md.
const RELAXATION: f64 = 1.8;
/// Sweeps over which the over-relaxation must reduce the error by the factor
/// [`RELAX_PROGRESS`]; otherwise ω is halved towards 1.
const RELAX_WINDOW: usize = 50;
/// See [`RELAX_WINDOW`].
const RELAX_PROGRESS: f64 = 0.95;
/// Sweeps over which the error of plain (ω = 1) sweeps must halve; otherwise the step is
/// "stalled" (a slow or cycling Gauss–Seidel) and continues with sweeps over-relaxed by
/// [`STALLED_RELAXATION`] in a fresh random order each sweep, with each contact's block solved
/// to rounding ([`LOCAL_EXACT`]); when the error grows over such a window the sweeps switch to
/// damped ([`DAMPING`]) and back.
const WINDOW: usize = 200;
/// Relaxation of the stalled sweeps (measured, same run as [`RELAXATION`]: 1 step of 1 000 at
/// the sweep cap with ½, none with 1 or 1.5; 207 and 131 mean sweeps).
const STALLED_RELAXATION: f64 = 1.5;
/// Relaxation of the damped sweeps.
const DAMPING: f64 = 0.5;
/// Alternations inside one contact's block once stalled (the alternation contracts by ≈ 0.7
/// per pass on a sphere–wall contact: 50 passes reach rounding).
const LOCAL_EXACT: usize = 50;
/// Sweeps between two error measurements while the error is above 10 tol.
const CHECK_EVERY: usize = 4;
/// Alternations of the Coulomb solve and the ball projection inside one contact's block.
const LOCAL: usize = 5;

/// State kept across steps: the rolling impulses of the last step (warm start and output).
#[derive(Debug, Clone, Default)]
pub struct RollingState {
    /// the last step's rolling impulses by contact key (warm start)
    pub(crate) previous: HashMap<(usize, Partner), [f64; 3]>,
    /// the rolling impulses y of the last step that had contacts, in the order of that
    /// step's contacts (`Simulation::contacts` after it); empty when μ_r = 0
    pub impulses: Vec<[f64; 3]>,
    /// the last step's rolling part of the residual sqrt(Σ ‖e_R,ᵢ‖²) / scale
    pub rolling_error: f64,
    /// the sweep's constants (defaults: the module's constants); for probes of the method
    /// (`examples/rolling_probe.rs`), not a user setting
    #[doc(hidden)]
    pub tuning: Tuning,
}

/// The constants of [`solve_step`]'s sweep, for probes (`examples/rolling_probe.rs`).
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    /// [`RELAXATION`]
    pub relaxation: f64,
    /// [`LOCAL`]
    pub local: usize,
    /// [`LOCAL_EXACT`]
    pub local_exact: usize,
    /// [`WINDOW`]
    pub window: usize,
    /// [`STALLED_RELAXATION`]
    pub stalled_relaxation: f64,
}

impl Default for Tuning {
    fn default() -> Self {
        Self {
            relaxation: RELAXATION,
            local: LOCAL,
            local_exact: LOCAL_EXACT,
            window: WINDOW,
            stalled_relaxation: STALLED_RELAXATION,
        }
    }
}

/// Effective radius R_e of a contact: R_A R_B / (R_A + R_B) between two spheres, R_A against an
/// obstacle.
pub fn effective_radius(world: &World, c: &Contact) -> f64 {
    let ra = world.bodies.get(c.body).map_or(0.0, |b| b.radius);
    match c.partner {
        Partner::Body(j) => {
            let rb = world.bodies.get(j).map_or(0.0, |b| b.radius);
            if ra + rb > 0.0 {
                ra * rb / (ra + rb)
            } else {
                0.0
            }
        }
        Partner::Obstacle(..) => ra,
    }
}

/// Projection of x onto the ball B(ρ) = {‖x‖ ≤ ρ}, ρ ≥ 0.
pub fn project_ball(rho: f64, x: [f64; 3]) -> [f64; 3] {
    let n = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    if n <= rho {
        x
    } else if n > 0.0 {
        [x[0] * rho / n, x[1] * rho / n, x[2] * rho / n]
    } else {
        [0.0; 3]
    }
}

/// ‖e_R‖² = ‖y − P_{B(μ_r max(r_N, 0))}(y − ω_R)‖² of the rolling law of one contact.
pub fn rolling_residual_sq(mu_r: f64, r_n: f64, y: [f64; 3], omega: [f64; 3]) -> f64 {
    let x = [y[0] - omega[0], y[1] - omega[1], y[2] - omega[2]];
    let p = project_ball(mu_r * r_n.max(0.0), x);
    (0..3).map(|k| (y[k] - p[k]).powi(2)).sum()
}

/// One contact's rows of J on at most two bodies: 5 rows (n, t₁, t₂, rolling t₁, t₂) × 12
/// columns (A's 6 dofs, then B's), and w₅.
#[derive(Debug, Clone)]
struct Block {
    /// first dof of A and of B (None: obstacle)
    dofs: [Option<usize>; 2],
    j: [[f64; 12]; 6],
    w: [f64; 6],
    mu: f64,
    /// μ_r of the contact (its pair of materials', or the parameters')
    mu_r: f64,
    /// W₆ = J M⁻¹ Jᵀ (diagonal block)
    a: [[f64; 6]; 6],
    /// W₆⁻¹ (None: singular, a body without rotational dof)
    a_inv: Option<[[f64; 6]; 6]>,
    /// the Coulomb block of W₆ (row-major 3 × 3) and its inverse
    a3: [f64; 9],
    a3_inv: [f64; 9],
    /// mean of the rolling block's diagonal (β of β I₃)
    beta: f64,
    /// K = A₃⁻¹ C (C: the Coulomb–rolling block of W₆), row-major: with the contact sticking,
    /// r = −A₃⁻¹ c_C − K y
    k: [f64; 9],
    /// S = W_RR − Cᵀ A₃⁻¹ C, the Schur complement (row-major): with the contact sticking,
    /// ω_R = S y + g
    s: [f64; 9],
}

impl Block {
    fn gather(&self, v: &[f64]) -> [f64; 12] {
        let mut x = [0.0; 12];
        for (s, d) in self.dofs.iter().enumerate() {
            if let Some(d) = d {
                x[6 * s..6 * s + 6].copy_from_slice(&v[*d..*d + 6]);
            }
        }
        x
    }
    /// (u, ω_R) = J v + w₅
    fn velocity(&self, v: &[f64]) -> [f64; 6] {
        let x = self.gather(v);
        let mut u = self.w;
        for (k, row) in self.j.iter().enumerate() {
            u[k] += row.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>();
        }
        u
    }
    /// v += M⁻¹ Jᵀ Δ
    fn scatter(&self, minv: &[f64], delta: &[f64; 6], v: &mut [f64]) {
        for (s, d) in self.dofs.iter().enumerate() {
            let Some(d) = d else { continue };
            for l in 0..6 {
                let col = 6 * s + l;
                let t: f64 = (0..6).map(|k| self.j[k][col] * delta[k]).sum();
                if t != 0.0 {
                    v[d + l] += minv[d + l] * t;
                }
            }
        }
    }
}

fn blocks(
    world: &World,
    contacts: &[Contact],
    problem: &GlobalProblem,
    mu_r: f64,
) -> Result<Vec<Block>, SolveError> {
    let h = &problem.h;
    let minv: Vec<f64> = problem.m.values.iter().map(|m| 1.0 / m).collect();
    let mut out = Vec::with_capacity(contacts.len());
    for (i, c) in contacts.iter().enumerate() {
        let a = 6 * c.body;
        let b = match c.partner {
            Partner::Body(j) => Some(6 * j),
            Partner::Obstacle(..) => None,
        };
        let mut blk = Block {
            dofs: [Some(a), b],
            j: [[0.0; 12]; 6],
            w: [0.0; 6],
            mu: problem.mu.get(i).copied().unwrap_or(0.0),
            mu_r: if world.materials.is_none() {
                mu_r
            } else {
                let default = crate::world::ContactLaw {
                    mu: 0.0,
                    restitution: 0.0,
                    rolling_friction: mu_r,
                };
                world
                    .contact_law(c.body, c.partner, default)
                    .rolling_friction
            },
            a: [[0.0; 6]; 6],
            a_inv: None,
            a3: [0.0; 9],
            a3_inv: [0.0; 9],
            beta: 0.0,
            k: [0.0; 9],
            s: [0.0; 9],
        };
        // the Coulomb rows: H's columns 3i + k, as assembled (so that u = Hᵀ v + w)
        for k in 0..3 {
            let col = 3 * i + k;
            if col + 1 >= h.col_ptr.len() {
                return Err(SolveError::Settings(format!(
                    "contact {i} has no column in H"
                )));
            }
            for p in h.col_ptr[col]..h.col_ptr[col + 1] {
                let row = h.row_idx[p];
                let slot = if row >= a && row < a + 6 {
                    row - a
                } else if b.is_some_and(|b| row >= b && row < b + 6) {
                    6 + row - b.unwrap_or(0)
                } else {
                    return Err(SolveError::Settings(format!(
                        "H column {col} touches a dof of neither body of contact {i}"
                    )));
                };
                blk.j[k][slot] += h.values[p];
            }
            blk.w[k] = problem.w.get(col).copied().unwrap_or(0.0);
        }
        // the rolling rows: R_e t_k on A's rotational dofs, −R_e t_k on B's
        let re = effective_radius(world, c);
        for (k, t) in [c.t1, c.t2, c.normal].iter().enumerate() {
            let row = t.to_array();
            let locked_a = world.bodies.get(c.body).is_none_or(|s| s.rotation_locked);
            if !locked_a {
                for (dst, x) in blk.j[3 + k][3..6].iter_mut().zip(row) {
                    *dst = re * x;
                }
            }
            match c.partner {
                Partner::Body(j) => {
                    if !world.bodies.get(j).is_none_or(|s| s.rotation_locked) {
                        for (dst, x) in blk.j[3 + k][9..12].iter_mut().zip(row) {
                            *dst = -re * x;
                        }
                    }
                }
                Partner::Obstacle(o, _) => {
                    if let Some(Motion::Rotate { axis, omega, .. }) =
                        world.obstacles.get(o).map(|ob| &ob.motion)
                    {
                        blk.w[3 + k] = -re * t.dot(*axis * *omega);
                    }
                }
            }
        }
        // W₅ = J M⁻¹ Jᵀ
        let mut md = [0.0; 12];
        for (s, d) in blk.dofs.iter().enumerate() {
            if let Some(d) = d {
                md[6 * s..6 * s + 6].copy_from_slice(&minv[*d..*d + 6]);
            }
        }
        for p in 0..6 {
            for q in 0..6 {
                blk.a[p][q] = (0..12).map(|l| blk.j[p][l] * md[l] * blk.j[q][l]).sum();
            }
        }
        blk.a_inv = inverse6(&blk.a);
        let a = &blk.a;
        blk.a3 = [
            a[0][0], a[0][1], a[0][2], a[1][0], a[1][1], a[1][2], a[2][0], a[2][1], a[2][2],
        ];
        blk.a3_inv = inverse3(&blk.a3);
        blk.beta = (a[3][3] + a[4][4] + a[5][5]) / 3.0;
        for p in 0..3 {
            for q in 0..3 {
                blk.k[3 * p + q] = (0..3).map(|l| blk.a3_inv[3 * p + l] * a[l][3 + q]).sum();
            }
        }
        for p in 0..3 {
            for q in 0..3 {
                let ck: f64 = (0..3).map(|l| a[l][3 + p] * blk.k[3 * l + q]).sum();
                blk.s[3 * p + q] = a[3 + p][3 + q] - ck;
            }
        }
        out.push(blk);
    }
    Ok(out)
}

fn inverse3(a: &[f64; 9]) -> [f64; 9] {
    let det = a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6])
        + a[2] * (a[3] * a[7] - a[4] * a[6]);
    let id = if det != 0.0 { 1.0 / det } else { 0.0 };
    [
        (a[4] * a[8] - a[5] * a[7]) * id,
        (a[2] * a[7] - a[1] * a[8]) * id,
        (a[1] * a[5] - a[2] * a[4]) * id,
        (a[5] * a[6] - a[3] * a[8]) * id,
        (a[0] * a[8] - a[2] * a[6]) * id,
        (a[2] * a[3] - a[0] * a[5]) * id,
        (a[3] * a[7] - a[4] * a[6]) * id,
        (a[1] * a[6] - a[0] * a[7]) * id,
        (a[0] * a[4] - a[1] * a[3]) * id,
    ]
}

/// The solution x of A x = −c (6 × 6, Gaussian elimination with partial pivoting); None when
/// A is singular to rounding (a body without rotational dof gives zero rolling rows).
fn solve6(a: &[[f64; 6]; 6], c: &[f64; 6]) -> Option<[f64; 6]> {
    let mut m = [[0.0; 7]; 6];
    let scale = (0..6).map(|k| a[k][k].abs()).fold(0.0, f64::max);
    for i in 0..6 {
        m[i][..6].copy_from_slice(&a[i]);
        m[i][6] = -c[i];
    }
    for col in 0..6 {
        let p = (col..6).max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))?;
        let pivot = m[p][col].abs();
        if pivot.is_nan() || pivot <= 1e-12 * scale {
            return None;
        }
        m.swap(col, p);
        let top = m[col];
        for row in m.iter_mut().skip(col + 1) {
            let f = row[col] / top[col];
            if f != 0.0 {
                for (x, t) in row[col..].iter_mut().zip(&top[col..]) {
                    *x -= f * t;
                }
            }
        }
    }
    let mut x = [0.0; 6];
    for i in (0..6).rev() {
        let s: f64 = (i + 1..6).map(|k| m[i][k] * x[k]).sum();
        x[i] = (m[i][6] - s) / m[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The minimizer of ½ yᵀS y + gᵀy over the ball B(ρ) (S symmetric positive definite 3 × 3,
/// row-major): y = −(S + λI)⁻¹ g with λ = 0 when that lies in the ball, else λ > 0 with
/// ‖y‖ = ρ, found by Newton's method on 1/‖y(λ)‖ − 1/ρ (Moré & Sorensen 1983, monotone from
/// λ = 0). None when S is not positive definite or the iteration fails.
pub(crate) fn ball_qp(s: &[f64; 9], g: &[f64; 3], rho: f64) -> Option<[f64; 3]> {
    if rho.is_nan() || rho <= 0.0 {
        return Some([0.0; 3]);
    }
    let solve = |lambda: f64, b: &[f64; 3]| -> [f64; 3] {
        let mut m = *s;
        m[0] += lambda;
        m[4] += lambda;
        m[8] += lambda;
        let inv = inverse3(&m);
        std::array::from_fn(|i| (0..3).map(|j| inv[3 * i + j] * b[j]).sum())
    };
    let ng = [-g[0], -g[1], -g[2]];
    let norm = |x: &[f64; 3]| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    let mut lambda = 0.0;
    for _ in 0..50 {
        let y = solve(lambda, &ng);
        let ny = norm(&y);
        if !ny.is_finite() {
            return None;
        }
        if lambda == 0.0 && ny <= rho {
            return Some(y);
        }
        if (ny - rho).abs() <= 1e-13 * rho {
            return Some(y.map(|v| v * rho / ny));
        }
        let z = solve(lambda, &y);
        let yz: f64 = (0..3).map(|i| y[i] * z[i]).sum();
        if yz.is_nan() || yz <= 0.0 {
            return None;
        }
        // φ(λ) = 1/‖y‖ − 1/ρ, φ' = yᵀ(S + λI)⁻¹y / ‖y‖³
        lambda += (ny - rho) / rho * ny * ny / yz;
        if !(lambda >= 0.0 && lambda.is_finite()) {
            return None;
        }
    }
    None
}

/// Contact i's 6-component law when its Coulomb part sticks (u = 0, r ∈ K_μ) and its rolling
/// part rolls (‖y‖ = μ_r r_N): with r = −A₃⁻¹c_C − K y the rolling law is the minimization of
/// ½ yᵀS y + gᵀy over B(μ_r r_N(y)) (S the Schur complement, g = c_R − Cᵀ A₃⁻¹ c_C), solved
/// by [`ball_qp`] with the radius updated from r_N(y) (a few times: r_N depends on y only
/// through the off-diagonal blocks). Returns (r, y) when the result satisfies both laws.
fn solve_stick_roll(blk: &Block, mu_r: f64, c: &[f64; 6]) -> Option<[f64; 6]> {
    let inv = &blk.a3_inv;
    let r0: [f64; 3] = std::array::from_fn(|i| -(0..3).map(|j| inv[3 * i + j] * c[j]).sum::<f64>());
    let a = &blk.a;
    let g: [f64; 3] =
        std::array::from_fn(|p| c[3 + p] + (0..3).map(|l| a[l][3 + p] * r0[l]).sum::<f64>());
    let r_of = |y: &[f64; 3]| -> [f64; 3] {
        std::array::from_fn(|i| r0[i] - (0..3).map(|j| blk.k[3 * i + j] * y[j]).sum::<f64>())
    };
    let mut y = [0.0; 3];
    let mut r = r0;
    for _ in 0..8 {
        let rho = mu_r * r[0].max(0.0);
        let next = ball_qp(&blk.s, &g, rho)?;
        let change: f64 = (0..3).map(|k| (next[k] - y[k]).abs()).sum();
        y = next;
        r = r_of(&y);
        if change <= 1e-12 * (rho + f64::MIN_POSITIVE) {
            break;
        }
    }
    let ny = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
    let rt = (r[1] * r[1] + r[2] * r[2]).sqrt();
    (r[0] > 0.0 && rt <= blk.mu * r[0] && ny <= mu_r * r[0] * (1.0 + 1e-9))
        .then_some([r[0], r[1], r[2], y[0], y[1], y[2]])
}

/// W₆⁻¹ column by column with [`solve6`]; None when W₆ is singular to rounding.
fn inverse6(a: &[[f64; 6]; 6]) -> Option<[[f64; 6]; 6]> {
    let mut inv = [[0.0; 6]; 6];
    for k in 0..6 {
        let mut e = [0.0; 6];
        e[k] = -1.0;
        let col = solve6(a, &e)?;
        for (row, x) in inv.iter_mut().zip(col) {
            row[k] = x;
        }
    }
    Some(inv)
}

/// Solves contact i's 6-component law with the other contacts frozen: (u, ω_R) = A₆ x + c.
/// Alternates the exact solve of (2.9) for the Coulomb part with y frozen and the minimizer of
/// ½ β‖y‖² + bᵀy over the ball B(μ_r r_N) with r frozen (A₆'s rolling block is β I₃ for spheres:
/// scalar inertia), at most [`LOCAL`] times, after two exact cases: take-off (c_N ≥ 0) and
/// stick without rotation (A₆ x = −c inside both cones).
fn solve_block(blk: &Block, mu_r: f64, c: &[f64; 6], old: &[f64; 6], local: usize) -> [f64; 6] {
    let a = &blk.a;
    let a3 = blk.a3;
    // take-off: r = 0, y = 0 (the ball shrinks to {0}) solves the block when c_N ≥ 0
    if c[0] >= 0.0 {
        return [0.0; 6];
    }
    // stick and no rotation: A₆ x = −c, accepted when r ∈ K_μ and ‖y‖ ≤ μ_r r_N (the common
    // case in a pile at rest)
    if let Some(inv) = &blk.a_inv {
        let x: [f64; 6] = std::array::from_fn(|k| -(0..6).map(|l| inv[k][l] * c[l]).sum::<f64>());
        let rt = (x[1] * x[1] + x[2] * x[2]).sqrt();
        let ry = (x[3] * x[3] + x[4] * x[4] + x[5] * x[5]).sqrt();
        if x[0] >= 0.0 && rt <= blk.mu * x[0] && ry <= mu_r * x[0] {
            return x;
        }
    }
    if blk.beta > 0.0 {
        if let Some(x) = solve_stick_roll(blk, mu_r, c) {
            return x;
        }
    }
    let ainv = blk.a3_inv;
    let beta = blk.beta;
    let mut x = *old;
    for _ in 0..local {
        // Coulomb part, y frozen: c_C + C y
        let mut cc = [0.0; 3];
        for k in 0..3 {
            cc[k] = c[k] + a[k][3] * x[3] + a[k][4] * x[4] + a[k][5] * x[5];
        }
        let mut one = OneContact {
            a: &a3,
            ainv: &ainv,
            d: 3,
            mu: blk.mu,
            c: cc,
        };
        let warm = [x[0], x[1], x[2]];
        let u_seed = [
            cc[0] + a3[0] * warm[0] + a3[1] * warm[1] + a3[2] * warm[2],
            cc[1] + a3[3] * warm[0] + a3[4] * warm[1] + a3[5] * warm[2],
            cc[2] + a3[6] * warm[0] + a3[7] * warm[1] + a3[8] * warm[2],
        ];
        let r = solve_contact_law(&one, &warm, &u_seed).unwrap_or_else(|| {
            // as the fused Gauss–Seidel of `coulomb`: the one-contact SOC-QP with De Saxcé's
            // term frozen at the current u
            one.c[0] += blk.mu * (u_seed[1] * u_seed[1] + u_seed[2] * u_seed[2]).sqrt();
            solve_contact(&one, &warm)
        });
        // rolling part, r frozen: b = c_R + Cᵀ r
        let mut b = [0.0; 3];
        for k in 0..3 {
            b[k] = c[3 + k] + (0..3).map(|l| a[3 + k][l] * r[l]).sum::<f64>();
        }
        let rho = mu_r * r[0].max(0.0);
        let y = if beta > 0.0 {
            project_ball(rho, [-b[0] / beta, -b[1] / beta, -b[2] / beta])
        } else {
            // no rotational dof on either side: y does not act, the law only fixes its
            // direction
            let big = f64::MAX.sqrt();
            project_ball(rho, [-b[0] * big, -b[1] * big, -b[2] * big])
        };
        let new = [r[0], r[1], r[2], y[0], y[1], y[2]];
        let change: f64 = new.iter().zip(&x).map(|(p, q)| (p - q).abs()).sum();
        let size: f64 = new.iter().map(|p| p.abs()).sum();
        x = new;
        if change <= 1e-9 * size {
            break;
        }
    }
    x
}

/// The error of the 6-component problem (module doc) and its rolling part, from (r, y) and v.
fn error_of(blocks: &[Block], r: &[f64], y: &[[f64; 3]], v: &[f64], q_norm: f64) -> (f64, f64) {
    let (mut e2, mut er2, mut r2, mut u2) = (0.0, 0.0, 0.0, 0.0);
    for (i, blk) in blocks.iter().enumerate() {
        let u = blk.velocity(v);
        let ri = &r[3 * i..3 * i + 3];
        e2 += coulomb::law::contact_residual_sq(blk.mu, &u[..3], ri);
        er2 += rolling_residual_sq(blk.mu_r, ri[0], y[i], [u[3], u[4], u[5]]);
        r2 += ri.iter().chain(&y[i]).map(|x| x * x).sum::<f64>();
        u2 += u.iter().map(|x| x * x).sum::<f64>();
    }
    let scale = q_norm.max(r2.sqrt()).max(u2.sqrt());
    let s = if scale > f64::EPSILON { scale } else { 1.0 };
    let err = (e2 + er2).sqrt() / s;
    let rolling = er2.sqrt() / s;
    if err.is_finite() {
        (err, rolling)
    } else {
        (f64::NAN, f64::NAN)
    }
}

/// v = M⁻¹ (f + Jᵀ (r, y)).
fn velocities(problem: &GlobalProblem, blocks: &[Block], r: &[f64], y: &[[f64; 3]]) -> Vec<f64> {
    let minv: Vec<f64> = problem.m.values.iter().map(|m| 1.0 / m).collect();
    let mut v: Vec<f64> = problem.f.iter().zip(&minv).map(|(f, mi)| f * mi).collect();
    for (i, blk) in blocks.iter().enumerate() {
        let d = [
            r[3 * i],
            r[3 * i + 1],
            r[3 * i + 2],
            y[i][0],
            y[i][1],
            y[i][2],
        ];
        blk.scatter(&minv, &d, &mut v);
    }
    v
}

/// Solves one step's 6-component problem (module doc) for the assembled Coulomb problem
/// `problem` (M diagonal, H, f, w, μ of `crate::assembly::assemble`) and the contacts it was
/// assembled from, warm started from `guess_r` (3 per contact) and the previous step's rolling
/// impulses of persisting contacts. On return `problem.f` holds f + J_Rᵀ y (the rolling
/// impulses as given external impulses), so that the returned r, v solve the Coulomb problem
/// as stored with the error of docs/error.md ≤ the reported 6-component error; the reported
/// `error` and status are those of the 6-component problem.
pub fn solve_step(
    world: &World,
    contacts: &[Contact],
    problem: &mut GlobalProblem,
    mu_r: f64,
    settings: &Settings,
    guess_r: &[f64],
    state: &mut RollingState,
) -> Result<Solution, SolveError> {
    let start = Instant::now();
    if !(mu_r.is_finite() && mu_r >= 0.0) {
        return Err(SolveError::Settings(format!(
            "rolling friction {mu_r} is not a finite nonnegative number"
        )));
    }
    if problem.m.values.len() != problem.dofs() || problem.m.values.iter().any(|m| *m <= 0.0) {
        return Err(SolveError::Settings(
            "rolling resistance needs the diagonal M of the granular assembly".into(),
        ));
    }
    let n = contacts.len();
    let blocks = blocks(world, contacts, problem, mu_r)?;
    let minv: Vec<f64> = problem.m.values.iter().map(|m| 1.0 / m).collect();
    let mut r: Vec<f64> = if guess_r.len() == 3 * n {
        guess_r.to_vec()
    } else {
        vec![0.0; 3 * n]
    };
    let mut y: Vec<[f64; 3]> = contacts
        .iter()
        .map(|c| state.previous.get(&c.key()).copied().unwrap_or([0.0; 3]))
        .collect();
    // ‖q₆‖, q₆ = J M⁻¹ f + w₆
    let v_free: Vec<f64> = problem.f.iter().zip(&minv).map(|(f, m)| f * m).collect();
    let q_norm = blocks
        .iter()
        .map(|b| b.velocity(&v_free).iter().map(|x| x * x).sum::<f64>())
        .sum::<f64>()
        .sqrt();
    let mut v = velocities(problem, &blocks, &r, &y);
    let (mut err, _) = error_of(&blocks, &r, &y, &v, q_norm);
    let mut sweeps = 0;
    let (mut stalled, mut window_start) = (false, err);
    let tuning = state.tuning;
    let (mut relax, mut relax_start) = (tuning.relaxation, f64::INFINITY);
    let mut order: Vec<usize> = (0..blocks.len()).collect();
    // xorshift64 state of the random sweep orders (deterministic)
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let max_sweeps = settings.max_inner.max(1);
    let mut stalled_omega = tuning.stalled_relaxation;
    let status = loop {
        if !err.is_finite() {
            break Status::NumericalError;
        }
        if err <= settings.tol {
            break Status::Converged;
        }
        if sweeps >= max_sweeps {
            break Status::MaxIterations;
        }
        if settings.time_limit.is_some_and(|t| start.elapsed() >= t) {
            break Status::TimeLimit;
        }
        if sweeps > 0 && sweeps % RELAX_WINDOW == 0 && relax > 1.0 {
            if err > RELAX_PROGRESS * relax_start {
                relax = 1.0 + 0.5 * (relax - 1.0);
                if relax < 1.01 {
                    relax = 1.0;
                }
            }
            relax_start = err;
        }
        if sweeps > 0 && sweeps % tuning.window == 0 {
            if stalled && err > window_start {
                // the error grew over a window: switch between over-relaxed and damped sweeps
                stalled_omega = if stalled_omega > 1.0 {
                    DAMPING
                } else {
                    tuning.stalled_relaxation
                };
            }
            if err > 0.5 * window_start && relax == 1.0 {
                stalled = true;
            }
            window_start = err;
        }
        // the first sweep is plain: it solves an isolated contact exactly
        let omega = match (stalled, sweeps) {
            (true, _) => stalled_omega,
            (false, 0) => 1.0,
            (false, _) => relax,
        };
        let local = if stalled {
            tuning.local_exact
        } else {
            tuning.local
        };
        if stalled {
            // a fresh random order each sweep (Fisher–Yates)
            for k in (1..order.len()).rev() {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                order.swap(k, (seed % (k as u64 + 1)) as usize);
            }
        }
        for &i in &order {
            let blk = &blocks[i];
            let u = blk.velocity(&v);
            let old = [
                r[3 * i],
                r[3 * i + 1],
                r[3 * i + 2],
                y[i][0],
                y[i][1],
                y[i][2],
            ];
            let mut c = [0.0; 6];
            for k in 0..6 {
                c[k] = u[k] - (0..6).map(|l| blk.a[k][l] * old[l]).sum::<f64>();
            }
            let mut new = solve_block(blk, blk.mu_r, &c, &old, local);
            if omega != 1.0 {
                // a convex combination of two points of the cones stays in them; an
                // over-relaxed one is projected back (r onto K_μ, then y onto B(μ_r r_N))
                for k in 0..6 {
                    new[k] = old[k] + omega * (new[k] - old[k]);
                }
                if omega > 1.0 {
                    let mut rr = [new[0], new[1], new[2]];
                    coulomb::cone::project(blk.mu, &mut rr);
                    let yy = project_ball(blk.mu_r * rr[0].max(0.0), [new[3], new[4], new[5]]);
                    new = [rr[0], rr[1], rr[2], yy[0], yy[1], yy[2]];
                }
            }
            if !new.iter().all(|x| x.is_finite()) {
                // a local solve that failed in rounding leaves the contact as it was
                continue;
            }
            let mut delta = [0.0; 6];
            for k in 0..6 {
                delta[k] = new[k] - old[k];
            }
            blk.scatter(&minv, &delta, &mut v);
            r[3 * i..3 * i + 3].copy_from_slice(&new[..3]);
            y[i] = [new[3], new[4], new[5]];
        }
        sweeps += 1;
        if sweeps % REFRESH == 0 {
            v = velocities(problem, &blocks, &r, &y);
        }
        // the error costs about a sweep: measured every CHECK_EVERY sweeps far from tol
        if err <= 10.0 * settings.tol || sweeps % CHECK_EVERY == 0 {
            err = error_of(&blocks, &r, &y, &v, q_norm).0;
        }
    };
    // the reported error, on v recomputed from (r, y)
    v = velocities(problem, &blocks, &r, &y);
    let (err, rolling_err) = error_of(&blocks, &r, &y, &v, q_norm);
    let status = match status {
        Status::Converged if err.is_nan() || err > settings.tol => Status::MaxIterations,
        s => s,
    };
    // the Coulomb problem as stored: f + J_Rᵀ y
    let zero_r = vec![0.0; 3 * n];
    let rolling_only = velocities(problem, &blocks, &zero_r, &y);
    for ((f, vr), (vf, m)) in problem
        .f
        .iter_mut()
        .zip(&rolling_only)
        .zip(v_free.iter().zip(&problem.m.values))
    {
        *f += (vr - vf) * m;
    }
    let u = problem.velocity(&v);
    let balance = problem.balance_residual(&v, &r);
    state.previous.clear();
    for (c, yi) in contacts.iter().zip(&y) {
        state.previous.insert(c.key(), *yi);
    }
    state.impulses = y;
    state.rolling_error = rolling_err;
    Ok(Solution {
        r,
        u,
        v: Some(v),
        s: Vec::new(),
        status,
        error: err,
        balance_residual: Some(balance),
        l: None,
        equality_residual: None,
        outer_iterations: 1,
        inner_iterations: sweeps,
        history: Vec::new(),
        solve_time: start.elapsed(),
    })
}

/// The rolling torque impulse on A of contact `c` with rolling impulse y: R_e (y₁ t₁ + y₂ t₂).
pub fn torque(world: &World, c: &Contact, y: [f64; 3]) -> Vec3 {
    (c.t1 * y[0] + c.t2 * y[1]) * effective_radius(world, c)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn ball_projection_and_residual() {
        assert_eq!(project_ball(1.0, [0.3, 0.4, 0.0]), [0.3, 0.4, 0.0]);
        let p = project_ball(1.0, [3.0, 0.0, 4.0]);
        assert!((p[0] - 0.6).abs() < 1e-15 && (p[2] - 0.8).abs() < 1e-15 && p[1] == 0.0);
        assert_eq!(project_ball(0.0, [3.0, 4.0, 1.0]), [0.0; 3]);
        // rolling and spinning: y = −μ_r r_N ω/‖ω‖ satisfies the law
        assert!(rolling_residual_sq(0.1, 2.0, [-0.12, 0.0, -0.16], [0.3, 0.0, 0.4]) < 1e-30);
        // wrong direction: violated
        assert!(rolling_residual_sq(0.1, 2.0, [0.2, 0.0, 0.0], [0.5, 0.0, 0.0]) > 0.01);
        // rotation stopped with y inside the ball: satisfied
        assert!(rolling_residual_sq(0.1, 2.0, [0.05, -0.1, 0.1], [0.0; 3]) < 1e-30);
        // no normal impulse: y must vanish
        assert!(rolling_residual_sq(0.1, 0.0, [0.05, 0.0, 0.0], [0.0; 3]) > 1e-4);
    }

    pub fn six_by_six_solve() {
        let a: [[f64; 6]; 6] = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let diag = if i == j { 2.0 } else { 0.0 };
                1.0 / (1.0 + (i as f64 - j as f64).abs()) + diag
            })
        });
        let c = [1.0, -2.0, 0.5, 0.0, 3.0, -1.0];
        let x = solve6(&a, &c).unwrap();
        for i in 0..6 {
            let r: f64 = (0..6).map(|j| a[i][j] * x[j]).sum::<f64>() + c[i];
            assert!(r.abs() < 1e-13);
        }
        assert!(solve6(&[[0.0; 6]; 6], &c).is_none());
    }

    /// ½ yᵀS y + gᵀy
    fn qp_value(s: &[f64; 9], g: &[f64; 3], y: &[f64; 3]) -> f64 {
        let sy: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| s[3 * i + j] * y[j]).sum());
        (0..3).map(|i| 0.5 * y[i] * sy[i] + g[i] * y[i]).sum()
    }

    pub fn ball_qp_is_the_minimizer_over_the_ball() {
        let s = [3.0, 0.5, -0.2, 0.5, 1.0, 0.1, -0.2, 0.1, 0.4];
        for (g, rho) in [
            ([1.0, -2.0, 0.5], 0.3),
            ([0.01, 0.02, 0.0], 10.0),
            ([-4.0, 0.0, 1.0], 1.0),
            ([0.0, 0.0, 1.0], 0.05),
        ] {
            let y = ball_qp(&s, &g, rho).unwrap();
            let ny = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
            assert!(ny <= rho * (1.0 + 1e-12), "{ny} > {rho}");
            // no point of the ball does better (a grid over the ball's surface and radii)
            let best = qp_value(&s, &g, &y);
            for i in 0..=20 {
                for j in 0..40 {
                    for k in 1..=10 {
                        let (th, ph) = (
                            std::f64::consts::PI * i as f64 / 20.0,
                            std::f64::consts::PI * j as f64 / 20.0,
                        );
                        let rad = rho * k as f64 / 10.0;
                        let z = [
                            rad * th.sin() * ph.cos(),
                            rad * th.sin() * ph.sin(),
                            rad * th.cos(),
                        ];
                        assert!(qp_value(&s, &g, &z) >= best - 1e-12);
                    }
                }
            }
        }
        assert_eq!(ball_qp(&s, &[1.0, 0.0, 0.0], 0.0), Some([0.0; 3]));
    }

    /// A sphere (R = 0.05 m, m = 1 kg) on the floor: the 6-component block of its contact
    /// in the problem (2.10) of one step (h = 0.02 s).
    fn floor_block(mu: f64) -> Block {
        let mut world = World::new();
        world.gravity = Vec3::new(0.0, 0.0, -9.81);
        world.obstacles.push(crate::world::Obstacle::fixed(
            "ground",
            crate::world::Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        world.bodies.push(crate::world::Sphere::new(
            Vec3::new(0.0, 0.0, 0.05),
            0.05,
            1.0,
        ));
        let h = 0.02;
        let contacts =
            crate::contact::detect(&world, 0.0, h, &crate::contact::Activation::default());
        let data = crate::assembly::StepData {
            h,
            t_end: h,
            restitution: 0.0,
            mu,
            close_gaps: true,
        };
        let problem = crate::assembly::assemble(&world, &contacts, &data).unwrap();
        blocks(&world, &contacts, &problem, 0.1).unwrap().remove(0)
    }

    pub fn stick_roll_solves_both_laws_on_a_floor_contact() {
        let blk = floor_block(0.5);
        let mu_r = 0.1;
        // pressed into the floor, pushed sideways gently, spinning: the contact sticks, the
        // rolling impulse sits on its ball
        let c = [-0.2, 0.01, -0.005, 0.3, -0.1, 0.05];
        let x = solve_stick_roll(&blk, mu_r, &c).expect("stick and roll");
        let u: [f64; 6] =
            std::array::from_fn(|k| c[k] + (0..6).map(|l| blk.a[k][l] * x[l]).sum::<f64>());
        assert!(coulomb::law::contact_residual_sq(blk.mu, &u[..3], &x[..3]) < 1e-24);
        assert!(rolling_residual_sq(mu_r, x[0], [x[3], x[4], x[5]], [u[3], u[4], u[5]]) < 1e-24);
        let ny = (x[3] * x[3] + x[4] * x[4] + x[5] * x[5]).sqrt();
        assert!((ny - mu_r * x[0]).abs() < 1e-12 * x[0]);
        // and solve_block agrees (its other cases do not apply here)
        let b = solve_block(&blk, mu_r, &c, &[0.0; 6], LOCAL);
        for k in 0..6 {
            assert!((b[k] - x[k]).abs() < 1e-12, "{b:?} {x:?}");
        }
        // pushed hard sideways: the contact slides, this case does not apply
        assert!(solve_stick_roll(&blk, mu_r, &[-0.2, 5.0, 0.0, 0.3, 0.0, 0.0]).is_none());
    }

    pub fn inverse_of_a_3x3() {
        let a = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
        let b = inverse3(&a);
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| a[3 * i + k] * b[3 * k + j]).sum();
                assert!((p - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
    }
}
