//! Scenes built in Python (`coulomb.granular.Scene`): the non-array part of a
//! [`SceneModel`] (gravity, materials, obstacles with their motions, batch metadata, step
//! settings) arrives as one JSON string (the model's serde form), the arrays (sphere
//! batches, mesh vertices and triangles) as numpy vectors; they are joined here into the
//! model, which `SceneModel::build` then validates. Also the region fills of
//! `coulomb_granular::generate` for `Scene.fill`.

use crate::convert;
use crate::errors;
use coulomb_granular::generate::{self, FillSpec, Packing, SizeDistribution};
use coulomb_granular::{MeshSide, ObstacleSpec, SceneError, SceneModel, Shape, TriangleMesh, Vec3};
use numpy::{PyArray1, PyReadonlyArray1, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};
use serde::Deserialize;
use serde_json::Value;

/// A scene-description error that is not one of the model's (malformed JSON, a mesh
/// reference out of range, ...).
fn describe_error(py: Python<'_>, field: Option<&str>, msg: String) -> PyErr {
    errors::scene_input_error(py, "description", field, py.None(), msg)
}

/// `n` points from a flat vector of 3n floats.
fn points(flat: &[f64]) -> Vec<Vec3> {
    flat.chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect()
}

/// The vertices and triangles of one mesh.
type MeshArrays = (Vec<Vec3>, Vec<[u64; 3]>);

/// The arrays of one sphere batch, copied out of numpy.
struct BatchArrays {
    positions: Vec<Vec3>,
    radii: Vec<f64>,
    velocities: Vec<Vec3>,
    angular_velocities: Vec<Vec3>,
    masses: Vec<f64>,
}

