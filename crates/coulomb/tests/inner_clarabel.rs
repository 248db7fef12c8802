//! Clarabel-based inner solvers: the dual (4.7) by interior point, the primal (3.15), and the
//! faceted QP of option (iv), checked against the optimality conditions (3.14) and against
//! each other on random strongly convex problems.

use coulomb::cone;
use coulomb::delassus::Delassus;
use coulomb::inner::faceted::FacetedSolver;
use coulomb::inner::ipm::{solve_primal, solve_primal_polished, IpmSolver};
use coulomb::inner::{InnerLimits, InnerProblem, InnerSolver, InnerStatus};
use coulomb::problem::GlobalProblem;
use coulomb::sparse::CscMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn limits() -> InnerLimits {
    InnerLimits {
        tol: 1e-10,
        max_iterations: 200,
        deadline: coulomb::deadline::Deadline::NEVER,
    }
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Dense row-major G (rows × cols) with entries uniform in [−1, 1].
fn random_dense(rng: &mut ChaCha8Rng, rows: usize, cols: usize) -> Vec<f64> {
    (0..rows * cols)
        .map(|_| rng.random_range(-1.0..1.0))
        .collect()
}

/// A random SPD matrix GᵀG/n + δ I of size n (row-major dense).
fn random_spd(rng: &mut ChaCha8Rng, n: usize, delta: f64) -> Vec<f64> {
    let g = random_dense(rng, n, n);
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let s: f64 = (0..n).map(|k| g[k * n + i] * g[k * n + j]).sum();
            a[i * n + j] = s / n as f64 + if i == j { delta } else { 0.0 };
        }
    }
    a
}

/// Friction coefficients in [0, 1], with every fourth one exactly 0.
fn random_mu(rng: &mut ChaCha8Rng, contacts: usize) -> Vec<f64> {
    (0..contacts)
        .map(|i| {
            if i % 4 == 1 {
                0.0
            } else {
                rng.random_range(0.0..1.0)
            }
        })
        .collect()
}

/// Distance of x to the product cone L = ∏ K_{μⁱ} (dual = false) or L* (dual = true).
fn cone_distance(dim: usize, mu: &[f64], x: &[f64], dual: bool) -> f64 {
    let mut p = x.to_vec();
    if dual {
        cone::project_product_dual(dim, mu, &mut p);
    } else {
        cone::project_product(dim, mu, &mut p);
    }
    dist(&p, x)
}

/// KKT residual of (4.7) at r, relative to max(1, ‖b‖, ‖r‖): the largest of dist(r, L),
/// dist(ũ, L*) and |rᵀũ|, with ũ = W r + b.
fn kkt_residual(dim: usize, w: &CscMatrix, b: &[f64], mu: &[f64], r: &[f64]) -> f64 {
    let mut u = b.to_vec();
    w.gemv_acc(1.0, r, &mut u);
    let scale = 1.0_f64.max(norm(b)).max(norm(r));
    let primal = cone_distance(dim, mu, r, false);
    let dual = cone_distance(dim, mu, &u, true);
    let comp = dot(r, &u).abs() / scale;
    primal.max(dual).max(comp) / scale
}

/// Natural-map residual ‖r − P_L(r − ũ)‖ / max(1, ‖b‖, ‖r‖) of (4.7), ũ = W r + b.
fn natural_residual(dim: usize, w: &CscMatrix, b: &[f64], mu: &[f64], r: &[f64]) -> f64 {
    let mut u = b.to_vec();
    w.gemv_acc(1.0, r, &mut u);
    let mut p: Vec<f64> = r.iter().zip(&u).map(|(x, y)| x - y).collect();
    cone::project_product(dim, mu, &mut p);
    dist(r, &p) / 1.0_f64.max(norm(b)).max(norm(r))
}

struct RandomDual {
    dim: usize,
    w: CscMatrix,
    b: Vec<f64>,
    mu: Vec<f64>,
}

fn random_dual(seed: u64, dim: usize) -> RandomDual {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let contacts = rng.random_range(3..=20);
    let m = dim * contacts;
    let w = CscMatrix::from_dense(m, m, &random_spd(&mut rng, m, 0.05));
    let b = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mu = random_mu(&mut rng, contacts);
    RandomDual { dim, w, b, mu }
}

