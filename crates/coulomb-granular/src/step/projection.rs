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
//! ±n_α Δλ_α / m. The normal of a sphere contact passes through the centres, so the moves
//! turn no sphere. The correction starts only when some penetration exceeds `trigger` and
//! stops when every penetration is below `target` (or after `max_sweeps`). What it then does to
//! the velocities is [`Velocities`]: rescale them to pay the lift's potential energy (the
//! default), nothing, or Moreau's inelastic projection on the corrected contacts, whose
//! impulses are added to the step's exported ones ([`inelastic_projection`]).
//!
//! The projection changes the potential energy by W_p = −Σ m g·Δx (reported as
//! [`ProjectionStats::work`]): the energy balance of a step is then
//! E_{k+1} − E_k = (dissipation of the velocity step, ≤ 0) + W_p (docs/granular.md).

use crate::contact::{par_chunked, BroadPhase, Contact, ObstacleIndex, Partner, SPHERE_CHUNK};
use crate::math::Vec3;
use crate::world::World;
use rayon::prelude::*;
use serde::Serialize;

/// Settings of the position correction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(from = "StoredProjection")]
pub struct Projection {
    /// start correcting when some penetration exceeds `trigger` × R_min (m/m)
    pub trigger: f64,
    /// stop when every penetration is below `target` × R_min
    pub target: f64,
    /// cap on Gauss–Seidel sweeps
    pub max_sweeps: usize,
    /// what the correction does to the velocities ([`Velocities`])
    pub velocities: Velocities,
}

/// [`Projection`] as stored (checkpoints): before `velocities` existed a boolean
/// `conserve_energy` chose between [`Velocities::Rescale`] (true) and
/// [`Velocities::PositionsOnly`] (false); both are read.
#[derive(serde::Deserialize)]
struct StoredProjection {
    trigger: f64,
    target: f64,
    max_sweeps: usize,
    #[serde(default)]
    velocities: Option<Velocities>,
    #[serde(default)]
    conserve_energy: Option<bool>,
}

impl From<StoredProjection> for Projection {
    fn from(s: StoredProjection) -> Self {
        let old = s.conserve_energy.map(|c| {
            if c {
                Velocities::Rescale
            } else {
                Velocities::PositionsOnly
            }
        });
        Self {
            trigger: s.trigger,
            target: s.target,
            max_sweeps: s.max_sweeps,
            velocities: s.velocities.or(old).unwrap_or(Velocities::Rescale),
        }
    }
}

/// What the position correction does to the velocities of the beads it moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Velocities {
    /// balance the potential energy ΔE_p a moving bead gains (or loses) by the correction with
    /// its own kinetic energy E_k: v and ω scaled by √(1 − ΔE_p / E_k), at most down to rest
    /// (a momentum change with no contact impulse: it carries weight, issue 52 bug 4)
    Rescale,
    /// velocities untouched (positions only, as the rigid engine's correction)
    PositionsOnly,
    /// Moreau's inelastic velocity projection on the corrected contacts of the step: an
    /// impulse p_α ≥ 0 along the normal of each contact of the index set that the correction
    /// moved (λ_α > 0), p ⊥ (u_N ≥ 0), which removes its approaching normal velocity; p is added
    /// to the contact's exported impulse
    Inelastic,
}

