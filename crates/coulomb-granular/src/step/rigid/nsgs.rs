//! The body-level nonsmooth Gauss–Seidel of [`super::RigidWorld::step`] for bodies of
//! any inertia: per contact, J_A and J_B (3 × 6 each, rows (t_k, Rᵀ(a × t_k))), w_i, μ_i
//! and W_ii = J_A M_A⁻¹ J_Aᵀ + J_B M_B⁻¹ J_Bᵀ; M diagonal per body in the principal
//! frame. The error of docs/error.md is always evaluated on the stored
//! (M, H, f, w, μ): v = M⁻¹(f + H r) recomputed from r, u = Hᵀ v + w,
//! q = Hᵀ M⁻¹ f + w.

use crate::bodies::joints::{JointRow, RowKind};
use crate::nsgs::relaxed_contact_law;
use coulomb::law;
use coulomb::problem::{GlobalProblem, ProblemError};
use coulomb::sparse::CscMatrix;

/// Whether a joint row with multiplier l is a row of G in the stored problem.
fn stored_row(kind: RowKind, l: f64) -> bool {
    match kind {
        RowKind::Equality => true,
        RowKind::Box(lo, hi) => l > lo && l < hi,
        RowKind::Unilateral => l > 0.0,
    }
}

/// Exact error evaluations: every this many sweeps.
pub const CHECK_EVERY: usize = 5;

/// A problem with at least this many contacts evaluates v = M⁻¹(f + H r + G λ) and
/// u = Hᵀ v + w in parallel (rayon), [`EVAL_CHUNK`] bodies or contacts per task: each
/// body's velocity gathers its own contacts in contact order, each contact's u is its
/// own, so the numbers are those of the sequential loops whatever the number of threads.
/// Below it (under ~10 µs of work) the evaluation stays on one thread.
pub const EVAL_PARALLEL_MIN: usize = 128;

/// Bodies (for v) or contacts (for u) per task of a parallel evaluation: a constant,
/// never a function of the number of threads.
pub const EVAL_CHUNK: usize = 64;

/// A step whose joints have at least this many equality rows in all solves them together
/// in each sweep (W_EE factored once per step, `rigid::step::equality`); below it, joint by
/// joint (the block solve of [`Problem::solve`]'s per-joint update).
pub const GLOBAL_EQUALITY_MIN_ROWS: usize = 1;

/// One contact: (body block, J) per side, w, μ.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// A's block index and J_A (None: A fixed)
    pub a: Option<(usize, [[f64; 6]; 3])>,
    /// B's block index and J_B (None: obstacle or fixed body)
    pub b: Option<(usize, [[f64; 6]; 3])>,
    /// w_i
    pub w: [f64; 3],
    /// μ_i
    pub mu: f64,
}

/// J_N v: the normal relative velocity of `row` for the body velocities `v`, without w_N.
pub fn normal_velocity(row: &Row, v: &[[f64; 6]]) -> f64 {
    row.a
        .iter()
        .chain(row.b.iter())
        .map(|(blk, j)| (0..6).map(|d| j[0][d] * v[*blk][d]).sum::<f64>())
        .sum()
}

/// The step problem in body-block form.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    /// contacts
    pub rows: Vec<Row>,
    /// diagonal of M per moving body
    pub mass: Vec<[f64; 6]>,
    /// f per moving body
    pub f: Vec<[f64; 6]>,
    q_norm: f64,
    /// the joints' blocks (equality rows, [`crate::bodies::joints`])
    pub joints: Vec<JointBlock>,
    /// the equality rows of all the joints factored together (W_EE, [`super::equality`]),
    /// when the step solves them together ([`GLOBAL_EQUALITY_MIN_ROWS`])
    equality: Option<std::sync::Arc<super::equality::EqualitySolve>>,
    /// the contacts coloured so that no two of one colour share a moving body (the
    /// sphere engine's [`crate::nsgs::Colouring`]); a sweep visits the colours in order
    colouring: crate::nsgs::Colouring,
    /// what one update reads of each contact, in colour order (colour k at
    /// `colouring.starts[k]..colouring.starts[k + 1]`): a copy, so that a sweep streams
    /// through memory instead of jumping between contacts (the sphere engine keeps its
    /// rows in colour order for the same reason)
    sweep_rows: Vec<SweepRow>,
    /// each body block's contacts, in contact order: (contact, whether the body is its
    /// side B), those of block b at `incident[incident_start[b]..incident_start[b + 1]]`
    /// (the gather of [`Problem::velocities_with`])
    incident: Vec<(usize, bool)>,
    incident_start: Vec<usize>,
}

/// W_ii is taken as diag(W_NN, W_TT, W_TT) in a contact's update (`SweepRow::isotropic`)
/// when its off-diagonal entries are at most this times the geometric mean of the
/// diagonal entries they couple and its two tangent entries differ by at most this times
/// the larger one: the blocks of contacts between balls or of a ball with an obstacle,
/// whose lever arms lie along the normal (their coupling entries are round-off, about
/// 1e-16 of the diagonal).
pub const ISOTROPIC_TOL: f64 = 1e-13;