#[test]
fn ipm_dual_satisfies_kkt_of_4_7() {
    for dim in [2, 3] {
        for seed in 0..15 {
            let p = random_dual(100 * dim as u64 + seed, dim);
            let problem = InnerProblem {
                dim: p.dim,
                w: &p.w,
                b: &p.b,
                mu: &p.mu,
            };
            // plain Clarabel, no polish
            let mut r = vec![0.0; p.b.len()];
            let report = IpmSolver::with_polish(0).solve(&problem, &limits(), &mut r);
            assert_eq!(report.status, InnerStatus::Solved, "d={dim} seed={seed}");
            assert!(report.iterations > 0 && report.iterations <= 200);
            let kkt = kkt_residual(p.dim, &p.w, &p.b, &p.mu, &r);
            assert!(kkt < 1e-7, "d={dim} seed={seed}: KKT residual {kkt:.3e}");
            let plain_natural = natural_residual(p.dim, &p.w, &p.b, &p.mu, &r);
            assert!(
                plain_natural < 1e-5,
                "d={dim} seed={seed}: {plain_natural:.3e}"
            );

            // with the default Newton polish: the natural residual drops to rounding level
            let mut r = vec![0.0; p.b.len()];
            let report = IpmSolver::new().solve(&problem, &limits(), &mut r);
            assert_eq!(report.status, InnerStatus::Solved, "d={dim} seed={seed}");
            let kkt = kkt_residual(p.dim, &p.w, &p.b, &p.mu, &r);
            assert!(kkt < 1e-7, "d={dim} seed={seed}: KKT residual {kkt:.3e}");
            let natural = natural_residual(p.dim, &p.w, &p.b, &p.mu, &r);
            assert!(
                natural < 1e-12,
                "d={dim} seed={seed}: natural residual {natural:.3e}"
            );
            assert!(report.residual < 1e-12, "{report:?}");
            // μ = 0 contacts carry no tangential impulse
            for (ri, &m) in r.chunks(dim).zip(&p.mu) {
                if m == 0.0 {
                    assert!(cone::tangent_norm(ri) < 1e-8);
                }
            }
        }
    }
}

#[test]
fn ipm_handles_singular_delassus() {
    // W = Gᵀ G with G of rank n < m (more contact components than dofs), b = Gᵀ c so that
    // (4.7) stays bounded below
    for seed in 0..5 {
        let mut rng = ChaCha8Rng::seed_from_u64(40 + seed);
        let (contacts, n) = (6, 8);
        let m = 3 * contacts;
        let g = random_dense(&mut rng, n, m);
        let mut w = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                w[i * m + j] = (0..n).map(|k| g[k * m + i] * g[k * m + j]).sum();
            }
        }
        let w = CscMatrix::from_dense(m, m, &w);
        let c: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let b: Vec<f64> = (0..m)
            .map(|i| (0..n).map(|k| g[k * m + i] * c[k]).sum::<f64>() + 0.1)
            .collect();
        let mu = random_mu(&mut rng, contacts);
        let mut r = vec![0.0; m];
        let report = IpmSolver::new().solve(
            &InnerProblem {
                dim: 3,
                w: &w,
                b: &b,
                mu: &mu,
            },
            &limits(),
            &mut r,
        );
        assert_eq!(report.status, InnerStatus::Solved, "seed={seed}");
        let kkt = kkt_residual(3, &w, &b, &mu, &r);
        assert!(kkt < 1e-7, "seed={seed}: KKT residual {kkt:.3e}");
    }
}

#[test]
fn ipm_repeated_solves_with_changing_b_stay_accurate() {
    // the fixed-point loop changes only b = q + E s; the cached Clarabel setup must follow
    let p = random_dual(7, 3);
    let mut solver = IpmSolver::new();
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    for _ in 0..5 {
        let b: Vec<f64> =
            p.b.iter()
                .map(|x| x + rng.random_range(-0.5..0.5))
                .collect();
        let mut r = vec![0.0; b.len()];
        let problem = InnerProblem {
            dim: 3,
            w: &p.w,
            b: &b,
            mu: &p.mu,
        };
        let report = solver.solve(&problem, &limits(), &mut r);
        assert_eq!(report.status, InnerStatus::Solved);
        let kkt = kkt_residual(3, &p.w, &b, &p.mu, &r);
        assert!(kkt < 1e-7, "KKT residual {kkt:.3e}");
    }
}

