//! Joints between rigid bodies (issue 53): the pendulum's period, a hanging chain's top force,
//! a motor under its torque limit, a limit, a door on two hinges (redundant rows), the drift
//! of a double pendulum, and every bad input refused with a typed error.

use coulomb_granular::rigid::joints::{JointDesc, JointKind, Motor};
use coulomb_granular::rigid::validation::{cuboid, one_material};
use coulomb_granular::rigid::{RigidBodyDesc, RigidError, RigidSettings, RigidStatus, RigidWorld};

const G: f64 = 9.81;

fn joint(kind: JointKind, a: usize, b: Option<usize>, anchor: [f64; 3]) -> JointDesc {
    JointDesc {
        kind,
        body_a: a,
        body_b: b,
        anchor,
        axis: None,
        limits: None,
        motor: None,
        limit_restitution: None,
        friction: None,
    }
}

fn hinge(a: usize, b: Option<usize>, anchor: [f64; 3], axis: [f64; 3]) -> JointDesc {
    JointDesc {
        axis: Some(axis),
        ..joint(JointKind::Revolute, a, b, anchor)
    }
}

fn world(
    bodies: Vec<RigidBodyDesc>,
    joints: &[JointDesc],
    settings: RigidSettings,
) -> Result<RigidWorld, RigidError> {
    RigidWorld::with_joints(bodies, vec![], one_material(0.3), settings, joints)
}

/// A bar of half extents (a, b, c) hanging below a hinge at the origin (axis y), swinging at
/// small amplitude: the period is 2π √(I / (m g d)) with I about the hinge.
#[test]
fn pendulum_period_at_small_amplitude() {
    let (a, b, c) = (0.02, 0.02, 0.25);
    let d = c;
    let mut bar = cuboid([a, b, c], 1000.0, [0.0, 0.0, -d]).unwrap();
    let m = bar.mass.mass;
    let i = m * (a * a + c * c) / 3.0 + m * d * d;
    let omega0 = 0.01 * (m * G * d / i).sqrt(); // amplitude 0.01 rad
    bar.angular_velocity = [0.0, omega0, 0.0];
    bar.velocity = [-omega0 * d, 0.0, 0.0];
    let mut w = world(
        vec![bar],
        &[hinge(0, None, [0.0; 3], [0.0, 1.0, 0.0])],
        RigidSettings::default(),
    )
    .unwrap();
    let period = 2.0 * std::f64::consts::PI * (i / (m * G * d)).sqrt();
    let h = w.settings().h;
    let mut crossings = Vec::new();
    let mut prev = w.joint_coordinate(0).unwrap().0;
    let steps = (3.2 * period / h) as usize;
    for _ in 0..steps {
        let r = w.step().unwrap();
        assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
        let (theta, _) = w.joint_coordinate(0).unwrap();
        // upward crossings of 0 (from negative to positive)
        if prev < 0.0 && theta >= 0.0 {
            let t = w.time() - h * theta / (theta - prev);
            crossings.push(t);
        }
        prev = theta;
    }
    assert!(crossings.len() >= 2, "{crossings:?}");
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let rel = (measured - period).abs() / period;
    eprintln!("pendulum: period {measured} s vs 2π√(I/(m g d)) = {period} s: {rel:.2e}");
    assert!(rel < 5e-3, "period {measured} vs {period}: {rel}");
    // the amplitude stays (no growth, little loss)
    assert!(w.joint_drift() < 1e-9, "{}", w.joint_drift());
}

