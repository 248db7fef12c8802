//! The fused outer method ([`crate::OuterKind::Fused`]): no separate outer loop on s, but
//! block Gauss–Seidel directly on Coulomb's law (2.9) of the local problem u = W r + q. The
//! sweep itself (one-contact law solves, u kept up to date through the columns of W) is
//! [`crate::inner::pgs`]'s; this file is the stopping logic around it.

use super::anderson::Anderson;
use crate::cone;
use crate::inner::pgs::{sweep, PgsSolver};
use crate::inner::{InnerLimits, InnerReport, InnerStatus};
use crate::linalg::sparse::CscMatrix;

/// Sweeps over which [`solve_fused`] measures its rate when asked to give up early.
pub const GIVE_UP_WINDOW: usize = 10;

/// A batch of fused sweeps stops at this fraction of tol: the default of
/// [`crate::settings::Tuning::fused_tol_fraction`].
pub const TOL_FRACTION: f64 = 0.9;

/// The defaults of the fused method's Anderson mixing, at their former path.
pub use crate::inner::pgs::{ANDERSON_MEMORY, ANDERSON_PERIOD};

/// Anderson mixing of the sweeps: type II on the map G = (`period` sweeps), x_{k+1} =
/// P_L(Anderson(x_k, G(x_k))) ([`Anderson::next_projected`]), taken only where its error
/// (docs/error.md, u = W x + q recomputed) is below that of the plain sweeps' G(x_k); otherwise
/// the differences are dropped and the iteration goes on from G(x_k). Where every contact keeps
/// its piece of the law (take-off, stick, slide) the sweeps are an affine map and the mixing
/// is a secant method on it: the slow linear phase of Gauss–Seidel on rank-deficient W is
/// what it shortens (measured: docs/tuning.md, `tuning.inner.gs_anderson_period`). Memory:
/// about 2 `memory` + 5 vectors of the size of r.
struct SweepMixing {
    period: usize,
    anderson: Anderson,
    /// x_k: r at the start of the current block of sweeps
    start: Vec<f64>,
    /// u = W x + q of the mixed point
    u: Vec<f64>,
}

impl SweepMixing {
    /// None when `period` is 0 (no mixing).
    fn new(period: usize, memory: usize, r: &[f64]) -> Option<Self> {
        (period > 0).then(|| Self {
            period,
            anderson: Anderson::new(memory),
            start: r.to_vec(),
            u: Vec::new(),
        })
    }

    /// After a block of sweeps, with r = G(x_k), u its maintained velocity and `error` its
    /// error: moves r (and u, exact) to the mixed point and returns its error when that is
    /// lower; the next block starts from r either way.
    #[allow(clippy::too_many_arguments)]
    fn step(
        &mut self,
        dim: usize,
        w: &CscMatrix,
        q: &[f64],
        mu: &[f64],
        q_norm: f64,
        r: &mut [f64],
        u: &mut [f64],
        error: f64,
    ) -> Option<f64> {
        let mixed = self
            .anderson
            .next_projected(&self.start, r, |x| cone::project_product(dim, mu, x));
        let mut taken = None;
        if self.anderson.depth() > 0 {
            self.u.clear();
            self.u.extend_from_slice(q);
            w.gemv_acc(1.0, &mixed, &mut self.u);
            let e = crate::law::error_measure(dim, mu, &mixed, &self.u, q_norm).error;
            if e < error {
                r.copy_from_slice(&mixed);
                u.copy_from_slice(&self.u);
                taken = Some(e);
            } else {
                self.anderson.restart();
            }
        }
        self.start.copy_from_slice(r);
        taken
    }
}

/// The fused iteration: Gauss–Seidel directly on Coulomb's law (local problem u = W r + q),
/// each contact given a solution of its one-contact law (take-off, stick or slide, see
/// [`solve_contact_law`]) — or, where the slip equation fails, a step of the one-contact
/// SOC-QP with De Saxcé's s = μ‖u_T‖ taken from the current u — every
/// [`PgsSolver::anderson_period`] sweeps followed by an Anderson step kept only where it
/// lowers the error. Stops when the error of docs/error.md, computed from the maintained
/// u (recomputed exactly every few sweeps and before stopping), is ≤ `limits.tol`. With
/// `give_up`, it also stops (status `MaxIterations`) as soon as the rate of the last
/// [`GIVE_UP_WINDOW`] sweeps, extrapolated over the sweeps left, cannot reach `limits.tol`.
/// Returns the report; `r` holds the warm start on entry and the result on exit.
///
/// [`solve_contact_law`]: crate::inner::contact::solve_contact_law
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
    let (period, memory) = (solver.anderson_period, solver.anderson_memory);
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
    let mut mixing = SweepMixing::new(period, memory, r);
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
        if let Some(m) = mixing.as_mut().filter(|m| iterations % m.period == 0) {
            if let Some(e) = m.step(dim, w, q, mu, q_norm, r, u, residual) {
                (residual, exact) = (e, true);
            }
        }
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

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use crate::deadline::Deadline;

    /// Sweeps to reach 1e-10 (None: not within 20 000) and the error recomputed from r.
    fn run(p: &crate::problem::LocalProblem, period: usize) -> (Option<usize>, f64, f64) {
        let mut solver = PgsSolver::new(p.dim, &p.w);
        solver.anderson_period = period;
        let limits = InnerLimits {
            tol: 1e-10,
            max_iterations: 20_000,
            deadline: Deadline::NEVER,
        };
        let mut r = vec![0.0; p.q.len()];
        let out = solve_fused(
            &mut solver,
            p.dim,
            &p.w,
            &p.q,
            &p.mu,
            &limits,
            false,
            &mut r,
        );
        let solved = (out.status == InnerStatus::Solved).then_some(out.iterations);
        (solved, out.residual, p.error(&r).error)
    }

    pub fn anderson_mixing_shortens_gauss_seidel_on_rank_deficient_problems() {
        // W = AᵀA + 0.01 I with A of rank m/2 (nearly rank-deficient, as for rigid bodies in
        // multi-point contact), q pushing into contact: Gauss–Seidel converges linearly and
        // slowly; with the mixing it needs fewer sweeps, and it never stops with an error
        // other than the one of its r
        let (mut plain_total, mut mixed_total, mut both) = (0, 0, 0);
        for seed in 0..8 {
            let mut p = crate::test_problems::problem(8, seed, 0.01, 0.0);
            p.q.iter_mut().step_by(3).for_each(|x| *x -= 0.5);
            let (plain, plain_res, plain_err) = run(&p, 0);
            let (mixed, mixed_res, mixed_err) = run(&p, ANDERSON_PERIOD);
            for (res, err) in [(plain_res, plain_err), (mixed_res, mixed_err)] {
                assert!((res - err).abs() <= 1e-9 * err.max(1e-10), "{res} vs {err}");
            }
            assert!(
                plain.is_none() || mixed.is_some(),
                "seed {seed}: mixing lost it"
            );
            if let (Some(a), Some(b)) = (plain, mixed) {
                (plain_total, mixed_total, both) = (plain_total + a, mixed_total + b, both + 1);
            }
        }
        assert!(both >= 4, "{both} problems solved by both");
        assert!(
            2 * mixed_total < plain_total,
            "sweeps: plain {plain_total}, mixed {mixed_total}"
        );
    }
}
