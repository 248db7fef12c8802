//! Checkpoint and restart: the whole state a [`Simulation`] carries from one Moreau–Jean step
//! to the next, in one HDF5 file (`hdf5-pure`), written atomically (`coulomb::atomic`), so that
//! running 2K steps and running K steps, saving, loading and running K more give the same bits.
//!
//! # What is stored
//!
//! The state carried between steps by [`Simulation::step`]:
//! - the world at t_k: the spheres, **column by column** as numeric datasets (`/bodies/…`,
//!   one row per sphere), the obstacles, gravity and the material table as JSON (`/json/scene`, through serde, so
//!   that new shapes and motions are stored as soon as they derive `Serialize`/`Deserialize`);
//!   an obstacle's phase is a function of t, so t_k fixes it;
//! - the parameters ([`Params`], JSON `/json/params`) including the activation rule, the
//!   position correction and the step method, and the library solver's settings
//!   (`coulomb::solver::Settings`, JSON `/json/solver`: every field, so they round-trip
//!   exactly, including the time limits);
//! - t_k, k, the bound ε_u on the residual velocity of the last step (it sets the activation
//!   threshold δ_k of the next step, [`Simulation::activation_threshold`]) (`/state/…`);
//! - the warm-start impulses of the last step by contact key (`/warm_start/…`), the rolling
//!   warm start and rolling impulses (`/rolling/…`), and the last step's active contacts with
//!   their impulses (`/contacts/…`: not needed by the next step, which detects its own, but
//!   read by the outputs, e.g. the contact forces of a VTK frame);
//! - `keep_problem` and `profile_delassus` (`/json/flags`).
//!
//! Not stored: `last_history` and `last_problem` (reports of the last step only; the next
//! step overwrites them). There is no random state: scenes are built from a seed once, and an
//! inlet that emits beads during a run is meant to be a pure function of (seed, emission
//! index), so the step count k is all it needs.
//!
//! # Layout and integrity
//!
//! Root attributes `format` = [`FORMAT_NAME`], `format_version` = [`FORMAT_VERSION`],
//! `coulomb_version` (the writer's crate version, informative) and `crc32`, the CRC-32 of
//! every stored dataset (its path and its values, little-endian, in a fixed order), and
//! `crc32_datasets`, the CRC-32 of each dataset alone (hexadecimal, space-separated, in the
//! same order; optional: files written before it are read without it), with which a checksum
//! error names the dataset that changed. Reading
//! checks the format name and version (another version is refused: no migration), every
//! dataset's type and shape, the checksum, index ranges and the parameters
//! ([`Simulation::new`]'s checks); any failure is a [`CheckpointError`] saying what is wrong
//! and where, and no simulation is returned (never a partial state). JSON floats round-trip
//! exactly (`serde_json`'s `float_roundtrip`); a state that JSON cannot hold (a non-finite
//! parameter) is refused when writing.
//!
//! Numeric layout (n spheres, m warm-start entries, c contacts, r rolling entries):
//!
//! | dataset | type | shape |
//! |---|---|---|
//! | `/state/time`, `/state/residual_velocity` | f64 | (1,) |
//! | `/state/steps_done` | i64 | (1,) |
//! | `/bodies/position`, `velocity`, `angular_velocity` | f64 | (n, 3) |
//! | `/bodies/radius`, `mass` | f64 | (n,) |
//! | `/bodies/rotation_locked` | u8 (0/1) | (n,) |
//! | `/bodies/material` | i64 (index into the world's material table) | (n,) |
//! | `/warm_start/body`, `partner_index`, `partner_feature` (an obstacle's feature: wall, cap, triangle) | i64 | (m,) |
//! | `/warm_start/partner_kind` | u8 (0 sphere, 1 obstacle) | (m,) |
//! | `/warm_start/impulse` | f64 (r_N, r_T1, r_T2) | (m, 3) |
//! | `/contacts/body`, `partner_index`, `partner_kind`, `partner_feature` | as above | (c,) |
//! | `/contacts/normal`, `t1`, `t2`, `point`, `impulse` | f64 | (c, 3) |
//! | `/contacts/gap`, `normal_velocity` | f64 | (c,) |
//! | `/rolling/body`, `partner_index`, `partner_kind`, `partner_feature`, `impulse` | as `/warm_start` | (r, …) |
//! | `/rolling/impulses` | f64 | (c', 3) |
//! | `/rolling/error` | f64 | (1,) |
//! | `/json/scene`, `/json/params`, `/json/solver`, `/json/flags` | UTF-8 string | scalar |

use crate::contact::{Contact, Partner};
use crate::math::Vec3;
use crate::simulation::{Params, Simulation, SimulationError};
use crate::world::{MaterialTable, Obstacle, Sphere, World};
use hdf5_pure::{AttrValue, DType, FileBuilder};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The `format` attribute of a checkpoint file.
pub const FORMAT_NAME: &str = "coulomb-granular-checkpoint";
/// The `format_version` attribute: bumped whenever the layout or the meaning of a stored
/// field changes; files of another version are refused.
pub const FORMAT_VERSION: i64 = 1;

/// Why a checkpoint could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// the file could not be read or written
    #[error("{}: {source}", path.display())]
    Io {
        /// the file
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
    /// the path is not a regular file of bounded size, or cannot be opened or read
    /// ([`coulomb::input`])
    #[error(transparent)]
    Input(#[from] coulomb::input::InputError),
    /// the file is not HDF5 at all
    #[error("{}: not an HDF5 file (no HDF5 signature)", path.display())]
    NotHdf5 {
        /// the file
        path: PathBuf,
    },
    /// HDF5, but not a checkpoint of this program
    #[error("{}: not a coulomb-granular checkpoint ({detail})", path.display())]
    WrongFormat {
        /// the file
        path: PathBuf,
        /// what was found instead
        detail: String,
    },
    /// a checkpoint of another format version
    #[error(
        "{}: checkpoint format version {found} (written by coulomb {writer}); this program reads version {expected} only",
        path.display()
    )]
    Version {
        /// the file
        path: PathBuf,
        /// the file's version
        found: i64,
        /// the version this program reads
        expected: i64,
        /// the writer's coulomb version, as stored
        writer: String,
    },
    /// the file is damaged: truncated, unreadable structure, wrong type or shape
    #[error("{}: corrupted checkpoint at {location}: {detail}", path.display())]
    Corrupt {
        /// the file
        path: PathBuf,
        /// where in the file (an HDF5 path)
        location: String,
        /// what is wrong
        detail: String,
    },
    /// the stored data do not match their checksum
    #[error(
        "{}: corrupted checkpoint{}: CRC-32 of {} is {computed:#010x}, the file says {stored:#010x}",
        path.display(),
        dataset.as_ref().map(|d| format!(" at /{d}")).unwrap_or_default(),
        if dataset.is_some() { "its values" } else { "the data" }
    )]
    Checksum {
        /// the file
        path: PathBuf,
        /// the stored checksum
        stored: u32,
        /// the checksum of the data as read
        computed: u32,
        /// the dataset whose values changed, found from the per-dataset checksums (the
        /// `crc32_datasets` attribute; `None` for files without it, or when every dataset
        /// matches its own checksum and only the whole does not)
        dataset: Option<String>,
    },
    /// readable, but a value is out of range (an index, a parameter, a non-finite state)
    #[error("{}: invalid checkpoint at {location}: {detail}", path.display())]
    Invalid {
        /// the file
        path: PathBuf,
        /// where in the file
        location: String,
        /// what is wrong
        detail: String,
    },
    /// the state cannot be stored (a value JSON cannot represent, e.g. a non-finite parameter)
    #[error("cannot write a checkpoint of this state: {0}")]
    Unrepresentable(String),
}

