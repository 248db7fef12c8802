//! The scene model: the one description every entry point (the built-in scenes, scene files,
//! Python) builds a simulation from — bodies, obstacles with their motions, gravity, materials
//! with per-pair contact laws, and the step settings — and its validated conversion into a
//! [`World`] and [`Params`] ([`SceneModel::build`]).
//!
//! Every type here is serde (`deny_unknown_fields` on structs): a scene file is the
//! serialization of a [`SceneModel`]. Vectors are arrays `[x, y, z]`.
//!
//! # Bodies
//! A body is a [`BodySpec`] whose shape is one field ([`BodyShape`], [`crate::shape`]), or
//! a columnar [`SphereBatch`] (positions, radii, velocities, … as arrays: building 10⁶ spheres
//! is one tight loop). The world's spheres are the free bodies of `bodies` in order, then the
//! free spheres of each batch in order.
//!
//! A model whose bodies are all spheres ([`SceneModel::has_shapes`] false) builds the sphere
//! simulator's [`World`] ([`SceneModel::build`], the fast path, unchanged); a model with any
//! other shape (cuboid, capsule, cylinder, cone, convex hull or polyhedron, compound) runs in
//! the rigid-body simulator (`crate::scene::rigid`), where spheres are balls and every body
//! has an orientation (unit quaternion (w, x, y, z), refused if not of unit norm) and may
//! override its mass and inertia.
//!
//! A *fixed* body (`fixed = true`) does not become a sphere of the world: it becomes a fixed
//! obstacle [`Shape::Sphere`] (`inside = false`) of its radius and material, appended after
//! the model's obstacles (named `fixed-body-K` / `fixed-batch-B-K`). Contacts with it are then
//! sphere–obstacle contacts (infinite mass, no dof), which the assembly, the body-level
//! Gauss–Seidel and the position correction already handle; its mass and velocities are not
//! used (a nonzero velocity is refused).
//!
//! # Materials
//! Materials are names; `default` always exists. Every pair of materials has a contact law
//! ([`ContactLaw`]: μ, e, μ_r): the pair's entry of `materials.pairs` (symmetric: (a, b) is
//! (b, a)) or `materials.default`. With a single law for every pair the world carries no table
//! ([`World::materials`] = `None`) and the [`Params`]' μ, e, μ_r are that law: the numbers are
//! those of the one-material code path, bit for bit.
//!
//! # Validation ([`SceneError`])
//! Non-finite or nonpositive radius, mass, density; both or neither of mass and density;
//! unknown materials (in a body, an obstacle or a pair); invalid obstacles (non-unit normals
//! or axes, empty boxes, orifice wider than the silo, degenerate, non-finite or out-of-range
//! meshes, open or inconsistently oriented meshes used as containers or solids, infinite
//! shapes rotating about an axis that moves them); spheres overlapping at the start (count
//! and worst overlap; [`resolve_overlaps`] relaxes them); free spheres outside every
//! container or inside a solid obstacle or behind a plane ([`Shape::admits`]); a memory
//! estimate above the memory available ([`memory_estimate`]).

use crate::contact::candidate_pairs;
use crate::math::Vec3;
use crate::mesh::MeshError;
use crate::nsgs::NsgsSettings;
use crate::projection::{Projection, Velocities};
pub use crate::shape::{BodyShape, CompoundPart, ShapeError};
use crate::simulation::{Params, StepMethod};
use crate::world::{
    ContactLaw, MaterialTable, MeshSide, Motion, Obstacle, Shape, Sphere, World, GRAVITY,
};
use crate::Activation;
use coulomb::{InnerKind, Method, MethodParams, OuterKind, Settings};
use serde::{Deserialize, Serialize};

/// The name of the material that always exists.
pub const DEFAULT_MATERIAL: &str = "default";

fn default_material() -> String {
    DEFAULT_MATERIAL.to_string()
}

fn default_gravity() -> Vec3 {
    Vec3::new(0.0, 0.0, -GRAVITY)
}

/// The contact law of `Params::default()`: μ = 0.3, e = 0.2, μ_r = 0.
pub const DEFAULT_LAW: ContactLaw = ContactLaw::DEFAULT;

/// A scene: everything a simulation is built from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneModel {
    /// gravity vector (m/s²), default (0, 0, −9.81)
    #[serde(default = "default_gravity")]
    pub gravity: Vec3,
    /// materials and the contact laws of their pairs
    #[serde(default)]
    pub materials: Materials,
    /// bodies one by one
    #[serde(default)]
    pub bodies: Vec<BodySpec>,
    /// spheres in columns
    #[serde(default)]
    pub sphere_batches: Vec<SphereBatch>,
    /// obstacles
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// time step, θ, tolerance, step method
    #[serde(default)]
    pub step: StepSettings,
    /// joints between bodies (issue 53), bodies numbered as the rigid-body simulator's:
    /// `bodies` in order, then the spheres of each batch; a scene with joints goes to the
    /// rigid-body simulator ([`SceneModel::has_shapes`])
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub joints: Vec<crate::bodies::joints::JointDesc>,
}

impl Default for SceneModel {
    fn default() -> Self {
        Self {
            gravity: default_gravity(),
            materials: Materials::default(),
            bodies: Vec::new(),
            sphere_batches: Vec::new(),
            obstacles: Vec::new(),
            step: StepSettings::default(),
            joints: Vec::new(),
        }
    }
}

/// The materials of a scene: their names (besides `default`), the law of every pair not
/// listed, and the listed pairs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Materials {
    /// material names besides `default` (which may be listed too)
    #[serde(default)]
    pub names: Vec<String>,
    /// the law of every pair not in `pairs` (default μ = 0.3, e = 0.2, μ_r = 0, also for a
    /// coefficient not given)
    #[serde(default)]
    pub default: ContactLaw,
    /// the laws of given pairs (symmetric)
    #[serde(default)]
    pub pairs: Vec<MaterialPair>,
}

impl Default for Materials {
    fn default() -> Self {
        Self {
            names: Vec::new(),
            default: DEFAULT_LAW,
            pairs: Vec::new(),
        }
    }
}

/// The contact law of a pair of materials, which is also that of the pair reversed: a scene
/// file's `[[pairs]]` entry. A coefficient not given is the default law's
/// ([`MaterialPair::law`], the one place a pair inherits).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialPair {
    /// the two materials (the same name twice for contacts within one material)
    pub materials: [String; 2],
    /// friction coefficient μ (default: the default law's)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// restitution e (default: the default law's)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restitution: Option<f64>,
    /// rolling friction μ_r (default: the default law's)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rolling_friction: Option<f64>,
}

impl MaterialPair {
    /// The pair's law: its coefficients, `default`'s where it gives none.
    pub fn law(&self, default: ContactLaw) -> ContactLaw {
        ContactLaw {
            mu: self.mu.unwrap_or(default.mu),
            restitution: self.restitution.unwrap_or(default.restitution),
            rolling_friction: self.rolling_friction.unwrap_or(default.rolling_friction),
        }
    }
}

/// Where [`Materials::check_key`] found a law refused: a scene file's error names its place.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LawKey {
    /// the default law
    Default,
    /// pair k (its law, or the pair given twice)
    Pair(usize),
    /// material i (0 or 1) of pair k
    PairMaterial(usize, usize),
}

impl Materials {
    /// The declared names, `default` first; refuses a name declared twice.
    fn declared(&self) -> Result<Vec<String>, SceneError> {
        let mut names = vec![default_material()];
        for n in self.names.iter().filter(|n| *n != DEFAULT_MATERIAL) {
            if names.contains(n) {
                return Err(SceneError::DuplicateMaterial(n.clone()));
            }
            names.push(n.clone());
        }
        Ok(names)
    }

