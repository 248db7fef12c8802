//! Validation cases of the rigid-body simulator (issue #41): scenes whose answer mechanics
//! gives, each returning the measured value next to the expected one. The quick ones are
//! unit tests (below); all of them are `coulomb validate` checks ([`checks`]).

use crate::bodies::rigid::{MassProperties, RigidBodyDesc, RigidError, RigidObstacle};
use crate::step::rigid::{RigidSettings, RigidStatus, RigidWorld};
use crate::validation::Check;
use crate::world::{ContactLaw, MaterialTable, Motion};
use parry3d_f64::math::Vector;
use parry3d_f64::shape::SharedShape;

/// One material with friction μ and no restitution.
pub fn one_material(mu: f64) -> MaterialTable {
    MaterialTable::uniform(
        vec!["default".into()],
        ContactLaw {
            mu,
            restitution: 0.0,
            rolling_friction: 0.0,
        },
    )
}

/// A cuboid body of half extents `half` and density ρ at `position` (its centre), at rest.
pub fn cuboid(
    half: [f64; 3],
    density: f64,
    position: [f64; 3],
) -> Result<RigidBodyDesc, RigidError> {
    let shape = SharedShape::cuboid(half[0], half[1], half[2]);
    let mass = MassProperties::from_shape(&shape, density)?;
    Ok(RigidBodyDesc {
        shape,
        mass,
        position,
        orientation: [1.0, 0.0, 0.0, 0.0],
        velocity: [0.0; 3],
        angular_velocity: [0.0; 3],
        material: 0,
        fixed: false,
    })
}

/// The fixed floor z = 0 (half-space, outward normal +z).
pub fn floor() -> RigidObstacle {
    RigidObstacle {
        name: "floor".into(),
        shape: SharedShape::halfspace(Vector::Z),
        position: [0.0; 3],
        orientation: [1.0, 0.0, 0.0, 0.0],
        motion: Motion::Fixed,
        material: 0,
    }
}

/// Result of [`free_top`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeTop {
    /// max over the steps of ||L| − |L₀|| / |L₀|
    pub momentum_drift: f64,
    /// max over the steps of |E − E₀| / E₀
    pub energy_drift: f64,
    /// the minimum over the run of Ωₖ / Ωₖ(0), k the body axis of the largest initial
    /// component (−1: the spin axis turned upside down)
    pub min_intermediate_ratio: f64,
}

/// A torque-free box (no gravity, no obstacle) of half extents (0.05, 0.1, 0.2) (three
/// distinct principal moments) spun with body-frame angular velocity `omega`, for `steps`
/// steps of h: the drifts of |L| and E, and whether the body-frame component on the
/// spin axis (the largest of `omega`) changed sign. The intermediate axis is y (the major x,
/// the minor z).
pub fn free_top(omega: [f64; 3], h: f64, steps: usize) -> Result<FreeTop, RigidError> {
    let mut b = cuboid([0.05, 0.1, 0.2], 1000.0, [0.0; 3])?;
    b.angular_velocity = omega;
    let settings = RigidSettings {
        h,
        gravity: [0.0; 3],
        ..RigidSettings::default()
    };
    let mut w = RigidWorld::new(vec![b], vec![], one_material(0.5), settings)?;
    let l = |w: &RigidWorld| Vector::from_array(w.angular_momenta()[0]).length();
    let (l0, e0) = (l(&w), w.kinetic_energy());
    let axis = (0..3)
        .max_by(|&i, &j| omega[i].abs().total_cmp(&omega[j].abs()))
        .unwrap_or(0);
    let body_y = |w: &RigidWorld| {
        let q = crate::bodies::dynamics::rotation_from_wxyz(w.orientations()[0]);
        (q.conjugate() * Vector::from_array(w.angular_velocities()[0])).to_array()[axis]
    };
    let y0 = body_y(&w);
    let mut out = FreeTop {
        momentum_drift: 0.0,
        energy_drift: 0.0,
        min_intermediate_ratio: 1.0,
    };
    for _ in 0..steps {
        w.step()?;
        out.momentum_drift = out.momentum_drift.max((l(&w) - l0).abs() / l0);
        out.energy_drift = out.energy_drift.max((w.kinetic_energy() - e0).abs() / e0);
        out.min_intermediate_ratio = out.min_intermediate_ratio.min(body_y(&w) / y0);
    }
    Ok(out)
}

