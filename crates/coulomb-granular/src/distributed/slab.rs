//! Slab decomposition along one horizontal axis: rank r owns the beads whose coordinate lies in
//! [b_r, b_{r+1}), b_0 = −∞, b_P = +∞, the inner bounds placed at bead-count quantiles so that
//! every rank owns about N/P beads; ghosts are the beads within a halo of a slab.

/// Bins of the histogram from which the quantiles are taken ([`quantile_bounds`]).
pub const HISTOGRAM_BINS: usize = 4096;

/// The slab bounds b_0 = −∞ < b_1 ≤ … ≤ b_{P−1} < b_P = +∞ (P + 1 values).
#[derive(Debug, Clone, PartialEq)]
pub struct Slabs {
    /// the bounds, P + 1 values
    pub bounds: Vec<f64>,
}

impl Slabs {
    /// P slabs from the P − 1 inner bounds (sorted).
    pub fn from_inner(inner: &[f64]) -> Self {
        let mut bounds = Vec::with_capacity(inner.len() + 2);
        bounds.push(f64::NEG_INFINITY);
        bounds.extend_from_slice(inner);
        bounds.push(f64::INFINITY);
        Self { bounds }
    }
    /// Number of slabs P.
    pub fn len(&self) -> usize {
        self.bounds.len().saturating_sub(1)
    }
    /// Whether there is no slab.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The rank owning coordinate x: the r with b_r ≤ x < b_{r+1} (a NaN goes to rank 0).
    pub fn owner(&self, x: f64) -> usize {
        let p = self.len();
        if p == 0 {
            return 0;
        }
        // number of inner bounds ≤ x
        let inner = &self.bounds[1..p];
        inner.partition_point(|&b| b <= x).min(p - 1)
    }
    /// The ranks other than `me` whose slab, widened by `halo` on both sides, contains x:
    /// b_r − halo ≤ x < b_{r+1} + halo. Walks outwards from `me`, so the cost is the number of
    /// ranks returned (plus two), not P.
    pub fn ghost_targets(&self, me: usize, x: f64, halo: f64, out: &mut Vec<usize>) {
        out.clear();
        let p = self.len();
        let mut r = me;
        while r > 0 {
            r -= 1;
            if x < self.bounds[r + 1] + halo {
                out.push(r);
            } else {
                break;
            }
        }
        let mut r = me + 1;
        while r < p {
            if x >= self.bounds[r] - halo {
                out.push(r);
                r += 1;
            } else {
                break;
            }
        }
    }

    /// The ranks other than `me` that can exchange ghosts with `me` for this `halo`: r < s
    /// are neighbours when b_s ≤ b_{r+1} + halo (with a relative slack of 10⁻⁶ against
    /// rounding), the same test on both sides, so the relation is symmetric and contains
    /// every pair that [`Self::ghost_targets`] links in either direction (a bead x of slab s
    /// goes to r < s when x < b_{r+1} + halo, where b_s ≤ x; to r > s when x ≥ b_r − halo, where
    /// x < b_{s+1}). Ascending; walks outwards from `me`.
    pub fn neighbours(&self, me: usize, halo: f64) -> Vec<usize> {
        let p = self.len();
        let reach = halo + 1e-6 * halo.abs() + 1e-12;
        let near = |r: usize, s: usize| {
            let (lo, hi) = (self.bounds[r + 1], self.bounds[s]);
            hi <= lo + reach + 1e-6 * (lo.abs() + hi.abs())
        };
        let mut out = Vec::new();
        let mut r = me;
        while r > 0 && near(r - 1, me) {
            r -= 1;
        }
        out.extend(r..me);
        let mut s = me + 1;
        while s < p && near(me, s) {
            out.push(s);
            s += 1;
        }
        out
    }
}

/// Inner bounds at the quantiles k W / P (k = 1 … P − 1) of a histogram of `HISTOGRAM_BINS`
/// equal bins over [lo, hi] (`counts`: bead counts or measured work, summed over all ranks,
/// W their total), linearly
/// interpolated inside a bin. Every rank computes the same bounds from the same reduced
/// histogram. With lo = hi (or no bead) all inner bounds are lo.
pub fn quantile_bounds(counts: &[f64], lo: f64, hi: f64, parts: usize) -> Vec<f64> {
    let total: f64 = counts.iter().sum();
    let nb = counts.len().max(1);
    let width = (hi - lo) / nb as f64;
    let mut inner = Vec::with_capacity(parts.saturating_sub(1));
    let (mut bin, mut below) = (0usize, 0.0f64);
    for k in 1..parts {
        let target = total * k as f64 / parts as f64;
        while bin < counts.len() && below + counts[bin] < target {
            below += counts[bin];
            bin += 1;
        }
        let b = if width.is_nan() || width <= 0.0 || bin >= counts.len() {
            if bin >= counts.len() {
                hi
            } else {
                lo
            }
        } else {
            let c = counts[bin];
            let frac = if c > 0.0 {
                ((target - below) / c).clamp(0.0, 1.0)
            } else {
                0.0
            };
            lo + width * (bin as f64 + frac)
        };
        inner.push(b);
    }
    inner
}

