//! Tests of the rigid step ([`super`]): whole worlds stepped.

use super::*;
use crate::validation::rigid::{cuboid, floor, one_material};

fn world(bodies: Vec<RigidBodyDesc>) -> Result<RigidWorld, RigidError> {
    RigidWorld::new(
        bodies,
        vec![floor()],
        one_material(0.5),
        RigidSettings::default(),
    )
}

pub fn refuses_bad_quaternions_without_normalizing() {
    let mut b = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 0.1]).unwrap();
    b.orientation = [1.0, 1e-4, 0.0, 0.0]; // |q| − 1 = 5e-9
    let e = world(vec![b.clone()]).unwrap_err();
    assert!(
        matches!(e, RigidError::Quaternion { ref what, .. } if what == "body 0"),
        "{e}"
    );
    b.orientation = [f64::NAN, 0.0, 0.0, 0.0];
    assert!(matches!(
        world(vec![b]).unwrap_err(),
        RigidError::Quaternion { .. }
    ));
}

pub fn refuses_bad_mass_state_and_material() {
    let good = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 0.1]).unwrap();
    let mut b = good.clone();
    b.mass.mass = 0.0;
    assert!(matches!(
        world(vec![b]).unwrap_err(),
        RigidError::Mass { .. }
    ));
    let mut b = good.clone();
    b.mass.inertia[0][0] = -1.0;
    assert!(matches!(
        world(vec![b]).unwrap_err(),
        RigidError::Mass { .. }
    ));
    let mut b = good.clone();
    b.velocity[1] = f64::INFINITY;
    assert!(matches!(
        world(vec![b]).unwrap_err(),
        RigidError::NonFinite {
            field: "velocity",
            ..
        }
    ));
    let mut b = good.clone();
    b.material = 3;
    assert!(matches!(
        world(vec![b]).unwrap_err(),
        RigidError::Material { material: 3, .. }
    ));
    let s = parry3d_f64::shape::SharedShape::cuboid(0.0, 0.1, 0.1);
    assert!(MassPropertiesCheck::zero_volume(&s));
}

struct MassPropertiesCheck;
impl MassPropertiesCheck {
    fn zero_volume(s: &SharedShape) -> bool {
        matches!(
            crate::bodies::rigid::MassProperties::from_shape(s, 1000.0),
            Err(RigidError::Mass { .. })
        )
    }
}

pub fn refuses_interpenetrating_bodies_with_count_and_depth() {
    let a = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 0.1]).unwrap();
    let b = cuboid([0.1; 3], 1000.0, [0.15, 0.0, 0.1]).unwrap();
    match world(vec![a.clone(), b]).unwrap_err() {
        RigidError::Interpenetration {
            count, depth, a, b, ..
        } => {
            assert!(count >= 1);
            assert!((depth - 0.05).abs() < 1e-9, "{depth}");
            assert_eq!((a, b), (0, Partner::Body(1)));
        }
        e => panic!("{e}"),
    }
    // sunk into the floor by 1 cm
    let c = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 0.09]).unwrap();
    match world(vec![c]).unwrap_err() {
        RigidError::Interpenetration { depth, b, .. } => {
            assert!((depth - 0.01).abs() < 1e-9, "{depth}");
            assert_eq!(b, Partner::Obstacle(0, 0));
        }
        e => panic!("{e}"),
    }
    // touching is fine
    assert!(world(vec![a]).is_ok());
}

/// Bits of every body's state (x, q, v, Ω) and of the last contacts' impulses.
fn state_bits(w: &RigidWorld) -> Vec<u64> {
    let mut out = Vec::new();
    for b in &w.bodies {
        let q = b.q;
        for x in [b.x, b.v, b.omega]
            .iter()
            .flat_map(|v| v.to_array())
            .chain([q.w, q.x, q.y, q.z])
        {
            out.push(x.to_bits());
        }
    }
    for c in w.contacts() {
        out.extend(c.impulse.iter().map(|x| x.to_bits()));
    }
    out
}

