//! `coulomb simulate`: Moreau–Jean time stepping of one of the granular scenes, with per-step
//! statistics (CSV, JSON), VTK frames for ParaView, checkpoints of the full state
//! (`--checkpoint-every`, `--restart`) and optional FCLIB dumps of each step.

use crate::exit::Outcome;
use crate::run_output::{
    dump_fclib, finish, open_outputs, write_checkpoint_bytes, write_failed, RunEnd,
};
use crate::sim_args::Args;
use anyhow::{bail, Context};
use coulomb_granular::output::{csv_line, VtkWriter, BODIES_NAMES, CSV_HEADER};
use coulomb_granular::output_dir::RunKind;
use coulomb_granular::run::RestMonitor;
use coulomb_granular::{Scene, Simulation, Summary};
use std::path::PathBuf;

/// Runs `coulomb simulate` in this process, on the scene checked by
/// [`crate::sim_args::checked_scene`] (main.rs hands distributed runs to `simulate_mpi`).
/// SIGINT/SIGTERM stop it after the step in progress, with every output written
/// ([`crate::interrupt`]): exit status 130/143; `--until-rest` at its step cap: 1.
pub fn run(args: Args, scene: Scene) -> anyhow::Result<Outcome> {
    let world = if args.spread_top {
        if scene != Scene::Box {
            bail!("--spread-top applies to the box scene only");
        }
        Scene::box_spread(args.beads, args.seed)
    } else {
        scene.build_with(args.beads, args.seed, &args.layout()?)
    };
    let sim = Simulation::new(world, args.params()).context("invalid simulation parameters")?;
    steps(&args, sim, scene.name(), false, &[], &mut NoHook)
}

/// `coulomb simulate --restart FILE`: the simulation stored in FILE, continued for `--steps`
/// more steps (or until rest, at most `--max-steps` more); with `--output`, the stats files
/// found there keep their rows before the checkpoint's step and get this run's appended.
pub fn restart(args: Args) -> anyhow::Result<Outcome> {
    let Some(file) = args.restart.clone() else {
        bail!("--restart needs a checkpoint file");
    };
    if crate::cmd::simulate_rigid::is_rigid_checkpoint(&file) {
        return crate::cmd::simulate_rigid::restart(&args, &file, None, &[]);
    }
    let sim = Simulation::load_checkpoint(&file)
        .with_context(|| format!("cannot restart from {}", file.display()))?;
    steps(&args, sim, "restart", true, &[], &mut NoHook)
}

/// Where the user sets the time step of this run: `--dt` for a built-in scene, `[step] h` in
/// a scene file (where `--dt` is refused), a new run for a restart (whose h is the
/// checkpoint's).
fn step_advice(args: &Args) -> String {
    match (&args.restart, args.scene.as_deref()) {
        (Some(_), _) => {
            "a restart keeps the checkpoint's h: run again from the start with a smaller h"
                .to_string()
        }
        (None, Some(f)) if crate::sim_args::is_scene_file(f) => {
            format!("set h in the [step] section of {f}; --dt is for the built-in scenes")
        }
        _ => "set it with --dt".to_string(),
    }
}

/// What a run does after each step besides the outputs (the inlets of a scene file), and
/// what it adds to the printed JSON summary.
pub(crate) trait StepHook {
    /// Called after the step from `t0` to `t1`.
    fn after_step(&mut self, sim: &mut Simulation, t0: f64, t1: f64) -> anyhow::Result<()>;
    /// Fields added to the `--json` summary, and a note for the one-line summary.
    fn report(&self) -> (serde_json::Map<String, serde_json::Value>, String) {
        (serde_json::Map::new(), String::new())
    }
}

/// A run with nothing to do between steps.
struct NoHook;

impl StepHook for NoHook {
    fn after_step(&mut self, _: &mut Simulation, _: f64, _: f64) -> anyhow::Result<()> {
        Ok(())
    }
}

