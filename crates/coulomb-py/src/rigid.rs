//! `coulomb_granular::rigid_scene::RigidScene` for Python: a scene with bodies of any shape
//! (cuboids, capsules, cylinders, cones, convex hulls and polyhedra, compounds; spheres as
//! balls), stepped by the rigid-body simulator with the GIL released.

use crate::convert;
use crate::scene::{model_from_parts, SceneArrays};
use crate::PyProblem;
use coulomb::problem::Problem;
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::{BuiltScene, InletRun};
use coulomb_granular::{BodySpec, CheckpointError, SceneModel, StepRecord};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::Arc;

/// A simulation of rigid bodies of any shape (Newton–Euler Moreau–Jean, one problem (2.10)
/// per step from parry3d's contact manifolds).
#[pyclass(name = "_RigidSimulation", module = "coulomb._coulomb")]
pub struct PyRigidSimulation {
    scene: RigidScene,
    /// the folder of `write_frames` and its writer
    frames: Option<(PathBuf, coulomb_granular::output::VtkWriter)>,
    /// the scene's inlets, pouring after each step
    pour: Vec<InletRun>,
}

fn rows<'py, const N: usize>(py: Python<'py>, v: &[[f64; N]]) -> Bound<'py, PyAny> {
    let flat: Vec<f64> = v.iter().flatten().copied().collect();
    let a = PyArray1::from_vec(py, flat);
    a.reshape([v.len(), N])
        .map(|a| a.into_any())
        .unwrap_or_else(|_| PyArray1::<f64>::zeros(py, 0, false).into_any())
}

/// Default time step of a rigid scene built in Python (that of the shipped rigid scene files).
pub(crate) const RIGID_H: f64 = 1e-3;
/// Default tolerance of a rigid scene built in Python (that of the shipped rigid scene files).
pub(crate) const RIGID_TOL: f64 = 1e-8;

fn build(
    py: Python<'_>,
    model: SceneModel,
    resolve_overlaps: Option<usize>,
) -> PyResult<PyRigidSimulation> {
    let scene = py
        .detach(move || match resolve_overlaps {
            None => RigidScene::new(&model),
            Some(sweeps) => RigidScene::new_relaxed(&model, sweeps).map(|(s, _)| s),
        })
        .map_err(|e| crate::errors::scene_error(py, &e))?;
    Ok(PyRigidSimulation {
        scene,
        frames: None,
        pour: Vec::new(),
    })
}

/// The rigid scene of a scene file that runs in the rigid-body simulator
/// ([`BuiltScene::runs_rigid`]), as `coulomb simulate FILE` builds it, `params` applied on
/// top of its model's step settings (as for `from_scene`), its inlets pouring after each step.
pub(crate) fn from_built(
    py: Python<'_>,
    mut built: BuiltScene,
    params: &Bound<'_, PyDict>,
    resolve_overlaps: Option<usize>,
) -> PyResult<PyRigidSimulation> {
    crate::granular::apply_to_model(&mut built.model, params)?;
    let mut sim = build(py, built.model, resolve_overlaps)?;
    sim.pour = built.inlets;
    Ok(sim)
}

impl PyRigidSimulation {
    /// One step t_k → t_{k+1}, then the inlets, in order, pour the bodies due in
    /// (t_k, t_{k+1}] ([`InletRun::pour_rigid`], as `coulomb simulate` does after each step,
    /// [`BuiltScene::pour_rigid`]); the step's record. Without the GIL.
    fn advance(&mut self, py: Python<'_>) -> PyResult<StepRecord> {
        let (scene, pour) = (&mut self.scene, &mut self.pour);
        py.detach(move || {
            let t0 = scene.world.time();
            let r = scene.step().map_err(|e| e.to_string())?;
            let record = StepRecord::of_rigid(&r, scene.world.potential_energy());
            let t1 = scene.world.time();
            for inlet in pour.iter_mut() {
                inlet
                    .pour_rigid(scene, t0, t1)
                    .map_err(|e| format!("inlet at t = {t1}: {e}"))?;
            }
            Ok(record)
        })
        .map_err(PyRuntimeError::new_err::<String>)
    }
}

