//! Scene files: a whole simulation — materials and their pairs, gravity, the step settings,
//! groups of spheres (inline, from a generator, or from a CSV/NPY file), obstacles (planes,
//! rectangles, boxes, cylinders with caps and an orifice, spheres, triangle meshes from
//! STL/OBJ) with their motions, and inlets — in TOML (`.toml`) or JSON (`.json`), read with
//! serde. Every key is documented in docs/granular.md, "Scene files".
//!
//! Unknown keys are refused with the file, line and column (for TOML, the byte span of the
//! parser's error turned into line:column; JSON's parser gives line:column itself), and so
//! are the semantic errors found after parsing (an unknown material, a bad radius, …), located
//! by their key path in the TOML document. Relative file names (particles, meshes) are
//! resolved against the scene file's folder.

use crate::generate::{self, FillSpec, Inlet, Packing, Rate, Region, SizeDistribution};
use crate::import::{self, ImportError, Transform, TriMesh};
use crate::math::Vec3;
use crate::mesh::TriangleMesh;
use crate::model::{
    BodyShape, BodySpec, BuildChecks, LawKey, MaterialPair, Materials, ObstacleSpec, SceneError,
    SceneModel, SphereBatch, StepSettings,
};
use crate::scene::rigid::RigidScene;
use crate::simulation::{Params, Simulation, SimulationError};
use crate::world::{ContactLaw, MeshSide, Motion, Shape, Sphere, World};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Why a scene file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum SceneFileError {
    /// the file could not be read
    #[error("{}: {source}", path.display())]
    Io {
        /// the scene file
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
    /// the path is not a regular file of bounded size, or cannot be opened or read
    /// ([`coulomb::input`])
    #[error(transparent)]
    Input(#[from] coulomb::input::InputError),
    /// the extension is neither .toml nor .json
    #[error("{}: a scene file must end in .toml or .json", path.display())]
    Extension {
        /// the scene file
        path: PathBuf,
    },
    /// the text does not parse, has an unknown key or a value of the wrong type
    #[error("{}:{line}:{column}: {message}", path.display())]
    Syntax {
        /// the scene file
        path: PathBuf,
        /// 1-based line
        line: usize,
        /// 1-based column (in characters)
        column: usize,
        /// the parser's message (it names the key)
        message: String,
    },
    /// a value is out of range or refers to something that does not exist
    #[error("{}{}: {key}: {message}", path.display(), at.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default())]
    Invalid {
        /// the scene file
        path: PathBuf,
        /// line and column of the key, when the format gives them
        at: Option<(usize, usize)>,
        /// the key path, e.g. `pairs[0].materials`
        key: String,
        /// what is wrong
        message: String,
    },
    /// the scene model refused the scene (overlapping spheres, a sphere outside every
    /// container, an invalid obstacle, …)
    #[error("{}: {source}", path.display())]
    Model {
        /// the scene file
        path: PathBuf,
        /// the model's error
        source: SceneError,
    },
    /// a URDF file named by `[[urdf]]` could not be imported
    #[error("{}{}: {key}: {source}", path.display(), at.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default())]
    Urdf {
        /// the scene file
        path: PathBuf,
        /// line and column of the `[[urdf]]` entry, when the format gives them
        at: Option<(usize, usize)>,
        /// the entry, e.g. `urdf[0]`
        key: String,
        /// the importer's error (it names the URDF file and the element)
        source: Box<crate::urdf::UrdfError>,
    },
    /// a particle or mesh file named by the scene could not be read
    #[error("{}: {key}: {source}", path.display())]
    Import {
        /// the scene file
        path: PathBuf,
        /// the key that names the file
        key: String,
        /// the reader's error (it names the file)
        source: ImportError,
    },
}

fn default_seed() -> u64 {
    1
}
fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -crate::world::GRAVITY]
}
fn default_material() -> String {
    DEFAULT_MATERIAL.to_string()
}
fn yes() -> bool {
    true
}

/// The material every body and obstacle has unless told otherwise.
pub const DEFAULT_MATERIAL: &str = "default";
/// Density of the default material (kg/m³, glass).
pub const DEFAULT_DENSITY: f64 = 2500.0;

/// A whole scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// a name for outputs (default: the file's stem)
    #[serde(default)]
    pub name: Option<String>,
    /// seed of every generator that has none of its own (default 1)
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// gravity vector (m/s², default (0, 0, −9.81))
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// time stepping and solver
    #[serde(default)]
    pub step: StepSection,
    /// materials by name; `default` always exists (density 2500 kg/m³ unless redefined)
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSection>,
    /// the contact law of every pair of materials not listed in `pairs` (the model's
    /// [`crate::world::ContactLaw`]: μ 0.3, e 0.2, μ_r 0 unless given)
    #[serde(default)]
    pub default_pair: ContactLaw,
    /// contact laws of given pairs of materials (the model's [`MaterialPair`]: a coefficient
    /// not given is `default_pair`'s)
    #[serde(default)]
    pub pairs: Vec<MaterialPair>,
    /// groups of spheres
    #[serde(default)]
    pub bodies: Vec<BodiesSection>,
    /// obstacles
    #[serde(default)]
    pub obstacles: Vec<ObstacleSection>,
    /// inlets pouring spheres during the run
    #[serde(default)]
    pub inlets: Vec<InletSection>,
    /// `[[joints]]`: joints between bodies (issue 53; keys kind, body_a, body_b (absent: the
    /// world), anchor, axis, limits = [lo, hi], limit_restitution, friction, motor = {velocity or
    /// position (+ gain), max_force}); bodies are
    /// numbered from 0 in file order over every `[[bodies]]` group
    #[serde(default)]
    pub joints: Vec<crate::bodies::joints::JointDesc>,
    /// `[[urdf]]`: robots read from URDF files (issue 53, [`crate::urdf`]); their links are
    /// bodies numbered after every `[[bodies]]` group's (robot after robot, each robot's
    /// links in its file's order), their joints come after `[[joints]]`
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub urdf: Vec<UrdfSection>,
}

/// `[[urdf]]`: a robot from a URDF file, placed in the world ([`crate::urdf::UrdfPlacement`]:
/// the same keys as Python's `Scene.add_urdf`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UrdfSection {
    /// the URDF file, relative to the scene file (`path` is accepted for it too)
    #[serde(alias = "path")]
    pub file: String,
    /// world position of the root link's frame (m, default the origin)
    #[serde(default)]
    pub position: [f64; 3],
    /// unit quaternion (w, x, y, z) turning the root link's frame into the world's (default
    /// identity)
    #[serde(default = "identity_quaternion")]
    pub orientation: [f64; 4],
    /// the root link fixed to the world (default false: free)
    #[serde(default)]
    pub fixed_base: bool,
    /// the material of every link (default `default`)
    #[serde(default = "default_material")]
    pub material: String,
}

fn identity_quaternion() -> [f64; 4] {
    crate::shape::IDENTITY
}

/// `[step]`: the scene model's [`StepSettings`] (`h`, `theta`, `tol`, `method`, `max_sweeps`,
/// `relaxation`, `gamma`, `projection`, `projection_velocities`, `gap_closure`,
/// `warm_start`: the model's keys and defaults) and the run's keys ([`RunSettings`]), in one
/// table: read by [`StepSection::deserialize`], which routes each key to its part.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct StepSection {
    /// the model's step settings
    #[serde(flatten)]
    pub settings: StepSettings,
    /// how long the run lasts
    #[serde(flatten)]
    pub run: RunSettings,
}

/// The keys of `[step]` that are the run's, not the scene model's (defaults: those of
/// `coulomb simulate`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunSettings {
    /// number of steps (default 200 unless `duration` or `until_rest`)
    pub steps: Option<usize>,
    /// simulated time (s): ⌈duration / h⌉ steps
    pub duration: Option<f64>,
    /// run until every sphere moves slower than `rest_speed` for 10 steps
    pub until_rest: bool,
    /// rest speed (m/s), default 0.05
    pub rest_speed: f64,
    /// step cap of `until_rest`, default 2000
    pub max_steps: usize,
}

impl Default for RunSettings {
    fn default() -> Self {
        Self {
            steps: None,
            duration: None,
            until_rest: false,
            rest_speed: 0.05,
            max_steps: 2000,
        }
    }
}

/// Every key of `[step]`.
const STEP_KEYS: &[&str] = &[
    "h",
    "theta",
    "tol",
    "method",
    "max_sweeps",
    "relaxation",
    "gamma",
    "projection",
    "projection_velocities",
    "gap_closure",
    "warm_start",
    "steps",
    "duration",
    "until_rest",
    "rest_speed",
    "max_steps",
];

impl<'de> Deserialize<'de> for StepSection {
    /// Each key into the model's settings or the run's (the defaults for the keys not given);
    /// an unknown or repeated key refused at its place, naming it.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::{DeserializeSeed, Error, MapAccess, Visitor};
        /// A key of `[step]` as its index in [`STEP_KEYS`]: an unknown key is refused while it
        /// is read, so that the parser locates it.
        struct Key;
        impl<'de> DeserializeSeed<'de> for Key {
            type Value = usize;
            fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
                let k = String::deserialize(d)?;
                (STEP_KEYS.iter().position(|x| *x == k))
                    .ok_or_else(|| D::Error::unknown_field(&k, STEP_KEYS))
            }
        }
        struct Keys;
        impl<'de> Visitor<'de> for Keys {
            type Value = StepSection;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a table of step settings")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<StepSection, A::Error> {
                let mut out = StepSection::default();
                let (s, r) = (&mut out.settings, &mut out.run);
                let mut seen = [false; STEP_KEYS.len()];
                while let Some(i) = m.next_key_seed(Key)? {
                    if std::mem::replace(&mut seen[i], true) {
                        return Err(A::Error::duplicate_field(STEP_KEYS[i]));
                    }
                    match STEP_KEYS[i] {
                        "h" => s.h = m.next_value()?,
                        "theta" => s.theta = m.next_value()?,
                        "tol" => s.tol = m.next_value()?,
                        "method" => s.method = m.next_value()?,
                        "max_sweeps" => s.max_sweeps = m.next_value()?,
                        "relaxation" => s.relaxation = m.next_value()?,
                        "gamma" => s.gamma = m.next_value()?,
                        "projection" => s.projection = m.next_value()?,
                        "projection_velocities" => s.projection_velocities = m.next_value()?,
                        "gap_closure" => s.gap_closure = m.next_value()?,
                        "warm_start" => s.warm_start = m.next_value()?,
                        "steps" => r.steps = m.next_value()?,
                        "duration" => r.duration = m.next_value()?,
                        "until_rest" => r.until_rest = m.next_value()?,
                        "rest_speed" => r.rest_speed = m.next_value()?,
                        "max_steps" => r.max_steps = m.next_value()?,
                        other => return Err(A::Error::unknown_field(other, STEP_KEYS)),
                    }
                }
                Ok(out)
            }
        }
        d.deserialize_map(Keys)
    }
}

impl StepSection {
    /// The number of steps of a fixed-length run: `steps`, else ⌈duration / h⌉, else 200.
    pub fn fixed_steps(&self) -> usize {
        match (self.run.steps, self.run.duration) {
            (Some(n), _) => n,
            (None, Some(d)) => (d / self.settings.h - 1e-9).ceil().max(0.0) as usize,
            (None, None) => 200,
        }
    }
}

/// `[materials.NAME]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSection {
    /// density (kg/m³)
    pub density: f64,
}

