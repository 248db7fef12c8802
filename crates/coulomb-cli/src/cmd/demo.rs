//! `coulomb demo`: the main job on built-in data. Builds a small problem in memory (discs in
//! a box, §5.6), writes it as FCLIB, reads it back, prints its info, checks existence, solves
//! it, then runs a short granular box simulation and writes its frames.

use anyhow::Context;
use coulomb::existence::{self, CheckSettings};
use coulomb::fclib::{self, FclibFile, StoredSolution};
use coulomb::solver::{self, Settings};
use coulomb::Problem;
use coulomb_granular::output::{write_stats, VtkWriter};
use coulomb_granular::run::{run_with, SimulationSettings, Stop};
use std::path::PathBuf;

/// Arguments of `coulomb demo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// folder for the demo's files (FCLIB problem and solution, simulation frames)
    #[arg(long, default_value = "coulomb-demo")]
    pub output: PathBuf,
    /// beads in the demo simulation (1 to 1000000, as for `simulate`)
    #[arg(long, default_value_t = 60, value_parser = crate::values::beads)]
    pub beads: usize,
    /// time steps of the demo simulation
    #[arg(long, default_value_t = 40, value_parser = crate::values::count)]
    pub steps: usize,
    /// print one JSON object instead of text
    #[arg(long)]
    pub json: bool,
}

/// Runs `coulomb demo`.
pub fn run(args: Args) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("creating {}", args.output.display()))?;
    let say = |s: String| {
        if !args.json {
            println!("{s}");
        }
    };

    // 1. a small problem built in memory: discs in a rigidly moving box (w = 0 when still)
    let problem = Problem::Global(coulomb::examples::moving_obstacle(0.3, [0.0, 0.0], 0.0)?);
    let path = args.output.join("discs-in-a-box.hdf5");
    crate::outputs::write_fclib(&path, &FclibFile::new(problem))?;
    let file = fclib::read(&path)?;
    let p = &file.problem;
    say(format!(
        "wrote and read back {}: {} problem, d = {}, {} contacts, {} dofs",
        path.display(),
        p.kind(),
        p.dim(),
        p.contacts(),
        p.dofs().map_or("-".into(), |n| n.to_string())
    ));

    // 2. existence (§4–5)
    let report = existence::check(p, &CheckSettings::default())?;
    let conclusion = serde_json::to_value(&report.conclusion)?;
    say(format!("existence: {conclusion}"));

    // 3. solve (fixed point over the SOC-QP), error recomputed from r and v
    let sol = solver::solve(p, &Settings::default())?;
    say(format!(
        "solve: {:?}, error {:.2e}, {} outer / {} inner iterations, {:.3} ms",
        sol.status,
        sol.error,
        sol.outer_iterations,
        sol.inner_iterations,
        sol.solve_time.as_secs_f64() * 1e3
    ));
    let mut with_solution = file.clone();
    with_solution.solution = Some(StoredSolution {
        v: sol.v.clone(),
        u: Some(sol.u.clone()),
        r: sol.r.clone(),
        l: None,
    });
    let sol_path = args.output.join("discs-in-a-box-solved.hdf5");
    crate::outputs::write_fclib(&sol_path, &with_solution)?;
    say(format!("wrote {}", sol_path.display()));

    // 4. a short granular simulation (Moreau–Jean, §6)
    let settings = SimulationSettings {
        beads: args.beads,
        stop: Stop::Steps(args.steps),
        ..SimulationSettings::default()
    };
    let frames = args.output.join("box");
    let mut vtk = VtkWriter::new(&frames).context("creating the frame folder")?;
    let mut io_error = None;
    let (summary, stats) = run_with(&settings, |sim, _| {
        if let Err(e) = vtk.frame(sim) {
            io_error.get_or_insert(e);
        }
    })?;
    if let Some(e) = io_error {
        return Err(e).context("writing VTK frames");
    }
    write_stats(&frames, &stats).context("writing per-step statistics")?;
    say(format!(
        "simulate box: {} beads, {} steps, {:.1} contacts/step, {:.2} subproblems/step, {:.2} ms/step, {} of {} steps converged, max penetration {:.2e} m",
        summary.bodies,
        summary.steps,
        summary.mean_contacts,
        summary.mean_subproblems().unwrap_or(0.0),
        summary.mean_solve_seconds * 1e3,
        summary.converged_steps,
        summary.steps,
        summary.max_penetration
    ));
    say(format!(
        "frames for ParaView: {}/bodies.pvd; statistics: {}/",
        frames.display(),
        frames.display()
    ));
    if args.json {
        let out = serde_json::json!({
            "problem": path,
            "contacts": p.contacts(),
            "existence": conclusion,
            "status": sol.status,
            "converged": sol.converged(),
            "error": sol.error,
            "simulation": summary,
        });
        println!("{}", crate::outputs::json(&out, false)?);
    }
    Ok(())
}