/// A random global problem: M SPD (n × n), H random n × m with n = m + 3 (H injective, so
/// r is unique and (3.15) is feasible for every shift), f and w random; plus a shift.
fn random_global(seed: u64, dim: usize, with_infinite_mu: bool) -> (GlobalProblem, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let contacts = rng.random_range(3..=12);
    let m = dim * contacts;
    let n = m + 3;
    let mass = CscMatrix::from_dense(n, n, &random_spd(&mut rng, n, 0.5));
    let h = CscMatrix::from_dense(n, m, &random_dense(&mut rng, n, m));
    let f: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
    let w: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mut mu = random_mu(&mut rng, contacts);
    if with_infinite_mu {
        mu[0] = f64::INFINITY;
    }
    let shift = w
        .iter()
        .map(|x| x + rng.random_range(0.0..0.5))
        .collect::<Vec<_>>();
    let problem = GlobalProblem::new(dim as i64, mass, h, f, w, mu).expect("valid problem");
    (problem, shift)
}

#[test]
fn primal_and_dual_agree_and_balance_holds() {
    for dim in [2, 3] {
        for seed in 0..10 {
            let (g, shift) = random_global(1000 * dim as u64 + seed, dim, seed % 3 == 2);
            let primal = solve_primal(&g, &shift, &limits());
            assert_eq!(
                primal.report.status,
                InnerStatus::Solved,
                "d={dim} seed={seed}"
            );
            assert_eq!(primal.v.len(), g.dofs());
            assert_eq!(primal.r.len(), g.w.len());

            // the multiplier mapping: M v = H r + f with the primal's own r
            let balance = g.balance_residual(&primal.v, &primal.r);
            assert!(balance < 1e-7, "d={dim} seed={seed}: balance {balance:.3e}");
            // (3.14): ũ = Hᵀ v + shift ∈ L*, r ∈ L, ũ ⊥ r
            let mut u = shift.clone();
            g.h.gemv_t_acc(1.0, &primal.v, &mut u);
            let scale = 1.0_f64.max(norm(&u)).max(norm(&primal.r));
            assert!(cone_distance(dim, &g.mu, &primal.r, false) < 1e-7 * scale);
            assert!(cone_distance(dim, &g.mu, &u, true) < 1e-7 * scale);
            assert!(dot(&primal.r, &u).abs() < 1e-7 * scale * scale);

            // the dual (4.7) on W = Hᵀ M⁻¹ H, b = q + (shift − w)
            let delassus = Delassus::new(&g).expect("M is SPD");
            let local = &delassus.local;
            let b: Vec<f64> = local
                .q
                .iter()
                .zip(shift.iter().zip(&g.w))
                .map(|(q, (s, w))| q + s - w)
                .collect();
            let mut r_dual = vec![0.0; b.len()];
            let report = IpmSolver::new().solve(
                &InnerProblem {
                    dim,
                    w: &local.w,
                    b: &b,
                    mu: &g.mu,
                },
                &limits(),
                &mut r_dual,
            );
            assert_eq!(report.status, InnerStatus::Solved);
            let v_dual = delassus.velocity(&g.h, &r_dual);
            let vs = 1.0_f64.max(norm(&primal.v));
            let dv = dist(&primal.v, &v_dual) / vs;
            assert!(dv < 1e-9, "d={dim} seed={seed}: |v - v_dual| = {dv:.3e}");
            let rs = 1.0_f64.max(norm(&r_dual));
            let dr = dist(&primal.r, &r_dual) / rs;
            assert!(dr < 1e-8, "d={dim} seed={seed}: |r - r_dual| = {dr:.3e}");

            // without polish both are Clarabel's own answers: agreement to IPM accuracy
            let plain = solve_primal_polished(&g, &shift, &limits(), 0);
            assert_eq!(plain.report.status, InnerStatus::Solved);
            assert!(g.balance_residual(&plain.v, &plain.r) < 1e-7);
            let dv = dist(&plain.v, &v_dual) / vs;
            assert!(
                dv < 1e-5,
                "d={dim} seed={seed}: unpolished |v - v_dual| = {dv:.3e}"
            );
        }
    }
}

