//! The joints' equality rows of a step solved together (issue 53): in the incremental problem
//! (2.10) with equality rows,
//!
//! ```text
//!     M v = H r + G λ + f,     u = Hᵀ v + w,     Gᵀ v + b = 0,     (uⁱ, rⁱ) ∈ C(eⁱ, μⁱ),
//! ```
//!
//! the Gauss–Seidel of [`super::nsgs`] holds r (and the motors', limits' and friction's
//! multipliers) fixed while it updates the multipliers λ_E of all the equality rows at once:
//! with the Schur complement W_EE = G_Eᵀ M⁻¹ G_E over those rows (M diagonal per body, so
//! W_EE is sparse: rows couple when their joints share a moving body; block-tridiagonal for a
//! chain),
//!
//! ```text
//!     W_EE δ = −(G_Eᵀ v + b_E),     λ_E += δ,     v += M⁻¹ G_E δ,
//! ```
//!
//! which makes every equality row hold exactly for the current r, however long the chain of
//! joints (a per-joint block solve carries a correction one joint further per sweep).
//!
//! W_EE is scaled to unit diagonal, S = D^{-1/2} W_EE D^{-1/2}, and factored once per step by
//! faer's sparse Cholesky (AMD ordering, simplicial, sequential: the same bits whatever the
//! thread count).
//!
//! # Redundant joints
//! W_EE is singular when rows are dependent (a door on two hinges, a closed loop): null(W_EE)
//! = null(G_E). A pivot of S at or below [`DEPENDENT_PIVOT`] (the squared sine of the angle,
//! in the metric of M⁻¹, between the row and the span of the rows factored before it) marks a
//! row dependent on those: it is replaced by [`DROPPED_PIVOT`] (faer's dynamic
//! regularization), which leaves the factor of the other rows exact and gives the dependent
//! row δ ≈ 0 (of order 1e-30 of the others'), the behaviour of the per-joint block solve
//! ([`crate::bodies::joints::solve_spd`]). On a consistent system (Gᵀ v + b in the range of
//! Gᵀ, as C(q)/h is after the position projection) the accepted rows' solution satisfies the
//! dependent rows too; no regularization of the accepted rows, no iterative refinement needed.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Par, Side};

/// A pivot of the unit-diagonal S = D^{-1/2} W_EE D^{-1/2} at or below this marks its row as
/// dependent on the rows factored before it (an angle below about 3e-6 rad from their span in
/// the M⁻¹ metric; rounding leaves an exactly dependent row a pivot of order n ε).
pub const DEPENDENT_PIVOT: f64 = 1e-11;

/// The value a dependent row's pivot is replaced by: its δ is ≈ 0 and its column of L
/// (entries ≤ √(pivot) before the division) vanishes.
pub const DROPPED_PIVOT: f64 = 1e30;

/// One equality row: where its multiplier sits in λ, its Jacobians on its bodies' dofs
/// (v, Ω body frame) and b.
#[derive(Debug, Clone, PartialEq)]
pub struct EqRow {
    /// index of the row's multiplier in λ
    pub lambda: usize,
    /// A's block and J_A (None: fixed)
    pub a: Option<(usize, [f64; 6])>,
    /// B's block and J_B (None: the world or a fixed body)
    pub b: Option<(usize, [f64; 6])>,
    /// b of Gᵀ v + b
    pub rhs: f64,
}

/// The factored W_EE of a step's equality rows ([`EqualitySolve::new`]).
#[derive(Debug)]
pub struct EqualitySolve {
    rows: Vec<EqRow>,
    /// D^{-1/2}: 1/√(W_kk) (1 for a zero row)
    scale: Vec<f64>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    dependent: usize,
}

impl PartialEq for EqualitySolve {
    fn eq(&self, other: &Self) -> bool {
        self.rows == other.rows && self.scale == other.scale && self.l_values == other.l_values
    }
}