pub fn set_positions_moves_the_shape_frames_and_same_positions_keep_the_bits() {
    // a tilted cuboid whose centre of mass is off its shape frame's origin, resting on
    // a second cuboid, above the floor; a fixed cuboid aside
    let mut a = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 0.1]).unwrap();
    a.mass.local_com = [0.01, -0.02, 0.0];
    let mut b = cuboid([0.05, 0.1, 0.05], 800.0, [0.0, 0.0, 0.25]).unwrap();
    let (c, s) = (0.3_f64.cos(), 0.3_f64.sin());
    b.orientation = [c, 0.0, 0.0, s];
    let mut f = cuboid([0.1; 3], 1000.0, [1.0, 0.0, 0.1]).unwrap();
    f.fixed = true;
    let started = || {
        let mut w = world(vec![a.clone(), b.clone(), f.clone()]).unwrap();
        for _ in 0..5 {
            w.step().unwrap();
        }
        w
    };
    let mut w = started();
    // the same positions: nothing changes, the next steps give the same bits
    let mut same = started();
    assert_eq!(state_bits(&same), state_bits(&w));
    same.set_positions(&w.positions()).unwrap();
    assert_eq!(state_bits(&same), state_bits(&w));
    for _ in 0..3 {
        w.step().unwrap();
        same.step().unwrap();
    }
    assert_eq!(state_bits(&same), state_bits(&w));
    assert!(!w.detector.pairs_of(1).is_empty());
    // moved: the origins read back, the orientations and velocities are kept
    let (q0, v0) = (w.orientations(), w.velocities());
    let mut x = w.positions();
    x[1][0] += 0.5;
    x[1][2] += 0.25;
    w.set_positions(&x).unwrap();
    for (got, want) in w.positions().iter().zip(&x) {
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-15, "{got:?} {want:?}");
        }
    }
    assert_eq!(w.orientations(), q0);
    assert_eq!(w.velocities(), v0);
    // the centre of mass follows the frame: x_com − origin = R_shape · local_com
    let com = w.centres_of_mass();
    let off = w.bodies[0].shape_rotation() * v3([0.01, -0.02, 0.0]);
    for k in 0..3 {
        assert!((com[0][k] - x[0][k] - off.to_array()[k]).abs() < 1e-15);
    }
    // the moved body's pair caches are gone; it now falls freely
    assert!(w.detector.pairs_of(1).is_empty());
    let z = w.positions()[1][2];
    w.step().unwrap();
    assert!(w.positions()[1][2] < z);
    // refusals leave the world as it was
    let before = state_bits(&w);
    let mut bad = w.positions();
    bad[0][1] = f64::NAN;
    let e = w.set_positions(&bad).unwrap_err();
    assert!(e.contains("body 0") && e.contains("non-finite"), "{e}");
    let e = w.set_positions(&bad[..2]).unwrap_err();
    assert!(e.contains("expected 3 positions"), "{e}");
    let mut moved_fixed = w.positions();
    moved_fixed[2][0] += 1.0;
    let e = w.set_positions(&moved_fixed).unwrap_err();
    assert!(e.contains("body 2 is fixed"), "{e}");
    assert_eq!(state_bits(&w), before);
}

pub fn the_solver_settings_and_keep_problem_can_be_changed() {
    let b = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 0.1]).unwrap();
    let mut other = world(vec![b.clone()]).unwrap();
    let mut w = world(vec![b]).unwrap();
    w.step().unwrap();
    other.step().unwrap();
    assert!(w.last_problem().is_some());
    w.set_keep_problem(false);
    assert!(!w.settings().keep_problem && w.last_problem().is_none());
    w.step().unwrap();
    assert!(w.last_problem().is_none());
    // the step does not depend on keeping its problem
    other.step().unwrap();
    assert!(other.last_problem().is_some());
    assert_eq!(state_bits(&other), state_bits(&w));
    let solver = coulomb::solver::Settings {
        max_outer: 7,
        ..Default::default()
    };
    w.set_solver(solver.clone());
    assert_eq!(w.settings().solver.max_outer, 7);
}

pub fn free_fall_is_exact_and_the_problem_is_kept() {
    let b = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 1.0]).unwrap();
    let mut w = world(vec![b]).unwrap();
    let r = w.step().unwrap();
    assert_eq!(r.status, RigidStatus::NoContact);
    assert!(w.last_problem().is_none());
    let g = crate::world::GRAVITY;
    let h = w.settings().h;
    assert!((w.velocities()[0][2] + g * h).abs() < 1e-15);
    // θ = ½: x₁ = x₀ + h (v₀ + v₁)/2
    assert!((w.positions()[0][2] - (1.0 - 0.5 * g * h * h)).abs() < 1e-15);
    // dropped onto the floor, the step's global problem is stored
    let b = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 0.1]).unwrap();
    let mut w = world(vec![b]).unwrap();
    let r = w.step().unwrap();
    assert_eq!(r.status, RigidStatus::Converged);
    let p = w.last_problem().unwrap();
    assert_eq!(p.contacts(), r.contacts);
    assert_eq!(p.dofs(), 6);
}

