//! `coulomb error`: the error of docs/error.md of a stored or given solution.

use crate::exit::Outcome;
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
    #[arg(long, default_value_t = 1e-8, value_parser = crate::values::positive)]
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

/// Runs `coulomb error`: exit status 0 when the solution is one at `--tol` ("yes"), 1 when
/// it is not ("no"), 2 when it cannot be evaluated.
pub fn run(args: Args) -> anyhow::Result<Outcome> {
    let (file, mut dropped) = crate::read::read_relaxed_dropped(&args.file)?;
    let (solution, source) = match &args.solution {
        Some(path) => {
            for e in dropped {
                eprintln!("warning: {e}; going on without it");
            }
            let s = fclib::read_solution(path)?
                .with_context(|| format!("{}: no /solution group", path.display()))?;
            (s, path.display().to_string())
        }
        None if file.solution.is_none()
            && dropped
                .iter()
                .any(|e| e.object_path().is_some_and(|p| p.starts_with("/solution"))) =>
        {
            // the group is there but unreadable: that is the answer
            let i = dropped
                .iter()
                .position(|e| e.object_path().is_some_and(|p| p.starts_with("/solution")))
                .unwrap_or(0);
            return Err(dropped.swap_remove(i).into());
        }
        None => {
            for e in dropped {
                eprintln!("warning: {e}; going on without it");
            }
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
        println!("{}", crate::outputs::json(&report, true)?);
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
    Ok(if report.converged {
        Outcome::Success
    } else {
        Outcome::No
    })
}
