//! Every conversion between the library's types and Python objects, in one place:
//! CSC arrays → [`CscMatrix`], keyword arguments → [`Settings`], [`Solution`] → dict.
//! When the library gains a `Settings` or `Solution` field, this file is the one to edit.

use crate::errors;
use coulomb::problem::ProblemError;
use coulomb::settings::ParseMethodError;
use coulomb::solver::{InnerKind, Method, OuterKind, Settings, Solution, Status};
use coulomb::sparse::{CscMatrix, SparseError};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::{PyRuntimeError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::time::Duration;

/// A read-only view of a 1-D integer array of either width (scipy uses int32 for small
/// matrices, int64 for large ones): read without converting the array on the Python side.
enum Indices<'py> {
    I32(PyReadonlyArray1<'py, i32>),
    I64(PyReadonlyArray1<'py, i64>),
}

impl<'py> Indices<'py> {
    fn extract(what: &str, x: &Bound<'py, PyAny>) -> PyResult<Self> {
        if let Ok(a) = x.extract::<PyReadonlyArray1<'py, i64>>() {
            return Ok(Indices::I64(a));
        }
        if let Ok(a) = x.extract::<PyReadonlyArray1<'py, i32>>() {
            return Ok(Indices::I32(a));
        }
        Err(PyTypeError::new_err(format!(
            "{what}: expected a 1-D int32 or int64 numpy array"
        )))
    }

    /// The indices as `usize`; the position of the first negative one is an error.
    fn to_usize(&self) -> Result<Vec<usize>, usize> {
        fn conv<T: Copy + TryInto<usize>>(s: &[T]) -> Result<Vec<usize>, usize> {
            s.iter()
                .enumerate()
                .map(|(k, &x)| x.try_into().map_err(|_| k))
                .collect()
        }
        match self {
            Indices::I32(a) => conv(a.as_slice().unwrap_or(&[])),
            Indices::I64(a) => conv(a.as_slice().unwrap_or(&[])),
        }
    }

    fn value_at(&self, k: usize) -> i64 {
        match self {
            Indices::I32(a) => a.as_slice().map_or(0, |s| s[k] as i64),
            Indices::I64(a) => a.as_slice().map_or(0, |s| s[k]),
        }
    }
}

/// A contiguous float64 vector as a slice (the Python layer passes `np.ascontiguousarray`).
pub fn slice<'a>(what: &str, a: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    a.as_slice()
        .map_err(|_| PyTypeError::new_err(format!("{what}: expected a contiguous float64 array")))
}

/// Builds a [`CscMatrix`] named `what` from `(nrows, ncols, indptr, indices, data)`: the
/// arrays of a `scipy.sparse.csc_array`, unsorted or duplicated entries allowed (summed).
/// Errors are the library's [`ProblemError::Sparse`].
pub fn csc_from_arrays(
    py: Python<'_>,
    what: &'static str,
    m: &Bound<'_, PyTuple>,
) -> PyResult<CscMatrix> {
    if m.len() != 5 {
        return Err(PyTypeError::new_err(format!(
            "{what}: expected (nrows, ncols, indptr, indices, data)"
        )));
    }
    let nrows: i64 = m.get_item(0)?.extract()?;
    let ncols: i64 = m.get_item(1)?.extract()?;
    let sparse = |source| errors::problem_error(py, &ProblemError::Sparse { what, source });
    let (Ok(nrows), Ok(ncols)) = (usize::try_from(nrows), usize::try_from(ncols)) else {
        return Err(errors::problem_error(
            py,
            &ProblemError::Shape {
                what,
                expected: "nonnegative dimensions".into(),
                found: format!("{nrows} x {ncols}"),
            },
        ));
    };
    let indptr = Indices::extract(what, &m.get_item(2)?)?;
    let indices = Indices::extract(what, &m.get_item(3)?)?;
    let data: PyReadonlyArray1<'_, f64> = m.get_item(4)?.extract()?;
    let data = slice(what, &data)?;
    let col_ptr = indptr.to_usize().map_err(|k| {
        sparse(SparseError::BadPointers(format!(
            "pointer {k} is negative ({})",
            indptr.value_at(k)
        )))
    })?;
    let row_idx = indices.to_usize().map_err(|k| {
        sparse(SparseError::IndexOutOfRange {
            entry: k,
            index: indices.value_at(k),
            dim: nrows,
        })
    })?;
    CscMatrix::from_csc_arrays(nrows, ncols, &col_ptr, &row_idx, data).map_err(sparse)
}