/// The obstacles and gravity of the world (`/json/scene`). Bodies are stored column by
/// column, not here.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneRecord {
    gravity: Vec3,
    obstacles: Vec<Obstacle>,
    materials: Option<MaterialTable>,
}

/// Settings of the simulation object that are not parameters of the scheme (`/json/flags`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Flags {
    keep_problem: bool,
    profile_delassus: bool,
}

/// One stored dataset's values.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Data {
    F64(Vec<f64>),
    I64(Vec<i64>),
    U8(Vec<u8>),
    Str(String),
}

/// Column of a dataset: the number of values per row (1: a vector, 3: an (n, 3) array, 0: a
/// scalar string).
pub(crate) type Entry = (&'static str, usize, Data);

pub(crate) fn crc_of(entries: &[Entry]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    for (path, _, data) in entries {
        h.update(path.as_bytes());
        match data {
            Data::F64(v) => v.iter().for_each(|x| h.update(&x.to_le_bytes())),
            Data::I64(v) => v.iter().for_each(|x| h.update(&x.to_le_bytes())),
            Data::U8(v) => h.update(v),
            Data::Str(s) => h.update(s.as_bytes()),
        }
    }
    h.finalize()
}

fn flat3(it: impl Iterator<Item = Vec3>) -> Vec<f64> {
    it.flat_map(|v| v.to_array()).collect()
}

pub(crate) fn index(i: usize) -> i64 {
    i64::try_from(i).unwrap_or(i64::MAX)
}

/// The (body, partner kind, partner index, obstacle feature) columns of contact keys.
struct KeyColumns {
    body: Vec<i64>,
    kind: Vec<u8>,
    partner: Vec<i64>,
    feature: Vec<i64>,
}

/// The columns of contact keys: kind 0 for a sphere (feature 0), 1 for an obstacle.
fn key_columns(keys: impl Iterator<Item = (usize, Partner)>) -> KeyColumns {
    let mut c = KeyColumns {
        body: Vec::new(),
        kind: Vec::new(),
        partner: Vec::new(),
        feature: Vec::new(),
    };
    for (b, p) in keys {
        c.body.push(index(b));
        let (k, j, f) = match p {
            Partner::Body(j) => (0u8, j, 0),
            Partner::Obstacle(j, f) => (1u8, j, f),
        };
        c.kind.push(k);
        c.partner.push(index(j));
        c.feature.push(i64::from(f));
    }
    c
}

/// Appends the four key columns of `keys` under `group`.
fn push_keys(e: &mut Vec<Entry>, group: &'static [&'static str; 4], keys: KeyColumns) {
    e.push((group[0], 1, Data::I64(keys.body)));
    e.push((group[1], 1, Data::U8(keys.kind)));
    e.push((group[2], 1, Data::I64(keys.partner)));
    e.push((group[3], 1, Data::I64(keys.feature)));
}

/// The datasets `/contacts/…` of `c` (the layout's table, one row per contact), in their
/// fixed order: the same for every scene's checkpoint ([`Cursor::contacts`] reads them).
pub(crate) fn push_contacts(e: &mut Vec<Entry>, c: &[Contact]) {
    push_keys(
        e,
        &[
            "contacts/body",
            "contacts/partner_kind",
            "contacts/partner_index",
            "contacts/partner_feature",
        ],
        key_columns(c.iter().map(Contact::key)),
    );
    e.push((
        "contacts/normal",
        3,
        Data::F64(flat3(c.iter().map(|x| x.normal))),
    ));
    e.push(("contacts/t1", 3, Data::F64(flat3(c.iter().map(|x| x.t1)))));
    e.push(("contacts/t2", 3, Data::F64(flat3(c.iter().map(|x| x.t2)))));
    e.push((
        "contacts/point",
        3,
        Data::F64(flat3(c.iter().map(|x| x.point))),
    ));
    e.push((
        "contacts/gap",
        1,
        Data::F64(c.iter().map(|x| x.gap).collect()),
    ));
    e.push((
        "contacts/normal_velocity",
        1,
        Data::F64(c.iter().map(|x| x.normal_velocity).collect()),
    ));
    e.push((
        "contacts/impulse",
        3,
        Data::F64(c.iter().flat_map(|x| x.impulse).collect()),
    ));
}

/// A JSON document of `value` that reads back equal to it (else the state is not storable).
pub(crate) fn json_of<T>(what: &str, value: &T) -> Result<String, CheckpointError>
where
    T: Serialize + for<'de> Deserialize<'de> + PartialEq,
{
    json_of_with(what, value, |_| {})
}

/// [`json_of`], `complete` filling the fields of the value read back that JSON skips.
fn json_of_with<T>(
    what: &str,
    value: &T,
    complete: impl Fn(&mut T),
) -> Result<String, CheckpointError>
where
    T: Serialize + for<'de> Deserialize<'de> + PartialEq,
{
    let s = serde_json::to_string(value)
        .map_err(|e| CheckpointError::Unrepresentable(format!("{what}: {e}")))?;
    let back = serde_json::from_str::<T>(&s).map(|mut back| {
        complete(&mut back);
        back
    });
    match back {
        Ok(back) if back == *value => Ok(s),
        _ => Err(CheckpointError::Unrepresentable(format!(
            "{what} does not survive JSON unchanged (a non-finite number?): {s}"
        ))),
    }
}

