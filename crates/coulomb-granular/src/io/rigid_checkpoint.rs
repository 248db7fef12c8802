//! Checkpoint and restart of a rigid-body scene ([`RigidScene`]): the state the Moreau–Jean
//! step (2.7)–(2.10) of [`crate::step::rigid::RigidWorld`] carries from t_k to t_{k+1}, in one HDF5
//! file written atomically, so that running 2K steps and running K steps, saving, loading and
//! running K more give the same bits (test `restart_gives_the_same_bits`).
//!
//! # What is stored
//! - the scene model the world was built from (`/json/model`: bodies with their shapes,
//!   materials, obstacles and motions, gravity, step settings); loading rebuilds the world
//!   from it, so the shapes, mass properties and obstacles are those of the original run;
//! - t_k and k (`/state/…`);
//! - per body the centre of mass x, the orientation q of its principal frame (w, x, y, z),
//!   v and the body-frame Ω (`/bodies/…`, numeric, bit for bit);
//! - the last step's impulses by contact key, the next step's warm start (`/warm_start/…`);
//! - the detector's pair caches (`/json/detector`, through parry3d's serde support): parry
//!   starts a pair's next GJK from its stored normal and, when the pose barely moved, updates
//!   the stored manifold points instead of recomputing them, so without them the continued
//!   run would differ in the last bits;
//! - the last step's contacts (`/contacts/…`, read by the outputs only): the sphere
//!   checkpoint's datasets ([`crate::checkpoint`]), written and read by the same code, since
//!   every scene's contact record is one [`Contact`] (version 6; versions 1 to 5 stored them
//!   as JSON, `/json/contacts`, without t₂ and u_{N,k}: t₂ = n × t₁ is recomputed and u_{N,k}
//!   read as NaN, unknown);
//! - per joint the last step's impulses by row slot, the next step's warm start, and its
//!   force and torque (`/joints/…`; version 2, absent from version-1 files, which are still
//!   read when their scene has no joint);
//! - the step's settings are the model's (`/json/model`, its `step`): version 3 stored γ,
//!   projection, gap closure and warm start apart (`/json/switches`, read into the model's
//!   step), versions 1 and 2 had the defaults;
//! - the library solver's settings and `keep_problem` (`/json/library`, `LibrarySettings`:
//!   `RigidWorld::set_solver`, `set_keep_problem`; version 4, the scene's defaults for older
//!   files);
//! - whether the world has switched to plain Gauss–Seidel sweeps (`/state/plain_sweeps`, 0 or
//!   1: `RigidWorld`'s `plain_sweeps`, set by the first step that the library's quick finish
//!   solved; version 5, 0 for older files, which ran before the switch existed).
//!
//! Not stored: the step reports and the last step's problem (reports of the steps already
//! taken). A sphere-only scene has its own checkpoint ([`crate::checkpoint`]); the `format`
//! attribute tells them apart ([`crate::checkpoint::format_of`]).
//!
//! # Layout and integrity
//! Root attributes as in [`crate::checkpoint`] with `format` = [`FORMAT_NAME`] and
//! `format_version` = [`FORMAT_VERSION`]; the same checks on reading (format, version, types
//! and shapes, CRC-32), and the stored state checked against the rebuilt world (row counts,
//! finite values, unit quaternions, fixed bodies at rest, indices in range): any failure is a
//! [`CheckpointError`] and no scene is returned.
//!
//! | dataset | type | shape |
//! |---|---|---|
//! | `/state/time` | f64 | (1,) |
//! | `/state/steps_done`, `/state/plain_sweeps` (version 5) | i64 | (1,) |
//! | `/bodies/position`, `velocity`, `angular_velocity` | f64 | (n, 3) |
//! | `/bodies/orientation` | f64 | (n, 4) |
//! | `/warm_start/key` | i64 (body A, partner kind 0 body / 1 obstacle, partner index, sub-shape A, sub-shape B, feature A, feature B, rank) | (m, 8) |
//! | `/warm_start/impulse` | f64, world axes | (m, 3) |
//! | `/contacts/…` (version 6) | as in [`crate::checkpoint`] | (c, …) |
//! | `/json/model`, `/json/detector` | UTF-8 string | scalar |
//! | `/json/contacts` (versions 1 to 5) | UTF-8 string | scalar |
//! | `/joints/warm_start` | f64, by row slot | (joints, `SLOTS`) |
//! | `/joints/force` | f64, force and torque, world axes | (joints, 6) |
//! | `/json/library` (versions 4 on), `/json/switches` (version 3 only) | UTF-8 string | scalar |

use crate::bodies::joints::SLOTS;
use crate::checkpoint::{
    check_rows, encode_entries, index, json_of, open, push_contacts, read_checked, read_file,
    write_file, CheckpointError, Cursor, Data, Entry, Reader,
};
use crate::collision::contact::{Contact, ContactJson, Partner};
use crate::collision::manifold::ContactKey;
use crate::model::SceneModel;
use crate::scene::rigid::RigidScene;
use crate::step::rigid::{LibrarySettings, RigidState};
use std::path::Path;

/// The `format` attribute of a rigid-scene checkpoint.
pub const FORMAT_NAME: &str = "coulomb-rigid-checkpoint";
/// The `format_version` attribute written (6: the contacts in the sphere checkpoint's
/// datasets). Versions 5 (the contacts as JSON), 4
/// (the step's settings in the model, the library solver's settings stored, no switch), 3
/// (the step's switches apart from the model, no library settings), 2 (before the switches
/// were stored) and 1 (before joints were, for scenes without joints) are still read; other
/// versions are refused.
pub const FORMAT_VERSION: i64 = 6;

/// `/json/switches` of a version-3 file: the step settings now in the model's step.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct V3Switches {
    gamma: f64,
    projection: bool,
    gap_closure: bool,
    warm_start: bool,
}

