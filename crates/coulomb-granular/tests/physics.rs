//! Physics checks of the Moreau–Jean scheme (2.5)–(2.7) with the coulomb solver: rest,
//! Newton's impact law by Moreau's rule, Coulomb's law on an incline, energy decay.

use coulomb::solver::Settings;
use coulomb_granular::{Obstacle, Params, Scene, Shape, Simulation, Sphere, Vec3, World};

fn ground_world(gravity: Vec3) -> World {
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

fn params(h: f64, mu: f64, restitution: f64) -> Params {
    Params {
        h,
        mu,
        restitution,
        solver: Settings {
            tol: 1e-10,
            ..Settings::default()
        },
        ..Params::default()
    }
}

#[test]
fn sphere_resting_on_the_ground_stays_put() {
    let mut w = ground_world(Vec3::new(0.0, 0.0, -9.81));
    let start = Vec3::new(0.3, -0.2, 0.05);
    w.bodies.push(Sphere::new(start, 0.05, 1.3));
    let mut sim = Simulation::new(w, params(0.02, 0.3, 0.2)).unwrap();
    for _ in 0..1000 {
        let s = sim.step().unwrap();
        assert_eq!(s.contacts, 1);
        assert!(s.converged, "{s:?}");
        assert!(
            s.max_penetration <= 1e-9,
            "penetration {}",
            s.max_penetration
        );
    }
    let b = &sim.world.bodies[0];
    assert!(
        (b.position - start).norm() < 1e-9,
        "drifted to {:?}",
        b.position
    );
    assert!(b.velocity.norm() < 1e-9);
    // the impulse balances gravity: r_N = m g h
    let r = sim.contacts[0].impulse;
    assert!((r[0] - 1.3 * 9.81 * 0.02).abs() < 1e-8, "r = {r:?}");
}

#[test]
fn dropped_sphere_rebounds_to_e_squared_of_the_height() {
    let (h0, e, dt, radius) = (1.0, 0.2, 0.0005, 0.05);
    let mut w = ground_world(Vec3::new(0.0, 0.0, -9.81));
    w.bodies
        .push(Sphere::new(Vec3::new(0.0, 0.0, radius + h0), radius, 1.0));
    let mut sim = Simulation::new(w, params(dt, 0.3, e)).unwrap();
    let mut impacted = false;
    let mut apex: f64 = 0.0;
    for _ in 0..3000 {
        let s = sim.step().unwrap();
        let b = &sim.world.bodies[0];
        if s.contacts > 0 && !impacted {
            impacted = true;
        }
        if impacted {
            apex = apex.max(b.position.z - radius);
            if b.velocity.z < 0.0 && apex > 0.0 {
                break;
            }
        }
    }
    assert!(impacted);
    // the impact is resolved within one step: the bounce point is off by at most h |v|
    let expected = e * e * h0;
    assert!(
        (apex - expected).abs() < 0.05 * expected,
        "rebound apex {apex} vs e² h0 = {expected}"
    );
}

/// Gravity tilted by α over a horizontal ground is the incline of angle α.
fn incline(alpha: f64, mu: f64, steps: usize) -> (f64, f64) {
    let g = 9.81;
    let mut w = ground_world(Vec3::new(g * alpha.sin(), 0.0, -g * alpha.cos()));
    let mut b = Sphere::new(Vec3::new(0.0, 0.0, 0.05), 0.05, 2.0);
    b.rotation_locked = true;
    w.bodies.push(b);
    let dt = 0.01;
    let mut sim = Simulation::new(w, params(dt, mu, 0.0)).unwrap();
    for _ in 0..steps {
        let s = sim.step().unwrap();
        assert!(s.converged, "{s:?}");
    }
    let b = &sim.world.bodies[0];
    assert!(b.angular_velocity.norm() == 0.0);
    assert!((b.position.z - 0.05).abs() < 1e-6, "z = {}", b.position.z);
    (b.velocity.x / (steps as f64 * dt), b.velocity.y.abs())
}

#[test]
fn sphere_on_an_incline_sticks_below_the_friction_angle() {
    let alpha = 20f64.to_radians();
    assert!(alpha.tan() < 0.5);
    let (a, side) = incline(alpha, 0.5, 200);
    assert!(a.abs() < 1e-7, "acceleration {a} while sticking");
    assert!(side < 1e-9);
}

#[test]
fn sphere_on_an_incline_slides_with_g_sin_minus_mu_cos() {
    for (deg, mu) in [(30.0f64, 0.3), (45.0, 0.5), (60.0, 0.1)] {
        let alpha = deg.to_radians();
        assert!(alpha.tan() > mu);
        let (a, side) = incline(alpha, mu, 200);
        let expected = 9.81 * (alpha.sin() - mu * alpha.cos());
        assert!(
            (a - expected).abs() < 1e-6 * expected.max(1.0),
            "α = {deg}°, μ = {mu}: a = {a}, expected {expected}"
        );
        assert!(side < 1e-9);
    }
}

/// The largest one-step increase of kinetic + potential energy and the final energy, for the
/// box scene with 30 beads.
fn box_energy(theta: f64) -> (f64, f64, f64) {
    let world = Scene::Box.build(30, 5);
    let p = Params {
        theta,
        ..params(0.01, 0.3, 0.2)
    };
    let mut sim = Simulation::new(world, p).unwrap();
    let e0 = sim.world.kinetic_energy() + sim.world.potential_energy();
    let scale = e0.abs().max(1.0);
    let mut prev = e0;
    let mut worst: f64 = 0.0;
    for _ in 0..200 {
        let s = sim.step().unwrap();
        let e = s.kinetic_energy + s.potential_energy;
        worst = worst.max(e - prev);
        prev = e;
    }
    assert!(prev < e0 - 0.01 * scale, "no dissipation: {prev} vs {e0}");
    (worst, scale, prev)
}

#[test]
fn energy_never_increases_in_a_closed_box_implicit_positions() {
    // θ = 1: the energy balance is r·u_{k+1} − ½‖v_{k+1} − v_k‖²_M − ½ h² ‖g‖²_M ≤ 0 up
    // to the solver's tolerance
    let (worst, scale, _) = box_energy(1.0);
    assert!(
        worst <= 1e-7 * scale,
        "energy increased by {worst} (scale {scale})"
    );
}

#[test]
fn energy_never_increases_in_a_closed_box_midpoint_positions() {
    // θ = 1/2 (default): free flight conserves the energy exactly; contacts separating at
    // t_k while still active may do work of order h² per step
    let (worst, scale, _) = box_energy(0.5);
    assert!(
        worst <= 1e-4 * scale,
        "energy increased by {worst} (scale {scale})"
    );
}