pub fn warm_start_matches_manifold_points_across_steps() {
    let b = cuboid([0.1, 0.05, 0.05], 1000.0, [0.0, 0.0, 0.05]).unwrap();
    let mut w = world(vec![b]).unwrap();
    let first = w.step().unwrap();
    let second = w.step().unwrap();
    assert_eq!(first.warm_started, 0);
    assert_eq!(second.warm_started, second.contacts);
    assert_eq!(second.contacts, 4);
}

pub fn a_stalled_step_is_handed_to_the_library_on_the_global_problem() {
    // one sweep only: Gauss–Seidel cannot reach 1e-8 on the 4-corner face contact
    let b = cuboid([0.1, 0.05, 0.05], 1000.0, [0.0, 0.0, 0.05]).unwrap();
    let settings = RigidSettings {
        max_sweeps: 1,
        ..RigidSettings::default()
    };
    let mut w = RigidWorld::new(vec![b], vec![floor()], one_material(0.5), settings).unwrap();
    let r = w.step().unwrap();
    assert_eq!(r.method, "nsgs+library", "{r:?}");
    assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
    assert!(r.error <= 1e-8);
    // the reported error is that of the stored global problem
    let p = w.last_problem().unwrap();
    let rr: Vec<f64> = w.contacts().iter().flat_map(|c| c.impulse).collect();
    let e = stored_error(p, &rr);
    assert!((e - r.error).abs() <= 1e-12, "{e} vs {}", r.error);
}

/// The error of docs/error.md of r on a stored global problem with M diagonal:
/// v = M⁻¹(f + H r), u = Hᵀ v + w, q = Hᵀ M⁻¹ f + w.
fn stored_error(p: &coulomb::problem::GlobalProblem, r: &[f64]) -> f64 {
    let mut hr = p.f.clone();
    p.h.gemv_acc(1.0, r, &mut hr);
    let v: Vec<f64> = hr.iter().zip(p.m.diagonal()).map(|(x, m)| x / m).collect();
    let u = p.velocity(&v);
    let q_norm = {
        let minv_f: Vec<f64> = p.f.iter().zip(p.m.diagonal()).map(|(x, m)| x / m).collect();
        coulomb::law::norm(&p.velocity(&minv_f))
    };
    coulomb::law::error_measure(3, &p.mu, r, &u, q_norm).error
}

/// The library's mixed Gauss–Seidel of a hand-over ([`super::quick_finish`]) solves a face
/// contact (4 corners: 12 contact unknowns for 6 degrees of freedom, W singular) to the
/// tolerance from r = 0, judged on the problem as stored.
pub fn the_quick_library_finish_solves_a_redundant_face_contact() {
    let b = cuboid([0.1, 0.05, 0.05], 1000.0, [0.0, 0.0, 0.05]).unwrap();
    let mut w = world(vec![b]).unwrap();
    w.step().unwrap();
    let p = w.last_problem().unwrap().clone();
    assert!(3 * p.mu.len() > p.f.len(), "{} contacts", p.mu.len());
    let settings = coulomb::solver::Settings::default();
    let global = coulomb::problem::Problem::Global(p.clone());
    let step_of = |sol: coulomb::solver::Solution| {
        let e = stored_error(&p, &sol.r);
        Some((sol.r, Vec::new(), e))
    };
    let (r, _, e) = super::quick_finish(&global, &settings, step_of).expect("solved");
    assert!(e <= settings.tol, "{e}");
    assert_eq!(stored_error(&p, &r), e);
    // the normal impulses carry the weight m g h over the 4 corners
    let s = w.settings();
    let weight = 1000.0 * 0.2 * 0.1 * 0.1 * -s.gravity[2] * s.h;
    let carried: f64 = r.chunks_exact(3).map(|c| c[0]).sum();
    assert!(
        (carried - weight).abs() <= 1e-6 * weight,
        "{carried} vs {weight}"
    );
}

