//! `coulomb simulate` distributed over MPI (feature `mpi`): started by `mpirun -np K coulomb
//! simulate …` or `srun -n K coulomb simulate …`, or with `--mpi`. A built-in scene is
//! streamed: every rank draws the same beads one at a time and keeps only those of its slab
//! (memory per rank ∝ N / ranks, [`DistributedSimulation::from_stream`]); a scene file
//! (without inlets, per-pair materials or rolling resistance) is streamed the same way where
//! its spheres can be enumerated one at a time (explicit `spheres` lists, `.csv`/`.npy`
//! sphere files, a first lattice fill: `crate::scene_arg`), else built whole on every rank,
//! which then keeps its slab. The
//! ranks step together ([`coulomb_granular::distributed`], docs/distributed.md); rank 0 prints the summary and writes stats.csv, stats.json (the
//! statistics of `coulomb simulate`), summary.json, distributed.json (per step: sweeps,
//! communication time, ghosts, interface contacts, migration, imbalance of beads and of
//! measured work, whether the bounds were recomputed) and ranks.json (per
//! rank: beads held while building, owned at the start and at the end, peak resident memory);
//! every rank writes its VTK pieces, rank 0 the .pvtp/.pvd collections.

use crate::exit::Outcome;
use crate::progress::bar as progress;
use crate::sim_args::{Args, BalanceArg, Method};
use anyhow::{bail, Context};
use coulomb_granular::distributed::{Balance, Comm, DistributedSimulation, DistributedStats};
use coulomb_granular::output::{write_stats, VtkWriter};
use coulomb_granular::scene::BoxLayout;
use coulomb_granular::{Scene, StepStats, Stop, Summary};

/// Runs `coulomb simulate` of a built-in scene on the ranks of MPI_COMM_WORLD, each rank
/// holding only its part of the beads. Exit status 1 on every rank when `--until-rest`
/// stopped at its step cap without reaching rest (as in one process).
pub fn run(args: Args, scene: Scene) -> anyhow::Result<Outcome> {
    let layout = args.layout()?;
    run_source(&args, Source::Scene(scene, layout), scene.name(), None)
}

/// Runs the world `world` (every rank builds the same, e.g. from a scene file) distributed
/// on the ranks of MPI_COMM_WORLD, `name` its scene's name in the outputs; `universe` is MPI
/// when already initialized (None: initialized here).
pub fn run_world(
    args: &Args,
    world: coulomb_granular::World,
    name: &str,
    universe: Option<Universe>,
) -> anyhow::Result<Outcome> {
    run_source(args, Source::World(world), name, universe)
}

/// Runs the distributed simulation `sim`, built on a communicator of `universe` (e.g.
/// streamed from a scene file), `name` its scene's name in the outputs.
pub fn run_built(
    args: &Args,
    sim: DistributedSimulation,
    name: &str,
    universe: Universe,
) -> anyhow::Result<Outcome> {
    run_source(args, Source::Built(Box::new(sim)), name, Some(universe))
}

/// The MPI environment (finalized when dropped).
pub type Universe = coulomb_granular::distributed::mpi::environment::Universe;

/// MPI initialized, or the error every distributed run gives when it cannot be.
pub fn initialize() -> anyhow::Result<Universe> {
    match coulomb_granular::distributed::mpi::initialize() {
        Some(u) => Ok(u),
        None => bail!("MPI could not be initialized (already initialized?)"),
    }
}

/// Where the beads of a distributed run come from.
enum Source {
    /// a whole world, the same on every rank
    World(coulomb_granular::World),
    /// a built-in scene, streamed (`Args::beads`, `Args::seed`, this layout)
    Scene(Scene, BoxLayout),
    /// a simulation already built (on a communicator of the universe handed with it)
    Built(Box<DistributedSimulation>),
}

/// Peak resident memory of this process (VmHWM of /proc/self/status, KiB); None where the
/// file or the line is missing (not Linux).
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// The memory numbers of one rank (ranks.json and the JSON summary).
#[derive(Debug, Clone, serde::Serialize)]
struct RankMemory {
    rank: usize,
    /// most beads held at once while building the simulation
    held_at_build: usize,
    /// beads owned after building
    beads_start: usize,
    /// beads owned at the end of the run
    beads_end: usize,
    /// peak resident memory at the end of the run (MiB; null where unknown)
    peak_rss_mib: Option<f64>,
}

