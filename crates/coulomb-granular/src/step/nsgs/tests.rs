//! Tests of the Gauss–Seidel sweep ([`super`]), several through whole simulations.

use super::*;
use crate::contact::{detect, Activation};
use crate::math::Vec3;
use crate::world::{Obstacle, Shape, Sphere};
use crate::{Params, Scene, Simulation, StepMethod};
use coulomb::problem::Problem;
use coulomb::solver::{InnerKind, OuterKind, Settings};

/// A heap of 150 beads after `steps` NSGS steps, and the problem of its next step.
fn heap(steps: usize) -> (World, Vec<Contact>, StepData) {
    let params = Params {
        method: StepMethod::Nsgs(NsgsSettings::default()),
        ..Params::default()
    };
    let mut sim = Simulation::new(Scene::Box.build(150, 3), params.clone()).unwrap();
    for _ in 0..steps {
        let s = sim.step().unwrap();
        assert!(s.converged, "{s:?}");
    }
    let delta = sim.activation_threshold();
    let contacts =
        crate::contact::detect_with(&sim.world, sim.time, params.h, &params.activation, delta);
    let data = StepData {
        h: params.h,
        t_end: sim.time + params.h,
        restitution: params.restitution,
        mu: params.mu,
        close_gaps: params.activation.close_gaps,
    };
    (sim.world, contacts, data)
}

/// Beads on a floor, touching their lattice neighbours (side × side), moving: enough
/// contacts per colour for the parallel path.
fn carpet(side: usize) -> (World, Vec<Contact>, StepData) {
    let mut w = World::new();
    w.obstacles.push(Obstacle::fixed(
        "ground",
        Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Z,
        },
    ));
    let r = 0.05;
    for i in 0..side * side {
        let (x, y) = ((i % side) as f64, (i / side) as f64);
        let mut b = Sphere::new(Vec3::new(2.0 * r * x, 2.0 * r * y, r), r, 1.0);
        b.velocity = Vec3::new(0.1 * (x * 0.7).sin(), -0.2 * (y * 1.3).cos(), -0.3);
        b.angular_velocity = Vec3::new(0.5 * (x * 0.3).cos(), 0.0, 0.2);
        w.bodies.push(b);
    }
    let contacts = detect(&w, 0.0, 0.02, &Activation::accurate());
    let data = StepData {
        h: 0.02,
        t_end: 0.02,
        restitution: 0.2,
        mu: 0.3,
        close_gaps: true,
    };
    (w, contacts, data)
}

pub fn rows_are_the_assembled_problem() {
    let (world, contacts, data) = heap(30);
    assert!(contacts.len() > 100);
    let p = StepProblem::new(&world, &contacts, &data).unwrap();
    let g = p.to_global().unwrap();
    let a = crate::assembly::assemble(&world, &contacts, &data).unwrap();
    assert_eq!(g, a, "body-block form and assembled problem differ");
    // the sweep's fast u agrees with Hᵀ v + w
    let v = world.velocities();
    let u = a.velocity(&v);
    for (i, row) in p.rows.iter().enumerate() {
        let va: [f64; 6] = std::array::from_fn(|d| v[6 * row.a + d]);
        let vb = row
            .b
            .map(|j| -> [f64; 6] { std::array::from_fn(|d| v[6 * j + d]) });
        let fast = row.velocity_fast(&va, vb.as_ref());
        for k in 0..3 {
            assert!((fast[k] - u[3 * i + k]).abs() <= 1e-12 * (1.0 + u[3 * i + k].abs()));
        }
    }
}

