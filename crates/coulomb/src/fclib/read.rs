//! Reading FCLIB files: tolerant about storage details (CSC/CSR/triplets, int32/int64
//! indices, `nzmax` larger than needed, unsorted or duplicate entries), strict about
//! anything that would change the problem (sizes that disagree, indices out of range,
//! constraints coulomb does not model).

use super::error::{FclibError, FclibErrorKind};
use super::{FclibFile, Info, ReadOptions, StoredSolution};
use crate::linalg::sparse::CscMatrix;
use crate::problem::{GlobalProblem, LocalProblem, Problem};
use hdf5_pure::{DType, Dataset, FormatError};

/// Upper bound on the bytes one dataset may declare: `max(4 × file size, 256 MiB)`. A dataset
/// stored in the file can never be larger than the file; one that was never written (HDF5
/// then returns its fill value, as for `/solution/r` in Capsules-i125-1213) can, but FCLIB
/// arrays that large in a small file only come from corruption, and honouring the declared
/// size would abort the process on allocation failure.
fn byte_limit(file_len: usize) -> u64 {
    (file_len as u64).saturating_mul(4).max(256 << 20)
}

/// The contents of an FCLIB file held in memory, with the name used in error messages.
pub(super) struct Reader<'a> {
    file: hdf5_pure::File,
    name: &'a str,
    limit: u64,
}

/// `/a/b` for messages, from `a/b` as the HDF5 crate takes it.
fn shown(path: &str) -> String {
    format!("/{path}")
}

impl<'a> Reader<'a> {
    /// Opens an in-memory HDF5 image.
    pub(super) fn open(name: &'a str, bytes: Vec<u8>) -> Result<Self, FclibError> {
        if !hdf5_pure::is_hdf5_bytes(&bytes) {
            return Err(FclibError::new(name, FclibErrorKind::NotHdf5));
        }
        let limit = byte_limit(bytes.len());
        let file = hdf5_pure::File::from_bytes(bytes).map_err(|e| {
            FclibError::new(
                name,
                FclibErrorKind::Corrupt {
                    path: "/".into(),
                    detail: e.to_string(),
                },
            )
        })?;
        Ok(Self { file, name, limit })
    }

    fn err(&self, kind: FclibErrorKind) -> FclibError {
        FclibError::new(self.name, kind)
    }

    fn bad(&self, path: &str, detail: String) -> FclibError {
        self.err(FclibErrorKind::BadValue {
            path: shown(path),
            detail,
        })
    }

    fn hdf5_err(&self, path: &str, e: hdf5_pure::Error) -> FclibError {
        self.err(FclibErrorKind::Corrupt {
            path: shown(path),
            detail: e.to_string(),
        })
    }

    /// Whether the group `path` exists; an object of another kind there is an error.
    pub(super) fn has_group(&self, path: &str) -> Result<bool, FclibError> {
        match self.file.group(path) {
            Ok(_) => Ok(true),
            Err(hdf5_pure::Error::Format(FormatError::PathNotFound(_))) => Ok(false),
            Err(hdf5_pure::Error::NotAGroup(_)) => Err(self.err(FclibErrorKind::WrongType {
                path: shown(path),
                expected: "a group".into(),
                found: "a dataset".into(),
            })),
            Err(e) => Err(self.hdf5_err(path, e)),
        }
    }

    /// Whether anything (group or dataset) is stored at `path`.
    fn exists(&self, path: &str) -> Result<bool, FclibError> {
        match self.file.dataset(path) {
            Ok(_) | Err(hdf5_pure::Error::NotADataset(_)) => Ok(true),
            Err(hdf5_pure::Error::Format(FormatError::PathNotFound(_))) => Ok(false),
            Err(e) => Err(self.hdf5_err(path, e)),
        }
    }

    fn dataset_opt(&self, path: &str) -> Result<Option<Dataset>, FclibError> {
        match self.file.dataset(path) {
            Ok(d) => Ok(Some(d)),
            Err(hdf5_pure::Error::Format(FormatError::PathNotFound(_))) => Ok(None),
            Err(hdf5_pure::Error::NotADataset(_)) => Err(self.err(FclibErrorKind::WrongType {
                path: shown(path),
                expected: "a dataset".into(),
                found: "a group".into(),
            })),
            Err(e) => Err(self.hdf5_err(path, e)),
        }
    }