/// One contact as a sweep reads it: its index, J and block per side, w, μ, W_ii, W_ii⁻¹.
#[derive(Debug, Clone, PartialEq)]
struct SweepRow {
    /// the contact's index (its r at 3i..3i + 3)
    i: usize,
    a: Option<(usize, [[f64; 6]; 3])>,
    b: Option<(usize, [[f64; 6]; 3])>,
    w: [f64; 3],
    mu: f64,
    w_ii: [f64; 9],
    w_inv: [f64; 9],
    /// W_ii = diag(W_NN, W_TT, W_TT) to [`ISOTROPIC_TOL`] (a ball's contact): the
    /// one-contact law is solved in closed form ([`crate::nsgs::isotropic_law`])
    isotropic: bool,
}

/// Whether the 3 × 3 block `w` (row-major) is diag(w_N, w_T, w_T) to [`ISOTROPIC_TOL`].
fn is_isotropic(w: &[f64; 9]) -> bool {
    let (n, t1, t2) = (w[0], w[4], w[8]);
    if !(n > 0.0 && t1 > 0.0 && t2 > 0.0 && n.is_finite() && t1.is_finite() && t2.is_finite()) {
        return false;
    }
    let small = |x: f64, p: f64, q: f64| x.abs() <= ISOTROPIC_TOL * (p * q).sqrt();
    small(w[1], n, t1)
        && small(w[3], n, t1)
        && small(w[2], n, t2)
        && small(w[6], n, t2)
        && small(w[5], t1, t2)
        && small(w[7], t1, t2)
        && (t1 - t2).abs() <= ISOTROPIC_TOL * t1.max(t2)
}

/// Raw storage shared by the updates of one colour, which touch disjoint bodies and
/// disjoint impulses.
#[derive(Clone, Copy)]
pub(super) struct Raw<T>(pub(super) *mut T);
// SAFETY: used only by `Problem::sweep` and the position correction (`super::correct`)
// inside one colour of a colouring checked by `Colouring::is_valid_pairs` (every block index
// in bounds, no two rows of one colour on one block, A ≠ B): two updates running at once
// never touch the same element.
unsafe impl<T> Send for Raw<T> {}
unsafe impl<T> Sync for Raw<T> {}
impl<T> Raw<T> {
    /// The pointer (a method, so that closures capture the whole wrapper).
    #[inline]
    pub(super) fn get(self) -> *mut T {
        self.0
    }
}

/// The blocks a row touches: (first, second), for the colouring.
fn ends(row: &Row) -> (usize, Option<usize>) {
    match (&row.a, &row.b) {
        (Some((a, _)), b) => (*a, b.as_ref().map(|(b, _)| *b)),
        (None, Some((b, _))) => (*b, None),
        // no moving body: refused by `Problem::new` (W_ii = 0)
        (None, None) => (usize::MAX, None),
    }
}

/// One joint's rows of Gᵀ on its bodies' dofs, b, the kinds of their multipliers, and
/// the block J M⁻¹ Jᵀ.
#[derive(Debug, Clone, PartialEq)]
pub struct JointBlock {
    /// A's block index (None: fixed)
    pub a: Option<usize>,
    /// B's block index (None: the world or a fixed body)
    pub b: Option<usize>,
    /// the rows
    pub rows: Vec<JointRow>,
    /// offset of its multipliers in λ
    pub offset: usize,
    /// J M⁻¹ Jᵀ (k × k, row-major)
    w: Vec<f64>,
    /// the equality rows and their block of w
    eq: Vec<usize>,
    w_eq: Vec<f64>,
}

/// When [`Problem::solve`] stops, and its over-relaxation ([`crate::step::rigid::RigidSettings`]'s
/// fields of the same names).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rule {
    /// tolerance on the error on the stored problem
    pub tol: f64,
    /// cap on sweeps
    pub max_sweeps: usize,
    /// stalled when the lowest error has not halved over this many sweeps
    pub stall_window: usize,
    /// over-relaxation ω ∈ [1, 2) from the second sweep on
    pub relaxation: f64,
    /// wall-clock cap, checked at the exact evaluations (`None`: none)
    pub time_limit: Option<std::time::Duration>,
}

/// Result of [`Problem::solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// r of lowest error met
    pub r: Vec<f64>,
    /// the joints' multipliers λ (impulses) with it
    pub lambda: Vec<f64>,
    /// its error on the stored problem
    pub error: f64,
    /// sweeps done
    pub sweeps: usize,
}

fn inv3(a: &[f64; 9]) -> Option<[f64; 9]> {
    let det = a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6])
        + a[2] * (a[3] * a[7] - a[4] * a[6]);
    if !(det.is_finite() && det > 0.0) {
        return None;
    }
    let d = 1.0 / det;
    Some([
        (a[4] * a[8] - a[5] * a[7]) * d,
        (a[2] * a[7] - a[1] * a[8]) * d,
        (a[1] * a[5] - a[2] * a[4]) * d,
        (a[5] * a[6] - a[3] * a[8]) * d,
        (a[0] * a[8] - a[2] * a[6]) * d,
        (a[2] * a[3] - a[0] * a[5]) * d,
        (a[3] * a[7] - a[4] * a[6]) * d,
        (a[1] * a[6] - a[0] * a[7]) * d,
        (a[0] * a[4] - a[1] * a[3]) * d,
    ])
}