/// `[[bodies]]`: a group of spheres, from exactly one of `spheres`, `file` or `fill`, or a
/// group of bodies of one `shape` (any [`BodyShape`]: the same keys as the scene model) at
/// `positions`, in `orientations`. File sugar: it expands into the model's
/// [`SphereBatch`]es and [`BodySpec`]s ([`LoadedScene::build`]). (`Default`: no source, the
/// material's name empty.)
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodiesSection {
    /// material of the group (a CSV `material` column overrides it per sphere)
    #[serde(default = "default_material")]
    pub material: String,
    /// density (kg/m³), instead of the material's
    #[serde(default)]
    pub density: Option<f64>,
    /// fixed spheres (they do not move; obstacles made of spheres)
    #[serde(default)]
    pub fixed: bool,
    /// initial velocity (m/s) of spheres that have none from their source (default 0)
    #[serde(default)]
    pub velocity: Option<[f64; 3]>,
    /// initial angular velocity (rad/s)
    #[serde(default)]
    pub angular_velocity: [f64; 3],
    /// inline spheres: [x, y, z, r] each
    #[serde(default)]
    pub spheres: Option<Vec<[f64; 4]>>,
    /// a CSV or NPY file (relative to the scene file)
    #[serde(default)]
    pub file: Option<String>,
    /// a generator
    #[serde(default)]
    pub fill: Option<FillSection>,
    /// the shape of every body of the group (with `positions`)
    #[serde(default)]
    pub shape: Option<BodyShape>,
    /// origins of the bodies' shape frames (m), one per body (with `shape`)
    #[serde(default)]
    pub positions: Option<Vec<[f64; 3]>>,
    /// unit quaternions (w, x, y, z), one per body or one for all (default identity; with
    /// `shape`)
    #[serde(default)]
    pub orientations: Option<Vec<[f64; 4]>>,
    /// mass of each body (kg), instead of the density's (with `shape`)
    #[serde(default)]
    pub mass: Option<f64>,
    /// inertia tensor about the centre of mass in the shape frame (kg m²), instead of the
    /// shape's (with `shape`, not a sphere)
    #[serde(default)]
    pub inertia: Option<[[f64; 3]; 3]>,
    /// centre of mass in the shape frame (m), instead of the shape's centroid (with `shape`,
    /// not a sphere, and `inertia`: the tensor about it)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre_of_mass: Option<[f64; 3]>,
}

/// A generated group: `count` spheres with radii from `sizes` placed in `region` (or in the
/// interior of the closed `mesh`) by `packing`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FillSection {
    /// how many spheres
    pub count: usize,
    /// a box or cylinder region (or give `mesh`)
    #[serde(default)]
    pub region: Option<generate::Shape>,
    /// a closed mesh whose interior is the region
    #[serde(default)]
    pub mesh: Option<MeshSource>,
    /// radii
    pub sizes: SizeDistribution,
    /// lattice (default) or random sequential addition
    #[serde(default)]
    pub packing: Packing,
    /// each velocity component gets U(−a, a) added (m/s)
    #[serde(default)]
    pub velocity_jitter: f64,
    /// seed (default: the scene's seed + the fill's index among the fills)
    #[serde(default)]
    pub seed: Option<u64>,
    /// refuse the scene when fewer than `count` spheres fit (default true)
    #[serde(default = "yes")]
    pub require_all: bool,
}

/// A triangle mesh: from a file (STL or OBJ, relative to the scene file) or inline.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSource {
    /// an .stl or .obj file
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// inline vertices (m)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertices: Option<Vec<[f64; 3]>>,
    /// inline triangles (vertex indices, from 0)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub triangles: Option<Vec<[usize; 3]>>,
    /// scale, rotation and translation applied to the vertices
    #[serde(default)]
    pub transform: Transform,
}

/// `[[obstacles]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSection {
    /// a name for outputs (default `obstacle-K`)
    #[serde(default)]
    pub name: Option<String>,
    /// material
    #[serde(default = "default_material")]
    pub material: String,
    /// geometry
    pub shape: ObstacleShape,
    /// prescribed motion (default fixed): the world's [`Motion`], its direction or axis
    /// normalized when read
    #[serde(default)]
    pub motion: Motion,
}

/// Geometry of an obstacle, by `kind`: a shape of the world ([`Shape`], its keys and
/// defaults: `plane`, `rectangle`, `cylinder_inside`, `box`, `cylinder`, `sphere`), its
/// normals and axes normalized when read (a rectangle's `u` made orthogonal to its normal
/// first), or `mesh`: a triangle mesh (any closed or open surface) from `file` or inline
/// ([`MeshSource`]) and the `side` the spheres live on (`surface`, the default, `inside` or
/// `outside`: a closed, consistently oriented mesh).
#[derive(Debug, Clone, PartialEq)]
pub enum ObstacleShape {
    /// any shape of the world but a mesh
    Shape(Shape),
    /// `kind = "mesh"`
    Mesh {
        /// the triangles
        source: MeshSource,
        /// where the spheres live
        side: MeshSide,
    },
}

impl Serialize for ObstacleShape {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Mesh<'a> {
            kind: &'static str,
            #[serde(flatten)]
            source: &'a MeshSource,
            side: MeshSide,
        }
        match self {
            ObstacleShape::Shape(x) => x.serialize(s),
            ObstacleShape::Mesh { source, side } => Mesh {
                kind: "mesh",
                source,
                side: *side,
            }
            .serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for ObstacleShape {
    /// The keys of a mesh or of the world's shape of that `kind` (errors at the shape).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        // buffered as JSON, where TOML's nan and inf become null (refused: every number of
        // an obstacle's shape must be finite)
        let mut v = serde_json::Value::deserialize(d)?;
        let custom = |e: serde_json::Error| -> D::Error {
            let mut m = e.to_string();
            if m.starts_with("invalid type: null") {
                m.push_str(" (every number of an obstacle's shape must be finite)");
            }
            serde::de::Error::custom(m)
        };
        if v.get("kind").and_then(serde_json::Value::as_str) != Some("mesh") {
            return Shape::deserialize(v)
                .map(ObstacleShape::Shape)
                .map_err(custom);
        }
        let side = v.as_object_mut().and_then(|m| {
            m.remove("kind");
            m.remove("side")
        });
        let side = match side {
            Some(x) => MeshSide::deserialize(x).map_err(custom)?,
            None => MeshSide::default(),
        };
        let source = MeshSource::deserialize(v).map_err(custom)?;
        Ok(ObstacleShape::Mesh { source, side })
    }
}

/// `[[inlets]]`: an [`Inlet`] whose spheres (or bodies of `shape`) are of `material`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InletSection {
    /// material of the poured spheres (its density turns a mass rate into spheres)
    #[serde(default = "default_material")]
    pub material: String,
    /// where the spheres appear (box or cylinder)
    pub region: generate::Shape,
    /// radii
    pub sizes: SizeDistribution,
    /// `{ count = spheres/s }` or `{ mass = kg/s }`
    pub rate: Rate,
    /// first emission time (s)
    #[serde(default)]
    pub start: f64,
    /// last emission time (s; default none)
    #[serde(default)]
    pub end: Option<f64>,
    /// initial velocity (m/s)
    #[serde(default)]
    pub velocity: [f64; 3],
    /// candidate positions per sphere (default 20)
    #[serde(default)]
    pub attempts: Option<usize>,
    /// seed (default: the scene's seed + 1000 + the inlet's index)
    #[serde(default)]
    pub seed: Option<u64>,
    /// the shape of the poured bodies, as in `[[bodies]]` (any size: each is scaled so that
    /// its bounding radius about its frame's origin is the sampled radius, and turned by a
    /// random rotation, [`Inlet`]); default: spheres. A scene whose inlet pours another shape
    /// than spheres runs in the rigid-body simulator ([`BuiltScene::runs_rigid`]).
    #[serde(default)]
    pub shape: Option<BodyShape>,
}

/// One segment of a key path.
#[derive(Debug, Clone, PartialEq)]
pub enum Seg {
    /// a table key
    Key(String),
    /// an array index
    Index(usize),
}

fn key(s: &str) -> Seg {
    Seg::Key(s.to_string())
}

fn path_string(p: &[Seg]) -> String {
    let mut s = String::new();
    for seg in p {
        match seg {
            Seg::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Seg::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let mut cut = offset;
    while !text.is_char_boundary(cut) {
        cut -= 1;
    }
    let before = &text[..cut];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map(|i| i + 1).unwrap_or(0);
    (line, before[start..].chars().count() + 1)
}

/// A parsed scene file, with its text (to locate keys) and folder (to resolve file names).
#[derive(Debug, Clone)]
pub struct LoadedScene {
    /// the scene file
    pub path: PathBuf,
    /// its content
    pub text: String,
    /// whether it is TOML (else JSON)
    pub is_toml: bool,
    /// the parsed content
    pub file: SceneFile,
}

/// Options of [`LoadedScene::build`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BuildOptions {
    /// replaces the file's `seed`
    pub seed: Option<u64>,
    /// caps the count of every fill (and lets a capped fill place fewer): small test runs
    pub max_fill: Option<usize>,
}

/// A sphere of the built scene, before the scene model's validation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BodyOut {
    /// centre (m)
    pub position: Vec3,
    /// radius (m)
    pub radius: f64,
    /// mass (kg)
    pub mass: f64,
    /// velocity (m/s)
    pub velocity: Vec3,
    /// angular velocity (rad/s)
    pub angular_velocity: Vec3,
    /// its material
    pub material: String,
    /// whether it is fixed
    pub fixed: bool,
}

/// A running inlet: what emits and the density and material of what it emits.
#[derive(Debug, Clone, PartialEq)]
pub struct InletRun {
    /// the inlet
    pub inlet: Inlet,
    /// density of its spheres (kg/m³)
    pub density: f64,
    /// material of its spheres
    pub material: String,
    /// emissions not tried so far because the region could hold no more in their step
    /// ([`crate::generate::Emission::capped`])
    pub capped: usize,
}

impl InletRun {
    /// Inserts into `sim` ([`Simulation::insert_bodies`]) the spheres due in (t0, t1]
    /// ([`Inlet::emit`], placed among the spheres present), with the materials of `model`;
    /// returns (inserted, skipped).
    pub fn emit(
        &mut self,
        sim: &mut Simulation,
        model: &SceneModel,
        t0: f64,
        t1: f64,
    ) -> Result<(usize, usize), SimulationError> {
        if let Some(shape) = self.inlet.poured_shape() {
            return Err(SimulationError::Parameter(format!(
                "inlet: it pours bodies of shape {}, which the sphere simulator cannot hold; a scene with such an inlet runs in the rigid-body simulator (InletRun::pour_rigid)",
                shape.kind()
            )));
        }
        let present: Vec<(Vec3, f64)> = sim
            .world
            .bodies
            .iter()
            .map(|b| (b.position, b.radius))
            .collect();
        let e = self.inlet.emit(t0, t1, &present);
        self.capped += e.capped;
        if e.particles.is_empty() {
            return Ok((0, e.skipped));
        }
        let batch = SphereBatch {
            positions: e.particles.iter().map(|p| p.position).collect(),
            radii: e.particles.iter().map(|p| p.radius).collect(),
            velocities: e.particles.iter().map(|p| p.velocity).collect(),
            masses: e
                .particles
                .iter()
                .map(|p| sphere_mass(self.density, p.radius))
                .collect(),
            material: self.material.clone(),
            ..SphereBatch::default()
        };
        let spheres = model
            .spheres_of(&batch)
            .map_err(|e| SimulationError::Parameter(format!("inlet: {e}")))?;
        sim.insert_bodies(spheres)?;
        Ok((e.particles.len(), e.skipped))
    }
}

/// What the inlets poured in one call of [`BuiltScene::pour_rigid`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Poured {
    /// bodies inserted
    pub inserted: usize,
    /// emissions that found no free position (the capped ones included)
    pub skipped: usize,
    /// emissions not tried because an inlet's region could hold no more in this step
    /// ([`crate::generate::Emission::capped`])
    pub capped: usize,
}

