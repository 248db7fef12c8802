//! `coulomb validate`: the physics validation suite (docs/validation.md) at the default
//! settings of `coulomb simulate` — each check states the value expected from mechanics, the
//! measured one and its tolerance; exit status 1 when a check fails.

use anyhow::{bail, Context};
use clap::Parser;
use coulomb_granular::validation::{self, Check};
use coulomb_granular::Params;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `coulomb validate`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// write the report (Markdown) to this file, e.g. docs/validation.md
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// skip the long checks (settled bed, drum, column collapse, 600-bead box at rest, the
    /// Janssen, Beverloo and angle-of-repose laws; shorter energy runs)
    #[arg(long)]
    pub quick: bool,
    /// print one JSON array of checks
    #[arg(long)]
    pub json: bool,
}

#[derive(Parser)]
struct Defaults {
    #[command(flatten)]
    simulate: crate::sim_args::Args,
}

/// The parameters `coulomb simulate box` uses when given no option.
fn simulate_defaults() -> anyhow::Result<Params> {
    let d = Defaults::try_parse_from(["simulate", "box"]).context("default simulate options")?;
    Ok(d.simulate.params())
}

/// Runs `coulomb validate`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(path) = &args.markdown {
        // a device, FIFO, folder or dangling link is refused before the suite runs
        crate::outputs::check("--markdown", path, &[])?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            if !dir.is_dir() {
                bail!(
                    "cannot write {}: no folder {}",
                    path.display(),
                    dir.display()
                );
            }
        }
    }
    let p = simulate_defaults()?;
    let mut checks: Vec<(String, Check)> = Vec::new();
    let section = |s: &str, c: Check, checks: &mut Vec<(String, Check)>| {
        if !args.json {
            eprintln!(
                "{} {}: expected {:.6}, measured {:.6}",
                if c.pass() { "pass" } else { "FAIL" },
                c.name,
                c.expected,
                c.measured
            );
        }
        checks.push((s.to_string(), c));
    };
    for deg in [10.0, 30.0, 45.0] {
        for mu in [0.1, 0.3, 0.8] {
            for rolling in [false, true] {
                let c = validation::incline(deg, mu, rolling, 1.0, &p)?;
                section("Incline", c, &mut checks);
            }
        }
    }
    for e in [0.0, 0.5, 0.8] {
        let (a, b) = validation::drop(1.0, e, &p)?;
        section("Drop", a, &mut checks);
        section("Drop", b, &mut checks);
    }
    let steps = if args.quick { 200 } else { 1000 };
    for (e, mu) in [(1.0, 0.0), (0.2, 0.3), (0.5, 0.8)] {
        let b = validation::box_energy(150, e, mu, steps, &p)?;
        let mut c = Check {
            name: format!(
                "box, 150 beads, e = {e}, μ = {mu}, {steps} steps: largest one-step increase of E − W_p, / E₀"
            ),
            expected: 0.0,
            measured: b.worst_increase.max(0.0) / b.e0,
            tolerance: p.solver.tol,
            unit: String::new(),
            not_converged: b.not_converged,
        };
        section("Energy", c.clone(), &mut checks);
        if e == 1.0 && mu == 0.0 {
            c.name = format!(
                "box, 150 beads, e = 1, μ = 0, {steps} steps: |E_n − E₀ − ΣW_p| / E₀ (E₀ = {:.3} J, ΣW_p = {:.3} J)",
                b.e0, b.projection_work
            );
            c.measured = (b.end - b.e0 - b.projection_work).abs() / b.e0;
            c.tolerance = 50.0 * p.solver.tol;
            section("Energy", c, &mut checks);
        }
    }
    let (a, b) = validation::cylinder_roll(10.0, 6.0, &p)?;
    section("Cylinder", a, &mut checks);
    section("Cylinder", b, &mut checks);
    // rolling resistance (--rolling-friction): the defaults with μ_r set
    let with_mu_r = |mu_r: f64| Params {
        rolling_friction: mu_r,
        ..p.clone()
    };
    for (deg, mu) in [(5.0, 0.5), (20.0, 0.5), (30.0, 0.1)] {
        let c = validation::incline_rolling_resistance(deg, mu, 1.0, &with_mu_r(0.1))?;
        section("Rolling resistance", c, &mut checks);
    }
    for mu_r in [0.05, 0.1] {
        let c = validation::rolling_deceleration(1.0, 1.0, &with_mu_r(mu_r))?;
        section("Rolling resistance", c, &mut checks);
    }
    let (beads, rsteps) = if args.quick { (60, 100) } else { (150, steps) };
    for (e, mu) in [(1.0, 0.0), (0.2, 0.3), (0.5, 0.8)] {
        let b = validation::box_energy(beads, e, mu, rsteps, &with_mu_r(0.1))?;
        let c = Check {
            name: format!(
                "box, {beads} beads, μ_r = 0.1, e = {e}, μ = {mu}, {rsteps} steps: largest one-step increase of E − W_p, / E₀"
            ),
            expected: 0.0,
            measured: b.worst_increase.max(0.0) / b.e0,
            tolerance: p.solver.tol,
            unit: String::new(),
            not_converged: b.not_converged,
        };
        section("Rolling resistance", c, &mut checks);
    }
    if !args.quick {
        let settings = coulomb_granular::SimulationSettings {
            scene: coulomb_granular::Scene::Box,
            beads: 600,
            seed: 1,
            params: with_mu_r(0.1),
            stop: coulomb_granular::Stop::until_rest(),
        };
        let s = coulomb_granular::run(&settings)?;
        let c = Check {
            name: format!(
                "box, 600 beads, μ_r = 0.1, `--until-rest` (speeds < 0.05 m/s for 10 steps, cap 2000): at rest (1 = yes), after {} steps",
                s.steps
            ),
            expected: 1.0,
            measured: if s.at_rest { 1.0 } else { 0.0 },
            tolerance: 0.0,
            unit: String::new(),
            not_converged: s.not_converged_steps,
        };
        section("Rolling resistance", c, &mut checks);
    }
    if !args.quick {
        let bed = validation::settled_bed(400, 0.5, 1500, &p)?;
        let mk = |name: &str, expected: f64, measured: f64, tolerance: f64| Check {
            name: format!(
                "settled bed, 400 beads, 0.5 m box ({} steps): {name}",
                bed.steps
            ),
            expected,
            measured,
            tolerance,
            unit: String::new(),
            not_converged: bed.not_converged,
        };
        section(
            "Settled bed",
            mk("largest overlap / R", 0.0, bed.max_overlap, 0.01),
            &mut checks,
        );
        section(
            "Settled bed",
            mk("mean overlap / R", 0.0, bed.mean_overlap, 0.001),
            &mut checks,
        );
        section(
            "Settled bed",
            mk(
                "largest gap / R of a bead resting on the floor",
                0.0,
                bed.max_floor_gap,
                0.01,
            ),
            &mut checks,
        );
        section(
            "Settled bed",
            mk(
                "packing fraction of the inner box (grid-sampled)",
                0.6,
                bed.packing_fraction,
                0.04,
            ),
            &mut checks,
        );
    }
    // the drum and the column collapse: values from the literature, see docs/granular.md
    // ("Validation") for the ranges and tolerances
    if !args.quick {
        let (angle, bad) = validation::drum_angle(300, 12.0, 8.0, &p)?;
        // dense-flow bounds arctan μ_s … arctan μ₂ of glass beads (Jop, Forterre & Pouliquen
        // 2006), the upper one raised by the friction of the caps 5 d apart (Jop et al. 2005:
        // + μ_w h / W ≤ 0.3 · 0.5)
        let (lo, hi) = (
            20.9_f64,
            (32.76_f64.to_radians().tan() + 0.15).atan().to_degrees(),
        );
        let c = Check {
            name: format!(
                "rotating drum, 300 beads, R = 0.6 m, ω = 1 rad/s (Froude ω²R/g = 0.06), μ = {}, μ_r = 0: dynamic angle of the free surface, mean over t = 4…12 s (range {lo:.1}°…{hi:.1}°)",
                p.mu
            ),
            expected: 0.5 * (lo + hi),
            measured: angle,
            tolerance: 0.5 * (hi - lo),
            unit: "°".into(),
            not_converged: bad,
        };
        section("Rotating drum", c, &mut checks);
        let (settle_cap, spread_cap) = (500, 3000);
        let col = validation::column_collapse(150, 0.3, settle_cap, spread_cap, &with_mu_r(0.1))?;
        let when = |done: bool, steps: usize, cap: usize| {
            if done {
                format!("after {steps} steps")
            } else {
                format!("NO, cap {cap} steps")
            }
        };
        let c = Check {
            name: format!(
                "column collapse, 150 beads, r₀ = 0.3 m, μ_r = 0.1, a = H₀/r₀ = {:.2} (settled in the gate {}, deposit at rest {}; rest: speeds < 0.02 m/s for 10 steps): runout (R∞ − r₀)/r₀, Lube et al. 2004",
                col.aspect,
                when(col.settled, col.settle_steps, settle_cap),
                when(col.at_rest, col.spread_steps, spread_cap)
            ),
            expected: col.expected,
            measured: col.runout,
            tolerance: 0.25 * col.expected,
            unit: String::new(),
            not_converged: col.not_converged,
        };
        section("Column collapse", c, &mut checks);
    }
    checks.extend(coulomb_granular::rigid::validation::checks(args.quick)?);
    checks.extend(coulomb_granular::rigid::joint_checks::checks(args.quick)?);
    // the granular laws, from the scene files of examples/scenes/validation/
    for (s, c) in coulomb_granular::laws::checks(!args.quick)? {
        section(&s, c, &mut checks);
    }
    let failed = checks.iter().filter(|(_, c)| !c.pass()).count();
    let md = markdown(&checks, args.quick);
    if let Some(path) = &args.markdown {
        crate::outputs::write(path, md.as_bytes())?;
    }
    if args.json {
        let list: Vec<serde_json::Value> = checks
            .iter()
            .map(|(s, c)| {
                let mut v = serde_json::to_value(c).unwrap_or_default();
                v["section"] = s.clone().into();
                v["pass"] = c.pass().into();
                v
            })
            .collect();
        println!("{}", serde_json::Value::Array(list));
    } else if args.markdown.is_none() {
        print!("{md}");
    }
    if failed > 0 {
        bail!("{failed} of {} checks failed", checks.len());
    }
    Ok(())
}