    fn dataset(&self, path: &str) -> Result<Dataset, FclibError> {
        self.dataset_opt(path)?
            .ok_or_else(|| self.err(FclibErrorKind::MissingDataset { path: shown(path) }))
    }

    /// Datatype and entry count of a dataset, after checking that its declared size is
    /// plausible (see [`byte_limit`]).
    fn inspect(&self, ds: &Dataset, path: &str) -> Result<(DType, u64), FclibError> {
        let dtype = ds.dtype().map_err(|e| self.hdf5_err(path, e))?;
        let shape = ds.shape().map_err(|e| self.hdf5_err(path, e))?;
        let elem = ds.element_size().map_err(|e| self.hdf5_err(path, e))?;
        let count = shape.iter().try_fold(1u64, |acc, &s| acc.checked_mul(s));
        let bytes = count.and_then(|c| c.checked_mul(elem));
        match (count, bytes) {
            (Some(c), Some(b)) if b <= self.limit => Ok((dtype, c)),
            _ => Err(self.err(FclibErrorKind::Corrupt {
                path: shown(path),
                detail: format!(
                    "declares shape {shape:?} of {elem}-byte entries, more than a file of this size can hold"
                ),
            })),
        }
    }

    /// A float array (float64, or float32 converted), required.
    pub(super) fn floats(&self, path: &str) -> Result<Vec<f64>, FclibError> {
        let ds = self.dataset(path)?;
        self.floats_of(&ds, path)
    }

    /// A float array, or `None` when absent.
    pub(super) fn floats_opt(&self, path: &str) -> Result<Option<Vec<f64>>, FclibError> {
        match self.dataset_opt(path)? {
            Some(ds) => self.floats_of(&ds, path).map(Some),
            None => Ok(None),
        }
    }

    fn floats_of(&self, ds: &Dataset, path: &str) -> Result<Vec<f64>, FclibError> {
        let (dtype, _) = self.inspect(ds, path)?;
        if !matches!(dtype, DType::F64 | DType::F32) {
            return Err(self.err(FclibErrorKind::WrongType {
                path: shown(path),
                expected: "a float64 array".into(),
                found: describe(&dtype),
            }));
        }
        ds.read_f64().map_err(|e| self.hdf5_err(path, e))
    }

    /// An integer array (any integer width), required.
    pub(super) fn ints(&self, path: &str) -> Result<Vec<i64>, FclibError> {
        let ds = self.dataset(path)?;
        let (dtype, _) = self.inspect(&ds, path)?;
        if !matches!(
            dtype,
            DType::I8
                | DType::I16
                | DType::I32
                | DType::I64
                | DType::U8
                | DType::U16
                | DType::U32
                | DType::U64
        ) {
            return Err(self.err(FclibErrorKind::WrongType {
                path: shown(path),
                expected: "an integer array (int32 or int64)".into(),
                found: describe(&dtype),
            }));
        }
        ds.read_i64().map_err(|e| self.hdf5_err(path, e))
    }

    /// An integer stored as a one-entry array (FCLIB's `int32[1]`) or a scalar.
    pub(super) fn int(&self, path: &str) -> Result<i64, FclibError> {
        let v = self.ints(path)?;
        match v.as_slice() {
            [x] => Ok(*x),
            _ => Err(self.err(FclibErrorKind::WrongLength {
                path: shown(path),
                expected: "1".into(),
                found: v.len() as u64,
            })),
        }
    }

    /// A non-negative integer that must fit in memory as a size.
    fn size(&self, path: &str) -> Result<usize, FclibError> {
        let x = self.int(path)?;
        usize::try_from(x).map_err(|_| self.bad(path, format!("{x} is not a valid size")))
    }

