//! The validation cases of the joints (issue 53) for `coulomb validate`: a simple pendulum's
//! period, a hanging chain's top force, a motorised hinge's acceleration, Newton's cradle's
//! speed transfer and a double pendulum's drift and energy, each with its expected value and tolerance (docs/joints.md).

use crate::bodies::joints::{JointDesc, JointKind, Motor};
use crate::bodies::rigid::RigidError;
use crate::step::rigid::{RigidSettings, RigidStatus, RigidWorld};
use crate::validation::rigid::{cuboid, one_material};
use crate::validation::Check;
use crate::world::GRAVITY;

fn hinge(a: usize, b: Option<usize>, anchor: [f64; 3], axis: [f64; 3]) -> JointDesc {
    JointDesc {
        kind: JointKind::Revolute,
        body_a: a,
        body_b: b,
        anchor,
        axis: Some(axis),
        limits: None,
        motor: None,
        limit_restitution: None,
        friction: None,
    }
}

/// Steps `w` n times; the steps not converged.
fn run(w: &mut RigidWorld, n: usize) -> Result<usize, RigidError> {
    let mut bad = 0;
    for _ in 0..n {
        if w.step()?.status == RigidStatus::NotConverged {
            bad += 1;
        }
    }
    Ok(bad)
}

/// A bar 0.04 × 0.04 × 0.5 m hanging from a hinge at its end, amplitude 0.01 rad: (measured
/// period from upward zero crossings of the hinge angle, 2π √(I/(m g d)), steps not
/// converged).
pub fn pendulum_period() -> Result<(f64, f64, usize), RigidError> {
    let (a, c) = (0.02, 0.25);
    let mut bar = cuboid([a, a, c], 1000.0, [0.0, 0.0, -c])?;
    let m = bar.mass.mass;
    let i = m * (a * a + c * c) / 3.0 + m * c * c;
    let w0 = 0.01 * (m * GRAVITY * c / i).sqrt();
    bar.angular_velocity = [0.0, w0, 0.0];
    bar.velocity = [-w0 * c, 0.0, 0.0];
    let joints = [hinge(0, None, [0.0; 3], [0.0, 1.0, 0.0])];
    let settings = RigidSettings::default();
    let mut w = RigidWorld::with_joints(vec![bar], vec![], one_material(0.3), settings, &joints)?;
    let period = 2.0 * std::f64::consts::PI * (i / (m * GRAVITY * c)).sqrt();
    let (measured, bad) = measured_period(&mut w, 0, 3.2 * period)?;
    Ok((measured, period, bad))
}

/// Steps `w` for `duration` s and measures the period of joint `j`'s oscillation: the mean
/// interval between the upward zero crossings of its coordinate (each crossing time
/// interpolated linearly within its step); (period (NaN with fewer than two crossings),
/// steps not converged). The simple pendulum's check and the URDF pendulum's test use it.
pub fn measured_period(
    w: &mut RigidWorld,
    j: usize,
    duration: f64,
) -> Result<(f64, usize), RigidError> {
    let h = w.settings().h;
    let (mut crossings, mut prev, mut bad) = (Vec::new(), 0.0, 0);
    for _ in 0..(duration / h) as usize {
        bad += run(w, 1)?;
        let theta = w.joint_coordinate(j).map_or(0.0, |c| c.0);
        if prev < 0.0 && theta >= 0.0 {
            crossings.push(w.time() - h * theta / (theta - prev));
        }
        prev = theta;
    }
    let measured = match crossings.as_slice() {
        [first, .., last] => (last - first) / (crossings.len() - 1) as f64,
        _ => f64::NAN,
    };
    Ok((measured, bad))
}

/// 20 links 0.02 × 0.02 × 0.1 m hanging from spherical joints, solved to 1e-13: (top joint's
/// vertical force, the chain's weight, steps not converged) after 3 steps.
pub fn hanging_chain() -> Result<(f64, f64, usize), RigidError> {
    let n = 20;
    let mut bodies = Vec::new();
    let mut joints = Vec::new();
    for k in 0..n {
        bodies.push(cuboid(
            [0.01, 0.01, 0.05],
            1000.0,
            [0.0, 0.0, -0.05 - 0.1 * k as f64],
        )?);
        joints.push(JointDesc {
            kind: JointKind::Spherical,
            axis: None,
            ..hinge(k, k.checked_sub(1), [0.0, 0.0, -0.1 * k as f64], [0.0; 3])
        });
    }
    let weight: f64 = bodies.iter().map(|b| b.mass.mass * GRAVITY).sum();
    let settings = RigidSettings {
        tolerance: 1e-13,
        max_sweeps: 50_000,
        stall_window: 5_000,
        ..RigidSettings::default()
    };
    let mut w = RigidWorld::with_joints(bodies, vec![], one_material(0.3), settings, &joints)?;
    let bad = run(&mut w, 3)?;
    Ok((w.joint_forces()[0][2], weight, bad))
}

