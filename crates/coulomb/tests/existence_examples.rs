//! Existence criteria on the paper's examples (§2.2, §5.2–§5.7, Fig. 3, Fig. 7), with every
//! certificate re-verified here from the problem data.

use coulomb::delassus::Delassus;
use coulomb::examples;
use coulomb::existence::{
    check, CertificateKind, CheckSettings, Conclusion, Criterion, ExistenceReport, Verdict,
};
use coulomb::law::{self, ContactStatus};
use coulomb::{GlobalProblem, Problem};

fn run(p: &GlobalProblem) -> ExistenceReport {
    check(&Problem::Global(p.clone()), &CheckSettings::default()).unwrap()
}

/// Margins x_N − μ‖x_T‖ of x = Hᵀ v + w at every contact (the (4.4) cone L*).
fn dual_cone_margins(p: &GlobalProblem, v: &[f64], with_w: bool) -> Vec<f64> {
    let mut x = p.h.mul_t_vec(v);
    if with_w {
        x.iter_mut().zip(&p.w).for_each(|(a, b)| *a += b);
    }
    x.chunks_exact(p.dim)
        .zip(&p.mu)
        .map(|(c, mu)| c[0] - mu * coulomb::cone::tangent_norm(c))
        .collect()
}

/// The error of docs/error.md for a global (v, r), with u = Hᵀ v + w and the Delassus q.
fn global_error(p: &GlobalProblem, v: &[f64], r: &[f64]) -> (f64, f64) {
    let q = Delassus::new(p).unwrap().local.q;
    let u = p.velocity(v);
    let e = law::error_measure(p.dim, &p.mu, r, &u, law::norm(&q));
    (e.error, p.balance_residual(v, r))
}

#[test]
fn painleve_4_4_matches_2_13_on_a_sweep() {
    let thetas = [0.15, 0.4, 0.7, 1.0, 1.3];
    let mus = [0.1, 0.5, 1.0, 2.5];
    let u0s = [-1.5, -0.2, 0.0, 0.3, 2.0];
    let mut cases = 0;
    for &theta in &thetas {
        for &mu in &mus {
            let tan: f64 = f64::tan(theta);
            if (tan - mu).abs() < 0.05 {
                continue;
            }
            for &u0 in &u0s {
                let p = examples::painleve(theta, mu, u0, -1.0).unwrap();
                let rep = run(&p);
                let expected = u0 <= 0.0 || tan > mu; // (2.13)
                let c = &rep.criteria.c4_4;
                let want = if expected {
                    Verdict::Holds
                } else {
                    Verdict::Fails
                };
                assert_eq!(c.verdict, want, "θ={theta} μ={mu} u0={u0}: {}", c.detail);
                // Re-verify the certificate independently.
                let cert = c.certificate.as_ref().unwrap();
                if expected {
                    assert_eq!(c.certificate_kind, Some(CertificateKind::Velocity));
                    let m = dual_cone_margins(&p, cert, true);
                    assert!(
                        m[0] >= -1e-7 * u0.abs().max(1.0),
                        "θ={theta} μ={mu} u0={u0}"
                    );
                    // With g = −1, (2.13) is necessary and sufficient: the conclusion is existence.
                    assert!(matches!(rep.conclusion, Conclusion::Exists { .. }));
                } else {
                    assert_eq!(c.certificate_kind, Some(CertificateKind::Impulse));
                    let hr = p.h.mul_vec(cert);
                    assert!(law::norm(&hr) <= 1e-6 * law::norm(cert));
                    assert!(coulomb::cone::contains(mu, cert, 1e-12));
                    let wr: f64 = cert.iter().zip(&p.w).map(|(a, b)| a * b).sum();
                    assert!(wr < 0.0);
                    // (4.5) still holds (v large makes u_N ≥ 0): the theory says nothing more.
                    assert_eq!(rep.criteria.c4_5.verdict, Verdict::Holds);
                    assert_eq!(rep.conclusion, Conclusion::Unknown);
                }
                // (4.6) agrees with (4.4) in d = 2 (Im Hᵀ + L* is polyhedral, hence closed).
                assert_eq!(rep.criteria.c4_6.verdict, c.verdict);
                // (5.1) ⇔ Ker H ∩ L = {0} ⇔ tan θ > μ (Ker H is spanned by (cos θ, −sin θ)).
                let want51 = if tan > mu {
                    Verdict::Holds
                } else {
                    Verdict::Fails
                };
                assert_eq!(rep.criteria.c5_1.verdict, want51, "θ={theta} μ={mu}");
                cases += 1;
            }
        }
    }
    assert!(cases >= 50, "only {cases} cases");
}

