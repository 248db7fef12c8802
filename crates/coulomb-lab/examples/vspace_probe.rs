//! Probe (experiment, issue #11 item 4): the proximal point on r solved in the velocity
//! space of a global problem (augmented Lagrangian on v).
//!
//! `cargo run --release -p coulomb-lab --example vspace_probe -- FILE.hdf5 [WARM_SECONDS] [LIMIT_SECONDS]`
//!
//! The probe that led to [`coulomb::multiplier`] (docs/rigid.md, "the method of multipliers
//! in the velocities"). Start: r = 0 (WARM_SECONDS = 0) or the default solver's point after
//! WARM_SECONDS. Env: RHO (ρ = RHO / mean(trace Wᵢᵢ / d), default 1; PERC: per contact),
//! AA (Anderson mixing of memory AA on λ), LAG (the De Saxcé term lagged during a step: a
//! convex subproblem with a symmetric J), INNER (Newton steps per outer step, 50),
//! INNER_TOL (‖G‖ ≤ INNER_TOL · err · max(1, ‖f‖), 1e-2), LOG (per Newton step).
//!
//! Outer step k (multiplier λ = r_k, ρ > 0): solve for v
//!   G(v) = M v − f − H P_K(λ − ρ ũ(Hᵀ v + w)) = 0
//! by a semismooth Newton method (J = M + ρ H ∂P Ã Hᵀ, Ã = ∂ũ/∂u = I + μ e t̂ᵀ, dense LU,
//! backtracking on ‖G‖), then r_{k+1} = P_K(λ − ρ ũ). A fixed point has r = P_K(r − ρ ũ),
//! i.e. Coulomb's law, and M v = H r + f. Equivalently r_{k+1} solves the law for
//! (W + I/ρ, q − r_k/ρ) (with ũ of the unregularized u), but in v (n unknowns) where v is
//! unique even when r is not.
#![allow(clippy::needless_range_loop)]

use coulomb::problem::{GlobalProblem, Problem};
use faer::linalg::solvers::Solve;
use std::time::{Duration, Instant};

fn envf(k: &str, d: f64) -> f64 {
    std::env::var(k)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(d)
}

struct Eval {
    g: Vec<f64>,
    r: Vec<f64>,
    norm: f64,
}

