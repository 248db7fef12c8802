//! An FCLIB problem with no contacts (issue 55 asked what it means; docs/error.md, "A problem
//! with no contacts"): a valid problem, read and solved as stored. Local: the empty r is its
//! exact solution, err = 0, converged in 0 iterations. Global: v = M⁻¹ f, judged by the
//! balance residual like every global solution.

use coulomb::fclib::{self, FclibFile, WriteOptions};
use coulomb::solver::{self, Settings, Status};
use coulomb::{CscMatrix, GlobalProblem, LocalProblem, Problem};

fn round_trip(p: Problem) -> Problem {
    let bytes = fclib::to_bytes(&FclibFile::new(p), &WriteOptions::default()).unwrap();
    fclib::read_bytes("zero.hdf5", bytes).unwrap().problem
}

#[test]
fn a_local_problem_without_contacts_is_solved_exactly() {
    let p = round_trip(Problem::Local(
        LocalProblem::new(3, CscMatrix::zeros(0, 0), vec![], vec![]).unwrap(),
    ));
    let sol = solver::solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Converged);
    assert_eq!(sol.error, 0.0);
    assert!(sol.r.is_empty() && sol.u.is_empty());
}

#[test]
fn a_global_problem_without_contacts_is_m_v_equals_f() {
    let m = CscMatrix::identity(3, 2.0);
    let f = vec![1.0, -4.0, 0.5];
    let p = round_trip(Problem::Global(
        GlobalProblem::new(3, m, CscMatrix::zeros(3, 0), f, vec![], vec![]).unwrap(),
    ));
    let sol = solver::solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Converged);
    assert!(sol.r.is_empty());
    let v = sol.v.expect("a global solution has v");
    for (vi, want) in v.iter().zip([0.5, -2.0, 0.25]) {
        assert!((vi - want).abs() <= 1e-12, "{v:?}");
    }
    assert!(sol.balance_residual.expect("a balance residual") <= 1e-8);
}