/// A flat float64 vector whose length is a multiple of 3 (an (n, 3) array raveled).
fn flat3(what: &str, a: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<Vec3>> {
    let s = convert::slice(what, a)?;
    if s.len() % 3 != 0 {
        return Err(PyErr::new::<pyo3::exceptions::PyValueError, _>(format!(
            "{what}: expected shape (n, 3), got {} entries",
            a.len()
        )));
    }
    Ok(points(s))
}

fn batch_arrays(item: &Bound<'_, PyAny>) -> PyResult<BatchArrays> {
    let t = item.cast::<PyTuple>()?;
    let arr = |i: usize| -> PyResult<PyReadonlyArray1<'_, f64>> { t.get_item(i)?.extract() };
    Ok(BatchArrays {
        positions: flat3("positions", &arr(0)?)?,
        radii: convert::slice("radii", &arr(1)?)?.to_vec(),
        velocities: flat3("velocities", &arr(2)?)?,
        angular_velocities: flat3("angular_velocities", &arr(3)?)?,
        masses: convert::slice("masses", &arr(4)?)?.to_vec(),
    })
}

fn mesh_arrays(item: &Bound<'_, PyAny>) -> PyResult<MeshArrays> {
    let t = item.cast::<PyTuple>()?;
    let v: PyReadonlyArray1<'_, f64> = t.get_item(0)?.extract()?;
    let tri: PyReadonlyArray1<'_, u64> = t.get_item(1)?.extract()?;
    let tri = tri.as_slice().map_err(|_| {
        PyErr::new::<pyo3::exceptions::PyValueError, _>("triangles: not contiguous")
    })?;
    if tri.len() % 3 != 0 {
        return Err(PyErr::new::<pyo3::exceptions::PyValueError, _>(format!(
            "triangles: expected shape (m, 3), got {} entries",
            tri.len()
        )));
    }
    let tris = tri.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    Ok((flat3("vertices", &v)?, tris))
}

/// The arrays of a Python scene: one entry per sphere batch and per mesh.
pub(crate) struct SceneArrays {
    batches: Vec<BatchArrays>,
    meshes: Vec<MeshArrays>,
}

impl SceneArrays {
    /// Copies the arrays out of the Python lists `batches` (tuples of float64 vectors:
    /// positions (3n), radii, velocities (3n or 0), angular velocities (3n or 0), masses)
    /// and `meshes` (tuples: vertices (3n float64), triangles (3m uint64)).
    pub(crate) fn extract(
        batches: &Bound<'_, PyList>,
        meshes: &Bound<'_, PyList>,
    ) -> PyResult<Self> {
        Ok(Self {
            batches: batches
                .iter()
                .map(|b| batch_arrays(&b))
                .collect::<PyResult<_>>()?,
            meshes: meshes
                .iter()
                .map(|m| mesh_arrays(&m))
                .collect::<PyResult<_>>()?,
        })
    }
}

/// Why the JSON description and the arrays do not make a model.
pub(crate) enum ModelError {
    /// a malformed description (the message says what and where)
    Description(String),
    /// a malformed obstacle (its index in the model, the message)
    Obstacle(usize, String),
    /// the model refused its data
    Scene(SceneError),
}

impl ModelError {
    pub(crate) fn into_py(self, py: Python<'_>) -> PyErr {
        match self {
            ModelError::Description(m) => describe_error(py, None, m),
            ModelError::Obstacle(k, m) => errors::scene_input_error(
                py,
                "description",
                Some("obstacles"),
                k.into_pyobject(py)
                    .map_or_else(|_| py.None(), |i| i.into_any().unbind()),
                m,
            ),
            ModelError::Scene(e) => errors::scene_error(py, &e),
        }
    }
}

/// The placeholder shape a mesh obstacle's JSON is read with before its mesh is put in.
fn placeholder_shape() -> Value {
    serde_json::json!({"kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]})
}

/// The model of `json` (a [`SceneModel`] whose sphere batches have empty `positions` and
/// `radii`, filled from `arrays.batches` in order, and whose mesh obstacles have the shape
/// `{"kind": "mesh", "mesh": K, "side": ...}` with K the index of their mesh in
/// `arrays.meshes`). Runs without the GIL (the meshes' spatial indices are built here).
pub(crate) fn model_from_parts(json: &str, arrays: SceneArrays) -> Result<SceneModel, ModelError> {
    let desc = |e: serde_json::Error| ModelError::Description(format!("scene description: {e}"));
    let mut root: Value = serde_json::from_str(json).map_err(desc)?;
    let obstacles = match root.as_object_mut() {
        Some(o) => o.remove("obstacles").unwrap_or(Value::Array(Vec::new())),
        None => {
            return Err(ModelError::Description(
                "scene description: not a JSON object".into(),
            ))
        }
    };
    let mut model: SceneModel = serde_json::from_value(root).map_err(desc)?;
    let Value::Array(obstacles) = obstacles else {
        return Err(ModelError::Description(
            "scene description: obstacles is not a list".into(),
        ));
    };
    let mut meshes: Vec<Option<MeshArrays>> = arrays.meshes.into_iter().map(Some).collect();
    for (k, mut ob) in obstacles.into_iter().enumerate() {
        let mesh_ref = ob
            .get("shape")
            .filter(|s| s.get("kind").and_then(Value::as_str) == Some("mesh"))
            .and_then(|s| s.get("mesh"))
            .and_then(Value::as_u64);
        let Some(m) = mesh_ref else {
            let spec: ObstacleSpec = serde_json::from_value(ob)
                .map_err(|e| ModelError::Obstacle(k, format!("obstacle {k}: {e}")))?;
            model.obstacles.push(spec);
            continue;
        };
        let side: MeshSide = match ob["shape"].get("side") {
            Some(s) => serde_json::from_value(s.clone())
                .map_err(|e| ModelError::Obstacle(k, format!("obstacle {k}: side: {e}")))?,
            None => MeshSide::default(),
        };
        ob["shape"] = placeholder_shape();
        let mut spec: ObstacleSpec = serde_json::from_value(ob)
            .map_err(|e| ModelError::Obstacle(k, format!("obstacle {k}: {e}")))?;
        let (vertices, triangles) = meshes
            .get_mut(m as usize)
            .and_then(Option::take)
            .ok_or_else(|| {
                ModelError::Obstacle(k, format!("obstacle {k}: no mesh arrays number {m}"))
            })?;
        let name = if spec.name.is_empty() {
            format!("obstacle-{k}")
        } else {
            spec.name.clone()
        };
        let mesh = TriangleMesh::new(vertices, triangles).map_err(|source| {
            ModelError::Scene(SceneError::Mesh {
                index: k,
                name,
                source,
            })
        })?;
        spec.shape = Shape::Mesh { mesh, side };
        model.obstacles.push(spec);
    }
    if model.sphere_batches.len() != arrays.batches.len() {
        return Err(ModelError::Description(format!(
            "scene description: {} sphere batches for {} sets of arrays",
            model.sphere_batches.len(),
            arrays.batches.len()
        )));
    }
    for (batch, a) in model.sphere_batches.iter_mut().zip(arrays.batches) {
        batch.positions = a.positions;
        batch.radii = a.radii;
        batch.velocities = a.velocities;
        batch.angular_velocities = a.angular_velocities;
        batch.masses = a.masses;
    }
    Ok(model)
}

/// What `Scene.fill` asks for (the fields of [`FillSpec`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FillArgs {
    count: usize,
    sizes: SizeDistribution,
    packing: Packing,
    #[serde(default)]
    velocity: [f64; 3],
    #[serde(default)]
    velocity_jitter: f64,
    #[serde(default)]
    seed: u64,
}

/// Fills the region `region` (JSON of `coulomb_granular::generate::Shape`: a box or a
/// cylinder; or `{"kind": "mesh"}`: the interior of the closed, consistently oriented mesh
/// `mesh` = (vertices (3n float64), triangles (3m uint64))) as `spec` says (JSON: count,
/// sizes, packing, velocity, velocity_jitter, seed), avoiding the spheres (`avoid_positions`
/// (3n), `avoid_radii` (n)) already in the scene; deterministic from the seed (ChaCha8).
/// Returns (positions (n, 3), radii (n,), velocities (n, 3), attempts).
#[pyfunction]
#[pyo3(signature = (region, spec, avoid_positions, avoid_radii, mesh=None))]
pub(crate) fn scene_fill<'py>(
    py: Python<'py>,
    region: &str,
    spec: &str,
    avoid_positions: PyReadonlyArray1<'_, f64>,
    avoid_radii: PyReadonlyArray1<'_, f64>,
    mesh: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let fill_err =
        |field: &str, m: String| errors::scene_input_error(py, "fill", Some(field), py.None(), m);
    let region: Value = serde_json::from_str(region)
        .map_err(|e| fill_err("region", format!("fill region: {e}")))?;
    let is_mesh = region.get("kind").and_then(Value::as_str) == Some("mesh");
    let args: FillArgs =
        serde_json::from_str(spec).map_err(|e| fill_err("fill", format!("fill: {e}")))?;
    // the memory of what the fill would build, from its count, before anything is generated
    coulomb_granular::model::check_memory(
        args.count.saturating_add(avoid_radii.len()),
        0,
        coulomb_granular::model::available_memory(),
    )
    .map_err(|e| fill_err("count", format!("fill: {e}")))?;
    let pos = flat3("avoid_positions", &avoid_positions)?;
    let rad = convert::slice("avoid_radii", &avoid_radii)?;
    let avoid: Vec<(Vec3, f64)> = pos.into_iter().zip(rad.iter().copied()).collect();
    let spec = FillSpec {
        count: args.count,
        sizes: args.sizes,
        packing: args.packing,
        velocity: Vec3::new(args.velocity[0], args.velocity[1], args.velocity[2]),
        velocity_jitter: args.velocity_jitter,
        seed: args.seed,
    };
    let filled = if is_mesh {
        let (vertices, triangles) = match mesh {
            Some(m) => mesh_arrays(m)?,
            None => {
                return Err(fill_err(
                    "region",
                    "fill: a mesh region needs its arrays".into(),
                ))
            }
        };
        let mesh = TriangleMesh::new(vertices, triangles)
            .and_then(|m| m.check_closed().map(|()| m))
            .map_err(|e| fill_err("region", format!("fill region mesh: {e}")))?;
        let (lo, hi) = mesh.bounds();
        py.detach(|| {
            let inside = |x: Vec3| mesh.contains(x) == Some(true);
            let clear = |c: Vec3, r: f64| {
                let mut hit = false;
                mesh.near_each(c, r, 0.0, |_, _, _| hit = true);
                !hit
            };
            let region = generate::Predicate {
                lo,
                hi,
                inside: &inside,
                clear: Some(&clear),
            };
            generate::fill(&region, &spec, &avoid)
        })
    } else {
        let region: generate::Shape = serde_json::from_value(region)
            .map_err(|e| fill_err("region", format!("fill region: {e}")))?;
        region
            .validate()
            .map_err(|e| fill_err("region", format!("fill: {e}")))?;
        py.detach(|| generate::fill(&region, &spec, &avoid))
    }
    .map_err(|e| fill_err("fill", format!("fill: {e}")))?;
    let p = &filled.particles;
    let positions = convert::rows3(py, p.iter().map(|s| s.position.to_array()));
    let radii = PyArray1::from_iter(py, p.iter().map(|s| s.radius)).into_any();
    let velocities = convert::rows3(py, p.iter().map(|s| s.velocity.to_array()));
    PyTuple::new(
        py,
        [
            positions,
            radii,
            velocities,
            filled.attempts.into_pyobject(py)?.into_any(),
        ],
    )
}

/// Writes the scene (`json`, `batches`, `meshes` as for `_Simulation.from_scene`; `inlets`
/// the JSON list of `{inlet, material}` of `Scene._inlets`) as the scene file `path` (`.toml` or
/// `.json`, `coulomb_granular::scene_save`), with the step settings the same `params` give
/// `Simulation(scene, **params)` (a scene with shaped bodies: the rigid defaults h = 1e-3 s,
/// tol = 1e-8) and `steps` steps (default: the scene files' 200). Written atomically; a path
/// that exists and is not a regular file is refused.
#[pyfunction]
#[pyo3(signature = (json, batches, meshes, inlets, params, path, steps=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn scene_save(
    py: Python<'_>,
    json: &str,
    batches: &Bound<'_, PyList>,
    meshes: &Bound<'_, PyList>,
    inlets: &str,
    params: &Bound<'_, pyo3::types::PyDict>,
    path: std::path::PathBuf,
    steps: Option<usize>,
) -> PyResult<()> {
    use coulomb_granular::scene_save::{self, SaveError};
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Entry {
        inlet: generate::Inlet,
        material: String,
    }
    let arrays = SceneArrays::extract(batches, meshes)?;
    let json = json.to_string();
    let mut model = py
        .detach(move || model_from_parts(&json, arrays))
        .map_err(|e| e.into_py(py))?;
    let entries: Vec<Entry> = serde_json::from_str(inlets)
        .map_err(|e| describe_error(py, Some("inlets"), format!("inlets: {e}")))?;
    // the scene runs in the rigid-body simulator (`BuiltScene::runs_rigid` of the file)
    let rigid = model.has_shapes() || entries.iter().any(|e| e.inlet.poured_shape().is_some());
    if rigid {
        model.step.h = crate::rigid::RIGID_H;
        model.step.tol = crate::rigid::RIGID_TOL;
    }
    crate::granular::apply_to_model(&mut model, params)?;
    if rigid
        && model
            .step
            .projection_velocities
            .is_some_and(|v| v != coulomb_granular::projection::Velocities::PositionsOnly)
    {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "projection_velocities: a scene with bodies of other shapes than spheres moves positions only (\"positions_only\")",
        ));
    }
    let inlets: Vec<_> = entries.into_iter().map(|e| (e.inlet, e.material)).collect();
    let mut file = scene_save::scene_file_of(&model, &inlets)
        .map_err(|e| describe_error(py, Some("scene"), e.to_string()))?;
    file.step.run.steps = steps;
    py.detach(|| scene_save::save(&path, &file))
        .map_err(|e| match e {
            SaveError::Io { path, source } => errors::output_error(source, &path),
            SaveError::Extension(_) => {
                errors::scene_input_error(py, "save", Some("path"), py.None(), e.to_string())
            }
            other => describe_error(py, Some("scene"), other.to_string()),
        })
}