    /// Refuses the default law or a pair out of range ([`ContactLaw::check`]), a pair naming
    /// an undeclared material, a pair given twice (in either order), with the place refused.
    pub fn check_key(&self) -> Result<(), (LawKey, SceneError)> {
        let names = self.declared().map_err(|e| (LawKey::Default, e))?;
        let d = self.default;
        d.check().map_err(|reason| {
            let reason = format!("the default law: {reason}");
            let (a, b) = (default_material(), default_material());
            (LawKey::Default, SceneError::InvalidLaw { a, b, reason })
        })?;
        let index = MaterialIndex { names };
        let mut seen = Vec::new();
        for (k, p) in self.pairs.iter().enumerate() {
            let mut ab = [0; 2];
            for (i, name) in p.materials.iter().enumerate() {
                ab[i] = index
                    .get(|| format!("material pair {k}"), name)
                    .map_err(|e| (LawKey::PairMaterial(k, i), e))?;
            }
            let invalid = |reason: String| {
                let [a, b] = p.materials.clone();
                (LawKey::Pair(k), SceneError::InvalidLaw { a, b, reason })
            };
            let key = (ab[0].min(ab[1]), ab[0].max(ab[1]));
            if seen.contains(&key) {
                return Err(invalid("the pair is given twice".into()));
            }
            seen.push(key);
            p.law(d).check().map_err(invalid)?;
        }
        Ok(())
    }
}

/// One body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// its shape
    pub shape: BodyShape,
    /// origin of the shape frame (m): a sphere's centre
    pub position: Vec3,
    /// unit quaternion (w, x, y, z) turning the shape frame into the world frame (default
    /// identity); refused, not normalized, when not of unit norm. Spheres keep no
    /// orientation in the sphere simulator (their orientation is reported as the identity).
    #[serde(default = "identity_quaternion")]
    pub orientation: [f64; 4],
    /// velocity (m/s) of the centre of mass
    #[serde(default)]
    pub velocity: Vec3,
    /// angular velocity (rad/s, world frame)
    #[serde(default)]
    pub angular_velocity: Vec3,
    /// mass (kg); exactly one of `mass` and `density` (with `mass`, a non-sphere shape's
    /// inertia is that of a uniform body of that mass)
    #[serde(default)]
    pub mass: Option<f64>,
    /// density (kg/m³); exactly one of `mass` and `density`
    #[serde(default)]
    pub density: Option<f64>,
    /// inertia tensor about the centre of mass in the shape frame (kg m²), replacing the
    /// shape's (non-sphere shapes only: symmetric positive definite)
    #[serde(default)]
    pub inertia: Option<[[f64; 3]; 3]>,
    /// centre of mass in the shape frame (m), replacing the shape's centroid (non-sphere
    /// shapes only, with `inertia`, the tensor about it): a body whose mass is not
    /// distributed as its collision shape's volume (a URDF link's `inertial` origin)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre_of_mass: Option<[f64; 3]>,
    /// material name
    #[serde(default = "default_material")]
    pub material: String,
    /// immobile (becomes a fixed obstacle, see the module docs)
    #[serde(default)]
    pub fixed: bool,
}

impl BodySpec {
    /// A free sphere at rest of radius R and density ρ, material `default`.
    pub fn sphere(position: Vec3, radius: f64, density: f64) -> Self {
        Self {
            shape: BodyShape::Sphere { radius },
            position,
            orientation: identity_quaternion(),
            velocity: Vec3::ZERO,
            angular_velocity: Vec3::ZERO,
            mass: None,
            density: Some(density),
            inertia: None,
            centre_of_mass: None,
            material: default_material(),
            fixed: false,
        }
    }

    /// A free body of any shape at rest, in the orientation (w, x, y, z), of density ρ,
    /// material `default`.
    pub fn new(shape: BodyShape, position: Vec3, orientation: [f64; 4], density: f64) -> Self {
        Self {
            shape,
            orientation,
            ..Self::sphere(position, 1.0, density)
        }
    }
}

fn identity_quaternion() -> [f64; 4] {
    crate::shape::IDENTITY
}

/// Spheres in columns: one entry per sphere in each array (`radii` and `masses` may also have
/// a single entry for all; `velocities`, `angular_velocities` may be empty: at rest).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereBatch {
    /// centres (m)
    pub positions: Vec<Vec3>,
    /// radii (m): one per sphere, or one for all
    pub radii: Vec<f64>,
    /// velocities (m/s): one per sphere, or none
    #[serde(default)]
    pub velocities: Vec<Vec3>,
    /// angular velocities (rad/s): one per sphere, or none
    #[serde(default)]
    pub angular_velocities: Vec<Vec3>,
    /// density (kg/m³) of every sphere; exactly one of `density` and `masses`
    #[serde(default)]
    pub density: Option<f64>,
    /// masses (kg): one per sphere, or one for all
    #[serde(default)]
    pub masses: Vec<f64>,
    /// material of every sphere
    #[serde(default = "default_material")]
    pub material: String,
    /// immobile spheres (fixed obstacles)
    #[serde(default)]
    pub fixed: bool,
}

impl Default for SphereBatch {
    /// No spheres, material `default`, free.
    fn default() -> Self {
        Self {
            positions: Vec::new(),
            radii: Vec::new(),
            velocities: Vec::new(),
            angular_velocities: Vec::new(),
            density: None,
            masses: Vec::new(),
            material: default_material(),
            fixed: false,
        }
    }
}

/// An obstacle of the scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    /// a name for outputs (default `obstacle-K`)
    #[serde(default)]
    pub name: String,
    /// its shape in the reference position
    pub shape: Shape,
    /// its prescribed motion (default fixed)
    #[serde(default)]
    pub motion: Motion,
    /// material name
    #[serde(default = "default_material")]
    pub material: String,
}

impl ObstacleSpec {
    /// A fixed obstacle of material `default`.
    pub fn fixed(name: &str, shape: Shape) -> Self {
        Self {
            name: name.to_string(),
            shape,
            motion: Motion::Fixed,
            material: default_material(),
        }
    }
}

/// Which solver takes each step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepChoice {
    /// body-level nonsmooth Gauss–Seidel, finished by the library's solver where it stalls
    /// (the default of `coulomb simulate`)
    #[default]
    Nsgs,
    /// the library's solver on the assembled problem of each step
    Library,
}

/// The time stepping of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepSettings {
    /// time step h (s), default 0.02
    #[serde(default = "d_h")]
    pub h: f64,
    /// θ of (2.7), default 0.5
    #[serde(default = "d_theta")]
    pub theta: f64,
    /// tolerance on the error of docs/error.md at every step, default 1e-4
    #[serde(default = "d_tol")]
    pub tol: f64,
    /// step solver, default `nsgs`
    #[serde(default)]
    pub method: StepChoice,
    /// cap on Gauss–Seidel sweeps per step (nsgs), default 20 000
    #[serde(default = "d_sweeps")]
    pub max_sweeps: usize,
    /// over-relaxation ω ∈ [1, 2) (nsgs), default 1.5
    #[serde(default = "d_relax")]
    pub relaxation: f64,
    /// γ ≥ 0 of the activation rule g + γ h min(u_N, 0) ≤ δ, default 1
    #[serde(default = "d_gamma")]
    pub gamma: f64,
    /// position correction after each step, default true
    #[serde(default = "yes")]
    pub projection: bool,
    /// what the position correction does to velocities (`None`: rescale, for spheres;
    /// scenes with other shapes move positions only and refuse any other choice)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub projection_velocities: Option<Velocities>,
    /// gap closure of resting contacts ([`crate::assembly::gap_closure`]), default true
    #[serde(default = "yes")]
    pub gap_closure: bool,
    /// warm starts from the previous step's impulses, default true
    #[serde(default = "yes")]
    pub warm_start: bool,
}

fn d_gamma() -> f64 {
    1.0
}
fn yes() -> bool {
    true
}

fn d_h() -> f64 {
    0.02
}
fn d_theta() -> f64 {
    0.5
}
fn d_tol() -> f64 {
    1e-4
}
fn d_sweeps() -> usize {
    20_000
}
fn d_relax() -> f64 {
    1.5
}

impl Default for StepSettings {
    fn default() -> Self {
        Self {
            h: d_h(),
            theta: d_theta(),
            tol: d_tol(),
            method: StepChoice::Nsgs,
            max_sweeps: d_sweeps(),
            relaxation: d_relax(),
            gamma: d_gamma(),
            projection: true,
            projection_velocities: None,
            gap_closure: true,
            warm_start: true,
        }
    }
}

