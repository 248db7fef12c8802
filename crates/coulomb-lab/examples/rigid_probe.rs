//! Probe (experiment, issue #11 item 4; results in docs/rigid.md): end games for rigid,
//! rank-deficient problems, started from the default solver's iterate.
//!
//! `cargo run --release -p coulomb-lab --example rigid_probe -- FILE METHOD [WARM_SECONDS] [LIMIT_SECONDS]`
//! (or `-- search`)
//!
//! The start point is `coulomb::solve` with the default settings (tol `WARM_TOL`, default
//! 1e-8) stopped after WARM_SECONDS; then METHOD runs for at most LIMIT_SECONDS:
//! - `lm`: Levenberg–Marquardt on the Alart–Curnier map Φ_ρ(r) = r − P(r − ρ u), u = W r + q,
//!   P(y) = (max(0, y_N), proj onto the disc of radius μ max(0, y_N) of y_T), ρ_i = 1/‖W_ii‖_F;
//!   direction (JᵀJ + λI) d = −JᵀΦ, J = I − D + ρ D W, damping by the trust-region ratio;
//! - `lmsw`: `lm` in segments of 8 steps; a segment that does not lower err by 30 % switches
//!   every ρ_i to another multiple (1, 0.1, 10, 0.3, 3, 0.03, 30): the pieces of Φ_ρ move
//!   while r stays, so a stationary point of ‖Φ_ρ‖² with Φ_ρ ≠ 0 is left;
//! - `nsnsw`: like `lmsw` with the regularized semismooth Newton step (J + λI) d = −Φ (LU);
//! - `nsn`: semismooth Newton (LU of J), Armijo, full step when the search fails (Siconos'
//!   NSN-AC globalization);
//! - `ppa` / `ppalm`: proximal point: r_{k+1} solves the law for (W + σI, q − σ r_k) by `nsn`
//!   (`ppa`) or `lm` (`ppalm`), σ = SIG · err^NU · max diag W (Siconos: σ = 5 err);
//! - `lib`: the library's end game [`coulomb::levenberg::solve`] (LM + watchdog + ρ switching;
//!   env LIB_WATCH, LIB_PER, LIB_SEG override its watchdog steps, watchdogs per switch and
//!   segment length);
//! - `cmp`: from r = 0, the Newton end game's `polish` against `levenberg::solve` and the
//!   probe's plain `lm` (no start solve);
//! - `search` (no FILE): random rank-deficient problems (W = AᵀA, A with m/2 rows) on which
//!   `polish` from r = 0 stalls and `levenberg::solve` reaches 1e-8 (the test problem of
//!   `levenberg`'s tests was found this way);
//! - `nsf`: Newton's method on the paper's fixed point s = F(s) (§6: "a sophisticated
//!   alternative is Newton's method, possibly coupled with a stabilizing device based on
//!   minimizing ‖F(s) − s‖²"): F(s) from an interior-point solve of (4.7) with b = q + E s
//!   (u(s) is unique even where r is not), its Jacobian from the linearized natural map of
//!   (4.7), r − P_L(r − ρũ), solved in the least-squares sense (J + εI), a backtracking search
//!   on ‖F(s) − s‖; ε adapted (÷10 after a full step, ×10 when no step lowers ‖F(s) − s‖;
//!   env NSF_EPS first ε, default 1e-4; NSF_FIXED: fixed ε, stop at the first failed search);
//!   NSF_DELTA: the interior point solves (4.7) with W + δ max(W_ii) I (bounded r(s) where
//!   L ∩ Ker W ≠ {0}: without it Clarabel may return r(s) 10⁶–10⁷ times the start's norm,
//!   whose small err is spurious; the end line prints ‖r‖ / ‖r_start‖); NSF_FD: a
//!   finite-difference check of the Newton direction at every step;
//! - `barrier`: the interior-point method on the law ([`coulomb::barrier::solve`]) from its
//!   cold start (WARM_SECONDS ignored; a global file uses its Schur path unless NO_SCHUR is
//!   set; a local one its skeleton when it has one, SKELETON_MAX=0 turns it off, RANK_TOL,
//!   REFINE, REFINE_TOL, STRIKES override its rank tolerance, refinement steps, tolerance and
//!   strikes), then LM from its best point;
//!   env BARRIER_STEPS, BARRIER_STALL, BARRIER_SETTLE, BARRIER_SETTLE_BELOW,
//!   BARRIER_SETTLE_ALPHA, BARRIER_SMOOTH,
//!   BARRIER_RECENTRE, BARRIER_MARGIN, BARRIER_TOL override its parameters; LMPROBE: the
//!   probe's own `lm` (100 steps, logged) from the barrier's point as well;
//! - `admm`: ADMM on the SOC-QP of (4.7) with s = μ‖u_T‖ updated at every iteration (the
//!   de Saxcé term lagged), one dense LU of W + ρI per ρ (W as stored), over-relaxation RELAX
//!   (default 1.6), ρ = RHO0 · mean Wᵢᵢ (default 1), adapted ×/÷ TAU (3) when the primal and
//!   dual residuals differ by more than ADAPT (10; 0: fixed ρ), at most MAXFACT (20)
//!   factorizations, error checked every EVERY (20) iterations; then the library's LM from its
//!   best point for LMT (10) seconds;
//! - `mucont`: continuation in μ (ALPHAS, default 0.3,0.5,0.7,0.85,1): the default solver
//!   on the law with μ scaled by the first α, then LM from the previous stage's r at each
//!   next α, the default solver warm-started there when LM fails (COLD: from r = 0);
//! - `trace`: the default solver's history on the local form (an interior-point try would
//!   show no ‖F(s) − s‖; the policy runs it on rigid global problems only);
//! - `diag`: the contacts that carry the residual at the start point;
//! - `base`: the start point only.
//!
//! Env: LOG (per-step lines), RHO (multiplies every ρ_i), LM_MU (first damping factor),
//! CGLS=N (matrix-free LM direction, N CGLS steps), DENSE_MAX (dense JᵀJ up to this m),
//! WATCH=K (`lmsw` takes K unconditional LM steps instead of switching ρ),
//! PERCONTACT (`lmsw` draws a log-uniform factor in [0.1, 10] per contact at each switch).
//! err is always the error of docs/error.md on the stored local problem (a global file is
//! turned into its Delassus form W = Hᵀ M⁻¹ H, q = Hᵀ M⁻¹ f + w first).
#![allow(clippy::needless_range_loop)]

use coulomb::problem::{LocalProblem, Problem};
use coulomb::sparse::CscMatrix;
use faer::linalg::solvers::Solve;
use std::time::{Duration, Instant};

fn err(p: &LocalProblem, r: &[f64]) -> f64 {
    p.error(r).error
}

/// The library's LM end game from `r` until `deadline`, reported on one line ("total" since
/// `start` when given).
fn lm_finish(
    p: &LocalProblem,
    r: &[f64],
    deadline: coulomb::deadline::Deadline,
    start: Option<Instant>,
) {
    let mut r1 = r.to_vec();
    let t1 = Instant::now();
    let lp = coulomb::settings::LmParams::default();
    let lr = coulomb::levenberg::solve(p, &mut r1, 1e-8, &lp, deadline);
    let total = start.map_or(String::new(), |t| {
        format!(" (total {:.2} s)", t.elapsed().as_secs_f64())
    });
    println!(
        "  then LM: {:?} steps {} err {:.2e} in {:.2} s{total}",
        lr.status,
        lr.steps,
        err(p, &r1),
        t1.elapsed().as_secs_f64()
    );
}

fn envf(name: &str, default: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// Alart–Curnier map Φ(r) for (W + σI, q − σ c) and the blocks D of ∂P (row-major per contact).
struct Map<'a> {
    p: &'a LocalProblem,
    rho: Vec<f64>,
    sigma: f64,
    center: Vec<f64>,
}

