//! One interface over the two engines for whole runs (issue 52, item 4): what a run loop
//! (`coulomb simulate`'s, [`crate::run::RestMonitor`]) needs of a scene, implemented by the
//! sphere engine's [`Simulation`] and the rigid engine's [`RigidScene`]. A step gives the
//! [`EngineStep`] of every scene (the `stats.csv` record and the engine's report); the rest
//! rule, the frames, the checkpoints and the FCLIB dumps are asked the same way.

use crate::bodies::rigid::RigidError;
use crate::checkpoint::CheckpointError;
use crate::output::{FrameSource, VtkWriter};
use crate::output_dir::{OutputDir, RunKind};
use crate::report::EngineStep;
use crate::scene::rigid::RigidScene;
use crate::simulation::{Simulation, SimulationError};
use coulomb::problem::GlobalProblem;
use std::io;
use std::sync::Arc;

/// Why an engine's step failed.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// the sphere engine's error
    #[error(transparent)]
    Spheres(#[from] SimulationError),
    /// the rigid engine's error
    #[error(transparent)]
    Rigid(#[from] RigidError),
}

/// A scene being simulated, whichever engine steps it; its frames are drawn by the one
/// [`VtkWriter`] ([`FrameSource`]).
pub trait Engine: FrameSource {
    /// One Moreau–Jean step.
    fn step(&mut self) -> Result<EngineStep, EngineError>;
    /// Steps taken since t = 0 (a restart's included): k of t_k.
    fn steps_done(&self) -> usize;
    /// Simulated time t_k (s).
    fn time(&self) -> f64;
    /// Bodies in the scene (obstacles excluded).
    fn bodies(&self) -> usize;
    /// Kinetic energy at t_k (J).
    fn kinetic_energy(&self) -> f64;
    /// Gravity's potential energy −Σ m g·x of the moving bodies at t_k (J).
    fn potential_energy(&self) -> f64;
    /// The largest speed over the bodies, |ẋ| + |ω| ρ with ρ the largest distance of the
    /// body's surface from its centre (R for a sphere): the quantity of the rest rule
    /// ([`crate::run::Stop::UntilRest`]).
    fn max_speed(&self) -> f64;
    /// The full state, in the engine's checkpoint format (`--restart` reads it back).
    fn checkpoint_bytes(&self) -> Result<Vec<u8>, CheckpointError>;
    /// Whether each step keeps its problem (2.10) for [`Engine::last_problem`].
    fn keep_problem(&mut self, keep: bool);
    /// The last step's problem (2.10) in global form (None without contacts or without
    /// [`Engine::keep_problem`]).
    fn last_problem(&self) -> Option<&GlobalProblem>;
    /// Which engine, for an output folder's `run.json` ([`crate::output_dir`]).
    fn run_kind(&self) -> RunKind;
    /// The frame writer into `dir`, continuing the collection found there from step
    /// `resumed` (a restart).
    fn frames(&self, dir: Arc<OutputDir>, resumed: Option<usize>) -> VtkWriter {
        let w = VtkWriter::in_dir(dir);
        match resumed {
            Some(k) => w.resumed(k),
            None => w,
        }
    }
    /// Writes the frame of the current state.
    fn frame(&self, frames: &mut VtkWriter) -> io::Result<()> {
        frames.frame(self)
    }
    /// A warning about the step size at the current velocities, said once per run: a body
    /// that may cross a wall or another body within one step before a contact is detected
    /// (spheres: [`crate::tunnelling`], against each obstacle's thickness and speed; other
    /// shapes: [`RigidWorld::travel_warning`], against half the body's thinnest width);
    /// `None` when nothing is wrong.
    ///
    /// [`RigidWorld::travel_warning`]: crate::step::rigid::RigidWorld::travel_warning
    fn step_warning(&self) -> Option<String>;
}

impl Engine for Simulation {
    fn step(&mut self) -> Result<EngineStep, EngineError> {
        Ok(EngineStep::of_spheres(Simulation::step(self)?))
    }
    fn steps_done(&self) -> usize {
        self.steps_done
    }
    fn time(&self) -> f64 {
        self.time
    }
    fn bodies(&self) -> usize {
        self.world.bodies.len()
    }
    fn kinetic_energy(&self) -> f64 {
        self.world.kinetic_energy()
    }
    fn potential_energy(&self) -> f64 {
        self.world.potential_energy()
    }
    fn max_speed(&self) -> f64 {
        Simulation::max_speed(self)
    }
    fn checkpoint_bytes(&self) -> Result<Vec<u8>, CheckpointError> {
        Simulation::checkpoint_bytes(self)
    }
    fn keep_problem(&mut self, keep: bool) {
        self.keep_problem = keep;
    }
    fn last_problem(&self) -> Option<&GlobalProblem> {
        self.last_problem.as_ref()
    }
    fn run_kind(&self) -> RunKind {
        RunKind::Spheres
    }
    fn step_warning(&self) -> Option<String> {
        let (v, r) = crate::tunnelling::speed_and_radius(&self.world);
        crate::tunnelling::check(&self.world, self.params.h, v, r)
            .err()
            .map(|t| t.to_string())
    }
}

impl Engine for RigidScene {
    fn step(&mut self) -> Result<EngineStep, EngineError> {
        let r = RigidScene::step(self)?;
        Ok(EngineStep::of_rigid(r, self.world.potential_energy()))
    }
    fn step_warning(&self) -> Option<String> {
        self.world.travel_warning()
    }
    fn steps_done(&self) -> usize {
        self.world.steps() as usize
    }
    fn time(&self) -> f64 {
        self.world.time()
    }
    fn bodies(&self) -> usize {
        self.world.len()
    }
    fn kinetic_energy(&self) -> f64 {
        self.world.kinetic_energy()
    }
    fn potential_energy(&self) -> f64 {
        self.world.potential_energy()
    }
    fn max_speed(&self) -> f64 {
        let n = |x: &[f64; 3]| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        let v = self.world.velocities();
        let w = self.world.angular_velocities();
        v.iter()
            .zip(&w)
            .zip(&self.shapes)
            .map(|((v, w), s)| {
                let t = s.tessellation().unwrap_or_default();
                let reach = t.vertices.iter().map(n).fold(0.0, f64::max);
                n(v) + n(w) * reach
            })
            .fold(0.0, f64::max)
    }
    fn checkpoint_bytes(&self) -> Result<Vec<u8>, CheckpointError> {
        RigidScene::checkpoint_bytes(self)
    }
    fn keep_problem(&mut self, _keep: bool) {
        // the rigid world keeps each step's problem (its settings' `keep_problem`, on by
        // default): nothing to switch here
    }
    fn last_problem(&self) -> Option<&GlobalProblem> {
        self.world.last_problem()
    }
    fn run_kind(&self) -> RunKind {
        RunKind::Rigid
    }
}
