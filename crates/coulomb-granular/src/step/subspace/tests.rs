//! Tests of [`super`] driven through the Gauss–Seidel solve of [`crate::nsgs`] (a
//! child module: the correction itself does not depend on the solve that calls it).

use crate::nsgs::{evaluate, solve, NsgsSettings, NsgsStatus, StepProblem};
use crate::step::fixtures::stack;

/// Sweeps of plain Gauss–Seidel and of Gauss–Seidel with subspace minimization every
/// 5 sweeps, cold, to `tol`; both verdicts checked on the stored problem.
fn compare(p: &StepProblem, tol: f64) -> (usize, usize, usize) {
    let r0 = vec![0.0; 3 * p.contacts()];
    let plain = NsgsSettings {
        tol,
        time_limit: None,
        ..NsgsSettings::default()
    };
    let sm = NsgsSettings {
        subspace_every: 5,
        ..plain
    };
    let a = solve(p, &r0, &plain, false);
    let b = solve(p, &r0, &sm, false);
    for s in [&a, &b] {
        assert_eq!(s.status, NsgsStatus::Converged, "{s:?}");
        let (err, _, balance, _) = evaluate(p, &s.r);
        assert!(err <= tol && balance <= tol, "err {err} balance {balance}");
    }
    eprintln!(
        "{} contacts: plain {} sweeps, subspace {} sweeps ({} corrections kept)",
        p.contacts(),
        a.sweeps,
        b.sweeps,
        b.subspace
    );
    (a.sweeps, b.sweeps, b.subspace)
}

pub fn a_column_of_spheres_converges_in_far_fewer_sweeps() {
    let p = stack(1, 1, 16);
    assert_eq!(p.contacts(), 16);
    let (plain, sm, kept) = compare(&p, 1e-8);
    assert!(kept >= 1, "no correction kept");
    assert!(3 * sm <= plain, "plain {plain} sweeps, subspace {sm}");
}

pub fn a_six_layer_stack_converges_in_far_fewer_sweeps() {
    let p = stack(4, 4, 6);
    assert!(p.contacts() > 100, "{}", p.contacts());
    let (plain, sm, kept) = compare(&p, 1e-6);
    assert!(kept >= 1, "no correction kept");
    assert!(3 * sm <= plain, "plain {plain} sweeps, subspace {sm}");
}

pub fn same_bits_on_one_and_two_threads() {
    let p = stack(4, 4, 6);
    let s = NsgsSettings {
        tol: 1e-6,
        subspace_every: 5,
        ..NsgsSettings::default()
    };
    let r0 = vec![0.0; 3 * p.contacts()];
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| solve(&p, &r0, &s, true));
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| solve(&p, &r0, &s, true));
    assert_eq!(one.r, two.r);
    assert_eq!(one.sweeps, two.sweeps);
}
