//! [`RigidWorld`]: the Moreau–Jean time stepping (2.5)–(2.7) of rigid bodies, each step's
//! incremental problem (2.10) in FCLIB convention
//!
//! ```text
//!     M v = H r + f,     u = Hᵀ v + w,     (uⁱ, rⁱ) satisfy Coulomb's law (2.9),
//! ```
//!
//! with, per moving body, the 6 dofs (v, Ω) (centre-of-mass velocity in world axes, angular
//! velocity in the principal body frame, [`crate::bodies::dynamics`]), M = diag(m, m, m, I₁, I₂, I₃),
//! f = (m (v_k + h g), I Ω_free) (Ω_free: the gyroscopic free-rotation predictor), and for
//! each manifold point i with frame (t₀ = n, t₁, t₂) and lever arms a = p − x the column
//! block of H holds (t_k, R_Aᵀ (a_A × t_k)) on A's dofs and −(t_k, R_Bᵀ (a_B × t_k)) on B's,
//! so (Hᵀ v)_k = t_k · (v_A(p) − v_B(p)). w carries an obstacle's prescribed velocity
//! (−t_k · V_B(p, t_{k+1})), Moreau's impact law on the normal row (ê u_{N,k},
//! [`crate::assembly::impact_offset`]) and, for a pair at a positive gap g_k that gravity's
//! look-ahead made active, the gap closure (1 − e) g_k / h (as the spheres'
//! [`crate::assembly::gap_closure`]: no hovering).
//!
//! # Solver
//! Body-level nonsmooth Gauss–Seidel ([`nsgs`]): one contact at a time with the others
//! frozen, its 3 × 3 Delassus block W_ii = J_A M_A⁻¹ J_Aᵀ + J_B M_B⁻¹ J_Bᵀ (the full world
//! inverse inertia R I⁻¹ Rᵀ inside), the one-contact law solved exactly by the library's
//! `solve_contact_law`. The error of docs/error.md is evaluated exactly on the stored
//! (M, H, f, w, μ) every few sweeps. On face contacts (4 coplanar points per face: W
//! rank-deficient) Gauss–Seidel may stall: when its error has not halved over
//! `stall_window` sweeps, or after `max_sweeps`, the step's global problem goes to
//! `coulomb::solver::solve_with_guess` from Gauss–Seidel's iterate, the same hand-over as the
//! sphere step's. The result with the smaller error on the stored problem is kept, and the
//! step's [`RigidStatus`] says whether it is ≤ the tolerance. With
//! [`RigidSettings::library_only`] (`method = "library"`) the library's solver alone solves
//! each step. Contacts with rolling resistance alternate that solve with passes over their
//! rolling impulses (`step/rolling.rs`).

use crate::bodies::dynamics::{rotation_from_wxyz, rotation_to_wxyz, BodyState};
use crate::bodies::joints::{Joint, JointDesc, SLOTS};
use crate::bodies::rigid::{RigidBodyDesc, RigidError, RigidObstacle, QUATERNION_TOLERANCE};
use crate::collision::contact::{Contact, Partner};
use crate::collision::manifold::{ContactKey, ContactPoint, Detector, PlacedObstacle};
use crate::world::{MaterialTable, Motion};
use coulomb::problem::GlobalProblem;
use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::shape::SharedShape;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

/// Settings of the rigid-body time stepping.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidSettings {
    /// time step h (s); default 1e-3
    pub h: f64,
    /// θ ∈ [0, 1] of the position update (2.7); default ½ (Siconos' mechanics default)
    pub theta: f64,
    /// gravity (m/s²); default (0, 0, −9.81)
    pub gravity: [f64; 3],
    /// tolerance on the error of docs/error.md of each step's problem; default 1e-8 (the
    /// rigid-body tolerance of the benchmarks)
    pub tolerance: f64,
    /// cap on Gauss–Seidel sweeps per step; default 2 000 (a scene's `max_sweeps`, 20 000 by
    /// default, the same cap as the sphere engine's [`crate::nsgs::NsgsSettings::max_sweeps`])
    pub max_sweeps: usize,
    /// Gauss–Seidel is judged stalled when the lowest error it has met has not halved over
    /// this many sweeps and, at that rate, would need more sweeps to reach the tolerance than
    /// it has done (then the library's solver takes over); default 100
    pub stall_window: usize,
    /// over-relaxation ω ∈ [1, 2) of the contact updates from the second sweep on, the
    /// meaning of the sphere engine's [`crate::nsgs::NsgsSettings::relaxation`]: the first
    /// sweep is plain, each update r_i' of a contact becomes P_{K_μ}(r_i + ω (r_i' − r_i)),
    /// and ω is halved towards 1 (ω ← 1 + (ω − 1)/2, 1 below 1.01) whenever Gauss–Seidel has
    /// not decreased over [`crate::nsgs::RELAX_WINDOW`] sweeps (judged on the exact error of
    /// the checks, where the sphere engine judges its sweep residual); default 1.5 (a scene's
    /// `relaxation`). A world whose plain sweeps were found drifting switches to ω = 1 for
    /// good ([`RigidWorld::plain_sweeps`]), as the sphere engine's ω falls to 1 within a step.
    pub relaxation: f64,
    /// wall-clock cap of one step's Gauss–Seidel, checked at its exact evaluations; reached,
    /// the step goes on as a stall does (to the library's solver, itself time-capped by
    /// `solver`); default 60 s, the sphere engine's
    /// [`crate::nsgs::NsgsSettings::time_limit`]; `None`: no cap
    pub time_limit: Option<std::time::Duration>,
    /// hand a step that Gauss–Seidel leaves above the tolerance to `coulomb::solver` on
    /// the step's global problem; default true
    pub library_finish: bool,
    /// solve every step's problem (2.10) by `coulomb::solver` alone, from the warm start,
    /// without Gauss–Seidel (a scene's `method = "library"`, as the sphere engine's
    /// [`crate::StepMethod::Library`]); default false
    pub library_only: bool,
    /// settings of the library's solver (its `tol` is replaced by `tolerance`)
    pub solver: coulomb::solver::Settings,
    /// γ ∈ [0, 1] of the activation rule g + γ h min(u_N, 0) ≤ δ; default 1
    pub activation_gamma: f64,
    /// δ ≥ 0 of the activation rule (m); default 1e-8
    pub activation_delta: f64,
    /// largest penetration accepted between bodies (and bodies and obstacles) at the start
    /// (m); default 1e-8
    pub max_initial_penetration: f64,
    /// warm start each contact from the impulse of the same manifold point (parry's
    /// feature ids) at the previous step; default true
    pub warm_start: bool,
    /// add (1 − e) g_k / h to the normal row of a pair at a positive gap g_k that gravity's
    /// look-ahead made active ([`crate::assembly::gap_closure`]'s rule; a scene's
    /// `gap_closure`); default true
    pub gap_closure: bool,
    /// correct the positions after each step when a contact ends deeper than 1e-3 of the
    /// thinnest half width, down to 1e-4 of it (the sphere scenes' projection,
    /// `correct_positions`); positions only, velocities and impulses untouched;
    /// default true
    pub position_correction: bool,
    /// keep each step's global problem ([`RigidWorld::last_problem`], `--dump-fclib`);
    /// default true
    pub keep_problem: bool,
}

impl Default for RigidSettings {
    fn default() -> Self {
        Self {
            h: 1e-3,
            theta: 0.5,
            gravity: [0.0, 0.0, -crate::world::GRAVITY],
            tolerance: 1e-8,
            max_sweeps: 2_000,
            stall_window: 100,
            relaxation: 1.5,
            time_limit: Some(std::time::Duration::from_secs(60)),
            library_finish: true,
            library_only: false,
            solver: coulomb::solver::Settings::default(),
            activation_gamma: 1.0,
            activation_delta: 1e-8,
            max_initial_penetration: 1e-8,
            warm_start: true,
            gap_closure: true,
            position_correction: true,
            keep_problem: true,
        }
    }
}

/// How a step's contact problem ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RigidStatus {
    /// no active contact (free flight)
    NoContact,
    /// error on the stored problem ≤ tolerance
    Converged,
    /// error above the tolerance after Gauss–Seidel (and the library's solver, if enabled)
    NotConverged,
}

