//! `coulomb paper`: the granular experiments of §6 — Table 1 (150/300/600 beads, projected
//! gradient and interior point), Fig. 8 (solve time per step against contacts, 600 beads) and
//! Fig. 9 (convergence of the fixed point for μ = 0.1 … 0.9).

use crate::cmd::simulate::{progress, solver_settings};
use anyhow::{bail, Context};
use coulomb::solver::InnerKind;
use coulomb_granular::output::write_stats;
use coulomb_granular::run::RestMonitor;
use coulomb_granular::{Params, Scene, Simulation, StepStats, Stop, Summary};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `coulomb paper`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// which experiment
    #[command(subcommand)]
    pub which: Which,
}

/// The experiments.
#[derive(clap::Subcommand, Debug)]
pub enum Which {
    /// Table 1: #TS, #contacts/TS, #subproblems/TS, CPU time/TS beside the paper's values
    Table1(Table1Args),
    /// Fig. 8: solve time per step against the number of contacts (600 beads), SVG
    Fig8(Fig8Args),
    /// Fig. 9: (6.1) per fixed-point iteration for μ = 0.1 … 0.9 (300 beads), SVG
    Fig9(Fig9Args),
}

/// Arguments of `coulomb paper table1`.
#[derive(clap::Args, Debug)]
pub struct Table1Args {
    /// bead counts
    #[arg(long, value_delimiter = ',', default_values_t = vec![150usize, 300, 600])]
    pub beads: Vec<usize>,
    /// step cap of each run (runs stop earlier when the pile is at rest)
    #[arg(long, default_value_t = 400)]
    pub max_steps: usize,
    /// tolerance on the reported error (docs/error.md) for "converged"
    #[arg(long, default_value_t = 1e-4)]
    pub tol: f64,
    /// seed of the initial arrangement
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// folder for the per-step statistics of each run (box_<beads>_<inner>/stats.csv)
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// write the table as Markdown into this file
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// only the projected-gradient runs
    #[arg(long)]
    pub pg_only: bool,
    /// inner solver of the "PG" rows (the paper's projected gradient is `apgd`; `pgs` is
    /// projected Gauss–Seidel)
    #[arg(long, value_enum, default_value_t = crate::cmd::simulate::Inner::Apgd)]
    pub pg_inner: crate::cmd::simulate::Inner,
}

/// Arguments of `coulomb paper fig8`.
#[derive(clap::Args, Debug)]
pub struct Fig8Args {
    /// number of beads
    #[arg(long, default_value_t = 600)]
    pub beads: usize,
    /// step cap
    #[arg(long, default_value_t = 400)]
    pub max_steps: usize,
    /// read the runs' stats.json from a `table1 --output` folder instead of simulating
    #[arg(long)]
    pub from: Option<PathBuf>,
    /// SVG file
    #[arg(long, default_value = "fig8.svg")]
    pub svg: PathBuf,
    /// seed
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Arguments of `coulomb paper fig9`.
#[derive(clap::Args, Debug)]
pub struct Fig9Args {
    /// number of beads
    #[arg(long, default_value_t = 300)]
    pub beads: usize,
    /// the step studied is the first with at least this many contacts
    #[arg(long, default_value_t = 250)]
    pub contacts: usize,
    /// ε of (6.1)
    #[arg(long, default_value_t = 1e-4)]
    pub fp_tol: f64,
    /// cap on fixed-point iterations
    #[arg(long, default_value_t = 50)]
    pub max_outer: usize,
    /// step cap while looking for the step
    #[arg(long, default_value_t = 400)]
    pub max_steps: usize,
    /// SVG file
    #[arg(long, default_value = "fig9.svg")]
    pub svg: PathBuf,
    /// seed
    #[arg(long, default_value_t = 1)]
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

/// The paper's setting (§6): h = 0.02 s, e = 0.2, μ, outer rule (6.1) with ε ≤ 20 iterations;
/// projected gradient capped at 250 iterations per subproblem.
fn paper_params(inner: InnerKind, mu: f64, tol: f64, fp_tol: f64, max_outer: usize) -> Params {
    let max_inner = (inner == InnerKind::Apgd).then_some(250);
    Params {
        h: 0.02,
        restitution: 0.2,
        mu,
        solver: solver_settings(inner, tol, fp_tol, max_outer, max_inner),
        ..Params::default()
    }
}

fn inner_label(inner: InnerKind) -> &'static str {
    match inner {
        InnerKind::Apgd => "PG",
        InnerKind::Ipm => "IP",
        InnerKind::Pgs => "PGS",
        InnerKind::Faceted => "FC",
    }
}

/// Runs the box scene until rest (or `max_steps`) with a progress bar.
fn box_run(
    beads: usize,
    seed: u64,
    params: Params,
    stop: Stop,
    label: &str,
    mut until: impl FnMut(&Simulation, &StepStats) -> bool,
) -> anyhow::Result<(Summary, Vec<StepStats>)> {
    let mut sim = Simulation::new(Scene::Box.build(beads, seed), params)?;
    let pb = progress(stop.max_steps(), false);
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
        let done = until(&sim, &s);
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

fn rest_stop(max_steps: usize) -> Stop {
    Stop::UntilRest {
        speed: 0.05,
        window: 10,
        max_steps,
    }
}

/// Runs `coulomb paper`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.which {
        Which::Table1(a) => table1(a),
        Which::Fig8(a) => fig8(a),
        Which::Fig9(a) => fig9(a),
    }
}