/// A URDF import error as Python's: the file cannot be read → `OSError` (or
/// `coulomb.InputError`, as for every input file); otherwise `coulomb.SceneError` with the
/// message (it names the URDF file and the element) and `kind` the variant (`xml`, `link`,
/// `joint`, `unknown_link`, `unsupported_joint`, `unsupported_geometry`, `package_uri`,
/// `tree`, `options`).
pub(crate) fn urdf_error(py: Python<'_>, e: &coulomb_granular::urdf::UrdfError) -> PyErr {
    use coulomb_granular::urdf::UrdfError as E;
    match e {
        E::Input(i) => errors::input_file_error(py, i),
        _ => {
            let kind = errors::variant_name(e);
            errors::scene_input_error(py, &kind, Some("path"), py.None(), e.to_string())
        }
    }
}

/// Reads the URDF file `path` placed as `placement` says (JSON of
/// `coulomb_granular::urdf::UrdfPlacement`: position, orientation, fixed_base, material) for
/// `Scene.add_urdf`: returns the JSON `{"links": [names], "bodies": [BodySpec], "joints":
/// [JointDesc]}`, the joints' bodies numbered from 0 over the robot's links (the file's
/// order). The same import as a scene file's `[[urdf]]`.
#[pyfunction]
pub(crate) fn urdf_robot(
    py: Python<'_>,
    path: std::path::PathBuf,
    placement: &str,
) -> PyResult<String> {
    let placement: coulomb_granular::urdf::UrdfPlacement = serde_json::from_str(placement)
        .map_err(|e| describe_error(py, Some("placement"), format!("add_urdf: {e}")))?;
    let robot = py
        .detach(|| coulomb_granular::urdf::read(&path, &placement))
        .map_err(|e| urdf_error(py, &e))?;
    let out = serde_json::json!({
        "links": robot.links,
        "bodies": robot.bodies,
        "joints": robot.joints,
    });
    serde_json::to_string(&out)
        .map_err(|e| describe_error(py, Some("path"), format!("add_urdf: {e}")))
}
