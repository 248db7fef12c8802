//! Body-level nonsmooth Gauss–Seidel (NSGS) for the incremental problem (2.10) of one step,
//! matrix-free: the Delassus operator W = Hᵀ M⁻¹ H is never formed.
//!
//! The step problem is the global problem of [`crate::assembly`] in FCLIB convention,
//!
//! ```text
//!     M v = H r + f,      u = Hᵀ v + w,      (uⁱ, rⁱ) satisfy Coulomb's law (2.9),
//! ```
//!
//! stored contact by contact ([`StepProblem`]): contact i touches one or two spheres, so its
//! column block H_i (n × 3) has nonzeros on the 6 dofs of body A and of body B only, kept as
//! two 3 × 6 blocks J_A, J_B with u_i = J_A v_A + J_B v_B + w_i. M is diagonal
//! (m, m, m, I, I, I per sphere), so the diagonal block of W is the 3 × 3 matrix
//!
//! ```text
//!     W_ii = J_A M_A⁻¹ J_Aᵀ + J_B M_B⁻¹ J_Bᵀ.
//! ```
//!
//! One Gauss–Seidel update of contact i ([`update_contact`]), the others frozen:
//! u_i = H_iᵀ v + w_i, c = u_i − W_ii r_i, the new r_i is a solution of the one-contact law
//! u_i' = W_ii r_i' + c by `coulomb::inner::pgs::solve_contact_law` (take-off, stick or slide;
//! where that fails the one-contact SOC-QP with De Saxcé's s = μ‖u_T‖, as the library's fused
//! iteration does), then v ← v + M⁻¹ H_i Δr_i keeps M v = H r + f. This is the library's
//! fused Gauss–Seidel on W (`coulomb::inner::pgs::solve_fused`) applied to the same W, but
//! each update costs O(1) (two bodies) instead of the nonzeros of W's columns, and memory is
//! O(contacts).
//!
//! # Parallel sweeps
//! The contacts are coloured ([`Colouring`]) so that two contacts of one colour share no
//! sphere (obstacles are fixed and never shared). A sweep visits the colours in order;
//! within a colour the updates touch disjoint velocities, so they run in parallel (rayon) and
//! give the same numbers as a sequential pass. Sums (residuals) are taken over fixed chunks
//! of contacts and combined in order, so the result is bitwise the same for every number of
//! threads.
//!
//! # Stopping
//! Each sweep also accumulates the error of docs/error.md from the pairs (u_i, r_i) it
//! meets (a proxy: u_i is taken before r_i moves). When the proxy is ≤ tol, v is recomputed
//! from scratch, v = M⁻¹ (f + H r), u = Hᵀ v + w, and the error of docs/error.md (and the
//! balance residual) is evaluated on the stored (M, H, f, w, μ); converged only if that is
//! ≤ tol. Iterations and time are capped ([`NsgsSettings`]) with a typed [`NsgsStatus`].
//!
//! # Over-relaxation
//! From the second sweep on, r_i' is replaced by P_{K_μ}(r_i + ω (r_i' − r_i)) with ω = 1.5 by
//! default, halved towards 1 when the sweep residual stalls (docs/scaling.md: 2–3× fewer
//! sweeps on the box heaps); the first sweep is plain, so that an isolated contact is solved
//! exactly. The fixed points are those of plain Gauss–Seidel: solutions of (2.10).

use crate::assembly::{contact_offset_one, StepData};
use crate::colour_progress::ColourProgress;
use crate::contact::{Contact, Partner};
use crate::step::rows::{cross, dot3};
pub use crate::step::rows::{invert_spd, ContactRow};
use crate::world::World;
use coulomb::inner::pgs::{solve_contact, solve_contact_law, OneContact};
use coulomb::problem::{GlobalProblem, ProblemError};
use coulomb::sparse::CscMatrix;
use coulomb::{cone, law};
use rayon::prelude::*;
use serde::Serialize;
use std::time::{Duration, Instant};

/// Largest number of contacts per chunk of a parallel pass (and of the fixed summation
/// order); whole-problem passes (evaluations) use it as is.
pub const CHUNK: usize = 256;
/// Smallest chunk of a colour ([`colour_chunk`]).
pub const MIN_CHUNK: usize = 16;
/// A colour with fewer contacts than this is swept sequentially (same numbers: the chunks,
/// hence the summation order, depend on the colour's size only).
pub const PARALLEL_MIN: usize = 4 * MIN_CHUNK;

/// Chunk length of a colour of `len` contacts: about 64 chunks per colour, between
/// [`MIN_CHUNK`] and half a [`CHUNK`] (≈ 10 µs of work), so that every colour of a sweep,
/// the small ones too, is shared evenly between the threads (rayon splits adaptively, so
/// small chunks cost little). A function of `len` only, never of the number of threads: the
/// sums of a sweep are bitwise the same for every pool size.
pub fn colour_chunk(len: usize) -> usize {
    (len / 64).clamp(MIN_CHUNK, CHUNK / 2)
}

/// Why a step problem cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepProblemError {
    /// a contact names a sphere that does not exist, or the same sphere twice
    #[error("contact {0} has an invalid body index")]
    Body(usize),
    /// a mass, inertia or W_ii is not positive definite (or not finite)
    #[error("contact {0}: its Delassus block W_ii is not positive definite")]
    Singular(usize),
}

/// The global problem (2.10) of one step in body-block form: (M, H, f, w, μ) as
/// [`crate::assembly::assemble`] builds it, without sparse matrices.
#[derive(Debug, Clone, PartialEq)]
pub struct StepProblem {
    /// the contacts, in the caller's order (the order of r)
    pub rows: Vec<ContactRow>,
    /// diagonal of M per sphere: (m, m, m, I, I, I)
    pub mass: Vec<[f64; 6]>,
    /// M⁻¹ per sphere
    pub inv_mass: Vec<[f64; 6]>,
    /// f = M v_k + h F_ext per sphere
    pub f: Vec<[f64; 6]>,
    /// the centre of each sphere (world axes): the cells of the coarse correction
    /// ([`crate::coarse`], `NsgsSettings::coarse_cell`); not part of the problem (2.10).
    /// Empty unless filled by [`StepProblem::with_positions`] (a grid coarse space without
    /// them is empty: no correction)
    pub position: Vec<[f64; 3]>,
}