/// A [`CscMatrix`] as `(nrows, ncols, indptr, indices, data)` numpy arrays (int64 indices).
pub fn csc_to_tuple<'py>(py: Python<'py>, a: &CscMatrix) -> PyResult<Bound<'py, PyTuple>> {
    let p: Vec<i64> = a.col_ptr.iter().map(|&x| x as i64).collect();
    let i: Vec<i64> = a.row_idx.iter().map(|&x| x as i64).collect();
    PyTuple::new(
        py,
        [
            a.nrows.into_pyobject(py)?.into_any(),
            a.ncols.into_pyobject(py)?.into_any(),
            PyArray1::from_vec(py, p).into_any(),
            PyArray1::from_vec(py, i).into_any(),
            PyArray1::from_slice(py, &a.values).into_any(),
        ],
    )
}

fn inner_name(k: InnerKind) -> &'static str {
    k.as_str()
}

fn outer_name(k: OuterKind) -> &'static str {
    k.as_str()
}

/// A library name (`FromStr` of [`InnerKind`], [`OuterKind`], [`Method`]: the spelling of the
/// CLI too), a `SettingsError` on `field` when unknown.
fn parse_name<T: std::str::FromStr<Err = ParseMethodError>>(
    py: Python<'_>,
    field: &str,
    s: &str,
) -> PyResult<T> {
    s.parse().map_err(|e: ParseMethodError| {
        errors::settings_error(py, field, format!("{field} = {s:?}: {e}"))
    })
}

fn parse_inner(py: Python<'_>, field: &str, s: &str) -> PyResult<InnerKind> {
    parse_name(py, field, s)
}

fn parse_outer(py: Python<'_>, field: &str, s: &str) -> PyResult<OuterKind> {
    parse_name(py, field, s)
}

/// The names accepted by [`settings_from_kwargs`]: the fields of [`Settings`] and of its
/// method parameters [`Settings::params`] (`warmup_sweeps`, `barrier_steps`,
/// `fixed_point_tol`, `facets`, `inner_tol_factor`, `newton_steps`, `newton_start`) by
/// their own names, in the order of the settings' JSON (plus `method`, a shorthand for
/// [`Settings::method`]; [`coulomb::settings::Tuning`] is not reached).
pub const SETTINGS_NAMES: &[&str] = &[
    "tol",
    "inner",
    "outer",
    "fallback",
    "warmup_sweeps",
    "barrier_steps",
    "max_outer",
    "max_inner",
    "time_limit",
    "fixed_point_tol",
    "facets",
    "inner_tol_factor",
    "newton_steps",
    "newton_start",
];

/// The library's [`Settings`] as a flat dict, the method parameters among the other fields
/// (seconds for the time limit, `None` for unset options).
pub fn settings_to_dict<'py>(py: Python<'py>, s: &Settings) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("tol", s.tol)?;
    d.set_item("inner", inner_name(s.inner))?;
    d.set_item("outer", outer_name(s.outer))?;
    d.set_item(
        "fallback",
        s.fallback.map(|(i, o)| (inner_name(i), outer_name(o))),
    )?;
    d.set_item("warmup_sweeps", s.params.warmup_sweeps)?;
    d.set_item("barrier_steps", s.params.barrier_steps)?;
    d.set_item("max_outer", s.max_outer)?;
    d.set_item("max_inner", s.max_inner)?;
    d.set_item("time_limit", s.time_limit.map(|t| t.as_secs_f64()))?;
    d.set_item("fixed_point_tol", s.params.fixed_point_tol)?;
    d.set_item("facets", s.params.facets)?;
    d.set_item("inner_tol_factor", s.params.inner_tol_factor)?;
    d.set_item("newton_steps", s.params.newton_steps)?;
    d.set_item("newton_start", s.params.newton_start)?;
    Ok(d)
}

