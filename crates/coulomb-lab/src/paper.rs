//! The engine of `coulomb paper`: the granular experiments of §6 — Table 1 ([`table1`]:
//! 150/300/600 beads, projected gradient and interior point), Fig. 8 ([`fig8`]: solve time per
//! step against contacts, 600 beads), Fig. 9 ([`fig9`]: convergence of the fixed point for
//! μ = 0.1 … 0.9), and a scaling curve ([`scaling`]: time per step against the number of beads).
//!
//! Each takes its options (`coulomb paper`'s arguments), checks them and its output paths
//! ([`crate::outputs::check`]) before the runs, shows the progress of each run through the
//! caller's [`NewSteps`], reports each run on stderr, gives its Markdown table to the caller's
//! `show` (the CLI prints it) and writes its files ([`crate::outputs`]).

use crate::progress::NewSteps;
use anyhow::{bail, Context};
use coulomb::{InnerKind, Settings};
use coulomb_granular::output::write_stats;
use coulomb_granular::run::RestMonitor;
use coulomb_granular::{Params, Scene, Simulation, StepStats, Stop, Summary};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

mod accurate;
pub use accurate::{Layout, Scaling};

/// Options of [`table1`] (`coulomb paper table1`'s arguments).
#[derive(Debug, Clone)]
pub struct Table1 {
    /// bead counts
    pub beads: Vec<usize>,
    /// time steps of each run (the paper's #TS is 255–352)
    pub steps: usize,
    /// tolerance on the reported error (docs/error.md) for "converged"
    pub tol: f64,
    /// ε of the outer rule (6.1) (the paper's 0.01); 0 disables it, so that only err ≤ tol or
    /// the cap ends a step
    pub fp_tol: f64,
    /// cap on subproblems (outer iterations) per step (the paper's 20)
    pub max_outer: usize,
    /// seed of the initial arrangement
    pub seed: u64,
    /// folder for the per-step statistics of each run (`box_<beads>_<inner>/stats.csv`)
    pub output: Option<PathBuf>,
    /// write the table as Markdown into this file
    pub markdown: Option<PathBuf>,
    /// only the projected-gradient runs
    pub pg_only: bool,
    /// inner solver of the "PG" rows (the paper's projected gradient is `apgd`; `pgs` is
    /// projected Gauss–Seidel)
    pub pg_inner: InnerKind,
}

/// Options of [`fig8`] (`coulomb paper fig8`'s arguments).
#[derive(Debug, Clone)]
pub struct Fig8 {
    /// number of beads
    pub beads: usize,
    /// time steps of each run
    pub steps: usize,
    /// read the runs' stats.json from a `table1 --output` folder instead of simulating
    pub from: Option<PathBuf>,
    /// SVG file; the data go beside it as CSV (same name, .csv)
    pub svg: PathBuf,
    /// seed
    pub seed: u64,
}

/// Options of [`fig9`] (`coulomb paper fig9`'s arguments).
#[derive(Debug, Clone)]
pub struct Fig9 {
    /// number of beads
    pub beads: usize,
    /// the step studied is the first with at least this many contacts
    pub contacts: usize,
    /// ε of (6.1)
    pub fp_tol: f64,
    /// cap on fixed-point iterations
    pub max_outer: usize,
    /// step cap while looking for the step
    pub max_steps: usize,
    /// cap on projected-gradient iterations per subproblem (the paper's 250)
    pub max_inner: usize,
    /// friction coefficients (default 0.1, 0.2, …, 0.9)
    pub mu: Vec<f64>,
    /// SVG file; the data go beside it as JSON (same name, .json)
    pub svg: PathBuf,
    /// seed
    pub seed: u64,
}

