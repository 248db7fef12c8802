//! One module per subcommand: its clap arguments and its `run`.

pub mod bench;
pub mod check;
pub mod corpus;
pub mod demo;
pub mod error;
pub mod example;
pub mod info;
pub mod paper;
pub mod simulate;
#[cfg(feature = "mpi")]
pub mod simulate_mpi;
pub mod simulate_rigid;
pub mod solve;
pub mod validate;
