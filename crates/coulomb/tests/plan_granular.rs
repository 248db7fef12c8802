//! The default plan on a deep pile of spheres (issue 54, item 2): a global problem of
//! granular matter gets Gauss–Seidel on Coulomb's law (pgs + fused) as its main method, says
//! why in the plan, and reaches the tolerance with the verdict recomputed here on the problem
//! as stored; a problem of the other kind keeps the settings' order.

use coulomb::evaluation;
use coulomb::plan::{StepKind, GRANULAR_MIN_CONTACTS};
use coulomb::solver::{InnerKind, OuterKind, Settings, Solver, Status};
use coulomb::{CscMatrix, GlobalProblem, Method, Problem};

const RADIUS: f64 = 0.5;
const H: f64 = 0.02;
const G: f64 = 9.81;

/// A simple cubic stack of `nx × ny × nz` unit spheres (6 dofs each, M diagonal) resting on a
/// floor, every neighbour pair and every bottom sphere on the floor in contact (μ = 0.3), with
/// gravity over one step h and a lateral velocity that varies from sphere to sphere, as the
/// global problem M v = H r + f, u = Hᵀ v + w of a Moreau–Jean step.
/// Returns the problem and the indices of the floor's contacts.
fn pile(nx: usize, ny: usize, nz: usize) -> (GlobalProblem, Vec<usize>) {
    let index = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
    let bodies = nx * ny * nz;
    let n = 6 * bodies;
    let mass = 4.0 / 3.0 * std::f64::consts::PI * RADIUS.powi(3);
    let inertia = 0.4 * mass * RADIUS * RADIUS;
    let mut m_diag = Vec::with_capacity(n);
    let mut f = Vec::with_capacity(n);
    for b in 0..bodies {
        let vx = 0.05 * (b as f64 * 0.7).sin();
        let vy = 0.05 * (b as f64 * 1.3).cos();
        m_diag.extend([mass, mass, mass, inertia, inertia, inertia]);
        f.extend([mass * vx, mass * vy, -mass * G * H, 0.0, 0.0, 0.0]);
    }
    // contacts: (body below or behind, body above or in front (None: the floor), normal)
    let mut contacts: Vec<(Option<usize>, usize, [f64; 3])> = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let b = index(x, y, z);
                if z == 0 {
                    contacts.push((None, b, [0.0, 0.0, 1.0]));
                } else {
                    contacts.push((Some(index(x, y, z - 1)), b, [0.0, 0.0, 1.0]));
                }
                if x > 0 {
                    contacts.push((Some(index(x - 1, y, z)), b, [1.0, 0.0, 0.0]));
                }
                if y > 0 {
                    contacts.push((Some(index(x, y - 1, z)), b, [0.0, 1.0, 0.0]));
                }
            }
        }
    }
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for (c, &(a, b, normal)) in contacts.iter().enumerate() {
        // a frame (n, t1, t2): t1 any unit vector orthogonal to n, t2 = n × t1
        let t1 = if normal[2] != 0.0 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 0.0, 1.0]
        };
        let frame = [normal, t1, cross(normal, t1)];
        // relative velocity at the contact point: v_b + ω_b × (−R n) − v_a − ω_a × (R n);
        // e · (ω × p) = ω · (p × e)
        let lever = RADIUS;
        for (k, e) in frame.iter().enumerate() {
            let col = 3 * c + k;
            let mut push = |body: usize, sign: f64, arm: [f64; 3]| {
                let rot = cross(arm, *e);
                for i in 0..3 {
                    if e[i] != 0.0 {
                        rows.push(6 * body + i);
                        cols.push(col);
                        vals.push(sign * e[i]);
                    }
                    if rot[i] != 0.0 {
                        rows.push(6 * body + 3 + i);
                        cols.push(col);
                        vals.push(sign * rot[i]);
                    }
                }
            };
            push(b, 1.0, normal.map(|x| -lever * x));
            if let Some(a) = a {
                push(a, -1.0, normal.map(|x| lever * x));
            }
        }
    }
    let nc = contacts.len();
    let h = CscMatrix::from_triplets(n, 3 * nc, &rows, &cols, &vals).unwrap();
    let m = CscMatrix::from_triplets(
        n,
        n,
        &(0..n).collect::<Vec<_>>(),
        &(0..n).collect::<Vec<_>>(),
        &m_diag,
    )
    .unwrap();
    let floor = (0..nc).filter(|&c| contacts[c].0.is_none()).collect();
    let p = GlobalProblem::new(3, m, h, f, vec![0.0; 3 * nc], vec![0.3; nc]).unwrap();
    (p, floor)
}

