//! A fuzz harness on stable Rust: mutated FCLIB files (byte edits of the shared files and of
//! generated ones, special f64 values written over the data, and structured layouts with wrong
//! shapes, NaN, huge and tiny scales, claimed sizes of 10¹², missing groups, malformed
//! /solution and /guesses) drive the library entry points in-process: `fclib::read_bytes`
//! (strict and symmetrizing), `fclib::evaluate` of the stored solution and guesses,
//! `solver::solve_with_guess` with a short time limit and several methods, and
//! `existence::check` with a short time limit.
//!
//! Every case runs on its own thread under a wall-clock cap. Counted: panics (caught), hangs
//! (cap exceeded), and **false "converged"**: a `Status::Converged` solve, or an `evaluate`
//! that says converged, whose error recomputed here independently on the data as read (own
//! u = W r + q or v, u = Hᵀ v + w, own projection, own scaled norms) is not a finite number
//! ≤ tol (10 × tol of slack for rounding; values in (tol, 10 tol] are counted as borderline, and
//! so is a balance residual above 10 tol that rounding alone can explain: 10⁻¹³ (|M||v| + |H||r|
//! + |f|) / max(1, ‖f‖), as when r ~ 10¹⁵³ balances M v ~ 10¹⁵³ and ‖f‖ < 1).
//!
//! - `fuzz_short` (CI): a fixed number of cases from fixed seeds, a few seconds.
//! - `fuzz_long` (ignored): `COULOMB_FUZZ_SECS` seconds (default 3600) from seed
//!   `COULOMB_FUZZ_SEED`; prints the tally every minute. Run in release mode:
//!   `cargo test --release -p coulomb --test integration -- --ignored --nocapture fuzz::fuzz_long`.
//!   Results: docs/fuzz.md.

use crate::common;

use coulomb::existence::{self, CheckSettings};
use coulomb::fclib::{self, FclibFile, StoredSolution};
use coulomb::solver::{self, Guess, InnerKind, OuterKind, Settings, Status};
use coulomb::{CscMatrix, Problem};
use hdf5_pure::{FileBuilder, GroupBuilder};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Wall-clock cap of one case (reading, solving with a 0.3 s limit, checking existence with
/// 0.5 s per conic solve): anything beyond is a hang.
const CASE_CAP: Duration = Duration::from_secs(60);
/// Tolerance of the solves.
const TOL: f64 = 1e-8;

/// Special values written over data.
const SPECIALS: [f64; 16] = [
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    0.0,
    -0.0,
    1e308,
    -1e308,
    1e155,
    -1e155,
    1e-300,
    -1e-300,
    5e-324,
    f64::MAX,
    -1.0,
    1e12,
    -0.01,
];

#[derive(Default, Debug, Clone)]
struct Tally {
    cases: u64,
    read_ok: u64,
    read_err: u64,
    solves: u64,
    converged: u64,
    evaluations: u64,
    checks: u64,
    panics: u64,
    hangs: u64,
    false_converged: u64,
    borderline: u64,
    unverified: u64,
    notes: Vec<String>,
}

impl Tally {
    fn add(&mut self, o: &Outcome) {
        self.read_ok += o.read_ok;
        self.read_err += o.read_err;
        self.solves += o.solves;
        self.converged += o.converged;
        self.evaluations += o.evaluations;
        self.checks += o.checks;
        self.false_converged += o.false_converged;
        self.borderline += o.borderline;
        self.unverified += o.unverified;
        for n in &o.notes {
            if self.notes.len() < 50 {
                self.notes.push(n.clone());
            }
        }
    }

    fn line(&self, secs: f64) -> String {
        format!(
            "{secs:.0} s: {} cases ({} read, {} refused), {} solves ({} converged), {} evaluations, {} existence checks; panics {}, hangs {}, false converged {}, borderline {}, unverified {}",
            self.cases,
            self.read_ok,
            self.read_err,
            self.solves,
            self.converged,
            self.evaluations,
            self.checks,
            self.panics,
            self.hangs,
            self.false_converged,
            self.borderline,
            self.unverified
        )
    }
}

#[derive(Default, Debug)]
struct Outcome {
    read_ok: u64,
    read_err: u64,
    solves: u64,
    converged: u64,
    evaluations: u64,
    checks: u64,
    false_converged: u64,
    borderline: u64,
    unverified: u64,
    notes: Vec<String>,
}

// ---------------------------------------------------------------------------------------
// Independent error of docs/error.md, on the data as read.

/// y += A x by triplets.
fn gemv(a: &CscMatrix, x: &[f64], y: &mut [f64]) {
    for (j, xj) in x.iter().enumerate().take(a.ncols) {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            y[a.row_idx[k]] += a.values[k] * xj;
        }
    }
}

