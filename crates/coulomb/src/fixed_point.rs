//! The outer iteration on s ∈ ℝⁿ₊ (§3.3, §6): s ← F(s) with F(s)ⁱ = ‖ũ_Tⁱ(s)‖ (3.19), either
//! by successive approximation or by safeguarded Anderson mixing, and the paper's stopping
//! measure (6.1).

use crate::cone;
use crate::solver::OuterKind;

/// Fⁱ(s) = ‖ũ_Tⁱ‖ (3.19) for every contact; the tangential part of ũ = W r + b does not
/// depend on E s, so `u` may be W r + q or W r + q + E s.
pub fn evaluate_f(dim: usize, u: &[f64]) -> Vec<f64> {
    u.chunks_exact(dim).map(cone::tangent_norm).collect()
}

/// b = q + E s: (E s)ⁱ = μⁱ sⁱ e, added to the normal component of each contact.
pub fn shifted(dim: usize, q: &[f64], mu: &[f64], s: &[f64], out: &mut Vec<f64>) {
    out.clear();
    out.extend_from_slice(q);
    for ((bi, &m), &si) in out.chunks_exact_mut(dim).zip(mu).zip(s) {
        if m > 0.0 && si > 0.0 {
            bi[0] += m * si;
        }
    }
}

/// ‖F(s) − s‖ and the paper's (6.1) measure ‖F(s) − s‖ / (n (‖s‖ + 1)).
pub fn residuals(s: &[f64], fs: &[f64]) -> (f64, f64) {
    let diff = s
        .iter()
        .zip(fs)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    let n = s.len().max(1) as f64;
    (diff, diff / (n * (crate::law::norm(s) + 1.0)))
}

/// Safeguarded Anderson mixing (type II) on g(s) = F(s) − s, with memory `m`:
///
/// ```text
///     s⁺ = F(s_k) − Σⱼ γⱼ ΔFⱼ,    γ = argmin ‖g_k − Σⱼ γⱼ Δgⱼ‖² (+ tiny ridge),
/// ```
///
/// projected onto s ≥ 0. The history is dropped and a plain step s⁺ = F(s_k) taken whenever
/// ‖g_k‖ grew compared with the previous iteration, or the least-squares system is
/// ill-conditioned.
#[derive(Debug, Clone)]
pub struct Anderson {
    memory: usize,
    prev: Option<(Vec<f64>, Vec<f64>)>, // (F(s_{k−1}), g_{k−1})
    prev_norm: f64,
    dg: Vec<Vec<f64>>,
    df: Vec<Vec<f64>>,
}

impl Anderson {
    /// Mixing with memory `memory` (≥ 1).
    pub fn new(memory: usize) -> Self {
        Self {
            memory: memory.max(1),
            prev: None,
            prev_norm: f64::INFINITY,
            dg: Vec::new(),
            df: Vec::new(),
        }
    }

    /// The next iterate from s_k and F(s_k).
    pub fn next(&mut self, s: &[f64], fs: &[f64]) -> Vec<f64> {
        let g: Vec<f64> = fs.iter().zip(s).map(|(a, b)| a - b).collect();
        let gnorm = crate::law::norm(&g);
        if gnorm > self.prev_norm {
            // safeguard: the residual grew, restart from a plain step
            self.dg.clear();
            self.df.clear();
        } else if let Some((pf, pg)) = &self.prev {
            self.dg.push(g.iter().zip(pg).map(|(a, b)| a - b).collect());
            self.df
                .push(fs.iter().zip(pf).map(|(a, b)| a - b).collect());
            if self.dg.len() > self.memory {
                self.dg.remove(0);
                self.df.remove(0);
            }
        }
        self.prev = Some((fs.to_vec(), g.clone()));
        self.prev_norm = gnorm;
        let mut next = fs.to_vec();
        if let Some(gamma) = least_squares(&self.dg, &g) {
            for (gj, dfj) in gamma.iter().zip(&self.df) {
                for (x, d) in next.iter_mut().zip(dfj) {
                    *x -= gj * d;
                }
            }
        } else {
            self.dg.clear();
            self.df.clear();
        }
        next.iter_mut().for_each(|x| *x = x.max(0.0));
        next
    }
}