/// Report of one step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RigidStepReport {
    /// step index k (from t_k to t_{k+1})
    pub step: u64,
    /// t_{k+1}
    pub time: f64,
    /// how the contact problem ended
    pub status: RigidStatus,
    /// error of docs/error.md of the returned (v, r) on the step's stored problem (0 without
    /// contacts)
    pub error: f64,
    /// active contacts (manifold points, the look-ahead ones included: every row of the
    /// step's problem)
    pub contacts: usize,
    /// contacts that carry load: normal impulse r_N > 10⁻⁶ max r_N of the step (what a
    /// side-by-side with another engine compares, whose activation rule differs)
    pub loaded_contacts: usize,
    /// contacts warm started from the previous step
    pub warm_started: usize,
    /// Gauss–Seidel sweeps
    pub sweeps: usize,
    /// "none", "nsgs" or "nsgs+library" (the library's solver finished the step)
    pub method: &'static str,
    /// wall-clock time of collision detection (s)
    pub detection_seconds: f64,
    /// wall-clock time of the contact solve (s)
    pub solve_seconds: f64,
    /// largest penetration max(0, −g) over the active contacts at t_k
    pub max_penetration: f64,
    /// kinetic energy at t_{k+1}
    pub kinetic_energy: f64,
    /// bodies whose free-rotation predictor did not converge to round-off (0 normally)
    pub rotation_unconverged: usize,
    /// "" when the step passed the physical checks, else the check it failed
    /// ("penetration": a contact deeper than [`PENETRATION_BOUND`] of the thinner
    /// body's half width; "energy growth": mechanical energy gained beyond
    /// [`ENERGY_GROWTH_BOUND`] with fixed obstacles); the status is then
    /// [`RigidStatus::NotConverged`]
    pub physics_check: &'static str,
}

pub(crate) mod correct;
pub(crate) mod equality;
pub mod nsgs;
mod phases;
pub(crate) mod relax;
mod rolling;
use correct::correct_positions;
pub use equality::{DEPENDENT_PIVOT, DROPPED_PIVOT};
pub use relax::{Overlaps, Relaxed};

/// A world of rigid bodies and obstacles advanced by [`RigidWorld::step`].
#[derive(Debug)]
pub struct RigidWorld {
    bodies: Vec<BodyState>,
    shapes: Vec<SharedShape>,
    obstacles: Vec<RigidObstacle>,
    obstacle_base: Vec<Pose>,
    materials: MaterialTable,
    settings: RigidSettings,
    gravity: Vector,
    time: f64,
    steps: u64,
    contacts: Vec<Contact>,
    last_problem: Option<GlobalProblem>,
    previous: BTreeMap<ContactKey, Vector>,
    detector: Detector,
    /// block index of each body among the moving ones (None: fixed)
    dof: Vec<Option<usize>>,
    /// half the thinnest width of each body's shape (m): the scale of the physical checks
    half_width: Vec<f64>,
    /// the joints ([`crate::bodies::joints`])
    joints: Vec<Joint>,
    /// the last step's joint impulses by row slot (the next step's warm start)
    joint_warm: Vec<[f64; SLOTS]>,
    /// the last step's force and torque of each joint on its body A
    joint_forces: Vec<[f64; 6]>,
    /// pairs of bodies (i < j) that a joint links: no contact between them
    jointed: std::collections::BTreeSet<(usize, usize)>,
    /// Gauss–Seidel without over-relaxation (ω = 1) from the first sweep of every step, set
    /// for good by the first step that [`quick_finish`] finished: on that scene plain sweeps
    /// drift and over-relaxed ones leave the warm starts where they drift (docs/rigid-bodies.md,
    /// "A drift")
    plain_sweeps: bool,
}

/// The state a [`RigidWorld`] carries between steps ([`RigidWorld::state`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RigidState {
    /// t_k
    pub time: f64,
    /// k
    pub steps: u64,
    /// x: centres of mass, world
    pub x: Vec<[f64; 3]>,
    /// q: principal frame → world, (w, x, y, z)
    pub q: Vec<[f64; 4]>,
    /// v, world
    pub v: Vec<[f64; 3]>,
    /// Ω, principal (body) frame
    pub omega: Vec<[f64; 3]>,
    /// the last step's impulses by contact key (world axes), the next step's warm start
    pub previous: Vec<(ContactKey, [f64; 3])>,
    /// the last step's contacts (read by the outputs)
    pub contacts: Vec<Contact>,
    /// the detector's pair caches, JSON ([`Detector::to_json`])
    pub detector: String,
    /// each joint's last impulses by row slot, the next step's warm start
    pub joint_warm: Vec<[f64; SLOTS]>,
    /// each joint's last force and torque (read by the outputs)
    pub joint_forces: Vec<[f64; 6]>,
    /// the library solver's settings and `keep_problem` (None: those of the world restored
    /// into, for files written before they were stored)
    pub library: Option<LibrarySettings>,
    /// [`RigidWorld`]'s switch to plain sweeps (false for files written before it was stored)
    pub plain_sweeps: bool,
}

/// The settings of a [`RigidWorld`] that the scene model does not hold,
/// set by [`RigidWorld::set_solver`] and [`RigidWorld::set_keep_problem`]; rigid checkpoints
/// store them (`/json/library`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LibrarySettings {
    /// [`RigidSettings::solver`]
    pub solver: coulomb::solver::Settings,
    /// [`RigidSettings::keep_problem`]
    pub keep_problem: bool,
}

fn v3(a: [f64; 3]) -> Vector {
    Vector::from_array(a)
}

fn math3(v: Vector) -> crate::math::Vec3 {
    crate::math::Vec3::from_slice(&v.to_array())
}

/// Checks a (w, x, y, z) quaternion: finite and ||q| − 1| ≤ [`QUATERNION_TOLERANCE`].
fn check_quaternion(what: &str, q: [f64; 4]) -> Result<Rotation, RigidError> {
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !(q.iter().all(|x| x.is_finite()) && (norm - 1.0).abs() <= QUATERNION_TOLERANCE) {
        return Err(RigidError::Quaternion {
            what: what.to_string(),
            q,
        });
    }
    Ok(rotation_from_wxyz(q))
}

fn check_finite(what: &str, field: &'static str, v: [f64; 3]) -> Result<(), RigidError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(RigidError::NonFinite {
            what: what.to_string(),
            field,
            value: v,
        })
    }
}

fn check_settings(s: &RigidSettings) -> Result<(), RigidError> {
    let bad = |m: String| Err(RigidError::Settings(m));
    if !(s.h.is_finite() && s.h > 0.0) {
        return bad(format!("time step h = {} must be finite and positive", s.h));
    }
    if !(0.0..=1.0).contains(&s.theta) {
        return bad(format!("theta = {} is not in [0, 1]", s.theta));
    }
    if !s.gravity.iter().all(|x| x.is_finite()) {
        return bad(format!("gravity {:?} is not finite", s.gravity));
    }
    if !(s.tolerance.is_finite() && s.tolerance > 0.0) {
        return bad(format!(
            "tolerance = {} must be finite and positive",
            s.tolerance
        ));
    }
    if s.max_sweeps == 0 || s.stall_window == 0 {
        return bad("max_sweeps and stall_window must be positive".into());
    }
    if !(s.relaxation.is_finite() && (1.0..2.0).contains(&s.relaxation)) {
        return bad(format!("relaxation = {} is not in [1, 2)", s.relaxation));
    }
    if !(0.0..=1.0).contains(&s.activation_gamma) {
        return bad(format!(
            "activation_gamma = {} is not in [0, 1]",
            s.activation_gamma
        ));
    }
    let nonneg = |x: f64| x.is_finite() && x >= 0.0;
    if !nonneg(s.activation_delta) || !nonneg(s.max_initial_penetration) {
        return bad(format!(
            "activation_delta = {} and max_initial_penetration = {} must be finite and >= 0",
            s.activation_delta, s.max_initial_penetration
        ));
    }
    Ok(())
}