/// y += Aᵀ x.
fn gemv_t(a: &CscMatrix, x: &[f64], y: &mut [f64]) {
    for (j, yj) in y.iter_mut().enumerate().take(a.ncols) {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            *yj += a.values[k] * x[a.row_idx[k]];
        }
    }
}

/// ‖x‖ / s for a positive scale s (no overflow as long as |xᵢ| / s is moderate).
fn scaled_norm(x: &[f64], s: f64) -> f64 {
    x.iter().map(|v| (v / s) * (v / s)).sum::<f64>().sqrt()
}

/// Projection onto K_μ = {‖x_T‖ ≤ μ x_N}.
fn proj(mu: f64, x: &[f64]) -> Vec<f64> {
    let n = x[0];
    if mu == f64::INFINITY {
        // the half-space {x_N ≥ 0}
        let mut out = x.to_vec();
        out[0] = n.max(0.0);
        return out;
    }
    let t = x[1..].iter().map(|v| v * v).sum::<f64>().sqrt();
    if t <= mu * n && n >= 0.0 {
        return x.to_vec();
    }
    if mu * t <= -n {
        return vec![0.0; x.len()];
    }
    let a = (n + mu * t) / (1.0 + mu * mu);
    let mut out = vec![a];
    for v in &x[1..] {
        out.push(if t > 0.0 { mu * a * v / t } else { 0.0 });
    }
    out
}

/// err of docs/error.md from (r, u, q), computed on entries divided by the largest magnitude
/// (the measure is a ratio of positively homogeneous functions). `None` when some entry is
/// not finite.
fn independent_error(dim: usize, mu: &[f64], r: &[f64], u: &[f64], q: &[f64]) -> Option<f64> {
    let all = r.iter().chain(u).chain(q);
    let mut big = 0.0f64;
    for v in all {
        if !v.is_finite() {
            return None;
        }
        big = big.max(v.abs());
    }
    if big == 0.0 {
        return Some(0.0);
    }
    let s = if big > 1.0 { big } else { 1.0 };
    let mut abs2 = 0.0;
    for c in 0..mu.len() {
        let rr: Vec<f64> = r[c * dim..(c + 1) * dim].iter().map(|v| v / s).collect();
        let uu: Vec<f64> = u[c * dim..(c + 1) * dim].iter().map(|v| v / s).collect();
        let ut = uu[1..].iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut x: Vec<f64> = rr.iter().zip(&uu).map(|(a, b)| a - b).collect();
        if ut > 0.0 {
            x[0] -= mu[c] * ut;
        }
        let p = proj(mu[c], &x);
        abs2 += rr
            .iter()
            .zip(&p)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>();
    }
    let abs = abs2.sqrt();
    let scale = scaled_norm(q, s)
        .max(scaled_norm(r, s))
        .max(scaled_norm(u, s));
    let e = if scale * s > f64::EPSILON {
        abs / scale
    } else {
        abs * s
    };
    e.is_finite().then_some(e)
}