/// 20 links hanging at rest from the world on spherical joints: the top joint carries the
/// chain's weight to 1e-8 (relative), the solve to a tight tolerance.
#[test]
fn hanging_chain_top_force_is_its_weight() {
    let n = 20;
    let half = [0.01, 0.01, 0.05];
    let mut bodies = Vec::new();
    let mut joints = Vec::new();
    for k in 0..n {
        let z = -0.05 - 0.1 * k as f64;
        bodies.push(cuboid(half, 1000.0, [0.0, 0.0, z]).unwrap());
        let anchor = [0.0, 0.0, -0.1 * k as f64];
        let other = if k == 0 { None } else { Some(k - 1) };
        joints.push(joint(JointKind::Spherical, k, other, anchor));
    }
    let weight: f64 = bodies.iter().map(|b| b.mass.mass * G).sum();
    let settings = RigidSettings {
        tolerance: 1e-13,
        max_sweeps: 50_000,
        stall_window: 5_000,
        ..RigidSettings::default()
    };
    let mut w = world(bodies, &joints, settings).unwrap();
    for _ in 0..3 {
        let r = w.step().unwrap();
        assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
    }
    let f = w.joint_forces();
    assert_eq!(f.len(), n);
    let rel = (f[0][2] - weight).abs() / weight;
    eprintln!(
        "chain: top force {} N vs weight {weight} N: {rel:.2e}",
        f[0][2]
    );
    assert!(
        rel <= 1e-8,
        "top force {} vs weight {weight}: {rel}",
        f[0][2]
    );
    assert!(f[0][0].abs() + f[0][1].abs() <= 1e-8 * weight, "{:?}", f[0]);
    // each joint carries the links below it
    let link = weight / n as f64;
    for (k, fk) in f.iter().enumerate() {
        let want = link * (n - k) as f64;
        assert!((fk[2] - want).abs() <= 1e-7 * weight, "joint {k}: {fk:?}");
    }
}

