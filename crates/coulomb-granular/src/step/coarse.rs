//! A two-level (coarse) correction of the step problem's Gauss–Seidel (issue 54, item 1):
//! the sweeps of [`crate::nsgs`] smooth the impulses locally but move a load by about one layer
//! of contacts per sweep; a coarse correction moves it through the whole pile at once.
//!
//! Aggregates: the contacts by layer of the contact graph. A sphere's level is its graph
//! distance to the floor (the obstacle contacts whose normal points up, n_z > ½); a contact's
//! level is the larger level of its spheres (an obstacle contact: its sphere's level);
//! spheres not connected to the floor form one more aggregate. `levels_per_aggregate`
//! consecutive levels form one aggregate J.
//!
//! Coarse space (3 unknowns per aggregate, a world-frame impulse δ_J): every closed contact i
//! (r_N > 0) of aggregate J receives Δr_i = s_i R_i δ_J, with R_i the rows (n, t₁, t₂) of its
//! frame and s_i = +1 when its sphere A is the upper one (higher level, or same level and
//! n_z ≥ 0; an obstacle contact: +1), −1 otherwise: the same impulse δ_J carried from the
//! layer below to the layer above by every contact of the band. Separated contacts
//! (r_N = 0) are left out. With Q that prolongation, the correction is the Galerkin
//! (energy-minimizing) one of the global problem (2.10) read as equalities on the closed rows:
//! (Qᵀ W Q) δ = −Qᵀ u, W = Hᵀ M⁻¹ H, assembled exactly as Gᵀ M⁻¹ G with G = H Q (M is
//! diagonal per sphere), a dense system of 3 × aggregates unknowns factored by Cholesky with
//! a shift of 10⁻⁹ times its diagonal. The caller projects r + α Q δ on the cones and keeps it
//! only if the error of docs/error.md on the stored problem decreased
//! ([`crate::nsgs::solve_coloured`]); every verdict stays that of the stored problem.

use crate::step::rows::ContactRow;

/// Relative shift of the coarse system's diagonal (it is singular when an aggregate has no
/// closed contact or its contacts cannot carry an impulse in some direction).
pub const SHIFT: f64 = 1e-9;

/// The most aggregates (a dense system of 3 × this many unknowns).
pub const MAX_AGGREGATES: usize = 400;

/// The aggregate of each contact, computed once per solve from the contact graph.
#[derive(Debug, Clone)]
pub struct Aggregates {
    /// aggregate of each row
    of: Vec<usize>,
    /// orientation s_i of each row
    sign: Vec<f64>,
    /// number of aggregates
    count: usize,
}

impl Aggregates {
    /// Levels of the contact graph of `rows` over `bodies` spheres, grouped by
    /// `levels_per_aggregate` (at least 1).
    pub(crate) fn new(rows: &[ContactRow], bodies: usize, levels_per_aggregate: usize) -> Self {
        let per = levels_per_aggregate.max(1);
        let mut adj: Vec<Vec<usize>> = vec![Vec::new(); bodies];
        let mut level = vec![usize::MAX; bodies];
        let mut queue = std::collections::VecDeque::new();
        for row in rows {
            match row.b {
                Some(b) if b < bodies && row.a < bodies => {
                    adj[row.a].push(b);
                    adj[b].push(row.a);
                }
                None if row.a < bodies && row.frame[0][2] > 0.5 && level[row.a] != 0 => {
                    level[row.a] = 0;
                    queue.push_back(row.a);
                }
                _ => {}
            }
        }
        while let Some(i) = queue.pop_front() {
            for &j in &adj[i] {
                if level[j] == usize::MAX {
                    level[j] = level[i] + 1;
                    queue.push_back(j);
                }
            }
        }
        let top = level
            .iter()
            .filter(|&&l| l != usize::MAX)
            .max()
            .map_or(0, |&l| l / per + 1);
        let agg = |l: usize| {
            if l == usize::MAX {
                top
            } else {
                (l / per).min(MAX_AGGREGATES - 2)
            }
        };
        let lv = |i: usize| level.get(i).copied().unwrap_or(usize::MAX);
        let mut of = Vec::with_capacity(rows.len());
        let mut sign = Vec::with_capacity(rows.len());
        for row in rows {
            let la = lv(row.a);
            match row.b {
                None => {
                    of.push(agg(la));
                    sign.push(1.0);
                }
                Some(b) => {
                    let lb = lv(b);
                    of.push(agg(la.max(lb)));
                    let upper_a = la > lb || (la == lb && row.frame[0][2] >= 0.0);
                    sign.push(if upper_a { 1.0 } else { -1.0 });
                }
            }
        }
        let count = of.iter().max().map_or(0, |&m| m + 1);
        Self { of, sign, count }
    }