/// Result of [`resting_box`].
#[derive(Debug, Clone, PartialEq)]
pub struct RestingBox {
    /// largest penetration over the last step's contacts / smallest side
    pub penetration: f64,
    /// Σ r_N of the last step
    pub normal_impulse: f64,
    /// m g h
    pub weight_impulse: f64,
    /// contacts of the last step
    pub contacts: usize,
    /// every contact impulse in K_μ (to 1e-12 relative) with r_N ≥ 0, and the impulses'
    /// moment about the centre of mass zero (to 1e-8 of m g h · half side)
    pub admissible: bool,
    /// steps whose error was above the tolerance
    pub not_converged: usize,
}

/// A box 0.2 × 0.1 × 0.1 m (ρ = 1000) dropped from `drop` m above the floor onto it, μ = 0.5,
/// `steps` steps of 1 ms: how deep it rests, and its last step's contact impulses.
pub fn resting_box(drop: f64, steps: usize) -> Result<RestingBox, RigidError> {
    let half = [0.1, 0.05, 0.05];
    let b = cuboid(half, 1000.0, [0.0, 0.0, half[2] + drop])?;
    let m = b.mass.mass;
    let mu = 0.5;
    let settings = RigidSettings::default();
    let h = settings.h;
    let g = -settings.gravity[2];
    let mut w = RigidWorld::new(vec![b], vec![floor()], one_material(mu), settings)?;
    let mut not_converged = 0;
    for _ in 0..steps {
        if w.step()?.status == RigidStatus::NotConverged {
            not_converged += 1;
        }
    }
    let contacts = w.contacts();
    let x = Vector::from_array(w.centres_of_mass()[0]);
    let mut moment = Vector::ZERO;
    let mut admissible = true;
    let mut penetration: f64 = 0.0;
    for c in contacts {
        let [rn, t1, t2] = c.impulse;
        admissible &= rn >= 0.0 && (t1 * t1 + t2 * t2).sqrt() <= mu * rn * (1.0 + 1e-12);
        let p = Vector::from_array(c.point.to_array());
        moment += (p - x).cross(Vector::from_array(c.world_impulse().to_array()));
        penetration = penetration.max(-c.gap);
    }
    // the end-of-step penetration: the lowest corner's depth below z = 0
    let q = crate::bodies::dynamics::rotation_from_wxyz(w.orientations()[0]);
    let origin = Vector::from_array(w.positions()[0]);
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                let corner = origin + q * Vector::new(sx * half[0], sy * half[1], sz * half[2]);
                penetration = penetration.max(-corner.z);
            }
        }
    }
    admissible &= moment.length() <= 1e-8 * m * g * h * half[0];
    Ok(RestingBox {
        penetration: penetration / (2.0 * half[1]),
        normal_impulse: contacts.iter().map(|c| c.impulse[0]).sum(),
        weight_impulse: m * g * h,
        contacts: contacts.len(),
        admissible,
        not_converged,
    })
}

/// Result of [`incline`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Incline {
    /// measured acceleration along the slope (from the velocity after the run)
    pub acceleration: f64,
    /// g (sin θ − μ cos θ) when tan θ > μ, else 0
    pub expected: f64,
    /// displacement along the slope over the run (m)
    pub displacement: f64,
    /// rotation angle of the box over the run (rad)
    pub rotation: f64,
    /// steps whose error was above the tolerance
    pub not_converged: usize,
}

/// A block of half extents (w/2, 0.05, hgt/2) at rest on a plane inclined by θ (°) with
/// friction μ, for `steps` steps of 1 ms. The plane is the floor z = 0 and gravity is turned
/// by θ about y (g (sin θ, 0, −cos θ)): the same mechanics, downhill is +x.
pub fn incline(
    deg: f64,
    mu: f64,
    width: f64,
    height: f64,
    steps: usize,
) -> Result<Incline, RigidError> {
    let theta = deg.to_radians();
    let g = crate::world::GRAVITY;
    let b = cuboid(
        [0.5 * width, 0.05, 0.5 * height],
        1000.0,
        [0.0, 0.0, 0.5 * height],
    )?;
    let settings = RigidSettings {
        gravity: [g * theta.sin(), 0.0, -g * theta.cos()],
        ..RigidSettings::default()
    };
    let h = settings.h;
    let mut w = RigidWorld::new(vec![b], vec![floor()], one_material(mu), settings)?;
    let x0 = w.centres_of_mass()[0];
    let mut not_converged = 0;
    for _ in 0..steps {
        if w.step()?.status == RigidStatus::NotConverged {
            not_converged += 1;
        }
    }
    let q = w.orientations()[0];
    let expected = if theta.tan() > mu {
        g * (theta.sin() - mu * theta.cos())
    } else {
        0.0
    };
    Ok(Incline {
        acceleration: w.velocities()[0][0] / (steps as f64 * h),
        expected,
        displacement: w.centres_of_mass()[0][0] - x0[0],
        rotation: 2.0 * q[0].abs().min(1.0).acos(),
        not_converged,
    })
}

