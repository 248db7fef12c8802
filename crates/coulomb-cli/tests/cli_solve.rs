//! `coulomb solve`: JSON fields, --output read back by `coulomb error`, and the existence
//! verdict printed beside a failure.

use crate::common;
use common::*;

use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    scratch_file("solve", name)
}

/// The crushed ball (Fig. 3) has no solution: the solve fails and says the model is at fault.
#[test]
fn failed_solve_reports_that_no_solution_exists() {
    let ball = tmp("crushed.hdf5");
    let made = coulomb(&[
        "example",
        "crushed-ball",
        "--output",
        ball.to_str().unwrap(),
    ]);
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let out = coulomb(&[
        "solve",
        ball.to_str().unwrap(),
        "--json",
        "--max-outer",
        "30",
    ]);
    // not converged: exit status 1
    assert_eq!(out.status.code(), Some(1));
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["converged"], false);
    assert_ne!(j["status"], "converged");
    assert_eq!(j["existence"]["conclusion"], "none");
    assert_eq!(j["existence"]["criteria"]["4.5"]["verdict"], "fails");
    let text = coulomb(&["solve", ball.to_str().unwrap(), "--max-outer", "30"]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("no solution can exist"), "{text}");
}

/// A Painlevé case with a solution: converged, and the written /solution passes `coulomb error`.
#[test]
fn solve_output_is_a_solution_for_coulomb_error() {
    let p = tmp("painleve.hdf5");
    painleve(&p, "30", "0.3", "-1");
    let out = tmp("painleve-solved.hdf5");
    let j = stdout_json(&coulomb(&[
        "solve",
        p.to_str().unwrap(),
        "--json",
        "--output",
        out.to_str().unwrap(),
    ]));
    for key in [
        "file",
        "status",
        "converged",
        "error",
        "outer_iterations",
        "inner_iterations",
        "solve_time_s",
    ] {
        assert!(j.get(key).is_some(), "missing {key}");
    }
    assert_eq!(j["converged"], true);
    assert!(j.get("existence").is_none());
    let e = stdout_json(&coulomb(&["error", out.to_str().unwrap(), "--json"]));
    assert!(e["error"].as_f64().unwrap() <= 1e-8);
    assert!(e["balance_residual"].as_f64().unwrap() <= 1e-8);
}

/// The README's tour on data/'s files: `info` lists each as data/README.md describes it,
/// `solve --output` converges on each and `error` confirms the written /solution (exit 0),
/// and `check` gives the documented conclusion with its exit status.
#[test]
fn data_files_info_solve_error_check_as_the_readme_shows() {
    // (file, kind, contacts, check's exit status: 0 a solution exists, 3 unknown)
    let files = [
        ("box-local.hdf5", "local", 147, 0),
        ("box-global.hdf5", "global", 147, 0),
        ("pile-nonsym-local.hdf5", "local", 64, 3),
        ("painleve.hdf5", "global", 1, 0),
    ];
    let paths: Vec<String> = files.iter().map(|f| data_file(f.0)).collect();
    let mut args = vec!["info", "--json"];
    args.extend(paths.iter().map(String::as_str));
    let info = stdout_json(&coulomb(&args));
    for ((name, kind, contacts, check_status), path) in files.into_iter().zip(&paths) {
        let i = info
            .as_array()
            .unwrap()
            .iter()
            .find(|i| i["file"] == path.as_str())
            .unwrap_or_else(|| panic!("{name} missing from {info}"));
        assert_eq!(
            (i["kind"].as_str(), i["contacts"].as_u64()),
            (Some(kind), Some(contacts))
        );
        let solved = tmp(&format!("solved-{name}"));
        let j = stdout_json(&coulomb(&[
            "solve",
            path,
            "--json",
            "--output",
            solved.to_str().unwrap(),
        ]));
        assert_eq!(j["converged"], true, "{name}: {j}");
        let e = coulomb(&["error", solved.to_str().unwrap(), "--worst", "3"]);
        assert_eq!(e.status.code(), Some(0), "{name}: error says yes");
        let c = coulomb(&["check", path]);
        assert_eq!(c.status.code(), Some(check_status), "{name}: check");
    }
}

