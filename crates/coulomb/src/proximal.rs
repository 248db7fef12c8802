//! The proximal point on Coulomb's law (2.9)–(2.10), local form: r_{k+1} solves the law for
//! the regularized data (W + σ_k I, q − σ_k r_k), i.e. u = W r + q + σ_k (r − r_k), by a
//! semismooth Newton method on the Alart–Curnier map
//! Φ_ρ(r) = r − P_μ(r − ρ u) (P_μ: projection onto the cone K_μᵢ of each contact, (2.9)),
//! J = I − D + ρ D (W + σ I) with D = ∂P_μ, solved by a sparse LU of J (W as stored: J is
//! not symmetric anyway). σ_k = `sigma_factor` · err(r_k) · max Wᵢᵢ with err of
//! docs/error.md on the stored problem, so σ → 0 as the iterates converge (the rule of
//! Siconos' PROX solver). A zero of the regularized map at r_{k+1} = r_k is a solution of the
//! law itself. It is the end game after a stalled Levenberg–Marquardt run
//! ([`crate::levenberg`]) on problems where the law is far from monotone (granular heaps at
//! μ = 1, docs/rigid.md): the regularization moves the kinks where LM's merit ½‖Φ_ρ‖² has
//! stationary points that are not zeros.
//!
//! Every iterate is judged as its projection onto L = Π K_μᵢ, and the best one is returned.

use crate::deadline::Deadline;
use crate::newton::JacobianPattern;
use crate::problem::LocalProblem;
use crate::settings::ProxParams;

/// Why [`solve`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProxStatus {
    /// the error of docs/error.md is ≤ the target
    Reached,
    /// [`ProxParams::max_outer`] proximal steps were taken above the target
    MaxSteps,
    /// the deadline passed
    TimeLimit,
    /// [`ProxParams::stall_steps`] proximal steps in a row did not lower the lowest error
    Stalled,
    /// the sizes of the problem and r disagree, r is not finite, or the symbolic LU of the
    /// pattern of J failed: no step taken
    Inconsistent,
}

/// The outcome of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProxReport {
    /// how it stopped
    pub status: ProxStatus,
    /// proximal steps (regularized problems solved)
    pub outer: usize,
    /// Newton steps (sparse LU factorizations of J) of all proximal steps
    pub steps: usize,
    /// the error of docs/error.md at the returned r (W r + q recomputed)
    pub error: f64,
}