/// ‖q‖ of the Delassus vector q = Hᵀ M⁻¹ f + w of a pile (M diagonal, w = 0).
fn q_norm(p: &GlobalProblem) -> f64 {
    let q: Vec<f64> = (0..p.h.ncols)
        .map(|j| {
            (p.h.col_ptr[j]..p.h.col_ptr[j + 1])
                .map(|k| {
                    let i = p.h.row_idx[k];
                    p.h.values[k] * p.f[i] / p.m.values[p.m.col_ptr[i]]
                })
                .sum()
        })
        .collect();
    q.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[test]
fn the_default_plan_solves_a_deep_pile_by_gauss_seidel_first() {
    // 8 × 8 × 6: 384 spheres, 1 376 contacts, 2n = 4 608 > m = 4 128 (no rigid structure)
    let (p, floor) = pile(8, 8, 6);
    assert_eq!(floor.len(), 64);
    let contacts = p.mu.len();
    assert!(contacts >= GRANULAR_MIN_CONTACTS, "{contacts}");
    let settings = Settings {
        tol: 1e-4,
        ..Settings::default()
    };
    let problem = Problem::Global(p.clone());
    let mut solver = Solver::new(&problem, settings.clone()).unwrap();
    assert!(solver.structure().granular(), "{}", solver.structure());
    assert_eq!(solver.structure().m_block, Some(1));
    let plan = solver.plan(None);
    let gs = Method::new(InnerKind::Pgs, OuterKind::Fused);
    assert_eq!(plan.steps[0].kind, StepKind::Main, "{plan}");
    assert_eq!(plan.steps[0].method, Some(gs), "{plan}");
    assert_eq!(plan.steps[1].kind, StepKind::Fallback, "{plan}");
    assert_eq!(plan.steps[1].method, Some(settings.main_method()), "{plan}");
    assert!(plan.to_string().contains("granular step"), "{plan}");

    let sol = solver.solve(None).unwrap();
    assert_eq!(sol.status, Status::Converged, "error {}", sol.error);
    // the main step (Gauss–Seidel) made the converged iterate
    assert_eq!(
        sol.history.last().map(|h| h.step),
        Some(StepKind::Main),
        "{:?}",
        sol.history.iter().map(|h| h.step).collect::<Vec<_>>()
    );
    // the verdict, recomputed here on the problem as stored from the returned r and v
    let v = sol.v.as_ref().expect("a global solve returns v");
    let (_, ev) = evaluation::global(&p, v, &sol.r, q_norm(&p));
    assert!(ev.converged(settings.tol), "{:?}", ev);
    assert!(ev.measure.error <= settings.tol, "{}", ev.measure.error);
    assert!(sol.error <= settings.tol);
    // the impulses carry the pile's weight: the floor's normal impulses sum to m g h per sphere
    let floor: f64 = floor.iter().map(|&c| sol.r[3 * c]).sum();
    let mass = 4.0 / 3.0 * std::f64::consts::PI * RADIUS.powi(3);
    let weight = 384.0 * mass * G * H;
    assert!(
        (floor - weight).abs() <= 1e-2 * weight,
        "{floor} vs {weight}"
    );
}

#[test]
fn a_small_pile_and_a_chosen_method_keep_their_plan() {
    let settings = Settings {
        tol: 1e-4,
        ..Settings::default()
    };
    // 4 × 4 × 4: 64 spheres, 208 contacts: below the granular size, the settings' order
    let small = Problem::Global(pile(4, 4, 4).0);
    let solver = Solver::new(&small, settings.clone()).unwrap();
    assert!(!solver.structure().granular());
    let plan = solver.plan(None);
    assert!(plan.main_reason.is_none(), "{plan}");
    let kinds: Vec<_> = plan.steps.iter().map(|s| s.kind).collect();
    assert_eq!(
        kinds,
        [StepKind::Warmup, StepKind::Main, StepKind::Fallback],
        "{plan}"
    );
    assert_eq!(plan.steps[1].method, Some(settings.main_method()));
    // the deep pile at a tolerance tighter than GRANULAR_MIN_TOL: the settings' order
    let deep = Problem::Global(pile(8, 8, 6).0);
    let tight = Settings {
        tol: 1e-8,
        ..Settings::default()
    };
    let plan = Solver::new(&deep, tight.clone()).unwrap().plan(None);
    assert!(plan.main_reason.is_none(), "{plan}");
    assert_eq!(plan.steps[0].kind, StepKind::Warmup, "{plan}");
    assert_eq!(plan.steps[1].method, Some(tight.main_method()), "{plan}");
    // the deep pile with a method named by the caller: that method alone
    let alone = Settings {
        tol: 1e-4,
        ..Settings::method(InnerKind::Apgd, OuterKind::Anderson)
    };
    let plan = Solver::new(&deep, alone.clone()).unwrap().plan(None);
    assert_eq!(plan.steps.len(), 1, "{plan}");
    assert_eq!(plan.steps[0].method, Some(alone.main_method()));
    assert!(plan.main_reason.is_none());
}
