//! The library's typed errors as Python exceptions (classes defined in `coulomb/_errors.py`).
//!
//! Every error carries what the Rust error says: the field (`"W"`, `"q"`, `"mu"`, ...), the
//! index where there is one (an int, or a `(row, col)` tuple), and a `kind` naming the variant.

use coulomb::fclib::{EvaluateError, FclibError, FclibErrorKind};
use coulomb::problem::ProblemError;
use coulomb::solver::SolveError;
use coulomb::sparse::SparseError;
use pyo3::exceptions::{
    PyFileNotFoundError, PyIsADirectoryError, PyOSError, PyPermissionError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// An instance of `coulomb._errors.<class>` with message `msg` and attributes `attrs`;
/// a plain `ValueError` if the Python package is not importable.
fn raise(py: Python<'_>, class: &str, msg: String, attrs: Vec<(&str, Py<PyAny>)>) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let cls = py.import("coulomb._errors")?.getattr(class)?;
        let exc = cls.call1((msg.clone(),))?;
        for (name, value) in attrs {
            exc.setattr(name, value)?;
        }
        Ok(PyErr::from_value(exc))
    };
    build().unwrap_or_else(|_| PyValueError::new_err(msg))
}

fn obj<'py, T: IntoPyObject<'py>>(py: Python<'py>, x: T) -> Py<PyAny> {
    use pyo3::BoundObject;
    match x.into_pyobject(py) {
        Ok(b) => b.into_any().unbind(),
        Err(_) => py.None(),
    }
}

/// `"index 5"` → 5, `"(3, 4)"` → (3, 4), as written by the library's validation.
fn parse_location(py: Python<'_>, location: &str) -> Py<PyAny> {
    if let Some(i) = location
        .strip_prefix("index ")
        .and_then(|s| s.parse::<usize>().ok())
    {
        return obj(py, i);
    }
    let inner = location.trim_start_matches('(').trim_end_matches(')');
    let parts: Vec<Option<usize>> = inner.split(',').map(|s| s.trim().parse().ok()).collect();
    if let [Some(r), Some(c)] = parts[..] {
        if let Ok(t) = PyTuple::new(py, [r, c]) {
            return t.into_any().unbind();
        }
    }
    obj(py, location)
}

/// The Debug name of an enum variant in snake_case (`NonFinite { .. }` → `non_finite`).
pub(crate) fn variant_name<E: std::fmt::Debug>(e: &E) -> String {
    let debug = format!("{e:?}");
    let name: String = debug.chars().take_while(|c| c.is_alphanumeric()).collect();
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            out.push('_');
        }
        out.extend(c.to_lowercase());
    }
    out
}

/// An error of a variant this module does not know (added to the library later): its
/// message and variant name.
fn variant_error<E: std::fmt::Debug + std::fmt::Display>(
    py: Python<'_>,
    class: &str,
    e: &E,
) -> PyErr {
    raise(
        py,
        class,
        e.to_string(),
        vec![
            ("kind", obj(py, variant_name(e))),
            ("field", py.None()),
            ("index", py.None()),
        ],
    )
}

/// [`ProblemError`] → `coulomb.ProblemError` (a `ValueError`) with `kind`, `field`, `index`.
pub fn problem_error(py: Python<'_>, e: &ProblemError) -> PyErr {
    let msg = e.to_string();
    let (kind, field, index): (&str, &str, Py<PyAny>) = match e {
        ProblemError::Dimension(_) => ("dimension", "dim", py.None()),
        ProblemError::Shape { what, .. } => ("shape", what, py.None()),
        ProblemError::NonFinite { what, location } => {
            ("non_finite", what, parse_location(py, location))
        }
        ProblemError::Friction { contact, .. } => ("friction", "mu", obj(py, *contact)),
        ProblemError::NotPositiveSemidefinite { what, .. } => {
            ("not_positive_semidefinite", what, py.None())
        }
        ProblemError::NotPositiveDefinite(_) => ("not_positive_definite", "M", py.None()),
        ProblemError::Sparse { what, source } => {
            let index = match source {
                SparseError::IndexOutOfRange { entry, .. } => obj(py, *entry),
                _ => py.None(),
            };
            ("sparse", what, index)
        }
        // a variant added to the library: its name, no field
        #[allow(unreachable_patterns)]
        _ => return variant_error(py, "ProblemError", e),
    };
    raise(
        py,
        "ProblemError",
        msg,
        vec![
            ("kind", obj(py, kind)),
            ("field", obj(py, field)),
            ("index", index),
        ],
    )
}

/// A bad keyword setting → `coulomb.SettingsError` (a `ValueError`) naming the setting.
pub fn settings_error(py: Python<'_>, field: &str, msg: String) -> PyErr {
    raise(
        py,
        "SettingsError",
        msg,
        vec![("field", obj(py, field)), ("index", py.None())],
    )
}