impl Map<'_> {
    fn eval(&self, r: &[f64], g: &mut [f64], dbl: &mut [f64]) -> f64 {
        let p = self.p;
        let d = p.dim;
        let mut u = p.q.clone();
        p.w.gemv_acc(1.0, r, &mut u);
        if self.sigma != 0.0 {
            for k in 0..u.len() {
                u[k] += self.sigma * (r[k] - self.center[k]);
            }
        }
        for (i, &mu) in p.mu.iter().enumerate() {
            let at = i * d;
            let dj = &mut dbl[i * d * d..(i + 1) * d * d];
            dj.iter_mut().for_each(|x| *x = 0.0);
            let ri = self.rho[i];
            let mut y = [0.0; 3];
            for k in 0..d {
                y[k] = r[at + k] - ri * u[at + k];
            }
            let pn = y[0].max(0.0);
            if y[0] > 0.0 {
                dj[0] = 1.0;
            }
            let t = y[1..d].iter().map(|x| x * x).sum::<f64>().sqrt();
            let radius = mu * pn;
            let mut pt = [0.0; 2];
            if t <= radius {
                for k in 1..d {
                    pt[k - 1] = y[k];
                    dj[k * d + k] = 1.0;
                }
            } else if t > 0.0 {
                let s = radius / t;
                for a in 1..d {
                    pt[a - 1] = s * y[a];
                    for b in 1..d {
                        let e = if a == b { 1.0 } else { 0.0 };
                        dj[a * d + b] = s * (e - y[a] * y[b] / (t * t));
                    }
                    if y[0] > 0.0 {
                        dj[a * d] = mu * y[a] / t;
                    }
                }
            }
            g[at] = r[at] - pn;
            for k in 1..d {
                g[at + k] = r[at + k] - pt[k - 1];
            }
        }
        g.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    /// J = I − D + ρ D (W + σ I) as a CSC matrix.
    fn jacobian(&self, dbl: &[f64]) -> CscMatrix {
        let p = self.p;
        let d = p.dim;
        let m = p.q.len();
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..p.mu.len() {
            let dj = &dbl[i * d * d..(i + 1) * d * d];
            let ri = self.rho[i];
            for a in 0..d {
                for b in 0..d {
                    let e = if a == b { 1.0 } else { 0.0 };
                    let v = e - dj[a * d + b] + ri * self.sigma * dj[a * d + b];
                    rows.push(i * d + a);
                    cols.push(i * d + b);
                    vals.push(v);
                }
            }
        }
        for j in 0..m {
            for k in p.w.col_ptr[j]..p.w.col_ptr[j + 1] {
                let row = p.w.row_idx[k];
                let w = p.w.values[k];
                let c = row / d;
                let b = row % d;
                let dj = &dbl[c * d * d..(c + 1) * d * d];
                for a in 0..d {
                    let v = self.rho[c] * dj[a * d + b] * w;
                    rows.push(c * d + a);
                    cols.push(j);
                    vals.push(v);
                }
            }
        }
        CscMatrix::from_triplets(m, m, &rows, &cols, &vals).unwrap()
    }
}

fn to_faer(a: &CscMatrix) -> faer::sparse::SparseColMat<usize, f64> {
    let trip: Vec<faer::sparse::Triplet<usize, usize, f64>> = a
        .triplets()
        .map(|(i, j, v)| faer::sparse::Triplet::new(i, j, v))
        .collect();
    faer::sparse::SparseColMat::try_new_from_triplets(a.nrows, a.ncols, &trip).unwrap()
}

/// JᵀJ + λI.
fn normal_matrix(j: &CscMatrix, lambda: f64) -> CscMatrix {
    let jt = j.transpose();
    let n = j.ncols;
    let mut acc = vec![0.0; n];
    let mut mark = vec![usize::MAX; n];
    let mut list = Vec::new();
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for c in 0..n {
        list.clear();
        for k in j.col_ptr[c]..j.col_ptr[c + 1] {
            let row = j.row_idx[k];
            let v = j.values[k];
            for kk in jt.col_ptr[row]..jt.col_ptr[row + 1] {
                let i = jt.row_idx[kk];
                if mark[i] != c {
                    mark[i] = c;
                    acc[i] = 0.0;
                    list.push(i);
                }
                acc[i] += v * jt.values[kk];
            }
        }
        if mark[c] != c {
            mark[c] = c;
            acc[c] = 0.0;
            list.push(c);
        }
        acc[c] += lambda;
        for &i in &list {
            rows.push(i);
            cols.push(c);
            vals.push(acc[i]);
        }
    }
    CscMatrix::from_triplets(n, n, &rows, &cols, &vals).unwrap()
}

thread_local! {
    static SYMLU: std::cell::RefCell<Option<(usize, faer::sparse::linalg::solvers::SymbolicLu<usize>)>> = const { std::cell::RefCell::new(None) };
}

/// LM direction from the augmented system [λI Jᵀ; J −I] [d; y] = [0; −Φ] (y = J d + Φ).
fn aug_solve(j: &CscMatrix, lambda: f64, g: &[f64]) -> Option<Vec<f64>> {
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
    let m = j.ncols;
    let jt = j.transpose();
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for c in 0..m {
        rows.push(c);
        cols.push(c);
        vals.push(lambda);
        rows.push(m + c);
        cols.push(m + c);
        vals.push(-1.0);
        for k in j.col_ptr[c]..j.col_ptr[c + 1] {
            rows.push(m + j.row_idx[k]);
            cols.push(c);
            vals.push(j.values[k]);
        }
        for k in jt.col_ptr[c]..jt.col_ptr[c + 1] {
            rows.push(jt.row_idx[k]);
            cols.push(m + c);
            vals.push(jt.values[k]);
        }
    }
    let a = CscMatrix::from_triplets(2 * m, 2 * m, &rows, &cols, &vals).ok()?;
    let n = 2 * m;
    let symm = SymbolicSparseColMatRef::new_checked(n, n, &a.col_ptr, None, &a.row_idx);
    let key = a.row_idx.len() * 1_000_003 + n;
    let sym = SYMLU.with(|c| {
        let mut c = c.borrow_mut();
        if c.as_ref().map(|x| x.0) != Some(key) {
            *c = faer::sparse::linalg::solvers::SymbolicLu::try_new(symm)
                .ok()
                .map(|s| (key, s));
        }
        c.as_ref().map(|x| x.1.clone())
    })?;
    let mat = SparseColMatRef::new(symm, &a.values);
    let lu = faer::sparse::linalg::solvers::Lu::try_new_with_symbolic(sym, mat).ok()?;
    let mut rhs = vec![0.0; n];
    for k in 0..m {
        rhs[m + k] = -g[k];
    }
    lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut rhs, n, 1));
    rhs.truncate(m);
    rhs.iter().all(|x| x.is_finite()).then_some(rhs)
}

fn lu_solve(a: &CscMatrix, rhs: &mut [f64]) -> bool {
    let f = to_faer(a);
    let Ok(lu) = f.sp_lu() else { return false };
    let n = rhs.len();
    lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(rhs, n, 1));
    rhs.iter().all(|x| x.is_finite())
}

thread_local! {
    static SYM: std::cell::RefCell<Option<(usize, faer::sparse::linalg::solvers::SymbolicLlt<usize>)>> = const { std::cell::RefCell::new(None) };
}

