//! `coulomb simulate SCENE.toml` for a scene file with bodies of other shapes than spheres
//! (issue 41): the rigid-body simulator ([`coulomb_granular::rigid_scene::RigidScene`]), with
//! the run options of the sphere path: `--steps` (or the file's), `--until-rest` (every body
//! slower than `rest_speed`, linear and angular speed times the body's size, for 10 steps, at
//! most `max_steps`), `--output` (VTK frames of the bodies as their shapes, contacts and
//! obstacles every `--frames-every` steps; `stats.json`, `stats.csv`, `summary.json`),
//! `--dump-fclib` (each step's problem (2.10) in FCLIB global form), `--checkpoint-every`
//! and `--restart` (a rigid checkpoint, [`coulomb_granular::rigid_checkpoint`]),
//! `--resolve-overlaps` (the bodies moved apart first, [`RigidScene::new_relaxed`]) and `--json`.
//! Exit 1 when a step ended above its tolerance or `--until-rest` hit its cap.

use crate::exit::Outcome;
use crate::sim_args::Args;
use anyhow::Context;
use coulomb_granular::output::RigidVtkWriter;
use coulomb_granular::output::BODIES_NAMES;
use coulomb_granular::output_dir::RunKind;
use coulomb_granular::rigid::RigidStatus;
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::BuiltScene;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The summary of a rigid run (`summary.json`, `--json`).
#[derive(Debug, Serialize)]
struct RigidSummary {
    scene: String,
    bodies: usize,
    steps: usize,
    time: f64,
    mean_contacts: f64,
    /// mean over the steps of the contacts carrying load (r_N > 10⁻⁶ max r_N)
    mean_loaded_contacts: f64,
    mean_sweeps: f64,
    max_error: f64,
    not_converged_steps: usize,
    max_penetration: f64,
    at_rest: bool,
    kinetic_energy: f64,
    /// why the run stopped, as the sphere runs' summary says it: `steps`, `rest`,
    /// `step_cap` (`--until-rest` at its cap) or `interrupted`
    stopped: coulomb_granular::Stopped,
    /// the signal that interrupted the run (`SIGINT`, `SIGTERM`), absent otherwise
    #[serde(skip_serializing_if = "Option::is_none")]
    signal: Option<String>,
}

/// Runs the rigid scene of `scene` with the run settings `a` (the file's, completed by the
/// command line: [`crate::scene_arg`]).
pub fn run(a: &Args, scene: &BuiltScene, inputs: &[PathBuf]) -> anyhow::Result<Outcome> {
    let file = scene.path.display().to_string();
    coulomb_granular::rigid_scene::check_step_section(&scene.step)
        .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
    let rigid = match a.resolve_overlaps {
        None => RigidScene::new(&scene.model).with_context(|| file.clone())?,
        Some(sweeps) => {
            let (rigid, r) =
                RigidScene::new_relaxed(&scene.model, sweeps).with_context(|| file.clone())?;
            if r.before.count > 0 {
                eprintln!(
                    "{file}: {} overlaps at the start (worst {:.3e} m) relaxed in {} sweeps, {} left",
                    r.before.count, r.before.worst, r.sweeps, r.left.count
                );
            }
            rigid
        }
    };
    steps(a, rigid, &scene.name, false, inputs, pour(scene))
}

/// `stats.json` of a rigid run: the rows kept from before a restart, then `reports`.
fn rigid_json(
    o: &coulomb_granular::output_dir::RunOutput,
    reports: &[coulomb_granular::rigid::RigidStepReport],
) -> anyhow::Result<String> {
    let mut all = o.old_json.clone();
    for r in reports {
        all.push(serde_json::to_value(r)?);
    }
    Ok(crate::outputs::json(&all, true)?)
}

/// Whether `path` is a rigid-scene checkpoint ([`coulomb_granular::rigid_checkpoint`]), not
/// a sphere one.
pub fn is_rigid_checkpoint(path: &Path) -> bool {
    coulomb_granular::checkpoint::format_of(path).as_deref()
        == Some(coulomb_granular::rigid_checkpoint::FORMAT_NAME)
}

/// `coulomb simulate [SCENE.toml] --restart FILE` for a rigid checkpoint: the scene stored in
/// FILE continued for `--steps` more steps (or `--until-rest`), the outputs of `--output`
/// continuing those found there. With the scene file, it must be the stored run's (the same
/// model; status 2 otherwise).
pub fn restart(
    a: &Args,
    checkpoint: &Path,
    scene: Option<&BuiltScene>,
    inputs: &[PathBuf],
) -> anyhow::Result<Outcome> {
    let rigid = RigidScene::load_checkpoint(checkpoint)
        .with_context(|| format!("cannot restart from {}", checkpoint.display()))?;
    let name = match scene {
        Some(s) => {
            if !rigid.is_built_from(&s.model, !s.inlets.is_empty()) {
                anyhow::bail!(
                    "{} is not the scene of the checkpoint {}: its bodies, obstacles or settings differ",
                    s.path.display(),
                    checkpoint.display()
                );
            }
            s.name.clone()
        }
        None => "restart".to_string(),
    };
    steps(a, rigid, &name, true, inputs, scene.and_then(pour))
}

