//! Distributed Moreau–Jean time stepping over MPI (feature `mpi`; design and measurements in
//! docs/distributed.md).
//!
//! * **Building.** [`DistributedSimulation::from_stream`] takes the beads one at a time in
//!   global id order (a built-in scene draws them again at each pass,
//!   [`crate::Scene::for_each_bead`]): every rank sees every bead but keeps only those of its
//!   slab, so that memory per rank is ∝ N / ranks from the start; [`DistributedSimulation::new`]
//!   does the same from a whole world (a scene file, built on every rank).
//! * **Decomposition.** Slabs along the wider horizontal axis of the initial bead cloud
//!   ([`slab`]), or a px × py grid of cells ([`grid`]: slabs along x, each cut along y at its
//!   own quantiles): rank r owns the beads whose coordinates lie in its slab or cell, the bounds
//!   at bead-count quantiles of histograms (at the start from the streamed beads, the same on
//!   every rank; later reduced over all ranks), recomputed every
//!   [`DistributedSimulation::rebalance_every`] steps (the heap spreads as it settles) at the
//!   quantiles of the work measured since the last rebalance ([`Balance::Work`], the default:
//!   per bead [`BEAD_WORK`] a step plus sweeps × the contacts it owns, counts and not times,
//!   so deterministic) or of the bead counts ([`Balance::Beads`]). Beads
//!   that leave a slab migrate to their new owner at the start of every step, with the warm
//!   start impulses of the contacts they own: point to point with the adjacent slabs or cells,
//!   or by one all-to-all exchange when some bead goes farther (after a rebalance).
//! * **Ghosts.** Each rank receives copies of the beads of other ranks within a halo
//!   2 R_max + margin of its slab, the margin of the broad phase (δ_k + 2 v_max h γ); every pair
//!   that can be active at this step then has both beads on the rank owning its lower-id bead.
//!   Ghost beads and, in the sweeps, their velocities and impulses travel point to point
//!   (`MPI_Isend`/`MPI_Irecv`) between neighbouring subdomains only ([`Grid::neighbours`]:
//!   those within the halo of each other), never through an all-to-all.
//! * **Contacts.** Detected on owned + ghost beads (ordered by global id, so that a contact has
//!   the same frame as on one process); contact (A, B) with id A < id B, and every contact with an
//!   obstacle, is owned by the owner of A. Interface contacts are those with a ghost B.
//! * **Solve.** The step's problem (2.10) by subdomain nonsmooth Gauss–Seidel ([`subdomain`]),
//!   pe's scheme: each rank sweeps its contacts on its copy of v (owned and ghost beads), then
//!   the velocity changes of ghost beads are sent to their owners and summed there, and the
//!   owners' velocities sent back to the ghost copies: two neighbour exchanges per sweep
//!   (Gauss–Seidel inside a subdomain, Jacobi across the interface). Only the beads some
//!   contact touches travel in these exchanges (the ranks tell each other which, once a step).
//!   A bead that the sweeps of k > 1 ranks move is split: each of them sees it with k times
//!   its inverse mass and its owner takes the mean of their changes
//!   ([`subdomain::SplitRow`], the mass splitting of Tonge et al. 2012), so that the ranks'
//!   steps on it do not add up (2 ranks on 2·10⁴ beads: 20 % fewer sweeps, docs/distributed.md).
//!   Every 16 sweeps, and
//!   before the step is accepted, v = M⁻¹(f + H r) is recomputed exactly from r (impulses of
//!   ghost beads reduced at their owners), so that the balance of (2.10) holds to rounding.
//! * **Error.** The error of docs/error.md, err = √(Σᵢ‖eᵢ‖²) / max(‖q‖, ‖r‖, ‖u‖), from four
//!   sums of squares over the contacts reduced over the ranks (each contact counted once, by its
//!   owner), with uᵢ = Hᵢᵀ v + wᵢ and qᵢ = Hᵢᵀ M⁻¹ f + wᵢ, in one `MPI_Allreduce` of seven
//!   numbers per sweep: the four sums and three flags (an entry above 2¹⁰⁰ on some rank, a NaN,
//!   past the time limit). Overflow: plain squares cannot overflow while every entry is at most
//!   2¹⁰⁰; when some rank has a larger one, the largest entry is reduced (a max) and every entry
//!   is multiplied by the same power of two α before squaring — exact, and eᵢ is positively
//!   homogeneous, so the ratio is unchanged ([`coulomb::law::error_measure`] does the same on
//!   one process). The sweep loop stops on that global err exactly as on one machine: err ≤ tol
//!   on the exact v, or the sweep cap, or the time limit (all ranks see the same reduced
//!   numbers and flags, so they stop at the same sweep).
//! * **Position correction** ([`crate::projection`]) in rounds (at most 4): ghosts refreshed,
//!   the largest penetration over all ranks reduced, and while it exceeds the trigger every
//!   rank corrects its owned + ghost beads with the ghosts' true masses and keeps the new
//!   positions of its own beads only (the ghost copies' are dropped), so an interface pair is
//!   corrected half by each side in a round, as on one process.
//!   (Ghosts held fixed instead made each side move its bead the whole way, and the larger
//!   moves pushed beads into pairs the correction does not track: a 6 mm overlap at step 22
//!   of the 2 000-bead box on 4 ranks.)
//! * **Statistics** of each step reduced over the ranks into the [`StepStats`] of
//!   `coulomb simulate` (same JSON), plus the communication time ([`DistributedStats`]).

mod comm;
pub mod grid;
pub mod slab;
pub mod subdomain;

pub use comm::Comm;
/// The MPI bindings (rsmpi), for `mpi::initialize()` in programs using this module.
pub use mpi;

use crate::assembly::StepData;
use crate::contact::{candidate_pairs, detect_with_speed, Contact, Partner};
use crate::math::Vec3;
use crate::nsgs::{StepProblem, RELAX_WINDOW};
use crate::output::{FrameBody, FrameContact, FrameData, FramePart, VtkWriter};
use crate::projection::project;
use crate::simulation::{
    check_spheres, Params, Simulation, SimulationError, StepMethod, StepStats,
};
use crate::world::{Obstacle, Sphere, World};
use grid::Grid;
use serde::Serialize;
use slab::HISTOGRAM_BINS;
use std::cmp::Ordering;
use std::collections::HashMap;
use std::time::{Duration, Instant};
use subdomain::{error_sums, impulses, max_entry, split_rows, sweep, velocities};

/// Words of a bead record: global id, x, v, ω, R, m, rotation lock.
const BEAD_WORDS: usize = 13;
/// Words of a warm-start record: partner kind, partner index, r (3).
const WARM_WORDS: usize = 5;
/// Rounds of the distributed position correction at most (each: ghosts refreshed, every rank
/// corrects its subdomain).
const PROJECTION_ROUNDS: usize = 4;
/// Sweeps between two exact recomputations of v from r.
const REFRESH: usize = 16;
/// The work of a bead per step outside the sweeps (detection, assembly, θ-method, position
/// correction, statistics), in contact updates: c_b / c_u = 6 µs / 0.23 µs ≈ 26, the costs
/// per bead and per contact update measured on one rank (docs/distributed.md, "Projected cost
/// per step"). A bead's measured work per step is this plus the updates of the contacts it
/// owns: their number times the step's sweeps ([`Balance::Work`]).
pub const BEAD_WORK: u64 = 26;

/// What the rebalancing equalises across the ranks (every [`DistributedSimulation::rebalance_every`]
/// steps; the bounds at the start are always at bead-count quantiles: nothing is measured yet).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Balance {
    /// bead counts: the bounds at the quantiles of the beads (the slabs of #16, to the bit)
    Beads,
    /// measured work: the bounds at the quantiles of the work the beads took since the last
    /// rebalance, each bead weighted by [`BEAD_WORK`] per step plus sweeps × the contacts it
    /// owns, counts of operations (not times), so the same bits for the same input whatever
    /// the machine's load
    #[default]
    Work,
}

