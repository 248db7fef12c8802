//! Random strongly convex SOC-QPs (4.7) for the inner solvers, and random local and global
//! problems for the whole solver (frictionless problems against the KKT conditions of the QP
//! of §5.1, frictional ones against the error measure).

use coulomb::cone;
#[allow(unused_imports)]
use coulomb::inner::{
    apgd::ApgdSolver, pgs::PgsSolver, InnerLimits, InnerProblem, InnerSolver, InnerStatus,
};
use coulomb::solver::{solve, InnerKind, OuterKind, Settings, Solver, Status};
use coulomb::{CscMatrix, GlobalProblem, LocalProblem, Problem};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The inner solvers under test, set up for (d, W); adding one is one line.
fn inner_solvers(dim: usize, w: &CscMatrix) -> Vec<Box<dyn InnerSolver>> {
    vec![
        Box::new(PgsSolver::new(dim, w)),
        Box::new(ApgdSolver::new(dim, w)),
    ]
}

/// Dense symmetric positive definite G Gᵀ + shift·I, as a CSC matrix.
fn random_spd(rng: &mut ChaCha8Rng, m: usize, shift: f64) -> CscMatrix {
    let k = m.max(2) / 2 + 1;
    let g: Vec<f64> = (0..m * k).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mut w = vec![0.0; m * m];
    for i in 0..m {
        for j in 0..m {
            w[i * m + j] = (0..k).map(|p| g[i * k + p] * g[j * k + p]).sum::<f64>()
                + if i == j { shift } else { 0.0 };
        }
    }
    CscMatrix::from_dense(m, m, &w)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// KKT residual of (4.7): r ∈ L, y = W r + b ∈ L*, rᵢᵀyᵢ = 0, each measured in absolute terms.
fn kkt_4_7(dim: usize, w: &CscMatrix, b: &[f64], mu: &[f64], r: &[f64]) -> f64 {
    let mut y = b.to_vec();
    w.gemv_acc(1.0, r, &mut y);
    let mut worst = 0.0f64;
    for ((ri, yi), &m) in r.chunks(dim).zip(y.chunks(dim)).zip(mu) {
        let mut pr = ri.to_vec();
        cone::project(m, &mut pr);
        let mut py = yi.to_vec();
        cone::project_dual(m, &mut py);
        let dr = pr
            .iter()
            .zip(ri)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let dy = py
            .iter()
            .zip(yi)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        worst = worst.max(dr).max(dy).max(dot(ri, yi).abs());
    }
    worst
}

/// Inner limits for exact solves: tolerance 1e-11, no practical iteration cap, no deadline.
fn tight_limits() -> InnerLimits {
    InnerLimits {
        tol: 1e-11,
        max_iterations: 100_000,
        deadline: coulomb::deadline::Deadline::NEVER,
    }
}

#[test]
fn inner_solvers_solve_random_soc_qps() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for trial in 0..30 {
        let dim = if trial % 2 == 0 { 3 } else { 2 };
        let nc = rng.random_range(1..15);
        let m = dim * nc;
        let w = random_spd(&mut rng, m, 0.5);
        let b: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mu: Vec<f64> = (0..nc).map(|_| rng.random_range(0.1..1.0)).collect();
        let problem = InnerProblem {
            dim,
            w: &w,
            b: &b,
            mu: &mu,
        };
        let limits = tight_limits();
        for mut solver in inner_solvers(dim, &w) {
            let mut r = vec![0.0; m];
            let report = solver.solve(&problem, &limits, &mut r);
            assert_eq!(
                report.status,
                InnerStatus::Solved,
                "{} trial {trial}: {report:?}",
                solver.name()
            );
            let k = kkt_4_7(dim, &w, &b, &mu, &r);
            let scale = 1.0 + dot(&r, &r).sqrt() + dot(&b, &b).sqrt();
            assert!(
                k <= 1e-8 * scale,
                "{} trial {trial}: KKT {k}",
                solver.name()
            );
            // warm start from the solution: done at once
            let report = solver.solve(&problem, &limits, &mut r);
            assert!(report.iterations <= 1, "{}: {report:?}", solver.name());
        }
    }
}

/// A [`Solver`] given a new W by `update_w` (the same allocation pattern, values changed)
/// solves the new problem exactly as a fresh solve does: its inner solvers' data are rebuilt,
/// not those of the old W reused.
#[test]
fn a_solver_given_a_new_w_solves_the_new_problem() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (dim, nc) = (3, 6);
    let m = dim * nc;
    let w = random_spd(&mut rng, m, 0.5);
    let q: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mu = vec![0.5; nc];
    let mut w3 = w.clone();
    w3.values.iter_mut().for_each(|v| *v *= 3.0);
    let first = Problem::Local(LocalProblem::new(3, w, q.clone(), mu.clone()).unwrap());
    let second = Problem::Local(LocalProblem::new(3, w3.clone(), q, mu).unwrap());
    for settings in settings_under_test() {
        let mut solver = Solver::new(&first, settings.clone()).unwrap();
        let a = solver.solve(None).unwrap();
        solver.update_w(w3.clone()).unwrap();
        let b = solver.solve(None).unwrap();
        let fresh = solve(&second, &settings).unwrap();
        assert!(b.converged(), "{settings:?}: {:?}", b.status);
        assert_eq!((b.status, &b.r), (fresh.status, &fresh.r), "{settings:?}");
        assert!(a.r.iter().zip(&b.r).any(|(x, y)| (x - y).abs() > 1e-6));
    }
}