impl Problem {
    /// The problem with its W_ii and their inverses; Err if a block is not positive
    /// definite or a mass not positive.
    pub fn new(rows: Vec<Row>, mass: Vec<[f64; 6]>, f: Vec<[f64; 6]>) -> Result<Self, String> {
        if mass.iter().flatten().any(|m| !(m.is_finite() && *m > 0.0)) {
            return Err("a mass or principal inertia is not positive".into());
        }
        if f.len() != mass.len() {
            return Err(format!("{} momenta for {} bodies", f.len(), mass.len()));
        }
        if let Some(i) = rows.iter().position(|r| match (&r.a, &r.b) {
            (Some((a, _)), Some((b, _))) => a == b,
            _ => false,
        }) {
            return Err(format!("contact {i}: both sides are the same body"));
        }
        let mut w_ii = Vec::with_capacity(rows.len());
        let mut w_inv = Vec::with_capacity(rows.len());
        for (i, row) in rows.iter().enumerate() {
            let mut w = [0.0; 9];
            for (blk, j) in row.a.iter().chain(row.b.iter()) {
                let m = mass
                    .get(*blk)
                    .ok_or(format!("contact {i}: no body {blk}"))?;
                // symmetric (the products commute): the upper triangle, mirrored
                for r in 0..3 {
                    for c in r..3 {
                        let x = (0..6).map(|d| j[r][d] * j[c][d] / m[d]).sum::<f64>();
                        w[3 * r + c] += x;
                        if c != r {
                            w[3 * c + r] += x;
                        }
                    }
                }
            }
            let inv = inv3(&w).ok_or(format!(
                "contact {i}: its Delassus block W_ii is not positive definite"
            ))?;
            w_ii.push(w);
            w_inv.push(inv);
        }
        let colouring =
            crate::nsgs::Colouring::greedy_pairs(rows.len(), mass.len(), |i| ends(&rows[i]));
        if !colouring.is_valid_pairs(rows.len(), mass.len(), |i| ends(&rows[i])) {
            return Err("the contacts could not be coloured".into());
        }
        // each block's contacts in contact order (a counting sort: blocks in bounds, checked
        // above when W_ii was built)
        let mut incident_start = vec![0usize; mass.len() + 1];
        for row in &rows {
            for (blk, _) in row.a.iter().chain(row.b.iter()) {
                incident_start[blk + 1] += 1;
            }
        }
        for b in 0..mass.len() {
            incident_start[b + 1] += incident_start[b];
        }
        let mut next = incident_start.clone();
        let mut incident = vec![(0, false); incident_start[mass.len()]];
        for (i, row) in rows.iter().enumerate() {
            let sides = [(&row.a, false), (&row.b, true)];
            for (blk, side_b) in sides
                .into_iter()
                .filter_map(|(s, b)| s.as_ref().map(|(blk, _)| (*blk, b)))
            {
                incident[next[blk]] = (i, side_b);
                next[blk] += 1;
            }
        }
        let sweep_rows = colouring
            .order
            .iter()
            .map(|&i| {
                let row = &rows[i];
                SweepRow {
                    i,
                    a: row.a,
                    b: row.b,
                    w: row.w,
                    mu: row.mu,
                    w_ii: w_ii[i],
                    w_inv: w_inv[i],
                    isotropic: row.mu.is_finite() && is_isotropic(&w_ii[i]),
                }
            })
            .collect();
        let mut p = Self {
            rows,
            mass,
            f,
            q_norm: 0.0,
            joints: Vec::new(),
            equality: None,
            colouring,
            sweep_rows,
            incident,
            incident_start,
        };
        let v0 = p.velocities(&[]);
        p.q_norm = law::norm(&p.u_all(&v0));
        Ok(p)
    }

    /// ‖q‖ = ‖Hᵀ M⁻¹ f + w‖ of the error's scale.
    pub fn q_norm(&self) -> f64 {
        self.q_norm
    }

    /// Number of contacts.
    pub fn contacts(&self) -> usize {
        self.rows.len()
    }

    /// The problem with the joints' blocks `joints` ((A's block, B's block, rows) each).
    pub fn with_joints(
        mut self,
        joints: Vec<(Option<usize>, Option<usize>, Vec<JointRow>)>,
    ) -> Result<Self, String> {
        let mut offset = 0;
        for (i, (a, b, rows)) in joints.into_iter().enumerate() {
            let k = rows.len();
            let mut w = vec![0.0; k * k];
            for (blk, pick) in [(a, 0), (b, 1)] {
                let Some(blk) = blk else { continue };
                let m = self
                    .mass
                    .get(blk)
                    .ok_or(format!("joint {i}: no body block {blk}"))?;
                for r in 0..k {
                    for c in 0..k {
                        let (jr, jc) = if pick == 0 {
                            (&rows[r].ja, &rows[c].ja)
                        } else {
                            (&rows[r].jb, &rows[c].jb)
                        };
                        w[r * k + c] += (0..6).map(|d| jr[d] * jc[d] / m[d]).sum::<f64>();
                    }
                }
            }
            let eq: Vec<usize> = (0..k)
                .filter(|&r| rows[r].kind == RowKind::Equality)
                .collect();
            let w_eq: Vec<f64> = eq
                .iter()
                .flat_map(|&r| eq.iter().map(move |&c| (r, c)))
                .map(|(r, c)| w[r * k + c])
                .collect();
            self.joints.push(JointBlock {
                a,
                b,
                rows,
                offset,
                w,
                eq,
                w_eq,
            });
            offset += k;
        }
        let rows: Vec<super::equality::EqRow> = self
            .joints
            .iter()
            .flat_map(|jb| {
                jb.eq.iter().map(|&r| super::equality::EqRow {
                    lambda: jb.offset + r,
                    a: jb.a.map(|a| (a, jb.rows[r].ja)),
                    b: jb.b.map(|b| (b, jb.rows[r].jb)),
                    rhs: jb.rows[r].b,
                })
            })
            .collect();
        if !rows.is_empty() && rows.len() >= GLOBAL_EQUALITY_MIN_ROWS {
            self.equality =
                super::equality::EqualitySolve::new(rows, &self.mass).map(std::sync::Arc::new);
        }
        Ok(self)
    }

