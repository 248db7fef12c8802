//! The accurate scaling study (`coulomb paper scaling --accurate`): time per step against the number of beads with every
//! step solved to err ≤ tol (docs/error.md) by body-level nonsmooth Gauss–Seidel
//! (coulomb_granular::nsgs), the physics of `coulomb simulate`, for each thread count.
//! Table: time per step and per contact, sweeps, steps converged, peak memory; also whether
//! the runs with different thread counts ended in bitwise the same state.

use crate::progress::NewSteps;
use crate::threads::with_threads;
use anyhow::{bail, Context};
use coulomb::InnerKind;
use coulomb_granular::scene::{BoxLayout, BEAD_RADIUS};
use coulomb_granular::{NsgsSettings, Params, Scene, Simulation, StepMethod};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of [`super::scaling`] (`coulomb paper scaling`'s arguments).
#[derive(Debug, Clone)]
pub struct Scaling {
    /// bead counts
    pub beads: Vec<usize>,
    /// untimed steps first (the beads land and the contacts form)
    pub settle: usize,
    /// timed steps after the settling ones
    pub window: usize,
    /// inner solver (the paper's tolerance: (6.1) with ε = 0.01, ≤ 20 subproblems)
    pub inner: InnerKind,
    /// seed
    pub seed: u64,
    /// SVG file; the data go beside it as JSON (same name, .json)
    pub svg: PathBuf,
    /// also write the table as Markdown into this file
    pub markdown: Option<PathBuf>,
    /// accurate mode: every step solved to err ≤ --tol by body-level Gauss–Seidel (the
    /// physics of `coulomb simulate`), once per --threads value; see docs/scaling.md
    pub accurate: bool,
    /// accurate mode: tolerance on the error of docs/error.md at every step
    pub tol: f64,
    /// accurate mode: thread counts to run each size with (default: 1 and all cores)
    pub threads: Vec<usize>,
    /// accurate mode: cap on Gauss–Seidel sweeps per step
    pub max_sweeps: usize,
    /// accurate mode: box layout — `spread` (default: the calibrated floor, the partial top
    /// layer spread over it at random) or `calibrated` (the partial top layer fills the
    /// first rows, as in the paper runs); see docs/scaling.md, "Scene sizing"
    pub layout: Layout,
    /// accurate mode: over-relaxation ω ∈ [1, 2) of the Gauss–Seidel updates
    pub relaxation: f64,
}

/// The box layout of the accurate study.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Layout {
    /// the calibrated floor with the partial top layer spread over it at random
    /// (`Scene::box_spread`): the same heap structure at every N
    Spread,
    /// the calibrated layout of the paper runs (`Scene::Box`): the partial top layer fills
    /// the first rows, a two-layer strip whose width grows as √N
    Calibrated,
}

impl Layout {
    /// Every layout.
    pub const ALL: [Layout; 2] = [Layout::Spread, Layout::Calibrated];

    /// The layout's name (as in the table and the data).
    pub fn as_str(self) -> &'static str {
        match self {
            Layout::Spread => "spread",
            Layout::Calibrated => "calibrated",
        }
    }

    /// What the layout is, in a few words.
    pub fn about(self) -> &'static str {
        match self {
            Layout::Spread => "the calibrated floor with the partial top layer spread over it at random (`Scene::box_spread`): the same heap structure at every N",
            Layout::Calibrated => "the calibrated layout of the paper runs (`Scene::Box`): the partial top layer fills the first rows, a two-layer strip whose width grows as √N",
        }
    }

    fn build(self, beads: usize, seed: u64) -> coulomb_granular::World {
        match self {
            Layout::Spread => Scene::box_spread(beads, seed),
            Layout::Calibrated => Scene::Box.build(beads, seed),
        }
    }
}