    /// Number of aggregates.
    pub fn count(&self) -> usize {
        self.count
    }
}

/// The target impulses r + Q δ (rows' order, not projected on their cones) from impulses `r`
/// and velocities `v` (v = M⁻¹ (f + H r), per sphere), or `None` when no contact is closed or
/// the coarse system cannot be solved.
pub(crate) fn correction(
    rows: &[ContactRow],
    inv_mass: &[[f64; 6]],
    agg: &Aggregates,
    r: &[[f64; 3]],
    v: &[[f64; 6]],
) -> Option<Vec<[f64; 3]>> {
    let n = 3 * agg.count;
    if n == 0 || agg.of.len() != rows.len() {
        return None;
    }
    // G = H Q per (sphere, aggregate): a 6 × 3 block, accumulated contact by contact
    let mut blocks: Vec<(usize, usize, [[f64; 6]; 3])> = Vec::new();
    let mut rhs = vec![0.0; n];
    let mut any = false;
    for (i, (row, ri)) in rows.iter().zip(r).enumerate() {
        if ri[0].is_nan() || ri[0] <= 0.0 {
            continue;
        }
        any = true;
        let (j, s) = (agg.of[i], agg.sign[i]);
        let u = row.velocity(&v[row.a], row.b.map(|b| &v[b]));
        // local impulse of unit world direction d: c_d = s R e_d, c_d[k] = s frame[k][d]
        for d in 0..3 {
            rhs[3 * j + d] -= s * (0..3).map(|k| row.frame[k][d] * u[k]).sum::<f64>();
        }
        for (body, side) in [(Some(row.a), false), (row.b, true)] {
            let Some(body) = body else { continue };
            let jac = row.jacobian(side);
            let mut g = [[0.0; 6]; 3];
            for (d, gd) in g.iter_mut().enumerate() {
                for (k, jk) in jac.iter().enumerate() {
                    let c = s * row.frame[k][d];
                    for e in 0..6 {
                        gd[e] += c * jk[e];
                    }
                }
            }
            blocks.push((body, j, g));
        }
    }
    if !any {
        return None;
    }
    blocks.sort_by_key(|b| (b.0, b.1));
    // merge the blocks of one (sphere, aggregate)
    let mut merged: Vec<(usize, usize, [[f64; 6]; 3])> = Vec::with_capacity(blocks.len());
    for (body, j, g) in blocks {
        match merged.last_mut() {
            Some(last) if last.0 == body && last.1 == j => {
                for (ld, gd) in last.2.iter_mut().zip(&g) {
                    for (x, y) in ld.iter_mut().zip(gd) {
                        *x += y;
                    }
                }
            }
            _ => merged.push((body, j, g)),
        }
    }
    // A = Gᵀ M⁻¹ G, sphere by sphere
    let mut a = vec![0.0; n * n];
    let mut b0 = 0;
    while b0 < merged.len() {
        let body = merged[b0].0;
        let mut b1 = b0;
        while b1 < merged.len() && merged[b1].0 == body {
            b1 += 1;
        }
        let minv = &inv_mass[body];
        for p in b0..b1 {
            for q in b0..b1 {
                for d in 0..3 {
                    for e in 0..3 {
                        let x: f64 = (0..6)
                            .map(|k| merged[p].2[d][k] * minv[k] * merged[q].2[e][k])
                            .sum();
                        a[(3 * merged[p].1 + d) * n + 3 * merged[q].1 + e] += x;
                    }
                }
            }
        }
        b0 = b1;
    }
    let scale = (0..n).map(|p| a[p * n + p]).fold(0.0, f64::max);
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    for p in 0..n {
        a[p * n + p] += SHIFT * scale;
    }
    let delta = cholesky_solve(&mut a, rhs, n)?;
    let out = rows
        .iter()
        .zip(r)
        .enumerate()
        .map(|(i, (row, ri))| {
            let mut x = *ri;
            if ri[0].is_nan() || ri[0] <= 0.0 {
                return x;
            }
            let (j, s) = (agg.of[i], agg.sign[i]);
            for (k, xk) in x.iter_mut().enumerate() {
                *xk += s
                    * (0..3)
                        .map(|d| row.frame[k][d] * delta[3 * j + d])
                        .sum::<f64>();
            }
            x
        })
        .collect();
    Some(out)
}

