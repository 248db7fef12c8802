//! The problem as stored, in the local form the outer loop works on, and the verdict on an r:
//! u (and v) recomputed from the stored data, the error of `docs/error.md`, the balance
//! residual, and the divergence test of [`crate::Status::Unbounded`].
//!
//! # The problem solved is the problem stored
//! W (local) or M (global) need not be symmetric: real files carry assembly round-off
//! (relative asymmetry 1e-16 … 1.3e-3), and the problem is the one stored. When W is not
//! symmetric the inner problem of §3.3 is no longer the QP (4.7) but the variational
//! inequality: find r ∈ L with ⟨W r + q + E s, r′ − r⟩ ≥ 0 for all r′ ∈ L, strongly
//! monotone when ½(W + Wᵀ) is positive definite. The QP inner solvers (APGD, projected
//! Gauss–Seidel, interior point, faceted) see only the quadratic form, i.e. the surrogate
//! ½(W + Wᵀ) ([`Form::qp_w`]); they are a stage. What finishes on the stored W: the error
//! measure and every status (always on the stored data), F(s) (3.19) (from u = W r + q), the
//! fused Gauss–Seidel on Coulomb's law (each contact's law solved with its own stored
//! diagonal block, u maintained through the stored columns), and the semismooth Newton end
//! game ([`crate::newton`], J = I − D + D A W with W as stored).

use crate::delassus::Delassus;
use crate::evaluation;
use crate::law;
use crate::linalg::sparse::CscMatrix;
use crate::problem::{GlobalProblem, LocalProblem};
use std::borrow::Cow;
use std::sync::OnceLock;

/// The problem as stored: borrowed from the caller, or owned once updated for a new step.
pub(crate) enum Stored<'a> {
    /// a local problem (W, q, μ)
    Local(Cow<'a, LocalProblem>),
    /// a global problem (M, H, f, w, μ) and its Delassus form, built once
    Global(Cow<'a, GlobalProblem>, Box<Delassus>),
}

/// The stored problem, and the surrogate matrix of the SOC-QP inner solvers.
pub(crate) struct Form<'a> {
    pub(crate) stored: Stored<'a>,
    /// ½(W + Wᵀ), formed at the first use of a QP inner solver when W is not exactly
    /// symmetric (a fused Gauss–Seidel or Newton run never needs it)
    surrogate: OnceLock<CscMatrix>,
    /// whether W is exactly symmetric
    pub(crate) symmetric: bool,
    /// ‖W‖ estimated by the largest trace of a diagonal block
    pub(crate) w_scale: f64,
    /// ‖q‖
    pub(crate) q_norm: f64,
    /// [`crate::settings::Tuning::unbounded_ratio`]
    pub(crate) unbounded_ratio: f64,
}

impl<'a> Form<'a> {
    pub(crate) fn new(stored: Stored<'a>, unbounded_ratio: f64) -> Self {
        let mut form = Self {
            stored,
            surrogate: OnceLock::new(),
            symmetric: true,
            w_scale: 0.0,
            q_norm: 0.0,
            unbounded_ratio,
        };
        form.refresh();
        form
    }

    /// Recomputes what is derived from W and q (after an update).
    pub(crate) fn refresh(&mut self) {
        self.surrogate = OnceLock::new();
        let local = self.local();
        let (w_scale, symmetric, q_norm) = (
            crate::inner::w_scale(local.dim, &local.w),
            local.w.is_exactly_symmetric(),
            law::norm(&local.q),
        );
        self.w_scale = w_scale;
        self.symmetric = symmetric;
        self.q_norm = q_norm;
    }

    /// The local form (W, q, μ): the stored one, or the Delassus form of a global problem.
    pub(crate) fn local(&self) -> &LocalProblem {
        match &self.stored {
            Stored::Local(p) => p,
            Stored::Global(_, d) => &d.local,
        }
    }

    /// Whether ‖W‖ ‖r‖ > ratio · max(‖q‖, ‖u‖) (‖W‖ estimated by the largest trace of a
    /// diagonal block).
    fn unbounded(&self, r: &[f64], u: &[f64]) -> bool {
        let data = self.q_norm.max(law::norm(u)).max(f64::MIN_POSITIVE);
        self.w_scale * law::norm(r) > self.unbounded_ratio * data
    }

    /// The matrix of the SOC-QP inner problems: W, or ½(W + Wᵀ) when W is not symmetric.
    pub(crate) fn qp_w(&self) -> &CscMatrix {
        if self.symmetric {
            &self.local().w
        } else {
            self.surrogate
                .get_or_init(|| self.local().w.symmetric_part())
        }
    }

    /// Recomputes u (and v) from r and evaluates the error of docs/error.md ([`crate::evaluation`],
    /// as [`crate::fclib::evaluate`] does for stored solutions): u = W r + q for a
    /// local problem; v = M⁻¹(H r + f), u = Hᵀ v + w and the balance residual for a global one.
    pub(crate) fn verdict(&self, r: &[f64]) -> Verdict {
        match &self.stored {
            Stored::Local(p) => {
                let (u, e) = evaluation::local(p, r, self.q_norm);
                let unbounded = self.unbounded(r, &u);
                Verdict {
                    u,
                    v: None,
                    error: e.measure.error,
                    balance: None,
                    unbounded,
                }
            }
            Stored::Global(g, d) => {
                // v = M⁻¹(H r + f); the Cholesky factor reads one triangle of M, so for an M
                // that is only nearly symmetric the balance residual (computed with the whole
                // M) can stay above tol: Status::BalanceResidual
                let v = d.velocity(&g.h, r);
                let (u, e) = evaluation::global(g, &v, r, self.q_norm);
                let unbounded = self.unbounded(r, &u);
                Verdict {
                    u,
                    v: Some(v),
                    error: e.measure.error,
                    balance: e.balance_residual,
                    unbounded,
                }
            }
        }
    }
}

/// The checked outcome for impulses r: (u, v, error, balance residual, divergence).
#[derive(Clone)]
pub(crate) struct Verdict {
    pub(crate) u: Vec<f64>,
    pub(crate) v: Option<Vec<f64>>,
    pub(crate) error: f64,
    pub(crate) balance: Option<f64>,
    /// ‖W‖ ‖r‖ > ratio · max(‖q‖, ‖u‖)
    pub(crate) unbounded: bool,
}

impl Verdict {
    /// error ≤ tol, balance residual ≤ tol, r bounded.
    pub(crate) fn converged(&self, tol: f64) -> bool {
        self.error <= tol && self.balance.is_none_or(|b| b <= tol) && !self.unbounded
    }

    /// The measure by which the lowest-error iterate of a solve is chosen: the error of
    /// docs/error.md, or the balance residual of a global problem when that is larger;
    /// infinite for a diverging r.
    pub(crate) fn merit(&self) -> f64 {
        if self.unbounded || !self.error.is_finite() {
            return f64::INFINITY;
        }
        self.error.max(self.balance.unwrap_or(0.0))
    }

    /// The error is ≤ tol only because r diverges.
    pub(crate) fn spurious(&self, tol: f64) -> bool {
        self.unbounded && self.error <= tol
    }
}