/// The datasets of a checkpoint of `sim`, in their fixed order.
fn entries(sim: &Simulation) -> Result<Vec<Entry>, CheckpointError> {
    let w = &sim.world;
    let b = &w.bodies;
    let scene = SceneRecord {
        gravity: w.gravity,
        obstacles: w.obstacles.clone(),
        materials: w.materials.clone(),
    };
    let flags = Flags {
        keep_problem: sim.keep_problem,
        profile_delassus: sim.profile_delassus,
    };
    let mut e: Vec<Entry> = vec![
        ("state/time", 1, Data::F64(vec![sim.time])),
        (
            "state/steps_done",
            1,
            Data::I64(vec![index(sim.steps_done)]),
        ),
        (
            "state/residual_velocity",
            1,
            Data::F64(vec![sim.residual_velocity]),
        ),
        (
            "bodies/position",
            3,
            Data::F64(flat3(b.iter().map(|s| s.position))),
        ),
        (
            "bodies/velocity",
            3,
            Data::F64(flat3(b.iter().map(|s| s.velocity))),
        ),
        (
            "bodies/angular_velocity",
            3,
            Data::F64(flat3(b.iter().map(|s| s.angular_velocity))),
        ),
        (
            "bodies/radius",
            1,
            Data::F64(b.iter().map(|s| s.radius).collect()),
        ),
        (
            "bodies/mass",
            1,
            Data::F64(b.iter().map(|s| s.mass).collect()),
        ),
        (
            "bodies/rotation_locked",
            1,
            Data::U8(b.iter().map(|s| u8::from(s.rotation_locked)).collect()),
        ),
        (
            "bodies/material",
            1,
            Data::I64(b.iter().map(|s| i64::from(s.material)).collect()),
        ),
    ];
    push_keys(
        &mut e,
        &[
            "warm_start/body",
            "warm_start/partner_kind",
            "warm_start/partner_index",
            "warm_start/partner_feature",
        ],
        key_columns(sim.previous.iter().map(|x| x.0)),
    );
    e.push((
        "warm_start/impulse",
        3,
        Data::F64(sim.previous.iter().flat_map(|x| x.1).collect()),
    ));
    push_contacts(&mut e, &sim.contacts);
    // the rolling warm start, sorted by key so that the file does not depend on hashing
    let mut rolling: Vec<((usize, Partner), [f64; 3])> =
        sim.rolling.previous.iter().map(|(k, v)| (*k, *v)).collect();
    rolling.sort_unstable_by_key(|x| x.0);
    push_keys(
        &mut e,
        &[
            "rolling/body",
            "rolling/partner_kind",
            "rolling/partner_index",
            "rolling/partner_feature",
        ],
        key_columns(rolling.iter().map(|x| x.0)),
    );
    e.push((
        "rolling/impulse",
        3,
        Data::F64(rolling.iter().flat_map(|x| x.1).collect()),
    ));
    e.push((
        "rolling/impulses",
        3,
        Data::F64(sim.rolling.impulses.iter().flatten().copied().collect()),
    ));
    e.push((
        "rolling/error",
        1,
        Data::F64(vec![sim.rolling.rolling_error]),
    ));
    e.push(("json/scene", 0, Data::Str(json_of("the scene", &scene)?)));
    e.push((
        "json/params",
        0,
        // `solver` is skipped by Params' serde; stored next
        Data::Str(json_of_with("the parameters", &sim.params, |p| {
            p.solver = sim.params.solver.clone()
        })?),
    ));
    e.push((
        "json/solver",
        0,
        Data::Str(json_of("the solver settings", &sim.params.solver)?),
    ));
    e.push(("json/flags", 0, Data::Str(json_of("the flags", &flags)?)));
    Ok(e)
}

/// The checkpoint of `sim` as the bytes of an HDF5 file, with `version` as its format version.
fn encode(sim: &Simulation, version: i64) -> Result<Vec<u8>, CheckpointError> {
    encode_entries(FORMAT_NAME, version, &entries(sim)?)
}

/// The bytes of an HDF5 file holding `entries` (grouped by their first path component) with
/// the root attributes `format`, `format_version`, `coulomb_version` and `crc32`.
pub(crate) fn encode_entries(
    format: &str,
    version: i64,
    entries: &[Entry],
) -> Result<Vec<u8>, CheckpointError> {
    let crc = crc_of(entries);
    let mut file = FileBuilder::new();
    file.set_attr("format", AttrValue::AsciiString(format.into()));
    file.set_attr("format_version", AttrValue::I64(version));
    file.set_attr(
        "coulomb_version",
        AttrValue::AsciiString(env!("CARGO_PKG_VERSION").into()),
    );
    file.set_attr("crc32", AttrValue::U32(crc));
    // one CRC-32 per dataset, in order (hexadecimal, space-separated): a damaged file's
    // error names the dataset that changed
    file.set_attr(
        "crc32_datasets",
        AttrValue::AsciiString(
            entries
                .iter()
                .map(|e| format!("{:08x}", crc_of(std::slice::from_ref(e))))
                .collect::<Vec<_>>()
                .join(" "),
        ),
    );
    // entries are grouped by their first path component, in order
    let mut k = 0;
    while k < entries.len() {
        let group = entries[k].0.split('/').next().unwrap_or("");
        let mut g = file.create_group(group);
        while k < entries.len() && entries[k].0.split('/').next() == Some(group) {
            let (path, cols, data) = &entries[k];
            let name = path.rsplit('/').next().unwrap_or(path);
            let ds = g.create_dataset(name);
            let rows = |len: usize| -> Vec<u64> {
                if *cols > 1 {
                    vec![(len / cols) as u64, *cols as u64]
                } else {
                    vec![len as u64]
                }
            };
            match data {
                Data::F64(v) => {
                    ds.with_f64_data(v).with_shape(&rows(v.len()));
                }
                Data::I64(v) => {
                    ds.with_i64_data(v).with_shape(&rows(v.len()));
                }
                Data::U8(v) => {
                    ds.with_u8_data(v).with_shape(&rows(v.len()));
                }
                Data::Str(s) => {
                    ds.with_strings(&[s.as_str()])
                        .map_err(|e| CheckpointError::Unrepresentable(format!("/{path}: {e}")))?
                        .with_shape(&[]);
                }
            }
            k += 1;
        }
        file.add_group(g.finish());
    }
    file.finish()
        .map_err(|e| CheckpointError::Unrepresentable(format!("HDF5 writer: {e}")))
}

/// Reads the datasets of a checkpoint file, checking types and shapes.
pub(crate) struct Reader<'a> {
    file: hdf5_pure::File,
    path: &'a Path,
    limit: u64,
}

impl Reader<'_> {
    pub(crate) fn corrupt(
        &self,
        location: &str,
        detail: impl std::fmt::Display,
    ) -> CheckpointError {
        CheckpointError::Corrupt {
            path: self.path.to_path_buf(),
            location: format!("/{location}"),
            detail: detail.to_string(),
        }
    }

    pub(crate) fn invalid(
        &self,
        location: &str,
        detail: impl std::fmt::Display,
    ) -> CheckpointError {
        CheckpointError::Invalid {
            path: self.path.to_path_buf(),
            location: format!("/{location}"),
            detail: detail.to_string(),
        }
    }

    /// The dataset at `path`, of `cols` values per row (0: a scalar string).
    fn read(&self, path: &'static str, cols: usize, want: &Data) -> Result<Entry, CheckpointError> {
        let ds = self
            .file
            .dataset(path)
            .map_err(|e| self.corrupt(path, format!("missing or unreadable dataset ({e})")))?;
        let dtype = ds.dtype().map_err(|e| self.corrupt(path, e))?;
        let shape = ds.shape().map_err(|e| self.corrupt(path, e))?;
        let elem = ds.element_size().map_err(|e| self.corrupt(path, e))?;
        let count = shape.iter().try_fold(1u64, |a, &s| a.checked_mul(s));
        match count.and_then(|c| c.checked_mul(elem)) {
            Some(bytes) if bytes <= self.limit => {}
            _ => {
                return Err(self.corrupt(
                    path,
                    format!(
                        "declares shape {shape:?} of {elem}-byte values, more than the file holds"
                    ),
                ))
            }
        }
        let shape_ok = match cols {
            0 => shape.iter().product::<u64>() == 1,
            1 => shape.len() == 1,
            c => shape.len() == 2 && shape[1] == c as u64,
        };
        if !shape_ok {
            let expected = match cols {
                0 => "a scalar".to_string(),
                1 => "(n,)".to_string(),
                c => format!("(n, {c})"),
            };
            return Err(self.corrupt(path, format!("shape {shape:?}, expected {expected}")));
        }
        let wrong = |found: &DType, expected: &str| {
            self.corrupt(path, format!("type {found:?}, expected {expected}"))
        };
        let data = match want {
            Data::F64(_) => {
                if dtype != DType::F64 {
                    return Err(wrong(&dtype, "float64"));
                }
                Data::F64(ds.read_f64().map_err(|e| self.corrupt(path, e))?)
            }
            Data::I64(_) => {
                if dtype != DType::I64 {
                    return Err(wrong(&dtype, "int64"));
                }
                Data::I64(ds.read_i64().map_err(|e| self.corrupt(path, e))?)
            }
            Data::U8(_) => {
                if dtype != DType::U8 {
                    return Err(wrong(&dtype, "uint8"));
                }
                Data::U8(ds.read_u8().map_err(|e| self.corrupt(path, e))?)
            }
            Data::Str(_) => {
                if !matches!(dtype, DType::String | DType::VariableLengthString) {
                    return Err(wrong(&dtype, "a string"));
                }
                let v = ds.read_string().map_err(|e| self.corrupt(path, e))?;
                match v.as_slice() {
                    [s] => Data::Str(s.clone()),
                    _ => return Err(self.corrupt(path, "expected one string")),
                }
            }
        };
        let len = match &data {
            Data::F64(v) => v.len() as u64,
            Data::I64(v) => v.len() as u64,
            Data::U8(v) => v.len() as u64,
            Data::Str(_) => 1,
        };
        if count != Some(len) {
            return Err(self.corrupt(path, format!("{len} values read, shape {shape:?}")));
        }
        Ok((path, cols, data))
    }
}

