//! The scene files shipped under examples/scenes: each parses, builds, and runs 3 steps
//! (fills capped at 40 spheres to keep the test short); `box.toml` and
//! `vibrating-plate.toml` build the built-in scenes' worlds to the bit.

use coulomb_granular::model::BuildChecks;
use coulomb_granular::scene_file::{BuildOptions, LoadedScene};
use coulomb_granular::{Scene, Simulation};
use std::path::PathBuf;

fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes")
}

#[test]
fn box_and_vibrating_plate_files_are_the_built_in_scenes() {
    for (file, scene) in [
        ("box.toml", Scene::Box),
        ("vibrating-plate.toml", Scene::VibratingPlate),
    ] {
        let loaded = LoadedScene::load(&scenes_dir().join(file)).unwrap();
        let built = loaded.build(&BuildOptions::default()).unwrap();
        let (world, _) = built.build(&BuildChecks::default()).unwrap();
        let reference = scene.build(150, 1);
        assert_eq!(world.bodies, reference.bodies, "{file}");
        assert_eq!(world.gravity, reference.gravity, "{file}");
        assert_eq!(world.obstacles.len(), reference.obstacles.len(), "{file}");
        for (a, b) in world.obstacles.iter().zip(&reference.obstacles) {
            assert_eq!((&a.shape, &a.motion), (&b.shape, &b.motion), "{file}");
        }
        // and the seed moves them
        let other = loaded
            .build(&BuildOptions {
                seed: Some(2),
                ..Default::default()
            })
            .unwrap();
        let (w2, _) = other.build(&BuildChecks::default()).unwrap();
        assert_eq!(w2.bodies, scene.build(150, 2).bodies);
    }
}

#[test]
fn every_shipped_scene_parses_builds_and_runs_three_steps() {
    let mut names: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml" || e == "json"))
        .collect();
    names.sort();
    assert!(names.len() >= 7, "{names:?}");
    for path in names {
        let loaded = LoadedScene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let mut built = loaded
            .build(&BuildOptions {
                max_fill: Some(40),
                ..Default::default()
            })
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(built.sphere_count() > 0, "{}", path.display());
        let (world, params) = built
            .build(&BuildChecks::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let mut sim = Simulation::new(world, params).unwrap();
        for _ in 0..3 {
            let t0 = sim.time;
            sim.step()
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let t1 = sim.time;
            for inlet in &mut built.inlets {
                inlet
                    .emit(&mut sim, &built.model, t0, t1)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            }
        }
        assert_eq!(sim.steps_done, 3);
    }
}

/// FNV-1a (64 bits) of `bytes`: a fingerprint of a built scene's text.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Fingerprints of what every scene file of the repository builds (fills capped at 100
/// spheres): the scene model's JSON (every number to the bit: serde_json writes the shortest
/// text that reads back to the same f64) and the run settings, inlets and fills. Recorded
/// before the scene file's schema became the model's own types (issue 52, item 5): the
/// same files must keep building the same models. A file changed on purpose gets its new
/// fingerprint from the failure message. Updated when the model's step took `gamma`,
/// `projection`, `projection_velocities`, `gap_closure` and `warm_start`: with those keys cut
/// from the JSON every file gave its fingerprint of before. Updated when `[[pairs]]` became
/// the model's `MaterialPair` (a pair held as written, `materials = [a, b]`, its coefficients
/// not given left to the default law) and `[step]` the model's `StepSettings` plus the run's
/// keys: the texts of before and after compared file by file, the only differences were the
/// two files with pairs (validation/incline.toml, validation/repose.toml: the same laws, the
/// same worlds and parameters to the bit) and the `[step]` section's Debug layout (the same
/// values).
const MODEL_FINGERPRINTS: &[(&str, u64)] = &[
    ("examples/scenes/box.toml", 0x9c469e0348f30f33),
    ("examples/scenes/chute.toml", 0x33fb83bfa75d76af),
    ("examples/scenes/drum-mesh.toml", 0x868cdc5974a66cc6),
    ("examples/scenes/funnel.toml", 0x8a22718968d4fee2),
    ("examples/scenes/rigid/ball-mill.toml", 0x9a8883a3c414459e),
    (
        "examples/scenes/rigid/brick-wall-touching.toml",
        0xece6f8b5f65443ee,
    ),
    ("examples/scenes/rigid/brick-wall.toml", 0x363361f3a6032b84),
    (
        "examples/scenes/rigid/capsule-hopper.toml",
        0x1a8a252496fe1a00,
    ),
    (
        "examples/scenes/rigid/cube-pyramid.toml",
        0x571a01cf50ca494e,
    ),
    (
        "examples/scenes/rigid/double-pendulum-urdf.toml",
        0x8d5f8b8b5a749f42,
    ),
    ("examples/scenes/rigid/incline.toml", 0xd57d89aa0f943602),
    ("examples/scenes/rigid/kapla-tower.toml", 0xd05f2cbe3604f40b),
    (
        "examples/scenes/rigid/newtons-cradle.toml",
        0x4aeae4b64478f754,
    ),
    (
        "examples/scenes/rigid/pendulum-chain.toml",
        0x8cd88d0457b3de9f,
    ),
    ("examples/scenes/rigid/rock-pile.json", 0x7899600c31161dc9),
    (
        "examples/scenes/rigid/slider-crank.toml",
        0x59299ec6c66c5ccc,
    ),
    (
        "examples/scenes/rigid/vehicle-on-spheres.toml",
        0x204a7fc941382395,
    ),
    ("examples/scenes/rigid/wall-impact.toml", 0xba88ab0d386b2015),
    ("examples/scenes/rotating-drum.toml", 0x48948d3c8e8238ac),
    ("examples/scenes/silo.toml", 0xcc444b0eba063367),
    (
        "examples/scenes/validation/beverloo.toml",
        0xf35b07a4f5c8a3d0,
    ),
    (
        "examples/scenes/validation/incline.toml",
        0x4d8c62403ee33e26,
    ),
    (
        "examples/scenes/validation/janssen.toml",
        0x2215e897991989d4,
    ),
    ("examples/scenes/validation/repose.toml", 0x17f74e436bf03fb5),
    ("examples/scenes/vibrating-plate.toml", 0x6be6e34304a97aec),
    ("scripts/onesim/spheres-cuboid.toml", 0xae96ec610183f2ce),
    ("scripts/onesim/spheres.toml", 0x148ca886c2c787ca),
];

#[test]
fn every_scene_file_builds_the_model_it_built_before() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut actual = Vec::new();
    for (file, _) in MODEL_FINGERPRINTS {
        let loaded = LoadedScene::load(&root.join(file)).unwrap_or_else(|e| panic!("{e}"));
        let built = loaded
            .build(&BuildOptions {
                max_fill: Some(100),
                ..Default::default()
            })
            .unwrap_or_else(|e| panic!("{e}"));
        let text = format!(
            "{}\n{:?}",
            serde_json::to_string(&built.model).unwrap(),
            (&built.name, &built.step, &built.inlets, &built.fills)
        );
        actual.push((file.to_string(), fnv1a(text.as_bytes())));
    }
    let table: String = actual
        .iter()
        .map(|(f, h)| format!("    (\"{f}\", {h:#018x}),\n"))
        .collect();
    let expected: Vec<(String, u64)> = MODEL_FINGERPRINTS
        .iter()
        .map(|(f, h)| (f.to_string(), *h))
        .collect();
    assert_eq!(actual, expected, "the fingerprints now:\n{table}");
}
