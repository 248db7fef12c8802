//! Textbook checks of the time stepping (docs/validation.md): each returns the value expected
//! from mechanics, the measured one and the tolerance, used by the fast tests
//! (`tests/physics.rs`) and by `coulomb validate`; those of bodies of other shapes in `rigid`,
//! of joints and mechanisms in `joints`.

pub mod joints;
pub mod laws;
pub mod rigid;

use crate::projection::penetrations;
use crate::simulation::{Params, Simulation, SimulationError};
use crate::world::{Obstacle, Shape, Sphere, World, GRAVITY};
use crate::{math::Vec3, scene::Scene};
use serde::Serialize;

/// One check: expected and measured values, absolute tolerance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    /// what is checked
    pub name: String,
    /// value from mechanics
    pub expected: f64,
    /// value measured
    pub measured: f64,
    /// |measured − expected| allowed (absolute)
    pub tolerance: f64,
    /// unit of the values
    pub unit: String,
    /// steps whose solve did not reach the tolerance
    pub not_converged: usize,
}

impl Check {
    fn new(name: String, expected: f64, measured: f64, tolerance: f64, unit: &str) -> Self {
        Self {
            name,
            expected,
            measured,
            tolerance,
            unit: unit.into(),
            not_converged: 0,
        }
    }
    /// |measured − expected| ≤ tolerance with all three finite (an expectation that came out
    /// infinite, e.g. a Janssen length over a wall that carries no friction, never passes),
    /// and every step converged.
    pub fn pass(&self) -> bool {
        (self.measured - self.expected).abs() <= self.tolerance
            && self.measured.is_finite()
            && self.expected.is_finite()
            && self.tolerance.is_finite()
            && self.not_converged == 0
    }
}

/// A world with a horizontal ground plane z = 0 and the given gravity.
pub fn ground_world(gravity: Vec3) -> World {
    let mut w = World::new();
    w.gravity = gravity;
    w.obstacles.push(Obstacle::fixed(
        "ground",
        Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Z,
        },
    ));
    w
}

fn steps(sim: &mut Simulation, n: usize) -> Result<usize, SimulationError> {
    let mut bad = 0;
    for _ in 0..n {
        if !sim.step()?.converged {
            bad += 1;
        }
    }
    Ok(bad)
}

/// A sphere (R = 0.05 m) on an incline of `deg` degrees (gravity tilted over a horizontal
/// ground), friction μ, released at rest, simulated for `duration` s. With `rolling` the
/// sphere may rotate: it rolls without slipping, a = 5/7 g sin θ, when tan θ ≤ 7/2 μ, else
/// slides with a = g (sin θ − μ cos θ); without rotation it slides with a = g (sin θ − μ cos θ)
/// when tan θ > μ and sticks otherwise. The measured acceleration is v_x(T) / T.
pub fn incline(
    deg: f64,
    mu: f64,
    rolling: bool,
    duration: f64,
    params: &Params,
) -> Result<Check, SimulationError> {
    let th = deg.to_radians();
    let g = GRAVITY;
    let mut w = ground_world(Vec3::new(g * th.sin(), 0.0, -g * th.cos()));
    let mut b = Sphere::new(Vec3::new(0.0, 0.0, 0.05), 0.05, 1.0);
    b.rotation_locked = !rolling;
    w.bodies.push(b);
    let p = Params {
        mu,
        restitution: 0.0,
        ..params.clone()
    };
    let n = (duration / p.h).round().max(1.0) as usize;
    let mut sim = Simulation::new(w, p.clone())?;
    let bad = steps(&mut sim, n)?;
    let t = n as f64 * p.h;
    let a = sim.world.bodies[0].velocity.x / t;
    let slide = g * (th.sin() - mu * th.cos());
    let expected = if rolling {
        if th.tan() <= 3.5 * mu {
            5.0 / 7.0 * g * th.sin()
        } else {
            slide
        }
    } else {
        slide.max(0.0)
    };
    let what = if rolling { "rolling" } else { "sliding" };
    let mut c = Check::new(
        format!("incline {deg}° μ = {mu} {what}: acceleration"),
        expected,
        a,
        1e-3 * g,
        "m/s²",
    );
    c.not_converged = bad;
    Ok(c)
}