/// A bad argument array (r0, v0, r, v) → `coulomb.InputError` (a `ValueError`).
pub fn input_error(py: Python<'_>, field: &str, index: Option<usize>, msg: String) -> PyErr {
    let index = index.map_or_else(|| py.None(), |i| obj(py, i));
    raise(
        py,
        "InputError",
        msg,
        vec![("field", obj(py, field)), ("index", index)],
    )
}

/// [`SolveError`] → the matching Python exception.
pub fn solve_error(py: Python<'_>, e: &SolveError) -> PyErr {
    match e {
        SolveError::Problem(p) => problem_error(py, p),
        SolveError::Settings(m) => {
            // the library names the setting first ("tol must be ...")
            let field = m.split_whitespace().next().unwrap_or("settings");
            settings_error(py, field, e.to_string())
        }
        SolveError::Guess(m) => {
            let field = if m.starts_with('v') { "v0" } else { "r0" };
            input_error(py, field, None, e.to_string())
        }
        #[allow(unreachable_patterns)]
        _ => variant_error(py, "CoulombError", e),
    }
}

/// [`EvaluateError`] → `InputError` (lengths, missing v) or `ProblemError`.
pub fn evaluate_error(py: Python<'_>, e: &EvaluateError) -> PyErr {
    match e {
        EvaluateError::Length { what, .. } => input_error(py, what, None, e.to_string()),
        EvaluateError::MissingVelocity => input_error(py, "v", None, e.to_string()),
        EvaluateError::MissingMultipliers => input_error(py, "l", None, e.to_string()),
        EvaluateError::Problem(p) => problem_error(py, p),
        #[allow(unreachable_patterns)]
        _ => variant_error(py, "InputError", e),
    }
}

/// [`FclibError`] → `OSError` (with errno and file name) for I/O failures, otherwise
/// `coulomb.FclibError` (a `ValueError`) with `file`, `path` (the HDF5 object) and `kind`;
/// for an invalid problem also the `field` and `index` of the [`ProblemError`].
pub fn fclib_error(py: Python<'_>, e: FclibError) -> PyErr {
    let msg = e.to_string();
    let path = e.object_path().map(str::to_string);
    let FclibError { file, kind } = e;
    let (kind_name, field, index): (&str, Py<PyAny>, Py<PyAny>) = match &kind {
        FclibErrorKind::Io(io) => {
            let args = (io.raw_os_error().unwrap_or(0), io.to_string(), file.clone());
            return match io.kind() {
                std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(args),
                std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(args),
                std::io::ErrorKind::IsADirectory => PyIsADirectoryError::new_err(args),
                _ => PyOSError::new_err(args),
            };
        }
        FclibErrorKind::Input(reason) => {
            let path = std::path::PathBuf::from(&file);
            return match reason {
                coulomb::input::InputReason::Open(io) | coulomb::input::InputReason::Read(io) => {
                    os_error(io, &path)
                }
                coulomb::input::InputReason::NotRegular(coulomb::atomic::NotRegular::Directory) => {
                    PyIsADirectoryError::new_err((21, msg, file))
                }
                _ => input_error(py, "path", None, msg),
            };
        }
        FclibErrorKind::NotHdf5 => ("not_hdf5", py.None(), py.None()),
        FclibErrorKind::Corrupt { .. } => ("corrupt", py.None(), py.None()),
        FclibErrorKind::MissingGroup { .. } => ("missing_group", py.None(), py.None()),
        FclibErrorKind::MissingDataset { .. } => ("missing_dataset", py.None(), py.None()),
        FclibErrorKind::WrongType { .. } => ("wrong_type", py.None(), py.None()),
        FclibErrorKind::WrongLength { .. } => ("wrong_length", py.None(), py.None()),
        FclibErrorKind::BadValue { .. } => ("bad_value", py.None(), py.None()),
        FclibErrorKind::Unsupported { .. } => ("unsupported", py.None(), py.None()),
        FclibErrorKind::InvalidProblem { source, .. } => {
            // reuse the field/index extraction of the problem error
            let pe = problem_error(py, source);
            let (field, index) = field_and_index(py, &pe);
            ("invalid_problem", field, index)
        }
        FclibErrorKind::Write { .. } => ("write", py.None(), py.None()),
        #[allow(unreachable_patterns)]
        _ => ("other", py.None(), py.None()),
    };
    raise(
        py,
        "FclibError",
        msg,
        vec![
            ("file", obj(py, file)),
            ("path", obj(py, path)),
            ("kind", obj(py, kind_name)),
            ("field", field),
            ("index", index),
        ],
    )
}