/// The cube pyramid of `examples/scenes/rigid/cube-pyramid.toml` (5 layers, μ = 0.7,
/// h = 1 ms, tol 1e-8): Gauss–Seidel switches to plain sweeps at the first step that the
/// library's quick finish solves (a library finish within [`QUICK_NEAR`] of the tolerance on a
/// step with more contact unknowns than degrees of freedom), not before; and every step
/// after it still reaches the tolerance on its stored problem.
pub fn a_quick_finish_switches_the_world_to_plain_sweeps() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/scenes/rigid/cube-pyramid.toml"
    );
    let loaded = crate::scene_file::LoadedScene::load(std::path::Path::new(path)).unwrap();
    let built = loaded.build(&Default::default()).unwrap();
    let mut scene = crate::scene::rigid::RigidScene::new(&built.model).unwrap();
    let w = &mut scene.world;
    let tol = w.settings().tolerance;
    assert_eq!(tol, 1e-8);
    let mut switched_at = None;
    for k in 0..40 {
        assert!(!w.plain_sweeps());
        let r = w.step().unwrap();
        if w.plain_sweeps() {
            assert_eq!(r.method, "nsgs+library", "step {k}");
            assert!(r.error <= tol, "step {k}: {}", r.error);
            switched_at = Some(k);
            break;
        }
    }
    let k = switched_at.expect("no quick finish in 40 steps");
    for j in 1..=5 {
        let r = w.step().unwrap();
        assert!(w.plain_sweeps());
        assert!(r.error <= tol, "step {}: {}", k + j, r.error);
    }
}

/// The parallel gather of v = M⁻¹(f + H r) and u = Hᵀ v + w: bitwise the numbers of the
/// contact-by-contact scatter, on 1, 2 and 3 threads, r full or short.
pub fn parallel_evaluation_is_the_sequential_scatter_bit_for_bit() {
    let bodies = 40;
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut jac = || -> [[f64; 6]; 3] { std::array::from_fn(|_| std::array::from_fn(|_| rnd())) };
    let n = 3 * nsgs::EVAL_PARALLEL_MIN;
    let rows: Vec<nsgs::Row> = (0..n)
        .map(|i| {
            let a = (7 * i) % bodies;
            let b = (a + 1 + (11 * i) % (bodies - 1)) % bodies;
            nsgs::Row {
                a: Some((a, jac())),
                b: (i % 3 != 0).then(|| (b, jac())),
                w: [0.1, -0.2, 0.3],
                mu: 0.5,
            }
        })
        .collect();
    // Delassus blocks: J J^T / m with random J, positive definite almost surely
    let mass: Vec<[f64; 6]> = (0..bodies)
        .map(|b| std::array::from_fn(|d| 1.0 + 0.1 * (b + d) as f64))
        .collect();
    let f: Vec<[f64; 6]> = (0..bodies)
        .map(|b| std::array::from_fn(|d| (b * 6 + d) as f64 * 0.01 - 1.0))
        .collect();
    let problem = nsgs::Problem::new(rows.clone(), mass.clone(), f.clone()).unwrap();
    let r: Vec<f64> = (0..3 * n)
        .map(|i| ((i * 37) % 101) as f64 * 0.013 - 0.4)
        .collect();
    for len in [3 * n, 3 * n - 5, 0] {
        let r = &r[..len];
        // the scatter, contact by contact
        let mut p = f.clone();
        for (i, row) in rows.iter().enumerate().take(len / 3) {
            for (blk, j) in row.a.iter().chain(row.b.iter()) {
                for k in 0..3 {
                    for d in 0..6 {
                        p[*blk][d] += j[k][d] * r[3 * i + k];
                    }
                }
            }
        }
        for (pb, m) in p.iter_mut().zip(&mass) {
            for d in 0..6 {
                pb[d] /= m[d];
            }
        }
        let u: Vec<f64> = (0..n).flat_map(|i| problem.u(i, &p)).collect();
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (v, uu) = pool.install(|| {
                let v = problem.velocities(r);
                let uu = problem.u_all(&v);
                (v, uu)
            });
            let bits =
                |x: &[[f64; 6]]| -> Vec<u64> { x.iter().flatten().map(|x| x.to_bits()).collect() };
            assert_eq!(bits(&v), bits(&p), "v, {threads} threads, r of {len}");
            let ub: Vec<u64> = uu.iter().map(|x| x.to_bits()).collect();
            let ur: Vec<u64> = u.iter().map(|x| x.to_bits()).collect();
            assert_eq!(ub, ur, "u, {threads} threads, r of {len}");
        }
    }
}