#[test]
fn primal_with_fewer_dofs_than_contact_components() {
    // H not injective: r is not unique (Theorem 3.3's remark) but v(s) is
    for seed in 0..5 {
        let mut rng = ChaCha8Rng::seed_from_u64(60 + seed);
        let (dim, contacts, n) = (3, 5, 9);
        let m = dim * contacts;
        let mass = CscMatrix::from_dense(n, n, &random_spd(&mut rng, n, 0.5));
        let h = CscMatrix::from_dense(n, m, &random_dense(&mut rng, n, m));
        let f: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let w: Vec<f64> = (0..m).map(|_| rng.random_range(0.0..1.0)).collect();
        let mu = random_mu(&mut rng, contacts);
        let g = GlobalProblem::new(3, mass, h, f, w.clone(), mu).expect("valid");
        let primal = solve_primal(&g, &w, &limits());
        assert_eq!(primal.report.status, InnerStatus::Solved, "seed={seed}");
        assert!(g.balance_residual(&primal.v, &primal.r) < 1e-9);
        let delassus = Delassus::new(&g).expect("SPD");
        let mut r_dual = vec![0.0; m];
        let report = IpmSolver::new().solve(
            &InnerProblem {
                dim,
                w: &delassus.local.w,
                b: &delassus.local.q,
                mu: &g.mu,
            },
            &limits(),
            &mut r_dual,
        );
        assert_eq!(report.status, InnerStatus::Solved, "seed={seed}");
        let v_dual = delassus.velocity(&g.h, &r_dual);
        let dv = dist(&primal.v, &v_dual) / 1.0_f64.max(norm(&primal.v));
        assert!(dv < 1e-6, "seed={seed}: |v - v_dual| = {dv:.3e}");
    }
}

#[test]
fn infeasible_primal_is_reported_infeasible() {
    // one contact, H = 0: u = shift is fixed, and its normal component is negative, so no v
    // makes Hᵀ v + shift ∈ L*: C̄(s) = ∅.
    for (dim, mu) in [(3, 0.5), (3, 0.0), (2, 0.3), (3, f64::INFINITY)] {
        let n = 4;
        let h = CscMatrix::zeros(n, dim);
        let g = GlobalProblem::new(
            dim as i64,
            CscMatrix::identity(n, 2.0),
            h,
            vec![1.0; n],
            vec![0.0; dim],
            vec![mu],
        )
        .expect("valid problem");
        let mut shift = vec![0.0; dim];
        shift[0] = -1.0;
        let out = solve_primal(&g, &shift, &limits());
        assert_eq!(
            out.report.status,
            InnerStatus::Infeasible,
            "d={dim} mu={mu}"
        );

        // its dual (4.7) has W = 0 and b = shift: unbounded below on L
        let w = CscMatrix::zeros(dim, dim);
        let mut r = vec![0.0; dim];
        let report = IpmSolver::new().solve(
            &InnerProblem {
                dim,
                w: &w,
                b: &shift,
                mu: &[mu],
            },
            &limits(),
            &mut r,
        );
        assert_eq!(
            report.status,
            InnerStatus::Infeasible,
            "dual d={dim} mu={mu}"
        );
    }
}

#[test]
fn primal_rejects_inconsistent_sizes_without_panicking() {
    let (g, shift) = random_global(5, 3, false);
    let out = solve_primal(&g, &shift[1..], &limits());
    assert_eq!(out.report.status, InnerStatus::NumericalError);
    assert!(out.v.is_empty() && out.r.is_empty());
}

