//! The rigid-body scene files shipped under examples/scenes/rigid (issue 41): each parses,
//! builds a rigid world (no body interpenetrating another or an obstacle), and runs two
//! steps with every step's error on its problem within the file's tolerance.

use coulomb_granular::rigid::RigidStatus;
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::{BuildOptions, LoadedScene};
use std::path::PathBuf;

fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/rigid")
}

#[test]
fn every_shipped_rigid_scene_parses_builds_and_runs_two_steps() {
    let mut names: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml" || e == "json"))
        .collect();
    names.sort();
    let stems: Vec<String> = names
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    for want in [
        "brick-wall",
        "brick-wall-touching",
        "capsule-hopper",
        "cube-pyramid",
        "incline",
        "kapla-tower",
        "rock-pile",
        "wall-impact",
    ] {
        assert!(stems.iter().any(|s| s == want), "{want} missing: {stems:?}");
    }
    for path in names {
        let shown = path.display().to_string();
        let loaded = LoadedScene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let built = loaded
            .build(&BuildOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(built.model.has_shapes(), "{shown}");
        let mut scene = RigidScene::new(&built.model).unwrap_or_else(|e| panic!("{shown}: {e}"));
        assert_eq!(scene.world.len(), built.model.bodies.len(), "{shown}");
        for _ in 0..2 {
            let r = scene.step().unwrap_or_else(|e| panic!("{shown}: {e}"));
            assert!(
                r.status != RigidStatus::NotConverged && r.error <= built.model.step.tol,
                "{shown}: {r:?}"
            );
        }
    }
    // the rock pile holds 500 rocks
    let rocks = LoadedScene::load(&scenes_dir().join("rock-pile.json"))
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap();
    assert_eq!(rocks.model.bodies.len(), 500);
}

/// A sphere rolling on a floor and one cuboid lying 5 m away, with the given `[default_pair]`
/// and `[step]` lines.
fn ball_and_box(pair: &str, step: &str) -> LoadedScene {
    let text = format!(
        "[step]\nh = 0.001\nsteps = 10\ntol = 1e-8\n{step}\n\
         [default_pair]\nmu = 0.5\nrestitution = 0.0\n{pair}\n\
         [[obstacles]]\nname = \"floor\"\nshape = {{ kind = \"plane\", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\n\
         [[bodies]]\nspheres = [[0.0, 0.0, 0.1, 0.1]]\nvelocity = [1.0, 0.0, 0.0]\n\
         [[bodies]]\ndensity = 1000\nshape = {{ kind = \"cuboid\", half_extents = [0.1, 0.1, 0.1] }}\npositions = [[5.0, 0.0, 0.1]]\n"
    );
    LoadedScene::parse(std::path::Path::new("ball-and-box.toml"), text, true)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Issue 52, item 3: the settings a scene with other shapes cannot honour are refused with
/// a message naming them, the others apply (tests/rigid_settings.rs shows what they do).
/// Before: rolling_friction 0.5 gave the kinetic energy of 0 to the last digit, `method`,
/// `relaxation`, `gamma`, `projection` were dropped; then all of them were refused.
#[test]
fn settings_a_scene_with_other_shapes_cannot_honour_are_refused() {
    let build = |pair: &str, step: &str| {
        let built = ball_and_box(pair, step)
            .build(&BuildOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        RigidScene::new(&built.model)
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    assert!(build("", "").is_ok());
    assert!(build("rolling_friction = 0.0", "").is_ok());
    // the cuboid lies on the floor with the same material: that pair has no ball
    let e = build("rolling_friction = 0.5", "").unwrap_err();
    assert!(
        e.contains("rolling_friction = 0.5")
            && e.contains("'default' and 'default'")
            && e.contains("body 1 (Cuboid)")
            && e.contains("obstacle 'floor' (HalfSpace)"),
        "{e}"
    );
    assert!(build("", "method = \"library\"").is_ok());
    // relaxation applies to the rigid Gauss–Seidel as to the spheres' (issue 52)
    assert!(build("", "relaxation = 1.2").is_ok());
    assert!(build("", "relaxation = 1.0").is_ok());
    // method = "library" with a motor (a bounded row, which only nsgs solves)
    let mut mill = LoadedScene::load(&scenes_dir().join("ball-mill.toml"))
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap();
    mill.model.step.method = coulomb_granular::model::StepChoice::Library;
    let e = RigidScene::new(&mill.model).unwrap_err().to_string();
    assert!(
        e.contains("method = \"library\"") && e.contains("joint "),
        "{e}"
    );
    let step = |line: &str| {
        let s = ball_and_box("", line);
        let built = s.build(&BuildOptions::default()).unwrap();
        RigidScene::new(&built.model).map_err(|e| e.to_string())
    };
    for line in [
        "",
        "gamma = 0.5",
        "projection = false",
        "gap_closure = false",
        "warm_start = false",
        "projection_velocities = \"positions_only\"",
    ] {
        assert!(step(line).is_ok(), "{line}");
    }
    let e = step("projection_velocities = \"inelastic\"").unwrap_err();
    assert!(e.contains("projection_velocities = \"inelastic\""), "{e}");
}

/// The shipped pendulum chain (issue 53): 8 links on revolute joints swinging into a brick
/// column; its joints are read from `[[joints]]` with the bodies numbered in file order, and
/// the chain swings down with every step solved and the joints held.
#[test]
fn the_pendulum_chain_swings_on_its_joints() {
    let built = LoadedScene::load(&scenes_dir().join("pendulum-chain.toml"))
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap();
    assert_eq!(built.model.joints.len(), 8);
    assert_eq!(built.model.bodies.len(), 14);
    let mut scene = RigidScene::new(&built.model).unwrap();
    let z0 = scene.world.centres_of_mass()[7][2];
    for _ in 0..300 {
        let r = scene.step().unwrap();
        assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
    }
    // the projection (at most 100 sweeps a step) leaves 1.1e-8 m on the swinging chain
    assert!(
        scene.world.joint_drift() < 1e-6,
        "{}",
        scene.world.joint_drift()
    );
    // the last link fell
    assert!(scene.world.centres_of_mass()[7][2] < z0 - 0.1);
    // the hinge to the world pulls the chain up and towards it
    let f = scene.world.joint_forces()[0];
    assert!(f[2] > 0.0, "{f:?}");
}

/// `[[joints]]` with a bad entry is refused naming the joint and the field; an unknown key
/// or kind names the key.
#[test]
fn bad_joints_in_a_scene_file_are_refused() {
    let base = "[step]\nh = 0.001\nsteps = 10\ntol = 1e-8\n\
         [[bodies]]\ndensity = 1000\nshape = { kind = \"cuboid\", half_extents = [0.1, 0.1, 0.1] }\npositions = [[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]]\n";
    for (joint, words) in [
        ("kind = \"revolute\"\nbody_a = 0\nbody_b = 5\nanchor = [0, 0, 2]\naxis = [0, 1, 0]", "joint 0: body_b: no body 5"),
        ("kind = \"revolute\"\nbody_a = 0\nbody_b = 0\nanchor = [0, 0, 2]\naxis = [0, 1, 0]", "joint 0: body_b"),
        ("kind = \"revolute\"\nbody_a = 0\nanchor = [0, 0, 2]\naxis = [0, 0, 0]", "joint 0: axis"),
        ("kind = \"prismatic\"\nbody_a = 0\nanchor = [0, 0, 2]\naxis = [0, 0, 1]\nlimits = [1.0, 0.0]", "joint 0: limits"),
        ("kind = \"revolute\"\nbody_a = 0\nanchor = [0, 0, 2]\naxis = [0, 0, 1]\nmotor = { velocity = 1.0, max_force = -1.0 }", "joint 0: motor.max_force"),
        ("kind = \"revolute\"\nbody_a = 0\nanchor = [0, 0, 2]\naxis = [0, 0, 1]\nmotor = { velocity = 1.0, position = 0.5, max_force = 1.0 }", "joint 0: motor: velocity and position both"),
        ("kind = \"revolute\"\nbody_a = 0\nanchor = [0, 0, 2]\naxis = [0, 0, 1]\nmotor = { position = 0.5, max_force = -1.0 }", "joint 0: motor.max_force"),
        ("kind = \"revolute\"\nbody_a = 0\nanchor = [0, 0, 2]\naxis = [0, 0, 1]\nlimit_restitution = 0.5", "joint 0: limit_restitution"),
    ] {
        let text = format!("{base}[[joints]]\n{joint}\n");
        let loaded = LoadedScene::parse(std::path::Path::new("j.toml"), text, true)
            .unwrap_or_else(|e| panic!("{e}"));
        let built = loaded.build(&BuildOptions::default()).unwrap();
        let e = RigidScene::new(&built.model).unwrap_err().to_string();
        assert!(e.contains(words), "{e}");
    }
    for (joint, words) in [
        ("kind = \"hinge\"\nbody_a = 0\nanchor = [0, 0, 2]", "hinge"),
        (
            "kind = \"spherical\"\nbody_a = 0\nanchor = [0, 0, 2]\nstiffness = 3",
            "stiffness",
        ),
    ] {
        let text = format!("{base}[[joints]]\n{joint}\n");
        let e = LoadedScene::parse(std::path::Path::new("j.toml"), text, true).unwrap_err();
        assert!(e.to_string().contains(words), "{e}");
    }
}

/// The shipped Newton's cradle (issue 53): 5 balls on hinges 1 mm apart with e = 1; ball 0,
/// released from 0.5 rad, hits the row and ball 4 leaves with ≥ 95 % of its speed while
/// the others stay (nearly) at rest.
#[test]
fn the_newtons_cradle_passes_the_speed_on() {
    let built = LoadedScene::load(&scenes_dir().join("newtons-cradle.toml"))
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap();
    assert_eq!(built.model.joints.len(), 5);
    let mut scene = RigidScene::new(&built.model).unwrap();
    let speed = |s: &RigidScene, i: usize| {
        let v = s.world.velocities()[i];
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    };
    let (mut first, mut last, mut others, mut touched) = (0.0f64, 0.0f64, 0.0f64, false);
    for _ in 0..500 {
        let r = scene.step().unwrap();
        assert_eq!(r.status, RigidStatus::Converged, "{r:?}");
        touched |= r.contacts > 0;
        if !touched {
            first = first.max(speed(&scene, 0));
        }
        let v4 = speed(&scene, 4);
        if last > 0.5 * first && v4 < last {
            others = (0..4).map(|i| speed(&scene, i)).fold(others, f64::max);
        }
        last = last.max(v4);
    }
    eprintln!("cradle scene: first {first} last {last} others {others}");
    assert!(first > 0.6, "{first}");
    assert!(last >= 0.95 * first, "{first} {last}");
    assert!(others <= 0.05 * first, "{others}");
}

/// The shipped slider-crank (issue 53): over one turn of the motorised crank (1 000 steps)
/// the piston follows x(φ) = r cos φ + √(l² − r² sin² φ) to 1e-6 m with every step solved.
#[test]
fn the_slider_crank_follows_its_kinematics() {
    let built = LoadedScene::load(&scenes_dir().join("slider-crank.toml"))
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap();
    assert_eq!(built.model.joints.len(), 4);
    let mut scene = RigidScene::new(&built.model).unwrap();
    let (r, l) = (0.1f64, 0.3f64);
    let mut worst: f64 = 0.0;
    let mut max_x: f64 = 0.0;
    for _ in 0..1000 {
        let rep = scene.step().unwrap();
        assert_eq!(rep.status, RigidStatus::Converged, "{rep:?}");
        let c = scene.world.centres_of_mass();
        let phi = c[0][1].atan2(c[0][0]);
        let want = r * phi.cos() + (l * l - (r * phi.sin()).powi(2)).sqrt();
        worst = worst.max((c[2][0] - want).abs());
        max_x = max_x.max(c[2][0]);
    }
    eprintln!("slider-crank scene: largest error {worst:.2e} m");
    assert!(worst < 1e-6, "{worst}");
    assert!((max_x - (r + l)).abs() < 1e-4, "{max_x}");
}