/// A sphere (R = 0.05 m) released at rest on an incline of `deg` degrees (gravity tilted over
/// a horizontal ground), friction μ and rolling friction μ_r = `params.rolling_friction`
/// (rolling torque ≤ μ_r R N, [`crate::rolling`]), simulated for `duration` s. Mechanics of a
/// ball with rolling resistance: it stays at rest when tan θ ≤ μ_r (and tan θ ≤ μ); otherwise
/// it rolls without slipping with a = 5/7 g (sin θ − μ_r cos θ) when the friction this needs,
/// F = 2/5 m a + μ_r m g cos θ, is ≤ μ m g cos θ, and slides with a = g (sin θ − μ cos θ) when
/// not. The measured acceleration is v_x(T) / T.
pub fn incline_rolling_resistance(
    deg: f64,
    mu: f64,
    duration: f64,
    params: &Params,
) -> Result<Check, SimulationError> {
    let th = deg.to_radians();
    let g = GRAVITY;
    let mu_r = params.rolling_friction;
    let mut w = ground_world(Vec3::new(g * th.sin(), 0.0, -g * th.cos()));
    w.bodies
        .push(Sphere::new(Vec3::new(0.0, 0.0, 0.05), 0.05, 1.0));
    let p = Params {
        mu,
        restitution: 0.0,
        ..params.clone()
    };
    let n = (duration / p.h).round().max(1.0) as usize;
    let mut sim = Simulation::new(w, p.clone())?;
    let bad = steps(&mut sim, n)?;
    let t = n as f64 * p.h;
    let a = sim.world.bodies[0].velocity.x / t;
    let roll = 5.0 / 7.0 * g * (th.sin() - mu_r * th.cos());
    let expected = if th.tan() <= mu_r && th.tan() <= mu {
        0.0
    } else if 0.4 * roll + mu_r * g * th.cos() <= mu * g * th.cos() {
        roll
    } else {
        g * (th.sin() - mu * th.cos())
    };
    let mut c = Check::new(
        format!("incline {deg}° μ = {mu} μ_r = {mu_r}: acceleration"),
        expected,
        a,
        1e-3 * g,
        "m/s²",
    );
    c.not_converged = bad;
    Ok(c)
}

/// A sphere (R = 0.05 m) rolling without slipping at `v0` on a horizontal floor with friction
/// μ = 0.5 and rolling friction μ_r = `params.rolling_friction`, for `duration` s (before it
/// stops: T < 7 v0 / (5 μ_r g)). Mechanics: the rolling torque μ_r R m g decelerates it at
/// a = −5/7 μ_r g (m a = −F, I a / R = F R − μ_r R m g). Measured: (v_x(T) − v0) / T.
pub fn rolling_deceleration(
    v0: f64,
    duration: f64,
    params: &Params,
) -> Result<Check, SimulationError> {
    let r = 0.05;
    let mu_r = params.rolling_friction;
    let mut w = ground_world(Vec3::new(0.0, 0.0, -GRAVITY));
    let mut b = Sphere::new(Vec3::new(0.0, 0.0, r), r, 1.0);
    b.velocity = Vec3::new(v0, 0.0, 0.0);
    b.angular_velocity = Vec3::new(0.0, v0 / r, 0.0);
    w.bodies.push(b);
    let p = Params {
        mu: 0.5,
        restitution: 0.0,
        ..params.clone()
    };
    let n = (duration / p.h).round().max(1.0) as usize;
    let mut sim = Simulation::new(w, p.clone())?;
    let bad = steps(&mut sim, n)?;
    let t = n as f64 * p.h;
    let a = (sim.world.bodies[0].velocity.x - v0) / t;
    let mut c = Check::new(
        format!("ball rolling at {v0} m/s on a floor, μ_r = {mu_r}: deceleration"),
        -5.0 / 7.0 * mu_r * GRAVITY,
        a,
        1e-3 * GRAVITY,
        "m/s²",
    );
    c.not_converged = bad;
    Ok(c)
}