/// The beads of a distributed run's initial state, handed to the callback one at a time in
/// global id order; called once per pass of [`DistributedSimulation::from_stream`], giving the
/// same sequence every time.
pub type BeadStream<'a> = dyn Fn(&mut dyn FnMut(Sphere)) + 'a;

/// Statistics of one distributed step: the [`StepStats`] of a single-process step (reduced
/// over the ranks) and the decomposition's own numbers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DistributedStats {
    /// the step's statistics, as `coulomb simulate` reports them
    pub step: StepStats,
    /// ranks
    pub ranks: usize,
    /// Gauss–Seidel sweeps of the step
    pub sweeps: usize,
    /// wall-clock time of the step on this rank (ms)
    pub step_ms: f64,
    /// time spent in MPI calls during the step, largest over the ranks (ms)
    pub comm_ms: f64,
    /// time spent in MPI calls during the step, mean over the ranks (ms)
    pub comm_mean_ms: f64,
    /// MPI messages (nonempty peer buffers and reductions) of this rank during the step
    pub messages: u64,
    /// bytes sent by this rank during the step
    pub bytes: u64,
    /// ghost beads, summed over the ranks
    pub ghosts: usize,
    /// interface contacts (with a ghost bead), summed over the ranks
    pub interface_contacts: usize,
    /// beads that changed rank at the start of the step
    pub migrated: usize,
    /// whether that migration went by one all-to-all exchange (some bead went beyond the
    /// adjacent slab) instead of point to point with the adjacent ranks
    pub migration_all_to_all: bool,
    /// most beads owned by one rank divided by the mean
    pub imbalance: f64,
    /// most work of one rank in this step divided by the mean over the ranks: work =
    /// [`BEAD_WORK`] per owned bead + sweeps × owned contacts (1 with no work anywhere)
    pub work_imbalance: f64,
    /// whether the bounds were recomputed at the start of this step
    /// ([`DistributedSimulation::rebalance`])
    pub rebalanced: bool,
}

/// The ghost beads of a rank and the bookkeeping of the exchanges that refresh them.
#[derive(Debug, Clone, Default)]
struct Ghosts {
    /// (global id, state, owner rank), sorted by global id
    beads: Vec<(usize, Sphere, usize)>,
    /// send[r]: owned bead indices sent to rank r, in order
    send: Vec<Vec<usize>>,
    /// recv[r]: ghost indices received from rank r, in order
    recv: Vec<Vec<usize>>,
    /// the ranks this rank exchanges ghosts with ([`Grid::neighbours`]), ascending
    peers: Vec<usize>,
}

/// The beads a rank works on in a step: owned and ghost, in global id order.
struct Local {
    world: World,
    /// local index of each owned bead
    of_owned: Vec<usize>,
    /// local index of each ghost
    of_ghost: Vec<usize>,
    /// whether a local bead is owned
    owned: Vec<bool>,
    /// global id of each local bead
    gid: Vec<usize>,
}

/// A Moreau–Jean simulation distributed over the ranks of an MPI communicator (module doc).
/// Every rank calls the same methods in the same order (they communicate).
#[derive(Debug)]
pub struct DistributedSimulation {
    /// the communicator
    pub comm: Comm,
    /// parameters (as [`Simulation`]); the tolerance and time limit of [`StepMethod::Nsgs`]
    /// (or of the library's settings) are used, the step is always solved by the subdomain
    /// Gauss–Seidel
    pub params: Params,
    /// t_k
    pub time: f64,
    /// k
    pub steps_done: usize,
    /// recompute the slab bounds every this many steps (0: never after the start)
    pub rebalance_every: usize,
    /// what the rebalancing equalises: bead counts or measured work ([`Balance`])
    pub balance: Balance,
    /// cap on Gauss–Seidel sweeps per step (from [`StepMethod::Nsgs`], else 20 000)
    pub max_sweeps: usize,
    /// the owned beads (global id, state), sorted by global id
    pub beads: Vec<(usize, Sphere)>,
    /// contact force Σ r / h on each owned bead at the last step (translational part)
    pub forces: Vec<Vec3>,
    /// work of each owned bead since the last rebalance, in contact updates ([`Balance::Work`]);
    /// travels with the bead when it migrates
    pub work: Vec<u64>,
    /// the owned contacts of the last step with their impulses, in global ids
    pub contacts: Vec<Contact>,
    /// the decomposition: slabs (p × 1) or a p₁ × p₂ grid of cells
    pub grid: Grid,
    obstacles: Vec<Obstacle>,
    gravity: Vec3,
    warm: HashMap<(usize, Partner), [f64; 3]>,
    residual_velocity: f64,
    rmax: f64,
    rmin: f64,
    total: usize,
    held_at_build: usize,
    /// whether the last migration went by all-to-all
    migrated_all_to_all: bool,
}

impl DistributedSimulation {
    /// A distributed simulation of `world` (the same world on every rank, e.g. built from the
    /// same scene and seed): as [`Self::from_stream`] with the world's beads, except that
    /// every rank holds all N beads until it returns ([`Self::held_at_build`] = N).
    pub fn new(comm: Comm, world: World, params: Params) -> Result<Self, SimulationError> {
        Self::new_on(comm, world, params, None)
    }

    /// [`Self::new`] on the decomposition `grid` ([`Self::from_stream_on`]).
    pub fn new_on(
        comm: Comm,
        world: World,
        params: Params,
        grid: Option<[usize; 2]>,
    ) -> Result<Self, SimulationError> {
        let World {
            bodies,
            obstacles,
            gravity,
            materials,
        } = world;
        let skeleton = World {
            bodies: Vec::new(),
            obstacles,
            gravity,
            materials,
        };
        let total = bodies.len();
        let mut sim = Self::from_stream_on(comm, skeleton, params, grid, &|emit| {
            for b in &bodies {
                emit(b.clone());
            }
        })?;
        sim.held_at_build = total.max(sim.held_at_build);
        Ok(sim)
    }

    /// A distributed simulation of the world `skeleton` (obstacles, gravity; its beads
    /// ignored) with the beads handed out by `beads`, in global id order, the same sequence
    /// on every rank and at every call (e.g. [`crate::Scene::for_each_bead`]). Parameters
    /// and beads are checked as by [`Simulation::new`] (every rank sees every bead, so all
    /// return the same error). Three passes over the beads, none holding them: (1) count,
    /// checks, the extent along x and y (the slabs go along the wider one) and the radii;
    /// (2) a histogram of [`HISTOGRAM_BINS`] bins along the slab axis, from which every rank
    /// computes the same bounds at the bead-count quantiles ([`slab::quantile_bounds`]); (3) each
    /// rank keeps the beads of its slab. Memory per rank: its part, about N / ranks beads
    /// ([`Self::held_at_build`]). The state is that of [`Self::new`] on the built world.
    pub fn from_stream(
        comm: Comm,
        skeleton: World,
        params: Params,
        beads: &BeadStream<'_>,
    ) -> Result<Self, SimulationError> {
        Self::from_stream_on(comm, skeleton, params, None, beads)
    }

