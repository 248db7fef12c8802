//! Generators of sphere packings: fill a region (box, cylinder, or any region given by an
//! inside test and a bounding box, such as a closed mesh's interior) on a jittered lattice or
//! by random sequential addition, with radii drawn from a size distribution; and an inlet that
//! pours spheres from a region over time.
//!
//! Everything here is pure and deterministic: a fill is a function of its arguments and its
//! seed (one ChaCha8 stream), and the spheres an [`Inlet`] emits between two times are a
//! function of (seed, emission index) and of the bodies already present — a restarted run
//! needs no random-number state to continue an inlet.

use crate::math::Vec3;
use crate::shape::BodyShape;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Why a generator refused its input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GenerateError {
    /// a size distribution's parameters are invalid
    #[error("size distribution: {0}")]
    Distribution(String),
    /// a region is empty or not finite
    #[error("region: {0}")]
    Region(String),
    /// another parameter is out of range
    #[error("{0}")]
    Parameter(String),
    /// the spheres asked for cannot fit in the region: their volume exceeds
    /// [`MAX_PACKING_FRACTION`] of the region's bounding box
    #[error("{count} spheres of radius at least {min_radius} m fill at least {volume:.6e} m³, more than {fraction} of the region's bounding box ({region:.6e} m³): they cannot fit; lower `count` or enlarge the region")]
    CannotFit {
        /// spheres asked for
        count: usize,
        /// the smallest radius of the size distribution (m)
        min_radius: f64,
        /// count × the volume of the smallest sphere (m³)
        volume: f64,
        /// the bounding box's volume (m³)
        region: f64,
        /// [`MAX_PACKING_FRACTION`]
        fraction: f64,
    },
    /// the random addition ran past its time limit
    #[error("random addition stopped after {seconds} s ({attempts} positions tried, {placed} of {count} spheres placed): the region is too crowded for this count; lower `count`, enlarge the region or use the lattice packing")]
    TimeLimit {
        /// the limit ([`FILL_TIME_LIMIT`], s)
        seconds: u64,
        /// positions tried
        attempts: usize,
        /// spheres placed
        placed: usize,
        /// spheres asked for
        count: usize,
    },
}

/// The densest packing fraction a random fill is asked for: 0.64, random close packing of
/// equal spheres (random sequential addition itself jams near 0.38). A random fill whose
/// spheres' volume (count × the smallest sphere's volume) exceeds this fraction of the
/// region's bounding box cannot place them all ([`check_fits`]): it tries at most as many
/// positions as the count that could fit would (1000 each by default) and keeps what fits.
pub const MAX_PACKING_FRACTION: f64 = 0.64;

/// The wall-clock limit of one random fill (s): past it the fill stops with
/// [`GenerateError::TimeLimit`] (an error, never a partial result, so that what a fill
/// returns does not depend on the machine's speed).
pub const FILL_TIME_LIMIT: u64 = 120;

fn dist_err<T>(msg: impl Into<String>) -> Result<T, GenerateError> {
    Err(GenerateError::Distribution(msg.into()))
}

/// Whether the cumulative fractions of a [`SizeDistribution::Psd`] table are by mass (a sieve
/// analysis: mass fraction finer than d) or by number (fraction of the particles smaller
/// than d).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PsdBasis {
    /// cumulative mass fraction (the default: what a sieve analysis gives)
    #[default]
    Mass,
    /// cumulative number fraction
    Number,
}

/// Distribution of the sphere radii (all lengths in m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SizeDistribution {
    /// every sphere has this radius
    Mono {
        /// radius (m)
        radius: f64,
    },
    /// radius uniform in [min, max]
    Uniform {
        /// smallest radius (m)
        min: f64,
        /// largest radius (m)
        max: f64,
    },
    /// radius normal N(mean, sd²), truncated to [min, max] (default mean ± 3 sd; the lower
    /// bound must be positive)
    Normal {
        /// mean radius before truncation (m)
        mean: f64,
        /// standard deviation (m)
        sd: f64,
        /// lower truncation (m)
        #[serde(default)]
        min: Option<f64>,
        /// upper truncation (m)
        #[serde(default)]
        max: Option<f64>,
    },
    /// ln(radius) normal: radius = median · exp(σ Z), Z ~ N(0, 1), truncated to [min, max]
    /// (default median · exp(∓4σ))
    LogNormal {
        /// median radius (m)
        median: f64,
        /// standard deviation σ of ln(radius)
        sigma: f64,
        /// lower truncation (m)
        #[serde(default)]
        min: Option<f64>,
        /// upper truncation (m)
        #[serde(default)]
        max: Option<f64>,
    },
    /// a cumulative particle-size distribution table: `cumulative[i]` is the fraction (by
    /// `basis`) of particles with diameter ≤ `diameters[i]`; diameters strictly increasing,
    /// fractions non-decreasing from 0 to 1; the cumulative fraction is linear in d between
    /// two rows
    Psd {
        /// diameters d_i (m), strictly increasing
        diameters: Vec<f64>,
        /// cumulative fractions F_i, from 0 to 1
        cumulative: Vec<f64>,
        /// whether F is by mass (default) or by number
        #[serde(default)]
        basis: PsdBasis,
    },
}

/// Standard normal cumulative distribution Φ(x) = ½ (1 + erf(x/√2)), erf by Abramowitz and
/// Stegun 7.1.26 (absolute error < 1.5e-7).
fn normal_cdf(x: f64) -> f64 {
    let z = x / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * z.abs());
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let erf = 1.0 - poly * (-z * z).exp();
    0.5 * (1.0 + if z >= 0.0 { erf } else { -erf })
}

/// A standard normal draw by the Box–Muller transform (two uniforms, the cosine branch).
fn standard_normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// Draws of a truncated normal are rejected at most this many times; the truncation interval
/// holds at least 1 % of the mass ([`SizeDistribution::validate`]), so reaching the cap has
/// probability below 0.99^10000 ≈ 1e-44 (then the draw is clamped into the interval).
const MAX_REJECTIONS: usize = 10_000;

impl SizeDistribution {
    /// A single radius.
    pub fn mono(radius: f64) -> Self {
        SizeDistribution::Mono { radius }
    }

    /// The truncation bounds [a, b] of the radius.
    fn bounds(&self) -> (f64, f64) {
        match *self {
            SizeDistribution::Mono { radius } => (radius, radius),
            SizeDistribution::Uniform { min, max } => (min, max),
            SizeDistribution::Normal { mean, sd, min, max } => (
                min.unwrap_or(mean - 3.0 * sd),
                max.unwrap_or(mean + 3.0 * sd),
            ),
            SizeDistribution::LogNormal {
                median,
                sigma,
                min,
                max,
            } => (
                min.unwrap_or(median * (-4.0 * sigma).exp()),
                max.unwrap_or(median * (4.0 * sigma).exp()),
            ),
            SizeDistribution::Psd { ref diameters, .. } => (
                0.5 * diameters.first().copied().unwrap_or(f64::NAN),
                0.5 * diameters.last().copied().unwrap_or(f64::NAN),
            ),
        }
    }

    /// The smallest radius a draw can have.
    pub fn min_radius(&self) -> f64 {
        self.bounds().0
    }

    /// The largest radius a draw can have.
    pub fn max_radius(&self) -> f64 {
        self.bounds().1
    }

