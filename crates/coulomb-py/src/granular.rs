//! `coulomb_granular::Simulation` for Python: build a scene, step it (GIL released), read and
//! steer the state (positions, velocities, parameters) between steps.

use crate::convert;
use crate::PyProblem;
use coulomb::problem::Problem;
use coulomb_granular::{Params, Scene, Simulation, SimulationError, Vec3, World};
use numpy::{PyReadonlyArray1, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::Arc;

fn sim_error(e: SimulationError) -> PyErr {
    match e {
        SimulationError::Parameter(m) => PyValueError::new_err(m),
        other => PyRuntimeError::new_err(other.to_string()),
    }
}

/// Applies `name = value` to the time-stepping parameters (the names of
/// `coulomb_granular::Params`).
fn set_param(p: &mut Params, name: &str, v: &Bound<'_, PyAny>) -> PyResult<()> {
    let real = || -> PyResult<f64> {
        v.extract()
            .map_err(|_| PyTypeError::new_err(format!("{name} must be a float")))
    };
    match name {
        "h" => p.h = real()?,
        "theta" => p.theta = real()?,
        "restitution" => p.restitution = real()?,
        "mu" => p.mu = real()?,
        "rolling_friction" => p.rolling_friction = real()?,
        "warm_start" => p.warm_start = v.extract()?,
        "gap_closure" => {
            p.activation.close_gaps = v
                .extract()
                .map_err(|_| PyTypeError::new_err("gap_closure must be a bool"))?
        }
        other => {
            return Err(PyTypeError::new_err(format!(
                "unexpected simulation parameter '{other}' \
                 (parameters: h, theta, restitution, mu, rolling_friction, warm_start, gap_closure; solver settings go in solver=)"
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
fn points(what: &str, n: usize, a: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<Vec3>> {
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

/// A granular simulation (Moreau–Jean time stepping (2.5)–(2.7), one problem (2.10) per step).
#[pyclass(name = "_Simulation", module = "coulomb._coulomb")]
pub struct PySimulation {
    sim: Simulation,
}

#[pymethods]
impl PySimulation {
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
        let mut p = Params {
            solver: convert::settings_from_kwargs(py, "Simulation", solver)?,
            ..Params::default()
        };
        for (k, v) in params.iter() {
            set_param(&mut p, &k.extract::<String>()?, &v)?;
        }
        let world = py.detach(move || scene.build(beads, seed));
        let sim = Simulation::new(world, p).map_err(sim_error)?;
        Ok(Self { sim })
    }

    /// One time step; its statistics (the fields of `coulomb_granular::StepStats`) as a dict.
    fn step<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let sim = &mut self.sim;
        let stats = py.detach(move || sim.step()).map_err(sim_error)?;
        let json = serde_json::to_value(&stats)
            .map_err(|e| PyRuntimeError::new_err(format!("cannot serialize step stats: {e}")))?;
        convert::json_to_py(py, &json)
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
            for (k, v) in kw.iter() {
                set_param(&mut p, &k.extract::<String>()?, &v)?;
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

    /// Writes the full state (bodies, obstacles, parameters and solver settings, t, k, warm
    /// starts) into the HDF5 checkpoint file `path`, atomically
    /// (`coulomb_granular::checkpoint`).
    fn save_checkpoint(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let sim = &self.sim;
        py.detach(|| sim.save_checkpoint(&path))
            .map_err(|e| crate::errors::checkpoint_error(py, e))
    }

    /// The simulation stored in the checkpoint file `path`; stepping it gives the same bits as
    /// stepping the saved one.
    #[staticmethod]
    fn load_checkpoint(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        py.detach(|| Simulation::load_checkpoint(&path))
            .map(|sim| Self { sim })
            .map_err(|e| crate::errors::checkpoint_error(py, e))
    }

    /// The last step's global problem (when `keep_problem` is set and the step had contacts).
    #[getter]
    fn last_problem(&self) -> Option<PyProblem> {
        self.sim.last_problem.as_ref().map(|g| PyProblem {
            inner: Arc::new(Problem::Global(g.clone())),
        })
    }
}
