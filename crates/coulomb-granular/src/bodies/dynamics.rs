//! Newton–Euler dynamics of one rigid body for the Moreau–Jean scheme (2.5)–(2.7).
//!
//! # State
//! A body's configuration is the position x of its centre of mass (world) and a unit
//! quaternion q (w, x, y, z) that maps its *principal* frame (the principal axes of inertia
//! through the centre of mass) to the world. Its velocity is (v, Ω): v the velocity of the
//! centre of mass in the world frame, Ω the angular velocity **in the body (principal)
//! frame**, as Siconos' `NewtonEulerDS` keeps it. In the principal frame the inertia tensor is
//! the constant diagonal I = diag(I₁, I₂, I₃), so the mass matrix of the body's 6 dofs (v, Ω)
//! is the constant diagonal M = diag(m, m, m, I₁, I₂, I₃). The world inertia
//! I_w = R(q) I R(q)ᵀ — the tensor rotated each step — is what a contact sees: with the
//! lever arm a = p − x of a contact point p, the rotational rows of H are R(q)ᵀ (a × t), so
//! that W_ii = J M⁻¹ Jᵀ holds (a × t)ᵀ I_w⁻¹ (a × t), the full 3 × 3 world inverse inertia.
//!
//! # One step (the gyroscopic term)
//! The Newton–Euler equations are m v̇ = F, I Ω̇ + Ω × IΩ = T (body frame). Their
//! gyroscopic term Ω × IΩ is taken by a *free rotation predictor*: before the contact
//! problem, the torque-free Euler equations are advanced over the step by the implicit
//! midpoint rule ([`free_rotation`]),
//!
//! ```text
//!     I (Ω_free − Ω_k) = h (I Ω̄) × Ω̄,     Ω̄ = (Ω_k + Ω_free) / 2,
//! ```
//!
//! solved by Newton's method to round-off (capped). This rule conserves both quadratic
//! invariants of the free rotation exactly: the kinetic energy ½ Ω·IΩ (dot the equation with
//! Ω̄) and |L| = |IΩ| (dot it with IΩ̄). The contact impulses and external torques then enter
//! linearly, as in (2.5): M (v_{k+1}, Ω_{k+1}) = M (v_k + h g, Ω_free) + h (0, Rᵀ T) + H r,
//! so that the step's problem is exactly the linear incremental problem (2.10).
//!
//! Siconos' `MoreauJeanOSI` (kernel/src/simulationTools/MoreauJeanOSI.cpp) with
//! `NewtonEulerDS` treats the same term differently: the gyroscopic force is one of the
//! body's nonlinear forces, evaluated in the θ-weighted force term of the free velocity, with
//! its Jacobian (`jacobianvForces`) added to the iteration matrix W = M − hθ ∂F/∂v when the
//! Jacobian is computed — a linearized (one Newton iteration per step) implicit treatment; with
//! θ = ½ and a single linearization it does not conserve E and |L| exactly. We keep Siconos'
//! body-frame Ω and its exponential-map orientation update, and replace the linearized
//! gyroscopic term by the exactly solved implicit midpoint predictor above (docs/rigid.md).
//!
//! # Position update (2.7)
//! x_{k+1} = x_k + h ((1 − θ) v_k + θ v_{k+1}), and the orientation by the exponential map of
//! the body-frame rotation vector φ = h ((1 − θ) Ω_k + θ Ω_{k+1}):
//! q_{k+1} = q_k ⊗ exp(φ / 2), re-normalized ([`integrate_orientation`]).

use parry3d_f64::math::{Pose, Rotation, Vector};

/// Newton iterations of [`free_rotation`] at most.
pub const FREE_ROTATION_MAX_ITERATIONS: usize = 50;