impl StepProblem {
    /// The problem of one step of `world` with the active `contacts` (rows built in
    /// parallel): the same (M, H, f, w, μ) as [`crate::assembly::assemble`].
    pub fn new(
        world: &World,
        contacts: &[Contact],
        data: &StepData,
    ) -> Result<Self, StepProblemError> {
        // per sphere and per contact in parallel (rayon), the same numbers as
        // `mass_diagonal`, `free_momentum` and `contact_offset`
        let (mass, f): (Vec<[f64; 6]>, Vec<[f64; 6]>) = world
            .bodies
            .par_iter()
            .map(|b| {
                let i = b.inertia();
                let p = b.velocity * b.mass + world.gravity * (data.h * b.mass);
                let l = if b.rotation_locked {
                    crate::math::Vec3::ZERO
                } else {
                    b.angular_velocity * i
                };
                (
                    [b.mass, b.mass, b.mass, i, i, i],
                    [p.x, p.y, p.z, l.x, l.y, l.z],
                )
            })
            .unzip();
        let inv_mass: Vec<[f64; 6]> = mass.par_iter().map(|m| m.map(|x| 1.0 / x)).collect();
        let row = |c: &Contact| {
            let wi = contact_offset_one(world, c, data);
            let mu = if world.materials.is_none() {
                data.mu
            } else {
                data.law(world, c).mu
            };
            ContactRow::new(world, c, wi, mu, &inv_mass)
        };
        // an indexed collect (each row written in place, in parallel); an invalid contact
        // leaves a placeholder and raises `failed`
        let failed = std::sync::atomic::AtomicBool::new(false);
        let rows: Vec<ContactRow> = contacts
            .par_iter()
            .map(|c| {
                row(c).unwrap_or_else(|| {
                    failed.store(true, std::sync::atomic::Ordering::Relaxed);
                    ContactRow {
                        a: 0,
                        b: None,
                        frame: [[0.0; 3]; 3],
                        arm_a: [0.0; 3],
                        arm_b: [0.0; 3],
                        w: [0.0; 3],
                        mu: 0.0,
                        w_ii: [0.0; 9],
                        w_inv: [0.0; 9],
                    }
                })
            })
            .collect();
        if failed.into_inner() {
            // the first invalid contact, found sequentially (deterministic)
            let i = contacts.iter().position(|c| row(c).is_none()).unwrap_or(0);
            let bad_body = contacts.get(i).is_none_or(|c| {
                c.body >= world.bodies.len()
                    || matches!(c.partner, Partner::Body(j) if j >= world.bodies.len() || j == c.body)
            });
            return Err(if bad_body {
                StepProblemError::Body(i)
            } else {
                StepProblemError::Singular(i)
            });
        }
        Ok(Self {
            rows,
            mass,
            inv_mass,
            f,
            position: Vec::new(),
        })
    }

    /// The problem with the centres of `world`'s spheres, which only the grid coarse space
    /// reads (`NsgsSettings::coarse_cell` > 0): one n × 24-byte copy, made only then.
    pub fn with_positions(mut self, world: &World) -> Self {
        self.position = world.bodies.iter().map(|b| b.position.to_array()).collect();
        self
    }

    /// Number of contacts.
    pub fn contacts(&self) -> usize {
        self.rows.len()
    }

    /// The same problem as a `coulomb` global problem (sparse M and H), for FCLIB dumps and
    /// for checks against the library's solver.
    pub fn to_global(&self) -> Result<GlobalProblem, ProblemError> {
        let n = 6 * self.mass.len();
        let m = 3 * self.rows.len();
        let mass = CscMatrix {
            nrows: n,
            ncols: n,
            col_ptr: (0..=n).collect(),
            row_idx: (0..n).collect(),
            values: self.mass.iter().flatten().copied().collect(),
        };
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        for (i, c) in self.rows.iter().enumerate() {
            let sides = [(Some(c.a), c.jacobian(false)), (c.b, c.jacobian(true))];
            for (body, j) in sides {
                let Some(body) = body else { continue };
                for (k, row) in j.iter().enumerate() {
                    for (d, &x) in row.iter().enumerate() {
                        if x != 0.0 {
                            rows.push(6 * body + d);
                            cols.push(3 * i + k);
                            vals.push(x);
                        }
                    }
                }
            }
        }
        let h = CscMatrix::from_triplets(n, m, &rows, &cols, &vals)
            .map_err(|source| ProblemError::Sparse { what: "H", source })?;
        let f = self.f.iter().flatten().copied().collect();
        let w = self.rows.iter().flat_map(|c| c.w).collect();
        let mu = self.rows.iter().map(|c| c.mu).collect();
        GlobalProblem::new_unfactored(3, mass, h, f, w, mu)
    }
}

/// A colouring of the contact graph: contacts that share a sphere get different colours.
#[derive(Debug, Clone, PartialEq)]
pub struct Colouring {
    /// contact indices, colour by colour (within a colour in increasing order)
    pub order: Vec<usize>,
    /// colour c is `order[starts[c]..starts[c + 1]]`
    pub starts: Vec<usize>,
}

impl Colouring {
    /// Greedy colouring in contact order: each contact gets the smallest colour not used by
    /// an earlier contact on one of its spheres (at most 1 + the largest number of contacts
    /// on two spheres). Deterministic.
    pub fn greedy(rows: &[ContactRow], bodies: usize) -> Self {
        Self::greedy_pairs(rows.len(), bodies, |i| (rows[i].a, rows[i].b))
    }

    /// [`Colouring::greedy`] of `n` items, item i touching spheres `ends(i)` = (A, B): the
    /// smallest colour not used by an earlier item on A or B. The colours used on each
    /// sphere are kept as a 64-bit mask (no allocation per sphere); past 64 colours on one
    /// sphere the search goes on through overflow lists (same result). Out-of-range
    /// spheres are ignored (the colouring is checked by [`Colouring::is_valid`] anyway).
    pub fn greedy_pairs(
        n: usize,
        bodies: usize,
        ends: impl Fn(usize) -> (usize, Option<usize>),
    ) -> Self {
        let mut mask = vec![0u64; bodies];
        // colours ≥ 64 per sphere (rare: a sphere with more than 64 coloured contacts)
        let mut high: Vec<(usize, u32)> = Vec::new();
        let mut colour = vec![0u32; n];
        let mut ncol = 0u32;
        for (i, slot) in colour.iter_mut().enumerate() {
            let (a, b) = ends(i);
            let b = b.filter(|&j| j < bodies);
            let m = mask.get(a).copied().unwrap_or(0) | b.map_or(0, |j| mask[j]);
            let k = if m != u64::MAX {
                (!m).trailing_zeros()
            } else {
                let used = |k: u32| {
                    high.iter()
                        .any(|&(s, c)| c == k && (s == a || Some(s) == b))
                };
                (64..).find(|&k| !used(k)).unwrap_or(64)
            };
            *slot = k;
            ncol = ncol.max(k + 1);
            for s in std::iter::once(a).chain(b) {
                if s < bodies {
                    if k < 64 {
                        mask[s] |= 1 << k;
                    } else {
                        high.push((s, k));
                    }
                }
            }
        }
        let mut starts = vec![0usize; ncol as usize + 1];
        for &k in &colour {
            starts[k as usize + 1] += 1;
        }
        for k in 0..ncol as usize {
            starts[k + 1] += starts[k];
        }
        let mut next = starts.clone();
        let mut order = vec![0usize; n];
        for (i, &k) in colour.iter().enumerate() {
            order[next[k as usize]] = i;
            next[k as usize] += 1;
        }
        Self { order, starts }
    }

