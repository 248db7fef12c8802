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
        "column" => {
            let r0: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0.25);
            let n: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(300);
            println!("{:?}", validation::column_collapse(n, r0, &p).unwrap())
        }
        "funnel" => {
            let n: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(300);
            println!("{:?}", validation::funnel_heap(n, 1500, &p).unwrap())
        }
        _ => eprintln!("drum | column R0 N | funnel N"),
    }
    eprintln!("{:.1} s", t.elapsed().as_secs_f64());
}