/// The histogram bin of x over [lo, hi] with `HISTOGRAM_BINS` bins (clamped to the range).
pub fn bin_of(x: f64, lo: f64, hi: f64) -> usize {
    if hi.is_nan() || lo.is_nan() || hi <= lo || !x.is_finite() {
        return 0;
    }
    let t = ((x - lo) / (hi - lo) * HISTOGRAM_BINS as f64).floor();
    (t.max(0.0) as usize).min(HISTOGRAM_BINS - 1)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn owners_and_ghost_targets() {
        let s = Slabs::from_inner(&[1.0, 2.0, 3.0]);
        assert_eq!(s.len(), 4);
        assert_eq!(s.owner(-5.0), 0);
        assert_eq!(s.owner(1.0), 1);
        assert_eq!(s.owner(2.5), 2);
        assert_eq!(s.owner(1e9), 3);
        let mut t = Vec::new();
        // 1.95 in slab 1: within 0.1 of slab 2, not of slab 0 (ends at 1)
        s.ghost_targets(1, 1.95, 0.1, &mut t);
        assert_eq!(t, vec![2]);
        s.ghost_targets(1, 1.05, 0.1, &mut t);
        assert_eq!(t, vec![0]);
        // a halo wider than a slab reaches two slabs away
        s.ghost_targets(0, 0.5, 1.6, &mut t);
        assert_eq!(t, vec![1, 2]);
        s.ghost_targets(3, 10.0, 0.1, &mut t);
        assert!(t.is_empty());
        // neighbours: symmetric, and every ghost target among them
        assert_eq!(s.neighbours(1, 0.1), vec![0, 2]);
        assert_eq!(s.neighbours(0, 1.6), vec![1, 2]);
        assert_eq!(s.neighbours(3, 1.6), vec![1, 2]);
        assert_eq!(s.neighbours(0, 0.5), vec![1]);
        for halo in [0.0, 0.1, 0.99, 1.0, 1.01, 2.5] {
            for me in 0..4 {
                let near = s.neighbours(me, halo);
                for &o in &near {
                    assert!(s.neighbours(o, halo).contains(&me), "{me} {o} {halo}");
                }
                for k in 0..=400 {
                    let x = -0.5 + k as f64 * 0.0125;
                    if s.owner(x) != me {
                        continue;
                    }
                    s.ghost_targets(me, x, halo, &mut t);
                    assert!(t.iter().all(|o| near.contains(o)), "{me} {x} {halo}: {t:?}");
                }
            }
        }
        // empty slabs (equal bounds) are neighbours of each other
        let e = Slabs::from_inner(&[1.0, 1.0, 1.0]);
        assert_eq!(e.neighbours(1, 0.0), vec![0, 2, 3]);
    }

    pub fn quantiles_split_the_beads_evenly() {
        // 1000 beads spread uniformly over [0, 10) and 1000 packed into [0, 1)
        let xs: Vec<f64> = (0..1000)
            .map(|i| i as f64 * 0.01)
            .chain((0..1000).map(|i| i as f64 * 0.001))
            .collect();
        let (lo, hi) = (0.0, 10.0);
        let mut counts = vec![0.0; HISTOGRAM_BINS];
        for &x in &xs {
            counts[bin_of(x, lo, hi)] += 1.0;
        }
        for parts in [1usize, 2, 3, 4, 7] {
            let inner = quantile_bounds(&counts, lo, hi, parts);
            assert_eq!(inner.len(), parts - 1);
            let s = Slabs::from_inner(&inner);
            let mut own = vec![0usize; parts];
            for &x in &xs {
                own[s.owner(x)] += 1;
            }
            let ideal = xs.len() / parts;
            for (r, &n) in own.iter().enumerate() {
                // within a bin's worth of beads (at most 1000 · 10/4096 + 1 per bin here)
                assert!(
                    n.abs_diff(ideal) <= 5,
                    "{parts} parts, rank {r}: {n} of {ideal}"
                );
            }
        }
        // degenerate range: all bounds at lo
        let inner = quantile_bounds(&[5.0, 0.0], 1.0, 1.0, 3);
        assert_eq!(inner, vec![1.0, 1.0]);
    }

    /// Weighted histograms (the measured work of `Balance::Work`): beads on [0, 1) weigh 3
    /// each, on [1, 2) 1 each, as many of each; two parts split the work, not the beads: the
    /// bound at 2/3, below which lies half of the total work 3 × 1000 + 1000.
    pub fn quantiles_of_weighted_histograms_split_the_work() {
        let xs: Vec<f64> = (0..2000).map(|i| (i as f64 + 0.5) * 0.001).collect();
        let mut counts = vec![0.0; HISTOGRAM_BINS];
        for &x in &xs {
            counts[bin_of(x, 0.0, 2.0)] += if x < 1.0 { 3.0 } else { 1.0 };
        }
        let inner = quantile_bounds(&counts, 0.0, 2.0, 2);
        assert!(
            (inner[0] - 2.0 / 3.0).abs() < 2.0 / HISTOGRAM_BINS as f64,
            "{inner:?}"
        );
        let s = Slabs::from_inner(&inner);
        let mut work = [0.0f64; 2];
        for &x in &xs {
            work[s.owner(x)] += if x < 1.0 { 3.0 } else { 1.0 };
        }
        assert!((work[0] - work[1]).abs() <= 6.0, "{work:?}");
    }
}