    /// [`Self::from_stream`] on the decomposition `grid`: None for slabs along the wider
    /// horizontal axis, `Some([px, py])` for a px × py grid of cells, px slabs along x each cut
    /// into py cells along y at its own bead-count quantiles (one more pass over the beads);
    /// px py must be the number of ranks (error otherwise).
    pub fn from_stream_on(
        comm: Comm,
        skeleton: World,
        params: Params,
        grid: Option<[usize; 2]>,
        beads: &BeadStream<'_>,
    ) -> Result<Self, SimulationError> {
        if let Some([px, py]) = grid {
            if px.checked_mul(py) != Some(comm.size()) || px == 0 {
                return Err(SimulationError::Parameter(format!(
                    "a {px} × {py} grid has {} cells for {} ranks: px py must be the number of ranks",
                    px.saturating_mul(py),
                    comm.size()
                )));
            }
        }
        if skeleton.materials.is_some() {
            // per-pair contact laws are not carried by the subdomain exchange
            return Err(SimulationError::Parameter(
                "per-pair materials are not supported by the distributed step (use one process)"
                    .into(),
            ));
        }
        if params.rolling_friction != 0.0 {
            // the subdomain sweep solves the law (2.9) only; ignoring μ_r silently would
            // change the physics (crate::rolling)
            return Err(SimulationError::Parameter(format!(
                "rolling friction μ_r = {} is not supported by the distributed step (use one process)",
                params.rolling_friction
            )));
        }
        if params
            .projection
            .is_some_and(|p| p.velocities == crate::projection::Velocities::Inelastic)
        {
            // the velocity projection adds impulses to the step's contacts, which the
            // subdomain correction does not hold; ignoring it silently would change the physics
            return Err(SimulationError::Parameter(
                "projection velocities = inelastic is not supported by the distributed step (use one process)"
                    .into(),
            ));
        }
        let skeleton = World {
            bodies: Vec::new(),
            ..skeleton
        };
        let sim = Simulation::new(skeleton, params)?;
        let Simulation { world, params, .. } = sim;
        let (rank, size) = (comm.rank(), comm.size());
        let max_sweeps = match params.method {
            StepMethod::Nsgs(s) => s.max_sweeps,
            StepMethod::Library => 20_000,
        };

        // pass 1: count, checks, extents, radii
        let mut n = 0usize;
        let mut bad: Option<SimulationError> = None;
        let mut ext = [
            (f64::INFINITY, f64::NEG_INFINITY),
            (f64::INFINITY, f64::NEG_INFINITY),
        ];
        let (mut rmax, mut rmin) = (0.0f64, f64::INFINITY);
        beads(&mut |b: Sphere| {
            if bad.is_none() {
                if let Err(e) = check_spheres(std::slice::from_ref(&b), n, 1) {
                    bad = Some(e);
                }
            }
            for (d, x) in [b.position.x, b.position.y].into_iter().enumerate() {
                ext[d] = (ext[d].0.min(x), ext[d].1.max(x));
            }
            rmax = rmax.max(b.radius);
            rmin = rmin.min(b.radius);
            n += 1;
        });
        if let Some(e) = bad {
            return Err(e);
        }
        let (axes, parts) = match grid {
            Some(g) => ([0, 1], g),
            None => {
                // slabs along the wider axis
                let a = usize::from(ext[1].1 - ext[1].0 > ext[0].1 - ext[0].0);
                ([a, 1 - a], [size, 1])
            }
        };
        let range = |a: usize| if n > 0 { ext[a] } else { (0.0, 0.0) };
        let ranges = [range(axes[0]), range(axes[1])];

        // pass 2: the bead-count histogram along the first axis, the same on every rank;
        // pass 2b (grid): each slab's histogram along the second axis
        let mut grid = Grid::unbalanced(axes, parts);
        if size > 1 {
            let mut outer = vec![0.0; HISTOGRAM_BINS];
            beads(&mut |b: Sphere| outer[grid.outer_bin(b.position, ranges[0])] += 1.0);
            grid = Grid::balanced(axes, parts, ranges, &outer, &[]);
            if parts[1] > 1 {
                let mut inner = vec![vec![0.0; HISTOGRAM_BINS]; parts[0]];
                beads(&mut |b: Sphere| {
                    inner[grid.slab_of(b.position)][grid.inner_bin(b.position, ranges[1])] += 1.0
                });
                grid = Grid::balanced(axes, parts, ranges, &outer, &inner);
            }
        }

        // pass 3: this rank's beads, in global id order
        let mut mine: Vec<(usize, Sphere)> = Vec::new();
        let mut gid = 0usize;
        beads(&mut |b: Sphere| {
            if grid.owner(b.position) == rank {
                mine.push((gid, b));
            }
            gid += 1;
        });
        if gid != n {
            return Err(SimulationError::Parameter(format!(
                "the bead stream gave {gid} beads after {n}: it must give the same beads at every pass"
            )));
        }
        Ok(Self {
            comm,
            params,
            time: 0.0,
            steps_done: 0,
            rebalance_every: 20,
            balance: Balance::default(),
            max_sweeps,
            forces: vec![Vec3::ZERO; mine.len()],
            work: vec![0; mine.len()],
            held_at_build: mine.len(),
            beads: mine,
            contacts: Vec::new(),
            grid,
            obstacles: world.obstacles,
            gravity: world.gravity,
            warm: HashMap::new(),
            residual_velocity: 0.0,
            rmax,
            rmin,
            total: n,
            migrated_all_to_all: false,
        })
    }

    /// Overlapping pairs (gap below −10⁻⁹ (R_A + R_B), the test of
    /// [`crate::model::overlaps`]) among this rank's beads as handed out by `beads` (the
    /// stream it was built from, one more pass) and those within 2 R_max of its cell, i.e. the
    /// ranks' counts together see every overlapping pair of the stream (a pair of beads
    /// owned by two ranks is counted by both). Holds those beads while counting
    /// ([`Self::held_at_build`] grows to their number). Local: no message.
    pub fn halo_overlaps(&mut self, beads: &BeadStream<'_>) -> usize {
        let me = self.comm.rank();
        let halo = 2.0 * self.rmax;
        let grid = &self.grid;
        let mut held = World::new();
        let mut targets = Vec::new();
        beads(&mut |b: Sphere| {
            let owner = grid.owner(b.position);
            let keep = owner == me || {
                grid.ghost_targets(owner, b.position, halo, &mut targets);
                targets.contains(&me)
            };
            if keep {
                held.bodies.push(b);
            }
        });
        self.held_at_build = self.held_at_build.max(held.bodies.len());
        crate::model::overlaps(&held).count
    }

    /// Most beads this rank held at once while the simulation was built: its part for
    /// [`Self::from_stream`], all N for [`Self::new`].
    pub fn held_at_build(&self) -> usize {
        self.held_at_build
    }

    /// Total number of beads.
    pub fn total_beads(&self) -> usize {
        self.total
    }

