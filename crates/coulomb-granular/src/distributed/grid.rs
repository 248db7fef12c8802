//! The decomposition of a distributed run: p₁ slabs along a first horizontal axis, each cut
//! into p₂ cells along the second, every slab at its own bounds (rank of cell (i, j) = i p₂ + j).
//! p₂ = 1 is the slab decomposition of [`super::slab`]; p₁ × p₂ with both above 1 a 2-D grid
//! whose cells hold about N / (p₁ p₂) beads each: the slab bounds at the bead-count quantiles
//! along the first axis, then each slab's cell bounds at the quantiles of its own beads along
//! the second.

use super::slab::{bin_of, quantile_bounds, Slabs};
use crate::math::Vec3;

/// Cells of a p₁ × p₂ decomposition (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// the first and second axis (0: x, 1: y)
    pub axes: [usize; 2],
    /// the p₁ slabs along the first axis
    pub outer: Slabs,
    /// the p₂ cells of each slab along the second axis
    pub inner: Vec<Slabs>,
}

/// The coordinate of p along axis `a` (0: x, else y).
fn along(p: Vec3, a: usize) -> f64 {
    if a == 0 {
        p.x
    } else {
        p.y
    }
}

/// Whether x lies in [lo − halo, hi + halo), the reach of [`Slabs::ghost_targets`].
fn within(x: f64, lo: f64, hi: f64, halo: f64) -> bool {
    x >= lo - halo && x < hi + halo
}

/// Whether the intervals [a₀, a₁) and [b₀, b₁) are within `halo` of each other (with the
/// relative slack of [`Slabs::neighbours`]); symmetric in a and b by construction.
fn near(a: (f64, f64), b: (f64, f64), halo: f64) -> bool {
    let reach = |lo: f64, hi: f64| halo + 1e-6 * (halo.abs() + lo.abs() + hi.abs()) + 1e-12;
    let apart = |lo: (f64, f64), hi: (f64, f64)| hi.0 > lo.1 + reach(lo.1, hi.0);
    !(apart(a, b) || apart(b, a))
}

impl Grid {
    /// p₁ × p₂ cells, all bounds at the first (every cell but the last of each axis empty):
    /// replaced by [`Grid::balanced`] before use.
    pub fn unbalanced(axes: [usize; 2], parts: [usize; 2]) -> Self {
        let outer = Slabs::from_inner(&vec![0.0; parts[0].saturating_sub(1)]);
        let inner = vec![Slabs::from_inner(&vec![0.0; parts[1].saturating_sub(1)]); parts[0]];
        Self { axes, outer, inner }
    }

    /// Cells p₁ × p₂.
    pub fn parts(&self) -> [usize; 2] {
        [self.outer.len(), self.inner.first().map_or(1, Slabs::len)]
    }

    /// Number of cells (ranks).
    pub fn len(&self) -> usize {
        let [a, b] = self.parts();
        a * b
    }

    /// Whether there is no cell.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Cell (i, j) of a rank.
    fn cell(&self, rank: usize) -> (usize, usize) {
        let p2 = self.parts()[1].max(1);
        (rank / p2, rank % p2)
    }

    /// The rectangle of a rank: ((lo, hi) along the first axis, (lo, hi) along the second).
    fn rect(&self, rank: usize) -> ((f64, f64), (f64, f64)) {
        let (i, j) = self.cell(rank);
        let o = &self.outer.bounds;
        let b = &self.inner[i].bounds;
        ((o[i], o[i + 1]), (b[j], b[j + 1]))
    }

    /// The rank owning position p ([`Slabs::owner`] along each axis: a NaN goes to cell 0).
    pub fn owner(&self, p: Vec3) -> usize {
        let i = self.outer.owner(along(p, self.axes[0]));
        let j = self.inner[i].owner(along(p, self.axes[1]));
        i * self.parts()[1] + j
    }