impl StepSettings {
    /// The [`Params`] of these settings with the contact law `law` (the parameters of
    /// `coulomb simulate` with its default arguments otherwise: accurate activation with
    /// these γ and gap closure, these position correction and warm starts; the library's solver with Gauss–Seidel inner iterations fused
    /// with the law, APGD + Anderson as fallback, up to 20 outer iterations).
    pub fn params(&self, law: ContactLaw) -> Params {
        let d = Settings::time_stepping(Method::new(InnerKind::Pgs, Settings::default().outer));
        let solver = Settings {
            tol: self.tol,
            max_outer: 20,
            params: MethodParams {
                fixed_point_tol: None,
                ..d.params
            },
            outer: OuterKind::Fused,
            fallback: Some((InnerKind::Apgd, OuterKind::Anderson)),
            ..d
        };
        Params {
            h: self.h,
            theta: self.theta,
            restitution: law.restitution,
            mu: law.mu,
            activation: Activation {
                gamma: self.gamma,
                close_gaps: self.gap_closure,
                ..Activation::accurate()
            },
            solver,
            warm_start: self.warm_start,
            projection: self.projection.then(|| Projection {
                velocities: self.projection_velocities.unwrap_or(Velocities::Rescale),
                ..Projection::default()
            }),
            method: match self.method {
                StepChoice::Nsgs => StepMethod::Nsgs(NsgsSettings {
                    tol: self.tol,
                    max_sweeps: self.max_sweeps,
                    relaxation: self.relaxation,
                    ..NsgsSettings::default()
                }),
                StepChoice::Library => StepMethod::Library,
            },
            rolling_friction: law.rolling_friction,
        }
    }

    /// Refuses invalid step settings (h, θ, tolerance, sweep cap, relaxation, γ, a
    /// `projection_velocities` without projection).
    pub fn check(&self) -> Result<(), SceneError> {
        self.check_key()
            .map_err(|(_, reason)| SceneError::InvalidStep(reason))
    }

    /// [`Self::check`] with the key of the setting refused (`h`, `theta`, `tol`,
    /// `max_sweeps`, `relaxation`, `gamma`, `projection_velocities`): a scene file's error
    /// names its place.
    pub fn check_key(&self) -> Result<(), (&'static str, String)> {
        if !(self.h.is_finite() && self.h > 0.0) {
            return Err((
                "h",
                format!("h = {} must be a positive number of seconds", self.h),
            ));
        }
        if !(0.0..=1.0).contains(&self.theta) {
            return Err(("theta", format!("theta = {} is not in [0, 1]", self.theta)));
        }
        coulomb::settings::check_tol(self.tol).map_err(|m| ("tol", m))?;
        if self.max_sweeps == 0 {
            return Err(("max_sweeps", "max_sweeps must be at least 1".into()));
        }
        if !(self.relaxation.is_finite() && (1.0..2.0).contains(&self.relaxation)) {
            return Err((
                "relaxation",
                format!("relaxation = {} is not in [1, 2)", self.relaxation),
            ));
        }
        if !(self.gamma.is_finite() && self.gamma >= 0.0) {
            return Err(("gamma", format!("gamma = {} must be ≥ 0", self.gamma)));
        }
        if self.projection_velocities.is_some() && !self.projection {
            return Err((
                "projection_velocities",
                "there is no position correction (projection = false) to apply it to".into(),
            ));
        }
        Ok(())
    }
}

/// Why a scene cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// a body, obstacle or pair names a material that is not declared
    #[error("{what}: unknown material '{name}' (declared: {known})")]
    UnknownMaterial {
        /// where ("body 3", "obstacle 1 ('floor')", "material pair 0")
        what: String,
        /// the unknown name
        name: String,
        /// the declared names, comma-separated
        known: String,
    },
    /// a material is declared twice
    #[error("material '{0}' is declared twice")]
    DuplicateMaterial(String),
    /// a pair's law is out of range, or a pair is given twice
    #[error("material pair ({a}, {b}): {reason}")]
    InvalidLaw {
        /// first material
        a: String,
        /// second material
        b: String,
        /// what is wrong
        reason: String,
    },
    /// a body's data are invalid
    #[error("{what}: {reason}")]
    InvalidBody {
        /// where ("body 3", "sphere batch 0, sphere 17")
        what: String,
        /// what is wrong
        reason: String,
    },
    /// an obstacle's data are invalid
    #[error("obstacle {index} ('{name}'): {reason}")]
    InvalidObstacle {
        /// obstacle index in the model
        index: usize,
        /// its name
        name: String,
        /// what is wrong
        reason: String,
    },
    /// a mesh obstacle is invalid
    #[error("obstacle {index} ('{name}'): {source}")]
    Mesh {
        /// obstacle index in the model
        index: usize,
        /// its name
        name: String,
        /// the mesh problem
        source: MeshError,
    },
    /// the step settings are invalid
    #[error("step settings: {0}")]
    InvalidStep(String),
    /// gravity is not finite
    #[error("gravity {0:?} is not finite")]
    InvalidGravity([f64; 3]),
    /// spheres overlap at the start
    #[error("{count} pair(s) of spheres overlap at the start, the worst by {worst:.3e} m (world spheres {pair:?}); relax them first (resolve_overlaps)")]
    Overlaps {
        /// overlapping pairs
        count: usize,
        /// largest overlap (m)
        worst: f64,
        /// the worst pair (world sphere indices)
        pair: (usize, usize),
    },
    /// the overlap relaxation reached its time cap with overlaps left
    #[error("the overlap relaxation stopped at its time limit of {seconds} s after {sweeps} sweeps, {count} pair(s) still overlapping (the worst by {worst:.3e} m): start from fewer or shallower overlaps")]
    RelaxationTimedOut {
        /// the time cap (s)
        seconds: f64,
        /// sweeps done
        sweeps: usize,
        /// overlapping pairs left
        count: usize,
        /// largest overlap left (m)
        worst: f64,
    },
    /// free spheres overlap an obstacle at the start (centre on the free side, but closer to
    /// it than their radius): released, they would be pushed out with energy from nowhere
    #[error("{count} sphere(s) overlap an obstacle at the start, the worst sphere {sphere} by {depth:.3e} m into obstacle {obstacle} ('{name}'); move them out, or relax them first (resolve_overlaps, `coulomb simulate --resolve-overlaps N`)")]
    Penetration {
        /// spheres overlapping some obstacle
        count: usize,
        /// the worst (world sphere index)
        sphere: usize,
        /// its obstacle (world obstacle index)
        obstacle: usize,
        /// the obstacle's name
        name: String,
        /// its overlap (m)
        depth: f64,
    },
    /// a free sphere's centre is where no sphere may be
    #[error("{what} at {position:?} is {reason}")]
    Outside {
        /// which body
        what: String,
        /// its centre
        position: [f64; 3],
        /// "outside every container", "inside obstacle 2 ('rock')", …
        reason: String,
    },
    /// the rigid-body simulator refused the scene (interpenetrating bodies, invalid mass
    /// properties, …)
    #[error("rigid bodies: {0}")]
    Rigid(crate::bodies::rigid::RigidError),
    /// the scene would need more memory than the machine has
    #[error("the scene needs about {estimate} bytes ({spheres} spheres, {triangles} mesh triangles), more than the {available} bytes of memory available")]
    Memory {
        /// spheres
        spheres: usize,
        /// triangles of all meshes
        triangles: usize,
        /// estimate (bytes)
        estimate: u64,
        /// MemAvailable of /proc/meminfo (bytes)
        available: u64,
    },
}

/// What [`SceneModel::build_with`] checks beyond the data's validity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BuildChecks {
    /// refuse overlapping spheres
    pub overlaps: bool,
    /// refuse free spheres outside every container, inside a solid, behind a plane
    pub containment: bool,
    /// refuse scenes whose memory estimate exceeds MemAvailable
    pub memory: bool,
}

impl Default for BuildChecks {
    fn default() -> Self {
        Self {
            overlaps: true,
            containment: true,
            memory: true,
        }
    }
}

/// Estimated bytes per sphere of a running simulation: the sphere (112), its blocks of the
/// step problem (mass, M⁻¹, f, v: 192), the broad phase (48) and about 3 contacts per sphere
/// (contact 184, Gauss–Seidel row 272, warm start 48, colouring 16: ≈ 1 560), rounded up.
pub const BYTES_PER_SPHERE: u64 = 2_048;
/// Estimated bytes per mesh triangle (indices, hierarchy node share, vertices).
pub const BYTES_PER_TRIANGLE: u64 = 128;

