//! Projected block Gauss–Seidel on the dual inner problem (4.7),
//!
//! ```text
//!     min_{r ∈ L}  ½ rᵀ W r + bᵀ r,      L = ∏ K_{μⁱ},
//! ```
//!
//! sweeping over the contacts and minimizing, for contact i with the other rʲ frozen, the
//! one-contact SOC-QP
//!
//! ```text
//!     min_{rᵢ ∈ K_{μⁱ}}  ½ rᵢᵀ Wᵢᵢ rᵢ + cᵢᵀ rᵢ,     cᵢ = bᵢ + Σ_{j≠i} Wᵢⱼ rⱼ.
//! ```
//!
//! # The one-contact solve is exact
//! Each contact is minimized exactly by [`solve_contact`] ([`super::contact`]).
//!
//! # The fused iteration
//! [`crate::outer::fused::solve_fused`] is Gauss–Seidel on Coulomb's law itself rather than on (4.7): contact i,
//! the others frozen, gets a solution of its own law (2.9) by [`solve_contact_law`] — take-off
//! r = 0 when c_N ≥ 0, stick r = −A⁻¹c when that lies in K_μ, otherwise slide
//! r = r_N (1, −μτ) with u_N = 0 and u_T ∥ τ, a scalar equation in the slip angle solved by
//! Newton's method (in d = 2, τ = ±1 in closed form). Rotations of the unit vectors τ and
//! (cos α, sin α) use polynomial cos/sin of the step, so no iteration calls a trigonometric
//! function.
//!
//! # Bookkeeping
//! The iteration keeps u = W r + b up to date: after contact i moves by δ, u ← u + W_{:,i} δ
//! through the columns of W, which costs the nonzeros of those d columns. Then
//! cᵢ = uᵢ − Wᵢᵢ rᵢ. The diagonal blocks Wᵢᵢ are extracted once per matrix, as stored: W need
//! not be symmetric, and the fused iteration then solves each contact's law with its own
//! non-symmetric block (the one-contact formulas of [`solve_contact_law`] hold for any
//! block with a positive definite symmetric part). The SOC-QP step [`solve_contact`] reads
//! a symmetric block; the inner solver is only given a symmetric W (the solver passes
//! ½(W + Wᵀ) when the stored W is not symmetric). A diagonal block that is singular (a contact that W barely sees) is solved
//! with a proximal term ε‖rᵢ − rᵢ_old‖²/2, which leaves the fixed points unchanged.
//!
//! # Stopping
//! At the end of each sweep: the natural-map residual of (4.7), ‖r − P_L(r − (W r + b))‖,
//! relative to max(‖b‖, ‖r‖, ‖W r + b‖), is compared with the tolerance.

use super::contact::matvec;
pub use super::contact::{solve_contact, solve_contact_law, DiagonalBlocks, OneContact};
use super::{InnerLimits, InnerProblem, InnerReport, InnerSolver, InnerStatus};
use crate::cone;
use crate::linalg::sparse::CscMatrix;
use crate::natural_map::dual_residual;

/// Sweeps between two Anderson steps of [`crate::outer::fused::solve_fused`] (the default of
/// [`crate::settings::InnerParams::gs_anderson_period`]; 0: no mixing).
pub const ANDERSON_PERIOD: usize = 4;

/// Memory of the Anderson mixing of [`crate::outer::fused::solve_fused`] (the default of
/// [`crate::settings::InnerParams::gs_anderson_memory`]).
pub const ANDERSON_MEMORY: usize = 5;

/// Projected block Gauss–Seidel on (4.7) with exact one-contact solves, set up for one
/// (d, W): the diagonal blocks Wᵢᵢ and their inverses are extracted by [`PgsSolver::new`].
#[derive(Debug, Clone)]
pub struct PgsSolver {
    /// sweeps between exact recomputations of u = W r + b ([`REFRESH`] by default; ≥ 1)
    pub refresh: usize,
    /// thresholds of the infeasible-ray test, run at each refresh
    /// ([`crate::settings::InnerParams::infeasible_ray`])
    pub ray: super::RayParams,
    /// fused iteration ([`crate::outer::fused`]) only: sweeps between two Anderson steps
    /// (0: none; default [`ANDERSON_PERIOD`])
    pub anderson_period: usize,
    /// fused iteration only: memory of its Anderson mixing (≥ 1; default
    /// [`ANDERSON_MEMORY`])
    pub anderson_memory: usize,
    blocks: DiagonalBlocks,
    /// maintained u = W r + b
    u: Vec<f64>,
}

impl PgsSolver {
    /// A solver for the d-dimensional problems on `w`: extracts and inverts its diagonal
    /// blocks.
    pub fn new(dim: usize, w: &CscMatrix) -> Self {
        Self {
            refresh: REFRESH,
            ray: super::RayParams::default(),
            anderson_period: ANDERSON_PERIOD,
            anderson_memory: ANDERSON_MEMORY,
            blocks: DiagonalBlocks::new(dim, w),
            u: Vec::new(),
        }
    }

