//! The criteria (4.1), (4.4), (4.5), (4.6) and (5.1), each decided by a margin problem
//! ([`super::margin`]) from verified certificates.

use super::margin::*;
use super::*;

/// (4.5): margin problem on the half-spaces {x_N ≥ 0}, all contacts shifted.
pub(super) fn criterion_4_5(data: &KinematicData, settings: &CheckSettings) -> CriterionReport {
    let n = data.contacts();
    let mp = MarginProblem {
        data,
        blocks: vec![Block::HalfSpace; n],
        mask: vec![true; n],
        homogeneous: false,
    };
    let ver = solve_and_verify(&mp, settings);
    let margin = ver.vel.as_ref().map(|(_, c)| c.masked.min(c.unmasked));
    if let (Some((v, _)), Some(m)) = (&ver.vel, margin) {
        if m >= -settings.tol {
            return CriterionReport {
                verdict: Verdict::Holds,
                certificate_residual: Some((-m).max(0.0)),
                certificate_kind: Some(CertificateKind::Velocity),
                certificate: Some(v.clone()),
                margin: Some(m),
                dual_bound: None,
                detail: format!(
                    "v found with (Hᵀv + w)_N ≥ {m:.3e}·‖w‖∞ at every contact: non-penetration is kinematically possible"
                ),
            };
        }
    }
    if let Some(imp) = &ver.imp {
        if imp.bound < -settings.tol && imp.residual <= settings.certificate_tol {
            let y: Vec<f64> = imp.r.chunks_exact(data.dim).map(|c| c[0]).collect();
            return CriterionReport {
                verdict: Verdict::Fails,
                certificate_residual: Some(imp.residual),
                certificate_kind: Some(CertificateKind::Farkas),
                certificate: Some(y),
                margin,
                dual_bound: Some(imp.bound),
                detail: format!(
                    "Farkas certificate y ≥ 0, Σy = 1, H_N y ≈ 0 (relative residual {:.2e}), w_Nᵀy = {:.3e}·‖w‖∞ (upper bound with the kernel-residual slack: {:.3e}) < 0: \
                     penetration cannot be prevented, no solution exists",
                    imp.residual, imp.value, imp.bound
                ),
            };
        }
    }
    undecided(
        format!(
            "no certificate verified (Clarabel: {}; best margin {}, dual bound {})",
            ver.solve.clarabel_status,
            fmt_opt(margin),
            fmt_opt(ver.imp.as_ref().map(|i| i.bound))
        ),
        margin,
        ver.imp.as_ref().map(|i| i.bound),
    )
}

/// (4.4) and (4.6) from one margin problem on L* with every contact shifted: t* ≥ 0 ⇔ (4.6);
/// an attained t* ≥ 0 ⇔ (4.4).
pub(super) fn criteria_4_4_and_4_6(
    data: &KinematicData,
    settings: &CheckSettings,
) -> (CriterionReport, CriterionReport) {
    let n = data.contacts();
    let blocks: Vec<Block> = (0..n).map(|i| data.dual_block(i)).collect();
    let polyhedral = data.dim == 2 || blocks.iter().all(|b| !matches!(b, Block::Soc(_)));
    let mp = MarginProblem {
        data,
        blocks,
        mask: vec![true; n],
        homogeneous: false,
    };
    let ver = solve_and_verify(&mp, settings);
    let margin = ver.vel.as_ref().map(|(_, c)| c.masked.min(c.unmasked));
    let dual_bound = ver.imp.as_ref().map(|i| i.bound);
    if let (Some((v, c)), Some(m)) = (&ver.vel, margin) {
        if m >= -settings.tol {
            let v_rel = crate::law::norm(v) * data.b_scale / data.w_scale;
            let r46 = CriterionReport {
                verdict: Verdict::Holds,
                certificate_residual: Some((-m).max(0.0)),
                certificate_kind: Some(CertificateKind::Velocity),
                certificate: Some(v.clone()),
                margin: Some(m),
                dual_bound,
                detail: format!(
                    "v found with worst margin x_N − μ‖x_T‖ = {m:.3e}·‖w‖∞ of Hᵀv + w: w ∈ cl(Im Hᵀ + L*) \
                     within tolerance, i.e. wᵀr ≥ 0 on L ∩ Ker H"
                ),
            };
            let unattained = m < 0.0 && !polyhedral && v_rel > UNATTAINED_V_NORM;
            let r44 = if unattained {
                undecided(
                    format!(
                        "margin sup ≈ 0 ({m:.3e}) reached only with ‖v‖ ≈ {v_rel:.1e}·‖w‖∞/max|H|: \
                         w lies on the boundary of Im Hᵀ + L*, which may not be closed (d = 3)"
                    ),
                    Some(m),
                    dual_bound,
                )
            } else {
                CriterionReport {
                    detail: format!(
                        "v found with Hᵀv + w ∈ L* (worst margin x_N − μ‖x_T‖ = {m:.3e}·‖w‖∞, max ‖xⁱ‖ = {:.3e}·‖w‖∞)",
                        c.size
                    ),
                    ..r46.clone()
                }
            };
            return (r44, r46);
        }
    }
    if let Some(imp) = &ver.imp {
        if imp.bound < -settings.tol && imp.residual <= settings.certificate_tol {
            let rep = CriterionReport {
                verdict: Verdict::Fails,
                certificate_residual: Some(imp.residual),
                certificate_kind: Some(CertificateKind::Impulse),
                certificate: Some(imp.r.clone()),
                margin,
                dual_bound: Some(imp.bound),
                detail: format!(
                    "r ∈ L with Σ r_N = 1, ‖H r‖ relative residual {:.2e}, wᵀr = {:.3e}·‖w‖∞ (upper bound with the kernel-residual slack: {:.3e}) < 0: \
                     w ∉ cl(Im Hᵀ + L*)",
                    imp.residual, imp.value, imp.bound
                ),
            };
            return (rep.clone(), rep);
        }
    }
    let detail = format!(
        "no certificate verified (Clarabel: {}; best margin {}, dual bound {})",
        ver.solve.clarabel_status,
        fmt_opt(margin),
        fmt_opt(dual_bound)
    );
    (
        undecided(detail.clone(), margin, dual_bound),
        undecided(detail, margin, dual_bound),
    )
}

