//! `coulomb simulate SCENE.toml` (or `.json`): a scene file (docs/granular.md, "Scene
//! files") instead of a built-in scene name. The file gives the spheres, obstacles,
//! materials, gravity and step settings; the command line adds the run's options
//! (`--steps`, `--until-rest`, `--output`, `--frames-every`, `--json`, `--threads`,
//! `--dump-fclib`, the library solver's `--inner`/`--outer`/`--fp-tol`/`--max-outer`/
//! `--max-inner`), `--seed` (when not 1: replaces the file's seed) and `--beads` (when not
//! 150: caps every generated group at that many spheres, for quick trials). Options that the
//! file sets (`--dt`, `--mu`, …) are refused when given, rather than silently ignored.
//! Every error in the file exits with status 2 before anything is written.

use crate::exit::Outcome;
use crate::run_loop::StepHook;
use crate::sim_args::{Args, Method};
use anyhow::{bail, Context};
use clap::Parser;
use coulomb_granular::model::{overlaps, relax, BuildChecks, StepChoice};
use coulomb_granular::scene_file::{BuildOptions, BuiltScene, LoadedScene};
use coulomb_granular::{Simulation, World};
use std::path::Path;

pub use crate::sim_args::is_scene_file;

#[derive(Parser)]
struct Defaults {
    #[command(flatten)]
    args: Args,
}

/// The options a scene file sets that the command line gives (`Args::given`, or a value
/// that differs from the default): refused, since the file's values are used — also when
/// given with the default value (`--tol 1e-4` on a file with `tol = 1e-2` is refused, not
/// dropped).
fn refused_options(args: &Args) -> Vec<&'static str> {
    let Ok(d) = Defaults::try_parse_from(["simulate", "x.toml"]) else {
        return Vec::new();
    };
    let d = d.args;
    let mut out = Vec::new();
    let mut check = |differs: bool, name: &'static str| {
        let id = name.trim_start_matches("--").replace('-', "_");
        if differs || args.given.contains(&id) {
            out.push(name);
        }
    };
    check(args.mu != d.mu, "--mu");
    check(
        args.rolling_friction != d.rolling_friction,
        "--rolling-friction",
    );
    check(args.restitution != d.restitution, "--restitution");
    check(args.dt != d.dt, "--dt");
    check(args.theta != d.theta, "--theta");
    check(args.tol != d.tol, "--tol");
    check(args.method != d.method, "--method");
    check(args.max_sweeps != d.max_sweeps, "--max-sweeps");
    check(args.relaxation != d.relaxation, "--relaxation");
    check(args.gamma != d.gamma, "--gamma");
    check(args.no_projection, "--no-projection");
    check(
        args.projection_velocities.is_some(),
        "--projection-velocities",
    );
    check(args.no_gap_closure, "--no-gap-closure");
    check(args.cold, "--cold");
    check(args.rest_speed != d.rest_speed, "--rest-speed");
    check(args.max_steps != d.max_steps, "--max-steps");
    check(args.box_side.is_some(), "--box-side");
    check(args.layer_pitch.is_some(), "--layer-pitch");
    check(args.drop_base.is_some(), "--drop-base");
    check(args.spread_top, "--spread-top");
    out
}

