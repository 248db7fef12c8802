//! The engine of `coulomb corpus`: writes a test corpus that nobody tunes on (issue #11,
//! item 3) — FCLIB files named `CLASS--NAME.hdf5` and a `manifest.json` describing each of
//! them ([`write()`]).
//!
//! Classes (see [`ClassName`]):
//! - `granular`: steps of coulomb's own Moreau–Jean simulations (box, funnel, rotating drum,
//!   vibrating plate; each step solved by body-level Gauss–Seidel, not by the solver under
//!   test), in the global form (M, H, f, w) and the local form (W, q) of (2.10);
//! - `boxes`: rigid cuboids stacked on a floor, four contact points per face contact, so that
//!   there are more contact unknowns than degrees of freedom and W = Hᵀ M⁻¹ H is rank-deficient;
//! - `gyro`: the box scenes that impact, with the linearized gyroscopic term of each spinning
//!   box in the iteration matrix (M̂ = M + h G(ω⁻), not symmetric): W = Hᵀ M̂⁻¹ H is not
//!   symmetric but has the rank of M, as in real files from rigid-body codes;
//! - `nonsym`: local problems of the two classes above with W perturbed to be slightly
//!   non-symmetric (relative asymmetry 1e-6…1e-3, as in real FCLIB files) by a random
//!   antisymmetric matrix on W's pattern, so that ½(W + Wᵀ) = W stays PSD;
//! - `painleve`: the rod of (2.12) for several θ, μ, u₀, with the existence verdict of (2.13);
//! - `random`: random sparse H, block-diagonal SPD M, random f, w and μ, in d = 2 and 3.
//!
//! The corpus is deterministic for a seed, and independent of the library's solver pipeline
//! (the granular simulations use their own Gauss–Seidel: `granular::STEP_SOLVER`). Files are
//! written to a temporary name and renamed.

mod boxes;
mod granular;
mod random;

use anyhow::{bail, Context};
use coulomb::delassus::Delassus;
use coulomb::fclib::{self, FclibFile, Info};
use coulomb::{CscMatrix, GlobalProblem, LocalProblem, Problem};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Problem size presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// about 50 small files, a few seconds (what the tests use)
    Small,
    /// about 500 files, up to 5 000 beads (for docs/corpus.md)
    Full,
}

impl Preset {
    /// Every preset.
    pub const ALL: [Preset; 2] = [Preset::Small, Preset::Full];

    /// The preset's name (as in the manifest).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Small => "small",
            Self::Full => "full",
        }
    }

    /// What the preset writes, in a few words.
    pub fn about(self) -> &'static str {
        match self {
            Self::Small => "about 50 small files, a few seconds (what the tests use)",
            Self::Full => "about 500 files, up to 5 000 beads (for docs/corpus.md)",
        }
    }
}

/// What a corpus run writes (`coulomb corpus`'s arguments).
#[derive(Debug, Clone)]
pub struct Options {
    /// output folder (created if needed; existing corpus files in it are overwritten)
    pub output: PathBuf,
    /// size preset
    pub preset: Preset,
    /// seed of every random choice
    pub seed: u64,
    /// write only these classes (default, when empty: all). `nonsym` is made from the local
    /// files of `granular` and `boxes`, which it then writes too. The files of a class are the
    /// same whatever else is written.
    pub classes: Vec<ClassName>,
}

/// The classes of the corpus (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClassName {
    /// steps of coulomb's own granular simulations
    Granular,
    /// rigid cuboids stacked on a floor
    Boxes,
    /// the impacting box scenes with the gyroscopic term (W not symmetric)
    Gyro,
    /// W of the local files of `granular` and `boxes` made slightly non-symmetric
    Nonsym,
    /// the Painlevé rod of (2.12)
    Painleve,
    /// random sparse problems
    Random,
}

impl ClassName {
    /// Every class.
    pub const ALL: [ClassName; 6] = [
        ClassName::Granular,
        ClassName::Boxes,
        ClassName::Gyro,
        ClassName::Nonsym,
        ClassName::Painleve,
        ClassName::Random,
    ];

    /// The class's name: the prefix of its file names.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Granular => "granular",
            Self::Boxes => "boxes",
            Self::Gyro => "gyro",
            Self::Nonsym => "nonsym",
            Self::Painleve => "painleve",
            Self::Random => "random",
        }
    }
}