    /// Places the bounds at the quantiles of the current positions weighted by bead count or
    /// by the work measured since the last rebalance ([`Self::balance`]): the ranges along
    /// both axes reduced (max), a histogram of [`HISTOGRAM_BINS`] bins along the first axis
    /// reduced (sum), and for a grid each slab's histogram along the second axis reduced
    /// (sum); every rank computes the same bounds ([`Grid::balanced`]). The weights are
    /// integers (exact in f64 below 2⁵³, so the sums do not depend on the reduction's order).
    /// The measured work restarts from zero. Beads move at the next [`Self::migrate`].
    pub fn rebalance(&mut self) {
        let size = self.comm.size();
        let work = std::mem::replace(&mut self.work, vec![0; self.beads.len()]);
        if size == 1 {
            return;
        }
        let weights: Vec<f64> = match self.balance {
            Balance::Beads => vec![1.0; self.beads.len()],
            Balance::Work => work.iter().map(|&w| w as f64).collect(),
        };
        let (axes, parts) = (self.grid.axes, self.grid.parts());
        let along = |p: Vec3, a: usize| if a == 0 { p.x } else { p.y };
        let mut range = [f64::NEG_INFINITY; 4];
        for (_, b) in &self.beads {
            for (k, &a) in axes.iter().enumerate() {
                let x = along(b.position, a);
                if x.is_finite() {
                    range[2 * k] = range[2 * k].max(-x);
                    range[2 * k + 1] = range[2 * k + 1].max(x);
                }
            }
        }
        self.comm.max(&mut range);
        let span = |k: usize| {
            if range[2 * k + 1].is_finite() {
                (-range[2 * k], range[2 * k + 1])
            } else {
                (0.0, 0.0)
            }
        };
        let ranges = [span(0), span(1)];
        let mut outer = vec![0.0; HISTOGRAM_BINS];
        for ((_, b), w) in self.beads.iter().zip(&weights) {
            outer[self.grid.outer_bin(b.position, ranges[0])] += w;
        }
        self.comm.sum(&mut outer);
        let mut grid = Grid::balanced(axes, parts, ranges, &outer, &[]);
        if parts[1] > 1 {
            let mut flat = vec![0.0; parts[0] * HISTOGRAM_BINS];
            for ((_, b), w) in self.beads.iter().zip(&weights) {
                let i = grid.slab_of(b.position);
                flat[i * HISTOGRAM_BINS + grid.inner_bin(b.position, ranges[1])] += w;
            }
            self.comm.sum(&mut flat);
            let inner: Vec<Vec<f64>> = flat
                .chunks_exact(HISTOGRAM_BINS)
                .map(<[f64]>::to_vec)
                .collect();
            grid = Grid::balanced(axes, parts, ranges, &outer, &inner);
        }
        self.grid = grid;
    }

    /// Sends every owned bead outside this rank's slab or cell to its owner, with the
    /// warm-start impulses of the contacts it owns; returns the number of beads sent. Point to
    /// point with the subdomains touching this one (slabs: r ± 1) when every bead on every
    /// rank goes to one of those (a flag reduced over the ranks decides); otherwise, e.g. after
    /// a rebalance moved the bounds far, one personalised all-to-all exchange.
    pub fn migrate(&mut self) -> usize {
        let (me, size) = (self.comm.rank(), self.comm.size());
        if size == 1 {
            return 0;
        }
        // the cells touching this one (slabs: r ± 1)
        let adjacent = self.grid.neighbours(me, 0.0);
        let mut leaving: HashMap<usize, usize> = HashMap::new();
        let mut far = 0.0;
        for (gid, b) in &self.beads {
            let dest = self.grid.owner(b.position);
            if dest != me {
                leaving.insert(*gid, dest);
                if !adjacent.contains(&dest) {
                    far = 1.0;
                }
            }
        }
        let mut any_far = [far];
        self.comm.max(&mut any_far);
        let mut warm_of: HashMap<usize, Vec<(Partner, [f64; 3])>> = HashMap::new();
        if !leaving.is_empty() {
            let keys: Vec<(usize, Partner)> = self
                .warm
                .keys()
                .filter(|k| leaving.contains_key(&k.0))
                .copied()
                .collect();
            for k in keys {
                if let Some(r) = self.warm.remove(&k) {
                    warm_of.entry(k.0).or_default().push((k.1, r));
                }
            }
        }
        let mut send = vec![Vec::new(); size];
        let mut kept = Vec::with_capacity(self.beads.len());
        let mut kept_forces = Vec::with_capacity(self.beads.len());
        let mut kept_work = Vec::with_capacity(self.beads.len());
        let work = std::mem::take(&mut self.work);
        let work = work.into_iter().chain(std::iter::repeat(0));
        for (((gid, b), f), wk) in self.beads.drain(..).zip(self.forces.drain(..)).zip(work) {
            match leaving.get(&gid) {
                Some(&dest) => {
                    let buf = &mut send[dest];
                    pack_bead(buf, gid, &b);
                    // the measured work, an integer (exact in f64 below 2⁵³)
                    buf.push(wk as f64);
                    let w = warm_of.remove(&gid).unwrap_or_default();
                    buf.push(w.len() as f64);
                    for (p, r) in w {
                        let (kind, idx) = match p {
                            Partner::Body(j) => (0.0, j),
                            // an obstacle's kind word carries its feature: 1 + feature
                            Partner::Obstacle(o, f) => (1.0 + f as f64, o),
                        };
                        buf.extend_from_slice(&[kind, idx as f64, r[0], r[1], r[2]]);
                    }
                }
                None => {
                    kept.push((gid, b));
                    kept_forces.push(f);
                    kept_work.push(wk);
                }
            }
        }
        self.migrated_all_to_all = any_far[0] > 0.0;
        let recv = if self.migrated_all_to_all {
            self.comm.exchange(&send)
        } else {
            self.comm.exchange_peers(&adjacent, &send)
        };
        for buf in recv {
            let mut at = 0;
            while at + BEAD_WORDS < buf.len() {
                let (gid, b) = unpack_bead(&buf[at..at + BEAD_WORDS]);
                at += BEAD_WORDS;
                let wk = buf[at] as u64;
                at += 1;
                let nw = buf.get(at).map_or(0, |x| *x as usize);
                at += 1;
                for _ in 0..nw {
                    if let Some(w) = buf.get(at..at + WARM_WORDS) {
                        let idx = w[1] as usize;
                        let p = if w[0] == 0.0 {
                            Partner::Body(idx)
                        } else {
                            Partner::Obstacle(idx, (w[0] - 1.0) as u32)
                        };
                        self.warm.insert((gid, p), [w[2], w[3], w[4]]);
                    }
                    at += WARM_WORDS;
                }
                kept.push((gid, b));
                kept_forces.push(Vec3::ZERO);
                kept_work.push(wk);
            }
        }
        let mut order: Vec<usize> = (0..kept.len()).collect();
        order.sort_by_key(|&i| kept[i].0);
        self.beads = order.iter().map(|&i| kept[i].clone()).collect();
        self.forces = order.iter().map(|&i| kept_forces[i]).collect();
        self.work = order.iter().map(|&i| kept_work[i]).collect();
        leaving.len()
    }

    /// Copies of the beads of other ranks within `halo` of this rank's cell. `moved`: the
    /// beads may have left their cells since the last migration (the position correction
    /// after the θ-method): the farthest any lies outside its cell is reduced (max) and the
    /// ranks talk to the neighbours within halo + that distance, so that every ghost target
    /// is among them.
    fn exchange_ghosts(&mut self, halo: f64, moved: bool) -> Ghosts {
        let (me, size) = (self.comm.rank(), self.comm.size());
        let mut g = Ghosts {
            beads: Vec::new(),
            send: vec![Vec::new(); size],
            recv: vec![Vec::new(); size],
            peers: Vec::new(),
        };
        if size == 1 {
            return g;
        }
        let mut out = [0.0];
        if moved {
            out[0] = self
                .beads
                .iter()
                .map(|(_, b)| self.grid.outside(me, b.position))
                .fold(0.0, f64::max);
            self.comm.max(&mut out);
        }
        g.peers = self.grid.neighbours(me, halo + out[0]);
        let mut bufs = vec![Vec::new(); size];
        let mut targets = Vec::new();
        for (i, (gid, b)) in self.beads.iter().enumerate() {
            self.grid.ghost_targets(me, b.position, halo, &mut targets);
            for &r in &targets {
                pack_bead(&mut bufs[r], *gid, b);
                g.send[r].push(i);
            }
        }
        let recv = self.comm.exchange_peers(&g.peers, &bufs);
        let mut list = Vec::new();
        for (r, buf) in recv.iter().enumerate() {
            for (k, rec) in buf.chunks_exact(BEAD_WORDS).enumerate() {
                let (gid, b) = unpack_bead(rec);
                list.push((gid, b, r, k));
            }
        }
        list.sort_by_key(|x| x.0);
        for (idx, (gid, b, r, k)) in list.into_iter().enumerate() {
            g.beads.push((gid, b, r));
            let slot = &mut g.recv[r];
            if slot.len() <= k {
                slot.resize(k + 1, usize::MAX);
            }
            slot[k] = idx;
        }
        g
    }