    /// Number of colours.
    pub fn colours(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    /// Whether this is a valid colouring of `rows` on `bodies` spheres: a permutation of the
    /// contacts in which no colour holds two contacts on one sphere, every sphere index
    /// valid and A ≠ B. The parallel sweep relies on it (checked before every solve).
    pub fn is_valid(&self, rows: &[ContactRow], bodies: usize) -> bool {
        self.is_valid_pairs(rows.len(), bodies, |i| (rows[i].a, rows[i].b))
    }

    /// [`Colouring::is_valid`] of `n` items, item i touching bodies `ends(i)` = (A, B) (the
    /// rigid engine's rows, [`crate::rigid`]): a permutation of the items in which no colour
    /// holds two items on one body, every body index below `bodies` and A ≠ B.
    pub fn is_valid_pairs(
        &self,
        n: usize,
        bodies: usize,
        ends: impl Fn(usize) -> (usize, Option<usize>),
    ) -> bool {
        if self.order.len() != n
            || self.starts.first() != Some(&0)
            || self.starts.last() != Some(&n)
            || self.starts.windows(2).any(|w| w[0] > w[1])
        {
            return false;
        }
        let mut seen = vec![false; n];
        let mut stamp = vec![usize::MAX; bodies];
        for c in 0..self.colours() {
            for &i in &self.order[self.starts[c]..self.starts[c + 1]] {
                if i >= n || std::mem::replace(&mut seen[i], true) {
                    return false;
                }
                let (a, b) = ends(i);
                if b == Some(a) {
                    return false;
                }
                for b in std::iter::once(a).chain(b) {
                    if b >= bodies || stamp[b] == c {
                        return false;
                    }
                    stamp[b] = c;
                }
            }
        }
        true
    }
}

/// What one contact update met: the natural-map residual ‖eᵢ‖² of docs/error.md of the pair
/// (u_i, r_i) before the update, ‖r_i‖², ‖u_i‖², and ‖Δr_i‖².
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct UpdateSums {
    /// Σ ‖eᵢ(uᵢ, rᵢ)‖²
    pub residual_sq: f64,
    /// Σ ‖rᵢ‖²
    pub r_sq: f64,
    /// Σ ‖uᵢ‖²
    pub u_sq: f64,
    /// Σ ‖Δrᵢ‖²
    pub change_sq: f64,
}

impl std::ops::Add for UpdateSums {
    type Output = Self;
    /// The componentwise sum of two sums.
    fn add(mut self, o: UpdateSums) -> Self {
        self.residual_sq += o.residual_sq;
        self.r_sq += o.r_sq;
        self.u_sq += o.u_sq;
        self.change_sq += o.change_sq;
        self
    }
}

/// One nonsmooth Gauss–Seidel update of contact `row` (the others frozen), in place:
///
/// - inputs: the row (frame and arms, i.e. J_A and J_B; w_i, μ, W_ii, W_ii⁻¹), M⁻¹ of sphere A (`minv_a`) and the
///   velocity v_A (6 dofs, (ẋ, ω)), the same for sphere B when the partner is a sphere
///   (`b`: (M_B⁻¹, v_B)), and the current impulse r_i (local frame, normal first);
/// - computes u_i = J_A v_A + J_B v_B + w_i, c = u_i − W_ii r_i, and a solution r_i' of the
///   one-contact Coulomb law with u_i' = W_ii r_i' + c (`solve_contact_law`, or the
///   one-contact SOC-QP with s = μ‖u_T‖ where that fails);
/// - with `omega` ≠ 1 (over-relaxation), replaces r_i' by P_{K_μ}(r_i + ω (r_i' − r_i));
/// - writes r_i', and v_A += M_A⁻¹ J_Aᵀ Δr, v_B += M_B⁻¹ J_Bᵀ Δr (so M v − H r stays fixed).
///
/// Returns the sums of the pair (u_i, r_i) met before the update.
#[inline(always)]
pub fn update_contact(
    row: &ContactRow,
    minv_a: &[f64; 6],
    va: &mut [f64; 6],
    b: Option<(&[f64; 6], &mut [f64; 6])>,
    r: &mut [f64; 3],
    omega: f64,
) -> UpdateSums {
    let (minv_b, vb) = match b {
        Some((m, v)) => (Some(m), Some(v)),
        None => (None, None),
    };
    let u = row.velocity_fast(va, vb.as_deref());
    let old = *r;
    let new = relaxed_contact_law(&row.w_ii, &row.w_inv, row.mu, &u, &old, omega, false);
    let delta = [new[0] - old[0], new[1] - old[1], new[2] - old[2]];
    let sums = UpdateSums {
        residual_sq: law::contact_residual_sq(row.mu, &u, &old),
        r_sq: dot3(&old, &old),
        u_sq: dot3(&u, &u),
        change_sq: dot3(&delta, &delta),
    };
    if sums.change_sq != 0.0 {
        // J_Aᵀ Δr = (P, arm_A × P) with P = Σ_k t_k Δr_k the impulse change in world axes
        let f = &row.frame;
        let p: [f64; 3] =
            std::array::from_fn(|d| f[0][d] * delta[0] + f[1][d] * delta[1] + f[2][d] * delta[2]);
        let apply = |v: &mut [f64; 6], minv: &[f64; 6], arm: &[f64; 3], sign: f64| {
            let l = cross(arm, &p);
            for d in 0..3 {
                v[d] += sign * minv[d] * p[d];
                v[3 + d] += sign * minv[3 + d] * l[d];
            }
        };
        apply(va, minv_a, &row.arm_a, 1.0);
        if let (Some(mb), Some(vb)) = (minv_b, vb) {
            apply(vb, mb, &row.arm_b, -1.0);
        }
    }
    *r = new;
    sums
}

/// r_i' of one Gauss–Seidel update of a contact from its velocity u_i at the current impulse
/// r_i = `old`: the solution of the one-contact Coulomb law (2.9) u' = W_ii r' + c with
/// c = u_i − W_ii r_i — in closed form ([`isotropic_law`]) when `isotropic`, else by
/// `solve_contact_law`, or the one-contact SOC-QP with s = μ‖u_T‖ where that fails — then
/// P_{K_μ}(r_i + ω (r_i' − r_i)) when ω ≠ 1 (over-relaxation). The contact update of both
/// sweeps: [`update_contact`] (`isotropic` false) and the sweep of bodies of any shape
/// (`step::rigid::nsgs`).
#[inline(always)]
pub(crate) fn relaxed_contact_law(
    w_ii: &[f64; 9],
    w_inv: &[f64; 9],
    mu: f64,
    u: &[f64; 3],
    old: &[f64; 3],
    omega: f64,
    isotropic: bool,
) -> [f64; 3] {
    let mut c = *u;
    for k in 0..3 {
        c[k] -= w_ii[3 * k] * old[0] + w_ii[3 * k + 1] * old[1] + w_ii[3 * k + 2] * old[2];
    }
    let new = if isotropic {
        isotropic_law(w_ii, mu, &c)
    } else {
        let mut contact = OneContact {
            a: w_ii,
            ainv: w_inv,
            d: 3,
            mu,
            c,
        };
        solve_contact_law(&contact, old, u).unwrap_or_else(|| {
            contact.c[0] += mu * cone::tangent_norm(u);
            solve_contact(&contact, old)
        })
    };
    if omega != 1.0 {
        let mut x: [f64; 3] = std::array::from_fn(|k| old[k] + omega * (new[k] - old[k]));
        cone::project(mu, &mut x);
        x
    } else {
        new
    }
}

/// The solution r of the one-contact Coulomb law (2.9), u = W r + c, for
/// W = diag(w_N, w_T, w_T) (w_T the mean of the block's two tangent entries), μ ∈ [0, ∞):
/// take-off r = 0 when c_N ≥ 0; stick r = −W⁻¹c when it lies in K_μ; else slide:
/// u_N = 0 gives r_N = −c_N / w_N (the normal row does not see r_T), and u_T = w_T r_T + c_T
/// opposite to r_T = −μ r_N τ gives τ = c_T / ‖c_T‖ (u_T = (‖c_T‖ − w_T μ r_N) τ, whose
/// factor is ≥ 0 exactly when sticking failed). The same cases as the library's
/// `solve_contact_law`, whose slip equation needs Newton's method for a general W_ii.
#[inline]
pub(crate) fn isotropic_law(w: &[f64; 9], mu: f64, c: &[f64; 3]) -> [f64; 3] {
    if c[0] >= 0.0 {
        return [0.0; 3];
    }
    let wt = 0.5 * (w[4] + w[8]);
    let rn = -c[0] / w[0];
    let stick = [rn, -c[1] / wt, -c[2] / wt];
    // r_N > 0 (c_N < 0): stick in K_μ iff ‖r_T‖² ≤ (μ r_N)² (no square root)
    let limit = mu * rn;
    if stick[1] * stick[1] + stick[2] * stick[2] <= limit * limit {
        return stick;
    }
    // sticking failed: μ r_N < ‖r_T‖ = ‖c_T‖ / w_T, so ‖c_T‖ > 0
    let ct = (c[1] * c[1] + c[2] * c[2]).sqrt();
    let s = mu * rn / ct;
    [rn, -s * c[1], -s * c[2]]
}

/// Settings of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
pub struct NsgsSettings {
    /// tolerance on the error of docs/error.md (and on the balance residual)
    pub tol: f64,
    /// cap on sweeps
    pub max_sweeps: usize,
    /// wall-clock cap of one solve
    pub time_limit: Option<Duration>,
    /// over-relaxation ω ∈ [1, 2) of the updates from the second sweep on (the first is
    /// plain, so that isolated contacts are solved exactly); halved towards 1
    /// (ω ← 1 + (ω − 1)/2) whenever the sweep residual has not decreased over
    /// [`RELAX_WINDOW`] sweeps, so that a solve ends as plain Gauss–Seidel if needed
    pub relaxation: f64,
    /// a time step of a scene with fewer spheres than this runs on one thread whatever the
    /// pool (`Simulation::step`): below it the pool's dispatch costs more than the second core
    /// saves (docs/scaling.md: 600 beads 1.65 ms on one thread, 2.08 ms on two; 1 000 beads
    /// equal; 2 500 beads 1.29× faster on two). The numbers are the same either way (the
    /// sweep is bitwise independent of the thread count), only the time differs.
    pub serial_below: usize,
    /// a step that Gauss–Seidel leaves above `tol` is finished by the library's solver
    /// (`Params::solver`, `Simulation::step`); false: Gauss–Seidel's result stands, so that
    /// the step depends on this crate's sweep and the one-contact law solve only, not on the
    /// library's solver pipeline (`coulomb corpus` generates its granular class this way, so
    /// that its files do not change when the solver under test does). Not applied to steps
    /// of more than `simulation::LIBRARY_FINISH_MAX_CONTACTS` contacts (memory)
    pub library_finish: bool,
    /// every this many sweeps, a subspace minimization ([`crate::subspace`]): the sweeps'
    /// stick / slip / separation pattern, one sparse Cholesky solve of the active rows, the
    /// result kept only if the error on the stored problem decreased; 0: never
    #[serde(default)]
    pub subspace_every: usize,
    /// every this many sweeps, a two-level (coarse) correction ([`crate::coarse`]): one
    /// Galerkin solve of 3 unknowns per layer of the contact graph (or per interface of
    /// `coarse_cell`), kept only if the error on the stored problem decreased; 0: never
    /// (docs/scaling.md, "Depth")
    #[serde(default)]
    pub coarse_every: usize,
    /// the coarse space of `coarse_every` ([`crate::coarse`]): 0 (default), the layers of the
    /// contact graph; k ≥ 1, one impulse per interface between aggregates of the spheres in
    /// cells of a grid of side k bead diameters (the obstacles 6 more aggregates). Used only
    /// with `coarse_every` > 0
    #[serde(default)]
    pub coarse_cell: usize,
    /// damped-Jacobi smoothing steps of the coarse prolongation (smoothed aggregation,
    /// [`crate::coarse`]); 0 (default): none. Used only with `coarse_every` > 0
    #[serde(default)]
    pub coarse_smooth: usize,
}

/// Levels of the contact graph per aggregate of the coarse correction.
pub const COARSE_LEVELS: usize = 1;

/// Subspace corrections tried in a row while each one lowers the error.
pub const SUBSPACE_REPEAT: usize = 4;

/// Step lengths α = 1, ½, ¼, … tried on each subspace correction.
pub const SUBSPACE_STEPS: usize = 8;

/// Sweeps over which the relaxation's progress is judged.
pub const RELAX_WINDOW: usize = 10;

impl Default for NsgsSettings {
    /// tol 1e-4, at most 20 000 sweeps and 60 s, ω = 1.5, one thread below 1 500 spheres
    /// (docs/scaling.md), the library's finish on.
    fn default() -> Self {
        Self {
            tol: 1e-4,
            max_sweeps: 20_000,
            time_limit: Some(Duration::from_secs(60)),
            relaxation: 1.5,
            serial_below: 1_500,
            library_finish: true,
            subspace_every: 0,
            coarse_every: 0,
            coarse_cell: 0,
            coarse_smooth: 0,
        }
    }
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NsgsStatus {
    /// error and balance residual ≤ tol, evaluated on the stored problem
    Converged,
    /// sweep cap reached with the error above tol
    MaxIterations,
    /// time cap reached with the error above tol
    TimeLimit,
    /// r or v became non-finite, or the problem's per-sphere data have inconsistent lengths
    NumericalError,
}

/// The result of [`solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct NsgsSolution {
    /// r (3 per contact, in the problem's contact order)
    pub r: Vec<f64>,
    /// v = M⁻¹ (f + H r) (6 per sphere)
    pub v: Vec<f64>,
    /// how it ended
    pub status: NsgsStatus,
    /// error of docs/error.md of (r, v) on the stored problem
    pub error: f64,
    /// its scale max(‖q‖, ‖r‖, ‖u‖), q = Hᵀ M⁻¹ f + w
    pub scale: f64,
    /// ‖M v − H r − f‖ / max(1, ‖f‖)
    pub balance_residual: f64,
    /// sweeps done
    pub sweeps: usize,
    /// exact evaluations of the error (each costs about half a sweep)
    pub evaluations: usize,
    /// colours of the contact graph
    pub colours: usize,
    /// subspace corrections kept (`NsgsSettings::subspace_every`)
    pub subspace: usize,
    /// coarse corrections kept (`NsgsSettings::coarse_every`)
    pub coarse: usize,
}

/// Raw velocity storage shared by the updates of one colour, which touch disjoint spheres.
#[derive(Clone, Copy)]
struct Shared(*mut [f64; 6]);
// SAFETY: used only inside one colour of a colouring checked by `Colouring::is_valid`: two
// updates running at once never touch the same sphere, and every index is in bounds.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}
impl Shared {
    #[inline]
    fn at(self, i: usize) -> *mut [f64; 6] {
        // SAFETY: i < bodies (checked by `Colouring::is_valid`)
        unsafe { self.0.add(i) }
    }
}

/// How many contacts ahead a sweep asks for the velocities and inverse masses of
/// ([`prefetch_row`]).
const PREFETCH_AHEAD: usize = 8;

/// Asks the processor to bring the velocities and inverse masses of the beads of `row` into the
/// cache (a hint: no load, no effect on any value). A colour's contacts are spread over the
/// whole heap, so past the caches (10⁵ beads and more) each update otherwise waits for them.
#[inline]
fn prefetch_row(row: &ContactRow, v: *const [f64; 6], inv_mass: &[[f64; 6]]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let hint = |p: *const [f64; 6]| {
            // 48 bytes: the line of its first and of its last entry
            let first = p.cast::<i8>();
            // SAFETY: sse is part of every x86_64 target; a prefetch never faults, whatever
            // the address (these are in bounds anyway: indices checked by the colouring)
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(first);
                _mm_prefetch::<_MM_HINT_T0>(first.wrapping_add(40));
            }
        };
        hint(v.wrapping_add(row.a));
        hint(inv_mass.as_ptr().wrapping_add(row.a));
        if let Some(b) = row.b {
            hint(v.wrapping_add(b));
            hint(inv_mass.as_ptr().wrapping_add(b));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (row, v, inv_mass);
}

/// Updates the contacts `rows` in order (impulses `rs`, velocities behind `v`), each by
/// [`update_contact`], asking for the beads of the contact [`PREFETCH_AHEAD`] places on;
/// returns the sums of the pairs met.
///
/// # Safety
/// No other thread reads or writes the velocities of the beads of `rows` meanwhile (one
/// colour of a valid colouring), and every bead index is in bounds of `v` and `inv_mass`.
#[inline]
unsafe fn sweep_chunk(
    rows: &[ContactRow],
    rs: &mut [[f64; 3]],
    v: Shared,
    inv_mass: &[[f64; 6]],
    omega: f64,
) -> UpdateSums {
    let mut s = UpdateSums::default();
    for (i, (row, r)) in rows.iter().zip(rs.iter_mut()).enumerate() {
        if let Some(ahead) = rows.get(i + PREFETCH_AHEAD) {
            prefetch_row(ahead, v.at(0), inv_mass);
        }
        // SAFETY: by the caller's contract, and a ≠ b (`Colouring::is_valid`)
        let va = unsafe { &mut *v.at(row.a) };
        let b = row.b.map(|j| (&inv_mass[j], unsafe { &mut *v.at(j) }));
        s = s + update_contact(row, &inv_mass[row.a], va, b, r, omega);
    }
    s
}

/// Runs `f` over the chunks of one colour (rows `ids`, impulses `rs`, both in colour order),
/// in parallel when the colour is large, and returns the per-chunk sums in chunk order.
fn for_colour(
    ids: &[ContactRow],
    rs: &mut [[f64; 3]],
    parallel: bool,
    f: impl Fn(&[ContactRow], &mut [[f64; 3]]) -> UpdateSums + Sync,
) -> UpdateSums {
    let chunk = colour_chunk(ids.len());
    if parallel && ids.len() >= PARALLEL_MIN {
        let parts: Vec<UpdateSums> = ids
            .par_chunks(chunk)
            .zip(rs.par_chunks_mut(chunk))
            .map(|(i, r)| f(i, r))
            .collect();
        parts.into_iter().fold(UpdateSums::default(), |a, b| a + b)
    } else {
        ids.chunks(chunk)
            .zip(rs.chunks_mut(chunk))
            .map(|(i, r)| f(i, r))
            .fold(UpdateSums::default(), |a, b| a + b)
    }
}

/// State of a solve: impulses in colour order and velocities per sphere.
struct State<'a> {
    problem: &'a StepProblem,
    colouring: &'a Colouring,
    /// the rows in colour order (a copy: the sweeps stream through memory)
    rows: Vec<ContactRow>,
    /// r in colour order
    r: Vec<[f64; 3]>,
    /// v per sphere
    v: Vec<[f64; 6]>,
    parallel: bool,
    /// the chunks of every colour, for the sweep as one parallel region
    passes: Vec<ColourPass>,
    /// one sum per chunk of [`State::passes`] (the region's output, folded in chunk order)
    chunk_sums: Vec<UpdateSums>,
}

