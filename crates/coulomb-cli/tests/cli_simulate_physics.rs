//! `coulomb simulate` physics defaults and `coulomb validate`, on tiny sizes.

use crate::common;
use common::*;

#[test]
fn simulate_reports_end_penetrations_and_unconverged_steps() {
    let out = coulomb(&[
        "simulate", "box", "--beads", "20", "--steps", "40", "--json",
    ]);
    let v = stdout_json(&out);
    for key in [
        "end_mean_penetration",
        "end_max_penetration",
        "not_converged_steps",
        "projection_work",
        "start_energy",
        "end_energy",
    ] {
        assert!(v[key].is_number(), "{key} missing in {v}");
    }
    // every step solved to 1e-4 by default
    assert_eq!(v["not_converged_steps"].as_u64(), Some(0), "{v}");
    assert!(v["max_error"].as_f64().unwrap() <= 1e-4, "{v}");
    // position correction on: penetrations at the end below 1 % of R = 5 cm
    assert!(v["end_max_penetration"].as_f64().unwrap() <= 5e-4, "{v}");
}

#[test]
fn simulate_elastic_frictionless_box_does_not_gain_energy() {
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "30",
        "--steps",
        "300",
        "--restitution",
        "1",
        "--mu",
        "0",
        "--no-projection",
        "--json",
    ]);
    let v = stdout_json(&out);
    let (e0, e1) = (
        v["start_energy"].as_f64().unwrap(),
        v["end_energy"].as_f64().unwrap(),
    );
    assert!((e1 - e0).abs() <= 5e-3 * e0.abs(), "{e0} → {e1}");
}

/// `--projection-velocities` runs each variant (the same `Velocities` as the scene files'
/// `[step] projection_velocities`), and is refused (exit 2) with `--no-projection`.
#[test]
fn simulate_chooses_what_the_correction_does_to_velocities() {
    for v in ["rescale", "positions-only", "inelastic"] {
        let out = coulomb(&[
            "simulate",
            "box",
            "--beads",
            "20",
            "--steps",
            "40",
            "--projection-velocities",
            v,
            "--json",
        ]);
        let j = stdout_json(&out);
        assert_eq!(j["not_converged_steps"].as_u64(), Some(0), "{v}: {j}");
        assert!(
            j["end_max_penetration"].as_f64().unwrap() <= 5e-4,
            "{v}: {j}"
        );
    }
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "5",
        "--no-projection",
        "--projection-velocities",
        "inelastic",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--projection-velocities"), "{err}");
}

#[test]
fn simulate_refuses_a_time_step_too_large_for_contact_detection() {
    let out = coulomb(&["simulate", "box", "--beads", "5", "--dt", "10"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--dt 10 is too large"), "{err}");
    let out = coulomb(&[
        "simulate", "box", "--beads", "5", "--steps", "2", "--dt", "0.03",
    ]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning: --dt 0.03"));
}

#[test]
fn simulate_refuses_a_coarse_space_without_the_coarse_correction() {
    // --coarse-cell and --coarse-smooth shape the correction of --coarse-every: refused,
    // not dropped, when it is off
    for opt in ["--coarse-cell", "--coarse-smooth"] {
        let out = coulomb(&["simulate", "box", "--beads", "5", "--steps", "2", opt, "2"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(opt) && err.contains("--coarse-every"), "{err}");
    }
    let dir = temp_dir("sim-coarse-cells");
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "40",
        "--steps",
        "15",
        "--coarse-every",
        "5",
        "--coarse-cell",
        "2",
        "--coarse-smooth",
        "1",
        "--frames-every",
        "0",
        "--json",
        "--output",
        dir.to_str().unwrap(),
    ]);
    ok(&out);
    let j = stdout_json(&out);
    assert_eq!(j["steps"], 15, "{j}");
    assert_eq!(j["not_converged_steps"].as_u64(), Some(0), "{j}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn simulate_writes_the_last_frame_between_two_frame_steps() {
    let dir = temp_dir("sim-last-frame");
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "8",
        "--steps",
        "13",
        "--frames-every",
        "5",
        "--output",
        dir.to_str().unwrap(),
    ]);
    ok(&out);
    for k in [0, 5, 10, 13] {
        let f = dir.join(format!("frames/bodies_{k:06}.vtp"));
        assert!(f.is_file(), "{} missing", f.display());
    }
    let pvd = std::fs::read_to_string(dir.join("bodies.pvd")).unwrap();
    assert!(pvd.contains("bodies_000013.vtp"));
}

#[test]
fn validate_quick_passes_and_writes_markdown() {
    let md = scratch_file("validate", "validation.md");
    let out = coulomb(&["validate", "--quick", "--markdown", md.to_str().unwrap()]);
    ok(&out);
    let text = std::fs::read_to_string(&md).unwrap();
    assert!(text.contains("| incline 30° μ = 0.3 rolling: acceleration |"));
    // the granular laws built from scene files: the incline only in quick mode
    assert!(text.contains("## Granular laws: incline (scene file)"));
    assert!(text.contains("examples/scenes/validation/incline.toml: glass ball"));
    assert!(!text.contains("Janssen"));
    assert!(!text.contains("**no**"), "{text}");
}

#[test]
fn simulate_with_rolling_friction_comes_to_rest() {
    // without rolling resistance spheres on a monolayer never stop rolling (#17 §4)
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "30",
        "--until-rest",
        "--max-steps",
        "400",
        "--rolling-friction",
        "0.2",
        "--json",
    ]);
    let v = stdout_json(&out);
    assert_eq!(v["at_rest"].as_bool(), Some(true), "{v}");
    assert_eq!(v["not_converged_steps"].as_u64(), Some(0), "{v}");
    assert!(v["max_error"].as_f64().unwrap() <= 1e-4, "{v}");
    let out = coulomb(&["simulate", "box", "--rolling-friction", "-1"]);
    assert!(!out.status.success());
}