/// The arguments of a built-in run with the file's step settings and default contact law
/// (so that [`Args::params`] makes the same parameters as for a built-in scene).
fn file_args(args: &Args, scene: &BuiltScene) -> Args {
    let s = &scene.model.step;
    let mut a = args.clone();
    a.dt = s.h;
    a.theta = s.theta;
    a.tol = s.tol;
    a.method = match s.method {
        StepChoice::Nsgs => Method::Nsgs,
        StepChoice::Library => Method::Library,
    };
    a.max_sweeps = s.max_sweeps;
    a.relaxation = s.relaxation;
    a.gamma = s.gamma;
    a.no_projection = !s.projection;
    a.projection_velocities = s
        .projection_velocities
        .map(crate::sim_args::ProjectionVelocities::of);
    a.no_gap_closure = !s.gap_closure;
    a.cold = !s.warm_start;
    let law = scene.model.materials.default;
    a.mu = law.mu;
    a.restitution = law.restitution;
    a.rolling_friction = law.rolling_friction;
    a.rest_speed = scene.step.run.rest_speed;
    a.max_steps = scene.step.run.max_steps;
    a.until_rest = args.until_rest || (scene.step.run.until_rest && args.steps.is_none());
    a.steps = if a.until_rest {
        None
    } else {
        Some(args.steps.unwrap_or_else(|| scene.step.fixed_steps()))
    };
    a
}

/// Refuses a time step in which the smallest sphere of the scene would fall more than its
/// radius (g h² > R_min: contacts cannot be detected), and warns above R_min / 10.
fn check_step(h: f64, scene: &BuiltScene) -> anyhow::Result<()> {
    let r = scene
        .model
        .sphere_batches
        .iter()
        .flat_map(|b| b.radii.iter().copied())
        .chain(scene.inlets.iter().map(|i| i.inlet.sizes.min_radius()))
        .fold(f64::INFINITY, f64::min);
    check_fall(h, r, scene)
}

/// [`check_step`] with `r` the smallest radius of the scene's spheres and inlets.
fn check_fall(h: f64, r: f64, scene: &BuiltScene) -> anyhow::Result<()> {
    let g = scene.model.gravity.norm();
    let fall = g * h * h;
    if r.is_finite() && fall > r {
        bail!(
            "[step] h = {h} is too large: a sphere falls g·h² = {fall:.3e} m in one step, more than the smallest radius {r} m; use h ≤ {:.3e}",
            (r / g).sqrt()
        );
    }
    if r.is_finite() && fall > 0.1 * r {
        eprintln!(
            "warning: [step] h = {h}: a sphere falls g·h² = {fall:.3e} m in one step (> R_min/10 = {:.3e} m); expect large transient penetrations",
            0.1 * r
        );
    }
    Ok(())
}

/// Refuses a time step with which a sphere, at the largest initial speed of the scene's
/// spheres and inlets, could cross a thin wall or a solid obstacle within one step
/// ([`coulomb_granular::tunnelling`]), and warns above half of that.
fn check_travel(h: f64, scene: &BuiltScene, world: &World, file: &str) -> anyhow::Result<()> {
    let (speed, r_min) = coulomb_granular::tunnelling::speed_and_radius(world);
    check_travel_of(h, scene, world, (speed, r_min), file)
}