/// The paper's Table 1: (beads, solver, #TS, #contacts/TS, #subprob./TS, CPU ms/TS).
const PAPER: [(usize, &str, f64, f64, f64, f64); 6] = [
    (150, "PG", 352.0, 239.0, 3.3, 768.0),
    (150, "IP", 323.0, 197.0, 3.1, 236.0),
    (300, "PG", 308.0, 506.0, 3.2, 1200.0),
    (300, "IP", 272.0, 393.0, 3.5, 1121.0),
    (600, "PG", 300.0, 741.0, 3.3, 1929.0),
    (600, "IP", 255.0, 524.0, 3.5, 949.0),
];

/// The paper's setting (§6): h = 0.02 s, e = 0.2, μ, successive approximations s ← F(s)
/// stopped by rule (6.1) with ε = `fp_tol` or after `max_outer` iterations; projected gradient
/// capped at 250 iterations per subproblem.
fn paper_params(inner: InnerKind, mu: f64, tol: f64, fp_tol: f64, max_outer: usize) -> Params {
    Params {
        h: 0.02,
        restitution: 0.2,
        mu,
        // the paper's algorithm: successive approximations s ← F(s) alone, without the
        // library's Newton end game (Settings::paper)
        solver: paper_settings(inner, tol, fp_tol, max_outer),
        // the paper's time stepping: Siconos' activation rule (γ = 1/2), no position correction
        activation: coulomb_granular::Activation::default(),
        projection: None,
        ..Params::default()
    }
}

/// The paper's algorithm ([`Settings::paper`]) with `inner`, stopped by rule (6.1) with
/// ε = `fp_tol` (when > 0) or after `max_outer` subproblems.
pub fn paper_settings(inner: InnerKind, tol: f64, fp_tol: f64, max_outer: usize) -> Settings {
    let mut s = Settings {
        tol,
        max_outer,
        ..Settings::paper(inner)
    };
    s.params.fixed_point_tol = (fp_tol > 0.0).then_some(fp_tol);
    s
}

/// `path` with its extension replaced by `ext`.
fn beside(path: &Path, ext: &str) -> PathBuf {
    path.with_extension(ext)
}

fn inner_label(inner: InnerKind) -> &'static str {
    match inner {
        InnerKind::Apgd => "PG",
        InnerKind::Ipm => "IP",
        InnerKind::Pgs => "PGS",
        InnerKind::Faceted => "FC",
    }
}

/// Runs the box scene until rest (or `max_steps`) with a progress report from `bars`.
fn box_run(
    bars: NewSteps<'_>,
    beads: usize,
    seed: u64,
    params: Params,
    stop: Stop,
    label: &str,
    mut until: impl FnMut(&mut Simulation, &StepStats) -> bool,
) -> anyhow::Result<(Summary, Vec<StepStats>)> {
    let mut sim = Simulation::new(Scene::Box.build(beads, seed), params)?;
    let pb = bars(stop.max_steps());
    pb.set_prefix(label.to_string());
    let mut stats = Vec::new();
    let mut monitor = RestMonitor::default();
    let mut at_rest = false;
    while sim.steps_done < stop.max_steps() {
        let s = sim
            .step()
            .with_context(|| format!("{label}: time step failed"))?;
        pb.set_message(format!("{} contacts, {:.0} ms", s.contacts, s.solve_ms));
        pb.inc(1);
        let done = until(&mut sim, &s);
        stats.push(s);
        let (stop_now, rest) = monitor.should_stop(&stop, &sim);
        if done || stop_now {
            at_rest = rest;
            break;
        }
    }
    pb.finish_and_clear();
    Ok((Summary::from_stats("box", beads, &stats, at_rest), stats))
}