fn markdown(checks: &[(String, Check)], quick: bool) -> String {
    let mut s = String::new();
    let passed = checks.iter().filter(|(_, c)| c.pass()).count();
    let _ = writeln!(
        s,
        "# Physics validation\n\nProduced by `coulomb validate{}` at the default settings of `coulomb simulate` \
         (h = 0.02 s, θ = ½, every step solved to err ≤ 1e-4 by Gauss–Seidel on the law, activation γ = 1 with δ from the \
         tolerance, position correction and gap closure on; μ_r set where a row names it). {passed} of {} checks pass. Why each tolerance: docs/granular.md, \"Validation\".\n",
        if quick { " --quick" } else { "" },
        checks.len()
    );
    let mut current = "";
    for (sec, c) in checks {
        if sec != current {
            let _ = writeln!(
                s,
                "\n## {sec}\n\n| check | expected | measured | tolerance | unit | steps not converged | pass |\n|---|---|---|---|---|---|---|"
            );
            current = sec;
        }
        let _ = writeln!(
            s,
            "| {} | {:.6} | {:.6} | {:.1e} | {} | {} | {} |",
            c.name,
            c.expected,
            c.measured,
            c.tolerance,
            c.unit,
            c.not_converged,
            if c.pass() { "yes" } else { "**no**" }
        );
    }
    s
}
