//! `coulomb_granular::Simulation` for Python: build a scene, step it (GIL released), read and
//! steer the state (positions, velocities, parameters) between steps.

use crate::convert;
use crate::scene::{model_from_parts, SceneArrays};
use crate::PyProblem;
use coulomb::problem::Problem;
use coulomb_granular::nsgs::NsgsSettings;
use coulomb_granular::scene::BoxLayout;
use coulomb_granular::scene_file::{BuildOptions, InletRun, LoadedScene, SceneFileError};
use coulomb_granular::{
    BuildChecks, Params, Scene, SceneModel, Simulation, SimulationError, StepChoice, StepMethod,
    Vec3, Velocities, World,
};
use numpy::{PyReadonlyArray1, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::Arc;

fn sim_error(e: SimulationError) -> PyErr {
    match e {
        SimulationError::Parameter(m) => PyValueError::new_err(m),
        other => PyRuntimeError::new_err(other.to_string()),
    }
}

/// The step method named `v` (`"nsgs"` or `"library"`).
fn step_choice(v: &Bound<'_, PyAny>) -> PyResult<StepChoice> {
    let name: String = v
        .extract()
        .map_err(|_| PyTypeError::new_err("method must be a string: 'nsgs' or 'library'"))?;
    match name.as_str() {
        "nsgs" => Ok(StepChoice::Nsgs),
        "library" => Ok(StepChoice::Library),
        other => Err(PyValueError::new_err(format!(
            "method: unknown step method {other:?} (methods: nsgs, library)"
        ))),
    }
}

/// The `projection_velocities` parameter: "rescale", "positions_only" or "inelastic"
/// (`coulomb_granular::Velocities`, the `[step]` key of scene files).
pub(crate) fn projection_velocities(v: &Bound<'_, PyAny>) -> PyResult<Velocities> {
    let s: String = v.extract().map_err(|_| {
        PyTypeError::new_err(
            "projection_velocities must be a str: rescale, positions_only or inelastic",
        )
    })?;
    match s.as_str() {
        "rescale" => Ok(Velocities::Rescale),
        "positions_only" => Ok(Velocities::PositionsOnly),
        "inelastic" => Ok(Velocities::Inelastic),
        other => Err(PyValueError::new_err(format!(
            "projection_velocities '{other}': expected rescale, positions_only or inelastic"
        ))),
    }
}

fn velocities_name(v: Velocities) -> &'static str {
    match v {
        Velocities::Rescale => "rescale",
        Velocities::PositionsOnly => "positions_only",
        Velocities::Inelastic => "inelastic",
    }
}

fn real(name: &str, v: &Bound<'_, PyAny>) -> PyResult<f64> {
    v.extract()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a float")))
}

fn count(name: &str, v: &Bound<'_, PyAny>) -> PyResult<usize> {
    v.extract()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a nonnegative int")))
}

const PARAM_NAMES: &str = "h, theta, tol, method, max_sweeps, relaxation, restitution, mu, \
rolling_friction, warm_start, gap_closure, projection_velocities; solver settings go in solver=";

