//! Issue #12: no false "converged" from an overflowing error measure, and no panic on any
//! `Settings` a caller can build (time limits beyond what `Instant` can hold).

use crate::common;

use coulomb::law::{self, error_measure};
use coulomb::solver::{self, Settings, Status};
use coulomb::{CscMatrix, GlobalProblem, LocalProblem, Problem};
use std::time::Duration;

const TOL: f64 = 1e-8;

/// err of docs/error.md for one contact computed by hand in units of `s` (entries / s are
/// moderate): the independent check the tests compare against.
fn err_by_hand(mu: f64, r: [f64; 3], u: [f64; 3], q: [f64; 3], s: f64) -> f64 {
    let r = r.map(|x| x / s);
    let u = u.map(|x| x / s);
    let q = q.map(|x| x / s);
    let ut = (u[1] * u[1] + u[2] * u[2]).sqrt();
    let x = [r[0] - u[0] - mu * ut, r[1] - u[1], r[2] - u[2]];
    let t = (x[1] * x[1] + x[2] * x[2]).sqrt();
    let p = if t <= mu * x[0] {
        x
    } else if mu * t <= -x[0] {
        [0.0; 3]
    } else {
        let a = (x[0] + mu * t) / (1.0 + mu * mu);
        [a, mu * a * x[1] / t, mu * a * x[2] / t]
    };
    let n = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let e = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
    n(e) / n(q).max(n(r)).max(n(u))
}

fn local(w: CscMatrix, q: Vec<f64>) -> Problem {
    Problem::Local(LocalProblem::new(3, w, q, vec![0.5]).unwrap())
}

/// A claim "converged" must survive the independent recomputation on the stored data.
fn assert_no_false_converged(p: &Problem, settings: &Settings) {
    let sol = solver::solve(p, settings).unwrap();
    if sol.status == Status::Converged {
        assert!(sol.error.is_finite() && sol.error <= TOL, "{sol:?}");
        let Problem::Local(l) = p else {
            // global: the balance residual and the error recomputed by the library from v
            assert!(sol.balance_residual.is_some_and(|b| b <= TOL), "{sol:?}");
            assert!(sol.u.iter().chain(&sol.r).all(|x| x.is_finite()), "{sol:?}");
            return;
        };
        let u = l.velocity(&sol.r);
        assert!(u.iter().chain(&sol.r).all(|x| x.is_finite()), "{sol:?}");
        let s = u
            .iter()
            .chain(&sol.r)
            .chain(&l.q)
            .fold(1.0f64, |m, x| m.max(x.abs()));
        let e = err_by_hand(
            0.5,
            [sol.r[0], sol.r[1], sol.r[2]],
            [u[0], u[1], u[2]],
            [l.q[0], l.q[1], l.q[2]],
            s,
        );
        assert!(
            e <= 10.0 * TOL,
            "converged with independent err {e:e}: {sol:?}"
        );
    }
}

#[test]
fn reliability_norm_does_not_overflow_or_underflow() {
    assert!((law::norm(&[3e200, 4e200]) / 5e200 - 1.0).abs() < 1e-15);
    assert!((law::norm(&[1e300, 1e300]) / (2f64.sqrt() * 1e300) - 1.0).abs() < 1e-15);
    assert!((law::norm(&[3e-200, 4e-200]) / 5e-200 - 1.0).abs() < 1e-15);
    assert_eq!(law::norm(&[f64::MAX, f64::MAX]), f64::INFINITY);
    assert!(law::norm(&[1.0, f64::NAN]).is_nan());
    assert_eq!(law::norm(&[]), 0.0);
}

