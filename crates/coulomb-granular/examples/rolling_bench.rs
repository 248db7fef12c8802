//! Cost of the rolling-resistance step (crate::rolling) on the box scene:
//! `cargo run --release --example rolling_bench -- BEADS STEPS E MU MU_R`
//! prints sweeps per step (mean, max), solve time per step (mean, total), steps not converged
//! and the largest error.
use coulomb::solver::Settings;
use coulomb_granular::{Params, Scene, Simulation};

fn main() {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|s| s.parse().ok())
        .collect();
    let get = |i: usize, d: f64| a.get(i).copied().unwrap_or(d);
    let (beads, steps) = (get(0, 150.0) as usize, get(1, 1000.0) as usize);
    let p = Params {
        restitution: get(2, 0.5),
        mu: get(3, 0.8),
        rolling_friction: get(4, 0.1),
        solver: Settings {
            tol: 1e-4,
            ..Settings::default()
        },
        ..Params::default()
    };
    let mut sim = Simulation::new(Scene::Box.build(beads, 1), p).expect("scene");
    let (mut sweeps, mut max_sweeps, mut ms, mut bad, mut worst) = (0usize, 0usize, 0.0, 0, 0.0f64);
    let t = std::time::Instant::now();
    for k in 0..steps {
        let s = sim.step().expect("step");
        sweeps += s.inner_iterations;
        max_sweeps = max_sweeps.max(s.inner_iterations);
        ms += s.solve_ms;
        worst = worst.max(s.error);
        if !s.converged {
            bad += 1;
            eprintln!(
                "step {k}: not converged, err {:.3e} (rolling part {:.3e}), sweeps {}",
                s.error, sim.rolling.rolling_error, s.inner_iterations
            );
        }
    }
    println!(
        "sweeps/step mean {:.1} max {max_sweeps}; solve ms/step {:.2}; wall {:.1} s; not converged {bad}; worst err {worst:.2e}",
        sweeps as f64 / steps as f64,
        ms / steps as f64,
        t.elapsed().as_secs_f64()
    );
}