/// The state of body `i` described by `b` (validated: quaternion, mass properties, finite
/// values, a material below `count`), half its thinnest width and its shape.
fn body_state(
    i: usize,
    b: RigidBodyDesc,
    count: usize,
) -> Result<(BodyState, f64, SharedShape), RigidError> {
    let what = format!("body {i}");
    let q_shape = check_quaternion(&what, b.orientation)?;
    b.mass.check().map_err(|detail| RigidError::Mass {
        what: what.clone(),
        detail,
    })?;
    check_finite(&what, "position", b.position)?;
    check_finite(&what, "velocity", b.velocity)?;
    check_finite(&what, "angular velocity", b.angular_velocity)?;
    if b.material as usize >= count {
        return Err(RigidError::Material {
            what,
            material: b.material,
            count,
        });
    }
    let (inertia, principal) = b.mass.principal().map_err(|detail| RigidError::Mass {
        what: what.clone(),
        detail,
    })?;
    let local_com = v3(b.mass.local_com);
    let q = (q_shape * principal).normalize();
    let x = v3(b.position) + q_shape * local_com;
    let local_aabb = b.shape.compute_local_aabb();
    let reach = [local_aabb.mins, local_aabb.maxs]
        .iter()
        .flat_map(|lo| {
            let hi = [local_aabb.mins, local_aabb.maxs];
            hi.into_iter().map(move |h| (*lo, h))
        })
        .map(|(a, c)| {
            let corner = Vector::new(a.x, c.y, if a.z > c.z { a.z } else { c.z });
            (corner - local_com).length()
        })
        .fold(0.0, f64::max)
        .max(
            (local_aabb.maxs - local_com)
                .abs()
                .max((local_aabb.mins - local_com).abs())
                .length(),
        );
    let (v, omega) = if b.fixed {
        (Vector::ZERO, Vector::ZERO)
    } else {
        (v3(b.velocity), q.conjugate() * v3(b.angular_velocity))
    };
    let state = BodyState {
        mass: b.mass.mass,
        inertia,
        local_com,
        principal,
        x,
        q,
        v,
        omega,
        material: b.material,
        fixed: b.fixed,
        reach,
    };
    let half = half_thinnest_width(&b.shape);
    Ok((state, half, b.shape))
}

impl RigidWorld {
    /// A world of `bodies` and `obstacles` at t = 0. Refuses, with a typed [`RigidError`]:
    /// invalid settings or material table, non-unit or non-finite quaternions, invalid mass
    /// properties, non-finite states, material indices out of the table, invalid motions, pairs
    /// of shapes parry has no manifold for, and bodies interpenetrating (with each other or an
    /// obstacle) deeper than `settings.max_initial_penetration` (count and depth).
    pub fn new(
        bodies: Vec<RigidBodyDesc>,
        obstacles: Vec<RigidObstacle>,
        materials: MaterialTable,
        settings: RigidSettings,
    ) -> Result<Self, RigidError> {
        Self::with_joints(bodies, obstacles, materials, settings, &[])
    }

    /// [`RigidWorld::new`] with `joints` between the bodies (numbered as in `bodies`), each
    /// validated ([`RigidError::Joint`] names the joint and the field); two bodies a joint
    /// links have no contact with each other.
    pub fn with_joints(
        bodies: Vec<RigidBodyDesc>,
        obstacles: Vec<RigidObstacle>,
        materials: MaterialTable,
        settings: RigidSettings,
        joints: &[JointDesc],
    ) -> Result<Self, RigidError> {
        check_settings(&settings)?;
        if materials.is_empty() {
            return Err(RigidError::Settings("the material table is empty".into()));
        }
        materials
            .check()
            .map_err(|e| RigidError::Settings(format!("material table: {e}")))?;
        let count = materials.len();
        let mut states = Vec::with_capacity(bodies.len());
        let mut shapes = Vec::with_capacity(bodies.len());
        let mut half_width = Vec::with_capacity(bodies.len());
        for (i, b) in bodies.into_iter().enumerate() {
            let (state, half, shape) = body_state(i, b, count)?;
            states.push(state);
            half_width.push(half);
            shapes.push(shape);
        }
        let mut obstacle_base = Vec::with_capacity(obstacles.len());
        for (o, ob) in obstacles.iter().enumerate() {
            let what = format!("obstacle {o} ('{}')", ob.name);
            let q = check_quaternion(&what, ob.orientation)?;
            check_finite(&what, "position", ob.position)?;
            ob.motion
                .check()
                .map_err(|e| RigidError::Settings(format!("{what}: {e}")))?;
            if ob.material as usize >= count {
                return Err(RigidError::Material {
                    what,
                    material: ob.material,
                    count,
                });
            }
            obstacle_base.push(Pose::from_parts(v3(ob.position), q));
        }
        let mut dof = Vec::with_capacity(states.len());
        let mut moving = 0;
        for b in &states {
            dof.push((!b.fixed).then(|| {
                moving += 1;
                moving - 1
            }));
        }
        let joints = joints
            .iter()
            .enumerate()
            .map(|(i, d)| Joint::new(i, d, &states))
            .collect::<Result<Vec<_>, _>>()?;
        let jointed = joints
            .iter()
            .filter_map(|j| {
                let (a, b) = (j.desc.body_a, j.desc.body_b?);
                Some((a.min(b), a.max(b)))
            })
            .collect();
        let mut world = Self {
            plain_sweeps: false,
            joint_warm: vec![[0.0; SLOTS]; joints.len()],
            joint_forces: vec![[0.0; 6]; joints.len()],
            joints,
            jointed,
            bodies: states,
            shapes,
            obstacles,
            obstacle_base,
            materials,
            gravity: v3(settings.gravity),
            settings,
            time: 0.0,
            steps: 0,
            contacts: Vec::new(),
            last_problem: None,
            previous: BTreeMap::new(),
            detector: Detector::default(),
            dof,
            half_width,
        };
        world.check_time_step()?;
        world.check_rolling()?;
        world.check_overlaps()?;
        Ok(world)
    }

    /// [`RigidWorld::with_joints`] for a world whose bodies may interpenetrate at the start:
    /// they are first moved apart by [`RigidWorld::relax_overlaps`] in at most `max_sweeps`
    /// sweeps, then the world is refused as `with_joints` refuses it if points deeper than
    /// `settings.max_initial_penetration` are left ([`RigidError::Interpenetration`]).
    pub fn relaxed(
        bodies: Vec<RigidBodyDesc>,
        obstacles: Vec<RigidObstacle>,
        materials: MaterialTable,
        settings: RigidSettings,
        joints: &[JointDesc],
        max_sweeps: usize,
    ) -> Result<(Self, Relaxed), RigidError> {
        let mut world = Self::overlapping(bodies, obstacles, materials, settings, joints)?;
        let relaxed = world.relax_overlaps(max_sweeps)?;
        world.check_overlaps()?;
        Ok((world, relaxed))
    }

    /// The same world with every contact pair through parry, balls included (no analytic
    /// fast path, `contacts`): the reference of the fast path's tests.
    #[cfg(feature = "unit-tests")]
    pub(crate) fn parry_only_detection(mut self) -> Self {
        self.detector = Detector::parry_only();
        self
    }

    /// [`RigidWorld::with_joints`] without the check of initial interpenetrations (a world
    /// whose state a checkpoint then replaces, or that [`RigidWorld::relaxed`] relaxes).
    pub(crate) fn overlapping(
        bodies: Vec<RigidBodyDesc>,
        obstacles: Vec<RigidObstacle>,
        materials: MaterialTable,
        settings: RigidSettings,
        joints: &[JointDesc],
    ) -> Result<Self, RigidError> {
        check_settings(&settings)?;
        let limit = settings.max_initial_penetration;
        let unchecked = RigidSettings {
            max_initial_penetration: f64::MAX,
            ..settings
        };
        let mut world = Self::with_joints(bodies, obstacles, materials, unchecked, joints)?;
        world.settings.max_initial_penetration = limit;
        Ok(world)
    }

