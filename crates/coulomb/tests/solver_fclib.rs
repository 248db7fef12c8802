//! Every problem of data/ (always) and of ../shared/fclib (when present) with the default
//! settings reaches error ≤ 1e-8, checked
//! independently: the solution is written as the file's /solution group, read back, and its
//! error recomputed by `fclib::evaluate` from r (and v) alone.

use crate::common;

use coulomb::fclib::{self, read, FclibFile, StoredSolution};
use coulomb::solver::{solve, Settings, Status};

#[test]
fn every_data_problem_converges_with_default_settings() {
    every_problem_converges(common::data_files(), "solver-data");
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_every_fclib_problem_converges_with_default_settings() {
    every_problem_converges(common::fclib_files(), "solver-fclib");
}

fn every_problem_converges(paths: Vec<std::path::PathBuf>, tag: &str) {
    let out_dir = common::tempdir(tag);
    for path in paths {
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        let file = read(&path).unwrap();
        let sol = solve(&file.problem, &Settings::default()).unwrap();
        println!(
            "{stem:45} {:?} err={:.2e} outer={} inner={} t={:?}",
            sol.status, sol.error, sol.outer_iterations, sol.inner_iterations, sol.solve_time
        );
        assert_eq!(sol.status, Status::Converged, "{stem}");
        // write /solution, read it back, evaluate it from scratch
        let written = out_dir.join(format!("{stem}.hdf5"));
        let mut with_solution = FclibFile::new(file.problem.clone());
        with_solution.solution = Some(StoredSolution {
            v: sol.v.clone(),
            u: Some(sol.u.clone()),
            r: sol.r.clone(),
            l: None,
        });
        fclib::write(&written, &with_solution).unwrap();
        let back = fclib::read(&written).unwrap();
        // the written problem is the one read, exactly (no symmetrization)
        assert_eq!(
            back.problem, file.problem,
            "{stem}: problem changed on writing"
        );
        let stored = back.solution.expect("the /solution group was written");
        let eval = fclib::evaluate(&back.problem, &stored).unwrap();
        assert!(
            eval.converged(1e-8),
            "{stem}: written solution has error {:.3e}, balance {:?}",
            eval.measure.error,
            eval.balance_residual
        );
        // and once more with the error of docs/error.md written out here, on the original
        // file's data, from the r (and v) read back
        let original = read(&path).unwrap().problem;
        let (err, balance) = independent_error(&original, &stored.r, stored.v.as_deref());
        assert!(
            err <= 1e-8 && balance <= 1e-8,
            "{stem}: recomputed error {err:.3e}, balance {balance:.3e}"
        );
    }
    let _ = std::fs::remove_dir_all(&out_dir);
}

/// y += A x for a CSC matrix (transposed: y += Aᵀ x).
fn csc_mul(a: &coulomb::CscMatrix, x: &[f64], y: &mut [f64], transposed: bool) {
    for j in 0..a.ncols {
        for p in a.col_ptr[j]..a.col_ptr[j + 1] {
            let i = a.row_idx[p];
            if transposed {
                y[j] += a.values[p] * x[i];
            } else {
                y[i] += a.values[p] * x[j];
            }
        }
    }
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// The error of docs/error.md (natural map, ρ = 1) and the balance residual, computed from
/// the problem data without the library's error code: u = W r + q (local) or u = Hᵀ v + w
/// (global, with q = Hᵀ M⁻¹ f + w for the scale).
fn independent_error(problem: &coulomb::Problem, r: &[f64], v: Option<&[f64]>) -> (f64, f64) {
    let (dim, mu, u, q, balance) = match problem {
        coulomb::Problem::Local(p) => {
            let mut u = p.q.clone();
            csc_mul(&p.w, r, &mut u, false);
            (p.dim, p.mu.clone(), u, p.q.clone(), 0.0)
        }
        coulomb::Problem::Global(g) => {
            let v = v.expect("global solution has v");
            let mut u = g.w.clone();
            csc_mul(&g.h, v, &mut u, true);
            let q = coulomb::delassus::Delassus::new(g).unwrap().local.q;
            let mut res = vec![0.0; g.f.len()];
            csc_mul(&g.m, v, &mut res, false);
            let mut hr = vec![0.0; g.f.len()];
            csc_mul(&g.h, r, &mut hr, false);
            for i in 0..res.len() {
                res[i] -= hr[i] + g.f[i];
            }
            (g.dim, g.mu.clone(), u, q, norm(&res) / norm(&g.f).max(1.0))
        }
    };
    let mut sum = 0.0;
    for (i, &m) in mu.iter().enumerate() {
        let (ri, ui) = (&r[i * dim..(i + 1) * dim], &u[i * dim..(i + 1) * dim]);
        let ut = norm(&ui[1..]);
        // x = r − ũ, ũ = (u_N + μ‖u_T‖, u_T)
        let mut x: Vec<f64> = ri.iter().zip(ui).map(|(a, b)| a - b).collect();
        x[0] -= m * ut;
        let (xn, xt) = (x[0], norm(&x[1..]));
        let p: Vec<f64> = if xt <= m * xn {
            x.clone()
        } else if m * xt <= -xn {
            vec![0.0; dim]
        } else {
            let a = (xn + m * xt) / (1.0 + m * m);
            let mut p = vec![a; dim];
            for k in 1..dim {
                p[k] = m * a * x[k] / xt;
            }
            p
        };
        sum += ri.iter().zip(&p).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
    }
    let scale = norm(&q).max(norm(r)).max(norm(&u));
    let abs = sum.sqrt();
    (
        if scale > f64::EPSILON {
            abs / scale
        } else {
            abs
        },
        balance,
    )
}
