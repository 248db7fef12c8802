//! The fused outer method ([`crate::OuterKind::Fused`]): no separate outer loop on s, but
//! block Gauss–Seidel directly on Coulomb's law (2.9) of the local problem u = W r + q. The
//! sweep itself (one-contact law solves, u kept up to date through the columns of W) is
//! [`crate::inner::pgs`]'s; this file is the stopping logic around it.

use crate::cone;
use crate::inner::pgs::{sweep, PgsSolver};
use crate::inner::{InnerLimits, InnerReport, InnerStatus};
use crate::sparse::CscMatrix;

/// Sweeps over which [`solve_fused`] measures its rate when asked to give up early.
pub const GIVE_UP_WINDOW: usize = 10;

/// The fused iteration: Gauss–Seidel directly on Coulomb's law (local problem u = W r + q),
/// each contact given a solution of its one-contact law (take-off, stick or slide, see
/// [`solve_contact_law`]) — or, where the slip equation fails, a step of the one-contact
/// SOC-QP with De Saxcé's s = μ‖u_T‖ taken from the current u. Stops when the error of docs/error.md, computed from the maintained
/// u (recomputed exactly every few sweeps and before stopping), is ≤ `limits.tol`. With
/// `give_up`, it also stops (status `MaxIterations`) as soon as the rate of the last
/// [`GIVE_UP_WINDOW`] sweeps, extrapolated over the sweeps left, cannot reach `limits.tol`.
/// Returns the report; `r` holds the warm start on entry and the result on exit.
#[allow(clippy::too_many_arguments)]
pub fn solve_fused(
    solver: &mut PgsSolver,
    dim: usize,
    w: &CscMatrix,
    q: &[f64],
    mu: &[f64],
    limits: &InnerLimits,
    give_up: bool,
    r: &mut [f64],
) -> InnerReport {
    let refresh = solver.refresh.max(1);
    let (blocks, u) = solver.parts();
    if !blocks.fits(dim, mu.len()) || w.ncols != dim * mu.len() || r.len() != w.ncols {
        return InnerReport {
            status: InnerStatus::NumericalError,
            iterations: 0,
            residual: f64::INFINITY,
        };
    }
    cone::project_product(dim, mu, r);
    let q_norm = crate::law::norm(q);
    u.clear();
    u.extend_from_slice(q);
    w.gemv_acc(1.0, r, u);
    let mut residual = crate::law::error_measure(dim, mu, r, u, q_norm).error;
    let mut window_start = residual;
    let mut iterations = 0;
    let mut exact = true;
    let status = loop {
        if !residual.is_finite() {
            break InnerStatus::NumericalError;
        }
        if residual <= limits.tol {
            if exact {
                break InnerStatus::Solved;
            }
            u.copy_from_slice(q);
            w.gemv_acc(1.0, r, u);
            exact = true;
            residual = crate::law::error_measure(dim, mu, r, u, q_norm).error;
            continue;
        }
        if iterations >= limits.max_iterations {
            break InnerStatus::MaxIterations;
        }
        if limits.past_deadline(iterations, w.nnz()) {
            break InnerStatus::TimeLimit;
        }
        sweep(blocks, w, mu, r, u, true);
        iterations += 1;
        exact = false;
        if iterations % refresh == 0 {
            u.copy_from_slice(q);
            w.gemv_acc(1.0, r, u);
            exact = true;
        }
        residual = crate::law::error_measure(dim, mu, r, u, q_norm).error;
        if give_up && iterations % GIVE_UP_WINDOW == 0 {
            // the rate over the last window, extrapolated over the sweeps left
            let rate = residual / window_start;
            let windows_left = (limits.max_iterations - iterations.min(limits.max_iterations))
                as f64
                / GIVE_UP_WINDOW as f64;
            if rate >= 1.0 || rate.powf(windows_left) * residual > limits.tol {
                break InnerStatus::MaxIterations;
            }
            window_start = residual;
        }
    };
    InnerReport {
        status,
        iterations,
        residual,
    }
}
