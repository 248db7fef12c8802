//! The solver on the paper's Painlevé examples where the existence criteria are silent or
//! non-unique (§5.3, §5.4). These need `solver::solve` (implemented on the solver branch).

use coulomb::examples;
use coulomb::existence::{check, CheckSettings, Conclusion};
use coulomb::law::{self, ContactStatus};
use coulomb::solver::{solve, Settings};
use coulomb::Problem;

#[test]
fn example_iii_solver_finds_the_take_off_solution() {
    // §5.3: (4.4) fails, the theory concludes nothing, yet the unique solution is take-off.
    let (theta, mu) = (0.3f64, 0.6);
    let p = examples::painleve(theta, mu, 1.0, 1.0).unwrap();
    let problem = Problem::Global(p.clone());
    let rep = check(&problem, &CheckSettings::default()).unwrap();
    assert_eq!(rep.conclusion, Conclusion::Unknown);
    let settings = Settings::default();
    let sol = solve(&problem, &settings).expect("solver runs");
    assert!(
        sol.converged(),
        "status {:?}, error {}",
        sol.status,
        sol.error
    );
    assert!(sol.error <= settings.tol);
    let v = sol.v.as_ref().expect("global solve returns v");
    assert!((v[0] - theta.sin()).abs() <= 1e-6, "v = {v:?}");
    assert!(law::norm(&sol.r) <= 1e-6, "r = {:?}", sol.r);
    let u = p.velocity(v);
    assert_eq!(law::status(mu, &u, &sol.r, 1e-6), ContactStatus::TakeOff);
}

#[test]
fn example_iv_solver_finds_one_of_the_two_solutions() {
    // §5.4: take-off (v = sin θ, r = 0) and sliding (v = 0, r = (1, −2)) both solve.
    let theta = std::f64::consts::FRAC_PI_4;
    let p = examples::painleve(theta, 2.0, 1.0, 1.0).unwrap();
    let settings = Settings::default();
    let sol = solve(&Problem::Global(p), &settings).expect("solver runs");
    assert!(
        sol.converged(),
        "status {:?}, error {}",
        sol.status,
        sol.error
    );
    let v = sol.v.as_ref().expect("global solve returns v")[0];
    let take_off = (v - theta.sin()).abs() <= 1e-6 && law::norm(&sol.r) <= 1e-6;
    let sliding =
        v.abs() <= 1e-6 && (sol.r[0] - 1.0).abs() <= 1e-6 && (sol.r[1] + 2.0).abs() <= 1e-6;
    assert!(take_off || sliding, "v = {v}, r = {:?}", sol.r);
}
