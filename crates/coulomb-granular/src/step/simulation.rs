//! The Moreau–Jean time-stepping loop (2.5)–(2.7): at each step, detect the active contacts,
//! assemble the incremental problem (2.10), solve it with `coulomb::solver`, then update
//! velocities and positions with the θ-method.

use crate::assembly::{assemble, free_momentum, mass_diagonal, StepData};
use crate::contact::{detect_with, Activation, Contact, Partner};
use crate::nsgs::{self, NsgsSettings, NsgsStatus, StepProblem, StepProblemError};
use crate::projection::{penetrations, project_contacts, Projection};
use crate::world::World;
use coulomb::problem::{GlobalProblem, Problem, ProblemError};
use coulomb::solver::{self, Guess, OuterRecord, Settings, SolveError, Status};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Parameters of the time stepping.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Params {
    /// time step h (s)
    pub h: f64,
    /// θ of the position update (2.7), in [0, 1]
    pub theta: f64,
    /// Newton restitution coefficient e ∈ [0, 1] (Moreau's rule)
    pub restitution: f64,
    /// friction coefficient μ of every contact
    pub mu: f64,
    /// the activation rule of the index set
    pub activation: Activation,
    /// settings of `coulomb::solver` (not serialized: a deserialized `Params` has
    /// `Settings::default()` here; whoever restores parameters sets it again)
    #[serde(skip)]
    pub solver: Settings,
    /// warm start from the previous step's impulses of persisting contacts
    pub warm_start: bool,
    /// position correction after each step ([`crate::projection`]); `None`: the plain
    /// Moreau–Jean scheme (the paper's)
    pub projection: Option<Projection>,
    /// which solver takes each step (`solver` is used by [`StepMethod::Library`] only).
    /// Default [`StepMethod::Library`]: every caller that sets `solver` (`coulomb paper`, the
    /// FCLIB corpus, Python's `solver=`) gets the steps solved by it, and rolling resistance
    /// and per-step histories ([`Simulation::last_history`]) need it; for large heaps at
    /// err ≤ 1e-4 use `StepMethod::Nsgs(NsgsSettings::default())`, as `coulomb simulate`
    /// does (docs/scaling.md)
    pub method: StepMethod,
    /// rolling-friction coefficient μ_r ≥ 0 (dimensionless): rolling torque impulse
    /// ≤ μ_r R_e r_N ([`crate::rolling`]); 0 (default): no rolling resistance
    pub rolling_friction: f64,
}

/// Which solver takes each step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum StepMethod {
    /// `coulomb::solver::solve_with_guess` with [`Params::solver`] on the assembled global
    /// problem (W = Hᵀ M⁻¹ H formed by the library)
    Library,
    /// body-level nonsmooth Gauss–Seidel, matrix-free and parallel ([`crate::nsgs`])
    Nsgs(NsgsSettings),
}

impl Default for Params {
    fn default() -> Self {
        Self {
            h: 0.02,
            theta: 0.5,
            restitution: 0.2,
            mu: 0.3,
            activation: Activation::accurate(),
            solver: Settings::default(),
            warm_start: true,
            projection: Some(Projection::default()),
            method: StepMethod::Library,
            rolling_friction: 0.0,
        }
    }
}

/// Why a step could not be taken.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimulationError {
    /// a parameter is out of range
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// the assembled problem is invalid (should not happen with finite states)
    #[error("assembly of step {step} failed: {source}")]
    Assembly {
        /// step index
        step: usize,
        /// the problem error
        source: ProblemError,
    },
    /// a contact of the body-level problem is invalid (should not happen with finite states)
    #[error("body-level problem of step {step}: {source}")]
    StepProblem {
        /// step index
        step: usize,
        /// the problem error
        source: StepProblemError,
    },
    /// the solver refused the problem
    #[error("solver failed at step {step}: {source}")]
    Solve {
        /// step index
        step: usize,
        /// the solver error
        source: SolveError,
    },
    /// velocities or positions became NaN or infinite
    #[error("non-finite state at step {0}")]
    NonFinite(usize),
}

