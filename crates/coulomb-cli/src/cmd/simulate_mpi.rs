//! `coulomb simulate` distributed over MPI (feature `mpi`): started by `mpirun -np K coulomb
//! simulate …` or `srun -n K coulomb simulate …`, or with `--mpi`. Every rank builds the same
//! scene (built-in, or a scene file without inlets, per-pair materials or rolling
//! resistance), keeps its slab of beads and steps with the others
//! ([`coulomb_granular::distributed`], docs/distributed.md); rank 0 prints the summary and
//! writes stats.csv, stats.json (the statistics of `coulomb simulate`), summary.json and
//! distributed.json (per step: sweeps, communication time, ghosts, interface contacts,
//! migration, imbalance); every rank writes its VTK pieces, rank 0 the .pvtp/.pvd collections.

use crate::exit::Outcome;
use crate::progress::bar as progress;
use crate::sim_args::{Args, Method};
use anyhow::{bail, Context};
use coulomb_granular::distributed::output::DistributedVtk;
use coulomb_granular::distributed::{Comm, DistributedSimulation, DistributedStats};
use coulomb_granular::output::write_stats;
use coulomb_granular::{Scene, StepStats, Stop, Summary};

/// Runs `coulomb simulate` on the ranks of MPI_COMM_WORLD. Exit status 1 on every rank when
/// `--until-rest` stopped at its step cap without reaching rest (as in one process).
pub fn run(args: Args, scene: Scene) -> anyhow::Result<Outcome> {
    let world = scene.build_with(args.beads, args.seed, &args.layout()?);
    run_world(&args, world, scene.name())
}

/// Runs the world `world` (every rank builds the same: a built-in scene or a scene file)
/// distributed on the ranks of MPI_COMM_WORLD, `name` its scene's name in the outputs.
pub fn run_world(
    args: &Args,
    world: coulomb_granular::World,
    name: &str,
) -> anyhow::Result<Outcome> {
    if args.dump_fclib.is_some() {
        bail!("--dump-fclib is not available in a distributed run");
    }
    if args.method != Method::Nsgs {
        bail!("a distributed run steps with the body-level Gauss–Seidel (--method nsgs) only");
    }
    let Some(universe) = coulomb_granular::distributed::mpi::initialize() else {
        bail!("MPI could not be initialized (already initialized?)");
    };
    let comm = Comm::new(universe.world());
    let rank = comm.rank();
    let stop = args.stop();
    let beads = world.bodies.len();
    let mut sim = DistributedSimulation::new(comm, world, args.params())
        .context("invalid simulation parameters")?;
    sim.rebalance_every = args.rebalance_every;
    let mut vtk = match &args.output {
        Some(dir) => Some(
            DistributedVtk::new(dir)
                .with_context(|| format!("cannot write into {}", dir.display()))?,
        ),
        None => None,
    };
    let frame = |sim: &mut DistributedSimulation, vtk: &mut Option<DistributedVtk>| {
        let failed = match vtk.as_mut() {
            Some(w) => w.frame(sim).err(),
            None => None,
        };
        // every rank learns whether one failed, so that none waits for the others forever
        let mut flag = [if failed.is_some() { 1.0 } else { 0.0 }];
        sim.comm.sum(&mut flag);
        match failed {
            Some(e) => Err(anyhow::Error::new(e).context("writing VTK frame")),
            None if flag[0] > 0.0 => bail!("another rank failed to write its VTK frame"),
            None => Ok(()),
        }
    };
    frame(&mut sim, &mut vtk)?;
    let start_energy = sim.energy();
    let pb = progress(stop.max_steps(), args.json || rank != 0);
    pb.set_prefix(format!("{name} {beads} on {} ranks", sim.comm.size()));
    let mut stats: Vec<DistributedStats> = Vec::new();
    let (mut calm, mut at_rest) = (0usize, false);
    while sim.steps_done < stop.max_steps() {
        let s = sim.step().context("time step failed")?;
        pb.set_message(format!(
            "{} contacts, {} sweeps, {:.1} ms ({:.1} ms comm), err {:.1e}",
            s.step.contacts, s.sweeps, s.step_ms, s.comm_ms, s.step.error
        ));
        pb.inc(1);
        if args.frames_every > 0 && sim.steps_done % args.frames_every == 0 {
            frame(&mut sim, &mut vtk)?;
        }
        stats.push(s);
        match stop {
            Stop::Steps(n) if sim.steps_done >= n => break,
            Stop::UntilRest { speed, window, .. } => {
                if sim.max_speed() < speed {
                    calm += 1;
                } else {
                    calm = 0;
                }
                if calm >= window.max(1) {
                    at_rest = true;
                    break;
                }
            }
            _ => {}
        }
    }
    pb.finish_and_clear();
    let written = args.frames_every > 0 && sim.steps_done % args.frames_every == 0;
    if !written && sim.steps_done > 0 {
        frame(&mut sim, &mut vtk)?;
    }
    let end_energy = sim.energy();
    let ranks = sim.comm.size();
    if rank != 0 {
        // the status of rank 0 (which says why), so that the launcher reports it whichever
        // rank it looks at
        let capped = matches!(stop, Stop::UntilRest { .. }) && !at_rest;
        return Ok(if capped {
            Outcome::No
        } else {
            Outcome::Success
        });
    }
    let steps: Vec<StepStats> = stats.iter().map(|s| s.step.clone()).collect();
    let summary = Summary::from_stats(name, beads, &steps, at_rest).stopped_by(&stop, None);
    let n = stats.len().max(1) as f64;
    let mean = |f: fn(&DistributedStats) -> f64| stats.iter().map(f).sum::<f64>() / n;
    let (step_ms, comm_ms, sweeps) = (
        mean(|s| s.step_ms),
        mean(|s| s.comm_ms),
        mean(|s| s.sweeps as f64),
    );
    if let Some(dir) = &args.output {
        write_stats(dir, &steps)
            .with_context(|| format!("writing stats into {}", dir.display()))?;
        crate::outputs::write(
            &dir.join("summary.json"),
            crate::outputs::json(&summary, true)?.as_bytes(),
        )?;
        crate::outputs::write(
            &dir.join("distributed.json"),
            crate::outputs::json(&stats, true)?.as_bytes(),
        )?;
    }
    if args.json {
        let extra = serde_json::json!({
            "ranks": ranks,
            "mean_sweeps": sweeps,
            "mean_step_ms": step_ms,
            "mean_comm_ms": comm_ms,
        });
        let extra = extra.as_object().cloned().unwrap_or_default();
        let obj = crate::sim_args::summary_json(&summary, start_energy, end_energy, extra);
        println!("{}", crate::outputs::json(&obj, false)?);
    } else {
        println!(
            "{}: {} beads on {} ranks, {} steps{}, {:.1} contacts/step, {:.1} sweeps/step, {:.2} ms/step ({:.2} ms communication), mean error {:.2e} (max {:.2e}), {} / {} steps converged ({} not converged), max penetration during the run {:.2e} m, at the end: mean {:.2e} m, max {:.2e} m",
            summary.scene,
            summary.beads,
            ranks,
            summary.steps,
            crate::interrupt::stopped_note(&summary),
            summary.mean_contacts,
            sweeps,
            step_ms,
            comm_ms,
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
    Ok(crate::interrupt::simulation_outcome(
        &summary,
        stop.max_steps(),
    ))
}