impl InletRun {
    /// Inserts into the rigid scene `rigid` ([`RigidScene::insert_bodies`]) the bodies due
    /// in (t0, t1] ([`Inlet::emit`]): spheres, or the inlet's shape scaled to each sampled
    /// radius and turned by its random rotation, each placed so that its bounding ball
    /// overlaps the bounding ball of no body present (centred on its shape frame's origin,
    /// [`BodyShape::bounding_radius`]: conservative), with the inlet's velocity, density and
    /// material; returns (inserted, skipped). Emission i depends only on (seed, i), the times
    /// and the bodies present, so a restarted run pours the bodies of the uninterrupted one.
    pub fn pour_rigid(
        &mut self,
        rigid: &mut RigidScene,
        t0: f64,
        t1: f64,
    ) -> Result<(usize, usize), SceneError> {
        let present: Vec<(Vec3, f64)> = rigid
            .world
            .positions()
            .iter()
            .zip(&rigid.shapes)
            .map(|(p, s)| (v3(*p), s.bounding_radius()))
            .collect();
        let e = self.inlet.emit(t0, t1, &present);
        self.capped += e.capped;
        if e.particles.is_empty() {
            return Ok((0, e.skipped));
        }
        let bodies: Vec<BodySpec> = e
            .particles
            .iter()
            .enumerate()
            .map(|(k, p)| BodySpec {
                shape: self.inlet.body_shape(p.radius),
                orientation: e
                    .orientations
                    .get(k)
                    .copied()
                    .unwrap_or(crate::shape::IDENTITY),
                velocity: p.velocity,
                material: self.material.clone(),
                ..BodySpec::sphere(p.position, p.radius, self.density)
            })
            .collect();
        let n = bodies.len();
        rigid.insert_bodies(bodies)?;
        Ok((n, e.skipped))
    }
}

/// The scene a file describes, built: the scene model, the run settings of `[step]` and the
/// inlets.
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltScene {
    /// the scene file
    pub path: PathBuf,
    /// name for outputs
    pub name: String,
    /// the scene model (spheres as batches, obstacles, materials, step settings)
    pub model: SceneModel,
    /// the `[step]` section (run length, activation, projection, warm starts)
    pub step: StepSection,
    /// the inlets
    pub inlets: Vec<InletRun>,
    /// what each fill placed, (asked, placed)
    pub fills: Vec<(usize, usize)>,
}

/// Mass ρ · 4/3 π R³ of a solid ball (the built-in scenes' expression, to the bit).
pub fn sphere_mass(density: f64, r: f64) -> f64 {
    density * 4.0 / 3.0 * std::f64::consts::PI * r * r * r
}

fn v3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