/// Statistics of one time step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepStats {
    /// step index k (the step from t_k to t_{k+1})
    pub step: usize,
    /// t_{k+1}
    pub time: f64,
    /// active contacts
    pub contacts: usize,
    /// outer (fixed-point) iterations, i.e. subproblems (3.15) solved
    pub subproblems: usize,
    /// inner iterations, summed
    pub inner_iterations: usize,
    /// solver wall-clock time (ms), assembly excluded
    pub solve_ms: f64,
    /// assembly + detection time (ms)
    pub assembly_ms: f64,
    /// time to form the Delassus operator W = Hᵀ M⁻¹ H and q (ms), measured by a separate
    /// construction before the solve when [`Simulation::profile_delassus`] is set (the solver
    /// does the same work inside `solve_ms`); 0 otherwise
    pub delassus_ms: f64,
    /// error of docs/error.md of the returned solution (0 without contacts)
    pub error: f64,
    /// the paper's (6.1) measure at the last outer iteration (0 without contacts)
    pub rule_6_1: f64,
    /// solver status ("converged", …, or "no_contact")
    pub status: String,
    /// whether the solver reported convergence (true without contacts)
    pub converged: bool,
    /// kinetic energy at t_{k+1}
    pub kinetic_energy: f64,
    /// potential energy at t_{k+1}
    pub potential_energy: f64,
    /// largest penetration max(0, −g_k) over the active contacts at t_k
    pub max_penetration: f64,
    /// contacts that were warm started
    pub warm_started: usize,
    /// threshold δ_k of the activation rule used at this step (m)
    pub delta: f64,
    /// largest penetration max(0, −g) over all pairs at t_{k+1}, after the position correction
    pub end_max_penetration: f64,
    /// mean penetration over the pairs in touch (g ≤ 0) at t_{k+1}
    pub end_mean_penetration: f64,
    /// change of potential energy caused by the position correction (J; 0 without it)
    pub projection_work: f64,
    /// Gauss–Seidel sweeps of the position correction (0: nothing to correct)
    pub projection_sweeps: usize,
}

impl StepStats {
    /// The statistics of step k (to t_{k+1} = `time`) known before its solve: the active
    /// contacts, their largest penetration at t_k and the activation threshold δ_k; the
    /// solve's fields are those of a step without contact until the solve sets them.
    fn before_solve(step: usize, time: f64, contacts: &[Contact], delta: f64) -> Self {
        StepStats {
            step,
            time,
            contacts: contacts.len(),
            subproblems: 0,
            inner_iterations: 0,
            solve_ms: 0.0,
            assembly_ms: 0.0,
            delassus_ms: 0.0,
            error: 0.0,
            rule_6_1: 0.0,
            status: "no_contact".into(),
            converged: true,
            kinetic_energy: 0.0,
            potential_energy: 0.0,
            max_penetration: contacts
                .iter()
                .map(|c| (-c.gap).max(0.0))
                .fold(0.0, f64::max),
            warm_started: 0,
            delta,
            end_max_penetration: 0.0,
            end_mean_penetration: 0.0,
            projection_work: 0.0,
            projection_sweeps: 0,
        }
    }
}

/// A one-thread rayon pool for small steps (built once; `None` if the system refuses a
/// thread, and the step then runs on the current pool).
fn serial_pool() -> Option<&'static rayon::ThreadPool> {
    static POOL: std::sync::OnceLock<Option<rayon::ThreadPool>> = std::sync::OnceLock::new();
    POOL.get_or_init(|| rayon::ThreadPoolBuilder::new().num_threads(1).build().ok())
        .as_ref()
}

