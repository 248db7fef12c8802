use coulomb::solver::Settings;
use coulomb_granular::{Params, Projection, Scene, Simulation};
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let beads: usize = a[1].parse().unwrap();
    let e: f64 = a[2].parse().unwrap();
    let mu: f64 = a[3].parse().unwrap();
    let proj = a[4] == "1";
    let steps: usize = a[5].parse().unwrap();
    let tol: f64 = a[6].parse().unwrap();
    let theta: f64 = a.get(7).map(|x| x.parse().unwrap()).unwrap_or(0.5);
    let gamma: f64 = a.get(8).map(|x| x.parse().unwrap()).unwrap_or(0.5);
    let keep = a.get(9).map(|x| x == "1").unwrap_or(false);
    let p = Params {
        activation: coulomb_granular::Activation {
            gamma,
            delta: 1e-8,
            keep_separating: keep,
        },
        restitution: e,
        mu,
        theta,
        projection: proj.then(Projection::default),
        solver: Settings {
            tol,
            ..Settings::default()
        },
        ..Params::default()
    };
    let mut sim = Simulation::new(Scene::Box.build(beads, 1), p).unwrap();
    let e0 = sim.world.kinetic_energy() + sim.world.potential_energy();
    let mut prev = e0;
    let (mut worst, mut wp, mut nc, mut maxpen): (f64, f64, usize, f64) = (0.0, 0.0, 0, 0.0);
    let mut emin = e0;
    let mut emax = e0;
    for k in 0..steps {
        let s = sim.step().unwrap();
        let en = s.kinetic_energy + s.potential_energy;
        let d = en - prev - s.projection_work;
        if d > worst {
            worst = d;
        }
        wp += s.projection_work;
        if !s.converged {
            nc += 1;
        }
        maxpen = maxpen.max(s.end_max_penetration);
        emin = emin.min(en);
        emax = emax.max(en);
        if k % (steps / 10).max(1) == 0 {
            println!("k {k} E {en:.6} dE-Wp {d:.3e} Wp {:.3e} c {} err {:.1e} delta {:.2e} pen {:.2e} mean {:.2e} sweeps {}", s.projection_work, s.contacts, s.error, s.delta, s.end_max_penetration, s.end_mean_penetration, s.projection_sweeps);
        }
        prev = en;
    }
    println!("E0 {e0:.6} Eend {prev:.6} min {emin:.6} max {emax:.6} worst step increase beyond Wp {worst:.3e} total Wp {wp:.3e} notconv {nc} maxpen {maxpen:.3e}");
}