#[pymethods]
impl PyRigidSimulation {
    /// A scene built in Python (as `_Simulation.from_scene`); `params` may set the step
    /// settings h, theta, tol, method, max_sweeps, relaxation, the default law mu,
    /// restitution, rolling_friction, the switches warm_start, gap_closure, projection_velocities (`"positions_only"` only).
    /// `inlets` (the JSON list of `Scene._inlets`) pour after each step; with some, the spheres of
    /// the batches become bodies (in the same order), after which the poured ones are
    /// appended, as a scene file's are.
    #[staticmethod]
    #[pyo3(signature = (json, batches, meshes, params, inlets, resolve_overlaps=None))]
    fn from_scene(
        py: Python<'_>,
        json: &str,
        batches: &Bound<'_, PyList>,
        meshes: &Bound<'_, PyList>,
        params: &Bound<'_, PyDict>,
        inlets: &str,
        resolve_overlaps: Option<usize>,
    ) -> PyResult<Self> {
        let (_, pour) = crate::granular::inlet_runs(py, json, inlets)?;
        let arrays = SceneArrays::extract(batches, meshes)?;
        let json = json.to_string();
        let mut model = py
            .detach(move || model_from_parts(&json, arrays))
            .map_err(|e| e.into_py(py))?;
        if !pour.is_empty() {
            for batch in std::mem::take(&mut model.sphere_batches) {
                let spheres = model
                    .spheres_of(&batch)
                    .map_err(|e| crate::errors::scene_error(py, &e))?;
                model.bodies.extend(spheres.iter().map(|s| BodySpec {
                    mass: Some(s.mass),
                    density: None,
                    velocity: s.velocity,
                    angular_velocity: s.angular_velocity,
                    material: batch.material.clone(),
                    fixed: batch.fixed,
                    ..BodySpec::sphere(s.position, s.radius, 1.0)
                }));
            }
        }
        // the rigid scene files' step defaults (h = 1e-3 s, tol = 1e-8), not the sphere
        // scenes' 0.02 s and 1e-4 (issue 55: a 10-cube tower sank 5.6 cm at those)
        model.step.h = RIGID_H;
        model.step.tol = RIGID_TOL;
        crate::granular::apply_to_model(&mut model, params)?;
        let mut sim = build(py, model, resolve_overlaps)?;
        sim.pour = pour;
        Ok(sim)
    }

