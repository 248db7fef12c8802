//! The arguments of `coulomb simulate` (shared by its single-process and MPI runs, and read
//! by `coulomb validate` for their defaults), what they make (the simulation parameters, the
//! box layout, the stop rule, the scene), and the JSON summary line of a run.

use anyhow::bail;
use coulomb::{InnerKind, OuterKind, Settings};
use coulomb_granular::scene::BoxLayout;
use coulomb_granular::{
    Activation, NsgsSettings, Params, Projection, Scene, StepMethod, Stop, Summary, Velocities,
};
use std::path::PathBuf;

/// The solver of each step.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// body-level nonsmooth Gauss–Seidel, matrix-free, parallel over a colouring of the
    /// contacts (docs/scaling.md)
    Nsgs,
    /// the library's solver (`--inner`, `--outer`) on the assembled problem
    Library,
}

/// What the position correction does to velocities (`--projection-velocities`).
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProjectionVelocities {
    /// v and ω scaled by √(1 − ΔE_p / E_k)
    Rescale,
    /// velocities untouched
    PositionsOnly,
    /// Moreau's inelastic velocity projection on the corrected contacts
    Inelastic,
}

impl ProjectionVelocities {
    /// The library's setting.
    pub fn velocities(self) -> Velocities {
        match self {
            Self::Rescale => Velocities::Rescale,
            Self::PositionsOnly => Velocities::PositionsOnly,
            Self::Inelastic => Velocities::Inelastic,
        }
    }
    /// The option's value for a library setting.
    pub fn of(v: Velocities) -> Self {
        match v {
            Velocities::Rescale => Self::Rescale,
            Velocities::PositionsOnly => Self::PositionsOnly,
            Velocities::Inelastic => Self::Inelastic,
        }
    }
}

/// The options that a checkpoint fixes (the parameters): refused with --restart. A scene is
/// refused too, unless it is the scene file of the stored run (its inlets continue).
const RESTART_CONFLICTS: [&str; 30] = [
    "beads",
    "mu",
    "rolling_friction",
    "restitution",
    "dt",
    "theta",
    "method",
    "max_sweeps",
    "relaxation",
    "subspace_every",
    "coarse_every",
    "coarse_cell",
    "coarse_smooth",
    "inner",
    "outer",
    "tol",
    "fp_tol",
    "max_outer",
    "max_inner",
    "gamma",
    "no_projection",
    "projection_velocities",
    "no_gap_closure",
    "cold",
    "seed",
    "box_side",
    "layer_pitch",
    "drop_base",
    "spread_top",
    "resolve_overlaps",
];

