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
