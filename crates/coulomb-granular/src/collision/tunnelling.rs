//! Tunnelling: whether a sphere can cross an obstacle within one time step.
//!
//! Contacts are found at the start of each step from the positions q_k (§5: the index set of
//! the step); a sphere whose centre moves past the middle of a wall during one step is found
//! on the far side at the next one, where the contact pushes it further through. The walls
//! of thin two-sided features — a rectangle, a surface mesh, the walls of a box or cylinder
//! container — have no thickness: a sphere of radius R crosses one when it moves more than R
//! relative to it in one step. A solid (a block, a post, a ball, the fixed spheres of a
//! scene) of thinnest dimension t is crossed beyond R + t/2. A plane, the inside of an
//! infinite cylinder or of a spherical container, and closed meshes used as containers or
//! solids (their inside test gives the side) cannot be crossed.
//!
//! The travel of a sphere relative to an obstacle during a step is at most
//! (|v|_max + V_o) h, V_o the largest normal speed of the obstacle's surface
//! ([`Obstacle::max_normal_speed`]).

use crate::world::{MeshSide, Obstacle, Shape, World};

/// The largest travel per step with which a sphere of radius `r_min` cannot cross the
/// obstacle: `r_min` for thin two-sided walls, `r_min` + t/2 for a solid of thinnest
/// dimension t, ∞ for shapes that cannot be crossed.
pub fn crossing_travel(o: &Obstacle, r_min: f64) -> f64 {
    let solid = |t: f64| r_min + 0.5 * t;
    match &o.shape {
        Shape::Plane { .. } | Shape::CylinderInside { .. } => f64::INFINITY,
        Shape::Sphere { inside: true, .. } => f64::INFINITY,
        Shape::Sphere { radius, .. } => solid(2.0 * radius),
        Shape::Rectangle { .. } => r_min,
        Shape::Box { inside: true, .. } | Shape::Cylinder { inside: true, .. } => r_min,
        Shape::Box { lo, hi, .. } => {
            let d = *hi - *lo;
            solid(d.x.min(d.y).min(d.z))
        }
        Shape::Cylinder { radius, height, .. } => solid((2.0 * radius).min(*height)),
        Shape::Mesh { side, .. } => match side {
            MeshSide::Surface => r_min,
            MeshSide::Inside | MeshSide::Outside => f64::INFINITY,
        },
    }
}

/// A sphere can cross an obstacle in one step: the travel bound exceeds the obstacle's
/// [`crossing_travel`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "a sphere can cross obstacle '{obstacle}' in one step: (sphere speed {speed:.3} m/s + obstacle speed {obstacle_speed:.3} m/s) × h = {h} s is {travel:.3e} m, more than {limit:.3e} m (the smallest radius {r_min} m{}); use h ≤ {h_max:.3e} s",
    if self.thin { ", the wall being thin" } else { " plus half the obstacle's thickness" }
)]
pub struct Tunnelling {
    /// the obstacle's name
    pub obstacle: String,
    /// the largest sphere speed considered (m/s)
    pub speed: f64,
    /// the largest normal speed of the obstacle's surface (m/s)
    pub obstacle_speed: f64,
    /// the time step (s)
    pub h: f64,
    /// (speed + obstacle_speed) h (m)
    pub travel: f64,
    /// the obstacle's [`crossing_travel`] (m)
    pub limit: f64,
    /// the smallest sphere radius (m)
    pub r_min: f64,
    /// whether the obstacle is a thin two-sided wall (limit = R_min)
    pub thin: bool,
    /// the largest time step with which travel ≤ limit (s)
    pub h_max: f64,
}

impl Tunnelling {
    /// travel / limit: above 1 a sphere can cross.
    pub fn ratio(&self) -> f64 {
        self.travel / self.limit
    }
}

