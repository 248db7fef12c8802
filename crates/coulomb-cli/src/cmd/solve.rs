//! `coulomb solve`: solve an FCLIB problem with the convex fixed-point solver and report the
//! error of docs/error.md recomputed from the returned r (and v).

use crate::exit::Outcome;
use anyhow::Context;
use coulomb::fclib::{FclibFile, StoredSolution};
use coulomb::solver::{self, InnerKind, OuterKind, Settings};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `coulomb solve`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// FCLIB problem file (.hdf5)
    pub file: PathBuf,
    /// Inner solver (default: the library's default settings)
    #[arg(long, value_parser = crate::method::inner())]
    pub inner: Option<InnerKind>,
    /// Outer iteration (default: the library's default settings)
    #[arg(long, value_parser = crate::method::outer())]
    pub outer: Option<OuterKind>,
    /// Tolerance on the error of docs/error.md (and the balance residual)
    #[arg(long, default_value_t = 1e-8, value_parser = crate::values::tolerance)]
    pub tol: f64,
    /// Cap on outer iterations
    #[arg(long, value_name = "N", value_parser = crate::values::count)]
    pub max_outer: Option<usize>,
    /// Newton steps of the interior-point try on Coulomb's law (coulomb::barrier) before
    /// the main method of a cold solve; 0 turns it off (default: the library's)
    #[arg(long, value_name = "N", value_parser = crate::values::count0)]
    pub barrier_steps: Option<usize>,
    /// Wall-clock limit in seconds (at most one week)
    #[arg(long, value_name = "SECONDS", value_parser = crate::values::time_limit)]
    pub time_limit: Option<f64>,
    /// Write the problem plus /solution {r, u, v} to this FCLIB file (replaced atomically;
    /// never the input file)
    #[arg(long, value_name = "OUT.hdf5")]
    pub output: Option<PathBuf>,
    /// Print one JSON object
    #[arg(long)]
    pub json: bool,
    /// Also print what the solver learnt of the problem (its structure) and the steps it
    /// runs (its plan: method, budget in work, starting point of each step); `--json`
    /// always carries both
    #[arg(long)]
    pub explain: bool,
}

/// What `coulomb solve --json` prints.
#[derive(Debug, Serialize)]
pub struct Report {
    /// the problem file
    pub file: String,
    /// how the solve ended
    pub status: solver::Status,
    /// err ≤ tol (and balance residual ≤ tol, and equality residual ≤ tol)
    pub converged: bool,
    /// the error of docs/error.md, recomputed from the returned r (and v)
    pub error: f64,
    /// ‖M v − H r − G λ − f‖ / max(1, ‖f‖) (global problems)
    pub balance_residual: Option<f64>,
    /// ‖Gᵀ v + b‖ / max(1, ‖b‖) (global problems with equality constraints only; absent
    /// otherwise)
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equality_residual: Option<f64>,
    /// outer iterations
    pub outer_iterations: usize,
    /// inner iterations, summed
    pub inner_iterations: usize,
    /// solve time in seconds, file reading excluded
    pub solve_time_s: f64,
    /// existence check on failure (filled by the existence module when available)
    #[serde(skip_serializing_if = "Option::is_none")]
    pub existence: Option<serde_json::Value>,
    /// relative asymmetry of W (local) or M (global) as stored; the problem solved, and the
    /// error reported, are always those of the stored data
    pub asymmetry: f64,
    /// what the solver learnt of the problem ([`coulomb::plan::Structure`])
    pub structure: coulomb::plan::Structure,
    /// the steps of the solve ([`coulomb::plan::Plan`])
    pub plan: coulomb::plan::Plan,
}

/// Settings from the arguments, on top of the library defaults.
pub fn settings(args: &Args) -> anyhow::Result<Settings> {
    let mut s = Settings {
        tol: args.tol,
        ..Settings::default()
    };
    if let Some(inner) = args.inner {
        s.inner = inner;
    }
    if let Some(outer) = args.outer {
        s.outer = outer;
    }
    if args.inner.is_some() || args.outer.is_some() {
        // an explicit method runs alone
        s.fallback = None;
        s.params.warmup_sweeps = 0;
        s.params.barrier_steps = 0;
    }
    if let Some(n) = args.max_outer {
        s.max_outer = n;
    }
    if let Some(n) = args.barrier_steps {
        s.params.barrier_steps = n;
    }
    if let Some(t) = args.time_limit {
        let checked = crate::values::time_limit(&t.to_string())
            .ok()
            .and_then(|t| Duration::try_from_secs_f64(t).ok());
        let Some(d) = checked else {
            anyhow::bail!(
                "--time-limit {t}: must be a positive number of seconds up to {}",
                crate::values::MAX_TIME_LIMIT_S
            );
        };
        s.time_limit = Some(d);
    }
    Ok(s)
}