/// One (beads, threads) run: means over the timed window.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AccuratePoint {
    beads: usize,
    threads: usize,
    box_x: f64,
    box_y: f64,
    settle_steps: usize,
    timed_steps: usize,
    /// active contacts per step
    contacts: f64,
    /// Gauss–Seidel sweeps per step (mean, max)
    sweeps: f64,
    max_sweeps: usize,
    /// wall-clock time of `Simulation::step` (detection, problem, solve, position update
    /// and correction, penetration statistics)
    step_ms: f64,
    /// of which the Gauss–Seidel solve
    solve_ms: f64,
    /// of which detection + building the step problem
    assembly_ms: f64,
    /// step_ms per contact (µs)
    us_per_contact: f64,
    /// CPU time per step summed over the process's threads (ms; Linux /proc/self/stat at
    /// 10 ms resolution over the window, None elsewhere): on a machine shared with other jobs the wall-clock times above include
    /// waiting for a core, this does not (rayon workers that spin while waiting count)
    cpu_ms: Option<f64>,
    /// cpu_ms per contact (µs)
    cpu_us_per_contact: Option<f64>,
    /// steps of the window with err ≤ tol
    converged: usize,
    /// steps of the whole run (settling included) with err ≤ tol, and their number
    converged_all: usize,
    steps_all: usize,
    mean_error: f64,
    max_error: f64,
    /// largest penetration at the end of the run, relative to R
    end_penetration_rel: f64,
    /// peak resident memory of the process so far (MiB; sizes run in increasing order)
    peak_rss_mib: Option<f64>,
    /// hash of the final state (positions and velocities, bitwise)
    state_hash: u64,
}

/// Peak resident set size of this process (VmHWM), MiB; None where /proc is missing.
fn peak_rss_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// CPU time (user + system) of this process so far, all threads, in ns, from
/// /proc/self/stat (clock ticks of 10 ms: meaningful over a window of many steps); None
/// where that is missing.
fn cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = s.get(s.rfind(')')? + 1..)?;
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: u64 = f.get(11)?.parse().ok()?;
    let stime: u64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) * 10_000_000)
}

/// FNV-1a over the bits of every position and velocity.
fn state_hash(sim: &Simulation) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for b in &sim.world.bodies {
        for x in b
            .position
            .to_array()
            .into_iter()
            .chain(b.velocity.to_array())
            .chain(b.angular_velocity.to_array())
        {
            for byte in x.to_bits().to_le_bytes() {
                h ^= byte as u64;
                h = h.wrapping_mul(0x100000001b3);
            }
        }
    }
    h
}

/// The parameters of `coulomb simulate` (accurate activation, position correction, warm
/// starts) with body-level Gauss–Seidel to `tol`.
pub fn accurate_params(tol: f64, max_sweeps: usize, relaxation: f64) -> Params {
    Params {
        method: StepMethod::Nsgs(NsgsSettings {
            tol,
            max_sweeps,
            relaxation,
            ..NsgsSettings::default()
        }),
        ..Params::default()
    }
}

fn run_one(
    beads: usize,
    threads: usize,
    a: &Scaling,
    bars: NewSteps<'_>,
) -> anyhow::Result<AccuratePoint> {
    let label = format!("{beads} beads, {threads} thread(s)");
    let params = accurate_params(a.tol, a.max_sweeps, a.relaxation);
    with_threads(Some(threads), || {
        let mut sim = Simulation::new(a.layout.build(beads, a.seed), params)?;
        let total = a.settle + a.window;
        let pb = bars(total);
        pb.set_prefix(label.clone());
        let mut rows = Vec::new();
        let mut converged_all = 0;
        let mut cpu_start = None;
        for k in 0..total {
            if k == a.settle {
                cpu_start = cpu_ns();
            }
            let t = Instant::now();
            let s = sim
                .step()
                .with_context(|| format!("{label}: time step failed"))?;
            let ms = t.elapsed().as_secs_f64() * 1e3;
            converged_all += usize::from(s.converged);
            pb.set_message(format!(
                "{} contacts, {} sweeps, {ms:.0} ms, err {:.1e}",
                s.contacts, s.inner_iterations, s.error
            ));
            pb.inc(1);
            rows.push((ms, s));
        }
        pb.finish_and_clear();
        let timed = rows.get(a.settle..).unwrap_or(&[]);
        let cpu_ms = match (cpu_start, cpu_ns()) {
            (Some(s), Some(e)) if !timed.is_empty() => {
                Some(e.saturating_sub(s) as f64 * 1e-6 / timed.len() as f64)
            }
            _ => None,
        };
        let n = timed.len().max(1) as f64;
        let mean = |f: &dyn Fn(&(f64, coulomb_granular::StepStats)) -> f64| {
            timed.iter().map(f).sum::<f64>() / n
        };
        let layout = BoxLayout::for_beads(beads);
        let contacts = mean(&|r| r.1.contacts as f64);
        let step_ms = mean(&|r| r.0);
        let last = rows.last().map(|r| r.1.end_max_penetration).unwrap_or(0.0);
        Ok(AccuratePoint {
            beads,
            threads,
            box_x: layout.side_x,
            box_y: layout.side_y,
            settle_steps: a.settle,
            timed_steps: timed.len(),
            contacts,
            sweeps: mean(&|r| r.1.inner_iterations as f64),
            max_sweeps: timed
                .iter()
                .map(|r| r.1.inner_iterations)
                .max()
                .unwrap_or(0),
            step_ms,
            solve_ms: mean(&|r| r.1.solve_ms),
            assembly_ms: mean(&|r| r.1.assembly_ms),
            us_per_contact: if contacts > 0.0 {
                1e3 * step_ms / contacts
            } else {
                0.0
            },
            cpu_ms,
            cpu_us_per_contact: cpu_ms
                .filter(|_| contacts > 0.0)
                .map(|c| 1e3 * c / contacts),
            converged: timed.iter().filter(|r| r.1.converged).count(),
            converged_all,
            steps_all: rows.len(),
            mean_error: mean(&|r| r.1.error),
            max_error: timed.iter().map(|r| r.1.error).fold(0.0, f64::max),
            end_penetration_rel: last / BEAD_RADIUS,
            peak_rss_mib: peak_rss_mib(),
            state_hash: state_hash(&sim),
        })
    })
}