    /// Checks the parameters: finite, positive radii, min ≤ max, σ ≥ 0, a truncation interval
    /// holding at least 1 % of the (log-)normal's mass, a well-formed PSD table.
    pub fn validate(&self) -> Result<(), GenerateError> {
        let (a, b) = self.bounds();
        let pos = |x: f64| x.is_finite() && x > 0.0;
        match self {
            SizeDistribution::Normal { mean, sd, .. } => {
                if !(pos(*mean) && sd.is_finite() && *sd >= 0.0) {
                    return dist_err(format!(
                        "normal: mean {mean} must be positive and sd {sd} ≥ 0"
                    ));
                }
                if *sd > 0.0 && normal_cdf((b - mean) / sd) - normal_cdf((a - mean) / sd) < 0.01 {
                    return dist_err(format!(
                        "normal: the truncation [{a}, {b}] holds less than 1 % of N({mean}, {sd}²)"
                    ));
                }
            }
            SizeDistribution::LogNormal { median, sigma, .. } => {
                if !(pos(*median) && sigma.is_finite() && *sigma >= 0.0) {
                    return dist_err(format!(
                        "log_normal: median {median} must be positive and sigma {sigma} ≥ 0"
                    ));
                }
                if *sigma > 0.0 && pos(a) && pos(b) {
                    let m = normal_cdf((b / median).ln() / sigma)
                        - normal_cdf((a / median).ln() / sigma);
                    if m < 0.01 {
                        return dist_err(format!(
                            "log_normal: the truncation [{a}, {b}] holds less than 1 % of the distribution"
                        ));
                    }
                }
            }
            SizeDistribution::Psd {
                diameters,
                cumulative,
                ..
            } => {
                if diameters.len() < 2 || diameters.len() != cumulative.len() {
                    return dist_err(format!(
                        "psd: needs at least 2 rows and as many diameters ({}) as cumulative fractions ({})",
                        diameters.len(),
                        cumulative.len()
                    ));
                }
                if !diameters.iter().all(|&d| pos(d)) || diameters.windows(2).any(|w| w[1] <= w[0])
                {
                    return dist_err("psd: diameters must be positive and strictly increasing");
                }
                if !cumulative.iter().all(|c| c.is_finite())
                    || cumulative.windows(2).any(|w| w[1] < w[0])
                {
                    return dist_err("psd: cumulative fractions must be finite and non-decreasing");
                }
                let (first, last) = (cumulative[0], cumulative[cumulative.len() - 1]);
                if first.abs() > 1e-9 || (last - 1.0).abs() > 1e-9 {
                    return dist_err(format!(
                        "psd: cumulative fractions must go from 0 to 1 (got {first} … {last})"
                    ));
                }
            }
            _ => {}
        }
        if !(pos(a) && pos(b) && a <= b) {
            return dist_err(format!(
                "radii must be positive and finite with min ≤ max (got [{a}, {b}])"
            ));
        }
        Ok(())
    }

    /// Draws one radius. Mono draws nothing from `rng`; uniform draws one number; normal and
    /// log-normal draw pairs until the value falls in the truncation interval (Box–Muller);
    /// a PSD table draws one number and inverts its cumulative distribution (by number) —
    /// linear in d between rows for a number table, and for a mass table the number density
    /// ∝ d⁻³ × (mass density, constant in d between rows), inverted exactly.
    /// Call [`SizeDistribution::validate`] first.
    pub fn sample(&self, rng: &mut ChaCha8Rng) -> f64 {
        let (a, b) = self.bounds();
        match self {
            SizeDistribution::Mono { radius } => *radius,
            SizeDistribution::Uniform { min, max } => {
                if max > min {
                    rng.random_range(*min..=*max)
                } else {
                    *min
                }
            }
            SizeDistribution::Normal { mean, sd, .. } => {
                let mut x = *mean;
                for _ in 0..MAX_REJECTIONS {
                    x = mean + sd * standard_normal(rng);
                    if (a..=b).contains(&x) {
                        return x;
                    }
                }
                x.clamp(a, b)
            }
            SizeDistribution::LogNormal { median, sigma, .. } => {
                let mut x = *median;
                for _ in 0..MAX_REJECTIONS {
                    x = median * (sigma * standard_normal(rng)).exp();
                    if (a..=b).contains(&x) {
                        return x;
                    }
                }
                x.clamp(a, b)
            }
            SizeDistribution::Psd {
                diameters,
                cumulative,
                basis,
            } => 0.5 * psd_inverse(diameters, cumulative, *basis, rng.random::<f64>()),
        }
    }
}

/// The diameter at number-cumulative fraction u ∈ [0, 1) of a PSD table.
fn psd_inverse(d: &[f64], c: &[f64], basis: PsdBasis, u: f64) -> f64 {
    let bins = d.len() - 1;
    match basis {
        PsdBasis::Number => {
            for i in 0..bins {
                let (c0, c1) = (c[i], c[i + 1]);
                if u < c1 && c1 > c0 {
                    return d[i] + (u - c0).max(0.0) / (c1 - c0) * (d[i + 1] - d[i]);
                }
            }
            d[bins]
        }
        PsdBasis::Mass => {
            // number in bin i ∝ (ΔF_i / Δd_i) ∫ d⁻³ dd = (ΔF_i / Δd_i) (d_i⁻² − d_{i+1}⁻²) / 2
            let inv2 = |x: f64| 1.0 / (x * x);
            let w: Vec<f64> = (0..bins)
                .map(|i| {
                    (c[i + 1] - c[i]) / (d[i + 1] - d[i]) * 0.5 * (inv2(d[i]) - inv2(d[i + 1]))
                })
                .collect();
            let total: f64 = w.iter().sum();
            let mut acc = 0.0;
            for i in 0..bins {
                let next = acc + w[i] / total;
                if u < next && w[i] > 0.0 {
                    let v = (u - acc).max(0.0) / (next - acc);
                    let (a, b) = (inv2(d[i]), inv2(d[i + 1]));
                    return (a - v * (a - b)).powf(-0.5).clamp(d[i], d[i + 1]);
                }
                acc = next;
            }
            d[bins]
        }
    }
}

/// A region to fill: its bounding box and whether a sphere lies inside it.
pub trait Region {
    /// The axis-aligned bounding box [lo, hi] (finite).
    fn bounds(&self) -> (Vec3, Vec3);
    /// Whether the sphere of centre `c` and radius `r` lies inside the region.
    fn contains_sphere(&self, c: Vec3, r: f64) -> bool;
}

/// A region given by a shape (the ones a scene file names).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// the box [lo, hi]
    Box {
        /// lower corner (m)
        lo: [f64; 3],
        /// upper corner (m)
        hi: [f64; 3],
    },
    /// the solid cylinder of `radius` whose axis runs from `base` along the unit `axis`
    /// over `height`
    Cylinder {
        /// centre of the base disc (m)
        base: [f64; 3],
        /// axis direction (normalized here)
        #[serde(default = "z_axis")]
        axis: [f64; 3],
        /// radius (m)
        radius: f64,
        /// height (m)
        height: f64,
    },
}

fn z_axis() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

fn v3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

impl Shape {
    /// Checks that the region is finite and not empty (a box with lo < hi, a cylinder with
    /// positive radius and height and a non-zero axis).
    pub fn validate(&self) -> Result<(), GenerateError> {
        let fin = |a: &[f64; 3]| a.iter().all(|x| x.is_finite());
        match self {
            Shape::Box { lo, hi } => {
                if !(fin(lo) && fin(hi) && (0..3).all(|k| lo[k] < hi[k])) {
                    return Err(GenerateError::Region(format!(
                        "box lo {lo:?} hi {hi:?} must be finite with lo < hi"
                    )));
                }
            }
            Shape::Cylinder {
                base,
                axis,
                radius,
                height,
            } => {
                let ok = fin(base)
                    && fin(axis)
                    && v3(*axis).norm() > 1e-12
                    && radius.is_finite()
                    && *radius > 0.0
                    && height.is_finite()
                    && *height > 0.0;
                if !ok {
                    return Err(GenerateError::Region(format!(
                        "cylinder base {base:?} axis {axis:?} radius {radius} height {height}: needs finite values, a non-zero axis, radius > 0 and height > 0"
                    )));
                }
            }
        }
        Ok(())
    }
}

