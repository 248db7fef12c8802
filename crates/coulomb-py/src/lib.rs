//! `coulomb._coulomb`: the compiled half of the Python package `coulomb`.
//!
//! The pure-Python layer (`python/coulomb/`) converts numpy / scipy.sparse input to CSC
//! arrays and wraps the dicts returned here into typed objects; this module holds the
//! library's problem, runs the solver and the existence check with the GIL released, and
//! turns the library's typed errors into Python exceptions (`errors.rs`). All conversions
//! live in `convert.rs`.

mod convert;
mod errors;
mod granular;
mod rigid;
mod scene;

use coulomb::existence::{self, CheckSettings};
use coulomb::fclib::{self, FclibFile, Info, StoredSolution};
use coulomb::problem::{GlobalProblem, LocalProblem, Problem};
use coulomb::solver::{self, Guess};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

fn owned(what: &str, a: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<f64>> {
    Ok(convert::slice(what, a)?.to_vec())
}

/// A validated problem of the library (local (W, q, μ) or global (M, H, f, w, μ)), shared
/// read-only between threads.
#[pyclass(frozen, name = "_Problem", module = "coulomb._coulomb")]
pub struct PyProblem {
    pub(crate) inner: Arc<Problem>,
}

#[pymethods]
impl PyProblem {
    /// Validates (W, q, μ) with `LocalProblem::new`.
    #[staticmethod]
    fn local(
        py: Python<'_>,
        dim: i64,
        w: &Bound<'_, PyTuple>,
        q: PyReadonlyArray1<'_, f64>,
        mu: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let w = convert::csc_from_arrays(py, "W", w)?;
        let p = LocalProblem::new(dim, w, owned("q", &q)?, owned("mu", &mu)?)
            .map_err(|e| errors::problem_error(py, &e))?;
        Ok(Self {
            inner: Arc::new(Problem::Local(p)),
        })
    }

    /// Validates (M, H, f, w, μ) with `GlobalProblem::new` (Cholesky test of M included),
    /// and the equality constraints (G, b) with `GlobalProblem::with_equality` when given
    /// (both or neither).
    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (dim, m, h, f, w, mu, g=None, b=None))]
    fn global_(
        py: Python<'_>,
        dim: i64,
        m: &Bound<'_, PyTuple>,
        h: &Bound<'_, PyTuple>,
        f: PyReadonlyArray1<'_, f64>,
        w: PyReadonlyArray1<'_, f64>,
        mu: PyReadonlyArray1<'_, f64>,
        g: Option<&Bound<'_, PyTuple>>,
        b: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<Self> {
        let m = convert::csc_from_arrays(py, "M", m)?;
        let h = convert::csc_from_arrays(py, "H", h)?;
        let (f, w, mu) = (owned("f", &f)?, owned("w", &w)?, owned("mu", &mu)?);
        let equality = match (g, b) {
            (None, None) => None,
            (Some(g), Some(b)) => Some((convert::csc_from_arrays(py, "G", g)?, owned("b", &b)?)),
            (g, _) => {
                let (what, other) = if g.is_some() { ("b", "G") } else { ("G", "b") };
                return Err(errors::input_error(
                    py,
                    what,
                    None,
                    format!("{other} is given without {what}: equality constraints need both"),
                ));
            }
        };
        let p = py
            .detach(move || {
                let p = GlobalProblem::new(dim, m, h, f, w, mu)?;
                match equality {
                    Some((g, b)) => p.with_equality(g, b),
                    None => Ok(p),
                }
            })
            .map_err(|e| errors::problem_error(py, &e))?;
        Ok(Self {
            inner: Arc::new(Problem::Global(p)),
        })
    }

    /// "local" or "global".
    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }

    /// Space dimension d.
    #[getter]
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    /// Number of contacts.
    #[getter]
    fn contacts(&self) -> usize {
        self.inner.contacts()
    }

    /// Degrees of freedom n (None for a local problem).
    #[getter]
    fn dofs(&self) -> Option<usize> {
        self.inner.dofs()
    }

    /// The stored data as numpy arrays; matrices as (nrows, ncols, indptr, indices, data).
    fn arrays<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        match &*self.inner {
            Problem::Local(p) => {
                d.set_item("W", convert::csc_to_tuple(py, &p.w)?)?;
                d.set_item("q", PyArray1::from_slice(py, &p.q))?;
                d.set_item("mu", PyArray1::from_slice(py, &p.mu))?;
            }
            Problem::Global(p) => {
                d.set_item("M", convert::csc_to_tuple(py, &p.m)?)?;
                d.set_item("H", convert::csc_to_tuple(py, &p.h)?)?;
                d.set_item("f", PyArray1::from_slice(py, &p.f))?;
                d.set_item("w", PyArray1::from_slice(py, &p.w))?;
                d.set_item("mu", PyArray1::from_slice(py, &p.mu))?;
                if let Some(e) = &p.equality {
                    d.set_item("G", convert::csc_to_tuple(py, &e.g)?)?;
                    d.set_item("b", PyArray1::from_slice(py, &e.b))?;
                }
            }
        }
        Ok(d)
    }
}