/// The chunks of one colour in a sweep: colour order `start..end`, chunks of `chunk`
/// contacts ([`colour_chunk`]) whose sums go to `first_sum..` of [`State::chunk_sums`].
struct ColourPass {
    start: usize,
    end: usize,
    chunk: usize,
    first_sum: usize,
    /// at least [`PARALLEL_MIN`] contacts (a sweep without such a colour runs on one thread)
    parallel: bool,
}

impl ColourPass {
    /// The passes of `colouring`, and the number of chunks of all of them.
    fn of(colouring: &Colouring) -> (Vec<Self>, usize) {
        let mut sums = 0;
        let passes = (0..colouring.colours())
            .map(|c| {
                let (start, end) = (colouring.starts[c], colouring.starts[c + 1]);
                let chunk = colour_chunk(end - start);
                let pass = ColourPass {
                    start,
                    end,
                    chunk,
                    first_sum: sums,
                    parallel: end - start >= PARALLEL_MIN,
                };
                sums += pass.chunks();
                pass
            })
            .collect();
        (passes, sums)
    }

    fn chunks(&self) -> usize {
        (self.end - self.start).div_ceil(self.chunk)
    }

    /// Contacts of chunk k, in colour order.
    fn chunk_range(&self, k: usize) -> std::ops::Range<usize> {
        let from = self.start + k * self.chunk;
        from..(from + self.chunk).min(self.end)
    }
}