/// Dense solve M x = b (Gaussian elimination with partial pivoting), small n only.
fn dense_solve(m: &CscMatrix, b: &[f64]) -> Option<Vec<f64>> {
    let n = m.nrows;
    let mut rm = vec![0.0; n * n];
    for j in 0..n {
        for k in m.col_ptr[j]..m.col_ptr[j + 1] {
            rm[m.row_idx[k] * n + j] = m.values[k];
        }
    }
    let mut x = b.to_vec();
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| {
            rm[i * n + col]
                .abs()
                .partial_cmp(&rm[j * n + col].abs())
                .unwrap_or(std::cmp::Ordering::Equal)
        })?;
        if rm[piv * n + col] == 0.0 || !rm[piv * n + col].is_finite() {
            return None;
        }
        for k in 0..n {
            rm.swap(col * n + k, piv * n + k);
        }
        x.swap(col, piv);
        for i in col + 1..n {
            let f = rm[i * n + col] / rm[col * n + col];
            for k in col..n {
                rm[i * n + k] -= f * rm[col * n + k];
            }
            x[i] -= f * x[col];
        }
    }
    for col in (0..n).rev() {
        let mut s = x[col];
        for k in col + 1..n {
            s -= rm[col * n + k] * x[k];
        }
        x[col] = s / rm[col * n + col];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The verdict on a claim "r (and v) solve `problem` at TOL": Ok(()) when the independent
/// error confirms it, Err(text) when it does not (false converged), and `None` inside when it
/// could not be verified (large global problem whose q needs M⁻¹).
enum Claim {
    Confirmed,
    Borderline(String),
    False(String),
    Unverified,
}

fn verify(problem: &Problem, r: &[f64], v: Option<&[f64]>, tol: f64) -> Claim {
    match problem {
        Problem::Local(p) => {
            let mut u = p.q.clone();
            if r.len() != p.q.len() {
                return Claim::False(format!("r has length {}", r.len()));
            }
            gemv(&p.w, r, &mut u);
            judge(independent_error(p.dim, &p.mu, r, &u, &p.q), tol)
        }
        Problem::Global(g) => {
            let Some(v) = v else {
                return Claim::False("global problem without v".into());
            };
            let mut u = g.w.clone();
            gemv_t(&g.h, v, &mut u);
            // balance residual ‖M v − H r − f‖ / max(1, ‖f‖)
            let mut res = vec![0.0; g.f.len()];
            gemv(&g.m, v, &mut res);
            let mut hr = vec![0.0; g.f.len()];
            gemv(&g.h, r, &mut hr);
            for ((x, a), b) in res.iter_mut().zip(&hr).zip(&g.f) {
                *x -= a + b;
            }
            let fmax = g.f.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            let bal = scaled_norm(&res, fmax) / scaled_norm(&g.f, fmax).max(1.0 / fmax);
            // what rounding alone can leave: ε (|M||v| + |H||r| + |f|), relative like bal
            let abs = |a: &CscMatrix| CscMatrix {
                values: a.values.iter().map(|x| x.abs()).collect(),
                ..a.clone()
            };
            let (va, ra): (Vec<f64>, Vec<f64>) = (
                v.iter().map(|x| x.abs()).collect(),
                r.iter().map(|x| x.abs()).collect(),
            );
            let mut size: Vec<f64> = g.f.iter().map(|x| x.abs()).collect();
            gemv(&abs(&g.m), &va, &mut size);
            gemv(&abs(&g.h), &ra, &mut size);
            let rounding =
                1e-13 * scaled_norm(&size, fmax) / scaled_norm(&g.f, fmax).max(1.0 / fmax);
            if !bal.is_finite() || bal > 10.0 * tol + rounding {
                return Claim::False(format!("balance residual {bal:e}"));
            }
            if bal > 10.0 * tol {
                return Claim::Borderline(format!(
                    "balance residual {bal:e} at rounding level ({rounding:e})"
                ));
            }
            // without q the scale is smaller, so this error is an upper bound of the true one
            let upper = independent_error(g.dim, &g.mu, r, &u, &[]);
            if let Some(e) = upper {
                if e <= tol {
                    return Claim::Confirmed;
                }
            }
            if g.m.nrows > 300 {
                return Claim::Unverified;
            }
            let Some(minv_f) = dense_solve(&g.m, &g.f) else {
                return Claim::Unverified;
            };
            let mut q = g.w.clone();
            gemv_t(&g.h, &minv_f, &mut q);
            judge(independent_error(g.dim, &g.mu, r, &u, &q), tol)
        }
    }
}

fn judge(e: Option<f64>, tol: f64) -> Claim {
    match e {
        None => Claim::False("non-finite r, u or q".into()),
        Some(e) if e <= tol => Claim::Confirmed,
        Some(e) if e <= 10.0 * tol => Claim::Borderline(format!("independent err {e:e}")),
        Some(e) => Claim::False(format!("independent err {e:e}")),
    }
}

fn record(out: &mut Outcome, claim: Claim, what: &str) {
    match claim {
        Claim::Confirmed => {}
        Claim::Borderline(s) => {
            out.borderline += 1;
            out.notes.push(format!("borderline {what}: {s}"));
        }
        Claim::False(s) => {
            out.false_converged += 1;
            out.notes.push(format!("FALSE CONVERGED {what}: {s}"));
        }
        Claim::Unverified => out.unverified += 1,
    }
}

// ---------------------------------------------------------------------------------------
// Driving the library.

fn methods() -> Vec<Settings> {
    let base = |mut s: Settings| {
        s.time_limit = Some(Duration::from_millis(300));
        s.max_outer = 30;
        s.max_inner = 2000;
        s
    };
    vec![
        base(Settings::default()),
        base(Settings::method(InnerKind::Pgs, OuterKind::Fused)),
        base(Settings::method(InnerKind::Ipm, OuterKind::FixedPoint)),
        base(Settings::method(InnerKind::Apgd, OuterKind::Anderson)),
        base(Settings::method(InnerKind::Faceted, OuterKind::FixedPoint)),
    ]
}

fn evaluate(out: &mut Outcome, f: &FclibFile, s: &StoredSolution, what: &str) {
    if let Ok(ev) = fclib::evaluate(&f.problem, s) {
        out.evaluations += 1;
        if ev.converged(TOL) {
            record(out, verify(&f.problem, &s.r, s.v.as_deref(), TOL), what);
        }
    }
}

/// Runs every entry point on one file image.
fn drive(bytes: Vec<u8>, method: usize, check: bool) -> Outcome {
    let mut out = Outcome::default();
    let strict = fclib::read_bytes("fuzz.hdf5", bytes.clone());
    // files are read as stored: the second read (formerly symmetrized) is the same read
    let relaxed = fclib::read_bytes("fuzz.hdf5", bytes);
    if strict.is_ok() {
        out.read_ok += 1;
    } else {
        out.read_err += 1;
    }
    let Ok(f) = relaxed else {
        return out;
    };
    if let Some(s) = &f.solution {
        evaluate(&mut out, &f, s, "evaluate /solution");
    }
    for g in &f.guesses {
        evaluate(&mut out, &f, g, "evaluate /guesses");
    }
    let all = methods();
    let settings = &all[method % all.len()];
    let guess = f.guesses.first().map(|g| Guess {
        r: g.r.clone(),
        v: g.v.clone(),
    });
    for g in [None, guess.as_ref()] {
        if let Ok(sol) = solver::solve_with_guess(&f.problem, settings, g) {
            out.solves += 1;
            if sol.status == Status::Converged {
                out.converged += 1;
                record(
                    &mut out,
                    verify(&f.problem, &sol.r, sol.v.as_deref(), TOL),
                    &format!("solve {:?}/{:?}", settings.inner, settings.outer),
                );
            }
        }
        if guess.is_none() {
            break;
        }
    }
    if check && f.problem.contacts() <= 60 {
        let cs = CheckSettings {
            time_limit: Duration::from_millis(500),
            max_iter: 60,
            ..CheckSettings::default()
        };
        if existence::check(&f.problem, &cs).is_ok() {
            out.checks += 1;
        }
    }
    out
}

enum Run {
    Done(Outcome),
    Panicked(String),
    Hung,
}

/// Runs `drive` on a thread with the wall-clock cap; a hung thread is left behind.
fn run_case(bytes: Vec<u8>, method: usize, check: bool) -> Run {
    let (tx, rx) = mpsc::channel();
    let spawned = std::thread::Builder::new()
        .name("fuzz-case".into())
        .spawn(move || {
            let r = catch_unwind(AssertUnwindSafe(|| drive(bytes, method, check)));
            let _ = tx.send(r);
        });
    if let Err(e) = spawned {
        return Run::Panicked(format!("the harness could not start a thread: {e}"));
    }
    match rx.recv_timeout(CASE_CAP) {
        Ok(Ok(o)) => Run::Done(o),
        Ok(Err(p)) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Run::Panicked(msg)
        }
        Err(_) => Run::Hung,
    }
}

