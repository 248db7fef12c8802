//! `coulomb bench`, run as the built binary.

use crate::common;
use common::*;

use serde_json::Value;

fn records(report: &Value) -> &Vec<Value> {
    report["records"].as_array().expect("records is an array")
}

#[test]
fn cli_bench_two_files_two_solvers_json_and_svg() {
    let out_dir = temp_dir("bench-two");
    let json = out_dir.join("b.json");
    let svg = out_dir.join("b.svg");
    let a = data_file("box-local.hdf5");
    let b = data_file("painleve.hdf5");
    let out = coulomb(&[
        "bench",
        &a,
        &b,
        "--solvers",
        "pgs,apgd+anderson",
        "--tol",
        "1e-8",
        "--time-limit",
        "20",
        "--repeat",
        "2",
        "--json",
        &json.display().to_string(),
        "--svg",
        &svg.display().to_string(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "stdout: {stdout}\nstderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // the terminal table names every problem and solver
    for name in ["box-local", "painleve", "pgs", "apgd+anderson"] {
        assert!(stdout.contains(name), "{name} missing from\n{stdout}");
    }

    let report = read_json(&json);
    assert_eq!(report["tol"].as_f64(), Some(1e-8));
    assert_eq!(report["repeat"].as_u64(), Some(2));
    assert!(report["command"].as_str().unwrap().contains("bench"));
    assert!(report["machine"].is_object());
    let recs = records(&report);
    assert_eq!(recs.len(), 4, "one record per (problem, solver) pair");
    for (problem, kind) in [("box-local", "local"), ("painleve", "global")] {
        for solver in ["pgs", "apgd+anderson"] {
            let r = recs
                .iter()
                .find(|r| r["problem"] == problem && r["solver"] == solver)
                .unwrap_or_else(|| panic!("pair ({problem}, {solver}) missing"));
            for key in [
                "problem",
                "contacts",
                "solver",
                "status",
                "converged",
                "error",
                "time_s",
                "outer_iterations",
                "inner_iterations",
            ] {
                assert!(r.get(key).is_some(), "{key} missing in {r}");
            }
            assert_eq!(r["kind"], kind);
            assert!(r["contacts"].as_u64().unwrap() >= 1);
            let time = r["time_s"].as_f64().expect("a solve ran");
            assert!(time >= 0.0);
            if r["converged"].as_bool().unwrap() {
                // solved means: converged status, error ≤ tol, both repeats run
                assert_eq!(r["status"], "converged");
                assert!(r["error"].as_f64().unwrap() <= 1e-8);
                assert_eq!(r["runs"].as_u64(), Some(2));
                assert!(time <= 20.0);
            } else {
                assert_ne!(r["status"], "converged");
            }
        }
    }
    assert_eq!(
        recs.iter()
            .find(|r| r["problem"] == "box-local")
            .and_then(|r| r["contacts"].as_u64()),
        Some(147)
    );
    let profile = report["profile"].as_array().expect("profile summary");
    assert_eq!(profile.len(), 2);
    for p in profile {
        let solved = p["solved"].as_u64().unwrap();
        let expected = recs
            .iter()
            .filter(|r| r["solver"] == p["solver"] && r["converged"] == true)
            .count() as u64;
        assert_eq!(solved, expected);
        assert_eq!(p["rho_max"].as_f64().unwrap(), solved as f64 / 2.0);
    }

    let svg_text = std::fs::read_to_string(&svg).expect("the SVG file was written");
    assert!(svg_text.trim_start().starts_with("<svg"), "not an SVG");
    assert!(svg_text.contains("<polyline") || svg_text.contains("<path"));
    assert!(svg_text.contains("pgs") && svg_text.contains("apgd+anderson"));
    assert!(svg_text.trim_end().ends_with("</svg>"));
    let _ = std::fs::remove_dir_all(&out_dir);
}

#[test]
fn cli_bench_unreadable_file_is_a_failed_record_not_a_crash() {
    let dir = temp_dir("bench-bad");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::write(dir.join("sub/garbage.hdf5"), b"not an hdf5 file").unwrap();
    std::fs::write(dir.join("readme.txt"), b"ignored").unwrap();
    let json = dir.join("out.json");
    let out = coulomb(&[
        "bench",
        &dir.display().to_string(),
        "--solvers",
        "ipm,faceted+anderson",
        "--json",
        &json.display().to_string(),
    ]);
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = read_json(&json);
    let recs = records(&report);
    assert_eq!(recs.len(), 2, "the .txt file is not benchmarked");
    for r in recs {
        assert_eq!(r["problem"], "garbage");
        assert_eq!(r["status"], "read_error");
        assert_eq!(r["converged"], false);
        assert!(r["time_s"].is_null());
        assert!(!r["message"].as_str().unwrap().is_empty());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_bench_bad_arguments_are_reported() {
    let dir = temp_dir("bench-args");
    let missing = dir.join("missing.hdf5");
    let cases: [(&[&str], &str); 4] = [
        (&["--solvers", "newton"], "unknown solver"),
        (&["--tol=-1"], "--tol"),
        (&["--time-limit", "0"], "--time-limit"),
        (&["--repeat", "0"], "--repeat"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["bench", "."];
        args.extend_from_slice(extra);
        let out = coulomb(&args);
        // exit status 2: bad input or usage (README, `coulomb --help`)
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    let out = coulomb(&["bench", &missing.display().to_string()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.hdf5"));
    // an empty directory holds nothing to run
    let out = coulomb(&["bench", &dir.display().to_string()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no FCLIB file"));
    let _ = std::fs::remove_dir_all(&dir);
}