impl LoadedScene {
    /// Reads and parses a scene file (`.toml` or `.json`), refusing unknown keys.
    pub fn load(path: &Path) -> Result<Self, SceneFileError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        let is_toml = match ext.as_deref() {
            Some("toml") => true,
            Some("json") => false,
            _ => {
                return Err(SceneFileError::Extension {
                    path: path.to_path_buf(),
                })
            }
        };
        let text = coulomb::input::read_to_string(path, coulomb::input::Kind::Scene)?;
        Self::parse(path, text, is_toml)
    }

    /// Parses `text` as the content of `path` (TOML or JSON).
    pub fn parse(path: &Path, text: String, is_toml: bool) -> Result<Self, SceneFileError> {
        let file: SceneFile = if is_toml {
            toml::from_str(&text).map_err(|e| {
                let (line, column) = line_column(&text, e.span().map(|s| s.start).unwrap_or(0));
                SceneFileError::Syntax {
                    path: path.to_path_buf(),
                    line,
                    column,
                    message: e.message().trim().to_string(),
                }
            })?
        } else {
            serde_json::from_str(&text).map_err(|e| SceneFileError::Syntax {
                path: path.to_path_buf(),
                line: e.line(),
                column: e.column(),
                message: e.to_string(),
            })?
        };
        Ok(Self {
            path: path.to_path_buf(),
            text,
            is_toml,
            file,
        })
        .and_then(|scene| {
            if is_toml {
                scene.check_no_dropped_elements()?;
            }
            Ok(scene)
        })
    }

    /// Refuses a TOML array longer than its field (`[x, y, z, r, 1]` for a sphere, a
    /// quaternion of 5 numbers, an inertia tensor of 4 rows): the TOML reader fills a
    /// fixed-size array from the first elements and drops the rest without a word (JSON
    /// refuses them itself). The file as parsed is written back and every array of the text
    /// compared with its counterpart: one that lost elements is an error at its line and
    /// column.
    fn check_no_dropped_elements(&self) -> Result<(), SceneFileError> {
        fn dropped(
            text: &toml::Value,
            kept: &toml::Value,
            at: &mut Vec<Seg>,
        ) -> Option<(Vec<Seg>, usize, usize)> {
            match (text, kept) {
                (toml::Value::Array(a), toml::Value::Array(b)) => {
                    if a.len() > b.len() {
                        return Some((at.clone(), a.len(), b.len()));
                    }
                    for (i, (x, y)) in a.iter().zip(b).enumerate() {
                        at.push(Seg::Index(i));
                        let found = dropped(x, y, at);
                        at.pop();
                        if found.is_some() {
                            return found;
                        }
                    }
                    None
                }
                (toml::Value::Table(a), toml::Value::Table(b)) => {
                    for (k, x) in a {
                        let Some(y) = b.get(k) else { continue };
                        at.push(Seg::Key(k.clone()));
                        let found = dropped(x, y, at);
                        at.pop();
                        if found.is_some() {
                            return found;
                        }
                    }
                    None
                }
                _ => None,
            }
        }
        let (Ok(text), Ok(kept)) = (
            toml::from_str::<toml::Value>(&self.text),
            toml::Value::try_from(&self.file),
        ) else {
            return Ok(());
        };
        match dropped(&text, &kept, &mut Vec::new()) {
            Some((at, found, expected)) => Err(self.invalid(
                &at,
                format!("{found} values where {expected} are expected: remove the extra ones"),
            )),
            None => Ok(()),
        }
    }

    /// Line and column of the key at `p` (TOML only; the deepest part of the path found).
    fn locate(&self, p: &[Seg]) -> Option<(usize, usize)> {
        if !self.is_toml {
            return None;
        }
        let doc = toml::de::DeTable::parse(&self.text).ok()?;
        let root = toml::de::DeValue::Table(doc.into_inner());
        let mut cur = &root;
        let mut span = None;
        for seg in p {
            let next = match seg {
                Seg::Key(k) => cur.get(k.as_str()),
                Seg::Index(i) => cur.get(*i),
            };
            match next {
                Some(v) => {
                    span = Some(v.span());
                    cur = v.get_ref();
                }
                None => break,
            }
        }
        span.map(|s| line_column(&self.text, s.start))
    }

    fn invalid(&self, p: &[Seg], message: impl Into<String>) -> SceneFileError {
        SceneFileError::Invalid {
            path: self.path.clone(),
            at: self.locate(p),
            key: path_string(p),
            message: message.into(),
        }
    }

    /// The files this scene reads: the scene file and every `file` it names (particle,
    /// mesh, shape and URDF files, and the meshes a URDF file names), resolved as they are read. The outputs of a run never replace
    /// one of them (`coulomb_granular::output_dir`).
    pub fn input_files(&self) -> Vec<PathBuf> {
        fn walk(v: &serde_json::Value, out: &mut Vec<String>) {
            match v {
                serde_json::Value::Object(m) => {
                    for (k, x) in m {
                        match x {
                            serde_json::Value::String(s) if k == "file" => out.push(s.clone()),
                            _ => walk(x, out),
                        }
                    }
                }
                serde_json::Value::Array(a) => a.iter().for_each(|x| walk(x, out)),
                _ => {}
            }
        }
        let mut names = Vec::new();
        if let Ok(v) = serde_json::to_value(&self.file) {
            walk(&v, &mut names);
        }
        let mut files = vec![self.path.clone()];
        files.extend(names.iter().map(|n| self.resolve(n)));
        // the meshes a `[[urdf]]` robot's links name
        for u in &self.file.urdf {
            files.extend(crate::urdf::mesh_files(&self.resolve(&u.file)));
        }
        files
    }

    fn resolve(&self, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.path.parent().unwrap_or_else(|| Path::new(".")).join(p)
        }
    }

    fn mesh(&self, src: &MeshSource, p: &[Seg]) -> Result<TriMesh, SceneFileError> {
        let mesh =
            match (&src.file, &src.vertices, &src.triangles) {
                (Some(f), None, None) => import::read_mesh(&self.resolve(f), &src.transform)
                    .map_err(|source| SceneFileError::Import {
                        path: self.path.clone(),
                        key: path_string(p),
                        source,
                    })?,
                (None, Some(v), Some(t)) => {
                    src.transform
                        .validate()
                        .map_err(|m| self.invalid(&[p, &[key("transform")]].concat(), m))?;
                    let m = TriMesh {
                        vertices: v.iter().map(|&a| v3(a)).collect(),
                        triangles: t.clone(),
                    }
                    .transformed(&src.transform);
                    m.validate().map_err(|m| self.invalid(p, m))?;
                    m
                }
                _ => {
                    return Err(self.invalid(
                        p,
                        "a mesh needs either `file` or both `vertices` and `triangles`",
                    ))
                }
            };
        Ok(mesh)
    }

    /// Builds the scene: checks every value, resolves materials, generates and reads the
    /// spheres (each group avoiding the spheres of the groups before it), reads the meshes.
    pub fn build(&self, opts: &BuildOptions) -> Result<BuiltScene, SceneFileError> {
        self.build_inner(opts, true)
    }

    /// [`Self::build`] without the spheres of `spheres` lists, files and fills: every check
    /// of the file but those of single spheres (fills validated with a count of 0, sphere
    /// files not read), the scene model with its obstacles, materials and settings and no
    /// sphere batch from those groups (shaped bodies built). With
    /// [`Self::for_each_sphere`] the pieces of a distributed build that holds no sphere it does
    /// not keep.
    pub fn build_skeleton(&self, opts: &BuildOptions) -> Result<BuiltScene, SceneFileError> {
        self.build_inner(opts, false)
    }

    /// Hands to `emit` the free spheres [`Self::build`] then [`BuiltScene::build`] put into
    /// the world, one at a time, in the world's order and to the bit (materials as index 0,
    /// as in a world of one contact law), holding none of them; returns their number. `None`
    /// (after emitting some, possibly) where this file cannot be enumerated so, i.e. unless
    /// every group of `[[bodies]]` is a free `spheres` list, a free sphere file (`.csv`,
    /// `.npy`: read row by row, [`import::for_each_particle`]) or a free lattice fill of a
    /// region with nothing placed before it (a later fill avoids the spheres before it) and
    /// the file has no inlet; and where a sphere would be refused by those builds (non-finite
    /// values, radius or mass not positive, an unknown material, an unreadable file, a fill
    /// with `require_all` placing fewer than asked): the whole build then says why. Containment and overlaps are not checked here. The same
    /// sequence at every call.
    pub fn for_each_sphere(
        &self,
        opts: &BuildOptions,
        emit: &mut dyn FnMut(Sphere),
    ) -> Option<usize> {
        let f = &self.file;
        if !f.inlets.is_empty() {
            return None;
        }
        let seed = opts.seed.unwrap_or(f.seed);
        let pos = |x: f64| x.is_finite() && x > 0.0;
        let mut n = 0usize;
        let mut ok = true;
        for (i, g) in f.bodies.iter().enumerate() {
            if g.fixed || g.shape.is_some() {
                return None;
            }
            let density_of = |m: &str| {
                f.materials
                    .get(m)
                    .map(|x| x.density)
                    .or((m == DEFAULT_MATERIAL).then_some(DEFAULT_DENSITY))
            };
            let rho_group = match g.density {
                Some(d) => d,
                None => density_of(&g.material)?,
            };
            let v0 = v3(g.velocity.unwrap_or([0.0; 3]));
            let w0 = v3(g.angular_velocity);
            let nothing_before = n == 0;
            let mut put = |position: Vec3, radius: f64, velocity: Vec3, rho: f64| {
                let mass = sphere_mass(rho, radius);
                ok &= pos(radius)
                    && pos(mass)
                    && position.is_finite()
                    && velocity.is_finite()
                    && w0.is_finite();
                n += 1;
                emit(Sphere {
                    position,
                    velocity,
                    angular_velocity: w0,
                    radius,
                    mass,
                    rotation_locked: false,
                    material: 0,
                });
            };
            if let Some(list) = &g.spheres {
                for s in list {
                    if !(s[..3].iter().all(|x| x.is_finite()) && pos(s[3])) {
                        return None;
                    }
                    put(Vec3::new(s[0], s[1], s[2]), s[3], v0, rho_group);
                }
            } else if let Some(name) = &g.file {
                let mut known = true;
                import::for_each_particle(&self.resolve(name), &mut |r| {
                    let rho = match (&r.material, g.density) {
                        (Some(m), None) => density_of(m),
                        (Some(m), Some(d)) => density_of(m).map(|_| d),
                        (None, _) => Some(rho_group),
                    };
                    match rho {
                        Some(rho) => put(r.position, r.radius, r.velocity.unwrap_or(v0), rho),
                        None => known = false,
                    }
                })
                .ok()?;
                if !known {
                    return None;
                }
            } else if let Some(fill) = &g.fill {
                let (Some(region), None) = (&fill.region, &fill.mesh) else {
                    return None;
                };
                if !nothing_before || !matches!(fill.packing, Packing::Lattice { .. }) {
                    return None;
                }
                let fill_index = f.bodies[..i].iter().filter(|b| b.fill.is_some()).count();
                let count = opts.max_fill.map_or(fill.count, |m| fill.count.min(m));
                let spec = FillSpec {
                    count,
                    sizes: fill.sizes.clone(),
                    packing: fill.packing.clone(),
                    velocity: v0,
                    velocity_jitter: fill.velocity_jitter,
                    seed: fill
                        .seed
                        .unwrap_or_else(|| seed.wrapping_add(fill_index as u64)),
                };
                region.validate().ok()?;
                let mut placed = 0usize;
                generate::fill_each(region, &spec, &[], &mut |q| {
                    placed += 1;
                    put(q.position, q.radius, q.velocity, rho_group);
                })
                .ok()?;
                if fill.require_all && opts.max_fill.is_none() && placed < count {
                    return None;
                }
            } else {
                return None;
            }
        }
        ok.then_some(n)
    }

    /// The spheres the scene will hold at most, from its counts alone (nothing generated):
    /// the `spheres` lists, the fills' `count` (capped by [`BuildOptions::max_fill`]) and what
    /// the inlets emit over the run when its length is known (`steps` × `h` or `duration`,
    /// else the inlet's `end`): a count rate × the time, a mass rate × the time over the mass
    /// of the smallest sphere, each at most [`generate::MAX_EMISSIONS`]. Particle files are
    /// not counted (their size is bounded by [`coulomb::input::Kind::Particles`]).
    pub fn planned_spheres(&self, opts: &BuildOptions) -> u64 {
        let f = &self.file;
        let mut n: u64 = 0;
        for g in &f.bodies {
            if let Some(s) = &g.spheres {
                n = n.saturating_add(s.len() as u64);
            }
            if let Some(fill) = &g.fill {
                let count = opts.max_fill.map_or(fill.count, |m| fill.count.min(m));
                n = n.saturating_add(count as u64);
            }
        }
        let run_end = match (f.step.run.steps, f.step.run.duration) {
            (Some(k), _) => Some(k as f64 * f.step.settings.h),
            (None, Some(d)) => Some(d),
            _ => None,
        };
        for s in &f.inlets {
            let end = match (s.end, run_end) {
                (Some(e), Some(r)) => e.min(r),
                (Some(e), None) => e,
                (None, Some(r)) => r,
                (None, None) => continue,
            };
            let time = end - s.start;
            if !(time.is_finite() && time > 0.0) {
                continue;
            }
            let per_second = match s.rate {
                Rate::Count(c) => c,
                Rate::Mass(m) => {
                    let rho = f
                        .materials
                        .get(&s.material)
                        .map_or(DEFAULT_DENSITY, |x| x.density);
                    let r = s.sizes.min_radius();
                    // a body of another shape is lighter than its bounding ball: its volume
                    // at bounding radius 1 (a shape that does not validate is refused later)
                    let unit = match s.shape.as_ref().filter(|x| !x.is_sphere()) {
                        None => 4.0 / 3.0 * std::f64::consts::PI,
                        Some(x) => {
                            let r0 = x.bounding_radius();
                            x.volume()
                                .map_or(4.0 / 3.0 * std::f64::consts::PI, |v| v / (r0 * r0 * r0))
                        }
                    };
                    m / (rho * unit * r * r * r)
                }
            };
            let emitted = (per_second * time).ceil();
            let emitted = if emitted.is_finite() && emitted >= 0.0 {
                (emitted as u64).min(generate::MAX_EMISSIONS as u64)
            } else {
                generate::MAX_EMISSIONS as u64
            };
            n = n.saturating_add(emitted);
        }
        n
    }

    /// Refuses, before anything is generated, a scene whose [`Self::planned_spheres`] need
    /// more memory than is available ([`crate::model::check_memory`]): `count = 1e12` is an
    /// error, not an allocation.
    fn check_planned_memory(&self, opts: &BuildOptions) -> Result<(), SceneFileError> {
        let n = self.planned_spheres(opts);
        let n = usize::try_from(n).unwrap_or(usize::MAX);
        crate::model::check_memory(n, 0, crate::model::available_memory()).map_err(|source| {
            SceneFileError::Model {
                path: self.path.clone(),
                source,
            }
        })
    }

    fn build_inner(
        &self,
        opts: &BuildOptions,
        spheres: bool,
    ) -> Result<BuiltScene, SceneFileError> {
        let f = &self.file;

        let seed = opts.seed.unwrap_or(f.seed);
        let fin3 = |a: &[f64; 3]| a.iter().all(|x| x.is_finite());
        let pos = |x: f64| x.is_finite() && x > 0.0;
        if spheres {
            self.check_planned_memory(opts)?;
        }
        if !fin3(&f.gravity) {
            return Err(self.invalid(&[key("gravity")], "must be finite"));
        }
        self.check_step()?;
        // materials
        let mut density: BTreeMap<String, f64> = BTreeMap::new();
        density.insert(DEFAULT_MATERIAL.into(), DEFAULT_DENSITY);
        for (name, m) in &f.materials {
            if !pos(m.density) {
                return Err(self.invalid(
                    &[key("materials"), key(name), key("density")],
                    format!("density {} must be finite and positive", m.density),
                ));
            }
            density.insert(name.clone(), m.density);
        }
        let known = |p: &[Seg], name: &str| -> Result<f64, SceneFileError> {
            density.get(name).copied().ok_or_else(|| {
                let names: Vec<&str> = density.keys().map(String::as_str).collect();
                self.invalid(
                    p,
                    format!(
                        "unknown material '{name}' (materials: {})",
                        names.join(", ")
                    ),
                )
            })
        };
        // the model's validation of the laws, located here
        let materials = Materials {
            names: density
                .keys()
                .filter(|n| n.as_str() != DEFAULT_MATERIAL)
                .cloned()
                .collect(),
            default: f.default_pair,
            pairs: f.pairs.clone(),
        };
        materials.check_key().map_err(|(at, e)| {
            let p = match at {
                LawKey::Default => vec![key("default_pair")],
                LawKey::Pair(k) => vec![key("pairs"), Seg::Index(k)],
                LawKey::PairMaterial(k, i) => {
                    vec![key("pairs"), Seg::Index(k), key("materials"), Seg::Index(i)]
                }
            };
            let message = match e {
                SceneError::InvalidLaw { reason, .. } if at == LawKey::Default => {
                    reason.trim_start_matches("the default law: ").to_string()
                }
                SceneError::UnknownMaterial { name, known, .. } => {
                    format!("unknown material '{name}' (materials: {known})")
                }
                e => e.to_string(),
            };
            self.invalid(&p, message)
        })?;
        // bodies
        let mut bodies: Vec<BodyOut> = Vec::new();
        // every group's bodies in file order: spheres (index into `bodies`) or shaped
        let mut order: Vec<Result<usize, BodySpec>> = Vec::new();
        let mut fills = Vec::new();
        for (i, g) in f.bodies.iter().enumerate() {
            let p = vec![key("bodies"), Seg::Index(i)];
            let at = |k: &str| [&p[..], &[key(k)]].concat();
            let rho_group = match g.density {
                Some(d) if !pos(d) => {
                    return Err(self.invalid(&at("density"), format!("{d} must be positive")))
                }
                Some(d) => d,
                None => known(&at("material"), &g.material)?,
            };
            known(&at("material"), &g.material)?;
            let v0 = g.velocity.unwrap_or([0.0; 3]);
            if !fin3(&v0) || !fin3(&g.angular_velocity) {
                return Err(self.invalid(&p, "velocity and angular_velocity must be finite"));
            }
            let sources = [
                g.spheres.is_some(),
                g.file.is_some(),
                g.fill.is_some(),
                g.shape.is_some(),
            ];
            if sources.iter().filter(|&&b| b).count() != 1 {
                return Err(self.invalid(
                    &p,
                    "give exactly one of `spheres`, `file`, `fill` and `shape`",
                ));
            }
            if g.shape.is_none() {
                for k in [
                    "positions",
                    "orientations",
                    "mass",
                    "inertia",
                    "centre_of_mass",
                ] {
                    let given = match k {
                        "positions" => g.positions.is_some(),
                        "orientations" => g.orientations.is_some(),
                        "mass" => g.mass.is_some(),
                        "inertia" => g.inertia.is_some(),
                        _ => g.centre_of_mass.is_some(),
                    };
                    if given {
                        return Err(self.invalid(&at(k), "only for a group with `shape`"));
                    }
                }
            }
            let first = bodies.len();
            let make =
                |pos: Vec3, r: f64, v: Option<Vec3>, mat: Option<String>, rho: f64| BodyOut {
                    position: pos,
                    radius: r,
                    mass: sphere_mass(rho, r),
                    velocity: v.unwrap_or(v3(v0)),
                    angular_velocity: v3(g.angular_velocity),
                    material: mat.unwrap_or_else(|| g.material.clone()),
                    fixed: g.fixed,
                };
            if let Some(list) = &g.spheres {
                let list = if spheres { &list[..] } else { &[] };
                for (k, s) in list.iter().enumerate() {
                    if !(s[..3].iter().all(|x| x.is_finite()) && pos(s[3])) {
                        return Err(self.invalid(
                            &[&p[..], &[key("spheres"), Seg::Index(k)]].concat(),
                            format!("sphere {s:?}: needs a finite centre and a positive radius"),
                        ));
                    }
                    bodies.push(make(
                        Vec3::new(s[0], s[1], s[2]),
                        s[3],
                        None,
                        None,
                        rho_group,
                    ));
                }
            } else if let Some(name) = &g.file {
                if !spheres {
                    order.extend((first..bodies.len()).map(Ok));
                    continue;
                }
                let recs = import::read_particles(&self.resolve(name)).map_err(|source| {
                    SceneFileError::Import {
                        path: self.path.clone(),
                        key: path_string(&at("file")),
                        source,
                    }
                })?;
                for r in recs {
                    let rho = match (&r.material, g.density) {
                        (Some(m), None) => known(&at("file"), m)?,
                        (Some(m), Some(d)) => {
                            known(&at("file"), m)?;
                            d
                        }
                        (None, _) => rho_group,
                    };
                    bodies.push(make(r.position, r.radius, r.velocity, r.material, rho));
                }
            } else if let Some(fill) = &g.fill {
                let fp = at("fill");
                let fill_index = f.bodies[..i].iter().filter(|b| b.fill.is_some()).count();
                let count = opts.max_fill.map_or(fill.count, |m| fill.count.min(m));
                let spec = FillSpec {
                    count: if spheres { count } else { 0 },
                    sizes: fill.sizes.clone(),
                    packing: fill.packing.clone(),
                    velocity: v3(v0),
                    velocity_jitter: fill.velocity_jitter,
                    seed: fill
                        .seed
                        .unwrap_or_else(|| seed.wrapping_add(fill_index as u64)),
                };
                let avoid: Vec<(Vec3, f64)> =
                    bodies.iter().map(|b| (b.position, b.radius)).collect();
                let must_fit = fill.require_all && opts.max_fill.is_none();
                let filled = match (&fill.region, &fill.mesh) {
                    (Some(r), None) => {
                        r.validate().map_err(|e| {
                            self.invalid(&[&fp[..], &[key("region")]].concat(), e.to_string())
                        })?;
                        if must_fit && matches!(spec.packing, generate::Packing::Random { .. }) {
                            generate::check_fits(r.bounds(), &spec)
                                .map_err(|e| self.invalid(&fp, e.to_string()))?;
                        }
                        generate::fill(r, &spec, &avoid)
                    }
                    (None, Some(m)) => {
                        let mp = [&fp[..], &[key("mesh")]].concat();
                        let mesh = self.mesh(m, &mp)?;
                        mesh.check_closed_and_oriented()
                            .map_err(|e| self.invalid(&mp, e))?;
                        let (lo, hi) = mesh.bounds();
                        if must_fit && matches!(spec.packing, generate::Packing::Random { .. }) {
                            generate::check_fits((lo, hi), &spec)
                                .map_err(|e| self.invalid(&fp, e.to_string()))?;
                        }
                        let inside = |x: Vec3| mesh.inside(x);
                        // a sphere clears the walls when no triangle is nearer than its radius
                        let tris = mesh.triangles.iter().map(|t| t.map(|i| i as u64)).collect();
                        let walls = TriangleMesh::new(mesh.vertices.clone(), tris)
                            .map_err(|e| self.invalid(&mp, e.to_string()))?;
                        let clear = |c: Vec3, r: f64| {
                            let mut hit = false;
                            walls.near_each(c, r, 0.0, |_, _, _| hit = true);
                            !hit
                        };
                        let region = generate::Predicate {
                            lo,
                            hi,
                            inside: &inside,
                            clear: Some(&clear),
                        };
                        generate::fill(&region as &dyn Region, &spec, &avoid)
                    }
                    _ => return Err(self.invalid(&fp, "give exactly one of `region` and `mesh`")),
                }
                .map_err(|e| self.invalid(&fp, e.to_string()))?;
                if must_fit && filled.placed() < filled.asked {
                    return Err(self.invalid(
                        &fp,
                        format!(
                            "only {} of {} spheres fit in the region ({} positions tried); enlarge it, lower `count`, or set require_all = false",
                            filled.placed(),
                            filled.asked,
                            filled.attempts
                        ),
                    ));
                }
                fills.push((filled.asked, filled.placed()));
                for q in filled.particles {
                    bodies.push(make(
                        q.position,
                        q.radius,
                        Some(q.velocity),
                        None,
                        rho_group,
                    ));
                }
            } else if let Some(shape) = &g.shape {
                order.extend(
                    self.shaped(g, shape, &p, rho_group, v0)?
                        .into_iter()
                        .map(Err),
                );
            }
            order.extend((first..bodies.len()).map(Ok));
        }
        // robots: their links after every group's bodies, their joints after [[joints]]
        let mut joints = f.joints.clone();
        for (i, u) in f.urdf.iter().enumerate() {
            let p = vec![key("urdf"), Seg::Index(i)];
            known(&[&p[..], &[key("material")]].concat(), &u.material)?;
            let placement = crate::urdf::UrdfPlacement {
                position: u.position,
                orientation: u.orientation,
                fixed_base: u.fixed_base,
                material: u.material.clone(),
            };
            let robot =
                crate::urdf::read(&self.resolve(&u.file), &placement).map_err(|source| {
                    SceneFileError::Urdf {
                        path: self.path.clone(),
                        at: self.locate(&p),
                        key: path_string(&p),
                        source: Box::new(source),
                    }
                })?;
            joints.extend(robot.joints_from(order.len()));
            order.extend(robot.bodies.into_iter().map(Err));
        }
        // obstacles
        let mut obstacles = Vec::new();
        for (i, o) in f.obstacles.iter().enumerate() {
            let p = [key("obstacles"), Seg::Index(i)];
            known(&[&p[..], &[key("material")]].concat(), &o.material)?;
            let name = o.name.clone().unwrap_or_else(|| format!("obstacle-{i}"));
            let mut shape = match &o.shape {
                ObstacleShape::Shape(s) => s.clone(),
                ObstacleShape::Mesh { source, side } => {
                    let sp = [&p[..], &[key("shape")]].concat();
                    let m = self.mesh(source, &sp)?;
                    let tris = m.triangles.iter().map(|t| t.map(|i| i as u64)).collect();
                    let mesh = TriangleMesh::new(m.vertices, tris)
                        .map_err(|e| self.invalid(&sp, e.to_string()))?;
                    Shape::Mesh { mesh, side: *side }
                }
            };
            let mut motion = o.motion.clone();
            self.unit_vectors(&p, &mut shape, &mut motion)?;
            // the model's validation, located here
            crate::model::check_obstacle(i, &name, &shape, &motion)
                .map_err(|e| self.invalid(&p, e.to_string()))?;
            obstacles.push(ObstacleSpec {
                name,
                shape,
                motion,
                material: o.material.clone(),
            });
        }
        // inlets
        let mut inlets = Vec::new();
        for (i, s) in f.inlets.iter().enumerate() {
            let p = vec![key("inlets"), Seg::Index(i)];
            let rho = known(&[&p[..], &[key("material")]].concat(), &s.material)?;
            let mut inlet = Inlet::new(
                s.region.clone(),
                s.sizes.clone(),
                rho,
                s.rate,
                s.seed.unwrap_or_else(|| seed.wrapping_add(1000 + i as u64)),
            );
            inlet.start = s.start;
            inlet.end = s.end.unwrap_or(f64::INFINITY);
            inlet.velocity = s.velocity;
            if let Some(a) = s.attempts {
                inlet.attempts = a;
            }
            if let Some(shape) = &s.shape {
                shape.validate().map_err(|e| {
                    self.invalid(
                        &[&p[..], &[key("shape")]].concat(),
                        format!("{} refused: {e}", shape.kind()),
                    )
                })?;
            }
            let inlet = inlet.with_shape(s.shape.clone());
            inlet
                .validate()
                .map_err(|e| self.invalid(&p, e.to_string()))?;
            inlets.push(InletRun {
                inlet,
                density: rho,
                material: s.material.clone(),
                capped: 0,
            });
        }
        let name = f.name.clone().unwrap_or_else(|| {
            self.path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("scene")
                .to_string()
        });
        let mut materials = materials;
        if materials
            .pairs
            .iter()
            .all(|p| p.law(materials.default) == materials.default)
        {
            materials.names.clear();
            materials.pairs.clear();
            for b in &mut bodies {
                b.material = DEFAULT_MATERIAL.to_string();
            }
            for o in &mut obstacles {
                o.material = DEFAULT_MATERIAL.to_string();
            }
            for b in order.iter_mut().filter_map(|e| e.as_mut().err()) {
                b.material = DEFAULT_MATERIAL.to_string();
            }
            for i in &mut inlets {
                i.material = DEFAULT_MATERIAL.to_string();
            }
        }
        // with shaped bodies (or an inlet pouring them), every body is a body spec in file
        // order (the rigid-body simulator's indices, after which poured bodies are appended);
        // else the spheres are batches (the sphere simulator's path)
        let rigid = order.iter().any(|e| e.is_err())
            || !joints.is_empty()
            || inlets.iter().any(|i| i.inlet.poured_shape().is_some());
        let (specs, sphere_batches) = if rigid {
            let specs = order
                .into_iter()
                .map(|e| match e {
                    Ok(i) => sphere_spec(&bodies[i]),
                    Err(spec) => spec,
                })
                .collect();
            (specs, Vec::new())
        } else {
            (Vec::new(), batches(&bodies))
        };
        let model = SceneModel {
            gravity: v3(f.gravity),
            materials,
            bodies: specs,
            sphere_batches,
            obstacles,
            step: f.step.settings.clone(),
            joints,
        };
        Ok(BuiltScene {
            path: self.path.clone(),
            name,
            model,
            step: f.step.clone(),
            inlets,
            fills,
        })
    }

    /// The bodies of a `shape` group, validated (shape, positions, orientations, mass,
    /// inertia), each error at its key.
    fn shaped(
        &self,
        g: &BodiesSection,
        shape: &BodyShape,
        p: &[Seg],
        density: f64,
        v0: [f64; 3],
    ) -> Result<Vec<BodySpec>, SceneFileError> {
        let at = |k: &str| [p, &[key(k)]].concat();
        shape
            .validate()
            .map_err(|e| self.invalid(&at("shape"), format!("{} refused: {e}", shape.kind())))?;
        let Some(positions) = &g.positions else {
            return Err(self.invalid(p, "a group with `shape` needs `positions`"));
        };
        let n = positions.len();
        let orientations = g.orientations.clone().unwrap_or_default();
        if !(orientations.len() <= 1 || orientations.len() == n) {
            return Err(self.invalid(
                &at("orientations"),
                format!(
                    "{} orientations for {n} bodies (one per body or one for all)",
                    orientations.len()
                ),
            ));
        }
        for (k, q) in orientations.iter().enumerate() {
            crate::shape::check_quaternion("orientation", *q).map_err(|e| {
                self.invalid(
                    &[&at("orientations")[..], &[Seg::Index(k)]].concat(),
                    e.to_string(),
                )
            })?;
        }
        if let Some(m) = g.mass {
            if !(m.is_finite() && m > 0.0) {
                return Err(self.invalid(&at("mass"), format!("{m} must be positive")));
            }
        }
        if g.inertia.is_some() && shape.is_sphere() {
            return Err(self.invalid(
                &at("inertia"),
                "a sphere's inertia is 2/5 m R²: `inertia` is for other shapes",
            ));
        }
        if let Some(c) = g.centre_of_mass {
            if shape.is_sphere() {
                return Err(self.invalid(
                    &at("centre_of_mass"),
                    "a sphere's centre of mass is its centre: `centre_of_mass` is for other shapes",
                ));
            }
            if g.inertia.is_none() {
                return Err(self.invalid(
                    &at("centre_of_mass"),
                    "needs `inertia` (the tensor about that centre of mass)",
                ));
            }
            if !c.iter().all(|x| x.is_finite()) {
                return Err(self.invalid(&at("centre_of_mass"), "must be finite"));
            }
        }
        if g.fixed && (v0 != [0.0; 3] || g.angular_velocity != [0.0; 3]) {
            return Err(self.invalid(p, "fixed bodies cannot have velocities"));
        }
        let mut out = Vec::with_capacity(n);
        for (k, x) in positions.iter().enumerate() {
            if !x.iter().all(|c| c.is_finite()) {
                return Err(self.invalid(
                    &[&at("positions")[..], &[Seg::Index(k)]].concat(),
                    "must be finite",
                ));
            }
            let orientation = match orientations.len() {
                0 => crate::shape::IDENTITY,
                1 => orientations[0],
                _ => orientations[k],
            };
            out.push(BodySpec {
                shape: shape.clone(),
                position: v3(*x),
                orientation,
                velocity: v3(v0),
                angular_velocity: v3(g.angular_velocity),
                mass: g.mass,
                density: g.mass.is_none().then_some(density),
                inertia: g.inertia,
                centre_of_mass: g.centre_of_mass,
                material: g.material.clone(),
                fixed: g.fixed,
            });
        }
        Ok(out)
    }

    fn check_step(&self) -> Result<(), SceneFileError> {
        let (settings, s) = (&self.file.step.settings, &self.file.step.run);
        let at = |k: &str| [key("step"), key(k)];
        // the model's validation, located here
        settings
            .check_key()
            .map_err(|(k, m)| self.invalid(&at(k), m))?;
        if let Some(d) = s.duration {
            if !(d.is_finite() && d >= 0.0) {
                return Err(self.invalid(&at("duration"), format!("{d} must be ≥ 0")));
            }
            if s.steps.is_some() {
                return Err(self.invalid(&at("duration"), "give `steps` or `duration`, not both"));
            }
        }
        if s.until_rest && (s.steps.is_some() || s.duration.is_some()) {
            return Err(self.invalid(
                &at("until_rest"),
                "until_rest stops by itself (cap: max_steps): drop `steps` and `duration`",
            ));
        }
        if !(s.rest_speed.is_finite() && s.rest_speed > 0.0) {
            return Err(self.invalid(&at("rest_speed"), "must be positive"));
        }
        if s.max_steps == 0 {
            return Err(self.invalid(&at("max_steps"), "must be ≥ 1"));
        }
        if self.file.step.fixed_steps() > 100_000_000 {
            return Err(self.invalid(&[key("step")], "more than 1e8 steps"));
        }
        Ok(())
    }

    /// The normals, axes and directions of obstacle `p` normalized (a rectangle's `u` made
    /// orthogonal to its normal first), each refused at its shape or motion where it is not
    /// finite and non-zero: a file may write `normal = [0, 0, 2]`, the model holds unit
    /// vectors.
    fn unit_vectors(
        &self,
        p: &[Seg],
        shape: &mut Shape,
        motion: &mut Motion,
    ) -> Result<(), SceneFileError> {
        let unit = |at: &str, v: &mut Vec3, what: &str| {
            if v.is_finite() && v.norm() > 0.0 {
                *v = v.normalized_or(Vec3::Z);
                Ok(())
            } else {
                Err(self.invalid(
                    &[p, &[key(at)]].concat(),
                    format!("{what} {:?} must be finite and non-zero", v.to_array()),
                ))
            }
        };
        match shape {
            Shape::Plane { normal, .. } => unit("shape", normal, "normal")?,
            Shape::Rectangle { normal, u, .. } => {
                unit("shape", &mut *normal, "normal")?;
                *u = *u - *normal * u.dot(*normal);
                unit("shape", u, "u (orthogonal to the normal)")?;
            }
            Shape::CylinderInside { axis, .. } | Shape::Cylinder { axis, .. } => {
                unit("shape", axis, "axis")?
            }
            _ => {}
        }
        match motion {
            Motion::Oscillate { direction, .. } => unit("motion", direction, "direction"),
            Motion::Rotate { axis, .. } => unit("motion", axis, "axis"),
            _ => Ok(()),
        }
    }
}

