//! `simulate --output DIR` as a hostile folder (issue 55, items 4, 5, 7, 8): links and FIFOs
//! planted at the names of the outputs are refused before anything is computed or created,
//! an input of the run in the folder is never written over, a restart appends only to its own
//! run's statistics, a write failing mid-run keeps every completed step's row and exits 4, and
//! an interrupted rigid run's summary says so.
#![cfg(unix)]

use crate::common;

use common::{coulomb, read_json, temp_dir};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn rigid_scene(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/scenes/rigid")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// The status and stderr of `coulomb args…`.
fn run(args: &[&str]) -> (Option<i32>, String) {
    let out = coulomb(args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn box_into(dir: &Path, extra: &[&str]) -> (Option<i32>, String) {
    let mut args = vec!["simulate", "box", "--beads", "20", "--steps", "4"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--output", s(dir)]);
    run(&args)
}

#[test]
fn links_planted_at_output_names_are_refused_before_computing() {
    let root = temp_dir("outdir-links");
    let victim = root.join("victim.txt");
    for name in [
        "summary.json",
        "stats.csv",
        "stats.json",
        "checkpoint.h5",
        "bodies.pvd",
    ] {
        std::fs::write(&victim, b"precious").unwrap();
        let out = root.join(format!("out-{name}"));
        std::fs::create_dir(&out).unwrap();
        std::os::unix::fs::symlink(&victim, out.join(name)).unwrap();
        let (code, err) = box_into(&out, &[]);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert!(err.contains("symbolic link"), "{name}: {err}");
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious", "{name}");
        assert!(!out.join("frames").exists(), "{name}: frames/ left behind");
        assert!(
            std::fs::symlink_metadata(out.join(name))
                .unwrap()
                .file_type()
                .is_symlink(),
            "{name}: the link is left as it was"
        );
    }
    // a planted frames/ link: refused, nothing written where it points
    let elsewhere = root.join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    std::fs::write(elsewhere.join("bodies_000000.vtp"), b"not a frame").unwrap();
    let out = root.join("out-frames");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("frames")).unwrap();
    let (code, err) = box_into(&out, &[]);
    assert_eq!(code, Some(2), "{err}");
    assert_eq!(
        std::fs::read(elsewhere.join("bodies_000000.vtp")).unwrap(),
        b"not a frame"
    );
    assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 1);
    assert!(!out.join("stats.csv").exists());
    // the same for a rigid run
    std::fs::write(&victim, b"precious").unwrap();
    let out = root.join("out-rigid");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&victim, out.join("stats.json")).unwrap();
    let (code, err) = run(&[
        "simulate",
        &rigid_scene("incline.toml"),
        "--steps",
        "2",
        "--output",
        s(&out),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
    assert!(!out.join("frames").exists());
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn a_fifo_at_checkpoint_h5_is_found_before_the_first_step() {
    let root = temp_dir("outdir-fifo");
    let out = root.join("out");
    std::fs::create_dir(&out).unwrap();
    let made = Command::new("mkfifo")
        .arg(out.join("checkpoint.h5"))
        .status();
    if !made.is_ok_and(|s| s.success()) {
        println!("skipped: mkfifo failed");
        return;
    }
    let (code, err) = box_into(&out, &["--checkpoint-every", "2"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("FIFO"), "{err}");
    assert!(!out.join("frames").exists(), "frames/ left behind");
    assert!(!out.join("stats.csv").exists(), "a step was computed");
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn an_input_of_the_run_in_the_output_folder_is_never_written_over() {
    let root = temp_dir("outdir-inputs");
    let out = root.join("out");
    std::fs::create_dir(&out).unwrap();
    // a scene file named summary.json in the output folder
    let scene = out.join("summary.json");
    let text = r#"{"step": {"h": 0.001, "steps": 2},
        "obstacles": [{"shape": {"kind": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}}],
        "bodies": [{"spheres": [[0, 0, 0.5, 0.1]]}]}"#;
    std::fs::write(&scene, text).unwrap();
    let (code, err) = run(&["simulate", s(&scene), "--output", s(&out)]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("is an input of this run"), "{err}");
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), text);
    assert!(!out.join("frames").exists());
    // a particle file named stats.csv in the output folder, read by a scene file beside it
    let out2 = root.join("out2");
    std::fs::create_dir(&out2).unwrap();
    let particles = out2.join("stats.csv");
    let rows = "x,y,z,r\n0,0,0.5,0.1\n0.3,0,0.5,0.1\n";
    std::fs::write(&particles, rows).unwrap();
    let scene2 = root.join("scene.toml");
    std::fs::write(
        &scene2,
        "[step]\nh = 0.001\nsteps = 2\n[[obstacles]]\nshape = { kind = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }\n[[bodies]]\nfile = \"out2/stats.csv\"\n",
    )
    .unwrap();
    let (code, err) = run(&["simulate", s(&scene2), "--output", s(&out2)]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("is an input of this run"), "{err}");
    assert_eq!(std::fs::read_to_string(&particles).unwrap(), rows);
    std::fs::remove_dir_all(&root).ok();
}

fn stats_steps(dir: &Path) -> Vec<u64> {
    std::fs::read_to_string(dir.join("stats.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect()
}

#[test]
fn a_restart_appends_only_to_its_own_runs_statistics() {
    let root = temp_dir("outdir-restart");
    let (a, b, c) = (root.join("a"), root.join("b"), root.join("c"));
    let box30 = [
        "simulate",
        "box",
        "--beads",
        "30",
        "--checkpoint-every",
        "10",
    ];
    let go = |steps: &str, dir: &Path| {
        let (code, err) = run(&[&box30[..], &["--steps", steps, "--output", s(dir)]].concat());
        assert_eq!(code, Some(0), "{err}");
    };
    go("10", &a);
    go("25", &b);
    go("20", &c);
    let ckpt = a.join("checkpoint.h5");
    // into the folder of another run: refused, its files untouched
    let before = std::fs::read(b.join("stats.csv")).unwrap();
    let (code, err) = run(&[
        "simulate",
        "--restart",
        s(&ckpt),
        "--steps",
        "5",
        "--output",
        s(&b),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("another run"), "{err}");
    assert_eq!(std::fs::read(b.join("stats.csv")).unwrap(), before);
    // continued in its own folder without a new checkpoint (as a run killed after step 15)…
    let (code, err) = run(&[
        "simulate",
        "--restart",
        s(&ckpt),
        "--steps",
        "5",
        "--output",
        s(&a),
    ]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(stats_steps(&a), (0..15).collect::<Vec<_>>());
    // …and from the same checkpoint again: the rows after step 10 are dropped, not mixed
    let (code, err) = run(&[
        "simulate",
        "--restart",
        s(&ckpt),
        "--steps",
        "10",
        "--output",
        s(&a),
    ]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(stats_steps(&a), (0..20).collect::<Vec<_>>());
    assert_eq!(
        std::fs::read(a.join("stats.csv"))
            .unwrap()
            .split(|&b| b == b'\n')
            .map(|l| l.split(|&b| b == b',').filter(|_| true).count())
            .filter(|&n| n > 1)
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        1,
        "one column count"
    );
    let json = read_json(&a.join("stats.json"));
    assert_eq!(json.as_array().unwrap().len(), 20);
    // a rigid checkpoint restarted into a sphere run's folder: refused, rows kept
    let r = root.join("r");
    let (code, err) = run(&[
        "simulate",
        &rigid_scene("incline.toml"),
        "--steps",
        "4",
        "--checkpoint-every",
        "2",
        "--output",
        s(&r),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let before = std::fs::read(c.join("stats.csv")).unwrap();
    let (code, err) = run(&[
        "simulate",
        "--restart",
        s(&r.join("checkpoint.h5")),
        "--steps",
        "2",
        "--output",
        s(&c),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert_eq!(std::fs::read(c.join("stats.csv")).unwrap(), before);
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn a_write_failing_mid_run_keeps_every_completed_row_and_exits_4() {
    let root = temp_dir("outdir-efbig");
    let out = root.join("out");
    // files may grow to 2 KiB (frames of 2 beads fit, stats.csv does not for long): the
    // writes beyond fail with EFBIG (SIGXFSZ ignored, as it stays across exec)
    let bin = env!("CARGO_BIN_EXE_coulomb");
    let cmd = format!(
        "trap '' XFSZ; ulimit -f 4; exec '{bin}' simulate box --beads 2 --steps 200 --frames-every 1 --output '{}'",
        s(&out)
    );
    let o = Command::new("sh")
        .args(["-c", &cmd])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(err.contains("stats.csv"), "{err}");
    let steps = stats_steps(&out);
    assert!(steps.len() >= 5, "{steps:?}");
    assert_eq!(steps, (0..steps.len() as u64).collect::<Vec<_>>());
    let text = std::fs::read_to_string(out.join("stats.csv")).unwrap();
    assert!(text.ends_with('\n'), "whole rows only");
    let frame = out.join(format!("frames/bodies_{:06}.vtp", steps.len()));
    assert!(frame.is_file(), "frames up to the failed step");
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn a_full_disk_on_a_frame_exits_4_and_keeps_the_statistics() {
    let root = temp_dir("outdir-full");
    let mnt = root.join("mnt");
    std::fs::create_dir(&mnt).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=64k", "tmpfs", s(&mnt)])
        .stderr(Stdio::null())
        .status();
    if !mounted.is_ok_and(|s| s.success()) {
        println!("skipped: cannot mount a tmpfs here (needs root)");
        return;
    }
    let out = mnt.join("out");
    let o = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "30",
        "--steps",
        "200",
        "--frames-every",
        "1",
        "--output",
        s(&out),
    ]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    let steps = stats_steps(&out);
    let _ = Command::new("umount").arg(&mnt).status();
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(err.contains("frames/"), "{err}");
    assert!(!steps.is_empty());
    assert_eq!(steps, (0..steps.len() as u64).collect::<Vec<_>>());
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn an_interrupted_rigid_run_says_stopped_and_signal() {
    let root = temp_dir("outdir-rigid-int");
    let out = root.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_coulomb"))
        .args([
            "simulate",
            &rigid_scene("incline.toml"),
            "--steps",
            "1000000",
            "--output",
            s(&out),
        ])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let first = out.join("frames/bodies_000000.vtp");
    let start = std::time::Instant::now();
    while !first.exists() {
        assert!(start.elapsed().as_secs() < 60, "no first frame");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let ok = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["stopped"], "interrupted", "{summary}");
    assert_eq!(summary["signal"], "SIGINT", "{summary}");
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn validate_refuses_a_fifo_as_markdown_before_running_the_suite() {
    let root = temp_dir("outdir-validate");
    let fifo = root.join("report.md");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        println!("skipped: mkfifo failed");
        return;
    }
    let out = coulomb(&["validate", "--quick", "--markdown", s(&fifo)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("FIFO"), "{err}");
    // refused before the first check ran (the suite prints a line per check)
    assert!(
        !String::from_utf8_lossy(&out.stdout).contains("pass "),
        "the suite ran first"
    );
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn options_that_cannot_apply_to_a_scene_file_are_refused() {
    let root = temp_dir("outdir-options");
    let scene = root.join("listed.toml");
    std::fs::write(
        &scene,
        "[step]\nh = 0.001\nsteps = 2\n[[obstacles]]\nshape = { kind = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }\n[[bodies]]\nspheres = [[0, 0, 0.5, 0.1]]\n",
    )
    .unwrap();
    for (opt, value) in [("--beads", "10"), ("--seed", "7")] {
        let (code, err) = run(&["simulate", s(&scene), opt, value]);
        assert_eq!(code, Some(2), "{opt}: {err}");
        assert!(err.contains(opt), "{err}");
    }
    let (code, err) = run(&["simulate", s(&scene)]);
    assert_eq!(code, Some(0), "{err}");
    let help = coulomb(&["--help"]);
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(!text.contains("rigid spheres"), "{text}");
    std::fs::remove_dir_all(&root).ok();
}
