//! Fuzzing of the simulator's input surfaces (issue 55, docs/fuzz.md "Third campaign"):
//! scene files (TOML), particle files (CSV), mesh files (OBJ, ASCII STL) and checkpoints
//! (sphere and rigid), each a valid file mutated by proptest — bytes flipped, inserted or
//! removed, numbers replaced by special values (NaN, ±∞, 0, −1, 10³⁰⁸, 10¹², 5e-324), keys
//! renamed, lines dropped or repeated — and read (and, for scene files, built with fills
//! capped as `--beads` does). Every case must end in a typed error with a message or a
//! success, without a panic, within 5 s. The counts are printed (`--nocapture`) and kept in
//! docs/fuzz.md.

use coulomb_granular::import::{self, Transform};
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::{BuildOptions, LoadedScene};
use coulomb_granular::{Scene, Simulation};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const CAP: Duration = Duration::from_secs(5);

/// A mutation of a text or byte file.
#[derive(Debug, Clone)]
enum Edit {
    /// flip bits of the byte at (position fraction, mask)
    Flip(f64, u8),
    /// insert a byte
    Insert(f64, u8),
    /// remove a run of bytes
    Remove(f64, usize),
    /// replace the k-th number of the text by a special value
    Number(usize, &'static str),
    /// rename the k-th key (`name =`)
    Key(usize),
    /// drop the k-th line
    DropLine(usize),
    /// repeat the k-th line
    RepeatLine(usize),
}

const SPECIALS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "0",
    "-0.0",
    "-1",
    "1e308",
    "1e12",
    "5e-324",
    "-1e308",
    "1e19",
    "18446744073709551616",
    "0.5",
    "\"x\"",
    "[]",
];

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (0.0..1.0f64, 1..=255u8).prop_map(|(p, m)| Edit::Flip(p, m)),
        (0.0..1.0f64, any::<u8>()).prop_map(|(p, b)| Edit::Insert(p, b)),
        (0.0..1.0f64, 1..40usize).prop_map(|(p, n)| Edit::Remove(p, n)),
        (0..200usize, prop::sample::select(SPECIALS)).prop_map(|(k, s)| Edit::Number(k, s)),
        (0..60usize).prop_map(Edit::Key),
        (0..60usize).prop_map(Edit::DropLine),
        (0..60usize).prop_map(Edit::RepeatLine),
    ]
}

fn at(len: usize, p: f64) -> usize {
    ((len as f64) * p).floor().min(len.saturating_sub(1) as f64) as usize
}

/// `bytes` with `edits` applied (text edits only where the bytes are UTF-8).
fn mutate(bytes: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    for e in edits {
        match e {
            Edit::Flip(p, m) if !b.is_empty() => {
                let i = at(b.len(), *p);
                b[i] ^= m;
            }
            Edit::Insert(p, x) => {
                let i = at(b.len() + 1, *p);
                b.insert(i.min(b.len()), *x);
            }
            Edit::Remove(p, n) if !b.is_empty() => {
                let i = at(b.len(), *p);
                let j = (i + n).min(b.len());
                b.drain(i..j);
            }
            Edit::Number(k, s) => {
                if let Ok(t) = String::from_utf8(b.clone()) {
                    let spans = number_spans(&t);
                    if !spans.is_empty() {
                        let (i, j) = spans[k % spans.len()];
                        b = format!("{}{}{}", &t[..i], s, &t[j..]).into_bytes();
                    }
                }
            }
            Edit::Key(k) => {
                if let Ok(t) = String::from_utf8(b.clone()) {
                    let keys: Vec<usize> = t.match_indices(" = ").map(|(i, _)| i).collect();
                    if !keys.is_empty() {
                        let i = keys[k % keys.len()];
                        b = format!("{}_x{}", &t[..i], &t[i..]).into_bytes();
                    }
                }
            }
            Edit::DropLine(k) | Edit::RepeatLine(k) => {
                if let Ok(t) = String::from_utf8(b.clone()) {
                    let mut lines: Vec<&str> = t.lines().collect();
                    if !lines.is_empty() {
                        let i = k % lines.len();
                        if matches!(e, Edit::DropLine(_)) {
                            lines.remove(i);
                        } else {
                            lines.insert(i, lines[i]);
                        }
                        b = (lines.join("\n") + "\n").into_bytes();
                    }
                }
            }
            _ => {}
        }
    }
    b
}