impl Region for Shape {
    fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Shape::Box { lo, hi } => (v3(*lo), v3(*hi)),
            Shape::Cylinder {
                base,
                axis,
                radius,
                height,
            } => {
                let a = v3(*axis).normalized_or(Vec3::Z);
                let (b0, b1) = (v3(*base), v3(*base) + a * *height);
                // a disc of radius R with unit normal a spans R √(1 − a_k²) along axis k
                let e = Vec3::new(
                    radius * (1.0 - a.x * a.x).max(0.0).sqrt(),
                    radius * (1.0 - a.y * a.y).max(0.0).sqrt(),
                    radius * (1.0 - a.z * a.z).max(0.0).sqrt(),
                );
                let lo = Vec3::new(b0.x.min(b1.x), b0.y.min(b1.y), b0.z.min(b1.z)) - e;
                let hi = Vec3::new(b0.x.max(b1.x), b0.y.max(b1.y), b0.z.max(b1.z)) + e;
                (lo, hi)
            }
        }
    }
    fn contains_sphere(&self, c: Vec3, r: f64) -> bool {
        match self {
            Shape::Box { lo, hi } => (0..3).all(|k| {
                let x = c.to_array()[k];
                x - r >= lo[k] && x + r <= hi[k]
            }),
            Shape::Cylinder {
                base,
                axis,
                radius,
                height,
            } => {
                let a = v3(*axis).normalized_or(Vec3::Z);
                let d = c - v3(*base);
                let along = d.dot(a);
                let radial = (d - a * along).norm();
                along >= r && along <= height - r && radial <= radius - r
            }
        }
    }
}

/// A region given by an inside test and a bounding box (a closed mesh's interior, for one).
/// A sphere is taken to be inside when its centre and the six points c ± r e_k are.
pub struct Predicate<'a> {
    /// lower corner of the bounding box
    pub lo: Vec3,
    /// upper corner of the bounding box
    pub hi: Vec3,
    /// whether a point is inside
    pub inside: &'a dyn Fn(Vec3) -> bool,
    /// whether a sphere (centre, radius) whose centre is inside keeps clear of the region's
    /// boundary (a mesh: no triangle nearer than the radius); `None`: the six points c ± r eₖ
    /// are tested with `inside` instead, which lets a sphere cut a wall that is oblique to
    /// the axes (issue 55: the drum mesh's fill overlapped its facets by up to 5 mm)
    pub clear: Option<&'a dyn Fn(Vec3, f64) -> bool>,
}

impl Region for Predicate<'_> {
    fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }
    fn contains_sphere(&self, c: Vec3, r: f64) -> bool {
        let f = self.inside;
        let inb = (0..3).all(|k| {
            let (x, lo, hi) = (
                c.to_array()[k],
                self.lo.to_array()[k],
                self.hi.to_array()[k],
            );
            x - r >= lo && x + r <= hi
        });
        inb && f(c)
            && match self.clear {
                Some(g) => g(c, r),
                None => [Vec3::X, Vec3::Y, Vec3::Z]
                    .iter()
                    .all(|&e| f(c + e * r) && f(c - e * r)),
            }
    }
}

/// A generated sphere (its mass is the caller's: density × 4/3 π r³).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Particle {
    /// centre (m)
    pub position: Vec3,
    /// radius (m)
    pub radius: f64,
    /// initial velocity (m/s)
    pub velocity: Vec3,
}

/// How a region is filled.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case", deny_unknown_fields)]
pub enum Packing {
    /// a cubic lattice filled layer by layer from the bottom (lowest z) up, x fastest, each
    /// site jittered; a site is kept when the jittered sphere lies in the region and overlaps
    /// none of the bodies to avoid
    Lattice {
        /// horizontal pitch (m); default 2.5 × the largest radius
        #[serde(default)]
        pitch: Option<f64>,
        /// vertical pitch (m); default the horizontal pitch
        #[serde(default)]
        layer_pitch: Option<f64>,
        /// height of the first layer's centres above the bounding box's bottom (m); default
        /// half the pitch
        #[serde(default)]
        base: Option<f64>,
        /// distance of the first sites from the bounding box's x and y sides (m); default
        /// half the pitch
        #[serde(default)]
        margin: Option<f64>,
        /// jitter amplitude as a fraction of the largest radius: each coordinate moves by
        /// U(−j R, j R); default 0.2. Refused when it could make two spheres overlap.
        #[serde(default = "default_jitter")]
        jitter: f64,
    },
    /// random sequential addition: the radii are drawn, sorted largest first, and each is
    /// tried at uniformly random positions of the bounding box until one lies in the region
    /// without overlap, for at most `max_attempts` positions in all
    Random {
        /// cap on tried positions over the whole fill; default 1000 × count
        #[serde(default)]
        max_attempts: Option<usize>,
    },
}

fn default_jitter() -> f64 {
    0.2
}

impl Default for Packing {
    fn default() -> Self {
        Packing::Lattice {
            pitch: None,
            layer_pitch: None,
            base: None,
            margin: None,
            jitter: default_jitter(),
        }
    }
}

/// What to place in a fill.
#[derive(Debug, Clone, PartialEq)]
pub struct FillSpec {
    /// number of spheres asked for
    pub count: usize,
    /// their radii
    pub sizes: SizeDistribution,
    /// lattice or random sequential addition
    pub packing: Packing,
    /// the initial velocity of every sphere (m/s)
    pub velocity: Vec3,
    /// each velocity component gets U(−a, a) added (m/s); 0: none drawn
    pub velocity_jitter: f64,
    /// seed of the ChaCha8 stream
    pub seed: u64,
}

/// The result of a fill.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Filled {
    /// the placed spheres
    pub particles: Vec<Particle>,
    /// how many were asked for
    pub asked: usize,
    /// lattice sites visited or random positions tried
    pub attempts: usize,
}

impl Filled {
    /// How many were placed.
    pub fn placed(&self) -> usize {
        self.particles.len()
    }
}

/// A uniform grid of cells of side `cell` holding spheres, for O(1) overlap queries.
struct Grid {
    cell: f64,
    max_r: f64,
    cells: HashMap<[i64; 3], Vec<(Vec3, f64)>>,
}