fn count(py: Python<'_>, name: &str, v: &Bound<'_, PyAny>) -> PyResult<usize> {
    let n: i64 = v
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be an int")))?;
    usize::try_from(n)
        .map_err(|_| errors::settings_error(py, name, format!("{name} = {n} must be >= 0")))
}

fn real(name: &str, v: &Bound<'_, PyAny>) -> PyResult<f64> {
    v.extract()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a float")))
}

fn text(name: &str, v: &Bound<'_, PyAny>) -> PyResult<String> {
    v.extract()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a str")))
}

/// A (inner, outer) pair from `"pgs+fused"` (a [`Method`] name; `"pgs"` alone is the plain
/// fixed point) or `("pgs", "fused")`.
fn method_pair(
    py: Python<'_>,
    name: &str,
    v: &Bound<'_, PyAny>,
) -> PyResult<(InnerKind, OuterKind)> {
    if let Ok(s) = v.extract::<String>() {
        return parse_name::<Method>(py, name, &s).map(Into::into);
    }
    let (i, o): (String, String) = v.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name} must be 'inner+outer' or a tuple (inner, outer)"
        ))
    })?;
    Ok((parse_inner(py, name, &i)?, parse_outer(py, name, &o)?))
}

/// [`Settings`] from keyword arguments: the library's defaults, `method` applied first
/// ([`Settings::method`]: that method alone, no warm-up, no fallback), then each named field.
/// An unknown name is a `TypeError` (as for any Python function); a value of the wrong type a
/// `TypeError`; a value out of range a `SettingsError` (the library's validation runs in
/// `solve`).
pub fn settings_from_kwargs(
    py: Python<'_>,
    func: &str,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<Settings> {
    let mut s = Settings::default();
    let Some(kw) = kwargs else { return Ok(s) };
    if let Some(m) = kw.get_item("method")? {
        if !m.is_none() {
            let (i, o) = method_pair(py, "method", &m)?;
            s = Settings::method(i, o);
        }
    }
    for (k, v) in kw.iter() {
        let name: String = k.extract()?;
        match name.as_str() {
            "method" => {}
            "tol" => {
                s.tol = real("tol", &v)?;
                coulomb::settings::check_tol(s.tol)
                    .map_err(|m| errors::settings_error(py, "tol", m))?;
            }
            "inner" => s.inner = parse_inner(py, "inner", &text("inner", &v)?)?,
            "outer" => s.outer = parse_outer(py, "outer", &text("outer", &v)?)?,
            "fallback" => {
                s.fallback = if v.is_none() {
                    None
                } else {
                    Some(method_pair(py, "fallback", &v)?)
                }
            }
            "warmup_sweeps" => s.params.warmup_sweeps = count(py, "warmup_sweeps", &v)?,
            "barrier_steps" => s.params.barrier_steps = count(py, "barrier_steps", &v)?,
            "max_outer" => s.max_outer = count(py, "max_outer", &v)?,
            "max_inner" => s.max_inner = count(py, "max_inner", &v)?,
            "time_limit" => {
                s.time_limit = if v.is_none() {
                    None
                } else {
                    let t = real("time_limit", &v)?;
                    let d = Duration::try_from_secs_f64(t).ok().filter(|_| t > 0.0);
                    Some(d.ok_or_else(|| {
                        errors::settings_error(
                            py,
                            "time_limit",
                            format!("time_limit = {t} must be a positive, finite number of seconds (or None)"),
                        )
                    })?)
                }
            }
            "fixed_point_tol" => {
                s.params.fixed_point_tol = if v.is_none() {
                    None
                } else {
                    Some(real("fixed_point_tol", &v)?)
                }
            }
            "facets" => s.params.facets = count(py, "facets", &v)?,
            "inner_tol_factor" => s.params.inner_tol_factor = real("inner_tol_factor", &v)?,
            "newton_steps" => s.params.newton_steps = count(py, "newton_steps", &v)?,
            "newton_start" => s.params.newton_start = real("newton_start", &v)?,
            other => {
                return Err(PyTypeError::new_err(format!(
                    "{func}() got an unexpected keyword argument '{other}' (settings: method, {})",
                    SETTINGS_NAMES.join(", ")
                )))
            }
        }
    }
    Ok(s)
}

/// The Python name of a [`Status`] (the value of the `coulomb.Status` enum): the library's
/// [`Status::as_str`].
pub fn status_name(s: Status) -> String {
    s.as_str().to_string()
}

/// A [`Solution`] as a dict; the vectors are moved into numpy arrays (no copy).
pub fn solution_to_dict(py: Python<'_>, sol: Solution) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("status", status_name(sol.status))?;
    d.set_item("converged", sol.converged())?;
    d.set_item("error", sol.error)?;
    d.set_item("balance_residual", sol.balance_residual)?;
    d.set_item("outer_iterations", sol.outer_iterations)?;
    d.set_item("inner_iterations", sol.inner_iterations)?;
    d.set_item("time", sol.solve_time.as_secs_f64())?;
    let h = &sol.history;
    let hist = PyDict::new(py);
    hist.set_item("error", PyArray1::from_iter(py, h.iter().map(|x| x.error)))?;
    hist.set_item(
        "fixed_point_residual",
        PyArray1::from_iter(py, h.iter().map(|x| x.fixed_point_residual)),
    )?;
    hist.set_item(
        "rule_6_1",
        PyArray1::from_iter(py, h.iter().map(|x| x.rule_6_1)),
    )?;
    hist.set_item(
        "inner_iterations",
        PyArray1::from_iter(py, h.iter().map(|x| x.inner_iterations as i64)),
    )?;
    d.set_item("history", hist)?;
    d.set_item("r", PyArray1::from_vec(py, sol.r))?;
    d.set_item("u", PyArray1::from_vec(py, sol.u))?;
    d.set_item("v", sol.v.map(|v| PyArray1::from_vec(py, v)))?;
    d.set_item("s", PyArray1::from_vec(py, sol.s))?;
    d.set_item("l", sol.l.map(|l| PyArray1::from_vec(py, l)))?;
    d.set_item("equality_residual", sol.equality_residual)?;
    Ok(d)
}

/// A list of float vectors (one per row) as a `(rows, 3)` array.
pub fn rows3<'py>(py: Python<'py>, rows: impl Iterator<Item = [f64; 3]>) -> Bound<'py, PyAny> {
    let flat: Vec<f64> = rows.flatten().collect();
    let n = flat.len() / 3;
    let a = PyArray1::from_vec(py, flat);
    a.reshape([n, 3])
        .map_or_else(|_| a.into_any(), |b| b.into_any())
}