    /// Appends `bodies` between two steps (an inlet pouring), numbered after the bodies
    /// present, whose indices, warm-start keys (pairs keyed by body index), contacts, joints
    /// and detector caches are unchanged; the broad phase is rebuilt at every detection, so
    /// the next step sees them. Each is validated as by [`RigidWorld::new`] and, if it moves,
    /// the time step checked for it as at the start (its fall g h² and its travel at its
    /// speed within half its thinnest width); on an error nothing is inserted. Overlaps are
    /// not checked here: the caller places them apart. Returns the indices given to them.
    pub fn insert_bodies(
        &mut self,
        bodies: Vec<RigidBodyDesc>,
    ) -> Result<std::ops::Range<usize>, RigidError> {
        let first = self.bodies.len();
        let count = self.materials.len();
        let (h, g) = (self.settings.h, self.gravity.length());
        let mut new = Vec::with_capacity(bodies.len());
        for (k, b) in bodies.into_iter().enumerate() {
            let i = first + k;
            let (state, w, shape) = body_state(i, b, count)?;
            if !state.fixed {
                let fall = g * h * h;
                let travel = h * (state.v.length() + state.omega.length() * state.reach);
                if fall > w || travel.is_nan() || travel > w {
                    return Err(RigidError::Settings(format!(
                        "time step h = {h} is too large for inserted body {i}: it falls g·h² = {fall:.3e} m and travels {travel:.3e} m in one step, more than half its thinnest width {w:.3e} m; use a smaller h, a lower speed or larger bodies"
                    )));
                }
            }
            new.push((state, w, shape));
        }
        let mut moving = self.dof.iter().filter(|d| d.is_some()).count();
        for (state, w, shape) in new {
            self.dof.push((!state.fixed).then(|| {
                moving += 1;
                moving - 1
            }));
            self.bodies.push(state);
            self.half_width.push(w);
            self.shapes.push(shape);
        }
        if let Err(e) = self.check_rolling() {
            self.dof.truncate(first);
            self.bodies.truncate(first);
            self.half_width.truncate(first);
            self.shapes.truncate(first);
            return Err(e);
        }
        Ok(first..self.bodies.len())
    }

    /// The thinnest half width over the moving bodies (∞ when none moves).
    fn thinnest_half_width(&self) -> f64 {
        self.half_width
            .iter()
            .zip(&self.bodies)
            .filter(|(_, b)| !b.fixed)
            .map(|(w, _)| *w)
            .fold(f64::INFINITY, f64::min)
    }

    /// Refuses a time step in which a body falls under gravity (g h²), or travels at its
    /// initial speed (|v| + |ω| × its reach, h times), more than half its thinnest width: its
    /// contacts could not be detected before it is through a wall or another body (the rule of
    /// sphere scenes, the radius replaced by half the thinnest width).
    fn check_time_step(&self) -> Result<(), RigidError> {
        let h = self.settings.h;
        let g = self.gravity.length();
        let thin = self.thinnest_half_width();
        if !thin.is_finite() {
            return Ok(());
        }
        let fall = g * h * h;
        if fall > thin {
            return Err(RigidError::Settings(format!(
                "time step h = {h} is too large: a body falls g·h² = {fall:.3e} m in one step, more than half the thinnest body width {thin:.3e} m; use h <= {:.3e}",
                (thin / g).sqrt()
            )));
        }
        for (i, travel, w) in self.travels() {
            if travel.is_nan() || travel > w {
                return Err(RigidError::Settings(format!(
                    "time step h = {h} is too large for body {i}: at its initial speed it travels {travel:.3e} m in one step, more than half its thinnest width {w:.3e} m (it could pass through a wall or a body); use h <= {:.3e} or a lower speed",
                    h * w / travel.max(f64::MIN_POSITIVE)
                )));
            }
        }
        Ok(())
    }