/// A sphere of the built scene as a body spec of the scene model (mass given).
fn sphere_spec(b: &BodyOut) -> BodySpec {
    BodySpec {
        mass: Some(b.mass),
        density: None,
        velocity: b.velocity,
        angular_velocity: b.angular_velocity,
        material: b.material.clone(),
        fixed: b.fixed,
        ..BodySpec::sphere(b.position, b.radius, 1.0)
    }
}

/// The spheres as batches of the scene model: one per run of consecutive spheres of the same
/// material and mobility, masses given (so that they are the file's to the bit).
fn batches(bodies: &[BodyOut]) -> Vec<SphereBatch> {
    let mut out: Vec<SphereBatch> = Vec::new();
    for b in bodies {
        let same = out
            .last()
            .is_some_and(|l| l.material == b.material && l.fixed == b.fixed);
        if !same {
            out.push(SphereBatch {
                material: b.material.clone(),
                fixed: b.fixed,
                ..SphereBatch::default()
            });
        }
        if let Some(l) = out.last_mut() {
            l.positions.push(b.position);
            l.radii.push(b.radius);
            l.masses.push(b.mass);
            l.velocities.push(b.velocity);
            l.angular_velocities.push(b.angular_velocity);
        }
    }
    // fixed spheres carry no velocity
    for l in &mut out {
        if l.fixed {
            l.velocities.clear();
            l.angular_velocities.clear();
        }
    }
    out
}

