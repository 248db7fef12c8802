//! A two-level (coarse) correction of the step problem's Gauss–Seidel (issue 54, item 1):
//! the sweeps of [`crate::nsgs`] smooth the impulses locally but move a load by about one layer
//! of contacts per sweep; a coarse correction moves it through the whole pile at once.
//!
//! Two coarse spaces, each a prolongation Q from coarse unknowns (world-frame impulses δ_J,
//! 3 per coarse block J) to the contacts' impulses, Δr_i = Σ_J B_iJ δ_J:
//!
//! - *Layers* (`NsgsSettings::coarse_cell` = 0): the contacts by layer of the contact graph.
//!   A sphere's level is its graph distance to the floor (the obstacle contacts whose normal
//!   points up, n_z > ½); a contact's level is the larger level of its spheres (an obstacle
//!   contact: its sphere's level); spheres not connected to the floor form one more block.
//!   Every closed contact i of layer J carries δ_J: B_iJ = s_i R_i, with R_i the rows
//!   (n, t₁, t₂) of its frame and s_i = +1 when its sphere A is the upper one (higher level,
//!   or same level and n_z ≥ 0; an obstacle contact: +1), −1 otherwise.
//! - *Interfaces between aggregates of a coarse grid* (`coarse_cell` = k ≥ 1): the spheres
//!   are grouped by cells of a grid of side k times the mean centre distance of the
//!   sphere–sphere contacts (≈ k bead diameters); the obstacles form 6 more aggregates, one per
//!   direction (±x, ±y, ±z) of their contacts' normals. One block δ_IJ per interface (a pair of
//!   aggregates I < J that share contacts), carried by every closed contact between them:
//!   B_i = ±R_i, + when sphere A lies in I (δ_IJ is the impulse that J applies to I). The
//!   contacts inside one aggregate are not in the coarse space.
//!
//! Separated contacts (r_N = 0) are left out. `NsgsSettings::coarse_smooth` = p applies p
//! damped-Jacobi smoothing steps to the prolongation on the closed contacts
//! (smoothed aggregation): Q ← (I − ω D⁻¹ W) Q, D the diagonal blocks W_ii, ω = 4 / (3 ρ)
//! with ρ a power-iteration estimate of the spectral radius of D⁻¹ W; each step spreads a
//! block's support by one sphere, so that the blocks of neighbouring interfaces overlap.
//!
//! With Q fixed, the correction is the Galerkin (energy-minimizing) one of the global problem
//! (2.10) read as equalities on the closed rows: (Qᵀ W Q) δ = −Qᵀ u, W = Hᵀ M⁻¹ H, assembled
//! exactly as Gᵀ M⁻¹ G with G = H Q (M is diagonal per sphere), factored by a sparse
//! Cholesky (`subspace::cholesky_solve`) with a shift of 10⁻⁹ times its largest
//! diagonal entry. The caller projects r + α Q δ on the cones and keeps it only if the error
//! of docs/error.md on the stored problem decreased ([`crate::nsgs::solve_coloured`]); every
//! verdict stays that of the stored problem.

use crate::step::rows::ContactRow;
use faer::sparse::Triplet;
use std::collections::BTreeMap;

/// Relative shift of the coarse system's diagonal (it is singular when a block's contacts
/// cannot carry an impulse in some direction).
pub const SHIFT: f64 = 1e-9;

/// The most layer blocks of the layer space.
pub const MAX_AGGREGATES: usize = 400;

/// The most coarse unknowns (3 per block); above it no correction is tried.
pub const MAX_UNKNOWNS: usize = 600_000;

/// Power iterations of the estimate of ρ(D⁻¹ W) (smoothed prolongations only).
pub const POWER_ITERATIONS: usize = 20;

/// A coarse space, computed once per solve from the contact graph (and the spheres' positions).
#[derive(Debug, Clone)]
pub struct Aggregates {
    /// (row, block, s): row `row` carries s R_row δ_block, sorted by row
    entries: Vec<(usize, usize, f64)>,
    /// number of blocks
    count: usize,
    /// smoothing steps of the prolongation
    smooth: usize,
    /// damping ω of the smoothing
    omega: f64,
}