/// A sphere dropped from height `h0` (bottom above the ground) with restitution e: the ratio
/// of the first rebound velocity to the impact velocity (expected e) and the time until it
/// rests (expected √(2 h0 / g) (1 + e) / (1 − e), the sum of the bounce series).
pub fn drop(h0: f64, e: f64, params: &Params) -> Result<(Check, Check), SimulationError> {
    let r = 0.05;
    let mut w = ground_world(Vec3::new(0.0, 0.0, -GRAVITY));
    w.bodies
        .push(Sphere::new(Vec3::new(0.0, 0.0, r + h0), r, 1.0));
    let p = Params {
        restitution: e,
        mu: 0.3,
        ..params.clone()
    };
    let h = p.h;
    let mut sim = Simulation::new(w, p)?;
    let t0 = (2.0 * h0 / GRAVITY).sqrt();
    let t_rest_expected = t0 * (1.0 + e) / (1.0 - e);
    let max_steps = ((3.0 * t_rest_expected + 1.0) / h) as usize;
    let mut ratio = f64::NAN;
    let mut bad = 0;
    let mut rest_since: Option<f64> = None;
    for _ in 0..max_steps {
        let vz = sim.world.bodies[0].velocity.z;
        let s = sim.step()?;
        if !s.converged {
            bad += 1;
        }
        let vz1 = sim.world.bodies[0].velocity.z;
        if ratio.is_nan() && s.contacts > 0 && vz < 0.0 && vz1 > vz {
            ratio = -vz1 / vz;
        }
        // at rest: in contact with |v| below the velocity gravity gives in one step
        let calm = s.contacts > 0 && sim.world.bodies[0].velocity.norm() < 0.5 * GRAVITY * h;
        match (calm, rest_since) {
            (true, None) => rest_since = Some(sim.time - h),
            (false, _) => rest_since = None,
            _ => {}
        }
        if rest_since.is_some_and(|t| sim.time - t > 0.2) {
            break;
        }
    }
    let mut c1 = Check::new(
        format!("drop from {h0} m, e = {e}: rebound velocity ratio"),
        e,
        ratio,
        1e-6,
        "",
    );
    c1.not_converged = bad;
    // the bounces shorter than a few steps are merged into rest: tolerance 2 steps per
    // remaining bounce at the discrete resolution, and 2 % for the position of the first impact
    let tol = 0.02 * t_rest_expected + 10.0 * h;
    let mut c2 = Check::new(
        format!("drop from {h0} m, e = {e}: time to rest"),
        t_rest_expected,
        rest_since.unwrap_or(f64::INFINITY),
        tol,
        "s",
    );
    c2.not_converged = bad;
    Ok((c1, c2))
}

/// Energy budget of the box scene with `beads` beads over `n` steps (θ = ½): the largest
/// one-step increase of E = kinetic + potential beyond the potential energy W_p added by the
/// position correction, relative to E₀ (expected ≤ 0: the velocity step never creates energy,
/// docs/granular.md), and the relative drift |E_n − E₀ − ΣW_p| / E₀.
pub fn box_energy(
    beads: usize,
    e: f64,
    mu: f64,
    n: usize,
    params: &Params,
) -> Result<EnergyBudget, SimulationError> {
    let p = Params {
        restitution: e,
        mu,
        ..params.clone()
    };
    let mut sim = Simulation::new(Scene::Box.build(beads, 1), p)?;
    let e0 = sim.world.kinetic_energy() + sim.world.potential_energy();
    let mut prev = e0;
    let mut out = EnergyBudget {
        e0,
        ..EnergyBudget::default()
    };
    for _ in 0..n {
        let s = sim.step()?;
        let en = s.kinetic_energy + s.potential_energy;
        let increase = en - prev - s.projection_work;
        out.worst_increase = out.worst_increase.max(increase);
        if increase > GAIN_THRESHOLD * e0 {
            out.gaining_steps += 1;
        }
        out.projection_work += s.projection_work;
        if !s.converged {
            out.not_converged += 1;
        }
        prev = en;
    }
    out.end = prev;
    Ok(out)
}

/// Result of [`box_energy`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct EnergyBudget {
    /// E₀ (J)
    pub e0: f64,
    /// E_n (J)
    pub end: f64,
    /// max_k (E_{k+1} − E_k − W_p,k) (J)
    pub worst_increase: f64,
    /// Σ W_p (J)
    pub projection_work: f64,
    /// steps not converged
    pub not_converged: usize,
    /// steps with E_{k+1} − E_k − W_p,k > [`GAIN_THRESHOLD`] · E₀
    pub gaining_steps: usize,
}

