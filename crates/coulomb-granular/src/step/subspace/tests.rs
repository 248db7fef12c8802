//! Tests of [`super`] driven through the Gauss–Seidel solve of [`crate::nsgs`] (a
//! child module: the correction itself does not depend on the solve that calls it).

use crate::assembly::StepData;
use crate::contact::{detect, Activation};
use crate::math::Vec3;
use crate::nsgs::{evaluate, solve, NsgsSettings, NsgsStatus, StepProblem};
use crate::world::{Obstacle, Shape, Sphere, World};

/// A `nx × ny × layers` simple-cubic stack of touching spheres at rest on a floor, and
/// its step problem (h = 0.02, μ = 0.5, e = 0): gravity's load goes straight down
/// through every column.
fn stack(nx: usize, ny: usize, layers: usize) -> StepProblem {
    let mut w = World::new();
    w.obstacles.push(Obstacle::fixed(
        "ground",
        Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Z,
        },
    ));
    let r = 0.05;
    for k in 0..layers {
        for j in 0..ny {
            for i in 0..nx {
                let p = Vec3::new(
                    2.0 * r * i as f64,
                    2.0 * r * j as f64,
                    r + 2.0 * r * k as f64,
                );
                w.bodies.push(Sphere::new(p, r, 1.0));
            }
        }
    }
    let contacts = detect(&w, 0.0, 0.02, &Activation::accurate());
    let data = StepData {
        h: 0.02,
        t_end: 0.02,
        restitution: 0.0,
        mu: 0.5,
        close_gaps: true,
    };
    StepProblem::new(&w, &contacts, &data).unwrap()
}

/// Sweeps of plain Gauss–Seidel and of Gauss–Seidel with subspace minimization every
/// 5 sweeps, cold, to `tol`; both verdicts checked on the stored problem.
fn compare(p: &StepProblem, tol: f64) -> (usize, usize, usize) {
    let r0 = vec![0.0; 3 * p.contacts()];
    let plain = NsgsSettings {
        tol,
        time_limit: None,
        ..NsgsSettings::default()
    };
    let sm = NsgsSettings {
        subspace_every: 5,
        ..plain
    };
    let a = solve(p, &r0, &plain, false);
    let b = solve(p, &r0, &sm, false);
    for s in [&a, &b] {
        assert_eq!(s.status, NsgsStatus::Converged, "{s:?}");
        let (err, _, balance, _) = evaluate(p, &s.r);
        assert!(err <= tol && balance <= tol, "err {err} balance {balance}");
    }
    eprintln!(
        "{} contacts: plain {} sweeps, subspace {} sweeps ({} corrections kept)",
        p.contacts(),
        a.sweeps,
        b.sweeps,
        b.subspace
    );
    (a.sweeps, b.sweeps, b.subspace)
}

#[test]
fn a_column_of_spheres_converges_in_far_fewer_sweeps() {
    let p = stack(1, 1, 16);
    assert_eq!(p.contacts(), 16);
    let (plain, sm, kept) = compare(&p, 1e-8);
    assert!(kept >= 1, "no correction kept");
    assert!(3 * sm <= plain, "plain {plain} sweeps, subspace {sm}");
}

#[test]
fn a_six_layer_stack_converges_in_far_fewer_sweeps() {
    let p = stack(4, 4, 6);
    assert!(p.contacts() > 100, "{}", p.contacts());
    let (plain, sm, kept) = compare(&p, 1e-6);
    assert!(kept >= 1, "no correction kept");
    assert!(3 * sm <= plain, "plain {plain} sweeps, subspace {sm}");
}

#[test]
fn same_bits_on_one_and_two_threads() {
    let p = stack(4, 4, 6);
    let s = NsgsSettings {
        tol: 1e-6,
        subspace_every: 5,
        ..NsgsSettings::default()
    };
    let r0 = vec![0.0; 3 * p.contacts()];
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| solve(&p, &r0, &s, true));
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| solve(&p, &r0, &s, true));
    assert_eq!(one.r, two.r);
    assert_eq!(one.sweeps, two.sweeps);
}