impl EqualitySolve {
    /// Assembles W_EE = G_Eᵀ M⁻¹ G_E of `rows` (`mass`: the diagonal of M per moving body)
    /// and factors it; None when there is no row, a value is not finite, or faer refuses.
    pub fn new(rows: Vec<EqRow>, mass: &[[f64; 6]]) -> Option<Self> {
        let n = rows.len();
        if n == 0 {
            return None;
        }
        // (body, row, J M⁻¹) of each row's side on a moving body, grouped by body
        let mut sides: Vec<(usize, usize, [f64; 6], [f64; 6])> = Vec::with_capacity(2 * n);
        for (k, row) in rows.iter().enumerate() {
            for (blk, j) in row.a.iter().chain(row.b.iter()) {
                let m = mass.get(*blk)?;
                sides.push((*blk, k, *j, std::array::from_fn(|d| j[d] / m[d])));
            }
        }
        sides.sort_by_key(|s| (s.0, s.1));
        let mut diag = vec![0.0; n];
        let mut entries: Vec<(usize, usize, f64)> = Vec::with_capacity(4 * sides.len());
        let mut s0 = 0;
        while s0 < sides.len() {
            let mut s1 = s0;
            while s1 < sides.len() && sides[s1].0 == sides[s0].0 {
                s1 += 1;
            }
            for p in s0..s1 {
                for q in s0..=p {
                    let x: f64 = (0..6).map(|d| sides[p].3[d] * sides[q].2[d]).sum();
                    let (r, c) = (sides[q].1, sides[p].1);
                    if r == c {
                        diag[r] += x;
                    }
                    // the lower triangle: row ≥ column
                    entries.push((c.max(r), c.min(r), x));
                }
            }
            s0 = s1;
        }
        if !diag.iter().all(|d| d.is_finite()) {
            return None;
        }
        let scale: Vec<f64> = diag
            .iter()
            .map(|&d| if d > 0.0 { 1.0 / d.sqrt() } else { 1.0 })
            .collect();
        let mut trip: Vec<Triplet<usize, usize, f64>> = entries
            .iter()
            .map(|&(r, c, x)| Triplet::new(r, c, x * scale[r] * scale[c]))
            .collect();
        // every diagonal entry present (a zero row gets a zero pivot: dependent)
        trip.extend((0..n).map(|k| Triplet::new(k, k, 0.0)));
        if !trip.iter().all(|t| t.val.is_finite()) {
            return None;
        }
        let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip).ok()?;
        drop(trip);
        let symbolic = factorize_symbolic_cholesky(
            mat.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
                ..Default::default()
            },
        )
        .ok()?;
        // sequential: the same bits whatever the thread count
        let par = Par::Seq;
        let mut l_values = vec![0.0; symbolic.len_val()];
        let mut mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .ok()?;
        symbolic
            .factorize_numeric_llt(
                &mut l_values,
                mat.as_ref(),
                Side::Lower,
                LltRegularization {
                    dynamic_regularization_delta: DROPPED_PIVOT,
                    dynamic_regularization_epsilon: DEPENDENT_PIVOT,
                },
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .ok()?;
        if !l_values.iter().all(|x| x.is_finite()) {
            return None;
        }
        let dependent = count_dropped(&symbolic, &l_values);
        Some(Self {
            rows,
            scale,
            symbolic,
            l_values,
            dependent,
        })
    }

    /// Number of rows found dependent on the others (given no update).
    pub fn dependent(&self) -> usize {
        self.dependent
    }

    /// (Gᵀ v + b)_k of each equality row.
    pub fn residual(&self, v: &[[f64; 6]]) -> Vec<f64> {
        self.rows
            .iter()
            .map(|row| {
                let mut u = row.rhs;
                for (blk, j) in row.a.iter().chain(row.b.iter()) {
                    u += (0..6).map(|d| j[d] * v[*blk][d]).sum::<f64>();
                }
                u
            })
            .collect()
    }

    /// δ = W_EE⁻¹ (−(G_Eᵀ v + b_E)) (dependent rows: ≈ 0), added to λ_E, and v += M⁻¹ G_E δ.
    /// Nothing changes if the solve gives a non-finite value.
    pub fn update(&self, mass: &[[f64; 6]], v: &mut [[f64; 6]], lambda: &mut [f64]) {
        let n = self.rows.len();
        let mut x: Vec<f64> = self
            .residual(v)
            .iter()
            .zip(&self.scale)
            .map(|(u, s)| -u * s)
            .collect();
        let par = Par::Seq;
        let Ok(mut mem) = MemBuffer::try_new(StackReq::any_of(&[self
            .symbolic
            .solve_in_place_scratch::<f64>(1, par)]))
        else {
            return;
        };
        LltRef::<usize, f64>::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            faer::Conj::No,
            faer::MatMut::from_column_major_slice_mut(&mut x, n, 1),
            par,
            MemStack::new(&mut mem),
        );
        if !x.iter().all(|d| d.is_finite()) {
            return;
        }
        for ((row, d), s) in self.rows.iter().zip(&x).zip(&self.scale) {
            let d = d * s;
            if d == 0.0 {
                continue;
            }
            lambda[row.lambda] += d;
            for (blk, j) in row.a.iter().chain(row.b.iter()) {
                let m = &mass[*blk];
                let vb = &mut v[*blk];
                for c in 0..6 {
                    vb[c] += j[c] * d / m[c];
                }
            }
        }
    }
}