/// A step of [`box_energy`] counts as gaining energy above this fraction of E₀ (round-off of
/// the energy sums is ~1e-12 E₀).
pub const GAIN_THRESHOLD: f64 = 1e-7;

/// A ball (R = 0.05 m) rolling inside a fixed cylinder of radius 1 m (horizontal axis),
/// released at rest at `deg` degrees from the bottom, simulated for `duration` s. Returns the
/// measured period (mean over the full periods seen, from upward zero crossings of x) and
/// the largest penetration into the wall at the end. Expected period for rolling without
/// slipping: T = 2π √(7 (R_c − r) / (5 g)) (1 + θ₀²/16) (small-amplitude series).
pub fn cylinder_roll(
    deg: f64,
    duration: f64,
    params: &Params,
) -> Result<(Check, Check), SimulationError> {
    let (rc, r) = (1.0, 0.05);
    let mut w = World::new();
    w.obstacles.push(Obstacle::fixed(
        "cylinder",
        Shape::CylinderInside {
            point: Vec3::ZERO,
            axis: Vec3::Y,
            radius: rc,
        },
    ));
    let th = deg.to_radians();
    let d = rc - r;
    w.bodies.push(Sphere::new(
        Vec3::new(d * th.sin(), 0.0, -d * th.cos()),
        r,
        1.0,
    ));
    let p = Params {
        mu: 0.5,
        restitution: 0.0,
        ..params.clone()
    };
    let mut sim = Simulation::new(w, p.clone())?;
    let n = (duration / p.h) as usize;
    let mut crossings = Vec::new();
    let mut bad = 0;
    let mut x_prev = sim.world.bodies[0].position.x;
    let mut worst_pen: f64 = 0.0;
    for _ in 0..n {
        let s = sim.step()?;
        if !s.converged {
            bad += 1;
        }
        worst_pen = worst_pen.max(s.end_max_penetration);
        let x = sim.world.bodies[0].position.x;
        if x_prev < 0.0 && x >= 0.0 {
            // linear interpolation of the crossing time
            let f = -x_prev / (x - x_prev);
            crossings.push(sim.time - p.h + f * p.h);
        }
        x_prev = x;
    }
    let period = if crossings.len() >= 2 {
        (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
    } else {
        f64::NAN
    };
    let expected =
        2.0 * std::f64::consts::PI * (7.0 * d / (5.0 * GRAVITY)).sqrt() * (1.0 + th * th / 16.0);
    // θ-method phase error O((ωh)²) and the series' next term: 1 %
    let mut c1 = Check::new(
        format!("ball rolling in a cylinder R_c = 1 m, {deg}°: period"),
        expected,
        period,
        0.01 * expected,
        "s",
    );
    c1.not_converged = bad;
    let mut c2 = Check::new(
        format!("ball rolling in a cylinder, {deg}°: largest penetration / R over the run"),
        0.0,
        worst_pen / r,
        0.01,
        "",
    );
    c2.not_converged = bad;
    Ok((c1, c2))
}

/// Settles a bed of `beads` beads in a box of side `side` (several layers) until rest
/// (speeds < 0.05 m/s for 10 steps, at most `max_steps`): mean and largest overlap / R and the
/// packing fraction of the slab between 2 R and h_bed − 2 R above the floor, away from the
/// walls by 2 R.
pub fn settled_bed(
    beads: usize,
    side: f64,
    max_steps: usize,
    params: &Params,
) -> Result<BedResult, SimulationError> {
    let layout = crate::scene::BoxLayout {
        side_x: side,
        side_y: side,
        ..crate::scene::BoxLayout::for_beads(beads)
    };
    let world = Scene::Box.build_with(beads, 1, &layout);
    let mut sim = Simulation::new(world, params.clone())?;
    let mut calm = 0;
    let mut out = BedResult::default();
    while sim.steps_done < max_steps {
        let s = sim.step()?;
        if !s.converged {
            out.not_converged += 1;
        }
        calm = if sim.max_speed() < 0.05 { calm + 1 } else { 0 };
        if calm >= 10 {
            out.at_rest = true;
            break;
        }
    }
    out.steps = sim.steps_done;
    let r = crate::scene::BEAD_RADIUS;
    let pen = penetrations(&sim.world, sim.time);
    out.mean_overlap = pen.mean / r;
    out.max_overlap = pen.max / r;
    // packing fraction of a box inside the bed: 2 R from the walls, the floor and the top
    let top = sim
        .world
        .bodies
        .iter()
        .map(|b| b.position.z)
        .fold(0.0, f64::max);
    out.max_floor_gap = resting_gap(&sim.world, sim.time, 0.1 * r) / r;
    out.packing_fraction = solid_fraction(
        &sim.world,
        [2.0 * r, 2.0 * r, 2.0 * r],
        [side - 2.0 * r, side - 2.0 * r, top - 2.0 * r],
        r / 32.0,
    );
    Ok(out)
}

/// The largest gap g between a sphere and an obstacle that faces up (normal within 25° of −g)
/// over the pairs with 0 < g < `within`: a sphere that rests on the floor should touch it
/// (g ≤ the activation threshold), one that hovers at a small positive gap is held by the
/// activation rule's look-ahead (docs/granular.md, "Resting on an obstacle"). 0 when no
/// such pair.
pub fn resting_gap(world: &World, t: f64, within: f64) -> f64 {
    let down = world.gravity.normalized_or(Vec3::new(0.0, 0.0, -1.0));
    let mut worst = 0.0f64;
    for b in &world.bodies {
        for o in &world.obstacles {
            let p = o.proximity(b.position, b.radius, t);
            if p.normal.dot(down) < -0.9 && p.gap > 0.0 && p.gap < within {
                worst = worst.max(p.gap);
            }
        }
    }
    worst
}

/// Fraction of the box [lo, hi] covered by the spheres of `world`, sampled at the centres of
/// a regular grid of spacing ≈ `spacing` (cells of side ≤ `spacing`): the volume of the union of
/// the spheres, cut exactly by the box's six faces up to the grid's resolution (the sampling
/// error is 0.09 % for spacing = R/32 on a sphere and on a simple cubic lattice, 0.6 % for
/// R/16: tests). 0 for an empty box.
pub fn solid_fraction(world: &World, lo: [f64; 3], hi: [f64; 3], spacing: f64) -> f64 {
    if !(spacing > 0.0 && spacing.is_finite()) {
        return 0.0;
    }
    let n: Vec<usize> = (0..3)
        .map(|k| (((hi[k] - lo[k]) / spacing).ceil().max(0.0) as usize).min(4096))
        .collect();
    if n.contains(&0) {
        return 0.0;
    }
    let step: Vec<f64> = (0..3).map(|k| (hi[k] - lo[k]) / n[k] as f64).collect();
    // spheres by the grid column (i, j) their horizontal extent covers
    let mut columns: Vec<Vec<usize>> = vec![Vec::new(); n[0] * n[1]];
    for (b, body) in world.bodies.iter().enumerate() {
        let (p, rad) = (body.position, body.radius);
        let range = |c: f64, k: usize| {
            let a = ((c - rad - lo[k]) / step[k]).floor().max(0.0) as usize;
            let z = (((c + rad - lo[k]) / step[k]).ceil().max(0.0) as usize).min(n[k]);
            a..z
        };
        for i in range(p.x, 0) {
            for j in range(p.y, 1) {
                columns[i * n[1] + j].push(b);
            }
        }
    }
    let mut inside = 0usize;
    for i in 0..n[0] {
        let x = lo[0] + (i as f64 + 0.5) * step[0];
        for j in 0..n[1] {
            let y = lo[1] + (j as f64 + 0.5) * step[1];
            let col = &columns[i * n[1] + j];
            for k in 0..n[2] {
                let z = lo[2] + (k as f64 + 0.5) * step[2];
                let hit = col.iter().any(|&b| {
                    let body = &world.bodies[b];
                    let d = body.position - crate::math::Vec3::new(x, y, z);
                    d.dot(d) <= body.radius * body.radius
                });
                inside += usize::from(hit);
            }
        }
    }
    inside as f64 / (n[0] * n[1] * n[2]) as f64
}

/// Result of [`settled_bed`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct BedResult {
    /// steps taken
    pub steps: usize,
    /// reached the rest rule
    pub at_rest: bool,
    /// mean overlap / R over the pairs in touch
    pub mean_overlap: f64,
    /// largest overlap / R
    pub max_overlap: f64,
    /// largest gap / R of a sphere within 10 % R above the floor ([`resting_gap`])
    pub max_floor_gap: f64,
    /// packing fraction of the inner box ([`solid_fraction`])
    pub packing_fraction: f64,
    /// steps not converged
    pub not_converged: usize,
}