/// The time-stepping simulation: a [`World`] advanced by [`Simulation::step`].
#[derive(Debug, Clone)]
pub struct Simulation {
    /// the mechanical system at t_k
    pub world: World,
    /// parameters
    pub params: Params,
    /// t_k
    pub time: f64,
    /// k
    pub steps_done: usize,
    /// the active contacts of the last step, with their impulses
    pub contacts: Vec<Contact>,
    /// the last step's outer history (for Fig. 9)
    pub last_history: Vec<OuterRecord>,
    /// the last step's problem, kept when `keep_problem` is set (FCLIB dumps)
    pub last_problem: Option<GlobalProblem>,
    /// keep each step's problem in `last_problem`
    pub keep_problem: bool,
    /// time the formation of the Delassus operator separately (`StepStats::delassus_ms`)
    pub profile_delassus: bool,
    /// the last step's impulses by contact key, sorted by key (warm starts by merge)
    pub(crate) previous: Vec<((usize, Partner), [f64; 3])>,
    /// bound ε_u = max(err, tol) · scale on the residual velocity of the last step's contacts
    pub(crate) residual_velocity: f64,
    /// rolling resistance (crate::rolling): warm start and last rolling impulses
    pub rolling: crate::rolling::RollingState,
}

impl Simulation {
    /// A simulation of `world` starting at t = 0.
    pub fn new(world: World, params: Params) -> Result<Self, SimulationError> {
        let p = &params;
        let bad = |s: String| Err(SimulationError::Parameter(s));
        if !(p.h.is_finite() && p.h > 0.0) {
            return bad(format!("time step h = {} must be positive", p.h));
        }
        if !(0.0..=1.0).contains(&p.theta) {
            return bad(format!("theta = {} is not in [0, 1]", p.theta));
        }
        if !(0.0..=1.0).contains(&p.restitution) {
            return bad(format!("restitution = {} is not in [0, 1]", p.restitution));
        }
        if !(p.mu >= 0.0 && p.mu.is_finite()) {
            return bad(format!("mu = {} is not a finite nonnegative number", p.mu));
        }
        if !(p.rolling_friction >= 0.0 && p.rolling_friction.is_finite()) {
            return bad(format!(
                "rolling friction = {} is not a finite nonnegative number",
                p.rolling_friction
            ));
        }
        if let Some(pr) = &p.projection {
            let ok = |x: f64| x.is_finite() && x > 0.0 && x < 1.0;
            if !(ok(pr.trigger) && ok(pr.target) && pr.max_sweeps > 0) {
                return bad(format!("projection {pr:?} out of range"));
            }
        }
        if let StepMethod::Nsgs(n) = &p.method {
            let omega_ok = n.relaxation.is_finite() && (1.0..2.0).contains(&n.relaxation);
            if !(n.tol.is_finite() && n.tol > 0.0 && n.max_sweeps > 0 && omega_ok) {
                return bad(format!("NSGS settings {n:?} out of range"));
            }
        }
        if !(0.0..=1.0).contains(&p.activation.gamma)
            || p.activation.delta.is_nan()
            || p.activation.delta < 0.0
        {
            return bad(format!("activation {:?} out of range", p.activation));
        }
        if let Some(t) = &world.materials {
            if let Err(e) = t.check() {
                return bad(format!("material table: {e}"));
            }
        }
        let materials = world.materials.as_ref().map_or(1, |t| t.len());
        for (i, o) in world.obstacles.iter().enumerate() {
            if o.material as usize >= materials {
                return bad(format!(
                    "obstacle {i} ('{}') has material {} of {materials}",
                    o.name, o.material
                ));
            }
        }
        check_spheres(&world.bodies, 0, materials)?;
        Ok(Self {
            world,
            params,
            time: 0.0,
            steps_done: 0,
            contacts: Vec::new(),
            last_history: Vec::new(),
            last_problem: None,
            keep_problem: false,
            profile_delassus: false,
            previous: Vec::new(),
            residual_velocity: 0.0,
            rolling: Default::default(),
        })
    }

    /// Appends `spheres` to the world (an inlet pouring new spheres mid-run), validated as
    /// [`Simulation::new`] validates its bodies; returns their indices. The existing spheres
    /// keep their indices, so the warm-start keys (sphere, partner) of the last step stay
    /// valid; the new spheres start without warm start. A sphere placed overlapping another
    /// is corrected by the position correction of the next step (if enabled) — place them
    /// apart.
    pub fn insert_bodies(
        &mut self,
        spheres: Vec<crate::world::Sphere>,
    ) -> Result<std::ops::Range<usize>, SimulationError> {
        let start = self.world.bodies.len();
        let materials = self.world.materials.as_ref().map_or(1, |t| t.len());
        check_spheres(&spheres, start, materials)?;
        self.world.bodies.extend(spheres);
        Ok(start..self.world.bodies.len())
    }

