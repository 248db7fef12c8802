//! The body model of bodies of any shape (issue #41): mass properties ([`MassProperties`],
//! from parry3d's), a body's description ([`RigidBodyDesc`]: shape, mass, pose, velocities,
//! material, fixed or free), an obstacle's ([`RigidObstacle`]: shape and prescribed motion)
//! and the engine's errors ([`RigidError`]). A contact's record is every scene's
//! [`crate::contact::Contact`]. The Newton–Euler dynamics are in
//! [`crate::bodies::dynamics`], joints in [`crate::bodies::joints`], the step in
//! [`crate::step::rigid`].
//!
//! Quaternions are (w, x, y, z) in every public API; a non-unit (||q| − 1| > 1e-9) or
//! non-finite one is refused, never normalized silently. docs/rigid.md has the details.

use crate::collision::contact::Partner;
use crate::world::Motion;
use parry::shape::SharedShape;
use parry3d_f64 as parry;
use serde::Serialize;

/// Largest accepted deviation ||q| − 1| of a quaternion.
pub const QUATERNION_TOLERANCE: f64 = 1e-9;

/// Mass, centre of mass (shape frame) and inertia tensor about the centre of mass (shape
/// frame axes) of a body.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MassProperties {
    /// mass m > 0
    pub mass: f64,
    /// centre of mass in the shape frame
    pub local_com: [f64; 3],
    /// inertia tensor about the centre of mass, shape-frame axes (symmetric positive definite)
    pub inertia: [[f64; 3]; 3],
}

impl MassProperties {
    /// The mass properties of `shape` with uniform `density` (kg/m³), from parry's
    /// mass properties. Refuses a non-positive or non-finite density and a shape whose mass
    /// or principal inertia is not positive (zero volume: degenerate hulls, half-spaces,
    /// meshes).
    pub fn from_shape(shape: &SharedShape, density: f64) -> Result<Self, RigidError> {
        if !(density.is_finite() && density > 0.0) {
            return Err(RigidError::Mass {
                what: "shape".into(),
                detail: format!("density {density} is not a finite positive number"),
            });
        }
        let mp = shape.mass_properties(density);
        let mass = mp.mass();
        let principal = mp.principal_inertia();
        let ok = mass.is_finite()
            && mass > 0.0
            && principal.is_finite()
            && principal.min_element() > 0.0
            && mp.local_com.is_finite();
        if !ok {
            return Err(RigidError::Mass {
                what: format!("shape {:?}", shape.shape_type()),
                detail: format!(
                    "mass {mass} and principal inertia {principal:?}: zero volume or degenerate shape"
                ),
            });
        }
        let m = mp.reconstruct_inertia_matrix();
        let cols = m.to_cols_array_2d();
        let inertia = std::array::from_fn(|r| std::array::from_fn(|c| cols[c][r]));
        Ok(Self {
            mass,
            local_com: mp.local_com.to_array(),
            inertia,
        })
    }

    /// Why these properties are not those of a body (mass or inertia not positive, inertia
    /// not symmetric, triangle inequality of the principal moments violated, non-finite).
    pub fn check(&self) -> Result<(), String> {
        let i = &self.inertia;
        if !(self.mass.is_finite() && self.mass > 0.0) {
            return Err(format!(
                "mass {} is not a finite positive number",
                self.mass
            ));
        }
        if !self.local_com.iter().all(|x| x.is_finite())
            || !i.iter().flatten().all(|x| x.is_finite())
        {
            return Err("non-finite centre of mass or inertia".into());
        }
        let scale = (0..3).map(|k| i[k][k].abs()).fold(0.0, f64::max);
        for r in 0..3 {
            for c in 0..3 {
                if (i[r][c] - i[c][r]).abs() > 1e-9 * scale {
                    return Err(format!("inertia tensor {i:?} is not symmetric"));
                }
            }
        }
        let p = self.principal()?.0;
        let min = p.iter().copied().fold(f64::INFINITY, f64::min);
        if min.is_nan() || min <= 0.0 {
            return Err(format!(
                "inertia tensor {i:?} is not positive definite (principal moments {p:?})"
            ));
        }
        Ok(())
    }

    /// The principal moments (I₁, I₂, I₃) and the rotation principal frame → shape frame.
    pub(crate) fn principal(&self) -> Result<([f64; 3], parry::math::Rotation), String> {
        use parry::math::{Matrix, Vector};
        let i = &self.inertia;
        let m = Matrix::from_cols(
            Vector::new(i[0][0], i[1][0], i[2][0]),
            Vector::new(i[0][1], i[1][1], i[2][1]),
            Vector::new(i[0][2], i[1][2], i[2][2]),
        );
        let mp = parry::mass_properties::MassProperties::with_inertia_matrix(
            Vector::from_array(self.local_com),
            self.mass,
            m,
        );
        let p = mp.principal_inertia();
        if !p.is_finite() {
            return Err(format!("inertia tensor {i:?}: no principal axes"));
        }
        // with_inertia_matrix drops negative eigenvalues to 0: check the trace too
        let trace = i[0][0] + i[1][1] + i[2][2];
        if trace.is_nan() || trace <= 0.0 || p.min_element() <= 1e-14 * trace {
            return Err(format!(
                "inertia tensor {i:?} is not positive definite (principal moments {p:?})"
            ));
        }
        Ok((p.to_array(), mp.principal_inertia_local_frame.normalize()))
    }
}