/// Runs the accurate scaling study; the table goes to `show`.
pub fn run(a: &Scaling, bars: NewSteps<'_>, show: &mut dyn FnMut(&str)) -> anyhow::Result<()> {
    if a.beads.is_empty() || a.beads.iter().any(|&b| b == 0 || b > 1_000_000) {
        bail!("--beads must list bead counts in 1..=1000000");
    }
    if a.window == 0 || a.window > 100_000 || a.settle > 100_000 {
        bail!("--window must be in 1..=100000 and --settle at most 100000");
    }
    let svg = &a.svg;
    let data = svg.with_extension("json");
    crate::outputs::check("--svg", svg, &[])?;
    crate::outputs::check("the data file", &data, &[])?;
    if let Some(path) = &a.markdown {
        crate::outputs::check("--markdown", path, &[])?;
    }
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let threads = if a.threads.is_empty() {
        let mut t = vec![1, cores];
        t.dedup();
        t
    } else {
        a.threads.clone()
    };
    let mut beads = a.beads.clone();
    beads.sort_unstable();
    beads.dedup();
    let mut points = Vec::new();
    let started = Instant::now();
    for &b in &beads {
        for &t in &threads {
            let p = run_one(b, t, a, bars)?;
            eprintln!(
                "{b} beads, {t} thread(s): {:.0} contacts, {:.0} sweeps, {:.2} ms/step, {:.2} µs/contact, {}/{} converged, max err {:.1e}, peak RSS {:.0} MiB ({:.0} s so far)",
                p.contacts,
                p.sweeps,
                p.step_ms,
                p.us_per_contact,
                p.converged_all,
                p.steps_all,
                p.max_error,
                p.peak_rss_mib.unwrap_or(f64::NAN),
                started.elapsed().as_secs_f64()
            );
            points.push(p);
        }
    }
    let md = table(a, &beads, &threads, cores, &points);
    show(&md);
    if let Some(path) = &a.markdown {
        crate::outputs::write(path, md.as_bytes())?;
    }
    crate::outputs::write(&data, crate::outputs::json(&points, true)?.as_bytes())?;
    plot(svg, &points, &threads)?;
    eprintln!("wrote {} and {}", svg.display(), data.display());
    Ok(())
}

fn opt(x: Option<f64>) -> String {
    x.map(|v| format!("{v:.2}")).unwrap_or_else(|| "–".into())
}

