//! The named phases of [`RigidWorld::step`], in the order the step calls them:
//! free rotation → detect → activate → assemble → solve → (joint impulses) → correction →
//! integrate → (apply the correction, project the joints) → physics checks → record.
//!
//! Each phase is a method on the world that takes the previous phases' values and returns its
//! own: the step itself (`super::RigidWorld::step`) only sequences them, times detection and
//! solve, and builds the [`super::RigidStepReport`].

use super::RigidStatus;
use super::{
    correct_positions, library_finish, nsgs, placed_obstacles, rolling, RigidWorld,
    ENERGY_GROWTH_BOUND, JOINT_DRIFT_TARGET, PENETRATION_BOUND, ROW_CHUNK,
};
use crate::bodies::dynamics::{free_rotation, integrate_orientation};
use crate::bodies::joints::{RowKind, SLOTS};
use crate::bodies::rigid::RigidError;
use crate::collision::contact::{Contact, Partner};
use crate::collision::manifold::ContactPoint;
use crate::math::Vec3;
use crate::world::Motion;
use parry3d_f64::math::Vector;
use std::time::Instant;

/// Ω_free of every body (zero for a fixed one) and how many free-rotation predictors did not
/// converge.
pub(super) struct FreeRotation {
    pub omega: Vec<Vector>,
    pub unconverged: usize,
}

/// The index set I_k of one step ([`RigidWorld::activate`]).
pub(super) struct IndexSet {
    /// the active manifold points, in detection order
    pub active: Vec<ContactPoint>,
    /// their rows of the problem (2.10)
    pub rows: Vec<nsgs::Row>,
    /// (u_{N,k}, −n·V_B(t_{k+1})) of each active point, for the end gaps
    pub normal_parts: Vec<(f64, f64)>,
    /// the detected points left out of the index set, (row, g_k, u_{N,k}, −n·V_B): the
    /// position correction watches their end gaps too (a body pushed within the step by its
    /// other contacts may close them), as the spheres' correction detects anew
    pub inactive: Vec<(nsgs::Row, f64, f64, f64)>,
}

/// The step's problem with its warm start ([`RigidWorld::assemble`]).
pub(super) struct Assembled {
    pub problem: nsgs::Problem,
    /// r of the previous step's impulses at the same manifold points (zero elsewhere)
    pub r0: Vec<f64>,
    /// the joints' multipliers of the previous step, clamped to their rows' bounds
    pub lambda0: Vec<f64>,
    /// the rolling-resistance rows of the active points
    pub rolling: rolling::Rolling,
    /// f before any rolling impulse (empty without rolling rows)
    pub f0: Vec<[f64; 6]>,
    /// active points warm started from the previous step
    pub warm_started: usize,
}

/// The solution of the step's problem ([`RigidWorld::solve`]).
pub(super) struct Solved {
    /// the problem solved (the last one, with rolling resistance)
    pub problem: nsgs::Problem,
    pub r: Vec<f64>,
    pub lambda: Vec<f64>,
    /// v_{k+1}, Ω_{k+1} per moving body
    pub v: Vec<[f64; 6]>,
    pub status: RigidStatus,
    pub error: f64,
    pub sweeps: usize,
    pub method: &'static str,
}

/// Mechanical energy (kinetic, potential).
pub(super) type Energy = (f64, f64);

impl RigidWorld {
    /// Ω_free of every body: the gyroscopic free-rotation predictor ([`free_rotation`]).
    pub(super) fn free_rotations(&self) -> FreeRotation {
        let h = self.settings.h;
        let mut unconverged = 0;
        let omega = self
            .bodies
            .iter()
            .map(|b| {
                if b.fixed {
                    return Vector::ZERO;
                }
                let fr = free_rotation(b.inertia, b.omega, h);
                if !fr.converged {
                    unconverged += 1;
                }
                fr.omega
            })
            .collect();
        FreeRotation { omega, unconverged }
    }

    /// The manifold points of the pairs the broad phase finds within each body's margin
    /// (its motion over the step, plus the obstacles' own), jointed pairs left out.
    pub(super) fn detect(
        &mut self,
        omega_free: &[Vector],
    ) -> Result<Vec<ContactPoint>, RigidError> {
        let mut margins = self.margins(omega_free);
        let extra: f64 = (0..self.obstacles.len())
            .map(|o| self.obstacle_margin(o))
            .fold(0.0, f64::max);
        if extra > 0.0 {
            margins.iter_mut().for_each(|m| *m += extra);
        }
        let mut points = {
            let placed = placed_obstacles(&self.obstacles, &self.obstacle_base, self.time);
            self.detector
                .detect(&self.bodies, &self.shapes, &placed, &margins)?
        };
        self.drop_jointed(&mut points);
        Ok(points)
    }

