//! The one error type of FCLIB reading and writing.

use crate::problem::ProblemError;
use thiserror::Error;

/// Why an FCLIB file could not be read or written. Displays as
/// `FILE: /group/dataset: what is wrong`, e.g.
/// `Capsules.hdf5: /fclib_local/W/p: expected 859 entries, found 12`.
#[derive(Debug, Error)]
#[error("{file}: {kind}")]
pub struct FclibError {
    /// the file as the caller named it (a path, or the name given to [`super::read_bytes`])
    pub file: String,
    /// what is wrong, and where inside the file
    pub kind: FclibErrorKind,
}

/// What is wrong with an FCLIB file. Every variant that concerns one object names its HDF5
/// path (`/fclib_local/W/p`).
#[derive(Debug, Error)]
pub enum FclibErrorKind {
    /// The file could not be opened, read or written.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The path is not a regular file of bounded size ([`crate::input`]).
    #[error("the FCLIB file {0}")]
    Input(crate::input::InputReason),
    /// The file does not start with the HDF5 signature.
    #[error("not an HDF5 file (no HDF5 signature)")]
    NotHdf5,
    /// The HDF5 structure itself is damaged (truncated file, bad addresses, ...).
    #[error("{path}: corrupt HDF5 data: {detail}")]
    Corrupt {
        /// the object being read when the damage showed
        path: String,
        /// what the HDF5 reader reported
        detail: String,
    },
    /// A required group is absent.
    #[error("{path}: missing group{hint}")]
    MissingGroup {
        /// the group
        path: String,
        /// extra explanation (may be empty)
        hint: String,
    },
    /// A required dataset is absent.
    #[error("{path}: missing dataset")]
    MissingDataset {
        /// the dataset
        path: String,
    },
    /// An object has the wrong HDF5 type (a group where a dataset is expected, a string where
    /// a float array is expected, ...).
    #[error("{path}: expected {expected}, found {found}")]
    WrongType {
        /// the object
        path: String,
        /// what FCLIB requires
        expected: String,
        /// what the file holds
        found: String,
    },
    /// A dataset has the wrong number of entries.
    #[error("{path}: expected {expected} entries, found {found}")]
    WrongLength {
        /// the dataset
        path: String,
        /// the required count (e.g. `859`, or `at least 1284`)
        expected: String,
        /// the count in the file
        found: u64,
    },
    /// A dataset has the right type and length but an impossible value (negative size,
    /// index out of range, pointers that decrease, `nz`/`p` inconsistent, ...).
    #[error("{path}: {detail}")]
    BadValue {
        /// the dataset
        path: String,
        /// what is wrong
        detail: String,
    },
    /// The file uses an FCLIB feature coulomb does not model (equality or bilateral
    /// constraints V, R, G). Reading it would silently change the problem, so it is refused.
    #[error("{path}: {detail}")]
    Unsupported {
        /// the object
        path: String,
        /// what is not supported
        detail: String,
    },
    /// The arrays are readable but do not form a valid problem (W not symmetric, M not
    /// positive definite, non-finite data, negative μ, ...).
    #[error("{group}: invalid problem: {source}")]
    InvalidProblem {
        /// `/fclib_local` or `/fclib_global`
        group: String,
        /// what the validation of [`crate::LocalProblem::new`] / [`crate::GlobalProblem::new`] found
        source: ProblemError,
    },
    /// The data to write cannot be stored as requested (e.g. an index that does not fit in
    /// int32), or the HDF5 writer failed.
    #[error("{path}: cannot write: {detail}")]
    Write {
        /// the object being written
        path: String,
        /// why
        detail: String,
    },
}

impl FclibError {
    /// Attaches a file name to an error kind.
    pub fn new(file: impl Into<String>, kind: FclibErrorKind) -> Self {
        Self {
            file: file.into(),
            kind,
        }
    }

    /// The HDF5 path of the object the error is about, when there is one.
    pub fn object_path(&self) -> Option<&str> {
        use FclibErrorKind::*;
        match &self.kind {
            Corrupt { path, .. }
            | MissingGroup { path, .. }
            | MissingDataset { path }
            | WrongType { path, .. }
            | WrongLength { path, .. }
            | BadValue { path, .. }
            | Unsupported { path, .. }
            | Write { path, .. } => Some(path),
            InvalidProblem { group, .. } => Some(group),
            Io(_) | Input(_) | NotHdf5 => None,
        }
    }
}