    /// The local world: owned and ghost beads merged in global id order.
    fn local(&self, ghosts: &Ghosts) -> Local {
        let n = self.beads.len() + ghosts.beads.len();
        let mut world = World {
            bodies: Vec::with_capacity(n),
            obstacles: self.obstacles.clone(),
            gravity: self.gravity,
            materials: None,
        };
        let mut of_owned = Vec::with_capacity(self.beads.len());
        let mut of_ghost = Vec::with_capacity(ghosts.beads.len());
        let mut owned = Vec::with_capacity(n);
        let mut gid = Vec::with_capacity(n);
        let (mut i, mut j) = (0, 0);
        while i < self.beads.len() || j < ghosts.beads.len() {
            let take_owned = j >= ghosts.beads.len()
                || (i < self.beads.len() && self.beads[i].0 < ghosts.beads[j].0);
            if take_owned {
                of_owned.push(world.bodies.len());
                gid.push(self.beads[i].0);
                world.bodies.push(self.beads[i].1.clone());
                owned.push(true);
                i += 1;
            } else {
                of_ghost.push(world.bodies.len());
                gid.push(ghosts.beads[j].0);
                world.bodies.push(ghosts.beads[j].1.clone());
                owned.push(false);
                j += 1;
            }
        }
        Local {
            world,
            of_owned,
            of_ghost,
            owned,
            gid,
        }
    }

    /// Adds the 6-vectors `x` (6 per local bead) of ghost beads into their owners' entries on
    /// the owning ranks, then zeroes the ghosts' entries: impulses or velocity changes of the
    /// interface reduced where the bead lives.
    fn reduce_ghosts(&mut self, ghosts: &Ghosts, local: &Local, x: &mut [[f64; 6]]) {
        let size = self.comm.size();
        if size == 1 {
            return;
        }
        let send: Vec<Vec<f64>> = ghosts
            .recv
            .iter()
            .map(|list| {
                let mut b = Vec::with_capacity(6 * list.len());
                for &gi in list {
                    match local.of_ghost.get(gi) {
                        Some(&l) => b.extend_from_slice(&x[l]),
                        None => b.extend_from_slice(&[0.0; 6]),
                    }
                }
                b
            })
            .collect();
        let lens: Vec<usize> = ghosts.send.iter().map(|s| 6 * s.len()).collect();
        let recv = self.comm.exchange_peers_known(&ghosts.peers, &send, &lens);
        for (r, buf) in recv.iter().enumerate() {
            for (k, &oi) in ghosts.send[r].iter().enumerate() {
                let l = local.of_owned[oi];
                if let Some(src) = buf.get(6 * k..6 * k + 6) {
                    for (xd, s) in x[l].iter_mut().zip(src) {
                        *xd += s;
                    }
                }
            }
        }
        for &l in &local.of_ghost {
            x[l] = [0.0; 6];
        }
    }

    /// Per local bead, the number of ranks whose sweeps move it (those with a contact on it),
    /// and the routes of the ghosts that some contact touches (beads left empty): the only
    /// ghosts whose velocities the solve exchanges. One flag per ghost goes to its owner, the
    /// counts come back to the touched ghost copies.
    fn shares(&mut self, ghosts: &Ghosts, local: &Local, p: &StepProblem) -> (Vec<f64>, Ghosts) {
        let n = p.inv_mass.len();
        let size = self.comm.size();
        if size == 1 {
            return (vec![1.0; n], Ghosts::default());
        }
        let mut touched = vec![false; n];
        for row in &p.rows {
            touched[row.a] = true;
            if let Some(b) = row.b {
                touched[b] = true;
            }
        }
        let is_touched = |gi: usize| local.of_ghost.get(gi).is_some_and(|&l| touched[l]);
        let send: Vec<Vec<f64>> = ghosts
            .recv
            .iter()
            .map(|list| {
                list.iter()
                    .map(|&gi| f64::from(u8::from(is_touched(gi))))
                    .collect()
            })
            .collect();
        let lens: Vec<usize> = ghosts.send.iter().map(Vec::len).collect();
        let flags = self.comm.exchange_peers_known(&ghosts.peers, &send, &lens);
        let mut x: Vec<[f64; 6]> = touched
            .iter()
            .map(|&t| [f64::from(u8::from(t)), 0.0, 0.0, 0.0, 0.0, 0.0])
            .collect();
        let mut active = Ghosts {
            beads: Vec::new(),
            send: vec![Vec::new(); size],
            recv: vec![Vec::new(); size],
            peers: ghosts.peers.clone(),
        };
        for (r, list) in ghosts.send.iter().enumerate() {
            for (k, &oi) in list.iter().enumerate() {
                if flags[r].get(k).is_some_and(|&f| f > 0.0) {
                    x[local.of_owned[oi]][0] += 1.0;
                    active.send[r].push(oi);
                }
            }
        }
        for (r, list) in ghosts.recv.iter().enumerate() {
            active.recv[r] = list.iter().copied().filter(|&gi| is_touched(gi)).collect();
        }
        self.broadcast_ghosts(&active, local, &mut x);
        (x.iter().map(|s| s[0]).collect(), active)
    }

    /// Copies the owners' velocities to the ghost copies.
    fn broadcast_ghosts(&mut self, ghosts: &Ghosts, local: &Local, v: &mut [[f64; 6]]) {
        if self.comm.size() == 1 {
            return;
        }
        let send: Vec<Vec<f64>> = ghosts
            .send
            .iter()
            .map(|list| {
                let mut b = Vec::with_capacity(6 * list.len());
                for &oi in list {
                    b.extend_from_slice(&v[local.of_owned[oi]]);
                }
                b
            })
            .collect();
        let lens: Vec<usize> = ghosts.recv.iter().map(|s| 6 * s.len()).collect();
        let recv = self.comm.exchange_peers_known(&ghosts.peers, &send, &lens);
        for (r, buf) in recv.iter().enumerate() {
            for (k, &gi) in ghosts.recv[r].iter().enumerate() {
                let Some(&l) = local.of_ghost.get(gi) else {
                    continue;
                };
                if let Some(src) = buf.get(6 * k..6 * k + 6) {
                    v[l].copy_from_slice(src);
                }
            }
        }
    }

    /// v = M⁻¹ (f + H r) on every local bead: impulses Gᵀ rᵢ of the local contacts, those of
    /// ghosts summed at their owners, v of owned beads formed, then copied to the ghosts.
    /// Returns the impulse of each local bead (owned beads: the total over all ranks).
    fn sync_exact(
        &mut self,
        ghosts: &Ghosts,
        local: &Local,
        p: &StepProblem,
        r: &[f64],
        v_free: &[[f64; 6]],
        v: &mut [[f64; 6]],
    ) -> Vec<[f64; 6]> {
        let mut imp = vec![[0.0; 6]; v.len()];
        impulses(p, r, &mut imp);
        self.reduce_ghosts(ghosts, local, &mut imp);
        for &l in &local.of_owned {
            for d in 0..6 {
                v[l][d] = v_free[l][d] + imp[l][d] * p.inv_mass[l][d];
            }
        }
        self.broadcast_ghosts(ghosts, local, v);
        imp
    }