/// The obstacle of `world` closest to being crossed within one step of `h` by a sphere of
/// radius `r_min` moving at `speed` (travel / [`crossing_travel`] largest), as a
/// [`Tunnelling`] whatever its ratio; `None` when no obstacle can be crossed. Obstacles whose
/// surface speed has no finite bound (a rotating unbounded shape) are skipped.
pub fn worst(world: &World, h: f64, speed: f64, r_min: f64) -> Option<Tunnelling> {
    let mut out: Option<Tunnelling> = None;
    for o in &world.obstacles {
        let limit = crossing_travel(o, r_min);
        let v_o = o.max_normal_speed();
        if !(limit.is_finite() && v_o.is_finite()) {
            continue;
        }
        let v = speed + v_o;
        let t = Tunnelling {
            obstacle: o.name.clone(),
            speed,
            obstacle_speed: v_o,
            h,
            travel: v * h,
            limit,
            r_min,
            thin: limit == r_min,
            h_max: if v > 0.0 { limit / v } else { f64::INFINITY },
        };
        if out.as_ref().is_none_or(|w| t.ratio() > w.ratio()) {
            out = Some(t);
        }
    }
    out
}

/// The largest speed and the smallest radius of the spheres of `world` (0 and ∞ without).
pub fn speed_and_radius(world: &World) -> (f64, f64) {
    world.bodies.iter().fold((0.0, f64::INFINITY), |(v, r), b| {
        (v.max(b.velocity.norm()), r.min(b.radius))
    })
}

/// [`worst`] as a check: `Err` when a sphere can cross an obstacle (ratio > 1).
pub fn check(world: &World, h: f64, speed: f64, r_min: f64) -> Result<(), Tunnelling> {
    match worst(world, h, speed, r_min) {
        Some(t) if t.ratio() > 1.0 => Err(t),
        _ => Ok(()),
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::world::{Motion, Sphere};

    fn world_with(shape: Shape, motion: Motion) -> World {
        let mut w = World::new();
        w.obstacles.push(Obstacle {
            motion,
            ..Obstacle::fixed("wall", shape)
        });
        w.bodies
            .push(Sphere::new(Vec3::new(0.0, 0.0, 0.5), 0.01, 1.0));
        w
    }

    fn rectangle() -> Shape {
        Shape::Rectangle {
            center: Vec3::ZERO,
            normal: Vec3::Z,
            u: Vec3::X,
            half_u: 1.0,
            half_v: 1.0,
        }
    }

    pub fn a_thin_wall_is_crossed_beyond_the_smallest_radius() {
        let w = world_with(rectangle(), Motion::Fixed);
        // 1 m/s × 5 ms = 5 mm < R = 1 cm; 3 m/s × 5 ms = 1.5 cm > 1 cm
        assert!(check(&w, 0.005, 1.0, 0.01).is_ok());
        let e = check(&w, 0.005, 3.0, 0.01).unwrap_err();
        assert_eq!(e.obstacle, "wall");
        assert!(e.thin && (e.travel - 0.015).abs() < 1e-12 && e.limit == 0.01);
        assert!((e.h_max - 0.01 / 3.0).abs() < 1e-15);
        let msg = e.to_string();
        assert!(msg.contains("'wall'") && msg.contains("use h ≤"), "{msg}");
    }

    pub fn the_obstacle_speed_adds_to_the_sphere_speed() {
        let moving = Motion::Oscillate {
            direction: Vec3::Z,
            amplitude: 0.01,
            frequency: 50.0,
        };
        // V_o = 2π · 50 · 0.01 ≈ 3.14 m/s: crossed at rest
        let w = world_with(rectangle(), moving);
        let e = check(&w, 0.005, 0.0, 0.01).unwrap_err();
        assert!((e.obstacle_speed - std::f64::consts::PI).abs() < 1e-12);
    }

    pub fn solids_have_their_thickness_and_one_sided_shapes_none() {
        let block = Shape::Box {
            lo: Vec3::ZERO,
            hi: Vec3::new(1.0, 1.0, 0.1),
            inside: false,
            open_top: false,
        };
        let w = world_with(block, Motion::Fixed);
        // limit 0.01 + 0.05 = 6 cm: 10 m/s × 5 ms = 5 cm passes
        assert!(check(&w, 0.005, 10.0, 0.01).is_ok());
        assert!(check(&w, 0.005, 13.0, 0.01).is_err());
        let plane = Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Z,
        };
        let w = world_with(plane, Motion::Fixed);
        assert!(worst(&w, 0.005, 1e6, 0.01).is_none());
        assert_eq!(speed_and_radius(&w), (0.0, 0.01));
    }
}
