//! Rolling resistance (crate::rolling): textbook mechanics of a ball with a rolling-friction
//! cone, the energy of a box run, and μ_r = 0 leaving the step unchanged. Fast (seconds).

use coulomb::solver::Settings;
use coulomb_granular::validation::{incline_rolling_resistance, rolling_deceleration};
use coulomb_granular::{Params, Scene, Simulation};

/// The defaults with every step solved to err ≤ 1e-4 (as `coulomb simulate`).
fn params(mu_r: f64) -> Params {
    Params {
        rolling_friction: mu_r,
        solver: Settings {
            tol: 1e-4,
            ..Settings::default()
        },
        ..Params::default()
    }
}

#[test]
fn ball_rests_on_an_incline_below_the_rolling_threshold() {
    // tan 5° = 0.087 ≤ μ_r = 0.1: stays at rest (without rolling resistance it would roll at
    // 5/7 g sin 5° = 0.61 m/s²)
    let c = incline_rolling_resistance(5.0, 0.5, 1.0, &params(0.1)).unwrap();
    assert_eq!(c.expected, 0.0);
    assert!(c.pass(), "{c:?}");
}

#[test]
fn ball_rolls_down_an_incline_with_the_reduced_acceleration() {
    // tan 20° = 0.36 > μ_r = 0.1: a = 5/7 g (sin θ − μ_r cos θ)
    let c = incline_rolling_resistance(20.0, 0.5, 1.0, &params(0.1)).unwrap();
    let th = 20f64.to_radians();
    let a = 5.0 / 7.0 * 9.81 * (th.sin() - 0.1 * th.cos());
    assert!((c.expected - a).abs() < 1e-12);
    assert!(c.pass(), "{c:?}");
}

#[test]
fn ball_decelerates_on_a_flat_floor() {
    // a = −5/7 μ_r g = −0.35 m/s² for μ_r = 0.05; stops after 2.85 s from 1 m/s
    let c = rolling_deceleration(1.0, 1.0, &params(0.05)).unwrap();
    assert!((c.expected + 5.0 / 7.0 * 0.05 * 9.81).abs() < 1e-12);
    assert!(c.pass(), "{c:?}");
}

#[test]
fn without_rolling_resistance_the_ball_keeps_rolling() {
    let c = rolling_deceleration(1.0, 1.0, &params(0.0)).unwrap();
    assert_eq!(c.expected, 0.0);
    assert!(c.pass(), "{c:?}");
}

#[test]
fn energy_never_grows_with_rolling_resistance() {
    // (e = 1, μ > 0 is left out: Coulomb friction alone can gain energy there, docs/granular.md)
    for (e, mu) in [(1.0, 0.0), (0.2, 0.3), (0.5, 0.8)] {
        let p = Params {
            restitution: e,
            mu,
            ..params(0.1)
        };
        let mut sim = Simulation::new(Scene::Box.build(60, 1), p).unwrap();
        let e0 = sim.world.kinetic_energy() + sim.world.potential_energy();
        let mut prev = e0;
        let mut rolled = 0.0f64;
        for _ in 0..100 {
            let s = sim.step().unwrap();
            assert!(s.converged, "e = {e}: step {} {s:?}", s.step);
            assert!(s.error <= 1e-4);
            let en = s.kinetic_energy + s.potential_energy;
            // E_{k+1} − E_k − W_p ≤ round-off of a step solved to err ≤ 1e-4
            assert!(
                en - prev - s.projection_work <= 1e-4 * e0,
                "e = {e}, step {}: E {prev} → {en}, W_p {}",
                s.step,
                s.projection_work
            );
            prev = en;
            let largest = sim
                .rolling
                .impulses
                .iter()
                .map(|y| (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt());
            rolled = rolled.max(largest.fold(0.0, f64::max));
        }
        assert!(rolled > 0.0, "the rolling cone was never used");
    }
}

#[test]
fn rolling_impulses_stay_in_their_cone() {
    let mut sim = Simulation::new(Scene::Box.build(50, 2), params(0.2)).unwrap();
    for _ in 0..60 {
        let s = sim.step().unwrap();
        assert!(s.converged);
        for (c, y) in sim.contacts.iter().zip(&sim.rolling.impulses) {
            assert!(
                (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt()
                    <= 0.2 * c.impulse[0].max(0.0) * (1.0 + 1e-9) + 1e-15
            );
        }
    }
}

#[test]
fn zero_rolling_friction_is_the_plain_step() {
    let a = Simulation::new(Scene::Box.build(60, 3), params(0.0));
    let mut a = a.unwrap();
    let plain = Params {
        solver: params(0.0).solver,
        ..Params::default()
    };
    let mut b = Simulation::new(Scene::Box.build(60, 3), plain).unwrap();
    for _ in 0..40 {
        a.step().unwrap();
        b.step().unwrap();
    }
    assert!(a.world == b.world, "μ_r = 0 changed the step");
    assert!(a.rolling.impulses.is_empty());
    assert!(Simulation::new(Scene::Box.build(10, 1), params(-1.0)).is_err());
    assert!(Simulation::new(Scene::Box.build(10, 1), params(f64::NAN)).is_err());
}

/// The sweep's constants (`rolling::Tuning`, used by `examples/rolling_probe.rs`) change the
/// path, not the law: from the same state, plain sweeps (ω = 1, blocks solved to rounding)
/// converge on every step like the default sweep, to velocities that differ by no more than
/// the tolerance allows.
#[test]
fn the_sweep_tuning_changes_the_path_not_the_solution() {
    let d = coulomb_granular::rolling::Tuning::default();
    let plain = coulomb_granular::rolling::Tuning {
        relaxation: 1.0,
        local: 50,
        ..d
    };
    let mut sim = Simulation::new(Scene::Box.build(40, 4), params(0.1)).unwrap();
    let mut compared = 0;
    for _ in 0..40 {
        let mut other = sim.clone();
        other.rolling.tuning = plain;
        let a = sim.step().unwrap();
        let b = other.step().unwrap();
        assert!(
            a.converged && b.converged,
            "step {}: {:.2e} {:.2e}",
            a.step,
            a.error,
            b.error
        );
        assert!(a.error <= 1e-4 && b.error <= 1e-4);
        if a.contacts == 0 {
            continue;
        }
        compared += 1;
        // both solve the same step problem to err ≤ 1e-4 relative to the step's scale, of
        // which g h (the free fall of one step) is a part
        let scale = sim
            .max_speed()
            .max(other.max_speed())
            .max(9.81 * sim.params.h);
        for (p, q) in sim.world.bodies.iter().zip(&other.world.bodies) {
            let dv = (p.velocity - q.velocity).norm();
            assert!(dv <= 1e-2 * scale, "step {}: |Δv| = {dv:.2e}", a.step);
        }
    }
    assert!(compared > 10);
}