    /// (i, h (|v| + |ω| × reach), half the thinnest width) of each moving body i at its
    /// current velocities: how far it may travel in one step, against how far it may travel
    /// before its contacts can be missed (the sphere scenes' rule, R replaced by half the
    /// thinnest width).
    fn travels(&self) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        let h = self.settings.h;
        (self.bodies.iter().zip(&self.half_width).enumerate())
            .filter(|(_, (b, _))| !b.fixed)
            .map(move |(i, (b, w))| (i, h * (b.v.length() + b.omega.length() * b.reach), *w))
    }

    /// The check that [`RigidWorld::new`] applies to the initial velocities, on the current
    /// ones, as a warning: the body that travels farthest beyond half its thinnest width in
    /// one step at its current speed (it may pass through a thin wall or another body before
    /// a contact is detected), or `None`. The run loop says it once per run, as it says the
    /// sphere scenes' ([`crate::tunnelling`]): `Engine::step_warning`.
    pub fn travel_warning(&self) -> Option<String> {
        let h = self.settings.h;
        let (i, travel, w) = self
            .travels()
            .filter(|&(_, t, w)| t.is_nan() || t > w)
            .max_by(|a, b| (a.1 / a.2).total_cmp(&(b.1 / b.2)))?;
        Some(format!(
            "body {i} travels {travel:.3e} m in one step of h = {h} s at its current speed, more than half its thinnest width {w:.3e} m: it may pass through a wall or another body before a contact is detected; use h <= {:.3e}",
            h * w / travel.max(f64::MIN_POSITIVE)
        ))
    }

    /// Refuses manifold points deeper than `max_initial_penetration` at t = 0.
    fn check_overlaps(&mut self) -> Result<(), RigidError> {
        let margins = vec![0.0; self.bodies.len()];
        let placed = placed_obstacles(&self.obstacles, &self.obstacle_base, self.time);
        let mut points = self
            .detector
            .detect(&self.bodies, &self.shapes, &placed, &margins)?;
        self.drop_jointed(&mut points);
        let limit = self.settings.max_initial_penetration;
        let deep: Vec<&ContactPoint> = points.iter().filter(|c| c.gap < -limit).collect();
        if let Some(worst) = deep.iter().min_by(|x, y| x.gap.total_cmp(&y.gap)) {
            return Err(RigidError::Interpenetration {
                count: deep.len(),
                depth: -worst.gap,
                a: worst.a,
                b: worst.b,
                limit,
            });
        }
        Ok(())
    }

    /// Drops the contact points between two bodies a joint links.
    fn drop_jointed(&self, points: &mut Vec<ContactPoint>) {
        if self.jointed.is_empty() {
            return;
        }
        points.retain(|c| match c.b {
            Partner::Body(j) => !self.jointed.contains(&(c.a.min(j), c.a.max(j))),
            Partner::Obstacle(_, _) => true,
        });
    }

    /// The joints' forces and torques of the last step on their bodies A, world axes:
    /// (F, τ) with F = Σ λ_k J_A,k / h over the joint's rows and τ the torque about the
    /// joint's anchor on A (h: the step; zeros before the first step).
    pub fn joint_forces(&self) -> Vec<[f64; 6]> {
        self.joint_forces.clone()
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// The largest violation |C| of the joints' equality constraints at the current
    /// positions (m for the point rows, rad for the angular ones).
    pub fn joint_drift(&self) -> f64 {
        self.joints
            .iter()
            .map(|j| j.violation(&self.bodies))
            .fold(0.0, f64::max)
    }

    /// The joint coordinate (revolute: angle of A relative to B about the axis, rad;
    /// prismatic: travel of A's anchor along the axis, m) and its rate, of joint `j`; None
    /// for the other kinds or an index out of range.
    pub fn joint_coordinate(&self, j: usize) -> Option<(f64, f64)> {
        self.joints.get(j)?.coordinate(&self.bodies)
    }

    /// What the world carries from step k to step k + 1 besides what it is built from (a
    /// checkpoint's state, [`crate::io::rigid_checkpoint`]); `Err` when the detector's caches
    /// cannot be written as JSON.
    pub(crate) fn state(&self) -> Result<RigidState, String> {
        let b = &self.bodies;
        Ok(RigidState {
            time: self.time,
            steps: self.steps,
            x: b.iter().map(|b| b.x.to_array()).collect(),
            q: b.iter().map(|b| rotation_to_wxyz(b.q)).collect(),
            v: b.iter().map(|b| b.v.to_array()).collect(),
            omega: b.iter().map(|b| b.omega.to_array()).collect(),
            previous: self
                .previous
                .iter()
                .map(|(k, r)| (*k, r.to_array()))
                .collect(),
            contacts: self.contacts.clone(),
            detector: self.detector.to_json()?,
            joint_warm: self.joint_warm.clone(),
            joint_forces: self.joint_forces.clone(),
            library: Some(LibrarySettings {
                solver: self.settings.solver.clone(),
                keep_problem: self.settings.keep_problem,
            }),
            plain_sweeps: self.plain_sweeps,
        })
    }

    /// Replaces the world's state at t_0 by `s` (taken by [`RigidWorld::state`] from a world
    /// built from the same bodies, obstacles and settings). Refuses, leaving the world
    /// unchanged: row counts other than the world's, non-finite values, quaternions that are
    /// not unit to [`QUATERNION_TOLERANCE`], a fixed body that moved, contact keys or pairs
    /// out of range.
    pub(crate) fn restore(&mut self, s: RigidState) -> Result<(), String> {
        let n = self.bodies.len();
        let no = self.obstacles.len();
        if [s.x.len(), s.q.len(), s.v.len(), s.omega.len()] != [n; 4] {
            return Err(format!(
                "{}, {}, {} and {} body rows for {n} bodies",
                s.x.len(),
                s.q.len(),
                s.v.len(),
                s.omega.len()
            ));
        }
        if !(s.time.is_finite() && s.time >= 0.0) {
            return Err(format!("time {}", s.time));
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        for i in 0..n {
            if !(finite(&s.x[i]) && finite(&s.v[i]) && finite(&s.omega[i])) {
                return Err(format!("body {i}: a non-finite position or velocity"));
            }
            let q = check_quaternion(&format!("body {i}"), s.q[i]).map_err(|e| e.to_string())?;
            let b = &self.bodies[i];
            let moved =
                v3(s.x[i]) != b.x || q != b.q || s.v[i] != [0.0; 3] || s.omega[i] != [0.0; 3];
            if b.fixed && moved {
                return Err(format!("body {i} is fixed but its stored state moved"));
            }
        }
        let partner_ok = |a: usize, p: Partner| {
            a < n
                && match p {
                    Partner::Body(j) => a < j && j < n,
                    Partner::Obstacle(o, f) => o < no && f == 0,
                }
        };
        if let Some((k, _)) = s
            .previous
            .iter()
            .find(|(k, r)| !partner_ok(k.0, k.1) || !finite(r))
        {
            return Err(format!(
                "warm start of pair ({}, {:?}) out of range or not finite",
                k.0, k.1
            ));
        }
        if let Some(c) = s.contacts.iter().find(|c| !partner_ok(c.body, c.partner)) {
            return Err(format!(
                "contact of pair ({}, {:?}) out of range",
                c.body, c.partner
            ));
        }
        let nj = self.joints.len();
        if s.joint_warm.len() != nj || s.joint_forces.len() != nj {
            return Err(format!(
                "joints: {} warm-start and {} force rows for the {nj} joints of the scene",
                s.joint_warm.len(),
                s.joint_forces.len()
            ));
        }
        if let Some(j) =
            (0..nj).find(|&j| !(finite(&s.joint_warm[j]) && finite(&s.joint_forces[j])))
        {
            return Err(format!("joints: row {j} is not finite"));
        }
        let detector = Detector::from_json(&s.detector, n, no)?;
        if let Some(l) = &s.library {
            l.solver
                .validate()
                .map_err(|e| format!("the library solver's settings: {e}"))?;
        }
        if let Some(l) = s.library {
            self.settings.solver = l.solver;
            self.settings.keep_problem = l.keep_problem;
        }
        for (i, b) in self.bodies.iter_mut().enumerate() {
            b.x = v3(s.x[i]);
            b.q = rotation_from_wxyz(s.q[i]);
            b.v = v3(s.v[i]);
            b.omega = v3(s.omega[i]);
        }
        self.time = s.time;
        self.steps = s.steps;
        self.previous = s.previous.into_iter().map(|(k, r)| (k, v3(r))).collect();
        self.contacts = s.contacts;
        self.detector = detector;
        self.joint_warm = s.joint_warm;
        self.joint_forces = s.joint_forces;
        self.plain_sweeps = s.plain_sweeps;
        self.last_problem = None;
        Ok(())
    }

    /// Time t_k.
    pub fn time(&self) -> f64 {
        self.time
    }
    /// Steps done k.
    pub fn steps(&self) -> u64 {
        self.steps
    }
    /// Number of bodies.
    pub fn len(&self) -> usize {
        self.bodies.len()
    }
    /// Whether there is no body.
    pub fn is_empty(&self) -> bool {
        self.bodies.is_empty()
    }
    /// The settings.
    pub fn settings(&self) -> &RigidSettings {
        &self.settings
    }
    /// Whether Gauss–Seidel now runs without over-relaxation (ω = 1) from the first sweep of
    /// every step: switched on for good by the first step that the library's quick finish
    /// solved after plain sweeps stalled just above the tolerance (a drift, docs/rigid-bodies.md).
    pub fn plain_sweeps(&self) -> bool {
        self.plain_sweeps
    }

    /// Origins of the bodies' shape frames, world.
    pub fn positions(&self) -> Vec<[f64; 3]> {
        self.bodies
            .iter()
            .map(|b| b.shape_origin().to_array())
            .collect()
    }
    /// Centres of mass, world.
    pub fn centres_of_mass(&self) -> Vec<[f64; 3]> {
        self.bodies.iter().map(|b| b.x.to_array()).collect()
    }
    /// Orientations of the shape frames (w, x, y, z).
    pub fn orientations(&self) -> Vec<[f64; 4]> {
        self.bodies
            .iter()
            .map(|b| rotation_to_wxyz(b.shape_rotation()))
            .collect()
    }
    /// Velocities of the centres of mass, world.
    pub fn velocities(&self) -> Vec<[f64; 3]> {
        self.bodies.iter().map(|b| b.v.to_array()).collect()
    }
    /// Masses m of the bodies (world order; a fixed body's too, though it never moves).
    pub fn masses(&self) -> Vec<f64> {
        self.bodies.iter().map(|b| b.mass).collect()
    }
    /// Replaces the velocities of the centres of mass (world) before the next step, as the
    /// sphere engine's `World::bodies[i].velocity`; refused, nothing changed, when the count
    /// is not the number of bodies, an entry is not finite, or a fixed body would move.
    pub fn set_velocities(&mut self, v: &[[f64; 3]]) -> Result<(), String> {
        if v.len() != self.bodies.len() {
            return Err(format!(
                "expected {} velocities (one per body), got {}",
                self.bodies.len(),
                v.len()
            ));
        }
        for (i, (b, vi)) in self.bodies.iter().zip(v).enumerate() {
            if vi.iter().any(|x| !x.is_finite()) {
                return Err(format!("body {i}: non-finite velocity {vi:?}"));
            }
            if b.fixed && vi.iter().any(|x| *x != 0.0) {
                return Err(format!(
                    "body {i} is fixed: its velocity stays 0, got {vi:?}"
                ));
            }
        }
        for (b, vi) in self.bodies.iter_mut().zip(v) {
            b.v = Vector::new(vi[0], vi[1], vi[2]);
        }
        Ok(())
    }
    /// Moves the bodies before the next step: `x[i]` is the new origin of body i's shape
    /// frame (world, as [`RigidWorld::positions`] returns it), its orientation unchanged; the
    /// centre of mass follows, x = origin + R_shape · local_com. What the sphere engine's
    /// `World::bodies[i].position` is for a sphere. Refused, nothing changed, when the count
    /// is not the number of bodies, an entry is not finite, or a fixed body would move (as
    /// [`RigidWorld::set_velocities`]: a fixed body's state is the scene's, which restarts
    /// check). A body given its current origin keeps its state to the bit (the next step's
    /// bits do not change); a moved body's pair caches in the detector are dropped, so its
    /// next contacts are found from its new pose alone. Overlaps are not checked (the sphere
    /// engine's setter does not check them either): the next step's contacts push them
    /// apart. Velocities, warm starts and the last step's contacts are kept.
    pub fn set_positions(&mut self, x: &[[f64; 3]]) -> Result<(), String> {
        if x.len() != self.bodies.len() {
            return Err(format!(
                "expected {} positions (one per body), got {}",
                self.bodies.len(),
                x.len()
            ));
        }
        let mut moved = vec![false; x.len()];
        for (i, (b, xi)) in self.bodies.iter().zip(x).enumerate() {
            if xi.iter().any(|c| !c.is_finite()) {
                return Err(format!("body {i}: non-finite position {xi:?}"));
            }
            moved[i] = b.shape_origin().to_array() != *xi;
            if b.fixed && moved[i] {
                return Err(format!(
                    "body {i} is fixed: it stays at {:?}, got {xi:?}",
                    b.shape_origin().to_array()
                ));
            }
        }
        for ((b, xi), m) in self.bodies.iter_mut().zip(x).zip(&moved) {
            if *m {
                b.x = v3(*xi) + b.shape_rotation() * b.local_com;
            }
        }
        self.detector.forget_moved(&moved);
        Ok(())
    }
    /// Replaces the settings of the library's solver ([`RigidSettings::solver`]: the finish
    /// of a step Gauss–Seidel leaves above the tolerance, or every step's solve with
    /// `library_only`) from the next step; its `tol` is replaced by the step's tolerance, as
    /// at construction.
    pub fn set_solver(&mut self, solver: coulomb::solver::Settings) {
        self.settings.solver = solver;
    }
    /// Whether each step keeps its problem (2.10) in global form
    /// ([`RigidWorld::last_problem`], [`RigidSettings::keep_problem`]), from the next step.
    /// The step does not need it: without it, the global problem is built only for the
    /// library's finish and dropped after. Switched off, the problem kept is dropped now.
    pub fn set_keep_problem(&mut self, keep: bool) {
        self.settings.keep_problem = keep;
        if !keep {
            self.last_problem = None;
        }
    }
    /// Angular velocities, world frame.
    pub fn angular_velocities(&self) -> Vec<[f64; 3]> {
        self.bodies
            .iter()
            .map(|b| b.world_omega().to_array())
            .collect()
    }
    /// Angular momenta about the centres of mass, world frame.
    pub fn angular_momenta(&self) -> Vec<[f64; 3]> {
        self.bodies
            .iter()
            .map(|b| b.angular_momentum().to_array())
            .collect()
    }
    /// Total kinetic energy.
    pub fn kinetic_energy(&self) -> f64 {
        self.bodies.iter().map(BodyState::kinetic_energy).sum()
    }
    /// Potential energy of gravity, −Σ m g·x over the moving bodies.
    pub fn potential_energy(&self) -> f64 {
        self.bodies
            .iter()
            .filter(|b| !b.fixed)
            .map(|b| -b.mass * self.gravity.dot(b.x))
            .sum()
    }
    /// Σ m (|g| (|x| + reach) + |v|²): the scale of the round-off of the energies.
    fn energy_scale(&self) -> f64 {
        let g = self.gravity.length();
        self.bodies
            .iter()
            .filter(|b| !b.fixed)
            .map(|b| b.mass * (g * (b.x.length() + b.reach) + b.v.length_squared()))
            .sum()
    }
    /// The last step's active contacts with their impulses: every scene's contact record
    /// ([`Contact`], as [`crate::Simulation::contacts`]), one per manifold point, its partner
    /// an obstacle as a whole (feature 0).
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts
    }
    /// The last step's problem (2.10) in global form (None without contacts or with
    /// `keep_problem` off), for `--dump-fclib`.
    pub fn last_problem(&self) -> Option<&GlobalProblem> {
        self.last_problem.as_ref()
    }

    /// How far body i may travel in one step (bound), plus δ: the broad phase's margin.
    fn margins(&self, omega_free: &[Vector]) -> Vec<f64> {
        let h = self.settings.h;
        self.bodies
            .iter()
            .zip(omega_free)
            .map(|(b, wf)| {
                if b.fixed {
                    return self.settings.activation_delta;
                }
                let v = b.v.length().max((b.v + h * self.gravity).length());
                let w = b.omega.length().max(wf.length());
                2.0 * h * (v + w * b.reach) + self.settings.activation_delta
            })
            .collect()
    }

    /// Largest speed of an obstacle's material points (bound), times h.
    fn obstacle_margin(&self, o: usize) -> f64 {
        let ob = &self.obstacles[o];
        let speed = match &ob.motion {
            Motion::Rotate { center, omega, .. } => {
                let aabb = ob.shape.compute_aabb(&self.obstacle_base[o]);
                let c = v3(center.to_array());
                let d = [aabb.mins, aabb.maxs]
                    .iter()
                    .map(|p| (*p - c).length())
                    .fold(0.0, f64::max);
                if d.is_finite() {
                    omega.abs() * d
                } else {
                    0.0
                }
            }
            m => m.max_normal_speed(),
        };
        2.0 * self.settings.h * speed
    }

    /// One Moreau–Jean step from t_k to t_{k+1} = t_k + h, as named phases
    /// (`step/phases.rs`):
    /// 1. `free_rotations`: the free rotation Ω_free of every body (gyroscopic predictor,
    ///    [`crate::bodies::dynamics`]);
    /// 2. `detect`: the manifold points of the pairs the broad phase finds;
    /// 3. `activate`: the index set, points with g_k + γ h min(u_{N,k}, u_{N,free}, 0) ≤ δ;
    /// 4. `assemble`: the problem (2.10) (module docs), warm started from the previous
    ///    impulses of the same points;
    /// 5. `solve`: Gauss–Seidel and, if it stalls, the library's solver; the status on the
    ///    problem as stored;
    /// 6. `correction`, `integrate`, `correct`: v_{k+1}, Ω_{k+1} from the solution,
    ///    x_{k+1} = x_k + h((1 − θ) v_k + θ v_{k+1}) and
    ///    q_{k+1} = q_k ⊗ exp(h ((1 − θ) Ω_k + θ Ω_{k+1}) / 2) (2.7), then the position
    ///    correction on the linearized end gaps and the joints' projection;
    /// 7. `physics_check`, `record_contacts`: the step's checks and its contacts.
    pub fn step(&mut self) -> Result<RigidStepReport, RigidError> {
        let k = self.steps;
        let t_end = self.time + self.settings.h;
        let free = self.free_rotations();
        let td = Instant::now();
        let points = self.detect(&free.omega)?;
        let detection_seconds = td.elapsed().as_secs_f64();
        let ts = Instant::now();
        let mut set = self.activate(points, &free.omega, t_end);
        let rows = std::mem::take(&mut set.rows);
        let assembled = self.assemble(rows, &set.active, &free.omega)?;
        let warm_started = assembled.warm_started;
        let solved = self.solve(assembled, set.active.is_empty())?;
        if solved.v.iter().flatten().any(|x| !x.is_finite())
            || solved
                .r
                .iter()
                .chain(&solved.lambda)
                .any(|x| !x.is_finite())
        {
            return Err(RigidError::NonFiniteState(k));
        }
        self.keep_joint_impulses(&solved);
        let solve_seconds = ts.elapsed().as_secs_f64();
        let before = (self.kinetic_energy(), self.potential_energy());
        let correction = self.correction(&set, &solved);
        self.integrate(&solved.v)?;
        // energies before the correction (its work, lifting bodies out, is not the step's)
        let after = (self.kinetic_energy(), self.potential_energy());
        self.correct(correction.as_deref())?;
        let max_penetration = set
            .active
            .iter()
            .map(|c| (-c.gap).max(0.0))
            .fold(0.0, f64::max);
        let physics_check = self.physics_check(&set.active, before, after);
        let status = if physics_check.is_empty() {
            solved.status
        } else {
            RigidStatus::NotConverged
        };
        let r = &solved.r;
        let max_rn = r.iter().step_by(3).copied().fold(0.0, f64::max);
        let loaded_contacts = r
            .iter()
            .step_by(3)
            .filter(|&&rn| max_rn > 0.0 && rn > 1e-6 * max_rn)
            .count();
        self.record_contacts(&set.active, &set.normal_parts, r);
        self.time = t_end;
        self.steps += 1;
        Ok(RigidStepReport {
            step: k,
            time: self.time,
            status,
            error: solved.error,
            contacts: set.active.len(),
            loaded_contacts,
            warm_started,
            sweeps: solved.sweeps,
            method: solved.method,
            detection_seconds,
            solve_seconds,
            max_penetration,
            kinetic_energy: self.kinetic_energy(),
            rotation_unconverged: free.unconverged,
            physics_check,
        })
    }

    /// The rolling-resistance row of manifold point `c` ([`rolling`]): J_R = ±R_e (Rᵀ t)
    /// for t = (t₁, t₂, n) on the rotational dofs of A (+) and B (−), w_R = −R_e t·ω_B of a
    /// rotating obstacle, μ_r in `mu`; None when the pair's μ_r is 0 or no side moves. R_e =
    /// R_A R_B / (R_A + R_B) between two balls, else the ball's radius (a pair without a ball
    /// is refused by [`RigidWorld::check_rolling`]).
    fn rolling_row(&self, c: &ContactPoint) -> Option<nsgs::Row> {
        let radius = |i: usize| self.shapes[i].as_ball().map(|b| b.radius);
        let a = &self.bodies[c.a];
        let (material, rb, omega_b) = match c.b {
            Partner::Body(j) => (self.bodies[j].material, radius(j), Vector::ZERO),
            Partner::Obstacle(o, _) => {
                let ob = &self.obstacles[o];
                let w = match &ob.motion {
                    Motion::Rotate { axis, omega, .. } => v3(axis.to_array()) * *omega,
                    _ => Vector::ZERO,
                };
                (ob.material, None, w)
            }
        };
        let mu_r = self.materials.law(a.material, material)?.rolling_friction;
        let re = match (radius(c.a), rb) {
            (Some(x), Some(y)) => x * y / (x + y),
            (Some(x), None) | (None, Some(x)) => x,
            (None, None) => return None,
        };
        let frame = [c.t1, c.t2, c.normal];
        let side = |i: usize, sign: f64| -> Option<(usize, [[f64; 6]; 3])> {
            let b = &self.bodies[i];
            let jac = std::array::from_fn(|k| {
                let t = b.q.conjugate() * (sign * re * frame[k]);
                [0.0, 0.0, 0.0, t.x, t.y, t.z]
            });
            (!b.fixed).then(|| (self.dof[i].unwrap_or(0), jac))
        };
        let row = nsgs::Row {
            a: side(c.a, 1.0),
            b: match c.b {
                Partner::Body(j) => side(j, -1.0),
                Partner::Obstacle(_, _) => None,
            },
            w: std::array::from_fn(|k| -re * frame[k].dot(omega_b)),
            mu: mu_r,
        };
        (mu_r > 0.0 && (row.a.is_some() || row.b.is_some())).then_some(row)
    }

    /// Refuses rolling friction (μ_r ≠ 0) between two bodies of which neither is a ball, or
    /// between a body that is not a ball and an obstacle: rolling resistance is defined with a
    /// ball's radius as lever arm (docs/granular.md, "Rolling resistance"). The error names
    /// the materials and the shapes of the first such pair.
    fn check_rolling(&self) -> Result<(), RigidError> {
        // the first two bodies of each material that are not balls
        let mut of: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
        for (i, (b, s)) in self.bodies.iter().zip(&self.shapes).enumerate() {
            if s.as_ball().is_none() {
                let v = of.entry(b.material).or_default();
                if v.len() < 2 {
                    v.push(i);
                }
            }
        }
        let body = |i: usize| format!("body {i} ({:?})", self.shapes[i].shape_type());
        for (&ma, bodies) in &of {
            let i = bodies[0];
            let others = of
                .iter()
                .filter_map(|(&mb, js)| js.iter().find(|&&j| j != i).map(|&j| (mb, body(j))))
                .chain(self.obstacles.iter().map(|o| {
                    let what = format!("obstacle '{}' ({:?})", o.name, o.shape.shape_type());
                    (o.material, what)
                }));
            for (mb, other) in others {
                let mu_r = self
                    .materials
                    .law(ma, mb)
                    .map_or(0.0, |l| l.rolling_friction);
                if mu_r != 0.0 {
                    let name = |m: u32| self.materials.names.get(m as usize).cloned();
                    return Err(RigidError::Settings(format!(
                        "rolling_friction = {mu_r} between materials '{}' and '{}' cannot apply between {} and {other}: rolling resistance is defined for contacts with a ball (its radius is the lever arm); set it to 0 for this pair of materials or give these bodies another material",
                        name(ma).unwrap_or_default(),
                        name(mb).unwrap_or_default(),
                        body(i)
                    )));
                }
            }
        }
        Ok(())
    }

    /// The row of manifold point `c` (Jacobians, w, μ), its normal velocity u_{N,k} at t_k
    /// and u_{N,free} of the free motion (gravity and free rotation).
    fn row(
        &self,
        c: &ContactPoint,
        omega_free: &[Vector],
        t_end: f64,
    ) -> (nsgs::Row, f64, f64, f64) {
        let h = self.settings.h;
        let frame = [c.normal, c.t1, c.t2];
        let a = &self.bodies[c.a];
        let side = |b: &BodyState, sign: f64| -> [[f64; 6]; 3] {
            let arm = c.point - b.x;
            std::array::from_fn(|k| {
                let t = frame[k];
                let rot = b.q.conjugate() * arm.cross(t);
                [
                    sign * t.x,
                    sign * t.y,
                    sign * t.z,
                    sign * rot.x,
                    sign * rot.y,
                    sign * rot.z,
                ]
            })
        };
        let free_point = |i: usize, b: &BodyState| -> Vector {
            if b.fixed {
                Vector::ZERO
            } else {
                (b.v + h * self.gravity) + (b.q * omega_free[i]).cross(c.point - b.x)
            }
        };
        let ja = (!a.fixed).then(|| side(a, 1.0));
        let va = a.point_velocity(c.point);
        let (jb, vb, vb_free, v_end, mat_b) = match c.b {
            Partner::Body(j) => {
                let b = &self.bodies[j];
                (
                    (!b.fixed).then(|| side(b, -1.0)),
                    b.point_velocity(c.point),
                    free_point(j, b),
                    Vector::ZERO,
                    b.material,
                )
            }
            Partner::Obstacle(o, _) => {
                let ob = &self.obstacles[o];
                let p = math3(c.point);
                let vt = ob.motion.velocity_at(p, self.time);
                let ve = ob.motion.velocity_at(p, t_end);
                (
                    None,
                    v3(vt.to_array()),
                    v3(ve.to_array()),
                    v3(ve.to_array()),
                    ob.material,
                )
            }
        };
        let u_nk = c.normal.dot(va - vb);
        let u_free = c.normal.dot(free_point(c.a, a) - vb_free);
        let law = self
            .materials
            .law(a.material, mat_b)
            .unwrap_or_default_law();
        let e = law.restitution;
        let w_obstacle = -c.normal.dot(v_end);
        let mut w = [w_obstacle, -c.t1.dot(v_end), -c.t2.dot(v_end)];
        w[0] += crate::assembly::impact_offset(e, u_nk);
        // gap closure of a pair that gravity's look-ahead made active (no hovering)
        let g = self.gravity.length();
        if self.settings.gap_closure && c.gap > 0.0 && u_nk >= -2.0 * h * g {
            w[0] += (1.0 - e).clamp(0.0, 1.0) * c.gap / h;
        }
        let row = nsgs::Row {
            a: ja.map(|j| (self.dof[c.a].unwrap_or(0), j)),
            b: match c.b {
                Partner::Body(j) => jb.map(|jj| (self.dof[j].unwrap_or(0), jj)),
                Partner::Obstacle(_, _) => None,
            },
            w,
            mu: law.mu,
        };
        (row, u_nk, u_free, w_obstacle)
    }
}