/// Arguments of `coulomb simulate`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// scene: box, funnel, vibrating-plate, rotating-drum, or a scene file ending in .toml or
    /// .json (docs/granular.md, "Scene files"; examples in examples/scenes); with --restart,
    /// none or the scene file of the stored run (whose inlets then keep pouring)
    #[arg(required_unless_present = "restart")]
    pub scene: Option<String>,
    /// number of beads
    #[arg(long, default_value_t = 150, value_parser = crate::values::beads)]
    pub beads: usize,
    /// friction coefficient μ
    #[arg(long, default_value_t = 0.3, value_parser = crate::values::nonnegative)]
    pub mu: f64,
    /// rolling-friction coefficient μ_r (dimensionless): rolling torque ≤ μ_r R_e r_N, R_e the
    /// effective radius (docs/granular.md, "Rolling resistance"); 0 (default): none
    #[arg(long, default_value_t = 0.0, value_parser = crate::values::nonnegative)]
    pub rolling_friction: f64,
    /// restitution coefficient e (Moreau's impact law)
    #[arg(long, default_value_t = 0.2, value_parser = crate::values::unit_interval)]
    pub restitution: f64,
    /// time step h (s)
    #[arg(long, default_value_t = 0.02, value_parser = crate::values::positive)]
    pub dt: f64,
    /// θ of the position update (2.7)
    #[arg(long, default_value_t = 0.5, value_parser = crate::values::unit_interval)]
    pub theta: f64,
    /// number of steps (default 200 unless --until-rest)
    #[arg(long, conflicts_with = "until_rest", value_parser = crate::values::count)]
    pub steps: Option<usize>,
    /// run until every bead moves slower than --rest-speed for 10 steps
    #[arg(long)]
    pub until_rest: bool,
    /// rest speed threshold (m/s) of --until-rest
    #[arg(long, default_value_t = 0.05, value_parser = crate::values::positive)]
    pub rest_speed: f64,
    /// step cap of --until-rest
    #[arg(long, default_value_t = 2000, value_parser = crate::values::count)]
    pub max_steps: usize,
    /// step solver: body-level Gauss–Seidel (default) or the library's solver with
    /// --inner/--outer
    #[arg(long, value_enum, default_value_t = Method::Nsgs)]
    pub method: Method,
    /// cap on Gauss–Seidel sweeps per step (--method nsgs)
    #[arg(long, default_value_t = 20_000, value_parser = crate::values::count)]
    pub max_sweeps: usize,
    /// over-relaxation ω ∈ [1, 2) of the Gauss–Seidel updates (--method nsgs; reduced
    /// towards 1 automatically when it does not help)
    #[arg(long, default_value_t = 1.5, value_parser = crate::values::relaxation)]
    pub relaxation: f64,
    /// every K Gauss–Seidel sweeps, a subspace minimization: one sparse Cholesky solve on
    /// the sweeps' stick / slip / separation pattern, kept only if the step's error
    /// decreased (--method nsgs; docs/scaling.md, "Depth"); 0: never
    #[arg(long, default_value_t = 0, value_parser = crate::values::count0)]
    pub subspace_every: usize,
    /// every K Gauss–Seidel sweeps, a two-level (coarse) correction: one Galerkin solve of
    /// 3 unknowns per layer of the contact graph (or per interface, --coarse-cell), kept only
    /// if the step's error decreased
    /// (--method nsgs; docs/scaling.md, "Depth"); 0: never
    #[arg(long, default_value_t = 0, value_parser = crate::values::count0)]
    pub coarse_every: usize,
    /// the coarse space of --coarse-every: 0 (default), the layers of the contact graph;
    /// k ≥ 1, one impulse per interface between aggregates of the beads in cells of a grid of
    /// side k bead diameters (docs/scaling.md, "Depth: aggregates of a coarse grid"); needs
    /// --coarse-every
    #[arg(long, default_value_t = 0, value_parser = crate::values::count0)]
    pub coarse_cell: usize,
    /// damped-Jacobi smoothing steps of the coarse prolongation of --coarse-every (smoothed
    /// aggregation); 0 (default): none; needs --coarse-every
    #[arg(long, default_value_t = 0, value_parser = crate::values::count0)]
    pub coarse_smooth: usize,
    /// worker threads (default: all cores); results do not depend on it
    #[arg(long, value_parser = crate::values::threads)]
    pub threads: Option<usize>,
    /// inner solver of --method library (default: Gauss–Seidel, the fastest to 1e-4 on the
    /// box scene, see docs/granular.md)
    #[arg(long, default_value_t = InnerKind::Pgs, value_parser = crate::method::inner())]
    pub inner: InnerKind,
    /// outer iteration (default: Gauss–Seidel fused with the law; apgd + Anderson as fallback)
    #[arg(long, default_value_t = OuterKind::Fused, value_parser = crate::method::outer())]
    pub outer: OuterKind,
    /// tolerance on the error of docs/error.md, reached at every step (steps that do not
    /// reach it are counted and reported)
    #[arg(long, default_value_t = 1e-4, value_parser = crate::values::tolerance)]
    pub tol: f64,
    /// ε of the paper's outer stopping rule (6.1); 0 (default) disables it, so that every
    /// step is solved to --tol
    #[arg(long, default_value_t = 0.0, value_parser = crate::values::nonnegative)]
    pub fp_tol: f64,
    /// cap on outer (fixed-point) iterations per step
    #[arg(long, default_value_t = 20, value_parser = crate::values::count)]
    pub max_outer: usize,
    /// cap on inner iterations per subproblem (default: the solver's)
    #[arg(long, value_parser = crate::values::count)]
    pub max_inner: Option<usize>,
    /// γ of the activation rule g + γ h min(u_N, 0) ≤ δ (docs/granular.md)
    #[arg(long, default_value_t = 1.0, value_parser = crate::values::nonnegative)]
    pub gamma: f64,
    /// no position correction (the plain Moreau–Jean scheme: penetrations stay)
    #[arg(long)]
    pub no_projection: bool,
    /// what the position correction does to the velocities of the beads it moves: rescale
    /// (default: v, ω scaled to pay the lift's potential energy; its momentum change carries
    /// some weight), positions-only, or inelastic (Moreau's inelastic velocity projection on
    /// the corrected contacts, its impulses added to the exported ones); docs/granular.md,
    /// "Position correction"
    #[arg(long, value_enum, conflicts_with = "no_projection")]
    pub projection_velocities: Option<ProjectionVelocities>,
    /// no gap closure: a sphere at rest may stay up to h² g above an obstacle, held by the
    /// activation rule's look-ahead (docs/granular.md, "Resting on an obstacle")
    #[arg(long)]
    pub no_gap_closure: bool,
    /// disable warm starts
    #[arg(long)]
    pub cold: bool,
    /// seed of the initial arrangement
    #[arg(long, default_value_t = 1, value_parser = crate::values::seed)]
    pub seed: u64,
    /// box scene: side of the square floor (m), instead of the calibrated one
    #[arg(long, value_parser = crate::values::positive)]
    pub box_side: Option<f64>,
    /// box scene: vertical pitch of the initial lattice (m), instead of the calibrated one
    #[arg(long, value_parser = crate::values::positive)]
    pub layer_pitch: Option<f64>,
    /// box scene: height of the lowest initial layer's centres (m), instead of the calibrated one
    #[arg(long, value_parser = crate::values::positive)]
    pub drop_base: Option<f64>,
    /// box scene: spread the partial top layer over the whole floor at random sites (the
    /// heap structure of `paper scaling --accurate`, docs/scaling.md)
    #[arg(long)]
    pub spread_top: bool,
    /// scene files: relax the bodies that overlap at the start (or sit in an obstacle) by at
    /// most this many Gauss–Seidel sweeps, instead of refusing them (spheres: pairwise
    /// separation, `coulomb_granular::model::relax`; other shapes: the rigid step's position
    /// correction, `RigidWorld::relaxed`); the run is refused if overlaps remain
    #[arg(long, value_name = "SWEEPS", num_args = 0..=1, default_missing_value = "1000")]
    pub resolve_overlaps: Option<usize>,
    /// output folder: stats.csv, stats.json, summary.json, bodies.pvd, contacts.pvd, frames/
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// write a VTK frame every K steps (with --output)
    #[arg(long, default_value_t = 10, value_parser = crate::values::count0)]
    pub frames_every: usize,
    /// write OUTPUT/checkpoint.h5, the full state of the run (docs/granular.md, "Checkpoint
    /// and restart"), every K steps and at the end (replaced atomically each time; 0: never;
    /// needs --output)
    #[arg(long, default_value_t = 0, value_parser = crate::values::count0, requires = "output")]
    pub checkpoint_every: usize,
    /// continue the run stored in this checkpoint file (written by --checkpoint-every or by
    /// Python's save_checkpoint): the scene, its state and every parameter come from the file,
    /// --steps counts the steps to add to the stored ones, and the stats files of --output
    /// continue those found there; give the run's scene file too to keep its inlets pouring
    #[arg(long, conflicts_with_all = RESTART_CONFLICTS)]
    pub restart: Option<PathBuf>,
    /// write each step's problem as an FCLIB global file into this folder
    #[arg(long)]
    pub dump_fclib: Option<PathBuf>,
    /// print one JSON summary object (no progress bar)
    #[arg(long)]
    pub json: bool,
    /// run distributed over MPI (automatic when started by mpirun/srun; docs/distributed.md)
    #[cfg(feature = "mpi")]
    #[arg(long)]
    pub mpi: bool,
    /// distributed run: recompute the slab bounds every K steps (0: only at the start)
    #[cfg(feature = "mpi")]
    #[arg(long, default_value_t = 20, value_parser = crate::values::count0)]
    pub rebalance_every: usize,
    /// distributed run: a PXxPY grid of subdomains (PX along x, PY along y, PX·PY = ranks)
    /// instead of slabs along the wider axis, e.g. --grid 2x2 on 4 ranks
    #[cfg(feature = "mpi")]
    #[arg(long, value_parser = crate::values::grid, value_name = "PXxPY")]
    pub grid: Option<[usize; 2]>,
    /// distributed run: what a rebalance equalises across the ranks, the measured work
    /// (contact updates of the beads' contacts in the sweeps, plus a fixed cost per bead;
    /// the default) or the bead counts (docs/distributed.md)
    #[cfg(feature = "mpi")]
    #[arg(long, value_enum, value_name = "WHAT")]
    pub balance: Option<BalanceArg>,
    /// the ids of the options given on the command line ([`given_options`], set by `main`),
    /// so that an option a scene file sets is refused even when given with its default value
    #[arg(skip)]
    pub given: Vec<String>,
}

