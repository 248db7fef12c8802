//! The `granular` class: steps of coulomb's own Moreau–Jean simulations (`coulomb simulate`'s
//! scenes, its default h, θ, e), taken at an early step (beads falling, first contacts), a few
//! steps later (impacts) and late (a settled heap, or the steady flow of the funnel and the
//! drum), each in global and local form.
//!
//! Each step of these simulations is solved by body-level Gauss–Seidel ([`STEP_SOLVER`]: err
//! ≤ 1e-4 or 20 000 sweeps, no time limit, no finish by the library's solver), not by the
//! solver under test: the simulations are chaotic, so a step solved by the default solver would
//! make every file after it depend on the build that generated the corpus, and a solver change
//! could not be measured on the same files as the build before it. The steps depend only on
//! `coulomb_granular`'s sweep and the library's one-contact law solve.

use super::{both_forms, Item, Preset};
use anyhow::Context;
use coulomb_granular::{NsgsSettings, Params, Scene, Simulation, StepMethod};

/// The step solver of the simulations: Gauss–Seidel (ω = 1.5) to err ≤ 1e-4 or 20 000 sweeps,
/// whichever comes first; deterministic (no time limit, the same numbers on any number of
/// threads) and independent of the library's solver pipeline.
pub const STEP_SOLVER: NsgsSettings = NsgsSettings {
    tol: 1e-4,
    max_sweeps: 20_000,
    time_limit: None,
    relaxation: 1.5,
    serial_below: 1_500,
    library_finish: false,
    subspace_every: 0,
    coarse_every: 0,
    coarse_cell: 0,
    coarse_smooth: 0,
};

/// (phase, step index) pairs; a step with fewer than [`min_contacts`] contacts is replaced by
/// the next one with enough (so that "falling" is the first step where a tenth of the beads
/// touch something, the rest still falling).
const PHASES: [(&str, usize); 3] = [("falling", 2), ("impacting", 8), ("settled", 60)];

/// Fewest contacts of a dumped step: a tenth of the beads, at least 5.
fn min_contacts(beads: usize) -> usize {
    (beads / 10).max(5)
}

/// Writes the class.
pub fn generate(
    preset: Preset,
    seed: u64,
    sink: &mut dyn FnMut(Item) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    // (scene, beads, μ)
    let mut runs: Vec<(Scene, usize, f64)> = Vec::new();
    match preset {
        Preset::Small => {
            runs.push((Scene::Box, 120, 0.3));
            runs.push((Scene::Funnel, 150, 0.6));
            runs.push((Scene::RotatingDrum, 80, 1.0));
            runs.push((Scene::VibratingPlate, 100, 0.1));
        }
        Preset::Full => {
            let mus = [0.1, 0.3, 0.6, 1.0];
            for (s, scene) in Scene::ALL.into_iter().enumerate() {
                // the funnel, drum and plate pile many beads in a small bin: their large runs
                // take minutes on a 2-core machine, so only the box goes to 5 000 beads
                let sizes = if scene == Scene::Box {
                    vec![100, 300, 1000, 2500, 5000]
                } else {
                    vec![100, 300, 1000]
                };
                for (b, beads) in sizes.into_iter().enumerate() {
                    runs.push((scene, beads, mus[(s + b) % 4]));
                    if beads <= 300 {
                        runs.push((scene, beads, mus[(s + b + 2) % 4]));
                    }
                }
            }
        }
    }
    let phases: &[(&str, usize)] = match preset {
        Preset::Small => &[("falling", 2), ("settled", 40)],
        Preset::Full => &PHASES,
    };
    for (k, (scene, beads, mu)) in runs.into_iter().enumerate() {
        let run_seed = seed.wrapping_add(k as u64);
        let params = Params {
            mu,
            method: StepMethod::Nsgs(STEP_SOLVER),
            ..Params::default()
        };
        let world = scene.build(beads, run_seed);
        let mut sim = Simulation::new(world, params).context("granular simulation")?;
        sim.keep_problem = true;
        let last = phases.iter().map(|p| p.1).max().unwrap_or(0);
        let mut next = 0;
        // at most 50 extra steps to find enough contacts for the last phase
        while next < phases.len() && sim.steps_done < last + 50 {
            sim.step()
                .with_context(|| format!("{} {beads} beads", scene.name()))?;
            let step = sim.steps_done;
            if step < phases[next].1 {
                continue;
            }
            let Some(g) = sim.last_problem.take() else {
                continue;
            };
            if g.mu.len() < min_contacts(beads) {
                continue;
            }
            let (phase, _) = phases[next];
            both_forms(
                "granular",
                &format!("{}-n{beads}-mu{mu}-{phase}-s{step}", scene.name()),
                g,
                None,
                serde_json::json!({
                    "scene": scene.name(), "beads": beads, "mu": mu, "phase": phase,
                    "step": step, "seed": run_seed, "h": sim.params.h,
                    "restitution": sim.params.restitution,
                }),
                sink,
            )?;
            next += 1;
        }
    }
    Ok(())
}