// ---------------------------------------------------------------------------------------
// Inputs.

#[derive(Clone, Debug)]
enum Data {
    F64(Vec<f64>),
    I32(Vec<i32>),
    I64(Vec<i64>),
    Str(String),
    Group,
}

type Layout = BTreeMap<String, Data>;

/// The HDF5 image of a layout (paths at least one group deep).
fn build(layout: &Layout) -> Vec<u8> {
    #[derive(Default)]
    struct Node {
        children: BTreeMap<String, Node>,
        data: Option<Data>,
    }
    let mut root = Node::default();
    for (path, d) in layout {
        let mut node = &mut root;
        for part in path.split('/') {
            node = node.children.entry(part.to_string()).or_default();
        }
        if !matches!(d, Data::Group) {
            node.data = Some(d.clone());
        }
    }
    fn fill(g: &mut GroupBuilder, node: &Node) {
        for (name, child) in &node.children {
            match &child.data {
                Some(Data::F64(v)) => {
                    g.create_dataset(name).with_f64_data(v);
                }
                Some(Data::I32(v)) => {
                    g.create_dataset(name).with_i32_data(v);
                }
                Some(Data::I64(v)) => {
                    g.create_dataset(name).with_i64_data(v);
                }
                Some(Data::Str(s)) => {
                    if let Ok(ds) = g.create_dataset(name).with_ascii_strings(&[s.as_str()]) {
                        ds.with_shape(&[]);
                    }
                }
                Some(Data::Group) | None => {
                    let mut sub = g.create_group(name);
                    fill(&mut sub, child);
                    g.add_group(sub.finish());
                }
            }
        }
    }
    let mut b = FileBuilder::new();
    for (name, child) in &root.children {
        let mut g = b.create_group(name);
        fill(&mut g, child);
        b.add_group(g.finish());
    }
    b.finish().unwrap_or_default()
}