/// `--explain` prints the structure and the plan; `--json` carries both: on the rigid pile of
/// data/ (a cold solve of a local W small enough for the skeleton probe) the plan has the
/// interior point and the multipliers between the warm-up and the main method.
#[test]
fn explain_prints_the_structure_and_the_plan_and_json_carries_them() {
    let file = data_file("pile-nonsym-local.hdf5");
    let out = coulomb(&["solve", &file, "--explain"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for expected in [
        "structure         local; d = 3, 64 contacts, m = 192; W not symmetric",
        "1. warm-up (pgs+fused)",
        "2. interior point",
        "3. multipliers",
        "4. main (apgd+anderson)",
        "5. fallback (pgs+fused)",
    ] {
        assert!(text.contains(expected), "{expected:?} not in\n{text}");
    }
    let j = stdout_json(&coulomb(&["solve", &file, "--json"]));
    let kinds: Vec<&str> = j["plan"]["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    assert_eq!(
        kinds,
        [
            "warmup",
            "interior_point",
            "multipliers",
            "main",
            "fallback"
        ]
    );
    assert_eq!(j["structure"]["contacts"], 64);
    assert_eq!(j["structure"]["symmetric"], false);
    assert_eq!(j["structure"]["rigid"], "skeleton_probe");
}

/// A ball of mass 2 pressed onto the floor, its x velocity held at 0.5 by two copies of the
/// same equality row (b = (−0.5, −0.5), consistent) or by two that disagree.
fn equality_ball(path: &std::path::Path, b: [f64; 2]) {
    use coulomb::{fclib, CscMatrix, GlobalProblem, Problem};
    let h = CscMatrix::from_dense(3, 3, &[0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0]);
    let g = CscMatrix::from_dense(3, 2, &[1.0, 1.0, 0.0, 0.0, 0.0, 0.0]);
    let p = GlobalProblem::new(
        3,
        CscMatrix::identity(3, 2.0),
        h,
        vec![2.0, 0.0, -2.0],
        vec![0.0; 3],
        vec![0.3],
    )
    .unwrap()
    .with_equality(g, b.to_vec())
    .unwrap();
    fclib::write(path, &fclib::FclibFile::new(Problem::Global(p))).unwrap();
}

#[test]
fn equality_constraints_through_info_solve_and_error() {
    let file = tmp("eq-ball.hdf5");
    equality_ball(&file, [-0.5, -0.5]);
    let f = file.to_str().unwrap();
    let info = stdout_json(&coulomb(&["info", "--json", f]));
    assert_eq!(info["equality_rows"], 2);
    let out = tmp("eq-ball-out.hdf5");
    let o = out.to_str().unwrap();
    let solved = coulomb(&["solve", f, "--json", "--output", o]);
    assert_eq!(solved.status.code(), Some(0));
    let j: serde_json::Value = serde_json::from_slice(&solved.stdout).unwrap();
    assert_eq!(j["status"], "converged");
    assert!(j["equality_residual"].as_f64().unwrap() <= 1e-8);
    // the written solution carries l and `coulomb error` recomputes every residual from it
    let sol = coulomb::fclib::read_solution(&out).unwrap().unwrap();
    let l = sol.l.unwrap();
    assert!(
        (l[0] + 0.2).abs() < 1e-7 && (l[1] + 0.2).abs() < 1e-7,
        "{l:?}"
    );
    let err = coulomb(&["error", o, "--json"]);
    assert_eq!(err.status.code(), Some(0));
    let e: serde_json::Value = serde_json::from_slice(&err.stdout).unwrap();
    assert_eq!(e["converged"], true);
    assert!(e["equality_residual"].as_f64().unwrap() <= 1e-8);
    // a plain problem has no equality_residual in its reports
    let plain = stdout_json(&coulomb(&[
        "solve",
        &data_file("box-global.hdf5"),
        "--json",
    ]));
    assert!(plain.get("equality_residual").is_none());

    // inconsistent rows: exit 1, status equality_residual, never converged
    let bad = tmp("eq-bad.hdf5");
    equality_ball(&bad, [-0.5, -0.4]);
    let solved = coulomb(&["solve", bad.to_str().unwrap(), "--json"]);
    assert_eq!(solved.status.code(), Some(1));
    let j: serde_json::Value = serde_json::from_slice(&solved.stdout).unwrap();
    assert_eq!(j["status"], "equality_residual");
    assert_eq!(j["converged"], false);
    assert_ne!(j["existence"]["conclusion"], "exists");
}
