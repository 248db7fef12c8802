//! FCLIB, the frictional-contact community's HDF5 exchange format (one problem per file).
//!
//! # Layout
//! ```text
//! /fclib_local/{W}            /fclib_local/vectors/{q, mu}          local:  u = W r + q
//! /fclib_global/{M, H}        /fclib_global/vectors/{f, w, mu}      global: M v = H r + f, u = Hᵀ v + w
//! /fclib_global/G             /fclib_global/vectors/b               optional: M v = H r + G λ + f, Gᵀ v + b = 0
//! /fclib_*/spacedim           int32[1], d ∈ {2, 3}
//! /fclib_*/info/{title, description, math_info}     strings, optional
//! /solution/{v?, u?, r, l?}                         optional
//! /guesses/number_of_guesses, /guesses/k/{v?, u?, r, l?}   optional, k = 1..N
//! ```
//! The problem is stored in coulomb's one convention, which is FCLIB's (see
//! [`crate::problem`]): no sign or transpose changes happen here. Each contact block is
//! ordered normal first.
//!
//! A matrix group holds `m`, `n` (rows, columns), `nz`, `nzmax` and arrays `p`, `i`, `x`:
//! `nz == -1` is compressed sparse column (p: n + 1 column pointers, i: row indices),
//! `nz == -2` compressed sparse row (p: m + 1 row pointers, i: column indices), `nz >= 0`
//! triplets (i: rows, p: columns, nz entries, duplicates summed). Only the entries that the
//! pointers (or `nz`) use are read; `nzmax` and longer arrays are tolerated.
//!
//! # Reading
//! [`read`] / [`read_bytes`] accept int32 or int64 index arrays, float32 or float64 values,
//! unsorted or duplicated entries, and HDF5 datasets that were created but never written
//! (HDF5 returns their fill value, zero: `/solution/r` of Capsules-i125-1213 is such a
//! dataset). They are strict about everything else: sizes that disagree, indices out of
//! range, decreasing pointers, and the validation of [`crate::LocalProblem::new`] /
//! [`crate::GlobalProblem::new`] (½(W + Wᵀ) positive semidefinite, the symmetric part of M positive
//! definite, finite data, μ ≥ 0; W and M are kept exactly as stored, symmetric or not). The
//! bilateral (equality) constraints of a global problem, `/fclib_global/G` (n × p, any of the
//! three storages) with `/fclib_global/vectors/b` (p), are read into
//! [`crate::problem::Equality`] (both or neither; G's rows must be M's), and their multipliers
//! λ are `/solution/l` (length p). The local problem's optional equality constraints
//! (`/fclib_local/{V, R}`) are refused with [`FclibErrorKind::Unsupported`] rather than dropped.
//! Every failure is an [`FclibError`] naming the file and the HDF5 object; a malformed file
//! never panics (the HDF5 crate is `hdf5-pure`, pure Rust; see `docs/hdf5-crates.md`).
//!
//! # Writing
//! [`write()`] writes what Siconos writes: CSC storage (`nz = -1`), int32 indices, `m`, `n`,
//! `nz`, `nzmax`, `spacedim` as `int32[1]`, fixed-length strings for info. [`write_with`]
//! takes [`WriteOptions`] for CSR or triplet storage and int64 indices. h5py (libhdf5)
//! reads the files.

mod error;
mod read;
mod write;

pub use error::{FclibError, FclibErrorKind};

use crate::delassus::Delassus;
use crate::law::norm;
use crate::problem::{Problem, ProblemError};
use std::path::Path;

/// `/fclib_*/info`: free text describing the problem. Absent strings read as empty.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Info {
    /// short name
    pub title: String,
    /// how the problem was produced
    pub description: String,
    /// mathematical properties, if the producer knew any (often empty or "unknown")
    pub math_info: String,
}

/// A stored (reference or initial-guess) solution: `/solution` or `/guesses/k`.
///
/// FCLIB's C library always writes u and r, and v for global problems. Here only r is
/// required: u is never trusted (the error of `docs/error.md` recomputes it from r or v),
/// and the files in the wild are not uniform. When read together with a problem, r and u
/// have length m = d · contacts and v (when present and the problem is global) has length n.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StoredSolution {
    /// velocities (global problems), length n
    pub v: Option<Vec<f64>>,
    /// local velocities, length m
    pub u: Option<Vec<f64>>,
    /// local impulses (reactions), length m
    pub r: Vec<f64>,
    /// multipliers λ of the equality (bilateral) constraints of a global problem, length p
    pub l: Option<Vec<f64>>,
}

/// The contents of one FCLIB file.
#[derive(Debug, Clone, PartialEq)]
pub struct FclibFile {
    /// the problem, validated
    pub problem: Problem,
    /// `/fclib_*/info`, when present
    pub info: Option<Info>,
    /// `/solution`, when present (data, not truth: check it with [`evaluate`])
    pub solution: Option<StoredSolution>,
    /// `/guesses/1 .. /guesses/N`, in order
    pub guesses: Vec<StoredSolution>,
}