fn value(rng: &mut ChaCha8Rng, scale: f64) -> f64 {
    if rng.random_range(0..20) == 0 {
        SPECIALS[rng.random_range(0..SPECIALS.len())]
    } else {
        scale * rng.random_range(-1.0..1.0)
    }
}

/// A CSC matrix layout under `path`: `diag` on the diagonal plus random symmetric off-diagonal
/// entries of size `off`.
fn put_matrix(l: &mut Layout, path: &str, n: usize, ncols: usize, entries: &[(usize, usize, f64)]) {
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); ncols];
    for &(i, j, x) in entries {
        if j < ncols && !cols[j].iter().any(|(r, _)| *r == i) {
            cols[j].push((i, x));
        }
    }
    let mut p = vec![0i32];
    let mut idx = Vec::new();
    let mut x = Vec::new();
    for c in &mut cols {
        c.sort_by_key(|e| e.0);
        for &(i, v) in c.iter() {
            idx.push(i as i32);
            x.push(v);
        }
        p.push(idx.len() as i32);
    }
    l.insert(format!("{path}/m"), Data::I32(vec![n as i32]));
    l.insert(format!("{path}/n"), Data::I32(vec![ncols as i32]));
    l.insert(format!("{path}/nz"), Data::I32(vec![-1]));
    l.insert(format!("{path}/nzmax"), Data::I32(vec![x.len() as i32]));
    l.insert(format!("{path}/p"), Data::I32(p));
    l.insert(format!("{path}/i"), Data::I32(idx));
    l.insert(format!("{path}/x"), Data::F64(x));
}