fn table(
    a: &Scaling,
    beads: &[usize],
    threads: &[usize],
    cores: usize,
    points: &[AccuratePoint],
) -> String {
    let mut md = String::new();
    let list = |v: &[usize]| {
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    let _ = writeln!(
        md,
        "Produced by `coulomb paper scaling --accurate --beads {} --threads {} --settle {} --window {} --tol {:e} --relaxation {} --layout {} --seed {}` on a {cores}-core machine. Box scene, floor ∝ N so that the heap height stays fixed (≈ {} initial layers; layout `{}`, docs/scaling.md); h = 0.02 s, e = 0.2, μ = 0.3; the physics of `coulomb simulate` (accurate activation, position correction, warm starts by contact identity); every step solved by body-level nonsmooth Gauss–Seidel (over-relaxed, ω reduced towards 1 where it does not help) to err ≤ {:e} (docs/error.md, on the stored problem). Means over steps {}..{}; `conv.` counts the steps of the whole run with err ≤ tol.\n",
        list(beads),
        list(threads),
        a.settle,
        a.window,
        a.tol,
        a.relaxation,
        a.layout.as_str(),
        a.seed,
        coulomb_granular::scene::BOX_LAYERS,
        a.layout.as_str(),
        a.tol,
        a.settle,
        a.settle + a.window,
    );
    let _ = writeln!(
        md,
        "| #beads | threads | box (m) | #contacts | sweeps (max) | step ms | of which solve | of which detect + build | of which rest (position correction, update, statistics) | µs / contact / step | CPU ms / step | CPU µs / contact | speed-up | conv. | max err | end pen. / R | peak RSS (MiB) | same state |"
    );
    let _ = writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for p in points {
        let base = points
            .iter()
            .find(|q| q.beads == p.beads && q.threads == threads[0]);
        let speedup = base.map(|q| q.step_ms / p.step_ms).unwrap_or(f64::NAN);
        let same = base.map(|q| q.state_hash == p.state_hash).unwrap_or(true);
        let _ = writeln!(
            md,
            "| {} | {} | {:.2} × {:.2} | {:.0} | {:.0} ({}) | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {:.2} | {}/{} | {:.1e} | {:.1e} | {} | {} |",
            p.beads,
            p.threads,
            p.box_x,
            p.box_y,
            p.contacts,
            p.sweeps,
            p.max_sweeps,
            p.step_ms,
            p.solve_ms,
            p.assembly_ms,
            (p.step_ms - p.solve_ms - p.assembly_ms).max(0.0),
            p.us_per_contact,
            opt(p.cpu_ms),
            opt(p.cpu_us_per_contact),
            speedup,
            p.converged_all,
            p.steps_all,
            p.max_error,
            p.end_penetration_rel,
            p.peak_rss_mib
                .map(|m| format!("{m:.0}"))
                .unwrap_or_else(|| "–".into()),
            if same { "yes" } else { "NO" }
        );
    }
    md
}

/// Log–log plot of µs per contact per step against beads, one line per thread count.
fn plot(path: &Path, points: &[AccuratePoint], threads: &[usize]) -> anyhow::Result<()> {
    let ok = |y: f64| y.is_finite() && y > 0.0;
    let xmax = points.iter().map(|p| p.beads as f64).fold(1.0, f64::max) * 1.25;
    let xmin = points
        .iter()
        .map(|p| p.beads as f64)
        .fold(f64::INFINITY, f64::min)
        .min(100.0)
        * 0.8;
    let ys = || points.iter().map(|p| p.us_per_contact).filter(|y| ok(*y));
    let ymin = ys().fold(f64::INFINITY, f64::min).min(1.0) * 0.5;
    let ymax = ys().fold(10.0, f64::max) * 2.0;
    let staged = crate::outputs::Staged::new(path);
    let tmp = staged.path().to_path_buf();
    let root = SVGBackend::new(&tmp, (800, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Cost per contact per step, err <= tol every step (NSGS)",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((xmin..xmax).log_scale(), (ymin..ymax).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("beads")
        .y_desc("µs per contact per step")
        .draw()?;
    let colors = [BLACK, BLUE, RED, GREEN, MAGENTA, CYAN];
    for (k, &t) in threads.iter().enumerate() {
        let color = colors[k % colors.len()];
        let pts: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.threads == t)
            .map(|p| (p.beads as f64, p.us_per_contact))
            .filter(|(_, y)| ok(*y))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color))?
            .label(format!("{t} thread(s)"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()?;
    root.present()?;
    staged.commit()?;
    Ok(())
}
