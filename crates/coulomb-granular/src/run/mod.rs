//! Whole runs of either engine: step until a stopping rule ([`RestMonitor`] over an
//! [`Engine`]), summarize (the quantities of Table 1, [`Summary`], the same for every scene).
//! Above both engines' folders (`step/`, `rigid/`) and `io/`: nothing of theirs imports it.

pub mod engine;

use crate::report::{EngineStep, StepDetails, StepRecord};
use crate::scene::Scene;
use crate::simulation::{Params, Simulation, SimulationError, StepStats};
use engine::Engine;
use serde::Serialize;

/// When a run stops.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// after exactly this many steps
    Steps(usize),
    /// when every body's speed |ẋ| + ρ|ω| ([`Engine::max_speed`]: R|ω| for a sphere) stays
    /// below `speed` for `window` consecutive steps (the pile is at rest), or after
    /// `max_steps`
    UntilRest {
        /// speed threshold (m/s)
        speed: f64,
        /// consecutive steps
        window: usize,
        /// step cap
        max_steps: usize,
    },
}

impl Stop {
    /// The default rest rule: speeds below 0.05 m/s over 10 steps, at most 2000 steps.
    pub fn until_rest() -> Self {
        Stop::UntilRest {
            speed: 0.05,
            window: 10,
            max_steps: 2000,
        }
    }
    /// The cap on the number of steps.
    pub fn max_steps(&self) -> usize {
        match *self {
            Stop::Steps(n) => n,
            Stop::UntilRest { max_steps, .. } => max_steps,
        }
    }
}

/// What to simulate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimulationSettings {
    /// the scene
    pub scene: Scene,
    /// number of beads
    pub beads: usize,
    /// seed of the initial arrangement
    pub seed: u64,
    /// time stepping and solver parameters
    pub params: Params,
    /// stopping rule
    pub stop: Stop,
}

impl Default for SimulationSettings {
    fn default() -> Self {
        Self {
            scene: Scene::Box,
            beads: 150,
            seed: 1,
            params: Params::default(),
            stop: Stop::Steps(100),
        }
    }
}

/// Why a run stopped (`"stopped"` in summary.json).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stopped {
    /// it took the number of steps asked for ([`Stop::Steps`])
    Steps,
    /// the rest rule held ([`Stop::UntilRest`])
    Rest,
    /// [`Stop::UntilRest`] reached its step cap without the rest rule holding: the pile was
    /// still moving (a negative answer: `coulomb simulate` exits with status 1)
    StepCap,
    /// a signal (SIGINT, SIGTERM) stopped it after the step in progress
    Interrupted,
}

/// What only the end state of a run gives its [`Summary`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndState {
    /// bodies in the scene at the end (inlets may have added some)
    pub bodies: usize,
    /// simulated time at the end (s)
    pub time: f64,
    /// kinetic energy at the end (J)
    pub kinetic_energy: f64,
}

/// The summary of a run (`summary.json`, `--json`), the same keys with the same meanings for
/// every scene, whichever engine stepped it: Table 1's columns and a few more, built from the
/// runs' [`StepRecord`]s ([`Summary::from_steps`]). What only one engine reports is under
/// `details` (docs/reference.md lists the keys).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// scene name
    pub scene: String,
    /// bodies at the end of the run (a sphere scene's beads; inlets may have added some)
    pub bodies: usize,
    /// time steps taken by this run (#TS)
    pub steps: usize,
    /// simulated time at the end (s)
    pub time: f64,
    /// mean active contacts per step (#contacts/TS)
    pub mean_contacts: f64,
    /// mean iterations of the contact solve per step (the record's `iterations`: Gauss–Seidel
    /// sweeps plus the library's inner iterations), over the steps with contacts
    pub mean_iterations: f64,
    /// mean wall-clock time of the contact solve per step (s) (CPU time/TS)
    pub mean_solve_seconds: f64,
    /// mean error of docs/error.md over the steps with contacts
    pub mean_error: f64,
    /// largest error
    pub max_error: f64,
    /// steps whose solve reached the tolerance (or that had no contact)
    pub converged_steps: usize,
    /// steps whose solve did not reach the tolerance
    pub not_converged_steps: usize,
    /// largest penetration over the active contacts of the steps (m)
    pub max_penetration: f64,
    /// mean penetration over the pairs in touch at the end of the run, after the position
    /// correction (m); `null` where the engine does not measure it (the rigid engine does
    /// not detect contacts at the end of a step) or without steps
    pub end_mean_penetration: Option<f64>,
    /// largest penetration at the end of the run (m); `null` as `end_mean_penetration`
    pub end_max_penetration: Option<f64>,
    /// total change of potential energy caused by the position correction (J); `null` where
    /// the engine does not report it (the rigid engine) or without steps
    pub projection_work: Option<f64>,
    /// whether the run stopped by the rest rule
    pub at_rest: bool,
    /// kinetic energy at the end (J)
    pub kinetic_energy: f64,
    /// why the run stopped ([`Summary::stopped_by`]; from [`Summary::from_steps`] alone:
    /// `rest` or `steps`)
    pub stopped: Stopped,
    /// the signal that interrupted the run (`SIGINT`, `SIGTERM`), absent otherwise
    #[serde(skip_serializing_if = "Option::is_none")]
    pub signal: Option<String>,
    /// what only the engine that stepped the scene reports
    pub details: SummaryDetails,
}