/// A structured layout: a local or global problem with random sizes and scales (1, 10¹⁵⁵,
/// 10³⁰⁸, 10⁻³⁰⁰, negative), then a few structural edits (dataset removed, length changed,
/// claimed size set to 10¹², a value replaced by a special one, solution and guesses of the
/// wrong shape).
fn structured(rng: &mut ChaCha8Rng) -> Vec<u8> {
    let dim = if rng.random_bool(0.8) { 3 } else { 2 };
    let nc = rng.random_range(1..=6);
    let m = dim * nc;
    let scales = [1.0, 1.0, 1.0, 1e155, 1e308, 1e-300, -1.0, -0.01, 1e-8, 1e8];
    let ws = scales[rng.random_range(0..scales.len())];
    let qs = scales[rng.random_range(0..scales.len())];
    let mut l = Layout::new();
    let global = rng.random_bool(0.35);
    let mu: Vec<f64> = (0..nc)
        .map(|_| {
            if rng.random_range(0..15) == 0 {
                SPECIALS[rng.random_range(0..SPECIALS.len())]
            } else {
                rng.random_range(0.0..1.5)
            }
        })
        .collect();
    let sym = |rng: &mut ChaCha8Rng, n: usize, s: f64| {
        let mut e = Vec::new();
        for i in 0..n {
            e.push((i, i, s * rng.random_range(0.5..2.0)));
        }
        for _ in 0..rng.random_range(0..n) {
            let i = rng.random_range(0..n);
            let j = rng.random_range(0..n);
            if i != j {
                let x = value(rng, 0.3 * s.abs());
                e.push((i, j, x));
                e.push((j, i, x));
            }
        }
        e
    };
    if global {
        let n = rng.random_range(1..=8);
        let me = sym(rng, n, ws);
        put_matrix(&mut l, "fclib_global/M", n, n, &me);
        let he: Vec<(usize, usize, f64)> = (0..m)
            .map(|j| (rng.random_range(0..n), j, value(rng, 1.0)))
            .collect();
        put_matrix(&mut l, "fclib_global/H", n, m, &he);
        let f: Vec<f64> = (0..n).map(|_| value(rng, qs)).collect();
        let w: Vec<f64> = (0..m).map(|_| value(rng, qs)).collect();
        l.insert("fclib_global/vectors/f".into(), Data::F64(f));
        l.insert("fclib_global/vectors/w".into(), Data::F64(w));
        l.insert("fclib_global/vectors/mu".into(), Data::F64(mu));
        l.insert("fclib_global/spacedim".into(), Data::I32(vec![dim as i32]));
        if rng.random_bool(0.5) {
            l.insert(
                "solution/v".into(),
                Data::F64((0..n).map(|_| value(rng, 1.0)).collect()),
            );
        }
    } else {
        let we = sym(rng, m, ws);
        put_matrix(&mut l, "fclib_local/W", m, m, &we);
        let q: Vec<f64> = (0..m).map(|_| value(rng, qs)).collect();
        l.insert("fclib_local/vectors/q".into(), Data::F64(q));
        l.insert("fclib_local/vectors/mu".into(), Data::F64(mu));
        l.insert("fclib_local/spacedim".into(), Data::I32(vec![dim as i32]));
    }
    if rng.random_bool(0.5) {
        let len = if rng.random_bool(0.8) {
            m
        } else {
            rng.random_range(0..2 * m + 2)
        };
        l.insert(
            "solution/r".into(),
            Data::F64((0..len).map(|_| value(rng, 1.0)).collect()),
        );
        l.insert(
            "solution/u".into(),
            Data::F64((0..m).map(|_| value(rng, 1.0)).collect()),
        );
    }
    if rng.random_bool(0.4) {
        let k = rng.random_range(0..3);
        l.insert("guesses/number_of_guesses".into(), Data::I32(vec![k]));
        for g in 1..=rng.random_range(0..3) {
            let len = if rng.random_bool(0.8) {
                m
            } else {
                rng.random_range(0..m + 3)
            };
            l.insert(
                format!("guesses/{g}/r"),
                Data::F64((0..len).map(|_| value(rng, 1.0)).collect()),
            );
        }
    }
    // structural edits
    for _ in 0..rng.random_range(0..3) {
        let keys: Vec<String> = l.keys().cloned().collect();
        let key = keys[rng.random_range(0..keys.len())].clone();
        match rng.random_range(0..7) {
            0 => {
                l.remove(&key);
            }
            1 => {
                let big = [1_000_000_000_000i64, i64::MAX, -1, 0, i32::MAX as i64]
                    [rng.random_range(0..5)];
                l.insert(key, Data::I64(vec![big]));
            }
            2 => {
                if let Some(Data::F64(v)) = l.get_mut(&key) {
                    if !v.is_empty() {
                        let i = rng.random_range(0..v.len());
                        v[i] = SPECIALS[rng.random_range(0..SPECIALS.len())];
                    }
                }
            }
            3 => {
                if let Some(Data::F64(v)) = l.get_mut(&key) {
                    let n = rng.random_range(0..v.len() + 3);
                    v.resize(n, 1.0);
                }
            }
            4 => {
                if let Some(Data::I32(v)) = l.get_mut(&key) {
                    if !v.is_empty() {
                        let i = rng.random_range(0..v.len());
                        v[i] = [-1, 0, 1, 7, i32::MAX, i32::MIN][rng.random_range(0..6)];
                    }
                }
            }
            5 => {
                l.insert(key, Data::Str("not a number".into()));
            }
            _ => {
                l.insert(key, Data::Group);
            }
        }
    }
    build(&l)
}

