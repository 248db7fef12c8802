//! Helpers shared by the library's integration tests: find ../shared/fclib, data/ and their files,
//! make scratch folders, tell whether h5py is there.
#![allow(dead_code)] // each test crate uses its own subset

use std::path::PathBuf;
use std::process::Command;

/// ../shared/fclib, whether or not it exists.
pub fn shared_fclib() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/fclib"
    ))
}

/// ../shared/fclib, for the tests named `needs_shared_*` (ignored without it: see build.rs);
/// run without it (`--ignored`), they fail here saying what is missing.
pub fn fclib_dir() -> PathBuf {
    let dir = shared_fclib();
    assert!(
        dir.is_dir(),
        "needs ../shared: {} is absent (tests named needs_shared_* read it)",
        dir.display()
    );
    dir
}

/// The *.hdf5 files of ../shared/fclib, sorted (see [`fclib_dir`]).
pub fn fclib_files() -> Vec<PathBuf> {
    hdf5_files(&fclib_dir())
}

/// The repository's data/ folder: small FCLIB files written by coulomb itself
/// (data/README.md), present in every clone.
pub fn data_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data"))
}

/// The *.hdf5 files of data/, sorted.
pub fn data_files() -> Vec<PathBuf> {
    hdf5_files(&data_dir())
}

/// The *.hdf5 files of `dir`, sorted; at least one.
fn hdf5_files(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{} is readable: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "hdf5"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no .hdf5 file in {}", dir.display());
    files
}

/// A fresh scratch folder under cargo's scratch folder for integration tests (`target/tmp`,
/// CARGO_TARGET_TMPDIR), unique to this process and `tag`.
pub fn tempdir(tag: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("coulomb-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir is writable");
    dir
}

/// Whether `python3 -c "import h5py"` works (the h5py cross-checks are skipped otherwise).
pub fn h5py_available() -> bool {
    Command::new("python3")
        .args(["-c", "import h5py"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}