fn chol_solve(a: &CscMatrix, rhs: &mut [f64]) -> bool {
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
    let n = a.nrows;
    let symm = SymbolicSparseColMatRef::new_checked(n, n, &a.col_ptr, None, &a.row_idx);
    let key = a.row_idx.len() * 1_000_003 + n;
    let sym = SYM.with(|c| {
        let mut c = c.borrow_mut();
        if c.as_ref().map(|x| x.0) != Some(key) {
            *c = faer::sparse::linalg::solvers::SymbolicLlt::try_new(symm, faer::Side::Lower)
                .ok()
                .map(|s| (key, s));
        }
        c.as_ref().map(|x| x.1.clone())
    });
    let Some(sym) = sym else { return false };
    let mat = SparseColMatRef::new(symm, &a.values);
    let Ok(llt) =
        faer::sparse::linalg::solvers::Llt::try_new_with_symbolic(sym, mat, faer::Side::Lower)
    else {
        return false;
    };
    let n = rhs.len();
    llt.solve_in_place(faer::MatMut::from_column_major_slice_mut(rhs, n, 1));
    rhs.iter().all(|x| x.is_finite())
}

fn rho_of(p: &LocalProblem) -> Vec<f64> {
    let d = p.dim;
    let mut sq = vec![0.0; p.mu.len()];
    for (i, j, v) in p.w.triplets() {
        if i / d == j / d {
            sq[i / d] += v * v;
        }
    }
    let scale = envf("RHO", 1.0);
    sq.iter()
        .map(|&s| {
            if s > 0.0 && s.is_finite() {
                scale / s.sqrt()
            } else {
                scale
            }
        })
        .collect()
}

thread_local! {
    /// steps `lm` accepts whatever the ratio (the watchdog of `lmsw` with WATCH)
    static FORCE: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Levenberg–Marquardt on ‖Φ‖² with the trust-region update of the damping.
fn lm(
    map: &Map,
    r: &mut Vec<f64>,
    deadline: Instant,
    max_it: usize,
    inner_target: f64,
    log: bool,
    mu_k: &mut f64,
) -> usize {
    let p = map.p;
    let m = r.len();
    let d = p.dim;
    let nb = p.mu.len() * d * d;
    let (mut g, mut dbl) = (vec![0.0; m], vec![0.0; nb]);
    let (mut g2, mut dbl2) = (vec![0.0; m], vec![0.0; nb]);
    let mut phi = map.eval(r, &mut g, &mut dbl);
    let t0 = Instant::now();
    let mut it = 0;
    while it < max_it && Instant::now() < deadline && phi > inner_target {
        it += 1;
        let j = map.jacobian(&dbl);
        let rn = coulomb::law::norm(r).max(1e-300);
        let lambda = *mu_k * (phi / rn).min(1.0);
        let dir = if std::env::var("CGLS").is_ok() {
            // CGLS on min ‖J d + Φ‖² + λ‖d‖² (matrix-free)
            let maxit = envf("CGLS", 200.0) as usize;
            let mut x = vec![0.0; m];
            let mut rr: Vec<f64> = g.iter().map(|v| -v).collect(); // b − J x
            let mut sv = vec![0.0; m];
            j.gemv_t_acc(1.0, &rr, &mut sv); // s = Jᵀ r − λ x
            let mut pv = sv.clone();
            let mut gamma: f64 = sv.iter().map(|v| v * v).sum();
            let g0 = gamma;
            for _ in 0..maxit {
                let q = j.mul_vec(&pv);
                let denom: f64 = q.iter().map(|v| v * v).sum::<f64>()
                    + lambda * pv.iter().map(|v| v * v).sum::<f64>();
                if denom <= 0.0 {
                    break;
                }
                let alpha = gamma / denom;
                for k in 0..m {
                    x[k] += alpha * pv[k];
                    rr[k] -= alpha * q[k];
                }
                sv.iter_mut().for_each(|v| *v = 0.0);
                j.gemv_t_acc(1.0, &rr, &mut sv);
                for k in 0..m {
                    sv[k] -= lambda * x[k];
                }
                let gnew: f64 = sv.iter().map(|v| v * v).sum();
                if gnew <= 1e-12 * g0 {
                    break;
                }
                let beta = gnew / gamma;
                gamma = gnew;
                for k in 0..m {
                    pv[k] = sv[k] + beta * pv[k];
                }
            }
            Some(x)
        } else if m <= envf("DENSE_MAX", 3000.0) as usize {
            // dense JᵀJ + λI, Cholesky
            let jt = j.transpose();
            let mut a = faer::Mat::<f64>::zeros(m, m);
            for c in 0..m {
                for k in j.col_ptr[c]..j.col_ptr[c + 1] {
                    let row = j.row_idx[k];
                    let v = j.values[k];
                    for kk in jt.col_ptr[row]..jt.col_ptr[row + 1] {
                        let i = jt.row_idx[kk];
                        a[(i, c)] += v * jt.values[kk];
                    }
                }
                a[(c, c)] += lambda;
            }
            let mut dir = vec![0.0; m];
            j.gemv_t_acc(-1.0, &g, &mut dir);
            match a.llt(faer::Side::Lower) {
                Ok(llt) => {
                    llt.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut dir, m, 1));
                    dir.iter().all(|x| x.is_finite()).then_some(dir)
                }
                Err(_) => None,
            }
        } else if std::env::var("AUG").is_err() {
            let nm = normal_matrix(&j, lambda);
            let mut dir = vec![0.0; m];
            j.gemv_t_acc(-1.0, &g, &mut dir);
            chol_solve(&nm, &mut dir).then_some(dir)
        } else {
            aug_solve(&j, lambda, &g)
        };
        let Some(dir) = dir else {
            *mu_k *= 10.0;
            continue;
        };
        let jd = j.mul_vec(&dir);
        let grad = {
            let mut gg = vec![0.0; m];
            j.gemv_t_acc(1.0, &g, &mut gg);
            coulomb::law::norm(&gg)
        };
        let pred = phi * phi
            - jd.iter()
                .zip(&g)
                .map(|(a, b)| (a + b) * (a + b))
                .sum::<f64>();
        let trial: Vec<f64> = r.iter().zip(&dir).map(|(a, b)| a + b).collect();
        let phi2 = map.eval(&trial, &mut g2, &mut dbl2);
        let ratio = (phi * phi - phi2 * phi2) / pred.max(1e-300);
        if log {
            println!(
                "  lm {it} phi {phi:.3e} -> {phi2:.3e} lam {lambda:.2e} ratio {ratio:.2} |J'g|/|g| {:.2e} |d| {:.2e} err {:.2e} t {:.2}", grad / phi, coulomb::law::norm(&dir),
                err(p, &trial),
                t0.elapsed().as_secs_f64()
            );
        }
        let forced = FORCE.with(|c| {
            let n = c.get();
            if n > 0 {
                c.set(n - 1);
            }
            n > 0
        });
        if forced || (ratio > 1e-4 && phi2 < phi) {
            *r = trial;
            std::mem::swap(&mut g, &mut g2);
            std::mem::swap(&mut dbl, &mut dbl2);
            phi = phi2;
            if ratio > 0.75 {
                *mu_k = (*mu_k / 4.0).max(1e-8);
            }
        } else {
            *mu_k *= 4.0;
        }
    }
    it
}