    /// One Moreau–Jean step from t_k to t_{k+1} = t_k + h:
    /// 1. index set: contacts active by the [`Activation`] rule at (q_k, v_k);
    /// 2. the incremental problem (2.10) of (2.5) with Moreau's impact law (assembly module);
    /// 3. its solution (v_{k+1}, r_{k+1}) by `coulomb::solver::solve_with_guess`, warm
    ///    started from the previous impulses of persisting contacts;
    /// 4. q_{k+1} = q_k + h((1 − θ) v_k + θ v_{k+1}) (2.7).
    ///
    /// With [`StepMethod::Nsgs`] a scene of fewer spheres than
    /// [`NsgsSettings::serial_below`](crate::nsgs::NsgsSettings::serial_below) is stepped on
    /// one thread (same numbers, less dispatch).
    pub fn step(&mut self) -> Result<StepStats, SimulationError> {
        if let StepMethod::Nsgs(s) = self.params.method {
            if self.world.bodies.len() < s.serial_below && rayon::current_num_threads() > 1 {
                if let Some(pool) = serial_pool() {
                    return pool.install(|| self.step_on_current_pool());
                }
            }
        }
        self.step_on_current_pool()
    }

    /// [`Simulation::step`] on the current rayon pool, as named phases: detect (with the
    /// index set's activation rule), assemble and solve (`solve_nsgs`, or `solve_library`
    /// with the assembled global problem), integrate, record the contacts, correct positions.
    fn step_on_current_pool(&mut self) -> Result<StepStats, SimulationError> {
        let k = self.steps_done;
        let h = self.params.h;
        let t0 = Instant::now();
        let delta = self.activation_threshold();
        let mut contacts = detect_with(&self.world, self.time, h, &self.params.activation, delta);
        let data = StepData {
            h,
            t_end: self.time + h,
            restitution: self.params.restitution,
            mu: self.params.mu,
            close_gaps: self.params.activation.close_gaps,
        };
        let mut stats = StepStats::before_solve(k, self.time + h, &contacts, delta);
        let v_new = if contacts.is_empty() {
            stats.assembly_ms = t0.elapsed().as_secs_f64() * 1e3;
            self.free_velocities()
        } else if let (StepMethod::Nsgs(settings), false) = (
            self.params.method,
            self.world.has_rolling(self.params.rolling_friction),
        ) {
            // with rolling resistance the step is the 6-component law of crate::rolling,
            // solved below whatever the method
            self.step_nsgs(&mut contacts, &data, &settings, &mut stats, t0)?
        } else {
            self.step_library(&mut contacts, &data, &mut stats, t0)?
        };
        if v_new.iter().any(|x| !x.is_finite()) {
            return Err(SimulationError::NonFinite(k));
        }
        self.integrate(&v_new);
        self.record_contacts(contacts);
        self.correct(&mut stats);
        self.steps_done += 1;
        stats.kinetic_energy = self.world.kinetic_energy();
        stats.potential_energy = self.world.potential_energy();
        Ok(stats)
    }

    /// v_{k+1} = M⁻¹ f of a step without contact (the free motion); no problem is kept.
    fn free_velocities(&mut self) -> Vec<f64> {
        self.last_history.clear();
        self.last_problem = None;
        let diag = mass_diagonal(&self.world);
        free_momentum(&self.world, self.params.h)
            .iter()
            .zip(&diag)
            .map(|(f, m)| f / m)
            .collect()
    }