/// Result of [`stack`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stack {
    /// bodies
    pub bodies: usize,
    /// largest displacement of a body's centre of mass over the run (m)
    pub max_displacement: f64,
    /// contacts at the last step
    pub contacts: usize,
    /// steps whose error was above the tolerance
    pub not_converged: usize,
    /// steps finished by the library's solver
    pub handed_over: usize,
    /// Gauss–Seidel sweeps, summed
    pub sweeps: usize,
}

/// Runs `bodies` on the floor with friction μ for `steps` steps of the default settings and
/// measures how far they move.
pub fn stack(bodies: Vec<RigidBodyDesc>, mu: f64, steps: usize) -> Result<Stack, RigidError> {
    let n = bodies.len();
    let mut w = RigidWorld::new(
        bodies,
        vec![floor()],
        one_material(mu),
        RigidSettings::default(),
    )?;
    let x0 = w.centres_of_mass();
    let mut out = Stack {
        bodies: n,
        max_displacement: 0.0,
        contacts: 0,
        not_converged: 0,
        handed_over: 0,
        sweeps: 0,
    };
    for _ in 0..steps {
        let r = w.step()?;
        out.contacts = r.contacts;
        out.sweeps += r.sweeps;
        if r.status == RigidStatus::NotConverged {
            out.not_converged += 1;
        }
        if r.method == "nsgs+library" {
            out.handed_over += 1;
        }
        for (a, b) in w.centres_of_mass().iter().zip(&x0) {
            let d = Vector::from_array(*a) - Vector::from_array(*b);
            out.max_displacement = out.max_displacement.max(d.length());
        }
    }
    Ok(out)
}

/// A running-bond brick wall of `courses` courses of `bricks` bricks 0.2 × 0.1 × 0.05 m
/// (ρ = 2000) along x, each course on the one below; odd courses are shifted by half a brick
/// and have one brick less.
pub fn brick_wall(courses: usize, bricks: usize) -> Result<Vec<RigidBodyDesc>, RigidError> {
    let half = [0.1, 0.05, 0.025];
    let mut out = Vec::new();
    for c in 0..courses {
        let odd = c % 2 == 1;
        let n = if odd {
            bricks.saturating_sub(1)
        } else {
            bricks
        };
        for i in 0..n {
            let x = (2 * i) as f64 * half[0] + if odd { half[0] } else { 0.0 };
            let z = (2 * c + 1) as f64 * half[2];
            out.push(cuboid(half, 2000.0, [x, 0.0, z])?);
        }
    }
    Ok(out)
}

/// A square pyramid of unit-density-ρ = 1000 cubes of side 0.1 m, `layers` layers: layer k
/// (from 0 at the bottom) has (layers − k)² cubes, shifted by half a cube in x and y from
/// the layer below (each cube rests on four).
pub fn cube_pyramid(layers: usize) -> Result<Vec<RigidBodyDesc>, RigidError> {
    let a = 0.05;
    let mut out = Vec::new();
    for k in 0..layers {
        let n = layers - k;
        for i in 0..n {
            for j in 0..n {
                let x = (2 * i + k) as f64 * a;
                let y = (2 * j + k) as f64 * a;
                let z = (2 * k + 1) as f64 * a;
                out.push(cuboid([a; 3], 1000.0, [x, y, z])?);
            }
        }
    }
    Ok(out)
}

/// Result of [`wall_impact`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallImpact {
    /// bricks
    pub bricks: usize,
    /// largest displacement of a brick's centre of mass at the end of the run (m)
    pub max_displacement: f64,
    /// bricks whose centre of mass ended more than 5 cm (the brick's thickness 0.1 m / 2)
    /// from where it started
    pub displaced: usize,
    /// the sphere's speed at the end of the run (m/s)
    pub sphere_speed: f64,
    /// steps whose error was above the tolerance
    pub not_converged: usize,
    /// most contacts in a step
    pub max_contacts: usize,
}