#[test]
fn painleve_frictionless_is_decided_by_4_4() {
    let p = examples::painleve(0.5, 0.0, 1.0, -1.0).unwrap();
    let rep = run(&p);
    assert!(rep.frictionless);
    assert_eq!(rep.criteria.c4_4.verdict, Verdict::Holds);
    assert!(matches!(
        rep.conclusion,
        Conclusion::Exists {
            by: Criterion::C4_4,
            ..
        }
    ));
}

#[test]
fn example_iii_4_4_fails_yet_take_off_solves() {
    // §5.3: g = +1, u0 = 1, θ < arctan μ.
    for (theta, mu) in [(0.3, 0.6), (0.5, 1.0), (0.2, 2.0)] {
        let p = examples::painleve(theta, mu, 1.0, 1.0).unwrap();
        let rep = run(&p);
        assert_eq!(rep.criteria.c4_4.verdict, Verdict::Fails);
        assert_eq!(rep.criteria.c4_1.verdict, Verdict::Fails);
        assert_eq!(rep.conclusion, Conclusion::Unknown);
        // Take-off: r = 0, v = M⁻¹ f = sin θ.
        let r = [0.0, 0.0];
        let v = [p.f[0] / 1.0];
        assert!((v[0] - f64::sin(theta)).abs() < 1e-15);
        let (err, bal) = global_error(&p, &v, &r);
        assert!(err <= 1e-12 && bal <= 1e-12, "err {err} balance {bal}");
        let u = p.velocity(&v);
        assert_eq!(law::status(mu, &u, &r, 1e-12), ContactStatus::TakeOff);
    }
}

#[test]
fn example_iv_two_solutions() {
    // §5.4: g = +1, u0 = 1, θ = π/4, μ = 2.
    let theta = std::f64::consts::FRAC_PI_4;
    let p = examples::painleve(theta, 2.0, 1.0, 1.0).unwrap();
    // Take-off: r = 0, v = sin θ.
    let (v1, r1) = ([theta.sin()], [0.0, 0.0]);
    // Sliding: u_N = sin θ v = 0 ⇒ v = 0; u_T = u0 = 1 ⇒ r_T = −μ r_N; balance
    // 0 = sin θ r_N + cos θ r_T + sin θ ⇒ r_N = 1, r_T = −2.
    let (v2, r2) = ([0.0], [1.0, -2.0]);
    for (v, r, want) in [
        (v1, r1, ContactStatus::TakeOff),
        (v2, r2, ContactStatus::Slide),
    ] {
        let (err, bal) = global_error(&p, &v, &r);
        assert!(err <= 1e-12 && bal <= 1e-12, "err {err} balance {bal}");
        assert_eq!(law::status(2.0, &p.velocity(&v), &r, 1e-12), want);
    }
    assert_ne!(v1, v2);
}