/// Pops the next entry's values.
pub(crate) struct Cursor<'a, 'b> {
    pub(crate) r: &'a Reader<'b>,
    pub(crate) entries: std::vec::IntoIter<Entry>,
}

impl Cursor<'_, '_> {
    fn next(&mut self) -> Result<(&'static str, Data), CheckpointError> {
        self.entries
            .next()
            .map(|(p, _, d)| (p, d))
            .ok_or_else(|| self.r.corrupt("", "missing dataset"))
    }
    pub(crate) fn f64s(&mut self) -> Result<(&'static str, Vec<f64>), CheckpointError> {
        match self.next()? {
            (p, Data::F64(v)) => Ok((p, v)),
            (p, _) => Err(self.r.corrupt(p, "expected float64 values")),
        }
    }
    pub(crate) fn f64_scalar(&mut self) -> Result<f64, CheckpointError> {
        let (p, v) = self.f64s()?;
        match v.as_slice() {
            [x] => Ok(*x),
            _ => Err(self.r.corrupt(p, format!("{} values, expected 1", v.len()))),
        }
    }
    pub(crate) fn i64s(&mut self) -> Result<(&'static str, Vec<i64>), CheckpointError> {
        match self.next()? {
            (p, Data::I64(v)) => Ok((p, v)),
            (p, _) => Err(self.r.corrupt(p, "expected int64 values")),
        }
    }
    pub(crate) fn u8s(&mut self) -> Result<(&'static str, Vec<u8>), CheckpointError> {
        match self.next()? {
            (p, Data::U8(v)) => Ok((p, v)),
            (p, _) => Err(self.r.corrupt(p, "expected uint8 values")),
        }
    }
    /// n points of an (n, 3) dataset
    pub(crate) fn points(&mut self, n: usize) -> Result<Vec<Vec3>, CheckpointError> {
        let (p, v) = self.f64s()?;
        if v.len() != 3 * n {
            return Err(self
                .r
                .invalid(p, format!("{} rows, expected {n}", v.len() / 3)));
        }
        Ok(v.chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect())
    }
    /// n rows of an (n, 3) dataset as triples
    pub(crate) fn triples(&mut self, n: usize) -> Result<Vec<[f64; 3]>, CheckpointError> {
        Ok(self.points(n)?.into_iter().map(Vec3::to_array).collect())
    }
    /// n values of an (n,) float dataset
    pub(crate) fn column(&mut self, n: usize) -> Result<Vec<f64>, CheckpointError> {
        let (p, v) = self.f64s()?;
        if v.len() != n {
            return Err(self.r.invalid(p, format!("{} rows, expected {n}", v.len())));
        }
        Ok(v)
    }
    /// contact keys (body, partner kind, partner index), each index checked against the
    /// number of spheres and obstacles
    fn keys(
        &mut self,
        bodies: usize,
        obstacles: usize,
    ) -> Result<Vec<(usize, Partner)>, CheckpointError> {
        let (pb, body) = self.i64s()?;
        let (pk, kind) = self.u8s()?;
        let (pp, partner) = self.i64s()?;
        let (pf, feature) = self.i64s()?;
        if kind.len() != body.len() || partner.len() != body.len() || feature.len() != body.len() {
            return Err(self.r.invalid(
                pk,
                format!(
                    "{} kinds and {} partners for {} keys",
                    kind.len(),
                    partner.len(),
                    body.len()
                ),
            ));
        }
        let mut keys = Vec::with_capacity(body.len());
        for (i, (((&b, &k), &j), &f)) in body
            .iter()
            .zip(&kind)
            .zip(&partner)
            .zip(&feature)
            .enumerate()
        {
            let b = usize::try_from(b)
                .ok()
                .filter(|&b| b < bodies)
                .ok_or_else(|| self.r.invalid(pb, format!("row {i}: body {b} of {bodies}")))?;
            let bound = match k {
                0 => bodies,
                1 => obstacles,
                _ => return Err(self.r.invalid(pk, format!("row {i}: kind {k} (0 or 1)"))),
            };
            let j = usize::try_from(j)
                .ok()
                .filter(|&j| j < bound)
                .ok_or_else(|| {
                    self.r
                        .invalid(pp, format!("row {i}: partner {j} of {bound}"))
                })?;
            let f = u32::try_from(f)
                .ok()
                .filter(|&f| k == 1 || f == 0)
                .ok_or_else(|| self.r.invalid(pf, format!("row {i}: feature {f}")))?;
            keys.push((
                b,
                if k == 0 {
                    Partner::Body(j)
                } else {
                    Partner::Obstacle(j, f)
                },
            ));
        }
        Ok(keys)
    }
    /// The contacts of the datasets `/contacts/…` ([`push_contacts`]), their bodies below
    /// `bodies` and their partners below `bodies` or `obstacles`.
    pub(crate) fn contacts(
        &mut self,
        bodies: usize,
        obstacles: usize,
    ) -> Result<Vec<Contact>, CheckpointError> {
        let keys = self.keys(bodies, obstacles)?;
        let nc = keys.len();
        let normal = self.points(nc)?;
        let t1 = self.points(nc)?;
        let t2 = self.points(nc)?;
        let point = self.points(nc)?;
        let gap = self.column(nc)?;
        let normal_velocity = self.column(nc)?;
        let impulse = self.triples(nc)?;
        Ok((0..nc)
            .map(|i| Contact {
                body: keys[i].0,
                partner: keys[i].1,
                normal: normal[i],
                t1: t1[i],
                t2: t2[i],
                point: point[i],
                gap: gap[i],
                normal_velocity: normal_velocity[i],
                impulse: impulse[i],
            })
            .collect())
    }
    pub(crate) fn json<T: for<'de> Deserialize<'de>>(&mut self) -> Result<T, CheckpointError> {
        match self.next()? {
            (p, Data::Str(s)) => {
                serde_json::from_str(&s).map_err(|e| self.r.invalid(p, format!("JSON: {e}")))
            }
            (p, _) => Err(self.r.corrupt(p, "expected a string")),
        }
    }
}

