//! The margin problem that decides every criterion, t* = max t s.t. Hᵀ v + w − t·e_S ∈ C,
//! t ≤ 1 (module docs of [`super`]), solved by Clarabel, and the verification of its
//! certificates: a velocity v is checked by recomputing Hᵀ v + w and its cone margins, an
//! impulse r by projecting it onto L and recomputing its kernel residual.

use super::*;

/// The purely kinematic data the criteria depend on (§5.5): x(v) = Bᵀ v + w with B = H
/// (global) or W (local).
pub(super) struct KinematicData<'a> {
    pub(super) dim: usize,
    pub(super) b: &'a CscMatrix,
    pub(super) w: &'a [f64],
    pub(super) mu: &'a [f64],
    /// ‖B₍:,ⱼ₎‖ for each column j
    pub(super) col_norms: Vec<f64>,
    /// ‖w‖∞, or 1 when w = 0
    pub(super) w_scale: f64,
    /// max |Bᵢⱼ|, or 1 when B = 0
    pub(super) b_scale: f64,
}

impl<'a> KinematicData<'a> {
    pub(super) fn new(
        dim: usize,
        b: &'a CscMatrix,
        w: &'a [f64],
        mu: &'a [f64],
    ) -> Result<Self, ProblemError> {
        b.check()
            .map_err(|source| ProblemError::Sparse { what: "H", source })?;
        let m = dim * mu.len();
        if b.ncols != m || w.len() != m {
            return Err(ProblemError::Shape {
                what: "H / w",
                expected: format!("{m} columns and entries (d · contacts)"),
                found: format!("{} columns, {} entries", b.ncols, w.len()),
            });
        }
        if let Some(i) = mu.iter().position(|x| x.is_nan() || *x < 0.0) {
            return Err(ProblemError::Friction {
                contact: i,
                value: mu[i],
            });
        }
        if let Some((r, c)) = b.first_non_finite() {
            return Err(ProblemError::NonFinite {
                what: "H",
                location: format!("({r}, {c})"),
            });
        }
        if let Some(i) = w.iter().position(|x| !x.is_finite()) {
            return Err(ProblemError::NonFinite {
                what: "w",
                location: format!("index {i}"),
            });
        }
        let col_norms = (0..b.ncols)
            .map(|j| {
                b.values[b.col_ptr[j]..b.col_ptr[j + 1]]
                    .iter()
                    .map(|x| x * x)
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let w_inf = w.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let b_inf = b.values[..b.nnz()]
            .iter()
            .fold(0.0f64, |a, x| a.max(x.abs()));
        Ok(Self {
            dim,
            b,
            w,
            mu,
            col_norms,
            w_scale: if w_inf > 0.0 { w_inf } else { 1.0 },
            b_scale: if b_inf > 0.0 { b_inf } else { 1.0 },
        })
    }

    pub(super) fn contacts(&self) -> usize {
        self.mu.len()
    }

    /// The cone of contact i in (4.4): K_{μ}* = K_{1/μ}.
    pub(super) fn dual_block(&self, i: usize) -> Block {
        let mu = self.mu[i];
        if mu == 0.0 {
            Block::HalfSpace
        } else if mu.is_infinite() {
            Block::Ray
        } else {
            Block::Soc(mu)
        }
    }
}

/// One contact's cone in the margin problem, written for x = (x_N, x_T).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Block {
    /// {x_N ≥ 0} = K_∞ = K_0*: frictionless contacts in L*, every contact in (4.5)
    HalfSpace,
    /// K_{1/μ} = K_μ* = {μ‖x_T‖ ≤ x_N}, 0 < μ < ∞
    Soc(f64),
    /// K_0 = K_∞* = {x_T = 0, x_N ≥ 0} (μ = ∞)
    Ray,
}

impl Block {
    /// Margin of x: the largest t with x − t e in the cone (−∞ … for a ray with x_T ≠ 0, the
    /// negative tangential size is returned instead).
    pub(super) fn margin(self, x: &[f64]) -> f64 {
        let n = x[0];
        let t = crate::cone::tangent_norm(x);
        match self {
            Block::HalfSpace => n,
            Block::Soc(mu) => n - mu * t,
            Block::Ray => {
                if t > 0.0 {
                    n.min(-t)
                } else {
                    n
                }
            }
        }
    }

