//! Assembly of the incremental problem (2.10) of one Moreau–Jean step, in FCLIB convention
//! (`M v = H r + f`, `u = Hᵀ v + w`, d = 3, contact blocks normal first):
//!
//! ```text
//!     M = diag(m, m, m, I, I, I, …)                 (block diagonal, I = 2/5 m R²)
//!     f = M v_k + h F_ext                           (2.5): F_ext = gravity
//!     Hᵀ v + w = u_{k+1} (+ e u_{N,k} on normal rows) (2.5) and Moreau's impact law
//! ```
//!
//! For a contact between sphere A and B (sphere or obstacle) at point p with frame
//! (t₀ = n, t₁, t₂), column 3i + k of H holds tₖ on A's translational rows and
//! (p − x_A) × tₖ on A's rotational rows, and the opposite for a sphere B, so that
//! (Hᵀ v)ₖ = tₖ · (v_A(p) − v_B(p)). The obstacle's prescribed velocity V_B(p, t_{k+1})
//! goes to w: wₖ = −tₖ · V_B. Moreau's rule (§2.1, after (2.10)) replaces the unknown normal
//! velocity by U_N = u_{N,k+1} + e u_{N,k} for contacts approaching at t_k (u_{N,k} ≤ 0);
//! a contact separating at t_k gets U_N = u_{N,k+1} + u_{N,k} ([`impact_offset`]), so that
//! the step never creates energy.

use crate::contact::{Contact, Partner};
use crate::math::Vec3;
use crate::world::{ContactLaw, World};
use coulomb::problem::{GlobalProblem, ProblemError};
use coulomb::sparse::CscMatrix;

/// Data of one step's assembly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepData {
    /// time step h
    pub h: f64,
    /// time t_{k+1} at which obstacle velocities are evaluated
    pub t_end: f64,
    /// restitution coefficient e ∈ [0, 1] of every contact when the world has no material
    /// table ([`crate::world::World::materials`]); otherwise each contact's pair law's
    pub restitution: f64,
    /// friction coefficient μ of every contact when the world has no material table;
    /// otherwise each contact's pair law's ([`StepData::law`])
    pub mu: f64,
    /// close the gap of a contact held by gravity's look-ahead ([`gap_closure`];
    /// [`crate::contact::Activation::close_gaps`])
    pub close_gaps: bool,
}

impl StepData {
    /// The law (μ, e) of contact `c`: the pair of materials' in the world's table, or
    /// (`self.mu`, `self.restitution`) without a table (the one-material fast path: the very
    /// numbers of the parameters). μ_r is not part of the step data (0 here).
    #[inline]
    pub fn law(&self, world: &World, c: &Contact) -> ContactLaw {
        let default = ContactLaw {
            mu: self.mu,
            restitution: self.restitution,
            rolling_friction: 0.0,
        };
        if world.materials.is_none() {
            return default;
        }
        world.contact_law(c.body, c.partner, default)
    }
}

/// Diagonal of M: (m, m, m, I, I, I) per sphere.
pub fn mass_diagonal(world: &World) -> Vec<f64> {
    let mut d = Vec::with_capacity(world.dofs());
    for b in &world.bodies {
        let i = b.inertia();
        d.extend_from_slice(&[b.mass, b.mass, b.mass, i, i, i]);
    }
    d
}

/// f = M v_k + h F_ext (gravity acts on the translational dofs).
pub fn free_momentum(world: &World, h: f64) -> Vec<f64> {
    let mut f = Vec::with_capacity(world.dofs());
    for b in &world.bodies {
        let p = b.velocity * b.mass + world.gravity * (h * b.mass);
        f.extend_from_slice(&p.to_array());
        let l = if b.rotation_locked {
            Vec3::ZERO
        } else {
            b.angular_velocity * b.inertia()
        };
        f.extend_from_slice(&l.to_array());
    }
    f
}

/// H (n × 3·contacts) as triplets pushed into (rows, cols, vals).
fn push_h(world: &World, contacts: &[Contact]) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let cap = contacts.len() * 3 * 12;
    let (mut rows, mut cols, mut vals) = (
        Vec::with_capacity(cap),
        Vec::with_capacity(cap),
        Vec::with_capacity(cap),
    );
    for (i, c) in contacts.iter().enumerate() {
        let frame = [c.normal, c.t1, c.t2];
        let mut side = |body: usize, sign: f64| {
            let Some(b) = world.bodies.get(body) else {
                return;
            };
            let arm = c.point - b.position;
            for (k, t) in frame.iter().enumerate() {
                let col = 3 * i + k;
                for (r, val) in t.to_array().into_iter().enumerate() {
                    if val != 0.0 {
                        rows.push(6 * body + r);
                        cols.push(col);
                        vals.push(sign * val);
                    }
                }
                if !b.rotation_locked {
                    for (r, val) in arm.cross(*t).to_array().into_iter().enumerate() {
                        if val != 0.0 {
                            rows.push(6 * body + 3 + r);
                            cols.push(col);
                            vals.push(sign * val);
                        }
                    }
                }
            }
        };
        side(c.body, 1.0);
        if let Partner::Body(j) = c.partner {
            side(j, -1.0);
        }
    }
    (rows, cols, vals)
}