/// The ids of the arguments of `m` given on the command line (not defaulted).
pub fn given_options(m: &clap::ArgMatches) -> Vec<String> {
    m.ids()
        .filter(|id| m.value_source(id.as_str()) == Some(clap::parser::ValueSource::CommandLine))
        .map(|id| id.as_str().to_string())
        .collect()
}

/// `--balance`: what the rebalancing of a distributed run equalises.
#[cfg(feature = "mpi")]
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum BalanceArg {
    /// the bead counts (the slabs of the first distributed version, to the bit)
    Beads,
    /// the work measured since the last rebalance (counts of contact updates, deterministic)
    Work,
}

impl Args {
    pub(crate) fn params(&self) -> Params {
        Params {
            h: self.dt,
            theta: self.theta,
            restitution: self.restitution,
            mu: self.mu,
            activation: Activation {
                gamma: self.gamma,
                close_gaps: !self.no_gap_closure,
                ..Activation::accurate()
            },
            solver: Settings {
                outer: self.outer,
                // a step the first method does not bring to --tol gets a second one
                fallback: Some(if self.outer == OuterKind::Fused {
                    (InnerKind::Apgd, OuterKind::Anderson)
                } else {
                    (InnerKind::Pgs, OuterKind::Fused)
                }),
                ..crate::method::time_stepping_settings(
                    self.inner,
                    self.tol,
                    self.fp_tol,
                    self.max_outer,
                    self.max_inner,
                )
            },
            warm_start: !self.cold,
            projection: (!self.no_projection).then(|| Projection {
                velocities: self
                    .projection_velocities
                    .map_or(Velocities::Rescale, ProjectionVelocities::velocities),
                ..Projection::default()
            }),
            method: match self.method {
                Method::Nsgs => StepMethod::Nsgs(NsgsSettings {
                    tol: self.tol,
                    max_sweeps: self.max_sweeps,
                    relaxation: self.relaxation,
                    subspace_every: self.subspace_every,
                    coarse_every: self.coarse_every,
                    coarse_cell: self.coarse_cell,
                    coarse_smooth: self.coarse_smooth,
                    time_limit: Some(step_time_limit(self.beads)),
                    ..NsgsSettings::default()
                }),
                Method::Library => StepMethod::Library,
            },
            rolling_friction: self.rolling_friction,
        }
    }

