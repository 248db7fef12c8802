//! The former paths of the rigid-body engine (issue #41), kept for the command line, the
//! bindings and users' code: its modules now stand in the folders of their concepts
//! (docs/architecture.md) — the body model in [`crate::bodies::rigid`], the Newton–Euler
//! dynamics in [`crate::bodies::dynamics`], joints in [`crate::bodies::joints`], contact
//! manifolds in [`crate::collision::manifold`], the step in [`crate::step::rigid`], scenes
//! in [`crate::scene::rigid`], checkpoints in [`crate::io::rigid_checkpoint`], validation
//! cases in [`crate::validation::rigid`] and [`crate::validation::joints`].

pub use crate::bodies::rigid::{
    MassProperties, RigidBodyDesc, RigidError, RigidObstacle, QUATERNION_TOLERANCE,
};
pub use crate::bodies::{dynamics as body, joints};
pub use crate::collision::{manifold as contacts, polytope};
pub use crate::io::rigid_checkpoint as checkpoint;
pub use crate::scene::rigid as scene;
pub use crate::step::rigid as step;
pub use crate::step::rigid::{RigidSettings, RigidStatus, RigidStepReport, RigidWorld};
pub use crate::validation::{joints as joint_checks, rigid as validation};
pub use parry3d_f64 as parry;