    /// Whether the equality rows are solved together (W_EE factored) in this step, and
    /// how many of them were found dependent on the others.
    pub fn global_equality(&self) -> Option<usize> {
        self.equality.as_ref().map(|e| e.dependent())
    }

    /// Number of joint rows (the length of λ).
    pub fn joint_rows(&self) -> usize {
        self.joints.last().map_or(0, |j| j.offset + j.rows.len())
    }

    /// v = M⁻¹ (f + H r) (r shorter than 3 · contacts: zeros).
    pub fn velocities(&self, r: &[f64]) -> Vec<[f64; 6]> {
        self.velocities_with(r, &[])
    }

    /// v = M⁻¹ (f + H r + G λ) (r or λ short: zeros).
    pub fn velocities_with(&self, r: &[f64], lambda: &[f64]) -> Vec<[f64; 6]> {
        let mut p = self.f.clone();
        for jb in &self.joints {
            for (k, row) in jb.rows.iter().enumerate() {
                let Some(l) = lambda.get(jb.offset + k) else {
                    break;
                };
                if let Some(a) = jb.a {
                    (0..6).for_each(|d| p[a][d] += row.ja[d] * l);
                }
                if let Some(b) = jb.b {
                    (0..6).for_each(|d| p[b][d] += row.jb[d] * l);
                }
            }
        }
        // the contacts r holds (r short: the first r.len() / 3)
        let n = (r.len() / 3).min(self.rows.len());
        // body b: its contacts in contact order, then M⁻¹: for each entry the additions
        // of the contact-by-contact scatter, in the same order (the same bits)
        let gather = |b: usize, pb: &mut [f64; 6]| {
            let ids = &self.incident[self.incident_start[b]..self.incident_start[b + 1]];
            for &(i, side_b) in ids {
                if i >= n {
                    break;
                }
                let row = &self.rows[i];
                let side = if side_b { &row.b } else { &row.a };
                let Some((_, j)) = side else { continue };
                for k in 0..3 {
                    for d in 0..6 {
                        pb[d] += j[k][d] * r[3 * i + k];
                    }
                }
            }
            let m = &self.mass[b];
            for d in 0..6 {
                pb[d] /= m[d];
            }
        };
        if self.rows.len() >= EVAL_PARALLEL_MIN {
            use rayon::prelude::*;
            p.par_chunks_mut(EVAL_CHUNK)
                .enumerate()
                .for_each(|(c, chunk)| {
                    for (o, pb) in chunk.iter_mut().enumerate() {
                        gather(c * EVAL_CHUNK + o, pb);
                    }
                });
        } else {
            for (b, pb) in p.iter_mut().enumerate() {
                gather(b, pb);
            }
        }
        p
    }

    /// u = Hᵀ v + w of every contact, 3 per contact ([`Problem::u`]; in parallel chunks of
    /// [`EVAL_CHUNK`] contacts from [`EVAL_PARALLEL_MIN`] contacts: each its own numbers).
    pub fn u_all(&self, v: &[[f64; 6]]) -> Vec<f64> {
        let mut u = vec![0.0; 3 * self.rows.len()];
        let fill = |first: usize, out: &mut [f64]| {
            for (o, ui) in out.chunks_exact_mut(3).enumerate() {
                ui.copy_from_slice(&self.u(first + o, v));
            }
        };
        if self.rows.len() >= EVAL_PARALLEL_MIN {
            use rayon::prelude::*;
            u.par_chunks_mut(3 * EVAL_CHUNK)
                .enumerate()
                .for_each(|(c, out)| fill(c * EVAL_CHUNK, out));
        } else {
            fill(0, &mut u);
        }
        u
    }

    /// u_i = J_A v_A + J_B v_B + w_i.
    pub fn u(&self, i: usize, v: &[[f64; 6]]) -> [f64; 3] {
        let row = &self.rows[i];
        let mut u = row.w;
        for (blk, j) in row.a.iter().chain(row.b.iter()) {
            for k in 0..3 {
                u[k] += (0..6).map(|d| j[k][d] * v[*blk][d]).sum::<f64>();
            }
        }
        u
    }

    /// The error of docs/error.md of r on the stored problem (v recomputed from r).
    pub fn error(&self, r: &[f64]) -> f64 {
        self.error_with(r, &[])
    }

    /// (Gᵀ v + b)_k of joint block `j`'s rows.
    pub fn joint_u(&self, j: usize, v: &[[f64; 6]]) -> Vec<f64> {
        let jb = &self.joints[j];
        jb.rows
            .iter()
            .map(|row| {
                let mut u = row.b;
                if let Some(a) = jb.a {
                    u += (0..6).map(|d| row.ja[d] * v[a][d]).sum::<f64>();
                }
                if let Some(b) = jb.b {
                    u += (0..6).map(|d| row.jb[d] * v[b][d]).sum::<f64>();
                }
                u
            })
            .collect()
    }

