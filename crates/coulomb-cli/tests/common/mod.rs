//! Helpers shared by the CLI tests: run the built `coulomb` binary, find ../shared/fclib and data/, make
//! scratch folders, read JSON.
#![allow(dead_code)] // each test crate uses its own subset

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the built binary with `args`.
pub fn coulomb(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coulomb"))
        .args(args)
        .output()
        .expect("the coulomb binary runs")
}

/// ../shared/fclib, for the tests named `needs_shared_*` (ignored without it: see build.rs);
/// run without it (`--ignored`), they fail here saying what is missing.
pub fn fclib_dir() -> PathBuf {
    let dir = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/fclib"
    ));
    assert!(
        dir.is_dir(),
        "needs ../shared: {} is absent (tests named needs_shared_* read it)",
        dir.display()
    );
    dir
}

/// `name` in the repository's data/ folder (small FCLIB files written by coulomb itself,
/// data/README.md), as a string for a command line.
pub fn data_file(name: &str) -> String {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data")).join(name);
    assert!(
        path.is_file(),
        "{} is part of the repository",
        path.display()
    );
    path.display().to_string()
}

/// A fresh empty directory under cargo's scratch folder for integration tests
/// (`target/tmp`, CARGO_TARGET_TMPDIR): what a test leaves stays inside the build folder.
pub fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("coulomb-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// `name` inside a per-process scratch directory for `tag` (created if needed, kept).
pub fn scratch_file(tag: &str, name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("coulomb-cli-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir.join(name)
}

/// The JSON document in the file at `path`.
pub fn read_json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).expect("the JSON file was written");
    serde_json::from_str(&text).expect("valid JSON")
}

/// Asserts that the command succeeded and returns its stdout.
pub fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "failed: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Asserts that the command succeeded and parses its stdout as JSON.
pub fn stdout_json(out: &Output) -> Value {
    serde_json::from_str(&ok(out)).expect("valid JSON on stdout")
}

/// Writes the Painlevé example (θ in degrees, μ, u₀) to `path` with `coulomb example
/// painleve`, asserting that it succeeded.
pub fn painleve(path: &Path, theta: &str, mu: &str, u0: &str) {
    let out = coulomb(&[
        "example",
        "painleve",
        "--theta",
        theta,
        "--mu",
        mu,
        "--u0",
        u0,
        "--output",
        path.to_str().expect("a UTF-8 path"),
    ]);
    ok(&out);
}