/// A plate 0.2 × 0.2 × 0.04 m on a hinge through its centre (axis z), motor torque limit
/// 0.05 N m, target speed out of reach, 500 steps: (measured angular acceleration, τ/I, steps
/// not converged).
pub fn motor_acceleration() -> Result<(f64, f64, usize), RigidError> {
    let plate = cuboid([0.1, 0.1, 0.02], 1000.0, [0.0, 0.0, 1.0])?;
    let i = plate.mass.mass * 0.02 / 3.0;
    let tau = 0.05;
    let joints = [JointDesc {
        motor: Some(Motor::with_velocity(1e3, tau)),
        ..hinge(0, None, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
    }];
    let mut w = RigidWorld::with_joints(
        vec![plate],
        vec![],
        one_material(0.3),
        RigidSettings::default(),
        &joints,
    )?;
    let bad = run(&mut w, 500)?;
    Ok((w.angular_velocities()[0][2] / w.time(), tau / i, bad))
}

/// A double pendulum of two bars 0.04 × 0.04 × 0.5 m released at θ = ½ rad, `steps` steps:
/// (largest joint drift (m), largest |E − E₀| / |E₀| (E from the hinge's height), steps not
/// converged).
pub fn double_pendulum(steps: usize) -> Result<(f64, f64, usize), RigidError> {
    let l = 0.5;
    let theta: f64 = 0.5;
    let u = [theta.sin(), 0.0, -theta.cos()];
    let q = [(-theta / 2.0).cos(), 0.0, (-theta / 2.0).sin(), 0.0];
    let at = |s: f64| [u[0] * s, 0.0, u[2] * s];
    let mut b1 = cuboid([0.02, 0.02, l / 2.0], 1000.0, at(l / 2.0))?;
    let mut b2 = cuboid([0.02, 0.02, l / 2.0], 1000.0, at(1.5 * l))?;
    b1.orientation = q;
    b2.orientation = q;
    let joints = [
        hinge(0, None, [0.0; 3], [0.0, 1.0, 0.0]),
        hinge(1, Some(0), at(l), [0.0, 1.0, 0.0]),
    ];
    let mut w = RigidWorld::with_joints(
        vec![b1, b2],
        vec![],
        one_material(0.3),
        RigidSettings::default(),
        &joints,
    )?;
    let e0 = w.kinetic_energy() + w.potential_energy();
    let (mut drift, mut energy, mut bad): (f64, f64, usize) = (0.0, 0.0, 0);
    for _ in 0..steps {
        bad += run(&mut w, 1)?;
        drift = drift.max(w.joint_drift());
        let e = w.kinetic_energy() + w.potential_energy();
        energy = energy.max((e - e0).abs() / e0.abs());
    }
    Ok((drift, energy, bad))
}

/// Result of [`newtons_cradle`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cradle {
    /// ball 0's largest speed before it first touches ball 1 (m/s)
    pub first_speed: f64,
    /// ball 4's largest speed over the run: its speed as it leaves (m/s)
    pub last_speed: f64,
    /// the largest speed of balls 0–3 after ball 4 has left (m/s): what the others kept
    pub others_speed: f64,
    /// the largest joint drift over the run (m)
    pub drift: f64,
    /// steps not converged
    pub not_converged: usize,
}

