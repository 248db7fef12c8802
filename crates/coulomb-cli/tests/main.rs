//! The integration tests of this crate, one module per file of `tests/`, built as one test
//! binary (`cargo test --test integration`): one link instead of one per file (docs/testing.md).
//! A new file of `tests/` must be declared here: `architecture::every_test_file_is_compiled`
//! (crates/coulomb/tests) fails when one is not, for every crate.

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
