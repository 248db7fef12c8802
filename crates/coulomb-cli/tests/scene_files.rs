//! `coulomb simulate SCENE.toml`: the shipped box.toml gives the numbers of `simulate box`
//! to the bit; inlets pour during the run; particles come from CSV files next to the scene;
//! bad scene files exit with status 2, name the file, line and column, and write nothing.

use crate::common;
use common::{coulomb, ok, temp_dir};
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes")
}

fn json(out: &str) -> serde_json::Value {
    serde_json::from_str(out.trim()).expect("one JSON object")
}

#[test]
fn box_file_gives_the_built_in_box_to_the_bit() {
    let dir = temp_dir("scene-box");
    let file = scenes_dir().join("box.toml");
    let (a, b) = (dir.join("file"), dir.join("builtin"));
    let run = |scene: &str, out: &Path| {
        json(&ok(&coulomb(&[
            "simulate",
            scene,
            "--steps",
            "12",
            "--json",
            "--frames-every",
            "6",
            "--output",
            out.to_str().unwrap(),
        ])))
    };
    let mut ja = run(file.to_str().unwrap(), &a);
    let mut jb = run("box", &b);
    for j in [&mut ja, &mut jb] {
        j.as_object_mut().unwrap().remove("mean_solve_seconds");
    }
    assert_eq!(ja, jb);
    assert!(ja["mean_contacts"].as_f64().unwrap() > 10.0);
    for k in [0, 6, 12] {
        let f = format!("frames/bodies_{k:06}.vtp");
        let (fa, fb) = (
            std::fs::read(a.join(&f)).unwrap(),
            std::fs::read(b.join(&f)).unwrap(),
        );
        assert_eq!(fa, fb, "{f}");
    }
}

#[test]
fn an_inlet_pours_during_the_run_and_csv_particles_are_read_next_to_the_scene() {
    let dir = temp_dir("scene-inlet");
    std::fs::write(
        dir.join("beads.csv"),
        "x,y,z,r,vx,vy,vz\n0.5,0.5,0.05,0.05,0,0,0\n0.2,0.2,0.05,0.05,0,0,0\n",
    )
    .unwrap();
    let scene = dir.join("pour.toml");
    std::fs::write(
        &scene,
        r#"
[step]
h = 0.01
steps = 30

[[obstacles]]
shape = { kind = "box", lo = [0, 0, 0], hi = [1, 1, 2], open_top = true }

[[bodies]]
file = "beads.csv"

[[inlets]]
region = { kind = "box", lo = [0.1, 0.1, 1.0], hi = [0.9, 0.9, 1.3] }
sizes = { kind = "uniform", min = 0.03, max = 0.04 }
rate = { count = 100 }
end = 0.2
velocity = [0, 0, -1]
"#,
    )
    .unwrap();
    let j = json(&ok(&coulomb(&[
        "simulate",
        scene.to_str().unwrap(),
        "--json",
    ])));
    let poured = j["poured"].as_u64().unwrap();
    assert_eq!(poured + j["inlet_skipped"].as_u64().unwrap(), 20);
    assert!(poured >= 18, "{j}");
    assert_eq!(j["bodies"].as_u64().unwrap(), 2 + poured);
    assert_eq!(j["steps"].as_u64().unwrap(), 30);
    // the same run twice: the same numbers
    let mut k = json(&ok(&coulomb(&[
        "simulate",
        scene.to_str().unwrap(),
        "--json",
    ])));
    let mut j = j;
    for x in [&mut j, &mut k] {
        x.as_object_mut().unwrap().remove("mean_solve_seconds");
    }
    assert_eq!(j, k);
}