    /// The index set: point i is active when g_k + γ h min(u_{N,k}, u_{N,free}, 0) ≤ δ; every
    /// point's row is built in parallel (each its own numbers), the set in point order.
    pub(super) fn activate(
        &self,
        points: Vec<ContactPoint>,
        omega_free: &[Vector],
        t_end: f64,
    ) -> IndexSet {
        let h = self.settings.h;
        let gamma = self.settings.activation_gamma;
        let delta = self.settings.activation_delta;
        let mut set = IndexSet {
            active: Vec::with_capacity(points.len()),
            rows: Vec::with_capacity(points.len()),
            normal_parts: Vec::with_capacity(points.len()),
            inactive: Vec::new(),
        };
        let look_ahead = h * self.gravity.length();
        let built: Vec<_> = {
            use rayon::prelude::*;
            points
                .par_iter()
                .with_min_len(ROW_CHUNK)
                .map(|c| self.row(c, omega_free, t_end))
                .collect()
        };
        for (c, (row, u_nk, u_free, w_obstacle)) in points.into_iter().zip(built) {
            // two bodies fall together in the free motion: either may be stopped by its other
            // contacts within the step, so the pair looks ahead by h |g| as a body does
            // against an obstacle (a stack with gaps just above δ closes them in one step)
            let u_free = match c.b {
                Partner::Body(_) => u_free - look_ahead,
                Partner::Obstacle(_, _) => u_free,
            };
            let u = u_nk.min(u_free).min(0.0);
            if c.gap + gamma * h * u <= delta {
                set.rows.push(row);
                set.normal_parts.push((u_nk, w_obstacle));
                set.active.push(c);
            } else if self.settings.position_correction {
                set.inactive.push((row, c.gap, u_nk, w_obstacle));
            }
        }
        set
    }

    /// The problem (2.10) of the step in body-block form: M = diag(m, m, m, I₁, I₂, I₃) and
    /// f = (m (v_k + h g), I Ω_free) per moving body, the contact rows, the joints' rows, and
    /// the warm start (r₀, λ₀) from the previous step's impulses.
    pub(super) fn assemble(
        &self,
        rows: Vec<nsgs::Row>,
        active: &[ContactPoint],
        omega_free: &[Vector],
    ) -> Result<Assembled, RigidError> {
        let k = self.steps;
        let h = self.settings.h;
        let moving = self.dof.iter().filter(|d| d.is_some()).count();
        let mut mass = vec![[0.0; 6]; moving];
        let mut f = vec![[0.0; 6]; moving];
        for (i, b) in self.bodies.iter().enumerate() {
            if let Some(d) = self.dof[i] {
                mass[d] = b.mass_block();
                let p = b.mass * (b.v + h * self.gravity);
                let l = Vector::from_array(b.inertia) * omega_free[i];
                f[d] = [p.x, p.y, p.z, l.x, l.y, l.z];
            }
        }
        let joint_blocks: Vec<_> = self
            .joints
            .iter()
            .map(|j| {
                let rows = j.step_rows(&self.bodies, h, self.settings.activation_delta);
                let blk = |b: Option<usize>| b.and_then(|i| self.dof[i]);
                (blk(Some(j.desc.body_a)), blk(j.desc.body_b), rows)
            })
            .collect();
        let lambda0: Vec<f64> = self
            .joints
            .iter()
            .zip(&joint_blocks)
            .zip(&self.joint_warm)
            .flat_map(|((_, (_, _, rows)), warm)| {
                rows.iter().map(|r| {
                    let l = if self.settings.warm_start {
                        warm[r.slot]
                    } else {
                        0.0
                    };
                    match r.kind {
                        RowKind::Box(lo, hi) => l.clamp(lo, hi),
                        RowKind::Unilateral => l.max(0.0),
                        RowKind::Equality => l,
                    }
                })
            })
            .collect();
        let rolling_rows = if self.materials.any_rolling() {
            let row = |(i, c): (usize, &ContactPoint)| self.rolling_row(c).map(|row| (i, row));
            active.iter().enumerate().filter_map(row).collect()
        } else {
            Vec::new()
        };
        let rolling = rolling::Rolling::new(rolling_rows, &mass);
        let f0 = if rolling.is_empty() {
            Vec::new()
        } else {
            f.clone()
        };
        let problem = nsgs::Problem::new(rows, mass, f)
            .and_then(|p| p.with_joints(joint_blocks))
            .map_err(|detail| RigidError::Solve { step: k, detail })?;
        let mut warm_started = 0;
        let r0: Vec<f64> = active
            .iter()
            .flat_map(|c| {
                let p = if self.settings.warm_start {
                    self.previous.get(&c.key).copied()
                } else {
                    None
                };
                if p.is_some() {
                    warm_started += 1;
                }
                let p = p.unwrap_or(Vector::ZERO);
                [p.dot(c.normal), p.dot(c.t1), p.dot(c.t2)]
            })
            .collect();
        Ok(Assembled {
            problem,
            r0,
            lambda0,
            rolling,
            f0,
            warm_started,
        })
    }

