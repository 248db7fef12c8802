//! `coulomb example …` writes the paper's examples; `coulomb check` reads them back and
//! reports the criteria (JSON format of the README).

use crate::common;
use common::*;

use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    scratch_file("check", name)
}

/// `check --json`; the exit status follows the conclusion (0 exists, 1 none, 3 unknown).
fn check_json(path: &Path) -> serde_json::Value {
    let out = coulomb(&["check", path.to_str().unwrap(), "--json"]);
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!("{e}: {}", String::from_utf8_lossy(&out.stderr));
    });
    let want = match j["conclusion"].as_str() {
        Some("exists") => 0,
        Some("none") => 1,
        _ => 3,
    };
    assert_eq!(out.status.code(), Some(want), "{j}");
    j
}

#[test]
fn painleve_round_trip_matches_2_13() {
    // (θ in degrees, μ, u0): (4.4) ⇔ u0 ≤ 0 or tan θ > μ.
    for (theta, mu, u0, holds) in [
        ("30", "0.3", "1", true),
        ("20", "0.6", "1", false),
        ("20", "0.6", "-0.5", true),
        ("20", "0.6", "0", true),
    ] {
        let out_file = tmp(&format!("painleve-{theta}-{mu}-{u0}.hdf5"));
        painleve(&out_file, theta, mu, u0);
        let j = check_json(&out_file);
        assert_eq!(j["file"], out_file.to_str().unwrap());
        let want = if holds { "holds" } else { "fails" };
        assert_eq!(
            j["criteria"]["4.4"]["verdict"], want,
            "θ={theta} μ={mu} u0={u0}"
        );
        assert!(j["criteria"]["4.4"]["certificate_residual"].is_number());
        for key in ["4.1", "4.4", "4.5", "4.6", "5.1"] {
            assert!(j["criteria"][key]["verdict"].is_string(), "{key}");
        }
        let conclusion = if holds { "exists" } else { "unknown" };
        assert_eq!(j["conclusion"], conclusion);
    }
}

#[test]
fn crushed_ball_is_none_and_rectangle_satisfies_5_1() {
    let ball = tmp("crushed.hdf5");
    let out = coulomb(&[
        "example",
        "crushed-ball",
        "--output",
        ball.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j = check_json(&ball);
    assert_eq!(j["conclusion"], "none");
    assert_eq!(j["criteria"]["4.5"]["verdict"], "fails");
    assert!(
        j["criteria"]["4.5"]["certificate_residual"]
            .as_f64()
            .unwrap()
            <= 1e-9
    );

    let rect = tmp("rectangle.hdf5");
    let out = coulomb(&["example", "rectangle", "--output", rect.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j = check_json(&rect);
    assert_eq!(j["criteria"]["5.1"]["verdict"], "holds");
    assert_eq!(j["conclusion"], "exists");

    let obst = tmp("obstacle.hdf5");
    let out = coulomb(&[
        "example",
        "moving-obstacle",
        "--vx",
        "0.5",
        "--omega",
        "-0.2",
        "--output",
        obst.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j = check_json(&obst);
    assert_eq!(j["criteria"]["4.4"]["verdict"], "holds");

    // The table form names the conclusion too.
    let out = coulomb(&["check", ball.to_str().unwrap()]);
    assert_eq!(
        out.status.code(),
        Some(1),
        "no solution exists: exit status 1"
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("NO solution exists"));
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let out = coulomb(&["check", "/nonexistent/file.hdf5"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent/file.hdf5"), "{err}");
    assert!(!err.contains("panicked"));

    let garbage = tmp("garbage.hdf5");
    std::fs::write(&garbage, b"not an hdf5 file").unwrap();
    let out = coulomb(&["check", garbage.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));

    let f = tmp("bad.hdf5");
    for args in [
        vec![
            "example", "painleve", "--theta", "95", "--mu", "0.3", "--u0", "1",
        ],
        vec![
            "example", "painleve", "--theta", "30", "--mu", "-1", "--u0", "1",
        ],
        vec!["example", "crushed-ball", "--mu", "nan"],
    ] {
        let mut a = args.clone();
        a.extend(["--output", f.to_str().unwrap()]);
        let out = coulomb(&a);
        assert!(!out.status.success(), "{args:?}");
        assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
    }
}

#[test]
fn a_check_past_its_time_limit_is_inconclusive() {
    // the whole check runs under --time-limit: past it the conclusion is "unknown" (exit
    // status 3) and says why; within it the same file gets its verdict
    let file = tmp("painleve-time-limit.hdf5");
    painleve(&file, "30", "0.3", "1");
    let f = file.to_str().unwrap();
    let out = coulomb(&["check", f, "--json", "--time-limit", "0.000001"]);
    assert_eq!(out.status.code(), Some(3));
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["conclusion"], "unknown");
    assert!(
        j["skipped"].as_str().unwrap().contains("did not finish"),
        "{j}"
    );
    let out = coulomb(&["check", f, "--time-limit", "0.000001"]);
    assert_eq!(out.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&out.stdout).contains("UNKNOWN"));
    assert_eq!(check_json(&file)["conclusion"], "exists");
    for bad in ["0", "-1", "nan"] {
        let out = coulomb(&["check", f, "--time-limit", bad]);
        assert_eq!(out.status.code(), Some(2), "--time-limit {bad}");
    }
}