impl Aggregates {
    /// Levels of the contact graph of `rows` over `bodies` spheres, grouped by
    /// `levels_per_aggregate` (at least 1): one block per group of levels.
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
            .map_or(0, |&l| l / per + 1)
            .min(MAX_AGGREGATES - 1);
        let agg = |l: usize| {
            if l == usize::MAX {
                top
            } else {
                (l / per).min(MAX_AGGREGATES - 2)
            }
        };
        let lv = |i: usize| level.get(i).copied().unwrap_or(usize::MAX);
        let mut entries = Vec::with_capacity(rows.len());
        for (i, row) in rows.iter().enumerate() {
            let la = lv(row.a);
            match row.b {
                None => entries.push((i, agg(la), 1.0)),
                Some(b) => {
                    let lb = lv(b);
                    let upper_a = la > lb || (la == lb && row.frame[0][2] >= 0.0);
                    entries.push((i, agg(la.max(lb)), if upper_a { 1.0 } else { -1.0 }));
                }
            }
        }
        let count = entries.iter().map(|e| e.1 + 1).max().unwrap_or(0);
        Self {
            entries,
            count,
            smooth: 0,
            omega: 0.0,
        }
    }

    /// Interfaces between aggregates of a grid of cells of side `side` mean contact
    /// distances (≈ bead diameters) over the spheres at `position` (see the module's text).
    /// Empty (no block) when `side` is 0 or a position is missing or not finite.
    pub(crate) fn cells(rows: &[ContactRow], position: &[[f64; 3]], side: usize) -> Self {
        let empty = Self {
            entries: Vec::new(),
            count: 0,
            smooth: 0,
            omega: 0.0,
        };
        let bodies = position.len();
        let valid = |i: usize| i < bodies && position[i].iter().all(|x| x.is_finite());
        if side == 0
            || rows
                .iter()
                .any(|r| !valid(r.a) || r.b.is_some_and(|b| !valid(b)))
        {
            return empty;
        }
        // the length scale: mean centre distance of the sphere–sphere contacts, else twice
        // the mean arm of the obstacle contacts
        let (mut sum, mut n) = (0.0, 0usize);
        for row in rows {
            if let Some(b) = row.b {
                let (pa, pb) = (position[row.a], position[b]);
                sum += (0..3).map(|k| (pa[k] - pb[k]).powi(2)).sum::<f64>().sqrt();
                n += 1;
            }
        }
        if n == 0 {
            for row in rows {
                sum += 2.0 * row.arm_a.iter().map(|x| x * x).sum::<f64>().sqrt();
                n += 1;
            }
        }
        let length = side as f64 * sum / n.max(1) as f64;
        if !(length > 0.0 && length.is_finite()) {
            return empty;
        }
        let key = |i: usize| position[i].map(|x| (x / length).floor() as i64);
        let mut cells: BTreeMap<[i64; 3], usize> = BTreeMap::new();
        for row in rows {
            cells.insert(key(row.a), 0);
            if let Some(b) = row.b {
                cells.insert(key(b), 0);
            }
        }
        for (id, v) in cells.values_mut().enumerate() {
            *v = id;
        }
        let obstacle = |n: &[f64; 3]| {
            let axis = (0..3)
                .max_by(|&p, &q| n[p].abs().total_cmp(&n[q].abs()))
                .unwrap_or(2);
            cells.len() + 2 * axis + usize::from(n[axis] < 0.0)
        };
        // (row, interface key, sign)
        let mut raw: Vec<(usize, (usize, usize), f64)> = Vec::new();
        for (i, row) in rows.iter().enumerate() {
            let ia = cells[&key(row.a)];
            let ib = match row.b {
                Some(b) => cells[&key(b)],
                None => obstacle(&row.frame[0]),
            };
            if ia != ib {
                let s = if ia < ib { 1.0 } else { -1.0 };
                raw.push((i, (ia.min(ib), ia.max(ib)), s));
            }
        }
        let mut interfaces: BTreeMap<(usize, usize), usize> =
            raw.iter().map(|e| (e.1, 0)).collect();
        for (id, v) in interfaces.values_mut().enumerate() {
            *v = id;
        }
        if 3 * interfaces.len() > MAX_UNKNOWNS {
            return empty;
        }
        Self {
            entries: raw.iter().map(|e| (e.0, interfaces[&e.1], e.2)).collect(),
            count: interfaces.len(),
            smooth: 0,
            omega: 0.0,
        }
    }

    /// The same space with `steps` damped-Jacobi smoothing steps of its prolongation, ω from
    /// a power-iteration estimate of ρ(D⁻¹ W) over all `rows`.
    pub(crate) fn smoothed(
        mut self,
        rows: &[ContactRow],
        inv_mass: &[[f64; 6]],
        steps: usize,
    ) -> Self {
        self.smooth = steps;
        if steps > 0 {
            let rho = spectral_radius(rows, inv_mass);
            self.omega = if rho > 0.0 && rho.is_finite() {
                4.0 / (3.0 * rho)
            } else {
                0.0
            };
        }
        self
    }

    /// Number of coarse blocks (3 unknowns each).
    pub fn count(&self) -> usize {
        self.count
    }
}