/// The keyword parameters in the order they are applied: `method` first (so that `tol`,
/// `max_sweeps` and `relaxation` apply to the method chosen in the same call).
fn ordered<'py>(kw: &Bound<'py, PyDict>) -> PyResult<Vec<(String, Bound<'py, PyAny>)>> {
    let mut v: Vec<(String, Bound<'py, PyAny>)> = kw
        .iter()
        .map(|(k, v)| Ok((k.extract::<String>()?, v)))
        .collect::<PyResult<_>>()?;
    v.sort_by_key(|(k, _)| k != "method");
    Ok(v)
}

/// Applies the constructor's keyword parameters to the scene model: the step settings (h,
/// theta, tol, method, max_sweeps, relaxation, warm_start, gap_closure,
/// projection_velocities) and the default contact law (mu, restitution, rolling_friction:
/// the law of every pair of materials not set by a pair).
pub(crate) fn apply_to_model(model: &mut SceneModel, kw: &Bound<'_, PyDict>) -> PyResult<()> {
    let flag = |name: &str, v: &Bound<'_, PyAny>| {
        v.extract::<bool>()
            .map_err(|_| PyTypeError::new_err(format!("{name} must be a bool")))
    };
    for (name, v) in ordered(kw)? {
        let (step, law) = (&mut model.step, &mut model.materials.default);
        match name.as_str() {
            "h" => step.h = real(&name, &v)?,
            "theta" => step.theta = real(&name, &v)?,
            "tol" => {
                step.tol = real(&name, &v)?;
                coulomb::settings::check_tol(step.tol).map_err(PyValueError::new_err)?;
            }
            "method" => step.method = step_choice(&v)?,
            "max_sweeps" => step.max_sweeps = count(&name, &v)?,
            "relaxation" => step.relaxation = real(&name, &v)?,
            "mu" => law.mu = real(&name, &v)?,
            "restitution" => law.restitution = real(&name, &v)?,
            "rolling_friction" => law.rolling_friction = real(&name, &v)?,
            "warm_start" => step.warm_start = flag(&name, &v)?,
            "gap_closure" => step.gap_closure = flag(&name, &v)?,
            "projection_velocities" => {
                step.projection_velocities = Some(projection_velocities(&v)?)
            }
            other => {
                return Err(PyTypeError::new_err(format!(
                    "unexpected simulation parameter '{other}' (parameters: {PARAM_NAMES})"
                )))
            }
        }
    }
    Ok(())
}

/// Applies `name = value` to the time-stepping parameters (the names of
/// `coulomb_granular::Params`, and `tol`, `method`, `max_sweeps`, `relaxation` of the step
/// settings: `tol` is the tolerance of both the library solver and the Gauss–Seidel steps).
fn set_param(p: &mut Params, name: &str, v: &Bound<'_, PyAny>) -> PyResult<()> {
    match name {
        "h" => p.h = real(name, v)?,
        "theta" => p.theta = real(name, v)?,
        "restitution" => p.restitution = real(name, v)?,
        "mu" => p.mu = real(name, v)?,
        "rolling_friction" => p.rolling_friction = real(name, v)?,
        "warm_start" => {
            p.warm_start = v
                .extract()
                .map_err(|_| PyTypeError::new_err("warm_start must be a bool"))?
        }
        "projection_velocities" => {
            let v = projection_velocities(v)?;
            match &mut p.projection {
                Some(pr) => pr.velocities = v,
                None => {
                    return Err(PyValueError::new_err(
                        "projection_velocities: there is no position correction (projection = false) to apply it to",
                    ))
                }
            }
        }
        "gap_closure" => {
            p.activation.close_gaps = v
                .extract()
                .map_err(|_| PyTypeError::new_err("gap_closure must be a bool"))?
        }
        "tol" => {
            let t = real(name, v)?;
            coulomb::settings::check_tol(t).map_err(PyValueError::new_err)?;
            p.solver.tol = t;
            if let StepMethod::Nsgs(s) = &mut p.method {
                s.tol = t;
            }
        }
        "method" => {
            p.method = match step_choice(v)? {
                StepChoice::Library => StepMethod::Library,
                StepChoice::Nsgs => match &p.method {
                    StepMethod::Nsgs(s) => StepMethod::Nsgs(*s),
                    _ => StepMethod::Nsgs(NsgsSettings {
                        tol: p.solver.tol,
                        ..NsgsSettings::default()
                    }),
                },
            }
        }
        "max_sweeps" | "relaxation" => {
            let StepMethod::Nsgs(s) = &mut p.method else {
                return Err(PyValueError::new_err(format!(
                    "{name} is a setting of method='nsgs'"
                )));
            };
            if name == "max_sweeps" {
                let n = count(name, v)?;
                if n == 0 {
                    return Err(PyValueError::new_err("max_sweeps must be at least 1"));
                }
                s.max_sweeps = n;
            } else {
                let w = real(name, v)?;
                if !(w.is_finite() && (1.0..2.0).contains(&w)) {
                    return Err(PyValueError::new_err(format!(
                        "relaxation = {w} is not in [1, 2)"
                    )));
                }
                s.relaxation = w;
            }
        }
        other => {
            return Err(PyTypeError::new_err(format!(
                "unexpected simulation parameter '{other}' (parameters: {PARAM_NAMES})"
            )))
        }
    }
    Ok(())
}