/// `coulomb::solver::solve_with_guess` with the GIL released; the solution as a dict.
#[pyfunction]
#[pyo3(signature = (problem, r0=None, v0=None, **settings))]
fn solve<'py>(
    py: Python<'py>,
    problem: &PyProblem,
    r0: Option<PyReadonlyArray1<'_, f64>>,
    v0: Option<PyReadonlyArray1<'_, f64>>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let settings = convert::settings_from_kwargs(py, "solve", settings)?;
    let guess = match (r0, v0) {
        (None, None) => None,
        (None, Some(_)) => {
            return Err(errors::input_error(
                py,
                "v0",
                None,
                "v0 needs r0 (the solver starts from impulses r0)".into(),
            ))
        }
        (Some(r), v) => Some(Guess {
            r: owned("r0", &r)?,
            v: v.map(|v| owned("v0", &v)).transpose()?,
        }),
    };
    let problem = Arc::clone(&problem.inner);
    let result = py.detach(move || solver::solve_with_guess(&problem, &settings, guess.as_ref()));
    match result {
        Ok(sol) => convert::solution_to_dict(py, sol),
        Err(e) => Err(errors::solve_error(py, &e)),
    }
}

/// The library's default settings as a dict.
#[pyfunction]
fn default_settings(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    convert::settings_to_dict(py, &solver::Settings::default())
}

/// The settings `solve(**kwargs)` would use, as a dict (validates the names and types).
#[pyfunction]
#[pyo3(signature = (**settings))]
fn resolve_settings<'py>(
    py: Python<'py>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = convert::settings_from_kwargs(py, "solve", settings)?;
    convert::settings_to_dict(py, &s)
}

/// The error of docs/error.md for impulses r (and velocities v of a global problem; when v is
/// None it is recomputed as M⁻¹(H r + f), or with equality constraints with λ as the
/// elimination of `coulomb::equality` gives them): dict with error, absolute, scale,
/// balance_residual, equality_residual.
#[pyfunction]
#[pyo3(signature = (problem, r, v=None, l=None))]
fn error<'py>(
    py: Python<'py>,
    problem: &PyProblem,
    r: PyReadonlyArray1<'_, f64>,
    v: Option<PyReadonlyArray1<'_, f64>>,
    l: Option<PyReadonlyArray1<'_, f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let r = owned("r", &r)?;
    let v = v.map(|v| owned("v", &v)).transpose()?;
    let l = l.map(|l| owned("l", &l)).transpose()?;
    let p = Arc::clone(&problem.inner);
    let m = p.dim() * p.contacts();
    if r.len() != m {
        return Err(errors::input_error(
            py,
            "r",
            None,
            format!("r has {} entries, the problem needs {m}", r.len()),
        ));
    }
    let eval = py.detach(move || -> Result<_, fclib::EvaluateError> {
        let (v, l) = match (&*p, v) {
            (Problem::Global(g), None) if g.equality.is_some() => {
                let (v, lr) = coulomb::equality::Reduction::new(g)?.recover(g, &r);
                (Some(v), l.or(Some(lr)))
            }
            (Problem::Global(g), None) => {
                let d = coulomb::delassus::Delassus::new(g)?;
                (Some(d.velocity(&g.h, &r)), l)
            }
            (_, v) => (v, l),
        };
        let stored = StoredSolution { v, u: None, r, l };
        fclib::evaluate(&p, &stored)
    });
    let eval = eval.map_err(|e| errors::evaluate_error(py, &e))?;
    let d = PyDict::new(py);
    d.set_item("error", eval.measure.error)?;
    d.set_item("absolute", eval.measure.absolute)?;
    d.set_item("scale", eval.measure.scale)?;
    d.set_item("balance_residual", eval.balance_residual)?;
    d.set_item("equality_residual", eval.equality_residual)?;
    Ok(d)
}

/// `coulomb::existence::check` with the GIL released; the report as nested dicts (the
/// library's serialization), vectors as numpy arrays.
#[pyfunction]
#[pyo3(signature = (problem, **settings))]
fn check<'py>(
    py: Python<'py>,
    problem: &PyProblem,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut s = CheckSettings::default();
    if let Some(kw) = settings {
        for (k, v) in kw.iter() {
            let name: String = k.extract()?;
            match name.as_str() {
                "tol" => s.tol = v.extract()?,
                "certificate_tol" => s.certificate_tol = v.extract()?,
                "max_iter" => s.max_iter = v.extract()?,
                "time_limit" => {
                    // seconds; +∞ and overflowing values mean no limit
                    let t: f64 = v.extract()?;
                    if t.is_nan() || t <= 0.0 {
                        let message = format!("time_limit = {t} is not > 0");
                        return Err(errors::settings_error(py, "time_limit", message));
                    }
                    s.time_limit = Duration::try_from_secs_f64(t)
                        .unwrap_or(Duration::MAX)
                        .max(Duration::from_nanos(1));
                }
                other => {
                    return Err(PyTypeError::new_err(format!(
                        "check() got an unexpected keyword argument '{other}' \
                         (settings: tol, certificate_tol, max_iter, time_limit)"
                    )))
                }
            }
        }
    }
    let p = Arc::clone(&problem.inner);
    let report = py.detach(move || existence::check(&p, &s));
    let report = report.map_err(|e| match e {
        existence::CheckError::Problem(p) => errors::problem_error(py, &p),
        existence::CheckError::Settings(m) => {
            let field = m
                .split_whitespace()
                .next()
                .unwrap_or("settings")
                .to_string();
            errors::settings_error(py, &field, m)
        }
    })?;
    let json = serde_json::to_value(&report)
        .map_err(|e| PyValueError::new_err(format!("cannot serialize the report: {e}")))?;
    convert::json_to_py(py, &json)
}