    /// The error of (r, λ), v recomputed from them: the larger of the error of
    /// docs/error.md of the contacts and the joints' residual ‖ρ‖ / max(1, ‖b‖), ρ_k the
    /// row's Gᵀ v + b where its multiplier is free (an equality row, a motor below its
    /// bound, a limit carrying load: the equality residual of docs/error.md on those rows)
    /// and its violation of the sign condition where the multiplier sits at a bound.
    pub fn error_with(&self, r: &[f64], lambda: &[f64]) -> f64 {
        self.error_at(r, lambda, &self.velocities_with(r, lambda))
    }

    /// [`Problem::error_with`] with v = [`Problem::velocities_with`]`(r, lambda)` already
    /// computed (the same number, v computed once).
    fn error_at(&self, r: &[f64], lambda: &[f64], v: &[[f64; 6]]) -> f64 {
        let (contact, joint) = self.error_parts_at(r, lambda, v);
        if joint.is_nan() {
            return f64::NAN;
        }
        contact.max(joint)
    }

    /// The two parts of [`Problem::error_with`]: (the contacts' error of docs/error.md,
    /// the joints' residual).
    pub fn error_parts(&self, r: &[f64], lambda: &[f64]) -> (f64, f64) {
        self.error_parts_at(r, lambda, &self.velocities_with(r, lambda))
    }

    /// [`Problem::error_parts`] at v = [`Problem::velocities_with`]`(r, lambda)`.
    fn error_parts_at(&self, r: &[f64], lambda: &[f64], v: &[[f64; 6]]) -> (f64, f64) {
        let u = self.u_all(v);
        let mu: Vec<f64> = self.rows.iter().map(|r| r.mu).collect();
        let contact = if self.rows.is_empty() {
            0.0
        } else {
            law::error_measure(3, &mu, r, &u, self.q_norm).error
        };
        if self.joints.is_empty() {
            return (contact, 0.0);
        }
        let (mut res, mut b2) = (0.0, 0.0);
        for (j, jb) in self.joints.iter().enumerate() {
            for (k, (row, uk)) in jb.rows.iter().zip(self.joint_u(j, v)).enumerate() {
                let l = lambda.get(jb.offset + k).copied().unwrap_or(0.0);
                let rho = match row.kind {
                    RowKind::Equality => uk,
                    RowKind::Box(_, hi) if l >= hi => uk.max(0.0),
                    RowKind::Box(lo, _) if l <= lo => uk.min(0.0),
                    RowKind::Box(..) => uk,
                    RowKind::Unilateral if l > 0.0 => uk,
                    RowKind::Unilateral => uk.min(0.0),
                };
                res += rho * rho;
                b2 += row.b * row.b;
            }
        }
        (contact, res.sqrt() / b2.sqrt().max(1.0))
    }

    /// One exact update of joint block j (the others frozen): its equality rows by the
    /// small dense solve of W_EE δ = −u_E (pivoted: dependent rows get no update), then
    /// each motor and limit row projected on its bound.
    fn update_joint(&self, j: usize, v: &mut [[f64; 6]], lambda: &mut [f64], with_equality: bool) {
        let jb = &self.joints[j];
        let k = jb.rows.len();
        let apply = |v: &mut [[f64; 6]], row: &JointRow, d: f64| {
            if let Some(a) = jb.a {
                (0..6).for_each(|c| v[a][c] += row.ja[c] * d / self.mass[a][c]);
            }
            if let Some(b) = jb.b {
                (0..6).for_each(|c| v[b][c] += row.jb[c] * d / self.mass[b][c]);
            }
        };
        if with_equality && !jb.eq.is_empty() {
            let u = self.joint_u(j, v);
            let rhs: Vec<f64> = jb.eq.iter().map(|&r| -u[r]).collect();
            let delta = crate::bodies::joints::solve_spd(&jb.w_eq, &rhs, jb.eq.len());
            for (&r, d) in jb.eq.iter().zip(delta) {
                if d != 0.0 && d.is_finite() {
                    lambda[jb.offset + r] += d;
                    apply(v, &jb.rows[r], d);
                }
            }
        }
        for r in 0..k {
            let row = &jb.rows[r];
            let (lo, hi) = match row.kind {
                RowKind::Equality => continue,
                RowKind::Box(lo, hi) => (lo, hi),
                RowKind::Unilateral => (0.0, f64::INFINITY),
            };
            let wrr = jb.w[r * k + r];
            if !(wrr.is_finite() && wrr > 0.0) {
                continue;
            }
            let mut u = row.b;
            if let Some(a) = jb.a {
                u += (0..6).map(|d| row.ja[d] * v[a][d]).sum::<f64>();
            }
            if let Some(b) = jb.b {
                u += (0..6).map(|d| row.jb[d] * v[b][d]).sum::<f64>();
            }
            let old = lambda[jb.offset + r];
            let new = (old - u / wrr).clamp(lo, hi);
            if new != old {
                lambda[jb.offset + r] = new;
                apply(v, row, new - old);
            }
        }
    }