    /// The diagonal blocks and the buffer of the maintained u, for the fused iteration
    /// ([`crate::outer::fused`]).
    pub(crate) fn parts(&mut self) -> (&DiagonalBlocks, &mut Vec<f64>) {
        (&self.blocks, &mut self.u)
    }
}

/// One Gauss–Seidel pass over all contacts. `u` must equal W r + b on entry (b = `shift` for
/// (4.7)); with `fused`, u = W r + q is maintained instead and contact i is given a solution
/// of its own Coulomb law (2.9) with the other contacts frozen ([`solve_contact_law`]), or,
/// where that fails, the one-contact SOC-QP with linear term uᵢ + μⁱ‖u_Tⁱ‖e (De Saxcé's s
/// from the current u). Returns the largest change ‖Δrᵢ‖.
pub(crate) fn sweep(
    blocks: &DiagonalBlocks,
    w: &CscMatrix,
    mu: &[f64],
    r: &mut [f64],
    u: &mut [f64],
    fused: bool,
) -> f64 {
    let d = blocks.dim;
    let mut max_change = 0.0f64;
    for (i, &m) in mu.iter().enumerate() {
        let j0 = i * d;
        let a = &blocks.blocks[i];
        let mut old = [0.0; 3];
        old[..d].copy_from_slice(&r[j0..j0 + d]);
        // cᵢ = uᵢ − Aᵢᵢ rᵢ (− ε rᵢ for the proximal term, already inside A)
        let ar = matvec(a, d, &old);
        let mut c = [0.0; 3];
        for k in 0..d {
            c[k] = u[j0 + k] - ar[k];
        }
        let mut contact = OneContact {
            a,
            ainv: &blocks.inverses[i],
            d,
            mu: m,
            c,
        };
        let new = if fused {
            let mut u_seed = [0.0; 3];
            u_seed[..d].copy_from_slice(&u[j0..j0 + d]);
            solve_contact_law(&contact, &old, &u_seed).unwrap_or_else(|| {
                contact.c[0] += m * cone::tangent_norm(&u_seed[..d]);
                solve_contact(&contact, &old)
            })
        } else {
            solve_contact(&contact, &old)
        };
        let mut change = 0.0;
        for k in 0..d {
            let delta = new[k] - old[k];
            if delta != 0.0 {
                change += delta * delta;
                let col = j0 + k;
                for p in w.col_ptr[col]..w.col_ptr[col + 1] {
                    u[w.row_idx[p]] += w.values[p] * delta;
                }
            }
        }
        r[j0..j0 + d].copy_from_slice(&new[..d]);
        max_change = max_change.max(change.sqrt());
    }
    max_change
}

/// Sweeps between exact recomputations of u = W r + b (against drift): the default of
/// [`PgsSolver::refresh`] and [`crate::settings::InnerParams::gs_refresh`].
pub const REFRESH: usize = 16;

impl InnerSolver for PgsSolver {
    fn name(&self) -> &'static str {
        "pgs"
    }

    fn solve(
        &mut self,
        problem: &InnerProblem<'_>,
        limits: &InnerLimits,
        r: &mut [f64],
    ) -> InnerReport {
        let (dim, w) = (problem.dim, problem.w);
        let (blocks, refresh, ray) = (&self.blocks, self.refresh.max(1), self.ray);
        if !blocks.fits(dim, problem.mu.len())
            || w.ncols != r.len()
            || w.ncols != dim * problem.mu.len()
        {
            return InnerReport {
                status: InnerStatus::NumericalError,
                iterations: 0,
                residual: f64::INFINITY,
            };
        }
        // start from a point of L
        cone::project_product(dim, problem.mu, r);
        let b_norm = crate::law::norm(problem.b);
        let u = &mut self.u;
        u.clear();
        u.extend_from_slice(problem.b);
        w.gemv_acc(1.0, r, u);
        let mut residual = dual_residual(dim, problem.mu, r, u, b_norm);
        let w_scale = blocks.w_scale;
        let mut wr = vec![0.0; r.len()];
        let mut iterations = 0;
        let status = loop {
            if !residual.is_finite() {
                break InnerStatus::NumericalError;
            }
            if residual <= limits.tol {
                break InnerStatus::Solved;
            }
            if iterations % refresh == 0 {
                for ((x, a), b) in wr.iter_mut().zip(u.iter()).zip(problem.b) {
                    *x = a - b;
                }
                if super::unbounded_ray(r, &wr, problem.b, w_scale, &ray) {
                    break InnerStatus::Infeasible;
                }
            }
            if iterations >= limits.max_iterations {
                break InnerStatus::MaxIterations;
            }
            if limits.past_deadline(iterations, w.nnz()) {
                break InnerStatus::TimeLimit;
            }
            sweep(blocks, w, problem.mu, r, u, false);
            iterations += 1;
            if iterations % refresh == 0 {
                u.copy_from_slice(problem.b);
                w.gemv_acc(1.0, r, u);
            }
            residual = dual_residual(dim, problem.mu, r, u, b_norm);
        };
        InnerReport {
            status,
            iterations,
            residual,
        }
    }
}