/// An error of a Python-built scene → `coulomb.SceneError` (a `ValueError`) with `kind`,
/// `field` (the datum: `"radii"`, `"material"`, `"triangles"`, ...) and `index` (an int, a
/// pair, or None).
pub fn scene_input_error(
    py: Python<'_>,
    kind: &str,
    field: Option<&str>,
    index: Py<PyAny>,
    msg: String,
) -> PyErr {
    let field = field.map_or_else(|| py.None(), |f| obj(py, f));
    raise(
        py,
        "SceneError",
        msg,
        vec![("kind", obj(py, kind)), ("field", field), ("index", index)],
    )
}

/// The index `I` of `"… sphere I"` / `"sphere I …"` in a scene error's location, if any.
fn sphere_index(what: &str) -> Option<usize> {
    let rest = &what[what.rfind("sphere ")? + "sphere ".len()..];
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    digits.parse().ok()
}

/// The datum a body error's reason names (`"radius nan is not …"` → `radii`).
fn body_field(reason: &str) -> &'static str {
    let first = reason.split_whitespace().next().unwrap_or("");
    match first {
        "radius" | "radii" => "radii",
        "mass" | "masses" => "masses",
        "density" => "density",
        "velocities" => "velocities",
        "angular_velocities" => "angular_velocities",
        "fixed" | "a" => "fixed",
        "give" => "density",
        _ => "positions",
    }
}

/// [`coulomb_granular::SceneError`] → `coulomb.SceneError` with the message of the Rust error
/// and the datum it is about.
pub fn scene_error(py: Python<'_>, e: &coulomb_granular::SceneError) -> PyErr {
    use coulomb_granular::{MeshError, SceneError as E};
    let msg = e.to_string();
    let none = || py.None();
    let (field, index): (Option<&str>, Py<PyAny>) = match e {
        E::UnknownMaterial { what, .. } => (
            Some(if what.starts_with("material pair") {
                "material_pair"
            } else {
                "material"
            }),
            none(),
        ),
        E::DuplicateMaterial(_) => (Some("material"), none()),
        E::InvalidLaw { reason, .. } => {
            let first = reason.split_whitespace().next().unwrap_or("");
            let f = match first {
                "mu" | "restitution" | "rolling_friction" => first,
                _ if reason.contains("mu =") => "mu",
                _ if reason.contains("restitution") => "restitution",
                _ if reason.contains("rolling") => "rolling_friction",
                _ => "material_pair",
            };
            (Some(f), none())
        }
        E::InvalidBody { what, reason } => (
            Some(body_field(reason)),
            sphere_index(what).map_or_else(none, |i| obj(py, i)),
        ),
        E::InvalidObstacle { index, .. } => (Some("obstacles"), obj(py, *index)),
        E::Mesh { source, .. } => {
            let (f, i) = match source {
                MeshError::NonFiniteVertex { vertex } => ("vertices", obj(py, *vertex)),
                MeshError::IndexOutOfRange { triangle, .. }
                | MeshError::Degenerate { triangle, .. } => ("triangles", obj(py, *triangle)),
                _ => ("triangles", none()),
            };
            (Some(f), i)
        }
        E::InvalidStep(reason) => (reason.split_whitespace().next(), none()),
        E::InvalidGravity(_) => (Some("gravity"), none()),
        E::Overlaps { pair, .. } => (Some("positions"), obj(py, *pair)),
        E::Penetration { sphere, .. } => (Some("positions"), obj(py, *sphere)),
        E::Outside { what, .. } => (
            Some("positions"),
            sphere_index(what).map_or_else(none, |i| obj(py, i)),
        ),
        E::Memory { .. } => (None, none()),
        #[allow(unreachable_patterns)]
        _ => (None, none()),
    };
    scene_input_error(py, &variant_name(e), field, index, msg)
}

/// [`coulomb_granular::scene_file::SceneFileError`] → `OSError` when the file cannot be read,
/// otherwise `coulomb.SceneError` with the message (file:line:column: key: what) and `kind`
/// (`extension`, `syntax`, `invalid`, `import`, or the model's variant with its `field` and
/// `index`).
pub fn scene_file_error(py: Python<'_>, e: &coulomb_granular::scene_file::SceneFileError) -> PyErr {
    use coulomb_granular::scene_file::SceneFileError as E;
    let msg = e.to_string();
    match e {
        E::Io { path, source } => os_error(source, path),
        E::Input(i) => input_file_error(py, i),
        E::Import {
            source: coulomb_granular::import::ImportError::Input(i),
            ..
        } => input_file_error(py, i),
        E::Urdf { source, .. }
            if matches!(**source, coulomb_granular::urdf::UrdfError::Input(_)) =>
        {
            crate::scene::urdf_error(py, source)
        }
        E::Urdf { key, .. } => scene_input_error(py, "urdf", Some(key), py.None(), msg),
        E::Model { source, .. } => {
            let err = scene_error(py, source);
            // the model's field and index, the message with the file's name
            let (field, index) = field_and_index(py, &err);
            let field: Option<String> = field.extract(py).ok();
            scene_input_error(py, &variant_name(source), field.as_deref(), index, msg)
        }
        E::Invalid { key, .. } => scene_input_error(py, "invalid", Some(key), py.None(), msg),
        E::Import { key, .. } => scene_input_error(py, "import", Some(key), py.None(), msg),
        _ => scene_input_error(py, &variant_name(e), None, py.None(), msg),
    }
}