    /// Gauss–Seidel from r0, over-relaxed by `rule.relaxation` from the second sweep on
    /// (ω halved towards 1 whenever the error of the checks has not decreased over
    /// [`crate::nsgs::RELAX_WINDOW`] sweeps, the sphere engine's rule), until the error
    /// on the stored problem is ≤ `rule.tol`, `rule.max_sweeps`, or a stall: the lowest
    /// error met has not halved over `rule.stall_window` sweeps and, decreasing at the
    /// rate of those sweeps, would need more sweeps to reach `rule.tol` than it has done
    /// (a plateau goes to the library, a slow but steady finish near the tolerance is left
    /// to Gauss–Seidel; a stall met while over-relaxed first sets ω = 1 and gives plain
    /// sweeps a window of their own), or `rule.time_limit`. Returns the iterate of
    /// lowest error (exactly evaluated: every [`CHECK_EVERY`] sweeps, the first and the
    /// last).
    pub fn solve(&self, r0: &[f64], lambda0: &[f64], rule: Rule) -> Solution {
        let Rule {
            tol,
            max_sweeps,
            stall_window,
            relaxation,
            time_limit,
        } = rule;
        let deadline = coulomb::deadline::deadline(std::time::Instant::now(), time_limit);
        let mut omega = if relaxation.is_finite() {
            relaxation.clamp(1.0, 1.99)
        } else {
            1.0
        };
        let mut window_start = f64::INFINITY;
        let n = self.rows.len();
        let nl = self.joint_rows();
        let mut r = if r0.len() == 3 * n && r0.iter().all(|x| x.is_finite()) {
            r0.to_vec()
        } else {
            vec![0.0; 3 * n]
        };
        let mut lambda = if lambda0.len() == nl && lambda0.iter().all(|x| x.is_finite()) {
            lambda0.to_vec()
        } else {
            vec![0.0; nl]
        };
        let mut v = self.velocities_with(&r, &lambda);
        let mut best = Solution {
            error: self.error_with(&r, &lambda),
            r: r.clone(),
            lambda: lambda.clone(),
            sweeps: 0,
        };
        if best.error <= tol {
            return best;
        }
        let mut history: Vec<(usize, f64)> = Vec::new();

        for sweep in 1..=max_sweeps {
            // the first sweep is plain Gauss–Seidel: it solves isolated contacts exactly
            self.sweep(&mut v, &mut r, if sweep == 1 { 1.0 } else { omega });
            match &self.equality {
                Some(eq) => {
                    for j in 0..self.joints.len() {
                        self.update_joint(j, &mut v, &mut lambda, false);
                    }
                    eq.update(&self.mass, &mut v, &mut lambda);
                }
                None => {
                    for j in 0..self.joints.len() {
                        self.update_joint(j, &mut v, &mut lambda, true);
                    }
                }
            }
            if sweep % CHECK_EVERY == 0 || sweep == max_sweeps || sweep == 1 {
                // exact evaluation on the stored problem (v from scratch)
                v = self.velocities_with(&r, &lambda);
                let err = self.error_at(&r, &lambda, &v);
                best.sweeps = sweep;
                if err < best.error || !best.error.is_finite() {
                    best.error = err;
                    best.r.copy_from_slice(&r);
                    best.lambda.copy_from_slice(&lambda);
                }
                if err <= tol || !err.is_finite() {
                    break;
                }
                // the time cap: the step goes on as after a stall
                if deadline.is_some_and(|d| std::time::Instant::now() >= d) {
                    break;
                }
                if sweep % crate::nsgs::RELAX_WINDOW == 0 {
                    if omega > 1.0 && err >= window_start {
                        omega = 1.0 + 0.5 * (omega - 1.0);
                        if omega < 1.01 {
                            omega = 1.0;
                        }
                    }
                    window_start = err;
                }
                history.push((sweep, best.error));
                let back = history
                    .iter()
                    .rev()
                    .find(|(s, _)| *s + stall_window <= sweep)
                    .map(|x| x.1);
                // stalled: the lowest error has not halved over the window, and at the
                // window's rate it would need more sweeps to reach tol than were done
                if let Some(old) = back {
                    let ratio = best.error / old;
                    let needed = if ratio < 1.0 {
                        stall_window as f64 * (tol / best.error).ln() / ratio.ln()
                    } else {
                        f64::INFINITY
                    };
                    if ratio > 0.5 && needed > sweep as f64 {
                        // over-relaxed sweeps can stall where plain ones still progress:
                        // before the library (seconds a hand-over on a thousand contacts),
                        // plain sweeps get a window of their own (docs/rigid-bodies.md,
                        // "A stall while over-relaxed")
                        if omega > 1.0 {
                            omega = 1.0;
                            history.clear();
                            continue;
                        }
                        break;
                    }
                }
            }
        }
        best
    }

    /// One sweep over the contacts, colour by colour: the rows of one colour touch
    /// disjoint bodies, so they are updated in parallel (rayon) where the colour is large,
    /// with the same numbers as one after the other: the result does not depend on the
    /// number of threads.
    fn sweep(&self, v: &mut [[f64; 6]], r: &mut [f64], omega: f64) {
        use rayon::prelude::*;
        assert!(v.len() == self.mass.len() && r.len() == 3 * self.rows.len());
        let (vp, rp) = (Raw(v.as_mut_ptr()), Raw(r.as_mut_ptr()));
        let c = &self.colouring;
        for k in 0..c.colours() {
            let rows = &self.sweep_rows[c.starts[k]..c.starts[k + 1]];
            // SAFETY: one colour of a valid colouring (checked in `Problem::new`), v and
            // r of the lengths asserted above
            let run = |chunk: &[SweepRow]| {
                for row in chunk {
                    unsafe { self.update(row, vp.get(), rp.get(), omega) }
                }
            };
            if rows.len() >= crate::nsgs::PARALLEL_MIN {
                rows.par_chunks(crate::nsgs::colour_chunk(rows.len()))
                    .for_each(run);
            } else {
                run(rows);
            }
        }
    }

