//! The Moreau–Jean step (2.5)–(2.7) as named phases. Sphere scenes: assemble the problem
//! (2.10) (`assembly`, its contacts' rows `rows`), solve it by body-level Gauss–Seidel
//! (`nsgs`, `subspace`, `rolling`)
//! with the library as fallback, correct positions (`projection`), integrate
//! (`simulation`); `coarse` is a two-level correction of the sweeps (off by default). Scenes
//! with bodies of other shapes: `rigid` (`RigidWorld`, its phases, Gauss–Seidel with joints,
//! position correction and overlap relaxation). Whole runs of either engine are in
//! [`crate::run`](mod@crate::run).

pub mod assembly;
pub mod coarse;
pub(crate) mod colour_progress;
#[cfg(feature = "unit-tests")]
pub(crate) mod fixtures;
pub mod nsgs;
pub mod projection;
pub mod rigid;
pub mod rolling;
pub mod rows;
pub mod simulation;
pub mod subspace;