/// Raw storage written by the chunks of one colour (disjoint ranges), or by one chunk per slot.
#[derive(Clone, Copy)]
struct SharedSlice<T>(*mut T);
// SAFETY: used only by `State::sweep_region`, where each index is written by the one thread
// that claimed its chunk, and every index is in bounds.
unsafe impl<T> Send for SharedSlice<T> {}
unsafe impl<T> Sync for SharedSlice<T> {}
impl<T> SharedSlice<T> {
    /// The element i (a method, so that closures capture the whole wrapper, not its pointer).
    #[inline]
    fn at(self, i: usize) -> *mut T {
        // SAFETY: i is in bounds (the callers' ranges come from `ColourPass::of`)
        unsafe { self.0.add(i) }
    }
}

/// The exact evaluation of (r, v) on the stored problem.
#[derive(Debug, Clone, Copy)]
struct Evaluation {
    error: f64,
    scale: f64,
    balance: f64,
}

impl State<'_> {
    /// One sweep over the colours; sums of the pairs met.
    fn sweep(&mut self, omega: f64) -> UpdateSums {
        let threads = rayon::current_num_threads();
        if self.parallel && threads > 1 && self.passes.iter().any(|c| c.parallel) {
            return self.sweep_region(omega, threads);
        }
        let p = self.problem;
        let v = Shared(self.v.as_mut_ptr());
        let mut total = UpdateSums::default();
        for c in 0..self.colouring.colours() {
            let range = self.colouring.starts[c]..self.colouring.starts[c + 1];
            let ids = &self.rows[range.clone()];
            let sums = for_colour(ids, &mut self.r[range], self.parallel, |ids, rs| {
                // SAFETY: within one colour no other update touches spheres a, b ≠ a
                unsafe { sweep_chunk(ids, rs, v, &p.inv_mass, omega) }
            });
            total = total + sums;
        }
        total
    }

    /// [`State::sweep`] as one parallel region instead of one parallel call per colour:
    /// `threads` tasks of one `rayon::scope` (the calling thread runs one) claim the chunks of
    /// each colour in turn, starting on a colour once the one before is done
    /// ([`ColourProgress`]). Same chunks ([`colour_chunk`]) and the same order of summation as
    /// [`for_colour`], hence the same bits for any number of threads.
    fn sweep_region(&mut self, omega: f64, threads: usize) -> UpdateSums {
        let p = self.problem;
        let v = Shared(self.v.as_mut_ptr());
        let r = SharedSlice(self.r.as_mut_ptr());
        let sums = SharedSlice(self.chunk_sums.as_mut_ptr());
        let rows = &self.rows;
        let passes = &self.passes;
        let chunks: Vec<usize> = passes.iter().map(ColourPass::chunks).collect();
        let progress = ColourProgress::new(&chunks);
        let run = |pass: &ColourPass, k: usize| {
            let range = pass.chunk_range(k);
            // SAFETY: chunk k of this colour is claimed by one thread only, so its impulses and
            // its sum slot are written by that thread alone
            let rs = unsafe {
                std::slice::from_raw_parts_mut(r.at(range.start), range.end - range.start)
            };
            // SAFETY: within one colour no other update touches spheres a, b ≠ a, and the
            // colour before is done (`wait_done`)
            let s = unsafe { sweep_chunk(&rows[range], rs, v, &p.inv_mass, omega) };
            // SAFETY: first_sum + k < chunk_sums.len() (ColourPass::of), one writer
            unsafe { *sums.at(pass.first_sum + k) = s };
        };
        let work = || {
            for (c, pass) in passes.iter().enumerate() {
                if c > 0 {
                    progress.wait_done(c - 1);
                }
                while let Some(k) = progress.claim(c) {
                    run(pass, k);
                    progress.finish(c);
                }
            }
        };
        rayon::scope(|s| {
            for _ in 1..threads {
                s.spawn(|_| work());
            }
            work();
        });
        passes.iter().fold(UpdateSums::default(), |total, pass| {
            let slots = &self.chunk_sums[pass.first_sum..pass.first_sum + pass.chunks()];
            total + slots.iter().fold(UpdateSums::default(), |a, &b| a + b)
        })
    }

    /// v = M⁻¹ (f + H r) from scratch (colour by colour: disjoint writes), and the
    /// balance residual ‖M v − H r − f‖ / max(1, ‖f‖) of the result.
    fn recompute_velocity(&mut self) -> f64 {
        let p = self.problem;
        // momentum f + H r
        let mut mom = p.f.clone();
        let shared = Shared(mom.as_mut_ptr());
        for c in 0..self.colouring.colours() {
            let range = self.colouring.starts[c]..self.colouring.starts[c + 1];
            let ids = &self.rows[range.clone()];
            for_colour(ids, &mut self.r[range], self.parallel, |ids, rs| {
                for (row, r) in ids.iter().zip(rs.iter()) {
                    let sides = [
                        (Some(row.a), row.jacobian(false)),
                        (row.b, row.jacobian(true)),
                    ];
                    for (body, j) in sides {
                        let Some(body) = body else { continue };
                        // SAFETY: as in `sweep`
                        let m = unsafe { &mut *shared.at(body) };
                        for d in 0..6 {
                            m[d] += j[0][d] * r[0] + j[1][d] * r[1] + j[2][d] * r[2];
                        }
                    }
                }
                UpdateSums::default()
            });
        }
        let inv = &p.inv_mass;
        let mass = &p.mass;
        // per chunk of spheres: Σ res², Σ f² and the largest |entry| (res = M v − (f + H r)),
        // combined in chunk order
        let parts: Vec<[f64; 3]> = self
            .v
            .par_chunks_mut(CHUNK)
            .zip(mom.par_chunks(CHUNK))
            .enumerate()
            .map(|(c, (vs, ms))| {
                let mut acc = [0.0f64; 3];
                for (k, (v, m)) in vs.iter_mut().zip(ms).enumerate() {
                    let b = c * CHUNK + k;
                    for d in 0..6 {
                        v[d] = m[d] * inv[b][d];
                        let res = mass[b][d] * v[d] - m[d];
                        let f = p.f[b][d];
                        acc[0] += res * res;
                        acc[1] += f * f;
                        acc[2] = acc[2].max(res.abs()).max(f.abs());
                    }
                }
                acc
            })
            .collect();
        let (mut res_sq, mut f_sq, mut max) = (0.0, 0.0, 0.0f64);
        for a in parts {
            res_sq += a[0];
            f_sq += a[1];
            max = max.max(a[2]);
        }
        if (1e-150..=1e150).contains(&max) && res_sq.is_finite() && f_sq.is_finite() {
            // ‖res‖ / max(1, ‖f‖), the value of `law::relative_norm` without its scaling
            res_sq.sqrt() / f_sq.sqrt().max(1.0)
        } else {
            let res: Vec<f64> = self
                .v
                .iter()
                .zip(&mom)
                .zip(mass)
                .flat_map(|((v, m), ms)| std::array::from_fn::<f64, 6, _>(|d| ms[d] * v[d] - m[d]))
                .collect();
            let f: Vec<f64> = p.f.iter().flatten().copied().collect();
            law::relative_norm(&res, &f)
        }
    }

    /// The error of docs/error.md on the stored problem from the current r, with v
    /// recomputed from scratch: u = Hᵀ v + w, scale max(‖q‖, ‖r‖, ‖u‖).
    fn evaluate(&mut self, q_norm: f64) -> Evaluation {
        let balance = self.recompute_velocity();
        let v = &self.v;
        let parts: Vec<UpdateSums> = self
            .rows
            .par_chunks(CHUNK)
            .zip(self.r.par_chunks(CHUNK))
            .map(|(ids, rs)| {
                let mut s = UpdateSums::default();
                for (row, r) in ids.iter().zip(rs) {
                    let u = row.velocity(&v[row.a], row.b.map(|j| &v[j]));
                    s.residual_sq += law::contact_residual_sq(row.mu, &u, r);
                    s.r_sq += r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                    s.u_sq += u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
                }
                s
            })
            .collect();
        let s = parts.into_iter().fold(UpdateSums::default(), |a, b| a + b);
        // the plain sums are exact unless some square overflows: then the library's scaled
        // evaluation (sequential) on the flattened vectors
        const LIMIT: f64 = 1e150;
        let plain = [s.residual_sq, s.r_sq, s.u_sq, q_norm * q_norm]
            .iter()
            .all(|x| x.is_finite() && *x < LIMIT);
        if plain {
            let scale = q_norm.max(s.r_sq.sqrt()).max(s.u_sq.sqrt());
            let abs = s.residual_sq.sqrt();
            let error = if scale > f64::EPSILON {
                abs / scale
            } else {
                abs
            };
            Evaluation {
                error,
                scale,
                balance,
            }
        } else {
            let (r, u, mu) = self.flat_ru();
            let m = law::error_measure(3, &mu, &r, &u, q_norm);
            Evaluation {
                error: m.error,
                scale: m.scale,
                balance,
            }
        }
    }

    /// r, u = Hᵀ v + w and μ flattened in the problem's contact order.
    fn flat_ru(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let p = self.problem;
        let n = p.rows.len();
        let mut r = vec![0.0; 3 * n];
        for (&i, ri) in self.colouring.order.iter().zip(&self.r) {
            r[3 * i..3 * i + 3].copy_from_slice(ri);
        }
        let u = velocity_of(p, &self.v);
        let mu = p.rows.iter().map(|c| c.mu).collect();
        (r, u, mu)
    }
}

