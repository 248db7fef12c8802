//! `coulomb simulate SCENE.toml` with bodies of other shapes (issue 41): the shipped incline
//! runs in the rigid-body simulator with VTK frames of the bodies as polygons, stats and the
//! steps' problems in FCLIB; a non-unit quaternion or a degenerate hull exits with status 2
//! naming the file, line and key; a run with `--checkpoint-every` continued by `--restart`
//! ends in the state of the uninterrupted run to the bit; URDF robots run, bad ones exit 2.

use crate::common;
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
    // one writer (issue 52): the block as its polygons in part 1, no ball in part 0
    let body = std::fs::read(out.join("frames/shapes_000020.vtp")).unwrap();
    assert!(String::from_utf8_lossy(&body).contains("NumberOfPolys=\"6\""));
    let balls = std::fs::read(out.join("frames/bodies_000020.vtp")).unwrap();
    assert!(String::from_utf8_lossy(&balls).contains("NumberOfPoints=\"0\""));
    assert!(fc.join("step_000019.hdf5").exists());
    // one statistics schema (issue 52): the rigid run's stats.csv has the columns of a sphere
    // run's, 12 fields a row, status and energies filled
    let spheres = dir.join("spheres");
    ok(&coulomb(&[
        "simulate",
        "box",
        "--beads",
        "10",
        "--steps",
        "2",
        "--output",
        spheres.to_str().unwrap(),
    ]));
    let header = |d: &std::path::Path| {
        std::fs::read_to_string(d.join("stats.csv"))
            .unwrap()
            .lines()
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(header(&out), header(&spheres));
    assert_eq!(header(&out), coulomb_granular::report::CSV_HEADER);
    // one frames file name for every scene (issue 52): bodies.pvd, frames/bodies_*.vtp
    for d in [&out, &spheres] {
        assert!(d.join("bodies.pvd").is_file() && !d.join("beads.pvd").exists());
    }
    assert!(spheres.join("frames/bodies_000002.vtp").is_file());
    let glyphs = std::fs::read(spheres.join("frames/bodies_000002.vtp")).unwrap();
    assert!(
        String::from_utf8_lossy(&glyphs).contains("Name=\"radius\""),
        "spheres as points with a radius array"
    );
    let rigid = std::fs::read_to_string(out.join("stats.csv")).unwrap();
    let last: Vec<&str> = rigid.lines().last().unwrap().split(',').collect();
    assert_eq!(last.len(), 12, "{last:?}");
    assert_eq!((last[0], last[2], last[3]), ("19", "converged", "true"));
    // the potential energy of the body on the incline: finite and not 0
    let pe: f64 = last[10].parse().unwrap();
    assert!(pe.is_finite() && pe != 0.0, "{pe}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// One summary for every scene (issue 52): a rigid scene and a sphere scene, run by the one
/// run loop, write `summary.json` with the same keys, their engine named under `details`, and
/// print the same keys with `--json`; their `stats.json` rows have the same keys too.
#[test]
fn a_rigid_and_a_sphere_run_write_the_same_summary_and_stats_keys() {
    let dir = temp_dir("rigid-same-keys");
    let (rigid, spheres) = (dir.join("rigid"), dir.join("spheres"));
    let rigid_json = ok(&coulomb(&[
        "simulate",
        &scene("incline.toml"),
        "--steps",
        "3",
        "--json",
        "--output",
        rigid.to_str().unwrap(),
    ]));
    let spheres_json = ok(&coulomb(&[
        "simulate",
        "box",
        "--beads",
        "10",
        "--steps",
        "3",
        "--json",
        "--output",
        spheres.to_str().unwrap(),
    ]));
    let keys = |v: &serde_json::Value| -> Vec<String> {
        let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
        k.sort();
        k
    };
    let read = |d: &std::path::Path, f: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join(f)).unwrap()).unwrap()
    };
    let (sr, ss) = (read(&rigid, "summary.json"), read(&spheres, "summary.json"));
    assert_eq!(keys(&sr), keys(&ss), "{sr}\n{ss}");
    for key in [
        "bodies",
        "time",
        "mean_iterations",
        "mean_solve_seconds",
        "kinetic_energy",
    ] {
        assert!(
            sr[key].is_number() && ss[key].is_number(),
            "{key}: {sr}\n{ss}"
        );
    }
    assert!(sr.get("beads").is_none() && ss.get("mean_solve_ms").is_none());
    assert_eq!(
        (sr["bodies"].as_u64(), ss["bodies"].as_u64()),
        (Some(1), Some(10))
    );
    assert_eq!(sr["steps"], 3);
    assert_eq!(ss["steps"], 3);
    assert_eq!(sr["details"]["engine"], "rigid");
    assert_eq!(ss["details"]["engine"], "spheres");
    assert!(
        sr["details"]["mean_loaded_contacts"].as_f64().unwrap() >= 3.0,
        "{sr}"
    );
    assert!(ss["details"]["mean_subproblems"].is_number(), "{ss}");
    // what the rigid engine does not measure is null, not a made-up 0
    assert!(sr["end_max_penetration"].is_null() && sr["projection_work"].is_null());
    assert!(ss["end_max_penetration"].is_number() && ss["projection_work"].is_number());
    // --json: the summary's keys and the energies at the start and the end
    let (jr, js): (serde_json::Value, serde_json::Value) = (
        serde_json::from_str(rigid_json.trim()).unwrap(),
        serde_json::from_str(spheres_json.trim()).unwrap(),
    );
    assert_eq!(keys(&jr), keys(&js));
    let mut with_energies = keys(&sr);
    with_energies.extend(["end_energy".to_string(), "start_energy".to_string()]);
    with_energies.sort();
    assert_eq!(keys(&jr), with_energies);
    assert_eq!(jr["mean_contacts"], sr["mean_contacts"]);
    // stats.json: the same row keys for every scene (the stats.csv columns and "details", the
    // engine's own report without the keys the record has)
    let (tr, ts) = (read(&rigid, "stats.json"), read(&spheres, "stats.json"));
    let (tr, ts) = (tr.as_array().unwrap(), ts.as_array().unwrap());
    assert_eq!((tr.len(), ts.len()), (3, 3));
    let mut columns: Vec<String> = coulomb_granular::report::CSV_HEADER
        .split(',')
        .map(String::from)
        .chain(["details".to_string()])
        .collect();
    columns.sort();
    for row in tr.iter().chain(ts) {
        assert_eq!(keys(row), columns, "{row}");
        assert!(row["details"].get("contacts").is_none(), "{row}");
    }
    assert!(tr[2]["details"]["loaded_contacts"].is_number(), "{}", tr[2]);
    assert!(ts[2]["details"]["subproblems"].is_number(), "{}", ts[2]);
    let _ = std::fs::remove_dir_all(&dir);
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

