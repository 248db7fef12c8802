//! The one run loop of `coulomb simulate` in one process, for every scene whichever engine
//! steps it ([`Engine`]: the sphere engine's `Simulation`, the rigid engine's `RigidScene`):
//! the progress report, `stats.csv` / `stats.json`, VTK frames, checkpoints, FCLIB dumps, the
//! rest rule of `--until-rest`, SIGINT/SIGTERM, the summary (`summary.json`, `--json`, the
//! printed line) and the exit status. `cmd/simulate.rs` (built-in scenes, restarts),
//! `cmd/simulate_rigid.rs` (rigid scenes) and `scene_arg` (scene files) build the scene and
//! hand it here; the outputs' files are written through [`crate::run_output`].

use crate::exit::Outcome;
use crate::run_output::{
    dump_fclib, finish, open_outputs, write_checkpoint_bytes, write_failed, RunEnd,
};
use crate::sim_args::Args;
use anyhow::Context;
use coulomb_granular::output::BODIES_NAMES;
use coulomb_granular::report::CSV_HEADER;
use coulomb_granular::run::{EndState, RestMonitor};
use coulomb_granular::{Engine, EngineStep, Summary};
use std::path::PathBuf;

/// What a run does after each step besides the outputs (the inlets of a scene file), and
/// what it adds to the printed JSON summary.
pub(crate) trait StepHook<E> {
    /// Called after the step from `t0` to `t1`.
    fn after_step(&mut self, sim: &mut E, t0: f64, t1: f64) -> anyhow::Result<()>;
    /// Fields added to the `--json` summary, and a note for the one-line summary.
    fn report(&self) -> (serde_json::Map<String, serde_json::Value>, String) {
        (serde_json::Map::new(), String::new())
    }
}

/// What the inlets of a run add to its `--json` summary (`poured`, `inlet_skipped`) and to its
/// one-line summary, the same for every scene; nothing for a scene without inlets.
pub(crate) fn inlet_report(
    has_inlets: bool,
    poured: usize,
    skipped: usize,
) -> (serde_json::Map<String, serde_json::Value>, String) {
    let mut extra = serde_json::Map::new();
    if !has_inlets {
        return (extra, String::new());
    }
    extra.insert("poured".into(), poured.into());
    extra.insert("inlet_skipped".into(), skipped.into());
    (extra, format!(" ({poured} poured, {skipped} skipped)"))
}

/// A run with nothing to do between steps.
pub(crate) struct NoHook;