/// NSGS reports the library's error measure on the stored global problem, and the
/// library's own solver on the same problem agrees.
pub fn error_agrees_with_the_library_on_a_heap() {
    let (world, contacts, data) = heap(30);
    let p = StepProblem::new(&world, &contacts, &data).unwrap();
    let g = p.to_global().unwrap();
    let tol = 1e-5;
    let settings = NsgsSettings {
        tol,
        ..NsgsSettings::default()
    };
    let sol = solve(&p, &vec![0.0; 3 * p.contacts()], &settings, true);
    assert_eq!(sol.status, NsgsStatus::Converged, "{:?}", sol.error);
    assert!(sol.sweeps > 1);
    // the library's measure on (M, H, f, w) as stored, from the returned r and v
    let u = g.velocity(&sol.v);
    let minv_f: Vec<f64> = g.f.iter().zip(&g.m.values).map(|(f, m)| f / m).collect();
    let q = g.velocity(&minv_f);
    let lib = law::error_measure(3, &g.mu, &sol.r, &u, law::norm(&q));
    assert!(lib.error <= tol, "{lib:?}");
    assert!(
        (lib.error - sol.error).abs() <= 1e-9 * lib.error,
        "{lib:?} vs {}",
        sol.error
    );
    assert!(g.balance_residual(&sol.v, &sol.r) <= 1e-12);
    // the reference evaluation agrees too
    let (e, _, bal, v) = evaluate(&p, &sol.r);
    assert!((e - sol.error).abs() <= 1e-9 * e && bal <= 1e-12);
    assert!(v
        .iter()
        .zip(&sol.v)
        .all(|(a, b)| (a - b).abs() <= 1e-12 * (1.0 + a.abs())));
    // the library's fused Gauss–Seidel on the same problem: its reported error is the
    // one NSGS computes for its r
    let s = Settings {
        tol,
        ..Settings::method(InnerKind::Pgs, OuterKind::Fused)
    };
    let lsol = coulomb::solver::solve(&Problem::Global(g), &s).unwrap();
    assert!(lsol.converged(), "{:?}", lsol.status);
    let (e, _, _, _) = evaluate(&p, &lsol.r);
    assert!(
        (e - lsol.error).abs() <= 1e-6 * lsol.error.max(1e-12),
        "{e} vs {}",
        lsol.error
    );
    assert!(e <= tol);
}

pub fn colouring_is_valid_and_checked() {
    for (world, contacts, data) in [heap(30), carpet(30)] {
        let p = StepProblem::new(&world, &contacts, &data).unwrap();
        let c = Colouring::greedy(&p.rows, world.bodies.len());
        assert!(c.is_valid(&p.rows, world.bodies.len()));
        assert!(c.colours() >= 2 && c.colours() <= 30, "{}", c.colours());
        // two contacts on one sphere in one colour: rejected
        let mut bad = c.clone();
        let i = p.rows.iter().position(|r| r.b.is_some()).unwrap();
        let j = p
            .rows
            .iter()
            .position(|r| r.a == p.rows[i].a && !std::ptr::eq(r, &p.rows[i]));
        if let Some(j) = j {
            bad.order = (0..p.contacts()).filter(|&k| k != i && k != j).collect();
            bad.order.insert(0, i);
            bad.order.insert(1, j);
            bad.starts = vec![0, 2, p.contacts()];
            assert!(!bad.is_valid(&p.rows, world.bodies.len()));
        }
        // not a permutation
        let mut dup = c.clone();
        dup.order[0] = dup.order[1];
        assert!(!dup.is_valid(&p.rows, world.bodies.len()));
    }
}

pub fn colouring_past_64_colours_on_one_sphere() {
    // sphere 0 touches spheres 1..=70 (70 colours), and a chain 71–72–73 on the side
    let mut pairs: Vec<(usize, Option<usize>)> = (1..=70).map(|j| (0, Some(j))).collect();
    pairs.extend([(71, Some(72)), (72, Some(73)), (0, None), (5, Some(6))]);
    let c = Colouring::greedy_pairs(pairs.len(), 74, |i| pairs[i]);
    assert_eq!(c.colours(), 71);
    let mut order = c.order.clone();
    order.sort_unstable();
    assert_eq!(order, (0..pairs.len()).collect::<Vec<_>>());
    for k in 0..c.colours() {
        let mut seen = std::collections::HashSet::new();
        for &i in &c.order[c.starts[k]..c.starts[k + 1]] {
            let (a, b) = pairs[i];
            assert!(seen.insert(a), "sphere {a} twice in colour {k}");
            if let Some(b) = b {
                assert!(seen.insert(b), "sphere {b} twice in colour {k}");
            }
        }
    }
    // (0, None) comes after the 70 contacts of sphere 0: colour 70; the chain reuses 0, 1
    let colour_of =
        |i: usize| (0..c.colours()).find(|&k| c.order[c.starts[k]..c.starts[k + 1]].contains(&i));
    assert_eq!(colour_of(72), Some(70));
    assert_eq!(colour_of(70), Some(0));
    assert_eq!(colour_of(71), Some(1));
}

pub fn same_numbers_for_one_and_two_threads() {
    let (world, contacts, data) = carpet(40);
    let p = StepProblem::new(&world, &contacts, &data).unwrap();
    let c = Colouring::greedy(&p.rows, world.bodies.len());
    // the parallel path is taken
    assert!((0..c.colours()).any(|k| c.starts[k + 1] - c.starts[k] >= PARALLEL_MIN));
    let settings = NsgsSettings {
        tol: 1e-8,
        max_sweeps: 60,
        ..NsgsSettings::default()
    };
    let r0 = vec![0.0; 3 * p.contacts()];
    let run = |threads: usize, parallel: bool| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| solve(&p, &r0, &settings, parallel))
    };
    let one = run(1, true);
    let two = run(2, true);
    let seq = run(2, false);
    assert!(one.sweeps > 1);
    assert_eq!(one, two);
    assert_eq!(one, seq);
}