/// Semismooth Newton with J (LU), Armijo, full step after a failed search (Siconos-style).
fn newton(
    map: &Map,
    r: &mut Vec<f64>,
    deadline: Instant,
    max_it: usize,
    target: f64,
    log: bool,
) -> (usize, f64) {
    let p = map.p;
    let m = r.len();
    let d = p.dim;
    let nb = p.mu.len() * d * d;
    let (mut g, mut dbl) = (vec![0.0; m], vec![0.0; nb]);
    let (mut g2, mut dbl2) = (vec![0.0; m], vec![0.0; nb]);
    let mut phi = map.eval(r, &mut g, &mut dbl);
    let mut it = 0;
    let mut best = (phi, r.clone());
    while it < max_it && Instant::now() < deadline && phi > target {
        it += 1;
        let j = map.jacobian(&dbl);
        let mut dir: Vec<f64> = g.iter().map(|x| -x).collect();
        if !lu_solve(&j, &mut dir) {
            if log {
                println!("   lu failed");
            }
            break;
        }
        let mut t = 1.0;
        let mut ok = false;
        for _ in 0..30 {
            let trial: Vec<f64> = r.iter().zip(&dir).map(|(a, b)| a + t * b).collect();
            let phi2 = map.eval(&trial, &mut g2, &mut dbl2);
            if phi2 <= (1.0 - 1e-4 * t) * phi {
                *r = trial;
                std::mem::swap(&mut g, &mut g2);
                std::mem::swap(&mut dbl, &mut dbl2);
                phi = phi2;
                ok = true;
                break;
            }
            t *= 0.5;
        }
        if !ok {
            // full step anyway
            for k in 0..m {
                r[k] += dir[k];
            }
            phi = map.eval(r, &mut g, &mut dbl);
            t = -1.0;
        }
        if phi < best.0 {
            best = (phi, r.clone());
        }
        if log {
            println!("   nsn {it} phi {phi:.3e} t {t} err {:.2e}", err(p, r));
        }
    }
    *r = best.1;
    (it, best.0)
}

