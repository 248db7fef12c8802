//! The bodies: spheres, obstacles and the world that holds them (`world`), the shapes of
//! other bodies and their mass properties (`shape`), triangle meshes (`mesh`), the obstacles'
//! surfaces (`surface`); bodies of any shape (`rigid`: mass properties, descriptions, contact
//! records, errors), their Newton–Euler dynamics (`dynamics`: quaternions, the gyroscopic
//! free rotation) and the joints between them (`joints`).

pub mod dynamics;
pub mod joints;
pub mod mesh;
pub mod rigid;
pub mod shape;
pub mod surface;
pub mod world;