/// The sphere of [`wall_impact`]: a steel ball (ρ = 7800) of radius 0.08 m, 0.15 m in front
/// of the wall's face (y < 0) at the height of its third course, thrown at the wall along +y
/// at `speed` m/s.
pub fn impact_sphere(wall: &[RigidBodyDesc], speed: f64) -> Result<RigidBodyDesc, RigidError> {
    let r = 0.08;
    let shape = SharedShape::ball(r);
    let mass = MassProperties::from_shape(&shape, 7800.0)?;
    let (lo, hi) = wall
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), b| {
            (lo.min(b.position[0]), hi.max(b.position[0]))
        });
    Ok(RigidBodyDesc {
        shape,
        mass,
        position: [0.5 * (lo + hi), -0.05 - r - 0.02, 0.125],
        orientation: [1.0, 0.0, 0.0, 0.0],
        velocity: [0.0, speed, 0.0],
        angular_velocity: [0.0; 3],
        material: 0,
        fixed: false,
    })
}

/// A wall hit by a sphere (issue #41, qualitative): the running-bond wall
/// [`brick_wall`]`(courses, bricks)` on the floor, μ = 0.7, hit at mid-length by
/// [`impact_sphere`] at `speed` m/s; `steps` steps of the default settings (h = 1 ms,
/// Moreau–Jean (2.5)–(2.7), each step's problem (2.10) solved to 1e-8). Measures how far the
/// bricks were thrown and whether every step converged.
pub fn wall_impact(
    courses: usize,
    bricks: usize,
    speed: f64,
    steps: usize,
) -> Result<WallImpact, RigidError> {
    let mut bodies = brick_wall(courses, bricks)?;
    let n = bodies.len();
    bodies.push(impact_sphere(&bodies, speed)?);
    let mut w = RigidWorld::new(
        bodies,
        vec![floor()],
        one_material(0.7),
        RigidSettings::default(),
    )?;
    let x0 = w.centres_of_mass();
    let (mut not_converged, mut max_contacts) = (0, 0);
    for _ in 0..steps {
        let r = w.step()?;
        max_contacts = max_contacts.max(r.contacts);
        if r.status == RigidStatus::NotConverged {
            not_converged += 1;
        }
    }
    let x = w.centres_of_mass();
    let moved: Vec<f64> = x[..n]
        .iter()
        .zip(&x0[..n])
        .map(|(a, b)| (Vector::from_array(*a) - Vector::from_array(*b)).length())
        .collect();
    Ok(WallImpact {
        bricks: n,
        max_displacement: moved.iter().copied().fold(0.0, f64::max),
        displaced: moved.iter().filter(|&&d| d > 0.05).count(),
        sphere_speed: Vector::from_array(w.velocities()[n]).length(),
        not_converged,
        max_contacts,
    })
}