/// Contact points per task of the parallel row building of [`RigidWorld::step`] (a
/// constant: each row is its point's own numbers whatever the number of threads).
const ROW_CHUNK: usize = 64;

/// The joints' positions are projected back until every |C| ≤ this (m or rad), at most 100
/// Gauss–Seidel Newton sweeps (`joints::project`).
pub const JOINT_DRIFT_TARGET: f64 = 1e-12;

/// A contact deeper than this fraction of the thinner body's half width makes the step's
/// status [`RigidStatus::NotConverged`] (a body went through another or an obstacle).
pub const PENETRATION_BOUND: f64 = 0.1;

/// Mechanical energy (kinetic + gravity's potential) gained in one step beyond this fraction
/// of the larger of the kinetic energy and Σ m (g h)² (plus round-off) makes the step's status
/// [`RigidStatus::NotConverged`] when every obstacle is fixed: Moreau–Jean with θ = ½ and
/// e ≤ 1 never creates energy (docs/rigid-bodies.md).
pub const ENERGY_GROWTH_BOUND: f64 = 1e-2;

/// Half the thinnest width of a shape (m): over the face normals of a polyhedron or cuboid,
/// else the smallest extent of its local bounding box (a ball's radius, a capsule's radius,
/// a cylinder's smaller of radius and half height).
fn half_thinnest_width(shape: &SharedShape) -> f64 {
    if let Some(w) = crate::collision::polytope::Polytope::of(shape).map(|p| p.thinnest_width()) {
        return 0.5 * w;
    }
    let b = shape.compute_local_aabb();
    0.5 * (b.maxs - b.mins).min_element()
}