/// Columns of `/warm_start/key`.
const KEY_COLUMNS: usize = 8;

fn flat<const N: usize>(rows: &[[f64; N]]) -> Vec<f64> {
    rows.iter().flatten().copied().collect()
}

/// The datasets of a checkpoint of `state` built from `model`, in their fixed order.
fn entries(model: &SceneModel, state: &RigidState) -> Result<Vec<Entry>, CheckpointError> {
    let mut keys = Vec::with_capacity(KEY_COLUMNS * state.previous.len());
    for ((a, b, s1, s2, f1, f2, rank), _) in &state.previous {
        let (kind, j) = match b {
            Partner::Body(j) => (0, *j),
            Partner::Obstacle(o, _) => (1, *o),
        };
        keys.extend([index(*a), kind, index(j)]);
        keys.extend([s1, s2, f1, f2, rank].map(|x| i64::from(*x)));
    }
    let impulses: Vec<[f64; 3]> = state.previous.iter().map(|(_, r)| *r).collect();
    let mut e = vec![
        ("state/time", 1, Data::F64(vec![state.time])),
        (
            "state/steps_done",
            1,
            Data::I64(vec![i64::try_from(state.steps).unwrap_or(i64::MAX)]),
        ),
        (
            "state/plain_sweeps",
            1,
            Data::I64(vec![i64::from(state.plain_sweeps)]),
        ),
        ("bodies/position", 3, Data::F64(flat(&state.x))),
        ("bodies/orientation", 4, Data::F64(flat(&state.q))),
        ("bodies/velocity", 3, Data::F64(flat(&state.v))),
        ("bodies/angular_velocity", 3, Data::F64(flat(&state.omega))),
        ("warm_start/key", KEY_COLUMNS, Data::I64(keys)),
        ("warm_start/impulse", 3, Data::F64(flat(&impulses))),
    ];
    push_contacts(&mut e, &state.contacts);
    e.extend([
        (
            "json/model",
            0,
            Data::Str(json_of("the scene model", model)?),
        ),
        ("json/detector", 0, Data::Str(state.detector.clone())),
        (
            "json/library",
            0,
            Data::Str(json_of(
                "the library solver's settings",
                &state.library.clone().unwrap_or(LibrarySettings {
                    solver: Default::default(),
                    keep_problem: true,
                }),
            )?),
        ),
        (
            "joints/warm_start",
            SLOTS,
            Data::F64(flat(&state.joint_warm)),
        ),
        ("joints/force", 6, Data::F64(flat(&state.joint_forces))),
    ]);
    Ok(e)
}

/// The datasets of a version-`v` checkpoint of `state` built from `model`: those of
/// [`entries`] as a file of that version holds them ([`older`]), the contacts as JSON before
/// version 6.
fn entries_of(
    v: i64,
    model: &SceneModel,
    state: &RigidState,
) -> Result<Vec<Entry>, CheckpointError> {
    let e = entries(model, state)?;
    if v >= 6 {
        return Ok(older(v, e));
    }
    let stored: Vec<ContactJson> = state.contacts.iter().map(ContactJson::from).collect();
    let json = json_of("the contacts", &stored)?;
    let mut e = older(v, e);
    let at = e
        .iter()
        .position(|(p, _, _)| *p == "json/model")
        .map_or(0, |i| i + 1);
    e.insert(at, ("json/contacts", 0, Data::Str(json)));
    Ok(e)
}

/// `values` as rows of `N`, `n` of them when given.
fn rows<const N: usize>(
    r: &Reader<'_>,
    path: &str,
    values: Vec<f64>,
    n: Option<usize>,
) -> Result<Vec<[f64; N]>, CheckpointError> {
    if values.len() % N != 0 || n.is_some_and(|n| values.len() != N * n) {
        return Err(r.invalid(
            path,
            format!("{} values, expected {N} per body", values.len()),
        ));
    }
    Ok(values
        .chunks_exact(N)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect())
}

/// The warm-start keys of `/warm_start/key`, each a valid key shape (indices ≥ 0 and within
/// u32 where the key holds u32; the ranges are checked against the world on restore).
fn keys(r: &Reader<'_>, raw: &[i64]) -> Result<Vec<ContactKey>, CheckpointError> {
    let path = "warm_start/key";
    let mut out = Vec::with_capacity(raw.len() / KEY_COLUMNS);
    for (i, k) in raw.chunks_exact(KEY_COLUMNS).enumerate() {
        let bad = || r.invalid(path, format!("row {i}: {k:?}"));
        let us = |x: i64| usize::try_from(x).map_err(|_| bad());
        let u32_of = |x: i64| u32::try_from(x).map_err(|_| bad());
        let b = match k[1] {
            0 => Partner::Body(us(k[2])?),
            1 => Partner::Obstacle(us(k[2])?, 0),
            _ => return Err(bad()),
        };
        out.push((
            us(k[0])?,
            b,
            u32_of(k[3])?,
            u32_of(k[4])?,
            u32_of(k[5])?,
            u32_of(k[6])?,
            u32_of(k[7])?,
        ));
    }
    if !out.windows(2).all(|w| w[0] < w[1]) {
        return Err(r.invalid(path, "keys not sorted and unique"));
    }
    Ok(out)
}

/// The layout of a checkpoint of `version` (paths, columns, types): version 1 has no
/// `/joints/…` datasets, only version 3 has `/json/switches`, versions 1 to 3 no
/// `/json/library`, versions 1 to 4 no `/state/plain_sweeps`.
fn layout(version: i64) -> Result<Vec<Entry>, CheckpointError> {
    let empty = RigidState {
        time: 0.0,
        steps: 0,
        x: Vec::new(),
        q: Vec::new(),
        v: Vec::new(),
        omega: Vec::new(),
        previous: Vec::new(),
        contacts: Vec::new(),
        detector: String::new(),
        joint_warm: Vec::new(),
        joint_forces: Vec::new(),
        library: None,
        plain_sweeps: false,
    };
    entries_of(version, &SceneModel::default(), &empty)
}