    /// The global error of docs/error.md over all ranks' contacts (module doc), and the scale
    /// max(‖q‖, ‖r‖, ‖u‖); `late` tells that this rank is past the time limit, and the third
    /// value whether any rank is.
    fn global_error(
        &mut self,
        p: &StepProblem,
        q: &[[f64; 3]],
        r: &[f64],
        v: &[[f64; 6]],
        late: bool,
    ) -> (f64, f64, bool) {
        const LIMIT: f64 = 1.2676506002282294e30; // 2¹⁰⁰
        let u = velocities(p, v);
        let m = max_entry(q, r, &u);
        // one reduction in the common case: the plain sums of squares (exact when every
        // entry is at most 2¹⁰⁰) with three flags: an entry above 2¹⁰⁰, a NaN, past the time
        // limit
        let big = m.is_nan() || m > LIMIT;
        let mut s = if big {
            [0.0; 4]
        } else {
            error_sums(p, q, r, &u, 1.0)
        };
        let mut head = [
            s[0],
            s[1],
            s[2],
            s[3],
            f64::from(u8::from(big)),
            f64::from(u8::from(m.is_nan())),
            f64::from(u8::from(late)),
        ];
        self.comm.sum(&mut head);
        let (any_big, nan, any_late) = (head[4] > 0.0, head[5] > 0.0, head[6] > 0.0);
        if nan {
            return (f64::NAN, f64::INFINITY, any_late);
        }
        let mut alpha = 1.0;
        if any_big {
            // rare: the largest entry over the ranks (a max), then the sums of the entries
            // multiplied by the same power of two α, exact, so that no square overflows
            let mut mx = [if m.is_nan() { f64::INFINITY } else { m }];
            self.comm.max(&mut mx);
            if !mx[0].is_finite() {
                return (f64::INFINITY, f64::INFINITY, any_late);
            }
            let e = mx[0].log2().ceil() as i32 + 1;
            alpha = 2f64.powi(-e.min(1022));
            s = error_sums(p, q, r, &u, alpha);
            self.comm.sum(&mut s);
        } else {
            s.copy_from_slice(&head[..4]);
        }
        let scaled_scale = s[1].sqrt().max(s[2].sqrt()).max(s[3].sqrt());
        let scale = scaled_scale / alpha;
        let err = if scale > f64::EPSILON {
            s[0].sqrt() / scaled_scale
        } else {
            s[0].sqrt() / alpha
        };
        (err, scale, any_late)
    }

    /// The threshold δ_k of the activation rule, as [`Simulation::activation_threshold`]
    /// (from the last step's global error and scale, the same on every rank).
    pub fn activation_threshold(&self) -> f64 {
        let a = &self.params.activation;
        if !a.delta_from_tolerance {
            return a.delta;
        }
        let lift = 2.0 * self.params.h * self.residual_velocity;
        let cap = if self.rmin.is_finite() {
            0.01 * self.rmin
        } else {
            0.0
        };
        lift.min(cap).max(a.delta)
    }

