//! One step record for every scene (issue 52): the row of `stats.csv` and the dict of Python's
//! `Simulation.step()`, the same fields with the same meanings whichever engine took the step
//! (the sphere engine's [`StepStats`] or the rigid engine's [`RigidStepReport`], each of which
//! keeps its engine's details for `stats.json`). docs/reference.md lists the columns.

use crate::simulation::StepStats;
use crate::step::rigid::{RigidStatus, RigidStepReport};
use serde::Serialize;

/// Header of `stats.csv`, the fields of [`StepRecord`] in order.
pub const CSV_HEADER: &str = "step,time,status,converged,error,contacts,warm_started,iterations,solve_seconds,kinetic_energy,potential_energy,max_penetration";

/// Index of the only column of [`CSV_HEADER`] that depends on the clock (`solve_seconds`).
pub const CLOCK_COLUMN: usize = 8;

/// One step of any scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepRecord {
    /// step index k (the step from t_k to t_{k+1})
    pub step: u64,
    /// t_{k+1} (s)
    pub time: f64,
    /// how the step's contact problem ended: "no_contact", "converged", or why it did not
    /// converge (the solver's status, e.g. "max_iterations", "not_converged")
    pub status: String,
    /// the error below the tolerance ("converged"), or no contact ("no_contact")
    pub converged: bool,
    /// error of docs/error.md of the returned (v, r) on the step's stored problem (0 without
    /// contacts)
    pub error: f64,
    /// active contacts (rows of the step's problem)
    pub contacts: usize,
    /// contacts warm started from the previous step's impulses
    pub warm_started: usize,
    /// iterations of the contact solve: Gauss–Seidel sweeps, plus the inner iterations of the
    /// library's solver when it solved or finished the step
    pub iterations: usize,
    /// wall-clock time of the contact solve (s)
    pub solve_seconds: f64,
    /// kinetic energy at t_{k+1} (J)
    pub kinetic_energy: f64,
    /// gravity's potential energy −Σ m g·x of the moving bodies at t_{k+1} (J)
    pub potential_energy: f64,
    /// largest penetration max(0, −g) over the active contacts at t_k (m)
    pub max_penetration: f64,
}

impl StepRecord {
    /// The record of a sphere-engine step.
    pub fn of_spheres(s: &StepStats) -> Self {
        Self {
            step: s.step as u64,
            time: s.time,
            status: s.status.clone(),
            converged: s.converged,
            error: s.error,
            contacts: s.contacts,
            warm_started: s.warm_started,
            iterations: s.inner_iterations,
            solve_seconds: s.solve_ms * 1e-3,
            kinetic_energy: s.kinetic_energy,
            potential_energy: s.potential_energy,
            max_penetration: s.max_penetration,
        }
    }

    /// The record of a rigid-engine step; `potential_energy` of the world after it
    /// (`RigidWorld::potential_energy`), which the report does not carry.
    pub fn of_rigid(r: &RigidStepReport, potential_energy: f64) -> Self {
        let status = match r.status {
            RigidStatus::NoContact => "no_contact",
            RigidStatus::Converged => "converged",
            RigidStatus::NotConverged => "not_converged",
        };
        Self {
            step: r.step,
            time: r.time,
            status: status.into(),
            converged: r.status != RigidStatus::NotConverged,
            error: r.error,
            contacts: r.contacts,
            warm_started: r.warm_started,
            iterations: r.sweeps,
            solve_seconds: r.solve_seconds,
            kinetic_energy: r.kinetic_energy,
            potential_energy,
            max_penetration: r.max_penetration,
        }
    }

    /// The row of `stats.csv` ([`CSV_HEADER`]).
    pub fn csv_line(&self) -> String {
        format!(
            "{},{:.6},{},{},{:.6e},{},{},{},{:.6e},{:.9e},{:.9e},{:.6e}",
            self.step,
            self.time,
            self.status,
            self.converged,
            self.error,
            self.contacts,
            self.warm_started,
            self.iterations,
            self.solve_seconds,
            self.kinetic_energy,
            self.potential_energy,
            self.max_penetration
        )
    }
}

