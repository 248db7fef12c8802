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
use crate::run_loop::{self, NoHook, StepHook};
use crate::sim_args::Args;
use anyhow::Context;
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::BuiltScene;
use std::path::{Path, PathBuf};

/// Runs the rigid scene of `scene` with the run settings `a` (the file's, completed by the
/// command line: [`crate::scene_arg`]).
pub fn run(a: &Args, scene: &BuiltScene, inputs: &[PathBuf]) -> anyhow::Result<Outcome> {
    let file = scene.path.display().to_string();
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
    run_loop::steps(a, rigid, &scene.name, false, inputs, &mut Pour::of(scene))
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
    match scene {
        Some(s) => run_loop::steps(a, rigid, &name, true, inputs, &mut Pour::of(s)),
        None => run_loop::steps(a, rigid, &name, true, inputs, &mut NoHook),
    }
}

/// The inlets of a rigid scene file, pouring after each step t_k → t_{k+1} the bodies due in
/// (t_k, t_{k+1}] ([`BuiltScene::pour_rigid`], before the step's frame and checkpoint).
struct Pour {
    /// the scene file, whose inlets pour (none: nothing to do)
    scene: BuiltScene,
    /// bodies poured, and emissions skipped, over the run
    poured: usize,
    skipped: usize,
    /// whether the warning about a full region was said (once per run)
    warned_full: bool,
}

impl Pour {
    fn of(scene: &BuiltScene) -> Self {
        Self {
            scene: scene.clone(),
            poured: 0,
            skipped: 0,
            warned_full: false,
        }
    }
}

impl StepHook<RigidScene> for Pour {
    fn after_step(&mut self, rigid: &mut RigidScene, t0: f64, t1: f64) -> anyhow::Result<()> {
        if self.scene.inlets.is_empty() {
            return Ok(());
        }
        let p = self
            .scene
            .pour_rigid(rigid, t0, t1)
            .with_context(|| format!("{}: inlet at t = {t1}", self.scene.name))?;
        self.poured += p.inserted;
        self.skipped += p.skipped;
        if p.capped > 0 && !self.warned_full {
            self.warned_full = true;
            eprintln!(
                "warning: an inlet's region is full at t = {t1}: {} emission(s) of this step skipped without trying (an inlet adds at most what its region holds per step; lower its rate)",
                p.capped
            );
        }
        Ok(())
    }

    /// The same fields and note as the sphere scenes' inlets.
    fn report(&self) -> (serde_json::Map<String, serde_json::Value>, String) {
        crate::run_loop::inlet_report(!self.scene.inlets.is_empty(), self.poured, self.skipped)
    }
}