/// The part of a [`Summary`] that only one engine reports (`"details"`, tagged by
/// `"engine"`).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "engine", rename_all = "snake_case")]
pub enum SummaryDetails {
    /// the sphere engine
    Spheres {
        /// mean subproblems (3.15) solved per step, the outer fixed-point iterations, over
        /// the steps with contacts (Table 1's #subprob./TS)
        mean_subproblems: f64,
    },
    /// the rigid-body engine
    Rigid {
        /// mean contacts carrying load per step (r_N > 10⁻⁶ max r_N of the step)
        mean_loaded_contacts: f64,
    },
}

impl Summary {
    /// The summary of the steps `steps` of a run of `scene` ending in `end`; `at_rest` when
    /// the rest rule stopped it. The details are those of the engine of the steps (the
    /// sphere engine's when there are none).
    pub fn from_steps(scene: &str, steps: &[EngineStep], end: EndState, at_rest: bool) -> Self {
        let records: Vec<&StepRecord> = steps.iter().map(|s| &s.record).collect();
        let n = records.len().max(1) as f64;
        let with: Vec<&StepRecord> = records.iter().copied().filter(|s| s.contacts > 0).collect();
        let nw = with.len().max(1) as f64;
        let mean_over_contacts = |f: &dyn Fn(&StepDetails) -> Option<f64>| {
            steps
                .iter()
                .filter(|s| s.record.contacts > 0)
                .filter_map(|s| f(&s.details))
                .sum::<f64>()
                / nw
        };
        let rigid = matches!(steps.first(), Some(s) if matches!(s.details, StepDetails::Rigid(_)));
        let details = if rigid {
            let loaded = steps
                .iter()
                .filter_map(|s| match &s.details {
                    StepDetails::Rigid(r) => Some(r.loaded_contacts as f64),
                    StepDetails::Spheres(_) => None,
                })
                .sum::<f64>();
            SummaryDetails::Rigid {
                mean_loaded_contacts: loaded / n,
            }
        } else {
            SummaryDetails::Spheres {
                mean_subproblems: mean_over_contacts(&|d| match d {
                    StepDetails::Spheres(s) => Some(s.subproblems as f64),
                    StepDetails::Rigid(_) => None,
                }),
            }
        };
        let end_penetration = steps.last().and_then(EngineStep::end_penetration);
        let projection_work = steps
            .iter()
            .map(EngineStep::projection_work)
            .try_fold(0.0, |sum, w| w.map(|w| sum + w))
            .filter(|_| !steps.is_empty());
        Self {
            scene: scene.to_string(),
            bodies: end.bodies,
            steps: records.len(),
            time: end.time,
            mean_contacts: records.iter().map(|s| s.contacts as f64).sum::<f64>() / n,
            mean_iterations: with.iter().map(|s| s.iterations as f64).sum::<f64>() / nw,
            mean_solve_seconds: records.iter().map(|s| s.solve_seconds).sum::<f64>() / n,
            mean_error: with.iter().map(|s| s.error).sum::<f64>() / nw,
            max_error: records.iter().map(|s| s.error).fold(0.0, f64::max),
            converged_steps: records.iter().filter(|s| s.converged).count(),
            not_converged_steps: records.iter().filter(|s| !s.converged).count(),
            max_penetration: records
                .iter()
                .map(|s| s.max_penetration)
                .fold(0.0, f64::max),
            end_mean_penetration: end_penetration.map(|p| p.0),
            end_max_penetration: end_penetration.map(|p| p.1),
            projection_work,
            at_rest,
            kinetic_energy: end.kinetic_energy,
            stopped: if at_rest {
                Stopped::Rest
            } else {
                Stopped::Steps
            },
            signal: None,
            details,
        }
    }