fn table1(a: Table1Args) -> anyhow::Result<()> {
    if a.beads.is_empty() || a.beads.iter().any(|&b| b == 0 || b > 100_000) {
        bail!("--beads must list bead counts in 1..=100000");
    }
    let inners: &[InnerKind] = if a.pg_only {
        &[InnerKind::Apgd]
    } else {
        &[InnerKind::Apgd, InnerKind::Ipm]
    };
    let pg: InnerKind = a.pg_inner.into();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Table 1 reproduced: box scene (docs/granular.md), h = 0.02 s, e = 0.2, μ = 0.3, (6.1) with ε = 0.01, ≤ 20 outer iterations\n"
    );
    let _ = writeln!(
        md,
        "PG rows: inner solver `{:?}`; IP rows: `Ipm` (Clarabel). Subproblems = outer iterations; CPU time = solver wall-clock per step on a shared 2-core machine; err = error of docs/error.md.\n",
        pg
    );
    let _ = writeln!(
        md,
        "| #beads | solver | #TS | #contacts/TS | #subprob./TS | CPU time/TS (ms) | mean err | max err | converged (err ≤ {:.0e}) | max penetration (m) | paper #TS | paper #contacts/TS | paper #subprob./TS | paper CPU/TS (ms) |",
        a.tol
    );
    let _ = writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for &beads in &a.beads {
        for &inner in inners {
            let label = format!("{beads} beads {}", inner_label(inner));
            let solver = if inner == InnerKind::Apgd { pg } else { inner };
            let params = paper_params(solver, 0.3, a.tol, 0.01, 20);
            let (s, stats) = box_run(
                beads,
                a.seed,
                params,
                rest_stop(a.max_steps),
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
            let _ = writeln!(
                md,
                "| {beads} | {} | {}{} | {:.0} | {:.2} | {:.1} | {:.1e} | {:.1e} | {}/{} | {:.1e} | {pcols} |",
                inner_label(inner),
                s.steps,
                if s.at_rest { "" } else { " (cap)" },
                s.mean_contacts,
                s.mean_subproblems,
                s.mean_solve_ms,
                s.mean_error,
                s.max_error,
                s.converged_steps,
                s.steps,
                s.max_penetration
            );
            eprintln!(
                "{label}: {} TS, {:.0} contacts/TS, {:.2} subproblems/TS, {:.1} ms/TS",
                s.steps, s.mean_contacts, s.mean_subproblems, s.mean_solve_ms
            );
        }
    }
    print!("{md}");
    if let Some(path) = &a.markdown {
        std::fs::write(path, &md).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn read_stats(path: &Path) -> anyhow::Result<Vec<(usize, f64)>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let Some(arr) = v.as_array() else {
        bail!("{}: expected a JSON array of step records", path.display());
    };
    Ok(arr
        .iter()
        .filter_map(|r| {
            Some((
                r.get("contacts")?.as_u64()? as usize,
                r.get("solve_ms")?.as_f64()?,
            ))
        })
        .collect())
}

fn fig8(a: Fig8Args) -> anyhow::Result<()> {
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
                    a.beads,
                    a.seed,
                    params,
                    rest_stop(a.max_steps),
                    &format!("{} beads {label}", a.beads),
                    |_, _| false,
                )?;
                stats.iter().map(|s| (s.contacts, s.solve_ms)).collect()
            }
        };
        series.push((label, points));
    }
    let xmax = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|x| x.0 as f64))
        .fold(1.0, f64::max);
    let ymax = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|x| x.1))
        .fold(1e-3, f64::max);
    let root = SVGBackend::new(&a.svg, (800, 560)).into_drawing_area();
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
    eprintln!("wrote {}", a.svg.display());
    Ok(())
}