/// Validates parameters the way `Simulation::new` does (on an empty world).
fn validate(p: &Params) -> PyResult<()> {
    Simulation::new(World::new(), p.clone())
        .map(|_| ())
        .map_err(sim_error)
}

/// A `(n, 3)` float64 array (flattened by the Python layer) as points.
pub(crate) fn points(what: &str, n: usize, a: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<Vec3>> {
    let s = convert::slice(what, a)?;
    if a.len() != 3 * n {
        return Err(PyValueError::new_err(format!(
            "{what}: expected shape ({n}, 3), got {} entries",
            a.len()
        )));
    }
    if let Some(k) = s.iter().position(|x| !x.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "{what}: non-finite entry at ({}, {})",
            k / 3,
            k % 3
        )));
    }
    Ok(s.chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect())
}

/// A step's record (`coulomb_granular::StepRecord`: the keys of every scene, the columns of
/// `stats.csv`) as a dict.
fn stats_to_py<'py>(
    py: Python<'py>,
    stats: &coulomb_granular::StepStats,
) -> PyResult<Bound<'py, PyAny>> {
    record_to_py(py, &coulomb_granular::StepRecord::of_spheres(stats))
}

/// A [`coulomb_granular::StepRecord`] as a dict.
pub(crate) fn record_to_py<'py>(
    py: Python<'py>,
    record: &coulomb_granular::StepRecord,
) -> PyResult<Bound<'py, PyAny>> {
    let json = serde_json::to_value(record)
        .map_err(|e| PyRuntimeError::new_err(format!("cannot serialize the step record: {e}")))?;
    convert::json_to_py(py, &json)
}

/// A granular simulation (Moreau–Jean time stepping (2.5)–(2.7), one problem (2.10) per step).
#[pyclass(name = "_Simulation", module = "coulomb._coulomb")]
pub struct PySimulation {
    sim: Simulation,
    /// the folder of `write_frames` and its writer (the collections continue while the
    /// same folder is given)
    frames: Option<(PathBuf, coulomb_granular::output::VtkWriter)>,
    /// the scene's inlets, pouring after each step
    feed: Feed,
}

/// The inlets of a sphere scene (`InletRun::emit`, the emission rule of `coulomb simulate`)
/// with the scene's materials (the inserted spheres' material indices).
#[derive(Clone, Default)]
struct Feed {
    model: SceneModel,
    inlets: Vec<InletRun>,
}

/// The build checks of a scene whose overlaps `resolve_overlaps=` relaxes: those
/// [`relaxed`] makes after the relaxation are skipped.
const UNCHECKED: BuildChecks = BuildChecks {
    overlaps: false,
    containment: false,
    memory: true,
};

/// `built` with its overlaps relaxed in at most `sweeps` sweeps and the skipped checks made
/// (`coulomb_granular::model::relax`, as `coulomb simulate --resolve-overlaps`).
fn relaxed(
    built: Result<(World, Params), coulomb_granular::SceneError>,
    sweeps: usize,
) -> Result<(World, Params), coulomb_granular::SceneError> {
    let (mut world, params) = built?;
    coulomb_granular::model::relax(&mut world, sweeps)?;
    Ok((world, params))
}

#[pymethods]
impl PySimulation {
    /// A built-in scene (`box`, `funnel`, `vibrating-plate`, `rotating-drum`) of `beads`
    /// spheres, deterministic from `seed`; the step settings of `coulomb simulate` (body-level
    /// Gauss–Seidel to tol = 1e-4) unless `params` say otherwise.
    #[new]
    #[pyo3(signature = (scene, beads, seed, params, solver))]
    fn new(
        py: Python<'_>,
        scene: &str,
        beads: usize,
        seed: u64,
        params: &Bound<'_, PyDict>,
        solver: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let scene = Scene::from_name(scene).ok_or_else(|| {
            let names: Vec<_> = Scene::ALL.iter().map(|s| s.name()).collect();
            PyValueError::new_err(format!(
                "unknown scene {scene:?} (scenes: {})",
                names.join(", ")
            ))
        })?;
        // the memory of the scene from `beads`, before anything is built
        coulomb_granular::model::check_memory(
            beads,
            0,
            coulomb_granular::model::available_memory(),
        )
        .map_err(|e| crate::errors::scene_error(py, &e))?;
        let mut model = py.detach(move || scene.model(beads, seed, &BoxLayout::for_beads(beads)));
        apply_to_model(&mut model, params)?;
        // the built-in arrangements are loose by construction: the data are validated, the
        // start checks (overlaps, containment) are those of `Scene::build` (none)
        let checks = BuildChecks {
            overlaps: false,
            containment: false,
            memory: true,
        };
        let built = py.detach(move || model.build_with(&checks));
        Self::finish(py, built, solver)
    }