fn search() {
    let mut found = 0;
    for seed in 0..3000u64 {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(1);
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let contacts = 3 + (seed % 6) as usize;
        let m = 3 * contacts;
        let k = m / 2;
        let a: Vec<f64> = (0..k * m).map(|_| next()).collect();
        let mut w = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                w[i * m + j] = (0..k).map(|l| a[l * m + i] * a[l * m + j]).sum::<f64>();
            }
        }
        let p = LocalProblem {
            dim: 3,
            w: CscMatrix::from_dense(m, m, &w),
            q: (0..m).map(|_| next()).collect(),
            mu: (0..contacts).map(|_| 0.3 + 0.7 * next().abs()).collect(),
        };
        let qn = coulomb::law::norm(&p.q);
        let mut r0 = vec![0.0; m];
        let nr = coulomb::newton::polish(
            &p,
            &mut r0,
            0.5e-8 * qn,
            200,
            coulomb::deadline::Deadline::NEVER,
        );
        let mut r1 = vec![0.0; m];
        let lp = coulomb::settings::LmParams {
            max_steps: 2000,
            ..Default::default()
        };
        let lr =
            coulomb::levenberg::solve(&p, &mut r1, 0.5e-8, &lp, coulomb::deadline::Deadline::NEVER);
        if err(&p, &r0) > 1e-8 && err(&p, &r1) <= 1e-8 {
            found += 1;
            println!("seed {seed} contacts {contacts}: newton {:?} {} err {:.2e} | lm {:?} {} ({} wd {} sw) err {:.2e}", nr.status, nr.steps, err(&p, &r0), lr.status, lr.steps, lr.watchdogs, lr.switches, err(&p, &r1));
        }
    }
    println!("found {found}");
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if std::env::var_os("FAER_SEQ").is_some() {
        faer::set_global_parallelism(faer::Par::Seq);
    }
    if args[1] == "search" {
        search();
        return;
    }
    let path = std::path::Path::new(&args[1]);
    let method = args.get(2).map(String::as_str).unwrap_or("lm");
    let warm: f64 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(2.0);
    let limit: f64 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(10.0);
    let log = std::env::var("LOG").is_ok();
    let file = coulomb::fclib::read(path).unwrap();
    let global = match &file.problem {
        Problem::Global(g) if std::env::var_os("NO_SCHUR").is_none() => Some(g.clone()),
        _ => None,
    };
    let p = match file.problem {
        Problem::Local(p) => p,
        Problem::Global(g) => {
            let s = coulomb::Solver::new_owned(Problem::Global(g), coulomb::Settings::default())
                .unwrap();
            s.local().clone()
        }
    };
    let name = path.file_stem().unwrap().to_string_lossy();
    if method == "trace" {
        // the default solver's history on the local form (an interior-point try would show a
        // NaN ‖F(s) − s‖)
        let settings = coulomb::Settings {
            time_limit: Some(Duration::from_secs_f64(limit)),
            ..Default::default()
        };
        let sol = coulomb::solver::solve(&Problem::Local(p.clone()), &settings).unwrap();
        for (k, h) in sol.history.iter().enumerate() {
            println!(
                "{k:4} err {:.3e} |F(s)-s| {:.3e} inner {}",
                h.error, h.fixed_point_residual, h.inner_iterations
            );
        }
        println!(
            "{name} trace: {:?} err {:.2e} in {:.2} s",
            sol.status,
            sol.error,
            sol.solve_time.as_secs_f64()
        );
        return;
    }
    if method == "mucont" {
        // continuation in μ: the law with every μᵢ scaled by α₀ solved by the default
        // solver, then α raised stage by stage (ALPHAS, comma-separated, last 1), each stage
        // LM (the library's end game) from the previous stage's r; a stage LM does not
        // finish within LIMIT_SECONDS falls back to the default solver warm-started there
        let t = Instant::now();
        let alphas: Vec<f64> = std::env::var("ALPHAS")
            .ok()
            .map(|s| s.split(',').map(|x| x.parse().unwrap()).collect())
            .unwrap_or_else(|| vec![0.3, 0.5, 0.7, 0.85, 1.0]);
        let stage_limit = Duration::from_secs_f64(limit);
        let mut r = vec![0.0; p.q.len()];
        for (k, &a) in alphas.iter().enumerate() {
            let mut pk = p.clone();
            for x in pk.mu.iter_mut() {
                *x *= a;
            }
            let t1 = Instant::now();
            let mut how = "lm";
            let mut done = false;
            if k > 0 {
                let lp = coulomb::settings::LmParams::default();
                let lr = coulomb::levenberg::solve(
                    &pk,
                    &mut r,
                    1e-8,
                    &lp,
                    Instant::now().checked_add(stage_limit).into(),
                );
                done = lr.error <= 1e-8;
                if !done {
                    println!(
                        "    stage {k} α {a}: LM {:?} {} steps err {:.2e}",
                        lr.status, lr.steps, lr.error
                    );
                }
            }
            if !done {
                how = "default";
                let settings = coulomb::Settings {
                    time_limit: Some(stage_limit),
                    ..Default::default()
                };
                let guess = coulomb::Guess {
                    r: r.clone(),
                    v: None,
                };
                let g = (k > 0 && std::env::var_os("COLD").is_none()).then_some(&guess);
                let sol =
                    coulomb::solve_with_guess(&Problem::Local(pk.clone()), &settings, g).unwrap();
                r = sol.r;
            }
            println!(
                "  stage {k} α {a}: {how} err {:.2e} in {:.2} s (err at μ: {:.2e}, total {:.2} s)",
                err(&pk, &r),
                t1.elapsed().as_secs_f64(),
                err(&p, &r),
                t.elapsed().as_secs_f64()
            );
        }
        println!(
            "{name} mucont: err {:.2e} in {:.2} s",
            err(&p, &r),
            t.elapsed().as_secs_f64()
        );
        return;
    }
    if method == "admm" {
        // ADMM on the SOC-QP with s = μ‖u_T‖ lagged (de Saxcé), dense LU of W + ρI
        let t = Instant::now();
        let d = p.dim;
        let n = p.mu.len();
        let m = n * d;
        let wd = p.w.to_dense();
        let diag_mean = (0..m).map(|k| wd[k * m + k]).sum::<f64>() / m as f64;
        let mut rho = envf("RHO0", 1.0) * diag_mean;
        let relax = envf("RELAX", 1.6);
        let adapt = envf("ADAPT", 10.0);
        let tau = envf("TAU", 3.0);
        let every = envf("EVERY", 20.0) as usize;
        let max_fact = envf("MAXFACT", 20.0) as usize;
        let factor = |rho: f64| {
            let mut a = faer::Mat::<f64>::zeros(m, m);
            for j in 0..m {
                for i in 0..m {
                    a[(i, j)] = wd[j * m + i];
                }
                a[(j, j)] += rho;
            }
            a.partial_piv_lu()
        };
        let mut lu = factor(rho);
        let mut facts = 1;
        let mut r = vec![0.0; m];
        let mut z = vec![0.0; m];
        let mut y = vec![0.0; m];
        let mut s = vec![0.0; m];
        let mut u = p.q.clone();
        let mut best = f64::INFINITY;
        let mut best_z = z.clone();
        let mut it = 0;
        let deadline = t + Duration::from_secs_f64(limit);
        loop {
            // s = μ‖u_T‖ e (u at z)
            for i in 0..n {
                let ut = (1..d).map(|k| u[i * d + k].powi(2)).sum::<f64>().sqrt();
                s[i * d] = p.mu[i] * ut;
            }
            // (W + ρI) r = ρ z − y − (q + s)
            let mut rhs: Vec<f64> = (0..m).map(|k| rho * z[k] - y[k] - p.q[k] - s[k]).collect();
            lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut rhs, m, 1));
            r.copy_from_slice(&rhs);
            let zold = z.clone();
            let mut rh = vec![0.0; m];
            for k in 0..m {
                rh[k] = relax * r[k] + (1.0 - relax) * zold[k];
                z[k] = rh[k] + y[k] / rho;
            }
            for i in 0..n {
                coulomb::cone::project(p.mu[i], &mut z[i * d..(i + 1) * d]);
            }
            for k in 0..m {
                y[k] += rho * (rh[k] - z[k]);
            }
            u.copy_from_slice(&p.q);
            p.w.gemv_acc(1.0, &z, &mut u);
            it += 1;
            if it % every == 0 {
                let e = err(&p, &z);
                if e < best {
                    best = e;
                    best_z.copy_from_slice(&z);
                }
                let prim =
                    coulomb::law::norm(&r.iter().zip(&z).map(|(a, b)| a - b).collect::<Vec<_>>());
                let dual = rho
                    * coulomb::law::norm(
                        &z.iter().zip(&zold).map(|(a, b)| a - b).collect::<Vec<_>>(),
                    );
                if log {
                    println!(
                        "it {it} err {e:.3e} prim {prim:.2e} dual {dual:.2e} rho {rho:.2e} t {:.2}",
                        t.elapsed().as_secs_f64()
                    );
                }
                if e <= 1e-8 || Instant::now() > deadline {
                    break;
                }
                if facts < max_fact && adapt > 0.0 {
                    let new = if prim > adapt * dual {
                        rho * tau
                    } else if dual > adapt * prim {
                        rho / tau
                    } else {
                        rho
                    };
                    if new != rho {
                        // y is unscaled: keep it
                        rho = new;
                        lu = factor(rho);
                        facts += 1;
                    }
                }
            }
        }
        println!("{name} admm: {it} its, {facts} factorizations, best err {best:.2e} in {:.2} s, rho {rho:.2e}", t.elapsed().as_secs_f64());
        if best > 1e-8 {
            let t1 = Instant::now();
            let limit = Some(Duration::from_secs_f64(envf("LMT", 10.0)));
            lm_finish(
                &p,
                &best_z,
                coulomb::deadline::Deadline::after(t1, limit),
                None,
            );
        }
        return;
    }
    if method == "barrier" {
        // the interior-point method on the law itself (coulomb::barrier), cold start
        // (WARM_SECONDS ignored), then LM from its best point
        let t = Instant::now();
        let d = coulomb::settings::BarrierParams::default();
        let params = coulomb::settings::BarrierParams {
            stall_steps: envf("BARRIER_STALL", d.stall_steps as f64) as usize,
            settle_steps: envf("BARRIER_SETTLE", d.settle_steps as f64) as usize,
            settle_below: envf("BARRIER_SETTLE_BELOW", d.settle_below),
            settle_alpha: envf("BARRIER_SETTLE_ALPHA", d.settle_alpha),
            start_margin: envf("BARRIER_MARGIN", d.start_margin),
            ..d
        };
        let path = coulomb::barrier::PathParams {
            smoothing: envf("BARRIER_SMOOTH", d.paths[0].smoothing),
            recentre: envf("BARRIER_RECENTRE", d.paths[0].recentre),
        };
        let steps = envf("BARRIER_STEPS", 150.0) as usize;
        let dl = coulomb::deadline::Deadline::after(t, Some(Duration::from_secs_f64(limit)));
        let tol = envf("BARRIER_TOL", 1e-8);
        let params = coulomb::settings::BarrierParams {
            max_skeleton_unknowns: envf("SKELETON_MAX", params.max_skeleton_unknowns as f64)
                as usize,
            rank_tol: envf("RANK_TOL", params.rank_tol),
            refine_steps: envf("REFINE", params.refine_steps as f64) as usize,
            refine_tol: envf("REFINE_TOL", params.refine_tol),
            skeleton_strikes: envf("STRIKES", params.skeleton_strikes as f64) as usize,
            ..params
        };
        let Some(setup) = coulomb::barrier::Setup::new(&p, global.as_ref(), &params, dl) else {
            println!("{name} barrier: no setup");
            return;
        };
        println!(
            "{name} setup {:?} in {:.3} s",
            setup.kind(),
            t.elapsed().as_secs_f64()
        );
        let (r, rep) = coulomb::barrier::solve_with(&p, &setup, tol, steps, &params, path, dl);
        println!(
            "{name} barrier {:?} steps {} ({} exact) err {:.2e} gap {:.2e} in {:.2} s, ‖r‖ {:.3e}",
            rep.status,
            rep.steps,
            rep.exact_steps,
            err(&p, &r),
            rep.gap,
            t.elapsed().as_secs_f64(),
            coulomb::law::norm(&r)
        );
        if std::env::var("LMPROBE").is_ok() {
            let map = Map {
                p: &p,
                rho: rho_of(&p),
                sigma: 0.0,
                center: vec![0.0; r.len()],
            };
            let mut r2 = r.clone();
            let mut mu_k = 1e-2;
            let far = Instant::now() + Duration::from_secs(5);
            let n2 = lm(&map, &mut r2, far, 100, 0.0, true, &mut mu_k);
            println!("probe lm {n2} steps err {:.2e}", err(&p, &r2));
        }
        if rep.error > 1e-8 {
            let dl = coulomb::deadline::Deadline::after(t, Some(Duration::from_secs_f64(limit)));
            lm_finish(&p, &r, dl, Some(t));
        }
        return;
    }
    if method == "cmp" {
        // from r = 0: the Newton end game's polish vs the library's LM end game
        let m = p.q.len();
        let qn = coulomb::law::norm(&p.q);
        let mut r0 = vec![0.0; m];
        let t = Instant::now();
        let nr = coulomb::newton::polish(
            &p,
            &mut r0,
            0.5e-8 * qn,
            200,
            coulomb::deadline::Deadline::NEVER,
        );
        let tn = t.elapsed().as_secs_f64();
        let mut r1 = vec![0.0; m];
        let t = Instant::now();
        let lp = coulomb::settings::LmParams {
            max_steps: 2000,
            ..Default::default()
        };
        let lr =
            coulomb::levenberg::solve(&p, &mut r1, 0.5e-8, &lp, coulomb::deadline::Deadline::NEVER);
        let map = Map {
            p: &p,
            rho: rho_of(&p),
            sigma: 0.0,
            center: vec![0.0; m],
        };
        let mut r2 = vec![0.0; m];
        let mut mu_k = 1e-2;
        let far = Instant::now() + Duration::from_secs(5);
        let n2 = lm(
            &map,
            &mut r2,
            far,
            200,
            0.0,
            std::env::var("LOG").is_ok(),
            &mut mu_k,
        );
        println!("probe lm {n2} steps err {:.2e}", err(&p, &r2));
        println!(
            "{name} m {m}: newton {:?} {} steps err {:.2e} {tn:.2}s | lm {:?} {} steps ({} wd, {} sw) err {:.2e} {:.2}s",
            nr.status, nr.steps, err(&p, &r0), lr.status, lr.steps, lr.watchdogs, lr.switches, err(&p, &r1), t.elapsed().as_secs_f64()
        );
        return;
    }
    let t0 = Instant::now();
    let s = coulomb::Settings {
        tol: envf("WARM_TOL", 1e-8),
        time_limit: Some(Duration::from_secs_f64(warm)),
        ..Default::default()
    };
    let sol = coulomb::solve(&Problem::Local(p.clone()), &s).unwrap();
    let mut r = sol.r.clone();
    let e0 = err(&p, &r);
    let tw = t0.elapsed().as_secs_f64();
    if method == "base" || e0 <= 1e-8 {
        println!(
            "{name} {method}: warm {:?} err {e0:.2e} t {tw:.2} ‖r‖ {:.3e} ‖q‖ {:.3e}",
            sol.status,
            coulomb::law::norm(&r),
            coulomb::law::norm(&p.q)
        );
        return;
    }
    let deadline = Instant::now() + Duration::from_secs_f64(limit);
    let rho = rho_of(&p);
    let m = r.len();
    let t1 = Instant::now();
    let tol = 1e-8;
    match method {
        "lib" => {
            // the library's end game, its parameters overridable by env
            let mut lp = coulomb::settings::LmParams {
                max_steps: 100_000,
                ..Default::default()
            };
            lp.watchdog_steps = envf("LIB_WATCH", lp.watchdog_steps as f64) as usize;
            lp.watchdogs_per_switch = envf("LIB_PER", lp.watchdogs_per_switch as f64) as usize;
            lp.segment_steps = envf("LIB_SEG", lp.segment_steps as f64) as usize;
            let rep = coulomb::levenberg::solve(
                &p,
                &mut r,
                tol,
                &lp,
                Instant::now()
                    .checked_add(Duration::from_secs_f64(limit))
                    .into(),
            );
            println!(
                "{name} lib: warm err {e0:.2e} ({tw:.2}s) -> err {:.2e} in {:.2}s, {rep:?}",
                err(&p, &r),
                t1.elapsed().as_secs_f64()
            );
        }
        "nsf" => {
            newton_on_s(&p, &r, deadline, log);
        }
        "lm" => {
            let map = Map {
                p: &p,
                rho: rho.clone(),
                sigma: 0.0,
                center: vec![0.0; m],
            };
            // run LM until err ≤ tol: target on ‖Φ‖ checked via err every call
            let mut total = 0;
            let mut mu_k = envf("LM_MU", 1e-2);
            while Instant::now() < deadline && err(&p, &r) > tol {
                let n = lm(&map, &mut r, deadline, 5, 0.0, log, &mut mu_k);
                total += n;
                if n == 0 {
                    break;
                }
            }
            println!(
                "{name} lm: warm err {e0:.2e} ({tw:.2}s) -> err {:.2e} in {:.2}s, {total} steps",
                err(&p, &r),
                t1.elapsed().as_secs_f64()
            );
        }
        "lmsw" => {
            // LM on the AC map; when ‖Φ‖ stalls, change ρ (the pieces of the map move, r stays)
            let scales = [1.0, 0.1, 10.0, 0.3, 3.0, 0.03, 30.0];
            let mut which = 0;
            let mut mu_k = envf("LM_MU", 1e-2);
            let mut total = 0;
            let mut switches = 0;
            let mut best = (e0, r.clone());
            while Instant::now() < deadline && err(&p, &r) > tol {
                let rho_s: Vec<f64> = if std::env::var("PERCONTACT").is_ok() && switches > 0 {
                    // every ρ_i times its own log-uniform factor in [0.1, 10] (seeded by the switch)
                    let mut state = 0x9E37_79B9_7F4A_7C15u64.wrapping_mul(switches as u64 + 1);
                    rho.iter()
                        .map(|x| {
                            state = state
                                .wrapping_mul(6364136223846793005)
                                .wrapping_add(1442695040888963407);
                            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                            x * 10f64.powf(2.0 * u - 1.0)
                        })
                        .collect()
                } else {
                    rho.iter().map(|x| x * scales[which]).collect()
                };
                let map = Map {
                    p: &p,
                    rho: rho_s,
                    sigma: 0.0,
                    center: vec![0.0; m],
                };
                let e_before = err(&p, &r);
                if e_before < best.0 {
                    best = (e_before, r.clone());
                }
                let n = lm(&map, &mut r, deadline, 8, 0.0, false, &mut mu_k);
                total += n;
                let e_after = err(&p, &r);
                if log {
                    println!(
                        "  seg rho x{} err {e_before:.2e} -> {e_after:.2e} t {:.2}",
                        scales[which],
                        t1.elapsed().as_secs_f64()
                    );
                }
                if e_after > 0.7 * e_before && std::env::var("WATCH").is_ok() {
                    // non-monotone escape: the next steps are taken whatever the merit says
                    FORCE.with(|c| c.set(envf("WATCH", 2.0) as usize));
                    mu_k = 1e-6;
                    switches += 1;
                } else if e_after > 0.7 * e_before {
                    which = (which + 1) % scales.len();
                    switches += 1;
                    mu_k = envf("LM_MU", 1e-2);
                }
            }
            if err(&p, &r) > best.0 {
                r = best.1;
            }
            println!(
                "{name} lmsw: warm err {e0:.2e} ({tw:.2}s) -> err {:.2e} in {:.2}s, {total} steps, {switches} switches",
                err(&p, &r),
                t1.elapsed().as_secs_f64()
            );
        }
        "nsnsw" => {
            // regularized semismooth Newton (J + λI, LU) on the AC map with Armijo; ρ switched on stall
            let scales = [1.0, 0.1, 10.0, 0.3, 3.0, 0.03, 30.0];
            let mut which = 0;
            let mut total = 0;
            let mut switches = 0;
            let d = p.dim;
            let nb = p.mu.len() * d * d;
            while Instant::now() < deadline && err(&p, &r) > tol {
                let rho_s: Vec<f64> = rho.iter().map(|x| x * scales[which]).collect();
                let map = Map {
                    p: &p,
                    rho: rho_s,
                    sigma: 0.0,
                    center: vec![0.0; m],
                };
                let e_before = err(&p, &r);
                let (mut g, mut dbl) = (vec![0.0; m], vec![0.0; nb]);
                let (mut g2, mut dbl2) = (vec![0.0; m], vec![0.0; nb]);
                let mut phi = map.eval(&r, &mut g, &mut dbl);
                for _ in 0..8 {
                    if Instant::now() >= deadline {
                        break;
                    }
                    total += 1;
                    let j = map.jacobian(&dbl);
                    let rn = coulomb::law::norm(&r).max(1e-300);
                    let mut lambda = envf("LAM", 1e-2) * (phi / rn).min(1.0);
                    let mut moved = false;
                    for _ in 0..4 {
                        let shifted = j.add_scaled(1.0, &CscMatrix::identity(m, lambda));
                        let mut dir: Vec<f64> = g.iter().map(|x| -x).collect();
                        if lu_solve(&shifted, &mut dir) {
                            let mut t = 1.0;
                            for _ in 0..12 {
                                let trial: Vec<f64> =
                                    r.iter().zip(&dir).map(|(a, b)| a + t * b).collect();
                                let phi2 = map.eval(&trial, &mut g2, &mut dbl2);
                                if phi2 <= (1.0 - 1e-4 * t) * phi {
                                    r = trial;
                                    std::mem::swap(&mut g, &mut g2);
                                    std::mem::swap(&mut dbl, &mut dbl2);
                                    phi = phi2;
                                    moved = true;
                                    break;
                                }
                                t *= 0.5;
                            }
                        }
                        if moved {
                            break;
                        }
                        lambda = (lambda * 100.0).max(1e-10);
                    }
                    if !moved {
                        break;
                    }
                }
                let e_after = err(&p, &r);
                if log {
                    println!(
                        "  seg rho x{} err {e_before:.2e} -> {e_after:.2e} t {:.2}",
                        scales[which],
                        t1.elapsed().as_secs_f64()
                    );
                }
                if e_after > 0.7 * e_before {
                    which = (which + 1) % scales.len();
                    switches += 1;
                }
            }
            println!(
                "{name} nsnsw: warm err {e0:.2e} ({tw:.2}s) -> err {:.2e} in {:.2}s, {total} steps, {switches} switches",
                err(&p, &r),
                t1.elapsed().as_secs_f64()
            );
        }
        "nsn" => {
            let map = Map {
                p: &p,
                rho: rho.clone(),
                sigma: 0.0,
                center: vec![0.0; m],
            };
            let (n, _) = newton(&map, &mut r, deadline, 200, 0.0, log);
            println!(
                "{name} nsn: warm err {e0:.2e} ({tw:.2}s) -> err {:.2e} in {:.2}s, {n} steps",
                err(&p, &r),
                t1.elapsed().as_secs_f64()
            );
        }
        "ppa" | "ppalm" => {
            let wmax = p.w.diagonal().iter().fold(0.0f64, |a, &b| a.max(b.abs()));
            let c = envf("SIG", 5.0);
            let nu = envf("NU", 1.0);
            let mut e = e0;
            let mut k = 0;
            let mut sigma = c * e.powf(nu) * wmax;
            while e > tol && Instant::now() < deadline && k < 500 {
                k += 1;
                let map = Map {
                    p: &p,
                    rho: rho.clone(),
                    sigma,
                    center: r.clone(),
                };
                let mut rk = r.clone();
                let (n, phi) = if method == "ppa" {
                    newton(&map, &mut rk, deadline, 50, 0.0, false)
                } else {
                    {
                        let tgt = 1e-14 * coulomb::law::norm(&rk);
                        {
                            let mut mu_k = envf("LM_MU", 1e-2);
                            (
                                lm(
                                    &map,
                                    &mut rk,
                                    deadline,
                                    envf("INNER", 50.0) as usize,
                                    tgt,
                                    std::env::var("LOG2").is_ok(),
                                    &mut mu_k,
                                ),
                                0.0,
                            )
                        }
                    }
                };
                let e1 = err(&p, &rk);
                if log {
                    println!(
                        "  ppa {k} sigma {sigma:.2e} inner {n} phi {phi:.2e} err {e:.2e} -> {e1:.2e} t {:.2}",
                        t1.elapsed().as_secs_f64()
                    );
                }
                r = rk;
                e = e1;
                sigma = c * e.powf(nu) * wmax;
            }
            println!(
                "{name} {method}: warm err {e0:.2e} ({tw:.2}s) -> err {:.2e} in {:.2}s, {k} prox steps",
                err(&p, &r),
                t1.elapsed().as_secs_f64()
            );
        }
        "diag" => {
            let u = p.velocity(&r);
            let d = p.dim;
            let scale = p.error(&r).scale;
            let rn_max = (0..p.mu.len()).map(|i| r[i * d]).fold(0.0f64, f64::max);
            let un_max = (0..p.mu.len())
                .map(|i| u[i * d].abs())
                .fold(0.0f64, f64::max);
            println!("scale {scale:.3e} max rN {rn_max:.3e} max |uN| {un_max:.3e}");
            let mut rows: Vec<(f64, String)> = Vec::new();
            for i in 0..p.mu.len() {
                let ui = &u[i * d..(i + 1) * d];
                let ri = &r[i * d..(i + 1) * d];
                let e = coulomb::natural_map::contact_residual_sq(p.mu[i], ui, ri).sqrt();
                let rt = ri[1..].iter().map(|x| x * x).sum::<f64>().sqrt();
                let ut = ui[1..].iter().map(|x| x * x).sum::<f64>().sqrt();
                rows.push((
                    e,
                    format!(
                        "c{i} mu {} rN {:.2e} |rT|/mu rN {:.4} uN {:.2e} |uT| {:.2e} e {e:.2e}",
                        p.mu[i],
                        ri[0],
                        rt / (p.mu[i] * ri[0]).max(1e-300),
                        ui[0],
                        ut
                    ),
                ));
            }
            rows.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
            let tot: f64 = rows.iter().map(|x| x.0 * x.0).sum::<f64>().sqrt();
            println!("total e {tot:.3e} err {:.3e}", err(&p, &r));
            for x in rows.iter().take(25) {
                println!("{}", x.1);
            }
        }
        _ => panic!("method"),
    }
}