/// A wheel on a motorised hinge through its centre (gravity has no torque), the motor's
/// target speed out of reach: it accelerates as τ/I with τ the torque limit.
#[test]
fn motorised_hinge_accelerates_as_torque_over_inertia() {
    let wheel = cuboid([0.1, 0.1, 0.02], 1000.0, [0.0, 0.0, 1.0]).unwrap();
    let weight = wheel.mass.mass * G;
    let i = wheel.mass.mass * (0.1f64.powi(2) + 0.1f64.powi(2)) / 3.0;
    let tau = 0.05;
    let j = JointDesc {
        motor: Some(Motor::with_velocity(1e3, tau)),
        ..hinge(0, None, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
    };
    let mut w = world(vec![wheel], &[j], RigidSettings::default()).unwrap();
    let steps = 500;
    for _ in 0..steps {
        let r = w.step().unwrap();
        assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
    }
    let t = w.time();
    let omega = w.angular_velocities()[0][2];
    let want = tau / i * t;
    assert!((omega - want).abs() <= 1e-6 * want, "{omega} vs {want}");
    let (_, rate) = w.joint_coordinate(0).unwrap();
    assert!((rate - omega).abs() <= 1e-9 * omega);
    // the torque on the wheel about the axis is the limit; the hinge holds the weight
    let f = w.joint_forces()[0];
    assert!((f[5] - tau).abs() <= 1e-8, "{f:?}");
    assert!((f[2] - weight).abs() <= 1e-6 * weight, "{f:?} vs {weight}");
}

/// A motor within reach of its target holds the speed; a limit stops the hinge.
#[test]
fn motor_reaches_its_speed_and_a_limit_stops_the_hinge() {
    let wheel = cuboid([0.1, 0.1, 0.02], 1000.0, [0.0, 0.0, 1.0]).unwrap();
    let j = JointDesc {
        motor: Some(Motor::with_velocity(2.0, 100.0)),
        limits: Some((-1.0, 0.5)),
        ..hinge(0, None, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
    };
    let mut w = world(vec![wheel], &[j], RigidSettings::default()).unwrap();
    let (_, rate) = {
        w.step().unwrap();
        w.joint_coordinate(0).unwrap()
    };
    assert!((rate - 2.0).abs() < 1e-8, "{rate}");
    let mut max_angle: f64 = 0.0;
    for _ in 0..1000 {
        let r = w.step().unwrap();
        assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
        max_angle = max_angle.max(w.joint_coordinate(0).unwrap().0);
    }
    let (angle, rate) = w.joint_coordinate(0).unwrap();
    // beyond the limit the positions are projected back at the end of the step
    assert!(max_angle <= 0.5 + 1e-9, "{max_angle}");
    assert!((angle - 0.5).abs() < 1e-6, "{angle}");
    assert!(rate.abs() < 1e-6, "{rate}");
}

/// A door on two hinges along the same axis: 10 rows for 6 dofs, rank 5 — it solves,
/// swings about its hinges, and neither sags nor drifts.
#[test]
fn door_on_two_hinges_solves() {
    let mut door = cuboid([0.4, 0.02, 1.0], 600.0, [0.4, 0.0, 1.0]).unwrap();
    door.angular_velocity = [0.0, 0.0, 1.0];
    door.velocity = [0.0, 0.4, 0.0];
    let joints = [
        hinge(0, None, [0.0, 0.0, 0.2], [0.0, 0.0, 1.0]),
        hinge(0, None, [0.0, 0.0, 1.8], [0.0, 0.0, 1.0]),
    ];
    let mut w = world(vec![door], &joints, RigidSettings::default()).unwrap();
    for _ in 0..300 {
        let r = w.step().unwrap();
        assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
        assert!(r.error <= 1e-8);
    }
    assert!(w.joint_drift() < 1e-9, "{}", w.joint_drift());
    // turned by about 0.3 rad about z at constant speed, no sag
    let (angle, rate) = w.joint_coordinate(0).unwrap();
    assert!((angle - 0.3).abs() < 1e-4, "{angle}");
    // velocity-level rows at the start configuration dissipate O(h² ω²) per step
    assert!((rate - 1.0).abs() < 1e-3, "{rate}");
    assert!(w.velocities()[0][2].abs() < 1e-9);
    // the two hinges together carry the weight
    let f = w.joint_forces();
    let weight = 600.0 * 0.8 * 0.04 * 2.0 * G;
    assert!(
        ((f[0][2] + f[1][2]) - weight).abs() < 1e-6 * weight,
        "{f:?}"
    );
}

/// A double pendulum released at θ = ½ rad: over 2 000 steps the joints' position drift
/// stays below 1e-6 m and the energy within 1 %.
#[test]
fn double_pendulum_drift_stays_bounded() {
    let l = 0.5;
    let theta: f64 = 0.5;
    let u = [theta.sin(), 0.0, -theta.cos()];
    // R_y(φ) maps −z to (−sin φ, 0, −cos φ): φ = −θ
    let q = [(-theta / 2.0).cos(), 0.0, (-theta / 2.0).sin(), 0.0];
    let at = |s: f64| [u[0] * s, 0.0, u[2] * s];
    let mut b1 = cuboid([0.02, 0.02, l / 2.0], 1000.0, at(l / 2.0)).unwrap();
    let mut b2 = cuboid([0.02, 0.02, l / 2.0], 1000.0, at(1.5 * l)).unwrap();
    b1.orientation = q;
    b2.orientation = q;
    let joints = [
        hinge(0, None, [0.0; 3], [0.0, 1.0, 0.0]),
        hinge(1, Some(0), at(l), [0.0, 1.0, 0.0]),
    ];
    let mut w = world(vec![b1, b2], &joints, RigidSettings::default()).unwrap();
    assert!(w.joint_drift() < 1e-12);
    let e0 = w.kinetic_energy() + w.potential_energy();
    let scale = w.potential_energy().abs().max(1e-12);
    let mut worst: f64 = 0.0;
    let mut energy: f64 = 0.0;
    for _ in 0..2000 {
        let r = w.step().unwrap();
        assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
        worst = worst.max(w.joint_drift());
        let e = w.kinetic_energy() + w.potential_energy();
        energy = energy.max((e - e0).abs());
    }
    eprintln!("double pendulum: drift {worst:.2e}, energy change {energy:.2e} J of {scale:.3} J");
    assert!(worst < 1e-6, "drift {worst}");
    // the swing is not trivial: the lower link moved
    assert!(w.joint_coordinate(1).unwrap().0.abs() > 1e-3);
    // energy relative to the drop of the system released at θ
    let drop = scale;
    assert!(energy <= 0.01 * drop, "energy change {energy} vs {drop}");
}

fn field_of(e: RigidError) -> (usize, &'static str) {
    match e {
        RigidError::Joint { joint, field, .. } => (joint, field),
        e => panic!("not a joint error: {e}"),
    }
}

#[test]
fn bad_joints_are_refused_with_the_joint_and_field() {
    let b0 = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 1.0]).unwrap();
    let b1 = cuboid([0.1; 3], 1000.0, [1.0, 0.0, 1.0]).unwrap();
    let mut fixed = cuboid([0.1; 3], 1000.0, [3.0, 0.0, 1.0]).unwrap();
    fixed.fixed = true;
    let bodies = vec![b0, b1, fixed];
    let good = hinge(0, Some(1), [0.5, 0.0, 1.0], [0.0, 1.0, 0.0]);
    let check = |bad: JointDesc, field: &str| {
        let e = world(
            bodies.clone(),
            &[good.clone(), bad.clone()],
            RigidSettings::default(),
        )
        .unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("joint 1: "), "{msg}");
        assert_eq!(field_of(e), (1, field), "{bad:?}: {msg}");
    };
    check(hinge(7, None, [0.0; 3], [0.0, 0.0, 1.0]), "body_a");
    check(hinge(0, Some(3), [0.0; 3], [0.0, 0.0, 1.0]), "body_b");
    check(hinge(1, Some(1), [0.0; 3], [0.0, 0.0, 1.0]), "body_b");
    check(hinge(2, None, [0.0; 3], [0.0, 0.0, 1.0]), "body_a");
    check(hinge(0, None, [0.0; 3], [0.0; 3]), "axis");
    check(hinge(0, None, [0.0; 3], [f64::NAN, 0.0, 1.0]), "axis");
    check(
        hinge(0, None, [f64::INFINITY, 0.0, 0.0], [0.0, 0.0, 1.0]),
        "anchor",
    );
    check(joint(JointKind::Revolute, 0, None, [0.0; 3]), "axis");
    check(
        JointDesc {
            axis: Some([0.0, 0.0, 1.0]),
            ..joint(JointKind::Spherical, 0, None, [0.0; 3])
        },
        "axis",
    );
    check(
        JointDesc {
            limits: Some((0.5, -0.5)),
            ..hinge(0, None, [0.0; 3], [0.0, 0.0, 1.0])
        },
        "limits",
    );
    check(
        JointDesc {
            limits: Some((0.0, 1.0)),
            ..joint(JointKind::Fixed, 0, None, [0.0; 3])
        },
        "limits",
    );
    check(
        JointDesc {
            motor: Some(Motor::with_velocity(1.0, -1.0)),
            ..hinge(0, None, [0.0; 3], [0.0, 0.0, 1.0])
        },
        "motor.max_force",
    );
    check(
        JointDesc {
            motor: Some(Motor::with_velocity(f64::NAN, 1.0)),
            ..hinge(0, None, [0.0; 3], [0.0, 0.0, 1.0])
        },
        "motor.velocity",
    );
    let servo = |m: Motor| JointDesc {
        motor: Some(m),
        ..hinge(0, None, [0.0; 3], [0.0, 0.0, 1.0])
    };
    check(
        servo(Motor {
            position: Some(0.5),
            ..Motor::with_velocity(1.0, 1.0)
        }),
        "motor",
    );
    check(
        servo(Motor {
            velocity: None,
            ..Motor::with_velocity(1.0, 1.0)
        }),
        "motor",
    );
    check(servo(Motor::with_position(0.5, -1.0)), "motor.max_force");
    check(servo(Motor::with_position(4.0, 1.0)), "motor.position");
    check(servo(Motor::with_position(f64::NAN, 1.0)), "motor.position");
    for g in [0.0, -1.0, f64::INFINITY] {
        check(
            servo(Motor {
                gain: Some(g),
                ..Motor::with_position(0.5, 1.0)
            }),
            "motor.gain",
        );
    }
    check(
        servo(Motor {
            gain: Some(5.0),
            ..Motor::with_velocity(1.0, 1.0)
        }),
        "motor.gain",
    );
    // the good one alone builds, and a joint to a fixed body is fine
    assert!(world(bodies.clone(), &[good], RigidSettings::default()).is_ok());
    assert!(world(
        bodies,
        &[hinge(0, Some(2), [1.5, 0.0, 1.0], [0.0, 1.0, 0.0])],
        RigidSettings::default()
    )
    .is_ok());
}