/// u = Hᵀ v + w (v per sphere), in contact order.
fn velocity_of(p: &StepProblem, v: &[[f64; 6]]) -> Vec<f64> {
    p.rows
        .par_iter()
        .flat_map_iter(|row| row.velocity(&v[row.a], row.b.map(|j| &v[j])))
        .collect()
}

/// ‖q‖, q = Hᵀ M⁻¹ f + w (the Delassus vector of docs/error.md), matrix-free.
pub fn q_norm(p: &StepProblem) -> f64 {
    let vfree: Vec<[f64; 6]> =
        p.f.iter()
            .zip(&p.inv_mass)
            .map(|(f, m)| std::array::from_fn(|d| f[d] * m[d]))
            .collect();
    law::norm(&velocity_of(p, &vfree))
}

/// Solves the step problem by body-level nonsmooth Gauss–Seidel from the impulses `r0`
/// (3 per contact, contact order; the velocities are v = M⁻¹ (f + H r0)), colouring the
/// contact graph with [`Colouring::greedy`]. `parallel`: run large colours on the rayon
/// pool (the numbers do not depend on it nor on the pool's size).
pub fn solve(
    problem: &StepProblem,
    r0: &[f64],
    settings: &NsgsSettings,
    parallel: bool,
) -> NsgsSolution {
    let colouring = Colouring::greedy(&problem.rows, problem.mass.len());
    solve_coloured(problem, &colouring, r0, settings, parallel)
}