/// The `coulomb validate` checks of the rigid-body simulator, by section. `quick` skips the
/// wall and the pyramid.
pub fn checks(_quick: bool) -> Result<Vec<(String, Check)>, RigidError> {
    let mut out = Vec::new();
    let mut push = |s: &str, c: Check| out.push((s.to_string(), c));
    let check = |name: String, expected: f64, measured: f64, tolerance: f64, bad: usize| Check {
        name,
        expected,
        measured,
        tolerance,
        unit: String::new(),
        not_converged: bad,
    };
    let top = free_top([0.5, 6.0, 0.3], 1e-3, 10_000)?;
    push(
        "Rigid bodies",
        check(
            "torque-free asymmetric top, 10⁴ steps: largest ||L| − |L₀|| / |L₀|".into(),
            0.0,
            top.momentum_drift,
            1e-10,
            0,
        ),
    );
    push(
        "Rigid bodies",
        check(
            "torque-free asymmetric top, 10⁴ steps: largest |E − E₀| / E₀".into(),
            0.0,
            top.energy_drift,
            1e-6,
            0,
        ),
    );
    push(
        "Rigid bodies",
        check(
            "tennis racket: spin about the intermediate axis flips (1 = Ω₂ changed sign)".into(),
            1.0,
            if top.min_intermediate_ratio < -0.9 {
                1.0
            } else {
                0.0
            },
            0.0,
            0,
        ),
    );
    for (deg, mu) in [(30.0, 0.3), (20.0, 0.1), (45.0, 0.5)] {
        let r = incline(deg, mu, 0.1, 0.1, 300)?;
        push(
            "Rigid bodies",
            check(
                format!("box on an incline θ = {deg}°, μ = {mu}: acceleration g (sin θ − μ cos θ) (m/s², 0.5 %)"),
                r.expected,
                r.acceleration,
                0.005 * r.expected,
                r.not_converged,
            ),
        );
    }
    for (deg, mu) in [(20.0, 0.5), (10.0, 0.3)] {
        let r = incline(deg, mu, 0.1, 0.1, 500)?;
        push(
            "Rigid bodies",
            check(
                format!(
                    "box on an incline θ = {deg}°, μ = {mu} (tan θ < μ): drift over 500 steps (m)"
                ),
                0.0,
                r.displacement.abs(),
                1e-6,
                r.not_converged,
            ),
        );
    }
    // slide vs topple: block of width w (downhill) and height hgt, textbook thresholds
    // tan θ = w / hgt (topple, rough contact) and tan θ = μ (slide)
    for (tan, mu, width, height) in [
        (0.4, 1.0, 0.05, 0.1),
        (0.6, 1.0, 0.05, 0.1),
        (0.25, 0.3, 0.1, 0.1),
        (0.4, 0.3, 0.1, 0.1),
    ] {
        let deg = f64::atan(tan).to_degrees();
        let r = incline(deg, mu, width, height, 1000)?;
        let (topples, slides) = (r.rotation > 0.2, r.displacement > 1e-3);
        let expect_topple = tan > width / height;
        let expect_slide = !expect_topple && tan > mu;
        push(
            "Rigid bodies",
            check(
                format!(
                    "block w/h = {:.2} on an incline tan θ = {tan}, μ = {mu}, 1 s: topples (1) / slides (2) / stays (0)",
                    width / height
                ),
                if expect_topple { 1.0 } else if expect_slide { 2.0 } else { 0.0 },
                if topples { 1.0 } else if slides { 2.0 } else { 0.0 },
                0.0,
                r.not_converged,
            ),
        );
    }
    let rest = resting_box(0.01, 300)?;
    push(
        "Rigid bodies",
        check(
            format!(
                "box at rest on the floor ({} contacts): Σ r_N / (m g h)",
                rest.contacts
            ),
            1.0,
            rest.normal_impulse / rest.weight_impulse,
            1e-8,
            rest.not_converged,
        ),
    );
    push(
        "Rigid bodies",
        check(
            "box at rest on the floor: corner impulses statically admissible (1 = yes)".into(),
            1.0,
            if rest.admissible { 1.0 } else { 0.0 },
            0.0,
            rest.not_converged,
        ),
    );
    push(
        "Rigid bodies",
        check(
            "box dropped 1 cm onto the floor: penetration at rest / smallest side".into(),
            0.0,
            rest.penetration,
            0.01,
            rest.not_converged,
        ),
    );
    if !_quick {
        for (what, bodies) in [
            (
                "10-course running-bond brick wall (10/9 bricks a course)",
                brick_wall(10, 10)?,
            ),
            ("5-layer cube pyramid (55 cubes)", cube_pyramid(5)?),
        ] {
            let r = stack(bodies, 0.7, 1000)?;
            push(
                "Rigid bodies",
                check(
                    format!(
                        "{what}, μ = 0.7, 1 000 steps of 1 ms ({} contacts, {} steps handed to the library): largest displacement (m)",
                        r.contacts, r.handed_over
                    ),
                    0.0,
                    r.max_displacement,
                    1e-5,
                    r.not_converged,
                ),
            );
        }
        let r = wall_impact(5, 4, 6.0, 120)?;
        push(
            "Rigid bodies",
            check(
                format!(
                    "5-course wall ({} bricks) hit by a steel ball (r = 8 cm, 6 m/s), 120 steps (at most {} contacts; largest displacement {:.2} m): collapses (1 = at least 3 bricks thrown more than 5 cm)",
                    r.bricks, r.max_contacts, r.max_displacement
                ),
                1.0,
                if r.displaced >= 3 { 1.0 } else { 0.0 },
                0.0,
                r.not_converged,
            ),
        );
    }
    Ok(out)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn torque_free_top_keeps_momentum_and_energy() {
        let top = free_top([0.5, 0.2, 6.0], 1e-3, 10_000).unwrap();
        assert!(top.momentum_drift < 1e-10, "{top:?}");
        assert!(top.energy_drift < 1e-6, "{top:?}");
    }

    pub fn tennis_racket_flips() {
        // spin about the intermediate axis y with a small perturbation: it flips
        let top = free_top([0.05, 6.0, 0.05], 1e-3, 4_000).unwrap();
        assert!(top.min_intermediate_ratio < -0.9, "{top:?}");
        // about the major (x) and minor (z) axes it does not
        for omega in [[6.0, 0.05, 0.05], [0.05, 0.05, 6.0]] {
            let stable = free_top(omega, 1e-3, 4_000).unwrap();
            assert!(stable.min_intermediate_ratio > 0.9, "{stable:?}");
        }
    }

    pub fn resting_box_carries_its_weight() {
        let r = resting_box(0.01, 300).unwrap();
        assert!(r.contacts >= 4, "{r:?}");
        assert!(r.penetration < 0.01, "{r:?}");
        assert!(
            (r.normal_impulse - r.weight_impulse).abs() <= 1e-8 * r.weight_impulse,
            "{r:?}"
        );
        assert!(r.admissible, "{r:?}");
        assert_eq!(r.not_converged, 0);
    }

    pub fn box_slides_down_an_incline() {
        let r = incline(30.0, 0.3, 0.1, 0.1, 200).unwrap();
        assert!(
            (r.acceleration - r.expected).abs() <= 0.005 * r.expected,
            "{r:?}"
        );
        assert_eq!(r.not_converged, 0);
    }

    pub fn box_sticks_on_a_gentle_incline() {
        let r = incline(20.0, 0.5, 0.1, 0.1, 500).unwrap();
        assert!(r.displacement.abs() < 1e-6, "{r:?}");
        assert_eq!(r.not_converged, 0);
    }
}