/// Table 1: the box scene with each bead count, solved by the projected gradient and the
/// interior point, beside the paper's figures; the table goes to `show` (and `--markdown`),
/// the per-step statistics of each run into `--output`.
pub fn table1(a: Table1, bars: NewSteps<'_>, show: &mut dyn FnMut(&str)) -> anyhow::Result<()> {
    if a.beads.is_empty() || a.beads.iter().any(|&b| b == 0 || b > 100_000) {
        bail!("--beads must list bead counts in 1..=100000");
    }
    if a.steps == 0 || a.steps > 100_000 {
        bail!("--steps must be in 1..=100000");
    }
    if a.max_outer == 0 || a.max_outer > 10_000 {
        bail!("--max-outer must be in 1..=10000");
    }
    let valid = a.fp_tol.is_finite() && a.fp_tol >= 0.0 && a.tol.is_finite() && a.tol > 0.0;
    if !valid {
        bail!("--fp-tol must be ≥ 0 and --tol > 0");
    }
    if let Some(path) = &a.markdown {
        crate::outputs::check("--markdown", path, &[])?;
    }
    let paper_rule = a.fp_tol == 0.01 && a.max_outer == 20 && a.tol == 1e-4;
    let rule = if a.fp_tol > 0.0 {
        format!(
            "stopped by (6.1) with ε = {} or by err ≤ {:.0e}",
            a.fp_tol, a.tol
        )
    } else {
        format!("stopped by err ≤ {:.0e} ((6.1) disabled)", a.tol)
    };
    let inners: &[InnerKind] = if a.pg_only {
        &[InnerKind::Apgd]
    } else {
        &[InnerKind::Apgd, InnerKind::Ipm]
    };
    let pg: InnerKind = a.pg_inner;
    let beads_arg: Vec<String> = a.beads.iter().map(|b| b.to_string()).collect();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Table 1 reproduced: box scene (docs/granular.md){}\n\nProduced by `coulomb paper table1 --beads {} --steps {}{}{}{} --seed {}` (this file is its standard output / `--markdown`). Setting: h = 0.02 s, e = 0.2, μ = 0.3, θ = 1/2, successive approximations {rule} or after {} subproblems; {} time steps per run (the paper's #TS: 255–352); calibrated box of docs/granular.md.\n",
        if paper_rule { "" } else { ", tighter outer rule than the paper's" },
        beads_arg.join(","),
        a.steps,
        if paper_rule {
            String::new()
        } else {
            format!(" --fp-tol {} --max-outer {} --tol {:.0e}", a.fp_tol, a.max_outer, a.tol)
        },
        if a.pg_only { " --pg-only" } else { "" },
        if pg == InnerKind::Apgd {
            String::new()
        } else {
            format!(" --pg-inner {pg:?}").to_lowercase()
        },
        a.seed,
        a.max_outer,
        a.steps
    );
    let _ = writeln!(
        md,
        "PG: inner solver `{pg:?}` capped at 250 iterations per subproblem (the paper's); IP: `Ipm` (Clarabel, primal (3.15)). #subprob./TS = outer iterations per step with contacts (0 when the warm start already meets tol = {:.0e}). CPU time/TS = solver wall-clock per step (Delassus W = Hᵀ M⁻¹ H included, detection and assembly excluded: column asm) on a {}-thread machine shared with other jobs. err = error of docs/error.md (mean over steps with contacts, max over all); converged = steps with err ≤ {:.0e}.\n",
        a.tol,
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        a.tol
    );
    let _ = writeln!(
        md,
        "| #beads | solver | #TS | #contacts/TS | #subprob./TS | CPU time/TS (ms) | asm/TS (ms) | mean err | max err | converged | max penetration (m) | paper #TS | paper #contacts/TS | paper #subprob./TS | paper CPU/TS (ms) |"
    );
    let _ = writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for &beads in &a.beads {
        for &inner in inners {
            let label = format!("{beads} beads {}", inner_label(inner));
            let solver = if inner == InnerKind::Apgd { pg } else { inner };
            let params = paper_params(solver, 0.3, a.tol, a.fp_tol, a.max_outer);
            let (s, stats) = box_run(
                bars,
                beads,
                a.seed,
                params,
                Stop::Steps(a.steps),
                &label,
                |_, _| false,
            )?;
            if let Some(dir) = &a.output {
                let sub = dir.join(format!("box_{beads}_{}", inner_label(inner).to_lowercase()));
                write_stats(&sub, &stats).with_context(|| format!("writing {}", sub.display()))?;
            }
            let paper = PAPER
                .iter()
                .find(|p| p.0 == beads && p.1 == inner_label(inner));
            let pcols = match paper {
                Some(p) => format!("{} | {} | {} | {}", p.2, p.3, p.4, p.5),
                None => "– | – | – | –".into(),
            };
            let asm = stats.iter().map(|x| x.assembly_ms).sum::<f64>() / stats.len().max(1) as f64;
            let _ = writeln!(
                md,
                "| {beads} | {} | {} | {:.0} | {:.2} | {:.1} | {:.1} | {:.1e} | {:.1e} | {}/{} | {:.1e} | {pcols} |",
                inner_label(inner),
                s.steps,
                s.mean_contacts,
                s.mean_subproblems().unwrap_or(0.0),
                s.mean_solve_seconds * 1e3,
                asm,
                s.mean_error,
                s.max_error,
                s.converged_steps,
                s.steps,
                s.max_penetration
            );
            eprintln!(
                "{label}: {} TS, {:.0} contacts/TS, {:.2} subproblems/TS, {:.1} ms/TS, mean err {:.1e}",
                s.steps,
                s.mean_contacts,
                s.mean_subproblems().unwrap_or(0.0),
                s.mean_solve_seconds * 1e3,
                s.mean_error
            );
        }
    }
    show(&md);
    if let Some(path) = &a.markdown {
        crate::outputs::write(path, md.as_bytes())?;
    }
    Ok(())
}