    /// The solution of the step's problem: Gauss–Seidel ([`nsgs::Problem::solve`]) and, when
    /// it stalls above the tolerance, the library's solver on the stored global problem
    /// ([`library_finish`]), the smaller error kept; with rolling resistance, alternated with
    /// passes over the rolling impulses (`rolling`). The status is decided on the problem as
    /// stored. Keeps the global problem when asked ([`RigidWorld::last_problem`]).
    pub(super) fn solve(&mut self, a: Assembled, no_contact: bool) -> Result<Solved, RigidError> {
        let k = self.steps;
        let Assembled {
            mut problem,
            mut r0,
            mut lambda0,
            rolling,
            f0,
            ..
        } = a;
        if no_contact && self.joints.is_empty() {
            self.last_problem = None;
            let v = problem.velocities(&[]);
            return Ok(Solved {
                problem,
                r: Vec::new(),
                lambda: Vec::new(),
                v,
                status: RigidStatus::NoContact,
                error: 0.0,
                sweeps: 0,
                method: "none",
            });
        }
        let s = &self.settings;
        // rolling resistance: the solve below alternates with passes over the rolling
        // impulses y (given impulses of the problem solved, `rolling` module)
        let mut y = vec![[0.0; 3]; rolling.rows.len()];
        let (mut passes, mut total_sweeps) = (0, 0);
        let deadline = coulomb::deadline::deadline(Instant::now(), s.time_limit);
        let solved = loop {
            // `library_only` (method = "library"): no Gauss–Seidel, the library's solver
            // from the warm start (r0, λ0) unless that already solves the problem
            let (mut best, mut lambda, sweeps) = if s.library_only {
                let err = problem.error_with(&r0, &lambda0);
                ((r0.clone(), err, "library"), lambda0.clone(), 0)
            } else {
                let sol = problem.solve(
                    &r0,
                    &lambda0,
                    nsgs::Rule {
                        tol: s.tolerance,
                        max_sweeps: s.max_sweeps,
                        stall_window: s.stall_window,
                        relaxation: if self.plain_sweeps { 1.0 } else { s.relaxation },
                        time_limit: s.time_limit,
                    },
                );
                ((sol.r, sol.error, "nsgs"), sol.lambda, sol.sweeps)
            };
            let library = s.library_finish || s.library_only;
            // wrapped once for the library (no copy of H)
            let global = if library && best.1 > s.tolerance || s.keep_problem {
                Some(coulomb::problem::Problem::Global(
                    problem
                        .to_global_with(&lambda)
                        .map_err(|e| RigidError::Solve {
                            step: k,
                            detail: format!("global problem: {e}"),
                        })?,
                ))
            } else {
                None
            };
            if best.1 > s.tolerance && library {
                if let Some(g) = &global {
                    if let Some((r_lib, l_lib, err_lib, quick)) =
                        library_finish(g, &problem, &best.0, &lambda, s)
                    {
                        // plain sweeps from now on (`RigidWorld::plain_sweeps`)
                        self.plain_sweeps |= quick;
                        if err_lib < best.1 || !best.1.is_finite() {
                            let how = if s.library_only {
                                "library"
                            } else {
                                "nsgs+library"
                            };
                            best = (r_lib, err_lib, how);
                            lambda = l_lib;
                        }
                    }
                }
            }
            self.last_problem = match global {
                Some(coulomb::problem::Problem::Global(g)) if s.keep_problem => Some(g),
                _ => None,
            };
            total_sweeps += sweeps;
            if rolling.is_empty() {
                break (best, lambda);
            }
            best.1 = rolling.error(&problem, &best.0, &lambda, &y);
            passes += 1;
            let late = deadline.is_some_and(|d| Instant::now() >= d);
            if best.1 <= s.tolerance || !best.1.is_finite() || passes >= rolling::MAX_PASSES || late
            {
                break (best, lambda);
            }
            let mut v = problem.velocities_with(&best.0, &lambda);
            rolling.sweep(&problem.mass, &mut v, &best.0, &mut y);
            let joints = problem
                .joints
                .iter()
                .map(|jb| (jb.a, jb.b, jb.rows.clone()))
                .collect();
            problem = nsgs::Problem::new(
                problem.rows.clone(),
                problem.mass.clone(),
                rolling.momenta(&f0, &y),
            )
            .and_then(|p| p.with_joints(joints))
            .map_err(|detail| RigidError::Solve { step: k, detail })?;
            (r0, lambda0) = (best.0, lambda);
        };
        let ((r, error, method), lambda) = solved;
        let v = problem.velocities_with(&r, &lambda);
        let status = if error <= s.tolerance {
            RigidStatus::Converged
        } else {
            RigidStatus::NotConverged
        };
        Ok(Solved {
            problem,
            r,
            lambda,
            v,
            status,
            error,
            sweeps: total_sweeps,
            method,
        })
    }