impl FclibFile {
    /// A file holding only `problem`.
    pub fn new(problem: Problem) -> Self {
        Self {
            problem,
            info: None,
            solution: None,
            guesses: Vec::new(),
        }
    }
}

/// Sparse storage used when writing a matrix group.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Storage {
    /// compressed sparse column, `nz = -1` (what Siconos writes)
    #[default]
    Csc,
    /// compressed sparse row, `nz = -2` (what LMGC90 writes for W)
    Csr,
    /// triplets, `nz` = number of entries
    Triplet,
}

/// Integer width of the index arrays `p` and `i` when writing (`m`, `n`, `nz`, `nzmax`,
/// `spacedim` are always `int32[1]`, as FCLIB specifies).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IndexWidth {
    /// int32 (what Siconos writes)
    #[default]
    Int32,
    /// int64
    Int64,
}

/// How [`write_with`] stores matrices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WriteOptions {
    /// sparse storage of W, M and H
    pub storage: Storage,
    /// width of the index arrays
    pub index: IndexWidth,
}

/// Options of [`read_with`]. The problem is always read exactly as stored: a W or M that is
/// not exactly symmetric (several real files: Capsules-i101-404, relative asymmetry 5.97e-4;
/// Capsules-i125-1213, 1.34e-3; OneObject-i1028-138, 1.15e-4; Rover1039, 9.16e-6; Rover4396,
/// 2.56e-5) is valid data and is never replaced by ½(A + Aᵀ).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct ReadOptions {}

fn file_name(path: &Path) -> String {
    path.display().to_string()
}

/// The bytes of the FCLIB file `path`, read through the checked reader of [`crate::input`]
/// (a regular file of at most [`crate::input::Kind::Fclib`]'s limit).
fn read_input(path: &Path) -> Result<Vec<u8>, FclibError> {
    crate::input::read(path, crate::input::Kind::Fclib)
        .map_err(|e| FclibError::new(file_name(path), FclibErrorKind::Input(e.reason)))
}

/// Reads an FCLIB file: the problem (validated strictly), info, solution and guesses.
pub fn read(path: &Path) -> Result<FclibFile, FclibError> {
    read_with(path, &ReadOptions::default())
}

/// Reads an FCLIB file with the given options.
pub fn read_with(path: &Path, options: &ReadOptions) -> Result<FclibFile, FclibError> {
    let name = file_name(path);
    let bytes = read_input(path)?;
    read_bytes_with(&name, bytes, options)
}

/// Reads an FCLIB file from memory (strict validation); `name` is used in error messages.
pub fn read_bytes(name: &str, bytes: Vec<u8>) -> Result<FclibFile, FclibError> {
    read_bytes_with(name, bytes, &ReadOptions::default())
}

/// Reads an FCLIB file from memory with the given options.
pub fn read_bytes_with(
    name: &str,
    bytes: Vec<u8>,
    options: &ReadOptions,
) -> Result<FclibFile, FclibError> {
    read::Reader::open(name, bytes)?.fclib_file(options)
}

/// Like [`read_with`], but stored solutions are data, not truth: a `/solution` or `/guesses`
/// group that cannot be read (wrong lengths, NaN, wrong types, …) is left out of the result
/// and its error returned in the list, instead of failing the read. The problem itself is
/// validated as strictly as by [`read_with`].
pub fn read_lenient(
    path: &Path,
    options: &ReadOptions,
) -> Result<(FclibFile, Vec<FclibError>), FclibError> {
    let name = file_name(path);
    let bytes = read_input(path)?;
    let mut dropped = Vec::new();
    let file = read::Reader::open(&name, bytes)?.fclib_file_with(options, Some(&mut dropped))?;
    Ok((file, dropped))
}

/// Reads only `/solution` of a file (for instance one written by `coulomb solve`), without
/// checking it against a problem; `Ok(None)` when the file has no `/solution` group.
/// Check the lengths with [`StoredSolution::check_lengths`] before use.
pub fn read_solution(path: &Path) -> Result<Option<StoredSolution>, FclibError> {
    let name = file_name(path);
    let bytes = read_input(path)?;
    let reader = read::Reader::open(&name, bytes)?;
    if !reader.has_group("solution")? {
        return Ok(None);
    }
    reader.solution("solution", None).map(Some)
}

/// Writes `file` in the default layout (CSC, int32 indices), replacing `path` atomically
/// ([`crate::atomic::write`]: a failed write leaves `path` as it was).
pub fn write(path: &Path, file: &FclibFile) -> Result<(), FclibError> {
    write_with(path, file, &WriteOptions::default())
}

/// Writes `file` with the given matrix storage and index width, replacing `path` atomically.
pub fn write_with(path: &Path, file: &FclibFile, options: &WriteOptions) -> Result<(), FclibError> {
    let name = file_name(path);
    let bytes = write::to_bytes_named(&name, file, options)?;
    crate::atomic::write(path, &bytes).map_err(|e| FclibError::new(&name, e.into()))
}

/// Serializes `file` to an in-memory HDF5 image (what [`write_with`] puts on disk).
pub fn to_bytes(file: &FclibFile, options: &WriteOptions) -> Result<Vec<u8>, FclibError> {
    write::to_bytes_named("<memory>", file, options)
}