impl Grid {
    fn new(cell: f64) -> Self {
        Self {
            cell,
            max_r: 0.0,
            cells: HashMap::new(),
        }
    }
    fn key(&self, p: Vec3) -> [i64; 3] {
        let k = |x: f64| (x / self.cell).floor().clamp(-1e15, 1e15) as i64;
        [k(p.x), k(p.y), k(p.z)]
    }
    fn insert(&mut self, p: Vec3, r: f64) {
        self.max_r = self.max_r.max(r);
        let k = self.key(p);
        self.cells.entry(k).or_default().push((p, r));
    }
    /// Whether the sphere (p, r) overlaps a stored one (a gap below 1e-12 m counts).
    fn overlaps(&self, p: Vec3, r: f64) -> bool {
        let reach = ((r + self.max_r) / self.cell).ceil() as i64;
        let k = self.key(p);
        for dz in -reach..=reach {
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    if let Some(v) = self.cells.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        if v.iter().any(|&(q, s)| (q - p).norm() < r + s + 1e-12) {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

/// A grid holding the spheres of `avoid` that can touch the box [lo, hi] grown by `reach`.
fn grid_of(avoid: &[(Vec3, f64)], lo: Vec3, hi: Vec3, reach: f64) -> Grid {
    let big = avoid.iter().map(|a| a.1).fold(0.0, f64::max);
    let mut grid = Grid::new((2.0 * reach).max(big).max(1e-9));
    for &(p, r) in avoid {
        let m = reach + r;
        let near = p.x >= lo.x - m
            && p.x <= hi.x + m
            && p.y >= lo.y - m
            && p.y <= hi.y + m
            && p.z >= lo.z - m
            && p.z <= hi.z + m;
        if near {
            grid.insert(p, r);
        }
    }
    grid
}

/// Lattice sites visited at most (a fill that has not placed its count by then stops).
const MAX_SITES: usize = 100_000_000;

/// Fills `region` with `spec.count` spheres that overlap neither each other nor the spheres of
/// `avoid` (centre, radius), deterministically from `spec.seed`. The lattice stops at the top
/// of the bounding box, the random addition at its attempt cap: [`Filled::placed`] may be
/// below [`FillSpec::count`] when the region is too small.
///
/// Lattice draws, per visited site: the three jitter offsets, the radius, then (when
/// `velocity_jitter` > 0) the three velocity offsets — the same sequence as the built-in
/// scenes' loose arrangement (`scene.rs`), so a file can reproduce them bit for bit.
pub fn fill(
    region: &dyn Region,
    spec: &FillSpec,
    avoid: &[(Vec3, f64)],
) -> Result<Filled, GenerateError> {
    let mut particles = Vec::with_capacity(spec.count.min(1 << 20));
    let attempts = fill_each(region, spec, avoid, &mut |q| particles.push(q))?;
    Ok(Filled {
        particles,
        asked: spec.count,
        attempts,
    })
}

/// Whether `spec.count` spheres can fit by random addition in the bounding box `(lo, hi)`:
/// [`GenerateError::CannotFit`] when count × the smallest sphere's volume exceeds
/// [`MAX_PACKING_FRACTION`] of the box (a fill with `require_all` is refused by it before
/// anything is tried; one without places what fits within the attempts of the count that
/// could).
pub fn check_fits(bounds: (Vec3, Vec3), spec: &FillSpec) -> Result<(), GenerateError> {
    let (lo, hi) = bounds;
    let rmin = spec.sizes.min_radius();
    let sphere = 4.0 / 3.0 * std::f64::consts::PI * rmin * rmin * rmin;
    let volume = spec.count as f64 * sphere;
    let bbox = (hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
    if volume > MAX_PACKING_FRACTION * bbox {
        return Err(GenerateError::CannotFit {
            count: spec.count,
            min_radius: rmin,
            volume,
            region: bbox,
            fraction: MAX_PACKING_FRACTION,
        });
    }
    Ok(())
}

/// [`fill`] handing each placed sphere to `emit` as it is placed, in the order of
/// [`Filled::particles`], instead of collecting them; returns the positions tried
/// ([`Filled::attempts`]). A lattice fill holds nothing per sphere beyond the spheres of
/// `avoid` (O(1) memory with nothing to avoid); a random fill keeps its placed spheres to
/// test the next ones.
pub fn fill_each(
    region: &dyn Region,
    spec: &FillSpec,
    avoid: &[(Vec3, f64)],
    emit: &mut dyn FnMut(Particle),
) -> Result<usize, GenerateError> {
    spec.sizes.validate()?;
    let (lo, hi) = region.bounds();
    if !(lo.is_finite() && hi.is_finite() && lo.x < hi.x && lo.y < hi.y && lo.z < hi.z) {
        return Err(GenerateError::Region(format!(
            "bounding box {lo:?} – {hi:?} must be finite and not empty"
        )));
    }
    if !(spec.velocity.is_finite()
        && spec.velocity_jitter.is_finite()
        && spec.velocity_jitter >= 0.0)
    {
        return Err(GenerateError::Parameter(
            "velocity and velocity_jitter must be finite (jitter ≥ 0)".into(),
        ));
    }
    let rmax = spec.sizes.max_radius();
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let mut grid = grid_of(avoid, lo, hi, rmax);
    let mut placed = 0usize;
    let mut attempts = 0usize;
    let vj = spec.velocity_jitter;
    let velocity = |rng: &mut ChaCha8Rng| {
        if vj > 0.0 {
            let mut v = || rng.random_range(-vj..vj);
            spec.velocity + Vec3::new(v(), v(), v())
        } else {
            spec.velocity
        }
    };
    match spec.packing {
        Packing::Lattice {
            pitch,
            layer_pitch,
            base,
            margin,
            jitter,
        } => {
            let s = pitch.unwrap_or(2.5 * rmax);
            let sz = layer_pitch.unwrap_or(s);
            let base = base.unwrap_or(0.5 * s);
            let margin = margin.unwrap_or(0.5 * s);
            let a = jitter * rmax;
            let fin = |x: f64| x.is_finite() && x >= 0.0;
            if !(fin(s) && s > 0.0 && fin(sz) && sz > 0.0 && fin(base) && fin(margin) && fin(a)) {
                return Err(GenerateError::Parameter(format!(
                    "lattice pitch {s}, layer_pitch {sz}, base {base}, margin {margin}, jitter {jitter}: need finite values, positive pitches"
                )));
            }
            if s.min(sz) - 2.0 * a < 2.0 * rmax {
                return Err(GenerateError::Parameter(format!(
                    "lattice: pitch {} − 2 × jitter {a} is below the largest diameter {}: spheres could overlap",
                    s.min(sz),
                    2.0 * rmax
                )));
            }
            let count = |len: f64, first: f64, last: f64, step: f64| -> usize {
                let span = len - first - last;
                if span < 0.0 {
                    0
                } else {
                    ((span / step).floor() as usize).saturating_add(1)
                }
            };
            let nx = count(hi.x - lo.x, margin, margin, s);
            let ny = count(hi.y - lo.y, margin, margin, s);
            let nz = count(hi.z - lo.z, base, 0.5 * sz, sz);
            'layers: for iz in 0..nz {
                for iy in 0..ny {
                    for ix in 0..nx {
                        if placed >= spec.count || attempts >= MAX_SITES {
                            break 'layers;
                        }
                        attempts += 1;
                        let site = Vec3::new(
                            lo.x + margin + ix as f64 * s,
                            lo.y + margin + iy as f64 * s,
                            lo.z + base + iz as f64 * sz,
                        );
                        let mut j = || {
                            if a > 0.0 {
                                rng.random_range(-a..a)
                            } else {
                                0.0
                            }
                        };
                        let p = site + Vec3::new(j(), j(), j());
                        let r = spec.sizes.sample(&mut rng);
                        if !region.contains_sphere(p, r) || grid.overlaps(p, r) {
                            continue;
                        }
                        let v = velocity(&mut rng);
                        placed += 1;
                        emit(Particle {
                            position: p,
                            radius: r,
                            velocity: v,
                        });
                    }
                }
            }
        }
        Packing::Random { max_attempts } => {
            // a count past the packing bound cannot all be placed: the attempts are those of
            // the count that could (a fill that must place every sphere is refused before,
            // by `check_fits`)
            let fit = match check_fits((lo, hi), spec) {
                Ok(()) => spec.count,
                Err(GenerateError::CannotFit { region, volume, .. }) => {
                    ((spec.count as f64) * MAX_PACKING_FRACTION * region / volume) as usize
                }
                Err(e) => return Err(e),
            };
            let start = std::time::Instant::now();
            let cap = max_attempts.unwrap_or(fit.saturating_mul(1000));
            let mut radii: Vec<f64> = (0..fit.min(MAX_SITES))
                .map(|_| spec.sizes.sample(&mut rng))
                .collect();
            radii.sort_by(|x, y| y.total_cmp(x));
            let placed_grid = &mut grid;
            'spheres: for r in radii {
                while attempts < cap {
                    attempts += 1;
                    if attempts % 4096 == 0 && start.elapsed().as_secs() >= FILL_TIME_LIMIT {
                        return Err(GenerateError::TimeLimit {
                            seconds: FILL_TIME_LIMIT,
                            attempts,
                            placed,
                            count: spec.count,
                        });
                    }
                    let p = Vec3::new(
                        rng.random_range(lo.x..=hi.x),
                        rng.random_range(lo.y..=hi.y),
                        rng.random_range(lo.z..=hi.z),
                    );
                    if region.contains_sphere(p, r) && !placed_grid.overlaps(p, r) {
                        let v = velocity(&mut rng);
                        placed_grid.insert(p, r);
                        placed += 1;
                        emit(Particle {
                            position: p,
                            radius: r,
                            velocity: v,
                        });
                        continue 'spheres;
                    }
                }
                break;
            }
        }
    }
    Ok(attempts)
}

/// The flow rate of an inlet.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Rate {
    /// spheres per second
    Count(f64),
    /// kilograms per second (the emitted mass Σ m_i never exceeds rate × elapsed time)
    Mass(f64),
}

/// Emission indices an inlet handles at most in all (a memory bound).
pub const MAX_EMISSIONS: usize = 10_000_000;

/// An inlet: from `start` to `end`, spheres appear in `region` at `rate` with `velocity`.
///
/// Emission rule. Sphere i (i = 0, 1, …) is due at the first time t with N(t) > i, where
/// N(t) = ⌊rate · (min(t, end) − start)⌋ for a count rate and, for a mass rate, the largest N
/// with m_0 + … + m_{N−1} ≤ rate · (min(t, end) − start). Its radius and its candidate
/// positions come from the ChaCha8 stream number i of `seed`: the radius first, then up to
/// `attempts` uniformly random positions in the region's bounding box; it is inserted at the
/// first candidate that lies in the region and overlaps neither a body present nor a sphere
/// inserted before it in the same call. When every candidate fails the sphere is skipped
/// (counted in [`Emission::skipped`]), never retried: what is emitted between two times
/// depends only on (seed, i), the times and the bodies present, so a restart needs no inlet
/// state beyond the time.
///
/// With a [`Inlet::shape`] (a body of any shape, not a sphere), emission i is that shape
/// scaled about its frame's origin so that its bounding radius
/// ([`BodyShape::bounding_radius`]) is the sampled radius, placed as the sphere of that
/// radius would be (its bounding ball avoids every body's bounding ball: conservative), then
/// turned by a uniformly random rotation drawn next from the same stream i (three more
/// numbers, Shoemake's method): emission i is the same body whatever the step or a restart.
/// Without a shape nothing more is drawn, so the spheres are those of an inlet without the
/// option, to the bit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Inlet {
    /// where spheres appear
    pub region: Shape,
    /// their radii
    pub sizes: SizeDistribution,
    /// their density (kg/m³), for mass rates
    pub density: f64,
    /// flow rate
    pub rate: Rate,
    /// first emission time (s)
    #[serde(default)]
    pub start: f64,
    /// no emission after this time (s); default: none
    #[serde(default = "infinity")]
    pub end: f64,
    /// initial velocity of every emitted sphere (m/s)
    #[serde(default)]
    pub velocity: [f64; 3],
    /// candidate positions per sphere
    #[serde(default = "default_attempts")]
    pub attempts: usize,
    /// seed of the ChaCha8 streams
    #[serde(default)]
    pub seed: u64,
    /// the shape of the emitted bodies (any size: it is scaled so that its bounding radius is
    /// the sampled radius); `None` (or a sphere): spheres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<BodyShape>,
    /// volume of the shape at bounding radius 1 (mass rates), computed on demand
    #[serde(skip)]
    unit_volume: Option<f64>,
    /// cumulative masses of the first emission indices (mass rates), rebuilt on demand
    #[serde(skip)]
    prefix_mass: Vec<f64>,
}

fn infinity() -> f64 {
    f64::INFINITY
}

fn default_attempts() -> usize {
    20
}

/// What an inlet emitted in one call.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Emission {
    /// the inserted spheres (for an inlet with a shape: each body's bounding ball, centred
    /// on its shape frame's origin), in emission order
    pub particles: Vec<Particle>,
    /// for an inlet with a shape, the orientation (w, x, y, z) of each inserted body, in the
    /// order of `particles`; empty for spheres
    pub orientations: Vec<[f64; 4]>,
    /// emission indices that found no free position
    pub skipped: usize,
    /// the emission indices handled: [first, end)
    pub indices: (usize, usize),
    /// emission indices of this step not even tried because the region could hold no more
    /// ([`Inlet::emit`]'s bound; counted in `skipped` too)
    pub capped: usize,
}

