//! `coulomb simulate --checkpoint-every K` and `--restart FILE`: a run of 20 steps with
//! checkpoints, continued for 10 steps from its checkpoint, ends in the state of a 30-step run
//! to the bit (the checkpoint files, the last VTK frames and the numbers of the stats files are
//! identical); bad checkpoints and options a checkpoint fixes are refused with status 2.

use crate::common;

use common::{coulomb, ok, temp_dir};
use std::path::Path;

fn simulate(extra: &[&str], out: &Path) {
    let mut args = vec!["simulate"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--frames-every", "10", "--output", out.to_str().unwrap()]);
    ok(&coulomb(&args));
}

/// The columns of stats.csv that do not depend on the clock (all but `solve_seconds`,
/// `coulomb_granular::report::CLOCK_COLUMN`), row by row.
fn stats_numbers(dir: &Path) -> Vec<String> {
    let csv = std::fs::read_to_string(dir.join("stats.csv")).unwrap();
    csv.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            [0, 1, 2, 3, 4, 5, 6, 7, 9, 10, 11]
                .iter()
                .map(|&i| f[i])
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect()
}

#[test]
fn restart_continues_a_run_to_the_bit() {
    let root = temp_dir("checkpoint");
    let (a, c) = (root.join("a"), root.join("c"));
    let box100 = ["box", "--beads", "100", "--checkpoint-every", "10"];
    simulate(&[&box100[..], &["--steps", "20"]].concat(), &a);
    simulate(&[&box100[..], &["--steps", "30"]].concat(), &c);
    let ckpt = a.join("checkpoint.h5");
    assert!(ckpt.is_file());
    // continued in its own folder: --steps counts the steps added
    simulate(
        &[
            "--restart",
            ckpt.to_str().unwrap(),
            "--steps",
            "10",
            "--checkpoint-every",
            "10",
        ],
        &a,
    );
    let read = |p: &Path| std::fs::read(p).unwrap();
    assert_eq!(read(&ckpt), read(&c.join("checkpoint.h5")));
    for f in ["frames/bodies_000030.vtp", "frames/contacts_000030.vtp"] {
        assert_eq!(read(&a.join(f)), read(&c.join(f)), "{f}");
    }
    let (sa, sc) = (stats_numbers(&a), stats_numbers(&c));
    assert_eq!(sa.len(), 30);
    assert_eq!(sa, sc);
    let json: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(a.join("stats.json")).unwrap()).unwrap();
    assert_eq!(json.len(), 30);
    let pvd = std::fs::read_to_string(a.join("bodies.pvd")).unwrap();
    assert_eq!(
        pvd.matches("<DataSet").count(),
        4,
        "frames 0, 10, 20, 30: {pvd}"
    );
    assert!(a.join("obstacles.pvd").is_file());
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn bad_restarts_are_refused() {
    let root = temp_dir("checkpoint-bad");
    let out = root.join("out");
    let status = |args: &[&str]| coulomb(args).status.code();
    // --checkpoint-every needs --output
    assert_eq!(
        status(&["simulate", "box", "--steps", "2", "--checkpoint-every", "1"]),
        Some(2)
    );
    simulate(
        &[
            "box",
            "--beads",
            "10",
            "--steps",
            "2",
            "--checkpoint-every",
            "1",
        ],
        &out,
    );
    let ckpt = out.join("checkpoint.h5");
    let c = ckpt.to_str().unwrap();
    // the scene and its parameters come from the checkpoint
    assert_eq!(status(&["simulate", "box", "--restart", c]), Some(2));
    assert_eq!(
        status(&["simulate", "--restart", c, "--mu", "0.5"]),
        Some(2)
    );
    // missing, truncated, flipped
    let missing = root.join("none.h5");
    let r = coulomb(&["simulate", "--restart", missing.to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(2));
    let bytes = std::fs::read(&ckpt).unwrap();
    let bad = root.join("bad.h5");
    std::fs::write(&bad, &bytes[..bytes.len() / 2]).unwrap();
    let r = coulomb(&["simulate", "--restart", bad.to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("bad.h5"), "{err}");
    // a valid restart of the same file works
    let r = coulomb(&["simulate", "--restart", c, "--steps", "2", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&ok(&r)).unwrap();
    assert_eq!(v["steps"], 2);
    assert_eq!(v["bodies"], 10);
    std::fs::remove_dir_all(&root).ok();
}

/// A scene file with an inlet (examples/scenes/silo.toml, its fill capped at 60 beads; the
/// inlet pours 100 beads/s): 20 steps with checkpoints, then continued for 10 steps from the
/// checkpoint with the scene file given, whose inlet keeps pouring, ends as the uninterrupted
/// 30-step run to the bit; a scene file that is not the stored run's is refused.
#[test]
fn restart_with_its_scene_file_keeps_the_inlets_pouring() {
    let root = temp_dir("checkpoint-inlet");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes");
    let silo = scenes.join("silo.toml");
    let s = silo.to_str().unwrap();
    let (a, c) = (root.join("a"), root.join("c"));
    let run = [s, "--beads", "60", "--checkpoint-every", "10"];
    simulate(&[&run[..], &["--steps", "20"]].concat(), &a);
    simulate(&[&run[..], &["--steps", "30"]].concat(), &c);
    let beads = |dir: &Path| common::read_json(&dir.join("summary.json"))["bodies"].clone();
    let at_20 = beads(&a).as_u64().unwrap();
    let ckpt = a.join("checkpoint.h5");
    let k = ckpt.to_str().unwrap();
    simulate(
        &[
            s,
            "--restart",
            k,
            "--steps",
            "10",
            "--checkpoint-every",
            "10",
        ],
        &a,
    );
    // the inlet poured during the continued steps, as in the uninterrupted run
    assert!(beads(&a).as_u64().unwrap() > at_20);
    assert_eq!(beads(&a), beads(&c));
    let read = |p: &Path| std::fs::read(p).unwrap();
    assert_eq!(read(&ckpt), read(&c.join("checkpoint.h5")));
    let f = "frames/bodies_000030.vtp";
    assert_eq!(read(&a.join(f)), read(&c.join(f)), "{f}");
    assert_eq!(stats_numbers(&a), stats_numbers(&c));
    // another scene's file is refused, nothing run
    let chute = scenes.join("chute.toml");
    let r = coulomb(&[
        "simulate",
        chute.to_str().unwrap(),
        "--restart",
        c.join("checkpoint.h5").to_str().unwrap(),
        "--steps",
        "1",
    ]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("is not the scene of the checkpoint"));
    std::fs::remove_dir_all(&root).ok();
}

/// A sphere scene whose inlet pours capsules runs in the rigid-body simulator: 40 steps with
/// checkpoints, continued for 20 steps from the checkpoint with the scene file given (the
/// inlet keeps pouring), ends as the uninterrupted 60-step run to the bit, its frames drawing
/// the poured capsules; a file with another body is refused.
#[test]
fn a_rigid_restart_with_its_scene_file_keeps_pouring_capsules() {
    let root = temp_dir("checkpoint-rigid-inlet");
    let scene = root.join("pour.toml");
    let text = "name = \"pour\"\n[step]\nh = 0.002\ntol = 1e-8\n\
        [[obstacles]]\nshape = { kind = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }\n\
        [[bodies]]\nspheres = [[0.0, 0.0, 0.03, 0.03]]\n\
        [[inlets]]\nregion = { kind = \"box\", lo = [-0.15, -0.15, 0.1], hi = [0.15, 0.15, 0.25] }\n\
        sizes = { kind = \"uniform\", min = 0.015, max = 0.025 }\nrate = { count = 300.0 }\n\
        velocity = [0.0, 0.0, -0.3]\nshape = { kind = \"capsule\", radius = 0.5, half_height = 1.0 }\n";
    std::fs::write(&scene, text).unwrap();
    let s = scene.to_str().unwrap();
    let (a, c) = (root.join("a"), root.join("c"));
    let run = [s, "--checkpoint-every", "20"];
    simulate(&[&run[..], &["--steps", "40"]].concat(), &a);
    simulate(&[&run[..], &["--steps", "60"]].concat(), &c);
    let bodies = |dir: &Path| common::read_json(&dir.join("summary.json"))["bodies"].clone();
    let at_40 = bodies(&a).as_u64().unwrap();
    assert!(at_40 > 20, "{at_40} bodies after 40 steps");
    let ckpt = a.join("checkpoint.h5");
    let k = ckpt.to_str().unwrap();
    simulate(
        &[
            s,
            "--restart",
            k,
            "--steps",
            "20",
            "--checkpoint-every",
            "20",
        ],
        &a,
    );
    assert!(bodies(&a).as_u64().unwrap() > at_40);
    assert_eq!(bodies(&a), bodies(&c));
    let read = |p: &Path| std::fs::read(p).unwrap();
    assert_eq!(read(&ckpt), read(&c.join("checkpoint.h5")));
    for f in ["frames/bodies_000060.vtp", "frames/shapes_000060.vtp"] {
        assert_eq!(read(&a.join(f)), read(&c.join(f)), "{f}");
    }
    // the frame draws the capsules as polygons (part 1; far more than the one ball's file)
    let first = read(&c.join("frames/bodies_000000.vtp")).len();
    assert!(read(&c.join("frames/shapes_000060.vtp")).len() > 10 * first);
    // a file with one more body is not the checkpoint's scene
    let other = root.join("other.toml");
    std::fs::write(
        &other,
        text.replace(
            "[0.0, 0.0, 0.03, 0.03]",
            "[0.0, 0.0, 0.03, 0.03], [0.5, 0.0, 0.03, 0.03]",
        ),
    )
    .unwrap();
    let r = coulomb(&[
        "simulate",
        other.to_str().unwrap(),
        "--restart",
        k,
        "--steps",
        "1",
    ]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("is not the scene of the checkpoint"));
    std::fs::remove_dir_all(&root).ok();
}
