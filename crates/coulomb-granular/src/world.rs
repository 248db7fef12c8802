//! The mechanical system: rigid spheres (6 dofs each) and obstacles (fixed or kinematically
//! driven), the data of (2.1)–(2.3) for a granular material.

use crate::math::Vec3;
use serde::Serialize;

/// Gravity used by every scene (m/s²), acting along −e_z.
pub const GRAVITY: f64 = 9.81;

/// A rigid sphere: 3 translational and 3 rotational dofs, v = (ẋ, ω). Its mass matrix is
/// diag(m, m, m, I, I, I) with I = 2/5 m R² (a solid ball; M is constant, as (2.5) assumes).
#[derive(Debug, Clone, PartialEq, Serialize)]
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
}

impl Sphere {
    /// A sphere at rest at `position`.
    pub fn new(position: Vec3, radius: f64, mass: f64) -> Self {
        Self {
            position,
            velocity: Vec3::ZERO,
            angular_velocity: Vec3::ZERO,
            radius,
            mass,
            rotation_locked: false,
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

/// The shape of an obstacle, in its reference position (time-independent).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
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
}

/// Prescribed rigid motion of an obstacle (§5.6: external objects in rigid motion).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Motion {
    /// motionless
    Fixed,
    /// translation d(t) = A sin(2π f t) · direction (vibrating plate)
    Oscillate {
        /// unit direction
        direction: Vec3,
        /// amplitude A (m)
        amplitude: f64,
        /// frequency f (Hz)
        frequency: f64,
    },
    /// rotation with angular velocity ω about the line through `center` along `axis`; the
    /// shape must be invariant under this rotation (a cylinder about its own axis, a plane
    /// orthogonal to it), so only the surface velocity ω × (p − c) matters
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
            _ => Vec3::ZERO,
        }
    }
    /// A bound on the normal speed of the obstacle's surface, max_t |n·V_B|: A·2πf for an
    /// oscillation, 0 for a fixed obstacle and for a rotation (its surface moves in itself).
    pub fn max_normal_speed(&self) -> f64 {
        match self {
            Motion::Oscillate {
                amplitude,
                frequency,
                ..
            } => (amplitude * 2.0 * std::f64::consts::PI * frequency).abs(),
            Motion::Fixed | Motion::Rotate { .. } => 0.0,
        }
    }
    /// Velocity of the obstacle's material point at position p and time t.
    pub fn velocity_at(&self, p: Vec3, t: f64) -> Vec3 {
        match self {
            Motion::Fixed => Vec3::ZERO,
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
}

/// An obstacle: a shape with a prescribed motion.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Obstacle {
    /// a name for outputs ("ground", "plate", "drum", …)
    pub name: String,
    /// the shape in its reference position
    pub shape: Shape,
    /// its prescribed motion
    pub motion: Motion,
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

impl Obstacle {
    /// A fixed obstacle.
    pub fn fixed(name: &str, shape: Shape) -> Self {
        Self {
            name: name.to_string(),
            shape,
            motion: Motion::Fixed,
        }
    }

    /// Gap, normal and contact point of a sphere (centre x, radius R) at time t.
    pub fn proximity(&self, x: Vec3, radius: f64, t: f64) -> Proximity {
        let off = self.motion.offset(t);
        match &self.shape {
            Shape::Plane { point, normal } => {
                let p0 = *point + off;
                let d = (x - p0).dot(*normal);
                Proximity {
                    gap: d - radius,
                    normal: *normal,
                    point: x - *normal * d,
                }
            }
            Shape::Rectangle {
                center,
                normal,
                u,
                half_u,
                half_v,
            } => {
                let c = *center + off;
                let v = normal.cross(*u);
                let d = x - c;
                let a = d.dot(*u).clamp(-half_u, *half_u);
                let b = d.dot(v).clamp(-half_v, *half_v);
                let p = c + *u * a + v * b;
                let e = x - p;
                let dist = e.norm();
                let side = if d.dot(*normal) >= 0.0 {
                    *normal
                } else {
                    -*normal
                };
                Proximity {
                    gap: dist - radius,
                    normal: e.normalized_or(side),
                    point: p,
                }
            }
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
                Proximity {
                    gap: rc - rho - radius,
                    normal: -outward,
                    point: x + outward * (rc - rho),
                }
            }
        }
    }
}

/// The mechanical system: spheres, obstacles, gravity.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct World {
    /// the rigid spheres
    pub bodies: Vec<Sphere>,
    /// the obstacles
    pub obstacles: Vec<Obstacle>,
    /// gravity vector (m/s²)
    pub gravity: Vec3,
}

impl World {
    /// An empty world with gravity −g e_z.
    pub fn new() -> Self {
        Self {
            bodies: Vec::new(),
            obstacles: Vec::new(),
            gravity: Vec3::new(0.0, 0.0, -GRAVITY),
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
}

impl Default for World {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_and_cylinder_gaps() {
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

    #[test]
    fn rectangle_edge_and_face() {
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

    #[test]
    fn motions() {
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
}
