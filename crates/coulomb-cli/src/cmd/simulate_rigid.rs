//! `coulomb simulate SCENE.toml` for a scene file with bodies of other shapes than spheres
//! (issue 41): the rigid-body simulator ([`coulomb_granular::rigid_scene::RigidScene`]), with
//! the run options of the sphere path: `--steps` (or the file's), `--until-rest` (every body
//! slower than `rest_speed`, linear and angular speed times the body's size, for 10 steps, at
//! most `max_steps`), `--output` (VTK frames of the bodies as their shapes, contacts and
//! obstacles every `--frames-every` steps; `stats.json`, `stats.csv`, `summary.json`),
//! `--dump-fclib` (each step's problem (2.10) in FCLIB global form), `--checkpoint-every`
//! and `--restart` (a rigid checkpoint, [`coulomb_granular::rigid_checkpoint`]),
//! `--resolve-overlaps` (the bodies moved apart first, [`RigidScene::new_relaxed`]) and `--json`.
//! This file builds the [`RigidScene`] (or loads its checkpoint); the steps, outputs, summary
//! and exit status are those of every scene, [`crate::run_loop::steps`].

use crate::exit::Outcome;
use crate::run_loop::{self, NoHook};
use crate::sim_args::Args;
use anyhow::Context;
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::BuiltScene;
use std::path::{Path, PathBuf};

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
    if !scene.inlets.is_empty() {
        anyhow::bail!(
            "{file}: inlets pour spheres into sphere-only scenes; this scene has other shapes"
        );
    }
    run_loop::steps(a, rigid, &scene.name, false, inputs, &mut NoHook)
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
            if s.model != rigid.model || !s.inlets.is_empty() {
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
    run_loop::steps(a, rigid, &name, true, inputs, &mut NoHook)
}