fn read_stats(path: &Path) -> anyhow::Result<Vec<(usize, f64)>> {
    // the checked reader of every input (a regular file of bounded size; coulomb::input)
    let text = coulomb::input::read_to_string(path, coulomb::input::Kind::Text)?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let Some(arr) = v.as_array() else {
        bail!("{}: expected a JSON array of step records", path.display());
    };
    Ok(arr
        .iter()
        .filter_map(|r| {
            // the record of every scene has solve_seconds (issue 52); older folders solve_ms
            let ms = match r.get("solve_seconds") {
                Some(s) => s.as_f64()? * 1e3,
                None => r.get("solve_ms")?.as_f64()?,
            };
            Some((r.get("contacts")?.as_u64()? as usize, ms))
        })
        .collect())
}

/// Fig. 8: the solve time of each step against its contacts, projected gradient and interior
/// point (simulated, or read from a [`table1`] output folder), as SVG with the data beside it
/// as CSV.
pub fn fig8(a: Fig8, bars: NewSteps<'_>) -> anyhow::Result<()> {
    if a.beads == 0 || a.beads > 100_000 || a.steps == 0 || a.steps > 100_000 {
        bail!("--beads and --steps must be in 1..=100000");
    }
    crate::outputs::check("--svg", &a.svg, &[])?;
    crate::outputs::check("the data file", &beside(&a.svg, "csv"), &[])?;
    let mut series = Vec::new();
    for inner in [InnerKind::Apgd, InnerKind::Ipm] {
        let label = inner_label(inner);
        let points = match &a.from {
            Some(dir) => read_stats(
                &dir.join(format!("box_{}_{}", a.beads, label.to_lowercase()))
                    .join("stats.json"),
            )?,
            None => {
                let params = paper_params(inner, 0.3, 1e-4, 0.01, 20);
                let (_, stats) = box_run(
                    bars,
                    a.beads,
                    a.seed,
                    params,
                    Stop::Steps(a.steps),
                    &format!("{} beads {label}", a.beads),
                    |_, _| false,
                )?;
                stats.iter().map(|s| (s.contacts, s.solve_ms)).collect()
            }
        };
        series.push((label, points));
    }
    let mut csv = String::from("solver,step,contacts,solve_ms\n");
    for (label, points) in &series {
        for (k, (c, t)) in points.iter().enumerate() {
            let _ = writeln!(csv, "{label},{k},{c},{t:.4}");
        }
    }
    let data = beside(&a.svg, "csv");
    crate::outputs::write(&data, csv.as_bytes())?;
    let xmax = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|x| x.0 as f64))
        .fold(1.0, f64::max);
    let ymax = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|x| x.1))
        .fold(1e-3, f64::max);
    let staged = crate::outputs::Staged::new(&a.svg);
    let staged_tmp = staged.path().to_path_buf();
    let root = SVGBackend::new(&staged_tmp, (800, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("Fig. 8: solve time per step, {} beads", a.beads),
            ("sans-serif", 22),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..xmax * 1.05, 0.0..ymax * 1.1)?;
    chart
        .configure_mesh()
        .x_desc("contacts")
        .y_desc("solve time per step (ms)")
        .draw()?;
    for (i, (label, points)) in series.iter().enumerate() {
        let color = if i == 0 { BLUE } else { RED };
        chart
            .draw_series(
                points
                    .iter()
                    .filter(|p| p.0 > 0)
                    .map(|p| Circle::new((p.0 as f64, p.1), 2, color.filled())),
            )?
            .label(*label)
            .legend(move |(x, y)| Circle::new((x + 10, y), 3, color.filled()));
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()?;
    root.present()?;
    staged.commit()?;
    eprintln!("wrote {} and {}", a.svg.display(), data.display());
    Ok(())
}

/// One curve of Fig. 9.
#[derive(serde::Serialize)]
struct Fig9Curve {
    mu: f64,
    step: usize,
    contacts: usize,
    /// (6.1) after each fixed-point iteration
    rule_6_1: Vec<f64>,
    /// error of docs/error.md after each fixed-point iteration
    error: Vec<f64>,
    inner_iterations: Vec<usize>,
}

/// Fig. 9: rule (6.1) and the error per fixed-point iteration at the first step with
/// `contacts` contacts, one curve per μ, as SVG with the data beside it as JSON.
pub fn fig9(a: Fig9, bars: NewSteps<'_>) -> anyhow::Result<()> {
    if a.beads == 0 || a.beads > 100_000 || a.max_outer == 0 || a.max_outer > 10_000 {
        bail!("--beads must be in 1..=100000 and --max-outer in 1..=10000");
    }
    crate::outputs::check("--svg", &a.svg, &[])?;
    crate::outputs::check("the data file", &beside(&a.svg, "json"), &[])?;
    if a.max_inner == 0 || a.max_inner > 1_000_000 {
        bail!("--max-inner must be in 1..=1000000");
    }
    if !(a.fp_tol.is_finite() && a.fp_tol > 0.0) {
        bail!("--fp-tol must be positive");
    }
    let mus: Vec<f64> = if a.mu.is_empty() {
        (1..=9).map(|k| 0.1 * k as f64).collect()
    } else {
        a.mu.clone()
    };
    if mus.iter().any(|m| !(m.is_finite() && *m >= 0.0)) {
        bail!("--mu must list nonnegative numbers");
    }
    let mut curves = Vec::new();
    for &mu in &mus {
        // tol 1e-12 on the error so that only (6.1) or the iteration cap stop the loop
        let mut params = paper_params(InnerKind::Apgd, mu, 1e-12, a.fp_tol, a.max_outer);
        params.solver.max_inner = a.max_inner;
        let mut found = None;
        let target = a.contacts;
        box_run(
            bars,
            a.beads,
            a.seed,
            params,
            Stop::Steps(a.max_steps),
            &format!("mu = {mu:.1}"),
            |sim, s| {
                if s.contacts >= target {
                    found = Some((s.step, s.contacts, sim.last_history.clone()));
                    true
                } else {
                    false
                }
            },
        )?;
        match found {
            Some((step, contacts, h)) => {
                eprintln!(
                    "mu = {mu:.1}: step {step}, {contacts} contacts, {} fixed-point iterations, final (6.1) {:.2e}, err {:.2e}",
                    h.len(),
                    h.last().map(|r| r.rule_6_1).unwrap_or(f64::NAN),
                    h.last().map(|r| r.error).unwrap_or(f64::NAN)
                );
                curves.push(Fig9Curve {
                    mu,
                    step,
                    contacts,
                    rule_6_1: h.iter().map(|r| r.rule_6_1).collect(),
                    error: h.iter().map(|r| r.error).collect(),
                    inner_iterations: h.iter().map(|r| r.inner_iterations).collect(),
                });
            }
            None => eprintln!("mu = {mu:.1}: no step reached {target} contacts"),
        }
    }
    if curves.is_empty() {
        bail!("no run reached {} contacts", a.contacts);
    }
    let data = beside(&a.svg, "json");
    crate::outputs::write(&data, crate::outputs::json(&curves, true)?.as_bytes())?;
    let staged = crate::outputs::Staged::new(&a.svg);
    let staged_tmp = staged.path().to_path_buf();
    let root = SVGBackend::new(&staged_tmp, (1200, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(600);
    let title = format!(
        "{} beads, first step with >= {} contacts",
        a.beads, a.contacts
    );
    fig9_panel(
        &left,
        &curves,
        |c| &c.rule_6_1,
        &format!("Fig. 9: (6.1), {title}"),
        "(6.1): |F(s) - s| / (n (|s| + 1))",
        a.fp_tol,
    )?;
    fig9_panel(
        &right,
        &curves,
        |c| &c.error,
        "error of docs/error.md per fixed-point iteration",
        "error (docs/error.md)",
        1e-4,
    )?;
    root.present()?;
    staged.commit()?;
    eprintln!("wrote {} and {}", a.svg.display(), data.display());
    Ok(())
}

/// One log-scale panel of Fig. 9: `get(curve)` per fixed-point iteration, one line per μ.
fn fig9_panel(
    area: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    curves: &[Fig9Curve],
    get: impl Fn(&Fig9Curve) -> &Vec<f64>,
    caption: &str,
    ydesc: &str,
    floor: f64,
) -> anyhow::Result<()> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    let all = || {
        curves
            .iter()
            .flat_map(|c| get(c).iter().copied().filter(|x| positive(*x)))
    };
    let ymin = all().fold(1.0, f64::min).min(floor) * 0.5;
    let ymax = all().fold(ymin * 10.0, f64::max) * 2.0;
    let xmax = curves
        .iter()
        .map(|c| get(c).len())
        .max()
        .unwrap_or(1)
        .max(2) as f64;
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(1.0..xmax, (ymin..ymax).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("fixed-point iteration")
        .y_desc(ydesc)
        .y_label_formatter(&|y: &f64| format!("{y:.0e}"))
        .draw()?;
    for (i, c) in curves.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = get(c)
            .iter()
            .enumerate()
            .filter(|(_, y)| positive(**y))
            .map(|(j, y)| ((j + 1) as f64, *y))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color))?
            .label(format!("mu = {:.1}", c.mu))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 2, color.filled())))?;
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()?;
    Ok(())
}

