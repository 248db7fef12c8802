//! `coulomb paper`: the granular experiments of §6 — Table 1, Fig. 8, Fig. 9 and a scaling
//! curve. The engine (the runs, the tables, the figures and their data) is
//! [`coulomb_lab::paper`]; this module parses the arguments, shows the progress of each run
//! ([`crate::progress`]) and prints the tables on stdout.

use crate::values::one_of;
use coulomb::InnerKind;
use coulomb_lab::paper::{self, Layout};
use coulomb_lab::progress::Steps;
use std::path::PathBuf;

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
    /// time per step against the number of beads (box scene, footprint growing with N), SVG + JSON
    Scaling(ScalingArgs),
}

/// Arguments of `coulomb paper table1`.
#[derive(clap::Args, Debug)]
pub struct Table1Args {
    /// bead counts
    #[arg(long, value_delimiter = ',', default_values_t = vec![150usize, 300, 600], value_parser = crate::values::beads)]
    pub beads: Vec<usize>,
    /// time steps of each run (the paper's #TS is 255–352)
    #[arg(long, default_value_t = 300, value_parser = crate::values::count)]
    pub steps: usize,
    /// tolerance on the reported error (docs/error.md) for "converged"
    #[arg(long, default_value_t = 1e-4, value_parser = crate::values::tolerance)]
    pub tol: f64,
    /// ε of the outer rule (6.1) (the paper's 0.01); 0 disables it, so that only err ≤ tol or
    /// the cap ends a step
    #[arg(long, default_value_t = 0.01, value_parser = crate::values::nonnegative)]
    pub fp_tol: f64,
    /// cap on subproblems (outer iterations) per step (the paper's 20)
    #[arg(long, default_value_t = 20, value_parser = crate::values::count)]
    pub max_outer: usize,
    /// seed of the initial arrangement
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// folder for the per-step statistics of each run (`box_<beads>_<inner>/stats.csv`)
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
    #[arg(long, default_value_t = InnerKind::Apgd, value_parser = crate::method::inner())]
    pub pg_inner: InnerKind,
}

