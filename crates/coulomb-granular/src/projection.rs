//! Position correction: after the velocity step (2.5) and the position update (2.7), the
//! centres are projected onto the admissible set {g(q) ≥ 0} (Siconos' "combined projection"
//! idea, on positions only):
//!
//! ```text
//!     q ← argmin ½ ‖q' − q‖²_M   subject to   g_α(q') ≥ 0 for every pair α
//! ```
//!
//! solved by nonlinear Gauss–Seidel on the multipliers λ_α ≥ 0 of the constraints, each
//! constraint's gap g_α and normal n_α evaluated *exactly* at the current positions (sphere
//! distance, plane, rectangle, inside of a cylinder), so that curved walls are handled without
//! linearisation: λ_α ← max(0, λ_α − g_α / w_α), w_α = 1/m_A + 1/m_B, the centres moved by
//! ±n_α Δλ_α / m. The normal of a sphere contact passes through the centres, so rotations and
//! velocities are untouched. The correction starts only when some penetration exceeds
//! `trigger` and stops when every penetration is below `target` (or after `max_sweeps`).
//!
//! The projection changes the potential energy by W_p = −Σ m g·Δx (reported as
//! [`ProjectionStats::work`]): the energy balance of a step is then
//! E_{k+1} − E_k = (dissipation of the velocity step, ≤ 0) + W_p (docs/granular.md).

use crate::contact::{candidate_pairs, Partner};
use crate::math::Vec3;
use crate::world::World;
use rayon::prelude::*;
use serde::Serialize;

/// Settings of the position correction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Projection {
    /// start correcting when some penetration exceeds `trigger` × R_min (m/m)
    pub trigger: f64,
    /// stop when every penetration is below `target` × R_min
    pub target: f64,
    /// cap on Gauss–Seidel sweeps
    pub max_sweeps: usize,
    /// balance the potential energy ΔE_p a moving bead gains (or loses) by the correction with
    /// its own kinetic energy E_k: v and ω scaled by √(1 − ΔE_p / E_k), at most down to rest,
    /// so that the correction neither feeds nor drains the energy of moving beads
    pub conserve_energy: bool,
}

impl Default for Projection {
    /// Trigger at 0.1 % of the smallest radius, down to 0.01 %, at most 200 sweeps.
    fn default() -> Self {
        Self {
            trigger: 1e-3,
            target: 1e-4,
            max_sweeps: 200,
            conserve_energy: true,
        }
    }
}

/// What a projection did.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct ProjectionStats {
    /// largest penetration before (m)
    pub max_before: f64,
    /// largest penetration after (m)
    pub max_after: f64,
    /// sweeps done (0: nothing to correct)
    pub sweeps: usize,
    /// change of kinetic + potential energy caused by the correction (J): −Σ m g·Δx, less the
    /// kinetic energy taken back with `conserve_energy`
    pub work: f64,
}

/// Penetration statistics of a configuration.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Penetration {
    /// pairs (sphere–sphere or sphere–obstacle) in touch: gap ≤ 0
    pub touching: usize,
    /// mean of −g over the pairs in touch (m)
    pub mean: f64,
    /// largest −g (m), 0 when none
    pub max: f64,
    /// largest −g / min(R_A, R_B)
    pub max_relative: f64,
}

/// One constraint of the projection.
#[derive(Debug, Clone, Copy)]
struct Constraint {
    a: usize,
    partner: Partner,
    lambda: f64,
}

/// Exact gap and normal (B → A) of a pair at the world's current positions, time t.
fn gap_normal(world: &World, a: usize, partner: Partner, t: f64) -> Option<(f64, Vec3)> {
    let ba = world.bodies.get(a)?;
    match partner {
        Partner::Body(j) => {
            let bb = world.bodies.get(j)?;
            let d = ba.position - bb.position;
            Some((d.norm() - ba.radius - bb.radius, d.normalized_or(Vec3::Z)))
        }
        Partner::Obstacle(o) => {
            let p = world.obstacles.get(o)?.proximity(ba.position, ba.radius, t);
            Some((p.gap, p.normal))
        }
    }
}

