//! The mechanical system: rigid spheres (6 dofs each) and obstacles (fixed or kinematically
//! driven), the data of (2.1)–(2.3) for a granular material, and the contact laws of the
//! pairs of materials.
//!
//! # Obstacles
//! An obstacle is a [`Shape`] in its reference position with a prescribed rigid [`Motion`]
//! (§5.6: external objects in rigid motion). A sphere's contacts with it are found by a
//! closest-point query ([`Obstacle::proximities`]): one [`Proximity`] per touching *feature*
//! (a wall of a box, the lateral wall or a cap of a cylinder, a triangle of a mesh; one
//! feature for the other shapes), the feature's index completing the contact's key
//! (the contact partner `Partner::Obstacle` of the collision module) so that warm starts follow it across steps.
//!
//! Motions and shapes combine freely. Translations ([`Motion::Translate`],
//! [`Motion::Oscillate`]) move the shape rigidly: exact for every shape. A rotation
//! ([`Motion::Rotate`]) moves the shape rigidly too: the query is made in the obstacle's
//! frame (the sphere centre rotated by −ωt about the axis) and the point and normal rotated
//! back; for a shape that the rotation maps onto itself (a plane orthogonal to the axis, a
//! cylinder or a sphere centred on it: [`Obstacle::rotation_invariant`]) that transformation
//! is skipped (it changes nothing but rounding), and only the surface velocity ω × (p − c)
//! matters. Every combination is exact; an infinite shape (plane, infinite cylinder) rotating
//! about an axis that does not leave it invariant has an unbounded surface speed and is
//! refused by the scene model.

use crate::math::Vec3;
use crate::mesh::{Region, TriangleMesh};
use serde::{Deserialize, Serialize};

/// Gravity used by every scene (m/s²), acting along −e_z.
pub const GRAVITY: f64 = 9.81;

/// A rigid sphere: 3 translational and 3 rotational dofs, v = (ẋ, ω). Its mass matrix is
/// diag(m, m, m, I, I, I) with I = 2/5 m R² (a solid ball; M is constant, as (2.5) assumes).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    /// centre x
    pub position: Vec3,
    /// translational velocity ẋ
    pub velocity: Vec3,
    /// angular velocity ω
    pub angular_velocity: Vec3,
    /// radius R
    pub radius: f64,
    /// mass m
    pub mass: f64,
    /// when true, the rotation is locked: ω stays 0 and contacts do not act on it
    pub rotation_locked: bool,
    /// index of its material in [`World::materials`] (0 without a table)
    #[serde(default)]
    pub material: u32,
}

impl Sphere {
    /// A sphere at rest at `position` (material 0).
    pub fn new(position: Vec3, radius: f64, mass: f64) -> Self {
        Self {
            position,
            velocity: Vec3::ZERO,
            angular_velocity: Vec3::ZERO,
            radius,
            mass,
            rotation_locked: false,
            material: 0,
        }
    }
    /// Moment of inertia 2/5 m R² of a solid ball.
    pub fn inertia(&self) -> f64 {
        0.4 * self.mass * self.radius * self.radius
    }
    /// Kinetic energy ½ m |ẋ|² + ½ I |ω|².
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mass * self.velocity.norm_sq()
            + 0.5 * self.inertia() * self.angular_velocity.norm_sq()
    }
}

/// The coefficients of the contact law of one pair of materials (a coefficient not given:
/// [`ContactLaw::DEFAULT`]'s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ContactLaw {
    /// friction coefficient μ ≥ 0 of Coulomb's cone (2.9)
    pub mu: f64,
    /// Newton restitution coefficient e ∈ [0, 1] of Moreau's impact law
    pub restitution: f64,
    /// rolling-friction coefficient μ_r ≥ 0 ([`crate::rolling`])
    pub rolling_friction: f64,
}

impl Default for ContactLaw {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl ContactLaw {
    /// The law of `Params::default()` and of every pair of materials without one of its own:
    /// μ = 0.3, e = 0.2, μ_r = 0.
    pub const DEFAULT: ContactLaw = ContactLaw {
        mu: 0.3,
        restitution: 0.2,
        rolling_friction: 0.0,
    };
    /// Why the coefficients are out of range (μ, μ_r finite ≥ 0, e ∈ [0, 1]), if they are.
    pub fn check(&self) -> Result<(), String> {
        if !(self.mu.is_finite() && self.mu >= 0.0) {
            return Err(format!("mu = {} is not a finite number ≥ 0", self.mu));
        }
        if !(0.0..=1.0).contains(&self.restitution) {
            return Err(format!(
                "restitution = {} is not in [0, 1]",
                self.restitution
            ));
        }
        if !(self.rolling_friction.is_finite() && self.rolling_friction >= 0.0) {
            return Err(format!(
                "rolling_friction = {} is not a finite number ≥ 0",
                self.rolling_friction
            ));
        }
        Ok(())
    }
}

/// The contact laws of every pair of materials: `names[k]` is material k (the index that
/// spheres and obstacles carry), `laws[a · n + b]` the law of the pair (a, b), symmetric.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialTable {
    /// material names, in index order
    pub names: Vec<String>,
    /// n × n laws, row-major, symmetric
    pub laws: Vec<ContactLaw>,
}