    /// Refuses time steps for which the activation rule cannot work and warns about risky
    /// ones: in one step a bead at rest free-falls g h² (velocity g h, moved ½ g h² … g h²
    /// by the θ-method); above R the linear gap prediction misses contacts entirely (beads
    /// pass through each other and through walls); above R/10 penetrations before the
    /// position correction reach tens of % of R.
    pub(crate) fn check_step(&self) -> anyhow::Result<()> {
        let h = self.dt;
        if !(h.is_finite() && h > 0.0) {
            bail!("--dt {h} must be a positive number of seconds");
        }
        let r = coulomb_granular::scene::BEAD_RADIUS;
        let g = coulomb_granular::world::GRAVITY;
        let fall = g * h * h;
        if fall > r {
            bail!(
                "--dt {h} is too large: a bead falls g·h² = {fall:.3} m in one step, more than its radius {r} m, so contacts cannot be detected or activated; use --dt ≤ {:.4}",
                (r / g).sqrt()
            );
        }
        if fall > 0.1 * r {
            eprintln!(
                "warning: --dt {h}: a bead falls g·h² = {fall:.4} m in one step (> R/10); expect large transient penetrations; --dt ≤ {:.4} is advised",
                (0.1 * r / g).sqrt()
            );
        }
        if !(self.fp_tol.is_finite() && self.fp_tol >= 0.0) {
            bail!("--fp-tol {} must be a finite number ≥ 0", self.fp_tol);
        }
        if self.outer == OuterKind::Fused && self.inner != InnerKind::Pgs {
            bail!("--outer fused needs --inner pgs");
        }
        self.check_coarse()
    }