/// Newton's cradle (issue 53, examples/scenes/rigid/newtons-cradle.toml): 5 steel balls of
/// radius 0.02 m (7800 kg/m³) in a row along x, `gap` apart (1 mm in the scene and the
/// check), centres at z = 0.1 m, each
/// hanging 0.2 m below its own revolute joint to the world (axis y); frictionless contacts
/// with e = 1. Ball 0 is released from `release` rad (pulled back, at rest) and swings into
/// the others; `steps` steps of `settings`.
pub fn newtons_cradle(
    release: f64,
    gap: f64,
    steps: usize,
    settings: RigidSettings,
) -> Result<Cradle, RigidError> {
    use crate::bodies::rigid::MassProperties;
    use parry3d_f64::shape::SharedShape;
    let (radius, length, n) = (0.02, 0.2, 5);
    let shape = SharedShape::ball(radius);
    let mass = MassProperties::from_shape(&shape, 7800.0)?;
    let mut bodies = Vec::new();
    let mut joints = Vec::new();
    for k in 0..n {
        let pivot = [k as f64 * (2.0 * radius + gap), 0.0, 0.1 + length];
        let a = if k == 0 { release } else { 0.0 };
        bodies.push(crate::bodies::rigid::RigidBodyDesc {
            shape: shape.clone(),
            mass,
            position: [
                pivot[0] - length * a.sin(),
                0.0,
                pivot[2] - length * a.cos(),
            ],
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            material: 0,
            fixed: false,
        });
        joints.push(hinge(k, None, pivot, [0.0, 1.0, 0.0]));
    }
    let materials = crate::world::MaterialTable::uniform(
        vec!["steel".into()],
        crate::world::ContactLaw {
            mu: 0.0,
            restitution: 1.0,
            rolling_friction: 0.0,
        },
    );
    let mut w = RigidWorld::with_joints(bodies, vec![], materials, settings, &joints)?;
    let speed = |w: &RigidWorld, i: usize| {
        let v = w.velocities()[i];
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    };
    let mut out = Cradle {
        first_speed: 0.0,
        last_speed: 0.0,
        others_speed: 0.0,
        drift: 0.0,
        not_converged: 0,
    };
    let (mut touched, mut left) = (false, false);
    for _ in 0..steps {
        let report = w.step()?;
        if report.status == RigidStatus::NotConverged {
            out.not_converged += 1;
        }
        touched |= report.contacts > 0;
        if !touched {
            out.first_speed = out.first_speed.max(speed(&w, 0));
        }
        let last = speed(&w, n - 1);
        // ball 4 has left once it slows down (gravity) after its largest speed
        left |= out.last_speed > 0.5 * out.first_speed && last < out.last_speed;
        out.last_speed = out.last_speed.max(last);
        if left {
            for i in 0..n - 1 {
                out.others_speed = out.others_speed.max(speed(&w, i));
            }
        }
        out.drift = out.drift.max(w.joint_drift());
    }
    Ok(out)
}

/// Result of [`slider_crank`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliderCrank {
    /// largest |x − x(φ)| of the piston over the run (m)
    pub max_error: f64,
    /// crank turns made
    pub turns: f64,
    /// smallest and largest piston position seen (m)
    pub x_range: (f64, f64),
    /// largest joint drift over the run (m or rad)
    pub drift: f64,
    /// steps not converged
    pub not_converged: usize,
}

/// Crank radius r and rod length l of [`slider_crank`] (m).
pub const CRANK: (f64, f64) = (0.1, 0.3);