/// Momentum H x of contact impulses `x` (rows' order), per sphere.
fn momentum(rows: &[ContactRow], bodies: usize, x: &[[f64; 3]]) -> Vec<[f64; 6]> {
    let mut y = vec![[0.0; 6]; bodies];
    for (row, xi) in rows.iter().zip(x) {
        for (body, side) in [(Some(row.a), false), (row.b, true)] {
            let Some(body) = body else { continue };
            let jac = row.jacobian(side);
            for (k, jk) in jac.iter().enumerate() {
                for e in 0..6 {
                    y[body][e] += jk[e] * xi[k];
                }
            }
        }
    }
    y
}

/// A power-iteration estimate of ρ(D⁻¹ W), D the diagonal blocks W_ii (a fixed start, a
/// fixed number of iterations: the same bits on every run), 5 % above the last ratio.
fn spectral_radius(rows: &[ContactRow], inv_mass: &[[f64; 6]]) -> f64 {
    let bodies = inv_mass.len();
    if rows
        .iter()
        .any(|r| r.a >= bodies || r.b.is_some_and(|b| b >= bodies))
    {
        return f64::NAN;
    }
    let mut x: Vec<[f64; 3]> = (0..rows.len())
        .map(|i| [1.0 + 0.1 * (i % 7) as f64, 0.3, 0.2])
        .collect();
    let norm = |x: &[[f64; 3]]| x.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    let mut rho = f64::NAN;
    for _ in 0..POWER_ITERATIONS {
        let n0 = norm(&x);
        if !(n0 > 0.0 && n0.is_finite()) {
            return f64::NAN;
        }
        let mut y = momentum(rows, bodies, &x);
        for (yb, m) in y.iter_mut().zip(inv_mass) {
            for e in 0..6 {
                yb[e] *= m[e];
            }
        }
        for (row, xi) in rows.iter().zip(x.iter_mut()) {
            let u = row.velocity(&y[row.a], row.b.map(|b| &y[b]));
            let u = [u[0] - row.w[0], u[1] - row.w[1], u[2] - row.w[2]];
            *xi = std::array::from_fn(|k| (0..3).map(|l| row.w_inv[3 * k + l] * u[l]).sum());
        }
        rho = norm(&x) / n0;
    }
    1.05 * rho
}

/// G = H Q per (sphere, block): 6 × 3 blocks (stored as 3 rows of 6), sorted by sphere then
/// block, those of one pair merged.
fn prolongate(
    rows: &[ContactRow],
    q: &[(usize, usize, [[f64; 3]; 3])],
) -> Vec<(usize, usize, [[f64; 6]; 3])> {
    let mut blocks: Vec<(usize, usize, [[f64; 6]; 3])> = Vec::with_capacity(2 * q.len());
    for (i, j, b) in q {
        let row = &rows[*i];
        for (body, side) in [(Some(row.a), false), (row.b, true)] {
            let Some(body) = body else { continue };
            let jac = row.jacobian(side);
            let mut g = [[0.0; 6]; 3];
            for (d, gd) in g.iter_mut().enumerate() {
                for (k, jk) in jac.iter().enumerate() {
                    let c = b[k][d];
                    for e in 0..6 {
                        gd[e] += c * jk[e];
                    }
                }
            }
            blocks.push((body, *j, g));
        }
    }
    blocks.sort_by_key(|b| (b.0, b.1));
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
    merged
}

/// One damped-Jacobi step Q ← Q − ω D⁻¹ W Q on the closed rows (`closed`).
fn smooth(
    rows: &[ContactRow],
    inv_mass: &[[f64; 6]],
    closed: &[bool],
    q: Vec<(usize, usize, [[f64; 3]; 3])>,
    omega: f64,
) -> Vec<(usize, usize, [[f64; 3]; 3])> {
    let bodies = inv_mass.len();
    let mut g = prolongate(rows, &q);
    for (body, _, gb) in &mut g {
        for gd in gb.iter_mut() {
            for e in 0..6 {
                gd[e] *= inv_mass[*body][e];
            }
        }
    }
    let mut start = vec![0usize; bodies + 1];
    for (body, _, _) in &g {
        start[body + 1] += 1;
    }
    for b in 0..bodies {
        start[b + 1] += start[b];
    }
    let mut out: BTreeMap<(usize, usize), [[f64; 3]; 3]> =
        q.into_iter().map(|(i, j, b)| ((i, j), b)).collect();
    let mut wq: BTreeMap<(usize, usize), [[f64; 3]; 3]> = BTreeMap::new();
    for (i, row) in rows.iter().enumerate() {
        if !closed[i] {
            continue;
        }
        for (body, side) in [(Some(row.a), false), (row.b, true)] {
            let Some(body) = body else { continue };
            let jac = row.jacobian(side);
            for (_, j, mg) in &g[start[body]..start[body + 1]] {
                let acc = wq.entry((i, *j)).or_insert([[0.0; 3]; 3]);
                for (k, jk) in jac.iter().enumerate() {
                    for (d, mgd) in mg.iter().enumerate() {
                        acc[k][d] += (0..6).map(|e| jk[e] * mgd[e]).sum::<f64>();
                    }
                }
            }
        }
    }
    for ((i, j), a) in wq {
        let winv = &rows[i].w_inv;
        let b = out.entry((i, j)).or_insert([[0.0; 3]; 3]);
        for k in 0..3 {
            for d in 0..3 {
                b[k][d] -= omega * (0..3).map(|l| winv[3 * k + l] * a[l][d]).sum::<f64>();
            }
        }
    }
    out.into_iter().map(|((i, j), b)| (i, j, b)).collect()
}

