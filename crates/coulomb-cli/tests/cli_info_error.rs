//! `coulomb info` and `coulomb error`, run as the built binary.

use crate::common;
use common::*;

use coulomb::fclib::{self, FclibFile, StoredSolution};
use coulomb::{CscMatrix, LocalProblem, Problem};
use serde_json::Value;

fn path(dir: &std::path::Path, name: &str) -> String {
    dir.join(format!("{name}.hdf5")).display().to_string()
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_cli_info_json_several_files_is_an_array() {
    let dir = fclib_dir();
    let a = path(&dir, "Capsules-i125-1213");
    let b = path(&dir, "Box_Stacks-i0122-82-5");
    let c = path(&dir, "LMGC_100_PR_PerioBox-i00361-60-03000");
    let v = stdout_json(&coulomb(&["info", "--json", &a, &b, &c]));
    let arr = v.as_array().expect("an array for several files");
    assert_eq!(arr.len(), 3);

    assert_eq!(arr[0]["file"], a.as_str());
    assert_eq!(arr[0]["kind"], "local");
    assert_eq!(arr[0]["dim"], 3);
    assert_eq!(arr[0]["contacts"], 286);
    assert_eq!(arr[0]["dofs"], Value::Null);
    assert_eq!(arr[0]["nnz"], 11772);
    assert_eq!(arr[0]["has_solution"], true);
    assert_eq!(arr[0]["guesses"], 1);
    // W is not symmetric in the file, and is reported (and used) as stored
    assert!((arr[0]["asymmetry"].as_f64().unwrap() - 1.337e-3).abs() < 1e-5);

    assert_eq!(arr[1]["kind"], "global");
    assert_eq!(arr[1]["contacts"], 82);
    assert_eq!(arr[1]["dofs"], 450);
    // nnz of M (450, diagonal) plus nnz of H (1284 triplets).
    assert_eq!(arr[1]["nnz"], 450 + 1284);
    assert_eq!(arr[1]["mu_min"], 0.3);
    assert_eq!(arr[1]["asymmetry"], 0.0);

    assert_eq!(arr[2]["contacts"], 60);
    let (lo, hi) = (
        arr[2]["mu_min"].as_f64().unwrap(),
        arr[2]["mu_max"].as_f64().unwrap(),
    );
    assert!(lo >= 0.3 && hi <= 0.5 && lo < hi);
    assert_eq!(arr[2]["has_solution"], false);

    // One file: a single object.
    let one = stdout_json(&coulomb(&["info", "--json", &c]));
    assert!(one.is_object());
    assert_eq!(one["contacts"], 60);

    // Human table mentions every file.
    let out = coulomb(&["info", &a, &b]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("Capsules-i125-1213.hdf5") && text.contains("Box_Stacks"));
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_cli_error_reproduces_documented_values() {
    let dir = fclib_dir();
    // the answer is "no": exit status 1, JSON on stdout all the same
    let out = coulomb(&["error", "--json", &path(&dir, "Capsules-i125-1213")]);
    assert_eq!(out.status.code(), Some(1));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let e = v["error"].as_f64().unwrap();
    assert!((e / 1.58e-2 - 1.0).abs() < 0.01, "{v}");
    assert_eq!(v["balance_residual"], Value::Null);
    assert_eq!(v["converged"], false);
    assert_eq!(v["kind"], "local");

    let out = coulomb(&["error", "--json", &path(&dir, "Box_Stacks-i0122-82-5")]);
    assert_eq!(out.status.code(), Some(1));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["error"].as_f64().unwrap(), 0.0, "{v}");
    let b = v["balance_residual"].as_f64().unwrap();
    assert!((b / 3.97e-2 - 1.0).abs() < 0.01, "{v}");
    assert_eq!(v["converged"], false);

    let out = coulomb(&["error", &path(&dir, "Capsules-i125-1213")]);
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("1.580e-2") && text.contains("solution at 1e-8: no"),
        "{text}"
    );
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_cli_error_missing_solution_and_bad_file() {
    let dir = fclib_dir();
    let out = coulomb(&["error", &path(&dir, "Rover4396")]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no /solution") && err.contains("Rover4396"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");

    let tmp = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("coulomb-cli-bad-{}.hdf5", std::process::id()));
    std::fs::write(&tmp, b"not hdf5").unwrap();
    let t = tmp.display().to_string();
    for args in [vec!["info", &t], vec!["error", &t]] {
        let out = coulomb(&args);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("not an HDF5 file") && err.contains(&t),
            "{err}"
        );
    }
    let out = coulomb(&["info", "--json", &t, &path(&dir, "Rover4396")]);
    assert!(
        !out.status.success(),
        "a failed file makes the command fail"
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v[0]["error"].as_str().unwrap().contains("not an HDF5 file"));
    assert_eq!(v[1]["contacts"], 2);
    let _ = std::fs::remove_file(tmp);
}