#[test]
fn reliability_error_of_huge_data_is_not_zero() {
    // W = I, q = 1e155·(−1, 1, 3), r = 0: u_N = −1e155 < 0, a violation of (2.9); the scale
    // max(‖q‖, ‖r‖, ‖u‖) used to overflow to ∞ and the error to be 0
    for k in [1e155f64, 1e200, 1e300, 5e307] {
        let q = [-k, k, 3.0 * k];
        let e = error_measure(3, &[0.5], &[0.0; 3], &q, law::norm(&q));
        let by_hand = err_by_hand(0.5, [0.0; 3], q, q, k);
        assert!(e.error.is_finite() && e.error > 0.1, "{k:e}: {e:?}");
        assert!(
            (e.error / by_hand - 1.0).abs() < 1e-12,
            "{k:e}: {e:?} vs {by_hand}"
        );
        assert!(!e.converged(TOL));
    }
    // ‖q‖ beyond the largest f64 (entries of 1e308): error +∞, not converged
    let q = [-1e308, 1e308, 1e308];
    let e = error_measure(3, &[0.5], &[0.0; 3], &q, law::norm(&q));
    assert!(!e.converged(TOL), "{e:?}");
    // a non-finite input is never converged
    for bad in [f64::INFINITY, f64::NAN] {
        let e = error_measure(3, &[0.5], &[0.0; 3], &[bad, 0.0, 0.0], 1.0);
        assert!(!e.converged(TOL) && !e.converged(f64::INFINITY), "{e:?}");
        let e = error_measure(3, &[0.5], &[0.0; 3], &[1.0, 0.0, 0.0], bad);
        assert!(!e.converged(TOL), "{e:?}");
    }
    // an exact solution at a huge scale keeps error 0
    let e = error_measure(3, &[0.5], &[0.0; 3], &[1e300, 0.0, 0.0], 1e300);
    assert_eq!(e.error, 0.0);
    assert!(e.converged(TOL));
    // the ordinary scale is unchanged
    let e = error_measure(3, &[0.5], &[1.0, 0.0, 0.0], &[-1.0, 0.0, 0.0], 2.0);
    assert!(
        (e.error - err_by_hand(0.5, [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [2.0, 0.0, 0.0], 1.0)).abs()
            < 1e-15
    );
}

#[test]
fn reliability_solve_never_falsely_converges_at_extreme_scales() {
    let settings = Settings {
        time_limit: Some(Duration::from_secs(5)),
        ..Settings::default()
    };
    // q = 1e155·(−1, 1, 3) with W = I (issue: "Converged, error 0, outer iterations 0")
    let p = local(CscMatrix::identity(3, 1.0), vec![-1e155, 1e155, 3e155]);
    let sol = solver::solve(&p, &settings).unwrap();
    assert!(
        sol.status != Status::Converged || sol.r.iter().any(|x| *x != 0.0),
        "r = 0 is not a solution: {sol:?}"
    );
    assert_no_false_converged(&p, &settings);
    // q = 1e308·(−1, 1, 1)
    let p = local(CscMatrix::identity(3, 1.0), vec![-1e308, 1e308, 1e308]);
    assert_no_false_converged(&p, &settings);
    // W = 1e308·I
    let p = local(CscMatrix::identity(3, 1e308), vec![-1.0, 1.0, 3.0]);
    assert_no_false_converged(&p, &settings);
    // a global problem with M = 1e-300·I: v = M⁻¹(H r + f) overflows
    let g = GlobalProblem::new_unfactored(
        3,
        CscMatrix::identity(3, 1e-300),
        CscMatrix::identity(3, 1.0),
        vec![-1.0, 1.0, 3.0],
        vec![-1.0, 1.0, 3.0],
        vec![0.5],
    )
    .unwrap();
    let p = Problem::Global(g);
    if let Ok(sol) = solver::solve(&p, &settings) {
        if sol.status == Status::Converged {
            assert!(sol.error.is_finite() && sol.error <= TOL, "{sol:?}");
            assert!(
                sol.v.as_ref().unwrap().iter().all(|x| x.is_finite()),
                "{sol:?}"
            );
        }
    }
    let e = coulomb::fclib::evaluate(
        &p,
        &coulomb::fclib::StoredSolution {
            r: vec![0.0; 3],
            v: Some(vec![-1e300, 1e300, 3e300]),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(!e.converged(TOL), "{e:?}");
}

#[test]
fn reliability_time_limits_beyond_instant_do_not_panic() {
    let p = local(CscMatrix::identity(3, 1.0), vec![-1.0, 0.2, 0.1]);
    let huge = [
        Duration::from_secs_f64(1e19),
        Duration::try_from_secs_f64(1e30).unwrap_or(Duration::MAX),
        Duration::MAX,
        Duration::from_secs(u64::MAX),
    ];
    for t in huge {
        for settings in [
            Settings::default(),
            Settings::method(solver::InnerKind::Apgd, solver::OuterKind::Anderson),
            Settings::method(solver::InnerKind::Ipm, solver::OuterKind::FixedPoint),
        ] {
            let s = Settings {
                time_limit: Some(t),
                ..settings
            };
            let sol = solver::solve(&p, &s).unwrap();
            assert_eq!(sol.status, Status::Converged, "{t:?}: {sol:?}");
        }
    }
    // a zero limit is a limit, not a panic
    let mut s = Settings {
        time_limit: Some(Duration::ZERO),
        ..Settings::default()
    };
    s.params.warmup_sweeps = 0;
    let sol = solver::solve(&p, &s).unwrap();
    assert!(
        matches!(sol.status, Status::Converged | Status::TimeLimit),
        "{sol:?}"
    );
}

#[test]
fn reliability_existence_check_with_huge_time_limit_does_not_panic() {
    let p = local(CscMatrix::identity(3, 1.0), vec![-1.0, 0.2, 0.1]);
    for t in [
        Duration::from_secs(u64::MAX / 2),
        Duration::from_secs(u64::MAX),
        Duration::MAX,
    ] {
        let s = coulomb::existence::CheckSettings {
            time_limit: t,
            ..Default::default()
        };
        let r = coulomb::existence::check(&p, &s);
        assert!(r.is_ok(), "{t:?}: {r:?}");
    }
    let zero = coulomb::existence::CheckSettings {
        time_limit: Duration::ZERO,
        ..Default::default()
    };
    assert!(coulomb::existence::check(&p, &zero).is_err());
}

/// μ = 0, x_T = 0, x_N < 0: the projection onto K_0 = {x_T = 0, x_N ≥ 0} is 0, not x (the
/// test t ≤ μ x_N read 0 ≤ −0). Before the fix r = (−1, 0), u = 0 had error 0: a negative
/// normal impulse "converged". Found while analysing the long fuzz run (docs/fuzz.md).
#[test]
fn reliability_frictionless_projection_of_negative_normal_is_zero() {
    for mu in [0.0, -0.0] {
        let mut x = [-1.0, 0.0];
        coulomb::cone::project(mu, &mut x);
        assert_eq!(x, [0.0, 0.0], "μ = {mu}");
        let mut x = [-1.0, 0.0, 0.0];
        coulomb::cone::project(mu, &mut x);
        assert_eq!(x, [0.0, 0.0, 0.0], "μ = {mu}");
        let e = error_measure(2, &[mu], &[-1.0, 0.0], &[0.0, 0.0], 1.0);
        assert!(e.error > 0.1 && !e.converged(TOL), "μ = {mu}: {e:?}");
    }
    // the cone itself is unchanged
    let mut x = [2.0, 0.0];
    coulomb::cone::project(0.0, &mut x);
    assert_eq!(x, [2.0, 0.0]);
}

/// ‖M v − H r − f‖ / max(1, ‖f‖) with ‖f‖ beyond the largest f64: the ratio used to be
/// finite / ∞ = 0, a false "balanced" (found by the long fuzz run, seed 5004999).
#[test]
fn reliability_balance_residual_of_huge_f_is_not_zero() {
    let g = GlobalProblem::new_unfactored(
        3,
        CscMatrix::identity(3, 1.0),
        CscMatrix::identity(3, 1.0),
        vec![1.5e308, 1.5e308, 1.5e308],
        vec![0.0; 3],
        vec![0.5],
    )
    .unwrap();
    // v = 0, r = 0: residual −f, relative residual 1
    let b = g.balance_residual(&[0.0; 3], &[0.0; 3]);
    assert!((b - 1.0).abs() < 1e-12, "{b}");
    assert!((law::relative_norm(&[3.0, 4.0], &[0.5]) - 5.0).abs() < 1e-15);
    assert!((law::relative_norm(&[3e300, 4e300], &[1e300]) - 5.0).abs() < 1e-12);
    assert!(law::relative_norm(&[f64::NAN], &[1.0]).is_nan());
}

/// A tolerance above 0.05 made the inner tolerance's clamp(tol/5, 1e-2) panic (min > max);
/// found by the command-line fuzz run (`solve F --tol 0.3`).
#[test]
fn reliability_large_tolerances_do_not_panic() {
    for path in common::data_files() {
        large_tolerances_on(&coulomb::fclib::read(&path).unwrap().problem);
    }
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_reliability_large_tolerances_do_not_panic_on_fclib() {
    let dir = common::fclib_dir();
    for name in ["Box_Stacks-i0122-82-5.hdf5", "Capsules-i125-1213.hdf5"] {
        large_tolerances_on(&coulomb::fclib::read(&dir.join(name)).unwrap().problem);
    }
}

fn large_tolerances_on(problem: &Problem) {
    // a tolerance of 1 or more accepts any answer of the relative error: refused (issue 55)
    for tol in [1.0, 1e3, 1e300] {
        let s = Settings {
            tol,
            ..Settings::default()
        };
        assert!(
            matches!(
                solver::solve(problem, &s),
                Err(solver::SolveError::Settings(_))
            ),
            "{tol}"
        );
    }
    for tol in [0.06, 0.3, 0.99] {
        for base in [
            Settings::default(),
            Settings::method(solver::InnerKind::Apgd, solver::OuterKind::FixedPoint),
            Settings::method(solver::InnerKind::Apgd, solver::OuterKind::Anderson),
        ] {
            let s = Settings {
                tol,
                max_outer: 3,
                // one inner iteration: the first outer iterate is far off, so the inner
                // tolerance of the second one is computed
                max_inner: 1,
                time_limit: Some(Duration::from_secs(5)),
                ..base
            };
            let sol = solver::solve(problem, &s).unwrap();
            assert!(
                sol.status != Status::Converged || sol.error <= tol,
                "{tol}: {sol:?}"
            );
        }
    }
}