/// The memory a simulation of `spheres` spheres and `triangles` mesh triangles needs, about
/// (bytes).
pub fn memory_estimate(spheres: usize, triangles: usize) -> u64 {
    (spheres as u64)
        .saturating_mul(BYTES_PER_SPHERE)
        .saturating_add((triangles as u64).saturating_mul(BYTES_PER_TRIANGLE))
        .saturating_add(64 << 20)
}

/// MemAvailable of /proc/meminfo (bytes), `None` where it cannot be read.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb.saturating_mul(1024))
}

/// Refuses a scene of `spheres` spheres and `triangles` mesh triangles whose
/// [`memory_estimate`] exceeds `available` bytes (no check when `None`).
pub fn check_memory(
    spheres: usize,
    triangles: usize,
    available: Option<u64>,
) -> Result<(), SceneError> {
    let estimate = memory_estimate(spheres, triangles);
    match available {
        Some(available) if estimate > available => Err(SceneError::Memory {
            spheres,
            triangles,
            estimate,
            available,
        }),
        _ => Ok(()),
    }
}

/// Overlaps of the spheres of a world: pairs with gap < −10⁻⁹ (R_A + R_B).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Overlaps {
    /// overlapping pairs
    pub count: usize,
    /// largest overlap (m), 0 when none
    pub worst: f64,
    /// the worst pair
    pub pair: (usize, usize),
}

/// The overlapping sphere pairs of `world` (broad phase of [`crate::contact`], O(N)).
pub fn overlaps(world: &World) -> Overlaps {
    let mut o = Overlaps::default();
    for (i, j) in candidate_pairs(world, 0.0) {
        let (a, b) = (&world.bodies[i], &world.bodies[j]);
        let sum = a.radius + b.radius;
        let depth = sum - (a.position - b.position).norm();
        if depth > 1e-9 * sum {
            o.count += 1;
            if depth > o.worst {
                o.worst = depth;
                o.pair = (i, j);
            }
        }
    }
    o
}

/// The free spheres of `world` that overlap an obstacle at t = 0 by more than 10⁻⁹ of their
/// radius (gap < 0 at a feature of an obstacle that admits their centre: a centre that is
/// not admitted is [`check_containment`]'s): `None` when there is none, else the refusal
/// naming the deepest (sphere, obstacle, overlap) and their count.
pub fn obstacle_penetration(world: &World) -> Option<SceneError> {
    let mut buf = Vec::new();
    let mut worst: Option<(usize, usize, f64)> = None;
    let mut count = 0;
    for (i, b) in world.bodies.iter().enumerate() {
        let mut deepest: Option<(usize, f64)> = None;
        for (k, ob) in world.obstacles.iter().enumerate() {
            buf.clear();
            ob.proximities(b.position, b.radius, 0.0, 0.0, &mut buf);
            for (_, p) in &buf {
                let depth = -p.gap;
                if depth > 1e-9 * b.radius
                    && ob.admits(b.position, 0.0)
                    && deepest.is_none_or(|(_, d)| depth > d)
                {
                    deepest = Some((k, depth));
                }
            }
        }
        if let Some((k, d)) = deepest {
            count += 1;
            if worst.is_none_or(|(_, _, w)| d > w) {
                worst = Some((i, k, d));
            }
        }
    }
    worst.map(|(sphere, obstacle, depth)| SceneError::Penetration {
        count,
        sphere,
        obstacle,
        name: world.obstacles[obstacle].name.clone(),
        depth,
    })
}

/// Result of [`resolve_overlaps`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Resolved {
    /// Gauss–Seidel sweeps done
    pub sweeps: usize,
    /// overlaps left (none when `count` is 0)
    pub left: Overlaps,
    /// the relaxation stopped at its time limit ([`RELAXATION_TIME_LIMIT`]) with sweeps left
    pub timed_out: bool,
}

/// The time cap of an overlap relaxation (`--resolve-overlaps`, Python's `resolve_overlaps=`),
/// besides its sweep cap: spheres ([`resolve_overlaps`]) and bodies of any shape
/// ([`crate::step::rigid::RigidWorld::relax_overlaps`]). A relaxation that reaches it with overlaps
/// left is refused, saying so.
pub const RELAXATION_TIME_LIMIT: std::time::Duration = std::time::Duration::from_secs(300);

/// Relaxes the overlaps of the spheres of `world`: Gauss–Seidel sweeps over the overlapping
/// pairs (each moves both centres apart along their line by half the overlap, and 0.1 % more)
/// and over the spheres penetrating an obstacle whose centre it admits (moved out along the
/// normal), at most `max_sweeps` sweeps; the velocities are not changed. Deterministic (pairs
/// in (i, j) order).
pub fn resolve_overlaps(world: &mut World, max_sweeps: usize) -> Resolved {
    resolve_overlaps_within(world, max_sweeps, RELAXATION_TIME_LIMIT)
}

/// [`resolve_overlaps`] stopped after `time_limit` (checked before each sweep, so that the
/// sweeps done are whole and the same on every machine that finishes them in time).
pub fn resolve_overlaps_within(
    world: &mut World,
    max_sweeps: usize,
    time_limit: std::time::Duration,
) -> Resolved {
    let start = std::time::Instant::now();
    let mut sweeps = 0;
    let mut buf = Vec::new();
    let mut timed_out = false;
    while sweeps < max_sweeps {
        if start.elapsed() >= time_limit {
            timed_out = true;
            break;
        }
        let pairs = candidate_pairs(world, 0.0);
        let mut moved = false;
        for (i, j) in pairs {
            let (xa, xb) = (world.bodies[i].position, world.bodies[j].position);
            let sum = world.bodies[i].radius + world.bodies[j].radius;
            let d = xa - xb;
            let depth = sum - d.norm();
            if depth > 1e-9 * sum {
                let n = d.normalized_or(Vec3::Z);
                let push = n * (0.5 * depth * 1.001);
                world.bodies[i].position += push;
                world.bodies[j].position += -push;
                moved = true;
            }
        }
        for b in world.bodies.iter_mut() {
            for ob in &world.obstacles {
                buf.clear();
                ob.proximities(b.position, b.radius, 0.0, 0.0, &mut buf);
                for (_, p) in &buf {
                    if p.gap < -1e-9 * b.radius && ob.admits(b.position, 0.0) {
                        b.position += p.normal * (-p.gap * 1.001);
                        moved = true;
                    }
                }
            }
        }
        sweeps += 1;
        if !moved {
            break;
        }
    }
    let left = overlaps(world);
    Resolved {
        sweeps,
        left,
        timed_out: timed_out && left.count > 0,
    }
}

/// Result of [`relax`]: the overlaps found, and the relaxation's [`Resolved`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Relaxation {
    /// overlaps before the relaxation
    pub before: Overlaps,
    /// sweeps done and overlaps left (none: `relax` refuses the world otherwise)
    pub done: Resolved,
}

/// `--resolve-overlaps` (and Python's `resolve_overlaps=`) on a world built without the
/// overlap and containment checks: [`resolve_overlaps`] in at most `max_sweeps` sweeps, then
/// the checks the build skipped: containment ([`check_containment`]), spheres still inside an
/// obstacle ([`obstacle_penetration`]) and overlaps left ([`SceneError::Overlaps`]).
pub fn relax(world: &mut World, max_sweeps: usize) -> Result<Relaxation, SceneError> {
    relax_within(world, max_sweeps, RELAXATION_TIME_LIMIT)
}

/// [`relax`] with the time cap `time_limit` instead of [`RELAXATION_TIME_LIMIT`].
pub fn relax_within(
    world: &mut World,
    max_sweeps: usize,
    time_limit: std::time::Duration,
) -> Result<Relaxation, SceneError> {
    let before = overlaps(world);
    let done = resolve_overlaps_within(world, max_sweeps, time_limit);
    if done.timed_out {
        return Err(SceneError::RelaxationTimedOut {
            seconds: time_limit.as_secs_f64(),
            sweeps: done.sweeps,
            count: done.left.count,
            worst: done.left.worst,
        });
    }
    check_containment(world)?;
    if let Some(e) = obstacle_penetration(world) {
        return Err(e);
    }
    if done.left.count > 0 {
        return Err(SceneError::Overlaps {
            count: done.left.count,
            worst: done.left.worst,
            pair: done.left.pair,
        });
    }
    Ok(Relaxation { before, done })
}