/// The `rotating-drum` scene (drum radius 0.6 m, ω = 1 rad/s) with `beads` beads, run for
/// `duration` s: the dynamic angle of the free surface (degrees), from a least-squares line
/// through the highest bead centre of each 2R-wide slice across the drum, over the slices of
/// the middle 60 % of the surface; averaged over the last `average` s.
pub fn drum_angle(
    beads: usize,
    duration: f64,
    average: f64,
    params: &Params,
) -> Result<(f64, usize), SimulationError> {
    let mut sim = Simulation::new(Scene::RotatingDrum.build(beads, 1), params.clone())?;
    let n = (duration / params.h) as usize;
    let from = ((duration - average) / params.h) as usize;
    let (mut sum, mut count, mut bad) = (0.0, 0usize, 0);
    for k in 0..n {
        if !sim.step()?.converged {
            bad += 1;
        }
        if k >= from {
            if let Some(a) = surface_angle(&sim.world) {
                sum += a;
                count += 1;
            }
        }
    }
    Ok((sum / count.max(1) as f64, bad))
}

/// The `funnel` scene with `beads` beads run until rest (speeds < 0.05 m/s for 10 steps) or
/// `max_steps`: the flank angle of the heap on the floor (degrees), seen along y — the highest
/// bead top (z + R) of each 2R-wide slice in x, least-squares lines through the slices whose
/// top is between 20 % and 80 % of the heap's height on each side of the summit, the mean of
/// the two flanks' angles.
pub fn funnel_heap(
    beads: usize,
    max_steps: usize,
    params: &Params,
) -> Result<HeapResult, SimulationError> {
    let mut sim = Simulation::new(Scene::Funnel.build(beads, 1), params.clone())?;
    let mut out = HeapResult::default();
    let mut calm = 0;
    while sim.steps_done < max_steps {
        if !sim.step()?.converged {
            out.not_converged += 1;
        }
        calm = if sim.max_speed() < 0.05 { calm + 1 } else { 0 };
        if calm >= 10 {
            out.at_rest = true;
            break;
        }
    }
    out.steps = sim.steps_done;
    let r = crate::scene::BEAD_RADIUS;
    let w = 2.0 * r;
    let mut top: std::collections::BTreeMap<i64, f64> = Default::default();
    for b in sim.world.bodies.iter().filter(|b| b.position.z < 0.9) {
        let k = (b.position.x / w).floor() as i64;
        let e = top.entry(k).or_insert(0.0);
        *e = f64::max(*e, b.position.z + b.radius);
    }
    let pts: Vec<(f64, f64)> = top
        .iter()
        .map(|(k, z)| ((*k as f64 + 0.5) * w, *z))
        .collect();
    let Some(&(xs, peak)) = pts.iter().max_by(|a, b| a.1.total_cmp(&b.1)) else {
        return Ok(out);
    };
    out.height = peak;
    let flank = |left: bool| -> Option<f64> {
        let sel: Vec<(f64, f64)> = pts
            .iter()
            .copied()
            .filter(|p| (p.0 < xs) == left && p.0 != xs)
            .filter(|p| p.1 >= 0.2 * peak && p.1 <= 0.8 * peak)
            .collect();
        slope(&sel).map(|s| s.atan().to_degrees().abs())
    };
    let (a, b) = (flank(true), flank(false));
    out.angle = match (a, b) {
        (Some(a), Some(b)) => 0.5 * (a + b),
        (Some(a), None) | (None, Some(a)) => a,
        _ => f64::NAN,
    };
    Ok(out)
}