    /// One Gauss–Seidel update of contact i = `row.i` (the others frozen), v kept =
    /// M⁻¹(f + H r): r_i' from the sphere engine's [`relaxed_contact_law`] (over-relaxed
    /// with ω ≠ 1; in closed form where W_ii is diag(W_NN, W_TT, W_TT), a ball's contact).
    ///
    /// # Safety
    /// `v` points to one velocity per body block and `r` to 3 impulses per contact; no
    /// other thread reads or writes the velocities of contact i's bodies or r_i meanwhile.
    unsafe fn update(&self, row: &SweepRow, v: *mut [f64; 6], r: *mut f64, omega: f64) {
        let i = row.i;
        let mut u = row.w;
        for (blk, j) in row.a.iter().chain(row.b.iter()) {
            // SAFETY: by the caller's contract
            let vb = unsafe { &*v.add(*blk) };
            for k in 0..3 {
                u[k] += (0..6).map(|d| j[k][d] * vb[d]).sum::<f64>();
            }
        }
        // SAFETY: by the caller's contract
        let ri = unsafe { &mut *r.add(3 * i).cast::<[f64; 3]>() };
        let old = *ri;
        let new = relaxed_contact_law(
            &row.w_ii,
            &row.w_inv,
            row.mu,
            &u,
            &old,
            omega,
            row.isotropic,
        );
        let delta = [new[0] - old[0], new[1] - old[1], new[2] - old[2]];
        if delta.iter().all(|x| *x == 0.0) {
            return;
        }
        for (blk, j) in row.a.iter().chain(row.b.iter()) {
            let m = &self.mass[*blk];
            // SAFETY: by the caller's contract
            let vb = unsafe { &mut *v.add(*blk) };
            for d in 0..6 {
                vb[d] += (j[0][d] * delta[0] + j[1][d] * delta[1] + j[2][d] * delta[2]) / m[d];
            }
        }
        *ri = new;
    }

    /// The same problem as a library global problem (M diagonal, H sparse).
    pub fn to_global(&self) -> Result<GlobalProblem, ProblemError> {
        self.to_global_with(&[])
    }

    /// The index in λ of each column of G of [`Problem::to_global_with`] at `lambda`.
    pub fn equality_columns(&self, lambda: &[f64]) -> Vec<usize> {
        let mut cols = Vec::new();
        for jb in &self.joints {
            for (k, row) in jb.rows.iter().enumerate() {
                let l = lambda.get(jb.offset + k).copied().unwrap_or(0.0);
                if stored_row(row.kind, l) {
                    cols.push(jb.offset + k);
                }
            }
        }
        cols
    }