/// (4.1): margin problem on L* with the contacts 0 < μ < ∞ shifted (interiors) and the
/// frictionless half-spaces kept closed.
pub(super) fn criterion_4_1(data: &KinematicData, settings: &CheckSettings) -> CriterionReport {
    let n = data.contacts();
    if let Some(i) = data.mu.iter().position(|m| m.is_infinite()) {
        return CriterionReport {
            verdict: Verdict::Fails,
            certificate_residual: None,
            certificate_kind: None,
            certificate: None,
            margin: None,
            dual_bound: None,
            detail: format!(
                "contact {i} has μ = ∞: its dual cone K_0 has empty interior, so 𝓛* = ∅"
            ),
        };
    }
    let blocks: Vec<Block> = (0..n).map(|i| data.dual_block(i)).collect();
    let mask: Vec<bool> = blocks.iter().map(|b| matches!(b, Block::Soc(_))).collect();
    let mp = MarginProblem {
        data,
        blocks,
        mask,
        homogeneous: false,
    };
    let ver = solve_and_verify(&mp, settings);
    let margin = ver.vel.as_ref().map(|(_, c)| c.masked);
    let dual_bound = ver.imp.as_ref().map(|i| i.bound);
    if let Some((v, c)) = &ver.vel {
        if c.masked > settings.tol && c.unmasked >= -settings.tol {
            let shown = if c.masked.is_finite() {
                format!("{:.3e}·‖w‖∞", c.masked)
            } else {
                "∞ (no contact with μ > 0)".to_string()
            };
            return CriterionReport {
                verdict: Verdict::Holds,
                certificate_residual: Some(if c.unmasked < 0.0 { -c.unmasked } else { 0.0 }),
                certificate_kind: Some(CertificateKind::Velocity),
                certificate: Some(v.clone()),
                margin: c.masked.is_finite().then_some(c.masked),
                dual_bound,
                detail: format!(
                    "v found with Hᵀv + w ∈ 𝓛*: margin x_N − μ‖x_T‖ ≥ {shown} at contacts with μ > 0, \
                     frictionless contacts x_N ≥ {:.3e}·‖w‖∞",
                    if c.unmasked.is_finite() { c.unmasked } else { 0.0 }
                ),
            };
        }
    }
    if let Some(imp) = &ver.imp {
        let bound_ok = if imp.on_mask {
            imp.bound <= settings.tol
        } else {
            imp.bound < -settings.tol
        };
        if bound_ok && imp.residual <= settings.certificate_tol {
            return CriterionReport {
                verdict: Verdict::Fails,
                certificate_residual: Some(imp.residual),
                certificate_kind: Some(CertificateKind::Impulse),
                certificate: Some(imp.r.clone()),
                margin,
                dual_bound: Some(imp.bound),
                detail: if imp.on_mask {
                    format!(
                        "r ∈ L ∩ Ker H (relative residual {:.2e}) with Σ_{{μ>0}} r_N = 1 bounds every margin by wᵀr = {:.3e}·‖w‖∞ (upper bound with the kernel-residual slack: {:.3e}) ≤ tol",
                        imp.residual, imp.value, imp.bound
                    )
                } else {
                    format!(
                        "r ∈ L ∩ Ker H (relative residual {:.2e}) with wᵀr = {:.3e}·‖w‖∞ (upper bound with the kernel-residual slack: {:.3e}) < 0: even the closed cone constraint is infeasible",
                        imp.residual, imp.value, imp.bound
                    )
                },
            };
        }
    }
    undecided(
        format!(
            "no certificate verified (Clarabel: {}; best margin {}, dual bound {})",
            ver.solve.clarabel_status,
            fmt_opt(margin),
            fmt_opt(dual_bound)
        ),
        margin,
        dual_bound,
    )
}