/// The datasets `e` of the current version as a version-`v` file holds them, without the
/// contacts before version 6 ([`entries_of`] adds their JSON).
fn older(v: i64, e: Vec<Entry>) -> Vec<Entry> {
    let mut e: Vec<Entry> = e
        .into_iter()
        .filter(|(p, _, _)| {
            (v > 5 || !p.starts_with("contacts/"))
                && (v > 1 || !p.starts_with("joints/"))
                && (v > 3 || *p != "json/library")
                && (v > 4 || *p != "state/plain_sweeps")
        })
        .collect();
    if v == 3 {
        // with the other json/ datasets: the writer groups datasets by their first component
        let at = e
            .iter()
            .position(|(p, _, _)| *p == "json/detector")
            .map_or(0, |i| i + 1);
        e.insert(at, ("json/switches", 0, Data::Str(String::new())));
    }
    e
}

fn decode_file(r: &Reader<'_>) -> Result<RigidScene, CheckpointError> {
    let layout_now = layout(FORMAT_VERSION)?;
    let (read, version) = match read_checked(r, FORMAT_NAME, FORMAT_VERSION, &layout_now) {
        Err(CheckpointError::Version { found, .. }) if (1..=5).contains(&found) => {
            (read_checked(r, FORMAT_NAME, found, &layout(found)?)?, found)
        }
        other => (other?, FORMAT_VERSION),
    };
    // one row per body in each body dataset, one per entry in the warm start: a count that
    // differs is blamed on the dataset that differs
    check_rows(
        r,
        &read,
        &[
            &[
                "bodies/position",
                "bodies/orientation",
                "bodies/velocity",
                "bodies/angular_velocity",
            ],
            &["warm_start/key", "warm_start/impulse"],
        ],
    )?;
    let mut c = Cursor {
        r,
        entries: read.into_iter(),
    };
    let time = c.f64_scalar()?;
    let (sp, steps) = c.i64s()?;
    let steps = match steps.as_slice() {
        [k] => u64::try_from(*k).map_err(|_| r.invalid(sp, format!("{k} steps")))?,
        _ => return Err(r.invalid(sp, "expected one value")),
    };
    let plain_sweeps = if version > 4 {
        let (pp, flag) = c.i64s()?;
        match flag.as_slice() {
            [0] => false,
            [1] => true,
            _ => return Err(r.invalid(pp, format!("{flag:?}, expected 0 or 1"))),
        }
    } else {
        false
    };
    let (pp, x) = c.f64s()?;
    let x: Vec<[f64; 3]> = rows(r, pp, x, None)?;
    let n = Some(x.len());
    let (p, q) = c.f64s()?;
    let q: Vec<[f64; 4]> = rows(r, p, q, n)?;
    let (p, v) = c.f64s()?;
    let v: Vec<[f64; 3]> = rows(r, p, v, n)?;
    let (p, omega) = c.f64s()?;
    let omega: Vec<[f64; 3]> = rows(r, p, omega, n)?;
    let (_, raw) = c.i64s()?;
    let keys = keys(r, &raw)?;
    let (p, imp) = c.f64s()?;
    let imp: Vec<[f64; 3]> = rows(r, p, imp, Some(keys.len()))?;
    // obstacle partners are checked against the world that the model builds (`restore`)
    let contacts = if version > 5 {
        Some(c.contacts(x.len(), usize::MAX)?)
    } else {
        None
    };
    // a pair of materials written before the pairs became the scene file's `[[pairs]]`
    // (`MaterialPair`) names its materials `a` and `b`: read as `materials = [a, b]`
    let mut json: serde_json::Value = c.json()?;
    let pairs = json.pointer_mut("/materials/pairs");
    for p in pairs.and_then(|p| p.as_array_mut()).into_iter().flatten() {
        if let Some(p) = p.as_object_mut().filter(|p| p.contains_key("a")) {
            let ab = [p.remove("a"), p.remove("b")];
            p.insert("materials".into(), serde_json::json!(ab));
        }
    }
    let mut model: SceneModel =
        serde_json::from_value(json).map_err(|e| r.invalid("json/model", format!("JSON: {e}")))?;
    let contacts = match contacts {
        Some(c) => c,
        None => (c.json::<Vec<ContactJson>>()?.into_iter())
            .map(Contact::from)
            .collect(),
    };
    let (dp, detector) = match c.entries.next() {
        Some((p, _, Data::Str(s))) => (p, s),
        _ => return Err(r.corrupt("json/detector", "expected a string")),
    };
    if version == 3 {
        let w: V3Switches = c.json()?;
        let s = &mut model.step;
        (s.gamma, s.projection, s.gap_closure, s.warm_start) =
            (w.gamma, w.projection, w.gap_closure, w.warm_start);
    }
    let library: Option<LibrarySettings> = if version > 3 { Some(c.json()?) } else { None };
    let (joint_warm, joint_forces) = if version == 1 {
        if !model.joints.is_empty() {
            return Err(r.invalid(
                "json/model",
                "a version-1 checkpoint cannot hold joints (the scene has some)",
            ));
        }
        (Vec::new(), Vec::new())
    } else {
        let nj = Some(model.joints.len());
        let (p, w) = c.f64s()?;
        let w: Vec<[f64; SLOTS]> = rows(r, p, w, nj)?;
        let (p, f) = c.f64s()?;
        let f: Vec<[f64; 6]> = rows(r, p, f, nj)?;
        (w, f)
    };
    let mut scene = RigidScene::for_restore(&model)
        .map_err(|e| r.invalid("json/model", format!("the stored scene: {e}")))?;
    // the state's checks, each on the dataset it reads (those left to `restore` — a fixed
    // body that moved, the detector's caches — name the rest)
    let n = scene.world.len();
    if x.len() != n {
        return Err(r.invalid(
            "bodies/position",
            format!(
                "{} rows (as the other body datasets) for the {n} bodies of /json/model",
                x.len()
            ),
        ));
    }
    if !(time.is_finite() && time >= 0.0) {
        return Err(r.invalid("state/time", format!("time {time}")));
    }
    for (path, rows) in [
        ("bodies/position", &x),
        ("bodies/velocity", &v),
        ("bodies/angular_velocity", &omega),
    ] {
        if let Some(i) = rows.iter().position(|a| !a.iter().all(|c| c.is_finite())) {
            return Err(r.invalid(path, format!("row {i}: {:?} is not finite", rows[i])));
        }
    }
    for (i, qi) in q.iter().enumerate() {
        crate::shape::check_quaternion(&format!("row {i}"), *qi)
            .map_err(|e| r.invalid("bodies/orientation", e))?;
    }
    if let Some(i) = imp.iter().position(|a| !a.iter().all(|c| c.is_finite())) {
        return Err(r.invalid(
            "warm_start/impulse",
            format!("row {i}: {:?} is not finite", imp[i]),
        ));
    }
    let state = RigidState {
        time,
        steps,
        x,
        q,
        v,
        omega,
        previous: keys.into_iter().zip(imp).collect(),
        contacts,
        detector,
        joint_warm,
        joint_forces,
        library,
        plain_sweeps,
    };
    scene.world.restore(state).map_err(|e| {
        // what `restore` still checks: fixed bodies at rest ("body i …"), warm-start and
        // contact pairs in range, the detector's caches
        let at = if e.starts_with("body ") {
            "bodies"
        } else if e.starts_with("warm start") {
            "warm_start/key"
        } else if e.starts_with("contact") {
            if version > 5 {
                "contacts/partner_index"
            } else {
                "json/contacts"
            }
        } else if e.starts_with("joints") {
            "joints/warm_start"
        } else if e.starts_with("the library solver") {
            "json/library"
        } else {
            dp
        };
        r.invalid(at, e)
    })?;
    Ok(scene)
}

