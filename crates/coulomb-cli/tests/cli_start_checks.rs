//! Issue 55: a sphere placed overlapping an obstacle at the start is refused (exit 2, the
//! sphere, the obstacle and the overlap named) unless `--resolve-overlaps` relaxes it; rigid
//! runs report their progress on stderr when it is not a terminal, as sphere runs do.

use crate::common;

use common::temp_dir;
use std::process::{Command, Output, Stdio};

fn run(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_coulomb"));
    c.args(args).stdin(Stdio::null());
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("the coulomb binary runs")
}

const SUNK: &str = r#"
[step]
steps = 5
[[obstacles]]
name = "floor"
shape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }
[[bodies]]
spheres = [[0.0, 0.0, 0.5, 0.05], [0.3, 0.0, 0.03, 0.05]]
"#;

#[test]
fn a_sphere_sunk_into_an_obstacle_is_refused_unless_relaxed() {
    let dir = temp_dir("sunk");
    let scene = dir.join("sunk.toml");
    std::fs::write(&scene, SUNK).unwrap();
    let s = scene.to_str().unwrap();
    let out = run(
        &["simulate", s, "--output", dir.join("a").to_str().unwrap()],
        &[],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("sphere 1") && err.contains("'floor'") && err.contains("2.000e-2"),
        "{err}"
    );
    assert!(!dir.join("a").join("stats.csv").exists());
    // relaxed: runs, and the sphere starts on the floor
    let out = run(
        &[
            "simulate",
            s,
            "--resolve-overlaps",
            "100",
            "--output",
            dir.join("b").to_str().unwrap(),
        ],
        &[],
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_rigid_run_reports_progress_when_stderr_is_not_a_terminal() {
    let dir = temp_dir("rigid-progress");
    let scene = dir.join("cube.toml");
    std::fs::write(
        &scene,
        r#"
[step]
h = 1e-3
tol = 1e-8
steps = 4
[[obstacles]]
shape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }
[[bodies]]
shape = { kind = "cuboid", half_extents = [0.05, 0.05, 0.05] }
positions = [[0.0, 0.0, 0.05]]
"#,
    )
    .unwrap();
    let out = run(
        &[
            "simulate",
            scene.to_str().unwrap(),
            "--output",
            dir.join("o").to_str().unwrap(),
        ],
        &[("COULOMB_PROGRESS_SECONDS", "0")],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    for k in 1..=4 {
        assert!(err.contains(&format!("cube 1: step {k}/4, ")), "{err}");
    }
    assert!(
        err.contains("contacts") && err.contains("iterations"),
        "{err}"
    );
    // --json: stderr without progress
    let out = run(
        &[
            "simulate",
            scene.to_str().unwrap(),
            "--json",
            "--output",
            dir.join("j").to_str().unwrap(),
        ],
        &[("COULOMB_PROGRESS_SECONDS", "0")],
    );
    assert_eq!(out.status.code(), Some(0));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("step 1/4"));
    std::fs::remove_dir_all(&dir).ok();
}