    /// A string dataset (fixed or variable length; invalid UTF-8 is replaced), or `None`.
    fn string_opt(&self, path: &str) -> Result<Option<String>, FclibError> {
        let Some(ds) = self.dataset_opt(path)? else {
            return Ok(None);
        };
        let (dtype, _) = self.inspect(&ds, path)?;
        if !matches!(dtype, DType::String | DType::VariableLengthString) {
            return Err(self.err(FclibErrorKind::WrongType {
                path: shown(path),
                expected: "a string".into(),
                found: describe(&dtype),
            }));
        }
        let v = ds.read_string().map_err(|e| self.hdf5_err(path, e))?;
        Ok(Some(v.concat()))
    }

    /// A float array whose length must be `expected` (explained by `why`).
    fn floats_len(&self, path: &str, expected: usize, why: &str) -> Result<Vec<f64>, FclibError> {
        let v = self.floats(path)?;
        self.check_len(path, v.len(), expected, why)?;
        Ok(v)
    }

    fn check_len(
        &self,
        path: &str,
        found: usize,
        expected: usize,
        why: &str,
    ) -> Result<(), FclibError> {
        if found != expected {
            return Err(self.err(FclibErrorKind::WrongLength {
                path: shown(path),
                expected: if why.is_empty() {
                    format!("{expected}")
                } else {
                    format!("{expected} ({why})")
                },
                found: found as u64,
            }));
        }
        Ok(())
    }

    /// Refuses FCLIB features coulomb does not model.
    fn refuse(&self, path: &str, what: &str) -> Result<(), FclibError> {
        if self.exists(path)? {
            return Err(self.err(FclibErrorKind::Unsupported {
                path: shown(path),
                detail: format!("{what} are not supported by coulomb"),
            }));
        }
        Ok(())
    }

    /// The spatial dimension d ∈ {2, 3}.
    fn spacedim(&self, group: &str) -> Result<usize, FclibError> {
        let path = format!("{group}/spacedim");
        let d = self.int(&path)?;
        if d != 2 && d != 3 {
            return Err(self.bad(&path, format!("spacedim = {d}, must be 2 or 3")));
        }
        Ok(d as usize)
    }

    /// The `(m, n)` header of a matrix group.
    fn matrix_shape(&self, group: &str) -> Result<(usize, usize), FclibError> {
        Ok((
            self.size(&format!("{group}/m"))?,
            self.size(&format!("{group}/n"))?,
        ))
    }

    /// Reads the first `count` entries of an index array (it may be longer, as when
    /// `nzmax` exceeds the entries used) as `usize`, every one in `0..bound`.
    fn indices(
        &self,
        path: &str,
        count: usize,
        why: &str,
        bound: usize,
        what: &str,
    ) -> Result<Vec<usize>, FclibError> {
        let raw = self.ints(path)?;
        self.at_least(path, raw.len(), count, why)?;
        let mut out = Vec::with_capacity(count);
        for (k, &x) in raw[..count].iter().enumerate() {
            match usize::try_from(x) {
                Ok(u) if u < bound => out.push(u),
                _ => {
                    return Err(self.bad(
                        path,
                        format!("entry {k} = {x} is not a {what} in 0..{bound}"),
                    ))
                }
            }
        }
        Ok(out)
    }

    fn at_least(&self, path: &str, len: usize, k: usize, why: &str) -> Result<(), FclibError> {
        if len < k {
            return Err(self.err(FclibErrorKind::WrongLength {
                path: shown(path),
                expected: format!("at least {k} ({why})"),
                found: len as u64,
            }));
        }
        Ok(())
    }

    /// Reads compressed pointers (CSC column or CSR row pointers): at least `count + 1`
    /// entries (the first `count + 1` are used), starting at 0, non-decreasing.
    fn pointers(&self, path: &str, count: usize) -> Result<Vec<usize>, FclibError> {
        let raw = self.ints(path)?;
        if raw.len() < count + 1 {
            return Err(self.err(FclibErrorKind::WrongLength {
                path: shown(path),
                expected: format!("{}", count + 1),
                found: raw.len() as u64,
            }));
        }
        let raw = &raw[..count + 1];
        if raw[0] != 0 {
            return Err(self.bad(path, format!("first pointer is {}, must be 0", raw[0])));
        }
        let mut out = Vec::with_capacity(raw.len());
        for (k, &x) in raw.iter().enumerate() {
            let prev = out.last().copied().unwrap_or(0);
            match usize::try_from(x) {
                Ok(u) if u >= prev => out.push(u),
                _ => {
                    return Err(self.bad(
                        path,
                        format!("pointer {k} = {x} is smaller than the one before it ({prev})"),
                    ))
                }
            }
        }
        Ok(out)
    }