/// G(v) and r = P_K(λ − ρ ũ(u)); optionally the blocks B_i = ρ ∂P_i Ã_i (row-major 3×3).
fn eval(
    p: &GlobalProblem,
    lam: &[f64],
    rho: &[f64],
    v: &[f64],
    blocks: Option<&mut Vec<f64>>,
    lag: Option<&[f64]>,
) -> Eval {
    let d = p.dim;
    let u = p.velocity(v);
    let m = u.len();
    let mut r = vec![0.0; m];
    let mut want = blocks;
    if let Some(b) = want.as_deref_mut() {
        b.clear();
        b.resize(p.contacts() * d * d, 0.0);
    }
    let mut jac = [0.0; 9];
    let mut pr = [0.0; 3];
    for i in 0..p.contacts() {
        let mu = p.mu[i];
        let ui = &u[i * d..(i + 1) * d];
        let t_now = coulomb::cone::tangent_norm(ui);
        let t = lag.map(|s| s[i]).unwrap_or(t_now);
        let mut y = [0.0; 3];
        for k in 0..d {
            let ut = if k == 0 { ui[0] + mu * t } else { ui[k] };
            y[k] = lam[i * d + k] - rho[i] * ut;
        }
        coulomb::natural_map::projection_jacobian(mu, &y[..d], &mut pr[..d], &mut jac[..d * d]);
        r[i * d..(i + 1) * d].copy_from_slice(&pr[..d]);
        if let Some(b) = want.as_deref_mut() {
            // B = ρ ∂P Ã, Ã = I + μ e t̂ᵀ (t̂ = u_T/‖u_T‖, 0 at u_T = 0)
            let mut a = [0.0; 9];
            for k in 0..d {
                a[k * d + k] = 1.0;
            }
            if lag.is_none() && t > 0.0 && mu > 0.0 {
                for k in 1..d {
                    a[k] += mu * ui[k] / t;
                }
            }
            let bi = &mut b[i * d * d..(i + 1) * d * d];
            for x in 0..d {
                for z in 0..d {
                    let mut s = 0.0;
                    for k in 0..d {
                        s += jac[x * d + k] * a[k * d + z];
                    }
                    bi[x * d + z] = rho[i] * s;
                }
            }
        }
    }
    let mut g = p.m.mul_vec(v);
    for (gi, fi) in g.iter_mut().zip(&p.f) {
        *gi -= fi;
    }
    p.h.gemv_acc(-1.0, &r, &mut g);
    let norm = coulomb::law::norm(&g);
    Eval { g, r, norm }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = std::path::Path::new(&args[1]);
    let warm: f64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(0.0);
    let limit: f64 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(10.0);
    let log = std::env::var("LOG").is_ok();
    let file = coulomb::fclib::read(path).unwrap();
    let p = match file.problem {
        Problem::Global(g) => g,
        _ => panic!("a global file"),
    };
    let d = p.dim;
    let n = p.dofs();
    let m = p.w.len();
    let nc = p.contacts();
    let mass = coulomb::mass::MassFactor::new(&p.m).unwrap();
    // Delassus q and diag blocks of W = Hᵀ M⁻¹ H
    let mut minv_f = p.f.clone();
    mass.solve_in_place(&mut minv_f);
    let q = p.velocity(&minv_f);
    let q_norm = coulomb::law::norm(&q);
    let mut wdiag = vec![0.0; nc];
    for i in 0..nc {
        let mut tr = 0.0;
        for k in 0..d {
            let j = i * d + k;
            let mut col = vec![0.0; n];
            for e in p.h.col_ptr[j]..p.h.col_ptr[j + 1] {
                col[p.h.row_idx[e]] = p.h.values[e];
            }
            let hc = col.clone();
            mass.solve_in_place(&mut col);
            tr += hc.iter().zip(&col).map(|(a, b)| a * b).sum::<f64>();
        }
        wdiag[i] = tr / d as f64;
    }
    let rho_scale = envf("RHO", 1.0);
    let per_contact = std::env::var("PERC").is_ok();
    let wmean = wdiag.iter().sum::<f64>() / nc as f64;
    let rho: Vec<f64> = wdiag
        .iter()
        .map(|&x| {
            rho_scale
                / if per_contact {
                    x.max(1e-12 * wmean)
                } else {
                    wmean
                }
        })
        .collect();

    let t0 = Instant::now();
    let (mut r, mut v) = if warm > 0.0 {
        let s = coulomb::Settings {
            time_limit: Some(Duration::from_secs_f64(warm)),
            ..Default::default()
        };
        let sol = coulomb::solve(&Problem::Global(p.clone()), &s).unwrap();
        (sol.r.clone(), sol.v.clone().unwrap())
    } else {
        (vec![0.0; m], minv_f.clone())
    };
    let (_, e0) = coulomb::evaluation::global(&p, &v, &r, q_norm);
    println!(
        "start: err {:.3e} bal {:.3e} t {:.2}s",
        e0.measure.error,
        e0.balance_residual.unwrap(),
        t0.elapsed().as_secs_f64()
    );
    let t1 = Instant::now();
    let deadline = t1 + Duration::from_secs_f64(limit);
    let max_inner = envf("INNER", 50.0) as usize;
    let inner_factor = envf("INNER_TOL", 1e-2);
    let f_norm = coulomb::law::norm(&p.f).max(1.0);
    let mut blocks = Vec::new();
    let mut best = e0.measure.error.max(e0.balance_residual.unwrap());
    let mut total_newton = 0;
    let aa = envf("AA", 0.0) as usize;
    let mut mix = coulomb::outer::anderson::Anderson::new(aa.max(1));
    let mut lam = r.clone();
    let lagged = std::env::var("LAG").is_ok();
    for k in 0..100_000 {
        if Instant::now() > deadline {
            break;
        }
        let lam_k = lam.clone();
        let lag: Option<Vec<f64>> = if lagged {
            let u = p.velocity(&v);
            Some(
                (0..nc)
                    .map(|i| coulomb::cone::tangent_norm(&u[i * d..(i + 1) * d]))
                    .collect(),
            )
        } else {
            None
        };
        let mut ev = eval(&p, &lam_k, &rho, &v, None, lag.as_deref());
        let (_, ecur) = coulomb::evaluation::global(&p, &v, &r, q_norm);
        let target = (inner_factor * ecur.measure.error * f_norm).max(1e-14 * f_norm);
        let mut steps = 0;
        while ev.norm > target && steps < max_inner && Instant::now() < deadline {
            steps += 1;
            ev = eval(&p, &lam_k, &rho, &v, Some(&mut blocks), lag.as_deref());
            // J = M + H B Hᵀ, dense
            let mut a = faer::Mat::<f64>::zeros(n, n);
            for j in 0..n {
                for e in p.m.col_ptr[j]..p.m.col_ptr[j + 1] {
                    a[(p.m.row_idx[e], j)] += p.m.values[e];
                }
            }
            for i in 0..nc {
                let b = &blocks[i * d * d..(i + 1) * d * d];
                for x in 0..d {
                    let cx = i * d + x;
                    for z in 0..d {
                        let bxz = b[x * d + z];
                        if bxz == 0.0 {
                            continue;
                        }
                        let cz = i * d + z;
                        for e1 in p.h.col_ptr[cx]..p.h.col_ptr[cx + 1] {
                            let row = p.h.row_idx[e1];
                            let hv = p.h.values[e1] * bxz;
                            for e2 in p.h.col_ptr[cz]..p.h.col_ptr[cz + 1] {
                                a[(row, p.h.row_idx[e2])] += hv * p.h.values[e2];
                            }
                        }
                    }
                }
            }
            let mut rhs = faer::Mat::<f64>::zeros(n, 1);
            for j in 0..n {
                rhs[(j, 0)] = -ev.g[j];
            }
            let dv = a.partial_piv_lu().solve(&rhs);
            let mut tstep = 1.0;
            let mut accepted = false;
            for _ in 0..30 {
                let vt: Vec<f64> = (0..n).map(|j| v[j] + tstep * dv[(j, 0)]).collect();
                let et = eval(&p, &lam_k, &rho, &vt, None, lag.as_deref());
                if et.norm.is_finite()
                    && et.norm * et.norm <= (1.0 - 1e-4 * tstep) * ev.norm * ev.norm
                {
                    v = vt;
                    ev = et;
                    accepted = true;
                    break;
                }
                tstep *= 0.5;
            }
            if !accepted {
                if log {
                    println!("   inner: no descent at ‖G‖ {:.3e}", ev.norm);
                }
                break;
            }
            if log {
                println!("   inner {steps}: ‖G‖ {:.3e} t {tstep}", ev.norm);
            }
        }
        total_newton += steps;
        r = ev.r.clone();
        lam = if aa > 0 {
            let mu = p.mu.clone();
            mix.next_projected(&lam_k, &r, |x| coulomb::cone::project_product(d, &mu, x))
        } else {
            r.clone()
        };
        let (_, e) = coulomb::evaluation::global(&p, &v, &r, q_norm);
        let err = e.measure.error.max(e.balance_residual.unwrap());
        best = best.min(err);
        println!(
            "{k:4} err {:.3e} bal {:.3e} newton {steps} (total {total_newton}) t {:.2}s",
            e.measure.error,
            e.balance_residual.unwrap(),
            t1.elapsed().as_secs_f64()
        );
        if e.measure.error <= 1e-8 && e.balance_residual.unwrap() <= 1e-8 {
            println!("CONVERGED in {:.2}s", t1.elapsed().as_secs_f64());
            break;
        }
    }
    println!("best {best:.3e}");
}
