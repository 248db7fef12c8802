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