impl RigidScene {
    /// The checkpoint of this scene as the bytes of an HDF5 file (module
    /// [`crate::io::rigid_checkpoint`]).
    pub fn checkpoint_bytes(&self) -> Result<Vec<u8>, CheckpointError> {
        let state = self
            .world
            .state()
            .map_err(|e| CheckpointError::Unrepresentable(format!("the detector's caches: {e}")))?;
        encode_entries(FORMAT_NAME, FORMAT_VERSION, &entries(&self.model, &state)?)
    }

    /// The scene stored in the bytes of a rigid checkpoint; `name` names it in errors.
    pub fn from_checkpoint_bytes(
        name: impl AsRef<Path>,
        bytes: Vec<u8>,
    ) -> Result<RigidScene, CheckpointError> {
        open(name.as_ref(), bytes, decode_file)
    }

    /// Writes the full state of the scene into the HDF5 file `path`, atomically (an existing
    /// file is replaced only by a complete one; a path that is not a regular file is refused
    /// by [`coulomb::atomic::write`]).
    pub fn save_checkpoint(&self, path: impl AsRef<Path>) -> Result<(), CheckpointError> {
        write_file(path.as_ref(), self.checkpoint_bytes()?)
    }

    /// The scene stored by [`RigidScene::save_checkpoint`] in `path`: stepping it gives the
    /// same bits as stepping the saved one. A sphere checkpoint, another format version, a
    /// damaged file or a state the rebuilt world refuses give a [`CheckpointError`].
    pub fn load_checkpoint(path: impl AsRef<Path>) -> Result<RigidScene, CheckpointError> {
        let path = path.as_ref();
        Self::from_checkpoint_bytes(path, read_file(path)?)
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::scene_file::LoadedScene;

    fn scene(toml: &str) -> RigidScene {
        let loaded = LoadedScene::parse(Path::new("mixed.toml"), toml.to_string(), true)
            .expect("scene file");
        let built = loaded.build(&Default::default()).expect("build");
        RigidScene::new(&built.model).expect("rigid scene")
    }

    /// Bodies of several shapes (cuboid, convex hull, compound of a cuboid and a capsule,
    /// sphere) falling onto a floor and a ramp of two triangles (a mesh), so that the pair
    /// caches hold convex and composite manifolds and composite workspaces.
    const MIXED: &str = r#"
        [step]
        h = 0.005
        tol = 1e-8

        [default_pair]
        mu = 0.4

        [[obstacles]]
        name = "floor"
        shape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }

        [[obstacles]]
        name = "ramp"
        [obstacles.shape]
        kind = "rectangle"
        center = [0.0, 0.3, 0.05]
        normal = [0.0, -0.2425356250363330, 0.9701425001453319]
        u = [1.0, 0.0, 0.0]
        half_u = 0.4
        half_v = 0.1

        [[bodies]]
        shape = { kind = "cuboid", half_extents = [0.05, 0.04, 0.03] }
        positions = [[0.0, 0.0, 0.05], [0.0, 0.3, 0.2]]

        [[bodies]]
        shape = { kind = "convex_hull", points = [[0.0, 0.0, 0.0], [0.08, 0.0, 0.0], [0.0, 0.07, 0.0], [0.0, 0.0, 0.06], [0.05, 0.05, 0.05]] }
        positions = [[0.2, 0.0, 0.15]]
        orientations = [[0.9238795325112867, 0.0, 0.3826834323650898, 0.0]]

        [[bodies]]
        positions = [[-0.2, 0.0, 0.08]]
        angular_velocity = [0.0, 3.0, 1.0]
        [bodies.shape]
        kind = "compound"
        parts = [
            { shape = { kind = "cuboid", half_extents = [0.03, 0.03, 0.03] }, position = [0.0, 0.0, 0.0] },
            { shape = { kind = "capsule", radius = 0.02, half_height = 0.04 }, position = [0.0, 0.06, 0.0] },
        ]