/// Consecutive emissions that found no free position after which [`Inlet::emit`] takes the
/// region for full and skips the rest of the step's emissions without trying them.
pub const FULL_AFTER: usize = 1000;

impl Inlet {
    /// An inlet with the default attempts (20), no end time, zero velocity.
    pub fn new(
        region: Shape,
        sizes: SizeDistribution,
        density: f64,
        rate: Rate,
        seed: u64,
    ) -> Self {
        Self {
            region,
            sizes,
            density,
            rate,
            start: 0.0,
            end: f64::INFINITY,
            velocity: [0.0; 3],
            attempts: default_attempts(),
            seed,
            shape: None,
            unit_volume: None,
            prefix_mass: Vec::new(),
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), GenerateError> {
        self.region.validate()?;
        self.sizes.validate()?;
        let r = match self.rate {
            Rate::Count(r) | Rate::Mass(r) => r,
        };
        let ok = r.is_finite()
            && r >= 0.0
            && self.density.is_finite()
            && self.density > 0.0
            && self.start.is_finite()
            && self.start >= 0.0
            && !self.end.is_nan()
            && self.end >= self.start
            && self.velocity.iter().all(|v| v.is_finite())
            && self.attempts >= 1;
        if !ok {
            return Err(GenerateError::Parameter(format!(
                "inlet: rate {r} must be ≥ 0, density {} > 0, 0 ≤ start {} ≤ end {}, velocity finite, attempts {} ≥ 1",
                self.density, self.start, self.end, self.attempts
            )));
        }
        if let Some(shape) = &self.shape {
            shape.validate().map_err(|e| {
                GenerateError::Parameter(format!("inlet shape: {} refused: {e}", shape.kind()))
            })?;
            let r0 = shape.bounding_radius();
            if !(r0.is_finite() && r0 > 0.0) {
                return Err(GenerateError::Parameter(format!(
                    "inlet shape: bounding radius {r0} must be positive"
                )));
            }
        }
        Ok(())
    }

    /// The inlet pouring bodies of `shape` (module docs of [`Inlet`]); a sphere is stored as
    /// no shape (the same spheres, to the bit).
    pub fn with_shape(mut self, shape: Option<BodyShape>) -> Self {
        self.shape = shape.filter(|s| !s.is_sphere());
        self.unit_volume = None;
        self.prefix_mass.clear();
        self
    }

    /// The shape of the bodies poured when they are not spheres.
    pub fn poured_shape(&self) -> Option<&BodyShape> {
        self.shape.as_ref().filter(|s| !s.is_sphere())
    }

    /// The body of an emission of (bounding) radius `radius`: a sphere of that radius
    /// without a shape; with one, the shape scaled so that its bounding radius is `radius`.
    pub fn body_shape(&self, radius: f64) -> BodyShape {
        match self.poured_shape() {
            None => BodyShape::Sphere { radius },
            Some(s) => s.scaled(radius / s.bounding_radius()),
        }
    }

    /// Volume of an emitted body of radius 1: 4/3 π for spheres, the shape's volume over its
    /// bounding radius cubed otherwise (NaN for a shape that does not validate).
    fn volume_factor(&mut self) -> f64 {
        let Some(shape) = self.shape.as_ref().filter(|s| !s.is_sphere()) else {
            return 4.0 / 3.0 * std::f64::consts::PI;
        };
        *self.unit_volume.get_or_insert_with(|| {
            let r0 = shape.bounding_radius();
            shape.volume().map_or(f64::NAN, |v| v / (r0 * r0 * r0))
        })
    }

    /// The radius of emission index i (the first draw of stream i).
    fn radius_of(&self, i: usize) -> f64 {
        let mut rng = self.stream(i);
        self.sizes.sample(&mut rng)
    }

    fn stream(&self, i: usize) -> ChaCha8Rng {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(i as u64);
        rng
    }

    /// N(t): how many emission indices are due by time t (capped at [`MAX_EMISSIONS`]).
    pub fn due(&mut self, t: f64) -> usize {
        let elapsed = t.min(self.end) - self.start;
        if elapsed.is_nan() || elapsed <= 0.0 {
            return 0;
        }
        match self.rate {
            Rate::Count(r) => {
                // the 1e-9 absorbs the rounding of t accumulated as a sum of steps
                let n = (r * elapsed + 1e-9).floor();
                if n >= MAX_EMISSIONS as f64 {
                    MAX_EMISSIONS
                } else {
                    n.max(0.0) as usize
                }
            }
            Rate::Mass(r) => {
                let budget = r * elapsed * (1.0 + 1e-12);
                let vol = self.volume_factor();
                while self.prefix_mass.last().copied().unwrap_or(0.0) <= budget
                    && self.prefix_mass.len() < MAX_EMISSIONS
                {
                    let i = self.prefix_mass.len();
                    let rad = self.radius_of(i);
                    let m = self.density * vol * rad * rad * rad;
                    let last = self.prefix_mass.last().copied().unwrap_or(0.0);
                    self.prefix_mass.push(last + m);
                }
                // prefix_mass[k] = m_0 + … + m_k: N = number of k with prefix ≤ budget
                self.prefix_mass.partition_point(|&m| m <= budget)
            }
        }
    }

    /// The spheres due in (t0, t1] (indices N(t0) … N(t1) − 1), placed by the emission rule
    /// among the bodies `present` (centre, radius).
    pub fn emit(&mut self, t0: f64, t1: f64, present: &[(Vec3, f64)]) -> Emission {
        let (first, last) = (self.due(t0), self.due(t1));
        let mut out = Emission {
            particles: Vec::new(),
            orientations: Vec::new(),
            skipped: 0,
            indices: (first, last.max(first)),
            capped: 0,
        };
        if last <= first {
            return out;
        }
        let (lo, hi) = self.region.bounds();
        let rmax = self.sizes.max_radius();
        let mut grid = grid_of(present, lo, hi, rmax);
        let velocity = v3(self.velocity);
        // the work of a step is bounded by what fits: at most as many spheres as the region's
        // bounding box holds at density one (by volume, smallest radius), and no more tries
        // once FULL_AFTER emissions in a row found no place (a rate of 1e30/s would otherwise
        // try 10⁷ × attempts positions in one step)
        let r_min = self.sizes.min_radius();
        let d = hi - lo;
        let fits = d.x.max(0.0) * d.y.max(0.0) * d.z.max(0.0)
            / (4.0 / 3.0 * std::f64::consts::PI * r_min * r_min * r_min);
        let capacity = if fits.is_finite() && fits < usize::MAX as f64 {
            fits.ceil() as usize
        } else {
            usize::MAX
        };
        let mut in_a_row = 0;
        for i in first..last {
            if out.particles.len() >= capacity || in_a_row >= FULL_AFTER {
                out.capped = last - i;
                out.skipped += last - i;
                break;
            }
            let mut rng = self.stream(i);
            let r = self.sizes.sample(&mut rng);
            let mut placed = false;
            for _ in 0..self.attempts {
                let p = Vec3::new(
                    rng.random_range(lo.x..=hi.x),
                    rng.random_range(lo.y..=hi.y),
                    rng.random_range(lo.z..=hi.z),
                );
                if self.region.contains_sphere(p, r) && !grid.overlaps(p, r) {
                    grid.insert(p, r);
                    out.particles.push(Particle {
                        position: p,
                        radius: r,
                        velocity,
                    });
                    if self.poured_shape().is_some() {
                        out.orientations.push(random_rotation(&mut rng));
                    }
                    placed = true;
                    break;
                }
            }
            if placed {
                in_a_row = 0;
            } else {
                out.skipped += 1;
                in_a_row += 1;
            }
        }
        out
    }
}

/// A rotation drawn uniformly (Haar measure) from three numbers of `rng` (Shoemake, "Uniform
/// random rotations", Graphics Gems III, 1992), as a unit quaternion (w, x, y, z).
fn random_rotation(rng: &mut ChaCha8Rng) -> [f64; 4] {
    let u1: f64 = rng.random_range(0.0..1.0);
    let a = std::f64::consts::TAU * rng.random_range(0.0..1.0);
    let b = std::f64::consts::TAU * rng.random_range(0.0..1.0);
    let (s1, s2) = ((1.0 - u1).sqrt(), u1.sqrt());
    let q = [s2 * b.cos(), s1 * a.sin(), s1 * a.cos(), s2 * b.sin()];
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.map(|x| x / n)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn a_huge_rate_is_bounded_by_what_fits_in_the_region() {
        let mut inlet = Inlet::new(
            Shape::Box {
                lo: [0.0, 0.0, 0.0],
                hi: [0.1, 0.1, 0.1],
            },
            SizeDistribution::Mono { radius: 0.01 },
            2500.0,
            Rate::Count(1e30),
            1,
        );
        let start = std::time::Instant::now();
        let e = inlet.emit(0.0, 1.0, &[]);
        // 10⁷ emissions due; the box holds a few hundred spheres at most
        assert_eq!(e.indices.1 - e.indices.0, MAX_EMISSIONS);
        assert!(e.capped > MAX_EMISSIONS - 10_000, "{}", e.capped);
        assert!(!e.particles.is_empty() && e.particles.len() < 240);
        assert_eq!(e.particles.len() + e.skipped, MAX_EMISSIONS);
        assert!(no_overlap(&e.particles));
        // bounded work, not a stall (a generous bound, not a timing claim)
        assert!(start.elapsed().as_secs() < 20);
    }

    fn no_overlap(ps: &[Particle]) -> bool {
        for (i, a) in ps.iter().enumerate() {
            for b in &ps[i + 1..] {
                if (a.position - b.position).norm() < a.radius + b.radius {
                    return false;
                }
            }
        }
        true
    }

    fn samples(d: &SizeDistribution, n: usize, seed: u64) -> Vec<f64> {
        d.validate().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n).map(|_| d.sample(&mut rng)).collect()
    }