/// The rows whose pivot was replaced by [`DROPPED_PIVOT`]: the diagonal of L (the first entry
/// of each column of the simplicial factor) at √DROPPED_PIVOT.
fn count_dropped(symbolic: &SymbolicCholesky<usize>, l_values: &[f64]) -> usize {
    use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
    let SymbolicCholeskyRaw::Simplicial(s) = symbolic.raw() else {
        return 0;
    };
    let col_ptr = s.col_ptr();
    let big = 0.5 * DROPPED_PIVOT.sqrt();
    (0..s.nrows())
        .filter(|&k| l_values[col_ptr[k]] >= big)
        .count()
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    /// A point row (axis `e`) between blocks a and b at lever arms zero.
    fn point(lambda: usize, a: usize, b: Option<usize>, e: usize, rhs: f64) -> EqRow {
        let mut j = [0.0; 6];
        j[e] = 1.0;
        EqRow {
            lambda,
            a: Some((a, j)),
            b: b.map(|b| (b, j.map(|x| -x))),
            rhs,
        }
    }

    pub fn a_chain_of_point_rows_is_solved_in_one_update() {
        // 200 unit masses on a line, each tied to the next along x, the first to the world:
        // one update makes every row hold, whatever the length
        let n = 200;
        let mass = vec![[1.0; 6]; n];
        let mut rows = vec![point(0, 0, None, 0, 0.5)];
        for i in 1..n {
            rows.push(point(i, i, Some(i - 1), 0, 0.01 * i as f64));
        }
        let eq = EqualitySolve::new(rows, &mass).unwrap();
        assert_eq!(eq.dependent(), 0);
        let mut v: Vec<[f64; 6]> = (0..n)
            .map(|i| [(i as f64).sin(), 0.0, 0.0, 0.0, 0.0, 0.0])
            .collect();
        let mut lambda = vec![0.0; n];
        eq.update(&mass, &mut v, &mut lambda);
        let worst = eq.residual(&v).iter().map(|x| x.abs()).fold(0.0, f64::max);
        assert!(worst < 1e-10, "{worst}");
    }

    pub fn dependent_rows_get_no_update_and_the_others_hold() {
        // two bodies tied along x twice (a door on two hinges in one dimension) and to the
        // world: rows 1 and 2 identical, W_EE singular, the system consistent
        let mass = vec![[2.0; 6], [3.0; 6]];
        let rows = vec![
            point(0, 0, None, 0, 0.1),
            point(1, 1, Some(0), 0, -0.2),
            point(2, 1, Some(0), 0, -0.2),
        ];
        let eq = EqualitySolve::new(rows, &mass).unwrap();
        assert_eq!(eq.dependent(), 1);
        let mut v = vec![
            [0.3, 0.0, 0.0, 0.0, 0.0, 0.0],
            [-0.7, 0.0, 0.0, 0.0, 0.0, 0.0],
        ];
        let mut lambda = vec![0.0; 3];
        eq.update(&mass, &mut v, &mut lambda);
        let worst = eq.residual(&v).iter().map(|x| x.abs()).fold(0.0, f64::max);
        assert!(worst < 1e-14, "{worst}");
        // one of the identical rows carries the load, the other none (δ of order 1e-30 of it)
        let (big, small) = (
            lambda[1].abs().max(lambda[2].abs()),
            lambda[1].abs().min(lambda[2].abs()),
        );
        assert!(big > 0.1 && small < 1e-30 * big, "{lambda:?}");
    }
}
