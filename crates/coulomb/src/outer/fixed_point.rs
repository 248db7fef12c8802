//! The outer iteration on s ∈ ℝⁿ₊ (§3.3, §6): the map F(s)ⁱ = ‖ũ_Tⁱ(s)‖ (3.19), the shift
//! b = q + E s of the inner problem, the paper's stopping measure (6.1), and the update rule
//! s ← F(s) (successive approximation) or Anderson mixing ([`super::anderson`]).

pub use super::anderson::Anderson;
use crate::cone;
use crate::outer::anderson::AndersonParams;
use crate::settings::OuterKind;

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

/// The update rule of the outer loop.
#[derive(Debug, Clone)]
pub enum OuterUpdate {
    /// s⁺ = F(s)
    Plain,
    /// safeguarded Anderson mixing
    Anderson(Anderson),
}

impl OuterUpdate {
    /// The rule for `kind` with the default Anderson memory. Fused iterations never call
    /// [`Self::next`].
    pub fn new(kind: OuterKind) -> Self {
        Self::with_params(kind, &crate::settings::Tuning::default().anderson)
    }

    /// The rule for `kind`, Anderson mixing with `params`.
    pub fn with_params(kind: OuterKind, params: &AndersonParams) -> Self {
        match kind {
            OuterKind::Anderson => OuterUpdate::Anderson(Anderson::new(params.memory)),
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

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    pub fn anderson_accelerates_a_linear_contraction() {
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

    pub fn shift_touches_normal_components_only() {
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
