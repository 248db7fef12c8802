//! Painlevé's example (2.11)–(2.13) in FCLIB convention (normal first): M = [m l²] = [1],
//! H = l [sin θ, cos θ] (normal, tangent), w = (0, u₀), f = −f_p = m g l h sin θ + m l² v₀
//! with m = l = h = 1, g = −1, v₀ = 0, so f = −sin θ.

use coulomb::solver::{solve, InnerKind, OuterKind, Settings, Status};
use coulomb::{CscMatrix, GlobalProblem, Problem};

fn painleve(theta: f64, u0: f64, mu: f64) -> Problem {
    let (s, c) = theta.sin_cos();
    let m = CscMatrix::from_dense(1, 1, &[1.0]);
    let h = CscMatrix::from_dense(1, 2, &[s, c]);
    Problem::Global(GlobalProblem::new(2, m, h, vec![-s], vec![0.0, u0], vec![mu]).unwrap())
}

fn all_settings() -> Vec<Settings> {
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

/// u₀ < 0: the contact is active and slides. u_N = sin θ · v = 0 gives v = 0, u_T = u₀ < 0,
/// so r_T = −μ r_N sign(u_T) = μ r_N, and the balance 0 = v = sin θ r_N + cos θ r_T − sin θ
/// gives r_N = sin θ / (sin θ + μ cos θ).
#[test]
fn painleve_sliding_matches_closed_form() {
    for &(theta, u0, mu) in &[(0.6, -1.0, 0.3), (1.2, -0.2, 0.9), (0.3, -2.0, 1.5)] {
        let (s, c) = f64::sin_cos(theta);
        let rn = s / (s + mu * c);
        let rt = mu * rn;
        for settings in all_settings() {
            let sol = solve(&painleve(theta, u0, mu), &settings).unwrap();
            assert_eq!(sol.status, Status::Converged, "{settings:?}: {sol:?}");
            assert!(sol.error <= 1e-8);
            let v = sol.v.as_ref().unwrap()[0];
            assert!(v.abs() < 1e-6, "v = {v}");
            assert!((sol.r[0] - rn).abs() < 1e-6, "r_N {} vs {rn}", sol.r[0]);
            assert!((sol.r[1] - rt).abs() < 1e-6, "r_T {} vs {rt}", sol.r[1]);
            assert!((sol.u[1] - u0).abs() < 1e-6);
            assert!(sol.balance_residual.unwrap() < 1e-12);
        }
    }
}

/// u₀ > 0 and tan θ < μ: (2.13) says there is no solution, so no solver may claim one.
#[test]
fn painleve_without_solution_is_not_converged() {
    for &(theta, u0, mu) in &[(0.3, 1.0, 0.8), (0.5, 0.1, 2.0)] {
        assert!(f64::tan(theta) < mu);
        for mut settings in all_settings() {
            settings.max_outer = 50;
            settings.max_inner = 500;
            let sol = solve(&painleve(theta, u0, mu), &settings).unwrap();
            assert_ne!(sol.status, Status::Converged, "{settings:?}");
            assert!(
                sol.status == Status::InnerInfeasible || sol.error > 1e-8,
                "{sol:?}"
            );
        }
    }
}

/// u₀ > 0 and tan θ > μ: a solution exists (2.13) and is found.
#[test]
fn painleve_with_solution_converges() {
    for settings in all_settings() {
        let sol = solve(&painleve(1.2, 0.5, 0.5), &settings).unwrap();
        assert_eq!(sol.status, Status::Converged, "{settings:?}: {sol:?}");
        assert!(sol.error <= 1e-8);
    }
}
