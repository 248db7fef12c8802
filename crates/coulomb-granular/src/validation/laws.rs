//! Classical granular laws as validation cases of `coulomb validate` (docs/granular.md,
//! "Granular laws"), each built from a scene file of `examples/scenes/validation/` (embedded
//! in the binary, so that `coulomb validate` runs from anywhere):
//!
//! - [`incline`]: balls on an inclined plane, rolling (a = 5/7 g sin θ) or sliding
//!   (a = g (sin θ − μ cos θ)), from the file's per-pair friction (quick);
//! - [`janssen`]: the vertical load carried across each height of a settled column in a tube
//!   whose wall friction is mobilised, fitted to Janssen's saturation, against the Janssen
//!   length λ = R / (2 μ_w K) with K measured in the run;
//! - [`beverloo`]: the discharge rate of a flat-bottomed silo through three orifices, fitted
//!   to Beverloo's W = C ρ_b √g (D − k d)^{5/2};
//! - [`repose`]: the slope of a heap poured on a rough floor.
//!
//! The long ones are benchmarks of the physics, not tests: `coulomb validate` runs them in
//! full mode only.

use crate::contact::Partner;
use crate::math::Vec3;
use crate::model::{BuildChecks, SceneModel};
use crate::scene_file::{BuildOptions, BuiltScene, LoadedScene, SceneFile, SceneFileError};
use crate::simulation::{Simulation, SimulationError};
use crate::validation::Check;
use crate::world::ContactLaw;
use crate::world::Shape;
use std::path::Path;

/// Why a law case could not be run.
#[derive(Debug, thiserror::Error)]
pub enum LawError {
    /// its scene file is invalid
    #[error(transparent)]
    Scene(#[from] SceneFileError),
    /// a step failed
    #[error("{case}: {source}")]
    Simulation {
        /// the case
        case: &'static str,
        /// the simulation's error
        source: SimulationError,
    },
    /// the scene lacks what the case measures (an obstacle of that name, …)
    #[error("{case}: {message}")]
    Setup {
        /// the case
        case: &'static str,
        /// what is missing
        message: String,
    },
}

/// A scene file of `examples/scenes/validation/`: its path (for messages) and its text.
type Embedded = (&'static str, &'static str);

const INCLINE: Embedded = (
    "examples/scenes/validation/incline.toml",
    include_str!("../../../../examples/scenes/validation/incline.toml"),
);
const JANSSEN: Embedded = (
    "examples/scenes/validation/janssen.toml",
    include_str!("../../../../examples/scenes/validation/janssen.toml"),
);
const BEVERLOO: Embedded = (
    "examples/scenes/validation/beverloo.toml",
    include_str!("../../../../examples/scenes/validation/beverloo.toml"),
);
const REPOSE: Embedded = (
    "examples/scenes/validation/repose.toml",
    include_str!("../../../../examples/scenes/validation/repose.toml"),
);

/// Every law case, with the section it belongs to: the incline always, the others when
/// `full` (minutes in release).
pub fn checks(full: bool) -> Result<Vec<(String, Check)>, LawError> {
    let mut out: Vec<(String, Check)> = Vec::new();
    let mut add = |s: &str, cs: Vec<Check>| out.extend(cs.into_iter().map(|c| (s.to_string(), c)));
    add("Granular laws: incline (scene file)", incline()?);
    if full {
        add("Granular laws: Janssen", janssen()?);
        add("Granular laws: Beverloo", beverloo()?);
        add("Granular laws: angle of repose", repose()?);
    }
    Ok(out)
}

/// A running scene file: the simulation, the built scene (its inlets pour after each step)
/// and the count of steps whose solve missed the tolerance.
struct Run {
    case: &'static str,
    sim: Simulation,
    scene: BuiltScene,
    not_converged: usize,
}

impl Run {
    /// Builds the scene of `file` after `edit` (the model's checks on).
    fn new(
        case: &'static str,
        file: Embedded,
        edit: impl FnOnce(&mut SceneFile),
    ) -> Result<Self, LawError> {
        let mut loaded = LoadedScene::parse(Path::new(file.0), file.1.to_string(), true)?;
        edit(&mut loaded.file);
        let scene = loaded.build(&BuildOptions::default())?;
        let (world, params) = scene.build(&BuildChecks::default())?;
        let sim = Simulation::new(world, params)
            .map_err(|source| LawError::Simulation { case, source })?;
        Ok(Self {
            case,
            sim,
            scene,
            not_converged: 0,
        })
    }