/// One point of the scaling curve: means over the timed window.
#[derive(Debug, serde::Serialize)]
struct ScalingPoint {
    beads: usize,
    /// floor of the box (m)
    box_x: f64,
    box_y: f64,
    settle_steps: usize,
    timed_steps: usize,
    contacts: f64,
    subproblems: f64,
    inner_iterations: f64,
    /// solver wall-clock per step (Delassus formation + inner iterations + checks)
    solve_ms: f64,
    /// detection + assembly per step
    assembly_ms: f64,
    /// formation of W = Hᵀ M⁻¹ H and q alone (a separate construction, same work as the
    /// solver's own)
    delassus_ms: f64,
    /// solve_ms − delassus_ms: inner iterations, (6.1) and error evaluations
    iterations_ms: f64,
    /// assembly_ms + solve_ms
    step_ms: f64,
    mean_error: f64,
    max_error: f64,
    max_penetration: f64,
}

/// The time per step against the number of beads (the paper's solver, or with `accurate`
/// body-level Gauss–Seidel to `tol` on each thread count); the table goes to `show` (and
/// `--markdown`), the data to JSON beside the SVG.
pub fn scaling(a: Scaling, bars: NewSteps<'_>, show: &mut dyn FnMut(&str)) -> anyhow::Result<()> {
    if a.accurate {
        return accurate::run(&a, bars, show);
    }
    if a.beads.is_empty() || a.beads.iter().any(|&b| b == 0 || b > 1_000_000) {
        bail!("--beads must list bead counts in 1..=1000000");
    }
    if a.window == 0 || a.window > 100_000 || a.settle > 100_000 {
        bail!("--window must be in 1..=100000 and --settle at most 100000");
    }
    crate::outputs::check("--svg", &a.svg, &[])?;
    crate::outputs::check("the data file", &beside(&a.svg, "json"), &[])?;
    if let Some(path) = &a.markdown {
        crate::outputs::check("--markdown", path, &[])?;
    }
    let inner: InnerKind = a.inner;
    let mut points = Vec::new();
    for &beads in &a.beads {
        let label = format!("{beads} beads {}", inner_label(inner));
        let params = paper_params(inner, 0.3, 1e-4, 0.01, 20);
        let settle = a.settle;
        let (_, stats) = box_run(
            bars,
            beads,
            a.seed,
            params,
            Stop::Steps(a.settle + a.window),
            &label,
            |sim, _| {
                // time the Delassus formation separately inside the window only
                sim.profile_delassus = sim.steps_done >= settle;
                false
            },
        )?;
        let timed = stats.get(a.settle..).unwrap_or(&[]);
        let n = timed.len().max(1) as f64;
        let mean = |f: &dyn Fn(&StepStats) -> f64| timed.iter().map(f).sum::<f64>() / n;
        let layout = coulomb_granular::scene::BoxLayout::for_beads(beads);
        let solve_ms = mean(&|s| s.solve_ms);
        let delassus_ms = mean(&|s| s.delassus_ms);
        let assembly_ms = mean(&|s| s.assembly_ms);
        let p = ScalingPoint {
            beads,
            box_x: layout.side_x,
            box_y: layout.side_y,
            settle_steps: a.settle,
            timed_steps: timed.len(),
            contacts: mean(&|s| s.contacts as f64),
            subproblems: mean(&|s| s.subproblems as f64),
            inner_iterations: mean(&|s| s.inner_iterations as f64),
            solve_ms,
            assembly_ms,
            delassus_ms,
            iterations_ms: (solve_ms - delassus_ms).max(0.0),
            step_ms: solve_ms + assembly_ms,
            mean_error: mean(&|s| s.error),
            max_error: timed.iter().map(|s| s.error).fold(0.0, f64::max),
            max_penetration: timed.iter().map(|s| s.max_penetration).fold(0.0, f64::max),
        };
        eprintln!(
            "{label}: {:.0} contacts, {:.2} ms solve/step ({:.2} Delassus), {:.2} ms assembly, err {:.1e}",
            p.contacts, p.solve_ms, p.delassus_ms, p.assembly_ms, p.mean_error
        );
        points.push(p);
    }
    let mut md = String::new();
    let beads_arg: Vec<String> = a.beads.iter().map(|b| b.to_string()).collect();
    let _ = writeln!(
        md,
        "Produced by `coulomb paper scaling --beads {} --settle {} --window {} --inner {} --seed {}` on a {}-thread machine. Box scene with the calibrated layout (footprint ∝ N, ≈ {} initial layers); h = 0.02 s, e = 0.2, μ = 0.3; {} with successive approximations stopped by (6.1), ε = 0.01, ≤ 20 subproblems. Means over steps {}..{} (the first {} steps are not timed).\n",
        beads_arg.join(","),
        a.settle,
        a.window,
        a.inner,
        a.seed,
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        coulomb_granular::scene::BOX_LAYERS,
        inner_label(inner),
        a.settle,
        a.settle + a.window,
        a.settle
    );
    let _ = writeln!(
        md,
        "| #beads | box (m) | #contacts | #subprob. | inner it. | solve ms/TS | of which Delassus | of which iterations | assembly ms/TS | step ms/TS | mean err | max err |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for p in &points {
        let _ = writeln!(
            md,
            "| {} | {:.2} × {:.2} | {:.0} | {:.2} | {:.0} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1e} | {:.1e} |",
            p.beads,
            p.box_x,
            p.box_y,
            p.contacts,
            p.subproblems,
            p.inner_iterations,
            p.solve_ms,
            p.delassus_ms,
            p.iterations_ms,
            p.assembly_ms,
            p.step_ms,
            p.mean_error,
            p.max_error
        );
    }
    show(&md);
    if let Some(path) = &a.markdown {
        crate::outputs::write(path, md.as_bytes())?;
    }
    let data = beside(&a.svg, "json");
    crate::outputs::write(&data, crate::outputs::json(&points, true)?.as_bytes())?;
    scaling_svg(&a.svg, &points, inner_label(inner))?;
    eprintln!("wrote {} and {}", a.svg.display(), data.display());
    Ok(())
}