    /// One distributed Moreau–Jean step from t_k to t_{k+1} (module doc); every rank gets
    /// the same reduced statistics.
    pub fn step(&mut self) -> Result<DistributedStats, SimulationError> {
        let t0 = Instant::now();
        let comm0 = self.comm.seconds();
        let (msg0, bytes0) = (self.comm.messages(), self.comm.bytes());
        let k = self.steps_done;
        let h = self.params.h;
        let size = self.comm.size();
        let due = k > 0 && self.rebalance_every > 0 && k % self.rebalance_every == 0;
        if due {
            self.rebalance();
        }
        let rebalanced = due && size > 1;
        let migrated_here = self.migrate();

        // global v_max for the broad phase margin, and the step's δ_k
        let vmax_local = self
            .beads
            .iter()
            .map(|(_, b)| b.velocity.norm() + b.angular_velocity.norm() * b.radius)
            .fold(0.0, f64::max);
        let mut head = [vmax_local];
        self.comm.max(&mut head);
        let delta = self.activation_threshold();
        let gamma = self.params.activation.gamma;
        let margin = delta.max(self.params.activation.delta) + 2.0 * head[0] * h * gamma + 1e-12;
        // every owned bead is in its cell (just migrated)
        let ghosts = self.exchange_ghosts(2.0 * self.rmax + margin + 1e-9, false);
        let local = self.local(&ghosts);

        // the owned contacts, in global id order (the local order is the global one); the
        // broad phase's margin from the global v_max, as on one process (a rank's own v_max
        // is smaller where its beads are calmer: its margin missed obstacle contacts that
        // one process keeps, e.g. a bead resting at a small positive gap above the floor)
        let contacts: Vec<Contact> = detect_with_speed(
            &local.world,
            self.time,
            h,
            &self.params.activation,
            delta,
            head[0],
        )
        .into_iter()
        .filter(|c| local.owned[c.body])
        .collect();
        let data = StepData {
            h,
            t_end: self.time + h,
            restitution: self.params.restitution,
            mu: self.params.mu,
            close_gaps: self.params.activation.close_gaps,
        };
        // the body-level problem (2.10) of the subdomain: rows of the owned contacts over the
        // owned and ghost beads (crate::nsgs)
        let problem = StepProblem::new(&local.world, &contacts, &data);
        let bad = if problem.is_err() { 1.0 } else { 0.0 };
        let key = |c: &Contact| -> (usize, Partner) {
            let p = match c.partner {
                Partner::Body(j) => Partner::Body(local.gid[j]),
                o => o,
            };
            (local.gid[c.body], p)
        };
        let mut r = vec![0.0; 3 * contacts.len()];
        let mut warm_started = 0usize;
        if self.params.warm_start {
            for (i, c) in contacts.iter().enumerate() {
                if let Some(prev) = self.warm.get(&key(c)) {
                    r[3 * i..3 * i + 3].copy_from_slice(prev);
                    warm_started += 1;
                }
            }
        }
        let interface = contacts
            .iter()
            .filter(|c| matches!(c.partner, Partner::Body(j) if !local.owned[j]))
            .count();
        let max_penetration = contacts
            .iter()
            .map(|c| (-c.gap).max(0.0))
            .fold(0.0, f64::max);
        let mut counts = [
            contacts.len() as f64,
            warm_started as f64,
            bad,
            ghosts.beads.len() as f64,
            interface as f64,
            migrated_here as f64,
        ];
        self.comm.sum(&mut counts);
        let problem = match problem {
            Ok(p) if counts[2] == 0.0 => p,
            Ok(_) => {
                return Err(SimulationError::Parameter(format!(
                    "step {k}: an invalid contact on another rank"
                )))
            }
            Err(source) => return Err(SimulationError::StepProblem { step: k, source }),
        };
        let v_free: Vec<[f64; 6]> = problem
            .f
            .iter()
            .zip(&problem.inv_mass)
            .map(|(f, m)| std::array::from_fn(|d| f[d] * m[d]))
            .collect();
        let q = velocities(&problem, &v_free);
        let n_contacts = counts[0] as usize;
        let assembly_ms = t0.elapsed().as_secs_f64() * 1e3;

        // the solve: subdomain nonsmooth Gauss–Seidel on the global error
        let t1 = Instant::now();
        let (tol, limit) = match self.params.method {
            StepMethod::Nsgs(s) => (s.tol, s.time_limit),
            StepMethod::Library => (self.params.solver.tol, self.params.solver.time_limit),
        };
        let limit = limit.unwrap_or(Duration::from_secs(600));
        // over-relaxation of the contacts inside a subdomain, on the schedule of one process
        // (crate::nsgs): ω from the second sweep, halved towards 1 when the (global) error
        // did not fall over RELAX_WINDOW sweeps; every rank sees the same error, hence ω
        let mut omega = match self.params.method {
            StepMethod::Nsgs(s) if s.relaxation.is_finite() => s.relaxation.clamp(1.0, 1.99),
            _ => 1.0,
        };
        let mut window_start = f64::INFINITY;
        let mut v = v_free.clone();
        let mut sweeps = 0usize;
        let (mut err, mut status) = (0.0, "no_contact");
        let mut imp = vec![[0.0; 6]; v.len()];
        if n_contacts > 0 {
            // mass splitting (subdomain::SplitRow): per local bead, how many ranks' sweeps
            // move it; only the ghosts some contact touches are exchanged in the solve
            let (share, active) = self.shares(&ghosts, &local, &problem);
            let split = split_rows(&problem, &share);
            imp = self.sync_exact(&active, &local, &problem, &r, &v_free, &mut v);
            let mut dv = vec![[0.0; 6]; v.len()];
            // ‖q‖ over the ranks, for the sweeps' error proxy
            let mut qsq = [q.iter().flatten().map(|x| x * x).sum::<f64>()];
            self.comm.sum(&mut qsq);
            let qn = qsq[0].sqrt();
            // beads whose contacts are over-relaxed: owned, and in no interface contact (a
            // contact with a ghost, coupled by Jacobi across the ranks; over-relaxing its
            // neighbours too made some steps take 5–15× the sweeps, docs/distributed.md)
            let mut relaxed = local.owned.clone();
            for row in &problem.rows {
                if let Some(b) = row.b {
                    if !(local.owned[row.a] && local.owned[b]) {
                        relaxed[row.a] = false;
                        relaxed[b] = false;
                    }
                }
            }
            let shared_owned: Vec<usize> = local
                .of_owned
                .iter()
                .copied()
                .filter(|&l| share[l] > 1.0)
                .collect();
            let mut own_dv = vec![[0.0; 6]; shared_owned.len()];
            // `exact`: v = M⁻¹(f + H r) to rounding; `real`: e is the error of docs/error.md
            // at (r, v), not the sweep's proxy
            let (mut exact, mut real) = (true, true);
            // after a failed check of the real error, this many sweeps before the next one
            let (mut wait, mut backoff) = (0usize, 1usize);
            let (mut e, mut scale, mut late) = self.global_error(&problem, &q, &r, &v, false);
            status = loop {
                if !e.is_finite() {
                    break "numerical_error";
                }
                if e <= tol {
                    if exact && real {
                        break "converged";
                    }
                    imp = self.sync_exact(&active, &local, &problem, &r, &v_free, &mut v);
                    (exact, real) = (true, true);
                    (e, scale, late) = self.global_error(&problem, &q, &r, &v, false);
                    if e > tol {
                        backoff = (2 * backoff).min(16);
                        wait = backoff;
                    }
                    continue;
                }
                if sweeps >= self.max_sweeps {
                    break "max_iterations";
                }
                if late {
                    break "time_limit";
                }
                dv.fill([0.0; 6]);
                let om = if sweeps == 0 { 1.0 } else { omega };
                let sums = sweep(&problem, &split, &mut r, &mut v, &mut dv, om, &relaxed);
                sweeps += 1;
                if sweeps % REFRESH == 0 {
                    imp = self.sync_exact(&active, &local, &problem, &r, &v_free, &mut v);
                    exact = true;
                } else {
                    // the owned beads' own changes are in v already: send and add only
                    // the ghosts' changes
                    for (o, &l) in own_dv.iter_mut().zip(&shared_owned) {
                        *o = dv[l];
                    }
                    for &l in &local.of_owned {
                        dv[l] = [0.0; 6];
                    }
                    self.reduce_ghosts(&active, &local, &mut dv);
                    for &l in &local.of_owned {
                        for d in 0..6 {
                            v[l][d] += dv[l][d];
                        }
                    }
                    // a split bead: v holds the sum t of the k ranks' changes (each k times
                    // too large, subdomain::SplitRow); keep their mean
                    for (o, &l) in own_dv.iter().zip(&shared_owned) {
                        let k = share[l];
                        for d in 0..6 {
                            let t = dv[l][d] + o[d];
                            v[l][d] += t / k - t;
                        }
                    }
                    self.broadcast_ghosts(&active, &local, &mut v);
                    exact = false;
                }
                // the proxy of one process (crate::nsgs): the sums of the pairs the sweep
                // met, reduced with the time-limit flag in one allreduce
                let mut head = [
                    sums.residual_sq,
                    sums.r_sq,
                    sums.u_sq,
                    f64::from(u8::from(t1.elapsed() > limit)),
                ];
                self.comm.sum(&mut head);
                late = head[3] > 0.0;
                let proxy_scale = qn.max(head[1].sqrt()).max(head[2].sqrt());
                let proxy = if proxy_scale > f64::EPSILON {
                    head[0].sqrt() / proxy_scale
                } else {
                    head[0].sqrt()
                };
                if sweeps % RELAX_WINDOW == 0 {
                    if omega > 1.0 && proxy.partial_cmp(&window_start) != Some(Ordering::Less) {
                        omega = 1.0 + 0.5 * (omega - 1.0);
                        if omega < 1.01 {
                            omega = 1.0;
                        }
                    }
                    window_start = proxy;
                }
                wait = wait.saturating_sub(1);
                let last = sweeps >= self.max_sweeps || late;
                // the real error also at every exact refresh: across the interface the proxy
                // meets ghost velocities one exchange old and may lag behind it
                let refreshed = sweeps % REFRESH == 0;
                if !proxy.is_finite() || last || refreshed || (proxy <= tol && wait == 0) {
                    (e, scale, late) = self.global_error(&problem, &q, &r, &v, late);
                    real = true;
                } else {
                    // above the tolerance by the proxy: sweep on (never reported)
                    e = proxy.max(tol * (1.0 + f64::EPSILON) + f64::MIN_POSITIVE);
                    real = false;
                }
            };
            if !(exact && real) {
                imp = self.sync_exact(&active, &local, &problem, &r, &v_free, &mut v);
                (e, scale, _) = self.global_error(&problem, &q, &r, &v, false);
            }
            err = e;
            self.residual_velocity = e.max(tol) * scale;
        } else {
            self.residual_velocity = 0.0;
        }
        let solve_ms = t1.elapsed().as_secs_f64() * 1e3;

        // the θ-method (2.7) on the owned beads; contacts and warm starts kept in global ids
        let theta = self.params.theta;
        let mut finite = 1.0;
        for (oi, (_, b)) in self.beads.iter_mut().enumerate() {
            let l = local.of_owned[oi];
            let vn = Vec3::from_slice(&v[l][..3]);
            let wn = Vec3::from_slice(&v[l][3..]);
            if !(vn.is_finite() && wn.is_finite()) {
                finite = 0.0;
            }
            b.position += (b.velocity * (1.0 - theta) + vn * theta) * h;
            b.velocity = vn;
            b.angular_velocity = if b.rotation_locked { Vec3::ZERO } else { wn };
            self.forces[oi] = Vec3::from_slice(&imp[l][..3]) * (1.0 / h);
        }
        let mut fin = [finite];
        self.comm.sum(&mut fin);
        if fin[0] < size as f64 {
            return Err(SimulationError::NonFinite(k));
        }
        // the measured work of each owned bead: BEAD_WORK plus sweeps × the contacts it owns
        let mut owned_contacts = vec![0u64; local.world.bodies.len()];
        for c in &contacts {
            owned_contacts[c.body] += 1;
        }
        self.work.resize(self.beads.len(), 0);
        let mut rank_work = 0u64;
        for (oi, w) in self.work.iter_mut().enumerate() {
            let add = BEAD_WORK + owned_contacts[local.of_owned[oi]] * sweeps as u64;
            // no overflow in practice (≈ 10⁵ a step), but never a panic either, e.g. with
            // --rebalance-every 0 (the counter never restarts)
            *w = w.saturating_add(add);
            rank_work = rank_work.saturating_add(add);
        }
        self.warm.clear();
        self.contacts.clear();
        for (i, c) in contacts.iter().enumerate() {
            let rr = [r[3 * i], r[3 * i + 1], r[3 * i + 2]];
            let (a, p) = key(c);
            self.warm.insert((a, p), rr);
            let mut g = c.clone();
            g.body = a;
            g.partner = p;
            g.impulse = rr;
            self.contacts.push(g);
        }
        self.time += h;

        // position correction in rounds: ghosts refreshed, penetrations over owned pairs
        // measured (reduced), and while some exceeds the trigger each rank corrects its
        // owned + ghost beads and keeps its owned beads' new positions
        let (mut proj_work, mut proj_sweeps) = (0.0, 0.0);
        let (mut touching, mut pen_sum, mut pen_max);
        let mut round = 0;
        loop {
            let ghosts = self.exchange_ghosts(2.0 * self.rmax + 0.05 * self.rmin + 1e-9, true);
            let mut local = self.local(&ghosts);
            (touching, pen_sum, pen_max) = self.owned_penetrations(&local);
            let mut worst = [pen_max];
            self.comm.max(&mut worst);
            let Some(pr) = self.params.projection else {
                break;
            };
            if round >= PROJECTION_ROUNDS || worst[0] <= pr.trigger * self.rmin {
                break;
            }
            round += 1;
            let energy = |b: &Sphere, g: Vec3| b.kinetic_energy() - b.mass * g.dot(b.position);
            let before: f64 = self
                .beads
                .iter()
                .map(|(_, b)| energy(b, self.gravity))
                .sum();
            let s = project(&mut local.world, self.time, &pr);
            for (oi, (_, b)) in self.beads.iter_mut().enumerate() {
                let src = &local.world.bodies[local.of_owned[oi]];
                b.position = src.position;
                b.velocity = src.velocity;
                b.angular_velocity = src.angular_velocity;
            }
            let after: f64 = self
                .beads
                .iter()
                .map(|(_, b)| energy(b, self.gravity))
                .sum();
            proj_work += after - before;
            proj_sweeps += s.sweeps as f64;
        }
        let ke: f64 = self.beads.iter().map(|(_, b)| b.kinetic_energy()).sum();
        let pe: f64 = self
            .beads
            .iter()
            .map(|(_, b)| -b.mass * self.gravity.dot(b.position))
            .sum();
        let mut sums = [ke, pe, proj_work, touching, pen_sum, rank_work as f64];
        self.comm.sum(&mut sums);
        let step_comm = self.comm.seconds() - comm0;
        let mut maxes = [
            max_penetration,
            pen_max,
            proj_sweeps,
            assembly_ms,
            step_comm,
            self.beads.len() as f64,
            rank_work as f64,
        ];
        self.comm.max(&mut maxes);
        let mut mean_comm = [step_comm];
        self.comm.sum(&mut mean_comm);
        self.steps_done += 1;
        let converged = status == "converged" || status == "no_contact";
        let stats = StepStats {
            step: k,
            time: self.time,
            contacts: n_contacts,
            subproblems: usize::from(n_contacts > 0),
            inner_iterations: sweeps,
            solve_ms,
            assembly_ms: maxes[3],
            delassus_ms: 0.0,
            error: err,
            rule_6_1: 0.0,
            status: status.to_string(),
            converged,
            kinetic_energy: sums[0],
            potential_energy: sums[1],
            max_penetration: maxes[0],
            warm_started: counts[1] as usize,
            delta,
            end_max_penetration: maxes[1],
            end_mean_penetration: if sums[3] > 0.0 {
                sums[4] / sums[3]
            } else {
                0.0
            },
            projection_work: sums[2],
            projection_sweeps: maxes[2] as usize,
        };
        Ok(DistributedStats {
            step: stats,
            ranks: size,
            sweeps,
            step_ms: t0.elapsed().as_secs_f64() * 1e3,
            comm_ms: maxes[4] * 1e3,
            comm_mean_ms: mean_comm[0] / size as f64 * 1e3,
            messages: self.comm.messages() - msg0,
            bytes: self.comm.bytes() - bytes0,
            ghosts: counts[3] as usize,
            interface_contacts: counts[4] as usize,
            migrated: counts[5] as usize,
            migration_all_to_all: self.migrated_all_to_all,
            imbalance: maxes[5] * size as f64 / self.total.max(1) as f64,
            work_imbalance: if sums[5] > 0.0 {
                maxes[6] * size as f64 / sums[5]
            } else {
                1.0
            },
            rebalanced,
        })
    }

