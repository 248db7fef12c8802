//! The integration tests of this crate, one module per file of `tests/`, built as one test
//! binary (`cargo test --test integration`): one link instead of one per file (docs/testing.md).
//! A new file of `tests/` must be declared here; the test below fails when one is not.

mod builtin_fingerprint;
mod example_scenes;
mod fuzz_inputs;
mod impulse_balance;
mod joints;
mod physics;
mod rigid_contacts;
mod rigid_scenes;
mod rolling;
mod scene_model;

/// Every `tests/*.rs` file is a module of this binary (with `autotests = false` a file that is
/// not declared here would silently not be compiled).
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let declared = include_str!("main.rs");
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("tests/ is readable") {
        let path = entry.expect("a directory entry").path();
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        if path.extension().is_some_and(|e| e == "rs")
            && stem != "main"
            && !declared.contains(&format!("\nmod {stem};"))
        {
            missing.push(stem.to_string());
        }
    }
    assert!(
        missing.is_empty(),
        "files of tests/ not declared as modules in tests/main.rs: {missing:?}"
    );
}