/// Which classes a run writes: all when none is named; `nonsym` brings its sources.
fn wanted(named: &[ClassName]) -> Vec<&'static str> {
    let mut out: Vec<&'static str> = if named.is_empty() {
        ClassName::ALL.iter().map(|c| c.as_str()).collect()
    } else {
        named.iter().map(|c| c.as_str()).collect()
    };
    if out.contains(&"nonsym") {
        out.extend(["granular", "boxes"]);
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// One file of the corpus, as recorded in `manifest.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Entry {
    /// file name, `CLASS--NAME.hdf5`
    pub file: String,
    /// the class (file name prefix)
    pub class: String,
    /// the rest of the name
    pub name: String,
    /// "local" or "global"
    pub kind: String,
    /// d
    pub dim: usize,
    /// number of contacts
    pub contacts: usize,
    /// contact unknowns m = d · contacts
    pub unknowns: usize,
    /// degrees of freedom n (global problems and local problems made from one)
    pub dofs: Option<usize>,
    /// rank of W (dense pivoted Cholesky), when m ≤ [`RANK_LIMIT`]
    pub rank_w: Option<usize>,
    /// rank(W) < m, when known (always true when m > n)
    pub rank_deficient: Option<bool>,
    /// relative asymmetry of the stored W (largest |W − Wᵀ| over largest |W|)
    pub asymmetry: f64,
    /// "exists" or "none" when known from the construction, otherwise null
    pub expected_existence: Option<String>,
    /// why `expected_existence` holds
    #[serde(skip_serializing_if = "Option::is_none")]
    pub existence_reason: Option<String>,
    /// parameters of the construction
    pub params: serde_json::Value,
}

/// Largest m for which the rank of W is computed (dense, O(m³)).
pub const RANK_LIMIT: usize = 1500;

/// A problem to be written, with what the manifest says about it.
pub struct Item {
    /// class (file name prefix)
    pub class: &'static str,
    /// name (without class and extension)
    pub name: String,
    /// the problem
    pub problem: Problem,
    /// degrees of freedom behind a local problem made from a global one
    pub dofs: Option<usize>,
    /// existence known from the construction, with its reason
    pub existence: Option<(&'static str, String)>,
    /// parameters
    pub params: serde_json::Value,
}

/// What [`write()`] wrote.
#[derive(Debug, Clone)]
pub struct Written {
    /// the manifest's entries, one per file, in the order written
    pub entries: Vec<Entry>,
    /// wall-clock time of the run, seconds (the manifest written)
    pub seconds: f64,
}

impl Written {
    /// Number of files of each class.
    pub fn by_class(&self) -> std::collections::BTreeMap<&str, usize> {
        let mut by_class: std::collections::BTreeMap<&str, usize> = Default::default();
        for e in &self.entries {
            *by_class.entry(e.class.as_str()).or_default() += 1;
        }
        by_class
    }