#[test]
fn crushed_ball_has_no_solution_with_a_verified_certificate() {
    for mu in [0.0, 0.3, 1.0, 5.0] {
        for u0 in [0.1, 1.0, 10.0] {
            let p = examples::crushed_ball(mu, u0).unwrap();
            let rep = run(&p);
            let c = &rep.criteria.c4_5;
            assert_eq!(c.verdict, Verdict::Fails, "{}", c.detail);
            assert_eq!(c.certificate_kind, Some(CertificateKind::Farkas));
            assert!(c.certificate_residual.unwrap() <= 1e-9);
            assert!(matches!(
                rep.conclusion,
                Conclusion::None {
                    by: Criterion::C4_5,
                    ..
                }
            ));
            // y ≥ 0, H_N y = 0, w_Nᵀ y < 0, checked here.
            let y = c.certificate.as_ref().unwrap();
            assert!(y.iter().all(|&x| x >= 0.0));
            let mut r = vec![0.0; 4];
            r[0] = y[0];
            r[2] = y[1];
            assert!(law::norm(&p.h.mul_vec(&r)) <= 1e-9);
            assert!(p.w[0] * y[0] + p.w[2] * y[1] < 0.0);
            // Every other criterion fails as well.
            assert_eq!(rep.criteria.c4_4.verdict, Verdict::Fails);
            assert_eq!(rep.criteria.c4_6.verdict, Verdict::Fails);
        }
    }
}

#[test]
fn rectangle_satisfies_5_1() {
    for mu in [0.0, 0.2, 1.0, 4.0] {
        for s in [[0.0, 0.0], [0.5, -2.0], [-1.0, 3.0]] {
            let p = examples::rectangle(mu, s).unwrap();
            let rep = run(&p);
            let c = &rep.criteria.c5_1;
            assert_eq!(c.verdict, Verdict::Holds, "μ={mu} s={s:?}: {}", c.detail);
            // Certificate: Hᵀ v ∈ int L*, checked here.
            let v = c.certificate.as_ref().unwrap();
            let m = dual_cone_margins(&p, v, false);
            assert!(m.iter().all(|&x| x > 0.0), "{m:?}");
            // Theorem 5.1: then (4.1), (4.4), (4.6) hold for this w too.
            for k in [Criterion::C4_1, Criterion::C4_4, Criterion::C4_6] {
                assert_eq!(rep.criteria.get(k).verdict, Verdict::Holds, "{k}");
            }
            assert!(matches!(rep.conclusion, Conclusion::Exists { .. }));
        }
    }
}

#[test]
fn moving_obstacle_satisfies_4_4() {
    for mu in [0.0, 0.3, 1.0] {
        for (vb, om) in [([0.0, 0.0], 0.0), ([0.4, -1.0], 0.0), ([-0.3, 0.2], 0.8)] {
            let p = examples::moving_obstacle(mu, vb, om).unwrap();
            let rep = run(&p);
            let c = &rep.criteria.c4_4;
            assert_eq!(c.verdict, Verdict::Holds, "μ={mu}: {}", c.detail);
            let v = c.certificate.as_ref().unwrap();
            let w_inf = p.w.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let scale = if w_inf > 0.0 { w_inf } else { 1.0 };
            let m = dual_cone_margins(&p, v, true);
            assert!(m.iter().all(|&x| x >= -1e-7 * scale), "{m:?}");
            assert!(matches!(rep.conclusion, Conclusion::Exists { .. }));
            // Two discs wedged between the walls: self-equilibrated impulses exist, so (5.1)
            // fails and the certificate is a nonzero r ∈ L ∩ Ker H.
            let c51 = &rep.criteria.c5_1;
            assert_eq!(c51.verdict, Verdict::Fails);
            let r = c51.certificate.as_ref().unwrap();
            assert!(law::norm(&p.h.mul_vec(r)) <= 1e-6 * law::norm(r));
            for (ri, mu) in r.chunks_exact(2).zip(&p.mu) {
                assert!(coulomb::cone::contains(*mu, ri, 1e-12));
            }
        }
    }
}

#[test]
fn report_serializes_with_paper_labels() {
    let p = examples::crushed_ball(0.3, 1.0).unwrap();
    let json = serde_json::to_value(run(&p)).unwrap();
    assert_eq!(json["criteria"]["4.5"]["verdict"], "fails");
    assert_eq!(json["conclusion"]["kind"], "none");
    assert_eq!(json["conclusion"]["by"], "4.5");
}