    /// Reads a matrix group (`m`, `n`, `nz`, `p`, `i`, `x`) in any of the three FCLIB
    /// storages into CSC, with m × n already checked against the problem by the caller.
    pub(super) fn matrix(&self, group: &str) -> Result<CscMatrix, FclibError> {
        let (m, n) = self.matrix_shape(group)?;
        let nz_path = format!("{group}/nz");
        let nz = self.int(&nz_path)?;
        let p_path = format!("{group}/p");
        let i_path = format!("{group}/i");
        let x_path = format!("{group}/x");
        let x = self.floats(&x_path)?;
        let built = match nz {
            -1 => {
                let p = self.pointers(&p_path, n)?;
                let nnz = p[n];
                let i = self.indices(&i_path, nnz, "p[n]", m, "row index")?;
                self.at_least(&x_path, x.len(), nnz, "p[n]")?;
                CscMatrix::from_csc_arrays(m, n, &p, &i, &x[..nnz])
            }
            -2 => {
                let p = self.pointers(&p_path, m)?;
                let nnz = p[m];
                let i = self.indices(&i_path, nnz, "p[m]", n, "column index")?;
                self.at_least(&x_path, x.len(), nnz, "p[m]")?;
                CscMatrix::from_csr_arrays(m, n, &p, &i, &x[..nnz])
            }
            k if k >= 0 => {
                let nnz = usize::try_from(k).unwrap_or(usize::MAX);
                let rows = self.indices(&i_path, nnz, "nz", m, "row index")?;
                let cols = self.indices(&p_path, nnz, "nz", n, "column index")?;
                self.at_least(&x_path, x.len(), nnz, "nz")?;
                CscMatrix::from_triplets(m, n, &rows, &cols, &x[..nnz])
            }
            k => {
                return Err(self.bad(
                    &nz_path,
                    format!("nz = {k}: must be -1 (CSC), -2 (CSR) or a triplet count >= 0"),
                ))
            }
        };
        built.map_err(|e| self.bad(group, format!("inconsistent sparse storage: {e}")))
    }

    /// `/fclib_*/info`, when present.
    fn info(&self, group: &str) -> Result<Option<Info>, FclibError> {
        let path = format!("{group}/info");
        if !self.has_group(&path)? {
            return Ok(None);
        }
        let get = |name: &str| -> Result<String, FclibError> {
            Ok(self
                .string_opt(&format!("{path}/{name}"))?
                .unwrap_or_default())
        };
        Ok(Some(Info {
            title: get("title")?,
            description: get("description")?,
            math_info: get("math_info")?,
        }))
    }

    /// The local problem in `/fclib_local`, exactly as stored.
    fn local(&self) -> Result<Problem, FclibError> {
        let g = "fclib_local";
        self.refuse("fclib_local/V", "equality constraints (V, R, s)")?;
        self.refuse("fclib_local/R", "equality constraints (V, R, s)")?;
        let d = self.spacedim(g)?;
        let wg = "fclib_local/W";
        if !self.has_group(wg)? {
            return Err(self.err(FclibErrorKind::MissingGroup {
                path: shown(wg),
                hint: String::new(),
            }));
        }
        let (m, n) = self.matrix_shape(wg)?;
        if m != n {
            return Err(self.bad(
                &format!("{wg}/n"),
                format!("W must be square, but m = {m} and n = {n}"),
            ));
        }
        if m % d != 0 {
            return Err(self.bad(
                &format!("{wg}/m"),
                format!("m = {m} is not a multiple of spacedim = {d}"),
            ));
        }
        let q = self.floats_len("fclib_local/vectors/q", m, "m of /fclib_local/W")?;
        let mu = self.floats_len("fclib_local/vectors/mu", m / d, "m / spacedim")?;
        let w = self.matrix(wg)?;
        LocalProblem::new(d as i64, w, q, mu)
            .map(Problem::Local)
            .map_err(|source| {
                self.err(FclibErrorKind::InvalidProblem {
                    group: shown(g),
                    source,
                })
            })
    }