/// Byte spans of the numbers of `t`.
fn number_spans(t: &str) -> Vec<(usize, usize)> {
    let b = t.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() || (b[i] == b'-' && i + 1 < b.len() && b[i + 1].is_ascii_digit());
        let in_word = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if starts && !in_word {
            let mut j = i + 1;
            while j < b.len() && (b[j].is_ascii_digit() || b".eE-+".contains(&b[j])) {
                j += 1;
            }
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// What the cases of one surface gave.
#[derive(Default, Debug)]
struct Tally {
    tried: usize,
    ok: usize,
    refused: usize,
    slowest: Duration,
}

impl Tally {
    /// Records one case: `run` must not panic, must end within [`CAP`], and an error must
    /// say something.
    fn case(
        &mut self,
        what: &str,
        run: impl FnOnce() -> Result<(), String>,
    ) -> Result<(), TestCaseError> {
        let start = Instant::now();
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(run));
        let took = start.elapsed();
        self.tried += 1;
        self.slowest = self.slowest.max(took);
        prop_assert!(took < CAP, "{what}: {took:?}");
        match r {
            Err(_) => return Err(TestCaseError::fail(format!("{what}: panicked"))),
            Ok(Ok(())) => self.ok += 1,
            Ok(Err(m)) => {
                prop_assert!(!m.trim().is_empty(), "{what}: an error without a message");
                self.refused += 1;
            }
        }
        Ok(())
    }

    fn report(&self, what: &str) {
        eprintln!(
            "fuzz {what}: {} inputs, {} accepted, {} refused with a typed error, 0 panics, slowest {:.3} s",
            self.tried,
            self.ok,
            self.refused,
            self.slowest.as_secs_f64()
        );
    }
}

/// A runner of `cases` cases from a fixed seed: the same inputs at every run (the counts of
/// docs/fuzz.md).
fn runner(cases: u32) -> TestRunner {
    TestRunner::new_with_rng(
        Config {
            cases,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    )
}

/// A folder of its own, removed when dropped.
struct Dir(PathBuf);
impl Dir {
    fn new(tag: &str) -> Self {
        let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("coulomb-fuzz-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Dir(d)
    }
    fn path(&self) -> &Path {
        &self.0
    }
}
impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

const SCENE: &str = r#"name = "fuzz"
seed = 3
gravity = [0.0, 0.0, -9.81]

[step]
h = 0.01
tol = 1e-4
steps = 10

[materials.glass]
density = 2500.0

[default_pair]
mu = 0.3
restitution = 0.2

[[pairs]]
materials = ["glass", "default"]
mu = 0.5

[[bodies]]
material = "glass"
spheres = [[0.0, 0.0, 0.2, 0.05], [0.2, 0.0, 0.2, 0.05]]
velocity = [0.1, 0.0, 0.0]

[[bodies]]
fill = { count = 20, region = { kind = "box", lo = [-0.4, -0.4, 0.3], hi = [0.4, 0.4, 0.8] }, sizes = { kind = "uniform", min = 0.03, max = 0.04 } }

[[bodies]]
file = "p.csv"

[[obstacles]]
name = "bin"
shape = { kind = "box", lo = [-0.5, -0.5, 0.0], hi = [0.5, 0.5, 1.0], inside = true }

[[obstacles]]
name = "ramp"
shape = { kind = "mesh", vertices = [[-0.4, -0.4, 0.1], [0.4, -0.4, 0.1], [0.0, 0.4, 0.1]], triangles = [[0, 1, 2]] }
motion = { kind = "oscillate", direction = [0.0, 0.0, 1.0], amplitude = 0.001, frequency = 5.0 }

[[inlets]]
region = { kind = "box", lo = [-0.3, -0.3, 0.85], hi = [0.3, 0.3, 0.95] }
sizes = { kind = "uniform", min = 0.02, max = 0.03 }
rate = { count = 100.0 }
"#;

const CSV: &str = "x,y,z,r,vx,vy,vz\n0.3,0.3,0.2,0.04,0,0,0\n-0.3,0.3,0.2,0.04,0,0,1\n";

#[test]
fn fuzz_scene_files() {
    let dir = Dir::new("scene");
    std::fs::write(dir.path().join("p.csv"), CSV).unwrap();
    let path = dir.path().join("s.toml");
    // the file as written builds
    LoadedScene::parse(&path, SCENE.into(), true)
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap();
    let tally = std::cell::RefCell::new(Tally::default());
    let mut runner = runner(300);
    let r = runner.run(&prop::collection::vec(edit(), 1..4), |edits| {
        let bytes = mutate(SCENE.as_bytes(), &edits);
        tally.borrow_mut().case("scene file", || {
            let text = String::from_utf8(bytes).map_err(|e| e.to_string())?;
            let loaded = LoadedScene::parse(&path, text, true).map_err(|e| e.to_string())?;
            let opts = BuildOptions {
                seed: None,
                max_fill: Some(200),
            };
            let built = loaded.build(&opts).map_err(|e| e.to_string())?;
            if built.model.has_shapes() {
                RigidScene::new(&built.model).map_err(|e| e.to_string())?;
            } else {
                built
                    .build(&Default::default())
                    .map_err(|e| e.to_string())?;
            }
            Ok(())
        })
    });
    let tally = tally.into_inner();
    tally.report("scene files");
    r.unwrap();
    assert!(tally.ok > 0 && tally.refused > 0, "{tally:?}");
}

#[test]
fn fuzz_particle_and_mesh_files() {
    let dir = Dir::new("files");
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    let stl = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
    let tally = std::cell::RefCell::new(Tally::default());
    for (name, text) in [("p.csv", CSV), ("m.obj", obj), ("m.stl", stl)] {
        let path = dir.path().join(name);
        let mut runner = runner(150);
        let r = runner.run(&prop::collection::vec(edit(), 1..4), |edits| {
            let bytes = mutate(text.as_bytes(), &edits);
            std::fs::write(&path, &bytes).unwrap();
            tally.borrow_mut().case(name, || {
                if name.ends_with(".csv") {
                    import::read_particles(&path)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                } else {
                    import::read_mesh(&path, &Transform::default())
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                }
            })
        });
        r.unwrap();
    }
    let tally = tally.into_inner();
    tally.report("particle and mesh files");
    assert!(tally.ok > 0 && tally.refused > 0, "{tally:?}");
}

#[test]
fn fuzz_checkpoints() {
    let mut sim = Simulation::new(Scene::Box.build(20, 1), Default::default()).unwrap();
    for _ in 0..10 {
        sim.step().unwrap();
    }
    let sphere = sim.checkpoint_bytes().unwrap();
    let rigid_scene = LoadedScene::parse(
        Path::new("r.toml"),
        r#"
[step]
h = 0.005
tol = 1e-8
[[obstacles]]
shape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }
[[bodies]]
shape = { kind = "cuboid", half_extents = [0.05, 0.04, 0.03] }
positions = [[0.0, 0.0, 0.031], [0.2, 0.0, 0.1]]
"#
        .into(),
        true,
    )
    .unwrap()
    .build(&BuildOptions::default())
    .unwrap();
    let mut rigid = RigidScene::new(&rigid_scene.model).unwrap();
    for _ in 0..5 {
        rigid.step().unwrap();
    }
    let rigid = rigid.checkpoint_bytes().unwrap();
    let tally = std::cell::RefCell::new(Tally::default());
    // byte edits only: the text edits of a binary file are byte edits too
    let bytes_edit = prop_oneof![
        (0.0..1.0f64, 1..=255u8).prop_map(|(p, m)| Edit::Flip(p, m)),
        (0.0..1.0f64, any::<u8>()).prop_map(|(p, b)| Edit::Insert(p, b)),
        (0.0..1.0f64, 1..40usize).prop_map(|(p, n)| Edit::Remove(p, n)),
    ];
    for (kind, good) in [("sphere", &sphere), ("rigid", &rigid)] {
        let mut runner = runner(200);
        let r = runner.run(&prop::collection::vec(bytes_edit.clone(), 1..4), |edits| {
            let bytes = mutate(good, &edits);
            tally.borrow_mut().case(kind, || {
                if kind == "sphere" {
                    Simulation::from_checkpoint_bytes("c.h5", bytes)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                } else {
                    RigidScene::from_checkpoint_bytes("c.h5", bytes)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                }
            })
        });
        r.unwrap();
    }
    let tally = tally.into_inner();
    tally.report("checkpoints");
    assert!(tally.refused > 0, "{tally:?}");
}