    /// Number of files whose W is known to be rank-deficient.
    pub fn rank_deficient(&self) -> usize {
        self.entries
            .iter()
            .filter(|e| e.rank_deficient == Some(true))
            .count()
    }
}

/// Writes the corpus of `args` into `args.output` (its files, then `manifest.json`), calling
/// `on_file` with the entry of each file once it is written.
pub fn write(args: &Options, on_file: &mut dyn FnMut(&Entry)) -> anyhow::Result<Written> {
    let dir = &args.output;
    if dir.exists() && !dir.is_dir() {
        bail!("--output {}: exists and is not a folder", dir.display());
    }
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let start = std::time::Instant::now();
    let mut writer = Writer {
        dir: dir.clone(),
        entries: Vec::new(),
        on_file,
    };
    let classes = wanted(&args.classes);
    generate(args.preset, args.seed, &classes, &mut |item| {
        if classes.contains(&item.class) {
            writer.add(item)
        } else {
            Ok(())
        }
    })?;
    // the perturbed class is made from the local files already written
    let sources: Vec<Entry> = writer
        .entries
        .iter()
        .filter(|e| e.kind == "local" && (e.class == "granular" || e.class == "boxes"))
        .cloned()
        .collect();
    // every other local file of classes 1–2
    let every = 2;
    let nonsym = if classes.contains(&"nonsym") {
        sources.as_slice()
    } else {
        &[]
    };
    for (k, src) in nonsym.iter().enumerate().filter(|(k, _)| k % every == 0) {
        let path = dir.join(&src.file);
        let file = fclib::read(&path).with_context(|| format!("re-reading {}", path.display()))?;
        let Problem::Local(p) = file.problem else {
            continue;
        };
        let levels = [1e-6, 1e-5, 1e-4, 1e-3];
        let target = levels[(k / every) % levels.len()];
        let pert = perturb(&p, target, args.seed ^ (k as u64).wrapping_mul(0x9E37));
        let stem = src.file.trim_end_matches(".hdf5");
        let stem = stem.split_once("--").map_or(stem, |(_, s)| s);
        let item = Item {
            class: "nonsym",
            name: format!("{stem}-asym{target:.0e}"),
            problem: Problem::Local(pert),
            dofs: src.dofs,
            existence: None,
            params: serde_json::json!({"source": src.file, "target_asymmetry": target}),
        };
        writer.add(item)?;
    }
    let entries = writer.entries;
    let manifest = serde_json::json!({
        "preset": args.preset,
        "seed": args.seed,
        "generator": format!("coulomb {} corpus", env!("CARGO_PKG_VERSION")),
        "files": entries,
    });
    write_atomic(
        &dir.join("manifest.json"),
        (serde_json::to_string_pretty(&manifest)? + "\n").as_bytes(),
    )?;
    Ok(Written {
        entries,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Calls `sink` with every problem of the preset except the perturbed ones, skipping the
/// generators of no class in `classes` (boxes writes both `boxes` and `gyro`).
fn generate(
    preset: Preset,
    seed: u64,
    classes: &[&str],
    sink: &mut dyn FnMut(Item) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let has = |c: &str| classes.contains(&c);
    if has("painleve") {
        painleve(preset, sink)?;
    }
    if has("random") {
        random::generate(preset, seed, sink)?;
    }
    if has("boxes") || has("gyro") {
        boxes::generate(preset, seed, sink)?;
    }
    if has("granular") {
        granular::generate(preset, seed, sink)?;
    }
    Ok(())
}

/// Both forms of a global problem: the global one and its Delassus local form
/// W = Hᵀ M⁻¹ H, q = Hᵀ M⁻¹ f + w.
pub fn both_forms(
    class: &'static str,
    name: &str,
    g: GlobalProblem,
    existence: Option<(&'static str, String)>,
    params: serde_json::Value,
    sink: &mut dyn FnMut(Item) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let local = Delassus::new(&g)
        .with_context(|| format!("Delassus form of {name}"))?
        .local;
    let n = g.m.nrows;
    sink(Item {
        class,
        name: format!("{name}-global"),
        problem: Problem::Global(g),
        dofs: Some(n),
        existence: existence.clone(),
        params: params.clone(),
    })?;
    sink(Item {
        class,
        name: format!("{name}-local"),
        problem: Problem::Local(local),
        dofs: Some(n),
        existence,
        params,
    })
}

/// The Painlevé rod (2.12) with g = −1 (Example 2.1): by (2.13) a solution exists iff
/// u₀ ≤ 0 or tan θ > μ. Cases with |tan θ − μ| < 0.05 are left out (the verdict is then
/// sensitive to rounding).
fn painleve(
    preset: Preset,
    sink: &mut dyn FnMut(Item) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let cases: Vec<(f64, f64, f64)> = match preset {
        Preset::Small => vec![
            (30.0, 0.3, -1.0),
            (30.0, 0.8, 1.0),
            (60.0, 0.8, 1.0),
            (45.0, 0.5, 0.0),
            (20.0, 1.0, 2.0),
            (80.0, 2.5, 0.5),
            // no solution, and large μ: r grows without bound while the relative error of
            // docs/error.md (scaled by ‖r‖) falls below 1e-8 (measured: reported converged)
            (30.0, 2.5, 2.0),
        ],
        Preset::Full => {
            let mut v = Vec::new();
            for th in [10.0, 30.0, 50.0, 70.0, 85.0] {
                for mu in [0.1, 0.4, 1.0, 2.5] {
                    for u0 in [-1.0, 0.0, 2.0] {
                        v.push((th, mu, u0));
                    }
                }
            }
            v
        }
    };
    for (th, mu, u0) in cases {
        let tan = f64::tan(f64::to_radians(th));
        if (tan - mu).abs() < 0.05 {
            continue;
        }
        let exists = u0 <= 0.0 || tan > mu;
        let g = coulomb::examples::painleve(th.to_radians(), mu, u0, -1.0)?;
        both_forms(
            "painleve",
            &format!("th{th}-mu{mu}-u{u0}"),
            g,
            Some((
                if exists { "exists" } else { "none" },
                format!(
                    "(2.13): a solution exists iff u0 <= 0 or tan(theta) > mu; here u0 = {u0}, \
                     tan(theta) = {tan:.3}, mu = {mu}"
                ),
            )),
            serde_json::json!({"theta_deg": th, "mu": mu, "u0": u0, "g": -1.0}),
            sink,
        )?;
    }
    Ok(())
}

/// W + δ K: K antisymmetric with independent random entries (uniform in [−1, 1]) on the
/// stored off-diagonal pattern of W, δ chosen so that the relative asymmetry
/// max|W' − W'ᵀ| / max|W'| equals `target`. The symmetric part ½(W' + W'ᵀ) is W itself, so it
/// stays PSD with the rank of W (no symmetric noise is added, which could break either).
pub fn perturb(p: &LocalProblem, target: f64, seed: u64) -> LocalProblem {
    let mut rng = Rng::new(seed);
    let w = &p.w;
    let scale = w.values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for (i, j, _) in w.triplets() {
        if i < j {
            let x = rng.uniform(-1.0, 1.0);
            rows.extend([i, j]);
            cols.extend([j, i]);
            vals.extend([x, -x]);
        }
    }
    let kmax = vals.iter().fold(0.0f64, |a: f64, v: &f64| a.max(v.abs()));
    if kmax == 0.0 || scale == 0.0 {
        return p.clone();
    }
    // max|δK − δKᵀ| = 2 δ kmax = target · max|W|
    let delta = target * scale / (2.0 * kmax);
    for v in vals.iter_mut() {
        *v *= delta;
    }
    let n = w.nrows;
    let pert = CscMatrix::from_triplets(n, n, &rows, &cols, &vals)
        .unwrap_or_else(|_| CscMatrix::zeros(n, n));
    LocalProblem {
        dim: p.dim,
        w: w.add_scaled(1.0, &pert),
        q: p.q.clone(),
        mu: p.mu.clone(),
    }
}

/// Rank of a symmetric positive semidefinite matrix (its symmetric part), by Cholesky with
/// diagonal pivoting: the number of pivots above `1e-10 · max diag · n`.
pub fn psd_rank(a: &CscMatrix) -> usize {
    let n = a.nrows;
    let mut d = vec![0.0; n * n];
    for (i, j, v) in a.triplets() {
        d[i * n + j] += 0.5 * v;
        d[j * n + i] += 0.5 * v;
    }
    let maxdiag = (0..n).map(|i| d[i * n + i]).fold(0.0f64, f64::max);
    if maxdiag <= 0.0 {
        return 0;
    }
    let tol = 1e-10 * maxdiag * (n as f64).max(1.0);
    let mut perm: Vec<usize> = (0..n).collect();
    let mut rank = 0;
    for k in 0..n {
        // pivot: largest remaining diagonal
        let (p, &best) = perm[k..]
            .iter()
            .enumerate()
            .map(|(i, &r)| (i, &d[r * n + r]))
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap_or((0, &0.0));
        if best <= tol {
            break;
        }
        perm.swap(k, k + p);
        let pk = perm[k];
        let s = best.sqrt();
        // column pk of L, on the remaining rows
        let col: Vec<(usize, f64)> = perm[k + 1..]
            .iter()
            .map(|&r| (r, d[r * n + pk] / s))
            .collect();
        for &(r, lr) in &col {
            for &(c, lc) in &col {
                d[r * n + c] -= lr * lc;
            }
        }
        rank += 1;
    }
    rank
}

/// Writes items into the corpus folder, keeps their manifest entries and reports each.
struct Writer<'a> {
    dir: PathBuf,
    entries: Vec<Entry>,
    on_file: &'a mut dyn FnMut(&Entry),
}

impl Writer<'_> {
    fn add(&mut self, item: Item) -> anyhow::Result<()> {
        let e = write_item(&self.dir, item)?;
        (self.on_file)(&e);
        self.entries.push(e);
        Ok(())
    }
}

fn write_item(dir: &Path, item: Item) -> anyhow::Result<Entry> {
    let file_name = format!("{}--{}.hdf5", item.class, item.name);
    let p = &item.problem;
    let (w_matrix, dofs) = match p {
        Problem::Local(l) => (Some(l.w.clone()), item.dofs),
        Problem::Global(g) => (None, Some(g.m.nrows)),
    };
    let unknowns = p.dim() * p.contacts();
    let w_for_rank = match (&w_matrix, p) {
        (Some(w), _) => Some(w.clone()),
        (None, Problem::Global(g)) if unknowns <= RANK_LIMIT => {
            Delassus::new(g).ok().map(|d| d.local.w)
        }
        _ => None,
    };
    let asymmetry = w_matrix.as_ref().map_or(0.0, CscMatrix::asymmetry);
    let rank_w = w_for_rank
        .as_ref()
        .filter(|_| unknowns <= RANK_LIMIT)
        .map(psd_rank);
    let rank_deficient = match (rank_w, dofs) {
        (Some(r), _) => Some(r < unknowns),
        (None, Some(n)) if unknowns > n => Some(true),
        _ => None,
    };
    let mut file = FclibFile::new(item.problem.clone());
    file.info = Some(Info {
        title: format!("{}--{}", item.class, item.name),
        description: format!(
            "coulomb corpus, class {}: {}",
            item.class,
            serde_json::to_string(&item.params)?
        ),
        math_info: String::new(),
    });
    let path = dir.join(&file_name);
    // atomic (coulomb::atomic): temporary file, rename; a non-regular file there is refused
    fclib::write(&path, &file).with_context(|| format!("writing {}", path.display()))?;
    Ok(Entry {
        file: file_name,
        class: item.class.to_string(),
        name: item.name,
        kind: p.kind().to_string(),
        dim: p.dim(),
        contacts: p.contacts(),
        unknowns,
        dofs,
        rank_w,
        rank_deficient,
        asymmetry,
        expected_existence: item.existence.as_ref().map(|(v, _)| v.to_string()),
        existence_reason: item.existence.map(|(_, r)| r),
        params: item.params,
    })
}

/// Writes `bytes` to `path` with [`crate::outputs::write()`] (atomic; a non-regular file at
/// `path` is refused).
fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    crate::outputs::write(path, bytes)?;
    Ok(())
}

/// A small deterministic generator (SplitMix64), so that the corpus depends on nothing but
/// the seed.
pub struct Rng(u64);

impl Rng {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x5DEE_CE66_D1CE_4E5B)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let x = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * x
    }
    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u = self.uniform(f64::EPSILON, 1.0);
        let v = self.uniform(0.0, 1.0);
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_classes_written_are_those_named_and_nonsym_brings_its_sources() {
        assert_eq!(wanted(&[]).len(), 6);
        assert_eq!(wanted(&[ClassName::Gyro]), vec!["gyro"]);
        assert_eq!(
            wanted(&[ClassName::Nonsym, ClassName::Random, ClassName::Random]),
            vec!["boxes", "granular", "nonsym", "random"]
        );
    }