/// A column of `n` touching balls (radius 0.05 m) on the floor, at rest.
fn ball_column(n: usize, relaxation: f64) -> RigidWorld {
    let shape = SharedShape::ball(0.05);
    let mass = crate::bodies::rigid::MassProperties::from_shape(&shape, 1000.0).unwrap();
    let bodies = (0..n)
        .map(|i| RigidBodyDesc {
            shape: shape.clone(),
            mass,
            position: [0.0, 0.0, 0.05 + 0.1 * i as f64],
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            material: 0,
            fixed: false,
        })
        .collect();
    let settings = RigidSettings {
        relaxation,
        library_finish: false,
        ..RigidSettings::default()
    };
    RigidWorld::new(bodies, vec![floor()], one_material(0.5), settings).unwrap()
}

/// `relaxation` means what the sphere engine's does (issue 52): over-relaxed sweeps
/// carry the weight of a column of balls down in fewer sweeps than plain Gauss–Seidel,
/// every verdict is the exact error on the stored problem, and ω outside [1, 2) is
/// refused.
pub fn over_relaxation_finishes_a_ball_column_in_fewer_sweeps() {
    let first = |relaxation: f64| ball_column(12, relaxation).step().unwrap();
    let (plain, relaxed) = (first(1.0), first(1.5));
    for r in [&plain, &relaxed] {
        assert_eq!(r.contacts, 12, "{r:?}");
        assert_eq!(r.method, "nsgs");
        assert_eq!(r.status == RigidStatus::Converged, r.error <= 1e-8, "{r:?}");
    }
    assert_eq!(relaxed.status, RigidStatus::Converged, "{relaxed:?}");
    assert!(relaxed.sweeps < plain.sweeps, "{relaxed:?} {plain:?}");
    for bad in [0.9, 2.0, f64::NAN] {
        let settings = RigidSettings {
            relaxation: bad,
            ..RigidSettings::default()
        };
        let b = cuboid([0.1; 3], 1000.0, [0.0, 0.0, 0.1]).unwrap();
        let e = RigidWorld::new(vec![b], vec![floor()], one_material(0.5), settings)
            .unwrap_err()
            .to_string();
        assert!(e.contains("relaxation"), "{e}");
    }
}

pub fn same_input_same_bits() {
    let run = || {
        let (bodies, obstacles) = crate::validation::rigid::rock_pile(20, 3).unwrap();
        let mut w = RigidWorld::new(
            bodies,
            obstacles,
            one_material(0.5),
            RigidSettings::default(),
        )
        .unwrap();
        for _ in 0..150 {
            w.step().unwrap();
        }
        (w.positions(), w.orientations(), w.contacts().len())
    };
    let (a, b) = (run(), run());
    assert!(a.2 > 0);
    assert_eq!(a, b);
}

/// The run's warning about the step size (`Engine::step_warning`) for bodies of any shape: at
/// rest none; a body whose current speed carries it farther than half its thinnest width in
/// one step is named, with the largest h that would not, and the warning goes once it slows.
pub fn a_body_too_fast_for_the_step_is_warned_about() {
    let mut w = world(vec![
        cuboid([0.1; 3], 1000.0, [0.0, 0.0, 0.1]).unwrap(),
        cuboid([0.02, 0.1, 0.1], 1000.0, [1.0, 0.0, 0.1]).unwrap(),
    ])
    .unwrap();
    assert_eq!(w.travel_warning(), None);
    let h = w.settings().h;
    // body 1 is 4 cm thick: 2 cm of travel per step is its limit
    let v = 1.5 * 0.02 / h;
    w.set_velocities(&[[0.0; 3], [v, 0.0, 0.0]]).unwrap();
    let warning = w.travel_warning().expect("a warning");
    assert!(warning.starts_with("body 1 travels"), "{warning}");
    let h_max = 0.02 / v;
    assert!(
        warning.contains(&format!("use h <= {h_max:.3e}")),
        "{warning}"
    );
    w.set_velocities(&[[0.0; 3], [0.5 * v, 0.0, 0.0]]).unwrap();
    assert_eq!(w.travel_warning(), None);
}
