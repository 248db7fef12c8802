//! Existence criteria in d = 3 (second-order cones, no longer polyhedral) and on local
//! problems (W, q) in place of (H, w).

use coulomb::delassus::Delassus;
use coulomb::existence::{check, CheckSettings, Conclusion, Criterion, Verdict};
use coulomb::{CscMatrix, GlobalProblem, Problem};

/// Painlevé's rod embedded in d = 3: H = [sin θ, cos θ, 0], w = (0, u0, 0).
fn painleve_3d(theta: f64, mu: f64, u0: f64) -> GlobalProblem {
    let m = CscMatrix::from_dense(1, 1, &[1.0]);
    let h = CscMatrix::from_dense(1, 3, &[theta.sin(), theta.cos(), 0.0]);
    GlobalProblem::new(3, m, h, vec![-theta.sin()], vec![0.0, u0, 0.0], vec![mu]).unwrap()
}

#[test]
fn painleve_in_3d_global_and_local_agree_with_2_13() {
    let mut cases = 0;
    for theta in [0.2f64, 0.6, 1.1] {
        for mu in [0.1, 0.8, 3.0] {
            if (theta.tan() - mu).abs() < 0.05 {
                continue;
            }
            for u0 in [-1.0, 0.0, 0.7] {
                let g = painleve_3d(theta, mu, u0);
                let expected = if u0 <= 0.0 || theta.tan() > mu {
                    Verdict::Holds
                } else {
                    Verdict::Fails
                };
                let global = check(&Problem::Global(g.clone()), &CheckSettings::default()).unwrap();
                assert_eq!(
                    global.criteria.c4_4.verdict, expected,
                    "θ={theta} μ={mu} u0={u0}"
                );
                // Local form: W = Hᵀ M⁻¹ H, q = Hᵀ M⁻¹ f + w; Ker W = Ker H and Im W = Im Hᵀ,
                // but q ≠ w: the criteria on (W, q) are about the same kinematics only if q − w
                // ∈ Im W, which holds here (q − w = Hᵀ M⁻¹ f).
                let local = Delassus::new(&g).unwrap().local;
                let rep = check(&Problem::Local(local), &CheckSettings::default()).unwrap();
                assert_eq!(
                    rep.criteria.c4_4.verdict, expected,
                    "local θ={theta} μ={mu} u0={u0}"
                );
                assert_eq!(rep.criteria.c5_1.verdict, global.criteria.c5_1.verdict);
                cases += 1;
            }
        }
    }
    assert!(cases >= 20);
}

#[test]
fn non_closed_case_is_not_claimed_as_4_4() {
    // One contact, μ = 1, Im Hᵀ = span (1, 1, 0) runs along the boundary of L* = K_1, and
    // w = (0, 0, 1): w ∈ cl(Im Hᵀ + L*) \ (Im Hᵀ + L*) (the margin s − √(s² + 1) → 0 only as
    // v = s → ∞). Ker H ∩ L = {(1, −1, 0)·t}, wᵀr = 0: (4.6) holds, (4.1) fails.
    let m = CscMatrix::from_dense(1, 1, &[1.0]);
    let h = CscMatrix::from_dense(1, 3, &[1.0, 1.0, 0.0]);
    let g = GlobalProblem::new(3, m, h, vec![0.0], vec![0.0, 0.0, 1.0], vec![1.0]).unwrap();
    let rep = check(&Problem::Global(g), &CheckSettings::default()).unwrap();
    let c = &rep.criteria;
    println!("{}", serde_json::to_string_pretty(&rep).unwrap());
    assert_ne!(c.c4_4.verdict, Verdict::Fails, "{}", c.c4_4.detail);
    assert_ne!(c.c4_4.verdict, Verdict::Holds, "{}", c.c4_4.detail);
    assert_ne!(c.c4_1.verdict, Verdict::Holds, "{}", c.c4_1.detail);
    assert_eq!(c.c5_1.verdict, Verdict::Fails, "{}", c.c5_1.detail);
    assert_ne!(c.c4_6.verdict, Verdict::Fails, "{}", c.c4_6.detail);
    assert_eq!(c.c4_5.verdict, Verdict::Holds);
    if c.c4_6.verdict == Verdict::Holds {
        assert!(matches!(
            rep.conclusion,
            Conclusion::Exists {
                by: Criterion::C4_6,
                ..
            }
        ));
    } else {
        assert_eq!(rep.conclusion, Conclusion::Unknown);
    }
}
