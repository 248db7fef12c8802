//! The research harness of coulomb, kept out of the library crate (issue #42, item 7): the
//! library holds what a user of it calls; the experiments that chose its methods, and the
//! engines of the CLI's research subcommands, live here. The subcommands `coulomb corpus`,
//! `coulomb paper` and `coulomb bench` stay in the CLI, thin: they parse their arguments into
//! the plain option structs of these modules, show the progress, print and choose the exit
//! status.
//!
//! Modules:
//! - [`corpus`]: the test corpus — the problem generators of each class (granular steps,
//!   stacked rigid boxes, gyroscopic boxes, non-symmetric W, the Painlevé rod, random
//!   problems), the rank of W and its asymmetry, the FCLIB files and `manifest.json`;
//! - [`paper`]: the granular experiments of the paper's §6 — Table 1, the data and SVG of
//!   Fig. 8 and Fig. 9, and the scaling curve (time per step against the number of beads, with
//!   the paper's solver or, accurate, body-level Gauss–Seidel on each thread count);
//! - [`bench`](mod@bench): solvers side by side on FCLIB collections — timed cold-start solves, their
//!   records judged by one rule, the Dolan–Moré performance profile, the table, the JSON and
//!   the SVG of the profile;
//! - [`outputs`]: how every file of `coulomb` is written (paths checked before a run, atomic
//!   replacement, JSON without −0.0), shared by these engines and the CLI's other commands;
//! - [`progress`]: the progress report an engine gives while it runs time steps, shown as
//!   its caller decides;
//! - [`threads`]: the worker-thread pool of the parallel runs.
//!
//! Examples:
//! - `examples/rigid_probe.rs`: the methods tried on the rigid (rank-deficient) problems —
//!   Levenberg–Marquardt variants, continuation in μ, ADMM, the interior point on the law,
//!   Newton on s = F(s) — each on one FCLIB file (docs/rigid.md, "Reproducing");
//!   `cargo run --release -p coulomb-lab --example rigid_probe -- FILE METHOD [WARM_S] [LIMIT_S]`.
//! - `examples/vspace_probe.rs`: the method of multipliers in the velocities that became
//!   `coulomb::multiplier` (docs/rigid.md);
//!   `cargo run --release -p coulomb-lab --example vspace_probe -- FILE.hdf5 [WARM_S] [LIMIT_S]`.

pub mod bench;
pub mod corpus;
pub mod outputs;
pub mod paper;
pub mod progress;
pub mod threads;