/// Number of rows of a dataset as read (values / columns).
pub(crate) fn rows_of(e: &Entry) -> usize {
    let len = match &e.2 {
        Data::F64(v) => v.len(),
        Data::I64(v) => v.len(),
        Data::U8(v) => v.len(),
        Data::Str(_) => 1,
    };
    len / e.1.max(1)
}

/// Checks that the datasets of each group of `groups` (paths of `read`) have the same number
/// of rows; where they do not, the error names the dataset whose count differs from that of
/// most of its group (the first such), not the one read after it.
pub(crate) fn check_rows(
    r: &Reader<'_>,
    read: &[Entry],
    groups: &[&[&str]],
) -> Result<(), CheckpointError> {
    for group in groups {
        let rows: Vec<(&str, usize)> = group
            .iter()
            .filter_map(|p| read.iter().find(|e| e.0 == *p))
            .map(|e| (e.0, rows_of(e)))
            .collect();
        // the count most of the group agree on (the first such on ties)
        let Some(&(_, n)) = rows.iter().max_by_key(|(p, n)| {
            let votes = rows.iter().filter(|(_, m)| m == n).count();
            let first = rows.iter().position(|(q, _)| q == p).unwrap_or(0);
            (votes, usize::MAX - first)
        }) else {
            continue;
        };
        if let Some(&(p, m)) = rows.iter().find(|(_, m)| *m != n) {
            let agree: Vec<String> = rows
                .iter()
                .filter(|(_, k)| *k == n)
                .map(|(q, _)| format!("/{q}"))
                .collect();
            return Err(r.invalid(
                p,
                format!(
                    "{m} rows, where {} {} {n}",
                    agree.join(", "),
                    if agree.len() == 1 { "has" } else { "have" }
                ),
            ));
        }
    }
    Ok(())
}

/// The simulation stored in `bytes` (the contents of the file at `path`, named in errors).
fn decode(path: &Path, bytes: Vec<u8>) -> Result<Simulation, CheckpointError> {
    open(path, bytes, decode_file)
}

/// `read` applied to the HDF5 file of `bytes` (the contents of the file at `path`, named in
/// errors); a file that is not HDF5, or on which the HDF5 reader fails, is an error.
pub(crate) fn open<T>(
    path: &Path,
    bytes: Vec<u8>,
    read: impl FnOnce(&Reader<'_>) -> Result<T, CheckpointError>,
) -> Result<T, CheckpointError> {
    if !hdf5_pure::is_hdf5_bytes(&bytes) {
        return Err(CheckpointError::NotHdf5 {
            path: path.to_path_buf(),
        });
    }
    let limit = (bytes.len() as u64).saturating_mul(4);
    // the HDF5 reader is fuzzed (crates/coulomb/tests/fuzz.rs); a panic on a damaged file
    // would still be a corrupted file, not a crash
    let opened = std::panic::catch_unwind(|| hdf5_pure::File::from_bytes(bytes));
    let file = match opened {
        Ok(Ok(f)) => f,
        Ok(Err(e)) => {
            return Err(CheckpointError::Corrupt {
                path: path.to_path_buf(),
                location: "/".into(),
                detail: e.to_string(),
            })
        }
        Err(_) => {
            return Err(CheckpointError::Corrupt {
                path: path.to_path_buf(),
                location: "/".into(),
                detail: "the HDF5 reader failed on this file".into(),
            })
        }
    };
    let r = Reader { file, path, limit };
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| read(&r))) {
        Ok(res) => res,
        Err(_) => Err(r.corrupt("", "the HDF5 reader failed on this file")),
    }
}

fn attr_string(v: Option<&AttrValue>) -> Option<String> {
    match v? {
        AttrValue::AsciiString(s) | AttrValue::String(s) => Some(s.clone()),
        _ => None,
    }
}

fn attr_int(v: Option<&AttrValue>) -> Option<i64> {
    match v? {
        AttrValue::I64(x) => Some(*x),
        AttrValue::I32(x) => Some(i64::from(*x)),
        AttrValue::U32(x) => Some(i64::from(*x)),
        AttrValue::U64(x) => i64::try_from(*x).ok(),
        _ => None,
    }
}

/// The datasets of `layout` (paths, columns and types; the values are ignored) read from the
/// file of `r`, after checking its root attributes: `format` must be `format`, `format_version`
/// `version`, and the CRC-32 of the datasets read the `crc32` attribute.
pub(crate) fn read_checked(
    r: &Reader<'_>,
    format: &str,
    version: i64,
    layout: &[Entry],
) -> Result<Vec<Entry>, CheckpointError> {
    let path = r.path;
    let attrs = r
        .file
        .root()
        .attrs()
        .map_err(|e| r.corrupt("", format!("root attributes: {e}")))?;
    let found = attr_string(attrs.get("format"));
    if found.as_deref() != Some(format) {
        return Err(CheckpointError::WrongFormat {
            path: path.to_path_buf(),
            detail: match found {
                Some(f) => format!("format attribute {f:?}, expected {format:?}"),
                None => "no format attribute".into(),
            },
        });
    }
    let writer = attr_string(attrs.get("coulomb_version")).unwrap_or_else(|| "?".into());
    let found = attr_int(attrs.get("format_version"))
        .ok_or_else(|| r.corrupt("", "no integer format_version attribute"))?;
    if found != version {
        return Err(CheckpointError::Version {
            path: path.to_path_buf(),
            found,
            expected: version,
            writer,
        });
    }
    let stored = attr_int(attrs.get("crc32"))
        .and_then(|x| u32::try_from(x).ok())
        .ok_or_else(|| r.corrupt("", "no crc32 attribute"))?;
    let mut read = Vec::with_capacity(layout.len());
    for (p, cols, want) in layout {
        read.push(r.read(p, *cols, want)?);
    }
    let computed = crc_of(&read);
    if computed != stored {
        // the per-dataset checksums, where the file has them, name the dataset that changed
        let each: Option<Vec<u32>> = attr_string(attrs.get("crc32_datasets")).and_then(|s| {
            s.split_whitespace()
                .map(|x| u32::from_str_radix(x, 16).ok())
                .collect()
        });
        let changed = each.filter(|c| c.len() == read.len()).and_then(|c| {
            read.iter().zip(c).find_map(|(e, stored)| {
                let computed = crc_of(std::slice::from_ref(e));
                (computed != stored).then(|| (e.0.to_string(), stored, computed))
            })
        });
        return Err(match changed {
            Some((dataset, stored, computed)) => CheckpointError::Checksum {
                path: path.to_path_buf(),
                stored,
                computed,
                dataset: Some(dataset),
            },
            None => CheckpointError::Checksum {
                path: path.to_path_buf(),
                stored,
                computed,
                dataset: None,
            },
        });
    }
    Ok(read)
}

/// The `format` attribute of the HDF5 file at `path` (`None`: not HDF5, unreadable, or
/// without one): tells a sphere checkpoint ([`FORMAT_NAME`]) from a rigid one
/// ([`crate::io::rigid_checkpoint::FORMAT_NAME`]).
pub fn format_of(path: impl AsRef<Path>) -> Option<String> {
    let bytes = read_file(path.as_ref()).ok()?;
    open(path.as_ref(), bytes, |r| {
        let attrs = r
            .file
            .root()
            .attrs()
            .map_err(|e| r.corrupt("", e.to_string()))?;
        Ok(attr_string(attrs.get("format")))
    })
    .ok()
    .flatten()
}

