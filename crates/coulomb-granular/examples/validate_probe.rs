use coulomb::solver::Settings;
use coulomb_granular::validation::*;
use coulomb_granular::Params;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let tol: f64 = a.get(1).map(|x| x.parse().unwrap()).unwrap_or(1e-4);
    let p = Params {
        solver: Settings {
            tol,
            ..Settings::default()
        },
        ..Params::default()
    };
    for (d, mu) in [(10.0, 0.1), (30.0, 0.3), (45.0, 0.8), (30.0, 0.1)] {
        for roll in [false, true] {
            let c = incline(d, mu, roll, 1.0, &p).unwrap();
            println!(
                "{} exp {:.6} meas {:.6} pass {} nc {}",
                c.name,
                c.expected,
                c.measured,
                c.pass(),
                c.not_converged
            );
        }
    }
    for e in [0.0, 0.5, 0.8] {
        let pd = Params {
            h: 1e-3,
            ..p.clone()
        };
        let (c1, c2) = drop(1.0, e, &pd).unwrap();
        println!(
            "{} exp {:.6} meas {:.6} pass {}",
            c1.name,
            c1.expected,
            c1.measured,
            c1.pass()
        );
        println!(
            "{} exp {:.6} meas {:.6} pass {}",
            c2.name,
            c2.expected,
            c2.measured,
            c2.pass()
        );
    }
    let (c1, c2) = cylinder_roll(10.0, 5.0, &p).unwrap();
    println!(
        "{} exp {:.6} meas {:.6} pass {}",
        c1.name,
        c1.expected,
        c1.measured,
        c1.pass()
    );
    println!(
        "{} exp {:.6} meas {:.6} pass {}",
        c2.name,
        c2.expected,
        c2.measured,
        c2.pass()
    );
    let t = std::time::Instant::now();
    let b = settled_bed(400, 0.5, 1000, &p).unwrap();
    println!("{b:?} {:?}", t.elapsed());
}
