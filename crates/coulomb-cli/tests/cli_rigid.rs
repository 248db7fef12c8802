//! `coulomb simulate SCENE.toml` with bodies of other shapes (issue 41): the shipped incline
//! runs in the rigid-body simulator with VTK frames of the bodies as polygons, stats and the
//! steps' problems in FCLIB; a non-unit quaternion or a degenerate hull exits with status 2
//! naming the file, line and key.

mod common;
use common::{coulomb, ok, temp_dir};
use std::path::PathBuf;

fn scene(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/scenes/rigid")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

#[test]
fn the_incline_runs_with_frames_stats_and_fclib_dumps() {
    let dir = temp_dir("rigid-incline");
    let out = dir.join("out");
    let fc = dir.join("fc");
    let text = ok(&coulomb(&[
        "simulate",
        &scene("incline.toml"),
        "--steps",
        "20",
        "--json",
        "--frames-every",
        "10",
        "--output",
        out.to_str().unwrap(),
        "--dump-fclib",
        fc.to_str().unwrap(),
    ]));
    let j: serde_json::Value = serde_json::from_str(text.trim()).unwrap();
    assert_eq!(j["bodies"], 1);
    assert_eq!(j["steps"], 20);
    assert_eq!(j["not_converged_steps"], 0);
    assert!(j["mean_contacts"].as_f64().unwrap() >= 3.0, "{j}");
    for f in [
        "bodies.pvd",
        "contacts.pvd",
        "obstacles.pvd",
        "stats.csv",
        "stats.json",
        "summary.json",
        "frames/bodies_000010.vtp",
        "frames/contacts_000020.vtp",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let body = std::fs::read(out.join("frames/bodies_000020.vtp")).unwrap();
    assert!(String::from_utf8_lossy(&body).contains("NumberOfPolys=\"6\""));
    assert!(fc.join("step_000019.hdf5").exists());
}

#[test]
fn bad_shapes_exit_2_with_file_line_and_key() {
    let dir = temp_dir("rigid-bad");
    for (text, line, words) in [
        (
            "[[bodies]]\nshape = { kind = \"cuboid\", half_extents = [1, 1, 1] }\npositions = [[0, 0, 1]]\norientations = [[1, 0, 0, 0.5]]\n",
            4,
            "unit quaternion",
        ),
        (
            "[[bodies]]\npositions = [[0, 0, 1]]\nshape = { kind = \"convex_hull\", points = [[0, 0, 0], [1, 0, 0], [0, 1, 0]] }\n",
            3,
            "at least 4 points",
        ),
    ] {
        let path = dir.join("bad.toml");
        std::fs::write(&path, text).unwrap();
        let o = coulomb(&["simulate", path.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(&format!("bad.toml:{line}:")) && err.contains(words),
            "{err}"
        );
    }
}
