//! Outputs that never replace what is not a regular file, runs that end well on SIGINT and
//! SIGTERM, `--until-rest` at its step cap, and `scripts/mpirun-local.sh` (issue 43, items
//! 5–7).
#![cfg(unix)]

use crate::common;

use common::{coulomb, painleve, read_json, temp_dir};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// The built binary, spawned with piped outputs.
fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_coulomb"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the coulomb binary starts")
}

/// Sends `signal` (`INT`, `TERM`) to `child` with kill(1).
fn send(child: &Child, signal: &str) {
    let ok = Command::new("kill")
        .arg(format!("-{signal}"))
        .arg(child.id().to_string())
        .status()
        .expect("kill runs");
    assert!(ok.success(), "kill -{signal} failed");
}

/// Waits until `ready()` holds (polling), at most 60 s; the child is killed if it does not.
fn wait_until(child: &mut Child, what: &str, ready: impl Fn() -> bool) {
    let start = Instant::now();
    while !ready() {
        if let Ok(Some(status)) = child.try_wait() {
            panic!("the command ended ({status}) before {what}");
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("no {what} within 60 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The child's exit status, its stdout and stderr; killed after 60 s (then a failure).
fn finish(mut child: Child) -> (ExitStatus, String, String) {
    let start = Instant::now();
    loop {
        if let Ok(Some(_)) = child.try_wait() {
            break;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("the command did not end within 60 s of the signal");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("outputs");
    (
        out.status,
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Makes a character device node at `path` with mknod(1) (the numbers of /dev/full, 1 7; a
/// new node in a scratch folder, never the real one). False, with the reason printed, when
/// this user may not (mknod needs root or CAP_MKNOD).
fn make_device(path: &Path) -> bool {
    match Command::new("mknod")
        .arg(path)
        .args(["c", "1", "7"])
        .output()
    {
        Ok(out) if out.status.success() => true,
        Ok(out) => {
            println!(
                "skipped: mknod failed (needs root or CAP_MKNOD): {}",
                String::from_utf8_lossy(&out.stderr).trim()
            );
            false
        }
        Err(e) => {
            println!("skipped: mknod not available: {e}");
            false
        }
    }
}

fn is_char_device(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_char_device())
}

fn is_fifo(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

fn mkfifo(path: &Path) {
    let ok = Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(ok.success());
}

fn s(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// Asserts exit status 2 with "output path refused" and the path named on stderr.
fn assert_refused(out: &std::process::Output, path: &Path) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("output path refused"), "{err}");
    assert!(err.contains(s(path)), "{err}");
}

#[test]
fn solve_refuses_a_device_node_as_output_and_leaves_it_a_device() {
    let dir = temp_dir("io-dev");
    let problem = dir.join("p.hdf5");
    painleve(&problem, "30", "0.3", "-1");
    let dev = dir.join("full");
    if !make_device(&dev) {
        return;
    }
    for extra in [&[][..], &["--json"][..]] {
        let mut args = vec!["solve", s(&problem), "--output", s(&dev)];
        args.extend_from_slice(extra);
        let out = coulomb(&args);
        assert_refused(&out, &dev);
        assert!(is_char_device(&dev), "the device node was replaced");
    }
    // a link to the device: refused the same way, link and device kept
    let link = dir.join("link-to-full");
    std::os::unix::fs::symlink(&dev, &link).unwrap();
    let out = coulomb(&["solve", s(&problem), "--output", s(&link)]);
    assert_refused(&out, &link);
    assert!(is_char_device(&dev));
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn outputs_refuse_fifos_dangling_links_and_folders_and_write_through_links_to_files() {
    let dir = temp_dir("io-kinds");
    let problem = dir.join("p.hdf5");
    painleve(&problem, "30", "0.3", "-1");
    let fifo = dir.join("pipe");
    mkfifo(&fifo);
    let dangling = dir.join("dangling.hdf5");
    std::os::unix::fs::symlink(dir.join("missing/x.hdf5"), &dangling).unwrap();
    let folder = dir.join("folder");
    std::fs::create_dir(&folder).unwrap();
    for path in [&fifo, &dangling, &folder] {
        // refused before the solve (never blocks on the FIFO)
        let out = coulomb(&["solve", s(&problem), "--output", s(path)]);
        assert_refused(&out, path);
    }
    assert!(is_fifo(&fifo));
    assert!(std::fs::read_link(&dangling).is_ok() && !dangling.exists());
    assert!(folder.is_dir() && std::fs::read_dir(&folder).unwrap().count() == 0);
    // a link to a regular file: the file is replaced by the solved problem, the link kept
    let target = dir.join("target.hdf5");
    std::fs::write(&target, b"old").unwrap();
    let link = dir.join("solved.hdf5");
    std::os::unix::fs::symlink("target.hdf5", &link).unwrap();
    let out = coulomb(&["solve", s(&problem), "--output", s(&link)]);
    assert!(out.status.success(), "{out:?}");
    assert_eq!(std::fs::read_link(&link).unwrap(), Path::new("target.hdf5"));
    let info = coulomb(&["info", s(&target), "--json"]);
    let v: Value = serde_json::from_slice(&info.stdout).expect("info JSON");
    assert!(v.to_string().contains("\"global\""), "{v}");
    // simulate --output DIR: its summary.json a FIFO, refused before the run (and at write
    // time: coulomb::atomic's own tests)
    let run = dir.join("run");
    std::fs::create_dir(&run).unwrap();
    let summary = run.join("summary.json");
    mkfifo(&summary);
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "20",
        "--steps",
        "2",
        "--output",
        s(&run),
    ]);
    assert_refused(&out, &summary);
    assert!(is_fifo(&summary));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `coulomb simulate box --beads 300 --steps 100000 --output DIR` stopped by `signal` once
/// its first frame is written: the exit status, the parsed summary.json, and stdout.
fn interrupted_simulation(tag: &str, signal: &str, json: bool) -> (ExitStatus, Value, String) {
    let dir = temp_dir(tag);
    let run = dir.join("run");
    let mut args = vec![
        "simulate", "box", "--beads", "300", "--steps", "100000", "--output",
    ];
    args.push(s(&run));
    if json {
        args.push("--json");
    }
    let mut child = spawn(&args);
    let first = run.join("frames/bodies_000000.vtp");
    wait_until(&mut child, "a first frame", || first.exists());
    send(&child, signal);
    let (status, stdout, stderr) = finish(child);
    assert!(stderr.contains("interrupted by SIG"), "{stderr}");
    for f in ["stats.csv", "stats.json", "summary.json"] {
        assert!(
            run.join(f).is_file(),
            "{f} missing after {signal}: {stderr}"
        );
    }
    let summary = read_json(&run.join("summary.json"));
    let stats = read_json(&run.join("stats.json"));
    let steps = summary["steps"].as_u64().unwrap();
    assert!((1..100_000).contains(&steps), "{summary}");
    assert_eq!(stats.as_array().unwrap().len() as u64, steps);
    let csv = std::fs::read_to_string(run.join("stats.csv")).unwrap();
    assert_eq!(
        csv.lines().count() as u64,
        steps + 1,
        "header + one row per step"
    );
    let _ = std::fs::remove_dir_all(&dir);
    (status, summary, stdout)
}

#[test]
fn simulate_on_sigint_finishes_the_step_writes_stats_and_summary_and_exits_130() {
    let (status, summary, _) = interrupted_simulation("io-int", "INT", false);
    assert_eq!(status.code(), Some(130), "{status}");
    assert_eq!(summary["stopped"], "interrupted", "{summary}");
    assert_eq!(summary["signal"], "SIGINT", "{summary}");
    assert_eq!(summary["at_rest"], false);
}

#[test]
fn simulate_on_sigterm_exits_143_and_its_json_says_interrupted() {
    let (status, summary, stdout) = interrupted_simulation("io-term", "TERM", true);
    assert_eq!(status.code(), Some(143), "{status}");
    assert_eq!(summary["signal"], "SIGTERM", "{summary}");
    let v: Value = serde_json::from_str(stdout.trim()).expect("one JSON object on stdout");
    assert_eq!(v["stopped"], "interrupted", "{v}");
    assert_eq!(v["signal"], "SIGTERM", "{v}");
    assert_eq!(v["steps"], summary["steps"]);
}

#[test]
fn until_rest_at_its_step_cap_says_so_and_exits_1() {
    let dir = temp_dir("io-cap");
    let run = dir.join("run");
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "40",
        "--until-rest",
        "--max-steps",
        "3",
        "--json",
        "--output",
        s(&run),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("step cap"), "{err}");
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    assert_eq!(v["stopped"], "step_cap", "{v}");
    assert_eq!(v["at_rest"], false, "{v}");
    assert_eq!(v["steps"], 3, "{v}");
    assert!(v.get("not_converged_steps").is_some(), "{v}");
    let summary = read_json(&run.join("summary.json"));
    assert_eq!(summary["stopped"], "step_cap");
    // a fixed number of steps is no negative answer
    let out = coulomb(&["simulate", "box", "--beads", "40", "--steps", "3", "--json"]);
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    assert!(out.status.success());
    assert_eq!(v["stopped"], "steps", "{v}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A Painlevé problem on which plain PGS fixed-point iterations cycle (error ~4e-3 without
/// end) until their iteration cap or time limit: with both large, a solve that runs as long
/// as it is allowed to.
fn cycling_problem(dir: &Path) -> PathBuf {
    let p = dir.join("cycling.hdf5");
    painleve(&p, "80", "5", "1");
    p
}

/// The solve of [`cycling_problem`] with a long time limit, stopped by SIGINT: the status is
/// `interrupted` (not `time_limit`), the error is that of the iterate, exit status 130.
#[test]
fn solve_on_sigint_stops_at_the_next_check_reports_interrupted_and_exits_130() {
    let dir = temp_dir("io-solve");
    let problem = cycling_problem(&dir);
    let out_file = dir.join("solved.hdf5");
    let args = [
        "solve",
        s(&problem),
        "--inner",
        "pgs",
        "--outer",
        "fixed-point",
        "--max-outer",
        "1000000000",
        "--time-limit",
        "120",
        "--json",
        "--output",
        s(&out_file),
    ];
    // the handlers are installed first thing; a signal that came earlier still (a very slow
    // start) kills the process by the default action: then once more, waiting longer
    let mut result = None;
    for wait_ms in [500, 3000] {
        let child = spawn(&args);
        std::thread::sleep(Duration::from_millis(wait_ms));
        send(&child, "INT");
        let (status, stdout, stderr) = finish(child);
        if status.code().is_some() {
            result = Some((status, stdout, stderr));
            break;
        }
    }
    let (status, stdout, stderr) = result.expect("the solve handled SIGINT");
    assert_eq!(status.code(), Some(130), "{stderr}");
    let v: Value = serde_json::from_str(stdout.trim()).expect("the JSON report");
    assert_eq!(v["status"], "interrupted", "{v}");
    assert_eq!(v["converged"], false, "{v}");
    assert!(v["error"].as_f64().unwrap().is_finite(), "{v}");
    assert!(
        v["existence"]["skipped"]
            .as_str()
            .unwrap()
            .contains("SIGINT"),
        "{v}"
    );
    assert!(stderr.contains("interrupted by SIGINT"), "{stderr}");
    // the iterate reached is stored, readable
    let info = coulomb(&["info", s(&out_file), "--json"]);
    assert!(info.status.success());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bench --repeat 1000` on three files (a one-contact Painlevé problem, done in ~0.1 s, then
/// twice a step of a 300-bead box, ~1 ms a solve, so ~1 s each), stopped by SIGINT once the
/// first is done: the table and JSON cover the problems done, the JSON says interrupted, and
/// the exit status is 130.
#[test]
fn bench_on_sigint_writes_the_partial_json_and_exits_130() {
    let dir = temp_dir("io-bench");
    let quick = dir.join("a.hdf5");
    painleve(&quick, "30", "0.3", "-1");
    let dump = dir.join("dump");
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "300",
        "--steps",
        "3",
        "--dump-fclib",
        s(&dump),
    ]);
    assert!(out.status.success(), "{out:?}");
    let (slow, slow2) = (dir.join("b.hdf5"), dir.join("c.hdf5"));
    std::fs::copy(dump.join("step_000002.hdf5"), &slow).unwrap();
    std::fs::copy(&slow, &slow2).unwrap();
    let json = dir.join("bench.json");
    let mut child = spawn(&[
        "bench",
        s(&quick),
        s(&slow),
        s(&slow2),
        "--solvers",
        "pgs",
        "--repeat",
        "1000",
        "--json",
        s(&json),
    ]);
    // stderr: one line per (problem, solver) pair; the first says problem 1 is done
    let stderr = child.stderr.take().unwrap();
    let mut lines = BufReader::new(stderr).lines();
    let mut seen = Vec::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        let first_done = line.starts_with("[1/3]");
        seen.push(line);
        if first_done {
            break;
        }
    }
    assert!(
        seen.last().is_some_and(|l| l.starts_with("[1/3]")),
        "{seen:?}"
    );
    send(&child, "INT");
    seen.extend(lines.map_while(Result::ok));
    let (status, stdout, _) = finish(child);
    let seen = seen.join("\n");
    assert_eq!(status.code(), Some(130), "{seen}");
    assert!(seen.contains("interrupted by SIGINT"), "{seen}");
    let v = read_json(&json);
    let done = v["interrupted"]["problems_done"].as_u64().unwrap();
    assert!((1..3).contains(&done), "{v}");
    assert_eq!(v["interrupted"]["problems_found"], 3);
    assert_eq!(v["interrupted"]["signal"], "SIGINT");
    assert_eq!(v["records"].as_array().unwrap().len() as u64, done);
    assert_eq!(v["records"][0]["problem"], "a", "{v}");
    assert!(stdout.contains("wrote"), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// scripts/mpirun-local.sh against a stand-in `mpirun` that reports itself as Open MPI and
/// prints its arguments: --allow-run-as-root exactly when root, --oversubscribe exactly when
/// the ranks exceed the cores, everything else passed through in order; a stand-in MPICH gets
/// no flag.
#[test]
fn mpirun_local_adds_root_and_oversubscribe_flags_only_when_needed() {
    use std::os::unix::fs::PermissionsExt;
    let dir = temp_dir("io-mpirun");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/mpirun-local.sh");
    let root = Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false);
    for (flavour, version) in [
        ("openmpi", "mpirun (Open MPI) 4.1.4"),
        ("mpich", "HYDRA build details:"),
    ] {
        let bin = dir.join(flavour);
        std::fs::create_dir_all(&bin).unwrap();
        let fake = bin.join("mpirun");
        std::fs::write(
            &fake,
            format!(
                "#!/bin/sh\nif [ \"$1\" = --version ]; then echo '{version}'; exit 0; fi\necho \"$@\"\nexit 7\n"
            ),
        )
        .unwrap();
        std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
        let path = format!(
            "{}:{}",
            bin.display(),
            std::env::var("PATH").unwrap_or_default()
        );
        let run = |args: &[&str]| {
            let out = Command::new("bash")
                .arg(&script)
                .args(args)
                .env("PATH", &path)
                .output()
                .expect("bash runs the script");
            // the stand-in's status comes through
            assert_eq!(out.status.code(), Some(7), "{out:?}");
            String::from_utf8_lossy(&out.stdout).trim().to_string()
        };
        let many = run(&["-np", "100000", "prog", "--until-rest", "a b"]);
        let one = run(&["-np", "1", "prog"]);
        if flavour == "openmpi" {
            let root_flag = if root { "--allow-run-as-root " } else { "" };
            assert_eq!(
                many,
                format!("{root_flag}--oversubscribe -np 100000 prog --until-rest a b")
            );
            assert_eq!(one, format!("{root_flag}-np 1 prog"));
        } else {
            assert_eq!(many, "-np 100000 prog --until-rest a b");
            assert_eq!(one, "-np 1 prog");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