/// The rigid body in the step's variables (principal frame at the centre of mass).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyState {
    /// mass m
    pub mass: f64,
    /// principal moments (I₁, I₂, I₃) about the centre of mass
    pub inertia: [f64; 3],
    /// centre of mass in the shape frame
    pub local_com: Vector,
    /// rotation principal frame → shape frame
    pub principal: Rotation,
    /// x: centre of mass, world
    pub x: Vector,
    /// q: unit quaternion principal frame → world
    pub q: Rotation,
    /// v: velocity of the centre of mass, world
    pub v: Vector,
    /// Ω: angular velocity in the principal (body) frame
    pub omega: Vector,
    /// material index
    pub material: u32,
    /// a fixed body never moves (its velocity is 0 and it has no dofs in the problem)
    pub fixed: bool,
    /// radius of a ball about the centre of mass that holds the shape (speed bounds)
    pub reach: f64,
}

impl BodyState {
    /// The body's diagonal block of M, diag(m, m, m, I₁, I₂, I₃) (principal frame).
    pub fn mass_block(&self) -> [f64; 6] {
        let [i1, i2, i3] = self.inertia;
        [self.mass, self.mass, self.mass, i1, i2, i3]
    }

    /// Orientation of the shape frame: q ⊗ principal⁻¹.
    pub fn shape_rotation(&self) -> Rotation {
        (self.q * self.principal.conjugate()).normalize()
    }
    /// Origin of the shape frame: x − R_shape · local_com.
    pub fn shape_origin(&self) -> Vector {
        self.x - self.shape_rotation() * self.local_com
    }
    /// Pose of the shape frame in the world (what parry's queries take).
    pub fn shape_pose(&self) -> Pose {
        Pose::from_parts(self.shape_origin(), self.shape_rotation())
    }
    /// Angular velocity in the world frame, ω = R(q) Ω.
    pub fn world_omega(&self) -> Vector {
        self.q * self.omega
    }
    /// Velocity of the material point at world position p: v + ω × (p − x).
    pub fn point_velocity(&self, p: Vector) -> Vector {
        self.v + self.world_omega().cross(p - self.x)
    }
    /// Kinetic energy ½ m |v|² + ½ Ω·IΩ.
    pub fn kinetic_energy(&self) -> f64 {
        let i = Vector::from_array(self.inertia);
        0.5 * self.mass * self.v.length_squared() + 0.5 * self.omega.dot(i * self.omega)
    }
    /// Angular momentum about the centre of mass in the world frame, L = R (I Ω).
    pub fn angular_momentum(&self) -> Vector {
        self.q * (Vector::from_array(self.inertia) * self.omega)
    }
}

/// Result of [`free_rotation`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeRotation {
    /// Ω_free
    pub omega: Vector,
    /// Newton iterations done
    pub iterations: usize,
    /// whether the last correction was at round-off level
    pub converged: bool,
}

/// The torque-free Euler equations over one step by the implicit midpoint rule:
/// the Ω_free with I (Ω_free − Ω) = h (I Ω̄) × Ω̄, Ω̄ = (Ω + Ω_free)/2, I = diag(`inertia`)
/// (principal frame). Newton's method from Ω (at most [`FREE_ROTATION_MAX_ITERATIONS`]
/// iterations, stopped when the correction is below 4 ulp of |Ω|). Conserves ½ Ω·IΩ and
/// |IΩ| up to the solve's round-off.
pub fn free_rotation(inertia: [f64; 3], omega: Vector, h: f64) -> FreeRotation {
    let i = Vector::from_array(inertia);
    let scale = omega.length();
    if scale == 0.0 || !scale.is_finite() {
        return FreeRotation {
            omega,
            iterations: 0,
            converged: scale.is_finite(),
        };
    }
    let mut w = omega;
    for it in 1..=FREE_ROTATION_MAX_ITERATIONS {
        let m = 0.5 * (omega + w);
        let im = i * m;
        // residual F(w) = I (w − Ω) − h (I m) × m
        let res = i * (w - omega) - h * im.cross(m);
        // Jacobian dF/dw = I − (h/2) (−[m]× I + [I m]×)
        let jac = jacobian(i, m, im, h);
        let Some(dw) = solve3(&jac, res) else {
            return FreeRotation {
                omega: w,
                iterations: it,
                converged: false,
            };
        };
        w -= dw;
        if !w.is_finite() {
            return FreeRotation {
                omega: w,
                iterations: it,
                converged: false,
            };
        }
        if dw.length() <= 4.0 * f64::EPSILON * scale {
            return FreeRotation {
                omega: w,
                iterations: it,
                converged: true,
            };
        }
    }
    FreeRotation {
        omega: w,
        iterations: FREE_ROTATION_MAX_ITERATIONS,
        converged: false,
    }
}