impl BuiltScene {
    /// Whether the scene runs in the rigid-body simulator: its model has bodies of other
    /// shapes than spheres or joints ([`SceneModel::has_shapes`]), or an inlet pours bodies
    /// of another shape (its spheres are then bodies of the rigid world, from the start).
    pub fn runs_rigid(&self) -> bool {
        self.model.has_shapes() || self.inlets.iter().any(|i| i.inlet.poured_shape().is_some())
    }

    /// Every inlet's bodies due in (t0, t1] inserted into `rigid` ([`InletRun::pour_rigid`],
    /// inlets in file order): what a run does after each step t0 → t1 of a rigid scene.
    pub fn pour_rigid(
        &mut self,
        rigid: &mut RigidScene,
        t0: f64,
        t1: f64,
    ) -> Result<Poured, SceneError> {
        let mut out = Poured::default();
        for inlet in &mut self.inlets {
            let before = inlet.capped;
            let (n, k) = inlet.pour_rigid(rigid, t0, t1)?;
            out.inserted += n;
            out.skipped += k;
            out.capped += inlet.capped - before;
        }
        Ok(out)
    }

    /// The world and parameters of the scene ([`SceneModel::build_with`] with `checks`).
    pub fn build(&self, checks: &BuildChecks) -> Result<(World, Params), SceneFileError> {
        self.model
            .build_with(checks)
            .map_err(|source| SceneFileError::Model {
                path: self.path.clone(),
                source,
            })
    }

    /// Every sphere the scene starts with (free and fixed).
    pub fn sphere_count(&self) -> usize {
        self.model
            .sphere_batches
            .iter()
            .map(|b| b.positions.len())
            .sum::<usize>()
            + self
                .model
                .bodies
                .iter()
                .filter(|b| b.shape.is_sphere())
                .count()
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::model::StepChoice;

    fn parse(text: &str) -> Result<LoadedScene, SceneFileError> {
        LoadedScene::parse(Path::new("t.toml"), text.to_string(), true)
    }

    /// A fill of 10¹² spheres (and an inlet pouring 10¹⁰ per second) is refused from its count
    /// alone, before anything is generated: a typed memory error at once, never an abort.
    /// Arrays longer than their field are refused at their line and column (issue 55: TOML
    /// dropped the extra elements), in a sphere list, a region corner and a shaped body's
    /// orientation and inertia; the same arrays of the right length are accepted.
    pub fn extra_array_elements_are_refused_with_their_place() {
        let base = "[[obstacles]]\nshape = { kind = \"box\", lo = [0, 0, 0], hi = [1, 1, 1] }\n";
        let ok = format!("{base}[[bodies]]\nspheres = [[0.5, 0.5, 0.5, 0.1]]\n");
        assert!(parse(&ok).is_ok());
        let e = parse(&format!(
            "{base}[[bodies]]\nspheres = [[0.5, 0.5, 0.5, 0.1], [0.2, 0.2, 0.2, 0.1, 1]]\n"
        ))
        .unwrap_err();
        let m = e.to_string();
        assert!(
            matches!(
                &e,
                SceneFileError::Invalid {
                    at: Some((4, _)),
                    ..
                }
            ),
            "{m}"
        );
        assert!(
            m.contains("bodies[0].spheres[1]") && m.contains("5 values where 4"),
            "{m}"
        );
        let e =
            parse("[[obstacles]]\nshape = { kind = \"box\", lo = [0, 0, 0, 7], hi = [1, 1, 1] }\n")
                .unwrap_err();
        // (the TOML reader refuses this one itself, as a syntax error)
        let m = e.to_string();
        assert!(
            m.contains("4 values where 3") || m.contains("invalid length 4"),
            "{m}"
        );
        let body = "[[bodies]]\nshape = { kind = \"cuboid\", half_extents = [0.1, 0.1, 0.1] }\npositions = [[0.5, 0.5, 0.5]]\n";
        assert!(parse(&format!("{base}{body}orientations = [[1, 0, 0, 0]]\n")).is_ok());
        let e = parse(&format!("{base}{body}orientations = [[1, 0, 0, 0, 0]]\n")).unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("bodies[0].orientations[0]") && m.contains("5 values where 4"),
            "{m}"
        );
        let e = parse(&format!(
            "{base}{body}mass = 1.0\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 0]]\n"
        ))
        .unwrap_err();
        assert!(
            e.to_string()
                .contains("bodies[0].inertia: 4 values where 3"),
            "{e}"
        );
    }

    pub fn a_huge_fill_or_inlet_is_refused_before_building() {
        let fill = "[step]\nh = 0.01\nsteps = 10\n[[obstacles]]\nshape = { kind = \"box\", lo = [0, 0, 0], hi = [1, 1, 1] }\n\
            [[bodies]]\n[bodies.fill]\ncount = 1000000000000\nregion = { kind = \"box\", lo = [0, 0, 0], hi = [1, 1, 1] }\nsizes = { kind = \"uniform\", min = 0.01, max = 0.02 }\n";
        let scene = parse(fill).unwrap();
        assert_eq!(
            scene.planned_spheres(&BuildOptions::default()),
            1_000_000_000_000
        );
        let t = std::time::Instant::now();
        let e = scene.build(&BuildOptions::default()).unwrap_err();
        assert!(t.elapsed() < std::time::Duration::from_secs(5));
        assert!(
            matches!(
                &e,
                SceneFileError::Model {
                    source: SceneError::Memory {
                        spheres: 1_000_000_000_000,
                        ..
                    },
                    ..
                }
            ),
            "{e}"
        );
        // a capped fill is not refused for the count it will not build
        let capped = BuildOptions {
            max_fill: Some(10),
            ..Default::default()
        };
        assert_eq!(scene.planned_spheres(&capped), 10);
        let inlet = "[step]\nh = 0.01\nsteps = 100\n[[obstacles]]\nshape = { kind = \"box\", lo = [0, 0, 0], hi = [1, 1, 1] }\n\
            [[inlets]]\nregion = { kind = \"box\", lo = [0, 0, 0.5], hi = [1, 1, 1] }\nsizes = { kind = \"uniform\", min = 0.01, max = 0.02 }\nrate = { count = 1e10 }\n";
        let scene = parse(inlet).unwrap();
        assert_eq!(
            scene.planned_spheres(&BuildOptions::default()),
            crate::generate::MAX_EMISSIONS as u64
        );
        // a mass rate of cubes counts bodies of a cube's mass, not its bounding ball's:
        // (4/3 π) / (8 / 3^1.5) ≈ 2.72 times as many
        let mass = "[step]\nh = 0.01\nsteps = 100\n[[inlets]]\nregion = { kind = \"box\", lo = [0, 0, 0.5], hi = [1, 1, 1] }\nsizes = { kind = \"uniform\", min = 0.01, max = 0.02 }\nrate = { mass = 100.0 }\n";
        let balls = parse(mass)
            .unwrap()
            .planned_spheres(&BuildOptions::default());
        let cubes = parse(&format!(
            "{mass}shape = {{ kind = \"cuboid\", half_extents = [1, 1, 1] }}\n"
        ))
        .unwrap()
        .planned_spheres(&BuildOptions::default());
        let ratio = cubes as f64 / balls as f64;
        assert!((ratio - 2.72).abs() < 0.01, "{cubes} / {balls}");
    }