#[cfg(feature = "unit-tests")]
pub mod stack_tests {
    use super::*;

    pub fn tall_block_topples_and_cube_slides_on_an_incline() {
        // tan θ = 0.6 > w/h = 0.5 with rough contact: topples
        let r = incline(0.6f64.atan().to_degrees(), 1.0, 0.05, 0.1, 600).unwrap();
        assert!(r.rotation > 0.2, "{r:?}");
        // tan θ = 0.4 < w/h: stays
        let r = incline(0.4f64.atan().to_degrees(), 1.0, 0.05, 0.1, 600).unwrap();
        assert!(r.rotation < 1e-6 && r.displacement.abs() < 1e-6, "{r:?}");
        // μ = 0.3 < tan θ = 0.4 < w/h = 1: slides without toppling
        let r = incline(0.4f64.atan().to_degrees(), 0.3, 0.1, 0.1, 600).unwrap();
        assert!(r.rotation < 1e-3 && r.displacement > 1e-2, "{r:?}");
    }

    pub fn small_wall_and_pyramid_stand() {
        let r = stack(brick_wall(3, 3).unwrap(), 0.7, 100).unwrap();
        assert!(r.max_displacement < 1e-6, "{r:?}");
        assert_eq!(r.not_converged, 0, "{r:?}");
        let r = stack(cube_pyramid(2).unwrap(), 0.7, 100).unwrap();
        assert!(r.max_displacement < 1e-6, "{r:?}");
        assert_eq!(r.not_converged, 0, "{r:?}");
    }
}

#[cfg(feature = "unit-tests")]
pub mod impact_tests {
    use super::*;

    /// A 3-course wall hit by the steel ball: bricks fly off, every step converges (the full
    /// 5-course case is a `coulomb validate` check).
    pub fn small_wall_is_knocked_over_by_a_ball() {
        let r = wall_impact(3, 2, 6.0, 25).unwrap();
        assert_eq!(r.not_converged, 0, "{r:?}");
        assert!(r.max_displacement > 0.05, "{r:?}");
        // the ball gave momentum to the bricks: it slowed down
        assert!(r.sphere_speed < 6.0, "{r:?}");
    }

    /// The `coulomb validate` case: the 5-course wall collapses, every step converges.
    #[ignore = "long (18 bricks, 120 steps): a `coulomb validate` check"]
    pub fn five_course_wall_collapses() {
        let r = wall_impact(5, 4, 6.0, 120).unwrap();
        println!("{r:?}");
        assert_eq!(r.not_converged, 0, "{r:?}");
        assert!(r.displaced >= 3, "{r:?}");
    }
}

