//! Whole runs: build a scene, step until a stopping rule, summarize (the quantities of
//! Table 1).

use crate::scene::Scene;
use crate::simulation::{Params, Simulation, SimulationError, StepStats};
use serde::Serialize;

/// When a run stops.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// after exactly this many steps
    Steps(usize),
    /// when every sphere's speed |ẋ| + R|ω| stays below `speed` for `window` consecutive
    /// steps (the pile is at rest), or after `max_steps`
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

/// Summary of a run: Table 1's columns and a few more.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// scene name
    pub scene: String,
    /// number of beads
    pub beads: usize,
    /// time steps taken (#TS)
    pub steps: usize,
    /// mean active contacts per step (#contacts/TS)
    pub mean_contacts: f64,
    /// mean subproblems (outer iterations) per step, over steps with contacts (#subprob./TS)
    pub mean_subproblems: f64,
    /// mean solve time per step (ms) (CPU time/TS)
    pub mean_solve_ms: f64,
    /// mean error of docs/error.md over steps with contacts
    pub mean_error: f64,
    /// largest error
    pub max_error: f64,
    /// largest penetration over the run
    pub max_penetration: f64,
    /// steps whose solve reported convergence (or that had no contact)
    pub converged_steps: usize,
    /// steps whose solve did not reach the tolerance
    pub not_converged_steps: usize,
    /// mean penetration over the pairs in touch at the end of the run (m)
    pub end_mean_penetration: f64,
    /// largest penetration at the end of the run (m)
    pub end_max_penetration: f64,
    /// total change of potential energy caused by the position correction (J)
    pub projection_work: f64,
    /// whether the run stopped by the rest rule
    pub at_rest: bool,
    /// why the run stopped ([`Summary::stopped_by`]; from [`Summary::from_stats`] alone:
    /// `rest` or `steps`)
    pub stopped: Stopped,
    /// the signal that interrupted the run (`SIGINT`, `SIGTERM`), absent otherwise
    #[serde(skip_serializing_if = "Option::is_none")]
    pub signal: Option<String>,
}

impl Summary {
    /// Summary of a sequence of step statistics.
    pub fn from_stats(scene: &str, beads: usize, stats: &[StepStats], at_rest: bool) -> Self {
        let n = stats.len().max(1) as f64;
        let with: Vec<&StepStats> = stats.iter().filter(|s| s.contacts > 0).collect();
        let nw = with.len().max(1) as f64;
        Self {
            scene: scene.to_string(),
            beads,
            steps: stats.len(),
            mean_contacts: stats.iter().map(|s| s.contacts as f64).sum::<f64>() / n,
            mean_subproblems: with.iter().map(|s| s.subproblems as f64).sum::<f64>() / nw,
            mean_solve_ms: stats.iter().map(|s| s.solve_ms).sum::<f64>() / n,
            mean_error: with.iter().map(|s| s.error).sum::<f64>() / nw,
            max_error: stats.iter().map(|s| s.error).fold(0.0, f64::max),
            max_penetration: stats.iter().map(|s| s.max_penetration).fold(0.0, f64::max),
            converged_steps: stats.iter().filter(|s| s.converged).count(),
            not_converged_steps: stats.iter().filter(|s| !s.converged).count(),
            end_mean_penetration: stats.last().map_or(0.0, |s| s.end_mean_penetration),
            end_max_penetration: stats.last().map_or(0.0, |s| s.end_max_penetration),
            projection_work: stats.iter().map(|s| s.projection_work).sum(),
            at_rest,
            stopped: if at_rest {
                Stopped::Rest
            } else {
                Stopped::Steps
            },
            signal: None,
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
    /// Whether the run must stop after `steps` steps with the simulation in its current state;
    /// the flag tells whether it stopped at rest.
    pub fn should_stop(&mut self, stop: &Stop, sim: &Simulation) -> (bool, bool) {
        match *stop {
            Stop::Steps(n) => (sim.steps_done >= n, false),
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
                (rest || sim.steps_done >= max_steps, rest)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stop_reason_tells_rest_cap_steps_and_signals_apart() {
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