    /// One step, then the inlets' spheres due in (t_k, t_{k+1}].
    fn step(&mut self) -> Result<(), LawError> {
        let case = self.case;
        let err = |source| LawError::Simulation { case, source };
        let t0 = self.sim.time;
        if !self.sim.step().map_err(err)?.converged {
            self.not_converged += 1;
        }
        let t1 = self.sim.time;
        for inlet in &mut self.scene.inlets {
            inlet
                .emit(&mut self.sim, &self.scene.model, t0, t1)
                .map_err(err)?;
        }
        Ok(())
    }

    /// `n` steps.
    fn steps(&mut self, n: usize) -> Result<(), LawError> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    /// Steps for at least `min_time` (s), then until every sphere has moved slower than
    /// `speed` (m/s) for 10 consecutive steps, at most `cap` steps in all; whether it came
    /// to rest. (Spheres released at rest move slower than g h after one step: the minimum
    /// time lets them fall first.)
    fn settle(&mut self, speed: f64, min_time: f64, cap: usize) -> Result<bool, LawError> {
        let min_steps = (min_time / self.sim.params.h).ceil() as usize;
        let mut calm = 0;
        for k in 0..cap {
            self.step()?;
            calm = if self.sim.max_speed() < speed {
                calm + 1
            } else {
                0
            };
            if k + 1 >= min_steps && calm >= 10 {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Index of the obstacle called `name` in the world.
    fn obstacle(&self, name: &str) -> Result<usize, LawError> {
        self.sim
            .world
            .obstacles
            .iter()
            .position(|o| o.name == name)
            .ok_or_else(|| LawError::Setup {
                case: self.case,
                message: format!("the scene has no obstacle '{name}'"),
            })
    }

    fn setup(&self, message: impl Into<String>) -> LawError {
        LawError::Setup {
            case: self.case,
            message: message.into(),
        }
    }
}

/// The contact law of materials `a` and `b` in `model` (the listed pair, else the default).
fn law_of(model: &SceneModel, a: &str, b: &str) -> ContactLaw {
    model
        .materials
        .pairs
        .iter()
        .find(|p| p.materials == [a, b] || p.materials == [b, a])
        .map_or(model.materials.default, |p| p.law(model.materials.default))
}

/// Least-squares line y = a + b x through the points; (a, b), or `None` with fewer than two
/// distinct x.
fn line_fit(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (points.len() >= 2 && sxx > 0.0).then(|| (my - sxy / sxx * mx, sxy / sxx))
}

/// Balls released at rest on the inclined plane `slope` of examples/scenes/validation/
/// incline.toml. With θ the angle between the plane's normal and −g and μ the friction of the
/// ball's material with the slope's, a ball rolls without slipping, a = 5/7 g sin θ, when
/// tan θ ≤ 7/2 μ, and slides with a = g (sin θ − μ cos θ) otherwise. Measured: the velocity
/// along the slope at the end over the time, v·s / T; tolerance 10⁻³ g.
pub fn incline() -> Result<Vec<Check>, LawError> {
    let mut run = Run::new("incline", INCLINE, |_| {})?;
    let slope = run.obstacle("slope")?;
    let Shape::Plane { normal, .. } = run.sim.world.obstacles[slope].shape else {
        return Err(run.setup("the obstacle 'slope' is not a plane"));
    };
    let n = run.scene.step.fixed_steps();
    run.steps(n)?;
    let g = run.sim.world.gravity;
    let gn = g.dot(normal);
    let along = g - normal * gn;
    let (sin, cos) = (along.norm() / g.norm(), -gn / g.norm());
    let down = along * (1.0 / along.norm());
    let t = run.sim.time;
    let slope_material = &run.scene.model.obstacles[slope].material;
    let mut out = Vec::new();
    for (i, batch) in run.scene.model.sphere_batches.iter().enumerate() {
        let mu = law_of(&run.scene.model, &batch.material, slope_material).mu;
        let rolls = sin / cos <= 3.5 * mu;
        let expected = if rolls {
            5.0 / 7.0 * g.norm() * sin
        } else {
            g.norm() * (sin - mu * cos)
        };
        let b = &run.sim.world.bodies[i];
        out.push(Check {
            name: format!(
                "{}: {} ball, θ = {:.1}°, μ = {mu}: {} acceleration along the slope",
                INCLINE.0,
                batch.material,
                sin.atan2(cos).to_degrees(),
                if rolls {
                    "rolling (5/7 g sin θ)"
                } else {
                    "sliding (g (sin θ − μ cos θ))"
                },
            ),
            expected,
            measured: b.velocity.dot(down) / t,
            tolerance: 1e-3 * g.norm(),
            unit: "m/s²".into(),
            not_converged: run.not_converged,
        });
    }
    Ok(out)
}

/// Bulk density of the packing of the spheres (kg/m³ of the cross-section `area`): the mass
/// of the spheres whose centres lie between the heights below which 20 % and 70 % of the
/// centres lie, over `area` times that height difference. Quantiles keep a few spheres above
/// the packing (bouncing, rolling on its top) from counting as part of it.
fn bulk_density(sim: &Simulation, area: f64) -> f64 {
    let mut z: Vec<(f64, f64)> = sim
        .world
        .bodies
        .iter()
        .map(|b| (b.position.z, b.mass))
        .collect();
    if z.len() < 10 {
        return f64::NAN;
    }
    z.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (i, j) = (z.len() / 5, z.len() * 7 / 10);
    let mass: f64 = z[i..j].iter().map(|p| p.1).sum();
    mass / (area * (z[j].0 - z[i].0))
}

/// The largest z + R of the spheres (the top of the packing).
fn top(sim: &Simulation) -> f64 {
    sim.world
        .bodies
        .iter()
        .map(|b| b.position.z + b.radius)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Janssen's saturation (examples/scenes/validation/janssen.toml). The beads settle in the
/// tube (at least 0.5 s, then until speeds < 0.05 m/s for 10 steps; at most 600 steps), then
/// the tube rises at 2 mm/s for 80 steps so that the beads slide along it and the wall
/// friction is mobilised upwards, as in the experiments of Ovarlez, Fond & Clément (Phys. Rev.
/// E 67, 060302, 2003). Over the last 30 steps the contact forces f = r / h are averaged and,
/// at heights z_j every 2 cm, the load carried across the plane z = z_j is
/// F(z_j) = g M(z_j) − Σ_{wall contacts above z_j} f_z, M(z_j) the mass of the beads above.
/// Janssen's model (wall shear τ = μ σ_wall, σ_wall = K σ_zz, both ratios constant with
/// depth) gives F = g M_s (1 − e^{−M / M_s}), M_s = ρ_b A λ, λ = R / (2 μ K); M_s is fitted
/// (least squares, golden section on log M_s), ρ_b measured in the column (`bulk_density`),
/// K measured as (Σ wall normal force) / (Σ over the slabs of 2 π R Δz F(z_mid) / A), and μ
/// as the mobilised wall friction (Σ wall f_z) / (Σ wall f_N): beads that roll along the wall
/// carry less than the Coulomb coefficient μ_w (about 85 % of it here, docs/granular.md). The
/// check: the fitted λ against R / (2 μ K), within 20 %; the name also gives R / (2 μ_w K).
pub fn janssen() -> Result<Vec<Check>, LawError> {
    let mut run = Run::new("janssen", JANSSEN, |_| {})?;
    let tube = run.obstacle("tube")?;
    let floor = run.obstacle("floor")?;
    let Shape::Cylinder { base, radius, .. } = run.sim.world.obstacles[tube].shape else {
        return Err(run.setup("the obstacle 'tube' is not a cylinder"));
    };
    let wall_material = run.scene.model.obstacles[tube].material.clone();
    let grain_material = run.scene.model.sphere_batches[0].material.clone();
    let mu_w = law_of(&run.scene.model, &grain_material, &wall_material).mu;
    let settled = run.settle(0.05, 0.5, 600)?;
    // the tube rises at v from now on: d(t) = v t from a base moved back by v t₀, so that it
    // does not jump
    let v = Vec3::new(0.0, 0.0, 0.002);
    let t0 = run.sim.time;
    {
        let o = &mut run.sim.world.obstacles[tube];
        if let Shape::Cylinder { base: b, .. } = &mut o.shape {
            *b = base - v * t0;
        }
        o.motion = crate::world::Motion::Translate { velocity: v };
    }
    let (moving, window) = (50, 30);
    run.steps(moving)?;
    let h = run.sim.params.h;
    let dz = 0.02;
    let z_top = top(&run.sim);
    let slabs = ((z_top / dz).floor() as usize).max(1);
    // per slab j (z in [j dz, (j+1) dz)): wall normal force, wall vertical force on the beads
    let mut normal = vec![0.0; slabs + 1];
    let mut lift = vec![0.0; slabs + 1];
    let mut base_load = 0.0;
    for _ in 0..window {
        run.step()?;
        for c in &run.sim.contacts {
            let Partner::Obstacle(o, _) = c.partner else {
                continue;
            };
            let f = c.world_impulse() * (1.0 / (h * window as f64));
            if o == tube {
                let j = ((c.point.z / dz).floor().max(0.0) as usize).min(slabs);
                normal[j] += c.impulse[0] / (h * window as f64);
                lift[j] += f.z;
            } else if o == floor {
                base_load += f.z;
            }
        }
    }
    let g = run.sim.world.gravity.norm();
    let area = std::f64::consts::PI * radius * radius;
    let mass_above = |z: f64| -> f64 {
        run.sim
            .world
            .bodies
            .iter()
            .filter(|b| b.position.z >= z)
            .map(|b| b.mass)
            .sum()
    };
    // F(z_j) for j = 0..slabs: the planes between the floor and the top
    let load: Vec<(f64, f64)> = (0..slabs)
        .map(|j| {
            let z = j as f64 * dz;
            let wall_above: f64 = lift[j..].iter().sum();
            (mass_above(z), g * mass_above(z) - wall_above)
        })
        .collect();
    let total = mass_above(f64::NEG_INFINITY);
    // least squares of F = g M_s (1 − e^{−M/M_s}) over log M_s, golden section (60 steps)
    let cost = |ms: f64| -> f64 {
        load.iter()
            .map(|&(m, f)| {
                let r = f - g * ms * (1.0 - (-m / ms).exp());
                r * r
            })
            .sum()
    };
    let (mut a, mut b) = ((1e-3 * total).ln(), (1e3 * total).ln());
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let (x1, x2) = (b - phi * (b - a), a + phi * (b - a));
        if cost(x1.exp()) < cost(x2.exp()) {
            b = x2;
        } else {
            a = x1;
        }
    }
    let m_s = (0.5 * (a + b)).exp();
    let rho_b = bulk_density(&run.sim, area);
    let lambda_fit = m_s / (rho_b * area);
    // K from the slabs below the top two (the free surface) and above the first (the foot)
    let (mut wall_n, mut vertical) = (0.0, 0.0);
    for j in 1..slabs.saturating_sub(2) {
        let f_mid = 0.5 * (load[j].1 + load[j + 1].1);
        wall_n += normal[j];
        vertical += 2.0 * std::f64::consts::PI * radius * dz * f_mid / area;
    }
    let k = wall_n / vertical;
    let mobilised = lift.iter().sum::<f64>() / normal.iter().sum::<f64>();
    let lambda_j = radius / (2.0 * mobilised * k);
    let lambda_nominal = radius / (2.0 * mu_w * k);
    let note = if settled {
        ""
    } else {
        " (NOT settled in 600 steps)"
    };
    Ok(vec![Check {
        name: format!(
            "{}: {} beads, tube R = {radius} m lifted at 2 mm/s, μ_w = {mu_w}: Janssen length λ fitted to the load across each height (column {z_top:.3} m, ρ_b = {rho_b:.0} kg/m³, floor load {:.2} of the weight, fitted saturation load {:.2} of it) against R / (2 μ K) with K = {k:.3} and the mobilised wall friction μ = F_z / F_N = {mobilised:.3} measured (with μ_w: R / (2 μ_w K) = {lambda_nominal:.4} m){note}; tolerance 20 %",
            JANSSEN.0,
            run.sim.world.bodies.len(),
            base_load / (g * total),
            m_s / total,
        ),
        expected: lambda_j,
        measured: lambda_fit,
        tolerance: 0.2 * lambda_j,
        unit: "m".into(),
        not_converged: run.not_converged + usize::from(!settled),
    }])
}

/// Beverloo's law (examples/scenes/validation/beverloo.toml). The beads settle in the closed
/// silo (at least 0.5 s, then until speeds < 0.05 m/s for 10 steps; at most 600 steps); ρ_b is measured in the packing (`bulk_density`).
/// From that state, for D = 5 d, 6 d, 7 d (d the mean diameter), a centred orifice of
/// diameter D is opened and the discharged mass (beads below the base) is recorded each
/// step; W is the slope of its least-squares line over 0.1 … 0.4 s after opening. Fitting
/// W^{2/5} = (C ρ_b √g)^{2/5} (D − k d) by a line in D gives C and k. Checks: C in
/// 0.5 … 0.7 and k in 1 … 3 (Beverloo, Leniger & van de Velde 1961; Nedderman 1992).
pub fn beverloo() -> Result<Vec<Check>, LawError> {
    let mut run = Run::new("beverloo", BEVERLOO, |_| {})?;
    let silo = run.obstacle("silo")?;
    let Shape::Cylinder { base, radius, .. } = run.sim.world.obstacles[silo].shape else {
        return Err(run.setup("the obstacle 'silo' is not a cylinder"));
    };
    let settled = run.settle(0.05, 0.5, 600)?;
    let d = 2.0 * run.sim.world.bodies.iter().map(|b| b.radius).sum::<f64>()
        / run.sim.world.bodies.len() as f64;
    let area = std::f64::consts::PI * radius * radius;
    let rho_b = bulk_density(&run.sim, area);
    let g = run.sim.world.gravity.norm();
    let h = run.sim.params.h;
    let total: f64 = run.sim.world.bodies.iter().map(|b| b.mass).sum();
    let (from, to) = ((0.1 / h).round() as usize, (0.4 / h).round() as usize);
    let mut rates = Vec::new();
    let mut not_converged = run.not_converged + usize::from(!settled);
    let mut notes = Vec::new();
    for ratio in [5.0, 6.0, 7.0] {
        let diameter = ratio * d;
        let mut r = Run {
            case: "beverloo",
            sim: run.sim.clone(),
            scene: run.scene.clone(),
            not_converged: 0,
        };
        if let Shape::Cylinder { orifice, .. } = &mut r.sim.world.obstacles[silo].shape {
            *orifice = 0.5 * diameter;
        }
        let mut out = Vec::new();
        for k in 0..=to {
            if k > 0 {
                r.step()?;
            }
            if k >= from {
                let gone: f64 = r
                    .sim
                    .world
                    .bodies
                    .iter()
                    .filter(|b| b.position.z < base.z - b.radius)
                    .map(|b| b.mass)
                    .sum();
                out.push((r.sim.time, gone));
            }
        }
        let w = line_fit(&out).map_or(f64::NAN, |(_, s)| s);
        notes.push(format!(
            "D = {ratio} d: W = {w:.3} kg/s ({:.0} % discharged)",
            100.0 * out.last().map_or(0.0, |p| p.1) / total
        ));
        not_converged += r.not_converged;
        rates.push((diameter, w.max(0.0).powf(0.4)));
    }
    let (c, k) = match line_fit(&rates) {
        Some((a, s)) if s > 0.0 => (s.powf(2.5) / (rho_b * g.sqrt()), -a / (s * d)),
        _ => (f64::NAN, f64::NAN),
    };
    let what = format!(
        "{}: {} beads, d = {d:.4} m, silo R = {radius} m, ρ_b = {rho_b:.0} kg/m³; {}",
        BEVERLOO.0,
        run.sim.world.bodies.len(),
        notes.join(", ")
    );
    Ok(vec![
        Check {
            name: format!("{what}: fitted C (range 0.5 … 0.7)"),
            expected: 0.6,
            measured: c,
            tolerance: 0.1,
            unit: String::new(),
            not_converged,
        },
        Check {
            name: format!("{what}: fitted k (range 1 … 3)"),
            expected: 2.0,
            measured: k,
            tolerance: 1.0,
            unit: String::new(),
            not_converged,
        },
    ])
}

/// The angle of repose (examples/scenes/validation/repose.toml): the beads of the inlet are
/// poured onto the floor, then the run continues until every bead moves slower than
/// 0.02 m/s for 10 consecutive steps (at most 1 000 steps more). The heap's surface is the highest z + R in rings of
/// width d about the pour axis; its slope is the least-squares line of that height against
/// the ring's radius over 25 … 75 % of the heap's radius (the radius holding 95 % of the
/// beads). Range 20° … 40°: the heaps of monosized spheres with sliding and rolling friction
/// of Zhou, Xu, Yu & Zulli (Phys. Rev. E 64, 021301, 2001), whose angle grows with both μ
/// and μ_r.
pub fn repose() -> Result<Vec<Check>, LawError> {
    let mut run = Run::new("repose", REPOSE, |_| {})?;
    let pour_end = run
        .scene
        .inlets
        .iter()
        .map(|i| i.inlet.end)
        .filter(|e| e.is_finite())
        .fold(0.0_f64, f64::max);
    let h = run.sim.params.h;
    run.steps((pour_end / h).ceil() as usize + 1)?;
    let rest = run.settle(0.02, 0.0, 1000)?;
    let bodies = &run.sim.world.bodies;
    if bodies.len() < 100 {
        return Err(run.setup(format!("only {} beads poured", bodies.len())));
    }
    let d = 2.0 * bodies.iter().map(|b| b.radius).sum::<f64>() / bodies.len() as f64;
    let mut radial: Vec<f64> = bodies
        .iter()
        .map(|b| b.position.x.hypot(b.position.y))
        .collect();
    radial.sort_by(f64::total_cmp);
    let heap = radial[(0.95 * radial.len() as f64) as usize - 1];
    let rings = (heap / d).ceil() as usize + 1;
    let mut height = vec![f64::NEG_INFINITY; rings];
    for b in bodies {
        let j = (b.position.x.hypot(b.position.y) / d) as usize;
        if j < rings {
            height[j] = height[j].max(b.position.z + b.radius);
        }
    }
    let pts: Vec<(f64, f64)> = height
        .iter()
        .enumerate()
        .map(|(j, &z)| ((j as f64 + 0.5) * d, z))
        .filter(|&(r, z)| z.is_finite() && r >= 0.25 * heap && r <= 0.75 * heap)
        .collect();
    let angle = line_fit(&pts).map_or(f64::NAN, |(_, s)| (-s).atan().to_degrees());
    let law = law_of(&run.scene.model, "glass", "glass");
    Ok(vec![Check {
        name: format!(
            "{}: {} beads poured, μ = {}, μ_r = {}, heap radius {heap:.3} m ({}): angle of repose (range 20° … 40°, Zhou et al. 2001)",
            REPOSE.0,
            bodies.len(),
            law.mu,
            law.rolling_friction,
            if rest { "at rest" } else { "NOT at rest after 1000 steps" }
        ),
        expected: 30.0,
        measured: angle,
        tolerance: 10.0,
        unit: "°".into(),
        not_converged: run.not_converged + usize::from(!rest),
    }])
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn the_law_scene_files_parse_and_build() {
        for file in [INCLINE, JANSSEN, BEVERLOO, REPOSE] {
            let loaded = LoadedScene::parse(Path::new(file.0), file.1.to_string(), true).unwrap();
            let opts = BuildOptions {
                max_fill: Some(20),
                ..BuildOptions::default()
            };
            let scene = loaded.build(&opts).unwrap();
            scene.build(&BuildChecks::default()).unwrap();
        }
    }

    pub fn the_incline_rolls_and_slides_as_mechanics_says() {
        let cs = incline().unwrap();
        assert_eq!(cs.len(), 2);
        for c in &cs {
            assert!(c.pass(), "{c:?}");
        }
        // the glass ball rolls, the ice ball slides faster
        assert!(cs[1].measured > cs[0].measured);
    }

    pub fn a_line_fit_recovers_a_line() {
        let pts: Vec<(f64, f64)> = (0..5).map(|i| (i as f64, 2.0 + 3.0 * i as f64)).collect();
        let (a, b) = line_fit(&pts).unwrap();
        assert!((a - 2.0).abs() < 1e-12 && (b - 3.0).abs() < 1e-12);
        assert!(line_fit(&[(1.0, 1.0)]).is_none());
    }

    #[ignore = "a benchmark of the physics (about a minute in release): run by `coulomb validate`"]
    pub fn janssen_length_matches() {
        let cs = janssen().unwrap();
        eprintln!("{cs:#?}");
        assert!(cs.iter().all(Check::pass));
    }

    #[ignore = "a benchmark of the physics (about 10 minutes in release): run by `coulomb validate`"]
    pub fn beverloo_fit_is_in_range() {
        let cs = beverloo().unwrap();
        eprintln!("{cs:#?}");
        assert!(cs.iter().all(Check::pass));
    }

    #[ignore = "a benchmark of the physics (about 3 minutes in release): run by `coulomb validate`"]
    pub fn repose_angle_is_in_range() {
        let cs = repose().unwrap();
        eprintln!("{cs:#?}");
        assert!(cs.iter().all(Check::pass));
    }
}