    #[test]
    fn rank_of_a_rank_two_matrix() {
        // W = a aᵀ + b bᵀ in R^4
        let a = [1.0, 2.0, 0.0, -1.0];
        let b = [0.0, 1.0, 1.0, 3.0];
        let mut d = vec![0.0; 16];
        for i in 0..4 {
            for j in 0..4 {
                d[i * 4 + j] = a[i] * a[j] + b[i] * b[j];
            }
        }
        assert_eq!(psd_rank(&CscMatrix::from_dense(4, 4, &d)), 2);
        assert_eq!(psd_rank(&CscMatrix::identity(5, 2.0)), 5);
    }

    #[test]
    fn perturbation_reaches_the_target_asymmetry() {
        let mut d = vec![0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                d[i * 3 + j] = if i == j { 2.0 } else { 0.5 };
            }
        }
        let p = LocalProblem {
            dim: 3,
            w: CscMatrix::from_dense(3, 3, &d),
            q: vec![-1.0, 0.0, 0.0],
            mu: vec![0.5],
        };
        let w = perturb(&p, 1e-4, 7).w;
        let a = w.asymmetry();
        assert!((a / 1e-4 - 1.0).abs() < 0.01, "asymmetry {a}");
        // the symmetric part is W itself
        assert_eq!(psd_rank(&w), 3);
        let sym = w.add_scaled(1.0, &w.transpose());
        let back = sym.add_scaled(-2.0, &p.w);
        assert!(back.values.iter().all(|x| x.abs() < 1e-15));
    }
}