/// [`check_travel`] with the largest speed and smallest radius of the world's spheres
/// given (`world`'s obstacles only are read).
fn check_travel_of(
    h: f64,
    scene: &BuiltScene,
    world: &World,
    (mut speed, mut r_min): (f64, f64),
    file: &str,
) -> anyhow::Result<()> {
    for i in &scene.inlets {
        let v = i.inlet.velocity;
        speed = speed.max((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt());
        r_min = r_min.min(i.inlet.sizes.min_radius());
    }
    if !r_min.is_finite() {
        return Ok(());
    }
    match coulomb_granular::tunnelling::worst(world, h, speed, r_min) {
        Some(t) if t.ratio() > 1.0 => bail!("{file}: [step] h = {h} is too large: {t}"),
        Some(t) if t.ratio() > 0.5 => {
            eprintln!("warning: {file}: [step] h = {h}: a sphere moves {:.0} % of what crosses obstacle '{}' in one step; {t}", 100.0 * t.ratio(), t.obstacle);
            Ok(())
        }
        _ => Ok(()),
    }
}

/// The world of `scene` with its initial overlaps relaxed by at most `sweeps` sweeps of
/// [`resolve_overlaps`], then checked as usual (an overlap left is refused, with its count).
fn relaxed(scene: &BuiltScene, sweeps: usize, file: &str) -> anyhow::Result<World> {
    let unchecked = BuildChecks {
        overlaps: false,
        containment: false,
        ..BuildChecks::default()
    };
    let (mut world, _) = scene.build(&unchecked)?;
    let before = overlaps(&world);
    let relaxed = relax(&mut world, sweeps);
    if before.count > 0 {
        let (done, left) = match &relaxed {
            Ok(r) => (r.done.sweeps, 0),
            Err(_) => (sweeps, overlaps(&world).count),
        };
        eprintln!(
            "{file}: {} overlaps at the start (worst {:.3e} m) relaxed in {done} sweeps, {left} left",
            before.count, before.worst
        );
    }
    relaxed?;
    Ok(world)
}

/// Refuses `--beads` and `--seed` where they cannot apply: `--beads` caps the spheres of a
/// scene file's fills, `--seed` replaces the seed of its fills and inlets; a file without
/// them would silently ignore the option.
fn refuse_unused_generators(args: &Args, scene: &BuiltScene, file: &str) -> anyhow::Result<()> {
    if args.beads != 150 && scene.fills.is_empty() {
        bail!(
            "--beads caps the spheres of a scene file's fills; {file} has no fill (its spheres are listed or read from files): remove --beads"
        );
    }
    if args.seed != 1 && scene.fills.is_empty() && scene.inlets.is_empty() {
        bail!(
            "--seed replaces the seed of a scene file's fills and inlets; {file} has neither: remove --seed"
        );
    }
    Ok(())
}

/// Runs `coulomb simulate FILE`.
pub fn run(args: &Args) -> anyhow::Result<Outcome> {
    let refused = refused_options(args);
    if !refused.is_empty() {
        bail!(
            "{} {} set by the scene file {} ([step], [default_pair]); change them there",
            refused.join(", "),
            if refused.len() == 1 { "is" } else { "are" },
            args.scene.as_deref().unwrap_or_default()
        );
    }
    let file = args.scene.as_deref().unwrap_or_default();
    args.check_coarse()?;
    let loaded = LoadedScene::load(Path::new(file))?;
    let opts = BuildOptions {
        seed: (args.seed != 1).then_some(args.seed),
        max_fill: (args.beads != 150).then_some(args.beads),
    };
    #[cfg(feature = "mpi")]
    let mut universe = None;
    #[cfg(feature = "mpi")]
    if (args.mpi || crate::sim_args::under_launcher())
        && args.resolve_overlaps.is_none()
        && std::env::var_os(WHOLE_BUILD).is_none()
    {
        match streamed(args, &loaded, &opts, file)? {
            Ok(outcome) => return Ok(outcome),
            Err(u) => universe = u,
        }
    }
    let mut scene = loaded.build(&opts)?;
    refuse_unused_generators(args, &scene, file)?;
    if scene.runs_rigid() {
        #[cfg(feature = "mpi")]
        if args.mpi || crate::sim_args::under_launcher() {
            bail!("{file}: scenes with bodies of other shapes than spheres, joints or an inlet pouring another shape run in the rigid-body simulator, in one process, not distributed");
        }
        if args.subspace_every > 0
            || args.coarse_every > 0
            || args.coarse_cell > 0
            || args.coarse_smooth > 0
        {
            bail!(
                "{file}: --subspace-every and --coarse-every (--coarse-cell, --coarse-smooth) act on the sphere engine's Gauss–Seidel; this scene has bodies of other shapes"
            );
        }
        return crate::cmd::simulate_rigid::run(
            &file_args(args, &scene),
            &scene,
            &loaded.input_files(),
        );
    }
    let world = match args.resolve_overlaps {
        None => scene.build(&BuildChecks::default())?.0,
        Some(sweeps) => relaxed(&scene, sweeps, file)?,
    };
    if world.bodies.is_empty() && scene.inlets.is_empty() {
        bail!("{file}: the scene has no sphere and no inlet");
    }
    let a = file_args(args, &scene);
    check_step(a.dt, &scene)?;
    check_travel(a.dt, &scene, &world, file)?;
    if a.outer == coulomb::OuterKind::Fused && a.inner != coulomb::InnerKind::Pgs {
        bail!("--outer fused needs --inner pgs");
    }
    #[cfg(feature = "mpi")]
    if a.mpi || crate::sim_args::under_launcher() {
        if !scene.inlets.is_empty() {
            bail!("{file}: a scene with inlets runs in one process, not distributed");
        }
        if a.checkpoint_every > 0 {
            bail!("--checkpoint-every is not supported by distributed runs");
        }
        // per-pair materials and rolling resistance are refused by the distributed step
        return crate::cmd::simulate_mpi::run_world(&a, world, &scene.name, universe);
    }
    let sim = Simulation::new(world, a.params()).context("invalid simulation parameters")?;
    let mut inlets = Inlets {
        scene: &mut scene,
        poured: 0,
        skipped: 0,
        warned_full: false,
    };
    let name = inlets.scene.name.clone();
    let inputs = loaded.input_files();
    crate::run_loop::steps(&a, sim, &name, false, &inputs, &mut inlets)
}

/// Environment variable that, set, makes a distributed run build a scene file whole on every
/// rank even where it could be streamed (the comparison of the two paths in the tests).
#[cfg(feature = "mpi")]
pub const WHOLE_BUILD: &str = "COULOMB_WHOLE_BUILD";

/// A distributed run of a scene file streamed ([`LoadedScene::for_each_sphere`] into
/// [`DistributedSimulation::from_stream_on`]): every rank enumerates the file's spheres and
/// keeps those of its cell, never holding the others; the same beads, ids, owners and
/// results as the whole build ([`crate::cmd::simulate_mpi::run_world`]) and the same
/// refusals, in the same order: the file's checks ([`LoadedScene::build_skeleton`]), each
/// sphere's validity and containment and the memory estimate (every rank sees every
/// sphere, so all decide alike), the overlaps (each rank counts those among its beads and
/// the beads within 2 R_max of its cell, [`DistributedSimulation::halo_overlaps`], and the
/// counts are summed, so every pair is seen and every rank decides alike), then the checks
/// of the step and travel and the options. `Err` where the whole build must run instead,
/// with MPI when it was initialized here: a file that cannot be streamed, or any of these
/// checks failing (the whole build then refuses the file with today's error).
#[cfg(feature = "mpi")]
fn streamed(
    args: &Args,
    loaded: &LoadedScene,
    opts: &BuildOptions,
    file: &str,
) -> anyhow::Result<Result<Outcome, Option<crate::cmd::simulate_mpi::Universe>>> {
    use coulomb_granular::distributed::{Comm, DistributedSimulation};
    use coulomb_granular::model::{available_memory, check_memory, contained};
    use coulomb_granular::world::Sphere;
    let Ok(scene) = loaded.build_skeleton(opts) else {
        return Ok(Err(None));
    };
    let law = scene.model.materials.default;
    if scene.model.has_shapes()
        || !scene.inlets.is_empty()
        || !scene.model.materials.pairs.is_empty()
        || law.rolling_friction != 0.0
        || !scene.model.sphere_batches.is_empty()
    {
        return Ok(Err(None));
    }
    let Ok((skeleton, _)) = scene.build(&BuildChecks::default()) else {
        return Ok(Err(None));
    };
    // every rank sees every sphere: validity, containment, count, speed and radius
    let (mut inside, mut speed, mut r_min) = (true, 0.0f64, f64::INFINITY);
    let count = loaded.for_each_sphere(opts, &mut |s: Sphere| {
        inside &= contained(&skeleton.obstacles, s.position);
        speed = speed.max(s.velocity.norm());
        r_min = r_min.min(s.radius);
    });
    let Some(n) = count else {
        return Ok(Err(None));
    };
    let memory = check_memory(n, scene.model.triangle_count(), available_memory());
    if !inside || n == 0 || memory.is_err() {
        return Ok(Err(None));
    }
    let a = file_args(args, &scene);
    let universe = crate::cmd::simulate_mpi::initialize()?;
    let stream = |emit: &mut dyn FnMut(Sphere)| {
        let _ = loaded.for_each_sphere(opts, emit);
    };
    let comm = Comm::new(universe.world());
    let built =
        DistributedSimulation::from_stream_on(comm, skeleton.clone(), a.params(), a.grid, &stream);
    // the errors of the build are the same on every rank (every rank saw every bead)
    let Ok(mut sim) = built else {
        return Ok(Err(Some(universe)));
    };
    let mut overlapping = [sim.halo_overlaps(&stream) as f64];
    sim.comm.sum(&mut overlapping);
    if overlapping[0] > 0.0 {
        drop(sim);
        return Ok(Err(Some(universe)));
    }
    // the checks the whole build runs after the world's, in its order
    check_fall(a.dt, r_min, &scene)?;
    check_travel_of(a.dt, &scene, &skeleton, (speed, r_min), file)?;
    if a.outer == coulomb::OuterKind::Fused && a.inner != coulomb::InnerKind::Pgs {
        bail!("--outer fused needs --inner pgs");
    }
    if a.checkpoint_every > 0 {
        bail!("--checkpoint-every is not supported by distributed runs");
    }
    crate::cmd::simulate_mpi::run_built(&a, sim, &scene.name, universe).map(Ok)
}

/// `coulomb simulate SCENE.toml --restart FILE`: the run stored in FILE continued as
/// [`crate::cmd::simulate::restart`] does, with the inlets of the scene file pouring. An
/// inlet's emissions are a pure function of (seed, emission index, time) and of the bodies
/// present ([`coulomb_granular::generate::Inlet`]), so the continued run is the uninterrupted
/// one to the bit. The file must be the stored run's: its gravity and obstacles are compared
/// with the checkpoint's, and a difference is refused (status 2).
pub fn restart(args: &Args) -> anyhow::Result<Outcome> {
    let file = args.scene.as_deref().unwrap_or_default();
    let Some(checkpoint) = args.restart.as_deref() else {
        bail!("--restart needs a checkpoint file");
    };
    if crate::cmd::simulate_rigid::is_rigid_checkpoint(checkpoint) {
        let loaded = LoadedScene::load(Path::new(file))?;
        let scene = loaded.build(&BuildOptions::default())?;
        return crate::cmd::simulate_rigid::restart(
            args,
            checkpoint,
            Some(&scene),
            &loaded.input_files(),
        );
    }
    let sim = Simulation::load_checkpoint(checkpoint)
        .with_context(|| format!("cannot restart from {}", checkpoint.display()))?;
    let loaded = LoadedScene::load(Path::new(file))?;
    let mut scene = loaded.build(&BuildOptions::default())?;
    let unchecked = BuildChecks {
        overlaps: false,
        containment: false,
        ..BuildChecks::default()
    };
    let (world, _) = scene.build(&unchecked)?;
    if world.gravity != sim.world.gravity || world.obstacles != sim.world.obstacles {
        bail!(
            "{file} is not the scene of the checkpoint {}: its gravity or obstacles differ",
            checkpoint.display()
        );
    }
    let mut inlets = Inlets {
        scene: &mut scene,
        poured: 0,
        skipped: 0,
        warned_full: false,
    };
    let name = inlets.scene.name.clone();
    let inputs = loaded.input_files();
    crate::run_loop::steps(args, sim, &name, true, &inputs, &mut inlets)
}

/// The inlets of a scene file, driven after each step: the spheres they owe for
/// (t_k, t_{k+1}] placed among the bodies at t_{k+1}.
struct Inlets<'a> {
    scene: &'a mut BuiltScene,
    poured: usize,
    skipped: usize,
    /// whether the warning of a full region was printed
    warned_full: bool,
}