impl MaterialTable {
    /// A table of the materials `names` whose every pair has the law `default`.
    pub fn uniform(names: Vec<String>, default: ContactLaw) -> Self {
        let n = names.len();
        Self {
            names,
            laws: vec![default; n * n],
        }
    }
    /// Number of materials.
    pub fn len(&self) -> usize {
        self.names.len()
    }
    /// Whether the table has no material.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }
    /// The index of material `name`.
    pub fn index(&self, name: &str) -> Option<u32> {
        self.names.iter().position(|n| n == name).map(|i| i as u32)
    }
    /// The law of the pair (a, b), `None` when an index is out of range.
    pub fn law(&self, a: u32, b: u32) -> Option<ContactLaw> {
        let n = self.names.len();
        let (a, b) = (a as usize, b as usize);
        (a < n && b < n).then(|| self.laws.get(a * n + b).copied())?
    }
    /// Sets the law of the pair (a, b) and (b, a).
    pub fn set(&mut self, a: u32, b: u32, law: ContactLaw) {
        let n = self.names.len();
        let (a, b) = (a as usize, b as usize);
        if a < n && b < n && self.laws.len() == n * n {
            self.laws[a * n + b] = law;
            self.laws[b * n + a] = law;
        }
    }
    /// Whether some pair has rolling friction μ_r > 0.
    pub fn any_rolling(&self) -> bool {
        self.laws.iter().any(|l| l.rolling_friction > 0.0)
    }
    /// Why the table is malformed (sizes, asymmetry, coefficients out of range), if it is.
    pub fn check(&self) -> Result<(), String> {
        let n = self.names.len();
        if n == 0 || self.laws.len() != n * n {
            return Err(format!(
                "{} materials need {} pair laws, the table has {}",
                n,
                n * n,
                self.laws.len()
            ));
        }
        for a in 0..n {
            for b in 0..n {
                let l = self.laws[a * n + b];
                l.check()
                    .map_err(|e| format!("pair ({}, {}): {e}", self.names[a], self.names[b]))?;
                if l != self.laws[b * n + a] {
                    return Err(format!(
                        "pair ({}, {}) differs from ({}, {})",
                        self.names[a], self.names[b], self.names[b], self.names[a]
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Which side of a mesh the spheres live on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MeshSide {
    /// either side: a two-sided surface, open or closed (a chute, a funnel, a drum's shell)
    #[default]
    Surface,
    /// inside a closed, consistently oriented mesh (a container)
    Inside,
    /// outside a closed, consistently oriented mesh (a solid)
    Outside,
}

fn yes() -> bool {
    true
}

fn z_axis() -> Vec3 {
    Vec3::Z
}

/// The shape of an obstacle, in its reference position (time-independent).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// The infinite plane through `point` with unit `normal`; spheres live on the side the
    /// normal points to (ground, walls, vibrating plate).
    Plane {
        /// a point of the plane
        point: Vec3,
        /// unit normal, towards the free side
        normal: Vec3,
    },
    /// A thin two-sided rectangle: centre, unit normal, unit in-plane axis `u` (the other
    /// axis is normal × u) and half-lengths (funnel walls).
    Rectangle {
        /// centre
        center: Vec3,
        /// unit normal
        normal: Vec3,
        /// unit in-plane axis
        u: Vec3,
        /// half-length along u
        half_u: f64,
        /// half-length along normal × u
        half_v: f64,
    },
    /// The inside of an infinite circular cylinder (rotating drum): spheres live within
    /// distance `radius` of the axis.
    CylinderInside {
        /// a point of the axis
        point: Vec3,
        /// unit axis direction
        axis: Vec3,
        /// inner radius
        radius: f64,
    },
    /// The axis-aligned box [lo, hi]. `inside`: a container of thin walls (features 0–5: the
    /// walls x = lo, x = hi, y = lo, y = hi, z = lo, z = hi), without its top wall z = hi
    /// when `open_top`; otherwise a solid box the spheres stay out of (one feature: the
    /// closest point of the box).
    Box {
        /// lower corner
        lo: Vec3,
        /// upper corner
        hi: Vec3,
        /// container (true, the default) or solid (false)
        #[serde(default = "yes")]
        inside: bool,
        /// container without its top wall z = hi
        #[serde(default)]
        open_top: bool,
    },
    /// A finite circular cylinder: axis from `base` along the unit `axis` over `height`.
    /// `inside`: a container of thin walls (feature 0: the lateral wall, 1: the bottom cap
    /// at `base`, 2: the top cap), the caps optional, the bottom cap pierced by a centred
    /// circular orifice of radius `orifice` (a silo); otherwise a solid cylinder with both
    /// caps (one feature; `bottom_cap`, `top_cap` must stay true, `orifice` 0).
    Cylinder {
        /// centre of the bottom cap
        base: Vec3,
        /// unit axis, bottom to top (default +z)
        #[serde(default = "z_axis")]
        axis: Vec3,
        /// radius
        radius: f64,
        /// length along the axis
        height: f64,
        /// container (true, the default) or solid (false)
        #[serde(default = "yes")]
        inside: bool,
        /// the bottom cap is there
        #[serde(default = "yes")]
        bottom_cap: bool,
        /// the top cap is there
        #[serde(default = "yes")]
        top_cap: bool,
        /// radius of the orifice in the bottom cap (0: none)
        #[serde(default)]
        orifice: f64,
    },
    /// A sphere of radius `radius` about `center`: the spheres live inside it (`inside`, a
    /// spherical container) or outside (a ball; fixed bodies of the scene model are these).
    Sphere {
        /// centre
        center: Vec3,
        /// radius
        radius: f64,
        /// container (true) or solid (false, the default)
        #[serde(default)]
        inside: bool,
    },
    /// A triangle mesh, open or closed (features: the triangles; duplicate contacts at shared
    /// edges and vertices removed, [`crate::mesh`]).
    Mesh {
        /// vertices and triangles, with the spatial index
        mesh: TriangleMesh,
        /// which side the spheres live on
        #[serde(default)]
        side: MeshSide,
    },
}

/// Prescribed rigid motion of an obstacle (§5.6: external objects in rigid motion).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Motion {
    /// motionless (the default)
    #[default]
    Fixed,
    /// translation d(t) = v t at constant velocity v
    Translate {
        /// velocity v (m/s)
        velocity: Vec3,
    },
    /// translation d(t) = A sin(2π f t) · direction (vibrating plate)
    Oscillate {
        /// unit direction
        direction: Vec3,
        /// amplitude A (m)
        amplitude: f64,
        /// frequency f (Hz)
        frequency: f64,
    },
    /// rotation by the angle ω t about the line through `center` along the unit `axis`
    /// (right-handed); see the module docs for how shapes follow it
    Rotate {
        /// a point of the rotation axis
        center: Vec3,
        /// unit axis
        axis: Vec3,
        /// angular velocity (rad/s)
        omega: f64,
    },
}

impl Motion {
    /// Translation of the shape at time t.
    pub fn offset(&self, t: f64) -> Vec3 {
        match self {
            Motion::Oscillate {
                direction,
                amplitude,
                frequency,
            } => *direction * (amplitude * (2.0 * std::f64::consts::PI * frequency * t).sin()),
            Motion::Translate { velocity } => *velocity * t,
            _ => Vec3::ZERO,
        }
    }
    /// A bound on the normal speed of the obstacle's surface, max_t |n·V_B|, for a shape the
    /// motion maps onto itself: |v| for a translation, A·2πf for an oscillation, 0 for a
    /// fixed obstacle and for a rotation (its surface moves in itself). For any shape use
    /// [`Obstacle::max_normal_speed`].
    pub fn max_normal_speed(&self) -> f64 {
        match self {
            Motion::Oscillate {
                amplitude,
                frequency,
                ..
            } => (amplitude * 2.0 * std::f64::consts::PI * frequency).abs(),
            Motion::Translate { velocity } => velocity.norm(),
            Motion::Fixed | Motion::Rotate { .. } => 0.0,
        }
    }
    /// Velocity of the obstacle's material point at position p and time t.
    pub fn velocity_at(&self, p: Vec3, t: f64) -> Vec3 {
        match self {
            Motion::Fixed => Vec3::ZERO,
            Motion::Translate { velocity } => *velocity,
            Motion::Oscillate {
                direction,
                amplitude,
                frequency,
            } => {
                let w = 2.0 * std::f64::consts::PI * frequency;
                *direction * (amplitude * w * (w * t).cos())
            }
            Motion::Rotate {
                center,
                axis,
                omega,
            } => (*axis * *omega).cross(p - *center),
        }
    }
    /// Why the motion's data are invalid (non-finite, non-unit axis), if they are.
    pub fn check(&self) -> Result<(), String> {
        let unit = |v: Vec3| v.is_finite() && (v.norm() - 1.0).abs() < 1e-9;
        match self {
            Motion::Fixed => Ok(()),
            Motion::Translate { velocity } if velocity.is_finite() => Ok(()),
            Motion::Oscillate {
                direction,
                amplitude,
                frequency,
            } if unit(*direction) && amplitude.is_finite() && frequency.is_finite() => Ok(()),
            Motion::Rotate {
                center,
                axis,
                omega,
            } if center.is_finite() && unit(*axis) && omega.is_finite() => Ok(()),
            m => Err(format!(
                "motion {m:?}: non-finite value or direction/axis not a unit vector"
            )),
        }
    }
}

/// An obstacle: a shape with a prescribed motion and a material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// a name for outputs ("ground", "plate", "drum", …)
    pub name: String,
    /// the shape in its reference position
    pub shape: Shape,
    /// its prescribed motion
    pub motion: Motion,
    /// index of its material in [`World::materials`] (0 without a table)
    #[serde(default)]
    pub material: u32,
}

/// Closest-point query of a sphere against an obstacle: the gap g (negative when
/// penetrating), the unit normal n pointing from the obstacle towards the sphere centre,
/// and the contact point on the obstacle surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Proximity {
    /// signed gap g = distance − R
    pub gap: f64,
    /// unit normal, obstacle → sphere
    pub normal: Vec3,
    /// contact point on the obstacle
    pub point: Vec3,
}

impl Proximity {
    /// No feature in reach.
    pub const FAR: Proximity = Proximity {
        gap: f64::INFINITY,
        normal: Vec3::Z,
        point: Vec3::ZERO,
    };
}

/// Closest point of the rectangle (centre c, axes u, v, half-lengths) to x, two-sided.
#[allow(clippy::too_many_arguments)]
fn rectangle_proximity(
    x: Vec3,
    radius: f64,
    c: Vec3,
    normal: Vec3,
    u: Vec3,
    v: Vec3,
    half_u: f64,
    half_v: f64,
) -> Proximity {
    let d = x - c;
    let a = d.dot(u).clamp(-half_u, half_u);
    let b = d.dot(v).clamp(-half_v, half_v);
    let p = c + u * a + v * b;
    let e = x - p;
    let dist = e.norm();
    let side = if d.dot(normal) >= 0.0 {
        normal
    } else {
        -normal
    };
    Proximity {
        gap: dist - radius,
        normal: e.normalized_or(side),
        point: p,
    }
}

/// A unit vector orthogonal to the unit `axis`.
fn orthogonal(axis: Vec3) -> Vec3 {
    axis.tangent_basis().0
}

impl Shape {
    /// Number of features (contacts one sphere can have with it at once, at most).
    pub fn features(&self) -> usize {
        match self {
            Shape::Box { inside: true, .. } => 6,
            Shape::Cylinder { inside: true, .. } => 3,
            Shape::Mesh { mesh, .. } => mesh.triangles().len(),
            _ => 1,
        }
    }

    /// The proximity of feature `f` in the shape's reference position translated by `off`
    /// (legacy shapes compute exactly as before features existed).
    fn feature(&self, f: u32, x: Vec3, radius: f64, off: Vec3) -> Option<Proximity> {
        if f as usize >= self.features() {
            return None;
        }
        match self {
            Shape::Plane { point, normal } => {
                let p0 = *point + off;
                let d = (x - p0).dot(*normal);
                Some(Proximity {
                    gap: d - radius,
                    normal: *normal,
                    point: x - *normal * d,
                })
            }
            Shape::Rectangle {
                center,
                normal,
                u,
                half_u,
                half_v,
            } => Some(rectangle_proximity(
                x,
                radius,
                *center + off,
                *normal,
                *u,
                normal.cross(*u),
                *half_u,
                *half_v,
            )),
            Shape::CylinderInside {
                point,
                axis,
                radius: rc,
            } => {
                let p0 = *point + off;
                let d = x - p0;
                let radial = d - *axis * d.dot(*axis);
                let rho = radial.norm();
                let outward = radial.normalized_or(-Vec3::Z);
                Some(Proximity {
                    gap: rc - rho - radius,
                    normal: -outward,
                    point: x + outward * (rc - rho),
                })
            }
            Shape::Box {
                lo,
                hi,
                inside: true,
                open_top,
            } => {
                if f >= 6 || (*open_top && f == 5) {
                    return None;
                }
                let (lo, hi) = (*lo + off, *hi + off);
                let k = (f / 2) as usize;
                let at_hi = f % 2 == 1;
                let (a, b) = ((k + 1) % 3, (k + 2) % 3);
                let unit = |i: usize| [Vec3::X, Vec3::Y, Vec3::Z][i];
                let face = if at_hi { hi.get(k) } else { lo.get(k) };
                let inward = if at_hi { -unit(k) } else { unit(k) };
                let c = (lo + hi) * 0.5;
                let center = c + unit(k) * (face - c.get(k));
                Some(rectangle_proximity(
                    x,
                    radius,
                    center,
                    inward,
                    unit(a),
                    unit(b),
                    0.5 * (hi.get(a) - lo.get(a)),
                    0.5 * (hi.get(b) - lo.get(b)),
                ))
            }
            Shape::Box {
                lo,
                hi,
                inside: false,
                ..
            } => {
                if f != 0 {
                    return None;
                }
                let (lo, hi) = (*lo + off, *hi + off);
                let p = x.max(lo).min(hi);
                let e = x - p;
                let dist = e.norm();
                if dist > 0.0 {
                    return Some(Proximity {
                        gap: dist - radius,
                        normal: e * (1.0 / dist),
                        point: p,
                    });
                }
                // centre inside the solid: out through the nearest face
                let mut best = (f64::INFINITY, Vec3::Z, x);
                for k in 0..3 {
                    let unit = [Vec3::X, Vec3::Y, Vec3::Z][k];
                    let dl = x.get(k) - lo.get(k);
                    let dh = hi.get(k) - x.get(k);
                    if dl < best.0 {
                        best = (dl, -unit, x - unit * dl);
                    }
                    if dh < best.0 {
                        best = (dh, unit, x + unit * dh);
                    }
                }
                Some(Proximity {
                    gap: -best.0 - radius,
                    normal: best.1,
                    point: best.2,
                })
            }
            Shape::Cylinder {
                base,
                axis,
                radius: rc,
                height,
                inside,
                bottom_cap,
                top_cap,
                orifice,
            } => {
                let b = *base + off;
                let d = x - b;
                let s = d.dot(*axis);
                let radial = d - *axis * s;
                let rho = radial.norm();
                let u = radial.normalized_or(orthogonal(*axis));
                let near = |p: Vec3, fallback: Vec3| {
                    let e = x - p;
                    Proximity {
                        gap: e.norm() - radius,
                        normal: e.normalized_or(fallback),
                        point: p,
                    }
                };
                if *inside {
                    match f {
                        0 => Some(near(
                            b + *axis * s.clamp(0.0, *height) + u * *rc,
                            if rho <= *rc { -u } else { u },
                        )),
                        1 if *bottom_cap => Some(near(
                            b + u * rho.clamp(orifice.min(*rc), *rc),
                            if s >= 0.0 { *axis } else { -*axis },
                        )),
                        2 if *top_cap => Some(near(
                            b + *axis * *height + u * rho.min(*rc),
                            if s <= *height { -*axis } else { *axis },
                        )),
                        _ => None,
                    }
                } else {
                    if f != 0 {
                        return None;
                    }
                    let outside = s < 0.0 || s > *height || rho > *rc;
                    if outside {
                        return Some(near(
                            b + *axis * s.clamp(0.0, *height) + u * rho.min(*rc),
                            u,
                        ));
                    }
                    let (dl, db, dt) = (rc - rho, s, height - s);
                    let (depth, normal, point) = if dl <= db && dl <= dt {
                        (dl, u, x + u * dl)
                    } else if db <= dt {
                        (db, -*axis, x - *axis * db)
                    } else {
                        (dt, *axis, x + *axis * dt)
                    };
                    Some(Proximity {
                        gap: -depth - radius,
                        normal,
                        point,
                    })
                }
            }
            Shape::Sphere {
                center,
                radius: rs,
                inside,
            } => {
                if f != 0 {
                    return None;
                }
                let d = x - (*center + off);
                let dist = d.norm();
                let dir = d.normalized_or(-Vec3::Z);
                let point = *center + off + dir * *rs;
                Some(if *inside {
                    Proximity {
                        gap: rs - dist - radius,
                        normal: -dir,
                        point,
                    }
                } else {
                    Proximity {
                        gap: dist - rs - radius,
                        normal: dir,
                        point,
                    }
                })
            }
            Shape::Mesh { mesh, side } => {
                let xl = x - off;
                let (p, region) = mesh.closest_on(f as usize, xl)?;
                Some(mesh_proximity(mesh, *side, f, xl, radius, p, region, off))
            }
        }
    }

    /// Every feature's proximity with gap ≤ `reach`, translated by `off`, into `out` (as
    /// (feature, proximity), in increasing feature order; not cleared). Features whose
    /// contact points coincide (an edge of two walls seen from outside) are kept once, the
    /// lowest feature.
    fn near(&self, x: Vec3, radius: f64, off: Vec3, reach: f64, out: &mut Vec<(u32, Proximity)>) {
        match self {
            Shape::Mesh { mesh, side } => {
                let xl = x - off;
                mesh.near_each(xl, radius, reach, |t, p, region| {
                    let prox = mesh_proximity(mesh, *side, t, xl, radius, p, region, off);
                    if prox.gap <= reach {
                        out.push((t, prox));
                    }
                });
            }
            _ => {
                let start = out.len();
                for f in 0..self.features() as u32 {
                    if let Some(p) = self.feature(f, x, radius, off) {
                        if p.gap <= reach {
                            let tol = 1e-12 * (1.0 + radius);
                            if !out[start..]
                                .iter()
                                .any(|(_, q)| (q.point - p.point).norm() <= tol)
                            {
                                out.push((f, p));
                            }
                        }
                    }
                }
            }
        }
    }

    /// Whether a rotation about the line (c, unit axis) maps the shape onto itself exactly:
    /// a plane orthogonal to the axis, an infinite or finite cylinder or a sphere centred on it.
    pub fn rotation_invariant(&self, c: Vec3, axis: Vec3) -> bool {
        let on_axis = |p: Vec3| {
            let d = p - c;
            (d - axis * d.dot(axis)).norm() <= 1e-12 * (1.0 + d.norm())
        };
        let parallel = |a: Vec3| a.cross(axis).norm() <= 1e-12;
        match self {
            Shape::Plane { normal, .. } => parallel(*normal),
            Shape::CylinderInside { point, axis: a, .. } => parallel(*a) && on_axis(*point),
            Shape::Cylinder { base, axis: a, .. } => parallel(*a) && on_axis(*base),
            Shape::Sphere { center, .. } => on_axis(*center),
            _ => false,
        }
    }

    /// Largest distance from the point c of a point of the shape (∞ for unbounded shapes).
    pub fn reach_from(&self, c: Vec3) -> f64 {
        match self {
            Shape::Plane { .. } | Shape::CylinderInside { .. } => f64::INFINITY,
            Shape::Rectangle {
                center,
                half_u,
                half_v,
                ..
            } => (*center - c).norm() + half_u.hypot(*half_v),
            Shape::Box { lo, hi, .. } => {
                let mut m: f64 = 0.0;
                for i in 0..8 {
                    let p = Vec3::new(
                        if i & 1 == 0 { lo.x } else { hi.x },
                        if i & 2 == 0 { lo.y } else { hi.y },
                        if i & 4 == 0 { lo.z } else { hi.z },
                    );
                    m = m.max((p - c).norm());
                }
                m
            }
            Shape::Cylinder {
                base,
                radius,
                height,
                ..
            } => (*base - c).norm() + height + radius,
            Shape::Sphere { center, radius, .. } => (*center - c).norm() + radius,
            Shape::Mesh { mesh, .. } => mesh.max_norm() + c.norm(),
        }
    }

    /// Whether the centre x (shape in its reference position) is where a sphere may be:
    /// on the free side of a plane, inside a container (a missing cap leaves its end open),
    /// outside a solid; always for rectangles and two-sided meshes.
    pub fn admits(&self, x: Vec3) -> bool {
        match self {
            Shape::Plane { point, normal } => (x - *point).dot(*normal) >= 0.0,
            Shape::Rectangle { .. } => true,
            Shape::CylinderInside {
                point,
                axis,
                radius,
            } => {
                let d = x - *point;
                (d - *axis * d.dot(*axis)).norm() <= *radius
            }
            Shape::Box {
                lo,
                hi,
                inside,
                open_top,
            } => {
                let within = (0..3).all(|k| {
                    x.get(k) >= lo.get(k)
                        && (x.get(k) <= hi.get(k) || (k == 2 && *open_top && *inside))
                });
                if *inside {
                    within
                } else {
                    !(0..3).all(|k| x.get(k) > lo.get(k) && x.get(k) < hi.get(k))
                }
            }
            Shape::Cylinder {
                base,
                axis,
                radius,
                height,
                inside,
                bottom_cap,
                top_cap,
                ..
            } => {
                let d = x - *base;
                let s = d.dot(*axis);
                let rho = (d - *axis * s).norm();
                if *inside {
                    rho <= *radius && (s >= 0.0 || !bottom_cap) && (s <= *height || !top_cap)
                } else {
                    !(rho < *radius && s > 0.0 && s < *height)
                }
            }
            Shape::Sphere {
                center,
                radius,
                inside,
            } => {
                let d = (x - *center).norm();
                if *inside {
                    d <= *radius
                } else {
                    d >= *radius
                }
            }
            Shape::Mesh { mesh, side } => match side {
                MeshSide::Surface => true,
                MeshSide::Inside => mesh.contains(x).unwrap_or(true),
                MeshSide::Outside => !mesh.contains(x).unwrap_or(false),
            },
        }
    }

    /// Whether the shape is a container (spheres live inside it): the containers of the
    /// "outside every container" check of the scene model.
    pub fn is_container(&self) -> bool {
        matches!(
            self,
            Shape::CylinderInside { .. }
                | Shape::Box { inside: true, .. }
                | Shape::Cylinder { inside: true, .. }
                | Shape::Sphere { inside: true, .. }
                | Shape::Mesh {
                    side: MeshSide::Inside,
                    ..
                }
        )
    }
}

/// The proximity of a sphere (centre xl in the mesh frame) to triangle t at its closest point
/// p: two-sided, except that a centre on the wrong side of a face of a closed mesh whose
/// spheres live inside (outside) is pushed back through that face.
#[allow(clippy::too_many_arguments)]
fn mesh_proximity(
    mesh: &TriangleMesh,
    side: MeshSide,
    t: u32,
    xl: Vec3,
    radius: f64,
    p: Vec3,
    region: Region,
    off: Vec3,
) -> Proximity {
    let n_out = mesh.face_normal(t as usize);
    if region == Region::Face {
        // in a face's interior the distance is along its normal: exact for flat faces
        let d = (xl - p).dot(n_out);
        let wrong = match side {
            MeshSide::Surface => false,
            MeshSide::Inside => d > 0.0,
            MeshSide::Outside => d < 0.0,
        };
        let toward = if d > 0.0 || (d == 0.0 && side != MeshSide::Inside) {
            n_out
        } else {
            -n_out
        };
        let normal = if wrong { -toward } else { toward };
        let dist = d.abs();
        return Proximity {
            gap: if wrong { -dist - radius } else { dist - radius },
            normal,
            point: xl - toward * dist + off,
        };
    }
    let e = xl - p;
    let dist = e.norm();
    let fallback = match side {
        MeshSide::Inside => -n_out,
        _ => n_out,
    };
    Proximity {
        gap: dist - radius,
        normal: e.normalized_or(fallback),
        point: p + off,
    }
}

impl Obstacle {
    /// A fixed obstacle (material 0).
    pub fn fixed(name: &str, shape: Shape) -> Self {
        Self {
            name: name.to_string(),
            shape,
            motion: Motion::Fixed,
            material: 0,
        }
    }

    /// Whether the obstacle's rotation (if any) leaves its shape invariant, or it does not
    /// rotate ([`Shape::rotation_invariant`]).
    pub fn rotation_invariant(&self) -> bool {
        match &self.motion {
            Motion::Rotate { center, axis, .. } => self.shape.rotation_invariant(*center, *axis),
            _ => true,
        }
    }

    /// The rigid rotation (centre, axis, angle) to apply at time t, when the shape rotates and
    /// is not invariant under it.
    fn rotation_at(&self, t: f64) -> Option<(Vec3, Vec3, f64)> {
        match &self.motion {
            Motion::Rotate {
                center,
                axis,
                omega,
            } if !self.shape.rotation_invariant(*center, *axis) => {
                Some((*center, *axis, omega * t))
            }
            _ => None,
        }
    }

    /// A bound on the normal speed max_t |n·V_B| of the obstacle's surface: the motion's
    /// ([`Motion::max_normal_speed`]), and for a rotation of a shape it does not leave
    /// invariant |ω| times the shape's largest distance from the centre (∞ if unbounded).
    pub fn max_normal_speed(&self) -> f64 {
        match &self.motion {
            Motion::Rotate {
                center,
                axis,
                omega,
            } if !self.rotation_invariant() => match &self.shape {
                // |V| = |ω| dist(p, axis), convex in p: its largest value on a triangle is at
                // a vertex
                Shape::Mesh { mesh, .. } => {
                    omega.abs() * mesh.max_distance_from_axis(*center, *axis)
                }
                shape => omega.abs() * shape.reach_from(*center),
            },
            m => m.max_normal_speed(),
        }
    }

    /// The proximities of every feature of the obstacle within `reach` of a sphere (centre x,
    /// radius R, gap ≤ reach) at time t, appended to `out` as (feature, proximity), in
    /// increasing feature order.
    pub fn proximities(
        &self,
        x: Vec3,
        radius: f64,
        t: f64,
        reach: f64,
        out: &mut Vec<(u32, Proximity)>,
    ) {
        match self.rotation_at(t) {
            None => self
                .shape
                .near(x, radius, self.motion.offset(t), reach, out),
            Some((c, axis, angle)) => {
                let (sin, cos) = angle.sin_cos();
                let xl = (x - c).rotated_sc(axis, -sin, cos) + c;
                let start = out.len();
                self.shape.near(xl, radius, Vec3::ZERO, reach, out);
                for (_, p) in &mut out[start..] {
                    p.point = (p.point - c).rotated_sc(axis, sin, cos) + c;
                    p.normal = p.normal.rotated_sc(axis, sin, cos);
                }
            }
        }
    }

    /// The proximity of feature `feature` of the obstacle to a sphere (centre x, radius R) at
    /// time t (`None` if there is no such feature).
    pub fn feature_proximity(
        &self,
        feature: u32,
        x: Vec3,
        radius: f64,
        t: f64,
    ) -> Option<Proximity> {
        match self.rotation_at(t) {
            None => self
                .shape
                .feature(feature, x, radius, self.motion.offset(t)),
            Some((c, axis, angle)) => {
                let (sin, cos) = angle.sin_cos();
                let xl = (x - c).rotated_sc(axis, -sin, cos) + c;
                let mut p = self.shape.feature(feature, xl, radius, Vec3::ZERO)?;
                p.point = (p.point - c).rotated_sc(axis, sin, cos) + c;
                p.normal = p.normal.rotated_sc(axis, sin, cos);
                Some(p)
            }
        }
    }

    /// Gap, normal and contact point of a sphere (centre x, radius R) at time t: the feature
    /// with the smallest gap ([`Proximity::FAR`] for a mesh with no triangle within 2R + 1 of
    /// the centre).
    pub fn proximity(&self, x: Vec3, radius: f64, t: f64) -> Proximity {
        if self.shape.features() == 1 && !matches!(self.shape, Shape::Mesh { .. }) {
            return self
                .feature_proximity(0, x, radius, t)
                .unwrap_or(Proximity::FAR);
        }
        let mut out = Vec::new();
        let reach = if matches!(self.shape, Shape::Mesh { .. }) {
            radius + 1.0
        } else {
            f64::INFINITY
        };
        self.proximities(x, radius, t, reach, &mut out);
        out.into_iter()
            .map(|(_, p)| p)
            .min_by(|a, b| a.gap.total_cmp(&b.gap))
            .unwrap_or(Proximity::FAR)
    }

    /// Centre and radius at time t of a solid sphere obstacle ([`Shape::Sphere`] with
    /// `inside = false`, e.g. a fixed body of the scene model); `None` for other shapes.
    pub fn ball_at(&self, t: f64) -> Option<(Vec3, f64)> {
        let Shape::Sphere {
            center,
            radius,
            inside: false,
        } = &self.shape
        else {
            return None;
        };
        let c = match self.rotation_at(t) {
            Some((rc, axis, angle)) => (*center - rc).rotated(axis, angle) + rc,
            None => *center + self.motion.offset(t),
        };
        Some((c, *radius))
    }

    /// Whether the centre x is where a sphere may be at time t ([`Shape::admits`] in the
    /// obstacle's frame).
    pub fn admits(&self, x: Vec3, t: f64) -> bool {
        let xl = match self.rotation_at(t) {
            Some((c, axis, angle)) => (x - c).rotated(axis, -angle) + c,
            None => x - self.motion.offset(t),
        };
        self.shape.admits(xl)
    }
}

/// The mechanical system: spheres, obstacles, gravity, and the contact laws of the materials.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct World {
    /// the rigid spheres
    pub bodies: Vec<Sphere>,
    /// the obstacles
    pub obstacles: Vec<Obstacle>,
    /// gravity vector (m/s²)
    pub gravity: Vec3,
    /// the contact law of each pair of materials; `None`: every contact has the law of
    /// [`crate::Params`] (μ, e, μ_r), the one-material case
    #[serde(default)]
    pub materials: Option<MaterialTable>,
}

impl World {
    /// An empty world with gravity −g e_z.
    pub fn new() -> Self {
        Self {
            bodies: Vec::new(),
            obstacles: Vec::new(),
            gravity: Vec3::new(0.0, 0.0, -GRAVITY),
            materials: None,
        }
    }
    /// Number of dofs n = 6 · bodies.
    pub fn dofs(&self) -> usize {
        6 * self.bodies.len()
    }
    /// Σ kinetic energies.
    pub fn kinetic_energy(&self) -> f64 {
        self.bodies.iter().map(Sphere::kinetic_energy).sum()
    }
    /// Potential energy −Σ m g·x of the gravity field.
    pub fn potential_energy(&self) -> f64 {
        self.bodies
            .iter()
            .map(|b| -b.mass * self.gravity.dot(b.position))
            .sum()
    }
    /// The velocity vector v = (ẋ₁, ω₁, ẋ₂, ω₂, …) ∈ ℝⁿ.
    pub fn velocities(&self) -> Vec<f64> {
        let mut v = Vec::with_capacity(self.dofs());
        for b in &self.bodies {
            v.extend_from_slice(&b.velocity.to_array());
            v.extend_from_slice(&b.angular_velocity.to_array());
        }
        v
    }
    /// Whether some contact of this world may have rolling friction, given the parameters'
    /// μ_r.
    pub fn has_rolling(&self, default_rolling: f64) -> bool {
        match &self.materials {
            Some(t) => t.any_rolling(),
            None => default_rolling > 0.0,
        }
    }
}

impl Default for World {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn plane_and_cylinder_gaps() {
        let ground = Obstacle::fixed(
            "ground",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        );
        let p = ground.proximity(Vec3::new(1.0, 2.0, 0.3), 0.1, 0.0);
        assert!((p.gap - 0.2).abs() < 1e-15);
        assert_eq!(p.normal, Vec3::Z);
        assert!((p.point - Vec3::new(1.0, 2.0, 0.0)).norm() < 1e-15);

        let drum = Obstacle::fixed(
            "drum",
            Shape::CylinderInside {
                point: Vec3::ZERO,
                axis: Vec3::Y,
                radius: 1.0,
            },
        );
        let p = drum.proximity(Vec3::new(0.0, 5.0, -0.8), 0.1, 0.0);
        assert!((p.gap - 0.1).abs() < 1e-12);
        assert!((p.normal - Vec3::Z).norm() < 1e-12);
        assert!((p.point - Vec3::new(0.0, 5.0, -1.0)).norm() < 1e-12);
    }

    pub fn rectangle_edge_and_face() {
        let r = Obstacle::fixed(
            "r",
            Shape::Rectangle {
                center: Vec3::ZERO,
                normal: Vec3::Z,
                u: Vec3::X,
                half_u: 1.0,
                half_v: 1.0,
            },
        );
        let p = r.proximity(Vec3::new(0.5, 0.0, -0.5), 0.1, 0.0);
        assert!((p.gap - 0.4).abs() < 1e-12);
        assert!((p.normal + Vec3::Z).norm() < 1e-12);
        let p = r.proximity(Vec3::new(2.0, 0.0, 0.0), 0.1, 0.0);
        assert!((p.gap - 0.9).abs() < 1e-12);
        assert!((p.normal - Vec3::X).norm() < 1e-12);
    }

    pub fn motions() {
        let m = Motion::Oscillate {
            direction: Vec3::Z,
            amplitude: 0.01,
            frequency: 10.0,
        };
        assert!((m.offset(0.025).z - 0.01).abs() < 1e-12);
        assert!(
            (m.velocity_at(Vec3::ZERO, 0.0).z - 0.01 * 20.0 * std::f64::consts::PI).abs() < 1e-12
        );
        let r = Motion::Rotate {
            center: Vec3::ZERO,
            axis: Vec3::Y,
            omega: 2.0,
        };
        // ω e_y × (0, 0, −1) = (−2, 0, 0)
        assert!(
            (r.velocity_at(Vec3::new(0.0, 0.0, -1.0), 0.0) - Vec3::new(-2.0, 0.0, 0.0)).norm()
                < 1e-12
        );
    }

    fn near(o: &Obstacle, x: Vec3, r: f64, t: f64, reach: f64) -> Vec<(u32, Proximity)> {
        let mut out = Vec::new();
        o.proximities(x, r, t, reach, &mut out);
        out
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).norm() < 1e-12
    }

    pub fn box_container_walls_and_open_top() {
        let lo = Vec3::ZERO;
        let hi = Vec3::new(1.0, 2.0, 3.0);
        let b = Obstacle::fixed(
            "bin",
            Shape::Box {
                lo,
                hi,
                inside: true,
                open_top: false,
            },
        );
        // in the corner (x = lo, y = lo, z = lo): three walls, normals inward
        let c = near(&b, Vec3::new(0.11, 0.12, 0.13), 0.1, 0.0, 0.05);
        assert_eq!(c.iter().map(|x| x.0).collect::<Vec<_>>(), vec![0, 2, 4]);
        assert!((c[0].1.gap - 0.01).abs() < 1e-12 && close(c[0].1.normal, Vec3::X));
        assert!((c[1].1.gap - 0.02).abs() < 1e-12 && close(c[1].1.normal, Vec3::Y));
        assert!((c[2].1.gap - 0.03).abs() < 1e-12 && close(c[2].1.normal, Vec3::Z));
        assert!(close(c[2].1.point, Vec3::new(0.11, 0.12, 0.0)));
        // under the lid: the top wall z = hi, normal −e_z
        let c = near(&b, Vec3::new(0.5, 1.0, 2.95), 0.1, 0.0, 0.0);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].0, 5);
        assert!((c[0].1.gap + 0.05).abs() < 1e-12 && close(c[0].1.normal, -Vec3::Z));
        // the closest single feature
        let p = b.proximity(Vec3::new(0.5, 1.0, 2.95), 0.1, 0.0);
        assert!((p.gap + 0.05).abs() < 1e-12);
        // open top: no lid, and a sphere above the rim of the wall x = hi touches its edge
        let open = Obstacle::fixed(
            "bin",
            Shape::Box {
                lo,
                hi,
                inside: true,
                open_top: true,
            },
        );
        assert!(near(&open, Vec3::new(0.5, 1.0, 2.95), 0.1, 0.0, 0.0).is_empty());
        let c = near(&open, Vec3::new(1.0, 1.0, 3.08), 0.1, 0.0, 0.0);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].0, 1);
        assert!((c[0].1.gap + 0.02).abs() < 1e-12 && close(c[0].1.normal, Vec3::Z));
        assert!(open.admits(Vec3::new(0.5, 1.0, 10.0), 0.0));
        assert!(!b.admits(Vec3::new(0.5, 1.0, 10.0), 0.0));
        assert!(!b.admits(Vec3::new(-0.5, 1.0, 1.0), 0.0));
    }

    pub fn solid_box_faces_edges_and_inside() {
        let b = Obstacle::fixed(
            "rock",
            Shape::Box {
                lo: Vec3::ZERO,
                hi: Vec3::new(1.0, 1.0, 1.0),
                inside: false,
                open_top: false,
            },
        );
        let p = b.proximity(Vec3::new(0.5, 0.5, 1.2), 0.1, 0.0);
        assert!((p.gap - 0.1).abs() < 1e-12 && close(p.normal, Vec3::Z));
        assert!(close(p.point, Vec3::new(0.5, 0.5, 1.0)));
        // off an edge: the normal points from the edge to the centre
        let p = b.proximity(Vec3::new(1.3, 0.5, 1.4), 0.1, 0.0);
        assert!((p.gap - 0.4).abs() < 1e-12);
        assert!(close(p.normal, Vec3::new(0.6, 0.0, 0.8)));
        // centre inside, nearest face x = hi: pushed out along +x
        let p = b.proximity(Vec3::new(0.9, 0.5, 0.5), 0.1, 0.0);
        assert!((p.gap + 0.2).abs() < 1e-12 && close(p.normal, Vec3::X));
        assert!(!b.admits(Vec3::new(0.9, 0.5, 0.5), 0.0));
        assert!(b.admits(Vec3::new(1.9, 0.5, 0.5), 0.0));
        assert_eq!(near(&b, Vec3::new(0.5, 0.5, 1.2), 0.1, 0.0, 0.1).len(), 1);
    }

    pub fn silo_with_orifice_and_solid_cylinder() {
        let silo = Obstacle::fixed(
            "silo",
            Shape::Cylinder {
                base: Vec3::ZERO,
                axis: Vec3::Z,
                radius: 1.0,
                height: 2.0,
                inside: true,
                bottom_cap: true,
                top_cap: false,
                orifice: 0.3,
            },
        );
        // against the wall, 0.5 above the floor
        let c = near(&silo, Vec3::new(0.85, 0.0, 0.5), 0.1, 0.0, 0.1);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].0, 0);
        assert!((c[0].1.gap - 0.05).abs() < 1e-12 && close(c[0].1.normal, -Vec3::X));
        // on the floor ring (outside the orifice): the bottom cap, normal +z
        let c = near(&silo, Vec3::new(0.0, 0.6, 0.09), 0.1, 0.0, 0.0);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].0, 1);
        assert!((c[0].1.gap + 0.01).abs() < 1e-12 && close(c[0].1.normal, Vec3::Z));
        // over the middle of the orifice: nothing within reach, the sphere falls through
        assert!(near(&silo, Vec3::new(0.0, 0.0, 0.09), 0.1, 0.0, 0.05).is_empty());
        // at the rim of the orifice: the contact point is on the rim circle
        let c = near(&silo, Vec3::new(0.25, 0.0, 0.05), 0.1, 0.0, 0.0);
        assert_eq!(c.len(), 1);
        assert!(close(c[0].1.point, Vec3::new(0.3, 0.0, 0.0)));
        let n = Vec3::new(-0.05, 0.0, 0.05).normalized_or(Vec3::Z);
        assert!(close(c[0].1.normal, n));
        // in the bottom corner: wall and floor
        assert_eq!(
            near(&silo, Vec3::new(0.0, 0.95, 0.05), 0.1, 0.0, 0.0).len(),
            2
        );
        // no top cap: open above
        assert!(silo.admits(Vec3::new(0.0, 0.0, 5.0), 0.0));
        assert!(!silo.admits(Vec3::new(0.0, 0.0, -0.5), 0.0));
        assert!(!silo.admits(Vec3::new(1.2, 0.0, 0.5), 0.0));
        let post = Obstacle::fixed(
            "post",
            Shape::Cylinder {
                base: Vec3::ZERO,
                axis: Vec3::Z,
                radius: 0.5,
                height: 1.0,
                inside: false,
                bottom_cap: true,
                top_cap: true,
                orifice: 0.0,
            },
        );
        let p = post.proximity(Vec3::new(0.0, 0.7, 0.5), 0.1, 0.0);
        assert!((p.gap - 0.1).abs() < 1e-12 && close(p.normal, Vec3::Y));
        let p = post.proximity(Vec3::new(0.1, 0.0, 1.15), 0.1, 0.0);
        assert!((p.gap - 0.05).abs() < 1e-12 && close(p.normal, Vec3::Z));
        // off the top rim
        let p = post.proximity(Vec3::new(0.8, 0.0, 1.4), 0.1, 0.0);
        assert!((p.gap - 0.4).abs() < 1e-12);
        assert!(close(p.normal, Vec3::new(0.6, 0.0, 0.8)));
        // centre inside, nearest the top
        let p = post.proximity(Vec3::new(0.0, 0.0, 0.9), 0.1, 0.0);
        assert!((p.gap + 0.2).abs() < 1e-12 && close(p.normal, Vec3::Z));
    }

    pub fn sphere_obstacles_inside_and_outside() {
        let ball = Obstacle::fixed(
            "ball",
            Shape::Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
                inside: false,
            },
        );
        let p = ball.proximity(Vec3::new(0.0, 1.2, 0.0), 0.1, 0.0);
        assert!((p.gap - 0.1).abs() < 1e-12 && close(p.normal, Vec3::Y));
        assert!(close(p.point, Vec3::Y));
        let shell = Obstacle::fixed(
            "shell",
            Shape::Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
                inside: true,
            },
        );
        let p = shell.proximity(Vec3::new(0.0, 0.0, -0.85), 0.1, 0.0);
        assert!((p.gap - 0.05).abs() < 1e-12 && close(p.normal, Vec3::Z));
        assert!(close(p.point, -Vec3::Z));
        assert!(shell.admits(Vec3::new(0.0, 0.5, 0.0), 0.0));
        assert!(!ball.admits(Vec3::new(0.0, 0.5, 0.0), 0.0));
    }

    pub fn translating_and_rotating_obstacles_move_rigidly() {
        // a plane translating upwards at 0.5 m/s: at t = 2 it is at z = 1
        let mut lift = Obstacle::fixed(
            "lift",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        );
        lift.motion = Motion::Translate {
            velocity: Vec3::new(0.0, 0.0, 0.5),
        };
        let p = lift.proximity(Vec3::new(0.0, 0.0, 1.3), 0.1, 2.0);
        assert!((p.gap - 0.2).abs() < 1e-12);
        assert!((lift.max_normal_speed() - 0.5).abs() < 1e-15);
        assert_eq!(
            lift.motion.velocity_at(Vec3::ZERO, 1.0),
            Vec3::new(0.0, 0.0, 0.5)
        );
        // a solid box [−1, 1] × [−0.5, 0.5] × [−0.5, 0.5] spinning about z at ω = π/2: at t = 1
        // it has turned by 90°, its long side along y
        let mut paddle = Obstacle::fixed(
            "paddle",
            Shape::Box {
                lo: Vec3::new(-1.0, -0.5, -0.5),
                hi: Vec3::new(1.0, 0.5, 0.5),
                inside: false,
                open_top: false,
            },
        );
        let w = std::f64::consts::FRAC_PI_2;
        paddle.motion = Motion::Rotate {
            center: Vec3::ZERO,
            axis: Vec3::Z,
            omega: w,
        };
        assert!(!paddle.rotation_invariant());
        let p = paddle.proximity(Vec3::new(0.0, 1.3, 0.0), 0.1, 1.0);
        assert!((p.gap - 0.2).abs() < 1e-12, "{p:?}");
        assert!((p.normal - Vec3::Y).norm() < 1e-12);
        assert!((p.point - Vec3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
        // at t = 0 the same point is 0.8 from the long face y = 0.5
        let p = paddle.proximity(Vec3::new(0.0, 1.3, 0.0), 0.1, 0.0);
        assert!((p.gap - 0.7).abs() < 1e-12);
        // surface speed bound: ω × the farthest corner
        let corner = Vec3::new(1.0, 0.5, 0.5).norm();
        assert!((paddle.max_normal_speed() - w * corner).abs() < 1e-12);
        // a coaxial cylinder is invariant: its surface moves in itself
        let drum = Obstacle {
            name: "drum".into(),
            shape: Shape::CylinderInside {
                point: Vec3::ZERO,
                axis: Vec3::Y,
                radius: 1.0,
            },
            motion: Motion::Rotate {
                center: Vec3::new(0.0, 3.0, 0.0),
                axis: Vec3::Y,
                omega: 2.0,
            },
            material: 0,
        };
        assert!(drum.rotation_invariant());
        assert_eq!(drum.max_normal_speed(), 0.0);
    }

    pub fn mesh_square_is_a_plane_to_a_sphere_on_it() {
        let mesh = crate::mesh::TriangleMesh::new(
            vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap();
        let square = Obstacle::fixed(
            "square",
            Shape::Mesh {
                mesh,
                side: MeshSide::Surface,
            },
        );
        let plane = Obstacle::fixed(
            "plane",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        );
        for x in [
            Vec3::new(0.3, -0.2, 0.12),
            Vec3::new(0.0, 0.0, 0.1),
            Vec3::new(-0.5, 0.5, 0.09),
            Vec3::new(0.7, 0.1, 0.101),
        ] {
            let c = near(&square, x, 0.1, 0.0, 0.05);
            assert_eq!(c.len(), 1, "{x:?}: {c:?}");
            let (m, p) = (c[0].1, plane.proximity(x, 0.1, 0.0));
            assert!((m.gap - p.gap).abs() < 1e-15, "{x:?}");
            assert!((m.normal - p.normal).norm() < 1e-15);
            assert!((m.point - p.point).norm() < 1e-15);
        }
    }

    pub fn material_table_is_symmetric_and_checked() {
        let law = |mu| ContactLaw {
            mu,
            restitution: 0.1,
            rolling_friction: 0.0,
        };
        let mut t = MaterialTable::uniform(vec!["default".into(), "steel".into()], law(0.3));
        t.set(0, 1, law(0.6));
        assert_eq!(t.law(1, 0), Some(law(0.6)));
        assert_eq!(t.law(1, 1), Some(law(0.3)));
        assert_eq!(t.law(2, 0), None);
        assert!(t.check().is_ok());
        t.laws[1] = law(0.7);
        assert!(t.check().is_err());
        assert!(!t.any_rolling());
    }

    pub fn a_rotating_mesh_drum_is_the_rotating_cylinder_up_to_its_chords() {
        let n = 256;
        let d = crate::mesh::cylinder_mesh(0.6, -0.25, 0.25, n);
        let mesh = crate::mesh::TriangleMesh::new(d.vertices, d.triangles).unwrap();
        let motion = Motion::Rotate {
            center: Vec3::ZERO,
            axis: Vec3::Z,
            omega: 1.0,
        };
        let drum = Obstacle {
            name: "drum".into(),
            shape: Shape::Mesh {
                mesh,
                side: MeshSide::Inside,
            },
            motion: motion.clone(),
            material: 0,
        };
        let cyl = Obstacle {
            name: "cyl".into(),
            shape: Shape::CylinderInside {
                point: Vec3::ZERO,
                axis: Vec3::Z,
                radius: 0.6,
            },
            motion,
            material: 0,
        };
        let sag = 0.6 * (1.0 - (std::f64::consts::PI / n as f64).cos());
        let half = std::f64::consts::PI / n as f64;
        for t in [0.0, 0.3, half, 2.0] {
            for a in [0.0, 0.1, 1.0, 4.0] {
                let x = Vec3::new(0.55 * f64::cos(a), 0.55 * f64::sin(a), 0.05);
                // one chord, or two at a (concave) vertex of the polygon
                let c = near(&drum, x, 0.05, t, 0.01);
                assert!((1..=2).contains(&c.len()), "t {t} a {a}: {c:?}");
                let m = c
                    .iter()
                    .map(|x| x.1)
                    .min_by(|a, b| a.gap.total_cmp(&b.gap))
                    .unwrap();
                let p = cyl.proximity(x, 0.05, t);
                let diff = p.gap - m.gap;
                assert!(
                    (-1e-12..=sag + 1e-12).contains(&diff),
                    "t {t} a {a}: {diff}"
                );
                assert!(m.normal.dot(p.normal) > (2.0 * half).cos());
            }
        }
        // at t = π/(n ω) the middle of a chord has turned to the angle 0: the gap there is
        // shorter by the full sagitta (at t = 0 a vertex of the polygon is there)
        let x = Vec3::new(0.55, 0.0, 0.05);
        let at = |t: f64| cyl.proximity(x, 0.05, t).gap - drum.proximity(x, 0.05, t).gap;
        assert!((at(half) - sag).abs() < 1e-9, "{}", at(half));
        // at a vertex the chords' lines pass 0.05 (1 − cos(π/n)) closer: 1/12 of the sagitta
        assert!((at(0.0) - sag * 0.05 / 0.6).abs() < 1e-9, "{}", at(0.0));
        // the surface's speed is |ω| × its largest distance from the axis: the radius 0.6
        // (the vertices lie on the circle), below |ω| × the reach from the centre (0.65)
        assert!((drum.max_normal_speed() - 0.6).abs() < 1e-12);
        assert!(drum.max_normal_speed() < drum.shape.reach_from(Vec3::ZERO));
    }
}