    /// A scene built in Python: `json` is the [`SceneModel`] without its arrays, `batches`
    /// and `meshes` the arrays (see `scene.rs`); `params` as for the constructor. Built and
    /// validated with every check of `SceneModel::build`, without the GIL.
    #[staticmethod]
    #[pyo3(signature = (json, batches, meshes, params, solver, inlets, resolve_overlaps=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_scene(
        py: Python<'_>,
        json: &str,
        batches: &Bound<'_, PyList>,
        meshes: &Bound<'_, PyList>,
        params: &Bound<'_, PyDict>,
        solver: Option<&Bound<'_, PyDict>>,
        inlets: &str,
        resolve_overlaps: Option<usize>,
    ) -> PyResult<Self> {
        // the inlets checked before the build
        let (materials, inlets) = inlet_runs(py, json, inlets)?;
        let arrays = SceneArrays::extract(batches, meshes)?;
        let json = json.to_string();
        let mut model = py
            .detach(move || model_from_parts(&json, arrays))
            .map_err(|e| e.into_py(py))?;
        apply_to_model(&mut model, params)?;
        let built = py.detach(move || match resolve_overlaps {
            None => model.build(),
            Some(sweeps) => relaxed(model.build_with(&UNCHECKED), sweeps),
        });
        let mut sim = Self::finish(py, built, solver)?;
        sim.feed = Feed {
            model: materials,
            inlets,
        };
        Ok(sim)
    }

    /// The scene of the file `path` (`.toml` or `.json`, `coulomb_granular::scene_file`;
    /// `seed` replaces the file's), `params` applied on top of its step settings; with the
    /// file's inlets pouring after each step: a `_RigidSimulation` when the scene runs in
    /// the rigid-body simulator (`BuiltScene::runs_rigid`), else a `_Simulation`.
    #[staticmethod]
    #[pyo3(signature = (path, seed, params, solver, resolve_overlaps=None))]
    fn from_file(
        py: Python<'_>,
        path: PathBuf,
        seed: Option<u64>,
        params: &Bound<'_, PyDict>,
        solver: Option<&Bound<'_, PyDict>>,
        resolve_overlaps: Option<usize>,
    ) -> PyResult<Py<PyAny>> {
        let file_err = |e: SceneFileError| crate::errors::scene_file_error(py, &e);
        let loaded = py.detach(|| LoadedScene::load(&path)).map_err(file_err)?;
        let opts = BuildOptions {
            seed,
            max_fill: None,
        };
        let mut built = py.detach(|| loaded.build(&opts)).map_err(file_err)?;
        if built.runs_rigid() {
            if solver.is_some_and(|d| !d.is_empty()) {
                return Err(PyValueError::new_err(format!(
                    "{}: solver= sets the sphere engine's library solver; this scene has bodies of other shapes (or pours them), whose steps use the library at its default settings",
                    path.display()
                )));
            }
            let sim = crate::rigid::from_built(py, built, params, resolve_overlaps)?;
            return Ok(Py::new(py, sim)?.into_any());
        }
        let feed = Feed {
            model: SceneModel {
                materials: built.model.materials.clone(),
                ..SceneModel::default()
            },
            inlets: built.inlets.clone(),
        };
        apply_to_model(&mut built.model, params)?;
        let world_params = match resolve_overlaps {
            None => py
                .detach(move || built.build(&BuildChecks::default()))
                .map_err(file_err)?,
            Some(sweeps) => {
                let unchecked = py.detach(|| built.build(&UNCHECKED)).map_err(file_err)?;
                let relaxed = py.detach(move || relaxed(Ok(unchecked), sweeps));
                relaxed.map_err(|e| crate::errors::scene_error(py, &e))?
            }
        };
        let mut sim = Self::finish(py, Ok(world_params), solver)?;
        sim.feed = feed;
        Ok(Py::new(py, sim)?.into_any())
    }

    /// One time step; its record (`coulomb_granular::StepRecord`, the same keys for every
    /// scene) as a dict.
    fn step<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let stats = self.advance(py)?;
        stats_to_py(py, &stats)
    }

    /// `n` time steps at once (GIL released for all of them); their records as a list.
    fn run<'py>(&mut self, py: Python<'py>, n: usize) -> PyResult<Bound<'py, PyList>> {
        // one step at a time without the GIL, the signals checked between steps: Ctrl-C
        // raises KeyboardInterrupt after the step in progress (the steps taken stay taken)
        let mut stats = Vec::with_capacity(n.min(1 << 20));
        for _ in 0..n {
            stats.push(self.advance(py)?);
            py.check_signals()?;
        }
        let list = PyList::empty(py);
        for s in &stats {
            list.append(stats_to_py(py, s)?)?;
        }
        Ok(list)
    }

    /// Sphere centres x at t_k, shape (n, 3).
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let b = &self.sim.world.bodies;
        convert::rows3(
            py,
            b.iter().map(|s| [s.position.x, s.position.y, s.position.z]),
        )
    }

    /// Sphere velocities ẋ at t_k, shape (n, 3).
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let b = &self.sim.world.bodies;
        convert::rows3(
            py,
            b.iter().map(|s| [s.velocity.x, s.velocity.y, s.velocity.z]),
        )
    }

    /// Sphere angular velocities ω at t_k, shape (n, 3).
    #[getter]
    fn angular_velocities<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let b = &self.sim.world.bodies;
        convert::rows3(
            py,
            b.iter().map(|s| {
                [
                    s.angular_velocity.x,
                    s.angular_velocity.y,
                    s.angular_velocity.z,
                ]
            }),
        )
    }

    /// Radii, shape (n,).
    #[getter]
    fn radii<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        numpy::PyArray1::from_iter(py, self.sim.world.bodies.iter().map(|s| s.radius)).into_any()
    }

    /// Masses, shape (n,).
    #[getter]
    fn masses<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        numpy::PyArray1::from_iter(py, self.sim.world.bodies.iter().map(|s| s.mass)).into_any()
    }

    /// The last step's contacts ([`convert::contacts_to_py`]: a sphere world's obstacles are
    /// the scene's, then its fixed spheres).
    #[getter]
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        convert::contacts_to_py(py, &self.sim.contacts, |k| k)
    }

    /// Replaces the sphere velocities (flattened (n, 3), finite).
    fn set_velocities(&mut self, v: PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        let n = self.sim.world.bodies.len();
        let v = points("velocities", n, &v)?;
        for (b, x) in self.sim.world.bodies.iter_mut().zip(v) {
            b.velocity = x;
        }
        Ok(())
    }

    /// Replaces the sphere positions (flattened (n, 3), finite).
    fn set_positions(&mut self, x: PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        let n = self.sim.world.bodies.len();
        let x = points("positions", n, &x)?;
        for (b, p) in self.sim.world.bodies.iter_mut().zip(x) {
            b.position = p;
        }
        Ok(())
    }

    /// Sets time-stepping parameters for the following steps (validated as at construction).
    #[pyo3(signature = (**params))]
    fn set_params(&mut self, params: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let mut p = self.sim.params.clone();
        if let Some(kw) = params {
            for (k, v) in ordered(kw)? {
                if self.sim.world.materials.is_some()
                    && matches!(k.as_str(), "mu" | "restitution" | "rolling_friction")
                {
                    return Err(PyValueError::new_err(format!(
                        "{k}: this scene has per-pair contact laws (a material table); \
                         set them with Scene.set_material_pair before building"
                    )));
                }
                set_param(&mut p, &k, &v)?;
            }
        }
        validate(&p)?;
        self.sim.params = p;
        Ok(())
    }

    /// Replaces the solver settings for the following steps (keyword arguments of `solve`).
    #[pyo3(signature = (**settings))]
    fn set_solver(&mut self, py: Python<'_>, settings: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        self.sim.params.solver = convert::settings_from_kwargs(py, "set_solver", settings)?;
        Ok(())
    }

    /// The time-stepping parameters and solver settings as a dict.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = &self.sim.params;
        let d = PyDict::new(py);
        d.set_item("h", p.h)?;
        d.set_item("theta", p.theta)?;
        d.set_item("restitution", p.restitution)?;
        d.set_item("mu", p.mu)?;
        d.set_item("rolling_friction", p.rolling_friction)?;
        d.set_item("warm_start", p.warm_start)?;
        d.set_item("gap_closure", p.activation.close_gaps)?;
        d.set_item(
            "projection_velocities",
            p.projection.map(|pr| velocities_name(pr.velocities)),
        )?;
        match &p.method {
            StepMethod::Nsgs(s) => {
                d.set_item("method", "nsgs")?;
                d.set_item("tol", s.tol)?;
                d.set_item("max_sweeps", s.max_sweeps)?;
                d.set_item("relaxation", s.relaxation)?;
            }
            _ => {
                d.set_item("method", "library")?;
                d.set_item("tol", p.solver.tol)?;
            }
        }
        d.set_item("solver", convert::settings_to_dict(py, &p.solver)?)?;
        Ok(d)
    }

    /// t_k.
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time
    }

    /// k, the number of steps taken.
    #[getter]
    fn steps_done(&self) -> usize {
        self.sim.steps_done
    }

    /// Keep each step's problem (2.10) for `last_problem`.
    #[getter]
    fn keep_problem(&self) -> bool {
        self.sim.keep_problem
    }

    #[setter]
    fn set_keep_problem(&mut self, keep: bool) {
        self.sim.keep_problem = keep;
    }

    /// The last step's global problem (when `keep_problem` is set and the step had contacts).
    #[getter]
    fn last_problem(&self) -> Option<PyProblem> {
        self.sim.last_problem.as_ref().map(|g| PyProblem {
            inner: Arc::new(Problem::Global(g.clone())),
        })
    }

    /// Writes the full state (bodies, obstacles, parameters and solver settings, t, k, warm
    /// starts) into the HDF5 checkpoint file `path`, atomically
    /// (`coulomb_granular::checkpoint`).
    fn save_checkpoint(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let sim = &self.sim;
        py.detach(|| sim.save_checkpoint(&path))
            .map_err(|e| crate::errors::checkpoint_error(py, e))
    }

    /// Writes the current state as a ParaView frame into the folder `dir` with the writer of
    /// `coulomb simulate --output` (`frames/bodies_KKKKKK.vtp`, contacts, obstacles and the
    /// `.pvd` collections; links and special files there refused, nothing written through a
    /// link: `coulomb_granular::output_dir`). Called again with the same folder, the frame is
    /// added to its collections; with another folder, new collections start there.
    fn write_frames(&mut self, py: Python<'_>, dir: PathBuf) -> PyResult<()> {
        let (sim, frames) = (&self.sim, &mut self.frames);
        let target = dir.clone();
        py.detach(move || {
            if frames.as_ref().is_none_or(|(d, _)| *d != dir) {
                let w = coulomb_granular::output::VtkWriter::new(&dir)?;
                *frames = Some((dir.clone(), w));
            }
            let (_, w) = frames.as_mut().expect("set above");
            w.frame(sim)
        })
        .map_err(|e| crate::errors::output_error(e, &target))
    }

    /// Makes the inlets of `scene` (the scene the stored run was built from) pour into this
    /// loaded run after each step, as `coulomb simulate FILE --restart`; False, nothing
    /// changed, when `scene` has other gravity or obstacles.
    fn pour_from(&mut self, scene: &PySimulation) -> bool {
        let (a, b) = (&self.sim.world, &scene.sim.world);
        if a.gravity != b.gravity || a.obstacles != b.obstacles {
            return false;
        }
        self.feed = scene.feed.clone();
        true
    }

    /// The simulation stored in the checkpoint file `path`; stepping it gives the same bits as
    /// stepping the saved one.
    #[staticmethod]
    fn load_checkpoint(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        py.detach(|| Simulation::load_checkpoint(&path))
            .map(|sim| Self {
                sim,
                frames: None,
                feed: Feed::default(),
            })
            .map_err(|e| crate::errors::checkpoint_error(py, e))
    }
}