fn settings_under_test() -> Vec<Settings> {
    let mut out = Vec::new();
    for inner in [InnerKind::Pgs, InnerKind::Apgd] {
        for outer in [OuterKind::FixedPoint, OuterKind::Anderson] {
            out.push(Settings::method(inner, outer));
        }
    }
    out.push(Settings::method(InnerKind::Pgs, OuterKind::Fused));
    out.push(Settings::default());
    out
}

/// §5.1: with all μ = 0 the problem is the QP min ½ rᵀWr + qᵀr over r_N ≥ 0, r_T = 0; its
/// KKT conditions: r_T = 0, r_N ≥ 0, u_N ≥ 0, r_N u_N = 0 (u = W r + q).
#[test]
fn frictionless_problems_give_the_qp_solution() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for trial in 0..10 {
        let dim = 2 + trial % 2;
        let nc = rng.random_range(1..12);
        let m = dim * nc;
        let w = random_spd(&mut rng, m, 0.2);
        let q: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
        let local = LocalProblem::new(dim as i64, w, q, vec![0.0; nc]).unwrap();
        for settings in settings_under_test() {
            let sol = solve(&Problem::Local(local.clone()), &settings).unwrap();
            assert_eq!(sol.status, Status::Converged, "{settings:?}");
            assert_eq!(sol.outer_iterations, 1, "no fixed point when μ = 0");
            let u = local.velocity(&sol.r);
            for (ri, ui) in sol.r.chunks(dim).zip(u.chunks(dim)) {
                assert!(ri[1..].iter().all(|t| t.abs() < 1e-12));
                assert!(ri[0] >= 0.0 && ui[0] >= -1e-7, "{ri:?} {ui:?}");
                assert!((ri[0] * ui[0]).abs() < 1e-7);
            }
        }
    }
}

#[test]
fn random_local_and_global_problems_converge() {
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    for trial in 0..8 {
        let dim = 2 + trial % 2;
        let nc = rng.random_range(1..10);
        let m = dim * nc;
        let mu: Vec<f64> = (0..nc).map(|_| rng.random_range(0.1..0.6)).collect();
        // global: M SPD (n = m + 2 dofs), H random dense n × m
        let n = m + 2;
        let mm = random_spd(&mut rng, n, 1.0);
        let hd: Vec<f64> = (0..n * m).map(|_| rng.random_range(-1.0..1.0)).collect();
        let h = CscMatrix::from_dense(n, m, &hd);
        let f: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let wv: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
        let global = GlobalProblem::new(dim as i64, mm, h, f, wv, mu.clone()).unwrap();
        let local = coulomb::delassus::Delassus::new(&global).unwrap().local;
        for problem in [Problem::Global(global), Problem::Local(local)] {
            for settings in settings_under_test() {
                let sol = solve(&problem, &settings).unwrap();
                assert_eq!(
                    sol.status,
                    Status::Converged,
                    "{settings:?} {:?}",
                    sol.history
                );
                assert!(sol.error <= settings.tol);
                if let Some(b) = sol.balance_residual {
                    assert!(b <= 1e-12);
                }
            }
        }
    }
}

#[test]
fn zero_contacts_is_trivial() {
    let m = CscMatrix::from_dense(2, 2, &[2.0, 0.0, 0.0, 4.0]);
    let h = CscMatrix::zeros(2, 0);
    let g = GlobalProblem::new(3, m, h, vec![1.0, 2.0], vec![], vec![]).unwrap();
    let sol = solve(&Problem::Global(g), &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Converged);
    let v = sol.v.unwrap();
    assert!((v[0] - 0.5).abs() < 1e-15 && (v[1] - 0.5).abs() < 1e-15);
}

/// APGD on the assembled W and on the matrix-free operator x ↦ Hᵀ M⁻¹ H x agree.
#[test]
fn apgd_runs_matrix_free() {
    use coulomb::delassus::{Delassus, DelassusOperator};
    use coulomb::inner::apgd::{lipschitz_estimate, solve_operator, MatrixFree};
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let (dim, nc) = (3, 6);
    let m = dim * nc;
    let n = m + 4;
    let mm = random_spd(&mut rng, n, 1.0);
    let hd: Vec<f64> = (0..n * m).map(|_| rng.random_range(-1.0..1.0)).collect();
    let h = CscMatrix::from_dense(n, m, &hd);
    let f: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
    let wv: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mu = vec![0.4; nc];
    let g = GlobalProblem::new(dim as i64, mm, h, f, wv, mu.clone()).unwrap();
    let d = Delassus::new(&g).unwrap();
    let op = MatrixFree {
        op: DelassusOperator::new(&g.h, &d.factor),
        size: m,
    };
    let limits = InnerLimits {
        tol: 1e-12,
        max_iterations: 100_000,
        deadline: coulomb::deadline::Deadline::NEVER,
    };
    let b = d.local.q.clone();
    let (ap, ray) = (
        coulomb::settings::ApgdParams::default(),
        coulomb::settings::RayParams::default(),
    );
    let mut r_free = vec![0.0; m];
    let lip = lipschitz_estimate(&op, 20);
    let rep = solve_operator(
        &op,
        dim,
        &b,
        &mu,
        lip,
        false,
        &ap,
        &ray,
        &limits,
        &mut r_free,
    );
    assert_eq!(rep.status, InnerStatus::Solved);
    let mut r_csc = vec![0.0; m];
    let lip = lipschitz_estimate(&d.local.w, 20);
    let rep = solve_operator(
        &d.local.w, dim, &b, &mu, lip, true, &ap, &ray, &limits, &mut r_csc,
    );
    assert_eq!(rep.status, InnerStatus::Solved);
    assert!(kkt_4_7(dim, &d.local.w, &b, &mu, &r_free) < 1e-9);
    let diff: f64 = r_free
        .iter()
        .zip(&r_csc)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-7, "{diff}");
}