/// \[a\]× as rows.
fn skew(a: Vector) -> [[f64; 3]; 3] {
    [[0.0, -a.z, a.y], [a.z, 0.0, -a.x], [-a.y, a.x, 0.0]]
}

/// dF/dw of [`free_rotation`]'s residual.
fn jacobian(i: Vector, m: Vector, im: Vector, h: f64) -> [[f64; 3]; 3] {
    let sm = skew(m);
    let sim = skew(im);
    let ia = i.to_array();
    let mut j = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            // (−[m]× I)_{rc} = −sm[r][c] I_c
            let g = -sm[r][c] * ia[c] + sim[r][c];
            j[r][c] = -0.5 * h * g;
        }
        j[r][r] += ia[r];
    }
    j
}

/// Solution of the 3 × 3 system a x = b by Cramer's rule, `None` if a is singular.
pub fn solve3(a: &[[f64; 3]; 3], b: Vector) -> Option<Vector> {
    let c0 = Vector::new(a[0][0], a[1][0], a[2][0]);
    let c1 = Vector::new(a[0][1], a[1][1], a[2][1]);
    let c2 = Vector::new(a[0][2], a[1][2], a[2][2]);
    let det = c0.dot(c1.cross(c2));
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    Some(Vector::new(
        b.dot(c1.cross(c2)) / det,
        c0.dot(b.cross(c2)) / det,
        c0.dot(c1.cross(b)) / det,
    ))
}

/// q ⊗ exp(φ/2) for the body-frame rotation vector φ, re-normalized: the rotation by |φ|
/// about φ/|φ| composed on the body side (exponential map of the quaternion update).
pub fn integrate_orientation(q: Rotation, phi: Vector) -> Rotation {
    let angle = phi.length();
    if angle == 0.0 {
        return q;
    }
    let half = 0.5 * angle;
    let s = half.sin() / angle;
    let dq = Rotation::from_xyzw(phi.x * s, phi.y * s, phi.z * s, half.cos());
    (q * dq).normalize()
}

/// A quaternion (w, x, y, z) as parry's rotation.
pub fn rotation_from_wxyz(q: [f64; 4]) -> Rotation {
    Rotation::from_xyzw(q[1], q[2], q[3], q[0])
}

/// Parry's rotation as (w, x, y, z).
pub fn rotation_to_wxyz(q: Rotation) -> [f64; 4] {
    [q.w, q.x, q.y, q.z]
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn free_rotation_conserves_energy_and_momentum_per_step() {
        let inertia = [1.0, 2.0, 3.0];
        let i = Vector::from_array(inertia);
        let w0 = Vector::new(0.3, 5.0, 0.2);
        let f = free_rotation(inertia, w0, 1e-2);
        assert!(f.converged);
        let e = |w: Vector| 0.5 * w.dot(i * w);
        assert!((e(f.omega) - e(w0)).abs() <= 1e-14 * e(w0));
        assert!(((i * f.omega).length() - (i * w0).length()).abs() <= 1e-14 * (i * w0).length());
        assert!(
            (f.omega - w0).length() > 1e-4,
            "the asymmetric top precesses"
        );
    }

    pub fn exponential_map_rotates_about_the_body_axis() {
        let q = integrate_orientation(
            Rotation::IDENTITY,
            Vector::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        let x = q * Vector::X;
        assert!((x - Vector::Y).length() < 1e-15);
        assert!((q.length() - 1.0).abs() < 1e-15);
    }
}
