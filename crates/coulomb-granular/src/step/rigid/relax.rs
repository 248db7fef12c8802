//! Relaxation of the interpenetrations of a rigid world at t = 0 (`--resolve-overlaps` for
//! scenes of any shapes; the sphere scenes' [`crate::model::resolve_overlaps`] for bodies of
//! any shape): rounds of detection, each followed by the step's position correction
//! ([`super::correct_positions`]) on the gaps found, until no point is deeper than
//! `max_initial_penetration`. Positions and orientations move; velocities do not.

use super::placed_obstacles;
use super::{correct_positions, nsgs, ContactPoint, RigidError, RigidWorld, Vector};

/// Interpenetrations: how many manifold points are deeper than the limit, and the deepest.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Overlaps {
    /// points deeper than `max_initial_penetration`
    pub count: usize,
    /// the deepest penetration (m), 0 when none
    pub worst: f64,
}

/// Result of [`RigidWorld::relax_overlaps`].
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Relaxed {
    /// before the relaxation
    pub before: Overlaps,
    /// Gauss–Seidel sweeps done (over all rounds)
    pub sweeps: usize,
    /// left after it (count 0 when the world is free of them)
    pub left: Overlaps,
    /// it stopped at its time cap with overlaps left
    /// ([`crate::model::RELAXATION_TIME_LIMIT`])
    pub timed_out: bool,
}

/// Sweeps of one round's position correction at most.
const SWEEPS_PER_ROUND: usize = 200;

impl RigidWorld {
    /// The manifold points at t_k, without those between bodies a joint links.
    fn points_now(&mut self) -> Result<Vec<ContactPoint>, RigidError> {
        let margins = vec![0.0; self.bodies.len()];
        let placed = placed_obstacles(&self.obstacles, &self.obstacle_base, self.time);
        let mut points = self
            .detector
            .detect(&self.bodies, &self.shapes, &placed, &margins)?;
        self.drop_jointed(&mut points);
        Ok(points)
    }

    /// The points deeper than `limit`.
    fn overlaps_in(points: &[ContactPoint], limit: f64) -> Overlaps {
        let deep = points.iter().filter(|c| c.gap < -limit);
        Overlaps {
            count: deep.clone().count(),
            worst: deep.map(|c| -c.gap).fold(0.0, f64::max),
        }
    }

    /// Moves the free bodies apart until no manifold point is deeper than
    /// `settings.max_initial_penetration`, in at most `max_sweeps` Gauss–Seidel sweeps: each
    /// round detects the points, then displaces the bodies by Δq = M⁻¹ H_Nᵀ λ, λ ≥ 0, so that
    /// every linearized gap g_i + (H_Nᵀ Δq)_i reaches half the limit (the step's position
    /// correction), and the joints are projected back. Deterministic (the detector's order).
    pub fn relax_overlaps(&mut self, max_sweeps: usize) -> Result<Relaxed, RigidError> {
        self.relax_overlaps_within(max_sweeps, crate::model::RELAXATION_TIME_LIMIT)
    }