    /// The summary of the sphere-engine steps `stats` of a run of `scene` with `bodies`
    /// beads, its end state that of the last step (time 0 and no kinetic energy without
    /// steps).
    pub fn from_stats(scene: &str, bodies: usize, stats: &[StepStats], at_rest: bool) -> Self {
        let end = EndState {
            bodies,
            time: stats.last().map_or(0.0, |s| s.time),
            kinetic_energy: stats.last().map_or(0.0, |s| s.kinetic_energy),
        };
        let steps: Vec<EngineStep> = stats.iter().cloned().map(EngineStep::of_spheres).collect();
        Self::from_steps(scene, &steps, end, at_rest)
    }

    /// Mean subproblems per step of a sphere run ([`SummaryDetails::Spheres`]); `None` for
    /// another engine.
    pub fn mean_subproblems(&self) -> Option<f64> {
        match self.details {
            SummaryDetails::Spheres { mean_subproblems } => Some(mean_subproblems),
            SummaryDetails::Rigid { .. } => None,
        }
    }

    /// The summary with why the run stopped, under the rule `stop`: interrupted by `signal`
    /// (when some), at rest, at the step cap of [`Stop::UntilRest`] without rest, or after
    /// the steps asked for.
    pub fn stopped_by(mut self, stop: &Stop, signal: Option<&str>) -> Self {
        self.stopped = match (signal, stop) {
            (Some(_), _) => Stopped::Interrupted,
            (None, _) if self.at_rest => Stopped::Rest,
            (None, Stop::UntilRest { .. }) => Stopped::StepCap,
            (None, Stop::Steps(_)) => Stopped::Steps,
        };
        self.signal = signal.map(str::to_string);
        self
    }
}

/// Tracks the rest rule of [`Stop::UntilRest`].
#[derive(Debug, Clone, Default)]
pub struct RestMonitor {
    calm: usize,
}

impl RestMonitor {
    /// Whether the run must stop with the scene `sim` (of either engine) in its current
    /// state; the flag tells whether it stopped at rest.
    pub fn should_stop<E: Engine + ?Sized>(&mut self, stop: &Stop, sim: &E) -> (bool, bool) {
        match *stop {
            Stop::Steps(n) => (sim.steps_done() >= n, false),
            Stop::UntilRest {
                speed,
                window,
                max_steps,
            } => {
                if sim.max_speed() < speed {
                    self.calm += 1;
                } else {
                    self.calm = 0;
                }
                let rest = self.calm >= window.max(1);
                (rest || sim.steps_done() >= max_steps, rest)
            }
        }
    }
}

/// Runs a simulation, calling `each(sim, stats)` after every step.
pub fn run_with(
    settings: &SimulationSettings,
    mut each: impl FnMut(&Simulation, &StepStats),
) -> Result<(Summary, Vec<StepStats>), SimulationError> {
    let world = settings.scene.build(settings.beads, settings.seed);
    let mut sim = Simulation::new(world, settings.params.clone())?;
    let mut stats = Vec::new();
    let mut monitor = RestMonitor::default();
    let mut at_rest = false;
    while sim.steps_done < settings.stop.max_steps() {
        let s = sim.step()?;
        each(&sim, &s);
        stats.push(s);
        let (stop, rest) = monitor.should_stop(&settings.stop, &sim);
        if stop {
            at_rest = rest;
            break;
        }
    }
    let summary = Summary::from_stats(settings.scene.name(), settings.beads, &stats, at_rest)
        .stopped_by(&settings.stop, None);
    Ok((summary, stats))
}

/// Runs a simulation and returns its summary (used by `coulomb demo`).
pub fn run(settings: &SimulationSettings) -> Result<Summary, SimulationError> {
    run_with(settings, |_, _| {}).map(|(s, _)| s)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn the_stop_reason_tells_rest_cap_steps_and_signals_apart() {
        let rest_rule = Stop::until_rest();
        let summary = |at_rest| Summary::from_stats("box", 3, &[], at_rest);
        assert_eq!(summary(true).stopped, Stopped::Rest);
        assert_eq!(summary(false).stopped, Stopped::Steps);
        let capped = summary(false).stopped_by(&rest_rule, None);
        assert_eq!(capped.stopped, Stopped::StepCap);
        assert_eq!(capped.signal, None);
        assert_eq!(
            summary(true).stopped_by(&rest_rule, None).stopped,
            Stopped::Rest
        );
        assert_eq!(
            summary(false).stopped_by(&Stop::Steps(5), None).stopped,
            Stopped::Steps
        );
        let stopped = summary(false).stopped_by(&Stop::Steps(5), Some("SIGTERM"));
        assert_eq!(stopped.stopped, Stopped::Interrupted);
        let json = serde_json::to_value(&stopped).unwrap();
        assert_eq!(json["stopped"], "interrupted");
        assert_eq!(json["signal"], "SIGTERM");
        let json = serde_json::to_value(&capped).unwrap();
        assert_eq!(json["stopped"], "step_cap");
        assert!(json.get("signal").is_none());
    }
}
