//! Issue #54 probe: does an interior point on the paper's convex inner problem (3.15) move
//! the load through a deep granular heap so that projected Gauss–Seidel (pgs + fused) then
//! finishes in fewer sweeps? For each variant, cold, on the global problem of an FCLIB file
//! (e.g. one dumped by `coulomb simulate box --dump-fclib`):
//!
//! - `pgs`: `Settings::method(Pgs, Fused)` from r = 0 (the baseline);
//! - `ipmK`: K fixed-point iterations s ← μ‖u_T‖ (3.19) whose inner problem (3.15) (with
//!   shift w + E s) is solved by Clarabel (`inner::ipm::solve_primal_polished`, tolerance
//!   IPM_TOL, no polish), from s = 0; then pgs + fused from the last r;
//! - `ipmK+newton`: the same, then the semismooth Newton end game on (3.9)
//!   (`newton::polish`, at most NEWTON_STEPS steps), then pgs + fused from there;
//! - `gsN:ipmK`: N sweeps of pgs + fused from r = 0 first, s = ‖u_T‖ (3.19) from that point, then
//!   `ipmK` from that s (the interior point then solves (3.15) with a nearly right s).
//!
//! Every final verdict is the solve's (`Solver::solve`, on the problem as stored); the
//! errors printed for the intermediate points are the error of docs/error.md of the
//! Delassus form (u = W r + q), for information. Prints one JSON line per variant.
//!
//! `cargo run -p coulomb-lab --example deep_hybrid -- FILE.hdf5 [TOL] [VARIANTS] [IPM_TOL] [NEWTON_STEPS]`
//! with VARIANTS a comma list such as `pgs,ipm1,ipm2,ipm1+newton` (the default).

use coulomb::deadline::Deadline;
use coulomb::fixed_point::{evaluate_f, shifted};
use coulomb::inner::ipm::solve_primal_polished;
use coulomb::inner::InnerLimits;
use coulomb::law::{error_measure, norm};
use coulomb::problem::Problem;
use coulomb::{Guess, InnerKind, OuterKind, Settings, Solver};
use std::path::Path;
use std::time::{Duration, Instant};