/// Runs the proximal point from `r` (projected onto the cones first) until the error of
/// docs/error.md on the problem as stored is ≤ `target`, a cap, a stall or the deadline;
/// `r` becomes the lowest-error iterate (in the cones).
pub fn solve(
    p: &LocalProblem,
    r: &mut [f64],
    target: f64,
    params: &ProxParams,
    deadline: Deadline,
) -> ProxReport {
    let (d, m) = (p.dim, r.len());
    let consistent = p.fits(r) && r.iter().all(|x| x.is_finite());
    let mut report = ProxReport {
        status: ProxStatus::Inconsistent,
        outer: 0,
        steps: 0,
        error: f64::NAN,
    };
    if !consistent {
        return report;
    }
    crate::cone::project_product(d, &p.mu, r);
    let mut best_err = p.error(r).error;
    report.error = best_err;
    if best_err <= target {
        report.status = ProxStatus::Reached;
        return report;
    }
    let Some(jac) = JacobianPattern::new(p) else {
        return report;
    };
    let rho = crate::levenberg::base_rho(p);
    let w_max = p.w.diagonal().iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let nb = p.mu.len() * d * d;
    let (mut g, mut dbl) = (vec![0.0; m], vec![0.0; nb]);
    let (mut g2, mut dbl2) = (vec![0.0; m], vec![0.0; nb]);
    let (mut shifted, mut blocks) = (vec![0.0; nb], vec![0.0; nb]);
    let (mut jv, mut wcol) = (Vec::new(), vec![0.0; m]);
    let mut x = r.to_vec();
    let mut error = best_err;
    let mut since_best = 0;
    report.status = loop {
        if best_err <= target {
            break ProxStatus::Reached;
        }
        if report.outer >= params.max_outer {
            break ProxStatus::MaxSteps;
        }
        if deadline.passed() {
            break ProxStatus::TimeLimit;
        }
        if since_best >= params.stall_steps {
            break ProxStatus::Stalled;
        }
        report.outer += 1;
        let sigma = params.sigma_factor * error * w_max;
        let center = x.clone();
        // Φ of the regularized problem at y: u = W y + q + σ (y − center)
        let eval = |y: &[f64], g: &mut [f64], dbl: &mut [f64]| {
            let mut u = p.velocity(y);
            for k in 0..m {
                u[k] += sigma * (y[k] - center[k]);
            }
            crate::levenberg::alart_curnier(d, &p.mu, &rho, y, &u, g, dbl)
        };
        let mut phi = eval(&x, &mut g, &mut dbl);
        for _ in 0..params.inner_steps {
            if deadline.passed() || phi.is_nan() || phi <= 0.0 {
                break;
            }
            report.steps += 1;
            // J = I − D + B (W + σ I), B = ρ D: the diagonal blocks of I − (D − σ B)
            for (i, &ri) in rho.iter().enumerate() {
                for k in i * d * d..(i + 1) * d * d {
                    blocks[k] = ri * dbl[k];
                    shifted[k] = dbl[k] - sigma * blocks[k];
                }
            }
            jac.fill(p, &shifted, &blocks, &mut wcol, &mut jv);
            let mut dir: Vec<f64> = g.iter().map(|v| -v).collect();
            if jac.solve(&jv, &mut dir).is_none() {
                break;
            }
            // Armijo on ‖Φ‖; when no step decreases it, the full step (a non-monotone
            // escape from a stationary point of the merit)
            let mut t = 1.0;
            let mut trial = vec![0.0; m];
            let mut moved = false;
            for _ in 0..params.line_search_steps {
                for k in 0..m {
                    trial[k] = x[k] + t * dir[k];
                }
                let phi2 = eval(&trial, &mut g2, &mut dbl2);
                if phi2 <= (1.0 - 1e-4 * t) * phi {
                    std::mem::swap(&mut x, &mut trial);
                    std::mem::swap(&mut g, &mut g2);
                    std::mem::swap(&mut dbl, &mut dbl2);
                    phi = phi2;
                    moved = true;
                    break;
                }
                t *= 0.5;
            }
            if !moved {
                for k in 0..m {
                    x[k] += dir[k];
                }
                phi = eval(&x, &mut g, &mut dbl);
            }
            if !x.iter().all(|v| v.is_finite()) {
                break;
            }
        }
        if !x.iter().all(|v| v.is_finite()) {
            x.copy_from_slice(r);
        }
        let y = crate::levenberg::projected(p, &x);
        error = p.error(&y).error;
        if error < best_err {
            best_err = error;
            r.copy_from_slice(&y);
            since_best = 0;
        } else {
            since_best += 1;
        }
        if !error.is_finite() {
            x.copy_from_slice(r);
            error = best_err;
        }
    };
    report.error = best_err;
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::levenberg::tests::problem;

    #[test]
    fn the_proximal_point_solves_a_rank_deficient_problem_and_reports_the_stored_error() {
        // rank-deficient W (more contact unknowns than rank), μ up to 1: from r = 0
        let mut solved = 0;
        for seed in 0..6 {
            let p = problem(12, seed, 0.0, 0.0);
            let mut r = vec![0.0; p.q.len()];
            let rep = solve(&p, &mut r, 1e-10, &ProxParams::default(), Deadline::NEVER);
            // the reported error is the one recomputed on the problem at the returned r,
            // which lies in the cones
            assert_eq!(rep.error, p.error(&r).error);
            for (c, mu) in r.chunks(3).zip(&p.mu) {
                let t = (c[1] * c[1] + c[2] * c[2]).sqrt();
                assert!(
                    t <= mu * c[0] * (1.0 + 1e-12) + 1e-300,
                    "{c:?} outside K_{mu}"
                );
            }
            if rep.status == ProxStatus::Reached {
                assert!(rep.error <= 1e-10);
                solved += 1;
            }
        }
        assert!(solved >= 4, "solved {solved} of 6");
    }

    #[test]
    fn bad_sizes_caps_and_deadlines_give_typed_statuses() {
        let p = problem(6, 1, 0.0, 0.0);
        let mut short = vec![0.0; 3];
        let rep = solve(
            &p,
            &mut short,
            1e-10,
            &ProxParams::default(),
            Deadline::NEVER,
        );
        assert_eq!(rep.status, ProxStatus::Inconsistent);
        let mut nan = vec![f64::NAN; p.q.len()];
        let rep = solve(&p, &mut nan, 1e-10, &ProxParams::default(), Deadline::NEVER);
        assert_eq!(rep.status, ProxStatus::Inconsistent);
        let mut r = vec![0.0; p.q.len()];
        let capped = ProxParams {
            max_outer: 0,
            ..ProxParams::default()
        };
        let rep = solve(&p, &mut r, 1e-30, &capped, Deadline::NEVER);
        assert_eq!(rep.status, ProxStatus::MaxSteps);
        assert_eq!(rep.outer, 0);
        let past = Deadline::after(std::time::Instant::now(), Some(std::time::Duration::ZERO));
        let rep = solve(&p, &mut r, 1e-30, &ProxParams::default(), past);
        assert_eq!(rep.status, ProxStatus::TimeLimit);
        assert!(rep.error.is_finite());
    }
}
