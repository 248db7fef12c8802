//! Subspace minimization of the step problem (Gauss–Seidel with subspace minimization,
//! Silcowitz, Niebe, Erleben 2010): the sweeps of [`crate::nsgs`] identify which contacts
//! separate, stick or slide; one sparse linear solve on that active set then moves the load
//! through the whole pile at once, where a sweep moves it by about one layer of contacts.
//!
//! From the current (r, u) of the global problem (2.10) (u = Hᵀ v + w, v = M⁻¹ (f + H r)):
//! - separated (r_N = 0): r_i stays 0;
//! - sticking (r_i inside the cone K_i, ‖r_T‖ < (1 − δ) μ r_N): all three rows, u_i = 0;
//! - sliding (r_i on the boundary of K_i): the normal row u_N,i = 0 with r_T,i fixed (the
//!   tangential impulse then changes by the sweeps only, which keeps the system symmetric).
//!
//! With C_A the columns of H of the unknowns (3 per sticking contact, the normal column per
//! sliding one), the change Δ of the unknowns that zeroes their rows of u solves
//! (C_Aᵀ M⁻¹ C_A + ε D) Δ = −u_A, the Delassus block W_AA of the active rows (M is block
//! diagonal, so W_AA is assembled exactly, body by body) shifted by ε times its diagonal D,
//! which keeps the Cholesky factorization defined on hyperstatic packings (W_AA singular).
//! The caller tries Π(r + α Δ) (each contact projected on its cone) for α = 1, ½, ¼, … and
//! keeps the best only if the error of docs/error.md on the stored problem decreased
//! ([`crate::nsgs::solve_coloured`]); every verdict stays that of the stored problem.

use crate::step::rows::ContactRow;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::factorize_symbolic_cholesky;
use faer::sparse::{SparseColMat, Triplet};
use faer::Side;

/// Relative margin δ of the sticking test ‖r_T‖ < (1 − δ) μ r_N.
pub const STICK_MARGIN: f64 = 1e-3;

/// Shift ε of the diagonal (relative to each diagonal entry of W_AA).
pub const SHIFT: f64 = 1e-6;

/// The largest active system factored (unknowns); above it no correction is tried.
pub const MAX_UNKNOWNS: usize = 3_000_000;

/// What one correction classified and solved.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Correction {
    /// contacts that stick (3 unknowns each)
    pub stick: usize,
    /// contacts that slide (1 unknown each)
    pub slide: usize,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Free,
    Stick,
    Slide,
}