/// A name → index map of the materials of a model.
struct MaterialIndex {
    names: Vec<String>,
}

impl MaterialIndex {
    fn get(&self, what: impl FnOnce() -> String, name: &str) -> Result<u32, SceneError> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| i as u32)
            .ok_or_else(|| SceneError::UnknownMaterial {
                what: what(),
                name: name.to_string(),
                known: self.names.join(", "),
            })
    }
}

fn positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

/// Mass of a ball of radius r and density ρ: ρ · 4/3 · π r³ (evaluated as the built-in
/// scenes always did).
pub fn ball_mass(density: f64, r: f64) -> f64 {
    density * 4.0 / 3.0 * std::f64::consts::PI * r * r * r
}

impl SceneModel {
    /// The material table (index order: `default`, then `materials.names` in order) and
    /// whether every pair has the same law (then the world carries no table).
    pub fn material_table(&self) -> Result<(MaterialTable, bool), SceneError> {
        let m = &self.materials;
        m.check_key().map_err(|(_, e)| e)?;
        let names = m.declared()?;
        let index = |n: &str| names.iter().position(|x| x == n).unwrap_or(0) as u32;
        let mut table = MaterialTable::uniform(names.clone(), m.default);
        for p in &m.pairs {
            let [a, b] = &p.materials;
            table.set(index(a), index(b), p.law(m.default));
        }
        let uniform = table.laws.iter().all(|l| *l == m.default);
        Ok((table, uniform))
    }

    /// Whether some body is not a sphere: then the scene runs in the rigid-body simulator
    /// (spheres as balls), else in the sphere simulator ([`SceneModel::build`]).
    pub fn has_shapes(&self) -> bool {
        self.bodies.iter().any(|b| !b.shape.is_sphere()) || !self.joints.is_empty()
    }

    /// Number of free spheres the world will have.
    pub fn sphere_count(&self) -> usize {
        self.bodies.iter().filter(|b| !b.fixed).count()
            + self
                .sphere_batches
                .iter()
                .filter(|b| !b.fixed)
                .map(|b| b.positions.len())
                .sum::<usize>()
    }

    /// Total triangles of the mesh obstacles.
    pub fn triangle_count(&self) -> usize {
        self.obstacles
            .iter()
            .map(|o| match &o.shape {
                Shape::Mesh { mesh, .. } => mesh.triangles().len(),
                _ => 0,
            })
            .sum()
    }

    /// The world and parameters of the scene, with every check ([`BuildChecks::default`]).
    pub fn build(&self) -> Result<(World, Params), SceneError> {
        self.build_with(&BuildChecks::default())
    }

    /// The world and parameters of the scene: the data validated, then the checks asked for.
    pub fn build_with(&self, checks: &BuildChecks) -> Result<(World, Params), SceneError> {
        self.step.check()?;
        if checks.memory {
            check_memory(
                self.sphere_count(),
                self.triangle_count(),
                available_memory(),
            )?;
        }
        let world = self.world()?;
        if checks.containment {
            check_containment(&world)?;
        }
        if checks.overlaps {
            if let Some(e) = obstacle_penetration(&world) {
                return Err(e);
            }
            let o = overlaps(&world);
            if o.count > 0 {
                return Err(SceneError::Overlaps {
                    count: o.count,
                    worst: o.worst,
                    pair: o.pair,
                });
            }
        }
        let params = self.step.params(self.materials.default);
        Ok((world, params))
    }

    /// The world of the scene, the data validated (materials, bodies, obstacles, gravity),
    /// without the checks of [`BuildChecks`].
    pub fn world(&self) -> Result<World, SceneError> {
        if !self.joints.is_empty() {
            return Err(SceneError::InvalidStep(format!(
                "{} joint(s): joints are simulated by the rigid-body simulator (a scene with joints is built with RigidScene), not the sphere simulator",
                self.joints.len()
            )));
        }
        let g = self.gravity;
        if !g.is_finite() {
            return Err(SceneError::InvalidGravity(g.to_array()));
        }
        let (table, uniform) = self.material_table()?;
        let index = MaterialIndex {
            names: table.names.clone(),
        };
        let mut world = World::new();
        world.gravity = g;
        world.materials = (!uniform).then(|| table.clone());
        for (k, spec) in self.obstacles.iter().enumerate() {
            let name = if spec.name.is_empty() {
                format!("obstacle-{k}")
            } else {
                spec.name.clone()
            };
            check_obstacle(k, &name, &spec.shape, &spec.motion)?;
            let material = index.get(|| format!("obstacle {k} ('{name}')"), &spec.material)?;
            world.obstacles.push(Obstacle {
                name,
                shape: spec.shape.clone(),
                motion: spec.motion.clone(),
                material,
            });
        }
        let mut fixed = Vec::new();
        world.bodies.reserve(self.sphere_count());
        for (k, b) in self.bodies.iter().enumerate() {
            let what = || format!("body {k}");
            let material = index.get(what, &b.material)?;
            let sphere = body_sphere(b, material).map_err(|reason| SceneError::InvalidBody {
                what: what(),
                reason,
            })?;
            if b.fixed {
                fixed.push((format!("fixed-body-{k}"), sphere));
            } else {
                world.bodies.push(sphere);
            }
        }
        for (k, batch) in self.sphere_batches.iter().enumerate() {
            let material = index.get(|| format!("sphere batch {k}"), &batch.material)?;
            let spheres = batch_spheres(k, batch, material)?;
            if batch.fixed {
                for (i, s) in spheres.into_iter().enumerate() {
                    fixed.push((format!("fixed-batch-{k}-{i}"), s));
                }
            } else {
                world.bodies.extend(spheres);
            }
        }
        for (name, s) in fixed {
            world.obstacles.push(Obstacle {
                name,
                shape: Shape::Sphere {
                    center: s.position,
                    radius: s.radius,
                    inside: false,
                },
                motion: Motion::Fixed,
                material: s.material,
            });
        }
        if world.materials.is_none() {
            // one law for every pair: no table, so every material is index 0 (the
            // one-material path; `Simulation::new` refuses indices beyond the table)
            for b in &mut world.bodies {
                b.material = 0;
            }
            for o in &mut world.obstacles {
                o.material = 0;
            }
        }
        Ok(world)
    }

    /// The spheres of `batch` with the materials of this model (an inlet's new spheres,
    /// [`crate::Simulation::insert_bodies`]); the batch's `fixed` flag is ignored.
    pub fn spheres_of(&self, batch: &SphereBatch) -> Result<Vec<Sphere>, SceneError> {
        let (table, uniform) = self.material_table()?;
        let index = MaterialIndex { names: table.names };
        let material = index.get(|| "inserted sphere batch".into(), &batch.material)?;
        // without a table (one law) every material is index 0, as in `world`
        batch_spheres(0, batch, if uniform { 0 } else { material })
    }
}

/// The sphere of a body spec (its velocities unchecked for fixed bodies beyond being zero).
fn body_sphere(b: &BodySpec, material: u32) -> Result<Sphere, String> {
    let BodyShape::Sphere { radius } = b.shape else {
        return Err(format!(
            "a {} is not a sphere: scenes with other shapes run in the rigid-body simulator (SceneModel::has_shapes)",
            b.shape.kind()
        ));
    };
    crate::shape::check_quaternion("orientation", b.orientation).map_err(|e| e.to_string())?;
    if b.inertia.is_some() {
        return Err("a sphere's inertia is 2/5 m R²: `inertia` is for other shapes".into());
    }
    if b.centre_of_mass.is_some() {
        return Err(
            "a sphere's centre of mass is its centre: `centre_of_mass` is for other shapes".into(),
        );
    }
    if !positive(radius) {
        return Err(format!("radius {radius} is not a finite positive number"));
    }
    let mass = match (b.mass, b.density) {
        (Some(m), None) if positive(m) => m,
        (None, Some(rho)) if positive(rho) => ball_mass(rho, radius),
        (Some(m), None) => return Err(format!("mass {m} is not a finite positive number")),
        (None, Some(rho)) => return Err(format!("density {rho} is not a finite positive number")),
        (Some(_), Some(_)) => return Err("give a mass or a density, not both".into()),
        (None, None) => return Err("give a mass or a density".into()),
    };
    if !(b.position.is_finite() && b.velocity.is_finite() && b.angular_velocity.is_finite()) {
        return Err("non-finite position, velocity or angular velocity".into());
    }
    if b.fixed && (b.velocity != Vec3::ZERO || b.angular_velocity != Vec3::ZERO) {
        return Err("a fixed body cannot have a velocity (use a moving obstacle)".into());
    }
    Ok(Sphere {
        position: b.position,
        velocity: b.velocity,
        angular_velocity: b.angular_velocity,
        radius,
        mass,
        rotation_locked: false,
        material,
    })
}