/// All pairs with gap ≤ `margin` at time t (sphere pairs through the grid broad phase).
fn pairs_within(world: &World, t: f64, margin: f64) -> Vec<(usize, Partner, f64)> {
    // in parallel (rayon), in a fixed order: spheres pairs, then obstacles by sphere
    let mut out: Vec<(usize, Partner, f64)> = candidate_pairs(world, margin.max(0.0))
        .par_iter()
        .filter_map(|&(i, j)| {
            let (g, _) = gap_normal(world, i, Partner::Body(j), t)?;
            (g <= margin).then_some((i, Partner::Body(j), g))
        })
        .collect();
    let walls: Vec<(usize, Partner, f64)> = world
        .bodies
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, b)| {
            world
                .obstacles
                .iter()
                .enumerate()
                .filter_map(move |(o, ob)| {
                    let g = ob.proximity(b.position, b.radius, t).gap;
                    (g <= margin).then_some((i, Partner::Obstacle(o), g))
                })
                .collect::<Vec<_>>()
        })
        .collect();
    out.extend(walls);
    out
}

fn min_radius(world: &World, a: usize, partner: Partner) -> f64 {
    let ra = world.bodies.get(a).map_or(f64::INFINITY, |b| b.radius);
    match partner {
        Partner::Body(j) => ra.min(world.bodies.get(j).map_or(f64::INFINITY, |b| b.radius)),
        Partner::Obstacle(_) => ra,
    }
}

/// Penetrations of the configuration at time t: every pair with gap ≤ 0, measured exactly.
pub fn penetrations(world: &World, t: f64) -> Penetration {
    let mut p = Penetration::default();
    let mut sum = 0.0;
    for (a, partner, g) in pairs_within(world, t, 0.0) {
        let depth = (-g).max(0.0);
        p.touching += 1;
        sum += depth;
        p.max = p.max.max(depth);
        p.max_relative = p.max_relative.max(depth / min_radius(world, a, partner));
    }
    if p.touching > 0 {
        p.mean = sum / p.touching as f64;
    }
    p
}