    /// Projects an impulse block onto the dual of this cone (the block of L, or of the
    /// normal ray for a half-space).
    pub(super) fn project_dual(self, r: &mut [f64]) {
        match self {
            Block::HalfSpace => {
                r[0] = r[0].max(0.0);
                r[1..].iter_mut().for_each(|x| *x = 0.0);
            }
            Block::Soc(mu) => crate::cone::project(mu, r),
            Block::Ray => r[0] = r[0].max(0.0),
        }
    }
}

/// The data of one margin problem.
pub(super) struct MarginProblem<'d, 'a> {
    pub(super) data: &'d KinematicData<'a>,
    pub(super) blocks: Vec<Block>,
    /// contacts whose margin is maximized (the set S)
    pub(super) mask: Vec<bool>,
    /// use w = 0 (for (5.1))
    pub(super) homogeneous: bool,
}

/// How a Clarabel solve ended, in the terms the verdicts need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum ConicStatus {
    Solved,
    Infeasible,
    Failed,
}

/// The raw output of a margin solve (before verification).
pub(super) struct MarginSolve {
    /// primal velocities (original scaling)
    pub(super) v: Option<Vec<f64>>,
    /// dual impulses (optimal dual or infeasibility certificate), unnormalized
    pub(super) r: Option<Vec<f64>>,
    pub(super) clarabel_status: String,
}

/// A verified velocity certificate.
pub(super) struct VelocityCheck {
    /// min over S of the margin / ‖w‖∞ (+∞ when S is empty)
    pub(super) masked: f64,
    /// min over the other contacts of the margin / ‖w‖∞ (+∞ when none)
    pub(super) unmasked: f64,
    /// max ‖xⁱ‖ / ‖w‖∞
    pub(super) size: f64,
}

/// A verified impulse certificate.
pub(super) struct ImpulseCheck {
    /// r projected onto L and normalized (Σ_S r_N = 1, or ‖r‖ = 1 if that sum vanishes)
    pub(super) r: Vec<f64>,
    /// wᵀ r / ‖w‖∞ for the normalized r
    pub(super) value: f64,
    /// whether Σ_S r_N > 0 (else r lives on contacts outside S and `value` < 0 means the
    /// cone constraint itself is infeasible)
    pub(super) on_mask: bool,
    /// ‖H r‖ / Σⱼ |rⱼ| ‖H₍:,ⱼ₎‖
    pub(super) residual: f64,
    /// `value` plus the uncertainty the kernel residual leaves on it (see [`KERNEL_SLACK`]):
    /// the verified upper bound on the margin
    pub(super) bound: f64,
}

/// How far wᵀr may move when an approximate r ∈ L (residual ε = ‖H r‖ relative) is replaced
/// by a point of L ∩ Ker H: |Δ(wᵀr)| ≤ κ ‖ŵ‖ ‖r‖ ε for polyhedral cones (Hoffman) and
/// κ ‖ŵ‖ ‖r‖ √ε for second-order cones (Hölderian error bound with exponent ½, which is
/// attained when Ker H runs along the boundary of L). κ = KERNEL_SLACK.
pub(super) const KERNEL_SLACK: f64 = 10.0;

impl<'d, 'a> MarginProblem<'d, 'a> {
    pub(super) fn w_hat(&self, j: usize) -> f64 {
        if self.homogeneous {
            0.0
        } else {
            self.data.w[j] / self.data.w_scale
        }
    }