#[test]
fn faceted_is_exact_in_2d() {
    for seed in 0..10 {
        let p = random_dual(500 + seed, 2);
        let problem = InnerProblem {
            dim: 2,
            w: &p.w,
            b: &p.b,
            mu: &p.mu,
        };
        let mut r_ipm = vec![0.0; p.b.len()];
        let mut r_fac = vec![0.0; p.b.len()];
        assert_eq!(
            IpmSolver::new()
                .solve(&problem, &limits(), &mut r_ipm)
                .status,
            InnerStatus::Solved
        );
        let report = FacetedSolver::new(8).solve(&problem, &limits(), &mut r_fac);
        assert_eq!(report.status, InnerStatus::Solved);
        let d = dist(&r_ipm, &r_fac) / 1.0_f64.max(norm(&r_ipm));
        assert!(d < 1e-6, "seed={seed}: |r_ipm - r_faceted| = {d:.3e}");
        let kkt = kkt_residual(2, &p.w, &p.b, &p.mu, &r_fac);
        assert!(kkt < 1e-7, "seed={seed}: KKT residual {kkt:.3e}");
    }
}

#[test]
fn faceted_approaches_ipm_as_facets_grow_in_3d() {
    for seed in 0..5 {
        let mut p = random_dual(700 + seed, 3);
        // push contacts into sliding: compressive normal, large tangential free velocity
        for (i, bi) in p.b.chunks_mut(3).enumerate() {
            bi[0] = -1.0;
            bi[1] *= 3.0;
            bi[2] *= 3.0;
            p.mu[i] = p.mu[i].max(0.2);
        }
        let problem = InnerProblem {
            dim: 3,
            w: &p.w,
            b: &p.b,
            mu: &p.mu,
        };
        let mut r_ipm = vec![0.0; p.b.len()];
        assert_eq!(
            IpmSolver::new()
                .solve(&problem, &limits(), &mut r_ipm)
                .status,
            InnerStatus::Solved
        );
        let scale = 1.0_f64.max(norm(&r_ipm));
        let mut distances = Vec::new();
        for facets in [8, 32, 128] {
            let mut r = vec![0.0; p.b.len()];
            let report = FacetedSolver::new(facets).solve(&problem, &limits(), &mut r);
            assert_eq!(report.status, InnerStatus::Solved, "k={facets}");
            // inscribed pyramid: the faceted r is an admissible Coulomb force, r ∈ L
            assert!(cone_distance(3, &p.mu, &r, false) < 1e-8 * scale);
            distances.push(dist(&r, &r_ipm) / scale);
        }
        assert!(
            distances[0] > 1e-5,
            "seed={seed}: problem too easy, faceting invisible: {distances:?}"
        );
        assert!(
            distances[1] < distances[0] && distances[2] < distances[1],
            "seed={seed}: not decreasing: {distances:?}"
        );
        // the inscribed polygon's facets turn by π/k: in the sliding regime the solution
        // error is O(1/k), a factor 16 from k = 8 to 128
        assert!(
            distances[2] < distances[0] / 8.0,
            "seed={seed}: {distances:?}"
        );
    }
}

#[test]
fn faceted_solver_reuses_setup_across_b() {
    let p = random_dual(900, 3);
    let mut solver = FacetedSolver::new(16);
    let mut first = vec![0.0; p.b.len()];
    let problem = InnerProblem {
        dim: 3,
        w: &p.w,
        b: &p.b,
        mu: &p.mu,
    };
    solver.solve(&problem, &limits(), &mut first);
    let b2: Vec<f64> = p.b.iter().map(|x| -0.5 * x + 0.1).collect();
    let problem2 = InnerProblem { b: &b2, ..problem };
    let mut again = vec![0.0; p.b.len()];
    assert_eq!(
        solver.solve(&problem2, &limits(), &mut again).status,
        InnerStatus::Solved
    );
    let mut fresh = vec![0.0; p.b.len()];
    FacetedSolver::new(16).solve(&problem2, &limits(), &mut fresh);
    let d = dist(&again, &fresh) / 1.0_f64.max(norm(&fresh));
    assert!(d < 1e-6, "cached vs fresh: {d:.3e}");
    // a solver with fewer facets solves a coarser problem
    let mut coarse = vec![0.0; p.b.len()];
    assert_eq!(
        FacetedSolver::new(4)
            .solve(&problem2, &limits(), &mut coarse)
            .status,
        InnerStatus::Solved
    );
    assert!(dist(&coarse, &fresh) / 1.0_f64.max(norm(&fresh)) > 1e-6);
}