/// The contacts of one step as Python's `Simulation.contacts`, for every scene: a list of
/// dicts `a`, `b` (`kind` "body" or "obstacle", `index`), `point`, `normal` (b → a), `t1`,
/// `gap`, `impulse` (r_N, r_T1, r_T2), an obstacle numbered by `obstacle` (the scene's
/// numbering) and named as a whole (not the wall of a box or the triangle of a mesh).
pub fn contacts_to_py<'py>(
    py: Python<'py>,
    contacts: &[coulomb_granular::Contact],
    obstacle: impl Fn(usize) -> usize,
) -> PyResult<Bound<'py, PyAny>> {
    use coulomb_granular::contact::ContactJson;
    use coulomb_granular::Partner;
    let c: Vec<ContactJson> = (contacts.iter())
        .map(|c| {
            let mut j = ContactJson::from(c);
            if let Partner::Obstacle(k, _) = c.partner {
                j.b = Partner::Obstacle(obstacle(k), 0);
            }
            j
        })
        .collect();
    let json = serde_json::to_value(c)
        .map_err(|e| PyRuntimeError::new_err(format!("cannot serialize: {e}")))?;
    json_to_py(py, &json)
}

/// A JSON value (from the library's `Serialize` impls) as Python objects.
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(f)) => f.into_pyobject(py)?.into_any(),
            _ => py.None().into_bound(py),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(a) => {
            if !a.is_empty() && a.iter().all(|x| x.is_number()) {
                PyArray1::from_iter(py, a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN))).into_any()
            } else {
                let l = PyList::empty(py);
                for x in a {
                    l.append(json_to_py(py, x)?)?;
                }
                l.into_any()
            }
        }
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}
