//! `coulomb simulate`: Moreau–Jean time stepping of one of the granular scenes, with per-step
//! statistics (CSV, JSON), VTK frames for ParaView, checkpoints of the full state
//! (`--checkpoint-every`, `--restart`) and optional FCLIB dumps of each step: the scene built
//! (or a checkpoint loaded) here and stepped by the one run loop, [`crate::run_loop::steps`].

use crate::exit::Outcome;
use crate::run_loop::{self, NoHook};
use crate::sim_args::Args;
use anyhow::{bail, Context};
use coulomb_granular::{Scene, Simulation};

/// Runs `coulomb simulate` in this process, on the scene checked by
/// [`crate::sim_args::checked_scene`] (main.rs hands distributed runs to `simulate_mpi`).
/// SIGINT/SIGTERM stop it after the step in progress, with every output written
/// ([`crate::interrupt`]): exit status 130/143; a step above its tolerance or `--until-rest`
/// at its step cap: 1.
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
    run_loop::steps(&args, sim, scene.name(), false, &[], &mut NoHook)
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
    run_loop::steps(&args, sim, "restart", true, &[], &mut NoHook)
}