/// Why a stored solution cannot be evaluated against a problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvaluateError {
    /// An array has the wrong length for the problem.
    #[error("{what} has {found} entries, the problem needs {expected}")]
    Length {
        /// `r`, `u` or `v`
        what: &'static str,
        /// needed length
        expected: usize,
        /// stored length
        found: usize,
    },
    /// A global problem's solution without velocities v.
    #[error("the solution of a global problem has no velocities v")]
    MissingVelocity,
    /// The solution of a global problem with equality constraints has no multipliers λ
    /// (`/solution/l`): its balance residual cannot be computed.
    #[error("the solution of a problem with equality constraints has no multipliers l")]
    MissingMultipliers,
    /// The Delassus form could not be built (M not positive definite).
    #[error("{0}")]
    Problem(#[from] ProblemError),
}

impl StoredSolution {
    /// Checks r, u (length m = d · contacts) and, for a global problem, v (length n).
    pub fn check_lengths(&self, problem: &Problem) -> Result<(), EvaluateError> {
        let m = problem.dim() * problem.contacts();
        let check = |what, found: usize, expected| {
            if found == expected {
                Ok(())
            } else {
                Err(EvaluateError::Length {
                    what,
                    expected,
                    found,
                })
            }
        };
        check("r", self.r.len(), m)?;
        if let Some(u) = &self.u {
            check("u", u.len(), m)?;
        }
        if let (Some(v), Some(n)) = (&self.v, problem.dofs()) {
            check("v", v.len(), n)?;
        }
        if let (Some(l), Problem::Global(g)) = (&self.l, problem) {
            if g.equality.is_some() {
                check("l", l.len(), g.equality_rows())?;
            }
        }
        Ok(())
    }
}

/// The evaluation of a candidate solution has its own module, shared with the solver.
pub use crate::evaluation::Evaluation;

/// Evaluates a stored solution against `problem` with the error of `docs/error.md`:
/// local, u = W r + q recomputed from r; global, u = Hᵀ v + w recomputed from the stored v,
/// the scale uses the Delassus vector q = Hᵀ M⁻¹ f + w, and the balance residual
/// ‖M v − H r − f‖ / max(1, ‖f‖) is reported. With equality constraints the stored λ (`l`,
/// required) enters the balance residual ‖M v − H r − G λ − f‖ / max(1, ‖f‖), the equality
/// residual ‖Gᵀ v + b‖ / max(1, ‖b‖) is reported, and the scale uses the reduced Delassus
/// vector q̃ ([`crate::equality`]). A stored u is never used.
pub fn evaluate(problem: &Problem, solution: &StoredSolution) -> Result<Evaluation, EvaluateError> {
    evaluate_with_velocity(problem, solution).map(|(_, e)| e)
}

/// [`evaluate`], with the relative velocity u it recomputed (u = W r + q, or u = Hᵀ v + w
/// from the stored v): the (uⁱ, rⁱ) whose natural-map residuals eᵢ make up the error.
pub fn evaluate_with_velocity(
    problem: &Problem,
    solution: &StoredSolution,
) -> Result<(Vec<f64>, Evaluation), EvaluateError> {
    solution.check_lengths(problem)?;
    match problem {
        Problem::Local(p) => Ok(crate::evaluation::local(p, &solution.r, norm(&p.q))),
        Problem::Global(p) => {
            let v = solution
                .v
                .as_deref()
                .ok_or(EvaluateError::MissingVelocity)?;
            if p.equality.is_some() {
                let l = solution
                    .l
                    .as_deref()
                    .ok_or(EvaluateError::MissingMultipliers)?;
                let reduction = crate::equality::Reduction::new(p)?;
                return Ok(crate::evaluation::global_with(
                    p,
                    v,
                    &solution.r,
                    Some(l),
                    norm(&reduction.local.q),
                ));
            }
            let delassus = Delassus::new(p)?;
            Ok(crate::evaluation::global(
                p,
                v,
                &solution.r,
                norm(&delassus.local.q),
            ))
        }
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use crate::test_problems::equality_ball;

    /// Two inconsistent equality rows (v_x = 0.5 and v_x = 0.4) and a solution that meets the
    /// first, the contact law and the balance exactly (r = (2, −0.6, 0), v = (0.5, 0, 0),
    /// λ₁ + λ₂ = −0.4): the stored evaluation reports the second row's miss, ‖Gᵀv + b‖ /
    /// max(1, ‖b‖) = 0.1, and never "converged".
    pub fn stored_evaluation_reports_the_equality_residual() {
        let p = Problem::Global(equality_ball(2, Some(vec![-0.5, -0.4])));
        let stored = StoredSolution {
            v: Some(vec![0.5, 0.0, 0.0]),
            u: None,
            r: vec![2.0, -0.6, 0.0],
            l: Some(vec![-0.4, 0.0]),
        };
        let ev = evaluate(&p, &stored).unwrap();
        let eq = ev.equality_residual.expect("an equality residual");
        assert!((eq - 0.1).abs() < 1e-12, "{eq}");
        assert!(!ev.converged(1e-8));
        assert!(!ev.converged(0.05));
    }
}
