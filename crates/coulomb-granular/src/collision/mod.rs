//! Contact detection: the sphere fast path — analytic sphere–sphere and sphere–obstacle
//! pairs on a grid broad phase (`contact`), and the tunnelling guard (`tunnelling`) — and
//! bodies of any shape: parry3d's BVH broad phase and contact manifolds, balls in closed form
//! (`manifold`), with the face clipping of cuboids and convex polyhedra (`polytope`).

pub mod contact;
pub mod manifold;
pub mod polytope;
pub mod tunnelling;