/// [`solve`] with a given colouring (checked: an invalid one is replaced by one colour per
/// contact, i.e. the sequential sweep in contact order).
pub fn solve_coloured(
    problem: &StepProblem,
    colouring: &Colouring,
    r0: &[f64],
    settings: &NsgsSettings,
    parallel: bool,
) -> NsgsSolution {
    let start = Instant::now();
    let n = problem.rows.len();
    let bodies = problem.mass.len();
    // per-sphere data of inconsistent lengths (a hand-made problem): refused, not indexed
    if problem.f.len() != bodies || problem.inv_mass.len() != bodies {
        return NsgsSolution {
            r: vec![0.0; 3 * n],
            v: Vec::new(),
            status: NsgsStatus::NumericalError,
            error: f64::NAN,
            scale: f64::NAN,
            balance_residual: f64::NAN,
            sweeps: 0,
            evaluations: 0,
            colours: 0,
            subspace: 0,
            coarse: 0,
        };
    }
    let sequential;
    let colouring = if colouring.is_valid(&problem.rows, bodies) {
        colouring
    } else {
        sequential = Colouring {
            order: (0..n).collect(),
            starts: (0..=n).collect(),
        };
        &sequential
    };
    let mut r: Vec<[f64; 3]> = colouring
        .order
        .par_iter()
        .map(|&i| match r0.get(3 * i..3 * i + 3) {
            Some(x) if x.iter().all(|v| v.is_finite()) => {
                let mut x = [x[0], x[1], x[2]];
                cone::project(problem.rows[i].mu, &mut x);
                x
            }
            _ => [0.0; 3],
        })
        .collect();
    if r.len() != n {
        r.resize(n, [0.0; 3]);
    }
    let rows: Vec<ContactRow> = colouring
        .order
        .par_iter()
        .map(|&i| problem.rows[i].clone())
        .collect();
    let (passes, chunk_count) = ColourPass::of(colouring);
    let mut state = State {
        problem,
        colouring,
        rows,
        r,
        v: vec![[0.0; 6]; bodies],
        parallel,
        passes,
        chunk_sums: vec![UpdateSums::default(); chunk_count],
    };
    let qn = q_norm(problem);
    let tol = settings.tol;
    let deadline = coulomb::deadline::deadline(start, settings.time_limit);
    let mut eval = state.evaluate(qn);
    let mut evaluations = 1;
    let mut sweeps = 0;
    // after a failed exact check, wait this many sweeps before the next one
    let mut wait = 0usize;
    let mut backoff = 1usize;
    let mut omega = if settings.relaxation.is_finite() {
        settings.relaxation.clamp(1.0, 1.99)
    } else {
        1.0
    };
    let mut window_start = f64::INFINITY;
    let mut subspace = 0usize;
    let mut coarse = 0usize;
    let aggregates = (settings.coarse_every > 0).then(|| {
        let space = if settings.coarse_cell == 0 {
            crate::coarse::Aggregates::new(&state.rows, bodies, COARSE_LEVELS)
        } else {
            crate::coarse::Aggregates::cells(&state.rows, &problem.position, settings.coarse_cell)
        };
        space.smoothed(&state.rows, &problem.inv_mass, settings.coarse_smooth)
    });
    let ok = |e: &Evaluation| e.error.is_finite() && e.error <= tol && e.balance <= tol;
    let status = loop {
        if !eval.error.is_finite() {
            break NsgsStatus::NumericalError;
        }
        if ok(&eval) {
            break NsgsStatus::Converged;
        }
        if sweeps >= settings.max_sweeps {
            break NsgsStatus::MaxIterations;
        }
        if deadline.is_some_and(|d| Instant::now() >= d) {
            break NsgsStatus::TimeLimit;
        }
        // the first sweep is plain Gauss–Seidel: it solves isolated contacts exactly
        let s = state.sweep(if sweeps == 0 { 1.0 } else { omega });
        sweeps += 1;
        let due_subspace = settings.subspace_every > 0 && sweeps % settings.subspace_every == 0;
        let due_coarse = settings.coarse_every > 0 && sweeps % settings.coarse_every == 0;
        if due_subspace || due_coarse {
            eval = state.evaluate(qn);
            evaluations += 1;
            for _ in 0..SUBSPACE_REPEAT {
                if ok(&eval) || !eval.error.is_finite() {
                    break;
                }
                let target = if due_subspace {
                    crate::subspace::correction(&state.rows, &problem.inv_mass, &state.r, &state.v)
                        .map(|t| t.0)
                } else {
                    aggregates.as_ref().and_then(|agg| {
                        crate::coarse::correction(
                            &state.rows,
                            &problem.inv_mass,
                            agg,
                            &state.r,
                            &state.v,
                        )
                    })
                };
                let Some(target) = target else {
                    break;
                };
                // projected line search on the error: Π(r + α (target − r)), α = 1, ½, …
                let saved = state.r.clone();
                let mut best: Option<(Evaluation, Vec<[f64; 3]>)> = None;
                let mut alpha = 1.0;
                for _ in 0..SUBSPACE_STEPS {
                    state.r = saved
                        .iter()
                        .zip(&target)
                        .zip(&state.rows)
                        .map(|((r, t), row)| {
                            let mut x: [f64; 3] =
                                std::array::from_fn(|k| r[k] + alpha * (t[k] - r[k]));
                            cone::project(row.mu, &mut x);
                            x
                        })
                        .collect();
                    let after = state.evaluate(qn);
                    evaluations += 1;
                    let better = after.error.is_finite()
                        && after.error < best.as_ref().map_or(eval.error, |b| b.0.error);
                    if better {
                        best = Some((after, state.r.clone()));
                    } else if best.is_some() {
                        break;
                    }
                    alpha *= 0.5;
                }
                match best {
                    Some((e, r)) => {
                        state.r = r;
                        state.recompute_velocity();
                        eval = e;
                        if due_subspace {
                            subspace += 1;
                        } else {
                            coarse += 1;
                        }
                    }
                    None => {
                        state.r = saved;
                        state.recompute_velocity();
                        break;
                    }
                }
            }
            continue;
        }
        let scale = qn.max(s.r_sq.sqrt()).max(s.u_sq.sqrt());
        let proxy = if scale > f64::EPSILON {
            s.residual_sq.sqrt() / scale
        } else {
            s.residual_sq.sqrt()
        };
        if sweeps % RELAX_WINDOW == 0 {
            if omega > 1.0 && proxy.partial_cmp(&window_start) != Some(std::cmp::Ordering::Less) {
                omega = 1.0 + 0.5 * (omega - 1.0);
                if omega < 1.01 {
                    omega = 1.0;
                }
            }
            window_start = proxy;
        }
        if !proxy.is_finite() {
            eval = state.evaluate(qn);
            evaluations += 1;
            continue;
        }
        wait = wait.saturating_sub(1);
        let last = sweeps >= settings.max_sweeps || deadline.is_some_and(|d| Instant::now() >= d);
        if (proxy <= tol && wait == 0) || last {
            eval = state.evaluate(qn);
            evaluations += 1;
            if !ok(&eval) {
                backoff = (2 * backoff).min(16);
                wait = backoff;
            }
        }
    };
    let mut r = vec![0.0; 3 * n];
    for (&i, ri) in colouring.order.iter().zip(&state.r) {
        r[3 * i..3 * i + 3].copy_from_slice(ri);
    }
    NsgsSolution {
        r,
        v: state.v.iter().flatten().copied().collect(),
        status,
        error: eval.error,
        scale: eval.scale,
        balance_residual: eval.balance,
        sweeps,
        evaluations,
        colours: colouring.colours(),
        subspace,
        coarse,
    }
}

