//! Issue #44 item 4 probe: does the order of a Gauss–Seidel sweep change the number of sweeps
//! on a deep sphere heap? Body-level nonsmooth Gauss–Seidel (the simulator's: exact contact
//! solve of (2.9) with the others frozen, over-relaxation ω from the second sweep) on the
//! global problem (M diagonal, H, f, w, μ) of an FCLIB file dumped by `coulomb simulate
//! --dump-fclib`, cold start, stopped when the error of docs/error.md (on the stored problem,
//! from v = M⁻¹(f + H r)) is ≤ TOL. Orders compared:
//! - `file`: contact order of the file (the simulator's);
//! - `up`: by level in the contact graph from the supports (contacts with one body: floor and
//!   walls), lowest first — a proxy for height that needs no positions;
//! - `down`: the same, highest first;
//! - `sym`: `file` forward then backward, alternately;
//! - `aa`: `file` order with Anderson acceleration of the sweep map r ↦ G(r) (depth
//!   AA_DEPTH, each mixed iterate projected on the cones, v recomputed from it; the mixed
//!   step is kept only when the fixed-point residual ‖G(r) − r‖ did not grow, else the
//!   history restarts from the plain sweep).
//!
//! `cargo run --release -p coulomb-lab --example sweep_order -- FILE.hdf5 [TOL] [MAX_SWEEPS] [OMEGA]`

use coulomb::cone;
use coulomb::inner::contact::{solve_contact, solve_contact_law, OneContact};
use coulomb::law::error_measure;
use coulomb::linalg::dense::least_squares;
use coulomb::problem::{GlobalProblem, Problem};
use coulomb_granular::nsgs::invert_spd;
use std::collections::VecDeque;
use std::time::Instant;

/// One contact's rows of H: (dof, column 0..3, value).
struct Rows {
    entries: Vec<(usize, usize, f64)>,
    bodies: Vec<usize>,
}

fn contact_rows(p: &GlobalProblem, dofs_per_body: usize) -> Vec<Rows> {
    let m = p.h.ncols / 3;
    (0..m)
        .map(|i| {
            let mut entries = Vec::new();
            for k in 0..3 {
                let j = 3 * i + k;
                for e in p.h.col_ptr[j]..p.h.col_ptr[j + 1] {
                    entries.push((p.h.row_idx[e], k, p.h.values[e]));
                }
            }
            let mut bodies: Vec<usize> = entries.iter().map(|e| e.0 / dofs_per_body).collect();
            bodies.sort_unstable();
            bodies.dedup();
            Rows { entries, bodies }
        })
        .collect()
}

/// Levels of the contact graph (contacts sharing a body are neighbours) by breadth-first
/// search from the contacts that touch one body only.
fn levels(rows: &[Rows], nbodies: usize) -> Vec<usize> {
    let mut by_body: Vec<Vec<usize>> = vec![Vec::new(); nbodies];
    for (i, r) in rows.iter().enumerate() {
        for &b in &r.bodies {
            by_body[b].push(i);
        }
    }
    let mut level = vec![usize::MAX; rows.len()];
    let mut queue = VecDeque::new();
    for (i, r) in rows.iter().enumerate() {
        if r.bodies.len() == 1 {
            level[i] = 0;
            queue.push_back(i);
        }
    }
    while let Some(i) = queue.pop_front() {
        for &b in &rows[i].bodies {
            for &j in &by_body[b] {
                if level[j] == usize::MAX {
                    level[j] = level[i] + 1;
                    queue.push_back(j);
                }
            }
        }
    }
    level
}

/// The data of the sweeps.
struct Ctx<'a> {
    p: &'a GlobalProblem,
    rows: &'a [Rows],
    w: &'a [[f64; 9]],
    winv: &'a [[f64; 9]],
    minv: &'a [f64],
    q: f64,
}