/// The target impulses r + Q δ (rows' order, not projected on their cones) from impulses `r`
/// and velocities `v` (v = M⁻¹ (f + H r), per sphere), or `None` when no contact of the
/// coarse space is closed or the coarse system cannot be solved.
pub(crate) fn correction(
    rows: &[ContactRow],
    inv_mass: &[[f64; 6]],
    agg: &Aggregates,
    r: &[[f64; 3]],
    v: &[[f64; 6]],
) -> Option<Vec<[f64; 3]>> {
    let bodies = inv_mass.len();
    if agg.count == 0
        || r.len() != rows.len()
        || v.len() != bodies
        || agg.entries.iter().any(|e| e.0 >= rows.len())
        || rows
            .iter()
            .any(|r| r.a >= bodies || r.b.is_some_and(|b| b >= bodies))
    {
        return None;
    }
    let closed: Vec<bool> = r.iter().map(|ri| ri[0] > 0.0).collect();
    let mut q: Vec<(usize, usize, [[f64; 3]; 3])> = agg
        .entries
        .iter()
        .filter(|e| closed[e.0])
        .map(|&(i, j, s)| (i, j, rows[i].frame.map(|f| f.map(|x| s * x))))
        .collect();
    if q.is_empty() {
        return None;
    }
    // number the blocks that have a closed contact
    let mut used = vec![usize::MAX; agg.count];
    let mut n = 0;
    for e in &q {
        if used[e.1] == usize::MAX {
            used[e.1] = n;
            n += 1;
        }
    }
    for e in &mut q {
        e.1 = used[e.1];
    }
    let n3 = 3 * n;
    for _ in 0..agg.smooth {
        if agg.omega > 0.0 {
            q = smooth(rows, inv_mass, &closed, q, agg.omega);
        }
    }
    let mut rhs = vec![0.0; n3];
    let mut u_of: Vec<Option<[f64; 3]>> = vec![None; rows.len()];
    for (i, j, b) in &q {
        let row = &rows[*i];
        let u = *u_of[*i].get_or_insert_with(|| row.velocity(&v[row.a], row.b.map(|b| &v[b])));
        for d in 0..3 {
            rhs[3 * j + d] -= (0..3).map(|k| b[k][d] * u[k]).sum::<f64>();
        }
    }
    // A = Gᵀ M⁻¹ G sphere by sphere, lower triangle
    let g = prolongate(rows, &q);
    let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
    let mut diag = vec![0.0; n3];
    let mut b0 = 0;
    while b0 < g.len() {
        let body = g[b0].0;
        let mut b1 = b0;
        while b1 < g.len() && g[b1].0 == body {
            b1 += 1;
        }
        let minv = &inv_mass[body];
        for p in b0..b1 {
            for c in b0..=p {
                for d in 0..3 {
                    for e in 0..3 {
                        let (row, col) = (3 * g[p].1 + d, 3 * g[c].1 + e);
                        if col > row {
                            continue;
                        }
                        let x: f64 = (0..6).map(|k| g[p].2[d][k] * minv[k] * g[c].2[e][k]).sum();
                        if row == col {
                            diag[row] += x;
                        }
                        trip.push(Triplet::new(row, col, x));
                    }
                }
            }
        }
        b0 = b1;
    }
    let scale = diag.iter().copied().fold(0.0, f64::max);
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    for p in 0..n3 {
        trip.push(Triplet::new(p, p, SHIFT * scale));
    }
    crate::subspace::cholesky_solve(n3, trip, &mut rhs)?;
    let mut out = r.to_vec();
    for (i, j, b) in &q {
        for k in 0..3 {
            out[*i][k] += (0..3).map(|d| b[k][d] * rhs[3 * j + d]).sum::<f64>();
        }
    }
    Some(out)
}

#[cfg(feature = "unit-tests")]
pub mod tests;