/// Arguments of `coulomb paper fig8`.
#[derive(clap::Args, Debug)]
pub struct Fig8Args {
    /// number of beads
    #[arg(long, default_value_t = 600, value_parser = crate::values::beads)]
    pub beads: usize,
    /// time steps of each run
    #[arg(long, default_value_t = 300)]
    pub steps: usize,
    /// read the runs' stats.json from a `table1 --output` folder instead of simulating
    #[arg(long)]
    pub from: Option<PathBuf>,
    /// SVG file; the data go beside it as CSV (same name, .csv)
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
    #[arg(long, default_value_t = 300, value_parser = crate::values::beads)]
    pub beads: usize,
    /// the step studied is the first with at least this many contacts
    #[arg(long, default_value_t = 250, value_parser = crate::values::count)]
    pub contacts: usize,
    /// ε of (6.1)
    #[arg(long, default_value_t = 1e-4, value_parser = crate::values::positive)]
    pub fp_tol: f64,
    /// cap on fixed-point iterations
    #[arg(long, default_value_t = 50, value_parser = crate::values::count)]
    pub max_outer: usize,
    /// step cap while looking for the step
    #[arg(long, default_value_t = 400, value_parser = crate::values::count)]
    pub max_steps: usize,
    /// cap on projected-gradient iterations per subproblem (the paper's 250)
    #[arg(long, default_value_t = 250, value_parser = crate::values::count)]
    pub max_inner: usize,
    /// friction coefficients (default 0.1, 0.2, …, 0.9)
    #[arg(long, value_delimiter = ',', value_parser = crate::values::nonnegative)]
    pub mu: Vec<f64>,
    /// SVG file; the data go beside it as JSON (same name, .json)
    #[arg(long, default_value = "fig9.svg")]
    pub svg: PathBuf,
    /// seed
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Arguments of `coulomb paper scaling`.
#[derive(clap::Args, Debug)]
pub struct ScalingArgs {
    /// bead counts
    #[arg(long, value_delimiter = ',', default_values_t = vec![150usize, 300, 600, 1200, 2500, 5000, 10000], value_parser = crate::values::beads)]
    pub beads: Vec<usize>,
    /// untimed steps first (the beads land and the contacts form)
    #[arg(long, default_value_t = 50, value_parser = crate::values::count0)]
    pub settle: usize,
    /// timed steps after the settling ones
    #[arg(long, default_value_t = 50, value_parser = crate::values::count)]
    pub window: usize,
    /// inner solver (the paper's tolerance: (6.1) with ε = 0.01, ≤ 20 subproblems)
    #[arg(long, default_value_t = InnerKind::Apgd, value_parser = crate::method::inner())]
    pub inner: InnerKind,
    /// seed
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// SVG file; the data go beside it as JSON (same name, .json)
    #[arg(long, default_value = "scaling.svg")]
    pub svg: PathBuf,
    /// also write the table as Markdown into this file
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// accurate mode: every step solved to err ≤ --tol by body-level Gauss–Seidel (the
    /// physics of `coulomb simulate`), once per --threads value; see docs/scaling.md
    #[arg(long)]
    pub accurate: bool,
    /// accurate mode: tolerance on the error of docs/error.md at every step
    #[arg(long, default_value_t = 1e-4, value_parser = crate::values::tolerance)]
    pub tol: f64,
    /// accurate mode: thread counts to run each size with (default: 1 and all cores)
    #[arg(long, value_delimiter = ',', value_parser = crate::values::threads)]
    pub threads: Vec<usize>,
    /// accurate mode: cap on Gauss–Seidel sweeps per step
    #[arg(long, default_value_t = 20_000, value_parser = crate::values::count)]
    pub max_sweeps: usize,
    /// accurate mode: box layout — `spread` (default: the calibrated floor, the partial top
    /// layer spread over it at random) or `calibrated` (the partial top layer fills the
    /// first rows, as in the paper runs); see docs/scaling.md, "Scene sizing"
    #[arg(long, default_value = "spread", value_parser = one_of(&Layout::ALL, Layout::as_str, Some(Layout::about)))]
    pub layout: Layout,
    /// accurate mode: over-relaxation ω ∈ [1, 2) of the Gauss–Seidel updates
    #[arg(long, default_value_t = 1.5, value_parser = crate::values::relaxation)]
    pub relaxation: f64,
}

/// The progress report of a run of `len` steps: [`crate::progress::bar`].
fn bar(len: usize) -> Box<dyn Steps> {
    Box::new(crate::progress::bar(len, false))
}

/// Prints a table on stdout.
fn print(md: &str) {
    print!("{md}");
}

/// Runs `coulomb paper`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.which {
        Which::Table1(a) => paper::table1(
            paper::Table1 {
                beads: a.beads,
                steps: a.steps,
                tol: a.tol,
                fp_tol: a.fp_tol,
                max_outer: a.max_outer,
                seed: a.seed,
                output: a.output,
                markdown: a.markdown,
                pg_only: a.pg_only,
                pg_inner: a.pg_inner,
            },
            &bar,
            &mut print,
        ),
        Which::Fig8(a) => paper::fig8(
            paper::Fig8 {
                beads: a.beads,
                steps: a.steps,
                from: a.from,
                svg: a.svg,
                seed: a.seed,
            },
            &bar,
        ),
        Which::Fig9(a) => paper::fig9(
            paper::Fig9 {
                beads: a.beads,
                contacts: a.contacts,
                fp_tol: a.fp_tol,
                max_outer: a.max_outer,
                max_steps: a.max_steps,
                max_inner: a.max_inner,
                mu: a.mu,
                svg: a.svg,
                seed: a.seed,
            },
            &bar,
        ),
        Which::Scaling(a) => paper::scaling(
            paper::Scaling {
                beads: a.beads,
                settle: a.settle,
                window: a.window,
                inner: a.inner,
                seed: a.seed,
                svg: a.svg,
                markdown: a.markdown,
                accurate: a.accurate,
                tol: a.tol,
                threads: a.threads,
                max_sweeps: a.max_sweeps,
                layout: a.layout,
                relaxation: a.relaxation,
            },
            &bar,
            &mut print,
        ),
    }
}