impl Default for Projection {
    /// Trigger at 0.1 % of the smallest radius, down to 0.01 %, at most 200 sweeps.
    fn default() -> Self {
        Self {
            trigger: 1e-3,
            target: 1e-4,
            max_sweeps: 200,
            velocities: Velocities::Rescale,
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
    /// kinetic energy taken back by the velocity rescaling or projection ([`Velocities`])
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
        Partner::Obstacle(o, f) => {
            let p = world
                .obstacles
                .get(o)?
                .feature_proximity(f, ba.position, ba.radius, t)?;
            Some((p.gap, p.normal))
        }
    }
}

/// All pairs with gap ≤ `margin` at time t (sphere pairs through the grid broad phase), in
/// one parallel pass over chunks of spheres, sorted by (sphere, partner) (obstacles after
/// spheres) whatever the number of threads.
fn pairs_within(world: &World, t: f64, margin: f64) -> Vec<(usize, Partner, f64)> {
    let grid = BroadPhase::new(world, margin.max(0.0));
    let obstacles = ObstacleIndex::new(world, t, margin.max(0.0));
    par_chunked(world.bodies.len(), SPHERE_CHUNK, |range, out| {
        let mut js = Vec::new();
        let mut near = Vec::new();
        let mut obs = Vec::new();
        for i in range {
            let Some(b) = world.bodies.get(i) else {
                continue;
            };
            grid.partners(i, &mut js);
            for &j in &js {
                if let Some((g, _)) = gap_normal(world, i, Partner::Body(j), t) {
                    if g <= margin {
                        out.push((i, Partner::Body(j), g));
                    }
                }
            }
            obstacles.candidates(b.position, &mut obs);
            for &o in &obs {
                let ob = &world.obstacles[o];
                near.clear();
                ob.proximities(b.position, b.radius, t, margin, &mut near);
                for &(f, p) in &near {
                    out.push((i, Partner::Obstacle(o, f), p.gap));
                }
            }
        }
    })
}

fn min_radius(world: &World, a: usize, partner: Partner) -> f64 {
    let ra = world.bodies.get(a).map_or(f64::INFINITY, |b| b.radius);
    match partner {
        Partner::Body(j) => ra.min(world.bodies.get(j).map_or(f64::INFINITY, |b| b.radius)),
        Partner::Obstacle(..) => ra,
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
    project_measured(world, t, settings).0
}

/// Largest number of constraints per chunk of a parallel pass over one colour (about 32
/// chunks per colour, at least 32 constraints each).
const CHUNK: usize = 512;
/// A colour with fewer constraints than this is swept sequentially (same numbers).
const PARALLEL_MIN: usize = 256;

/// Raw position storage shared by the updates of one colour, which move disjoint spheres.
#[derive(Clone, Copy)]
struct Shared(*mut Vec3);
// SAFETY: used only inside one colour of a colouring built by `Colouring::greedy_pairs` from
// pairs of valid, distinct sphere indices: two updates running at once never move the same
// sphere.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}
impl Shared {
    #[inline]
    fn at(self, i: usize) -> *mut Vec3 {
        // SAFETY: i < bodies (checked by the caller)
        unsafe { self.0.add(i) }
    }
}

/// Exact gap and normal (B → A) of a pair with A's centre `xa` and, for a sphere B, B's
/// centre `xb`, time t (as [`gap_normal`]).
#[inline]
fn gap_normal_of(
    world: &World,
    a: usize,
    xa: Vec3,
    partner: Partner,
    xb: Option<Vec3>,
    t: f64,
) -> Option<(f64, Vec3)> {
    let ra = world.bodies.get(a)?.radius;
    match partner {
        Partner::Body(j) => {
            let d = xa - xb?;
            Some((
                d.norm() - ra - world.bodies.get(j)?.radius,
                d.normalized_or(Vec3::Z),
            ))
        }
        Partner::Obstacle(o, f) => {
            let p = world.obstacles.get(o)?.feature_proximity(f, xa, ra, t)?;
            Some((p.gap, p.normal))
        }
    }
}

/// [`gap_normal_of`] with the centres `pos`.
fn gap_normal_at(
    world: &World,
    pos: &[Vec3],
    a: usize,
    partner: Partner,
    t: f64,
) -> Option<(f64, Vec3)> {
    let xb = match partner {
        Partner::Body(j) => Some(*pos.get(j)?),
        Partner::Obstacle(..) => None,
    };
    gap_normal_of(world, a, *pos.get(a)?, partner, xb, t)
}

/// [`project`], and the [`penetrations`] of the corrected configuration (the same numbers as
/// calling [`penetrations`] afterwards, without a second broad phase when it can be avoided).
///
/// The Gauss–Seidel sweeps are coloured (`crate::nsgs::Colouring::greedy_pairs`): two
/// constraints of one colour share no sphere, so a colour's updates run in parallel (rayon)
/// and give the numbers of a sequential pass over the colours; the sweep's largest
/// penetration is a maximum, exact in any order. The result is the same for every number of
/// threads.
///
/// The pairs found within the margin m = 0.05 R_min before the correction contain every pair
/// in touch after it when the correction moved no centre by d with 2d ≥ m/2 (gaps are
/// 1-Lipschitz in each centre); the penetrations are then measured on those pairs, in the
/// order of [`penetrations`], else by [`penetrations`] itself.
pub fn project_measured(
    world: &mut World,
    t: f64,
    settings: &Projection,
) -> (ProjectionStats, Penetration) {
    project_contacts(world, t, settings, &mut [])
}

/// [`project_measured`] after a step whose active contacts, sorted by key, are `contacts`:
/// with [`Velocities::Inelastic`] the impulses of the velocity projection are added to
/// theirs ([`inelastic_projection`]).
pub fn project_contacts(
    world: &mut World,
    t: f64,
    settings: &Projection,
    contacts: &mut [Contact],
) -> (ProjectionStats, Penetration) {
    let rmin = world
        .bodies
        .iter()
        .map(|b| b.radius)
        .fold(f64::INFINITY, f64::min);
    let mut stats = ProjectionStats::default();
    if !rmin.is_finite() || world.bodies.is_empty() {
        return (stats, penetrations(world, t));
    }
    let trigger = settings.trigger * rmin;
    let target = settings.target * rmin;
    // pairs within a small margin, so that pairs pushed into contact by the correction are seen
    let margin = 0.05 * rmin;
    let found = pairs_within(world, t, margin);
    stats.max_before = found.iter().map(|x| -x.2).fold(0.0, f64::max);
    stats.max_after = stats.max_before;
    let measure = |world: &World, gaps: &[f64]| -> Penetration {
        let mut p = Penetration::default();
        let mut sum = 0.0;
        for ((a, partner, _), &g) in found.iter().zip(gaps) {
            if g > 0.0 {
                continue;
            }
            let depth = (-g).max(0.0);
            p.touching += 1;
            sum += depth;
            p.max = p.max.max(depth);
            p.max_relative = p.max_relative.max(depth / min_radius(world, *a, *partner));
        }
        if p.touching > 0 {
            p.mean = sum / p.touching as f64;
        }
        p
    };
    if stats.max_before <= trigger {
        let gaps: Vec<f64> = found.iter().map(|x| x.2).collect();
        let pen = measure(world, &gaps);
        return (stats, pen);
    }
    let nb = world.bodies.len();
    let colouring = crate::nsgs::Colouring::greedy_pairs(found.len(), nb, |i| {
        let (a, partner, _) = found[i];
        match partner {
            Partner::Body(j) => (a, Some(j)),
            Partner::Obstacle(..) => (a, None),
        }
    });
    // constraints in colour order (pairs_within gives valid, distinct sphere indices)
    let mut cons: Vec<Constraint> = colouring
        .order
        .iter()
        .map(|&i| Constraint {
            a: found[i].0,
            partner: found[i].1,
            lambda: 0.0,
        })
        .collect();
    let start: Vec<Vec3> = world.bodies.iter().map(|b| b.position).collect();
    let mut pos = start.clone();
    let inv_mass: Vec<f64> = world.bodies.iter().map(|b| 1.0 / b.mass).collect();
    let shared = Shared(pos.as_mut_ptr());
    let world_ref: &World = world;
    // one constraint's update; returns its penetration before the update
    let update = |c: &mut Constraint| -> f64 {
        let other = match c.partner {
            Partner::Body(j) => Some(j),
            Partner::Obstacle(..) => None,
        };
        if c.a >= nb || other.is_some_and(|j| j >= nb || j == c.a) {
            return 0.0;
        }
        // SAFETY: in bounds (checked above); no other update of this colour moves a or b
        let (xa, xb) = unsafe { (*shared.at(c.a), other.map(|j| *shared.at(j))) };
        let Some((g, n)) = gap_normal_of(world_ref, c.a, xa, c.partner, xb, t) else {
            return 0.0;
        };
        let (wa, wb, b) = match c.partner {
            Partner::Body(j) => (inv_mass[c.a], inv_mass[j], Some(j)),
            Partner::Obstacle(..) => (inv_mass[c.a], 0.0, None),
        };
        let new = (c.lambda - g / (wa + wb)).max(0.0);
        let d = new - c.lambda;
        if d != 0.0 {
            c.lambda = new;
            // SAFETY: no other update of this colour moves sphere a or b (a ≠ b)
            unsafe {
                *shared.at(c.a) += n * (d * wa);
                if let Some(j) = b {
                    *shared.at(j) += n * (-d * wb);
                }
            }
        }
        -g
    };
    for sweep in 0..settings.max_sweeps {
        let mut worst: f64 = 0.0;
        for k in 0..colouring.colours() {
            let part = &mut cons[colouring.starts[k]..colouring.starts[k + 1]];
            let w = if part.len() >= PARALLEL_MIN {
                part.par_chunks_mut((part.len() / 32).clamp(PARALLEL_MIN / 8, CHUNK))
                    .map(|ch| ch.iter_mut().map(update).fold(0.0, f64::max))
                    .reduce(|| 0.0, f64::max)
            } else {
                part.iter_mut().map(update).fold(0.0, f64::max)
            };
            worst = worst.max(w);
        }
        stats.sweeps = sweep + 1;
        if worst <= target {
            break;
        }
    }
    stats.max_after = cons
        .par_iter()
        .filter_map(|c| gap_normal_at(world_ref, &pos, c.a, c.partner, t))
        .map(|(g, _)| -g)
        .reduce(|| 0.0, f64::max);
    let gravity = world.gravity;
    let mut work = 0.0;
    let mut moved: f64 = 0.0;
    for ((b, x0), x) in world.bodies.iter_mut().zip(&start).zip(&pos) {
        b.position = *x;
        moved = moved.max((*x - *x0).norm());
        let gained = -b.mass * gravity.dot(b.position - *x0);
        work += gained;
        if settings.velocities == Velocities::Rescale && gained != 0.0 {
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
    if settings.velocities == Velocities::Inelastic {
        let mut corrected: Vec<(usize, Partner)> = cons
            .iter()
            .filter(|c| c.lambda > 0.0)
            .map(|c| (c.a, c.partner))
            .collect();
        corrected.sort_unstable();
        work -= inelastic_projection(world, t, contacts, &corrected);
    }
    stats.work = work;
    let world_ref: &World = world;
    let pen = if moved.is_finite() && 2.0 * moved < 0.5 * margin {
        let gaps: Vec<f64> = found
            .par_iter()
            .map(|&(a, partner, _)| {
                gap_normal(world_ref, a, partner, t).map_or(f64::INFINITY, |x| x.0)
            })
            .collect();
        measure(world_ref, &gaps)
    } else {
        penetrations(world_ref, t)
    };
    (stats, pen)
}

/// Largest number of Gauss–Seidel sweeps of the inelastic velocity projection.
const INELASTIC_SWEEPS: usize = 200;

/// Moreau's inelastic velocity projection on the contacts of `contacts` (sorted by key) whose
/// keys are in `corrected` (sorted): impulses p_α ≥ 0 along each contact's normal n_α such
/// that u_α = n_α·(v_A − v_B − V_B(x_α, t)) ≥ 0 and p_α u_α = 0 (the linear complementarity
/// problem of an impact with e = 0 on these contacts, solved by projected Gauss–Seidel in
/// the order of `contacts`, at most `INELASTIC_SWEEPS` sweeps). The normal of a sphere
/// contact passes through the centre, so only v changes. Each p_α is added to the contact's
/// normal impulse, so that the impulses stored are those that acted. Returns the kinetic
/// energy removed (≥ 0: an inelastic impact).
pub fn inelastic_projection(
    world: &mut World,
    t: f64,
    contacts: &mut [Contact],
    corrected: &[(usize, Partner)],
) -> f64 {
    let nb = world.bodies.len();
    let rows: Vec<usize> = (0..contacts.len())
        .filter(|&i| corrected.binary_search(&contacts[i].key()).is_ok())
        .filter(|&i| {
            let c = &contacts[i];
            c.body < nb
                && match c.partner {
                    Partner::Body(j) => j < nb && j != c.body,
                    Partner::Obstacle(o, _) => o < world.obstacles.len(),
                }
        })
        .collect();
    if rows.is_empty() {
        return 0.0;
    }
    let mut touched: Vec<usize> = rows
        .iter()
        .flat_map(|&i| {
            let c = &contacts[i];
            [
                Some(c.body),
                match c.partner {
                    Partner::Body(j) => Some(j),
                    Partner::Obstacle(..) => None,
                },
            ]
        })
        .flatten()
        .collect();
    touched.sort_unstable();
    touched.dedup();
    let energy = |w: &World| -> f64 {
        touched
            .iter()
            .map(|&i| 0.5 * w.bodies[i].mass * w.bodies[i].velocity.norm_sq())
            .sum()
    };
    let before = energy(world);
    // obstacle velocity at each contact point, and the scale of the velocities
    let wall: Vec<Vec3> = rows
        .iter()
        .map(|&i| {
            let c = &contacts[i];
            match c.partner {
                Partner::Obstacle(o, _) => world.obstacles[o].motion.velocity_at(c.point, t),
                Partner::Body(_) => Vec3::ZERO,
            }
        })
        .collect();
    let mut p = vec![0.0; rows.len()];
    for _ in 0..INELASTIC_SWEEPS {
        let mut change: f64 = 0.0;
        let mut speed: f64 = 0.0;
        for (k, &i) in rows.iter().enumerate() {
            let c = &contacts[i];
            let a = c.body;
            let (vb, wb) = match c.partner {
                Partner::Body(j) => (world.bodies[j].velocity, 1.0 / world.bodies[j].mass),
                Partner::Obstacle(..) => (wall[k], 0.0),
            };
            let wa = 1.0 / world.bodies[a].mass;
            let u = c.normal.dot(world.bodies[a].velocity - vb);
            speed = speed.max(u.abs());
            let new = (p[k] - u / (wa + wb)).max(0.0);
            let d = new - p[k];
            if d != 0.0 {
                p[k] = new;
                world.bodies[a].velocity += c.normal * (d * wa);
                if let Partner::Body(j) = c.partner {
                    world.bodies[j].velocity += c.normal * (-d * wb);
                }
                change = change.max(d.abs() * (wa + wb));
            }
        }
        if change <= 1e-14 * speed {
            break;
        }
    }
    for (k, &i) in rows.iter().enumerate() {
        contacts[i].impulse[0] += p[k];
    }
    (before - energy(world)).max(0.0)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::world::{Obstacle, Shape, Sphere};

    pub fn projection_lifts_a_sunk_sphere_out_of_a_cylinder_exactly() {
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

    pub fn projection_separates_a_stack_with_minimum_displacement() {
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

    /// The inelastic velocity projection stops the sinking of a sphere it lifts out of the
    /// floor with a floor impulse added to the contact's: the momentum change equals the
    /// exported impulse, the tangential velocity is kept, and the kinetic energy removed is
    /// ½ m v_z² (reported as negative work next to the lift's m g d).
    pub fn inelastic_projection_exports_the_impulse_it_applies() {
        let mut w = World::new();
        w.obstacles.push(Obstacle::fixed(
            "ground",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        let mut b = Sphere::new(Vec3::new(0.0, 0.0, 0.048), 0.05, 2.0);
        b.velocity = Vec3::new(0.3, 0.0, -0.1);
        w.bodies.push(b);
        let (a, partner, gap) = pairs_within(&w, 0.0, 0.0)[0];
        let mut contacts = vec![Contact {
            body: a,
            partner,
            normal: Vec3::Z,
            t1: Vec3::X,
            t2: Vec3::Y,
            point: Vec3::ZERO,
            gap,
            normal_velocity: -0.1,
            impulse: [1.5, 0.0, 0.0],
        }];
        let settings = Projection {
            velocities: Velocities::Inelastic,
            ..Projection::default()
        };
        let m0 = w.bodies[0].velocity * w.bodies[0].mass;
        let (s, _) = project_contacts(&mut w, 0.0, &settings, &mut contacts);
        let v = w.bodies[0].velocity;
        assert!((w.bodies[0].position.z - 0.05).abs() < 1e-5);
        assert_eq!((v.x, v.y), (0.3, 0.0));
        assert!(v.z.abs() < 1e-15, "{v:?}");
        let dp = v * w.bodies[0].mass - m0;
        assert!((contacts[0].impulse[0] - 1.5 - dp.z).abs() < 1e-15);
        assert!((dp.z - 0.2).abs() < 1e-15);
        let lift = 2.0 * 9.81 * (w.bodies[0].position.z - 0.048);
        assert!((s.work - (lift - 0.5 * 2.0 * 0.01)).abs() < 1e-9, "{s:?}");
        // a separating sphere keeps its velocity and the impulse is unchanged
        w.bodies[0].position.z = 0.048;
        w.bodies[0].velocity = Vec3::new(0.0, 0.0, 0.1);
        let (s, _) = project_contacts(&mut w, 0.0, &settings, &mut contacts);
        assert_eq!(w.bodies[0].velocity, Vec3::new(0.0, 0.0, 0.1));
        assert!((contacts[0].impulse[0] - 1.7).abs() < 1e-15);
        assert!(s.sweeps >= 1);
    }

    pub fn stored_settings_without_velocities_read_as_before() {
        let old = |c: bool| {
            format!(r#"{{"trigger":0.001,"target":0.0001,"max_sweeps":200,"conserve_energy":{c}}}"#)
        };
        let p: Projection = serde_json::from_str(&old(true)).unwrap();
        assert_eq!(p, Projection::default());
        let p: Projection = serde_json::from_str(&old(false)).unwrap();
        assert_eq!(p.velocities, Velocities::PositionsOnly);
        let q = Projection {
            velocities: Velocities::Inelastic,
            ..Projection::default()
        };
        let back: Projection = serde_json::from_str(&serde_json::to_string(&q).unwrap()).unwrap();
        assert_eq!(back, q);
    }

    /// A layer of side × side beads sunk 1–2 mm into the floor (1 mm apart) and a layer of
    /// (side − 1)² beads in its hollows, sunk about 1 mm into their four neighbours below:
    /// enough constraints per colour for the parallel path.
    fn sunk_layers(side: usize) -> World {
        let mut w = World::new();
        w.obstacles.push(Obstacle::fixed(
            "ground",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        let r = 0.05;
        let s = 2.0 * r + 1e-3;
        for i in 0..side * side {
            let (x, y) = ((i % side) as f64, (i / side) as f64);
            let sink = 1e-3 * (1.5 + 0.5 * (0.37 * i as f64).sin());
            let mut b = Sphere::new(Vec3::new(s * x, s * y, r - sink), r, 1.0);
            b.velocity = Vec3::new(0.0, 0.0, -0.1);
            w.bodies.push(b);
        }
        let rise = (4.0 * r * r - 0.5 * s * s).sqrt();
        for i in 0..(side - 1) * (side - 1) {
            let (x, y) = ((i % (side - 1)) as f64, (i / (side - 1)) as f64);
            let z = r + rise - 2e-3 - 1e-3 * (0.71 * i as f64).cos();
            let b = Sphere::new(Vec3::new(s * (x + 0.5), s * (y + 0.5), z), r, 1.3);
            w.bodies.push(b);
        }
        w
    }

    pub fn coloured_projection_is_the_same_for_one_and_two_threads() {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut w = sunk_layers(30);
                let (s, pen) = project_measured(&mut w, 0.0, &Projection::default());
                (w, s, pen)
            })
        };
        let (w1, s1, p1) = run(1);
        let (w2, s2, p2) = run(2);
        assert_eq!(w1, w2);
        assert_eq!(s1, s2);
        assert_eq!(p1, p2);
        // corrected: from ~2–3 mm (5 % R) down to the target 1e-4 R
        assert!(s1.max_before > 1e-3 && s1.sweeps >= 2, "{s1:?}");
        assert!(s1.max_after <= 1e-4 * 0.05 * 1.0001, "{s1:?}");
        // the penetrations reported are those measured from scratch
        assert_eq!(p1, penetrations(&w1, 0.0));
        // below the trigger: nothing moves, the same penetrations
        let mut w = w1.clone();
        let (s, p) = project_measured(&mut w, 0.0, &Projection::default());
        assert_eq!((s.sweeps, &w), (0, &w1));
        assert_eq!(p, penetrations(&w1, 0.0));
    }
}