    /// Solves max t s.t. B̂ᵀ v̂ + ŵ − t e_S ∈ C, t ≤ 1 with Clarabel, on B̂ = B / max|B|,
    /// ŵ = w / ‖w‖∞. Only the dofs that some contact sees are variables.
    pub(super) fn solve(&self, settings: &CheckSettings) -> MarginSolve {
        let d = self.data;
        let dim = d.dim;
        let b = d.b;
        // Compact the dofs: rows of B with at least one entry.
        let mut dof_index = vec![usize::MAX; b.nrows];
        let mut nv = 0usize;
        for &row in &b.row_idx[..b.nnz()] {
            if dof_index[row] == usize::MAX {
                dof_index[row] = nv;
                nv += 1;
            }
        }
        let t_col = nv;
        let mut rows = Vec::new();
        let mut cols = Vec::new();
        let mut vals = Vec::new();
        let mut rhs = Vec::new();
        let mut cones: Vec<cs::SupportedConeT<f64>> = Vec::new();
        // Row of the Clarabel system holding contact component j, and its scale factor.
        let mut push_row = |j: usize, scale: f64, shift: bool, rhs: &mut Vec<f64>| {
            let row = rhs.len();
            for p in b.col_ptr[j]..b.col_ptr[j + 1] {
                rows.push(row);
                cols.push(dof_index[b.row_idx[p]]);
                vals.push(-scale * b.values[p] / d.b_scale);
            }
            if shift {
                rows.push(row);
                cols.push(t_col);
                vals.push(1.0);
            }
            rhs.push(scale * self.w_hat(j));
        };
        for (i, block) in self.blocks.iter().enumerate() {
            let j0 = i * dim;
            let shift = self.mask[i];
            match *block {
                Block::HalfSpace => {
                    push_row(j0, 1.0, shift, &mut rhs);
                    cones.push(cs::NonnegativeConeT(1));
                }
                Block::Soc(mu) => {
                    push_row(j0, 1.0, shift, &mut rhs);
                    for k in 1..dim {
                        push_row(j0 + k, mu, false, &mut rhs);
                    }
                    cones.push(cs::SecondOrderConeT(dim));
                }
                Block::Ray => {
                    push_row(j0, 1.0, shift, &mut rhs);
                    cones.push(cs::NonnegativeConeT(1));
                    for k in 1..dim {
                        push_row(j0 + k, 1.0, false, &mut rhs);
                    }
                    cones.push(cs::ZeroConeT(dim - 1));
                }
            }
        }
        // t ≤ 1
        rows.push(rhs.len());
        cols.push(t_col);
        vals.push(1.0);
        rhs.push(1.0);
        cones.push(cs::NonnegativeConeT(1));

        let nx = nv + 1;
        let a = ca::CscMatrix::new_from_triplets(rhs.len(), nx, rows, cols, vals);
        let p = ca::CscMatrix::zeros((nx, nx));
        let mut q = vec![0.0; nx];
        q[t_col] = -1.0;
        let csettings = cs::DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(settings.max_iter)
            .time_limit(settings.time_limit.as_secs_f64())
            .build();
        let Ok(csettings) = csettings else {
            return MarginSolve::failed("Clarabel settings rejected");
        };
        let mut solver = match cs::DefaultSolver::new(&p, &q, &a, &rhs, &cones, csettings) {
            Ok(s) => s,
            Err(e) => return MarginSolve::failed(&format!("Clarabel setup failed: {e}")),
        };
        solver.solve();
        let sol = &solver.solution;
        let status = match sol.status {
            cs::SolverStatus::Solved | cs::SolverStatus::AlmostSolved => ConicStatus::Solved,
            cs::SolverStatus::PrimalInfeasible | cs::SolverStatus::AlmostPrimalInfeasible => {
                ConicStatus::Infeasible
            }
            _ => ConicStatus::Failed,
        };
        let all_finite = sol.x.iter().chain(&sol.z).all(|x| x.is_finite());
        // Map back: v = (‖w‖∞ / max|B|) v̂ (v̂ is the solution on scaled data; for (5.1) w = 0
        // and only the direction matters).
        let v_factor = if self.homogeneous {
            1.0 / d.b_scale
        } else {
            d.w_scale / d.b_scale
        };
        let mut v = vec![0.0; b.nrows];
        for (k, &idx) in dof_index.iter().enumerate() {
            if idx != usize::MAX {
                v[k] = sol.x.get(idx).copied().unwrap_or(0.0) * v_factor;
            }
        }
        // Dual z → impulses r (z in C*, r = D z with D the tangential scaling).
        let mut r = vec![0.0; dim * d.contacts()];
        let mut row = 0usize;
        for (i, block) in self.blocks.iter().enumerate() {
            let j0 = i * dim;
            let z = |k: usize| sol.z.get(k).copied().unwrap_or(0.0);
            match *block {
                Block::HalfSpace => {
                    r[j0] = z(row);
                    row += 1;
                }
                Block::Soc(mu) => {
                    r[j0] = z(row);
                    for k in 1..dim {
                        r[j0 + k] = mu * z(row + k);
                    }
                    row += dim;
                }
                Block::Ray => {
                    for k in 0..dim {
                        r[j0 + k] = z(row + k);
                    }
                    row += dim;
                }
            }
        }
        let t_opt =
            (status == ConicStatus::Solved).then(|| sol.x.get(t_col).copied().unwrap_or(0.0));
        let clarabel_status = match t_opt {
            Some(t) => format!("{:?}, t* = {t:.3e}", sol.status),
            None => format!("{:?}", sol.status),
        };
        if !all_finite {
            return MarginSolve::failed(&format!("Clarabel {clarabel_status}: non-finite output"));
        }
        MarginSolve {
            v: (status == ConicStatus::Solved || status == ConicStatus::Failed).then_some(v),
            r: Some(r),
            clarabel_status,
        }
    }