    /// Steps 2–3 by the library: the incremental problem (2.10) assembled as a global
    /// problem, solved by `coulomb::solver::solve_with_guess` warm started from the previous
    /// impulses of persisting contacts (with rolling resistance, by `crate::rolling`);
    /// returns v_{k+1}.
    fn step_library(
        &mut self,
        contacts: &mut [Contact],
        data: &StepData,
        stats: &mut StepStats,
        t0: Instant,
    ) -> Result<Vec<f64>, SimulationError> {
        let k = self.steps_done;
        let problem = assemble(&self.world, contacts, data)
            .map_err(|source| SimulationError::Assembly { step: k, source })?;
        let r0 = self.warm_start(contacts, stats);
        // v consistent with the guess: v = M⁻¹ (H r + f)
        let mut hr = problem.f.clone();
        problem.h.gemv_acc(1.0, &r0, &mut hr);
        let v0: Vec<f64> = hr
            .iter()
            .zip(&problem.m.values)
            .map(|(x, m)| x / m)
            .collect();
        let guess = Guess { r: r0, v: Some(v0) };
        stats.assembly_ms = t0.elapsed().as_secs_f64() * 1e3;
        if self.profile_delassus {
            let td = Instant::now();
            let delassus = coulomb::delassus::Delassus::new(&problem)
                .map_err(|source| SimulationError::Assembly { step: k, source })?;
            stats.delassus_ms = td.elapsed().as_secs_f64() * 1e3;
            drop(delassus);
        }
        let mut problem = problem;
        let t1 = Instant::now();
        // ---- hook: rolling resistance (crate::rolling). With μ_r > 0 the step's
        // 6-component problem is solved there (problem.f then holds the rolling impulses);
        // otherwise the library's solver, as before.
        let rolling = self
            .world
            .has_rolling(self.params.rolling_friction)
            .then(|| {
                crate::rolling::solve_step(
                    &self.world,
                    contacts,
                    &mut problem,
                    self.params.rolling_friction,
                    &self.params.solver,
                    &guess.r,
                    &mut self.rolling,
                )
            });
        let wrapped = Problem::Global(problem);
        let sol = match rolling {
            Some(sol) => sol,
            None => solver::solve_with_guess(&wrapped, &self.params.solver, Some(&guess)),
        }
        .map_err(|source| SimulationError::Solve { step: k, source })?;
        // ---- end of the rolling-resistance hook
        stats.solve_ms = t1.elapsed().as_secs_f64() * 1e3;
        stats.subproblems = sol.outer_iterations;
        stats.inner_iterations = sol.inner_iterations;
        stats.error = sol.error;
        stats.rule_6_1 = sol.history.last().map(|r| r.rule_6_1).unwrap_or(0.0);
        stats.converged = sol.status == Status::Converged;
        stats.status = serde_json::to_value(sol.status)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_else(|| format!("{:?}", sol.status));
        let Problem::Global(problem) = wrapped else {
            return Err(SimulationError::NonFinite(k));
        };
        let v = match &sol.v {
            Some(v) if v.len() == problem.dofs() => v.clone(),
            _ => {
                let mut hr = problem.f.clone();
                problem.h.gemv_acc(1.0, &sol.r, &mut hr);
                hr.iter()
                    .zip(&problem.m.values)
                    .map(|(x, m)| x / m)
                    .collect()
            }
        };
        self.residual_velocity =
            sol.error.max(self.params.solver.tol) * local_scale(&problem, &sol.r, &v);
        self.keep_impulses(contacts, &sol.r);
        self.last_history = sol.history;
        self.last_problem = self.keep_problem.then_some(problem);
        Ok(v)
    }

    /// The position update (2.7), q_{k+1} = q_k + h((1 − θ) v_k + θ v_{k+1}), sphere by
    /// sphere, and (v, ω) ← v_{k+1} (ω zero for a sphere whose rotation is locked).
    fn integrate(&mut self, v_new: &[f64]) {
        let (h, theta) = (self.params.h, self.params.theta);
        self.world
            .bodies
            .par_iter_mut()
            .zip(v_new.par_chunks(6))
            .for_each(|(b, vn6)| {
                let vn = crate::math::Vec3::from_slice(&vn6[..3]);
                let vo = b.velocity;
                b.position += (vo * (1.0 - theta) + vn * theta) * h;
                b.velocity = vn;
                b.angular_velocity = if b.rotation_locked {
                    crate::math::Vec3::ZERO
                } else {
                    crate::math::Vec3::from_slice(&vn6[3..6])
                };
            });
    }