/// Solves A x = b in place (A dense, row-major, symmetric positive definite), `None` when a
/// pivot is not positive or x is not finite.
fn cholesky_solve(a: &mut [f64], mut b: Vec<f64>, n: usize) -> Option<Vec<f64>> {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return None;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut x = a[i * n + j];
            for k in 0..j {
                x -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = x / d;
        }
    }
    for i in 0..n {
        for k in 0..i {
            b[i] -= a[i * n + k] * b[k];
        }
        b[i] /= a[i * n + i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            b[i] -= a[k * n + i] * b[k];
        }
        b[i] /= a[i * n + i];
    }
    b.iter().all(|x| x.is_finite()).then_some(b)
}

#[cfg(test)]
mod tests {
    use crate::assembly::StepData;
    use crate::contact::{detect, Activation};
    use crate::math::Vec3;
    use crate::nsgs::{evaluate, solve, NsgsSettings, NsgsStatus, StepProblem};
    use crate::world::{Obstacle, Shape, Sphere, World};

    /// A `nx × ny × layers` simple-cubic stack of touching spheres at rest on a floor
    /// (h = 0.02, μ = 0.5, e = 0).
    fn stack(nx: usize, ny: usize, layers: usize) -> StepProblem {
        let mut w = World::new();
        w.obstacles.push(Obstacle::fixed(
            "ground",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        let r = 0.05;
        for k in 0..layers {
            for j in 0..ny {
                for i in 0..nx {
                    let p = Vec3::new(
                        2.0 * r * i as f64,
                        2.0 * r * j as f64,
                        r + 2.0 * r * k as f64,
                    );
                    w.bodies.push(Sphere::new(p, r, 1.0));
                }
            }
        }
        let contacts = detect(&w, 0.0, 0.02, &Activation::accurate());
        let data = StepData {
            h: 0.02,
            t_end: 0.02,
            restitution: 0.0,
            mu: 0.5,
            close_gaps: true,
        };
        StepProblem::new(&w, &contacts, &data).unwrap()
    }

    /// Sweeps of plain Gauss–Seidel and with a coarse correction every `every` sweeps, cold,
    /// to `tol`; both verdicts checked on the stored problem, and both solutions close.
    fn compare(p: &StepProblem, tol: f64, every: usize) -> (usize, usize, usize) {
        let r0 = vec![0.0; 3 * p.contacts()];
        let plain = NsgsSettings {
            tol,
            time_limit: None,
            library_finish: false,
            ..NsgsSettings::default()
        };
        let two = NsgsSettings {
            coarse_every: every,
            ..plain
        };
        let a = solve(p, &r0, &plain, false);
        let b = solve(p, &r0, &two, false);
        for s in [&a, &b] {
            assert_eq!(s.status, NsgsStatus::Converged, "{s:?}");
            let (err, _, balance, _) = evaluate(p, &s.r);
            assert!(err <= tol && balance <= tol, "err {err} balance {balance}");
        }
        eprintln!(
            "{} contacts: plain {} sweeps, coarse every {every}: {} sweeps ({} corrections kept)",
            p.contacts(),
            a.sweeps,
            b.sweeps,
            b.coarse
        );
        (a.sweeps, b.sweeps, b.coarse)
    }

    #[test]
    fn the_aggregates_of_a_column_are_its_layers() {
        let p = stack(1, 1, 10);
        let agg = super::Aggregates::new(&p.rows, p.mass.len(), 1);
        assert_eq!(agg.count(), 10);
        let mut of = agg.of.clone();
        of.sort_unstable();
        assert_eq!(of, (0..10).collect::<Vec<_>>());
        assert!(agg.sign.iter().all(|&s| s == 1.0 || s == -1.0));
    }

    #[test]
    fn a_column_of_ten_spheres_converges_in_fewer_sweeps() {
        let p = stack(1, 1, 10);
        assert_eq!(p.contacts(), 10);
        let (plain, two, kept) = compare(&p, 1e-6, 5);
        assert!(kept >= 1, "no correction kept");
        assert!(2 * two <= plain, "plain {plain} sweeps, coarse {two}");
    }

    #[test]
    fn a_six_layer_stack_converges_in_fewer_sweeps() {
        let p = stack(4, 4, 6);
        assert!(p.contacts() > 100, "{}", p.contacts());
        let (plain, two, kept) = compare(&p, 1e-6, 5);
        assert!(kept >= 1, "no correction kept");
        assert!(two < plain, "plain {plain} sweeps, coarse {two}");
    }
}