        [[bodies]]
        shape = { kind = "sphere", radius = 0.03 }
        positions = [[0.0, 0.0, 0.2]]
        velocity = [0.5, 0.0, 0.0]
    "#;

    /// Positions, orientations, velocities and angular velocities, as bits.
    fn snapshot(s: &RigidScene) -> Vec<u64> {
        let w = &s.world;
        let mut bits: Vec<u64> = w
            .positions()
            .iter()
            .flatten()
            .map(|x| x.to_bits())
            .collect();
        bits.extend(w.orientations().iter().flatten().map(|x| x.to_bits()));
        bits.extend(w.velocities().iter().flatten().map(|x| x.to_bits()));
        bits.extend(w.angular_velocities().iter().flatten().map(|x| x.to_bits()));
        bits
    }

    pub fn restart_gives_the_same_bits() {
        let mut a = scene(MIXED);
        for _ in 0..40 {
            a.step().expect("step");
        }
        let bytes = a.checkpoint_bytes().expect("checkpoint");
        let mut b = RigidScene::from_checkpoint_bytes("mixed.h5", bytes).expect("load");
        assert_eq!(b.world.time(), a.world.time());
        assert_eq!(b.world.steps(), a.world.steps());
        assert_eq!(snapshot(&b), snapshot(&a));
        assert_eq!(b.world.contacts(), a.world.contacts());
        assert!(!a.world.contacts().is_empty(), "the bodies touch something");
        for _ in 0..40 {
            let ra = a.step().expect("step a");
            let rb = b.step().expect("step b");
            assert_eq!(ra.contacts, rb.contacts);
            assert_eq!(ra.sweeps, rb.sweeps);
            assert_eq!(ra.error.to_bits(), rb.error.to_bits());
        }
        assert_eq!(snapshot(&b), snapshot(&a));
        assert_eq!(b.world.contacts(), a.world.contacts());
    }

    /// The switch to plain sweeps (`/state/plain_sweeps`) is restored, and a restart with it
    /// continues to the bit; a version-4 file (before it was stored) reads with it off, and a
    /// value other than 0 or 1 is refused, naming the dataset.
    pub fn the_switch_to_plain_sweeps_is_restored() {
        let mut a = scene(MIXED);
        for _ in 0..10 {
            a.step().expect("step");
        }
        let mut state = a.world.state().expect("state");
        assert!(!state.plain_sweeps);
        state.plain_sweeps = true;
        let bytes = encode_entries(
            FORMAT_NAME,
            FORMAT_VERSION,
            &entries(&a.model, &state).expect("entries"),
        )
        .expect("bytes");
        let mut b = RigidScene::from_checkpoint_bytes("plain.h5", bytes).expect("load");
        assert!(b.world.plain_sweeps());
        for _ in 0..5 {
            b.step().expect("b");
        }
        let again = b.checkpoint_bytes().expect("bytes");
        let mut c = RigidScene::from_checkpoint_bytes("again.h5", again).expect("load");
        assert!(c.world.plain_sweeps());
        for _ in 0..5 {
            let rb = b.step().expect("b");
            let rc = c.step().expect("c");
            assert_eq!(rb.sweeps, rc.sweeps);
        }
        assert_eq!(snapshot(&c), snapshot(&b));
        // version 4: off
        let v4 = entries_of(4, &a.model, &state).expect("entries");
        assert!(v4.iter().all(|(p, _, _)| *p != "state/plain_sweeps"));
        let bytes = encode_entries(FORMAT_NAME, 4, &v4).expect("v4 bytes");
        let d = RigidScene::from_checkpoint_bytes("v4.h5", bytes).expect("v4 loads");
        assert!(!d.world.plain_sweeps());
        // neither 0 nor 1
        let mut e = entries(&a.model, &state).expect("entries");
        for (p, _, data) in e.iter_mut() {
            if *p == "state/plain_sweeps" {
                *data = Data::I64(vec![2]);
            }
        }
        let bytes = encode_entries(FORMAT_NAME, FORMAT_VERSION, &e).expect("bytes");
        let err = RigidScene::from_checkpoint_bytes("two.h5", bytes).expect_err("2 read");
        assert!(err.to_string().contains("state/plain_sweeps"), "{err}");
    }

    /// The model's step settings (γ, projection, gap closure, warm start among them) are
    /// restored with it, and a version-3 file's `/json/switches` goes into the model's step.
    pub fn the_library_settings_are_restored() {
        let mut a = scene(MIXED);
        let solver = coulomb::solver::Settings {
            max_outer: 17,
            max_inner: 33,
            ..Default::default()
        };
        a.world.set_solver(solver.clone());
        a.world.set_keep_problem(false);
        for _ in 0..3 {
            a.step().expect("step");
        }
        let bytes = a.checkpoint_bytes().expect("bytes");
        let mut b = RigidScene::from_checkpoint_bytes("library.h5", bytes).expect("load");
        assert_eq!(b.world.settings().solver, solver);
        assert!(!b.world.settings().keep_problem);
        a.step().expect("a");
        b.step().expect("b");
        assert_eq!(snapshot(&b), snapshot(&a));
        assert!(b.world.last_problem().is_none());
        // a version-2 file (before they were stored) gives the scene's defaults
        let state = a.world.state().expect("state");
        let v2 = entries_of(2, &a.model, &state).expect("entries");
        let bytes = encode_entries(FORMAT_NAME, 2, &v2).expect("v2 bytes");
        let c = RigidScene::from_checkpoint_bytes("v2.h5", bytes).expect("v2 loads");
        assert_eq!(c.world.settings().solver, Default::default());
        assert!(c.world.settings().keep_problem);
        // settings the library refuses are refused on reading, naming the dataset
        let mut bad = a.world.state().expect("state");
        if let Some(l) = bad.library.as_mut() {
            l.solver.max_outer = 0;
        }
        let bytes = encode_entries(
            FORMAT_NAME,
            FORMAT_VERSION,
            &entries(&a.model, &bad).expect("entries"),
        )
        .expect("bytes");
        let Err(err) = RigidScene::from_checkpoint_bytes("bad.h5", bytes) else {
            panic!("a checkpoint with max_outer = 0 was read");
        };
        let err = err.to_string();
        assert!(
            err.contains("json/library") && err.contains("max_outer"),
            "{err}"
        );
    }

