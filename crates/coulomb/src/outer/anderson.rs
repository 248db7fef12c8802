//! Safeguarded Anderson mixing on the outer variable s (§3.3): an acceleration of the
//! successive approximation s ← F(s) of (3.19).

use crate::linalg::dense::least_squares;

/// Parameters of safeguarded Anderson mixing on s ([`Anderson`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AndersonParams {
    /// number of previous differences kept (≥ 1)
    pub memory: usize,
}

impl Default for AndersonParams {
    fn default() -> Self {
        Self { memory: 5 }
    }
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
        self.next_projected(s, fs, |next| next.iter_mut().for_each(|x| *x = x.max(0.0)))
    }

    /// The next iterate from x_k and F(x_k), projected by `project` (onto s ≥ 0 for
    /// [`Anderson::next`], onto L for the sweeps of [`super::fused`]).
    pub fn next_projected(
        &mut self,
        s: &[f64],
        fs: &[f64],
        project: impl FnOnce(&mut [f64]),
    ) -> Vec<f64> {
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
        project(&mut next);
        next
    }

    /// Differences the last step mixed (0: it was the plain step F(x_k)).
    pub fn depth(&self) -> usize {
        self.dg.len()
    }

    /// Drops the differences but keeps the last point (x_k, F(x_k)): the next step mixes
    /// one difference, from there on.
    pub fn restart(&mut self) {
        self.dg.clear();
        self.df.clear();
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    /// x ↦ A x + b with A = diag(0.999, 0.99, 0.9) rotated: a slow affine contraction.
    fn affine(x: &[f64]) -> Vec<f64> {
        let a = [
            [0.995, 0.004, 0.0],
            [-0.004, 0.99, 0.002],
            [0.0, -0.002, 0.9],
        ];
        let b = [1.0, -2.0, 0.5];
        (0..3)
            .map(|i| (0..3).map(|j| a[i][j] * x[j]).sum::<f64>() + b[i])
            .collect()
    }

    fn steps_to(tol: f64, mut next: impl FnMut(&[f64], &[f64]) -> Vec<f64>) -> usize {
        let mut x = vec![0.0; 3];
        for k in 0..100_000 {
            let fx = affine(&x);
            let res: f64 = fx.iter().zip(&x).map(|(a, b)| (a - b).powi(2)).sum();
            if res.sqrt() <= tol {
                return k;
            }
            x = next(&x, &fx);
        }
        usize::MAX
    }

    pub fn mixing_solves_an_affine_fixed_point_in_a_few_steps() {
        let plain = steps_to(1e-10, |_, fx| fx.to_vec());
        let mut aa = Anderson::new(5);
        let mixed = steps_to(1e-10, |x, fx| aa.next_projected(x, fx, |_| {}));
        // the plain iteration contracts by 0.995 per step; on an affine map in ℝ³ type-II
        // mixing with memory ≥ 3 is a secant method that terminates after a few steps
        assert!(plain > 1000, "plain {plain}");
        assert!(mixed < 30, "mixed {mixed}");
    }

    pub fn restart_drops_the_differences_and_keeps_the_last_point() {
        let mut aa = Anderson::new(3);
        let mut x = vec![0.0; 3];
        let mut depths = Vec::new();
        for k in 0..5 {
            if k == 3 {
                aa.restart();
            }
            x = aa.next_projected(&x, &affine(&x), |_| {});
            depths.push(aa.depth());
        }
        assert_eq!(depths, [0, 1, 2, 1, 2]);
    }
}