    /// One time step; its record (`coulomb_granular::StepRecord`, the same keys for every
    /// scene) as a dict.
    fn step<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let record = self.advance(py)?;
        crate::granular::record_to_py(py, &record)
    }

    /// `n` steps at once (GIL released); their records (as [`Self::step`]).
    fn run<'py>(&mut self, py: Python<'py>, n: usize) -> PyResult<Bound<'py, PyList>> {
        // one step at a time without the GIL, the signals checked between steps: Ctrl-C
        // raises KeyboardInterrupt after the step in progress (the steps taken stay taken)
        let mut records = Vec::with_capacity(n.min(1 << 20));
        for _ in 0..n {
            records.push(self.advance(py)?);
            py.check_signals()?;
        }
        let out = PyList::empty(py);
        for r in &records {
            out.append(crate::granular::record_to_py(py, r)?)?;
        }
        Ok(out)
    }

    /// Origins of the bodies' shape frames, (n, 3).
    #[getter]
    fn body_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        rows(py, &self.scene.world.positions())
    }

    /// The joints' force and torque on their body A in the last step (world axes; torque
    /// about the joint's anchor): (n_joints, 6), the impulse / h.
    #[getter]
    fn joint_forces<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        rows(py, &self.scene.world.joint_forces())
    }

    /// Largest violation of the joints' constraints at t_k (m or rad).
    #[getter]
    fn joint_drift(&self) -> f64 {
        self.scene.world.joint_drift()
    }

    /// Orientations (w, x, y, z), (n, 4).
    #[getter]
    fn body_orientations<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        rows(py, &self.scene.world.orientations())
    }

    /// Velocities of the centres of mass, (n, 3).
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        rows(py, &self.scene.world.velocities())
    }

    /// Radii, (n,): a sphere body's radius, NaN for every other shape (a radius that is not
    /// the shape's would mislead whoever sizes glyphs or packing fractions with it).
    #[getter]
    fn radii<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let r = self.scene.shapes.iter().map(|s| match s {
            coulomb_granular::shape::BodyShape::Sphere { radius } => *radius,
            _ => f64::NAN,
        });
        PyArray1::from_iter(py, r).into_any()
    }

    /// Masses, (n,).
    #[getter]
    fn masses<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        PyArray1::from_vec(py, self.scene.world.masses()).into_any()
    }

    /// Replaces the velocities of the centres of mass (flattened (n, 3), finite; a fixed
    /// body's must be 0).
    fn set_velocities(&mut self, v: numpy::PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        let s = convert::slice("velocities", &v)?;
        if s.len() != 3 * self.scene.world.len() {
            return Err(PyValueError::new_err(format!(
                "velocities: expected shape ({}, 3), got {} entries",
                self.scene.world.len(),
                s.len()
            )));
        }
        let rows: Vec<[f64; 3]> = s.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        self.scene
            .world
            .set_velocities(&rows)
            .map_err(|e| PyValueError::new_err(format!("velocities: {e}")))
    }

    /// Angular velocities (world frame), (n, 3).
    #[getter]
    fn angular_velocities<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        rows(py, &self.scene.world.angular_velocities())
    }

    /// The last step's contacts ([`convert::contacts_to_py`]), an obstacle numbered as in the
    /// scene (not as the part of it the rigid world holds), as the sphere scenes' contacts are.
    #[getter]
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let of = &self.scene.obstacle_of;
        convert::contacts_to_py(py, self.scene.world.contacts(), |k| {
            of.get(k).copied().unwrap_or(k)
        })
    }

    /// t_k (s).
    #[getter]
    fn time(&self) -> f64 {
        self.scene.world.time()
    }

    /// Steps taken.
    #[getter]
    fn steps_done(&self) -> u64 {
        self.scene.world.steps()
    }

    /// Writes the current state as a ParaView frame into the folder `dir` with the writer of
    /// `coulomb simulate --output`, the one of every scene (balls as glyph points, other
    /// bodies as their shapes' polygons; the same folder safety).
    fn write_frames(&mut self, py: Python<'_>, dir: PathBuf) -> PyResult<()> {
        let (scene, frames) = (&self.scene, &mut self.frames);
        let target = dir.clone();
        py.detach(move || {
            if frames.as_ref().is_none_or(|(d, _)| *d != dir) {
                let w = coulomb_granular::output::VtkWriter::new(&dir)?;
                *frames = Some((dir.clone(), w));
            }
            let (_, w) = frames.as_mut().expect("set above");
            w.frame(scene)
        })
        .map_err(|e| crate::errors::output_error(e, &target))
    }

    /// Number of bodies.
    fn __len__(&self) -> usize {
        self.scene.world.len()
    }

    /// The last step's problem (2.10) in global form, or None.
    #[getter]
    fn last_problem(&self) -> Option<PyProblem> {
        self.scene.world.last_problem().map(|p| PyProblem {
            inner: Arc::new(Problem::Global(p.clone())),
        })
    }

    /// Writes the scene's full state into the HDF5 checkpoint file `path`, atomically
    /// (`coulomb_granular::rigid_checkpoint`).
    fn save_checkpoint(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let scene = &self.scene;
        py.detach(|| scene.save_checkpoint(&path))
            .map_err(|e| crate::errors::checkpoint_error(py, e))
    }

    /// The scene stored in the rigid checkpoint file `path`; stepping it gives the same bits
    /// as stepping the saved one.
    #[staticmethod]
    fn load_checkpoint(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        py.detach(|| RigidScene::load_checkpoint(&path))
            .map(|scene| Self {
                scene,
                frames: None,
                pour: Vec::new(),
            })
            .map_err(|e| crate::errors::checkpoint_error(py, e))
    }

    /// The step settings and contact law the rigid world runs with, under the keys of the
    /// sphere scenes' `params`: those it fixes (method "nsgs" finished by the library,
    /// warm starts, gap closure, position correction moving positions only) as it fixes them.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let step = &self.scene.model.step;
        let law = &self.scene.model.materials.default;
        let s = self.scene.world.settings();
        let d = PyDict::new(py);
        d.set_item("h", step.h)?;
        d.set_item("theta", step.theta)?;
        d.set_item("restitution", law.restitution)?;
        d.set_item("mu", law.mu)?;
        d.set_item("rolling_friction", law.rolling_friction)?;
        d.set_item("warm_start", s.warm_start)?;
        d.set_item("gap_closure", s.gap_closure)?;
        d.set_item(
            "projection_velocities",
            s.position_correction.then_some("positions_only"),
        )?;
        d.set_item("method", if s.library_only { "library" } else { "nsgs" })?;
        d.set_item("tol", step.tol)?;
        d.set_item("max_sweeps", step.max_sweeps)?;
        d.set_item("relaxation", step.relaxation)?;
        d.set_item("solver", convert::settings_to_dict(py, &s.solver)?)?;
        Ok(d)
    }

    /// Changes the settings of `from_scene` (h, theta, tol, method, max_sweeps, relaxation,
    /// the default law mu, restitution, rolling_friction, the switches warm_start,
    /// gap_closure, projection_velocities) for the following steps: the scene's model takes them and the world is
    /// rebuilt from it with its state at t_k (the round trip of a checkpoint, what a restart
    /// does), so that its checks apply and its checkpoints hold them. Refused, nothing
    /// changed, as the constructor refuses them.
    #[pyo3(signature = (**params))]
    fn set_params(&mut self, params: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let Some(kw) = params else { return Ok(()) };
        let mut model = self.scene.model.clone();
        crate::granular::apply_to_model(&mut model, kw)?;
        let old = std::mem::replace(&mut self.scene.model, model);
        let rebuilt = self
            .scene
            .checkpoint_bytes()
            .and_then(|b| RigidScene::from_checkpoint_bytes("set_params", b));
        match rebuilt {
            Ok(scene) => {
                self.scene = scene;
                Ok(())
            }
            Err(e) => {
                self.scene.model = old;
                // the model's error, not the round trip's wrapping of it
                let why = match &e {
                    CheckpointError::Invalid { detail, .. } => detail
                        .strip_prefix("the stored scene: ")
                        .unwrap_or(detail)
                        .to_string(),
                    other => other.to_string(),
                };
                Err(PyValueError::new_err(format!("set_params: {why}")))
            }
        }
    }

    /// Whether each step keeps its problem (2.10) in `last_problem` (default True).
    #[getter]
    fn keep_problem(&self) -> bool {
        self.scene.world.settings().keep_problem
    }

    /// Switches keeping each step's problem on or off (`RigidWorld::set_keep_problem`): the
    /// rigid step builds the global problem for the library's finish without it.
    #[setter]
    fn set_keep_problem(&mut self, keep: bool) {
        self.scene.world.set_keep_problem(keep);
    }

    /// Replaces the settings of the library's solver that finishes (or, with method
    /// "library", takes) the steps, from the next step: the keyword arguments of `solve`,
    /// checked as the sphere scenes' `set_solver` checks them; its tol is the scene's
    /// (`set_params(tol=...)`), as at construction.
    #[pyo3(signature = (**settings))]
    fn set_solver(&mut self, py: Python<'_>, settings: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let s = convert::settings_from_kwargs(py, "set_solver", settings)?;
        self.scene.world.set_solver(s);
        Ok(())
    }

    /// Moves the bodies before the next step: the origins of their shape frames (flattened
    /// (n, 3), finite, as `body_positions`), orientations unchanged (`RigidWorld::set_positions`;
    /// a fixed body must stay where it is). Refused, nothing changed, otherwise.
    fn set_positions(&mut self, x: numpy::PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        let n = self.scene.world.len();
        let rows: Vec<[f64; 3]> = crate::granular::points("positions", n, &x)?
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect();
        self.scene
            .world
            .set_positions(&rows)
            .map_err(|e| PyValueError::new_err(format!("positions: {e}")))
    }

    /// Makes the inlets of `scene` (the scene file or `Scene` the stored run was built from)
    /// pour into this loaded run after each step, as `coulomb simulate FILE --restart`: an
    /// emission depends only on its inlet's seed, the time and the bodies present, so the
    /// continued run pours the uninterrupted one's bodies. False, nothing changed, when
    /// `scene` is not this run's (its bodies, those poured since aside, obstacles,
    /// materials, gravity or joints differ; the step settings may).
    fn pour_from(&mut self, scene: &Self) -> bool {
        let model = SceneModel {
            step: self.scene.model.step.clone(),
            ..scene.scene.model.clone()
        };
        if !self.scene.is_built_from(&model, !scene.pour.is_empty()) {
            return false;
        }
        self.pour.clone_from(&scene.pour);
        true
    }
}

/// Whether the file at `path` is a rigid-scene checkpoint (not a sphere one).
#[pyfunction]
pub fn _checkpoint_is_rigid(py: Python<'_>, path: PathBuf) -> bool {
    py.detach(|| {
        coulomb_granular::checkpoint::format_of(&path).as_deref()
            == Some(coulomb_granular::rigid_checkpoint::FORMAT_NAME)
    })
}