fn fig9(a: Fig9Args) -> anyhow::Result<()> {
    let mut curves = Vec::new();
    for k in 1..=9 {
        let mu = 0.1 * k as f64;
        let params = paper_params(InnerKind::Apgd, mu, 1e-8, a.fp_tol, a.max_outer);
        let mut history = None;
        let target = a.contacts;
        box_run(
            a.beads,
            a.seed,
            params,
            Stop::Steps(a.max_steps),
            &format!("mu = {mu:.1}"),
            |sim, s| {
                if s.contacts >= target {
                    history = Some((s.step, s.contacts, sim.last_history.clone()));
                    true
                } else {
                    false
                }
            },
        )?;
        match history {
            Some((step, contacts, h)) => {
                eprintln!(
                    "mu = {mu:.1}: step {step}, {contacts} contacts, {} fixed-point iterations, final (6.1) {:.2e}, err {:.2e}",
                    h.len(),
                    h.last().map(|r| r.rule_6_1).unwrap_or(f64::NAN),
                    h.last().map(|r| r.error).unwrap_or(f64::NAN)
                );
                curves.push((mu, h.iter().map(|r| r.rule_6_1).collect::<Vec<f64>>()));
            }
            None => eprintln!("mu = {mu:.1}: no step reached {target} contacts"),
        }
    }
    if curves.is_empty() {
        bail!("no run reached {} contacts", a.contacts);
    }
    let positive = |x: f64| x.is_finite() && x > 0.0;
    let ymin = curves
        .iter()
        .flat_map(|c| c.1.iter().copied().filter(|x| positive(*x)))
        .fold(1.0, f64::min)
        .min(a.fp_tol)
        * 0.5;
    let ymax = curves
        .iter()
        .flat_map(|c| c.1.iter().copied().filter(|x| positive(*x)))
        .fold(ymin * 10.0, f64::max)
        * 2.0;
    let xmax = curves.iter().map(|c| c.1.len()).max().unwrap_or(1).max(2) as f64;
    let root = SVGBackend::new(&a.svg, (800, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "Fig. 9: fixed-point convergence, {} beads, first step with ≥ {} contacts",
                a.beads, a.contacts
            ),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(1.0..xmax, (ymin..ymax).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("fixed-point iteration")
        .y_desc("(6.1): |F(s) - s| / (n (|s| + 1))")
        .draw()?;
    for (i, (mu, ys)) in curves.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        chart
            .draw_series(LineSeries::new(
                ys.iter()
                    .enumerate()
                    .filter(|(_, y)| positive(**y))
                    .map(|(j, y)| ((j + 1) as f64, *y)),
                color,
            ))?
            .label(format!("mu = {mu:.1}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()?;
    root.present()?;
    eprintln!("wrote {}", a.svg.display());
    Ok(())
}