impl PySimulation {
    /// One step t_k → t_{k+1}, then the inlets insert the spheres due in (t_k, t_{k+1}]
    /// (`InletRun::emit`, placed among the spheres present, as `coulomb simulate` does after
    /// each step); the step's statistics. Without the GIL.
    fn advance(&mut self, py: Python<'_>) -> PyResult<coulomb_granular::StepStats> {
        let (sim, feed) = (&mut self.sim, &mut self.feed);
        py.detach(move || {
            let t0 = sim.time;
            let stats = sim.step()?;
            let t1 = sim.time;
            for inlet in feed.inlets.iter_mut() {
                inlet.emit(sim, &feed.model, t0, t1)?;
            }
            Ok(stats)
        })
        .map_err(sim_error)
    }

    /// The simulation of a built scene, `solver` (keyword settings of `coulomb.solve`)
    /// replacing the library solver's settings when given.
    fn finish(
        py: Python<'_>,
        built: Result<(World, Params), coulomb_granular::SceneError>,
        solver: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let (world, mut p) = built.map_err(|e| crate::errors::scene_error(py, &e))?;
        // the g·h² rule of `coulomb simulate` (issue 55: Python skipped it): a sphere must not
        // fall more than the smallest radius in one step
        let r_min = world
            .bodies
            .iter()
            .map(|b| b.radius)
            .fold(f64::INFINITY, f64::min);
        let g = world.gravity.norm();
        let fall = g * p.h * p.h;
        if r_min.is_finite() && fall > r_min {
            return Err(PyValueError::new_err(format!(
                "h = {} is too large: a sphere falls g·h² = {fall:.3e} m in one step, more than the smallest radius {r_min} m; use h <= {:.3e}",
                p.h,
                (r_min / g).sqrt()
            )));
        }
        if let Some(kw) = solver.filter(|d| !d.is_empty()) {
            p.solver = convert::settings_from_kwargs(py, "Simulation", Some(kw))?;
        }
        let sim = py
            .detach(move || Simulation::new(world, p))
            .map_err(sim_error)?;
        Ok(Self {
            sim,
            frames: None,
            feed: Feed::default(),
        })
    }
}

