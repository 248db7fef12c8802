//! The integration tests of this crate, one module per file of `tests/`, built as one test
//! binary (`cargo test --test integration`): one link instead of one per file (docs/testing.md).
//! A new file of `tests/` must be declared here: `architecture::every_test_file_is_compiled`
//! (crates/coulomb/tests) fails when one is not, for every crate.

mod architecture;
mod common;
mod determinism;
mod existence_3d;
mod existence_examples;
mod existence_fclib;
mod existence_solver;
mod fclib_corrupt;
mod fclib_read;
mod fclib_roundtrip;
mod fuzz;
mod inner_clarabel;
mod plan_granular;
mod reliability;
mod settings_json;
mod solver_fclib;
mod solver_painleve;
mod solver_random;
mod unit;
mod zero_contacts;