/// CPU seconds of this process so far (utime + stime of /proc/self/stat, 100 ticks a second;
/// NaN where it cannot be read): on a shared machine a better measure of work than the wall
/// clock, every phase here but the Delassus setup running on one thread.
fn cpu_s() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // the fields after the command name (in parentheses, which may hold spaces)
    let Some((_, rest)) = stat.rsplit_once(')') else {
        return f64::NAN;
    };
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let tick = |k: usize| fields.get(k).and_then(|x| x.parse::<f64>().ok());
    match (tick(11), tick(12)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let file = args.get(1).ok_or_else(|| {
        anyhow::anyhow!("usage: deep_hybrid FILE [TOL] [VARIANTS] [IPM_TOL] [NEWTON_STEPS]")
    })?;
    let tol: f64 = args.get(2).map_or(Ok(1e-4), |s| s.parse())?;
    let variants = args
        .get(3)
        .cloned()
        .unwrap_or_else(|| "pgs,ipm1,ipm2,ipm1+newton".to_string());
    let ipm_tol: f64 = args.get(4).map_or(Ok(1e-6), |s| s.parse())?;
    let newton_steps: usize = args.get(5).map_or(Ok(20), |s| s.parse())?;
    let problem = coulomb::fclib::read(Path::new(file))?.problem;
    let Problem::Global(g) = &problem else {
        anyhow::bail!("{file}: a global problem is needed (the inner problem (3.15) is on M, H)");
    };
    let mut settings = Settings::method(InnerKind::Pgs, OuterKind::Fused);
    settings.tol = tol;
    settings.time_limit = Some(Duration::from_secs(600));
    let t = Instant::now();
    let mut solver = Solver::new(&problem, settings)?;
    let setup_s = t.elapsed().as_secs_f64();
    let local = solver.local().clone();
    let q_norm = norm(&local.q);
    let err_of =
        |r: &[f64]| error_measure(local.dim, &local.mu, r, &local.velocity(r), q_norm).error;
    for variant in variants.split(',') {
        let (pre_sweeps, rest) = match variant.split_once(':') {
            Some((gs, rest)) => (
                gs.strip_prefix("gs")
                    .ok_or_else(|| anyhow::anyhow!("unknown variant {variant}"))?
                    .parse::<usize>()?,
                rest,
            ),
            None => (0, variant),
        };
        let (ipm_outer, newton) = match rest {
            "pgs" => (0, false),
            v => {
                let (k, newton) = match v.strip_suffix("+newton") {
                    Some(k) => (k, true),
                    None => (v, false),
                };
                let k: usize = k
                    .strip_prefix("ipm")
                    .ok_or_else(|| anyhow::anyhow!("unknown variant {v}"))?
                    .parse()?;
                (k, newton)
            }
        };
        let t0 = Instant::now();
        let c0 = cpu_s();
        let m = local.mu.len() * local.dim;
        let mut r = vec![0.0; m];
        let mut v: Option<Vec<f64>> = None;
        let mut s = vec![0.0; local.mu.len()];
        let mut pre = None;
        if pre_sweeps > 0 {
            let mut first = Settings::method(InnerKind::Pgs, OuterKind::Fused);
            first.tol = tol;
            first.max_outer = 1;
            first.max_inner = pre_sweeps;
            // the sweeps alone: a fused solve stopped by its cap below 1e-3 would else try
            // the Newton end game (a sparse LU of W) before returning
            first.params.newton_steps = 0;
            let main = solver.settings().clone();
            solver.set_settings(first)?;
            let sol = solver.solve(None);
            solver.set_settings(main)?;
            let sol = sol?;
            r = sol.r;
            v = sol.v;
            s = evaluate_f(local.dim, &local.velocity(&r));
            pre = Some((sol.inner_iterations, err_of(&r)));
        }
        let mut ipm_iterations = Vec::new();
        let mut ipm_errors = Vec::new();
        let mut shift = Vec::new();
        for _ in 0..ipm_outer {
            shifted(local.dim, &g.w, &g.mu, &s, &mut shift);
            let limits = InnerLimits {
                tol: ipm_tol,
                max_iterations: 200,
                deadline: Deadline::NEVER,
            };
            let out = solve_primal_polished(g, &shift, &limits, 0);
            ipm_iterations.push(out.report.iterations);
            if out.r.len() != m {
                anyhow::bail!("{file}: the interior point failed: {:?}", out.report);
            }
            r = out.r;
            v = Some(out.v);
            ipm_errors.push(err_of(&r));
            s = evaluate_f(local.dim, &local.velocity(&r));
        }
        let ipm_s = t0.elapsed().as_secs_f64();
        let c1 = cpu_s();
        let mut newton_report = None;
        if newton {
            let target = tol * 0.5 * q_norm.max(norm(&r));
            let rep =
                coulomb::newton::polish(&local, &mut r, target, newton_steps, Deadline::NEVER);
            newton_report = Some((rep.steps, format!("{:?}", rep.status), err_of(&r)));
            v = None;
        }
        let newton_s = t0.elapsed().as_secs_f64() - ipm_s;
        let guess = (ipm_outer + pre_sweeps > 0).then(|| Guess {
            r: r.clone(),
            v: v.clone(),
        });
        let t1 = Instant::now();
        let c2 = cpu_s();
        let sol = solver.solve(guess.as_ref())?;
        let pgs_s = t1.elapsed().as_secs_f64();
        let c3 = cpu_s();
        println!(
            "{}",
            serde_json::json!({
                "file": file,
                "variant": variant,
                "tol": tol,
                "ipm_tol": ipm_tol,
                "setup_s": setup_s,
                "pre_sweeps_error": pre,
                "ipm_iterations": ipm_iterations,
                "ipm_errors": ipm_errors,
                "ipm_s": ipm_s,
                "newton": newton_report,
                "newton_s": newton_s,
                "sweeps": sol.inner_iterations,
                "pgs_s": pgs_s,
                "total_s": ipm_s + newton_s + pgs_s,
                "cpu_before_pgs_s": c1 - c0,
                "cpu_newton_s": c2 - c1,
                "cpu_pgs_s": c3 - c2,
                "cpu_total_s": c3 - c0,
                "status": sol.status.as_str(),
                "converged": sol.converged(),
                "error": sol.error,
                "balance": sol.balance_residual,
            })
        );
    }
    Ok(())
}