/// (5.1): margin problem on L* with w = 0 and every contact shifted: t* = 1 ⇔ ∃ v with
/// Hᵀv ∈ int L* ⇔ Ker H ∩ L = {0}; t* = 0 ⇔ a nonzero r ∈ L ∩ Ker H.
pub(super) fn criterion_5_1(data: &KinematicData, settings: &CheckSettings) -> CriterionReport {
    let n = data.contacts();
    let blocks: Vec<Block> = (0..n).map(|i| data.dual_block(i)).collect();
    let mp = MarginProblem {
        data,
        blocks,
        mask: vec![true; n],
        homogeneous: true,
    };
    let ver = solve_and_verify(&mp, settings);
    // Homogeneous: the margin is relative to the size of Hᵀ v.
    let margin = ver.vel.as_ref().map(|(_, c)| {
        if c.size > 0.0 {
            c.masked.min(c.unmasked) / c.size
        } else {
            0.0
        }
    });
    if let (Some((v, _)), Some(m)) = (&ver.vel, margin) {
        if m > settings.tol {
            return CriterionReport {
                verdict: Verdict::Holds,
                certificate_residual: Some(0.0),
                certificate_kind: Some(CertificateKind::Velocity),
                certificate: Some(v.clone()),
                margin: Some(m),
                dual_bound: None,
                detail: format!(
                    "v found with Hᵀv ∈ int L* (relative margin {m:.3e}): Ker H ∩ L = {{0}}, so every w satisfies (4.1), (4.4), (4.6)"
                ),
            };
        }
    }
    if let Some(imp) = &ver.imp {
        if imp.on_mask && imp.residual <= settings.certificate_tol {
            return CriterionReport {
                verdict: Verdict::Fails,
                certificate_residual: Some(imp.residual),
                certificate_kind: Some(CertificateKind::Impulse),
                certificate: Some(imp.r.clone()),
                margin,
                dual_bound: None,
                detail: format!(
                    "nonzero r ∈ L ∩ Ker H: Σ r_N = 1, ‖H r‖ relative residual {:.2e} (self-equilibrated contact impulses)",
                    imp.residual
                ),
            };
        }
    }
    undecided(
        format!(
            "no certificate verified (Clarabel: {}; relative margin {})",
            ver.solve.clarabel_status,
            fmt_opt(margin)
        ),
        margin,
        None,
    )
}

pub(super) fn trivially_holds(detail: &str) -> CriterionReport {
    CriterionReport {
        verdict: Verdict::Holds,
        certificate_residual: Some(0.0),
        certificate_kind: None,
        certificate: None,
        margin: None,
        dual_bound: None,
        detail: detail.to_string(),
    }
}

pub(super) fn run_all_with(
    data: &KinematicData,
    kind: &'static str,
    settings: &CheckSettings,
    progress: &mut dyn FnMut(Criterion),
) -> Result<ExistenceReport, CheckError> {
    validate_settings(settings)?;
    let start = Instant::now();
    let frictionless = data.mu.iter().all(|&m| m == 0.0);
    let criteria = if data.contacts() == 0 {
        let h = trivially_holds("no contacts");
        Criteria {
            c4_1: h.clone(),
            c4_4: h.clone(),
            c4_5: h.clone(),
            c4_6: h.clone(),
            c5_1: h,
        }
    } else {
        progress(Criterion::C4_5);
        let c4_5 = criterion_4_5(data, settings);
        progress(Criterion::C4_4);
        let (c4_4, c4_6) = criteria_4_4_and_4_6(data, settings);
        progress(Criterion::C4_1);
        let c4_1 = criterion_4_1(data, settings);
        progress(Criterion::C5_1);
        let c5_1 = criterion_5_1(data, settings);
        Criteria {
            c4_1,
            c4_4,
            c4_5,
            c4_6,
            c5_1,
        }
    };
    let conclusion = conclude(&criteria, frictionless);
    Ok(ExistenceReport {
        kind,
        dim: data.dim,
        contacts: data.contacts(),
        frictionless,
        criteria,
        conclusion,
        note: None,
        seconds: start.elapsed().as_secs_f64(),
    })
}