    /// Keeps the step's contacts (their impulses are the next step's warm start) and
    /// advances the time to t_{k+1}.
    fn record_contacts(&mut self, contacts: Vec<Contact>) {
        if contacts.is_empty() {
            self.previous.clear();
            self.residual_velocity = 0.0;
        }
        self.contacts = contacts;
        self.time += self.params.h;
    }

    /// The position correction at t_{k+1} ([`project_contacts`]), or the end penetrations
    /// alone without it; both into `stats`.
    fn correct(&mut self, stats: &mut StepStats) {
        let pen = match &self.params.projection {
            Some(pr) => {
                let (p, pen) = project_contacts(&mut self.world, self.time, pr, &mut self.contacts);
                stats.projection_work = p.work;
                stats.projection_sweeps = p.sweeps;
                pen
            }
            None => penetrations(&self.world, self.time),
        };
        stats.end_max_penetration = pen.max;
        stats.end_mean_penetration = pen.mean;
    }

    /// The warm start r₀ of the step: the previous impulse of each persisting contact (same
    /// (body, partner) key), 0 for new ones; counts the warm-started contacts into `stats`.
    /// Both lists are sorted by key ([`detect_with`] sorts the contacts): each chunk of
    /// contacts finds its first key by bisection and merges from there, in parallel.
    fn warm_start(&self, contacts: &[Contact], stats: &mut StepStats) -> Vec<f64> {
        let mut r0 = vec![0.0; 3 * contacts.len()];
        if self.params.warm_start {
            const CHUNK: usize = 512;
            let prev = &self.previous;
            let found: usize = r0
                .par_chunks_mut(3 * CHUNK)
                .zip(contacts.par_chunks(CHUNK))
                .map(|(r, cs)| {
                    let Some(first) = cs.first() else {
                        return 0;
                    };
                    let mut k = prev.partition_point(|x| x.0 < first.key());
                    let mut found = 0;
                    for (i, c) in cs.iter().enumerate() {
                        let key = c.key();
                        while k < prev.len() && prev[k].0 < key {
                            k += 1;
                        }
                        if let Some((pk, p)) = prev.get(k) {
                            if *pk == key {
                                r[3 * i..3 * i + 3].copy_from_slice(p);
                                found += 1;
                            }
                        }
                    }
                    found
                })
                .sum();
            stats.warm_started += found;
        }
        r0
    }

    /// Stores the step's impulses `r` (3 per contact) into `contacts` and, by key, into the
    /// warm-start list (sorted by key).
    fn keep_impulses(&mut self, contacts: &mut [Contact], r: &[f64]) {
        let n = contacts.len().min(r.len() / 3);
        self.previous = contacts[..n]
            .par_iter_mut()
            .zip(r.par_chunks_exact(3))
            .map(|(c, ri)| {
                c.impulse = [ri[0], ri[1], ri[2]];
                (c.key(), c.impulse)
            })
            .collect();
        if !self.previous.is_sorted_by_key(|x| x.0) {
            self.previous.sort_unstable_by_key(|x| x.0);
        }
    }