    /// A random fill past the packing bound: refused at once when every sphere must be placed,
    /// else the spheres that fit are kept, within the attempts of the count that could fit.
    pub fn an_overfull_random_fill_is_refused_or_keeps_what_fits() {
        let text = |require_all: bool| {
            format!(
                "[step]\nh = 0.01\nsteps = 10\n[[obstacles]]\nshape = {{ kind = \"box\", lo = [0, 0, 0], hi = [0.5, 0.5, 0.5] }}\n\
                 [[bodies]]\n[bodies.fill]\ncount = 20000\nrequire_all = {require_all}\npacking = {{ method = \"random\" }}\n\
                 region = {{ kind = \"box\", lo = [0, 0, 0], hi = [0.5, 0.5, 0.5] }}\nsizes = {{ kind = \"uniform\", min = 0.02, max = 0.03 }}\n"
            )
        };
        let t = std::time::Instant::now();
        let e = parse(&text(true))
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap_err();
        assert!(t.elapsed() < std::time::Duration::from_secs(5));
        assert!(e.to_string().contains("cannot fit"), "{e}");
        let built = parse(&text(false))
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap();
        let (asked, placed) = built.fills[0];
        assert_eq!(asked, 20000);
        assert!(placed > 100 && placed < 20000, "{placed}");
    }