    /// The problem as a library global problem with the joints' equality constraints
    /// (G, b) at the multipliers λ: the equality rows, a motor row whose impulse is below
    /// its bound and a limit row that carries load are rows of Gᵀ v + b = 0; a motor at
    /// its bound is the known impulse J λ added to f; a limit carrying none is left out
    /// (the active set of the returned solution).
    pub fn to_global_with(&self, lambda: &[f64]) -> Result<GlobalProblem, ProblemError> {
        let n = 6 * self.mass.len();
        let diag: Vec<f64> = self.mass.iter().flatten().copied().collect();
        let idx: Vec<usize> = (0..n).collect();
        let m = CscMatrix::from_triplets(n, n, &idx, &idx, &diag)
            .map_err(|source| ProblemError::Sparse { what: "M", source })?;
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        for (i, row) in self.rows.iter().enumerate() {
            for (blk, j) in row.a.iter().chain(row.b.iter()) {
                for (k, jk) in j.iter().enumerate() {
                    for (d, x) in jk.iter().enumerate() {
                        if *x != 0.0 {
                            rows.push(6 * blk + d);
                            cols.push(3 * i + k);
                            vals.push(*x);
                        }
                    }
                }
            }
        }
        let h = CscMatrix::from_triplets(n, 3 * self.rows.len(), &rows, &cols, &vals)
            .map_err(|source| ProblemError::Sparse { what: "H", source })?;
        let mut f: Vec<f64> = self.f.iter().flatten().copied().collect();
        let w: Vec<f64> = self.rows.iter().flat_map(|r| r.w).collect();
        let mu: Vec<f64> = self.rows.iter().map(|r| r.mu).collect();
        let problem = GlobalProblem::new_unfactored(3, m, h, f.clone(), w.clone(), mu.clone())?;
        if self.joints.is_empty() {
            return Ok(problem);
        }
        let (mut rows, mut cols, mut vals, mut b) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for jb in &self.joints {
            for (k, row) in jb.rows.iter().enumerate() {
                let l = lambda.get(jb.offset + k).copied().unwrap_or(0.0);
                let stored = stored_row(row.kind, l);
                let parts = [(jb.a, &row.ja), (jb.b, &row.jb)];
                if stored {
                    for (blk, j) in parts {
                        let Some(blk) = blk else { continue };
                        for (d, x) in j.iter().enumerate() {
                            if *x != 0.0 {
                                rows.push(6 * blk + d);
                                cols.push(b.len());
                                vals.push(*x);
                            }
                        }
                    }
                    b.push(row.b);
                } else if matches!(row.kind, RowKind::Box(..)) {
                    for (blk, j) in parts {
                        let Some(blk) = blk else { continue };
                        for (d, x) in j.iter().enumerate() {
                            f[6 * blk + d] += x * l;
                        }
                    }
                }
            }
        }
        let g = CscMatrix::from_triplets(n, b.len(), &rows, &cols, &vals)
            .map_err(|source| ProblemError::Sparse { what: "G", source })?;
        let problem = GlobalProblem { f, ..problem };
        problem.with_equality(g, b)
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::nsgs::isotropic_law;
    use coulomb::cone;
    use coulomb::inner::pgs::{solve_contact_law, OneContact};

    /// A deterministic generator of numbers in [−½, ½).
    fn numbers(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// The closed form satisfies Coulomb's law (2.9) (natural-map residual of
    /// docs/error.md at round-off) in all its cases, and gives the library's solution
    /// where the library's one-contact solve finds one.
    pub fn isotropic_law_solves_the_one_contact_law() {
        let mut rnd = numbers(0x9e37_79b9_7f4a_7c15);
        let (mut stick, mut slide, mut off) = (0, 0, 0);
        for trial in 0..20_000 {
            let wn = 0.1 + 10.0 * (rnd() + 0.5);
            let wt = 0.1 + 10.0 * (rnd() + 0.5);
            let w = [wn, 0.0, 0.0, 0.0, wt, 0.0, 0.0, 0.0, wt];
            let winv = [1.0 / wn, 0.0, 0.0, 0.0, 1.0 / wt, 0.0, 0.0, 0.0, 1.0 / wt];
            let mu = [0.0, 0.3, 1.5][trial % 3];
            let c = [4.0 * rnd(), 4.0 * rnd(), 4.0 * rnd()];
            assert!(is_isotropic(&w));
            let r = isotropic_law(&w, mu, &c);
            let u: [f64; 3] = std::array::from_fn(|k| w[4 * k] * r[k] + c[k]);
            let scale = 1.0 + c.iter().map(|x| x.abs()).sum::<f64>();
            let e = law::contact_residual_sq(mu, &u, &r).sqrt();
            assert!(
                e <= 1e-14 * scale,
                "trial {trial}: mu {mu} c {c:?} r {r:?} e {e}"
            );
            match (r[0] > 0.0, cone::contains(mu, &r, -1e-12)) {
                (false, _) => off += 1,
                (true, true) => stick += 1,
                (true, false) => slide += 1,
            }
            let contact = OneContact {
                a: &w,
                ainv: &winv,
                d: 3,
                mu,
                c,
            };
            if let Some(lib) = solve_contact_law(&contact, &[0.0; 3], &c) {
                for k in 0..3 {
                    assert!((lib[k] - r[k]).abs() <= 1e-12 * scale, "{lib:?} vs {r:?}");
                }
            }
        }
        assert!(
            stick > 1000 && slide > 1000 && off > 1000,
            "{stick} {slide} {off}"
        );
    }

    /// J of a contact at lever arm `arm` (body frame = world) with frame n, t₁, t₂.
    fn jacobian(arm: [f64; 3], frame: [[f64; 3]; 3], sign: f64) -> [[f64; 6]; 3] {
        std::array::from_fn(|k| {
            let t = frame[k];
            let x = [
                arm[1] * t[2] - arm[2] * t[1],
                arm[2] * t[0] - arm[0] * t[2],
                arm[0] * t[1] - arm[1] * t[0],
            ];
            [t[0], t[1], t[2], x[0], x[1], x[2]].map(|e| sign * e)
        })
    }

    /// A ball's contacts (lever arm along the normal, scalar inertia) take the closed
    /// form, a box's corner (lever arm across the normal) the library's solve; both
    /// problems are solved to the tolerance on the stored problem.
    pub fn ball_contacts_take_the_closed_form() {
        let s = 0.5f64.sqrt();
        let n = [0.0, s, s];
        let frame = [n, [1.0, 0.0, 0.0], [0.0, s, -s]];
        let (m, radius) = (2.0, 0.1);
        let inertia = 0.4 * m * radius * radius;
        let ball = [m, m, m, inertia, inertia, inertia];
        let rule = Rule {
            tol: 1e-10,
            max_sweeps: 500,
            stall_window: 100,
            relaxation: 1.0,
            time_limit: None,
        };
        // two balls in contact, the lower one on an inclined plane (gravity along −z)
        let f = [[0.0, 0.0, -0.1 * m, 0.0, 0.0, 0.0]; 2];
        let rows = vec![
            Row {
                a: Some((0, jacobian(n.map(|x| -radius * x), frame, 1.0))),
                b: None,
                w: [0.0; 3],
                mu: 0.3,
            },
            Row {
                a: Some((1, jacobian(n.map(|x| -radius * x), frame, 1.0))),
                b: Some((0, jacobian(n.map(|x| radius * x), frame, -1.0))),
                w: [0.0; 3],
                mu: 0.3,
            },
        ];
        let p = Problem::new(rows, vec![ball; 2], f.to_vec()).unwrap();
        assert!(p.sweep_rows.iter().all(|r| r.isotropic));
        let sol = p.solve(&[], &[], rule);
        assert!(sol.error <= 1e-10, "{}", sol.error);
        // a box (inertia not scalar) on its corner
        let cuboid = [m, m, m, 0.01, 0.02, 0.03];
        let rows = vec![Row {
            a: Some((0, jacobian([-0.1, -0.05, -0.2], frame, 1.0))),
            b: None,
            w: [0.0; 3],
            mu: 0.3,
        }];
        let p = Problem::new(rows, vec![cuboid], vec![f[0]]).unwrap();
        assert!(!p.sweep_rows[0].isotropic);
        let sol = p.solve(&[], &[], rule);
        assert!(sol.error <= 1e-10, "{}", sol.error);
    }
}