    /// [`RigidWorld::relax_overlaps`] stopped after `time_limit` (checked before each round).
    pub fn relax_overlaps_within(
        &mut self,
        max_sweeps: usize,
        time_limit: std::time::Duration,
    ) -> Result<Relaxed, RigidError> {
        let start = std::time::Instant::now();
        let mut timed_out = false;
        let limit = self.settings.max_initial_penetration;
        let mut points = self.points_now()?;
        let before = Self::overlaps_in(&points, limit);
        let mut sweeps = 0;
        let moving = self.dof.iter().filter(|d| d.is_some()).count();
        let omega = vec![Vector::ZERO; self.bodies.len()];
        while sweeps < max_sweeps && Self::overlaps_in(&points, limit).count > 0 {
            if start.elapsed() >= time_limit {
                timed_out = true;
                break;
            }
            let mut mass = vec![[0.0; 6]; moving];
            for (i, b) in self.bodies.iter().enumerate() {
                if let Some(d) = self.dof[i] {
                    mass[d] = b.mass_block();
                }
            }
            let (rows, gaps): (Vec<nsgs::Row>, Vec<f64>) = points
                .iter()
                .filter(|c| c.gap < 0.0)
                .map(|c| (self.row(c, &omega, self.time).0, c.gap - 0.5 * limit))
                .unzip();
            let problem = nsgs::Problem::new(rows, mass, vec![[0.0; 6]; moving])
                .map_err(|detail| RigidError::Solve { step: 0, detail })?;
            let budget = SWEEPS_PER_ROUND.min(max_sweeps - sweeps);
            let Some((dq, done)) = correct_positions(&problem, &[], &gaps, 0.0, 0.0, budget) else {
                break;
            };
            sweeps += done.max(1);
            self.correct(Some(&dq))?;
            points = self.points_now()?;
        }
        let left = Self::overlaps_in(&points, limit);
        if timed_out && left.count > 0 {
            return Err(RigidError::RelaxationTimedOut {
                seconds: time_limit.as_secs_f64(),
                sweeps,
                count: left.count,
                depth: left.worst,
            });
        }
        Ok(Relaxed {
            before,
            sweeps,
            left,
            timed_out: false,
        })
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use crate::bodies::rigid::{MassProperties, RigidBodyDesc};
    use crate::step::rigid::{RigidSettings, RigidWorld};
    use crate::world::{ContactLaw, MaterialTable};
    use parry3d_f64::shape::SharedShape;

    fn cube(z: f64) -> RigidBodyDesc {
        let half = 0.05;
        let m = 1.0;
        let i = m * (2.0 * half) * (2.0 * half) / 6.0;
        RigidBodyDesc {
            shape: SharedShape::cuboid(half, half, half),
            mass: MassProperties {
                mass: m,
                local_com: [0.0; 3],
                inertia: [[i, 0.0, 0.0], [0.0, i, 0.0], [0.0, 0.0, i]],
            },
            position: [0.0, 0.0, z],
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            material: 0,
            fixed: false,
        }
    }

    fn table() -> MaterialTable {
        MaterialTable::uniform(
            vec!["default".into()],
            ContactLaw {
                mu: 0.5,
                restitution: 0.0,
                rolling_friction: 0.0,
            },
        )
    }

    /// Two cubes stacked 1 cm into each other and 5 mm into the floor: refused as built,
    /// relaxed apart (every point within the limit) without changing a velocity, and the
    /// relaxed world then builds its steps as a valid one.
    pub fn a_sunken_stack_is_relaxed_apart() {
        let bodies = || vec![cube(0.045), cube(0.135)];
        let settings = RigidSettings {
            h: 1e-3,
            ..RigidSettings::default()
        };
        let refused = RigidWorld::new(
            bodies(),
            vec![crate::validation::rigid::floor()],
            table(),
            settings.clone(),
        )
        .expect_err("deep");
        assert!(refused.to_string().contains("interpenetrat"), "{refused}");
        let (mut w, r) = RigidWorld::relaxed(
            bodies(),
            vec![crate::validation::rigid::floor()],
            table(),
            settings,
            &[],
            1000,
        )
        .expect("relaxed");
        assert!(r.before.count > 0 && r.before.worst > 9e-3, "{r:?}");
        assert_eq!(r.left.count, 0, "{r:?}");
        assert!(r.sweeps > 0 && r.sweeps <= 1000);
        let z: Vec<f64> = w.positions().iter().map(|p| p[2]).collect();
        assert!(z[0] >= 0.05 - 1e-8 && z[1] >= z[0] + 0.1 - 1e-8, "{z:?}");
        assert!(w.velocities().iter().flatten().all(|v| *v == 0.0));
        assert!(w.step().is_ok());
    }

    /// A relaxation that reaches its time cap with overlaps left is refused, saying so.
    pub fn a_relaxation_past_its_time_cap_is_refused() {
        let settings = RigidSettings {
            h: 1e-3,
            ..RigidSettings::default()
        };
        let mut w = RigidWorld::overlapping(
            vec![cube(0.045), cube(0.135)],
            vec![crate::validation::rigid::floor()],
            table(),
            settings,
            &[],
        )
        .unwrap();
        let e = w
            .relax_overlaps_within(1000, std::time::Duration::ZERO)
            .expect_err("no time");
        assert!(
            matches!(e, crate::bodies::rigid::RigidError::RelaxationTimedOut { sweeps: 0, count, .. } if count > 0),
            "{e}"
        );
        assert!(e.to_string().contains("time limit"), "{e}");
        let r = w
            .relax_overlaps_within(1000, std::time::Duration::from_secs(600))
            .expect("in time");
        assert_eq!(r.left.count, 0, "{r:?}");
    }

    /// A budget too small leaves overlaps: the world is refused with the typed error.
    pub fn a_budget_too_small_is_refused() {
        let settings = RigidSettings {
            h: 1e-3,
            ..RigidSettings::default()
        };
        let e = RigidWorld::relaxed(
            vec![cube(0.045), cube(0.135)],
            vec![crate::validation::rigid::floor()],
            table(),
            settings,
            &[],
            0,
        )
        .expect_err("no sweep");
        assert!(e.to_string().contains("interpenetrat"), "{e}");
    }
}