/// Projects the centres of `world` at time t onto {g ≥ 0} (module doc), when some penetration
/// exceeds the trigger.
pub fn project(world: &mut World, t: f64, settings: &Projection) -> ProjectionStats {
    let rmin = world
        .bodies
        .iter()
        .map(|b| b.radius)
        .fold(f64::INFINITY, f64::min);
    let mut stats = ProjectionStats::default();
    if !rmin.is_finite() || world.bodies.is_empty() {
        return stats;
    }
    let trigger = settings.trigger * rmin;
    let target = settings.target * rmin;
    // pairs within a small margin, so that pairs pushed into contact by the correction are seen
    let margin = 0.05 * rmin;
    let found = pairs_within(world, t, margin);
    stats.max_before = found.iter().map(|x| -x.2).fold(0.0, f64::max);
    stats.max_after = stats.max_before;
    if stats.max_before <= trigger {
        return stats;
    }
    let mut cons: Vec<Constraint> = found
        .into_iter()
        .map(|(a, partner, _)| Constraint {
            a,
            partner,
            lambda: 0.0,
        })
        .collect();
    let start: Vec<Vec3> = world.bodies.iter().map(|b| b.position).collect();
    let inv_mass: Vec<f64> = world.bodies.iter().map(|b| 1.0 / b.mass).collect();
    for sweep in 0..settings.max_sweeps {
        let mut worst: f64 = 0.0;
        for c in cons.iter_mut() {
            let Some((g, n)) = gap_normal(world, c.a, c.partner, t) else {
                continue;
            };
            worst = worst.max(-g);
            let (wa, wb, b) = match c.partner {
                Partner::Body(j) => (inv_mass[c.a], inv_mass[j], Some(j)),
                Partner::Obstacle(_) => (inv_mass[c.a], 0.0, None),
            };
            let w = wa + wb;
            let new = (c.lambda - g / w).max(0.0);
            let d = new - c.lambda;
            if d == 0.0 {
                continue;
            }
            c.lambda = new;
            world.bodies[c.a].position += n * (d * wa);
            if let Some(j) = b {
                world.bodies[j].position += n * (-d * wb);
            }
        }
        stats.sweeps = sweep + 1;
        if worst <= target {
            break;
        }
    }
    stats.max_after = cons
        .iter()
        .filter_map(|c| gap_normal(world, c.a, c.partner, t))
        .map(|(g, _)| -g)
        .fold(0.0, f64::max);
    let gravity = world.gravity;
    let mut work = 0.0;
    for (b, x0) in world.bodies.iter_mut().zip(&start) {
        let gained = -b.mass * gravity.dot(b.position - *x0);
        work += gained;
        if settings.conserve_energy && gained != 0.0 {
            let ke = b.kinetic_energy();
            if ke > 0.0 {
                let f = (1.0 - gained / ke).max(0.0).sqrt();
                if !f.is_finite() {
                    // ke so small (a bead held at rest) that gained / ke overflows: no rescale
                    continue;
                }
                work -= ke * (1.0 - f * f);
                b.velocity = b.velocity * f;
                b.angular_velocity = b.angular_velocity * f;
            }
        }
    }
    stats.work = work;
    stats
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::{Obstacle, Shape, Sphere};

    #[test]
    fn projection_lifts_a_sunk_sphere_out_of_a_cylinder_exactly() {
        let mut w = World::new();
        w.obstacles.push(Obstacle::fixed(
            "drum",
            Shape::CylinderInside {
                point: Vec3::ZERO,
                axis: Vec3::Y,
                radius: 1.0,
            },
        ));
        // centre 0.97 from the axis, off the vertical: gap 1 − 0.97 − 0.05 = −0.02
        let (c, sn) = (0.6f64.cos(), 0.6f64.sin());
        w.bodies
            .push(Sphere::new(Vec3::new(0.97 * sn, 0.3, -0.97 * c), 0.05, 1.0));
        let before = penetrations(&w, 0.0);
        assert!((before.max - 0.02).abs() < 1e-12, "{before:?}");
        let s = project(&mut w, 0.0, &Projection::default());
        assert!(s.sweeps >= 1);
        let after = penetrations(&w, 0.0);
        assert!(after.max <= 1e-4 * 0.05, "{after:?}");
        // moved radially towards the axis, to 0.95 from it, along the same radius
        let x = w.bodies[0].position;
        assert!(
            ((x.x * x.x + x.z * x.z).sqrt() - 0.95).abs() < 5e-6,
            "{x:?}"
        );
        assert!((x.x / x.z + sn / c).abs() < 1e-9);
        assert!((x.y - 0.3).abs() < 1e-15);
        // lifted by 0.02 cos 0.6
        assert!((s.work - 9.81 * 0.02 * c).abs() < 1e-4, "{s:?}");
    }

    #[test]
    fn projection_separates_a_stack_with_minimum_displacement() {
        let mut w = World::new();
        w.obstacles.push(Obstacle::fixed(
            "ground",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        // two equal spheres overlapping by 0.01, the lower one 0.005 into the ground
        w.bodies
            .push(Sphere::new(Vec3::new(0.0, 0.0, 0.045), 0.05, 1.0));
        w.bodies
            .push(Sphere::new(Vec3::new(0.0, 0.0, 0.135), 0.05, 1.0));
        let s = project(&mut w, 0.0, &Projection::default());
        let p = penetrations(&w, 0.0);
        assert!(p.max <= 5e-6, "{p:?} {s:?}");
        assert!((w.bodies[0].position.z - 0.05).abs() < 1e-5);
        assert!((w.bodies[1].position.z - 0.15).abs() < 1e-5);
        // lifting both: ΔE_p = m g (0.005 + 0.015)
        assert!((s.work - 9.81 * 0.02).abs() < 1e-3, "{s:?}");
    }
}