impl Ctx<'_> {
    /// v = M⁻¹ (f + H r)
    fn velocity(&self, r: &[f64]) -> Vec<f64> {
        let mut hr = self.p.f.clone();
        self.p.h.gemv_acc(1.0, r, &mut hr);
        hr.iter().zip(self.minv).map(|(x, m)| x * m).collect()
    }

    /// error of docs/error.md at r, v from r
    fn error(&self, r: &[f64]) -> f64 {
        let v = self.velocity(r);
        let mut u = self.p.w.clone();
        self.p.h.gemv_t_acc(1.0, &v, &mut u);
        error_measure(3, &self.p.mu, r, &u, self.q).error
    }

    /// one Gauss–Seidel sweep in `order`, over-relaxed by `om`
    fn sweep(&self, order: &[usize], om: f64, r: &mut [f64], v: &mut [f64]) {
        let p = self.p;
        for &i in order {
            let ri = [r[3 * i], r[3 * i + 1], r[3 * i + 2]];
            let mut u = [p.w[3 * i], p.w[3 * i + 1], p.w[3 * i + 2]];
            for &(d, k, hv) in &self.rows[i].entries {
                u[k] += hv * v[d];
            }
            let a = &self.w[i];
            let c: [f64; 3] = std::array::from_fn(|k| {
                u[k] - (a[3 * k] * ri[0] + a[3 * k + 1] * ri[1] + a[3 * k + 2] * ri[2])
            });
            let one = OneContact {
                a,
                ainv: &self.winv[i],
                d: 3,
                mu: p.mu[i],
                c,
            };
            let exact =
                solve_contact_law(&one, &ri, &u).unwrap_or_else(|| solve_contact(&one, &ri));
            let mut new: [f64; 3] = std::array::from_fn(|k| ri[k] + om * (exact[k] - ri[k]));
            if om != 1.0 {
                cone::project(p.mu[i], &mut new);
            }
            for &(d, k, hv) in &self.rows[i].entries {
                v[d] += self.minv[d] * hv * (new[k] - ri[k]);
            }
            r[3 * i..3 * i + 3].copy_from_slice(&new);
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: sweep_order FILE.hdf5 [TOL] [MAX_SWEEPS] [OMEGA]");
        std::process::exit(2);
    };
    let tol: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1e-4);
    let max_sweeps: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let omega: f64 = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(1.5);
    let file = match coulomb::fclib::read(std::path::Path::new(path)) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(2);
        }
    };
    let Problem::Global(p) = file.problem else {
        eprintln!("{path}: not a global problem");
        std::process::exit(2);
    };
    let n = p.m.nrows;
    let mut minv = vec![0.0; n];
    for (j, slot) in minv.iter_mut().enumerate() {
        for e in p.m.col_ptr[j]..p.m.col_ptr[j + 1] {
            if p.m.row_idx[e] != j && p.m.values[e] != 0.0 {
                eprintln!("M is not diagonal");
                std::process::exit(2);
            }
            if p.m.row_idx[e] == j {
                *slot = 1.0 / p.m.values[e];
            }
        }
    }
    let rows = contact_rows(&p, 6);
    let m = rows.len();
    let level = levels(&rows, n / 6);
    let deepest = level.iter().filter(|&&l| l != usize::MAX).max().copied();
    println!(
        "{path}: {} bodies, {m} contacts, graph levels 0..={deepest:?}, tol {tol}, ω {omega}",
        n / 6
    );
    // W_ii and its inverse
    let mut w = vec![[0.0; 9]; m];
    let mut winv = vec![[0.0; 9]; m];
    for (i, r) in rows.iter().enumerate() {
        for &(d1, k1, h1) in &r.entries {
            for &(d2, k2, h2) in &r.entries {
                if d1 == d2 {
                    w[i][3 * k1 + k2] += h1 * minv[d1] * h2;
                }
            }
        }
        winv[i] = invert_spd(&w[i]).unwrap_or([0.0; 9]);
    }
    let q = {
        let mf: Vec<f64> = p.f.iter().zip(&minv).map(|(f, m)| f * m).collect();
        let mut q = p.w.clone();
        p.h.gemv_t_acc(1.0, &mf, &mut q);
        q.iter().map(|x| x * x).sum::<f64>().sqrt()
    };
    let file_order: Vec<usize> = (0..m).collect();
    let mut up = file_order.clone();
    up.sort_by_key(|&i| (level[i], i));
    let down: Vec<usize> = up.iter().rev().copied().collect();
    let backward: Vec<usize> = file_order.iter().rev().copied().collect();
    let ctx = Ctx {
        p: &p,
        rows: &rows,
        w: &w,
        winv: &winv,
        minv: &minv,
        q,
    };
    for (name, orders) in [
        ("file", vec![&file_order]),
        ("up", vec![&up]),
        ("down", vec![&down]),
        ("sym", vec![&file_order, &backward]),
    ] {
        let t0 = Instant::now();
        let mut r = vec![0.0; 3 * m];
        let mut sweeps = 0;
        let mut err = f64::INFINITY;
        while sweeps < max_sweeps {
            let om = if sweeps == 0 { 1.0 } else { omega };
            let mut v = ctx.velocity(&r);
            ctx.sweep(orders[sweeps % orders.len()], om, &mut r, &mut v);
            sweeps += 1;
            err = ctx.error(&r);
            if err <= tol {
                break;
            }
        }
        println!(
            "{name:>5}: {sweeps:>6} sweeps, err {err:.2e}, {:.2} s",
            t0.elapsed().as_secs_f64()
        );
    }
    for depth in [3usize, 5, 10] {
        let t0 = Instant::now();
        let mut r = vec![0.0; 3 * m];
        let mut sweeps = 0;
        let mut err = f64::INFINITY;
        let mut hist_f: VecDeque<Vec<f64>> = VecDeque::new();
        let mut hist_g: VecDeque<Vec<f64>> = VecDeque::new();
        let (mut last_f, mut last_g): (Option<Vec<f64>>, Option<Vec<f64>>) = (None, None);
        let mut best_res = f64::INFINITY;
        let mut kept = 0;
        while sweeps < max_sweeps {
            let om = if sweeps == 0 { 1.0 } else { omega };
            let mut g = r.clone();
            let mut v = ctx.velocity(&g);
            ctx.sweep(&file_order, om, &mut g, &mut v);
            sweeps += 1;
            let f: Vec<f64> = g.iter().zip(&r).map(|(a, b)| a - b).collect();
            let res = f.iter().map(|x| x * x).sum::<f64>().sqrt();
            if res > 2.0 * best_res {
                hist_f.clear();
                hist_g.clear();
                last_f = None;
                last_g = None;
            }
            best_res = best_res.min(res);
            if let (Some(lf), Some(lg)) = (&last_f, &last_g) {
                hist_f.push_back(f.iter().zip(lf).map(|(a, b)| a - b).collect());
                hist_g.push_back(g.iter().zip(lg).map(|(a, b)| a - b).collect());
                if hist_f.len() > depth {
                    hist_f.pop_front();
                    hist_g.pop_front();
                }
            }
            last_f = Some(f.clone());
            last_g = Some(g.clone());
            let mut next = g.clone();
            let history: Vec<Vec<f64>> = hist_f.iter().cloned().collect();
            if let Some(gamma) = least_squares(&history, &f).filter(|g| !g.is_empty()) {
                for (k, dg) in hist_g.iter().enumerate() {
                    for (x, d) in next.iter_mut().zip(dg) {
                        *x -= gamma[k] * d;
                    }
                }
                for (i, mu) in p.mu.iter().enumerate() {
                    cone::project(*mu, &mut next[3 * i..3 * i + 3]);
                }
                kept += 1;
            }
            // the plain sweep's error, and the mixed iterate's; keep the better
            let e_g = ctx.error(&g);
            let e_next = ctx.error(&next);
            if e_next <= e_g {
                r = next;
                err = e_next;
            } else {
                r = g;
                err = e_g;
            }
            if err <= tol {
                break;
            }
        }
        println!(
            "aa({depth:>2}): {sweeps:>6} sweeps, err {err:.2e}, {:.2} s, {kept} mixed",
            t0.elapsed().as_secs_f64()
        );
    }
}