/// A material law, with μ = 0, e = 0 when the pair is out of the table (cannot happen
/// after [`RigidWorld::new`]'s checks).
trait OrDefaultLaw {
    fn unwrap_or_default_law(self) -> crate::world::ContactLaw;
}

impl OrDefaultLaw for Option<crate::world::ContactLaw> {
    fn unwrap_or_default_law(self) -> crate::world::ContactLaw {
        self.unwrap_or(crate::world::ContactLaw {
            mu: 0.0,
            restitution: 0.0,
            rolling_friction: 0.0,
        })
    }
}

/// The obstacles at time t.
fn placed_obstacles<'a>(
    obstacles: &'a [RigidObstacle],
    base: &[Pose],
    t: f64,
) -> Vec<PlacedObstacle<'a>> {
    obstacles
        .iter()
        .zip(base)
        .map(|(o, base)| PlacedObstacle {
            shape: &o.shape,
            pose: obstacle_pose(&o.motion, base, t),
        })
        .collect()
}

/// The pose at time t of an obstacle whose pose at t = 0 is `base`: translated by the
/// motion's offset, or turned by the angle ω t about the motion's axis through its centre.
pub fn obstacle_pose(motion: &Motion, base: &Pose, t: f64) -> Pose {
    match motion {
        Motion::Rotate {
            center,
            axis,
            omega,
        } => {
            let c = v3(center.to_array());
            let r = Rotation::from_axis_angle(v3(axis.to_array()).normalize(), omega * t);
            Pose::from_parts(
                c + r * (base.translation - c),
                (r * base.rotation).normalize(),
            )
        }
        m => Pose::from_parts(base.translation + v3(m.offset(t).to_array()), base.rotation),
    }
}