/// The local problem (W = I, q, μ) in 3-D.
fn unit_delassus(q: Vec<f64>, mu: Vec<f64>) -> Problem {
    let m = q.len();
    Problem::Local(LocalProblem::new(3, CscMatrix::identity(m, 1.0), q, mu).unwrap())
}

#[test]
fn cli_error_with_solution_file() {
    // W = I, q = (1, 0, 0): take-off, r = 0, u = q is the exact solution.
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("coulomb-cli-sol-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let problem = unit_delassus(vec![1.0, 0.0, 0.0], vec![0.5]);
    let prob_path = dir.join("p.hdf5");
    fclib::write(&prob_path, &FclibFile::new(problem.clone())).unwrap();
    let mut with_sol = FclibFile::new(problem);
    with_sol.solution = Some(StoredSolution {
        r: vec![0.0; 3],
        ..Default::default()
    });
    let sol_path = dir.join("sol.hdf5");
    fclib::write(&sol_path, &with_sol).unwrap();
    let p = prob_path.display().to_string();
    let s = sol_path.display().to_string();
    let v = stdout_json(&coulomb(&["error", "--json", &p, "--solution", &s]));
    assert_eq!(v["error"].as_f64().unwrap(), 0.0);
    assert_eq!(v["converged"], true);
    assert_eq!(v["solution_file"], s.as_str());
    // A solution file without /solution is a clear error.
    let out = coulomb(&["error", &p, "--solution", &p]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no /solution"));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn cli_error_worst_lists_the_contacts_that_carry_the_error() {
    // W = I, q = (1, 0, 0, −1, 0, 0), μ = 0.5; r = (0, 0, 0, 0.5, 0, 0): contact 0 takes off
    // exactly (u = q), contact 1 is pushed too little: u = (−0.5, 0, 0), ũ = u, r − ũ =
    // (1, 0, 0) ∈ K, e₁ = r − (1, 0, 0) = (−0.5, 0, 0); scale = max(‖q‖, ‖r‖, ‖u‖) = √2.
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("coulomb-cli-worst-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let problem = unit_delassus(vec![1.0, 0.0, 0.0, -1.0, 0.0, 0.0], vec![0.5, 0.5]);
    let mut file = FclibFile::new(problem);
    file.solution = Some(StoredSolution {
        r: vec![0.0, 0.0, 0.0, 0.5, 0.0, 0.0],
        ..Default::default()
    });
    let path = dir.join("p.hdf5");
    fclib::write(&path, &file).unwrap();
    let p = path.display().to_string();
    // not a solution: exit status 1, the report on stdout all the same
    let json = |args: &[&str]| -> Value {
        let out = coulomb(args);
        assert_eq!(out.status.code(), Some(1), "not a solution at 1e-8");
        serde_json::from_slice(&out.stdout).expect("valid JSON on stdout")
    };
    let v = json(&["error", "--json", "--worst", "5", &p]);
    let expected = 0.5 / 2f64.sqrt();
    assert!((v["error"].as_f64().unwrap() - expected).abs() < 1e-15);
    let worst = v["worst_contacts"].as_array().expect("worst_contacts");
    assert_eq!(worst.len(), 2, "only two contacts exist");
    assert_eq!(worst[0]["contact"], 1);
    assert!((worst[0]["error"].as_f64().unwrap() - expected).abs() < 1e-15);
    assert_eq!(worst[0]["share"].as_f64().unwrap(), 1.0);
    assert_eq!(worst[0]["r_n"].as_f64().unwrap(), 0.5);
    assert_eq!(worst[0]["u_n"].as_f64().unwrap(), -0.5);
    assert_eq!(worst[1]["contact"], 0);
    assert_eq!(worst[1]["error"].as_f64().unwrap(), 0.0);
    assert_eq!(worst[1]["u_n"].as_f64().unwrap(), 1.0);
    // without --worst the list is absent; the text form names the worst contact
    let plain = json(&["error", "--json", &p]);
    assert!(plain.get("worst_contacts").is_none());
    let out = coulomb(&["error", "--worst", "1", &p]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("worst contacts"), "{text}");
    assert_eq!(out.status.code(), Some(1), "not a solution at 1e-8");
    let _ = std::fs::remove_dir_all(dir);
}