/// Jointed bodies that overlap at the joint (links of a chain) are not refused as
/// interpenetrating and get no contact.
#[test]
fn jointed_bodies_may_overlap() {
    let a = cuboid([0.05, 0.05, 0.1], 1000.0, [0.0, 0.0, -0.1]).unwrap();
    let b = cuboid([0.05, 0.05, 0.1], 1000.0, [0.0, 0.0, -0.28]).unwrap();
    assert!(matches!(
        world(vec![a.clone(), b.clone()], &[], RigidSettings::default()),
        Err(RigidError::Interpenetration { .. })
    ));
    let joints = [
        joint(JointKind::Spherical, 0, None, [0.0; 3]),
        joint(JointKind::Fixed, 1, Some(0), [0.0, 0.0, -0.19]),
    ];
    let mut w = world(vec![a, b], &joints, RigidSettings::default()).unwrap();
    let r = w.step().unwrap();
    assert_eq!(r.contacts, 0);
    assert_eq!(r.status, RigidStatus::Converged);
}

/// The joints' checks of `coulomb validate --quick` pass (expected values and tolerances of
/// docs/joints.md).
#[test]
fn validate_joint_checks_pass() {
    let checks = coulomb_granular::rigid::joint_checks::checks(true).unwrap();
    assert_eq!(checks.len(), 7);
    for (section, c) in &checks {
        assert_eq!(section, "Joints");
        eprintln!(
            "{}: expected {} measured {}",
            c.name, c.expected, c.measured
        );
        assert!(c.pass(), "{c:?}");
    }
}