    /// Penetrations of the pairs owned here (bead pairs with the lower id owned, and every
    /// owned bead with the obstacles) in the local world: (pairs with g ≤ 0, Σ −g, max −g).
    fn owned_penetrations(&self, local: &Local) -> (f64, f64, f64) {
        let (mut touching, mut sum, mut max) = (0.0, 0.0, 0.0f64);
        let mut add = |g: f64| {
            if g <= 0.0 {
                touching += 1.0;
                sum += -g;
                max = max.max(-g);
            }
        };
        for (i, j) in candidate_pairs(&local.world, 0.0) {
            if local.owned[i] {
                let (a, b) = (&local.world.bodies[i], &local.world.bodies[j]);
                add((a.position - b.position).norm() - a.radius - b.radius);
            }
        }
        for &l in &local.of_owned {
            let b = &local.world.bodies[l];
            for ob in &self.obstacles {
                add(ob.proximity(b.position, b.radius, self.time).gap);
            }
        }
        (touching, sum, max)
    }

    /// Largest speed |ẋ| + R|ω| over all beads (reduced).
    pub fn max_speed(&mut self) -> f64 {
        let mut m = [self
            .beads
            .iter()
            .map(|(_, b)| b.velocity.norm() + b.radius * b.angular_velocity.norm())
            .fold(0.0, f64::max)];
        self.comm.max(&mut m);
        m[0]
    }

    /// Total kinetic + potential energy (reduced).
    pub fn energy(&mut self) -> f64 {
        let mut e = [self
            .beads
            .iter()
            .map(|(_, b)| b.kinetic_energy() - b.mass * self.gravity.dot(b.position))
            .sum::<f64>()];
        self.comm.sum(&mut e);
        e[0]
    }

    /// Writes this rank's part of the frame of the current state through the one VTK writer
    /// ([`VtkWriter::write_frame`], docs/distributed.md); every rank calls it (the region the
    /// obstacles are drawn over is reduced over the ranks).
    pub fn frame(&mut self, vtk: &mut VtkWriter) -> std::io::Result<()> {
        let h = self.params.h;
        let f = FrameData {
            step: self.steps_done,
            time: self.time,
            bodies: self.beads.iter().map(|(_, b)| FrameBody::ball(b)).collect(),
            contacts: (self.contacts.iter())
                .map(|c| FrameContact::of(c, h))
                .collect(),
            obstacles: &self.obstacles,
        };
        let ids: Vec<usize> = self.beads.iter().map(|(gid, _)| *gid).collect();
        let comm = &mut self.comm;
        let part = FramePart {
            rank: comm.rank(),
            ranks: comm.size(),
            ids: &ids,
            max: &mut |x| comm.max(x),
        };
        vtk.write_frame(&f, &self.forces, Some(part))
    }
}

fn pack_bead(buf: &mut Vec<f64>, gid: usize, b: &Sphere) {
    let (x, v, w) = (b.position, b.velocity, b.angular_velocity);
    buf.extend_from_slice(&[
        gid as f64,
        x.x,
        x.y,
        x.z,
        v.x,
        v.y,
        v.z,
        w.x,
        w.y,
        w.z,
        b.radius,
        b.mass,
        if b.rotation_locked { 1.0 } else { 0.0 },
    ]);
}

fn unpack_bead(s: &[f64]) -> (usize, Sphere) {
    let mut b = Sphere::new(Vec3::new(s[1], s[2], s[3]), s[10], s[11]);
    b.velocity = Vec3::new(s[4], s[5], s[6]);
    b.angular_velocity = Vec3::new(s[7], s[8], s[9]);
    b.rotation_locked = s[12] != 0.0;
    (s[0] as usize, b)
}