fn stored_to_dict<'py>(py: Python<'py>, s: StoredSolution) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("r", PyArray1::from_vec(py, s.r))?;
    d.set_item("u", s.u.map(|x| PyArray1::from_vec(py, x)))?;
    d.set_item("v", s.v.map(|x| PyArray1::from_vec(py, x)))?;
    d.set_item("l", s.l.map(|x| PyArray1::from_vec(py, x)))?;
    Ok(d)
}

/// Reads an FCLIB file exactly as stored: dict with problem, info, solution, guesses,
/// asymmetry (of W or M).
#[pyfunction]
fn fclib_read<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let file = py
        .detach(move || fclib::read(&path))
        .map_err(|e| errors::fclib_error(py, e))?;
    let d = PyDict::new(py);
    d.set_item("asymmetry", file.problem.asymmetry())?;
    d.set_item(
        "problem",
        PyProblem {
            inner: Arc::new(file.problem),
        },
    )?;
    match file.info {
        Some(i) => {
            let info = PyDict::new(py);
            info.set_item("title", i.title)?;
            info.set_item("description", i.description)?;
            info.set_item("math_info", i.math_info)?;
            d.set_item("info", info)?;
        }
        None => d.set_item("info", py.None())?,
    }
    match file.solution {
        Some(s) => d.set_item("solution", stored_to_dict(py, s)?)?,
        None => d.set_item("solution", py.None())?,
    }
    let guesses = file
        .guesses
        .into_iter()
        .map(|g| stored_to_dict(py, g))
        .collect::<PyResult<Vec<_>>>()?;
    d.set_item("guesses", guesses)?;
    Ok(d)
}

/// Writes `problem` (and optionally a solution r, u, v and info strings) as FCLIB, atomically:
/// the bytes go to a temporary file in the same directory, renamed over `path` once complete.
#[pyfunction]
#[pyo3(signature = (path, problem, r=None, u=None, v=None, info=None))]
fn fclib_write(
    py: Python<'_>,
    path: PathBuf,
    problem: &PyProblem,
    r: Option<PyReadonlyArray1<'_, f64>>,
    u: Option<PyReadonlyArray1<'_, f64>>,
    v: Option<PyReadonlyArray1<'_, f64>>,
    info: Option<(String, String, String)>,
) -> PyResult<()> {
    let mut file = FclibFile::new((*problem.inner).clone());
    file.info = info.map(|(title, description, math_info)| Info {
        title,
        description,
        math_info,
    });
    if let Some(r) = r {
        let s = StoredSolution {
            r: owned("r", &r)?,
            u: u.map(|x| owned("u", &x)).transpose()?,
            v: v.map(|x| owned("v", &x)).transpose()?,
            l: None,
        };
        s.check_lengths(&file.problem)
            .map_err(|e| errors::evaluate_error(py, &e))?;
        file.solution = Some(s);
    } else if u.is_some() || v.is_some() {
        return Err(errors::input_error(
            py,
            "r",
            None,
            "a stored solution needs r".into(),
        ));
    }
    let name = path.display().to_string();
    let bytes = fclib::to_bytes(&file, &Default::default()).map_err(|e| {
        errors::fclib_error(
            py,
            fclib::FclibError {
                file: name.clone(),
                kind: e.kind,
            },
        )
    })?;
    let io = |e: std::io::Error| errors::fclib_error(py, fclib::FclibError::new(&name, e.into()));
    // coulomb::atomic: temporary file beside the destination, rename; a destination that
    // is not a regular file (device, FIFO, directory, dangling link) is refused
    py.detach(|| coulomb::atomic::write(&path, &bytes))
        .map_err(io)
}

/// The compiled module `coulomb._coulomb`.
#[pymodule]
fn _coulomb(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyProblem>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(default_settings, m)?)?;
    m.add_function(wrap_pyfunction!(resolve_settings, m)?)?;
    m.add_function(wrap_pyfunction!(error, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(scene::scene_fill, m)?)?;
    m.add_function(wrap_pyfunction!(scene::scene_save, m)?)?;
    m.add_function(wrap_pyfunction!(scene::urdf_robot, m)?)?;
    m.add_function(wrap_pyfunction!(fclib_read, m)?)?;
    m.add_function(wrap_pyfunction!(fclib_write, m)?)?;
    m.add_class::<granular::PySimulation>()?;
    m.add_class::<rigid::PyRigidSimulation>()?;
    m.add_function(wrap_pyfunction!(rigid::_checkpoint_is_rigid, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