/// The double pendulum: 10 s (10⁴ steps) released at θ = ½: drift < 1e-6 m, energy
/// within 1 % of |E₀|.
#[test]
fn double_pendulum_ten_seconds() {
    let (drift, energy, bad) =
        coulomb_granular::rigid::joint_checks::double_pendulum(10_000).unwrap();
    eprintln!("double pendulum 10 s: drift {drift:.2e} m, |E - E0|/|E0| {energy:.2e}");
    assert_eq!(bad, 0);
    assert!(drift < 1e-6, "{drift}");
    assert!(energy < 0.01, "{energy}");
}

/// A slider on a prismatic joint along a 45° axis slides at g/√2 without turning; on a
/// vertical cylindrical joint a spinning body falls freely and keeps its spin; a welded body
/// stays where it is and its joint carries its weight.
#[test]
fn prismatic_cylindrical_and_fixed_joints_move_as_they_should() {
    let s2 = std::f64::consts::FRAC_1_SQRT_2;
    let body = || cuboid([0.05, 0.05, 0.05], 1000.0, [0.0, 0.0, 1.0]).unwrap();
    let slide = JointDesc {
        axis: Some([s2, 0.0, -s2]),
        limits: Some((-1.0, 1.0)),
        ..joint(JointKind::Prismatic, 0, None, [0.0, 0.0, 1.0])
    };
    let mut w = world(vec![body()], &[slide], RigidSettings::default()).unwrap();
    for _ in 0..200 {
        assert_eq!(w.step().unwrap().status, RigidStatus::Converged);
    }
    let (s, rate) = w.joint_coordinate(0).unwrap();
    let t = w.time();
    assert!((rate - G * s2 * t).abs() < 1e-9 * G * t, "{rate}");
    assert!((s - 0.5 * G * s2 * t * t).abs() < 1e-6, "{s}");
    let v = w.velocities()[0];
    assert!((v[0] + v[2]).abs() < 1e-9 && v[1].abs() < 1e-12, "{v:?}");
    assert!(w.angular_velocities()[0].iter().all(|x| x.abs() < 1e-9));
    // cylindrical, vertical: free fall with the spin kept
    let mut spinning = body();
    spinning.angular_velocity = [0.0, 0.0, 3.0];
    let cyl = JointDesc {
        axis: Some([0.0, 0.0, 1.0]),
        ..joint(JointKind::Cylindrical, 0, None, [0.0, 0.0, 1.0])
    };
    let mut w = world(vec![spinning], &[cyl], RigidSettings::default()).unwrap();
    for _ in 0..100 {
        assert_eq!(w.step().unwrap().status, RigidStatus::Converged);
    }
    let t = w.time();
    assert!(
        (w.velocities()[0][2] + G * t).abs() < 1e-9,
        "{:?}",
        w.velocities()
    );
    assert!((w.angular_velocities()[0][2] - 3.0).abs() < 1e-9);
    assert!(w.joint_drift() < 1e-9);
    // fixed to the world
    let weld = joint(JointKind::Fixed, 0, None, [0.0, 0.0, 1.0]);
    let b = body();
    let weight = b.mass.mass * G;
    let mut w = world(vec![b], &[weld], RigidSettings::default()).unwrap();
    for _ in 0..50 {
        assert_eq!(w.step().unwrap().status, RigidStatus::Converged);
    }
    assert!((w.centres_of_mass()[0][2] - 1.0).abs() < 1e-12);
    let f = w.joint_forces()[0];
    assert!((f[2] - weight).abs() < 1e-9 * weight, "{f:?}");
    assert!(f[3..].iter().all(|x| x.abs() < 1e-9), "{f:?}");
}

