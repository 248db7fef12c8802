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
    #[arg(long, default_value_t = 1e-8, value_parser = crate::values::tolerance)]
    pub tol: f64,
    /// Also list the K contacts with the largest natural-map residual ‖eᵢ‖ (where the error
    /// lives), with their r and recomputed u
    #[arg(long, value_name = "K", default_value_t = 0)]
    pub worst: usize,
    /// Print one JSON object
    #[arg(long)]
    pub json: bool,
}

/// One contact of `coulomb error --worst K`.
#[derive(Debug, Serialize)]
pub struct ContactReport {
    /// the contact's index i (its unknowns are d i … d i + d − 1)
    pub contact: usize,
    /// ‖eᵢ‖ / scale: its part of the error (error² = Σ of their squares)
    pub error: f64,
    /// ‖eᵢ‖² / Σⱼ‖eⱼ‖² (0 when the sum is 0, NaN when it is not finite)
    pub share: f64,
    /// μᵢ
    pub mu: f64,
    /// r_N
    pub r_n: f64,
    /// ‖r_T‖
    pub r_t: f64,
    /// u_N (recomputed from the problem data)
    pub u_n: f64,
    /// ‖u_T‖ (recomputed)
    pub u_t: f64,
}

/// The `k` contacts of largest ‖eᵢ‖ = ‖rᵢ − P_{K_μ}(rᵢ − ũᵢ)‖ (docs/error.md), largest first.
fn worst_contacts(
    problem: &coulomb::Problem,
    r: &[f64],
    u: &[f64],
    scale: f64,
    k: usize,
) -> Vec<ContactReport> {
    if k == 0 {
        return Vec::new();
    }
    let d = problem.dim();
    let mu = problem.mu();
    let sq: Vec<f64> = (0..problem.contacts())
        .map(|i| {
            coulomb::law::contact_residual_sq(mu[i], &u[d * i..d * (i + 1)], &r[d * i..d * (i + 1)])
        })
        .collect();
    let total: f64 = sq.iter().sum();
    let mut order: Vec<usize> = (0..sq.len()).collect();
    order.sort_by(|&a, &b| sq[b].total_cmp(&sq[a]));
    let tangent = |x: &[f64]| x[1..].iter().map(|t| t * t).sum::<f64>().sqrt();
    order
        .into_iter()
        .take(k)
        .map(|i| {
            let (ri, ui) = (&r[d * i..d * (i + 1)], &u[d * i..d * (i + 1)]);
            ContactReport {
                contact: i,
                error: if scale > f64::EPSILON {
                    sq[i].sqrt() / scale
                } else {
                    sq[i].sqrt()
                },
                share: if total == 0.0 { 0.0 } else { sq[i] / total },
                mu: mu[i],
                r_n: ri[0],
                r_t: tangent(ri),
                u_n: ui[0],
                u_t: tangent(ui),
            }
        })
        .collect()
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
    /// ‖M v − H r − G λ − f‖ / max(1, ‖f‖) (null for a local problem)
    pub balance_residual: Option<f64>,
    /// ‖Gᵀ v + b‖ / max(1, ‖b‖) (global problems with equality constraints only; absent
    /// otherwise)
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equality_residual: Option<f64>,
    /// the tolerance of `converged`
    pub tol: f64,
    /// err ≤ tol (and balance residual ≤ tol, and equality residual ≤ tol)
    pub converged: bool,
    /// relative asymmetry of W (local) or M (global) as stored (the error is always that of
    /// the stored problem)
    pub asymmetry: f64,
    /// with `--worst K`: the K contacts of largest residual, largest first
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub worst_contacts: Vec<ContactReport>,
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
    let (u, eval) = fclib::evaluate_with_velocity(&file.problem, &solution).with_context(|| {
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
        equality_residual: eval.equality_residual,
        tol: args.tol,
        converged: eval.converged(args.tol),
        asymmetry: file.problem.asymmetry(),
        worst_contacts: worst_contacts(
            &file.problem,
            &solution.r,
            &u,
            eval.measure.scale,
            args.worst,
        ),
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
        if let Some(e) = report.equality_residual {
            println!("equality residual {e:.3e}");
        }
        println!(
            "solution at {:.0e}: {}",
            report.tol,
            if report.converged { "yes" } else { "no" }
        );
        if !report.worst_contacts.is_empty() {
            println!("worst contacts    ‖eᵢ‖/scale  share    μ      r_N         ‖r_T‖       u_N         ‖u_T‖");
            for c in &report.worst_contacts {
                println!(
                    "  {:>6}          {:.3e}   {:>5.1}%  {:<5}  {:>10.3e}  {:>10.3e}  {:>10.3e}  {:>10.3e}",
                    c.contact,
                    c.error,
                    100.0 * c.share,
                    c.mu,
                    c.r_n,
                    c.r_t,
                    c.u_n,
                    c.u_t
                );
            }
        }
    }
    Ok(if report.converged {
        Outcome::Success
    } else {
        Outcome::No
    })
}