/// The spheres of a batch, validated (one tight loop).
fn batch_spheres(k: usize, batch: &SphereBatch, material: u32) -> Result<Vec<Sphere>, SceneError> {
    let n = batch.positions.len();
    let bad = |what: String, reason: String| SceneError::InvalidBody { what, reason };
    let len_ok = |len: usize, allow_empty: bool, allow_one: bool| {
        len == n || (allow_empty && len == 0) || (allow_one && len == 1)
    };
    let field = |name: &str, len: usize, rule: &str| {
        bad(
            format!("sphere batch {k}"),
            format!("{name} has {len} entries for {n} spheres ({rule})"),
        )
    };
    if !len_ok(batch.radii.len(), false, true) {
        return Err(field(
            "radii",
            batch.radii.len(),
            "one per sphere or one for all",
        ));
    }
    if !len_ok(batch.velocities.len(), true, false) {
        return Err(field(
            "velocities",
            batch.velocities.len(),
            "one per sphere or none",
        ));
    }
    if !len_ok(batch.angular_velocities.len(), true, false) {
        return Err(field(
            "angular_velocities",
            batch.angular_velocities.len(),
            "one per sphere or none",
        ));
    }
    match (batch.density, batch.masses.len()) {
        (Some(rho), 0) if positive(rho) => {}
        (Some(rho), 0) => {
            return Err(bad(
                format!("sphere batch {k}"),
                format!("density {rho} is not a finite positive number"),
            ))
        }
        (None, 0) => {
            return Err(bad(
                format!("sphere batch {k}"),
                "give a density or masses".into(),
            ))
        }
        (Some(_), _) => {
            return Err(bad(
                format!("sphere batch {k}"),
                "give a density or masses, not both".into(),
            ))
        }
        (None, m) if !len_ok(m, false, true) => {
            return Err(field("masses", m, "one per sphere or one for all"))
        }
        _ => {}
    }
    if batch.fixed
        && batch
            .velocities
            .iter()
            .chain(&batch.angular_velocities)
            .any(|v| *v != Vec3::ZERO)
    {
        return Err(bad(
            format!("sphere batch {k}"),
            "fixed spheres cannot have velocities".into(),
        ));
    }
    let pick = |v: &[f64], i: usize| if v.len() == 1 { v[0] } else { v[i] };
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let radius = pick(&batch.radii, i);
        let mass = match batch.density {
            Some(rho) => ball_mass(rho, radius),
            None => pick(&batch.masses, i),
        };
        let position = batch.positions[i];
        let velocity = batch.velocities.get(i).copied().unwrap_or(Vec3::ZERO);
        let angular_velocity = batch
            .angular_velocities
            .get(i)
            .copied()
            .unwrap_or(Vec3::ZERO);
        if !(positive(radius)
            && positive(mass)
            && position.is_finite()
            && velocity.is_finite()
            && angular_velocity.is_finite())
        {
            let reason = if !positive(radius) {
                format!("radius {radius} is not a finite positive number")
            } else if !positive(mass) {
                format!("mass {mass} is not a finite positive number")
            } else {
                "non-finite position, velocity or angular velocity".into()
            };
            return Err(bad(format!("sphere batch {k}, sphere {i}"), reason));
        }
        out.push(Sphere {
            position,
            velocity,
            angular_velocity,
            radius,
            mass,
            rotation_locked: false,
            material,
        });
    }
    Ok(out)
}

/// Validation of one obstacle's shape and motion (a scene file's obstacles too, located in
/// the file by `crate::scene_file`).
pub(crate) fn check_obstacle(
    index: usize,
    name: &str,
    shape: &Shape,
    motion: &Motion,
) -> Result<(), SceneError> {
    let bad = |reason: String| {
        Err(SceneError::InvalidObstacle {
            index,
            name: name.to_string(),
            reason,
        })
    };
    let unit = |v: Vec3| v.is_finite() && (v.norm() - 1.0).abs() < 1e-9;
    let finite = |v: Vec3| v.is_finite();
    match shape {
        Shape::Plane { point, normal } => {
            if !(finite(*point) && unit(*normal)) {
                return bad("plane: non-finite point or normal not a unit vector".into());
            }
        }
        Shape::Rectangle {
            center,
            normal,
            u,
            half_u,
            half_v,
        } => {
            let ok = finite(*center)
                && unit(*normal)
                && unit(*u)
                && normal.dot(*u).abs() < 1e-9
                && positive(*half_u)
                && positive(*half_v);
            if !ok {
                return bad("rectangle: needs a finite centre, orthogonal unit normal and u, positive half-lengths".into());
            }
        }
        Shape::CylinderInside {
            point,
            axis,
            radius,
        } => {
            if !(finite(*point) && unit(*axis) && positive(*radius)) {
                return bad(
                    "cylinder_inside: needs a finite point, unit axis, positive radius".into(),
                );
            }
        }
        Shape::Box {
            lo,
            hi,
            inside,
            open_top,
        } => {
            if !(finite(*lo) && finite(*hi) && lo.x < hi.x && lo.y < hi.y && lo.z < hi.z) {
                return bad(format!(
                    "box: lo {lo:?} must be below hi {hi:?} in every coordinate"
                ));
            }
            if *open_top && !inside {
                return bad("box: open_top is for containers (inside = true)".into());
            }
        }
        Shape::Cylinder {
            base,
            axis,
            radius,
            height,
            inside,
            bottom_cap,
            top_cap,
            orifice,
        } => {
            if !(finite(*base) && unit(*axis) && positive(*radius) && positive(*height)) {
                return bad(
                    "cylinder: needs a finite base, unit axis, positive radius and height".into(),
                );
            }
            if !(orifice.is_finite() && *orifice >= 0.0 && orifice < radius) {
                return bad(format!(
                    "cylinder: orifice {orifice} must be in [0, radius {radius})"
                ));
            }
            if *orifice > 0.0 && !bottom_cap {
                return bad("cylinder: an orifice needs the bottom cap".into());
            }
            if !inside && (!bottom_cap || !top_cap || *orifice > 0.0) {
                return bad(
                    "cylinder: a solid cylinder (inside = false) has both caps and no orifice"
                        .into(),
                );
            }
        }
        Shape::Sphere { center, radius, .. } => {
            if !(finite(*center) && positive(*radius)) {
                return bad("sphere: needs a finite centre and a positive radius".into());
            }
        }
        Shape::Mesh { mesh, side } => {
            if *side != MeshSide::Surface {
                mesh.check_closed().map_err(|source| SceneError::Mesh {
                    index,
                    name: name.to_string(),
                    source,
                })?;
            }
        }
    }
    motion.check().or_else(bad)?;
    if let Motion::Rotate { center, axis, .. } = motion {
        if !shape.rotation_invariant(*center, *axis) && !shape.reach_from(*center).is_finite() {
            return bad("an unbounded shape rotating about an axis that moves it (its surface speed is unbounded)".into());
        }
    }
    Ok(())
}

/// Whether a free sphere centred at `x` passes [`check_containment`] among `obstacles`:
/// admitted by every obstacle that is not a container and, when there are containers, by
/// one of them.
pub fn contained(obstacles: &[Obstacle], x: Vec3) -> bool {
    let mut containers = obstacles
        .iter()
        .filter(|o| o.shape.is_container())
        .peekable();
    let in_one = containers.peek().is_none() || containers.any(|o| o.admits(x, 0.0));
    in_one
        && obstacles
            .iter()
            .all(|o| o.shape.is_container() || o.admits(x, 0.0))
}