/// [`library_finish`] first tries [`quick_finish`] when Gauss–Seidel stalled at an error at
/// most this many times the tolerance on a step with more contact unknowns than degrees of
/// freedom (W = H M⁻¹ Hᵀ singular: r can drift in its null space at a constant error).
pub(crate) const QUICK_NEAR: f64 = 2.0;

/// Sweeps of the two runs of the library's Gauss–Seidel in [`quick_finish`].
pub(crate) const QUICK_SWEEPS: [usize; 2] = [100, 400];

/// [`quick_finish`] gives up after its first run if the error is above this many times the
/// tolerance.
pub(crate) const QUICK_FAR: f64 = 100.0;

/// The library's own Gauss–Seidel (pgs + fused: its sweeps mixed by Anderson's method, s
/// updated as it sweeps; no end game) on the step's global problem from r = 0, in two runs of
/// [`QUICK_SWEEPS`] sweeps, the second from the first's r and only if the first's error is
/// ≤ [`QUICK_FAR`] times the tolerance: the step (r, λ, error on the stored problem) once that
/// error is ≤ the tolerance, else None.
///
/// Plain Gauss–Seidel that stalls just above the tolerance is often drifting: r moves by the
/// same vector every sweep at the same error, for thousands of sweeps, while the mixed sweeps
/// from scratch converge in tens to hundreds (the cube pyramid: 41 to 420 sweeps, 0.05–0.5 s,
/// where the default plan's end game took 10–15 s). Where they are far from the tolerance
/// after the first run (a brick wall: 2e-4 for 1e-8) the default plan follows at once
/// (docs/rigid-bodies.md, "A drift").
fn quick_finish(
    global: &coulomb::problem::Problem,
    settings: &coulomb::solver::Settings,
    step_of: impl Fn(coulomb::solver::Solution) -> Option<(Vec<f64>, Vec<f64>, f64)>,
) -> Option<(Vec<f64>, Vec<f64>, f64)> {
    use coulomb::solver::{Guess, InnerKind, MethodParams, OuterKind, Settings};
    let mut tuning = settings.params.tuning;
    tuning.lm.max_steps = 0;
    let mut quick = Settings {
        inner: InnerKind::Pgs,
        outer: OuterKind::Fused,
        fallback: None,
        max_outer: 1,
        max_inner: QUICK_SWEEPS[0],
        params: MethodParams {
            warmup_sweeps: 0,
            barrier_steps: 0,
            newton_steps: 0,
            tuning,
            ..settings.params
        },
        ..settings.clone()
    };
    let tol = settings.tol;
    let first = step_of(coulomb::solver::solve_with_guess(global, &quick, None).ok()?)?;
    if first.2 <= tol {
        return Some(first);
    }
    if first.2 > QUICK_FAR * tol || first.2.is_nan() {
        return None;
    }
    quick.max_inner = QUICK_SWEEPS[1];
    let guess = Guess {
        r: first.0,
        v: None,
    };
    let second = step_of(coulomb::solver::solve_with_guess(global, &quick, Some(&guess)).ok()?)?;
    (second.2 <= tol).then_some(second)
}

/// The library's solver on the step's global problem: first from its own start (no guess),
/// then, if that did not reach the tolerance, from Gauss–Seidel's iterate `r`; (r, error on
/// the stored problem) of the better one, or None if both refused. Cold first because the
/// stalled iterate is a poor start on face contacts: on a brick wall with touching joints
/// (2 742 unknowns, W rank-deficient) the library took 2.4 s a step from it and 0.1 s from
/// its own start, both to 1e-8 (docs/rigid-bodies.md, "Touching bricks"). With
/// [`RigidSettings::library_only`] (no Gauss–Seidel), only from `r`, the step's warm start, as
/// the sphere engine's `method = "library"` solves from its guess.
///
/// With joints, `global` is the problem at Gauss–Seidel's multipliers `lambda` (its active set
/// of motors and limits, [`nsgs::Problem::to_global_with`]): the library's multipliers of the
/// stored equality rows replace those, the others keep theirs, and the error is that of
/// [`nsgs::Problem::error_with`] (bounds and signs included).
///
/// The last value is true when [`quick_finish`] found the step.
fn library_finish(
    global: &coulomb::problem::Problem,
    problem: &nsgs::Problem,
    r: &[f64],
    lambda: &[f64],
    s: &RigidSettings,
) -> Option<(Vec<f64>, Vec<f64>, f64, bool)> {
    use coulomb::solver::{solve_with_guess, Guess};
    let start = if r.iter().all(|x| x.is_finite()) {
        r.to_vec()
    } else {
        vec![0.0; r.len()]
    };
    let v: Vec<f64> = problem
        .velocities_with(&start, lambda)
        .into_iter()
        .flatten()
        .collect();
    let columns = problem.equality_columns(lambda);
    let guess = Guess {
        r: start,
        v: Some(v),
    };
    let settings = coulomb::solver::Settings {
        tol: s.tolerance,
        ..s.solver.clone()
    };
    let step_of = |sol: coulomb::solver::Solution| {
        if sol.r.len() != r.len() || sol.r.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let mut l = lambda.to_vec();
        if !columns.is_empty() {
            let lib = sol.l.as_ref()?;
            if lib.len() != columns.len() || lib.iter().any(|x| !x.is_finite()) {
                return None;
            }
            for (&k, x) in columns.iter().zip(lib) {
                l[k] = *x;
            }
        }
        let err = problem.error_with(&sol.r, &l);
        Some((sol.r, l, err))
    };
    let run = |guess: Option<&Guess>| step_of(solve_with_guess(global, &settings, guess).ok()?);
    let default =
        |found: Option<(Vec<f64>, Vec<f64>, f64)>| found.map(|(r, l, e)| (r, l, e, false));
    if s.library_only {
        return default(run(Some(&guess)));
    }
    // a drift lives in the null space of W = H M⁻¹ Hᵀ: only where there are more contact
    // unknowns than degrees of freedom
    let redundant = 3 * problem.rows.len() > 6 * problem.mass.len();
    if redundant && problem.error_with(r, lambda) <= QUICK_NEAR * s.tolerance {
        if let Some((r, l, e)) = quick_finish(global, &settings, step_of) {
            return Some((r, l, e, true));
        }
    }
    let cold = run(None);
    if cold.as_ref().is_some_and(|(_, _, e)| *e <= s.tolerance) {
        return default(cold);
    }
    default(match (cold, run(Some(&guess))) {
        (Some(a), Some(b)) => Some(if b.2 < a.2 { b } else { a }),
        (a, b) => a.or(b),
    })
}

#[cfg(feature = "unit-tests")]
pub mod tests;