/// Runs the beads of `source` distributed on the ranks of MPI_COMM_WORLD.
fn run_source(
    args: &Args,
    source: Source,
    name: &str,
    universe: Option<Universe>,
) -> anyhow::Result<Outcome> {
    if args.dump_fclib.is_some() {
        bail!("--dump-fclib is not available in a distributed run");
    }
    if args.method != Method::Nsgs {
        bail!("a distributed run steps with the body-level Gauss–Seidel (--method nsgs) only");
    }
    let universe = match universe {
        Some(u) => u,
        None => initialize()?,
    };
    let comm = Comm::new(universe.world());
    let rank = comm.rank();
    let stop = args.stop();
    let built = match source {
        Source::Built(sim) => Ok(*sim),
        Source::World(world) => {
            DistributedSimulation::new_on(comm, world, args.params(), args.grid)
        }
        Source::Scene(scene, layout) => {
            let (n, seed) = (args.beads, args.seed);
            DistributedSimulation::from_stream_on(
                comm,
                scene.skeleton(seed, &layout),
                args.params(),
                args.grid,
                &|emit| scene.for_each_bead(n, seed, &layout, emit),
            )
        }
    };
    let mut sim = built.context("invalid simulation parameters")?;
    let beads = sim.total_beads();
    let beads_start = sim.beads.len();
    sim.rebalance_every = args.rebalance_every;
    sim.balance = match args.balance {
        Some(BalanceArg::Beads) => Balance::Beads,
        Some(BalanceArg::Work) => Balance::Work,
        None => Balance::default(),
    };
    let mut vtk = match &args.output {
        Some(dir) => Some(
            VtkWriter::new(dir).with_context(|| format!("cannot write into {}", dir.display()))?,
        ),
        None => None,
    };
    let frame = |sim: &mut DistributedSimulation, vtk: &mut Option<VtkWriter>| {
        let failed = match vtk.as_mut() {
            Some(w) => sim.frame(w).err(),
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
    // per rank: beads held while building, owned at the start and the end, peak RSS (−1:
    // unknown), gathered by a sum of vectors zero but for each rank's own entries
    let mut mem = vec![0.0; 4 * ranks];
    mem[4 * rank..4 * rank + 4].copy_from_slice(&[
        sim.held_at_build() as f64,
        beads_start as f64,
        sim.beads.len() as f64,
        peak_rss_kib().map_or(-1.0, |k| k as f64),
    ]);
    sim.comm.sum(&mut mem);
    let per_rank: Vec<RankMemory> = mem
        .chunks_exact(4)
        .enumerate()
        .map(|(r, m)| RankMemory {
            rank: r,
            held_at_build: m[0] as usize,
            beads_start: m[1] as usize,
            beads_end: m[2] as usize,
            peak_rss_mib: (m[3] >= 0.0).then(|| m[3] / 1024.0),
        })
        .collect();
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
    let (imbalance, work_imbalance) = (mean(|s| s.imbalance), mean(|s| s.work_imbalance));
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
        crate::outputs::write(
            &dir.join("ranks.json"),
            crate::outputs::json(&per_rank, true)?.as_bytes(),
        )?;
    }
    if args.json {
        let extra = serde_json::json!({
            "ranks": ranks,
            "mean_sweeps": sweeps,
            "mean_step_ms": step_ms,
            "mean_comm_ms": comm_ms,
            "balance": sim.balance,
            "mean_imbalance": imbalance,
            "mean_work_imbalance": work_imbalance,
            "per_rank": per_rank,
        });
        let extra = extra.as_object().cloned().unwrap_or_default();
        let obj = crate::sim_args::summary_json(&summary, start_energy, end_energy, extra);
        println!("{}", crate::outputs::json(&obj, false)?);
    } else {
        println!(
            "{}: {} beads on {} ranks, {} steps{}, {:.1} contacts/step, {:.1} sweeps/step, {:.2} ms/step ({:.2} ms communication), mean error {:.2e} (max {:.2e}), {} / {} steps converged ({} not converged), max penetration during the run {:.2e} m, at the end: mean {:.2e} m, max {:.2e} m",
            summary.scene,
            summary.bodies,
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
            summary.end_mean_penetration.unwrap_or(0.0),
            summary.end_max_penetration.unwrap_or(0.0)
        );
        let mem: Vec<String> = per_rank
            .iter()
            .map(|m| match m.peak_rss_mib {
                Some(x) => format!("{x:.0}"),
                None => "?".into(),
            })
            .collect();
        let held: Vec<String> = per_rank
            .iter()
            .map(|m| m.held_at_build.to_string())
            .collect();
        println!(
            "per rank: peak resident memory {} MiB, beads held while building {}; imbalance (most loaded rank / mean, mean over the steps) of beads {:.3}, of work {:.3} (balanced by {})",
            mem.join(" / "),
            held.join(" / "),
            imbalance,
            work_imbalance,
            match sim.balance {
                Balance::Beads => "beads",
                Balance::Work => "work",
            }
        );
    }
    Ok(crate::interrupt::simulation_outcome(
        &summary,
        stop.max_steps(),
    ))
}