/// sⁱ = μⁱ ‖u_Tⁱ‖ for every contact (F of (3.19), scaled by μ).
fn f_of(p: &LocalProblem, u: &[f64]) -> Vec<f64> {
    let d = p.dim;
    (0..p.mu.len())
        .map(|i| p.mu[i] * coulomb::cone::tangent_norm(&u[i * d..(i + 1) * d]))
        .collect()
}

/// F(s) of (3.19) and r(s): the inner problem (4.7) with b = q + E s by the interior point.
fn eval_f(
    p: &LocalProblem,
    ipm: &mut (coulomb::inner::ipm::IpmSolver, CscMatrix),
    s: &[f64],
    r: &mut [f64],
) -> (Vec<f64>, Vec<f64>) {
    use coulomb::inner::{InnerLimits, InnerProblem, InnerSolver};
    let d = p.dim;
    let mut b = p.q.clone();
    for (i, &si) in s.iter().enumerate() {
        b[i * d] += si;
    }
    r.iter_mut().for_each(|x| *x = 0.0);
    let limits = InnerLimits {
        tol: 1e-12,
        max_iterations: 300,
        deadline: coulomb::deadline::Deadline::NEVER,
    };
    let _ = ipm.0.solve(
        &InnerProblem {
            dim: d,
            w: &ipm.1,
            b: &b,
            mu: &p.mu,
        },
        &limits,
        r,
    );
    let f = f_of(p, &p.velocity(r));
    (f, b)
}

