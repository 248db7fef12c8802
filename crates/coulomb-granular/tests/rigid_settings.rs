//! Issue 52, item 3: the `[step]` settings and rolling friction mean in a scene with bodies
//! of other shapes (the rigid-body step) what they mean in a sphere scene (docs/granular.md,
//! "`[step]`"); each run here has a cuboid lying far away, so that it is a rigid scene.

use coulomb_granular::model::BuildChecks;
use coulomb_granular::rigid::{RigidStatus, RigidStepReport};
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::{BuildOptions, BuiltScene, LoadedScene};
use coulomb_granular::Simulation;

/// A ball of radius 0.1 m (material `ball`) at height `z` with velocity `v` over a floor,
/// the given `[step]` lines and `[[pairs]]` law of (ball, default), and, with `cuboid`, a
/// cuboid lying 5 m away (material `default`).
fn scene(step: &str, pair: &str, z: f64, v: [f64; 3], cuboid: bool) -> BuiltScene {
    let cuboid = if cuboid {
        "[[bodies]]\ndensity = 1000\nshape = { kind = \"cuboid\", half_extents = [0.1, 0.1, 0.1] }\npositions = [[5.0, 0.0, 0.1]]\n"
    } else {
        ""
    };
    let text = format!(
        "[step]\nh = 0.001\ntol = 1e-8\n{step}\n\
         [materials.ball]\ndensity = 2500\n\
         [default_pair]\nmu = 0.5\nrestitution = 0.0\n\
         [[pairs]]\nmaterials = [\"ball\", \"default\"]\n{pair}\n\
         [[obstacles]]\nname = \"floor\"\nshape = {{ kind = \"plane\", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\n\
         [[bodies]]\nmaterial = \"ball\"\nspheres = [[0.0, 0.0, {z}, 0.1]]\nvelocity = {v:?}\n{cuboid}"
    );
    LoadedScene::parse(std::path::Path::new("settings.toml"), text, true)
        .and_then(|l| l.build(&BuildOptions::default()))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The rigid scene of `built` (its `[step]` settings are its model's), and the reports of
/// `n` steps.
fn run(built: &BuiltScene, n: usize) -> (RigidScene, Vec<RigidStepReport>) {
    let mut s = RigidScene::new(&built.model).unwrap_or_else(|e| panic!("{e}"));
    let reports = (0..n).map(|_| s.step().unwrap()).collect();
    (s, reports)
}

/// The ball's gap above the floor.
fn gap(s: &RigidScene) -> f64 {
    s.world.positions()[0][2] - 0.1
}

#[test]
fn warm_start_false_starts_every_step_cold() {
    let built = |w: &str| scene(w, "", 0.1, [1.0, 0.0, 0.0], true);
    let (_, warm) = run(&built(""), 5);
    let (_, cold) = run(&built("warm_start = false"), 5);
    assert!(warm[1..].iter().all(|r| r.warm_started > 0), "{warm:?}");
    assert!(cold.iter().all(|r| r.warm_started == 0), "{cold:?}");
    assert!(cold.iter().all(|r| r.status == RigidStatus::Converged));
}

/// A ball at rest 5 µm above the floor (e = 0): gravity's look-ahead activates the contact;
/// with the gap closure it comes down onto the floor, without it it hovers.
#[test]
fn gap_closure_false_lets_a_resting_ball_hover() {
    let built = |w: &str| scene(w, "", 0.1 + 5e-6, [0.0; 3], true);
    let (closed, _) = run(&built(""), 20);
    let (hover, _) = run(&built("gap_closure = false"), 20);
    // down onto the floor, at most the closure's overshoot (g_k / 2, below the correction's
    // trigger) into it, as a sphere of a sphere scene
    assert!(
        gap(&closed) < 1e-6 && gap(&closed) > -3e-6,
        "{}",
        gap(&closed)
    );
    assert!((gap(&hover) - 5e-6).abs() < 1e-8, "{}", gap(&hover));
}

/// A ball 0.5 mm above the floor falling at 2 m/s (e = 0) ends its impact step 0.5 mm deep:
/// the position correction lifts it out, `projection = false` leaves it; with γ = 0 the pair
/// is not active before contact (g ≤ δ only), with γ = 1 it is (the cuboid resting on the
/// floor has its own contacts in every run).
#[test]
fn projection_and_gamma_mean_what_they_mean_for_spheres() {
    let built = |w: &str| scene(w, "", 0.1005, [0.0, 0.0, -2.0], true);
    let (corrected, r) = run(&built(""), 1);
    let (deep, _) = run(&built("projection = false"), 1);
    assert!(gap(&corrected) > -1.1e-5, "{}", gap(&corrected));
    assert!(gap(&deep) < -4e-4, "{}", gap(&deep));
    let (_, r0) = run(&built("gamma = 0.0"), 1);
    let (_, r5) = run(&built("gamma = 0.5"), 1);
    assert_eq!(r0[0].contacts + 1, r[0].contacts);
    assert_eq!(r5[0].contacts, r[0].contacts);
    // positions only is what the rigid correction does; the others are refused by name
    let rigid = |b: BuiltScene| RigidScene::new(&b.model).map(|_| ());
    assert!(rigid(built("projection_velocities = \"positions_only\"")).is_ok());
    for v in ["rescale", "inelastic"] {
        let line = format!("projection_velocities = \"{v}\"");
        let e = rigid(built(&line)).unwrap_err().to_string();
        assert!(e.contains(&line), "{e}");
    }
}

/// `method = "library"`: every step solved by the library's solver, no Gauss–Seidel sweep,
/// to the tolerance, and the same motion as nsgs to it.
#[test]
fn method_library_solves_every_step_with_the_library() {
    let built = |w: &str| scene(w, "", 0.1, [1.0, 0.0, 0.0], true);
    let (lib, r) = run(&built("method = \"library\""), 20);
    let (gs, _) = run(&built(""), 20);
    assert!(
        r.iter().all(|r| r.sweeps == 0 && r.method == "library"),
        "{r:?}"
    );
    assert!(
        r.iter().all(|r| r.status == RigidStatus::Converged),
        "{r:?}"
    );
    let (a, b) = (lib.world.velocities()[0], gs.world.velocities()[0]);
    assert!((a[0] - b[0]).abs() < 1e-6, "{a:?} {b:?}");
}

/// The scene: a ball rolling on a floor with rolling friction 0 and 0.5, a cuboid
/// 5 m away. Its kinetic energy after 0.2 s differs, and is that of the sphere engine
/// without the cuboid to 1e-6 (the same law; the solvers differ within their tolerance
/// 1e-8); the velocities are those of the laws of motion.
#[test]
fn rolling_friction_next_to_a_cuboid_is_the_sphere_engines() {
    let energy_rigid = |mu_r: f64| {
        let (s, r) = run(
            &scene(
                "",
                &format!("rolling_friction = {mu_r}"),
                0.1,
                [2.0, 0.0, 0.0],
                true,
            ),
            200,
        );
        assert!(
            r.iter().all(|r| r.status == RigidStatus::Converged),
            "{:?}",
            r.last()
        );
        (s.world.kinetic_energy(), s.world.velocities()[0][0])
    };
    let energy_spheres = |mu_r: f64| {
        let built = scene(
            "",
            &format!("rolling_friction = {mu_r}"),
            0.1,
            [2.0, 0.0, 0.0],
            false,
        );
        let (world, params) = built.build(&BuildChecks::default()).unwrap();
        let mut sim = Simulation::new(world, params).unwrap();
        for _ in 0..200 {
            sim.step().unwrap();
        }
        sim.world.kinetic_energy()
    };
    let (e0, _) = energy_rigid(0.0);
    let (e1, v1) = energy_rigid(0.1);
    let (e5, v5) = energy_rigid(0.5);
    let s = [0.0, 0.1, 0.5].map(energy_spheres);
    eprintln!("kinetic energy (J), rigid: {e0} {e1} {e5}, spheres: {s:?}");
    assert!(e5 < 0.6 * e0, "{e5} {e0}");
    for (rigid, spheres) in [e0, e1, e5].into_iter().zip(s) {
        assert!(
            (rigid - spheres).abs() <= 1e-6 * spheres,
            "{rigid} {spheres}"
        );
    }
    // μ_r = 0.1: it slides (−μ g; ω̇ = 5/2 (μ − μ_r) g / R) until it rolls at t* = v0 / (g (μ
    // + 5/2 (μ − μ_r))), v* = 4/3 m/s, then decelerates at 5/7 μ_r g
    let (g, t) = (9.81, 2.0 / (9.81 * 1.5));
    let v = 4.0 / 3.0 - 5.0 / 7.0 * 0.1 * g * (0.2 - t);
    assert!((v1 - v).abs() < 2e-3, "{v1} {v}");
    // μ_r = μ: the rolling resistance holds ω at 0 against the friction's torque, so the
    // ball slides at −μ g (exactly, step by step): v(0.2 s) = 2 − 0.5 g 0.2
    assert!((v5 - (2.0 - 0.5 * 9.81 * 0.2)).abs() < 1e-4, "{v5}");
}

/// Two balls (R = 0.1 m spinning at (0, 3, 5) rad/s, R = 0.05 m at rest just beside it) on
/// the floor, rolling friction 0.2 between the balls (R_e = R_A R_B / (R_A + R_B)) and 0.05
/// with the floor, a cuboid far away: after 0.3 s the kinetic energy is the sphere engine's
/// without the cuboid to 1e-4 of the initial one E₀ (measured 5e-5 E₀; without any rolling
/// friction the engines differ by 3e-5 of their end energy: their activation and gap closure
/// of body pairs differ; the balls' rolling friction alone changes the end energy by 6e-3 E₀).
#[test]
fn two_balls_with_rolling_friction_move_as_in_the_sphere_engine() {
    let text = |cuboid: bool| {
        let cuboid = if cuboid {
            "[[bodies]]\nshape = { kind = \"cuboid\", half_extents = [0.1, 0.1, 0.1] }\npositions = [[5.0, 0.0, 0.1]]\n"
        } else {
            ""
        };
        format!(
            "[step]\nh = 0.001\ntol = 1e-8\nprojection_velocities = \"positions_only\"\n[materials.ball]\ndensity = 2500\n\
             [default_pair]\nmu = 0.5\nrestitution = 0.0\n\
             [[pairs]]\nmaterials = [\"ball\", \"ball\"]\nrolling_friction = 0.2\n\
             [[pairs]]\nmaterials = [\"ball\", \"default\"]\nrolling_friction = 0.05\n\
             [[obstacles]]\nname = \"floor\"\nshape = {{ kind = \"plane\", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\n\
             [[bodies]]\nmaterial = \"ball\"\nspheres = [[0.0, 0.0, 0.1, 0.1]]\nangular_velocity = [0.0, 3.0, 5.0]\n\
             [[bodies]]\nmaterial = \"ball\"\nspheres = [[0.1414214, 0.0, 0.05, 0.05]]\n{cuboid}"
        )
    };
    let built = |cuboid: bool| {
        LoadedScene::parse(std::path::Path::new("balls.toml"), text(cuboid), true)
            .and_then(|l| l.build(&BuildOptions::default()))
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let e0 = RigidScene::new(&built(true).model)
        .unwrap()
        .world
        .kinetic_energy();
    let (rigid, r) = run(&built(true), 300);
    assert!(r.iter().all(|r| r.status == RigidStatus::Converged));
    let (world, params) = built(false).build(&BuildChecks::default()).unwrap();
    let mut sim = Simulation::new(world, params).unwrap();
    for _ in 0..300 {
        sim.step().unwrap();
    }
    let (a, b) = (rigid.world.kinetic_energy(), sim.world.kinetic_energy());
    eprintln!("two balls, kinetic energy (J): rigid {a}, spheres {b}");
    assert!((a - b).abs() <= 1e-4 * e0, "{a} {b} {e0}");
}