/// A slider-crank (issue 53, examples/scenes/rigid/slider-crank.toml) in the plane z = 0,
/// steel (7800 kg/m³): a crank bar of r = 0.1 m on a revolute joint to the world at the
/// origin (axis z) whose motor turns it at 2π rad/s (at most 50 N m), a connecting rod of l =
/// 0.3 m hinged to the crank pin, a piston hinged to the rod and on a prismatic joint to the
/// world along x; starts at φ = 0 at rest; `steps` steps of h = 1e-3 s. The piston's centre
/// (its pin) follows x(φ) = r cos φ + √(l² − r² sin² φ), φ the crank's angle from its centre
/// of mass.
pub fn slider_crank(steps: usize) -> Result<SliderCrank, RigidError> {
    let (r, l) = CRANK;
    let bodies = vec![
        cuboid([r / 2.0, 0.01, 0.01], 7800.0, [r / 2.0, 0.0, 0.0])?,
        cuboid([l / 2.0, 0.01, 0.01], 7800.0, [r + l / 2.0, 0.0, 0.02])?,
        cuboid([0.03, 0.03, 0.03], 7800.0, [r + l, 0.0, 0.02])?,
    ];
    let z = [0.0, 0.0, 1.0];
    let joints = [
        JointDesc {
            motor: Some(Motor::with_velocity(2.0 * std::f64::consts::PI, 50.0)),
            ..hinge(0, None, [0.0; 3], z)
        },
        hinge(1, Some(0), [r, 0.0, 0.01], z),
        hinge(2, Some(1), [r + l, 0.0, 0.02], z),
        JointDesc {
            kind: JointKind::Prismatic,
            ..hinge(2, None, [r + l, 0.0, 0.02], [1.0, 0.0, 0.0])
        },
    ];
    let mut w = RigidWorld::with_joints(
        bodies,
        vec![],
        one_material(0.3),
        RigidSettings::default(),
        &joints,
    )?;
    let mut out = SliderCrank {
        max_error: 0.0,
        turns: 0.0,
        x_range: (f64::INFINITY, f64::NEG_INFINITY),
        drift: 0.0,
        not_converged: 0,
    };
    let mut prev = 0.0;
    let mut unwrapped = 0.0;
    for _ in 0..steps {
        out.not_converged += run(&mut w, 1)?;
        let c = w.centres_of_mass();
        let phi = c[0][1].atan2(c[0][0]);
        let mut d = phi - prev;
        if d > std::f64::consts::PI {
            d -= 2.0 * std::f64::consts::PI;
        } else if d < -std::f64::consts::PI {
            d += 2.0 * std::f64::consts::PI;
        }
        unwrapped += d;
        prev = phi;
        let x = c[2][0];
        let want = r * phi.cos() + (l * l - (r * phi.sin()).powi(2)).sqrt();
        out.max_error = out.max_error.max((x - want).abs());
        out.x_range = (out.x_range.0.min(x), out.x_range.1.max(x));
        out.drift = out.drift.max(w.joint_drift());
    }
    out.turns = unwrapped / (2.0 * std::f64::consts::PI);
    Ok(out)
}

/// The joints' checks of `coulomb validate` (section "Joints"); `quick`: the double pendulum
/// over 2 s instead of 10 s.
pub fn checks(quick: bool) -> Result<Vec<(String, Check)>, RigidError> {
    let check = |name: &str, expected: f64, measured: f64, tolerance: f64, bad: usize| {
        (
            "Joints".to_string(),
            Check {
                name: name.to_string(),
                expected,
                measured,
                tolerance,
                unit: String::new(),
                not_converged: bad,
            },
        )
    };
    let mut out = Vec::new();
    let (period, expected, bad) = pendulum_period()?;
    out.push(check(
        "simple pendulum, amplitude 0.01 rad: period 2π √(I/(m g d)) (s, 0.5 %)",
        expected,
        period,
        0.005 * expected,
        bad,
    ));
    let (force, weight, bad) = hanging_chain()?;
    out.push(check(
        "hanging chain of 20 links at rest: top joint force = chain weight (N, 1e-8 relative)",
        weight,
        force,
        1e-8 * weight,
        bad,
    ));
    let (acc, expected, bad) = motor_acceleration()?;
    out.push(check(
        "motorised hinge under its torque limit: angular acceleration τ/I (rad/s², 1e-6 relative)",
        expected,
        acc,
        1e-6 * expected,
        bad,
    ));
    let c = newtons_cradle(0.5, 1e-3, 500, RigidSettings::default())?;
    out.push(check(
        "Newton's cradle, 5 balls 1 mm apart, e = 1: the last ball leaves with ≥ 95 % of the first ball's speed (m/s)",
        c.first_speed,
        c.last_speed,
        0.05 * c.first_speed,
        c.not_converged,
    ));
    let sc = slider_crank(3_000)?;
    out.push(check(
        &format!(
            "slider-crank, {:.2} turns: piston x − (r cos φ + √(l² − r² sin² φ)), largest (m, < 1e-6)",
            sc.turns
        ),
        0.0,
        sc.max_error,
        1e-6,
        sc.not_converged,
    ));
    let steps = if quick { 2_000 } else { 10_000 };
    let (drift, energy, bad) = double_pendulum(steps)?;
    out.push(check(
        &format!("double pendulum θ = ½, {steps} steps: joint position drift (m, < 1e-6)"),
        0.0,
        drift,
        1e-6,
        bad,
    ));
    out.push(check(
        &format!("double pendulum θ = ½, {steps} steps: largest |E − E₀| / |E₀| (1 %)"),
        0.0,
        energy,
        0.01,
        bad,
    ));
    Ok(out)
}
