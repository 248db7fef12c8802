//! The integration tests of this crate, one module per file of `tests/`, built as one test
//! binary (`cargo test --test integration`): one link instead of one per file (docs/testing.md).
//! A new file of `tests/` must be declared here; the test below fails when one is not.

mod cli_bench;
mod cli_check;
mod cli_checkpoint;
mod cli_corpus;
mod cli_info_error;
mod cli_io_safety;
mod cli_mpi;
mod cli_output_folder;
mod cli_paper;
mod cli_reliability;
mod cli_rigid;
mod cli_simulate_physics;
mod cli_solve;
mod cli_special_inputs;
mod cli_start_checks;
mod common;
mod fuzz_cli;
mod scene_files;

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