/// The engine's own report of one step, kept beside its [`StepRecord`]: the sphere engine's
/// [`StepStats`] or the rigid engine's [`RigidStepReport`] (`"details"` of a `stats.json` row).
#[derive(Debug, Clone, PartialEq)]
pub enum StepDetails {
    /// a step of the sphere engine
    Spheres(StepStats),
    /// a step of the rigid-body engine
    Rigid(RigidStepReport),
}

/// One step of any scene as a run keeps it: the record every scene shares and its engine's
/// report.
#[derive(Debug, Clone, PartialEq)]
pub struct EngineStep {
    /// the fields every scene has (`stats.csv`)
    pub record: StepRecord,
    /// the engine's report
    pub details: StepDetails,
}

impl EngineStep {
    /// A step of the sphere engine.
    pub fn of_spheres(s: StepStats) -> Self {
        Self {
            record: StepRecord::of_spheres(&s),
            details: StepDetails::Spheres(s),
        }
    }

    /// A step of the rigid engine, with the world's potential energy after it.
    pub fn of_rigid(r: RigidStepReport, potential_energy: f64) -> Self {
        Self {
            record: StepRecord::of_rigid(&r, potential_energy),
            details: StepDetails::Rigid(r),
        }
    }

    /// The mean and largest penetration over the pairs in touch at the end of the step,
    /// after the position correction, where the engine measures them (the sphere engine;
    /// the rigid engine does not detect contacts at the end of a step: `None`).
    pub fn end_penetration(&self) -> Option<(f64, f64)> {
        match &self.details {
            StepDetails::Spheres(s) => Some((s.end_mean_penetration, s.end_max_penetration)),
            StepDetails::Rigid(_) => None,
        }
    }

    /// The change of potential energy caused by the step's position correction (J), where
    /// the engine reports it (the sphere engine; `None` for the rigid engine, whose report
    /// does not carry it).
    pub fn projection_work(&self) -> Option<f64> {
        match &self.details {
            StepDetails::Spheres(s) => Some(s.projection_work),
            StepDetails::Rigid(_) => None,
        }
    }

    /// The row of `stats.json`: the record's fields (the columns of [`CSV_HEADER`]), then
    /// `"details"`: the engine's report without the fields the record has under the same
    /// name.
    pub fn json_row(&self) -> serde_json::Result<serde_json::Value> {
        let mut row = serde_json::to_value(&self.record)?;
        let mut details = match &self.details {
            StepDetails::Spheres(s) => serde_json::to_value(s)?,
            StepDetails::Rigid(r) => serde_json::to_value(r)?,
        };
        if let (Some(row), Some(details)) = (row.as_object_mut(), details.as_object_mut()) {
            details.retain(|k, _| !row.contains_key(k));
            row.insert("details".into(), serde_json::Value::Object(details.clone()));
        }
        Ok(row)
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn the_csv_row_has_one_field_per_column() {
        let r = StepRecord {
            step: 3,
            time: 0.08,
            status: "converged".into(),
            converged: true,
            error: 1e-5,
            contacts: 12,
            warm_started: 10,
            iterations: 40,
            solve_seconds: 1e-3,
            kinetic_energy: 1.5,
            potential_energy: -2.0,
            max_penetration: 1e-6,
        };
        let line = r.csv_line();
        assert_eq!(line.split(',').count(), CSV_HEADER.split(',').count());
        assert_eq!(
            CSV_HEADER.split(',').nth(CLOCK_COLUMN),
            Some("solve_seconds")
        );
        // the serialized record has the columns' names, in order
        let json = serde_json::to_value(&r).unwrap();
        let keys: Vec<&str> = json
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        let mut names: Vec<&str> = CSV_HEADER.split(',').collect();
        names.sort_unstable();
        let mut sorted = keys.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, names);
        assert_eq!(line.split(',').nth(2), Some("converged"));
    }
}