/// The target impulses r + Δ (in the order of `rows`, not yet projected on their cones: the
/// caller searches Π(r + α Δ), α = 1, ½, …, on the error) from impulses
/// `r` and velocities `v` (v = M⁻¹ (f + H r), per sphere), or `None` when no contact is
/// active, the system is too large, or its factorization fails or gives a non-finite Δ.
pub(crate) fn correction(
    rows: &[ContactRow],
    inv_mass: &[[f64; 6]],
    r: &[[f64; 3]],
    v: &[[f64; 6]],
) -> Option<(Vec<[f64; 3]>, Correction)> {
    // classify, number the unknowns
    let mut kind = Vec::with_capacity(rows.len());
    let mut start = Vec::with_capacity(rows.len());
    let mut unknowns = 0usize;
    let mut stats = Correction::default();
    for (row, ri) in rows.iter().zip(r) {
        let rt = (ri[1] * ri[1] + ri[2] * ri[2]).sqrt();
        let k = if ri[0].is_nan() || ri[0] <= 0.0 {
            Kind::Free
        } else if row.mu > 0.0 && rt < (1.0 - STICK_MARGIN) * row.mu * ri[0] {
            stats.stick += 1;
            Kind::Stick
        } else {
            stats.slide += 1;
            Kind::Slide
        };
        start.push(unknowns);
        unknowns += match k {
            Kind::Free => 0,
            Kind::Stick => 3,
            Kind::Slide => 1,
        };
        kind.push(k);
    }
    if unknowns == 0 || unknowns > MAX_UNKNOWNS {
        return None;
    }
    // the columns of C_A per sphere: (sphere, unknown, column restricted to the sphere)
    let mut cols: Vec<(usize, usize, [f64; 6])> = Vec::with_capacity(2 * unknowns);
    let mut rhs = vec![0.0; unknowns];
    for (i, row) in rows.iter().enumerate() {
        let n = match kind[i] {
            Kind::Free => continue,
            Kind::Stick => 3,
            Kind::Slide => 1,
        };
        let u = row.velocity(&v[row.a], row.b.map(|j| &v[j]));
        for k in 0..n {
            rhs[start[i] + k] = -u[k];
        }
        for (body, side) in [(Some(row.a), false), (row.b, true)] {
            let Some(body) = body else { continue };
            let j = row.jacobian(side);
            for (k, jk) in j.iter().enumerate().take(n) {
                cols.push((body, start[i] + k, *jk));
            }
        }
    }
    cols.sort_by_key(|c| (c.0, c.1));
    // W_AA body by body (lower triangle), its diagonal for the shift
    let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(8 * cols.len());
    let mut diag = vec![0.0; unknowns];
    let mut b0 = 0;
    while b0 < cols.len() {
        let body = cols[b0].0;
        let mut b1 = b0;
        while b1 < cols.len() && cols[b1].0 == body {
            b1 += 1;
        }
        let minv = &inv_mass[body];
        for p in b0..b1 {
            let gp: [f64; 6] = std::array::from_fn(|d| cols[p].2[d] * minv[d]);
            for q in b0..=p {
                let x: f64 = (0..6).map(|d| gp[d] * cols[q].2[d]).sum();
                let (a, b) = (cols[p].1, cols[q].1);
                if a == b {
                    diag[a] += x;
                }
                trip.push(Triplet::new(a.max(b), a.min(b), x));
            }
        }
        b0 = b1;
    }
    for (p, d) in diag.iter().enumerate() {
        trip.push(Triplet::new(p, p, SHIFT * d.max(f64::MIN_POSITIVE)));
    }
    cholesky_solve(unknowns, trip, &mut rhs)?;
    let out = rows
        .iter()
        .zip(r)
        .enumerate()
        .map(|(i, (_, ri))| {
            let mut x = *ri;
            match kind[i] {
                Kind::Free => return x,
                Kind::Stick => {
                    for k in 0..3 {
                        x[k] += rhs[start[i] + k];
                    }
                }
                Kind::Slide => x[0] += rhs[start[i]],
            }
            x
        })
        .collect();
    Some((out, stats))
}

/// Solves A x = b in place for a sparse symmetric positive definite A of order `n` given by
/// its lower triangle (`lower`: triplets, duplicates summed), by faer's sparse Cholesky
/// factorization run sequentially (the same bits whatever the thread count); `None` when
/// the matrix cannot be built or factored, or x is not finite. Shared by the subspace
/// minimization and the coarse correction ([`crate::coarse`]).
pub(crate) fn cholesky_solve(
    n: usize,
    lower: Vec<Triplet<usize, usize, f64>>,
    b: &mut [f64],
) -> Option<()> {
    if b.len() != n {
        return None;
    }
    let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &lower).ok()?;
    drop(lower);
    let symbolic = factorize_symbolic_cholesky(
        mat.symbolic(),
        Side::Lower,
        Default::default(),
        Default::default(),
    )
    .ok()?;
    let par = faer::Par::Seq;
    let mut l_values = vec![0.0; symbolic.len_val()];
    let scratch = StackReq::any_of(&[
        symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        symbolic.solve_in_place_scratch::<f64>(1, par),
    ]);
    let mut mem = MemBuffer::try_new(scratch).ok()?;
    let llt = symbolic
        .factorize_numeric_llt(
            &mut l_values,
            mat.as_ref(),
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .ok()?;
    llt.solve_in_place_with_conj(
        faer::Conj::No,
        faer::MatMut::from_column_major_slice_mut(b, n, 1),
        par,
        MemStack::new(&mut mem),
    );
    b.iter().all(|x| x.is_finite()).then_some(())
}

#[cfg(feature = "unit-tests")]
pub mod tests;
