//! The bodies: spheres, obstacles and the world that holds them (`world`), the shapes of
//! other bodies and their mass properties (`shape`), triangle meshes (`mesh`), the obstacles' surfaces (`surface`).

pub mod mesh;
pub mod shape;
pub mod surface;
pub mod world;