fn decode_file(r: &Reader<'_>) -> Result<Simulation, CheckpointError> {
    // the datasets, in the writer's order (the types come from an empty state's entries)
    let layout = Simulation::new(World::new(), Params::default())
        .map_err(|e| r.corrupt("", format!("internal layout: {e}")))
        .and_then(|empty| entries(&empty))?;
    let read = read_checked(r, FORMAT_NAME, FORMAT_VERSION, &layout)?;
    // datasets that hold one row per sphere, per warm-start entry, per contact, per rolling
    // entry: a count that differs is blamed on the dataset that differs
    let keys = |g: &'static str| -> [&'static str; 4] {
        match g {
            "warm_start" => [
                "warm_start/body",
                "warm_start/partner_kind",
                "warm_start/partner_index",
                "warm_start/partner_feature",
            ],
            "contacts" => [
                "contacts/body",
                "contacts/partner_kind",
                "contacts/partner_index",
                "contacts/partner_feature",
            ],
            _ => [
                "rolling/body",
                "rolling/partner_kind",
                "rolling/partner_index",
                "rolling/partner_feature",
            ],
        }
    };
    let contacts = [
        &keys("contacts")[..],
        &[
            "contacts/normal",
            "contacts/t1",
            "contacts/t2",
            "contacts/point",
            "contacts/gap",
            "contacts/normal_velocity",
            "contacts/impulse",
        ],
    ]
    .concat();
    check_rows(
        r,
        &read,
        &[
            &[
                "bodies/position",
                "bodies/velocity",
                "bodies/angular_velocity",
                "bodies/radius",
                "bodies/mass",
                "bodies/rotation_locked",
                "bodies/material",
            ],
            &[&keys("warm_start")[..], &["warm_start/impulse"]].concat(),
            &contacts,
            &[&keys("rolling")[..], &["rolling/impulse"]].concat(),
        ],
    )?;
    let mut c = Cursor {
        r,
        entries: read.into_iter(),
    };
    let time = c.f64_scalar()?;
    let (sp, steps) = c.i64s()?;
    let steps_done = match steps.as_slice() {
        [k] => usize::try_from(*k).map_err(|_| r.invalid(sp, format!("{k} steps")))?,
        _ => return Err(r.invalid(sp, "expected one value")),
    };
    let residual_velocity = c.f64_scalar()?;
    if !(time.is_finite() && residual_velocity.is_finite() && residual_velocity >= 0.0) {
        return Err(r.invalid(
            "state",
            format!("time {time}, residual velocity {residual_velocity}"),
        ));
    }
    let (pp, pos) = c.f64s()?;
    if pos.len() % 3 != 0 {
        return Err(r.corrupt(pp, "not (n, 3)"));
    }
    let n = pos.len() / 3;
    let position: Vec<Vec3> = pos
        .chunks_exact(3)
        .map(|x| Vec3::new(x[0], x[1], x[2]))
        .collect();
    let velocity = c.points(n)?;
    let angular_velocity = c.points(n)?;
    let radius = c.column(n)?;
    let mass = c.column(n)?;
    let (lp, locked) = c.u8s()?;
    if locked.len() != n || locked.iter().any(|&x| x > 1) {
        return Err(r.invalid(lp, format!("{n} flags 0 or 1 expected")));
    }
    let (mp, material) = c.i64s()?;
    let material: Vec<u32> = material
        .iter()
        .map(|&m| u32::try_from(m).ok())
        .collect::<Option<_>>()
        .filter(|m: &Vec<u32>| m.len() == n)
        .ok_or_else(|| r.invalid(mp, format!("{n} material indices ≥ 0 expected")))?;
    let bodies: Vec<Sphere> = (0..n)
        .map(|i| Sphere {
            position: position[i],
            velocity: velocity[i],
            angular_velocity: angular_velocity[i],
            radius: radius[i],
            mass: mass[i],
            rotation_locked: locked[i] == 1,
            material: material[i],
        })
        .collect();
    // obstacles are needed to check the keys: read the JSON documents from the end
    let mut numeric: Vec<Entry> = c.entries.by_ref().collect();
    let json = numeric.split_off(numeric.len().saturating_sub(4));
    let mut j = Cursor {
        r,
        entries: json.into_iter(),
    };
    let scene: SceneRecord = j.json()?;
    let mut params: Params = j.json()?;
    params.solver = j.json()?;
    let flags: Flags = j.json()?;
    if !scene.gravity.is_finite() {
        return Err(r.invalid("json/scene", "non-finite gravity"));
    }
    let no = scene.obstacles.len();
    let mut c = Cursor {
        r,
        entries: numeric.into_iter(),
    };
    let keys = c.keys(n, no)?;
    let impulses = c.triples(keys.len())?;
    if !keys.windows(2).all(|w| w[0] < w[1]) {
        return Err(r.invalid("warm_start/body", "keys not sorted and unique"));
    }
    let previous: Vec<((usize, Partner), [f64; 3])> = keys.into_iter().zip(impulses).collect();
    let contacts = c.contacts(n, no)?;
    let rkeys = c.keys(n, no)?;
    let rimp = c.triples(rkeys.len())?;
    let (ip, flat) = c.f64s()?;
    if flat.len() % 3 != 0 {
        return Err(r.corrupt(ip, "not (n, 3)"));
    }
    let rolling_impulses: Vec<[f64; 3]> =
        flat.chunks_exact(3).map(|x| [x[0], x[1], x[2]]).collect();
    let rolling_error = c.f64_scalar()?;
    let world = World {
        bodies,
        obstacles: scene.obstacles,
        gravity: scene.gravity,
        materials: scene.materials,
    };
    let mut sim = Simulation::new(world, params).map_err(|e| match e {
        SimulationError::Parameter(m) => r.invalid("json/params", m),
        other => r.invalid("", other),
    })?;
    sim.time = time;
    sim.steps_done = steps_done;
    sim.residual_velocity = residual_velocity;
    sim.previous = previous;
    sim.contacts = contacts;
    sim.keep_problem = flags.keep_problem;
    sim.profile_delassus = flags.profile_delassus;
    sim.rolling.previous = rkeys.into_iter().zip(rimp).collect::<HashMap<_, _>>();
    sim.rolling.impulses = rolling_impulses;
    sim.rolling.rolling_error = rolling_error;
    Ok(sim)
}

impl Simulation {
    /// The checkpoint of this simulation as the bytes of an HDF5 file (module
    /// [`crate::checkpoint`]).
    pub fn checkpoint_bytes(&self) -> Result<Vec<u8>, CheckpointError> {
        encode(self, FORMAT_VERSION)
    }

    /// The simulation stored in the bytes of a checkpoint file; `name` names it in errors.
    pub fn from_checkpoint_bytes(
        name: impl AsRef<Path>,
        bytes: Vec<u8>,
    ) -> Result<Simulation, CheckpointError> {
        decode(name.as_ref(), bytes)
    }