/// A body to simulate.
#[derive(Debug, Clone)]
pub struct RigidBodyDesc {
    /// the shape, defined in the body's shape frame
    pub shape: SharedShape,
    /// mass properties (shape frame)
    pub mass: MassProperties,
    /// origin of the shape frame, world
    pub position: [f64; 3],
    /// unit quaternion (w, x, y, z): shape frame → world
    pub orientation: [f64; 4],
    /// velocity of the centre of mass, world frame
    pub velocity: [f64; 3],
    /// angular velocity, world frame (converted to the body frame inside)
    pub angular_velocity: [f64; 3],
    /// index into the world's [`crate::world::MaterialTable`]
    pub material: u32,
    /// a fixed body does not move (infinite mass)
    pub fixed: bool,
}

/// An obstacle: a shape with a prescribed motion.
#[derive(Debug, Clone)]
pub struct RigidObstacle {
    /// name (for messages)
    pub name: String,
    /// `HalfSpace` for planes, any convex shape, `TriMesh`, `HeightField`, compounds
    pub shape: SharedShape,
    /// origin of the shape frame at t = 0, world
    pub position: [f64; 3],
    /// unit quaternion (w, x, y, z): shape frame → world, at t = 0
    pub orientation: [f64; 4],
    /// prescribed motion, as for sphere obstacles (a rotation turns the shape about the
    /// motion's axis through its centre)
    pub motion: Motion,
    /// index into the world's material table
    pub material: u32,
}

/// Why a rigid world cannot be built or stepped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RigidError {
    /// a quaternion is not finite or not of unit length (never normalized silently)
    #[error("{what}: orientation {q:?} (w, x, y, z) is not a finite unit quaternion (||q| - 1| must be <= 1e-9)")]
    Quaternion {
        /// "body 3", "obstacle 'floor'"
        what: String,
        /// the quaternion given
        q: [f64; 4],
    },
    /// invalid mass properties or density
    #[error("{what}: invalid mass properties: {detail}")]
    Mass {
        /// which body or shape
        what: String,
        /// what is wrong
        detail: String,
    },
    /// a non-finite position or velocity
    #[error("{what}: {field} {value:?} is not finite")]
    NonFinite {
        /// which body or obstacle
        what: String,
        /// which field
        field: &'static str,
        /// its value
        value: [f64; 3],
    },
    /// a material index out of the table
    #[error("{what}: material {material} is not in the material table ({count} materials)")]
    Material {
        /// which body or obstacle
        what: String,
        /// the index given
        material: u32,
        /// materials in the table
        count: usize,
    },
    /// an invalid setting, material law or motion
    #[error("invalid setting: {0}")]
    Settings(String),
    /// bodies interpenetrate at the start
    #[error("{count} interpenetrating contact point(s) at the start, deepest {depth} m between body {a} and {b:?} (limit {limit} m)")]
    Interpenetration {
        /// contact points deeper than the limit
        count: usize,
        /// deepest penetration (m)
        depth: f64,
        /// body of the deepest one
        a: usize,
        /// its partner
        b: Partner,
        /// the limit (`RigidSettings::max_initial_penetration`)
        limit: f64,
    },
    /// the overlap relaxation reached its time cap with interpenetrations left
    #[error("the overlap relaxation stopped at its time limit of {seconds} s after {sweeps} sweeps, {count} contact point(s) still interpenetrating (the deepest by {depth:.3e} m): start from fewer or shallower overlaps")]
    RelaxationTimedOut {
        /// the time cap (s)
        seconds: f64,
        /// sweeps done
        sweeps: usize,
        /// contact points deeper than the limit left
        count: usize,
        /// deepest penetration left (m)
        depth: f64,
    },
    /// parry has no contact-manifold algorithm for this pair of shapes
    #[error("no contact manifold between body {a} ({shape_a}) and {b:?} ({shape_b})")]
    Unsupported {
        /// body A
        a: usize,
        /// its shape type
        shape_a: String,
        /// partner
        b: Partner,
        /// its shape type
        shape_b: String,
    },
    /// the step's problem could not be built or solved
    #[error("step {step}: {detail}")]
    Solve {
        /// step index
        step: u64,
        /// what failed
        detail: String,
    },
    /// positions or velocities became non-finite
    #[error("non-finite state at step {0}")]
    NonFiniteState(u64),
    /// an invalid joint ([`crate::bodies::joints`])
    #[error("joint {joint}: {field}: {detail}")]
    Joint {
        /// the joint's index
        joint: usize,
        /// the field at fault ("body_a", "axis", "limits", "motor.max_force", ...)
        field: &'static str,
        /// what is wrong
        detail: String,
    },
}