/// The term added to the normal row of an active contact by the impact law: the normal
/// unknown is U_N = u_{N,k+1} + ê u_{N,k} with ê = e for a contact approaching at t_k
/// (u_{N,k} ≤ 0, Moreau's rule) and ê = 1 for one that separates (u_{N,k} > 0, kept in the
/// index set because it penetrates). With r_N ⊥ U_N the normal work of the step,
/// ½ r_N (u_{N,k+1} + u_{N,k}) = ½ r_N (1 − ê) u_{N,k}, is then ≤ 0 for every e ∈ [0, 1]
/// (docs/granular.md, "Energy"); ê u_{N,k} = max(e u_{N,k}, u_{N,k}).
pub fn impact_offset(restitution: f64, u_nk: f64) -> f64 {
    (restitution * u_nk).max(u_nk)
}

/// w: the obstacles' prescribed motion −tₖ·V_B(p, t_{k+1}) plus the impact law's
/// [`impact_offset`] on the normal row.
pub fn contact_offset(world: &World, contacts: &[Contact], data: &StepData) -> Vec<f64> {
    contacts
        .iter()
        .flat_map(|c| contact_offset_one(world, c, data))
        .collect()
}

/// w_i of one contact (the three entries of [`contact_offset`] for `c`).
pub fn contact_offset_one(world: &World, c: &Contact, data: &StepData) -> [f64; 3] {
    let mut w = [0.0; 3];
    if let Partner::Obstacle(o, _) = c.partner {
        if let Some(ob) = world.obstacles.get(o) {
            let vb = ob.motion.velocity_at(c.point, data.t_end);
            w = [-c.normal.dot(vb), -c.t1.dot(vb), -c.t2.dot(vb)];
        }
    }
    let e = if world.materials.is_none() {
        data.restitution
    } else {
        data.law(world, c).restitution
    };
    w[0] += impact_offset(e, c.normal_velocity);
    if data.close_gaps {
        w[0] += gap_closure_with(world, c, data, e);
    }
    w
}

/// The term (1 − e) g_k / h added to the normal row of a sphere–obstacle contact held by
/// gravity's look-ahead: one with a positive gap g_k that approaches no faster than gravity
/// accelerates it in one step (u_{N,k} ≥ h γ_g·n, γ_g·n < 0 the gravity's normal
/// component). The activation rule ([`crate::contact::Activation`]) makes such a contact
/// active up to h² |γ_g·n| above the obstacle; without this term U_N ≥ 0 would hold the
/// sphere at that gap for good (a sphere at rest "hovers"). With it the law reads
/// U_N = u_{N,k+1} + ê u_{N,k} + (1 − e) g_k / h ≥ 0: for e = 0 the sphere may close the gap
/// in the step, for e = 1 nothing changes (an elastic sphere micro-bounces forever: holding
/// it conserves energy). Energy: the normal work ½ r_N (u_{N,k+1} + u_{N,k}) gains the term
/// −½ r_N (1 − e) g_k / h ≤ 0, so the step still never creates energy (docs/granular.md,
/// "Energy" and "Resting on an obstacle"). Fast impacts (u_{N,k} < h γ_g·n) are left to
/// Moreau's law alone: their rebound ratio stays exactly e. 0 for sphere–sphere contacts
/// (gravity cancels in their look-ahead).
pub fn gap_closure(world: &World, c: &Contact, data: &StepData) -> f64 {
    gap_closure_with(world, c, data, data.law(world, c).restitution)
}

/// [`gap_closure`] with the contact's restitution e given.
fn gap_closure_with(world: &World, c: &Contact, data: &StepData, restitution: f64) -> f64 {
    let Partner::Obstacle(..) = c.partner else {
        return 0.0;
    };
    let gn = world.gravity.dot(c.normal);
    let held = gn < 0.0 && c.gap > 0.0 && c.normal_velocity >= data.h * gn;
    if held && data.h > 0.0 {
        (1.0 - restitution).clamp(0.0, 1.0) * c.gap / data.h
    } else {
        0.0
    }
}

