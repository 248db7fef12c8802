//! The position correction of a rigid step ([`correct_positions`]): projected Gauss–Seidel
//! on the normal rows' displacements, sequential (its result depends on the order of the
//! rows, so it stays one loop in contact order: the same bits on any number of threads).
//! Each row's normal Jacobian rows and its bodies' masses are gathered once into a compact
//! table (about a third of a [`nsgs::Row`]'s bytes), which the sweeps read instead of the
//! rows themselves; the arithmetic is that of the plain loop over the rows, operation by
//! operation (test `the_compact_correction_is_the_plain_loop_bit_for_bit`).

use super::nsgs;

/// One side of a row in the correction: (body block, J_N on its 6 dofs).
type Side = (usize, [f64; 6]);

/// The position correction of a step (`RigidSettings::position_correction`), the sphere
/// scenes' projection (`crate::projection`) for bodies of any shape: when some contact's end
/// gap g_i (linearized along its normal: g_k + h((1 − θ) u_{N,k} + θ u_{N,k+1})) is below
/// −`trigger`, the displacements Δq = M⁻¹ H_Nᵀ λ (translations and body-frame rotations, the
/// metric of M) with λ ≥ 0 that bring every g_i + (H_Nᵀ Δq)_i to ≥ 0, by projected
/// Gauss–Seidel on λ until every gap is ≥ −`target` (at most 200 sweeps). Positions only: the
/// velocities and the impulses are untouched, so the correction carries no load (the
/// impulses written out balance the weight). None when nothing is below −`trigger`; else the
/// displacements and the sweeps done (at most `max_sweeps`). The constraints are the rows of
/// `problem` then those of `extra` (points outside the index set), `end_gaps` in that order.
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
    let mut dq = vec![[0.0; 6]; mass.len()];
    let mut lambda = vec![0.0; end_gaps.len()];
    // per row: its sides (A then B, as `row.a.iter().chain(row.b.iter())`), then w_i
    let side = |s: &Option<(usize, [[f64; 6]; 3])>| s.as_ref().map(|(blk, j)| (*blk, j[0]));
    let rows: Vec<[Option<Side>; 2]> = problem
        .rows
        .iter()
        .chain(extra.iter().copied())
        .map(|row| [side(&row.a), side(&row.b)])
        .collect();
    let w: Vec<f64> = rows
        .iter()
        .map(|sides| {
            sides
                .iter()
                .flatten()
                .map(|(blk, j)| (0..6).map(|d| j[d] * j[d] / mass[*blk][d]).sum::<f64>())
                .sum()
        })
        .collect();
    let mut sweeps = 0;
    while sweeps < max_sweeps {
        sweeps += 1;
        let mut worst: f64 = 0.0;
        for (i, sides) in rows.iter().enumerate() {
            if w[i].is_nan() || w[i] <= 0.0 {
                continue;
            }
            let mut g = end_gaps[i];
            for (blk, j) in sides.iter().flatten() {
                g += (0..6).map(|d| j[d] * dq[*blk][d]).sum::<f64>();
            }
            worst = worst.max(-g);
            let new = (lambda[i] - g / w[i]).max(0.0);
            let delta = new - lambda[i];
            if delta != 0.0 {
                lambda[i] = new;
                for (blk, j) in sides.iter().flatten() {
                    for d in 0..6 {
                        dq[*blk][d] += j[d] * delta / mass[*blk][d];
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The correction as it was written before the compact table: the plain loop over the
    /// rows (the reference).
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
            for (i, row) in rows.iter().enumerate() {
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

    #[test]
    fn the_compact_correction_is_the_plain_loop_bit_for_bit() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(52);
        let mut corrected = 0;
        for case in 0..20 {
            let bodies = 3 + case % 9;
            let mass: Vec<[f64; 6]> = (0..bodies)
                .map(|_| std::array::from_fn(|d| rng.random_range(0.5..2.0) * (1.0 + d as f64)))
                .collect();
            let rows = random_rows(&mut rng, 4 + 3 * case, bodies);
            let f = vec![[0.0; 6]; bodies];
            let problem = nsgs::Problem::new(rows, mass, f).expect("positive definite blocks");
            let extra_rows = random_rows(&mut rng, case % 5, bodies);
            let extra: Vec<&nsgs::Row> = extra_rows.iter().collect();
            let n = problem.rows.len() + extra.len();
            let gaps: Vec<f64> = (0..n).map(|_| rng.random_range(-1e-2..1e-3)).collect();
            for (trigger, target, max_sweeps) in [(1e-4, 1e-5, 200), (0.0, 0.0, 7)] {
                let a = correct_positions(&problem, &extra, &gaps, trigger, target, max_sweeps);
                let b = plain(&problem, &extra, &gaps, trigger, target, max_sweeps);
                let bits = |x: &Option<(Vec<[f64; 6]>, usize)>| {
                    x.as_ref().map(|(dq, s)| {
                        let v: Vec<u64> = dq.iter().flatten().map(|x| x.to_bits()).collect();
                        (v, *s)
                    })
                };
                assert_eq!(bits(&a), bits(&b), "case {case}");
                if let Some((dq, _)) = &a {
                    assert!(dq.iter().flatten().any(|x| *x != 0.0), "case {case}");
                    corrected += 1;
                }
            }
        }
        // the comparison is not vacuous: most cases move bodies
        assert!(corrected >= 30, "{corrected}");
    }
}
