//! The position correction of a rigid step ([`correct_positions`]): projected Gauss–Seidel
//! on the normal rows' displacements, coloured as the sphere scenes' projection
//! (`crate::projection`): rows that share no body get one colour and are updated in parallel
//! where the colour is large, with the numbers of one after the other in colour order, so the
//! result is the same on any number of threads. Each row's normal Jacobian rows and its
//! bodies' masses are gathered once into a compact table in colour order (about a third of a
//! [`nsgs::Row`]'s bytes), which the sweeps read instead of the rows themselves (test
//! `the_coloured_correction_is_the_sequential_loop_bit_for_bit`).

use super::nsgs;
use rayon::prelude::*;

/// One side of a row in the correction: (body block, J_N on its 6 dofs).
type Side = (usize, [f64; 6]);

/// A colour with fewer rows than this is swept on one thread (the same numbers).
const PARALLEL_MIN: usize = 256;

/// One row of the correction in colour order: its sides, w_i = J_N M⁻¹ J_Nᵀ, its end gap and
/// its multiplier λ_i.
#[derive(Debug, Clone, Copy)]
struct Constraint {
    sides: [Option<Side>; 2],
    w: f64,
    gap: f64,
    lambda: f64,
}

/// The displacements Δq, shared by the updates of one colour (which touch disjoint bodies).
type Shared = nsgs::Raw<[f64; 6]>;

/// The blocks a row touches (first, second), for the colouring.
fn ends(sides: &[Option<Side>; 2]) -> (usize, Option<usize>) {
    match sides {
        [Some((a, _)), b] => (*a, b.map(|(b, _)| b)),
        [None, Some((b, _))] => (*b, None),
        [None, None] => (usize::MAX, None),
    }
}

/// One row's update: λ_i ← max(0, λ_i − g_i / w_i), g_i the end gap plus J_N Δq, Δq moved by
/// M⁻¹ J_Nᵀ Δλ_i; returns −g_i before the update (0 for a row of no weight).
///
/// # Safety
/// `dq` points to the displacements of every block of `c`, which no other update running at
/// the same time touches.
#[inline]
unsafe fn update(c: &mut Constraint, dq: Shared, mass: &[[f64; 6]]) -> f64 {
    if c.w.is_nan() || c.w <= 0.0 {
        return 0.0;
    }
    let dq = dq.get();
    let mut g = c.gap;
    for (blk, j) in c.sides.iter().flatten() {
        // SAFETY: the caller's contract
        let q = unsafe { &*dq.add(*blk) };
        g += (0..6).map(|d| j[d] * q[d]).sum::<f64>();
    }
    let new = (c.lambda - g / c.w).max(0.0);
    let delta = new - c.lambda;
    if delta != 0.0 {
        c.lambda = new;
        for (blk, j) in c.sides.iter().flatten() {
            // SAFETY: the caller's contract
            let q = unsafe { &mut *dq.add(*blk) };
            for d in 0..6 {
                q[d] += j[d] * delta / mass[*blk][d];
            }
        }
    }
    -g
}