/// Log–log plot of the time per step against the number of beads.
fn scaling_svg(path: &Path, points: &[ScalingPoint], label: &str) -> anyhow::Result<()> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    let xs = || points.iter().map(|p| p.beads as f64);
    let ys = || {
        points
            .iter()
            .flat_map(|p| [p.step_ms, p.solve_ms, p.assembly_ms, p.delassus_ms])
            .filter(|y| positive(*y))
    };
    let xmin = xs().fold(f64::INFINITY, f64::min).min(100.0) * 0.8;
    let xmax = xs().fold(1.0, f64::max) * 1.25;
    let ymin = ys().fold(f64::INFINITY, f64::min).min(1.0) * 0.5;
    let ymax = ys().fold(10.0, f64::max) * 2.0;
    let staged = crate::outputs::Staged::new(path);
    let staged_tmp = staged.path().to_path_buf();
    let root = SVGBackend::new(&staged_tmp, (800, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("Time per step against beads ({label}, (6.1) eps = 0.01)"),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((xmin..xmax).log_scale(), (ymin..ymax).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("beads")
        .y_desc("ms per time step")
        .draw()?;
    type Get = fn(&ScalingPoint) -> f64;
    let series: [(&str, Get, RGBColor); 4] = [
        ("step (assembly + solve)", |p| p.step_ms, BLACK),
        ("solve", |p| p.solve_ms, BLUE),
        ("of which Delassus W", |p| p.delassus_ms, GREEN),
        ("detection + assembly", |p| p.assembly_ms, RED),
    ];
    for (name, get, color) in series {
        let pts: Vec<(f64, f64)> = points
            .iter()
            .map(|p| (p.beads as f64, get(p)))
            .filter(|(_, y)| positive(*y))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
    }
    // the 10 ms aim
    chart.draw_series(LineSeries::new(
        [(xmin, 10.0), (xmax, 10.0)],
        ShapeStyle::from(&BLACK.mix(0.3)).stroke_width(1),
    ))?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use coulomb::OuterKind;

    #[test]
    fn paper_settings_are_the_former_hand_built_settings() {
        // what paper built by hand before the library had presets
        let inner = InnerKind::Apgd;
        let mut by_hand = Settings {
            tol: 1e-4,
            max_outer: 20,
            max_inner: 250,
            outer: OuterKind::FixedPoint,
            ..Settings::method(inner, OuterKind::Anderson)
        };
        by_hand.params.fixed_point_tol = Some(0.01);
        by_hand.params.inner_tol_factor = 1e-6;
        by_hand.params.newton_steps = 0;
        assert_eq!(paper_settings(inner, 1e-4, 0.01, 20), by_hand);
        let ipm = paper_settings(InnerKind::Ipm, 1e-4, 0.0, 20);
        assert_eq!(
            (ipm.max_inner, ipm.params.fixed_point_tol),
            (Settings::default().max_inner, None)
        );
    }
}