impl<E> StepHook<E> for NoHook {
    fn after_step(&mut self, _: &mut E, _: f64, _: f64) -> anyhow::Result<()> {
        Ok(())
    }
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

/// The rows of `stats.json` of `steps`: the same keys for every scene
/// ([`EngineStep::json_row`]).
fn json_rows(steps: &[EngineStep]) -> Vec<serde_json::Value> {
    steps
        .iter()
        .map(EngineStep::json_row)
        .filter_map(Result::ok)
        .collect()
}

/// The time steps of a run from `sim` (new, loaded by a restart when `restarted`, or built
/// from a scene file) and its outputs: frames, statistics, summary, checkpoints, FCLIB
/// dumps; stopped by its stop rule or by SIGINT/SIGTERM. Exit status 1 when a step ended
/// above its tolerance or `--until-rest` reached its step cap; 130/143 when interrupted.
pub(crate) fn steps<E: Engine>(
    args: &Args,
    mut sim: E,
    name: &str,
    restarted: bool,
    inputs: &[PathBuf],
    hook: &mut dyn StepHook<E>,
) -> anyhow::Result<Outcome> {
    crate::interrupt::install().context("installing the SIGINT/SIGTERM handlers")?;
    let first_step = sim.steps_done();
    let stop = args.stop_after(first_step);
    sim.keep_problem(args.dump_fclib.is_some());
    // every output checked before anything is created or computed
    let mut out = open_outputs(
        args,
        sim.run_kind(),
        &BODIES_NAMES,
        CSV_HEADER,
        inputs,
        restarted.then_some(first_step as u64),
    )?;
    if let Some(dir) = &args.dump_fclib {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let mut vtk = out
        .as_ref()
        .map(|o| sim.frames(o.dir.clone(), restarted.then_some(first_step)));
    let frame_failed = |k: usize| {
        let dir = args.output.clone().unwrap_or_default();
        write_failed(&dir, &format!("frames/bodies_{k:06}.vtp"))
    };
    if let Some(w) = vtk.as_mut() {
        sim.frame(w).map_err(frame_failed(first_step))?;
    }
    let start_energy = sim.kinetic_energy() + sim.potential_energy();
    // a bar on a terminal, plain lines on stderr every few seconds otherwise, nothing with
    // --json
    let pb = crate::progress::bar(stop.max_steps().saturating_sub(first_step), args.json);
    pb.set_prefix(format!("{name} {}", sim.bodies()));
    let mut steps: Vec<EngineStep> = Vec::new();
    let mut monitor = RestMonitor::default();
    let mut at_rest = false;
    let mut interrupted = None;
    // a step-size warning (a sphere fast enough to cross a thin wall) is said once
    let mut warned = false;
    let mut run = || -> anyhow::Result<()> {
        while sim.steps_done() < stop.max_steps() {
            let t0 = sim.time();
            let s = sim
                .step()
                .with_context(|| format!("{name}: time step failed"))?;
            let t1 = sim.time();
            if let Some(o) = out.as_mut() {
                o.row(&s.record.csv_line())
                    .map_err(write_failed(o.dir.path(), "stats.csv"))?;
            }
            pb.set_message(format!(
                "{} contacts, {} iterations, {:.1} ms, err {:.1e}",
                s.record.contacts,
                s.record.iterations,
                s.record.solve_seconds * 1e3,
                s.record.error
            ));
            pb.inc(1);
            steps.push(s);
            hook.after_step(&mut sim, t0, t1)?;
            if !warned {
                if let Some(w) = sim.step_warning() {
                    let k = sim.steps_done();
                    eprintln!("warning: step {k}: {w} ({})", step_advice(args));
                    warned = true;
                }
            }
            let k = sim.steps_done();
            if let (Some(dir), Some(p)) = (&args.dump_fclib, sim.last_problem()) {
                dump_fclib(dir, k - 1, p)?;
            }
            if let Some(w) = vtk.as_mut() {
                if args.frames_every > 0 && k % args.frames_every == 0 {
                    sim.frame(w).map_err(frame_failed(k))?;
                }
            }
            if let Some(o) = out.as_mut() {
                if args.checkpoint_every > 0 && k % args.checkpoint_every == 0 {
                    write_checkpoint_bytes(o, k as u64, sim.checkpoint_bytes())?;
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
            if let Ok(text) = o.json_text(&json_rows(&steps)) {
                let _ = o.write_json(&text);
            }
        }
        return Err(e);
    }
    let k = sim.steps_done();
    // the last state, when the run stopped between two frames
    if let Some(w) = vtk.as_mut() {
        let written = args.frames_every > 0 && k % args.frames_every == 0;
        if !written && !steps.is_empty() {
            sim.frame(w).map_err(frame_failed(k))?;
        }
    }
    let end = EndState {
        bodies: sim.bodies(),
        time: sim.time(),
        kinetic_energy: sim.kinetic_energy(),
    };
    let summary = Summary::from_steps(name, &steps, end, at_rest)
        .stopped_by(&stop, interrupted.map(|s| s.name()));
    let end_energy = sim.kinetic_energy() + sim.potential_energy();
    if let Some(o) = out.as_mut() {
        let text = o
            .json_text(&json_rows(&steps))
            .map_err(write_failed(o.dir.path(), "stats.json"))?;
        let end = RunEnd {
            steps_done: k as u64,
            stepped: !steps.is_empty(),
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
        let pen = |p: Option<f64>| p.map_or("–".to_string(), |p| format!("{p:.2e} m"));
        println!(
            "{}: {} bodies{note}, {} steps ({:.4} s){}, {:.1} contacts/step, {:.2} iterations/step, {:.2} ms solve/step, mean error {:.2e} (max {:.2e}), {} / {} steps converged ({} not converged), max penetration during the run {:.2e} m, at the end: mean {}, max {}",
            summary.scene,
            summary.bodies,
            summary.steps,
            summary.time,
            crate::interrupt::stopped_note(&summary),
            summary.mean_contacts,
            summary.mean_iterations,
            summary.mean_solve_seconds * 1e3,
            summary.mean_error,
            summary.max_error,
            summary.converged_steps,
            summary.steps,
            summary.not_converged_steps,
            summary.max_penetration,
            pen(summary.end_mean_penetration),
            pen(summary.end_max_penetration)
        );
    }
    if let Some(signal) = interrupted {
        return crate::interrupt::simulation_interrupted(k, args.output.as_deref(), signal);
    }
    Ok(crate::interrupt::simulation_outcome(
        &summary,
        stop.max_steps(),
    ))
}