/// The error of docs/error.md of impulses `r` (contact order) on the stored problem, with
/// v = M⁻¹ (f + H r) computed sequentially in contact order: (error, scale, balance
/// residual, v). A plain reference evaluation (tests, checks).
pub fn evaluate(problem: &StepProblem, r: &[f64]) -> (f64, f64, f64, Vec<f64>) {
    let mut mom = problem.f.clone();
    for (i, row) in problem.rows.iter().enumerate() {
        let ri = [r[3 * i], r[3 * i + 1], r[3 * i + 2]];
        for (body, j) in [
            (Some(row.a), row.jacobian(false)),
            (row.b, row.jacobian(true)),
        ] {
            if let Some(m) = body.and_then(|b| mom.get_mut(b)) {
                for d in 0..6 {
                    m[d] += j[0][d] * ri[0] + j[1][d] * ri[1] + j[2][d] * ri[2];
                }
            }
        }
    }
    let v: Vec<[f64; 6]> = mom
        .iter()
        .zip(&problem.inv_mass)
        .map(|(m, inv)| std::array::from_fn(|d| m[d] * inv[d]))
        .collect();
    let res: Vec<f64> = v
        .iter()
        .zip(&mom)
        .zip(&problem.mass)
        .flat_map(|((v, m), mass)| std::array::from_fn::<f64, 6, _>(|d| mass[d] * v[d] - m[d]))
        .collect();
    let f: Vec<f64> = problem.f.iter().flatten().copied().collect();
    let balance = law::relative_norm(&res, &f);
    let u = velocity_of(problem, &v);
    let mu: Vec<f64> = problem.rows.iter().map(|c| c.mu).collect();
    let m = law::error_measure(3, &mu, r, &u, q_norm(problem));
    (m.error, m.scale, balance, v.into_iter().flatten().collect())
}

#[cfg(feature = "unit-tests")]
pub mod tests;