    fn mean(x: &[f64]) -> f64 {
        x.iter().sum::<f64>() / x.len() as f64
    }

    fn spec(count: usize, sizes: SizeDistribution, packing: Packing) -> FillSpec {
        FillSpec {
            count,
            sizes,
            packing,
            velocity: Vec3::ZERO,
            velocity_jitter: 0.0,
            seed: 7,
        }
    }

    pub fn lattice_fill_of_a_box_is_deterministic_counted_and_free_of_overlaps() {
        let region = Shape::Box {
            lo: [0.0; 3],
            hi: [1.0, 1.0, 2.0],
        };
        let s = spec(
            300,
            SizeDistribution::Uniform {
                min: 0.02,
                max: 0.05,
            },
            Packing::default(),
        );
        let a = fill(&region, &s, &[]).unwrap();
        let b = fill(&region, &s, &[]).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.placed(), 300);
        assert!(no_overlap(&a.particles));
        assert!(a
            .particles
            .iter()
            .all(|p| region.contains_sphere(p.position, p.radius)));
        let c = fill(
            &region,
            &FillSpec {
                seed: 8,
                ..s.clone()
            },
            &[],
        )
        .unwrap();
        assert_ne!(a, c);
        // layers fill bottom up: the lowest sphere is within a pitch of the floor
        let zmin = a.particles.iter().map(|p| p.position.z).fold(9.0, f64::min);
        assert!(zmin < 0.125 + 0.011);
        // a region too small places what fits and says so
        let small = Shape::Box {
            lo: [0.0; 3],
            hi: [0.25, 0.25, 0.25],
        };
        let f = fill(&small, &s, &[]).unwrap();
        assert_eq!(f.placed(), 8);
        assert_eq!(f.asked, 300);
    }

    pub fn random_addition_fills_a_cylinder_without_overlap_and_respects_obstacles() {
        let region = Shape::Cylinder {
            base: [0.0, 0.0, 0.0],
            axis: [0.0, 0.0, 1.0],
            radius: 0.5,
            height: 1.0,
        };
        let avoid = vec![(Vec3::new(0.0, 0.0, 0.5), 0.2)];
        let s = spec(
            400,
            SizeDistribution::Uniform {
                min: 0.02,
                max: 0.04,
            },
            Packing::Random { max_attempts: None },
        );
        let a = fill(&region, &s, &avoid).unwrap();
        assert_eq!(a.placed(), 400);
        assert_eq!(a, fill(&region, &s, &avoid).unwrap());
        assert!(no_overlap(&a.particles));
        for p in &a.particles {
            assert!(region.contains_sphere(p.position, p.radius));
            assert!((p.position - avoid[0].0).norm() >= p.radius + 0.2);
        }
        // largest first
        assert!(a.particles.windows(2).all(|w| w[0].radius >= w[1].radius));
        // a count whose volume exceeds the packing bound of the bounding box cannot fit
        // (issue 55: 1000 × count attempts for a count that cannot): `check_fits` says so
        // (a fill that must place all is refused by it), and the fill itself places what
        // fits within the attempts of the count that could (not the default 1000 × 10⁵)
        let big = spec(
            100_000,
            SizeDistribution::mono(0.05),
            Packing::Random { max_attempts: None },
        );
        let e = check_fits(region.bounds(), &big).unwrap_err();
        assert!(
            matches!(e, GenerateError::CannotFit { count: 100_000, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("cannot fit"), "{e}");
        let some = fill(&region, &big, &[]).unwrap();
        let (lo, hi) = region.bounds();
        let bbox = (hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
        let bound = (MAX_PACKING_FRACTION * bbox
            / (4.0 / 3.0 * std::f64::consts::PI * 0.05f64.powi(3))) as usize;
        assert!(
            some.placed() > 100 && some.placed() < bound,
            "{}",
            some.placed()
        );
        assert!(some.attempts <= 1000 * bound);
        assert!(no_overlap(&some.particles));
        // the attempt cap stops a fill within the bound that random addition cannot place
        // (volume fraction 0.5 of the bounding box, 0.63 of the cylinder: past jamming)
        let full = fill(
            &region,
            &spec(
                950,
                SizeDistribution::mono(0.05),
                Packing::Random {
                    max_attempts: Some(20_000),
                },
            ),
            &[],
        )
        .unwrap();
        assert!(full.placed() < 950 && full.placed() > 100);
        assert_eq!(full.attempts, 20_000);
        assert!(no_overlap(&full.particles));
    }

    pub fn predicate_region_fills_the_inside_only() {
        // a ball of radius 0.5 as an inside test
        let inside = |p: Vec3| (p - Vec3::new(0.5, 0.5, 0.5)).norm() < 0.5;
        let region = Predicate {
            lo: Vec3::ZERO,
            hi: Vec3::new(1.0, 1.0, 1.0),
            inside: &inside,
            clear: None,
        };
        for packing in [Packing::default(), Packing::Random { max_attempts: None }] {
            let f = fill(
                &region,
                &spec(50, SizeDistribution::mono(0.04), packing),
                &[],
            )
            .unwrap();
            assert_eq!(f.placed(), 50);
            assert!(no_overlap(&f.particles));
            for p in &f.particles {
                assert!((p.position - Vec3::new(0.5, 0.5, 0.5)).norm() < 0.5);
            }
        }
    }

    pub fn distribution_moments() {
        let n = 10_000;
        let x = samples(&SizeDistribution::Uniform { min: 1.0, max: 3.0 }, n, 1);
        assert!((mean(&x) - 2.0).abs() < 0.02 * 2.0);
        assert!(x.iter().all(|&r| (1.0..=3.0).contains(&r)));

        let d = SizeDistribution::Normal {
            mean: 1.0,
            sd: 0.1,
            min: None,
            max: None,
        };
        let x = samples(&d, n, 2);
        let m = mean(&x);
        let sd = (x.iter().map(|r| (r - m).powi(2)).sum::<f64>() / n as f64).sqrt();
        assert!((m - 1.0).abs() < 0.01);
        // truncated at ±3 sd: the sd is 0.9866 of the untruncated one
        assert!((sd - 0.0987).abs() < 0.05 * 0.0987, "{sd}");
        assert!(x.iter().all(|&r| (0.7..=1.3).contains(&r)));

        let d = SizeDistribution::LogNormal {
            median: 0.01,
            sigma: 0.3,
            min: None,
            max: None,
        };
        let x = samples(&d, n, 3);
        // E[r] = median · exp(σ²/2) (the ±4σ truncation changes it by < 1e-4)
        let expect = 0.01 * (0.045f64).exp();
        assert!((mean(&x) - expect).abs() < 0.02 * expect);
        let mut sorted = x.clone();
        sorted.sort_by(f64::total_cmp);
        assert!((sorted[n / 2] - 0.01).abs() < 0.02 * 0.01);

        assert_eq!(samples(&SizeDistribution::mono(0.3), 5, 4), vec![0.3; 5]);
    }

    /// Empirical cumulative fraction (by number, or by mass ∝ d³) at each table diameter.
    fn empirical(radii: &[f64], diameters: &[f64], by_mass: bool) -> Vec<f64> {
        let w = |r: f64| if by_mass { r * r * r } else { 1.0 };
        let total: f64 = radii.iter().map(|&r| w(r)).sum();
        diameters
            .iter()
            .map(|&d| {
                radii
                    .iter()
                    .filter(|&&r| 2.0 * r <= d)
                    .map(|&r| w(r))
                    .sum::<f64>()
                    / total
            })
            .collect()
    }

    pub fn psd_sampling_matches_the_table() {
        let diameters = vec![1e-3, 2e-3, 3e-3, 5e-3];
        let cumulative = vec![0.0, 0.2, 0.7, 1.0];
        for basis in [PsdBasis::Number, PsdBasis::Mass] {
            let d = SizeDistribution::Psd {
                diameters: diameters.clone(),
                cumulative: cumulative.clone(),
                basis,
            };
            let x = samples(&d, 20_000, 5);
            assert!(x.iter().all(|&r| (0.5e-3..=2.5e-3).contains(&r)));
            let e = empirical(&x, &diameters, basis == PsdBasis::Mass);
            for (k, (got, want)) in e.iter().zip(&cumulative).enumerate() {
                assert!(
                    (got - want).abs() < 0.015,
                    "{basis:?} row {k}: {got} vs {want}"
                );
            }
            // linear interpolation within a bin (by number): half of bin 2's fraction below
            // its mid-diameter
            if basis == PsdBasis::Number {
                let mid = empirical(&x, &[2.5e-3], false)[0];
                assert!((mid - 0.45).abs() < 0.015, "{mid}");
            }
        }
    }

    pub fn bad_distributions_are_refused() {
        let bad = [
            SizeDistribution::mono(-1.0),
            SizeDistribution::mono(f64::NAN),
            SizeDistribution::Uniform { min: 2.0, max: 1.0 },
            SizeDistribution::Normal {
                mean: 1.0,
                sd: 0.5,
                min: None,
                max: None,
            },
            SizeDistribution::Normal {
                mean: 1.0,
                sd: 0.1,
                min: Some(2.0),
                max: Some(3.0),
            },
            SizeDistribution::Psd {
                diameters: vec![1.0, 2.0],
                cumulative: vec![0.0, 0.9],
                basis: PsdBasis::Mass,
            },
            SizeDistribution::Psd {
                diameters: vec![2.0, 1.0],
                cumulative: vec![0.0, 1.0],
                basis: PsdBasis::Mass,
            },
        ];
        for d in bad {
            assert!(d.validate().is_err(), "{d:?}");
        }
    }

    pub fn inlet_emits_by_rate_without_overlap_and_without_state() {
        let region = Shape::Box {
            lo: [0.0, 0.0, 1.0],
            hi: [1.0, 1.0, 1.2],
        };
        let mut inlet = Inlet::new(
            region.clone(),
            SizeDistribution::Uniform {
                min: 0.02,
                max: 0.03,
            },
            2500.0,
            Rate::Count(100.0),
            11,
        );
        inlet.start = 0.1;
        inlet.end = 0.5;
        inlet.validate().unwrap();
        let h = 0.01;
        let mut all: Vec<Particle> = Vec::new();
        let mut restarted: Vec<Particle> = Vec::new();
        let mut skipped = 0;
        for k in 0..60 {
            let (t0, t1) = (k as f64 * h, (k + 1) as f64 * h);
            let present: Vec<(Vec3, f64)> = all.iter().map(|p| (p.position, p.radius)).collect();
            let e = inlet.emit(t0, t1, &present);
            skipped += e.skipped;
            // a fresh inlet (as after a restart) emits the same spheres
            let mut fresh = Inlet::new(
                region.clone(),
                inlet.sizes.clone(),
                2500.0,
                Rate::Count(100.0),
                11,
            );
            fresh.start = 0.1;
            fresh.end = 0.5;
            assert_eq!(fresh.emit(t0, t1, &present), e);
            restarted.extend(fresh.emit(t0, t1, &present).particles);
            all.extend(e.particles);
        }
        assert_eq!(all.len() + skipped, 40);
        assert!(all.len() >= 35, "{}", all.len());
        assert_eq!(all, restarted);
        assert!(no_overlap(&all));
        for p in &all {
            assert!(region.contains_sphere(p.position, p.radius));
        }
        // an inlet whose region is occupied skips
        let present = vec![(Vec3::new(0.5, 0.5, 1.1), 2.0)];
        let e = inlet.emit(0.0, 0.3, &present);
        assert!(e.particles.is_empty());
        assert_eq!(e.skipped, 20);
    }

    pub fn an_inlet_shape_adds_only_a_rotation_drawn_after_the_sphere() {
        let sphere = || {
            let mut inlet = Inlet::new(
                Shape::Box {
                    lo: [0.0, 0.0, 0.0],
                    hi: [0.5, 0.5, 0.5],
                },
                SizeDistribution::Uniform {
                    min: 0.02,
                    max: 0.04,
                },
                1000.0,
                Rate::Count(400.0),
                9,
            );
            inlet.velocity = [0.0, 0.0, -1.0];
            inlet
        };
        let present = [(Vec3::new(0.25, 0.25, 0.25), 0.1)];
        let plain = sphere().emit(0.0, 0.25, &present);
        assert_eq!(plain.particles.len() + plain.skipped, 100);
        assert!(plain.particles.len() >= 90);
        assert!(plain.orientations.is_empty());
        // a sphere as the shape: the same inlet, the same spheres to the bit
        let ball = sphere().with_shape(Some(BodyShape::Sphere { radius: 3.0 }));
        assert_eq!(ball, sphere());
        // a capsule: the same bounding balls (placement draws first), and a unit
        // quaternion per body, each its own
        let capsule = BodyShape::Capsule {
            radius: 0.5,
            half_height: 1.0,
        };
        let mut shaped = sphere().with_shape(Some(capsule.clone()));
        shaped.validate().unwrap();
        let e = shaped.emit(0.0, 0.25, &present);
        assert_eq!(e.particles, plain.particles);
        assert_eq!(e.orientations.len(), e.particles.len());
        for q in &e.orientations {
            crate::shape::check_quaternion("q", *q).unwrap();
        }
        let distinct: std::collections::BTreeSet<_> =
            e.orientations.iter().map(|q| q.map(f64::to_bits)).collect();
        assert_eq!(distinct.len(), e.orientations.len());
        // stateless: the emissions of (0.1, 0.25] by a fresh inlet are the tail of the above
        let mut fresh = sphere().with_shape(Some(capsule.clone()));
        let first = fresh.due(0.1);
        let mut present_then = present.to_vec();
        present_then.extend(e.particles[..first].iter().map(|p| (p.position, p.radius)));
        let tail = fresh.emit(0.1, 0.25, &present_then);
        assert_eq!(tail.particles, e.particles[first..]);
        assert_eq!(tail.orientations, e.orientations[first..]);
        // the body: the capsule scaled to the radius
        let r = e.particles[0].radius;
        let body = shaped.body_shape(r);
        assert!((body.bounding_radius() - r).abs() <= 1e-15);
        // a mass rate counts each body's mass: the shape's volume at that radius
        let mut by_mass = sphere().with_shape(Some(capsule));
        by_mass.rate = Rate::Mass(2.0);
        let n = by_mass.due(0.5);
        let mass: f64 = (0..n)
            .map(|i| 1000.0 * by_mass.body_shape(by_mass.radius_of(i)).volume().unwrap())
            .sum();
        assert!(mass <= 1.0 * (1.0 + 1e-9), "{mass}");
        let next = 1000.0 * by_mass.body_shape(by_mass.radius_of(n)).volume().unwrap();
        assert!(mass + next > 1.0 * (1.0 - 1e-9), "{mass} + {next}");
        // an invalid shape is refused by validate
        let bad = sphere().with_shape(Some(BodyShape::Cuboid {
            half_extents: [1.0, -1.0, 1.0],
        }));
        assert!(bad.validate().is_err());
    }

    pub fn mass_rate_inlet_never_exceeds_its_mass() {
        let mut inlet = Inlet::new(
            Shape::Cylinder {
                base: [0.0; 3],
                axis: [0.0, 0.0, 1.0],
                radius: 0.5,
                height: 0.5,
            },
            SizeDistribution::Uniform {
                min: 0.01,
                max: 0.03,
            },
            1000.0,
            Rate::Mass(2.0),
            3,
        );
        inlet.validate().unwrap();
        let n = inlet.due(1.0);
        let vol = 4.0 / 3.0 * std::f64::consts::PI;
        let mass = |k: usize| -> f64 {
            (0..k)
                .map(|i| 1000.0 * vol * inlet.radius_of(i).powi(3))
                .sum()
        };
        assert!(mass(n) <= 2.0 * (1.0 + 1e-9));
        assert!(mass(n + 1) > 2.0);
        assert!(n > 10);
        // a fresh inlet agrees
        let mut fresh = inlet.clone();
        fresh.prefix_mass.clear();
        assert_eq!(fresh.due(1.0), n);
        assert_eq!(fresh.due(0.5), inlet.due(0.5));
    }
}