/// Builds the global problem (2.10) of the step: (M, H, f, w, μ) in FCLIB convention.
pub fn assemble(
    world: &World,
    contacts: &[Contact],
    data: &StepData,
) -> Result<GlobalProblem, ProblemError> {
    let n = world.dofs();
    let m = 3 * contacts.len();
    let diag = mass_diagonal(world);
    let mass = CscMatrix {
        nrows: n,
        ncols: n,
        col_ptr: (0..=n).collect(),
        row_idx: (0..n).collect(),
        values: diag,
    };
    let (rows, cols, vals) = push_h(world, contacts);
    let h = CscMatrix::from_triplets(n, m, &rows, &cols, &vals)
        .map_err(|source| ProblemError::Sparse { what: "H", source })?;
    let f = free_momentum(world, data.h);
    let w = contact_offset(world, contacts, data);
    let mu = if world.materials.is_none() {
        vec![data.mu; contacts.len()]
    } else {
        contacts.iter().map(|c| data.law(world, c).mu).collect()
    };
    GlobalProblem::new_unfactored(3, mass, h, f, w, mu)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::contact::{detect, relative_velocity, Activation};
    use crate::world::{Motion, Obstacle, Shape, Sphere};

    /// A world with two touching spheres and a moving ground under the first one.
    fn world() -> World {
        let mut w = World::new();
        w.obstacles.push(Obstacle {
            name: "plate".into(),
            shape: Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
            motion: Motion::Oscillate {
                direction: Vec3::Z,
                amplitude: 0.0,
                frequency: 0.0,
            },
            material: 0,
        });
        w.obstacles.push(Obstacle {
            name: "drum".into(),
            shape: Shape::CylinderInside {
                point: Vec3::new(0.0, 0.0, 1.0),
                axis: Vec3::Y,
                radius: 1.0,
            },
            motion: Motion::Rotate {
                center: Vec3::new(0.0, 0.0, 1.0),
                axis: Vec3::Y,
                omega: 3.0,
            },
            material: 0,
        });
        let mut a = Sphere::new(Vec3::new(0.0, 0.0, 0.1), 0.1, 2.0);
        a.velocity = Vec3::new(0.3, -0.2, -0.5);
        a.angular_velocity = Vec3::new(1.0, 2.0, -0.5);
        let mut b = Sphere::new(Vec3::new(0.108, 0.0, 0.244), 0.08, 1.0);
        b.velocity = Vec3::new(-0.1, 0.4, -0.7);
        b.angular_velocity = Vec3::new(-2.0, 0.5, 1.5);
        w.bodies.push(a);
        w.bodies.push(b);
        w
    }

    pub fn h_and_w_give_the_relative_velocities() {
        let w = world();
        let contacts = detect(&w, 0.0, 0.02, &Activation::default());
        assert_eq!(contacts.len(), 3, "{contacts:?}");
        let data = StepData {
            h: 0.02,
            t_end: 0.0,
            restitution: 0.0,
            mu: 0.3,
            close_gaps: true,
        };
        let p = assemble(&w, &contacts, &data).unwrap();
        let u = p.velocity(&w.velocities());
        for (i, c) in contacts.iter().enumerate() {
            let rel = relative_velocity(&w, c.body, c.partner, c.point, 0.0);
            for (k, t) in [c.normal, c.t1, c.t2].iter().enumerate() {
                assert!(
                    (u[3 * i + k] - t.dot(rel)).abs() < 1e-12,
                    "contact {i} component {k}: {} vs {}",
                    u[3 * i + k],
                    t.dot(rel)
                );
            }
        }
        // the drum's wall moves at ω R = 3 m/s along −x at the bottom: seen in the tangent rows
        let drum = contacts
            .iter()
            .position(|c| c.partner == Partner::Obstacle(1, 0))
            .unwrap();
        let c = &contacts[drum];
        // V_B = 3 e_y × (p − c) = 3 (p_z − 1, 0, −p_x)
        let vb = Vec3::new(3.0 * (c.point.z - 1.0), 0.0, -3.0 * c.point.x);
        assert!(vb.norm() > 2.9);
        assert!((p.w[3 * drum + 1] + c.t1.dot(vb)).abs() < 1e-9);
        assert!((p.w[3 * drum + 2] + c.t2.dot(vb)).abs() < 1e-9);
    }

    pub fn restitution_enters_the_normal_rows_only_when_approaching() {
        let w = world();
        let contacts = detect(&w, 0.0, 0.02, &Activation::default());
        let data = StepData {
            h: 0.02,
            t_end: 0.0,
            restitution: 0.2,
            mu: 0.3,
            close_gaps: true,
        };
        let p0 = assemble(
            &w,
            &contacts,
            &StepData {
                restitution: 0.0,
                ..data
            },
        )
        .unwrap();
        let p = assemble(&w, &contacts, &data).unwrap();
        for (i, c) in contacts.iter().enumerate() {
            let extra = if c.normal_velocity < 0.0 {
                0.2 * c.normal_velocity
            } else {
                0.0
            };
            assert!((p.w[3 * i] - p0.w[3 * i] - extra).abs() < 1e-15);
            assert_eq!(p.w[3 * i + 1], p0.w[3 * i + 1]);
        }
        assert!(contacts.iter().any(|c| c.normal_velocity < 0.0));
        // the impact law: ê = e when approaching, 1 when separating
        assert_eq!(impact_offset(0.2, -1.0), -0.2);
        assert_eq!(impact_offset(0.2, 0.5), 0.5);
        assert_eq!(impact_offset(1.0, 0.5), 0.5);
        assert_eq!(impact_offset(0.0, -0.5), 0.0);
    }

    pub fn mass_and_free_momentum() {
        let w = world();
        let d = mass_diagonal(&w);
        assert_eq!(d.len(), 12);
        assert!((d[3] - 0.4 * 2.0 * 0.01).abs() < 1e-15);
        let f = free_momentum(&w, 0.02);
        assert!((f[2] - (2.0 * -0.5 - 2.0 * 9.81 * 0.02)).abs() < 1e-12);
        assert!((f[0] - 0.6).abs() < 1e-15);
    }
}