    /// The spheres [`LoadedScene::for_each_sphere`] hands out are the built world's, bit for
    /// bit and in order, for an explicit list followed by another and for a first lattice fill
    /// (examples/scenes/box.toml, with and without a cap and another seed) and for a CSV
    /// sphere file after a list (a material per row, the group's velocity where the file has
    /// none); the skeleton holds none of them; files it cannot enumerate (a fill after
    /// spheres, a random fill, a fixed group), a sphere the build refuses and a missing
    /// sphere file give `None`.
    pub fn streamed_spheres_are_the_built_ones() {
        let list = "[[obstacles]]\nshape = { kind = \"plane\", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }\n\
            [[bodies]]\nspheres = [[0.0, 0.0, 0.1, 0.1], [0.3, 0.0, 0.2, 0.15]]\nvelocity = [1.0, 0.0, 0.0]\n\
            [materials.heavy]\ndensity = 7800.0\n\
            [[bodies]]\nmaterial = \"heavy\"\nangular_velocity = [0.0, 2.0, 0.0]\nspheres = [[1.0, 0.0, 0.1, 0.05]]\n";
        let bx = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/scenes/box.toml"
        ))
        .unwrap();
        let capped = BuildOptions {
            seed: Some(7),
            max_fill: Some(40),
        };
        let dir = std::env::temp_dir().join(format!("coulomb-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let csv = dir.join("spheres.csv");
        std::fs::write(
            &csv,
            "x,y,z,r,vx,vy,vz,material\n2,0,0.1,0.1,0,0,-1,heavy\n2.5,0,0.1,0.05,0,0,0,\n",
        )
        .unwrap();
        let with_file = format!(
            "{list}[[bodies]]\nfile = \"{}\"\nvelocity = [0.5, 0.0, 0.0]\n",
            csv.display()
        );
        for (text, opts) in [
            (list, BuildOptions::default()),
            (&with_file[..], BuildOptions::default()),
            (&bx[..], BuildOptions::default()),
            (&bx[..], capped),
        ] {
            let loaded = parse(text).unwrap();
            let (world, _) = loaded
                .build(&opts)
                .unwrap()
                .build(&BuildChecks::default())
                .unwrap();
            let mut streamed = Vec::new();
            let n = loaded.for_each_sphere(&opts, &mut |s| streamed.push(s));
            assert_eq!(n, Some(world.bodies.len()));
            assert_eq!(streamed, world.bodies);
            let skeleton = loaded.build_skeleton(&opts).unwrap();
            assert!(skeleton.model.sphere_batches.is_empty());
            assert_eq!(
                skeleton.model.obstacles,
                loaded.build(&opts).unwrap().model.obstacles
            );
        }
        let fill = bx.split("[[bodies]]").nth(1).unwrap();
        let after = format!("{list}[[bodies]]{fill}");
        let random = bx.replace(
            "packing = { method = \"lattice\", pitch = 0.125, jitter = 0.2 }",
            "packing = { method = \"random\" }",
        );
        let fixed = list.replace("velocity = [1.0, 0.0, 0.0]", "fixed = true");
        let bad = list.replace("[0.3, 0.0, 0.2, 0.15]", "[0.3, 0.0, 0.2, -0.15]");
        let unknown = with_file.replace("spheres.csv", "missing.csv");
        for text in [&after[..], &random, &fixed, &bad, &unknown] {
            let loaded = parse(text).unwrap();
            assert_eq!(
                loaded.for_each_sphere(&BuildOptions::default(), &mut |_| {}),
                None
            );
        }
    }

    pub fn unknown_keys_are_refused_with_file_line_and_column() {
        let e = parse("seed = 1\ngravty = [0, 0, -1]\n").unwrap_err();
        match &e {
            SceneFileError::Syntax {
                line,
                column,
                message,
                ..
            } => {
                assert_eq!((*line, *column), (2, 1), "{e}");
                assert!(message.contains("gravty"), "{e}");
            }
            other => panic!("{other:?}"),
        }
        assert!(e.to_string().starts_with("t.toml:2:1: "), "{e}");
        let e = parse("[step]\nh = 0.01\n  tehta = 0.5\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.toml:3:3: ") && e.contains("tehta"), "{e}");
        let e = parse("[[bodies]]\nspheres = [[0, 0, 1, 0.1]]\ncolour = 'red'\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.toml:3:1: ") && e.contains("colour"), "{e}");
        // JSON: serde_json's line and column
        let e = LoadedScene::parse(
            Path::new("t.json"),
            "{\n  \"seed\": 1,\n  \"stepp\": {}\n}".into(),
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("t.json:3:") && e.contains("stepp"), "{e}");
        // a syntax error
        let e = parse("seed = \n").unwrap_err();
        assert!(matches!(e, SceneFileError::Syntax { line: 1, .. }), "{e}");
    }

    pub fn a_pair_naming_an_unknown_material_is_refused_where_it_is() {
        let text = "[materials.glass]\ndensity = 2500\n\n[[pairs]]\nmaterials = [\"glass\", \"steel\"]\nmu = 0.5\n";
        let e = parse(text)
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap_err();
        let s = e.to_string();
        assert!(s.starts_with("t.toml:5:"), "{s}");
        assert!(
            s.contains("pairs[0].materials[1]") && s.contains("unknown material 'steel'"),
            "{s}"
        );
        // the model's refusal of a pair given twice (in either order), at the second one
        let e = parse(&format!("{text}[[pairs]]\nmaterials = [\"glass\", \"glass\"]\n[[pairs]]\nmaterials = [\"glass\", \"glass\"]\nrestitution = 0.1\n").replace("\"steel\"", "\"default\""))
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.toml:9:") && e.contains("pairs[2]") && e.contains("given twice"),
            "{e}"
        );
        // a body's material too
        let e = parse("[[bodies]]\nmaterial = \"sand\"\nspheres = [[0, 0, 1, 0.1]]\n")
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.toml:2:") && e.contains("'sand'"), "{e}");
    }

    pub fn bad_values_are_refused() {
        let cases = [
            ("[step]\nh = -1\n", "step.h"),
            ("[[bodies]]\nspheres = [[0, 0, 1, -0.1]]\n", "bodies[0].spheres[0]"),
            ("[[bodies]]\n", "exactly one of"),
            ("[default_pair]\nrestitution = 2\n", "default_pair"),
            ("[materials.x]\ndensity = 0\n", "materials.x.density"),
            (
                "[[bodies]]\n[bodies.fill]\ncount = 1000\nregion = { kind = \"box\", lo = [0,0,0], hi = [0.2,0.2,0.2] }\nsizes = { kind = \"mono\", radius = 0.05 }\n",
                "only 1 of 1000",
            ),
            (
                "[[obstacles]]\nshape = { kind = \"plane\", point = [0,0,0], normal = [0,0,0] }\n",
                "obstacles[0].shape",
            ),
            ("[[bodies]]\nfile = \"missing.csv\"\n", "missing.csv"),
        ];
        for (text, want) in cases {
            let e = parse(text)
                .and_then(|s| s.build(&BuildOptions::default()))
                .unwrap_err()
                .to_string();
            assert!(e.contains(want), "{text}: {e}");
        }
    }

    pub fn inline_spheres_materials_and_pairs() {
        let text = "[materials.steel]\ndensity = 7800\n[[pairs]]\nmaterials = [\"steel\", \"default\"]\nmu = 0.1\n[[bodies]]\nmaterial = \"steel\"\nvelocity = [1, 0, 0]\nspheres = [[0, 0, 1, 0.1], [1, 0, 1, 0.2]]\n";
        let b = parse(text)
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap();
        assert_eq!(b.sphere_count(), 2);
        let batch = &b.model.sphere_batches[0];
        assert_eq!(batch.masses[1], sphere_mass(7800.0, 0.2));
        assert_eq!(batch.velocities[0], Vec3::X);
        assert_eq!(batch.material, "steel");
        let pair = &b.model.materials.pairs[0];
        assert_eq!(pair.materials, ["steel", "default"]);
        // the restitution not given is the default law's
        let law = pair.law(b.model.materials.default);
        assert_eq!((law.mu, law.restitution), (0.1, 0.2));
        let (world, params) = b.build(&BuildChecks::default()).unwrap();
        assert_eq!(world.bodies.len(), 2);
        // the steel–default law is in the world's table; the default law in the parameters
        assert!(world.materials.is_some());
        assert_eq!(params.mu, 0.3);
    }

    pub fn files_next_to_the_scene_fixed_spheres_and_a_mesh_obstacle() {
        let dir = std::env::temp_dir().join(format!("coulomb-scene-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let stl = "solid f\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 2 0 0\nvertex 2 2 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 2 2 0\nvertex 0 2 0\nendloop\nendfacet\nendsolid f\n";
        std::fs::write(dir.join("floor.stl"), stl).unwrap();
        std::fs::write(
            dir.join("beads.csv"),
            "x,y,z,r,material\n0.5,0.5,0.5,0.1,rubber\n1.5,1.5,0.5,0.1,\n",
        )
        .unwrap();
        let scene = dir.join("s.toml");
        let text = "[materials.rubber]\ndensity = 1100\n[[pairs]]\nmaterials = [\"rubber\", \"default\"]\nrestitution = 0.8\n[[bodies]]\nfile = \"beads.csv\"\n[[bodies]]\nfixed = true\nspheres = [[1.0, 1.0, 0.1, 0.1]]\n[[obstacles]]\nname = \"floor\"\nshape = { kind = \"mesh\", file = \"floor.stl\", transform = { translate = [-0.5, -0.5, 0.0], scale = 1.5 } }\n";
        std::fs::write(&scene, text).unwrap();
        let b = LoadedScene::load(&scene)
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap();
        // the CSV's material column splits the group: rubber, then default; then the fixed one
        let mats: Vec<(&str, bool, usize)> = b
            .model
            .sphere_batches
            .iter()
            .map(|x| (x.material.as_str(), x.fixed, x.positions.len()))
            .collect();
        assert_eq!(
            mats,
            vec![
                ("rubber", false, 1),
                ("default", false, 1),
                ("default", true, 1)
            ]
        );
        assert_eq!(
            b.model.sphere_batches[0].masses[0],
            sphere_mass(1100.0, 0.1)
        );
        let (world, _) = b.build(&BuildChecks::default()).unwrap();
        assert_eq!(world.bodies.len(), 2);
        // the mesh (scaled by 1.5, moved by −0.5) and the fixed sphere
        assert_eq!(world.obstacles.len(), 2);
        match &world.obstacles[0].shape {
            Shape::Mesh { mesh, .. } => {
                let (lo, hi) = mesh.bounds();
                assert_eq!((lo.x, hi.x), (-0.5, 2.5));
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            world.obstacles[1].shape,
            Shape::Sphere { inside: false, .. }
        ));
        assert!(world.materials.is_some());
    }

    pub fn shaped_groups_become_body_specs_in_file_order() {
        let text = r#"
[materials.stone]
density = 2000

[[pairs]]
materials = ["stone", "stone"]
mu = 0.7

[[bodies]]
spheres = [[0, 0, 1, 0.1]]

[[bodies]]
material = "stone"
shape = { kind = "cuboid", half_extents = [0.2, 0.1, 0.05] }
positions = [[0, 0, 0.05], [0.5, 0, 0.05]]
orientations = [[0.7071067811865476, 0, 0, 0.7071067811865476]]
velocity = [1, 0, 0]

[[bodies]]
shape = { kind = "compound", parts = [
  { shape = { kind = "capsule", radius = 0.05, half_height = 0.1 }, position = [0, 0, 0] },
  { shape = { kind = "sphere", radius = 0.08 }, position = [0, 0.2, 0] },
] }
positions = [[2, 0, 1]]
mass = 3.0
"#;
        let built = parse(text)
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap();
        let m = &built.model;
        assert!(m.has_shapes() && m.sphere_batches.is_empty());
        let kinds: Vec<&str> = m.bodies.iter().map(|b| b.shape.kind()).collect();
        assert_eq!(kinds, ["sphere", "cuboid", "cuboid", "compound"]);
        assert_eq!(m.bodies[2].position, Vec3::new(0.5, 0.0, 0.05));
        assert_eq!(m.bodies[2].orientation[3], std::f64::consts::FRAC_1_SQRT_2);
        assert_eq!(m.bodies[1].density, Some(2000.0));
        assert_eq!(m.bodies[1].velocity, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!((m.bodies[3].mass, m.bodies[3].density), (Some(3.0), None));
        assert_eq!(m.bodies[1].material, "stone");
        assert_eq!(built.sphere_count(), 1);
        // the sphere simulator refuses the cuboids, saying where they go
        let e = m.world().unwrap_err().to_string();
        assert!(e.contains("body 1") && e.contains("cuboid"), "{e}");
        // JSON: the same keys
        let json = r#"{"bodies": [{"shape": {"kind": "cone", "radius": 0.1, "half_height": 0.2},
            "positions": [[0, 0, 1]]}]}"#;
        let j = LoadedScene::parse(Path::new("t.json"), json.into(), false)
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap();
        assert_eq!(j.model.bodies[0].shape.kind(), "cone");
    }

    pub fn bad_shaped_groups_are_refused_where_they_are() {
        let build = |t: &str| {
            parse(t)
                .unwrap()
                .build(&BuildOptions::default())
                .unwrap_err()
                .to_string()
        };
        let cube = "shape = { kind = \"cuboid\", half_extents = [1, 1, 1] }\n";
        let ball = "shape = { kind = \"sphere\", radius = 1 }\n";
        // a non-unit quaternion: refused at its line, not normalized
        let e = build(&format!(
            "[[bodies]]\n{cube}positions = [[0, 0, 1]]\norientations = [\n  [1, 0, 0, 0.1],\n]\n"
        ));
        assert!(
            e.starts_with("t.toml:5:") && e.contains("orientations[0]") && e.contains("unit"),
            "{e}"
        );
        // a coplanar hull: refused at the shape
        let e = build("[[bodies]]\npositions = [[0, 0, 1]]\nshape = { kind = \"convex_hull\", points = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]] }\n");
        assert!(e.starts_with("t.toml:3:") && e.contains("coplanar"), "{e}");
        // an unknown shape key: a syntax error with its line
        let e = parse("[[bodies]]\npositions = [[0, 0, 1]]\nshape = { kind = \"cuboid\", half_extent = [1, 1, 1] }\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.toml:3:") && e.contains("half_extent"),
            "{e}"
        );
        // shape keys without a shape, two sources, missing positions, mismatched counts
        let e = build("[[bodies]]\nspheres = [[0, 0, 1, 0.1]]\norientations = [[1, 0, 0, 0]]\n");
        assert!(
            e.contains("orientations") && e.contains("only for a group with `shape`"),
            "{e}"
        );
        let e = build(&format!("[[bodies]]\nspheres = [[0, 0, 1, 0.1]]\n{ball}"));
        assert!(e.contains("exactly one of"), "{e}");
        let e = build(&format!("[[bodies]]\n{ball}"));
        assert!(e.contains("needs `positions`"), "{e}");
        let e = build(&format!("[[bodies]]\n{ball}positions = [[0, 0, 1], [0, 0, 3], [0, 0, 5]]\norientations = [[1, 0, 0, 0], [1, 0, 0, 0]]\n"));
        assert!(e.contains("2 orientations for 3 bodies"), "{e}");
        let e = build(&format!(
            "[[bodies]]\n{ball}positions = [[0, 0, 1]]\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n"
        ));
        assert!(e.contains("inertia"), "{e}");
    }

    /// Obstacle shapes and motions, the default law and the step method are the model's own
    /// types (one schema with Python's description): the same keys and defaults read the same
    /// values, and the model's validation refuses bad values at their place in the file.
    pub fn obstacles_laws_and_steps_are_the_models_types_validated_once() {
        let text = "[default_pair]\nmu = 0.5\n[step]\nmethod = \"library\"\n\
            [[obstacles]]\nname = \"drum\"\nshape = { kind = \"cylinder_inside\", point = [0, 0, 0], axis = [0, 2, 0], radius = 1 }\n\
            motion = { kind = \"rotate\", center = [0, 0, 0], axis = [0, 3, 0], omega = 1.5 }\n\
            [[obstacles]]\nshape = { kind = \"box\", lo = [-1, -1, -1], hi = [1, 1, 1] }\n";
        let b = parse(text)
            .unwrap()
            .build(&BuildOptions::default())
            .unwrap();
        // a law's missing coefficients are the default law's, in a file as in a model
        let model: SceneModel =
            serde_json::from_str(r#"{"materials": {"default": {"mu": 0.5}}}"#).unwrap();
        assert_eq!(b.model.materials.default, model.materials.default);
        assert_eq!(b.model.materials.default.restitution, 0.2);
        assert_eq!(b.model.step.method, StepChoice::Library);
        // axes normalized; the box a container by default
        let o = &b.model.obstacles;
        assert_eq!(
            (&o[0].shape, &o[0].motion),
            (
                &Shape::CylinderInside {
                    point: Vec3::ZERO,
                    axis: Vec3::Y,
                    radius: 1.0
                },
                &Motion::Rotate {
                    center: Vec3::ZERO,
                    axis: Vec3::Y,
                    omega: 1.5
                }
            )
        );
        assert!(matches!(o[1].shape, Shape::Box { inside: true, .. }));
        assert_eq!(
            (o[1].name.as_str(), &o[1].motion),
            ("obstacle-1", &Motion::Fixed)
        );
        // the model's refusals, at the obstacle's, the law's and the setting's lines
        let refused = |t: &str| {
            parse(t)
                .and_then(|s| s.build(&BuildOptions::default()))
                .unwrap_err()
                .to_string()
        };
        let e = refused(
            "seed = 1\n[[obstacles]]\nshape = { kind = \"box\", lo = [1, 0, 0], hi = [0, 1, 1] }\n",
        );
        let located = |e: &str, lines: [usize; 2]| {
            lines.iter().any(|l| e.starts_with(&format!("t.toml:{l}:")))
        };
        assert!(
            located(&e, [2, 3]) && e.contains("obstacles[0]") && e.contains("below hi"),
            "{e}"
        );
        let e = refused("[[obstacles]]\nshape = { kind = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }\nmotion = { kind = \"oscillate\", direction = [0, 0, 1], amplitude = inf, frequency = 1 }\n");
        assert!(located(&e, [1, 2]) && e.contains("motion"), "{e}");
        let e = refused("[[obstacles]]\nshape = { kind = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }\nmotion = { kind = \"rotate\", center = [0, 0, 0], axis = [0, 0, 0], omega = 1 }\n");
        assert!(
            e.contains("obstacles[0].motion") && e.contains("non-zero"),
            "{e}"
        );
        let e = refused("[[obstacles]]\nshape = { kind = \"plane\", point = [0, 0, 0], normal = [0, 0, 1] }\nmotion = { kind = \"translate\", velocity = [1, 0, 0, 0] }\n");
        assert!(
            e.starts_with("t.toml:3:") && e.contains("invalid length 4"),
            "{e}"
        );
        let e = refused("seed = 1\n[default_pair]\nrolling_friction = -1\n");
        assert!(
            located(&e, [2, 3]) && e.contains("default_pair: rolling_friction = -1"),
            "{e}"
        );
        // [step]: each key to the model's settings or the run's; a repeated key refused
        let s = parse("[step]\nsteps = 7\nh = 0.01\nuntil_rest = false\ngamma = 0.5\n").unwrap();
        assert_eq!(
            (s.file.step.run.steps, s.file.step.settings.h),
            (Some(7), 0.01)
        );
        assert_eq!(s.file.step.settings.gamma, 0.5);
        let e = LoadedScene::parse(
            Path::new("t.json"),
            "{\"step\": {\"h\": 0.01,\n \"h\": 0.02}}".into(),
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("t.json:2:") && e.contains("duplicate field `h`"),
            "{e}"
        );
        let e = refused("[step]\n\ntol = 1.5\n");
        assert!(e.starts_with("t.toml:3:") && e.contains("step.tol"), "{e}");
        let e = refused("[step]\nrelaxation = 2\n");
        assert!(
            e.starts_with("t.toml:2:") && e.contains("step.relaxation"),
            "{e}"
        );
        // a mesh obstacle is written back as it was read: arrays that lost elements found
        let mesh = "[[obstacles]]\nshape = { kind = \"mesh\", vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles = [[0, 1, 2]], side = \"surface\" }\n";
        let e = parse(&format!(
            "{mesh}[[bodies]]\nspheres = [[0.5, 0.5, 0.5, 0.1, 1]]\n"
        ))
        .unwrap_err();
        assert!(e.to_string().contains("5 values where 4"), "{e}");
        let loaded = parse(mesh).unwrap();
        let back: SceneFile = toml::from_str(&toml::to_string(&loaded.file).unwrap()).unwrap();
        assert_eq!(back, loaded.file);
        // the model alone refuses the same settings
        let step = StepSettings {
            tol: 1.5,
            ..StepSettings::default()
        };
        assert!(matches!(step.check(), Err(SceneError::InvalidStep(_))));
    }

    pub fn line_column_counts_characters() {
        let t = "ab\nμx = 1\n";
        assert_eq!(line_column(t, 0), (1, 1));
        assert_eq!(line_column(t, 3), (2, 1));
        assert_eq!(line_column(t, 5), (2, 2));
    }
}
