//! Tells the integration tests whether the FCLIB collection `../shared/fclib` beside the
//! repository is there: `--cfg shared_data` when it is. The tests that read it are named
//! `needs_shared_*` and marked `#[cfg_attr(not(shared_data), ignore = "needs ../shared")]`, so
//! that without it `cargo test` counts them as ignored, never as passed (docs/testing.md).

use std::path::PathBuf;

fn main() {
    println!("cargo:rustc-check-cfg=cfg(shared_data)");
    let manifest = std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let fclib = PathBuf::from(manifest).join("../../../shared/fclib");
    if fclib.is_dir() {
        println!("cargo:rustc-cfg=shared_data");
        println!("cargo:rerun-if-changed={}", fclib.display());
    } else {
        // A rerun-if-changed on a missing path would rerun this script on every cargo command,
        // and so recompile this crate and all that depend on it each time. Without the folder
        // the script reruns only when it changes: after adding ../shared, `touch` this file.
        println!("cargo:rerun-if-changed=build.rs");
    }
}
