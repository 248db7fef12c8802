//! `coulomb solve`: JSON fields, --output read back by `coulomb error`, and the existence
//! verdict printed beside a failure.

mod common;
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