#[cfg(feature = "unit-tests")]
pub mod report {
    /// The full list of `coulomb validate`'s rigid checks, printed (long: the wall and the
    /// pyramid run 1 000 steps each).
    #[ignore = "long (the 10-course wall and the 5-layer pyramid): run by `coulomb validate`"]
    pub fn print_rigid_checks() {
        for (s, c) in super::checks(false).unwrap() {
            println!(
                "{s} | {} | expected {:e} | measured {:e} | tol {:e} | not converged {} | {}",
                c.name,
                c.expected,
                c.measured,
                c.tolerance,
                c.not_converged,
                if c.pass() { "pass" } else { "FAIL" }
            );
        }
    }
}

#[cfg(feature = "unit-tests")]
pub mod shape_tests {
    use super::*;
    use parry3d_f64::math::Pose;

    fn body(shape: SharedShape, z: f64) -> RigidBodyDesc {
        let mass = MassProperties::from_shape(&shape, 1000.0).unwrap();
        RigidBodyDesc {
            shape,
            mass,
            position: [0.0, 0.0, z],
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            material: 0,
            fixed: false,
        }
    }

    /// Every shape kind falls 2 cm onto the floor (a half-space, then a two-triangle mesh)
    /// and comes to rest on it without sinking: the lowest surface point ends within 1 % of
    /// the shape's size of z = 0, and the last steps converge.
    pub fn every_shape_comes_to_rest_on_a_plane_and_a_mesh() {
        let hull = SharedShape::convex_hull(&[
            Vector::new(-0.05, -0.05, -0.04),
            Vector::new(0.06, -0.04, -0.05),
            Vector::new(0.0, 0.07, -0.05),
            Vector::new(0.01, 0.0, 0.06),
            Vector::new(-0.03, 0.02, 0.03),
        ])
        .unwrap();
        let compound = SharedShape::compound(vec![
            (
                Pose::translation(-0.05, 0.0, 0.0),
                SharedShape::cuboid(0.05, 0.05, 0.05),
            ),
            (Pose::translation(0.05, 0.0, 0.0), SharedShape::ball(0.05)),
        ]);
        // (shape, how far its lowest point is below its frame's origin: z of the origin at rest)
        let lying = crate::bodies::dynamics::rotation_to_wxyz(
            parry3d_f64::math::Rotation::from_rotation_x(std::f64::consts::FRAC_PI_2),
        );
        let cases: Vec<(SharedShape, [f64; 4], f64)> = vec![
            (SharedShape::ball(0.05), [1.0, 0.0, 0.0, 0.0], 0.05),
            (
                SharedShape::cuboid(0.05, 0.03, 0.02),
                [1.0, 0.0, 0.0, 0.0],
                0.02,
            ),
            // capsule and cylinder axes along y, lying on their side
            (
                SharedShape::capsule_y(0.05, 0.03),
                [1.0, 0.0, 0.0, 0.0],
                0.03,
            ),
            (SharedShape::cylinder(0.05, 0.04), lying, 0.05),
            (SharedShape::cone(0.05, 0.04), lying, 0.05),
            (compound, [1.0, 0.0, 0.0, 0.0], 0.05),
            (hull, [1.0, 0.0, 0.0, 0.0], 0.05),
        ];
        let mesh = SharedShape::trimesh(
            vec![
                Vector::new(-1.0, -1.0, 0.0),
                Vector::new(1.0, -1.0, 0.0),
                Vector::new(1.0, 1.0, 0.0),
                Vector::new(-1.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap();
        for use_mesh in [false, true] {
            for (k, (shape, q, depth)) in cases.iter().enumerate() {
                let mut b = body(shape.clone(), depth + 0.02);
                b.orientation = *q;
                // capsule lying: rotate it too (its axis is y, so it already lies flat)
                let mut ob = floor();
                if use_mesh {
                    ob.shape = mesh.clone();
                }
                let mut w = RigidWorld::new(
                    vec![b],
                    vec![ob],
                    one_material(0.5),
                    RigidSettings::default(),
                )
                .unwrap();
                let mut last = None;
                for _ in 0..300 {
                    last = Some(w.step().unwrap());
                }
                let last = last.unwrap();
                assert_eq!(
                    last.status,
                    RigidStatus::Converged,
                    "case {k}, mesh {use_mesh}"
                );
                assert!(last.contacts >= 1, "case {k}, mesh {use_mesh}");
                // the lowest point of the shape: its AABB's bottom at the final pose
                let pose = Pose::from_parts(
                    Vector::from_array(w.positions()[0]),
                    crate::bodies::dynamics::rotation_from_wxyz(w.orientations()[0]),
                );
                let bottom = shape.compute_aabb(&pose).mins.z;
                assert!(
                    bottom.abs() < 0.01 * 2.0 * depth,
                    "case {k}, mesh {use_mesh}: bottom {bottom}, {last:?}"
                );
            }
        }
    }
}

/// A pile of `n` random convex rocks (hulls of 12 points, size 4–6 cm, ρ = 2500, seeded
/// ChaCha8) on a grid of about four layers above the floor inside four walls (half-spaces): the bodies, the
/// obstacles. For the benchmark `scripts/bench_rigid_pile.sh`.
pub fn rock_pile(
    n: usize,
    seed: u64,
) -> Result<(Vec<RigidBodyDesc>, Vec<RigidObstacle>), RigidError> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    // about 4 layers: a pile, not a single layer
    let side = (n as f64 / 4.0).sqrt().ceil().max(1.0) as usize;
    let pitch = 0.14;
    let mut bodies = Vec::with_capacity(n);
    for k in 0..n {
        let size = rng.random_range(0.04..0.06);
        let points: Vec<Vector> = (0..12)
            .map(|_| {
                let d = Vector::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                d.normalize_or_zero() * size * rng.random_range(0.7..1.0)
            })
            .collect();
        let shape = SharedShape::convex_hull(&points).ok_or_else(|| RigidError::Mass {
            what: format!("rock {k}"),
            detail: "degenerate hull".into(),
        })?;
        let mass = MassProperties::from_shape(&shape, 2500.0)?;
        let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
        bodies.push(RigidBodyDesc {
            shape,
            mass,
            position: [
                (i as f64 + 0.5) * pitch,
                (j as f64 + 0.5) * pitch,
                0.1 + l as f64 * pitch,
            ],
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            material: 0,
            fixed: false,
        });
    }
    let width = side as f64 * pitch;
    let wall = |name: &str, normal: Vector, at: [f64; 3]| RigidObstacle {
        name: name.into(),
        shape: SharedShape::halfspace(normal),
        position: at,
        orientation: [1.0, 0.0, 0.0, 0.0],
        motion: Motion::Fixed,
        material: 0,
    };
    let obstacles = vec![
        floor(),
        wall("x-", Vector::X, [0.0; 3]),
        wall("x+", -Vector::X, [width, 0.0, 0.0]),
        wall("y-", Vector::Y, [0.0; 3]),
        wall("y+", -Vector::Y, [0.0, width, 0.0]),
    ];
    Ok((bodies, obstacles))
}

#[cfg(feature = "unit-tests")]
pub mod bench {
    use super::*;

    /// The rock-pile benchmark (scripts/bench_rigid_pile.sh sets RIGID_PILE_ROCKS and
    /// RIGID_PILE_STEPS): time per step, sweeps per step, share of collision detection.
    #[ignore = "benchmark: scripts/bench_rigid_pile.sh"]
    pub fn rigid_pile_benchmark() {
        let var = |k: &str, d: usize| {
            std::env::var(k)
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(d)
        };
        let (n, steps) = (var("RIGID_PILE_ROCKS", 200), var("RIGID_PILE_STEPS", 300));
        let (bodies, obstacles) = rock_pile(n, 1).unwrap();
        let settings = RigidSettings {
            tolerance: 1e-4,
            ..RigidSettings::default()
        };
        let mut w = RigidWorld::new(bodies, obstacles, one_material(0.5), settings).unwrap();
        let (mut total, mut detect, mut sweeps, mut contacts, mut bad, mut lib) =
            (0.0, 0.0, 0, 0, 0, 0);
        let t0 = std::time::Instant::now();
        for _ in 0..steps {
            let r = w.step().unwrap();
            detect += r.detection_seconds;
            sweeps += r.sweeps;
            contacts += r.contacts;
            bad += usize::from(r.status == RigidStatus::NotConverged);
            lib += usize::from(r.method == "nsgs+library");
        }
        total += t0.elapsed().as_secs_f64();
        let s = steps as f64;
        println!(
            "rocks {n}, steps {steps}, tol 1e-4: {:.3} ms/step, detection {:.1} %, {:.1} sweeps/step, {:.0} contacts/step, {bad} steps not converged, {lib} handed to the library, kinetic energy at the end {:.3e} J",
            1e3 * total / s,
            100.0 * detect / total,
            sweeps as f64 / s,
            contacts as f64 / s,
            w.kinetic_energy()
        );
    }
}