/// γ = argmin ‖g − Σ γⱼ aⱼ‖ by the normal equations with a small ridge (k ≤ 10 columns);
/// None if the system is singular or the coefficients are huge.
fn least_squares(a: &[Vec<f64>], g: &[f64]) -> Option<Vec<f64>> {
    let k = a.len();
    if k == 0 {
        return Some(Vec::new());
    }
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    let mut n = vec![0.0; k * k];
    let mut rhs = vec![0.0; k];
    for i in 0..k {
        for j in 0..=i {
            let v = dot(&a[i], &a[j]);
            n[i * k + j] = v;
            n[j * k + i] = v;
        }
        rhs[i] = dot(&a[i], g);
    }
    let trace: f64 = (0..k).map(|i| n[i * k + i]).sum();
    if trace.is_nan() || trace <= 0.0 {
        return None;
    }
    for i in 0..k {
        n[i * k + i] += 1e-10 * trace;
    }
    // Gaussian elimination with partial pivoting
    for c in 0..k {
        let p = (c..k).max_by(|&x, &y| n[x * k + c].abs().total_cmp(&n[y * k + c].abs()))?;
        if n[p * k + c].abs() <= 1e-14 * trace {
            return None;
        }
        if p != c {
            for j in 0..k {
                n.swap(c * k + j, p * k + j);
            }
            rhs.swap(c, p);
        }
        for row in c + 1..k {
            let f = n[row * k + c] / n[c * k + c];
            for j in c..k {
                n[row * k + j] -= f * n[c * k + j];
            }
            rhs[row] -= f * rhs[c];
        }
    }
    let mut x = vec![0.0; k];
    for c in (0..k).rev() {
        let s: f64 = (c + 1..k).map(|j| n[c * k + j] * x[j]).sum();
        x[c] = (rhs[c] - s) / n[c * k + c];
    }
    (x.iter().all(|v| v.is_finite() && v.abs() < 1e4)).then_some(x)
}

/// The update rule of the outer loop.
#[derive(Debug, Clone)]
pub enum OuterUpdate {
    /// s⁺ = F(s)
    Plain,
    /// safeguarded Anderson mixing
    Anderson(Anderson),
}

impl OuterUpdate {
    /// The rule for `kind` (Anderson memory 5). Fused iterations never call [`Self::next`].
    pub fn new(kind: OuterKind) -> Self {
        match kind {
            OuterKind::Anderson => OuterUpdate::Anderson(Anderson::new(5)),
            _ => OuterUpdate::Plain,
        }
    }

    /// The next s from s and F(s).
    pub fn next(&mut self, s: &[f64], fs: &[f64]) -> Vec<f64> {
        match self {
            OuterUpdate::Plain => fs.to_vec(),
            OuterUpdate::Anderson(a) => a.next(s, fs),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anderson_accelerates_a_linear_contraction() {
        // F(s) = A s + c with a slowly contracting A: plain iteration needs hundreds of steps
        let n = 6;
        let f = |s: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    let nb = if i + 1 < n { s[i + 1] } else { 0.0 };
                    0.9 * s[i] + 0.05 * nb + 1.0
                })
                .collect()
        };
        let run = |mut upd: OuterUpdate| -> usize {
            let mut s = vec![0.0; n];
            for k in 0..2000 {
                let fs = f(&s);
                if residuals(&s, &fs).0 < 1e-10 {
                    return k;
                }
                s = upd.next(&s, &fs);
            }
            2000
        };
        let plain = run(OuterUpdate::Plain);
        let anderson = run(OuterUpdate::new(OuterKind::Anderson));
        assert!(plain > 100, "plain {plain}");
        assert!(anderson < 30, "anderson {anderson}");
    }

    #[test]
    fn shift_touches_normal_components_only() {
        let mut b = Vec::new();
        shifted(
            3,
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            &[0.5, 0.0],
            &[2.0, 7.0],
            &mut b,
        );
        assert_eq!(b, vec![2.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(evaluate_f(2, &[1.0, -3.0, 0.0, 4.0]), vec![3.0, 4.0]);
    }
}