    /// The global problem in `/fclib_global`, exactly as stored.
    fn global(&self) -> Result<Problem, FclibError> {
        let g = "fclib_global";
        let d = self.spacedim(g)?;
        for mg in ["fclib_global/M", "fclib_global/H"] {
            if !self.has_group(mg)? {
                return Err(self.err(FclibErrorKind::MissingGroup {
                    path: shown(mg),
                    hint: String::new(),
                }));
            }
        }
        let (mm, mn) = self.matrix_shape("fclib_global/M")?;
        if mm != mn {
            return Err(self.bad(
                "fclib_global/M/n",
                format!("M must be square, but m = {mm} and n = {mn}"),
            ));
        }
        let (hm, hn) = self.matrix_shape("fclib_global/H")?;
        if hm != mm {
            return Err(self.bad(
                "fclib_global/H/m",
                format!("H must have as many rows as M (m = {mm}), found m = {hm}"),
            ));
        }
        if hn % d != 0 {
            return Err(self.bad(
                "fclib_global/H/n",
                format!("n = {hn} is not a multiple of spacedim = {d}"),
            ));
        }
        let f = self.floats_len("fclib_global/vectors/f", mm, "m of /fclib_global/M")?;
        let w = self.floats_len("fclib_global/vectors/w", hn, "n of /fclib_global/H")?;
        let mu = self.floats_len("fclib_global/vectors/mu", hn / d, "n of H / spacedim")?;
        let equality = self.equality(mm)?;
        let mmat = self.matrix("fclib_global/M")?;
        let hmat = self.matrix("fclib_global/H")?;
        GlobalProblem::new(d as i64, mmat, hmat, f, w, mu)
            .and_then(|p| match equality {
                Some((gmat, b)) => p.with_equality(gmat, b),
                None => Ok(p),
            })
            .map(Problem::Global)
            .map_err(|source| {
                self.err(FclibErrorKind::InvalidProblem {
                    group: shown(g),
                    source,
                })
            })
    }

    /// The equality constraints `/fclib_global/G` (n × p, n = `dofs`) and
    /// `/fclib_global/vectors/b` (p), when present: both or neither.
    fn equality(&self, dofs: usize) -> Result<Option<(CscMatrix, Vec<f64>)>, FclibError> {
        let (gg, bp) = ("fclib_global/G", "fclib_global/vectors/b");
        let has_g = self.exists(gg)?;
        let has_b = self.exists(bp)?;
        match (has_g, has_b) {
            (false, false) => return Ok(None),
            (false, true) => {
                return Err(self.err(FclibErrorKind::MissingGroup {
                    path: shown(gg),
                    hint: " (/fclib_global/vectors/b is stored: equality constraints need both)"
                        .into(),
                }))
            }
            (true, false) => {
                return Err(self.err(FclibErrorKind::MissingDataset { path: shown(bp) }))
            }
            (true, true) => {}
        }
        // a dataset stored at G is refused here (WrongType: expected a group)
        self.has_group(gg)?;
        let (gm, gn) = self.matrix_shape(gg)?;
        if gm != dofs {
            return Err(self.bad(
                "fclib_global/G/m",
                format!("G must have as many rows as M (m = {dofs}), found m = {gm}"),
            ));
        }
        let b = self.floats_len(bp, gn, "n of /fclib_global/G")?;
        let gmat = self.matrix(gg)?;
        Ok(Some((gmat, b)))
    }