    /// Steps 2–3 by body-level nonsmooth Gauss–Seidel ([`crate::nsgs`]): the step problem in
    /// body-block form (no W), solved to `settings.tol`; returns v_{k+1}.
    fn step_nsgs(
        &mut self,
        contacts: &mut [Contact],
        data: &StepData,
        settings: &NsgsSettings,
        stats: &mut StepStats,
        t0: Instant,
    ) -> Result<Vec<f64>, SimulationError> {
        let k = self.steps_done;
        let mut problem = StepProblem::new(&self.world, contacts, data)
            .map_err(|source| SimulationError::StepProblem { step: k, source })?;
        if settings.coarse_every > 0 && settings.coarse_cell > 0 {
            problem = problem.with_positions(&self.world);
        }
        let r0 = self.warm_start(contacts, stats);
        stats.assembly_ms = t0.elapsed().as_secs_f64() * 1e3;
        let t1 = Instant::now();
        let sol = nsgs::solve(&problem, &r0, settings, true);
        stats.subproblems = 1;
        stats.inner_iterations = sol.sweeps;
        stats.error = sol.error;
        stats.converged = sol.status == NsgsStatus::Converged;
        stats.status = serde_json::to_value(sol.status)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_else(|| format!("{:?}", sol.status));
        // Gauss–Seidel can stall (cycle) on a frictional step: then the library's solver
        // finishes the same problem (2.10) from Gauss–Seidel's iterate (unless turned off)
        let finish = if stats.converged
            || !settings.library_finish
            || contacts.len() > LIBRARY_FINISH_MAX_CONTACTS
        {
            None
        } else {
            self.finish_with_library(&problem, &sol, &r0, settings, stats)?
        };
        let (r, v, scale) = finish.unwrap_or((sol.r, sol.v, sol.scale));
        stats.solve_ms = t1.elapsed().as_secs_f64() * 1e3;
        self.residual_velocity = stats.error.max(settings.tol) * scale;
        self.keep_impulses(contacts, &r);
        self.last_history.clear();
        self.last_problem = if self.keep_problem {
            Some(
                problem
                    .to_global()
                    .map_err(|source| SimulationError::Assembly { step: k, source })?,
            )
        } else {
            None
        };
        Ok(v)
    }

    /// The finish of a step that Gauss–Seidel left above its tolerance: the library's solver
    /// (`params.solver` with the step's tolerance and time limit) on the same problem (2.10)
    /// as a global problem, warm started from Gauss–Seidel's iterate (or the warm start if that
    /// is not finite). Its result replaces Gauss–Seidel's when it converges or ends with a
    /// smaller error of docs/error.md (both measured on the same stored problem); `stats` then
    /// counts its iterations and carries its status and error. Returns (r, v, scale) or `None`
    /// (Gauss–Seidel's result stands).
    fn finish_with_library(
        &self,
        problem: &StepProblem,
        sol: &nsgs::NsgsSolution,
        r0: &[f64],
        settings: &NsgsSettings,
        stats: &mut StepStats,
    ) -> Result<Option<Finish>, SimulationError> {
        let k = self.steps_done;
        let global = problem
            .to_global()
            .map_err(|source| SimulationError::Assembly { step: k, source })?;
        let start = if sol.r.len() == r0.len() && sol.r.iter().all(|x| x.is_finite()) {
            sol.r.clone()
        } else {
            r0.to_vec()
        };
        let v_of = |global: &GlobalProblem, r: &[f64]| -> Vec<f64> {
            let mut hr = global.f.clone();
            global.h.gemv_acc(1.0, r, &mut hr);
            hr.iter()
                .zip(&global.m.values)
                .map(|(x, m)| x / m)
                .collect()
        };
        let guess = Guess {
            v: Some(v_of(&global, &start)),
            r: start,
        };
        let lib = Settings {
            tol: settings.tol,
            time_limit: settings.time_limit,
            ..self.params.solver.clone()
        };
        let wrapped = Problem::Global(global);
        let Ok(ls) = solver::solve_with_guess(&wrapped, &lib, Some(&guess)) else {
            return Ok(None);
        };
        let better = ls.status == Status::Converged
            || (ls.error.is_finite() && (ls.error < sol.error || !sol.error.is_finite()));
        if !better || ls.r.iter().any(|x| !x.is_finite()) {
            return Ok(None);
        }
        let Problem::Global(global) = wrapped else {
            return Ok(None);
        };
        let v = match &ls.v {
            Some(v) if v.len() == global.dofs() => v.clone(),
            _ => v_of(&global, &ls.r),
        };
        stats.subproblems += ls.outer_iterations;
        stats.inner_iterations += ls.inner_iterations;
        stats.error = ls.error;
        stats.converged = ls.status == Status::Converged;
        stats.status = serde_json::to_value(ls.status)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_else(|| format!("{:?}", ls.status));
        let scale = local_scale(&global, &ls.r, &v);
        Ok(Some((ls.r, v, scale)))
    }