/// Least-squares slope of z over x (None with fewer than 2 distinct x).
fn slope(pts: &[(f64, f64)]) -> Option<f64> {
    if pts.len() < 2 {
        return None;
    }
    let m = pts.len() as f64;
    let (sx, sz) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, mz) = (sx / m, sz / m);
    let (mut sxx, mut sxz) = (0.0, 0.0);
    for p in pts {
        sxx += (p.0 - mx) * (p.0 - mx);
        sxz += (p.0 - mx) * (p.1 - mz);
    }
    (sxx > 0.0).then(|| sxz / sxx)
}

/// Result of [`funnel_heap`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct HeapResult {
    /// steps taken
    pub steps: usize,
    /// reached the rest rule
    pub at_rest: bool,
    /// height of the summit (m)
    pub height: f64,
    /// mean flank angle (degrees)
    pub angle: f64,
    /// steps not converged
    pub not_converged: usize,
}

/// Angle (degrees) of the free surface of the beads, seen along the y axis.
fn surface_angle(world: &World) -> Option<f64> {
    let r = crate::scene::BEAD_RADIUS;
    let w = 2.0 * r;
    let mut top: std::collections::BTreeMap<i64, f64> = Default::default();
    for b in &world.bodies {
        let k = (b.position.x / w).floor() as i64;
        let e = top.entry(k).or_insert(f64::NEG_INFINITY);
        *e = e.max(b.position.z);
    }
    let pts: Vec<(f64, f64)> = top
        .iter()
        .map(|(k, z)| ((*k as f64 + 0.5) * w, *z))
        .collect();
    if pts.len() < 5 {
        return None;
    }
    let cut = pts.len() / 5;
    let mid = &pts[cut..pts.len() - cut];
    let m = mid.len() as f64;
    let (sx, sz) = mid.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, mz) = (sx / m, sz / m);
    let (mut sxx, mut sxz) = (0.0, 0.0);
    for p in mid {
        sxx += (p.0 - mx) * (p.0 - mx);
        sxz += (p.0 - mx) * (p.1 - mz);
    }
    (sxx > 0.0).then(|| (sxz / sxx).atan().to_degrees().abs())
}

