//! Solve time per step of the box scene at err ≤ 1e-4 for several solver methods (the table of
//! docs/granular.md, "Solver settings in simulations"). Run:
//! `cargo run --release -p coulomb-granular --example step_methods -- BEADS STEPS`.

use coulomb::solver::{InnerKind, Method, OuterKind, Settings};
use coulomb_granular::{Params, Scene, Simulation};
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let beads: usize = a[1].parse().unwrap();
    let steps: usize = a[2].parse().unwrap();
    let d = Settings {
        tol: 1e-4,
        ..Settings::default()
    };
    let cands: Vec<(&str, Settings)> = vec![
        ("default", d.clone()),
        (
            "apgd+fp",
            Settings {
                tol: 1e-4,
                max_outer: 20,
                ..Settings::time_stepping(Method::new(InnerKind::Apgd, OuterKind::FixedPoint))
            },
        ),
        (
            "apgd+anderson",
            Settings {
                tol: 1e-4,
                ..Settings::method(InnerKind::Apgd, OuterKind::Anderson)
            },
        ),
        (
            "pgs+fused",
            Settings {
                tol: 1e-4,
                ..Settings::method(InnerKind::Pgs, OuterKind::Fused)
            },
        ),
    ];
    for (name, s) in cands {
        let p = Params {
            solver: s,
            ..Params::default()
        };
        let mut sim = Simulation::new(Scene::Box.build(beads, 1), p).unwrap();
        let (mut ms, mut nc, mut err, mut worst) = (0.0, 0, 0.0, 0.0f64);
        let t = std::time::Instant::now();
        for _ in 0..steps {
            let s = sim.step().unwrap();
            ms += s.solve_ms;
            if !s.converged {
                nc += 1;
            }
            err += s.error;
            worst = worst.max(s.error);
        }
        println!("{name:14} beads {beads}: solve {:.2} ms/step, total {:.2} s, not converged {nc}, mean err {:.1e}, max {:.1e}", ms / steps as f64, t.elapsed().as_secs_f64(), err / steps as f64, worst);
    }
}