impl StepHook<Simulation> for Inlets<'_> {
    fn after_step(&mut self, sim: &mut Simulation, t0: f64, t1: f64) -> anyhow::Result<()> {
        let model = &self.scene.model;
        for (j, inlet) in self.scene.inlets.iter_mut().enumerate() {
            let before = inlet.capped;
            let (n, k) = inlet.emit(sim, model, t0, t1).context("inlet")?;
            self.poured += n;
            self.skipped += k;
            if inlet.capped > before && !self.warned_full {
                self.warned_full = true;
                eprintln!(
                    "warning: inlet {} at t = {t1}: its region is full; {} emission(s) of this step skipped without trying (an inlet adds at most what its region holds per step; lower its rate)",
                    j + 1,
                    inlet.capped - before
                );
            }
        }
        Ok(())
    }

    fn report(&self) -> (serde_json::Map<String, serde_json::Value>, String) {
        crate::run_loop::inlet_report(!self.scene.inlets.is_empty(), self.poured, self.skipped)
    }
}

/// The stop rule of a file run (for tests).
#[cfg(test)]
fn stop_of(args: &Args, scene: &BuiltScene) -> coulomb_granular::Stop {
    file_args(args, scene).stop()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(extra: &[&str]) -> Args {
        let mut v = vec!["simulate", "x.toml"];
        v.extend_from_slice(extra);
        use clap::{CommandFactory, FromArgMatches};
        let m = Defaults::command().try_get_matches_from(v).unwrap();
        let mut a = Defaults::from_arg_matches(&m).unwrap().args;
        a.given = crate::sim_args::given_options(&m);
        a
    }

    #[test]
    fn scene_files_are_recognised_by_extension() {
        assert!(is_scene_file("a/b.toml") && is_scene_file("B.JSON"));
        assert!(!is_scene_file("box") && !is_scene_file("box.csv"));
    }

    #[test]
    fn options_the_file_sets_are_refused() {
        assert!(refused_options(&args(&[])).is_empty());
        assert!(refused_options(&args(&["--steps", "3", "--json", "--seed", "4"])).is_empty());
        assert_eq!(refused_options(&args(&["--dt", "0.01"])), vec!["--dt"]);
        assert_eq!(
            refused_options(&args(&["--mu", "0.5", "--cold"])),
            vec!["--mu", "--cold"]
        );
        // given with the default value: still the file's setting, so refused, not dropped
        assert_eq!(refused_options(&args(&["--tol", "1e-4"])), vec!["--tol"]);
        assert_eq!(
            refused_options(&args(&["--method", "nsgs", "--max-sweeps", "20000"])),
            vec!["--method", "--max-sweeps"]
        );
    }

    #[test]
    fn steps_come_from_the_file_unless_given() {
        let text = "[step]\nh = 0.01\nduration = 0.1\n[[bodies]]\nspheres = [[0, 0, 1, 0.1]]\n";
        let loaded = LoadedScene::parse(Path::new("x.toml"), text.to_string(), true).unwrap();
        let scene = loaded.build(&BuildOptions::default()).unwrap();
        assert_eq!(
            stop_of(&args(&[]), &scene),
            coulomb_granular::Stop::Steps(10)
        );
        assert_eq!(
            stop_of(&args(&["--steps", "3"]), &scene),
            coulomb_granular::Stop::Steps(3)
        );
        assert!(matches!(
            stop_of(&args(&["--until-rest"]), &scene),
            coulomb_granular::Stop::UntilRest { .. }
        ));
        assert_eq!(file_args(&args(&[]), &scene).dt, 0.01);
    }
}