    /// Recomputes x = Hᵀ v + w (w = 0 when homogeneous) and its margins.
    pub(super) fn check_velocity(&self, v: &[f64]) -> VelocityCheck {
        let d = self.data;
        let mut x = if self.homogeneous {
            vec![0.0; d.w.len()]
        } else {
            d.w.to_vec()
        };
        d.b.gemv_t_acc(1.0, v, &mut x);
        let mut masked = f64::INFINITY;
        let mut unmasked = f64::INFINITY;
        let mut size = 0.0f64;
        for (i, xi) in x.chunks_exact(d.dim).enumerate() {
            let m = self.blocks[i].margin(xi) / d.w_scale;
            size = size.max(crate::law::norm(xi) / d.w_scale);
            if self.mask[i] {
                masked = masked.min(m);
            } else {
                unmasked = unmasked.min(m);
            }
        }
        VelocityCheck {
            masked,
            unmasked,
            size,
        }
    }

    /// Projects r onto the dual cones, normalizes it and recomputes wᵀ r and ‖H r‖.
    pub(super) fn check_impulse(&self, r: &[f64]) -> Option<ImpulseCheck> {
        let d = self.data;
        let mut r = r.to_vec();
        for (i, ri) in r.chunks_exact_mut(d.dim).enumerate() {
            self.blocks[i].project_dual(ri);
        }
        let on_mask_sum: f64 = (0..d.contacts())
            .filter(|&i| self.mask[i])
            .map(|i| r[i * d.dim])
            .sum();
        let norm = crate::law::norm(&r);
        if norm == 0.0 || !norm.is_finite() {
            return None;
        }
        let on_mask = on_mask_sum > 1e-9 * norm;
        let scale = if on_mask { on_mask_sum } else { norm };
        r.iter_mut().for_each(|x| *x /= scale);
        let value = if self.homogeneous {
            0.0
        } else {
            r.iter().zip(d.w).map(|(a, b)| a * b).sum::<f64>() / d.w_scale
        };
        let hr = d.b.mul_vec(&r);
        let denom: f64 = r.iter().zip(&d.col_norms).map(|(a, c)| a.abs() * c).sum();
        let residual = if denom > 0.0 {
            crate::law::norm(&hr) / denom
        } else {
            // H r = 0 trivially: every column r touches is zero.
            0.0
        };
        let polyhedral = d.dim == 2 || self.blocks.iter().all(|b| !matches!(b, Block::Soc(_)));
        let w_hat_norm = if self.homogeneous {
            0.0
        } else {
            crate::law::norm(d.w) / d.w_scale
        };
        let spread = if polyhedral {
            residual
        } else {
            residual.sqrt()
        };
        let bound = value + KERNEL_SLACK * w_hat_norm * crate::law::norm(&r) * spread;
        Some(ImpulseCheck {
            r,
            value,
            on_mask,
            residual,
            bound,
        })
    }
}

impl MarginSolve {
    pub(super) fn failed(msg: &str) -> Self {
        Self {
            v: None,
            r: None,
            clarabel_status: msg.to_string(),
        }
    }
}

pub(super) fn undecided(
    detail: String,
    margin: Option<f64>,
    dual_bound: Option<f64>,
) -> CriterionReport {
    CriterionReport {
        verdict: Verdict::Undecided,
        certificate_residual: None,
        certificate_kind: None,
        certificate: None,
        margin,
        dual_bound,
        detail,
    }
}

/// Everything one margin solve yields, verified.
pub(super) struct Verified {
    pub(super) solve: MarginSolve,
    pub(super) vel: Option<(Vec<f64>, VelocityCheck)>,
    pub(super) imp: Option<ImpulseCheck>,
}

pub(super) fn solve_and_verify(mp: &MarginProblem, settings: &CheckSettings) -> Verified {
    let solve = mp.solve(settings);
    let vel = solve.v.as_ref().map(|v| (v.clone(), mp.check_velocity(v)));
    let imp = solve.r.as_ref().and_then(|r| mp.check_impulse(r));
    Verified { solve, vel, imp }
}

pub(super) fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "n/a".to_string(), |v| format!("{v:.3e}"))
}