/// The inlets `inlets` (JSON list of `{inlet, material}`: `inlet` the serde form of
/// `Inlet`, its `shape` optional) validated, with a model holding the materials of the scene
/// description `json` (an inlet's material must be one of them).
pub(crate) fn inlet_runs(
    py: Python<'_>,
    json: &str,
    inlets: &str,
) -> PyResult<(SceneModel, Vec<InletRun>)> {
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Entry {
        inlet: coulomb_granular::generate::Inlet,
        material: String,
    }
    let bad = |field: &str, index: Option<usize>, m: String| {
        let index = index.map_or_else(
            || py.None(),
            |i| {
                i.into_pyobject(py)
                    .map_or_else(|_| py.None(), |x| x.into_any().unbind())
            },
        );
        crate::errors::scene_input_error(py, "inlet", Some(field), index, m)
    };
    let desc: serde_json::Value = serde_json::from_str(json)
        .map_err(|e| bad("inlets", None, format!("scene description: {e}")))?;
    let materials: coulomb_granular::Materials = desc
        .get("materials")
        .map(|m| serde_json::from_value(m.clone()))
        .transpose()
        .map_err(|e| bad("inlets", None, format!("materials: {e}")))?
        .unwrap_or_default();
    let model = SceneModel {
        materials,
        ..SceneModel::default()
    };
    let entries: Vec<Entry> =
        serde_json::from_str(inlets).map_err(|e| bad("inlets", None, format!("inlets: {e}")))?;
    let mut out = Vec::with_capacity(entries.len());
    for (k, e) in entries.into_iter().enumerate() {
        e.inlet
            .validate()
            .map_err(|err| bad("inlets", Some(k), format!("inlet {k}: {err}")))?;
        // the material must exist (the error of the model, naming the inlet)
        let probe = coulomb_granular::SphereBatch {
            material: e.material.clone(),
            density: Some(e.inlet.density),
            ..Default::default()
        };
        model
            .spheres_of(&probe)
            .map_err(|err| bad("material", Some(k), format!("inlet {k}: {err}")))?;
        out.push(InletRun {
            density: e.inlet.density,
            material: e.material,
            inlet: e.inlet,
            capped: 0,
        });
    }
    Ok((model, out))
}