    /// The ranks other than `me` whose cell, widened by `halo` on every side, contains p
    /// (b_lo − halo ≤ x < b_hi + halo along each axis), in no particular order. The cost is
    /// the number of ranks returned plus a few, not P.
    pub fn ghost_targets(&self, me: usize, p: Vec3, halo: f64, out: &mut Vec<usize>) {
        out.clear();
        let (x, y) = (along(p, self.axes[0]), along(p, self.axes[1]));
        let p2 = self.parts()[1];
        let mut cols = Vec::new();
        let mut cells = Vec::new();
        let i0 = self.outer.owner(x);
        let o = &self.outer.bounds;
        if within(x, o[i0], o[i0 + 1], halo) {
            cols.push(i0);
        }
        self.outer.ghost_targets(i0, x, halo, &mut cells);
        cols.extend_from_slice(&cells);
        for i in cols {
            let col = &self.inner[i];
            let j0 = col.owner(y);
            if within(y, col.bounds[j0], col.bounds[j0 + 1], halo) && i * p2 + j0 != me {
                out.push(i * p2 + j0);
            }
            col.ghost_targets(j0, y, halo, &mut cells);
            out.extend(cells.iter().map(|&j| i * p2 + j).filter(|&r| r != me));
        }
    }

    /// The ranks other than `me` whose cell lies within `halo` of this rank's along both axes
    /// (so that ghosts within `halo` of a cell can only come from and go to these), ascending.
    /// Symmetric: the same test, symmetric in the two cells, on both sides. Visits the slabs
    /// within reach ([`Slabs::neighbours`]) and all cells of each.
    pub fn neighbours(&self, me: usize, halo: f64) -> Vec<usize> {
        let (i0, _) = self.cell(me);
        let p2 = self.parts()[1];
        let (_, mine) = self.rect(me);
        let mut cols = self.outer.neighbours(i0, halo);
        cols.push(i0);
        cols.sort_unstable();
        let mut out = Vec::new();
        for i in cols {
            for j in 0..p2 {
                let r = i * p2 + j;
                if r != me && near(mine, self.rect(r).1, halo) {
                    out.push(r);
                }
            }
        }
        out
    }

    /// The grid with p₁ × p₂ cells balanced by the histograms' weights (bead counts, or the
    /// measured work of [`super::Balance::Work`]): the slab bounds at the quantiles of `outer`
    /// (a [`super::slab::HISTOGRAM_BINS`]-bin histogram along the first axis over `range[0]`),
    /// then the cell bounds of slab i at the quantiles of `inner[i]` (its beads' histogram
    /// along the second axis over `range[1]`); every rank computes the same grid from the same
    /// histograms.
    pub fn balanced(
        axes: [usize; 2],
        parts: [usize; 2],
        range: [(f64, f64); 2],
        outer: &[f64],
        inner: &[Vec<f64>],
    ) -> Self {
        let outer_s = Slabs::from_inner(&quantile_bounds(outer, range[0].0, range[0].1, parts[0]));
        let inner_s = (0..parts[0])
            .map(|i| {
                let counts = inner.get(i).map_or(&[][..], Vec::as_slice);
                Slabs::from_inner(&quantile_bounds(counts, range[1].0, range[1].1, parts[1]))
            })
            .collect();
        Self {
            axes,
            outer: outer_s,
            inner: inner_s,
        }
    }

    /// The histogram bin of p along the first axis over `range`.
    pub fn outer_bin(&self, p: Vec3, range: (f64, f64)) -> usize {
        bin_of(along(p, self.axes[0]), range.0, range.1)
    }

    /// The histogram bin of p along the second axis over `range`.
    pub fn inner_bin(&self, p: Vec3, range: (f64, f64)) -> usize {
        bin_of(along(p, self.axes[1]), range.0, range.1)
    }

    /// The slab along the first axis that owns p.
    pub fn slab_of(&self, p: Vec3) -> usize {
        self.outer.owner(along(p, self.axes[0]))
    }