/// [`coulomb_granular::CheckpointError`] → `OSError` (with errno and file name) for I/O
/// failures, otherwise `coulomb.CheckpointError` (a `ValueError`) with `file`, `path` (the
/// HDF5 object, where known) and `kind` (`not_hdf5`, `wrong_format`, `version`, `corrupt`,
/// `checksum`, `invalid`, `unrepresentable`).
pub fn checkpoint_error(py: Python<'_>, e: coulomb_granular::CheckpointError) -> PyErr {
    use coulomb_granular::CheckpointError as E;
    let msg = e.to_string();
    let shown = |p: &std::path::Path| Some(p.display().to_string());
    let (kind, file, path) = match &e {
        E::Io { path, source } => {
            return os_error(source, path);
        }
        E::Input(i) => return input_file_error(py, i),
        E::NotHdf5 { path } => ("not_hdf5", shown(path), None),
        E::WrongFormat { path, .. } => ("wrong_format", shown(path), None),
        E::Version { path, .. } => ("version", shown(path), None),
        E::Corrupt { path, location, .. } => ("corrupt", shown(path), Some(location.clone())),
        E::Checksum { path, dataset, .. } => (
            "checksum",
            shown(path),
            dataset.as_ref().map(|d| format!("/{d}")),
        ),
        E::Invalid { path, location, .. } => ("invalid", shown(path), Some(location.clone())),
        E::Unrepresentable(_) => ("unrepresentable", None, None),
        #[allow(unreachable_patterns)]
        _ => ("other", None, None),
    };
    raise(
        py,
        "CheckpointError",
        msg,
        vec![
            ("file", obj(py, file)),
            ("path", obj(py, path)),
            ("kind", obj(py, kind)),
        ],
    )
}

/// The `field` and `index` attributes of a raised error of this package (None where absent).
fn field_and_index(py: Python<'_>, err: &PyErr) -> (Py<PyAny>, Py<PyAny>) {
    let v = err.value(py);
    let get = |name: &str| v.getattr(name).map_or_else(|_| py.None(), |x| x.unbind());
    (get("field"), get("index"))
}

/// An input that could not be read ([`coulomb::input`]): a failure to open it as the matching
/// `OSError` subclass (errno, message, file name), a directory as `IsADirectoryError`;
/// a FIFO, a device, a socket, a file over its kind's size limit or text that is not UTF-8
/// as `coulomb.InputError` (a `ValueError`) with `field` = `"path"` and the message naming
/// the file and what it is.
pub fn input_file_error(py: Python<'_>, e: &coulomb::input::InputError) -> PyErr {
    use coulomb::input::InputReason;
    match &e.reason {
        InputReason::Open(io) | InputReason::Read(io) => os_error(io, &e.path),
        InputReason::NotRegular(coulomb::atomic::NotRegular::Directory) => {
            PyIsADirectoryError::new_err((21, e.to_string(), e.path.display().to_string()))
        }
        _ => input_error(py, "path", None, e.to_string()),
    }
}

/// An operating-system failure on `path` as the matching `OSError` subclass, with errno, the
/// message and the file name.
pub(crate) fn os_error(source: &std::io::Error, path: &std::path::Path) -> PyErr {
    let args = (
        source.raw_os_error().unwrap_or(0),
        source.to_string(),
        path.display().to_string(),
    );
    match source.kind() {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(args),
        std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(args),
        std::io::ErrorKind::IsADirectory => PyIsADirectoryError::new_err(args),
        _ => PyOSError::new_err(args),
    }
}

/// An error of the output-folder layer (`coulomb_granular::output_dir`) on `dir`: a refused
/// name (a link, folder or special file where an output goes) → `ValueError` with the
/// message; other I/O failures → the matching `OSError`.
pub(crate) fn output_error(e: std::io::Error, dir: &std::path::Path) -> PyErr {
    match coulomb::atomic::refusal(&e) {
        Some(r) => PyValueError::new_err(r.to_string()),
        None => os_error(&e, dir),
    }
}