/// The columns of a rigid stats.csv that do not depend on the clock (all but `solve_seconds`,
/// `coulomb_granular::report::CLOCK_COLUMN`), row by row.
fn rigid_stats(dir: &std::path::Path) -> Vec<String> {
    let csv = std::fs::read_to_string(dir.join("stats.csv")).unwrap();
    csv.lines()
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(i, _)| *i != 8)
                .map(|(_, x)| x)
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect()
}

#[test]
fn a_rigid_run_restarts_to_the_bit() {
    let root = temp_dir("rigid-restart");
    let (a, c) = (root.join("a"), root.join("c"));
    let run = |extra: &[&str], out: &std::path::Path| {
        let mut args = vec!["simulate"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&[
            "--frames-every",
            "3",
            "--checkpoint-every",
            "3",
            "--output",
            out.to_str().unwrap(),
        ]);
        ok(&coulomb(&args));
    };
    let wall = scene("wall-impact.toml");
    run(&[&wall, "--steps", "6"], &a);
    run(&[&wall, "--steps", "12"], &c);
    let ckpt = a.join("checkpoint.h5");
    // without the scene file, then with it (its inlets, none here, would continue)
    run(&["--restart", ckpt.to_str().unwrap(), "--steps", "3"], &a);
    run(
        &[&wall, "--restart", ckpt.to_str().unwrap(), "--steps", "3"],
        &a,
    );
    let read = |p: &std::path::Path| std::fs::read(p).unwrap();
    assert_eq!(read(&ckpt), read(&c.join("checkpoint.h5")));
    for f in [
        "frames/bodies_000012.vtp",
        "frames/shapes_000012.vtp",
        "frames/contacts_000012.vtp",
        "bodies.pvd",
    ] {
        assert_eq!(read(&a.join(f)), read(&c.join(f)), "{f}");
    }
    assert_eq!(rigid_stats(&a), rigid_stats(&c));
    assert_eq!(rigid_stats(&a).len(), 13);
    // another scene file is refused
    let o = coulomb(&[
        "simulate",
        &scene("incline.toml"),
        "--restart",
        ckpt.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not the scene of the checkpoint"));
    // and so is the same scene with other `[step]` switches (the checkpoint stores them),
    // not a copy of it
    let (same, cold) = (root.join("same.toml"), root.join("cold.toml"));
    let text = std::fs::read_to_string(&wall).unwrap();
    std::fs::write(&same, &text).unwrap();
    ok(&coulomb(&[
        "simulate",
        same.to_str().unwrap(),
        "--restart",
        ckpt.to_str().unwrap(),
        "--steps",
        "1",
    ]));
    std::fs::write(
        &cold,
        text.replacen("[step]", "[step]\nwarm_start = false", 1),
    )
    .unwrap();
    let o = coulomb(&[
        "simulate",
        cold.to_str().unwrap(),
        "--restart",
        ckpt.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not the scene of the checkpoint"));
}

/// Issues 52 (item 3) and 55 (item 6): a rigid scene with h = 100 s, a cube thrown at
/// 1e8 m/s, rolling friction between the cube and the floor (no ball), γ > 1 or
/// `projection_velocities = "rescale"` exits 2 naming the setting (before: h = 100 and the
/// cube ran to the end with every step "converged", exit 0; the settings were dropped).
#[test]
fn unsafe_steps_and_unhonoured_settings_exit_2() {
    let dir = temp_dir("rigid-unsafe");
    let cube = |step: &str, pair: &str, velocity: &str| {
        format!(
            "[step]\nsteps = 5\n{step}\n[default_pair]\nmu = 0.5\n{pair}\n\
             [[obstacles]]\nname = \"floor\"\nshape = {{ kind = \"plane\", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\n\
             [[bodies]]\ndensity = 1000\nshape = {{ kind = \"cuboid\", half_extents = [0.1, 0.1, 0.1] }}\npositions = [[0.0, 0.0, 0.1]]\nvelocity = {velocity}\n"
        )
    };
    for (text, words) in [
        (cube("h = 100.0", "", "[0.0, 0.0, 0.0]"), "h = 100"),
        (cube("h = 0.001", "", "[0.0, 0.0, -1e8]"), "travels"),
        (
            cube("h = 0.001", "rolling_friction = 0.5", "[0.0, 0.0, 0.0]"),
            "rolling_friction = 0.5",
        ),
        (
            cube("h = 0.001\ngamma = 2.0", "", "[0.0, 0.0, 0.0]"),
            "gamma = 2",
        ),
        (
            cube(
                "h = 0.001\nprojection_velocities = \"rescale\"",
                "",
                "[0.0, 0.0, 0.0]",
            ),
            "projection_velocities = \"rescale\"",
        ),
    ] {
        let path = dir.join("cube.toml");
        std::fs::write(&path, &text).unwrap();
        let o = coulomb(&["simulate", path.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{text}\n{err}");
        assert!(err.contains(words), "{err}");
    }
    // the same cube at rest with h = 1e-3 runs, with the `[step]` switches too (issue 52,
    // item 3: they apply to every scene)
    let path = dir.join("cube.toml");
    for step in [
        "h = 0.001",
        "h = 0.001\ngamma = 0.5\nprojection = false\ngap_closure = false\nwarm_start = false\nmethod = \"library\"",
    ] {
        std::fs::write(&path, cube(step, "", "[0.0, 0.0, 0.0]")).unwrap();
        ok(&coulomb(&["simulate", path.to_str().unwrap()]));
    }
}

/// A scene file with a bad joint exits 2 naming the joint and the field (issue 53); a good
/// one of spheres only runs in the rigid-body simulator.
#[test]
fn bad_joints_exit_2_and_a_sphere_pendulum_runs() {
    let dir = temp_dir("rigid-joints");
    let text = |axis: &str| {
        format!(
            "[step]\nh = 0.001\nsteps = 5\ntol = 1e-8\n\
             [[bodies]]\nspheres = [[0.0, 0.0, -0.5, 0.05]]\n\
             [[joints]]\nkind = \"revolute\"\nbody_a = 0\nanchor = [0.0, 0.0, 0.0]\naxis = {axis}\n"
        )
    };
    let path = dir.join("pendulum.toml");
    std::fs::write(&path, text("[0.0, 0.0, 0.0]")).unwrap();
    let o = coulomb(&["simulate", path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("joint 0: axis"), "{err}");
    std::fs::write(&path, text("[0.0, 1.0, 0.0]")).unwrap();
    let out = dir.join("out");
    let fc = dir.join("fc");
    let o = coulomb(&[
        "simulate",
        path.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
        "--dump-fclib",
        fc.to_str().unwrap(),
    ]);
    ok(&o);
    // each step's problem, with the joint's equality rows, is written
    let dumped = std::fs::read_dir(&fc).unwrap().count();
    assert!(dumped >= 1, "{dumped}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 53, URDF import: the shipped URDF double pendulum runs; a scene whose `[[urdf]]`
/// names a missing file, a URDF with a floating joint or a `package://` mesh exits with
/// status 2 naming the scene file, the URDF file and the element, and writes nothing.
#[test]
fn urdf_robots_run_and_bad_ones_exit_2_naming_the_element() {
    let dir = temp_dir("rigid-urdf");
    let out = dir.join("out");
    ok(&coulomb(&[
        "simulate",
        &scene("double-pendulum-urdf.toml"),
        "--steps",
        "5",
        "--output",
        out.to_str().unwrap(),
    ]));
    let link = |name: &str, geometry: &str| {
        format!(
            r#"<link name="{name}"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial><collision><geometry>{geometry}</geometry></collision></link>"#
        )
    };
    let cube = r#"<box size="0.1 0.1 0.1"/>"#;
    for (name, urdf, words) in [
        (
            "floating",
            format!(
                r#"<robot name="r">{}{}<joint name="free" type="floating"><parent link="a"/><child link="b"/></joint></robot>"#,
                link("a", cube),
                link("b", cube)
            ),
            "joint 'free'",
        ),
        (
            "package",
            format!(
                r#"<robot name="r">{}</robot>"#,
                link("arm", r#"<mesh filename="package://arm/arm.stl"/>"#)
            ),
            "package://",
        ),
        ("missing", String::new(), "missing.urdf"),
    ] {
        let urdf_path = dir.join(format!("{name}.urdf"));
        if !urdf.is_empty() {
            std::fs::write(&urdf_path, urdf).unwrap();
        }
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(
            &path,
            format!("[step]\nh = 0.001\n\n[[urdf]]\nfile = \"{name}.urdf\"\n"),
        )
        .unwrap();
        let o = coulomb(&[
            "simulate",
            path.to_str().unwrap(),
            "--output",
            dir.join(format!("{name}.out")).to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains(&format!("{name}.toml:4:1"))
                && err.contains(&format!("{name}.urdf"))
                && err.contains(words),
            "{name}: {err}"
        );
        assert!(!dir.join(format!("{name}.out")).exists(), "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