pub fn simulation_is_deterministic_across_thread_counts() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            // serial_below 0: the 200-bead step really runs on the pool's threads
            let params = Params {
                method: StepMethod::Nsgs(NsgsSettings {
                    serial_below: 0,
                    ..NsgsSettings::default()
                }),
                ..Params::default()
            };
            let mut sim = Simulation::new(Scene::Box.build(200, 5), params).unwrap();
            for _ in 0..15 {
                sim.step().unwrap();
            }
            sim.world
        })
    };
    assert_eq!(run(1), run(2));
}

pub fn a_step_gauss_seidel_leaves_above_tol_is_finished_by_the_library() {
    // two sweeps cannot reach 1e-4 on a falling heap: the library's solver finishes
    let params = Params {
        method: StepMethod::Nsgs(NsgsSettings {
            max_sweeps: 2,
            ..NsgsSettings::default()
        }),
        ..Params::default()
    };
    let mut sim = Simulation::new(Scene::Box.build(60, 2), params).unwrap();
    let mut finished = 0;
    for _ in 0..30 {
        let s = sim.step().unwrap();
        assert!(s.converged, "step {} {} err {}", s.step, s.status, s.error);
        assert!(s.error <= 1e-4);
        if s.subproblems > 1 {
            finished += 1;
            assert!(s.inner_iterations > 2);
        }
    }
    assert!(finished > 0);
}

pub fn without_the_library_finish_a_step_depends_on_gauss_seidel_alone() {
    // two sweeps leave steps above 1e-4; without the finish those steps stand as
    // Gauss–Seidel left them, whatever the library's settings say
    let run = |solver: coulomb::Settings| {
        let params = Params {
            method: StepMethod::Nsgs(NsgsSettings {
                max_sweeps: 2,
                library_finish: false,
                ..NsgsSettings::default()
            }),
            solver,
            ..Params::default()
        };
        let mut sim = Simulation::new(Scene::Box.build(60, 2), params).unwrap();
        let mut unconverged = 0;
        for _ in 0..30 {
            let s = sim.step().unwrap();
            assert_eq!(s.subproblems, 1, "step {} {}", s.step, s.status);
            assert!(s.inner_iterations <= 2);
            if !s.converged {
                unconverged += 1;
                assert!(s.error > 1e-4 && s.error.is_finite(), "err {}", s.error);
            }
        }
        assert!(unconverged > 0);
        sim.world
    };
    let loose = coulomb::Settings {
        max_outer: 1,
        tol: 1e-2,
        ..coulomb::Settings::default()
    };
    assert_eq!(run(coulomb::Settings::default()), run(loose));
}

pub fn caps_give_typed_statuses() {
    let (world, contacts, data) = heap(30);
    let p = StepProblem::new(&world, &contacts, &data).unwrap();
    let r0 = vec![0.0; 3 * p.contacts()];
    let s = NsgsSettings {
        tol: 1e-14,
        max_sweeps: 3,
        ..NsgsSettings::default()
    };
    let sol = solve(&p, &r0, &s, true);
    assert_eq!(sol.status, NsgsStatus::MaxIterations);
    assert_eq!(sol.sweeps, 3);
    assert!(sol.error > 1e-14 && sol.error.is_finite());
    let s = NsgsSettings {
        tol: 1e-14,
        max_sweeps: usize::MAX,
        time_limit: Some(Duration::from_micros(1)),
        ..NsgsSettings::default()
    };
    let sol = solve(&p, &r0, &s, true);
    assert_eq!(sol.status, NsgsStatus::TimeLimit);
    assert!(sol.error > 1e-14, "{}", sol.error);
    // a non-finite warm start is replaced by 0, not propagated
    let mut bad = r0.clone();
    bad[0] = f64::NAN;
    let sol = solve(&p, &bad, &NsgsSettings::default(), true);
    assert_eq!(sol.status, NsgsStatus::Converged);
    // inconsistent per-sphere data: refused with a typed status, never indexed
    let mut broken = p.clone();
    broken.f.pop();
    let sol = solve(&broken, &r0, &NsgsSettings::default(), true);
    assert_eq!(sol.status, NsgsStatus::NumericalError);
    assert!(sol.error.is_nan());
}