/// Every free sphere at t = 0 must be admitted by every obstacle that is not a container
/// (free side of planes, outside solids) and, when there are containers, by one of them.
pub fn check_containment(world: &World) -> Result<(), SceneError> {
    let containers: Vec<&Obstacle> = world
        .obstacles
        .iter()
        .filter(|o| o.shape.is_container())
        .collect();
    for (i, b) in world.bodies.iter().enumerate() {
        let x = b.position;
        for (k, o) in world.obstacles.iter().enumerate() {
            if !o.shape.is_container() && !o.admits(x, 0.0) {
                return Err(SceneError::Outside {
                    what: format!("sphere {i}"),
                    position: x.to_array(),
                    reason: format!("on the wrong side of obstacle {k} ('{}')", o.name),
                });
            }
        }
        if !containers.is_empty() && !containers.iter().any(|o| o.admits(x, 0.0)) {
            return Err(SceneError::Outside {
                what: format!("sphere {i}"),
                position: x.to_array(),
                reason: "outside every container".into(),
            });
        }
    }
    Ok(())
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::mesh::{box_mesh, TriangleMesh};

    fn ball(x: f64, y: f64, z: f64) -> BodySpec {
        BodySpec::sphere(Vec3::new(x, y, z), 0.1, 1000.0)
    }

    fn floor() -> ObstacleSpec {
        ObstacleSpec::fixed(
            "floor",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        )
    }

    /// A model with every kind of body, obstacle and motion.
    fn everything() -> SceneModel {
        let cube = box_mesh(Vec3::new(2.0, 2.0, 0.0), Vec3::new(3.0, 3.0, 1.0));
        let mesh = TriangleMesh::new(cube.vertices, cube.triangles).unwrap();
        let mut m = SceneModel::default();
        m.materials.names = vec!["steel".into(), "glass".into()];
        m.materials.pairs.push(MaterialPair {
            materials: ["steel".into(), "glass".into()],
            mu: Some(0.6),
            restitution: Some(0.5),
            rolling_friction: Some(0.01),
        });
        m.bodies.push(ball(0.0, 0.0, 0.5));
        let mut fixed = ball(1.0, 0.0, 0.1);
        fixed.fixed = true;
        fixed.material = "steel".into();
        m.bodies.push(fixed);
        m.sphere_batches.push(SphereBatch {
            positions: vec![Vec3::new(0.0, 1.0, 0.5), Vec3::new(0.5, 1.0, 0.5)],
            radii: vec![0.1, 0.12],
            masses: vec![1.0],
            material: "glass".into(),
            ..SphereBatch::default()
        });
        m.obstacles.push(floor());
        m.obstacles.push(ObstacleSpec {
            name: "cube".into(),
            shape: Shape::Mesh {
                mesh,
                side: MeshSide::Outside,
            },
            motion: Motion::Rotate {
                center: Vec3::new(2.5, 2.5, 0.5),
                axis: Vec3::Z,
                omega: 1.0,
            },
            material: "steel".into(),
        });
        m.obstacles.push(ObstacleSpec {
            name: "silo".into(),
            shape: Shape::Cylinder {
                base: Vec3::new(0.0, 0.0, -0.5),
                axis: Vec3::Z,
                radius: 5.0,
                height: 10.0,
                inside: true,
                bottom_cap: true,
                top_cap: false,
                orifice: 0.5,
            },
            motion: Motion::Oscillate {
                direction: Vec3::Z,
                amplitude: 0.01,
                frequency: 5.0,
            },
            material: "default".into(),
        });
        m.obstacles.push(ObstacleSpec {
            name: "lid".into(),
            shape: Shape::Box {
                lo: Vec3::new(-1.0, -1.0, 3.0),
                hi: Vec3::new(1.0, 1.0, 3.5),
                inside: false,
                open_top: false,
            },
            motion: Motion::Translate {
                velocity: Vec3::new(0.0, 0.0, -0.1),
            },
            material: "default".into(),
        });
        m
    }

    pub fn a_model_builds_and_round_trips_through_serde() {
        let m = everything();
        let (world, params) = m.build().unwrap();
        // free spheres: the body, then the batch; the fixed body is the last obstacle
        assert_eq!(world.bodies.len(), 3);
        assert_eq!(world.obstacles.len(), 5);
        assert_eq!(world.obstacles[4].name, "fixed-body-1");
        assert!(matches!(
            world.obstacles[4].shape,
            Shape::Sphere { inside: false, .. }
        ));
        let t = world.materials.as_ref().unwrap();
        assert_eq!(t.names, vec!["default", "steel", "glass"]);
        assert_eq!(world.bodies[2].material, 2);
        assert_eq!(world.obstacles[4].material, 1);
        assert_eq!(t.law(1, 2).unwrap().mu, 0.6);
        assert_eq!(t.law(2, 1).unwrap().mu, 0.6);
        assert_eq!(t.law(0, 2).unwrap().mu, 0.3);
        assert_eq!(world.bodies[1].radius, 0.1);
        assert_eq!(world.bodies[2].radius, 0.12);
        assert_eq!(world.bodies[2].mass, 1.0);
        assert_eq!(world.bodies[0].mass, ball_mass(1000.0, 0.1));
        assert_eq!(params.h, 0.02);
        assert!(matches!(params.method, StepMethod::Nsgs(_)));
        let json = serde_json::to_string(&m).unwrap();
        let back: SceneModel = serde_json::from_str(&json).unwrap();
        assert_eq!(back, m);
        let wjson = serde_json::to_string(&world).unwrap();
        let wback: World = serde_json::from_str(&wjson).unwrap();
        assert_eq!(wback, world);
        // unknown keys are refused, at every level
        let bad = json.replacen("\"gravity\"", "\"gravitty\"", 1);
        assert!(serde_json::from_str::<SceneModel>(&bad).is_err());
        let bad = json.replacen("\"open_top\"", "\"open_tpo\"", 1);
        assert!(serde_json::from_str::<SceneModel>(&bad).is_err());
        // defaults: an almost empty model
        let m: SceneModel = serde_json::from_str(
            r#"{"bodies": [{"shape": {"kind": "sphere", "radius": 0.1}, "position": [0, 0, 1], "density": 2500}]}"#,
        )
        .unwrap();
        assert_eq!(m.gravity, Vec3::new(0.0, 0.0, -GRAVITY));
        assert_eq!(m.step, StepSettings::default());
        assert_eq!(m.build().unwrap().0.bodies.len(), 1);
    }

    pub fn bad_input_gives_typed_errors() {
        let base = || {
            let mut m = SceneModel::default();
            m.obstacles.push(floor());
            m.bodies.push(ball(0.0, 0.0, 0.5));
            m
        };
        let err = |m: SceneModel| m.build().unwrap_err();
        // unknown materials: body, obstacle, pair
        let mut m = base();
        m.bodies[0].material = "wood".into();
        assert!(matches!(err(m), SceneError::UnknownMaterial { name, .. } if name == "wood"));
        let mut m = base();
        m.obstacles[0].material = "ice".into();
        assert!(matches!(err(m), SceneError::UnknownMaterial { name, .. } if name == "ice"));
        let mut m = base();
        m.materials.pairs.push(MaterialPair {
            materials: ["default".into(), "rubber".into()],
            mu: Some(1.0),
            restitution: Some(0.0),
            rolling_friction: None,
        });
        assert!(matches!(err(m), SceneError::UnknownMaterial { name, .. } if name == "rubber"));
        let mut m = base();
        m.materials.names = vec!["a".into(), "a".into()];
        assert!(matches!(err(m), SceneError::DuplicateMaterial(n) if n == "a"));
        let mut m = base();
        m.materials.default.restitution = 1.5;
        assert!(matches!(err(m), SceneError::InvalidLaw { .. }));
        // radius, mass, density
        let mut m = base();
        m.bodies[0].shape = BodyShape::Sphere { radius: -0.1 };
        assert!(matches!(err(m), SceneError::InvalidBody { what, .. } if what == "body 0"));
        let mut m = base();
        m.bodies[0].density = Some(f64::NAN);
        assert!(matches!(err(m), SceneError::InvalidBody { .. }));
        let mut m = base();
        m.bodies[0].mass = Some(1.0);
        assert!(
            matches!(err(m), SceneError::InvalidBody { reason, .. } if reason.contains("not both"))
        );
        let mut m = base();
        m.sphere_batches.push(SphereBatch {
            positions: vec![Vec3::new(1.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 1.0)],
            radii: vec![0.1, 0.1, 0.1],
            density: Some(1.0),
            ..SphereBatch::default()
        });
        assert!(
            matches!(err(m), SceneError::InvalidBody { reason, .. } if reason.contains("radii"))
        );
        let mut m = base();
        m.sphere_batches.push(SphereBatch {
            positions: vec![Vec3::new(1.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 1.0)],
            radii: vec![0.1, f64::INFINITY],
            density: Some(1.0),
            ..SphereBatch::default()
        });
        assert!(
            matches!(err(m), SceneError::InvalidBody { what, .. } if what == "sphere batch 0, sphere 1")
        );
        // obstacles
        let mut m = base();
        m.obstacles.push(ObstacleSpec::fixed(
            "silo",
            Shape::Cylinder {
                base: Vec3::ZERO,
                axis: Vec3::Z,
                radius: 1.0,
                height: 2.0,
                inside: true,
                bottom_cap: true,
                top_cap: true,
                orifice: 1.5,
            },
        ));
        assert!(matches!(
            err(m),
            SceneError::InvalidObstacle { index: 1, .. }
        ));
        let mut m = base();
        m.obstacles[0].motion = Motion::Rotate {
            center: Vec3::ZERO,
            axis: Vec3::X,
            omega: 1.0,
        };
        assert!(
            matches!(err(m), SceneError::InvalidObstacle { reason, .. } if reason.contains("unbounded"))
        );
        let mut m = base();
        let open = TriangleMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        m.obstacles.push(ObstacleSpec::fixed(
            "tray",
            Shape::Mesh {
                mesh: open,
                side: MeshSide::Inside,
            },
        ));
        assert!(matches!(
            err(m),
            SceneError::Mesh {
                source: MeshError::NotClosed(..),
                ..
            }
        ));
        // a mesh file with a NaN vertex does not even deserialize
        let json = r#"{"kind": "mesh", "mesh": {"vertices": [[0,0,0],[1,0,0],[0,1,1e999]], "triangles": [[0,1,2]]}}"#;
        assert!(serde_json::from_str::<Shape>(json).is_err());
        let json = r#"{"kind": "mesh", "mesh": {"vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1,3]]}}"#;
        let e = serde_json::from_str::<Shape>(json).unwrap_err().to_string();
        assert!(e.contains("vertex 3"), "{e}");
        // step settings, gravity
        let mut m = base();
        m.step.h = 0.0;
        assert!(matches!(err(m), SceneError::InvalidStep(_)));
        let mut m = base();
        m.gravity = Vec3::new(0.0, f64::NAN, 0.0);
        assert!(matches!(err(m), SceneError::InvalidGravity(_)));
        // memory
        assert!(check_memory(1000, 0, Some(1 << 40)).is_ok());
        let e = check_memory(10_000_000, 5, Some(1 << 30)).unwrap_err();
        assert!(matches!(
            e,
            SceneError::Memory {
                spheres: 10_000_000,
                triangles: 5,
                ..
            }
        ));
        assert!(e.to_string().contains("20547109504"), "{e}");
        assert!(check_memory(10_000_000, 5, None).is_ok());
    }

    pub fn spheres_overlapping_an_obstacle_are_refused_and_relaxed() {
        let mut m = SceneModel::default();
        m.obstacles.push(floor());
        m.obstacles.push(ObstacleSpec::fixed(
            "wall",
            Shape::Plane {
                point: Vec3::new(1.0, 0.0, 0.0),
                normal: Vec3::new(-1.0, 0.0, 0.0),
            },
        ));
        m.bodies.push(ball(0.0, 0.0, 0.5));
        m.bodies.push(ball(0.0, 0.5, 0.08));
        m.bodies.push(ball(0.91, 1.0, 0.5));
        match m.build().unwrap_err() {
            SceneError::Penetration {
                count,
                sphere,
                obstacle,
                name,
                depth,
            } => {
                assert_eq!((count, sphere, obstacle), (2, 1, 0));
                assert_eq!(name, "floor");
                assert!((depth - 0.02).abs() < 1e-12, "{depth}");
            }
            e => panic!("{e}"),
        }
        let msg = m.build().unwrap_err().to_string();
        assert!(msg.contains("sphere 1") && msg.contains("'floor'"), "{msg}");
        // touching is not overlapping
        let mut touching = m.clone();
        touching.bodies[1] = ball(0.0, 0.5, 0.1);
        touching.bodies[2] = ball(0.9, 1.0, 0.5);
        assert!(touching.build().is_ok());
        // relaxed: moved out along the normals, nothing left
        let checks = BuildChecks {
            overlaps: false,
            ..BuildChecks::default()
        };
        let (mut world, _) = m.build_with(&checks).unwrap();
        resolve_overlaps(&mut world, 100);
        assert!(obstacle_penetration(&world).is_none());
        assert!(world.bodies[1].position.z >= 0.1);
    }

    pub fn overlaps_and_containment_are_refused_and_overlaps_relaxed() {
        let mut m = SceneModel::default();
        m.obstacles.push(ObstacleSpec::fixed(
            "bin",
            Shape::Box {
                lo: Vec3::ZERO,
                hi: Vec3::new(1.0, 1.0, 1.0),
                inside: true,
                open_top: true,
            },
        ));
        m.bodies.push(ball(0.5, 0.5, 0.2));
        m.bodies.push(ball(0.65, 0.5, 0.2));
        m.bodies.push(ball(0.5, 0.62, 0.2));
        match m.build().unwrap_err() {
            SceneError::Overlaps { count, worst, pair } => {
                assert_eq!(count, 3);
                assert!((worst - 0.08).abs() < 1e-12);
                assert_eq!(pair, (0, 2));
            }
            e => panic!("{e}"),
        }
        let checks = BuildChecks {
            overlaps: false,
            ..BuildChecks::default()
        };
        // the time cap: reached with overlaps left, the relaxation is refused, saying so
        let (mut world, _) = m.build_with(&checks).unwrap();
        let e = relax_within(&mut world, 1000, std::time::Duration::ZERO).unwrap_err();
        assert!(
            matches!(
                e,
                SceneError::RelaxationTimedOut {
                    sweeps: 0,
                    count: 3,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("time limit"), "{e}");
        let (mut world, _) = m.build_with(&checks).unwrap();
        let r = resolve_overlaps(&mut world, 1000);
        assert_eq!(r.left.count, 0, "{r:?}");
        assert!(!r.timed_out);
        assert!(r.sweeps >= 2 && r.sweeps < 1000);
        assert_eq!(overlaps(&world).count, 0);
        // outside the container, and inside a solid
        let mut out = m.clone();
        out.bodies.truncate(1);
        out.bodies.push(ball(2.0, 0.5, 0.5));
        match out.build().unwrap_err() {
            SceneError::Outside { what, reason, .. } => {
                assert_eq!(what, "sphere 1");
                assert!(reason.contains("every container"));
            }
            e => panic!("{e}"),
        }
        let mut inside_rock = m.clone();
        inside_rock.bodies.truncate(1);
        inside_rock.obstacles.push(ObstacleSpec::fixed(
            "rock",
            Shape::Sphere {
                center: Vec3::new(0.5, 0.5, 0.25),
                radius: 0.1,
                inside: false,
            },
        ));
        assert!(matches!(
            inside_rock.build().unwrap_err(),
            SceneError::Outside { reason, .. } if reason.contains("rock")
        ));
        // behind a plane
        let mut behind = SceneModel::default();
        behind.obstacles.push(floor());
        behind.bodies.push(ball(0.0, 0.0, -0.5));
        assert!(matches!(
            behind.build().unwrap_err(),
            SceneError::Outside { .. }
        ));
        // a closed mesh container: inside is fine, outside is not
        let cube = box_mesh(Vec3::ZERO, Vec3::new(1.0, 1.0, 1.0));
        let mesh = TriangleMesh::new(cube.vertices, cube.triangles).unwrap();
        let mut cup = SceneModel::default();
        cup.obstacles.push(ObstacleSpec::fixed(
            "cup",
            Shape::Mesh {
                mesh,
                side: MeshSide::Inside,
            },
        ));
        cup.bodies.push(ball(0.5, 0.5, 0.5));
        assert!(cup.build().is_ok());
        cup.bodies.push(ball(1.5, 0.5, 0.5));
        assert!(matches!(
            cup.build().unwrap_err(),
            SceneError::Outside { .. }
        ));
    }
}
