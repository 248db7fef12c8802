//! The integration tests of this crate, one module per file of `tests/`, built as one test
//! binary (`cargo test --test integration`): one link instead of one per file (docs/testing.md).
//! A new file of `tests/` must be declared here: `architecture::every_test_file_is_compiled`
//! (crates/coulomb/tests) fails when one is not, for every crate.

mod builtin_fingerprint;
mod example_scenes;
mod fuzz_inputs;
mod impulse_balance;
mod joints;
mod long_chains;
mod mechanisms;
mod physics;
mod rigid_contacts;
mod rigid_inlets;
mod rigid_scenes;
mod rigid_settings;
mod rigid_threads;
mod rolling;
mod scene_model;
mod unit;
mod urdf;