/// The time steps of a run from `sim` (new, loaded by a restart, or built from a scene file)
/// and its outputs: frames, statistics, summary, checkpoints, FCLIB dumps; one loop for every
/// kind of run, stopped by its stop rule or by SIGINT/SIGTERM.
pub(crate) fn steps(
    args: &Args,
    mut sim: Simulation,
    name: &str,
    restarted: bool,
    inputs: &[PathBuf],
    hook: &mut dyn StepHook,
) -> anyhow::Result<Outcome> {
    crate::interrupt::install().context("installing the SIGINT/SIGTERM handlers")?;
    let first_step = sim.steps_done;
    let stop = args.stop_after(first_step);
    let beads = sim.world.bodies.len();
    sim.keep_problem = args.dump_fclib.is_some();
    // every output checked before anything is created or computed
    let mut out = open_outputs(
        args,
        RunKind::Spheres,
        &BODIES_NAMES,
        CSV_HEADER,
        inputs,
        restarted.then_some(first_step as u64),
    )?;
    if let Some(dir) = &args.dump_fclib {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let mut vtk = out.as_ref().map(|o| {
        let w = VtkWriter::in_dir(o.dir.clone());
        if restarted {
            w.resumed(first_step)
        } else {
            w
        }
    });
    let frame_failed = |k: usize| {
        let dir = args.output.clone().unwrap_or_default();
        write_failed(&dir, &format!("frames/bodies_{k:06}.vtp"))
    };
    if let Some(w) = vtk.as_mut() {
        w.frame(&sim).map_err(frame_failed(sim.steps_done))?;
    }
    let start_energy = sim.world.kinetic_energy() + sim.world.potential_energy();
    let pb = crate::progress::bar(stop.max_steps().saturating_sub(first_step), args.json);
    pb.set_prefix(format!("{name} {beads}"));
    let mut stats = Vec::new();
    let mut monitor = RestMonitor::default();
    let mut at_rest = false;
    let mut interrupted = None;
    // a sphere fast enough to cross a thin wall within one step is reported once
    let mut warned_travel = false;
    let mut run = || -> anyhow::Result<()> {
        while sim.steps_done < stop.max_steps() {
            let t0 = sim.time;
            let s = sim.step().context("time step failed")?;
            let t1 = sim.time;
            if let Some(o) = out.as_mut() {
                o.row(&csv_line(&s))
                    .map_err(write_failed(o.dir.path(), "stats.csv"))?;
            }
            stats.push(s);
            hook.after_step(&mut sim, t0, t1)?;
            if !warned_travel {
                let (v, r) = coulomb_granular::tunnelling::speed_and_radius(&sim.world);
                if let Err(t) = coulomb_granular::tunnelling::check(&sim.world, sim.params.h, v, r)
                {
                    eprintln!(
                        "warning: step {}: {t} ({})",
                        sim.steps_done,
                        step_advice(args)
                    );
                    warned_travel = true;
                }
            }
            let s = stats.last().expect("pushed above");
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
                    w.frame(&sim).map_err(frame_failed(sim.steps_done))?;
                }
            }
            if let Some(o) = out.as_mut() {
                if args.checkpoint_every > 0 && sim.steps_done % args.checkpoint_every == 0 {
                    write_checkpoint_bytes(o, sim.steps_done as u64, sim.checkpoint_bytes())?;
                }
            }
            let (stop_now, rest) = monitor.should_stop(&stop, &sim);
            if stop_now {
                at_rest = rest;
                break;
            }
            interrupted = crate::interrupt::received();
            if interrupted.is_some() {
                break;
            }
        }
        Ok(())
    };
    let result = run();
    pb.finish_and_clear();
    if let Err(e) = result {
        // the statistics of every completed step are kept (stats.csv has them already)
        if let Some(o) = out.as_mut() {
            if let Ok(text) = o.json_text(&stats) {
                let _ = o.write_json(&text);
            }
        }
        return Err(e);
    }
    // the last state, when the run stopped between two frames
    if let Some(w) = vtk.as_mut() {
        let written = args.frames_every > 0 && sim.steps_done % args.frames_every == 0;
        if !written && sim.steps_done > 0 {
            w.frame(&sim).map_err(frame_failed(sim.steps_done))?;
        }
    }
    let summary = Summary::from_stats(name, sim.world.bodies.len(), &stats, at_rest)
        .stopped_by(&stop, interrupted.map(|s| s.name()));
    let end_energy = sim.world.kinetic_energy() + sim.world.potential_energy();
    if let Some(o) = out.as_mut() {
        let text = o
            .json_text(&stats)
            .map_err(write_failed(o.dir.path(), "stats.json"))?;
        let end = RunEnd {
            steps_done: sim.steps_done as u64,
            stepped: !stats.is_empty(),
            interrupted: interrupted.is_some(),
        };
        let summary_json = crate::outputs::json(&summary, true)?;
        finish(
            o,
            args,
            end,
            || sim.checkpoint_bytes(),
            &text,
            &summary_json,
        )?;
    }
    let (extra, note) = hook.report();
    if args.json {
        let obj = crate::sim_args::summary_json(&summary, start_energy, end_energy, extra);
        println!("{}", crate::outputs::json(&obj, false)?);
    } else {
        println!(
            "{}: {} beads{note}, {} steps{}, {:.1} contacts/step, {:.2} subproblems/step, {:.2} ms solve/step, mean error {:.2e} (max {:.2e}), {} / {} steps converged ({} not converged), max penetration during the run {:.2e} m, at the end: mean {:.2e} m, max {:.2e} m",
            summary.scene,
            summary.beads,
            summary.steps,
            crate::interrupt::stopped_note(&summary),
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
    if let Some(signal) = interrupted {
        return crate::interrupt::simulation_interrupted(&sim, args.output.as_deref(), signal);
    }
    Ok(crate::interrupt::simulation_outcome(
        &summary,
        stop.max_steps(),
    ))
}
