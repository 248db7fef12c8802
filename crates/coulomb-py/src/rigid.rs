//! `coulomb_granular::rigid_scene::RigidScene` for Python: a scene with bodies of any shape
//! (cuboids, capsules, cylinders, cones, convex hulls and polyhedra, compounds; spheres as
//! balls), stepped by the rigid-body simulator with the GIL released.

use crate::convert;
use crate::scene::{model_from_parts, SceneArrays};
use crate::PyProblem;
use coulomb::problem::Problem;
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::{BuildOptions, LoadedScene};
use coulomb_granular::SceneModel;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
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
    frames: Option<(PathBuf, coulomb_granular::output::RigidVtkWriter)>,
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
    })
}

/// `rest` (the keywords `warm_start`, `gap_closure`) applied to the switches `w`
/// (`coulomb_granular::rigid::StepSwitches`); any other keyword refused.
fn switches_of(
    rest: Vec<(String, Bound<'_, PyAny>)>,
    mut w: coulomb_granular::rigid::StepSwitches,
) -> PyResult<coulomb_granular::rigid::StepSwitches> {
    for (k, v) in rest {
        let b = || {
            v.extract::<bool>()
                .map_err(|_| PyTypeError::new_err(format!("{k} must be a bool")))
        };
        match k.as_str() {
            "warm_start" => w.warm_start = b()?,
            "gap_closure" => w.gap_closure = b()?,
            _ => {
                return Err(PyTypeError::new_err(format!(
                    "'{k}' is not a parameter of rigid-body scenes (h, theta, tol, method, max_sweeps, relaxation, mu, restitution, rolling_friction, warm_start, gap_closure)"
                )))
            }
        }
    }
    Ok(w)
}

#[pymethods]
impl PyRigidSimulation {
    /// A scene built in Python (as `_Simulation.from_scene`); `params` may set the step
    /// settings h, theta, tol, method, max_sweeps, relaxation, the default law mu,
    /// restitution, rolling_friction, and the switches warm_start, gap_closure.
    #[staticmethod]
    #[pyo3(signature = (json, batches, meshes, params, resolve_overlaps=None))]
    fn from_scene(
        py: Python<'_>,
        json: &str,
        batches: &Bound<'_, PyList>,
        meshes: &Bound<'_, PyList>,
        params: &Bound<'_, PyDict>,
        resolve_overlaps: Option<usize>,
    ) -> PyResult<Self> {
        let arrays = SceneArrays::extract(batches, meshes)?;
        let json = json.to_string();
        let mut model = py
            .detach(move || model_from_parts(&json, arrays))
            .map_err(|e| e.into_py(py))?;
        // the rigid scene files' step defaults (h = 1e-3 s, tol = 1e-8), not the sphere
        // scenes' 0.02 s and 1e-4 (issue 55: a 10-cube tower sank 5.6 cm at those)
        model.step.h = RIGID_H;
        model.step.tol = RIGID_TOL;
        let rest = crate::granular::apply_to_model(&mut model, params)?;
        let switches = switches_of(rest, Default::default())?;
        let mut sim = build(py, model, resolve_overlaps)?;
        sim.scene
            .world
            .set_switches(switches)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(sim)
    }

    /// The scene of a scene file with shaped bodies; `params` as for `from_scene`.
    #[staticmethod]
    #[pyo3(signature = (path, seed, params, resolve_overlaps=None))]
    fn from_file(
        py: Python<'_>,
        path: PathBuf,
        seed: Option<u64>,
        params: &Bound<'_, PyDict>,
        resolve_overlaps: Option<usize>,
    ) -> PyResult<Self> {
        let file_err = |e| crate::errors::scene_file_error(py, &e);
        let loaded = py.detach(|| LoadedScene::load(&path)).map_err(file_err)?;
        let opts = BuildOptions {
            seed,
            max_fill: None,
        };
        let mut built = py.detach(|| loaded.build(&opts)).map_err(file_err)?;
        if !built.inlets.is_empty() {
            return Err(PyValueError::new_err(format!(
                "{}: the inlets of a scene that runs in the rigid-body simulator (bodies of other shapes, joints, or an inlet with a shape) pour in `coulomb simulate` only, not yet in Python",
                path.display()
            )));
        }
        let rest = crate::granular::apply_to_model(&mut built.model, params)?;
        // the file's [step] switches (gamma, projection, gap_closure, warm_start), as
        // `coulomb simulate` sets them, then the keywords'
        let switches = coulomb_granular::scene_file::check_rigid_step(&built.step)
            .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?;
        let switches = switches_of(rest, switches)?;
        let mut sim = build(py, built.model, resolve_overlaps)?;
        sim.scene
            .world
            .set_switches(switches)
            .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?;
        Ok(sim)
    }

    /// One time step; its record (`coulomb_granular::StepRecord`, the same keys for every
    /// scene) as a dict.
    fn step<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let scene = &mut self.scene;
        let r = py
            .detach(move || scene.step())
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let record =
            coulomb_granular::StepRecord::of_rigid(&r, self.scene.world.potential_energy());
        crate::granular::record_to_py(py, &record)
    }

    /// `n` steps at once (GIL released); their records (as [`Self::step`]).
    fn run<'py>(&mut self, py: Python<'py>, n: usize) -> PyResult<Bound<'py, PyList>> {
        // one step at a time without the GIL, the signals checked between steps: Ctrl-C
        // raises KeyboardInterrupt after the step in progress (the steps taken stay taken)
        let mut records = Vec::with_capacity(n.min(1 << 20));
        for _ in 0..n {
            let scene = &mut self.scene;
            let r = py
                .detach(move || scene.step())
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
            records.push(coulomb_granular::StepRecord::of_rigid(
                &r,
                self.scene.world.potential_energy(),
            ));
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

    /// The last step's contacts (`RigidContact`: a, b, point, normal, t1, gap, impulse).
    #[getter]
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = serde_json::to_value(self.scene.world.contacts())
            .map_err(|e| PyRuntimeError::new_err(format!("cannot serialize: {e}")))?;
        convert::json_to_py(py, &json)
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
    /// `coulomb simulate --output` (each body as its shape's polygons; the same folder
    /// safety as the sphere frames).
    fn write_frames(&mut self, py: Python<'_>, dir: PathBuf) -> PyResult<()> {
        let (scene, frames) = (&self.scene, &mut self.frames);
        let target = dir.clone();
        py.detach(move || {
            if frames.as_ref().is_none_or(|(d, _)| *d != dir) {
                let w = coulomb_granular::output::RigidVtkWriter::new(&dir, scene)?;
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
            })
            .map_err(|e| crate::errors::checkpoint_error(py, e))
    }

    /// Whether `other` was built from the same scene (bodies at t = 0, obstacles, materials,
    /// gravity; the step settings, which the checkpoint holds, may differ).
    /// The step settings and the default contact law the rigid world runs with (h, theta,
    /// tol, max_sweeps, mu, restitution: the parameters `from_scene` accepts).
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let step = &self.scene.model.step;
        let law = &self.scene.model.materials.default;
        let d = PyDict::new(py);
        d.set_item("h", step.h)?;
        d.set_item("theta", step.theta)?;
        d.set_item("tol", step.tol)?;
        d.set_item("max_sweeps", step.max_sweeps)?;
        d.set_item("mu", law.mu)?;
        d.set_item("restitution", law.restitution)?;
        Ok(d)
    }

    fn same_setup(&self, other: &Self) -> bool {
        let step = self.scene.model.step.clone();
        SceneModel {
            step,
            ..other.scene.model.clone()
        } == self.scene.model
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

/// Whether the scene file at `path` has bodies of another shape than the sphere, joints or
/// URDF robots (then it runs in the rigid-body simulator, as `SceneModel::has_shapes` says
/// of its model).
#[pyfunction]
pub fn _scene_file_has_shapes(py: Python<'_>, path: PathBuf) -> PyResult<bool> {
    let loaded = py
        .detach(|| LoadedScene::load(&path))
        .map_err(|e| crate::errors::scene_file_error(py, &e))?;
    let f = &loaded.file;
    Ok(!f.joints.is_empty()
        || !f.urdf.is_empty()
        || f.bodies
            .iter()
            .any(|g| g.shape.as_ref().is_some_and(|s| !s.is_sphere()))
        || f.inlets
            .iter()
            .any(|i| i.shape.as_ref().is_some_and(|s| !s.is_sphere())))
}