    /// Writes the full state of the simulation into the HDF5 file `path`, atomically (a
    /// temporary file renamed over `path`; an existing checkpoint is replaced only by a
    /// complete one). See [`crate::checkpoint`] for what is stored.
    pub fn save_checkpoint(&self, path: impl AsRef<Path>) -> Result<(), CheckpointError> {
        write_file(path.as_ref(), self.checkpoint_bytes()?)
    }

    /// The simulation stored by [`Simulation::save_checkpoint`] in `path`: stepping it gives
    /// the same bits as stepping the saved one. Another format version, a damaged or
    /// truncated file, or out-of-range values give a [`CheckpointError`] and no simulation.
    pub fn load_checkpoint(path: impl AsRef<Path>) -> Result<Simulation, CheckpointError> {
        let path = path.as_ref();
        decode(path, read_file(path)?)
    }
}

/// Writes `bytes` to `path` atomically ([`coulomb::atomic::write`]: a temporary file renamed
/// over `path`; a path that is not a regular file is refused).
pub(crate) fn write_file(path: &Path, bytes: Vec<u8>) -> Result<(), CheckpointError> {
    coulomb::atomic::write(path, bytes).map_err(|source| CheckpointError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The bytes of the file at `path`.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, CheckpointError> {
    Ok(coulomb::input::read(
        path,
        coulomb::input::Kind::Checkpoint,
    )?)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::contact::Activation;
    use crate::nsgs::NsgsSettings;
    use crate::projection::Projection;
    use crate::scene::Scene;
    use crate::simulation::{StepMethod, StepStats};
    use coulomb::solver::{InnerKind, Method, OuterKind, Settings};

    /// The parameters `coulomb simulate` builds from its defaults (crates/coulomb-cli,
    /// sim_args.rs): body-level Gauss–Seidel to 1e-4, the accurate activation rule, the
    /// position correction, the library's fused Gauss–Seidel as finish.
    fn cli_params() -> Params {
        Params {
            h: 0.02,
            theta: 0.5,
            restitution: 0.2,
            mu: 0.3,
            activation: Activation::accurate(),
            solver: Settings {
                tol: 1e-4,
                max_outer: 20,
                fallback: Some((InnerKind::Apgd, OuterKind::Anderson)),
                outer: OuterKind::Fused,
                ..Settings::time_stepping(Method::new(InnerKind::Pgs, OuterKind::Anderson))
            },
            warm_start: true,
            projection: Some(Projection::default()),
            method: StepMethod::Nsgs(NsgsSettings::default()),
            rolling_friction: 0.0,
        }
    }

    /// The box's library-method parameters with rolling resistance μ_r = 0.1.
    fn rolling_params() -> Params {
        Params {
            rolling_friction: 0.1,
            method: StepMethod::Library,
            ..cli_params()
        }
    }

    /// Everything of a step's statistics that does not depend on the clock.
    fn numbers(s: &StepStats) -> Vec<u64> {
        [
            s.time,
            s.error,
            s.rule_6_1,
            s.kinetic_energy,
            s.potential_energy,
            s.max_penetration,
            s.delta,
            s.end_max_penetration,
            s.end_mean_penetration,
            s.projection_work,
        ]
        .iter()
        .map(|x| x.to_bits())
        .chain(
            [
                s.step,
                s.contacts,
                s.subproblems,
                s.inner_iterations,
                s.warm_started,
                s.projection_sweeps,
                usize::from(s.converged),
            ]
            .iter()
            .map(|&k| k as u64),
        )
        .collect()
    }

    /// Bits of every state carried between steps.
    fn state_bits(sim: &Simulation) -> Vec<u64> {
        let mut v = vec![sim.time.to_bits(), sim.steps_done as u64];
        v.push(sim.residual_velocity.to_bits());
        for b in &sim.world.bodies {
            for x in [b.position, b.velocity, b.angular_velocity] {
                v.extend(x.to_array().map(f64::to_bits));
            }
        }
        for (k, r) in &sim.previous {
            v.push(k.0 as u64);
            v.extend(r.map(f64::to_bits));
        }
        for c in &sim.contacts {
            v.extend(c.impulse.map(f64::to_bits));
        }
        v.extend(sim.rolling.impulses.iter().flatten().map(|x| x.to_bits()));
        v
    }

    fn run(sim: &mut Simulation, steps: usize) -> Vec<Vec<u64>> {
        (0..steps)
            .map(|_| numbers(&sim.step().expect("step")))
            .collect()
    }

    /// Run 2K steps == run K, save, load, run K: the same bits (states and statistics).
    fn restart_is_exact(params: Params, beads: usize, k: usize, name: &str) {
        let world = Scene::Box.build(beads, 1);
        let mut straight = Simulation::new(world.clone(), params.clone()).unwrap();
        let stats_straight = run(&mut straight, 2 * k);

        let mut first = Simulation::new(world, params).unwrap();
        let mut stats_split = run(&mut first, k);
        let dir =
            std::env::temp_dir().join(format!("coulomb-checkpoint-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("checkpoint.h5");
        if first.params.rolling_friction > 0.0 {
            assert!(!first.rolling.previous.is_empty(), "no rolling warm start");
        }
        assert!(!first.previous.is_empty() && !first.contacts.is_empty());
        first.save_checkpoint(&path).unwrap();
        let mut second = Simulation::load_checkpoint(&path).unwrap();
        assert_eq!(state_bits(&second), state_bits(&first));
        assert_eq!(second.params, first.params);
        assert_eq!(second.world, first.world);
        assert_eq!(second.contacts, first.contacts);
        assert_eq!(second.rolling.previous, first.rolling.previous);
        drop(first);
        stats_split.extend(run(&mut second, k));
        assert!(stats_straight.iter().any(|s| s[11] > 0), "no contacts");
        assert_eq!(stats_split, stats_straight);
        assert_eq!(state_bits(&second), state_bits(&straight));
        assert_eq!(second.world, straight.world);
        std::fs::remove_dir_all(&dir).ok();
    }

    pub fn restart_is_bitwise_nsgs() {
        restart_is_exact(cli_params(), 120, 100, "nsgs");
    }

    pub fn restart_is_bitwise_with_rolling_friction() {
        let p = rolling_params();
        restart_is_exact(p, 60, 100, "rolling");
    }

    pub fn every_shape_and_motion_round_trips() {
        use crate::world::{Motion, Shape};
        for scene in Scene::ALL {
            let mut sim = Simulation::new(scene.build(20, 3), Params::default()).unwrap();
            sim.step().unwrap();
            let back =
                Simulation::from_checkpoint_bytes("x", sim.checkpoint_bytes().unwrap()).unwrap();
            assert_eq!(back.world, sim.world, "{}", scene.name());
            assert_eq!(back.params, sim.params);
        }
        let mut w = World::new();
        w.obstacles.push(Obstacle {
            name: "paroi inclinée \"α\"".into(),
            material: 0,
            shape: Shape::Rectangle {
                center: Vec3::new(0.1, 0.2, 1.0 / 3.0),
                normal: Vec3::Z,
                u: Vec3::X,
                half_u: 0.7,
                half_v: std::f64::consts::PI,
            },
            motion: Motion::Rotate {
                center: Vec3::new(1e-300, 0.0, -1.0),
                axis: Vec3::Y,
                omega: 0.1 + 0.2,
            },
        });
        w.bodies
            .push(Sphere::new(Vec3::new(0.0, 0.0, 2.0), 0.05, 1.0));
        w.bodies[0].rotation_locked = true;
        let mut p = Params::default();
        p.solver.time_limit = None;
        p.solver.tol = 1.0 / 7.0;
        let sim = Simulation::new(w, p).unwrap();
        let back = Simulation::from_checkpoint_bytes("x", sim.checkpoint_bytes().unwrap()).unwrap();
        assert_eq!(back.world, sim.world);
        assert_eq!(back.params, sim.params);
    }

    fn small_checkpoint() -> (Simulation, Vec<u8>) {
        let mut sim = Simulation::new(Scene::Box.build(30, 2), cli_params()).unwrap();
        for _ in 0..30 {
            sim.step().unwrap();
        }
        assert!(!sim.contacts.is_empty());
        let bytes = sim.checkpoint_bytes().unwrap();
        (sim, bytes)
    }

    pub fn truncated_files_are_refused() {
        let (_, bytes) = small_checkpoint();
        for len in [
            0,
            1,
            8,
            100,
            bytes.len() / 3,
            bytes.len() / 2,
            bytes.len() - 1,
        ] {
            let r = Simulation::from_checkpoint_bytes("t.h5", bytes[..len].to_vec());
            assert!(r.is_err(), "truncated to {len} of {} bytes", bytes.len());
        }
    }

    pub fn flipped_bytes_never_give_a_different_state() {
        let (sim, bytes) = small_checkpoint();
        let want = state_bits(&sim);
        // a flip in the stored positions is caught by the checksum
        let x0 = sim.world.bodies[0].position.x.to_le_bytes();
        let at = bytes
            .windows(8)
            .position(|w| w == x0)
            .expect("positions stored raw");
        let mut bad = bytes.clone();
        bad[at + 3] ^= 0x10;
        let e = Simulation::from_checkpoint_bytes("f.h5", bad).unwrap_err();
        assert!(matches!(e, CheckpointError::Checksum { .. }), "{e}");
        // a flip anywhere: an error, or (in padding and unused bytes) the same state
        let (mut refused, mut same) = (0, 0);
        for i in (0..bytes.len()).step_by(7) {
            let mut bad = bytes.clone();
            bad[i] ^= 0x5a;
            match Simulation::from_checkpoint_bytes("f.h5", bad) {
                Err(_) => refused += 1,
                Ok(s) => {
                    assert_eq!(state_bits(&s), want, "flip at byte {i}");
                    assert_eq!(s.world, sim.world);
                    assert_eq!(s.params, sim.params);
                    same += 1;
                }
            }
        }
        assert!(refused > 0 && refused + same > 100);
    }

    pub fn other_versions_and_formats_are_refused() {
        let (sim, _) = small_checkpoint();
        let bytes = encode(&sim, FORMAT_VERSION + 1).unwrap();
        let e = Simulation::from_checkpoint_bytes("v.h5", bytes).unwrap_err();
        match &e {
            CheckpointError::Version {
                found, expected, ..
            } => assert_eq!((*found, *expected), (FORMAT_VERSION + 1, FORMAT_VERSION)),
            other => panic!("{other}"),
        }
        assert!(e.to_string().contains("v.h5"));
        let e =
            Simulation::from_checkpoint_bytes("n.h5", b"not a checkpoint".to_vec()).unwrap_err();
        assert!(matches!(e, CheckpointError::NotHdf5 { .. }), "{e}");
        // an HDF5 file of another kind
        let mut other = FileBuilder::new();
        other.create_dataset("x").with_f64_data(&[1.0]);
        let e = Simulation::from_checkpoint_bytes("o.h5", other.finish().unwrap()).unwrap_err();
        assert!(matches!(e, CheckpointError::WrongFormat { .. }), "{e}");
        let e = Simulation::load_checkpoint("/nonexistent/dir/c.h5").unwrap_err();
        assert!(
            matches!(&e, CheckpointError::Input(i) if i.is_not_found()),
            "{e}"
        );
    }

    pub fn out_of_range_indices_are_refused() {
        let (mut sim, _) = small_checkpoint();
        let n = sim.world.bodies.len();
        sim.contacts[0].body = n + 5;
        let e =
            Simulation::from_checkpoint_bytes("i.h5", sim.checkpoint_bytes().unwrap()).unwrap_err();
        match &e {
            CheckpointError::Invalid { location, .. } => assert_eq!(location, "/contacts/body"),
            other => panic!("{other}"),
        }
    }

    pub fn non_finite_parameters_are_not_written() {
        let mut sim = Simulation::new(Scene::Box.build(3, 1), Params::default()).unwrap();
        sim.params.activation.delta = f64::INFINITY;
        let e = sim.checkpoint_bytes().unwrap_err();
        assert!(matches!(e, CheckpointError::Unrepresentable(_)), "{e}");
    }

    /// The stored bytes of `values` (little-endian f64) inside `bytes`: their offset.
    fn find_f64s(bytes: &[u8], values: &[f64]) -> usize {
        let needle: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
        bytes
            .windows(needle.len())
            .position(|w| w == needle.as_slice())
            .expect("values stored contiguously")
    }

    pub fn a_changed_value_is_named_by_its_dataset() {
        let (sim, bytes) = small_checkpoint();
        let radii: Vec<f64> = sim.world.bodies.iter().map(|b| b.radius).collect();
        let masses: Vec<f64> = sim.world.bodies.iter().map(|b| b.mass).collect();
        for (values, dataset) in [(&radii, "bodies/radius"), (&masses, "bodies/mass")] {
            let at = find_f64s(&bytes, values);
            let mut bad = bytes.clone();
            bad[at + 8 * 3 + 2] ^= 0x01;
            let e = Simulation::from_checkpoint_bytes("f.h5", bad).unwrap_err();
            match &e {
                CheckpointError::Checksum { dataset: d, .. } => {
                    assert_eq!(d.as_deref(), Some(dataset), "{e}")
                }
                _ => panic!("{e}"),
            }
            assert!(e.to_string().contains(&format!("at /{dataset}:")), "{e}");
        }
    }

    pub fn a_dataset_of_the_wrong_length_is_the_one_named() {
        let (sim, _) = small_checkpoint();
        let good = entries(&sim).unwrap();
        for (dataset, cut) in [
            ("bodies/position", 3),
            ("bodies/velocity", 3),
            ("bodies/mass", 1),
            ("contacts/gap", 1),
            ("contacts/partner_kind", 1),
            ("warm_start/impulse", 3),
        ] {
            let mut e = good.clone();
            let entry = e.iter_mut().find(|x| x.0 == dataset).unwrap();
            match &mut entry.2 {
                Data::F64(v) => v.truncate(v.len() - cut),
                Data::U8(v) => v.truncate(v.len() - cut),
                Data::I64(v) => v.truncate(v.len() - cut),
                Data::Str(_) => unreachable!(),
            }
            let bytes = encode_entries(FORMAT_NAME, FORMAT_VERSION, &e).unwrap();
            let err = Simulation::from_checkpoint_bytes("f.h5", bytes).unwrap_err();
            match &err {
                CheckpointError::Invalid { location, .. } => {
                    assert_eq!(location, &format!("/{dataset}"), "{err}")
                }
                _ => panic!("{dataset}: {err}"),
            }
        }
    }
}