    /// The threshold δ_k of the activation rule at this step: twice the largest lift h ε_u
    /// that the last step's solver error allows (ε_u = max(err, tol) · scale of
    /// docs/error.md bounds the residual normal velocity of a resting contact), at least the
    /// activation's floor, at most 1 % of the smallest radius (docs/granular.md, "Activation
    /// and tolerance").
    pub fn activation_threshold(&self) -> f64 {
        let rmin = self
            .world
            .bodies
            .iter()
            .map(|b| b.radius)
            .fold(f64::INFINITY, f64::min);
        if !self.params.activation.delta_from_tolerance {
            return self.params.activation.delta;
        }
        let lift = 2.0 * self.params.h * self.residual_velocity;
        let cap = if rmin.is_finite() { 0.01 * rmin } else { 0.0 };
        lift.min(cap).max(self.params.activation.delta)
    }

    /// Largest speed |ẋ| + R|ω| over the spheres.
    pub fn max_speed(&self) -> f64 {
        self.world
            .bodies
            .iter()
            .map(|b| b.velocity.norm() + b.radius * b.angular_velocity.norm())
            .fold(0.0, f64::max)
    }
}

/// Checks spheres (numbered from `first`): positive finite radius and mass, finite state,
/// material index below `materials`.
pub(crate) fn check_spheres(
    spheres: &[crate::world::Sphere],
    first: usize,
    materials: usize,
) -> Result<(), SimulationError> {
    for (i, b) in spheres.iter().enumerate() {
        let valid = b.radius > 0.0
            && b.mass > 0.0
            && b.radius.is_finite()
            && b.mass.is_finite()
            && b.position.is_finite()
            && b.velocity.is_finite()
            && b.angular_velocity.is_finite();
        if !valid {
            return Err(SimulationError::Parameter(format!(
                "body {} has invalid radius, mass or state",
                first + i
            )));
        }
        if b.material as usize >= materials {
            return Err(SimulationError::Parameter(format!(
                "body {} has material {} of {materials}",
                first + i,
                b.material
            )));
        }
    }
    Ok(())
}

/// Above this many contacts a step that Gauss–Seidel leaves above its tolerance is not handed
/// to the library's solver (`NsgsSettings::library_finish`): it stands as Gauss–Seidel left it,
/// reported not converged with Gauss–Seidel's status. The finish assembles the global problem
/// (2.10) (H as triplets, then compressed columns) and the library's solver forms W = H M⁻¹ Hᵀ:
/// about 2.7 KiB per contact on top of the body-level problem, measured as a transient of
/// +2.7 GB on a 10⁶-bead box (docs/scaling.md, "A million beads"), more than the whole
/// simulation holds otherwise — and on a step that large Gauss–Seidel stops on its time cap,
/// which the finish, given the same cap, does not beat.
pub const LIBRARY_FINISH_MAX_CONTACTS: usize = 200_000;

/// A step finished by the library's solver: (r, v, scale max(‖q‖, ‖r‖, ‖u‖)).
type Finish = (Vec<f64>, Vec<f64>, f64);

/// The scale max(‖q‖, ‖r‖, ‖u‖) of docs/error.md for a global problem (M diagonal):
/// q = Hᵀ M⁻¹ f + w, u = Hᵀ v + w.
fn local_scale(problem: &GlobalProblem, r: &[f64], v: &[f64]) -> f64 {
    let h = &problem.h;
    let minv_f: Vec<f64> = problem
        .f
        .iter()
        .zip(&problem.m.values)
        .map(|(f, m)| f / m)
        .collect();
    let mut q2 = 0.0;
    let mut u2 = 0.0;
    for j in 0..h.ncols {
        let (mut q, mut u) = (problem.w[j], problem.w[j]);
        for k in h.col_ptr[j]..h.col_ptr[j + 1] {
            let (i, x) = (h.row_idx[k], h.values[k]);
            q += x * minv_f.get(i).copied().unwrap_or(0.0);
            u += x * v.get(i).copied().unwrap_or(0.0);
        }
        q2 += q * q;
        u2 += u * u;
    }
    let r2: f64 = r.iter().map(|x| x * x).sum();
    q2.sqrt().max(u2.sqrt()).max(r2.sqrt())
}