    pub fn the_step_switches_are_restored() {
        let mut model = scene(MIXED).model;
        let s = &mut model.step;
        (s.gamma, s.projection, s.gap_closure, s.warm_start) = (0.5, false, false, false);
        let mut a = RigidScene::new(&model).expect("scene");
        for _ in 0..10 {
            a.step().expect("step");
        }
        let bytes = a.checkpoint_bytes().expect("checkpoint");
        let mut b = RigidScene::from_checkpoint_bytes("switches.h5", bytes).expect("load");
        assert_eq!(b.model.step, model.step);
        assert_eq!(b.world.settings(), a.world.settings());
        // the same state as a version-3 file: the model with default switches, the switches
        // apart
        let state = a.world.state().expect("state");
        let mut v3 = entries_of(3, &scene(MIXED).model, &state).expect("entries");
        for e in &mut v3 {
            if e.0 == "json/switches" {
                e.2 = Data::Str(
                    r#"{"gamma":0.5,"projection":false,"gap_closure":false,"warm_start":false}"#
                        .into(),
                );
            }
        }
        let bytes = encode_entries(FORMAT_NAME, 3, &v3).expect("v3 bytes");
        let c = RigidScene::from_checkpoint_bytes("v3.h5", bytes).expect("v3 loads");
        assert_eq!(c.model.step, model.step);
        assert_eq!(c.world.settings(), a.world.settings());
        for _ in 0..10 {
            assert_eq!(a.step().expect("a").warm_started, 0);
            b.step().expect("b");
        }
        assert_eq!(snapshot(&b), snapshot(&a));
    }

