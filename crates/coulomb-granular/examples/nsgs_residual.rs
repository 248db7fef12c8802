//! Where the Gauss–Seidel residual of one accurate step sits (docs/scaling.md, "Scene
//! sizing"): runs the box scene for STEPS steps with NSGS, then solves the next step's problem
//! from the warm start with 0, 10, 40, 160, 320 sweeps and prints the error, the share of the
//! squared residual carried by the worst 1 % and 10 % of the contacts, and the worst contacts.
//!
//! `cargo run --release --example nsgs_residual -- BEADS STEPS` (SPREAD=1: the spread layout;
//! ONLY=1: print the colouring and stop).

use coulomb_granular::assembly::StepData;
use coulomb_granular::nsgs::{solve, NsgsSettings, StepProblem};
use coulomb_granular::{Params, Scene, Simulation, StepMethod};
fn main() {
    let beads: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2500);
    let steps: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    let params = Params {
        method: StepMethod::Nsgs(NsgsSettings::default()),
        ..Params::default()
    };
    let mut sim = Simulation::new(
        if std::env::var("SPREAD").is_ok() {
            Scene::box_spread(beads, 1)
        } else {
            Scene::Box.build(beads, 1)
        },
        params.clone(),
    )
    .unwrap();
    for _ in 0..steps {
        sim.step().unwrap();
    }
    let contacts = coulomb_granular::contact::detect_with(
        &sim.world,
        sim.time,
        params.h,
        &params.activation,
        sim.activation_threshold(),
    );
    let data = StepData {
        h: params.h,
        t_end: sim.time + params.h,
        restitution: params.restitution,
        mu: params.mu,
        close_gaps: params.activation.close_gaps,
    };
    let p = StepProblem::new(&sim.world, &contacts, &data).unwrap();
    let mut r0 = vec![0.0; 3 * contacts.len()];
    for (i, c) in contacts.iter().enumerate() {
        if let Some(prev) = sim.contacts.iter().find(|d| d.key() == c.key()) {
            r0[3 * i..3 * i + 3].copy_from_slice(&prev.impulse);
        }
    }
    let c = coulomb_granular::nsgs::Colouring::greedy(&p.rows, sim.world.bodies.len());
    println!(
        "contacts {} colours {} sizes {:?}",
        p.rows.len(),
        c.colours(),
        c.starts.windows(2).map(|w| w[1] - w[0]).collect::<Vec<_>>()
    );
    if std::env::var("ONLY").is_ok() {
        return;
    }
    for k in [0usize, 10, 40, 160, 320] {
        let s = NsgsSettings {
            tol: 1e-12,
            max_sweeps: k.max(1),
            ..NsgsSettings::default()
        };
        let sol = solve(&p, &r0, &s, false);
        let r = if k == 0 { r0.clone() } else { sol.r.clone() };
        let (err, scale, _, v) = coulomb_granular::nsgs::evaluate(&p, &r);
        let mut e: Vec<(f64, usize)> = p
            .rows
            .iter()
            .enumerate()
            .map(|(i, row)| {
                let va: [f64; 6] = std::array::from_fn(|d| v[6 * row.a + d]);
                let vb = row
                    .b
                    .map(|j| -> [f64; 6] { std::array::from_fn(|d| v[6 * j + d]) });
                let u = row.velocity(&va, vb.as_ref());
                (
                    coulomb::law::contact_residual_sq(row.mu, &u, &r[3 * i..3 * i + 3]),
                    i,
                )
            })
            .collect();
        e.sort_by(|a, b| b.0.total_cmp(&a.0));
        let tot: f64 = e.iter().map(|x| x.0).sum();
        let top = |f: f64| {
            e.iter()
                .take(((e.len() as f64) * f).ceil() as usize)
                .map(|x| x.0)
                .sum::<f64>()
                / tot
        };
        let worst: Vec<String> = e
            .iter()
            .take(6)
            .map(|&(x, i)| {
                let c = &contacts[i];
                format!(
                    "{}-{:?} z{:.2} x{:.2} y{:.2} e{:.1e} r{:.2e}",
                    c.body,
                    c.partner,
                    c.point.z,
                    c.point.x,
                    c.point.y,
                    x.sqrt() / scale,
                    r[3 * i]
                )
            })
            .collect();
        println!(
            "k={k} err {err:.2e} top1% {:.2} top10% {:.2}\n   {}",
            top(0.01),
            top(0.1),
            worst.join("\n   ")
        );
    }
}