/// Newton's cradle, 5 balls 1 mm apart on hinges, e = 1, ball 0 released from 0.5 rad: the
/// last ball leaves with ≥ 95 % of the first ball's speed and the others are (nearly) at rest.
#[test]
fn newtons_cradle_passes_the_speed_on() {
    let c = coulomb_granular::rigid::joint_checks::newtons_cradle(
        0.5,
        1e-3,
        500,
        RigidSettings::default(),
    )
    .unwrap();
    eprintln!("{c:?}");
    assert_eq!(c.not_converged, 0);
    assert!(c.first_speed > 0.6, "{c:?}");
    assert!(c.last_speed >= 0.95 * c.first_speed, "{c:?}");
    assert!(c.others_speed <= 0.05 * c.first_speed, "{c:?}");
    assert!(c.drift < 1e-9, "{c:?}");
}

/// The slider-crank of `coulomb validate`: over 3 turns of the motorised crank the piston
/// follows x(φ) = r cos φ + √(l² − r² sin² φ) and sweeps [l − r, l + r].
#[test]
fn slider_crank_follows_its_kinematics() {
    let sc = coulomb_granular::rigid::joint_checks::slider_crank(3_000).unwrap();
    eprintln!("{sc:?}");
    let (r, l) = coulomb_granular::rigid::joint_checks::CRANK;
    assert_eq!(sc.not_converged, 0);
    assert!(sc.turns > 2.99 && sc.turns < 3.01, "{sc:?}");
    assert!(sc.max_error < 1e-6, "{sc:?}");
    assert!((sc.x_range.0 - (l - r)).abs() < 1e-4, "{sc:?}");
    assert!((sc.x_range.1 - (l + r)).abs() < 1e-4, "{sc:?}");
    assert!(sc.drift < 1e-6, "{sc:?}");
}

