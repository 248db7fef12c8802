//! `coulomb error`: the error of docs/error.md of a stored or given solution.

use anyhow::Context;
use coulomb::fclib;
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `coulomb error`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// FCLIB problem file (.hdf5)
    pub file: PathBuf,
    /// Take the solution from /solution of this file instead of FILE's own
    #[arg(long, value_name = "SOL.hdf5")]
    pub solution: Option<PathBuf>,
    /// Tolerance at which the result counts as a solution (err ≤ tol and, for a global
    /// problem, balance residual ≤ tol)
    #[arg(long, default_value_t = 1e-8)]
    pub tol: f64,
    /// Print one JSON object
    #[arg(long)]
    pub json: bool,
}

/// What `coulomb error --json` prints.
#[derive(Debug, Serialize)]
pub struct Report {
    /// the problem file
    pub file: String,
    /// where the solution came from
    pub solution_file: String,
    /// "local" or "global"
    pub kind: &'static str,
    /// the error of docs/error.md (u recomputed from r, or from v for a global problem)
    pub error: f64,
    /// sqrt(Σ‖eᵢ‖²), before scaling
    pub absolute_error: f64,
    /// max(‖q‖, ‖r‖, ‖u‖)
    pub scale: f64,
    /// ‖M v − H r − f‖ / max(1, ‖f‖) (null for a local problem)
    pub balance_residual: Option<f64>,
    /// the tolerance of `converged`
    pub tol: f64,
    /// err ≤ tol (and balance residual ≤ tol)
    pub converged: bool,
    /// relative asymmetry of W (local) or M (global) as stored (the error is always that of
    /// the stored problem)
    pub asymmetry: f64,
}

/// Runs `coulomb error`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let file = coulomb::fclib::read(&args.file)?;
    let (solution, source) = match &args.solution {
        Some(path) => {
            let s = fclib::read_solution(path)?
                .with_context(|| format!("{}: no /solution group", path.display()))?;
            (s, path.display().to_string())
        }
        None => {
            let s = file.solution.clone().with_context(|| {
                format!(
                    "{}: no /solution group; give one with --solution SOL.hdf5",
                    args.file.display()
                )
            })?;
            (s, args.file.display().to_string())
        }
    };
    let eval = fclib::evaluate(&file.problem, &solution).with_context(|| {
        format!(
            "solution from {source} does not fit {}",
            args.file.display()
        )
    })?;
    let report = Report {
        file: args.file.display().to_string(),
        solution_file: source,
        kind: file.problem.kind(),
        error: eval.measure.error,
        absolute_error: eval.measure.absolute,
        scale: eval.measure.scale,
        balance_residual: eval.balance_residual,
        tol: args.tol,
        converged: eval.converged(args.tol),
        asymmetry: file.problem.asymmetry(),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("file              {} ({})", report.file, report.kind);
        println!("solution from     {}", report.solution_file);
        println!(
            "error             {:.3e}   (absolute {:.3e}, scale {:.3e})",
            report.error, report.absolute_error, report.scale
        );
        if let Some(b) = report.balance_residual {
            println!("balance residual  {b:.3e}");
        }
        println!(
            "solution at {:.0e}: {}",
            report.tol,
            if report.converged { "yes" } else { "no" }
        );
    }
    Ok(())
}