    /// Refuses the coarse space's options without the coarse correction they shape.
    pub(crate) fn check_coarse(&self) -> anyhow::Result<()> {
        if self.coarse_every == 0 {
            for (value, name) in [
                (self.coarse_cell, "--coarse-cell"),
                (self.coarse_smooth, "--coarse-smooth"),
            ] {
                if value > 0 {
                    bail!("{name} {value} shapes the coarse correction of --coarse-every, which is off (0)");
                }
            }
        }
        Ok(())
    }
    /// The box layout: the calibrated one for `--beads`, with the command line's overrides.
    pub(crate) fn layout(&self) -> anyhow::Result<BoxLayout> {
        let mut l = BoxLayout::for_beads(self.beads);
        let r = coulomb_granular::scene::BEAD_RADIUS;
        if let Some(x) = self.box_side {
            if !(x.is_finite() && x >= 2.5 * r && x <= 1e4) {
                bail!("--box-side {x} must be in [{}, 10000] m", 2.5 * r);
            }
            l.side_x = x;
            l.side_y = x;
        }
        if let Some(x) = self.layer_pitch {
            if !(x.is_finite() && x >= 2.5 * r && x <= 100.0) {
                bail!("--layer-pitch {x} must be in [{}, 100] m", 2.5 * r);
            }
            l.layer_pitch = x;
        }
        if let Some(x) = self.drop_base {
            if !(x.is_finite() && x >= 1.25 * r && x <= 1000.0) {
                bail!("--drop-base {x} must be in [{}, 1000] m", 1.25 * r);
            }
            l.base = x;
        }
        Ok(l)
    }
    /// The stop rule of a new run.
    #[cfg(any(feature = "mpi", test))]
    pub(crate) fn stop(&self) -> Stop {
        self.stop_after(0)
    }
    /// The stop rule of a run that starts after `done` steps (a restart): its step counts
    /// (--steps, --max-steps) are added to `done`.
    pub(crate) fn stop_after(&self, done: usize) -> Stop {
        if self.until_rest {
            Stop::UntilRest {
                speed: self.rest_speed,
                window: 10,
                max_steps: done.saturating_add(self.max_steps),
            }
        } else {
            Stop::Steps(done.saturating_add(self.steps.unwrap_or(200)))
        }
    }
}

/// The checked scene of `args`: a known name, 1 ≤ beads ≤ 10⁶, a usable time step.
pub(crate) fn checked_scene(args: &Args) -> anyhow::Result<Scene> {
    let name = args.scene.as_deref().unwrap_or_default();
    let Some(scene) = Scene::from_name(name) else {
        let names: Vec<&str> = Scene::ALL.iter().map(|s| s.name()).collect();
        bail!(
            "unknown scene '{name}': expected one of {}, or a scene file (.toml, .json)",
            names.join(", ")
        );
    };
    if args.beads == 0 {
        bail!("--beads must be positive");
    }
    if args.beads > 1_000_000 {
        bail!("--beads {} is above the limit of 1000000", args.beads);
    }
    check_beads_fit(args.beads, coulomb_granular::model::available_memory())?;
    args.check_step()?;
    Ok(scene)
}