/// The column of [`column_collapse`] before settling: a floor, the gate (a vertical cylinder of
/// radius `r0` about the z axis) and `beads` beads on a lattice inside it.
pub fn column_world(beads: usize, r0: f64) -> World {
    let r = crate::scene::BEAD_RADIUS;
    let mut world = ground_world(Vec3::new(0.0, 0.0, -GRAVITY));
    world.obstacles.push(Obstacle::fixed(
        "gate",
        Shape::CylinderInside {
            point: Vec3::ZERO,
            axis: Vec3::Z,
            radius: r0,
        },
    ));
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(1);
    let mut bodies = Vec::with_capacity(beads);
    crate::scene::fill_lattice(
        &mut rng,
        beads,
        &crate::scene::Lattice {
            lo: Vec3::new(-r0, -r0, 0.0),
            hi: Vec3::new(r0, r0, f64::INFINITY),
            pitch: 2.5 * r,
            layer_pitch: 2.5 * r,
            base: 1.25 * r,
        },
        |x| (x.x * x.x + x.y * x.y).sqrt() <= r0 - 1.2 * r,
        &mut |b| bodies.push(b),
    );
    world.bodies = bodies;
    world
}

/// Collapse of a granular column (Lube et al. 2004, axisymmetric): `beads` beads settled in a
/// vertical cylinder of radius `r0` on a floor (until speeds < 0.02 m/s for 10 steps, at most
/// `settle_steps`), the cylinder removed, the heap run to rest (same rule, at most `max_steps`).
/// Returns the aspect ratio a = H₀ / r₀ and the normalised runout (R∞ − r₀) / r₀ (R∞: the
/// 95th percentile of the beads' distances from the axis, plus R).
pub fn column_collapse(
    beads: usize,
    r0: f64,
    settle_steps: usize,
    max_steps: usize,
    params: &Params,
) -> Result<ColumnResult, SimulationError> {
    let world = column_world(beads, r0);
    let mut sim = Simulation::new(world, params.clone())?;
    let mut out = ColumnResult::default();
    let rest = |sim: &mut Simulation, cap: usize, out: &mut ColumnResult| {
        let mut calm = 0;
        for k in 0..cap {
            if !sim.step()?.converged {
                out.not_converged += 1;
            }
            calm = if sim.max_speed() < 0.02 { calm + 1 } else { 0 };
            if calm >= 10 {
                return Ok((true, k + 1));
            }
        }
        Ok::<(bool, usize), SimulationError>((false, cap))
    };
    (out.settled, out.settle_steps) = rest(&mut sim, settle_steps, &mut out)?;
    let h0 = sim
        .world
        .bodies
        .iter()
        .map(|b| b.position.z + b.radius)
        .fold(0.0, f64::max);
    out.aspect = h0 / r0;
    sim.world.obstacles.truncate(1);
    (out.at_rest, out.spread_steps) = rest(&mut sim, max_steps, &mut out)?;
    let mut d: Vec<f64> = sim
        .world
        .bodies
        .iter()
        .map(|b| (b.position.x.powi(2) + b.position.y.powi(2)).sqrt() + b.radius)
        .collect();
    d.sort_by(f64::total_cmp);
    let rinf = d[((d.len() as f64 * 0.95) as usize).min(d.len() - 1)];
    out.runout = (rinf - r0) / r0;
    out.expected = if out.aspect <= 1.7 {
        1.24 * out.aspect
    } else {
        1.6 * out.aspect.sqrt()
    };
    Ok(out)
}

