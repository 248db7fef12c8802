//! Exploration of rolling resistance on the drum, column-collapse and funnel scenes:
//! `cargo run --release --example rolling_explore -- WHAT MU_R`.
use coulomb::solver::Settings;
use coulomb_granular::validation;
use coulomb_granular::Params;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map(String::as_str).unwrap_or("drum");
    let mu_r: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.0);
    let p = Params {
        rolling_friction: mu_r,
        solver: Settings {
            tol: 1e-4,
            inner: coulomb::solver::InnerKind::Pgs,
            outer: coulomb::solver::OuterKind::Fused,
            ..Settings::default()
        },
        ..Params::default()
    };
    let t = std::time::Instant::now();
    match what {
        "drum" => println!("{:?}", validation::drum_angle(300, 6.0, 2.0, &p).unwrap()),
        "colstep" => {
            // the column scene step by step, with progress
            use coulomb_granular::{Simulation, Vec3};
            let r0: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0.25);
            let n: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(300);
            let world = validation::column_world(n, r0);
            let mut sim = Simulation::new(world, p.clone()).unwrap();
            for k in 0..3000 {
                if k == 300 {
                    sim.world.obstacles.truncate(1);
                }
                let s = sim.step().unwrap();
                if k % 50 == 0 {
                    let top = sim
                        .world
                        .bodies
                        .iter()
                        .map(|b| b.position.z)
                        .fold(0.0, f64::max);
                    let far = sim
                        .world
                        .bodies
                        .iter()
                        .map(|b| (b.position - Vec3::new(0.0, 0.0, b.position.z)).norm())
                        .fold(0.0, f64::max);
                    eprintln!("{k} contacts {} sweeps {} ms {:.0} conv {} vmax {:.3} top {top:.3} far {far:.3}", s.contacts, s.inner_iterations, s.solve_ms, s.converged, sim.max_speed());
                }
            }
        }
        "column" => {
            let r0: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0.25);
            let n: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(300);
            println!(
                "{:?}",
                validation::column_collapse(n, r0, 500, 3000, &p).unwrap()
            )
        }
        "funnel" => {
            let n: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(300);
            let cap: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(600);
            println!("{:?}", validation::funnel_heap(n, cap, &p).unwrap())
        }
        _ => eprintln!("drum | column R0 N | funnel N"),
    }
    eprintln!("{:.1} s", t.elapsed().as_secs_f64());
}