/// Runs `coulomb solve`: exit status 0 when converged, 1 otherwise (see `crate::exit`);
/// 130/143 when SIGINT/SIGTERM stopped it ([`crate::interrupt`]: the solver stops at its next
/// time-limit check with status `interrupted` and its best iterate, whose error is reported
/// as always; the existence check is skipped).
pub fn run(args: Args) -> anyhow::Result<Outcome> {
    crate::interrupt::install().context("installing the SIGINT/SIGTERM handlers")?;
    let mut settings = settings(&args)?;
    settings.cancel = crate::interrupt::cancel();
    if let Some(out) = &args.output {
        crate::outputs::check("--output", out, &[&args.file])?;
    }
    let file = crate::read::read_relaxed(&args.file)?;
    let context = || format!("solving {}", args.file.display());
    let mut solver = solver::Solver::new(&file.problem, settings.clone()).with_context(context)?;
    let (structure, plan) = (solver.structure().clone(), solver.plan(None));
    let sol = solver.solve(None).with_context(context)?;
    if let Some(out) = &args.output {
        let mut written = FclibFile::new(file.problem.clone());
        written.info = file.info.clone();
        written.solution = Some(StoredSolution {
            v: sol.v.clone(),
            u: Some(sol.u.clone()),
            r: sol.r.clone(),
            l: sol.l.clone(),
        });
        crate::outputs::write_fclib(out, &written)?;
    }
    // a solve that did not converge: say whether a solution can exist at all (§4–5), within
    // the solve's time limit again (30 s without one)
    let interrupted = crate::interrupt::received();
    let existence = if sol.converged() {
        None
    } else if let Some(signal) = interrupted {
        Some(serde_json::json!({
            "conclusion": "unknown",
            "skipped": format!("interrupted by {}", signal.name()),
        }))
    } else {
        let budget = settings.time_limit.unwrap_or(Duration::from_secs(30));
        let check = coulomb::existence::CheckSettings {
            time_limit: budget,
            ..Default::default()
        };
        let problem = file.problem.clone();
        let checked =
            crate::budget::within(budget, move || coulomb::existence::check(&problem, &check));
        let stopped = crate::interrupt::received();
        Some(match checked {
            Some(Ok(ex)) => crate::existence_json::to_json(&args.file, &ex, false),
            Some(Err(e)) => serde_json::json!({ "error": e.to_string() }),
            None if stopped.is_some() => serde_json::json!({
                "conclusion": "unknown",
                "skipped": format!(
                    "interrupted by {}",
                    stopped.map_or("a signal", |s| s.name())
                ),
            }),
            None => serde_json::json!({
                "conclusion": "unknown",
                "skipped": format!(
                    "the existence check did not finish within {:.3} s (the solve's time limit)",
                    budget.as_secs_f64()
                ),
            }),
        })
    };
    let report = Report {
        file: args.file.display().to_string(),
        status: sol.status,
        converged: sol.converged(),
        error: sol.error,
        balance_residual: sol.balance_residual,
        equality_residual: sol.equality_residual,
        outer_iterations: sol.outer_iterations,
        inner_iterations: sol.inner_iterations,
        solve_time_s: sol.solve_time.as_secs_f64(),
        existence,
        asymmetry: file.problem.asymmetry(),
        structure,
        plan,
    };
    if args.json {
        println!("{}", crate::outputs::json(&report, false)?);
    } else {
        println!("file              {}", report.file);
        if report.asymmetry > coulomb::problem::SYMMETRY_TOLERANCE {
            println!(
                "note              {} not symmetric (relative asymmetry {:.2e}); solved as stored",
                if file.problem.kind() == "local" {
                    "W"
                } else {
                    "M"
                },
                report.asymmetry
            );
        }
        println!("status            {:?}", report.status);
        println!("error             {:.3e}", report.error);
        if let Some(b) = report.balance_residual {
            println!("balance residual  {b:.3e}");
        }
        if let Some(e) = report.equality_residual {
            println!("equality residual {e:.3e}");
        }
        println!("outer iterations  {}", report.outer_iterations);
        println!("inner iterations  {}", report.inner_iterations);
        println!("solve time        {:.3} ms", 1e3 * report.solve_time_s);
        if args.explain {
            print!("structure         {}", report.structure);
            println!("plan");
            for line in report.plan.to_string().lines() {
                println!("  {line}");
            }
        }
        if let Some(ex) = &report.existence {
            let conclusion = ex
                .get("conclusion")
                .and_then(|c| c.as_str())
                .unwrap_or("unknown");
            let verdict = match conclusion {
                "none" => "no solution can exist: the model, not the solver, is at fault",
                "exists" => "a solution exists: the solver missed it",
                _ => "the existence criteria are inconclusive",
            };
            match ex.get("skipped").and_then(|m| m.as_str()) {
                Some(why) => println!("existence         not checked: {why}"),
                None => println!("existence         {conclusion} ({verdict})"),
            }
            if let Some(by) = ex.get("by").and_then(|b| b.as_str()) {
                println!("                  by criterion ({by})");
            }
        }
    }
    // a signal during the existence check counts too
    if let Some(signal) = interrupted.or_else(crate::interrupt::received) {
        eprintln!(
            "interrupted by {}: status {}, error {:.3e}{}",
            signal.name(),
            report.status,
            report.error,
            match &args.output {
                Some(out) => format!(
                    "; {} holds the iterate the solve had reached",
                    out.display()
                ),
                None => String::new(),
            }
        );
        return Ok(Outcome::Interrupted(signal));
    }
    Ok(if report.converged {
        Outcome::Success
    } else {
        Outcome::No
    })
}