/// The position correction of a step (`RigidSettings::position_correction`), the sphere
/// scenes' projection (`crate::projection`) for bodies of any shape: when some contact's end
/// gap g_i (linearized along its normal: g_k + h((1 − θ) u_{N,k} + θ u_{N,k+1})) is below
/// −`trigger`, the displacements Δq = M⁻¹ H_Nᵀ λ (translations and body-frame rotations, the
/// metric of M) with λ ≥ 0 that bring every g_i + (H_Nᵀ Δq)_i to ≥ 0, by projected
/// Gauss–Seidel on λ, colour by colour, until every gap is ≥ −`target` (at most `max_sweeps`
/// sweeps). Positions only: the velocities and the impulses are untouched, so the correction
/// carries no load (the impulses written out balance the weight). None when nothing is below
/// −`trigger` or a displacement is not finite; else the displacements and the sweeps done. The
/// constraints are the rows of `problem` then those of `extra` (points outside the index set),
/// `end_gaps` in that order.
pub(super) fn correct_positions(
    problem: &nsgs::Problem,
    extra: &[&nsgs::Row],
    end_gaps: &[f64],
    trigger: f64,
    target: f64,
    max_sweeps: usize,
) -> Option<(Vec<[f64; 6]>, usize)> {
    let worst = end_gaps.iter().map(|g| -g).fold(0.0, f64::max);
    if worst.is_nan() || worst <= trigger {
        return None;
    }
    let mass = &problem.mass;
    let nb = mass.len();
    // per row: its sides (A then B, as `row.a.iter().chain(row.b.iter())`)
    let side = |s: &Option<(usize, [[f64; 6]; 3])>| s.as_ref().map(|(blk, j)| (*blk, j[0]));
    let rows: Vec<[Option<Side>; 2]> = problem
        .rows
        .iter()
        .chain(extra.iter().copied())
        .map(|row| [side(&row.a), side(&row.b)])
        .take(end_gaps.len())
        .collect();
    let colouring = crate::nsgs::Colouring::greedy_pairs(rows.len(), nb, |i| ends(&rows[i]));
    if !colouring.is_valid_pairs(rows.len(), nb, |i| ends(&rows[i])) {
        return None;
    }
    let mut cons: Vec<Constraint> = colouring
        .order
        .iter()
        .map(|&i| {
            let sides = rows[i];
            let w = sides
                .iter()
                .flatten()
                .map(|(blk, j)| (0..6).map(|d| j[d] * j[d] / mass[*blk][d]).sum::<f64>())
                .sum();
            Constraint {
                sides,
                w,
                gap: end_gaps[i],
                lambda: 0.0,
            }
        })
        .collect();
    let mut dq = vec![[0.0; 6]; nb];
    let shared = nsgs::Raw(dq.as_mut_ptr());
    // SAFETY (both closures): the colouring is valid, so the rows of one colour touch
    // disjoint blocks, all in bounds
    let one = |c: &mut Constraint| unsafe { update(c, shared, mass) };
    let mut sweeps = 0;
    while sweeps < max_sweeps {
        sweeps += 1;
        let mut worst: f64 = 0.0;
        for k in 0..colouring.colours() {
            let part = &mut cons[colouring.starts[k]..colouring.starts[k + 1]];
            let w = if part.len() >= PARALLEL_MIN {
                part.par_chunks_mut(PARALLEL_MIN / 4)
                    .map(|ch| ch.iter_mut().map(one).fold(0.0, f64::max))
                    .reduce(|| 0.0, f64::max)
            } else {
                part.iter_mut().map(one).fold(0.0, f64::max)
            };
            worst = worst.max(w);
        }
        if worst <= target {
            break;
        }
    }
    dq.iter()
        .flatten()
        .all(|x| x.is_finite())
        .then_some((dq, sweeps))
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The correction as a plain loop over the rows, one after the other in the order of the
    /// greedy colouring of the rows (the reference for the coloured, parallel sweeps).
    fn plain(
        problem: &nsgs::Problem,
        extra: &[&nsgs::Row],
        end_gaps: &[f64],
        trigger: f64,
        target: f64,
        max_sweeps: usize,
    ) -> Option<(Vec<[f64; 6]>, usize)> {
        let worst = end_gaps.iter().map(|g| -g).fold(0.0, f64::max);
        if worst.is_nan() || worst <= trigger {
            return None;
        }
        let mut dq = vec![[0.0; 6]; problem.mass.len()];
        let mut lambda = vec![0.0; end_gaps.len()];
        let rows: Vec<&nsgs::Row> = problem.rows.iter().chain(extra.iter().copied()).collect();
        let colouring = crate::nsgs::Colouring::greedy_pairs(rows.len(), problem.mass.len(), |i| {
            match (&rows[i].a, &rows[i].b) {
                (Some((a, _)), b) => (*a, b.as_ref().map(|(b, _)| *b)),
                (None, Some((b, _))) => (*b, None),
                (None, None) => (usize::MAX, None),
            }
        });
        let w: Vec<f64> = rows
            .iter()
            .map(|row| {
                row.a
                    .iter()
                    .chain(row.b.iter())
                    .map(|(blk, j)| {
                        (0..6)
                            .map(|d| j[0][d] * j[0][d] / problem.mass[*blk][d])
                            .sum::<f64>()
                    })
                    .sum()
            })
            .collect();
        let mut sweeps = 0;
        while sweeps < max_sweeps {
            sweeps += 1;
            let mut worst: f64 = 0.0;
            for &i in &colouring.order {
                let row = rows[i];
                if w[i].is_nan() || w[i] <= 0.0 {
                    continue;
                }
                let mut g = end_gaps[i];
                for (blk, j) in row.a.iter().chain(row.b.iter()) {
                    g += (0..6).map(|d| j[0][d] * dq[*blk][d]).sum::<f64>();
                }
                worst = worst.max(-g);
                let new = (lambda[i] - g / w[i]).max(0.0);
                let delta = new - lambda[i];
                if delta != 0.0 {
                    lambda[i] = new;
                    for (blk, j) in row.a.iter().chain(row.b.iter()) {
                        for d in 0..6 {
                            dq[*blk][d] += j[0][d] * delta / problem.mass[*blk][d];
                        }
                    }
                }
            }
            if worst <= target {
                break;
            }
        }
        dq.iter()
            .flatten()
            .all(|x| x.is_finite())
            .then_some((dq, sweeps))
    }

    /// Random rows between `bodies` bodies (some against an obstacle, some with A fixed).
    fn random_rows(rng: &mut rand::rngs::StdRng, n: usize, bodies: usize) -> Vec<nsgs::Row> {
        let jac = |rng: &mut rand::rngs::StdRng| -> [[f64; 6]; 3] {
            std::array::from_fn(|_| std::array::from_fn(|_| rng.random_range(-1.0..1.0)))
        };
        (0..n)
            .map(|i| {
                let a = rng.random_range(0..bodies);
                let b = (a + 1 + rng.random_range(0..bodies - 1)) % bodies;
                let (ja, jb) = (jac(rng), jac(rng));
                nsgs::Row {
                    a: (i % 7 != 3).then_some((a, ja)),
                    b: (i % 3 != 0 || i % 7 == 3).then_some((b, jb)),
                    w: [0.0; 3],
                    mu: 0.5,
                }
            })
            .collect()
    }

    /// The coloured correction gives the numbers of the plain loop in colour order, bit for
    /// bit, on 1, 2 and 3 threads, for small problems (every colour on one thread) and large
    /// ones (colours of more than `PARALLEL_MIN` rows, swept in parallel); and where it
    /// stops before its sweep cap every linearized end gap is ≥ −target.
    pub fn the_coloured_correction_is_the_sequential_loop_bit_for_bit() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(52);
        let mut corrected = 0;
        let cases: Vec<(usize, usize)> = (0..20)
            .map(|case| (3 + case % 9, 4 + 3 * case))
            .chain([(3_000, 2_000), (1_500, 4_000)])
            .collect();
        for (case, &(bodies, n)) in cases.iter().enumerate() {
            let mass: Vec<[f64; 6]> = (0..bodies)
                .map(|_| std::array::from_fn(|d| rng.random_range(0.5..2.0) * (1.0 + d as f64)))
                .collect();
            let rows = random_rows(&mut rng, n, bodies);
            let f = vec![[0.0; 6]; bodies];
            let problem = nsgs::Problem::new(rows, mass, f).expect("positive definite blocks");
            let extra_rows = random_rows(&mut rng, case % 5, bodies);
            let extra: Vec<&nsgs::Row> = extra_rows.iter().collect();
            let all: Vec<&nsgs::Row> = problem.rows.iter().chain(extra.iter().copied()).collect();
            let gaps: Vec<f64> = (0..all.len())
                .map(|_| rng.random_range(-1e-2..1e-3))
                .collect();
            for (trigger, target, max_sweeps) in [(1e-4, 1e-5, 200), (0.0, 0.0, 7)] {
                let b = plain(&problem, &extra, &gaps, trigger, target, max_sweeps);
                let bits = |x: &Option<(Vec<[f64; 6]>, usize)>| {
                    x.as_ref().map(|(dq, s)| {
                        let v: Vec<u64> = dq.iter().flatten().map(|x| x.to_bits()).collect();
                        (v, *s)
                    })
                };
                for threads in [1, 2, 3] {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    let a = pool.install(|| {
                        correct_positions(&problem, &extra, &gaps, trigger, target, max_sweeps)
                    });
                    assert_eq!(bits(&a), bits(&b), "case {case}, {threads} threads");
                }
                if let Some((dq, sweeps)) = &b {
                    assert!(dq.iter().flatten().any(|x| *x != 0.0), "case {case}");
                    corrected += 1;
                    if *sweeps < max_sweeps {
                        for (row, g) in all.iter().zip(&gaps) {
                            let moved: f64 = row
                                .a
                                .iter()
                                .chain(row.b.iter())
                                .map(|(blk, j)| (0..6).map(|d| j[0][d] * dq[*blk][d]).sum::<f64>())
                                .sum();
                            assert!(g + moved >= -target * (1.0 + 1e-9), "case {case}");
                        }
                    }
                }
            }
        }
        // the comparison is not vacuous: most cases move bodies
        assert!(corrected >= 30, "{corrected}");
    }

    /// The large cases above have colours that are swept in parallel.
    pub fn large_corrections_have_parallel_colours() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let rows = random_rows(&mut rng, 2_000, 3_000);
        let colouring = crate::nsgs::Colouring::greedy_pairs(rows.len(), 3_000, |i| {
            let s = [
                rows[i].a.as_ref().map(|(b, j)| (*b, j[0])),
                rows[i].b.as_ref().map(|(b, j)| (*b, j[0])),
            ];
            ends(&s)
        });
        let largest = (0..colouring.colours())
            .map(|k| colouring.starts[k + 1] - colouring.starts[k])
            .max()
            .unwrap_or(0);
        assert!(largest >= PARALLEL_MIN, "{largest}");
    }
}