/// The scene whose inlets pour after each step ([`BuiltScene::pour_rigid`]), if it has some.
fn pour(scene: &BuiltScene) -> Option<BuiltScene> {
    (!scene.inlets.is_empty()).then(|| scene.clone())
}

/// The size of a body for `--until-rest`: the farthest vertex of its tessellation.
fn size_of(s: &coulomb_granular::model::BodyShape) -> f64 {
    let t = s.tessellation().unwrap_or_default();
    t.vertices
        .iter()
        .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
        .fold(0.0, f64::max)
}

/// The time steps of `rigid` (new, or loaded by a restart when `restarted`) and their
/// outputs; after each step t_k → t_{k+1} the inlets of `inlets` pour the bodies due in
/// (t_k, t_{k+1}] (before the step's frame and checkpoint).
fn steps(
    a: &Args,
    mut rigid: RigidScene,
    name: &str,
    restarted: bool,
    inputs: &[PathBuf],
    mut inlets: Option<BuiltScene>,
) -> anyhow::Result<Outcome> {
    use crate::run_output::{write_checkpoint_bytes, write_failed};
    crate::interrupt::install().context("installing the SIGINT/SIGTERM handlers")?;
    let first = rigid.world.steps();
    // every output checked before anything is created or computed (run_output::open_outputs)
    let mut out = crate::run_output::open_outputs(
        a,
        RunKind::Rigid,
        &BODIES_NAMES,
        coulomb_granular::report::CSV_HEADER,
        inputs,
        restarted.then_some(first),
    )?;
    if let Some(dir) = &a.dump_fclib {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let mut vtk = out.as_ref().map(|o| {
        let w = RigidVtkWriter::in_dir(o.dir.clone(), &rigid);
        if restarted {
            w.resumed(first as usize)
        } else {
            w
        }
    });
    let frame_failed = |k: u64| {
        let dir = a.output.clone().unwrap_or_default();
        write_failed(&dir, &format!("frames/bodies_{k:06}.vtp"))
    };
    if let Some(w) = vtk.as_mut() {
        w.frame(&rigid).map_err(frame_failed(first))?;
    }
    let more = if a.until_rest {
        a.max_steps
    } else {
        a.steps.unwrap_or(200)
    };
    let max_steps = (first as usize).saturating_add(more);
    let mut sizes: Vec<f64> = rigid.shapes.iter().map(size_of).collect();
    let mut warned_full = false;
    // the progress report of sphere runs: a bar on a terminal, plain lines on stderr every
    // few seconds otherwise (a log file, CI), nothing with --json
    let pb = crate::progress::bar(
        max_steps.saturating_sub(rigid.world.steps() as usize),
        a.json,
    );
    pb.set_prefix(format!("{name} {}", rigid.world.len()));
    let mut still = 0;
    let mut at_rest = false;
    let mut interrupted = None;
    let mut run = || -> anyhow::Result<()> {
        while (rigid.world.steps() as usize) < max_steps {
            let k = rigid.world.steps() as usize;
            let t0 = rigid.world.time();
            let r = rigid
                .step()
                .with_context(|| format!("{name}: time step failed"))?;
            if let Some(scene) = inlets.as_mut() {
                let t1 = rigid.world.time();
                let p = scene
                    .pour_rigid(&mut rigid, t0, t1)
                    .with_context(|| format!("{name}: inlet at t = {t1}"))?;
                if p.capped > 0 && !warned_full {
                    warned_full = true;
                    eprintln!(
                        "warning: an inlet's region is full at t = {t1}: {} emission(s) of this step skipped without trying (an inlet adds at most what its region holds per step; lower its rate)",
                        p.capped
                    );
                }
                sizes.extend(rigid.shapes[sizes.len()..].iter().map(size_of));
            }
            if let Some(o) = out.as_mut() {
                let line =
                    coulomb_granular::StepRecord::of_rigid(&r, rigid.world.potential_energy())
                        .csv_line();
                o.row(&line)
                    .map_err(write_failed(o.dir.path(), "stats.csv"))?;
            }
            if let (Some(dir), Some(p)) = (&a.dump_fclib, rigid.world.last_problem()) {
                crate::run_output::dump_fclib(dir, k, p)?;
            }
            if let Some(w) = vtk.as_mut() {
                if a.frames_every > 0 && (k + 1) % a.frames_every == 0 {
                    w.frame(&rigid).map_err(frame_failed(k as u64 + 1))?;
                }
            }
            if let Some(o) = out.as_mut() {
                if a.checkpoint_every > 0 && (k + 1) % a.checkpoint_every == 0 {
                    write_checkpoint_bytes(o, k as u64 + 1, rigid.checkpoint_bytes())?;
                }
            }
            pb.set_message(format!(
                "{} contacts, {} sweeps, error {:.1e}",
                r.contacts, r.sweeps, r.error
            ));
            pb.inc(1);
            if a.until_rest {
                let v = rigid.world.velocities();
                let w = rigid.world.angular_velocities();
                let fastest = v
                    .iter()
                    .zip(&w)
                    .zip(&sizes)
                    .map(|((v, w), s)| {
                        let n = |x: &[f64; 3]| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
                        n(v) + n(w) * s
                    })
                    .fold(0.0, f64::max);
                still = if fastest < a.rest_speed { still + 1 } else { 0 };
                if still >= 10 {
                    at_rest = true;
                    break;
                }
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
            if let Ok(text) = rigid_json(o, &rigid.reports) {
                let _ = o.write_json(&text);
            }
        }
        return Err(e);
    }
    let reports = &rigid.reports;
    let n = reports.len().max(1) as f64;
    let summary = RigidSummary {
        scene: name.to_string(),
        bodies: rigid.world.len(),
        steps: reports.len(),
        time: rigid.world.time(),
        mean_contacts: reports.iter().map(|r| r.contacts as f64).sum::<f64>() / n,
        mean_loaded_contacts: reports
            .iter()
            .map(|r| r.loaded_contacts as f64)
            .sum::<f64>()
            / n,
        mean_sweeps: reports.iter().map(|r| r.sweeps as f64).sum::<f64>() / n,
        max_error: reports.iter().map(|r| r.error).fold(0.0, f64::max),
        not_converged_steps: reports
            .iter()
            .filter(|r| r.status == RigidStatus::NotConverged)
            .count(),
        max_penetration: reports
            .iter()
            .map(|r| r.max_penetration)
            .fold(0.0, f64::max),
        at_rest,
        kinetic_energy: rigid.world.kinetic_energy(),
        stopped: match interrupted {
            Some(_) => coulomb_granular::Stopped::Interrupted,
            None if at_rest => coulomb_granular::Stopped::Rest,
            None if a.until_rest => coulomb_granular::Stopped::StepCap,
            None => coulomb_granular::Stopped::Steps,
        },
        signal: interrupted.map(|s| s.name().to_string()),
    };
    if let Some(w) = vtk.as_mut() {
        let written = a.frames_every > 0 && rigid.world.steps() as usize % a.frames_every == 0;
        if !written && !reports.is_empty() {
            w.frame(&rigid).map_err(frame_failed(rigid.world.steps()))?;
        }
    }
    if let Some(o) = out.as_mut() {
        let text = rigid_json(o, reports)?;
        let end = crate::run_output::RunEnd {
            steps_done: rigid.world.steps(),
            stepped: !reports.is_empty(),
            interrupted: interrupted.is_some(),
        };
        let summary_json = crate::outputs::json(&summary, true)?;
        crate::run_output::finish(o, a, end, || rigid.checkpoint_bytes(), &text, &summary_json)?;
    }
    if a.json {
        println!("{}", crate::outputs::json(&summary, false)?);
    } else {
        println!(
            "{}: {} bodies, {} steps ({:.4} s){}, {:.1} contacts/step, {:.1} sweeps/step, max error {:.2e}, {} / {} steps converged, max penetration {:.2e} m",
            summary.scene,
            summary.bodies,
            summary.steps,
            summary.time,
            if at_rest { " (at rest)" } else { "" },
            summary.mean_contacts,
            summary.mean_sweeps,
            summary.max_error,
            summary.steps - summary.not_converged_steps,
            summary.steps,
            summary.max_penetration
        );
    }
    if let Some(signal) = interrupted {
        match &a.output {
            Some(dir) => eprintln!(
                "interrupted by {} after {} steps: frames, stats.csv, stats.json, summary.json and checkpoint.h5 (resume with --restart) in {} cover those steps",
                signal.name(),
                rigid.world.steps(),
                dir.display()
            ),
            None => eprintln!("interrupted by {} after {} steps", signal.name(), rigid.world.steps()),
        }
        return Ok(Outcome::Interrupted(signal));
    }
    if summary.not_converged_steps > 0 {
        eprintln!(
            "{} step(s) ended above the tolerance {}",
            summary.not_converged_steps, rigid.model.step.tol
        );
        return Ok(Outcome::No);
    }
    if a.until_rest && !at_rest {
        eprintln!("not at rest: --until-rest stopped at its step cap ({max_steps} steps)");
        return Ok(Outcome::No);
    }
    Ok(Outcome::Success)
}