    /// Keeps each joint's impulses by row slot (the next step's warm start) and its force and
    /// torque on body A (world axes, torque about A's anchor).
    pub(super) fn keep_joint_impulses(&mut self, solved: &Solved) {
        let h = self.settings.h;
        for (j, jb) in solved.problem.joints.iter().enumerate() {
            let mut warm = [0.0; SLOTS];
            let (mut force, mut torque_body) = (Vector::ZERO, Vector::ZERO);
            for (kk, row) in jb.rows.iter().enumerate() {
                let l = solved.lambda[jb.offset + kk];
                warm[row.slot] = l;
                force += l * Vector::new(row.ja[0], row.ja[1], row.ja[2]);
                torque_body += l * Vector::new(row.ja[3], row.ja[4], row.ja[5]);
            }
            self.joint_warm[j] = warm;
            let a = &self.bodies[self.joints[j].desc.body_a];
            let arm = self.joints[j].anchor_a(&self.bodies) - a.x;
            let (force, torque) = (force / h, (a.q * torque_body) / h);
            let torque = torque - arm.cross(force);
            self.joint_forces[j] = [force.x, force.y, force.z, torque.x, torque.y, torque.z];
        }
    }

    /// The position correction Δq per moving body on the linearized end gaps
    /// g_k + h((1 − θ) u_{N,k} + θ u_{N,k+1}) of every detected point, in the index set or not
    /// ([`correct_positions`]); None when it is off, there is nothing to correct, or it fails.
    pub(super) fn correction(&self, set: &IndexSet, solved: &Solved) -> Option<Vec<[f64; 6]>> {
        if !self.settings.position_correction || set.active.is_empty() && set.inactive.is_empty() {
            return None;
        }
        let h = self.settings.h;
        let theta = self.settings.theta;
        let (problem, v) = (&solved.problem, &solved.v);
        let mut end_gaps: Vec<f64> = set
            .active
            .iter()
            .zip(&set.normal_parts)
            .enumerate()
            .map(|(i, (c, (u_nk, w_obstacle)))| {
                let u_end = problem.u(i, v)[0] - problem.rows[i].w[0] + w_obstacle;
                c.gap + h * ((1.0 - theta) * u_nk + theta * u_end)
            })
            .collect();
        end_gaps.extend(set.inactive.iter().map(|(row, gap, u_nk, w_obstacle)| {
            let u_end = nsgs::normal_velocity(row, v) + w_obstacle;
            gap + h * ((1.0 - theta) * u_nk + theta * u_end)
        }));
        let extra: Vec<&nsgs::Row> = set.inactive.iter().map(|(row, ..)| row).collect();
        let scale = self.thinnest_half_width();
        correct_positions(problem, &extra, &end_gaps, 1e-3 * scale, 1e-4 * scale, 200)
            .map(|(dq, _)| dq)
    }

    /// The position update (2.7): x_{k+1} = x_k + h((1 − θ) v_k + θ v_{k+1}),
    /// q_{k+1} = q_k ⊗ exp(h ((1 − θ) Ω_k + θ Ω_{k+1}) / 2), and (v, Ω) ← (v_{k+1}, Ω_{k+1}).
    pub(super) fn integrate(&mut self, v: &[[f64; 6]]) -> Result<(), RigidError> {
        let (h, theta) = (self.settings.h, self.settings.theta);
        for (i, b) in self.bodies.iter_mut().enumerate() {
            let Some(d) = self.dof[i] else {
                continue;
            };
            let vn = Vector::new(v[d][0], v[d][1], v[d][2]);
            let wn = Vector::new(v[d][3], v[d][4], v[d][5]);
            b.x += h * ((1.0 - theta) * b.v + theta * vn);
            b.q = integrate_orientation(b.q, h * ((1.0 - theta) * b.omega + theta * wn));
            b.v = vn;
            b.omega = wn;
            if !(b.x.is_finite() && b.q.is_finite()) {
                return Err(RigidError::NonFiniteState(self.steps));
            }
        }
        Ok(())
    }