/// Newton's method on G(s) = s − F(s) (see the `nsf` mode).
fn newton_on_s(p: &LocalProblem, r0: &[f64], deadline: Instant, log: bool) {
    let t0 = Instant::now();
    let d = p.dim;
    let n = p.mu.len();
    let m = n * d;
    let rho = rho_of(p);
    let wt = p.w.transpose();
    let delta = envf("NSF_DELTA", 0.0);
    let maxdiag =
        p.w.triplets()
            .filter(|t| t.0 == t.1)
            .map(|t| t.2)
            .fold(0.0f64, f64::max);
    let wreg =
        p.w.add_scaled(1.0, &CscMatrix::identity(m, delta * maxdiag));
    let mut ipm = (coulomb::inner::ipm::IpmSolver::new(), wreg);
    let r0norm = coulomb::law::norm(r0);
    // s₀ = F at the start point
    let mut s = f_of(p, &p.velocity(r0));
    let mut r = vec![0.0; m];
    let (mut f, mut b) = eval_f(p, &mut ipm, &s, &mut r);
    let gnorm = |s: &[f64], f: &[f64]| {
        s.iter()
            .zip(f)
            .map(|(a, c)| (a - c) * (a - c))
            .sum::<f64>()
            .sqrt()
    };
    let mut g = gnorm(&s, &f);
    let mut best = (err(p, &r), r.clone());
    println!(
        "nsf start: |G| {g:.3e} err(r(s)) {:.3e} ({:.2}s)",
        best.0,
        t0.elapsed().as_secs_f64()
    );
    let mut eps_rel = envf("NSF_EPS", 1e-4);
    let adaptive = std::env::var("NSF_FIXED").is_err();
    for k in 0..500 {
        if Instant::now() > deadline || best.0 <= 1e-8 {
            break;
        }
        // linearized natural map of (4.7) at r(s): J = I − D + ρ D W, ũ = W r + b
        let mut ut = b.clone();
        p.w.gemv_acc(1.0, &r, &mut ut);
        let mut dbl = vec![0.0; n * d * d];
        let mut proj = vec![0.0; d];
        for i in 0..n {
            let y: Vec<f64> = (0..d)
                .map(|k| r[i * d + k] - rho[i] * ut[i * d + k])
                .collect();
            coulomb::natural_map::projection_jacobian(
                p.mu[i],
                &y,
                &mut proj,
                &mut dbl[i * d * d..(i + 1) * d * d],
            );
        }
        let eps = eps_rel;
        if k == 0 {
            let (mut inside, mut zero) = (0, 0);
            for i in 0..n {
                let db = &dbl[i * d * d..(i + 1) * d * d];
                if (0..d).all(|a| (db[a * d + a] - 1.0).abs() < 1e-12) {
                    inside += 1;
                } else if db.iter().all(|&x| x == 0.0) {
                    zero += 1;
                }
            }
            println!(
                "  pieces at r(s): {inside} sticking (D = I: {} equations W dr = −E ds), {zero} open, {} sliding; {n} contacts, m = {m}",
                d * inside,
                n - inside - zero
            );
        }
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..n {
            let db = &dbl[i * d * d..(i + 1) * d * d];
            for a in 0..d {
                for c in 0..d {
                    let id = if a == c { 1.0 + eps } else { 0.0 };
                    rows.push(i * d + a);
                    cols.push(i * d + c);
                    vals.push(id - db[a * d + c]);
                }
                for bb in 0..d {
                    let dab = db[a * d + bb];
                    if dab == 0.0 {
                        continue;
                    }
                    let row = i * d + bb;
                    for q in wt.col_ptr[row]..wt.col_ptr[row + 1] {
                        rows.push(i * d + a);
                        cols.push(wt.row_idx[q]);
                        vals.push(rho[i] * dab * wt.values[q]);
                    }
                }
            }
        }
        let jm = CscMatrix::from_triplets(m, m, &rows, &cols, &vals).unwrap();
        let Ok(lu) = to_faer(&jm).sp_lu() else {
            println!("nsf: LU failed");
            break;
        };
        // dr/ds: J X = −ρ D E (column i: −ρᵢ Dᵢ e_N in the rows of contact i)
        let mut x = vec![0.0; m * n];
        for i in 0..n {
            for a in 0..d {
                x[i * m + i * d + a] = -rho[i] * dbl[i * d * d + a * d];
            }
        }
        lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, m, n));
        // J_F[i, j] = μᵢ t̂ᵢᵀ (W X + E)_{T,i} e_j
        let mut jf = vec![0.0; n * n]; // row-major
        let mut col = vec![0.0; m];
        let uu = p.velocity(&r);
        for j in 0..n {
            col.iter_mut().for_each(|c| *c = 0.0);
            p.w.gemv_acc(1.0, &x[j * m..(j + 1) * m], &mut col);
            for i in 0..n {
                let ut_i = &uu[i * d + 1..(i + 1) * d];
                let t = ut_i.iter().map(|v| v * v).sum::<f64>().sqrt();
                if t <= 1e-14 || p.mu[i] == 0.0 {
                    continue;
                }
                let dot: f64 = (1..d).map(|k| ut_i[k - 1] / t * col[i * d + k]).sum();
                jf[i * n + j] = p.mu[i] * dot;
            }
        }
        // (I − J_F) ds = −(s − F)
        let mut a = faer::Mat::<f64>::zeros(n, n);
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] = if i == j { 1.0 } else { 0.0 } - jf[i * n + j];
            }
        }
        let mut rhs = faer::Mat::<f64>::zeros(n, 1);
        for i in 0..n {
            rhs[(i, 0)] = f[i] - s[i];
        }
        let ds = a.partial_piv_lu().solve(&rhs);
        if std::env::var("NSF_FD").is_ok() {
            // finite-difference check of (I − J_F) ds
            let sn = s.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-3);
            let dn = (0..n).map(|i| ds[(i, 0)] * ds[(i, 0)]).sum::<f64>().sqrt();
            for h in [1e-3, 1e-5] {
                let hh = h * sn / dn;
                let st: Vec<f64> = (0..n).map(|i| s[i] + hh * ds[(i, 0)]).collect();
                let mut rt = vec![0.0; m];
                let (ft, _) = eval_f(p, &mut ipm, &st, &mut rt);
                let (mut num, mut den, mut dif) = (0.0, 0.0, 0.0);
                for i in 0..n {
                    let fd = ((st[i] - ft[i]) - (s[i] - f[i])) / hh;
                    let pred = f[i] - s[i]; // (I − J_F) ds = −G
                    num += fd * pred;
                    den += pred * pred;
                    dif += (fd - pred) * (fd - pred);
                }
                println!(
                    "  FD h {h:.0e}: <fd,pred>/|pred|² {:.3} |fd − pred|/|pred| {:.3}",
                    num / den,
                    (dif / den).sqrt()
                );
            }
        }
        // backtracking on |G|
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..(if adaptive { 5 } else { 8 }) {
            let st: Vec<f64> = (0..n)
                .map(|i| (s[i] + alpha * ds[(i, 0)]).max(0.0))
                .collect();
            let mut rt = vec![0.0; m];
            let (ft, bt) = eval_f(p, &mut ipm, &st, &mut rt);
            let gt = gnorm(&st, &ft);
            let et = err(p, &rt);
            if log {
                println!("  try α {alpha:.3} |G| {gt:.3e} err {et:.3e}");
            }
            if et < best.0 {
                best = (et, rt.clone());
            }
            if gt < (1.0 - 1e-4 * alpha) * g {
                s = st;
                f = ft;
                b = bt;
                r = rt;
                g = gt;
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        println!(
            "nsf {k}: |G| {g:.3e} err(r(s)) {:.3e} best {:.3e} α {alpha:.3} ε {eps_rel:.0e} ({:.2}s){}",
            err(p, &r),
            best.0,
            t0.elapsed().as_secs_f64(),
            if accepted { "" } else { " no decrease" }
        );
        if !adaptive {
            if !accepted {
                break;
            }
        } else if accepted {
            if alpha == 1.0 {
                eps_rel = (eps_rel * 0.1).max(1e-10);
            }
        } else {
            eps_rel *= 10.0;
            if eps_rel > 10.0 {
                break;
            }
        }
    }
    println!(
        "nsf end: best err {:.3e} in {:.2}s, |r_best| / |r_start| = {:.2e}",
        best.0,
        t0.elapsed().as_secs_f64(),
        coulomb::law::norm(&best.1) / r0norm
    );
}