    pub fn the_shipped_wall_restarts_to_the_bit() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/scenes/rigid/brick-wall.toml"
        );
        let loaded = LoadedScene::load(Path::new(path)).expect("load");
        let built = loaded.build(&Default::default()).expect("build");
        let mut a = RigidScene::new(&built.model).expect("scene");
        for _ in 0..5 {
            a.step().expect("step");
        }
        let mut b =
            RigidScene::from_checkpoint_bytes("wall.h5", a.checkpoint_bytes().expect("save"))
                .expect("load");
        for _ in 0..5 {
            a.step().expect("step a");
            b.step().expect("step b");
        }
        assert_eq!(snapshot(&b), snapshot(&a));
    }

    /// The shipped pendulum chain (8 links on revolute joints) swinging into its brick wall:
    /// the joints' warm starts and forces are stored, so the continued run gives the bits of
    /// the uninterrupted one.
    pub fn a_scene_with_joints_restarts_to_the_bit() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/scenes/rigid/pendulum-chain.toml"
        );
        let loaded = LoadedScene::load(Path::new(path)).expect("load");
        let built = loaded.build(&Default::default()).expect("build");
        let mut a = RigidScene::new(&built.model).expect("scene");
        for _ in 0..60 {
            a.step().expect("step");
        }
        let mut b =
            RigidScene::from_checkpoint_bytes("chain.h5", a.checkpoint_bytes().expect("save"))
                .expect("load");
        assert_eq!(b.world.joint_forces(), a.world.joint_forces());
        for _ in 0..60 {
            let ra = a.step().expect("step a");
            let rb = b.step().expect("step b");
            assert_eq!(ra.sweeps, rb.sweeps);
            assert_eq!(ra.error.to_bits(), rb.error.to_bits());
        }
        assert_eq!(snapshot(&b), snapshot(&a));
        let bits = |s: &RigidScene| -> Vec<u64> {
            s.world
                .joint_forces()
                .iter()
                .flatten()
                .map(|x| x.to_bits())
                .collect()
        };
        assert_eq!(bits(&b), bits(&a));
        assert!(a.world.joint_forces()[0].iter().any(|f| *f != 0.0));
    }

    /// A version-1 file (written before the joints' datasets existed) still reads for a scene
    /// without joints, and is refused, naming the dataset, for a scene with some.
    pub fn version_one_files_read_without_joints() {
        let mut a = scene(MIXED);
        for _ in 0..5 {
            a.step().expect("step");
        }
        let state = a.world.state().expect("state");
        let v1 = entries_of(1, &a.model, &state).expect("entries");
        let bytes = encode_entries(FORMAT_NAME, 1, &v1).expect("v1 bytes");
        let mut b = RigidScene::from_checkpoint_bytes("v1.h5", bytes).expect("v1 loads");
        let v2 = entries_of(2, &a.model, &state).expect("entries");
        let bytes = encode_entries(FORMAT_NAME, 2, &v2).expect("v2 bytes");
        let mut b2 = RigidScene::from_checkpoint_bytes("v2.h5", bytes).expect("v2 loads");
        a.step().expect("a");
        b.step().expect("b");
        b2.step().expect("b2");
        assert_eq!(snapshot(&b), snapshot(&a));
        assert_eq!(snapshot(&b2), snapshot(&a));
        // a version-1 file whose model has joints cannot be continued to the bit
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/scenes/rigid/pendulum-chain.toml"
        );
        let loaded = LoadedScene::load(Path::new(path)).expect("load");
        let built = loaded.build(&Default::default()).expect("build");
        let c = RigidScene::new(&built.model).expect("scene");
        let state = c.world.state().expect("state");
        let v1 = entries_of(1, &c.model, &state).expect("entries");
        let bytes = encode_entries(FORMAT_NAME, 1, &v1).expect("v1 bytes");
        let e = RigidScene::from_checkpoint_bytes("v1j.h5", bytes).expect_err("joints in v1");
        assert!(e.to_string().contains("json/model"), "{e}");
        // and another version is refused
        let bytes = encode_entries(
            FORMAT_NAME,
            FORMAT_VERSION + 1,
            &entries(&a.model, &a.world.state().expect("s")).expect("e"),
        )
        .expect("next version's bytes");
        let e = RigidScene::from_checkpoint_bytes("v7.h5", bytes).expect_err("v7");
        assert!(
            matches!(e, CheckpointError::Version { found, .. } if found == FORMAT_VERSION + 1),
            "{e}"
        );
    }

    /// Version 6 stores the contacts in the sphere checkpoint's datasets, every field of the
    /// one contact record; a version-5 file's JSON contacts read as the same contacts, t₂
    /// recomputed as n × t₁ and u_{N,k}, which they did not hold, NaN; both continue to the
    /// bit.
    pub fn contacts_are_the_sphere_checkpoints_and_version_5_json_still_reads() {
        let mut a = scene(MIXED);
        for _ in 0..40 {
            a.step().expect("step");
        }
        let state = a.world.state().expect("state");
        assert!(!state.contacts.is_empty());
        let now = entries(&a.model, &state).expect("entries");
        assert!(now.iter().any(|(p, _, _)| *p == "contacts/normal_velocity"));
        assert!(now.iter().all(|(p, _, _)| *p != "json/contacts"));
        let b = RigidScene::from_checkpoint_bytes("v6.h5", a.checkpoint_bytes().expect("bytes"))
            .expect("v6 loads");
        assert_eq!(b.world.contacts(), a.world.contacts());
        let v5 = entries_of(5, &a.model, &state).expect("entries");
        assert!(v5.iter().all(|(p, _, _)| !p.starts_with("contacts/")));
        let bytes = encode_entries(FORMAT_NAME, 5, &v5).expect("v5 bytes");
        let mut c = RigidScene::from_checkpoint_bytes("v5.h5", bytes).expect("v5 loads");
        for (x, y) in c.world.contacts().iter().zip(a.world.contacts()) {
            assert!(x.normal_velocity.is_nan() && y.normal_velocity.is_finite());
            let (mut x, mut y) = (x.clone(), y.clone());
            (x.normal_velocity, y.normal_velocity) = (0.0, 0.0);
            assert_eq!(x, y);
        }
        assert_eq!(c.world.contacts().len(), a.world.contacts().len());
        let mut b = b;
        for _ in 0..3 {
            a.step().expect("a");
            b.step().expect("b");
            c.step().expect("c");
        }
        assert_eq!(snapshot(&b), snapshot(&a));
        assert_eq!(snapshot(&c), snapshot(&a));
        // a contact whose partner is not in the world is refused, naming the dataset
        let mut e = entries(&a.model, &a.world.state().expect("state")).expect("entries");
        for (p, _, d) in e.iter_mut() {
            if *p == "contacts/partner_index" {
                if let Data::I64(v) = d {
                    v[0] = 1_000_000;
                }
            }
        }
        let bytes = encode_entries(FORMAT_NAME, FORMAT_VERSION, &e).expect("bytes");
        let err = RigidScene::from_checkpoint_bytes("far.h5", bytes).expect_err("partner");
        assert!(err.to_string().contains("contacts/partner_index"), "{err}");
    }

    /// A rigid checkpoint written before the pairs became the scene file's `[[pairs]]`
    /// stored each pair of materials as `{"a", "b", "mu", …}`: it reads as
    /// `materials = [a, b]`, gives the same model, and continues to the bit.
    pub fn pairs_written_as_a_and_b_read_as_the_same_materials() {
        let mut a = scene(
            r#"
            [step]
            h = 0.005
            tol = 1e-8

            [materials.wood]
            density = 600.0
            [materials.steel]
            density = 7800.0

            [default_pair]
            mu = 0.4

            [[pairs]]
            materials = ["wood", "steel"]
            mu = 0.7
            restitution = 0.1

            [[obstacles]]
            name = "floor"
            material = "steel"
            shape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }

            [[bodies]]
            material = "wood"
            shape = { kind = "cuboid", half_extents = [0.05, 0.04, 0.03] }
            positions = [[0.0, 0.0, 0.0305]]
            velocity = [0.4, 0.0, 0.0]
            "#,
        );
        for _ in 0..5 {
            a.step().expect("step");
        }
        let state = a.world.state().expect("state");
        let mut e = entries(&a.model, &state).expect("entries");
        let mut rewritten = 0;
        for (p, _, d) in &mut e {
            if let (true, Data::Str(json)) = (*p == "json/model", &mut *d) {
                let mut v: serde_json::Value = serde_json::from_str(json).expect("model JSON");
                let pairs = v.pointer_mut("/materials/pairs").expect("pairs");
                for pair in pairs.as_array_mut().expect("array") {
                    let o = pair.as_object_mut().expect("object");
                    let m = o.remove("materials").expect("materials");
                    o.insert("a".into(), m[0].clone());
                    o.insert("b".into(), m[1].clone());
                    rewritten += 1;
                }
                *json = v.to_string();
            }
        }
        assert_eq!(rewritten, 1, "the model holds one pair");
        let bytes = encode_entries(FORMAT_NAME, FORMAT_VERSION, &e).expect("encode");
        let mut b = RigidScene::from_checkpoint_bytes("old-pairs.h5", bytes).expect("old pairs");
        assert_eq!(
            serde_json::to_value(&b.model).expect("b"),
            serde_json::to_value(&a.model).expect("a")
        );
        for _ in 0..5 {
            a.step().expect("a");
            b.step().expect("b");
        }
        assert_eq!(snapshot(&b), snapshot(&a));
    }

    pub fn damaged_or_foreign_files_are_refused_with_a_reason() {
        let mut a = scene(MIXED);
        a.step().expect("step");
        let bytes = a.checkpoint_bytes().expect("checkpoint");
        // truncated
        let e = RigidScene::from_checkpoint_bytes("t.h5", bytes[..bytes.len() / 2].to_vec())
            .expect_err("truncated");
        assert!(
            matches!(
                e,
                CheckpointError::Corrupt { .. } | CheckpointError::Checksum { .. }
            ),
            "{e}"
        );
        // not HDF5
        let e = RigidScene::from_checkpoint_bytes("x.h5", b"not hdf5".to_vec()).expect_err("text");
        assert!(matches!(e, CheckpointError::NotHdf5 { .. }), "{e}");
        // a sphere checkpoint is another format
        let sim =
            crate::Simulation::new(crate::World::new(), crate::Params::default()).expect("empty");
        let e = RigidScene::from_checkpoint_bytes("s.h5", sim.checkpoint_bytes().expect("s"))
            .expect_err("sphere file");
        assert!(matches!(e, CheckpointError::WrongFormat { .. }), "{e}");
        // and a rigid one is not a sphere checkpoint
        let e = crate::Simulation::from_checkpoint_bytes("r.h5", bytes.clone())
            .expect_err("rigid file");
        assert!(matches!(e, CheckpointError::WrongFormat { .. }), "{e}");
        // a flipped byte in the data fails the checksum or the structure, never loads
        let mut flipped = 0;
        for at in (bytes.len() / 3..bytes.len()).step_by(97).take(40) {
            let mut b = bytes.clone();
            b[at] ^= 0x5a;
            if RigidScene::from_checkpoint_bytes("f.h5", b).is_err() {
                flipped += 1;
            }
        }
        assert!(flipped > 0);
    }

    pub fn a_state_that_does_not_fit_the_world_is_refused() {
        let mut a = scene(MIXED);
        a.step().expect("step");
        let good = a.world.state().expect("state");
        let mut w = scene(MIXED).world;
        let mut s = good.clone();
        s.x.pop();
        assert!(w.restore(s).unwrap_err().contains("body rows"));
        let mut s = good.clone();
        s.q[0] = [2.0, 0.0, 0.0, 0.0];
        assert!(w.restore(s).is_err());
        let mut s = good.clone();
        s.v[1][0] = f64::NAN;
        assert!(w.restore(s).unwrap_err().contains("non-finite"));
        let mut s = good.clone();
        s.detector = "{\"pairs\": [[[0, {\"kind\": \"body\", \"index\": 99}], {\"manifolds\": [], \"workspace\": null}]]}".into();
        assert!(w.restore(s).unwrap_err().contains("out of range"));
        assert!(w.restore(good).is_ok());
    }

    /// A checkpoint of MIXED with one dataset replaced by `edit` of it.
    fn edited(edit: impl Fn(&str, &mut Data)) -> Result<RigidScene, CheckpointError> {
        let mut a = scene(MIXED);
        for _ in 0..20 {
            a.step().expect("step");
        }
        let state = a.world.state().expect("state");
        let mut e = entries(&a.model, &state).expect("entries");
        for (p, _, d) in &mut e {
            edit(p, d);
        }
        let bytes = encode_entries(FORMAT_NAME, FORMAT_VERSION, &e).expect("encode");
        RigidScene::from_checkpoint_bytes("e.h5", bytes)
    }

    fn location(r: Result<RigidScene, CheckpointError>) -> String {
        match r {
            Err(CheckpointError::Invalid { location, .. }) => location,
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("loaded"),
        }
    }

    pub fn errors_name_the_dataset_that_is_wrong() {
        let f64s = |d: &mut Data| match d {
            Data::F64(v) => v.clone(),
            _ => unreachable!(),
        };
        // one row short: the short dataset, not the one read after it
        for (name, cols) in [
            ("bodies/position", 3),
            ("bodies/orientation", 4),
            ("bodies/angular_velocity", 3),
        ] {
            let at = location(edited(|p, d| {
                if p == name {
                    let mut v = f64s(d);
                    v.truncate(v.len() - cols);
                    *d = Data::F64(v);
                }
            }));
            assert_eq!(at, format!("/{name}"));
        }
        // a non-finite value or a quaternion that is not unit: its dataset
        for (name, k, x) in [
            ("bodies/velocity", 4, f64::NAN),
            ("bodies/orientation", 1, 0.5),
            ("bodies/position", 0, f64::INFINITY),
        ] {
            let at = location(edited(|p, d| {
                if p == name {
                    let mut v = f64s(d);
                    v[k] = x;
                    *d = Data::F64(v);
                }
            }));
            assert_eq!(at, format!("/{name}"));
        }
        let at = location(edited(|p, d| {
            if p == "state/time" {
                *d = Data::F64(vec![-1.0]);
            }
        }));
        assert_eq!(at, "/state/time");
        // a value changed after writing: the checksum names its dataset
        let mut a = scene(MIXED);
        a.step().expect("step");
        let bytes = a.checkpoint_bytes().expect("checkpoint");
        let v = a.world.velocities();
        let needle: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let at = bytes
            .windows(needle.len())
            .position(|w| w == needle.as_slice())
            .expect("velocities stored");
        let mut bad = bytes.clone();
        bad[at + 5] ^= 0x04;
        match RigidScene::from_checkpoint_bytes("c.h5", bad) {
            Err(CheckpointError::Checksum { dataset, .. }) => {
                assert_eq!(dataset.as_deref(), Some("bodies/velocity"))
            }
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("loaded"),
        }
    }
}