/// The wall-clock cap of one step's Gauss–Seidel solve for a scene of `beads` beads: 60 s
/// (`NsgsSettings::default`) up to 120 000 beads, then 0.5 ms per bead (500 s at 10⁶). A
/// sweep costs about 0.3 µs per contact on one core (≈ 1 contact per bead), so a 10⁶-bead
/// step gets some 1 600 sweeps of one core before the cap; with 60 s it got ~50 on a loaded
/// machine and stopped unconverged (docs/scaling.md, "A million beads"). The sweep cap
/// (`--max-sweeps`) bounds the step whatever the clock.
pub(crate) fn step_time_limit(beads: usize) -> std::time::Duration {
    std::time::Duration::from_secs_f64((beads as f64 * 5e-4).max(60.0))
}

/// Refuses, before anything is built, a built-in scene of `beads` spheres whose memory
/// estimate ([`coulomb_granular::model::memory_estimate`], about 2 KiB per sphere: measured
/// 1.6 KiB at 10⁶ beads, docs/scaling.md) exceeds `available` bytes (MemAvailable; no check
/// when `None`), with the estimate in the message. Scene files get the same check from the
/// scene model.
pub(crate) fn check_beads_fit(beads: usize, available: Option<u64>) -> anyhow::Result<()> {
    if let Err(e) = coulomb_granular::model::check_memory(beads, 0, available) {
        bail!("--beads {beads}: {e}");
    }
    Ok(())
}

#[cfg(feature = "mpi")]
/// Whether this process was started by an MPI launcher (Open MPI's mpirun, or a PMI/PMIx
/// launcher such as srun or MPICH's mpiexec).
pub fn under_launcher() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
}

/// The JSON summary object of a run (`--json`): the run's [`Summary`], the energies at the
/// start and the end, and `extra` fields (those of a distributed run) appended.
pub(crate) fn summary_json(
    summary: &Summary,
    start_energy: f64,
    end_energy: f64,
    extra: serde_json::Map<String, serde_json::Value>,
) -> serde_json::Value {
    let mut obj = serde_json::to_value(summary).unwrap_or_default();
    if let Some(map) = obj.as_object_mut() {
        map.insert("start_energy".into(), start_energy.into());
        map.insert("end_energy".into(), end_energy.into());
    }
    if let Some(map) = obj.as_object_mut() {
        map.extend(extra);
    }
    obj
}

/// Whether the scene argument names a scene file (it ends in .toml or .json).
pub fn is_scene_file(scene: &str) -> bool {
    let lower = scene.to_ascii_lowercase();
    lower.ends_with(".toml") || lower.ends_with(".json")
}

#[cfg(test)]
mod tests {
    use super::check_beads_fit;

    #[test]
    fn the_step_time_cap_grows_with_the_bead_count_past_120_000() {
        use super::step_time_limit;
        use std::time::Duration;
        assert_eq!(step_time_limit(150), Duration::from_secs(60));
        assert_eq!(step_time_limit(120_000), Duration::from_secs(60));
        assert_eq!(step_time_limit(1_000_000), Duration::from_secs(500));
    }

    #[test]
    fn a_bead_count_the_memory_cannot_hold_is_refused_with_the_estimate() {
        let estimate = coulomb_granular::model::memory_estimate(1_000_000, 0);
        assert!(check_beads_fit(1_000_000, Some(estimate)).is_ok());
        assert!(check_beads_fit(1_000_000, None).is_ok());
        let e = check_beads_fit(1_000_000, Some(estimate - 1))
            .unwrap_err()
            .to_string();
        assert!(e.contains("--beads 1000000"), "{e}");
        assert!(e.contains(&format!("{estimate} bytes")), "{e}");
        assert!(e.contains(&format!("{} bytes", estimate - 1)), "{e}");
    }
}