/// Byte-level edits of an image: bit flips, random bytes, f64 specials over 8 bytes (most
/// land in data arrays), copied chunks, truncation.
fn mutate_bytes(rng: &mut ChaCha8Rng, mut b: Vec<u8>) -> Vec<u8> {
    if b.is_empty() {
        return b;
    }
    for _ in 0..rng.random_range(1..=6) {
        let n = b.len();
        match rng.random_range(0..10) {
            0 => {
                let i = rng.random_range(0..n);
                b[i] ^= 1 << rng.random_range(0..8);
            }
            1 => {
                let i = rng.random_range(0..n);
                b[i] = rng.random();
            }
            2..=6 => {
                // an f64 special at an 8-aligned offset in the second half (data arrays)
                if n >= 16 {
                    let i = (rng.random_range(n / 4..n - 8) / 8) * 8;
                    let x = SPECIALS[rng.random_range(0..SPECIALS.len())];
                    b[i..i + 8].copy_from_slice(&x.to_le_bytes());
                }
            }
            7 => {
                if n > 64 {
                    let len = rng.random_range(1..32);
                    let from = rng.random_range(0..n - len);
                    let to = rng.random_range(0..n - len);
                    let chunk = b[from..from + len].to_vec();
                    b[to..to + len].copy_from_slice(&chunk);
                }
            }
            8 => {
                let keep = rng.random_range(0..n);
                b.truncate(keep.max(1));
            }
            _ => {
                // a 4- or 8-byte integer field set to a huge value
                if n > 8 {
                    let i = rng.random_range(0..n - 8);
                    let x: u64 = [u64::MAX, 1 << 40, 0x7fff_ffff, 0][rng.random_range(0..4)];
                    b[i..i + 8].copy_from_slice(&x.to_le_bytes());
                }
            }
        }
    }
    b
}