/// A plate on a vertical hinge (gravity along the axis) turning at 2 rad/s into its limit at
/// 0.5 rad: with `limit_restitution` = 1 it comes back at −2 rad/s, with 0 it stops there.
#[test]
fn a_limit_with_restitution_rebounds_and_without_stops() {
    for e in [1.0, 0.0] {
        let mut plate = cuboid([0.1, 0.1, 0.02], 1000.0, [0.0, 0.0, 1.0]).unwrap();
        plate.angular_velocity = [0.0, 0.0, 2.0];
        let j = JointDesc {
            limits: Some((-0.5, 0.5)),
            limit_restitution: Some(e),
            ..hinge(0, None, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
        };
        let mut w = world(vec![plate], &[j], RigidSettings::default()).unwrap();
        let mut max_angle: f64 = 0.0;
        // 0.25 s to the limit, then 0.1 s more
        for _ in 0..350 {
            let r = w.step().unwrap();
            assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
            max_angle = max_angle.max(w.joint_coordinate(0).unwrap().0);
        }
        let (angle, rate) = w.joint_coordinate(0).unwrap();
        eprintln!("e = {e}: angle {angle} rate {rate} largest angle {max_angle}");
        assert!(max_angle <= 0.5 + 1e-9, "{max_angle}");
        // the impact comes up to one step's travel (2e-3 rad) early
        assert!(max_angle > 0.5 - 2.0 * 1e-3 - 1e-12, "{max_angle}");
        if e == 1.0 {
            assert!((rate + 2.0).abs() < 1e-8, "{rate}");
            assert!(angle < 0.5 - 0.19, "{angle}");
        } else {
            assert!(rate.abs() < 1e-8, "{rate}");
            assert!((angle - 0.5).abs() < 1e-8, "{angle}");
        }
    }
}

/// `limit_restitution` without limits, or outside [0, 1], is refused naming the field.
#[test]
fn bad_limit_restitution_is_refused() {
    let body = || cuboid([0.05, 0.05, 0.05], 1000.0, [0.0, 0.0, 1.0]).unwrap();
    for (limits, e, words) in [
        (None, 0.5, "give limits"),
        (Some((-0.5, 0.5)), 1.5, "[0, 1]"),
        (Some((-0.5, 0.5)), -0.1, "[0, 1]"),
        (Some((-0.5, 0.5)), f64::NAN, "[0, 1]"),
    ] {
        let j = JointDesc {
            limits,
            limit_restitution: Some(e),
            ..hinge(0, None, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
        };
        let err = world(vec![body()], &[j], RigidSettings::default()).unwrap_err();
        assert_eq!(field_of(err.clone()), (0, "limit_restitution"));
        assert!(err.to_string().contains(words), "{err}");
    }
}

/// A bar hanging from a horizontal hinge (gravity torque up to m g c = 1.96 N m) with a
/// position servo to 0.8 rad (at most 5 N m): it settles there, still, the motor holding the
/// gravity torque m g c sin 0.8; a servo on a prismatic joint settles at its travel too.
#[test]
fn a_position_servo_settles_at_its_target() {
    let (a, c) = (0.02, 0.25);
    let bar = cuboid([a, a, c], 1000.0, [0.0, 0.0, -c]).unwrap();
    let m = bar.mass.mass;
    let j = JointDesc {
        motor: Some(Motor::with_position(0.8, 5.0)),
        ..hinge(0, None, [0.0; 3], [0.0, 1.0, 0.0])
    };
    let mut w = world(vec![bar], &[j], RigidSettings::default()).unwrap();
    let mut trace = Vec::new();
    for k in 0..3000 {
        let r = w.step().unwrap();
        assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
        if k % 500 == 499 {
            trace.push(w.joint_coordinate(0).unwrap());
        }
    }
    eprintln!("servo: {trace:?}");
    let (angle, rate) = w.joint_coordinate(0).unwrap();
    assert!((angle - 0.8).abs() < 1e-6, "{angle}");
    assert!(rate.abs() < 1e-6, "{rate}");
    // the holding torque about the axis is the gravity torque
    let torque = w.joint_forces()[0][4].abs();
    let want = m * G * c * 0.8f64.sin();
    assert!((torque - want).abs() < 1e-4 * want, "{torque} vs {want}");
    // prismatic: a block on a vertical slide servoed to 0.1 m above its start
    let block = cuboid([0.05, 0.05, 0.05], 1000.0, [0.0, 0.0, 1.0]).unwrap();
    let j = JointDesc {
        kind: JointKind::Prismatic,
        motor: Some(Motor {
            gain: Some(20.0),
            ..Motor::with_position(0.1, 50.0)
        }),
        ..hinge(0, None, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
    };
    let mut w = world(vec![block], &[j], RigidSettings::default()).unwrap();
    for _ in 0..2000 {
        assert_eq!(w.step().unwrap().status, RigidStatus::Converged);
    }
    let (s, rate) = w.joint_coordinate(0).unwrap();
    eprintln!("prismatic servo: {s} {rate}");
    assert!((s - 0.1).abs() < 1e-6, "{s}");
    assert!(rate.abs() < 1e-6, "{rate}");
}

/// Joint friction: a plate spinning at 2 rad/s on a vertical hinge (gravity along the axis)
/// with a friction torque of 0.05 N m slows at τ/I, stops at t = ω₀ I/τ and stays; a bar on
/// a horizontal hinge whose friction exceeds the gravity torque stays where it is put.
#[test]
fn joint_friction_brakes_and_holds() {
    let mut plate = cuboid([0.1, 0.1, 0.02], 1000.0, [0.0, 0.0, 1.0]).unwrap();
    plate.angular_velocity = [0.0, 0.0, 2.0];
    let i = plate.mass.mass * 0.02 / 3.0;
    let tau = 0.05;
    let j = JointDesc {
        friction: Some(tau),
        ..hinge(0, None, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
    };
    let mut w = world(vec![plate], &[j], RigidSettings::default()).unwrap();
    for _ in 0..200 {
        assert_eq!(w.step().unwrap().status, RigidStatus::Converged);
    }
    let (_, rate) = w.joint_coordinate(0).unwrap();
    let want = 2.0 - tau / i * w.time();
    eprintln!(
        "friction: rate {rate} vs {want}, stops at {} s",
        2.0 * i / tau
    );
    assert!((rate - want).abs() < 1e-9, "{rate} vs {want}");
    for _ in 0..600 {
        assert_eq!(w.step().unwrap().status, RigidStatus::Converged);
    }
    let (_, rate) = w.joint_coordinate(0).unwrap();
    assert!(rate.abs() < 1e-9, "{rate}");
    // a bar at 0.3 rad on a hinge with friction 3 N m > m g c sin 0.3 = 0.58 N m: it holds
    let (a, c) = (0.02, 0.25);
    let th: f64 = 0.3;
    let mut bar = cuboid([a, a, c], 1000.0, [c * th.sin(), 0.0, -c * th.cos()]).unwrap();
    bar.orientation = [(-th / 2.0).cos(), 0.0, (-th / 2.0).sin(), 0.0];
    let j = JointDesc {
        friction: Some(3.0),
        ..hinge(0, None, [0.0; 3], [0.0, 1.0, 0.0])
    };
    let mut w = world(vec![bar], &[j], RigidSettings::default()).unwrap();
    for _ in 0..500 {
        assert_eq!(w.step().unwrap().status, RigidStatus::Converged);
    }
    // it creeps only at the solver's tolerance (measured: 1.3e-9 rad, 6.7e-9 rad/s)
    let (angle, rate) = w.joint_coordinate(0).unwrap();
    assert!(angle.abs() < 1e-7 && rate.abs() < 1e-7, "{angle} {rate}");
    // bad friction: negative, or on a spherical joint
    let body = || cuboid([0.05, 0.05, 0.05], 1000.0, [0.0, 0.0, 1.0]).unwrap();
    for j in [
        JointDesc {
            friction: Some(-1.0),
            ..hinge(0, None, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
        },
        JointDesc {
            friction: Some(1.0),
            ..joint(JointKind::Spherical, 0, None, [0.0, 0.0, 1.0])
        },
    ] {
        let err = world(vec![body()], &[j], RigidSettings::default()).unwrap_err();
        assert_eq!(field_of(err), (0, "friction"));
    }
}
