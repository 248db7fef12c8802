//! Tests of the equality rows ([`super`]), several through the whole solver.

use super::*;
use crate::problem::Problem;
use crate::settings::Settings;
use crate::solution::Status;
use crate::test_problems::equality_ball as ball;

const TOL: f64 = 1e-8;

fn solve(p: &GlobalProblem) -> crate::Solution {
    let problem = Problem::Global(p.clone());
    let settings = Settings {
        tol: TOL,
        ..Settings::default()
    };
    crate::solve(&problem, &settings).unwrap()
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

pub fn ball_held_by_one_constraint_slides_at_the_imposed_velocity() {
    // By hand: v_z = 0 needs r_N = 2; v_x = 0.5 slides, so r_T = −μ r_N e_x = (−0.6, 0);
    // the x balance 2 · 0.5 = −0.6 + λ + 2 gives λ = −0.4; v = (0.5, 0, 0).
    let p = ball(1, None);
    let sol = solve(&p);
    assert_eq!(sol.status, Status::Converged, "{sol:?}");
    assert!(close(&sol.r, &[2.0, -0.6, 0.0], 1e-7), "r = {:?}", sol.r);
    assert!(close(sol.v.as_ref().unwrap(), &[0.5, 0.0, 0.0], 1e-7));
    assert!(close(sol.l.as_ref().unwrap(), &[-0.4], 1e-7));
    assert!(sol.error <= TOL && sol.balance_residual.unwrap() <= TOL);
    assert!(sol.equality_residual.unwrap() <= TOL);
    // the reduced problem: the x tangent has no stiffness left, q̃ = Hᵀ (0.5, 0, −1)
    let red = Reduction::new(&p).unwrap();
    assert_eq!(red.rank(), 1);
    assert!(close(
        &red.local.w.to_dense(),
        &[0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5],
        1e-15
    ));
    assert!(close(&red.local.q, &[-1.0, 0.5, 0.0], 1e-15));
}

pub fn identical_rows_solve_and_share_the_multiplier() {
    // two copies of the same constraint: S is singular (rank 1); the same r and v as
    // with one row, λ = −0.4 split equally (the minimum-norm multipliers)
    let sol = solve(&ball(2, None));
    assert_eq!(sol.status, Status::Converged, "{sol:?}");
    assert!(close(&sol.r, &[2.0, -0.6, 0.0], 1e-7));
    assert!(close(sol.v.as_ref().unwrap(), &[0.5, 0.0, 0.0], 1e-7));
    assert!(close(sol.l.as_ref().unwrap(), &[-0.2, -0.2], 1e-7));
    assert!(sol.equality_residual.unwrap() <= TOL);
}

pub fn inconsistent_rows_are_not_converged() {
    // v_x = 0.5 and v_x = 0.4: no v satisfies both
    let p = ball(2, Some(vec![-0.5, -0.4]));
    let sol = solve(&p);
    assert_eq!(sol.status, Status::EqualityResidual);
    assert!(!sol.converged());
    let eq = sol.equality_residual.unwrap();
    // the accepted row holds exactly (v_x = 0.5 or 0.4), the dependent one misses by 0.1;
    // ‖b‖ < 1, so the residual is 0.1
    assert!((eq - 0.1).abs() < 1e-12, "{eq}");
    // (fclib's tests: the stored evaluation of this solution agrees)
}

pub fn pendulum_against_a_frictionless_wall() {
    // A unit point mass on a rod from a pivot, the rod along d = (sin θ, −cos θ):
    // dᵀ v = 0 (G = d, b = 0). Free velocity f = (−1, −0.5) toward a wall with normal
    // e_x, μ = 0. The only motion left, along t = (cos θ, sin θ), is stopped by the wall:
    // v = 0, tᵀ (f + r_N e_x) = 0 gives r_N = 1 + 0.5 tan θ, and M v = H r + G λ + f gives
    // λ = −0.5 / cos θ.
    let theta = 0.5f64;
    let (s, c) = theta.sin_cos();
    let m = CscMatrix::identity(2, 1.0);
    let h = CscMatrix::identity(2, 1.0);
    let g = CscMatrix::from_dense(2, 1, &[s, -c]);
    let p = GlobalProblem::new(2, m, h, vec![-1.0, -0.5], vec![0.0; 2], vec![0.0])
        .unwrap()
        .with_equality(g, vec![0.0])
        .unwrap();
    let sol = solve(&p);
    assert_eq!(sol.status, Status::Converged, "{sol:?}");
    assert!(
        close(&sol.r, &[1.0 + 0.5 * theta.tan(), 0.0], 1e-7),
        "{:?}",
        sol.r
    );
    assert!(close(sol.v.as_ref().unwrap(), &[0.0, 0.0], 1e-7));
    assert!(close(sol.l.as_ref().unwrap(), &[-0.5 / c], 1e-7));
}

pub fn random_problems_meet_every_residual() {
    // bodies of 3 dofs with random SPD mass blocks, one floor contact each, random
    // constraint rows coupling them, b in the range of Gᵀ (b = −Gᵀ v₀)
    for seed in 0..20u64 {
        let mut next = crate::test_problems::uniform(seed, 7);
        let bodies = 2 + (seed as usize % 4);
        let n = 3 * bodies;
        let p = 1 + seed as usize % (n - 2).min(4);
        let mut mt = Vec::new();
        let (mut rows, mut cols) = (Vec::new(), Vec::new());
        for body in 0..bodies {
            let a: Vec<f64> = (0..9).map(|_| next()).collect();
            for i in 0..3 {
                for j in 0..3 {
                    let x: f64 = (0..3).map(|k| a[k * 3 + i] * a[k * 3 + j]).sum::<f64>()
                        + if i == j { 1.0 } else { 0.0 };
                    rows.push(3 * body + i);
                    cols.push(3 * body + j);
                    mt.push(x);
                }
            }
        }
        let m = CscMatrix::from_triplets(n, n, &rows, &cols, &mt).unwrap();
        // contact of body k: normal e_z, tangents e_x, e_y of its dofs
        let mut hd = vec![0.0; n * n];
        for body in 0..bodies {
            let (o, c) = (3 * body, 3 * body);
            hd[(o + 2) * n + c] = 1.0;
            hd[o * n + c + 1] = 1.0;
            hd[(o + 1) * n + c + 2] = 1.0;
        }
        let h = CscMatrix::from_dense(n, n, &hd);
        let gd: Vec<f64> = (0..n * p).map(|_| next()).collect();
        let g = CscMatrix::from_dense(n, p, &gd);
        let v0: Vec<f64> = (0..n).map(|_| 0.3 * next()).collect();
        let b: Vec<f64> = g.mul_t_vec(&v0).iter().map(|x| -x).collect();
        let f: Vec<f64> = (0..n).map(|_| next() - 0.5).collect();
        let mu: Vec<f64> = (0..bodies).map(|_| 0.2 + 0.5 * next().abs()).collect();
        let prob = GlobalProblem::new(3, m, h, f, vec![0.0; n], mu)
            .unwrap()
            .with_equality(g, b)
            .unwrap();
        let sol = solve(&prob);
        assert_eq!(sol.status, Status::Converged, "seed {seed}: {sol:?}");
        assert!(sol.error <= TOL, "seed {seed}");
        assert!(sol.balance_residual.unwrap() <= TOL, "seed {seed}");
        assert!(sol.equality_residual.unwrap() <= TOL, "seed {seed}");
        // the residuals recomputed here from the returned r, v, λ
        let v = sol.v.as_ref().unwrap();
        let l = sol.l.as_ref().unwrap();
        assert!(prob.equality_residual(v).unwrap() <= TOL);
        assert!(prob.balance_residual_with(v, &sol.r, Some(l)) <= TOL);
        assert_eq!(l.len(), p);
    }
}

pub fn equality_rows_without_contacts() {
    // no contact: v = M⁻¹ (f + G λ) with Gᵀ v + b = 0; M = I, f = 0, G = e₀ + e₁,
    // b = −1: v = λ (1, 1) and 2 λ = 1, so λ = 1/2 and v = (1/2, 1/2)
    let m = CscMatrix::identity(2, 1.0);
    let h = CscMatrix::zeros(2, 0);
    let g = CscMatrix::from_dense(2, 1, &[1.0, 1.0]);
    let p = GlobalProblem::new(3, m, h, vec![0.0, 0.0], vec![], vec![])
        .unwrap()
        .with_equality(g, vec![-1.0])
        .unwrap();
    let sol = solve(&p);
    assert_eq!(sol.status, Status::Converged, "{sol:?}");
    assert!(close(sol.v.as_ref().unwrap(), &[0.5, 0.5], 1e-12));
    assert!(close(sol.l.as_ref().unwrap(), &[0.5], 1e-12));
}

pub fn invalid_equality_data_is_refused() {
    let p = ball(1, None);
    let base = GlobalProblem {
        equality: None,
        ..p
    };
    let g = CscMatrix::from_dense(3, 1, &[1.0, 0.0, 0.0]);
    assert!(matches!(
        base.clone().with_equality(g.clone(), vec![0.0, 1.0]),
        Err(ProblemError::Shape { what: "G", .. })
    ));
    assert!(matches!(
        base.clone().with_equality(g.clone(), vec![f64::NAN]),
        Err(ProblemError::NonFinite { what: "b", .. })
    ));
    let bad = CscMatrix::from_dense(3, 1, &[1.0, f64::INFINITY, 0.0]);
    assert!(matches!(
        base.clone().with_equality(bad, vec![0.0]),
        Err(ProblemError::NonFinite { what: "G", .. })
    ));
    let wrong_rows = CscMatrix::from_dense(2, 1, &[1.0, 0.0]);
    assert!(matches!(
        base.with_equality(wrong_rows, vec![0.0]),
        Err(ProblemError::Shape { what: "G", .. })
    ));
}