/// Result of [`column_collapse`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct ColumnResult {
    /// the column settled inside its cylinder
    pub settled: bool,
    /// steps taken to settle in the cylinder (the cap when not settled)
    pub settle_steps: usize,
    /// the heap came to rest after release
    pub at_rest: bool,
    /// steps taken after the release (the cap when not at rest)
    pub spread_steps: usize,
    /// a = H₀ / r₀
    pub aspect: f64,
    /// (R∞ − r₀) / r₀ measured
    pub runout: f64,
    /// Lube et al. (2004): 1.24 a (a ≤ 1.7), 1.6 a^½ (a > 1.7)
    pub expected: f64,
    /// steps not converged
    pub not_converged: usize,
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn a_check_passes_only_on_finite_values_within_tolerance() {
        let c = |e: f64, m: f64, t: f64| Check::new("c".into(), e, m, t, "m");
        assert!(c(1.0, 1.05, 0.1).pass());
        assert!(!c(1.0, 1.2, 0.1).pass());
        assert!(!c(1.0, f64::NAN, 0.1).pass());
        assert!(!c(f64::NAN, 1.0, 0.1).pass());
        // an expectation of ∞ with a tolerance relative to it (∞) is no pass
        assert!(!c(f64::INFINITY, 1.0, f64::INFINITY).pass());
        assert!(!c(1.0, 1.0, f64::INFINITY).pass());
        let mut late = c(1.0, 1.0, 0.1);
        late.not_converged = 1;
        assert!(!late.pass());
    }

    pub fn solid_fraction_of_known_arrangements() {
        use std::f64::consts::PI;
        let ball = |x: f64, y: f64, z: f64| Sphere::new(Vec3::new(x, y, z), 1.0, 1.0);
        // one whole sphere, and one cut in half by a face of the box
        let mut w = World::new();
        w.bodies.push(ball(0.0, 0.0, 0.0));
        let f = solid_fraction(&w, [-2.0; 3], [2.0; 3], 1.0 / 32.0);
        assert!((f * 64.0 / (4.0 / 3.0 * PI) - 1.0).abs() < 2e-3, "{f}");
        let f = solid_fraction(&w, [-2.0, -2.0, 0.0], [2.0, 2.0, 2.0], 1.0 / 32.0);
        assert!((f * 32.0 / (2.0 / 3.0 * PI) - 1.0).abs() < 2e-3, "{f}");
        // a simple cubic lattice of touching spheres: π/6 in any box of whole cells
        let mut w = World::new();
        for i in -1..6 {
            for j in -1..6 {
                for k in -1..6 {
                    w.bodies
                        .push(ball(2.0 * i as f64, 2.0 * j as f64, 2.0 * k as f64));
                }
            }
        }
        let f = solid_fraction(&w, [1.0; 3], [5.0; 3], 1.0 / 32.0);
        assert!((f / (PI / 6.0) - 1.0).abs() < 2e-3, "{f}");
        assert_eq!(solid_fraction(&w, [1.0; 3], [1.0; 3], 0.1), 0.0);
        assert_eq!(solid_fraction(&w, [1.0; 3], [5.0; 3], 0.0), 0.0);
        assert_eq!(solid_fraction(&w, [1.0; 3], [5.0; 3], f64::NAN), 0.0);
    }
}
