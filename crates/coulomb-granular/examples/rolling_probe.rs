//! Probe of the rolling-resistance sweep's constants (`rolling::Tuning`) on a stored run:
//! `cargo run -p coulomb-granular --example rolling_probe -- CHECKPOINT STEPS RELAX LOCAL
//! LOCAL_EXACT WINDOW STALLED_RELAX [MU_R [TOL]]`; prints, per step, the contacts, sweeps, error and
//! solve time, then the totals (docs/granular.md, "Granular laws", tolerance and cost).
use coulomb_granular::rolling::Tuning;
use coulomb_granular::Simulation;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = a.first() else {
        eprintln!("usage: rolling_probe CHECKPOINT STEPS [RELAX LOCAL LOCAL_EXACT WINDOW STALLED]");
        std::process::exit(2);
    };
    let num = |i: usize| a.get(i).and_then(|s| s.parse::<f64>().ok());
    let steps = num(1).unwrap_or(10.0) as usize;
    let d = Tuning::default();
    let tuning = Tuning {
        relaxation: num(2).unwrap_or(d.relaxation),
        local: num(3).map_or(d.local, |x| x as usize),
        local_exact: num(4).map_or(d.local_exact, |x| x as usize),
        window: num(5).map_or(d.window, |x| x as usize),
        stalled_relaxation: num(6).unwrap_or(d.stalled_relaxation),
    };
    let mut sim = match Simulation::load_checkpoint(path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    sim.rolling.tuning = tuning;
    // optional 8th argument: the rolling-friction coefficient instead of the stored one
    if let Some(mu_r) = num(7) {
        sim.params.rolling_friction = mu_r;
    }
    // optional 9th argument: the tolerance of every step instead of the stored one
    if let Some(tol) = num(8) {
        sim.params.solver.tol = tol;
        if let coulomb_granular::StepMethod::Nsgs(s) = &mut sim.params.method {
            s.tol = tol;
        }
    }
    println!("{tuning:?}");
    let (mut sweeps, mut ms, mut bad) = (0usize, 0.0, 0usize);
    for _ in 0..steps {
        let s = match sim.step() {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        };
        println!(
            "step {} contacts {} sweeps {} err {:.3e} {} {:.0} ms",
            s.step, s.contacts, s.inner_iterations, s.error, s.status, s.solve_ms
        );
        sweeps += s.inner_iterations;
        ms += s.solve_ms;
        bad += usize::from(!s.converged);
    }
    println!("total sweeps {sweeps} solve {ms:.0} ms not converged {bad}");
}