/// Seed images: data/'s FCLIB files, the shared ones (the smaller ones, when ../shared is
/// there) and structured images.
fn seed_images() -> Vec<Vec<u8>> {
    let mut out: Vec<Vec<u8>> = common::data_files()
        .iter()
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    let dir = common::shared_fclib();
    if let Ok(rd) = std::fs::read_dir(&dir) {
        let mut paths: Vec<_> = rd.filter_map(|e| e.ok()).map(|e| e.path()).collect();
        paths.sort();
        for p in paths {
            if let Ok(b) = std::fs::read(&p) {
                if b.len() <= 200_000 {
                    out.push(b);
                }
            }
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for _ in 0..8 {
        out.push(structured(&mut rng));
    }
    out
}

/// One case from `seed`: (image, method index, whether to check existence).
fn case(seed: u64, seeds: &[Vec<u8>]) -> (Vec<u8>, usize, bool) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let bytes = match rng.random_range(0..10) {
        0..=4 => structured(&mut rng),
        5 => {
            let s = structured(&mut rng);
            mutate_bytes(&mut rng, s)
        }
        _ => {
            let s = seeds[rng.random_range(0..seeds.len())].clone();
            mutate_bytes(&mut rng, s)
        }
    };
    (bytes, rng.random_range(0..5), rng.random_bool(0.3))
}

/// Runs cases `first..` until `n` cases or `budget` is spent; prints the tally every minute
/// when `verbose`.
fn campaign(first: u64, n: u64, budget: Duration, verbose: bool) -> Tally {
    let seeds = seed_images();
    let start = Instant::now();
    let mut last_print = Instant::now();
    let mut t = Tally::default();
    let mut seed = first;
    while t.cases < n && start.elapsed() < budget {
        let (bytes, method, check) = case(seed, &seeds);
        t.cases += 1;
        match run_case(bytes, method, check) {
            Run::Done(o) => {
                for note in &o.notes {
                    if verbose {
                        println!("seed {seed}: {note}");
                    }
                }
                let notes: Vec<String> = o
                    .notes
                    .iter()
                    .map(|n| format!("seed {seed}: {n}"))
                    .collect();
                t.add(&Outcome { notes, ..o });
            }
            Run::Panicked(m) => {
                t.panics += 1;
                let note = format!("seed {seed}: PANIC {m}");
                if verbose {
                    println!("{note}");
                }
                t.notes.push(note);
            }
            Run::Hung => {
                t.hangs += 1;
                let note = format!("seed {seed}: HANG (over {CASE_CAP:?})");
                if verbose {
                    println!("{note}");
                }
                t.notes.push(note);
            }
        }
        seed += 1;
        if verbose && last_print.elapsed() > Duration::from_secs(60) {
            println!("{}", t.line(start.elapsed().as_secs_f64()));
            last_print = Instant::now();
        }
    }
    if verbose {
        println!("final: {}", t.line(start.elapsed().as_secs_f64()));
    }
    t
}

/// Panics of the case threads are counted, not printed; any other panic (the harness itself)
/// is printed as usual.
fn quiet_panics() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if std::thread::current().name() != Some("fuzz-case") {
            default(info);
        }
    }));
}

#[test]
fn fuzz_short() {
    quiet_panics();
    let t = campaign(0, 1000, Duration::from_secs(30), false);
    assert!(t.cases >= 20, "{}", t.line(0.0));
    assert!(
        t.panics == 0 && t.hangs == 0 && t.false_converged == 0,
        "{}\n{}",
        t.line(0.0),
        t.notes.join("\n")
    );
    // the harness reaches the solver, not only the reader
    assert!(t.read_ok > 0 && t.solves > 0, "{}", t.line(0.0));
}

#[test]
#[ignore = "long fuzz run: COULOMB_FUZZ_SECS (default 3600), release mode"]
fn fuzz_long() {
    quiet_panics();
    let secs: u64 = std::env::var("COULOMB_FUZZ_SECS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3600);
    let first: u64 = std::env::var("COULOMB_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let t = campaign(first, u64::MAX, Duration::from_secs(secs), true);
    for n in &t.notes {
        println!("{n}");
    }
    assert!(t.panics == 0 && t.hangs == 0 && t.false_converged == 0);
}

/// Replays one case: `COULOMB_FUZZ_ONE=SEED cargo test -p coulomb --test integration -- --ignored
/// --nocapture fuzz::fuzz_one` prints what each entry point returned.
#[test]
#[ignore = "replays the case COULOMB_FUZZ_ONE"]
fn fuzz_one() {
    let seed: u64 = std::env::var("COULOMB_FUZZ_ONE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let seeds = seed_images();
    let (bytes, method, _) = case(seed, &seeds);
    let f = fclib::read_bytes("fuzz.hdf5", bytes);
    match &f {
        Ok(f) => {
            println!("problem: {:?}", f.problem);
            println!("guesses: {:?}", f.guesses);
            let s = &methods()[method % 5];
            for g in [None, f.guesses.first()] {
                let g = g.map(|g| Guess {
                    r: g.r.clone(),
                    v: g.v.clone(),
                });
                let sol = solver::solve_with_guess(&f.problem, s, g.as_ref());
                match sol {
                    Ok(sol) => println!(
                        "{:?}/{:?}: {:?} err {:e} r {:?} u {:?} v {:?}",
                        s.inner, s.outer, sol.status, sol.error, sol.r, sol.u, sol.v
                    ),
                    Err(e) => println!("{e}"),
                }
            }
        }
        Err(e) => println!("{e}"),
    }
}