    /// Moves each moving body by its correction Δq (positions only: velocities are kept),
    /// then projects the joints back onto their constraints; `NonFiniteState` when a pose
    /// became non-finite. The step's last position phase and each round of the overlap
    /// relaxation ([`super::relax`]).
    pub(super) fn correct(&mut self, correction: Option<&[[f64; 6]]>) -> Result<(), RigidError> {
        if let Some(dq) = correction {
            for (i, b) in self.bodies.iter_mut().enumerate() {
                let Some(d) = self.dof[i] else {
                    continue;
                };
                let x = dq[d];
                b.x += Vector::new(x[0], x[1], x[2]);
                b.q = integrate_orientation(b.q, Vector::new(x[3], x[4], x[5]));
            }
        }
        if !self.joints.is_empty() {
            crate::bodies::joints::project(&self.joints, &mut self.bodies, JOINT_DRIFT_TARGET);
        }
        if self
            .bodies
            .iter()
            .any(|b| !(b.x.is_finite() && b.q.is_finite()))
        {
            return Err(RigidError::NonFiniteState(self.steps));
        }
        Ok(())
    }

    /// The step's physical checks: "penetration" for an active point deeper than
    /// [`PENETRATION_BOUND`] of the thinner body's half width, "energy growth" for mechanical
    /// energy gained beyond [`ENERGY_GROWTH_BOUND`] of the step's scale while every obstacle
    /// is fixed and no motor works; "" when both pass.
    pub(super) fn physics_check(
        &self,
        active: &[ContactPoint],
        before: Energy,
        after: Energy,
    ) -> &'static str {
        let h = self.settings.h;
        let ((kinetic_before, potential_before), (kinetic_after, potential_after)) =
            (before, after);
        let too_deep = active.iter().any(|c| {
            let wa = self.half_width[c.a];
            let w = match c.b {
                Partner::Body(j) => wa.min(self.half_width[j]),
                Partner::Obstacle(_, _) => wa,
            };
            -c.gap > PENETRATION_BOUND * w
        });
        let gained = kinetic_after + potential_after - kinetic_before - potential_before;
        // motors do work: the check applies without them
        let fixed_obstacles = self
            .obstacles
            .iter()
            .all(|o| matches!(o.motion, Motion::Fixed))
            && self.joints.iter().all(|j| j.desc.motor.is_none());
        // 1 % of the kinetic energy, or of that which gravity gives in one step, Σ m (g h)²
        // (the scale of what a solve within its tolerance may add to a body at rest)
        let step_scale: f64 = self
            .bodies
            .iter()
            .filter(|b| !b.fixed)
            .map(|b| b.mass * (h * self.gravity.length()).powi(2))
            .sum();
        let allowed = ENERGY_GROWTH_BOUND * kinetic_before.max(kinetic_after).max(step_scale)
            + 1e-12 * self.energy_scale();
        let energy_grew = fixed_obstacles && (gained.is_nan() || gained > allowed);
        if too_deep {
            "penetration"
        } else if energy_grew {
            "energy growth"
        } else {
            ""
        }
    }

    /// Records the step's contacts (read by the outputs), each with its u_{N,k} from
    /// `normal_parts` (the index set's, point by point), and their impulses in world axes by
    /// contact key (the next step's warm start).
    pub(super) fn record_contacts(
        &mut self,
        active: &[ContactPoint],
        normal_parts: &[(f64, f64)],
        r: &[f64],
    ) {
        let v3 = |x: Vector| Vec3::new(x.x, x.y, x.z);
        self.previous.clear();
        self.contacts = active
            .iter()
            .zip(normal_parts)
            .enumerate()
            .map(|(i, (c, &(u_nk, _)))| {
                let ri = [r[3 * i], r[3 * i + 1], r[3 * i + 2]];
                self.previous
                    .insert(c.key, ri[0] * c.normal + ri[1] * c.t1 + ri[2] * c.t2);
                Contact {
                    body: c.a,
                    partner: c.b,
                    normal: v3(c.normal),
                    t1: v3(c.t1),
                    t2: v3(c.t2),
                    point: v3(c.point),
                    gap: c.gap,
                    normal_velocity: u_nk,
                    impulse: ri,
                }
            })
            .collect();
    }
}
