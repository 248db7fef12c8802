//! `coulomb simulate`: Moreau–Jean time stepping of one of the granular scenes, with per-step
//! statistics (CSV, JSON), VTK frames for ParaView and optional FCLIB dumps of each step.

use crate::sim_args::Args;
use anyhow::{bail, Context};
use coulomb_granular::output::{write_stats, VtkWriter};
use coulomb_granular::run::RestMonitor;
use coulomb_granular::{Scene, Simulation, Summary};

/// Runs `coulomb simulate` in this process, on the scene checked by
/// [`crate::sim_args::checked_scene`] (main.rs hands distributed runs to `simulate_mpi`).
pub fn run(args: Args, scene: Scene) -> anyhow::Result<()> {
    let stop = args.stop();
    let world = if args.spread_top {
        if scene != Scene::Box {
            bail!("--spread-top applies to the box scene only");
        }
        Scene::box_spread(args.beads, args.seed)
    } else {
        scene.build_with(args.beads, args.seed, &args.layout()?)
    };
    let mut sim = Simulation::new(world, args.params()).context("invalid simulation parameters")?;
    sim.keep_problem = args.dump_fclib.is_some();
    if let Some(dir) = &args.dump_fclib {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let mut vtk = match &args.output {
        Some(dir) => Some(
            VtkWriter::new(dir).with_context(|| format!("cannot write into {}", dir.display()))?,
        ),
        None => None,
    };
    if let Some(w) = vtk.as_mut() {
        w.frame(&sim).context("writing VTK frame")?;
    }
    let start_energy = sim.world.kinetic_energy() + sim.world.potential_energy();
    let pb = crate::progress::bar(stop.max_steps(), args.json);
    pb.set_prefix(format!("{} {}", scene.name(), args.beads));
    let mut stats = Vec::new();
    let mut monitor = RestMonitor::default();
    let mut at_rest = false;
    while sim.steps_done < stop.max_steps() {
        let s = sim.step().context("time step failed")?;
        pb.set_message(format!(
            "{} contacts, {} subproblems, {:.1} ms, err {:.1e}",
            s.contacts, s.subproblems, s.solve_ms, s.error
        ));
        pb.inc(1);
        if let (Some(dir), Some(p)) = (&args.dump_fclib, &sim.last_problem) {
            dump_fclib(dir, sim.steps_done - 1, p)?;
        }
        if let Some(w) = vtk.as_mut() {
            if args.frames_every > 0 && sim.steps_done % args.frames_every == 0 {
                w.frame(&sim).context("writing VTK frame")?;
            }
        }
        stats.push(s);
        let (stop_now, rest) = monitor.should_stop(&stop, &sim);
        if stop_now {
            at_rest = rest;
            break;
        }
    }
    pb.finish_and_clear();
    // the last state, when the run stopped between two frames
    if let Some(w) = vtk.as_mut() {
        let written = args.frames_every > 0 && sim.steps_done % args.frames_every == 0;
        if !written && sim.steps_done > 0 {
            w.frame(&sim).context("writing VTK frame")?;
        }
    }
    let summary = Summary::from_stats(scene.name(), args.beads, &stats, at_rest);
    let end_energy = sim.world.kinetic_energy() + sim.world.potential_energy();
    if let Some(dir) = &args.output {
        write_stats(dir, &stats)
            .with_context(|| format!("writing stats into {}", dir.display()))?;
        crate::outputs::write(
            &dir.join("summary.json"),
            crate::outputs::json(&summary, true)?.as_bytes(),
        )?;
    }
    if args.json {
        let obj =
            crate::sim_args::summary_json(&summary, start_energy, end_energy, Default::default());
        println!("{}", crate::outputs::json(&obj, false)?);
    } else {
        println!(
            "{}: {} beads, {} steps{}, {:.1} contacts/step, {:.2} subproblems/step, {:.2} ms solve/step, mean error {:.2e} (max {:.2e}), {} / {} steps converged ({} not converged), max penetration during the run {:.2e} m, at the end: mean {:.2e} m, max {:.2e} m",
            summary.scene,
            summary.beads,
            summary.steps,
            if summary.at_rest { " (at rest)" } else { "" },
            summary.mean_contacts,
            summary.mean_subproblems,
            summary.mean_solve_ms,
            summary.mean_error,
            summary.max_error,
            summary.converged_steps,
            summary.steps,
            summary.not_converged_steps,
            summary.max_penetration,
            summary.end_mean_penetration,
            summary.end_max_penetration
        );
    }
    Ok(())
}

/// Writes one step's problem as `step_KKKKKK.hdf5` in FCLIB global format.
pub(crate) fn dump_fclib(
    dir: &std::path::Path,
    step: usize,
    problem: &coulomb::problem::GlobalProblem,
) -> anyhow::Result<()> {
    use coulomb::fclib::{FclibFile, Info};
    let path = dir.join(format!("step_{step:06}.hdf5"));
    let mut file = FclibFile::new(coulomb::problem::Problem::Global(problem.clone()));
    file.info = Some(Info {
        title: format!("granular step {step}"),
        description: "Moreau-Jean step of coulomb simulate (coulomb-granular)".into(),
        math_info: String::new(),
    });
    crate::outputs::write_fclib(&path, &file)
}
