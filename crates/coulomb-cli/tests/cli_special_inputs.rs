//! Special files given as inputs (issue 55, cause 2): a FIFO, `/dev/zero` (through a link
//! with the expected extension) and a directory, given as each kind of input — an FCLIB file
//! to `solve`, `info`, `error`, `check`; a scene file, a particle file (CSV, NPY), a mesh
//! (STL, OBJ) named by a scene file, a checkpoint to `simulate --restart` — end with exit
//! status 2 and a message that names the path and what it is, at once: no hang on the FIFO,
//! no read of `/dev/zero` until memory runs out, no abort.
#![cfg(unix)]

use crate::common;

use common::temp_dir;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Runs the binary with `args` in `dir`; its status code and stderr. Killed (a failure)
/// when it has not ended within 30 s.
fn run_with_deadline(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_coulomb"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the coulomb binary starts");
    let start = Instant::now();
    loop {
        if let Ok(Some(_)) = child.try_wait() {
            break;
        }
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("coulomb {args:?} did not end within 30 s (hangs on a special file)");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let out = child.wait_with_output().expect("output");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn mkfifo(path: &Path) {
    let ok = Command::new("mkfifo").arg(path).status().expect("mkfifo");
    assert!(ok.success());
}

/// The three special inputs named `name` in `dir`: a FIFO, a link to /dev/zero, a directory;
/// each with what its message must say.
fn specials(dir: &Path, name: &str) -> Vec<(PathBuf, &'static str)> {
    let sub = |kind: &str| {
        let d = dir.join(kind);
        std::fs::create_dir_all(&d).unwrap();
        d.join(name)
    };
    let fifo = sub("fifo");
    mkfifo(&fifo);
    let zero = sub("zero");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let folder = sub("folder");
    std::fs::create_dir(&folder).unwrap();
    vec![
        (fifo, "FIFO"),
        (zero, "character device"),
        (folder, "directory"),
    ]
}

fn assert_refused(args: &[&str], cwd: &Path, path: &Path, what: &str) {
    let (code, err) = run_with_deadline(cwd, args);
    assert_eq!(code, Some(2), "coulomb {args:?}: {err}");
    let name = path.file_name().unwrap().to_str().unwrap();
    assert!(
        err.contains(name) && err.contains(what),
        "coulomb {args:?}: the message names neither the file nor what it is: {err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn special_files_as_fclib_inputs_exit_2_at_once() {
    let dir = temp_dir("special-fclib");
    for (path, what) in specials(&dir, "problem.hdf5") {
        let p = path.to_str().unwrap();
        for args in [
            vec!["solve", p],
            vec!["info", p],
            vec!["error", p],
            vec!["check", p],
        ] {
            assert_refused(&args, &dir, &path, what);
        }
    }
}

#[test]
fn special_files_as_scene_and_checkpoint_exit_2_at_once() {
    let dir = temp_dir("special-scene");
    for (path, what) in specials(&dir, "scene.toml") {
        assert_refused(&["simulate", path.to_str().unwrap()], &dir, &path, what);
    }
    for (path, what) in specials(&dir, "checkpoint.h5") {
        let args = [
            "simulate",
            "--restart",
            path.to_str().unwrap(),
            "--steps",
            "1",
        ];
        assert_refused(&args, &dir, &path, what);
    }
}

#[test]
fn special_files_named_by_a_scene_exit_2_at_once() {
    let dir = temp_dir("special-named");
    for name in ["beads.csv", "beads.npy"] {
        for (path, what) in specials(&dir, name) {
            let scene = path.parent().unwrap().join("s.toml");
            std::fs::write(
                &scene,
                format!(
                    "[step]\nh = 0.01\nsteps = 1\n\n[[obstacles]]\nshape = {{ kind = \"box\", lo = [0, 0, 0], hi = [1, 1, 1] }}\n\n[[bodies]]\nfile = \"{name}\"\n"
                ),
            )
            .unwrap();
            assert_refused(&["simulate", scene.to_str().unwrap()], &dir, &path, what);
        }
    }
    for name in ["wall.stl", "wall.obj"] {
        for (path, what) in specials(&dir, name) {
            let scene = path.parent().unwrap().join("m.toml");
            std::fs::write(
                &scene,
                format!(
                    "[step]\nh = 0.01\nsteps = 1\n\n[[obstacles]]\nshape = {{ kind = \"mesh\", file = \"{name}\" }}\n"
                ),
            )
            .unwrap();
            assert_refused(&["simulate", scene.to_str().unwrap()], &dir, &path, what);
        }
    }
}

#[test]
fn a_missing_input_is_named_once() {
    let dir = temp_dir("special-missing");
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        "[step]\nh = 0.01\nsteps = 1\n\n[[obstacles]]\nshape = { kind = \"box\", lo = [0, 0, 0], hi = [1, 1, 1] }\n\n[[bodies]]\nfile = \"absent.csv\"\n",
    )
    .unwrap();
    let (code, err) = run_with_deadline(&dir, &["simulate", scene.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{err}");
    assert_eq!(err.matches("absent.csv").count(), 1, "{err}");
    assert_eq!(err.matches("os error 2").count(), 1, "{err}");
}

/// Issue 55, cause 1: a fill of 10¹² spheres is refused from its count before anything is
/// generated (it aborted with exit status 134), with the memory it would need.
#[test]
fn a_huge_fill_is_refused_before_it_is_built() {
    let dir = temp_dir("huge-fill");
    let scene = dir.join("huge.toml");
    std::fs::write(
        &scene,
        "[step]\nh = 0.01\nsteps = 1\n\n[[obstacles]]\nshape = { kind = \"box\", lo = [0, 0, 0], hi = [1, 1, 1] }\n\n[[bodies]]\n[bodies.fill]\ncount = 1000000000000\nregion = { kind = \"box\", lo = [0, 0, 0], hi = [1, 1, 1] }\nsizes = { kind = \"uniform\", min = 0.01, max = 0.02 }\n",
    )
    .unwrap();
    let (code, err) = run_with_deadline(&dir, &["simulate", scene.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("1000000000000 spheres") && err.contains("memory"),
        "{err}"
    );
}
