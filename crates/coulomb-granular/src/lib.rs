//! coulomb-granular: Moreau–Jean time stepping (2.5)–(2.7) of rigid spheres with Coulomb
//! friction, each step's incremental problem (2.10) solved by `coulomb::solver` — the
//! granular experiments of §6 (Table 1, Fig. 8, Fig. 9).
//!
//! ```no_run
//! use coulomb_granular::{Scene, Simulation, Params};
//! let world = Scene::Box.build(150, 1);
//! let mut sim = Simulation::new(world, Params::default()).unwrap();
//! let stats = sim.step().unwrap();
//! println!("{} contacts, {} subproblems", stats.contacts, stats.subproblems);
//! ```
//!
//! A scene of one's own is a [`SceneModel`] ([`model`]): bodies (or columns of spheres),
//! obstacles ([`Shape`]: planes, rectangles, box and cylinder containers or solids, spheres,
//! triangle meshes) with prescribed [`Motion`]s, gravity, materials with per-pair contact laws
//! and the step settings, built into a [`World`] and [`Params`] with typed errors:
//!
//! ```
//! use coulomb_granular::{BodySpec, ObstacleSpec, SceneModel, Shape, Simulation, Vec3};
//! let mut scene = SceneModel::default();
//! scene.obstacles.push(ObstacleSpec::fixed(
//!     "bin",
//!     Shape::Box { lo: Vec3::ZERO, hi: Vec3::new(1.0, 1.0, 1.0), inside: true, open_top: true },
//! ));
//! scene.bodies.push(BodySpec::sphere(Vec3::new(0.5, 0.5, 0.3), 0.05, 2500.0));
//! let (world, params) = scene.build().unwrap();
//! let mut sim = Simulation::new(world, params).unwrap();
//! sim.step().unwrap();
//! ```

pub mod bodies;
pub mod collision;
#[cfg(feature = "mpi")]
pub mod distributed;
pub mod io;
pub mod math;
pub mod rigid;
pub mod run;
pub mod scene;
pub mod step;
// The unit tests, compiled into the library for the integration test binary (docs/testing.md,
// "Unit tests in the library"); the feature is on only when the crate's tests are built.
#[cfg(feature = "unit-tests")]
#[doc(hidden)]
pub mod unit_tests;
pub mod validation;

// The modules' paths from before the folders (issue 52, item 6), kept so that
// `coulomb_granular::world::World` and the like still name the same items.
pub use bodies::{mesh, shape, world};
pub use collision::{contact, tunnelling};
pub use io::rigid_checkpoint;
pub use io::{checkpoint, output, output_dir, report};
pub use run::engine;
pub use scene::rigid as rigid_scene;
pub use scene::{file as scene_file, generate, import, model, save as scene_save, urdf};
use step::colour_progress;
pub use step::{assembly, coarse, nsgs, projection, rolling, simulation, subspace};
pub use validation::laws;

pub use checkpoint::CheckpointError;
pub use contact::{Activation, Contact, Partner};
pub use engine::{Engine, EngineError};
pub use math::Vec3;
pub use mesh::{MeshError, TriangleMesh};
pub use model::{
    resolve_overlaps, BodyShape, BodySpec, BuildChecks, LawKey, MaterialPair, Materials,
    ObstacleSpec, SceneError, SceneModel, SphereBatch, StepChoice, StepSettings,
};
pub use nsgs::{NsgsSettings, NsgsStatus, StepProblem};
pub use projection::{Penetration, Projection, ProjectionStats, Velocities};
pub use report::{EngineStep, StepDetails, StepRecord};
pub use run::{
    run, run_with, EndState, SimulationSettings, Stop, Stopped, Summary, SummaryDetails,
};
pub use scene::Scene;
pub use simulation::{Params, Simulation, SimulationError, StepMethod, StepStats};
pub use world::{ContactLaw, MaterialTable, MeshSide, Motion, Obstacle, Shape, Sphere, World};