    /// Reads `group` (`solution` or `guesses/k`) as a stored solution. When `problem` is
    /// given, the lengths of r, u (m) and v (dofs, global problems) are checked.
    pub(super) fn solution(
        &self,
        group: &str,
        problem: Option<&Problem>,
    ) -> Result<StoredSolution, FclibError> {
        let path = |name: &str| format!("{group}/{name}");
        let sol = StoredSolution {
            v: self.floats_opt(&path("v"))?,
            u: self.floats_opt(&path("u"))?,
            r: self.floats(&path("r"))?,
            l: self.floats_opt(&path("l"))?,
        };
        if let Some(p) = problem {
            let m = p.dim() * p.contacts();
            self.check_len(&path("r"), sol.r.len(), m, "d × contacts")?;
            if let Some(u) = &sol.u {
                self.check_len(&path("u"), u.len(), m, "d × contacts")?;
            }
            if let (Some(v), Some(n)) = (&sol.v, p.dofs()) {
                self.check_len(&path("v"), v.len(), n, "dofs")?;
            }
            if let (Some(l), Problem::Global(g)) = (&sol.l, p) {
                if g.equality.is_some() {
                    self.check_len(&path("l"), l.len(), g.equality_rows(), "equality rows")?;
                }
            }
        }
        Ok(sol)
    }

    /// `/guesses/1 ... /guesses/N`.
    fn guesses(&self, problem: &Problem) -> Result<Vec<StoredSolution>, FclibError> {
        if !self.has_group("guesses")? {
            return Ok(Vec::new());
        }
        let count_path = "guesses/number_of_guesses";
        let count = self.int(count_path)?;
        if count < 0 {
            return Err(self.bad(count_path, format!("{count} guesses")));
        }
        let mut out = Vec::new();
        for k in 1..=count {
            let g = format!("guesses/{k}");
            if !self.has_group(&g)? {
                return Err(self.err(FclibErrorKind::MissingGroup {
                    path: shown(&g),
                    hint: format!(" (number_of_guesses = {count})"),
                }));
            }
            out.push(self.solution(&g, Some(problem))?);
        }
        Ok(out)
    }

    /// The whole file.
    pub(super) fn fclib_file(&self, opts: &ReadOptions) -> Result<FclibFile, FclibError> {
        self.fclib_file_with(opts, None)
    }

    /// The whole file; with `dropped`, a /solution or /guesses group that cannot be read is
    /// left out and its error pushed there instead of failing the read.
    pub(super) fn fclib_file_with(
        &self,
        _opts: &ReadOptions,
        mut dropped: Option<&mut Vec<FclibError>>,
    ) -> Result<FclibFile, FclibError> {
        let local = self.has_group("fclib_local")?;
        let global = self.has_group("fclib_global")?;
        let (problem, group) =
            match (local, global) {
                (true, false) => (self.local()?, "fclib_local"),
                (false, true) => (self.global()?, "fclib_global"),
                (true, true) => return Err(self.err(FclibErrorKind::Unsupported {
                    path: "/".into(),
                    detail:
                        "holds both /fclib_local and /fclib_global; an FCLIB file has one problem"
                            .into(),
                })),
                (false, false) => {
                    return Err(self.err(FclibErrorKind::MissingGroup {
                        path: "/fclib_local".into(),
                        hint: " (and no /fclib_global either): not an FCLIB problem file".into(),
                    }))
                }
            };
        let info = self.info(group)?;
        let solution = self.has_group("solution").and_then(|has| {
            has.then(|| self.solution("solution", Some(&problem)))
                .transpose()
        });
        let solution = match (solution, dropped.as_deref_mut()) {
            (Ok(s), _) => s,
            (Err(e), Some(list)) => {
                list.push(e);
                None
            }
            (Err(e), None) => return Err(e),
        };
        let guesses = match (self.guesses(&problem), dropped) {
            (Ok(g), _) => g,
            (Err(e), Some(list)) => {
                list.push(e);
                Vec::new()
            }
            (Err(e), None) => return Err(e),
        };
        Ok(FclibFile {
            problem,
            info,
            solution,
            guesses,
        })
    }
}

/// Human description of an HDF5 datatype for error messages.
fn describe(dtype: &DType) -> String {
    match dtype {
        DType::String => "a fixed-length string".into(),
        DType::VariableLengthString => "a variable-length string".into(),
        other => format!("datatype {other}"),
    }
}