#[test]
fn bad_scene_files_exit_2_with_the_place_and_write_nothing() {
    let dir = temp_dir("scene-bad");
    let cases = [
        (
            "typo.toml",
            "seed = 1\n[step]\nh = 0.01\nstpes = 10\n",
            "typo.toml:4:1",
            "stpes",
        ),
        (
            "pair.toml",
            "[[pairs]]\nmaterials = [\"default\", \"rubber\"]\nmu = 0.9\n",
            "pair.toml:2:",
            "unknown material 'rubber'",
        ),
        (
            "typo.json",
            "{\"seed\": 1, \"gravity\": [0, 0, -9.81], \"bodys\": []}",
            "typo.json:1:",
            "bodys",
        ),
        ("empty.toml", "seed = 1\n", "empty.toml", "no sphere"),
        // 3 m/s × 10 ms = 3 cm in one step, more than the radius 1 cm: the thin plate is
        // crossed (tunnelling)
        (
            "fast.toml",
            "[step]\nh = 0.01\n[[obstacles]]\nname = \"plate\"\nshape = { kind = \"rectangle\", center = [0, 0, 0], normal = [0, 0, 1], u = [1, 0, 0], half_u = 1, half_v = 1 }\n[[bodies]]\nvelocity = [0, 0, -3]\nspheres = [[0, 0, 0.5, 0.01]]\n",
            "fast.toml",
            "can cross obstacle 'plate' in one step",
        ),
    ];
    for (name, text, place, what) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let out_dir = dir.join(format!("{name}.out"));
        let out = coulomb(&[
            "simulate",
            path.to_str().unwrap(),
            "--output",
            out_dir.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(place) && err.contains(what), "{name}: {err}");
        assert!(!out_dir.exists(), "{name}: output written");
    }
    // an option the file sets
    let out = coulomb(&[
        "simulate",
        scenes_dir().join("box.toml").to_str().unwrap(),
        "--dt",
        "0.01",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--dt"));
    // the same with the CLI's default value: refused, not silently dropped for the file's
    let out = coulomb(&[
        "simulate",
        scenes_dir().join("box.toml").to_str().unwrap(),
        "--tol",
        "1e-4",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--tol"));
    // a missing file
    let out = coulomb(&["simulate", "no/such/scene.toml"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn beads_caps_the_fills_and_json_scenes_run() {
    let drum = scenes_dir().join("rotating-drum.toml");
    let j = json(&ok(&coulomb(&[
        "simulate",
        drum.to_str().unwrap(),
        "--beads",
        "20",
        "--steps",
        "2",
        "--json",
    ])));
    assert_eq!(j["bodies"].as_u64(), Some(20));
    assert_eq!(j["steps"].as_u64(), Some(2));
    assert_eq!(j["scene"].as_str(), Some("rotating-drum"));
    let dir = temp_dir("scene-json");
    let scene = dir.join("two.json");
    std::fs::write(
        &scene,
        r#"{"step": {"h": 0.01, "steps": 5},
            "obstacles": [{"shape": {"kind": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}}],
            "bodies": [{"spheres": [[0, 0, 0.1, 0.1], [0.5, 0, 0.1, 0.1]]}]}"#,
    )
    .unwrap();
    let j = json(&ok(&coulomb(&[
        "simulate",
        scene.to_str().unwrap(),
        "--json",
    ])));
    assert_eq!(j["bodies"].as_u64(), Some(2));
    assert_eq!(j["steps"].as_u64(), Some(5));
    assert_eq!(j["not_converged_steps"].as_u64(), Some(0));
}

#[test]
fn overlapping_spheres_are_refused_unless_resolve_overlaps_relaxes_them() {
    let dir = temp_dir("scene-overlap");
    let scene = dir.join("overlap.toml");
    // two spheres of radius 0.05 whose centres are 0.06 apart (overlap 0.04) above a floor
    std::fs::write(
        &scene,
        "[step]\nh = 0.005\nsteps = 5\n\
         [[bodies]]\nspheres = [[0.0, 0.0, 0.2, 0.05], [0.06, 0.0, 0.2, 0.05]]\n\
         [[obstacles]]\nshape = { kind = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }\n",
    )
    .unwrap();
    let scene = scene.to_str().unwrap();
    let refused = dir.join("refused");
    let out = coulomb(&["simulate", scene, "--output", refused.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("overlap"), "{err}");
    assert!(!refused.exists(), "output written");
    // relaxed: the run goes on, and says what it did
    let out = coulomb(&["simulate", scene, "--resolve-overlaps", "--json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("1 overlaps at the start") && err.contains("0 left"),
        "{err}"
    );
    assert_eq!(json(&String::from_utf8_lossy(&out.stdout))["steps"], 5);
    // not for the built-in scenes, and not with a zero sweep budget that leaves overlaps
    let out = coulomb(&["simulate", "box", "--resolve-overlaps"]);
    assert_eq!(out.status.code(), Some(2));
    let out = coulomb(&["simulate", scene, "--resolve-overlaps", "0"]);
    assert_eq!(out.status.code(), Some(2));
}

/// Issue 52, item 3: `--resolve-overlaps` means the same for scenes of any shapes: a cuboid
/// sunk 1 cm into the floor under a sphere sunk into it is refused, then relaxed and run.
#[test]
fn resolve_overlaps_relaxes_bodies_of_any_shape() {
    let dir = temp_dir("scene-overlap-rigid");
    let scene = dir.join("sunk.toml");
    std::fs::write(
        &scene,
        "[step]\nh = 0.001\nsteps = 5\ntol = 1e-8\n\
         [[bodies]]\nshape = { kind = \"cuboid\", half_extents = [0.1, 0.1, 0.05] }\n\
         positions = [[0.0, 0.0, 0.04]]\n\
         [[bodies]]\nshape = { kind = \"sphere\", radius = 0.05 }\n\
         positions = [[0.0, 0.0, 0.135]]\n\
         [[obstacles]]\nshape = { kind = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }\n",
    )
    .unwrap();
    let scene = scene.to_str().unwrap();
    let out = coulomb(&["simulate", scene, "--json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("interpenetrat"), "{err}");
    let out = coulomb(&["simulate", scene, "--resolve-overlaps", "--json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("overlaps at the start") && err.contains(", 0 left"),
        "{err}"
    );
    let j = json(&String::from_utf8_lossy(&out.stdout));
    assert_eq!(j["steps"], 5);
    assert!(j["max_penetration"].as_f64().unwrap() < 1e-6, "{j}");
    let out = coulomb(&["simulate", scene, "--resolve-overlaps", "0"]);
    assert_eq!(out.status.code(), Some(2));
    // the sphere engine's sweep accelerations are refused, not dropped
    for opt in ["--subspace-every", "--coarse-every"] {
        let out = coulomb(&["simulate", scene, "--resolve-overlaps", opt, "10"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains("other shapes"), "{err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
