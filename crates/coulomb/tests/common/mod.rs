//! Helpers shared by the library's integration tests: find ../shared/fclib and its files,
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

/// ../shared/fclib when present (the test prints "skipped" and returns otherwise).
pub fn fclib_dir() -> Option<PathBuf> {
    let dir = shared_fclib();
    if dir.is_dir() {
        Some(dir)
    } else {
        println!("skipped: ../shared absent");
        None
    }
}

/// The *.hdf5 files of ../shared/fclib, sorted (None, with "skipped" printed, when absent).
pub fn fclib_files() -> Option<Vec<PathBuf>> {
    let dir = fclib_dir()?;
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("../shared/fclib is readable")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "hdf5"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no .hdf5 file in {}", dir.display());
    Some(files)
}

/// A fresh scratch folder under the system's temp dir, unique to this process and `tag`.
pub fn tempdir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coulomb-{tag}-{}", std::process::id()));
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