    /// How far p lies outside the cell of `rank` (0 inside; the larger of the two axes'
    /// distances; 0 for a NaN coordinate, which no cell reaches).
    pub fn outside(&self, rank: usize, p: Vec3) -> f64 {
        let ((a0, a1), (b0, b1)) = self.rect(rank);
        let gap = |x: f64, lo: f64, hi: f64| {
            let d = (lo - x).max(x - hi).max(0.0);
            if d.is_nan() {
                0.0
            } else {
                d
            }
        };
        gap(along(p, self.axes[0]), a0, a1).max(gap(along(p, self.axes[1]), b0, b1))
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::super::slab::HISTOGRAM_BINS;
    use super::*;

    /// A 3 × 2 grid over a uniform cloud: balanced cells; owners, ghost targets and
    /// neighbours agree with a brute-force check over all cells; the 1-D case (p₂ = 1) gives
    /// the targets and neighbours of [`Slabs`].
    pub fn grid_cells_targets_and_neighbours() {
        let pts: Vec<Vec3> = (0..60)
            .flat_map(|a| (0..40).map(move |b| Vec3::new(a as f64 * 0.1, b as f64 * 0.05, 0.0)))
            .collect();
        let (rx, ry) = ((0.0, 5.9), (0.0, 1.95));
        let mut outer = vec![0.0; HISTOGRAM_BINS];
        let g0 = Grid::unbalanced([0, 1], [3, 2]);
        for p in &pts {
            outer[g0.outer_bin(*p, rx)] += 1.0;
        }
        let g1 = Grid::balanced([0, 1], [3, 1], [rx, ry], &outer, &[]);
        let mut inner = vec![vec![0.0; HISTOGRAM_BINS]; 3];
        for p in &pts {
            inner[g1.slab_of(*p)][g1.inner_bin(*p, ry)] += 1.0;
        }
        let g = Grid::balanced([0, 1], [3, 2], [rx, ry], &outer, &inner);
        assert_eq!((g.len(), g.parts()), (6, [3, 2]));
        let mut own = [0usize; 6];
        for p in &pts {
            own[g.owner(*p)] += 1;
        }
        assert!(own.iter().all(|&n| n.abs_diff(400) <= 20), "{own:?}");
        let mut t = Vec::new();
        for halo in [0.0, 0.07, 0.3, 2.5] {
            for me in 0..6 {
                let near_me = g.neighbours(me, halo);
                for &o in &near_me {
                    assert!(g.neighbours(o, halo).contains(&me), "{me} {o} {halo}");
                }
                for p in &pts {
                    let mut want: Vec<usize> = (0..6)
                        .filter(|&r| {
                            let ((a0, a1), (b0, b1)) = g.rect(r);
                            r != me && within(p.x, a0, a1, halo) && within(p.y, b0, b1, halo)
                        })
                        .collect();
                    g.ghost_targets(me, *p, halo, &mut t);
                    t.sort_unstable();
                    assert_eq!(t, want, "{me} {p:?} {halo}");
                    if g.owner(*p) == me {
                        want.retain(|r| !near_me.contains(r));
                        assert!(want.is_empty(), "{me} {p:?} {halo}: {want:?}");
                    }
                }
            }
        }
        // p₂ = 1: the slabs
        let s = Slabs::from_inner(&[1.0, 2.0, 3.0]);
        let g = Grid {
            axes: [0, 1],
            outer: s.clone(),
            inner: vec![Slabs::from_inner(&[]); 4],
        };
        let mut u = Vec::new();
        for me in 0..4 {
            for halo in [0.0, 0.1, 1.6] {
                assert_eq!(g.neighbours(me, halo), s.neighbours(me, halo));
                for k in 0..80 {
                    let x = -0.5 + k as f64 * 0.0625;
                    if s.owner(x) != me {
                        continue;
                    }
                    s.ghost_targets(me, x, halo, &mut t);
                    g.ghost_targets(me, Vec3::new(x, 7.0, 0.0), halo, &mut u);
                    t.sort_unstable();
                    u.sort_unstable();
                    assert_eq!(t, u, "{me} {x} {halo}");
                }
            }
        }
        assert_eq!(g.outside(1, Vec3::new(2.5, 0.0, 0.0)), 0.5);
        assert_eq!(g.outside(1, Vec3::new(1.5, 0.0, 0.0)), 0.0);
    }
}
