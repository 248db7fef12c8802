//! Contact detection: a uniform-grid broad phase (O(N) per step), exact sphere–sphere and
//! sphere–obstacle narrow phase, a frame (n, t₁, t₂) per contact, and Moreau–Jean's
//! activation rule (the index set of active contacts).

use crate::math::Vec3;
use crate::world::{ContactLaw, World};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;

/// The other party B of a contact, for every body (sphere or not): another body, or a
/// feature of an obstacle.
///
/// As JSON (checkpoints' contacts and pair caches, Python's `contacts`): `{"kind": "body",
/// "index": j}` or `{"kind": "obstacle", "index": o}`, with `"feature": f` when f ≠ 0 (the
/// form of the rigid scenes' records before this type was theirs too, so older files read).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, serde::Deserialize,
)]
#[serde(into = "PartnerRecord", try_from = "PartnerRecord")]
pub enum Partner {
    /// another body (its index is larger than the contact's first body)
    Body(usize),
    /// a feature of an obstacle: (obstacle index, feature index — the wall of a box, the
    /// triangle of a mesh, 0 for one-feature shapes; [`crate::world::Obstacle::proximities`]).
    /// The rigid engine's pairs are whole obstacles (feature 0): a point's sub-shape is in
    /// its contact key ([`crate::collision::manifold::ContactKey`]).
    Obstacle(usize, u32),
}

/// [`Partner`] as serde reads and writes it.
#[derive(Clone, Copy, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct PartnerRecord {
    kind: PartnerKind,
    index: usize,
    #[serde(default, skip_serializing_if = "is_zero")]
    feature: u32,
}

#[derive(Clone, Copy, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
enum PartnerKind {
    Body,
    Obstacle,
}

fn is_zero(f: &u32) -> bool {
    *f == 0
}

impl From<Partner> for PartnerRecord {
    fn from(p: Partner) -> Self {
        match p {
            Partner::Body(index) => Self {
                kind: PartnerKind::Body,
                index,
                feature: 0,
            },
            Partner::Obstacle(index, feature) => Self {
                kind: PartnerKind::Obstacle,
                index,
                feature,
            },
        }
    }
}

impl TryFrom<PartnerRecord> for Partner {
    type Error = String;
    fn try_from(r: PartnerRecord) -> Result<Self, String> {
        match r.kind {
            PartnerKind::Body if r.feature != 0 => Err(format!(
                "body {}: a body has no feature ({})",
                r.index, r.feature
            )),
            PartnerKind::Body => Ok(Partner::Body(r.index)),
            PartnerKind::Obstacle => Ok(Partner::Obstacle(r.index, r.feature)),
        }
    }
}

/// An active contact i between sphere `body` (A) and `partner` (B) at time t_k.
///
/// The frame is normal first: `normal` points from B towards A, so the relative velocity
/// u = v_A(p) − v_B(p) has u_N = n·u > 0 when the two separate, and the impulse r acts on A
/// (−r on B). The local coordinates of u and r are (n·, t₁·, t₂·).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Contact {
    /// sphere A
    pub body: usize,
    /// B
    pub partner: Partner,
    /// unit normal n (B → A)
    pub normal: Vec3,
    /// first tangent t₁
    pub t1: Vec3,
    /// second tangent t₂ = n × t₁
    pub t2: Vec3,
    /// contact point (midway between the surfaces)
    pub point: Vec3,
    /// gap g_k (negative: penetration)
    pub gap: f64,
    /// normal relative velocity u_{N,k} at the beginning of the step
    pub normal_velocity: f64,
    /// impulse r_{k+1} in local coordinates (n, t₁, t₂), filled after the solve
    pub impulse: [f64; 3],
}

impl Contact {
    /// The key (body, partner) identifying a contact across steps (warm start).
    pub fn key(&self) -> (usize, Partner) {
        (self.body, self.partner)
    }
    /// The impulse in world coordinates, acting on A: r_N n + r_T1 t₁ + r_T2 t₂.
    pub fn world_impulse(&self) -> Vec3 {
        self.normal * self.impulse[0] + self.t1 * self.impulse[1] + self.t2 * self.impulse[2]
    }
}

/// A [`Contact`] in its JSON form: body A (`a`), partner B (`b`), point, normal (B → A), t₁,
/// gap and impulse (r_N, r_T1, r_T2), without t₂ = n × t₁ and u_{N,k}. The form of Python's
/// `Simulation.contacts` for every scene, and of the contacts of rigid checkpoints before
/// version 6 (`/json/contacts`).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactJson {
    /// body A
    pub a: usize,
    /// B
    pub b: Partner,
    /// contact point
    pub point: [f64; 3],
    /// unit normal n, B → A
    pub normal: [f64; 3],
    /// first tangent t₁
    pub t1: [f64; 3],
    /// gap at the start of the step
    pub gap: f64,
    /// impulse (r_N, r_T1, r_T2)
    pub impulse: [f64; 3],
}

impl From<&Contact> for ContactJson {
    fn from(c: &Contact) -> Self {
        ContactJson {
            a: c.body,
            b: c.partner,
            point: c.point.to_array(),
            normal: c.normal.to_array(),
            t1: c.t1.to_array(),
            gap: c.gap,
            impulse: c.impulse,
        }
    }
}

impl From<ContactJson> for Contact {
    /// t₂ recomputed as n × t₁; u_{N,k}, which the form does not hold, NaN (unknown).
    fn from(c: ContactJson) -> Self {
        let (normal, t1) = (Vec3::from_slice(&c.normal), Vec3::from_slice(&c.t1));
        Contact {
            body: c.a,
            partner: c.b,
            normal,
            t1,
            t2: normal.cross(t1),
            point: Vec3::from_slice(&c.point),
            gap: c.gap,
            normal_velocity: f64::NAN,
            impulse: c.impulse,
        }
    }
}

/// Moreau–Jean's activation rule. A candidate pair with gap g_k and normal relative velocity
/// u_{N,k} enters the index set when its gap predicted at t_k + γh is below the threshold
/// ([`detect`] passes min(u_{N,k}, u_{N,free}), u_{N,free} the normal velocity of the free
/// motion at t_{k+1}, gravity included):
///
/// ```text
///     g_k + γ h u_{N,k} ≤ δ_k
/// ```
///
/// (unclamped, as Siconos' `MoreauJeanOSI::addInteractionInIndexSet`: a pair that separates
/// at t_k leaves the index set as soon as its predicted gap is positive). γ = 1/2 by default.
/// `delta` is the floor of δ_k; with `delta_from_tolerance`, [`crate::Simulation`] raises δ_k each step to twice the lift
/// h·ε_u that a contact solved to the step's tolerance can get (ε_u = err · scale of
/// docs/error.md, a bound on the residual normal velocity of a resting contact), so that a
/// resting contact lifted by solver error never leaves the index set (docs/granular.md,
/// "Activation and tolerance"). `Default` is Siconos' rule (γ = 1/2, unclamped), used by
/// `coulomb paper`; [`Activation::accurate`] is the rule of `coulomb simulate`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
pub struct Activation {
    /// γ ∈ [0, 1]
    pub gamma: f64,
    /// floor of δ ≥ 0, an absolute distance (m)
    pub delta: f64,
    /// keep a pair with g_k ≤ δ in the index set even when it separates at t_k (the rule
    /// becomes g_k + γ h min(u_{N,k}, 0) ≤ δ): a resting contact whose solver residual
    /// lifts it slightly stays active; energy-safe with the impact law of
    /// [`crate::assembly::impact_offset`]
    pub keep_separating: bool,
    /// raise δ each step to the lift the solver's residual allows
    /// ([`crate::Simulation::activation_threshold`]); otherwise δ = `delta`
    pub delta_from_tolerance: bool,
    /// let a sphere–obstacle contact that the look-ahead by gravity holds at a positive gap
    /// close it ([`crate::assembly::gap_closure`]): a sphere at rest settles onto the
    /// obstacle instead of hovering up to h² |g·n| above it
    pub close_gaps: bool,
}

impl Default for Activation {
    fn default() -> Self {
        Self {
            gamma: 0.5,
            delta: 1e-8,
            keep_separating: false,
            delta_from_tolerance: false,
            close_gaps: false,
        }
    }
}

impl Activation {
    /// The rule of `coulomb simulate`: γ = 1 (a pair that the linear prediction closes within
    /// the step is active, so that an elastic contact does not penetrate), pairs with g ≤ δ kept
    /// even when they separate.
    pub fn accurate() -> Self {
        Self {
            gamma: 1.0,
            delta: 1e-8,
            keep_separating: true,
            delta_from_tolerance: true,
            close_gaps: true,
        }
    }

    /// Whether a pair with gap g and normal velocity u_N is active for step size h, with the
    /// floor δ of `self`.
    pub fn is_active(&self, gap: f64, u_n: f64, h: f64) -> bool {
        self.is_active_with(gap, u_n, h, self.delta)
    }
    /// Whether g + γ h u_N ≤ δ for the given δ.
    pub fn is_active_with(&self, gap: f64, u_n: f64, h: f64, delta: f64) -> bool {
        let u = if self.keep_separating {
            u_n.min(0.0)
        } else {
            u_n
        };
        gap + self.gamma * h * u <= delta
    }
}

/// Relative velocity v_A(p) − v_B(p) at point p of a contact (B = body or obstacle) at time t.
pub fn relative_velocity(world: &World, a: usize, partner: Partner, p: Vec3, t: f64) -> Vec3 {
    let point_velocity = |i: usize| -> Vec3 {
        world
            .bodies
            .get(i)
            .map(|b| b.velocity + b.angular_velocity.cross(p - b.position))
            .unwrap_or(Vec3::ZERO)
    };
    let va = point_velocity(a);
    let vb = match partner {
        Partner::Body(j) => point_velocity(j),
        Partner::Obstacle(o, _) => world
            .obstacles
            .get(o)
            .map(|ob| ob.motion.velocity_at(p, t))
            .unwrap_or(Vec3::ZERO),
    };
    va - vb
}

/// Runs `f` over the chunks `[c·chunk, (c+1)·chunk) ∩ [0, n)` in parallel (rayon), each
/// chunk pushing its items into its own buffer, and concatenates the buffers in chunk order
/// (the copy in parallel too): the result does not depend on the number of threads.
pub(crate) fn par_chunked<T: Send>(
    n: usize,
    chunk: usize,
    f: impl Fn(std::ops::Range<usize>, &mut Vec<T>) + Sync,
) -> Vec<T> {
    let chunk = chunk.max(1);
    let parts: Vec<Vec<T>> = (0..n.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let mut out = Vec::new();
            f(c * chunk..((c + 1) * chunk).min(n), &mut out);
            out
        })
        .collect();
    let total = parts.iter().map(Vec::len).sum();
    let mut out: Vec<T> = Vec::with_capacity(total);
    {
        // disjoint destination slices, one per part, filled in parallel
        let mut slots: Vec<&mut [std::mem::MaybeUninit<T>]> = Vec::with_capacity(parts.len());
        let mut rest = &mut out.spare_capacity_mut()[..total];
        for p in &parts {
            let (head, tail) = rest.split_at_mut(p.len());
            slots.push(head);
            rest = tail;
        }
        parts
            .into_par_iter()
            .zip(slots.into_par_iter())
            .for_each(|(p, slot)| {
                for (dst, x) in slot.iter_mut().zip(p) {
                    dst.write(x);
                }
            });
    }
    // SAFETY: the `total` slots were all written above (the parts' lengths sum to `total`)
    unsafe { out.set_len(total) };
    out
}

/// Spheres per chunk of the parallel broad and narrow phases.
pub(crate) const SPHERE_CHUNK: usize = 256;

/// The uniform grid of the broad phase: cells of the size of the largest enlarged diameter
/// 2 R_max + margin, so that each sphere is compared with the spheres of its 27
/// neighbouring cells only (O(N) for bounded density).
pub(crate) struct BroadPhase<'a> {
    world: &'a World,
    margin: f64,
    keys: Vec<[i64; 3]>,
    dense: Option<DenseGrid>,
    hash: HashMap<[i64; 3], Vec<usize>>,
}

impl<'a> BroadPhase<'a> {
    pub(crate) fn new(world: &'a World, margin: f64) -> Self {
        let rmax = world
            .bodies
            .iter()
            .map(|b| b.radius)
            .fold(0.0_f64, f64::max);
        let cell = (2.0 * rmax + margin).max(1e-12);
        let key = |x: Vec3| -> [i64; 3] {
            let k = |c: f64| (c / cell).floor().clamp(-1e15, 1e15) as i64;
            [k(x.x), k(x.y), k(x.z)]
        };
        let keys: Vec<[i64; 3]> = world.bodies.par_iter().map(|b| key(b.position)).collect();
        let dense = DenseGrid::new(&keys);
        let mut hash: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        if dense.is_none() {
            hash.reserve(keys.len());
            for (i, k) in keys.iter().enumerate() {
                hash.entry(*k).or_default().push(i);
            }
        }
        Self {
            world,
            margin,
            keys,
            dense,
            hash,
        }
    }

    /// The spheres j > i whose enlarged bounding spheres meet sphere i's (|x_i − x_j| ≤
    /// R_i + R_j + margin), in increasing order, into `out` (cleared first).
    pub(crate) fn partners(&self, i: usize, out: &mut Vec<usize>) {
        out.clear();
        let bodies = &self.world.bodies;
        let Some(a) = bodies.get(i) else {
            return;
        };
        let mut test = |j: usize| {
            if j > i {
                if let Some(b) = bodies.get(j) {
                    let reach = a.radius + b.radius + self.margin;
                    if (a.position - b.position).norm_sq() <= reach * reach {
                        out.push(j);
                    }
                }
            }
        };
        let k = self.keys[i];
        match &self.dense {
            Some(grid) => grid.neighbours(k, test),
            None => {
                let [cx, cy, cz] = k;
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            let cell = self.hash.get(&[cx + dx, cy + dy, cz + dz]);
                            for &j in cell.into_iter().flatten() {
                                test(j);
                            }
                        }
                    }
                }
            }
        }
        out.sort_unstable();
    }
}

/// Solid sphere obstacles (fixed bodies of the scene model) from which a grid is built: below
/// this many, every sphere is tested against every obstacle.
pub(crate) const OBSTACLE_GRID_MIN: usize = 32;

/// The obstacles a sphere may touch: every obstacle, except that when the world has at least
/// [`OBSTACLE_GRID_MIN`] solid sphere obstacles these are found through a uniform grid of their
/// centres (cells of 2 (r_max + R_max) + reach: a sphere is tested against the obstacles of
/// the 27 cells around it), so that a floor made of 10⁴ fixed spheres costs O(contacts), not
/// O(N · obstacles). The candidates come in increasing obstacle order; the contacts found are
/// those of the full loop (the grid only skips obstacles out of reach).
pub(crate) struct ObstacleIndex {
    /// obstacles tested for every sphere
    always: Vec<usize>,
    /// cell size and the ball obstacles by cell
    grid: Option<(f64, CellMap)>,
}

/// Obstacle indices by grid cell.
type CellMap = HashMap<[i64; 3], Vec<usize>>;

impl ObstacleIndex {
    /// The index of `world`'s obstacles at time t for contacts within `reach` of the surfaces.
    pub(crate) fn new(world: &World, t: f64, reach: f64) -> Self {
        let balls = world
            .obstacles
            .iter()
            .filter(|o| o.ball_at(t).is_some())
            .count();
        let all = (0..world.obstacles.len()).collect();
        if balls < OBSTACLE_GRID_MIN || !reach.is_finite() {
            return Self {
                always: all,
                grid: None,
            };
        }
        let rmax = world
            .bodies
            .iter()
            .map(|b| b.radius)
            .fold(0.0_f64, f64::max);
        let bmax = world
            .obstacles
            .iter()
            .filter_map(|o| o.ball_at(t).map(|b| b.1))
            .fold(0.0_f64, f64::max);
        let cell = (2.0 * (rmax + bmax) + reach.max(0.0)).max(1e-12);
        let mut always = Vec::new();
        let mut cells: CellMap = HashMap::new();
        for (o, ob) in world.obstacles.iter().enumerate() {
            match ob.ball_at(t) {
                Some((c, _)) if c.is_finite() => {
                    cells.entry(cell_key(c, cell)).or_default().push(o)
                }
                _ => always.push(o),
            }
        }
        Self {
            always,
            grid: Some((cell, cells)),
        }
    }

    /// The candidate obstacles of a sphere centred at x, in increasing order, into `out`.
    pub(crate) fn candidates(&self, x: Vec3, out: &mut Vec<usize>) {
        out.clear();
        out.extend_from_slice(&self.always);
        if let Some((cell, cells)) = &self.grid {
            let [cx, cy, cz] = cell_key(x, *cell);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(v) = cells.get(&[cx + dx, cy + dy, cz + dz]) {
                            out.extend_from_slice(v);
                        }
                    }
                }
            }
            out.sort_unstable();
        }
    }
}

fn cell_key(x: Vec3, cell: f64) -> [i64; 3] {
    let k = |c: f64| (c / cell).floor().clamp(-1e15, 1e15) as i64;
    [k(x.x), k(x.y), k(x.z)]
}

/// Uniform grid broad phase: candidate sphere pairs (i < j) whose bounding boxes, enlarged by
/// `margin`, may overlap. Cells have the size of the largest enlarged diameter, so each sphere
/// is compared with the spheres of its 27 neighbouring cells only: O(N) for bounded density.
/// Built in parallel, in (i, j) order.
pub fn candidate_pairs(world: &World, margin: f64) -> Vec<(usize, usize)> {
    let grid = BroadPhase::new(world, margin);
    par_chunked(world.bodies.len(), SPHERE_CHUNK, |range, out| {
        let mut js = Vec::new();
        for i in range {
            grid.partners(i, &mut js);
            out.extend(js.iter().map(|&j| (i, j)));
        }
    })
}

/// Cells of the broad phase as a dense array over the spheres' bounding box (compressed
/// rows: the spheres of cell c are `items[start[c]..start[c + 1]]`), when that box has at
/// most 8 cells per sphere (otherwise a hash map is used).
struct DenseGrid {
    lo: [i64; 3],
    dims: [i64; 3],
    start: Vec<usize>,
    items: Vec<usize>,
}

impl DenseGrid {
    fn new(keys: &[[i64; 3]]) -> Option<Self> {
        let first = keys.first()?;
        let (mut lo, mut hi) = (*first, *first);
        for k in keys {
            for d in 0..3 {
                lo[d] = lo[d].min(k[d]);
                hi[d] = hi[d].max(k[d]);
            }
        }
        let dims = [hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1];
        let cells = dims
            .iter()
            .try_fold(1i64, |acc, &d| acc.checked_mul(d))
            .filter(|&c| c <= 8 * keys.len() as i64 + 64)? as usize;
        let index = |k: &[i64; 3]| {
            (((k[2] - lo[2]) * dims[1] + (k[1] - lo[1])) * dims[0] + (k[0] - lo[0])) as usize
        };
        let mut start = vec![0usize; cells + 1];
        for k in keys {
            start[index(k) + 1] += 1;
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let mut next = start.clone();
        let mut items = vec![0usize; keys.len()];
        for (i, k) in keys.iter().enumerate() {
            let c = index(k);
            items[next[c]] = i;
            next[c] += 1;
        }
        Some(Self {
            lo,
            dims,
            start,
            items,
        })
    }

    /// Calls `f` on every sphere of the 27 cells around cell `k`.
    fn neighbours(&self, k: [i64; 3], mut f: impl FnMut(usize)) {
        for dz in -1..=1 {
            let z = k[2] - self.lo[2] + dz;
            if z < 0 || z >= self.dims[2] {
                continue;
            }
            for dy in -1..=1 {
                let y = k[1] - self.lo[1] + dy;
                if y < 0 || y >= self.dims[1] {
                    continue;
                }
                let row = (z * self.dims[1] + y) * self.dims[0];
                let x0 = (k[0] - self.lo[0] - 1).max(0);
                let x1 = (k[0] - self.lo[0] + 1).min(self.dims[0] - 1);
                // cells x0..=x1 of this row are contiguous
                let (a, b) = ((row + x0) as usize, (row + x1) as usize);
                for &j in &self.items[self.start[a]..self.start[b + 1]] {
                    f(j);
                }
            }
        }
    }
}

/// Detects the active contacts of `world` at time t for step size h: candidate pairs within
/// a margin from the broad phase, exact gaps and frames, then the [`Activation`] rule.
/// Contacts are ordered by (body, partner), obstacles after bodies.
pub fn detect(world: &World, t: f64, h: f64, activation: &Activation) -> Vec<Contact> {
    detect_with(world, t, h, activation, activation.delta)
}

/// [`detect`] with the threshold δ given (≥ the activation's floor).
pub fn detect_with(
    world: &World,
    t: f64,
    h: f64,
    activation: &Activation,
    delta: f64,
) -> Vec<Contact> {
    let vmax = world
        .bodies
        .iter()
        .map(|b| b.velocity.norm() + b.angular_velocity.norm() * b.radius)
        .fold(0.0_f64, f64::max);
    detect_with_speed(world, t, h, activation, delta, vmax)
}

/// [`detect_with`] with the largest speed v_max = max |v| + R|ω| of the broad phase's margin
/// δ + 2 v_max h γ (sphere–obstacle pairs: + γ h (h |g| + V_B), the look-ahead by gravity
/// and the obstacle's largest normal speed) given: a part of a larger system (a rank's subdomain in
/// `crate::distributed`, feature `mpi`) passes the whole system's v_max, so that its margin,
/// and with it the obstacle contacts it finds, are those of one process.
pub fn detect_with_speed(
    world: &World,
    t: f64,
    h: f64,
    activation: &Activation,
    delta: f64,
    vmax: f64,
) -> Vec<Contact> {
    let delta = delta.max(activation.delta);
    let margin = delta + 2.0 * vmax * h * activation.gamma + 1e-12;
    let make = |a: usize, partner: Partner, normal: Vec3, point: Vec3, gap: f64| {
        let u = relative_velocity(world, a, partner, point, t);
        let un = u.dot(normal);
        // the free motion's normal velocity at t_{k+1}: gravity acts on A alone when B is an
        // obstacle (it cancels between two spheres)
        let free = match partner {
            Partner::Obstacle(..) => un + h * world.gravity.dot(normal),
            Partner::Body(_) => un,
        };
        activation
            .is_active_with(gap, un.min(free), h, delta)
            .then(|| {
                let (t1, t2) = normal.tangent_basis();
                Contact {
                    body: a,
                    partner,
                    normal,
                    t1,
                    t2,
                    point,
                    gap,
                    normal_velocity: un,
                    impulse: [0.0; 3],
                }
            })
    };
    // broad and narrow phases in one parallel pass over chunks of spheres: sphere i's
    // contacts with spheres j > i in increasing j, then with the obstacles in order, i.e.
    // the contacts come out sorted by (body, partner), whatever the number of threads
    // an obstacle contact's look-ahead also sees gravity (h u_{N,free} reaches h² |g|
    // further) and the obstacle's own normal speed
    let obstacle_margin: Vec<f64> = world
        .obstacles
        .iter()
        .map(|o| margin + activation.gamma * h * (h * world.gravity.norm() + o.max_normal_speed()))
        .collect();
    let grid = BroadPhase::new(world, margin);
    let reach = obstacle_margin.iter().copied().fold(0.0_f64, f64::max);
    let obstacles = ObstacleIndex::new(world, t, reach);
    par_chunked(world.bodies.len(), SPHERE_CHUNK, |range, out| {
        let mut js = Vec::new();
        let mut near = Vec::new();
        let mut obs = Vec::new();
        for i in range {
            let Some(a) = world.bodies.get(i) else {
                continue;
            };
            grid.partners(i, &mut js);
            for &j in &js {
                let b = &world.bodies[j];
                let d = a.position - b.position;
                let dist = d.norm();
                let n = d.normalized_or(Vec3::Z);
                let gap = dist - a.radius - b.radius;
                // the point midway between the two surfaces
                let point = b.position + n * (b.radius + 0.5 * gap);
                out.extend(make(i, Partner::Body(j), n, point, gap));
            }
            obstacles.candidates(a.position, &mut obs);
            for &o in &obs {
                let ob = &world.obstacles[o];
                near.clear();
                ob.proximities(a.position, a.radius, t, obstacle_margin[o], &mut near);
                for &(f, p) in &near {
                    let point = p.point + p.normal * (0.5 * p.gap);
                    out.extend(make(i, Partner::Obstacle(o, f), p.normal, point, p.gap));
                }
            }
        }
    })
}

/// The contact laws of a world's sphere pairs (kept beside [`Partner`], which names them).
impl World {
    /// The contact law of sphere `a` with `partner`: the pair of their materials in
    /// [`World::materials`], or `default` (the parameters' law) without a table or for an
    /// index out of range.
    #[inline]
    pub fn contact_law(&self, a: usize, partner: Partner, default: ContactLaw) -> ContactLaw {
        let Some(table) = &self.materials else {
            return default;
        };
        let ma = self.bodies.get(a).map(|b| b.material);
        let mb = match partner {
            Partner::Body(j) => self.bodies.get(j).map(|b| b.material),
            Partner::Obstacle(o, _) => self.obstacles.get(o).map(|b| b.material),
        };
        match (ma, mb) {
            (Some(ma), Some(mb)) => table.law(ma, mb).unwrap_or(default),
            _ => default,
        }
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::world::{Motion, Obstacle, Shape, Sphere};
    use rand::{Rng, SeedableRng};

    /// One partner type for every contact: its JSON is the rigid records' form (written
    /// and read back), a feature appears only when it is not 0, and a body with a feature
    /// or an unknown kind is refused.
    pub fn a_partner_reads_and_writes_the_rigid_records_form() {
        let cases = [
            (Partner::Body(3), r#"{"kind":"body","index":3}"#),
            (Partner::Obstacle(2, 0), r#"{"kind":"obstacle","index":2}"#),
            (
                Partner::Obstacle(2, 5),
                r#"{"kind":"obstacle","index":2,"feature":5}"#,
            ),
        ];
        for (p, json) in cases {
            assert_eq!(serde_json::to_string(&p).unwrap(), json);
            assert_eq!(serde_json::from_str::<Partner>(json).unwrap(), p);
        }
        for bad in [
            r#"{"kind":"body","index":1,"feature":2}"#,
            r#"{"kind":"wall","index":1}"#,
            r#"{"kind":"body","index":1,"side":0}"#,
        ] {
            assert!(serde_json::from_str::<Partner>(bad).is_err(), "{bad}");
        }
    }

    pub fn grid_finds_the_same_pairs_as_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut world = World::new();
        for _ in 0..400 {
            let x = Vec3::new(
                rng.random_range(0.0..1.0),
                rng.random_range(0.0..1.0),
                rng.random_range(0.0..1.0),
            );
            world
                .bodies
                .push(Sphere::new(x, rng.random_range(0.01..0.04), 1.0));
        }
        let margin = 0.01;
        let grid = candidate_pairs(&world, margin);
        let mut brute = Vec::new();
        for i in 0..world.bodies.len() {
            for j in i + 1..world.bodies.len() {
                let (a, b) = (&world.bodies[i], &world.bodies[j]);
                if (a.position - b.position).norm() <= a.radius + b.radius + margin {
                    brute.push((i, j));
                }
            }
        }
        assert!(!brute.is_empty());
        assert_eq!(grid, brute);
        // a far sphere makes the dense grid too large: the hash-map path, same pairs
        world
            .bodies
            .push(Sphere::new(Vec3::new(1e6, -1e6, 3e5), 0.02, 1.0));
        assert!(DenseGrid::new(&[[0, 0, 0], [1_000_000, 0, 0]]).is_none());
        assert_eq!(candidate_pairs(&world, margin), brute);
    }

    pub fn resting_spheres_find_floor_contacts_that_only_gravity_or_the_floor_closes() {
        // everything at rest (v_max = 0): the sphere–sphere margin is δ alone, but a sphere
        // 2 mm above a fixed floor is active by gravity's look-ahead (2 mm < h² g = 3.9 mm),
        // and one 5 mm above a plate rising at 0.5 m/s by the plate's motion (5 mm < h·0.5 + h² g)
        let h = 0.02;
        let mut world = World::new();
        world.gravity = Vec3::new(0.0, 0.0, -9.81);
        world.obstacles.push(Obstacle::fixed(
            "ground",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        world
            .bodies
            .push(Sphere::new(Vec3::new(0.0, 0.0, 0.1 + 2e-3), 0.1, 1.0));
        let c = detect(&world, 0.0, h, &Activation::accurate());
        assert_eq!(c.len(), 1, "{c:?}");
        assert!((c[0].gap - 2e-3).abs() < 1e-12);
        let mut plate = Obstacle::fixed(
            "plate",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        );
        let speed = 0.5;
        plate.motion = Motion::Oscillate {
            direction: Vec3::Z,
            amplitude: 0.01,
            frequency: speed / (2.0 * std::f64::consts::PI * 0.01),
        };
        world.obstacles[0] = plate;
        world.bodies[0].position.z = 0.1 + 5e-3;
        let c = detect(&world, 0.0, h, &Activation::accurate());
        assert_eq!(c.len(), 1, "{c:?}");
        assert!((c[0].normal_velocity + speed).abs() < 1e-12, "{c:?}");
        // out of reach: 2 cm above the rising plate
        world.bodies[0].position.z = 0.1 + 2e-2;
        assert!(detect(&world, 0.0, h, &Activation::accurate()).is_empty());
    }

    pub fn detection_frames_and_activation() {
        let mut world = World::new();
        world.obstacles.push(Obstacle::fixed(
            "ground",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        world
            .bodies
            .push(Sphere::new(Vec3::new(0.0, 0.0, 0.1), 0.1, 1.0));
        let mut falling = Sphere::new(Vec3::new(0.0, 0.0, 0.31), 0.1, 1.0);
        falling.velocity = Vec3::new(0.0, 0.0, -1.0);
        world.bodies.push(falling);
        // far sphere, no contact
        world
            .bodies
            .push(Sphere::new(Vec3::new(5.0, 0.0, 0.5), 0.1, 1.0));
        let h = 0.02;
        let c = detect(&world, 0.0, h, &Activation::default());
        // body 0 – body 1: gap 0.01, u_N = −1 → 0.01 − 0.5·0.02·1 = 0 ≤ 0: active
        // body 0 – ground: gap 0: active
        assert_eq!(c.len(), 2);
        assert_eq!(c[0].key(), (0, Partner::Body(1)));
        assert!(
            (c[0].normal + Vec3::Z).norm() < 1e-12,
            "normal from B=1 to A=0"
        );
        assert!((c[0].gap - 0.01).abs() < 1e-12);
        assert!((c[0].normal_velocity + 1.0).abs() < 1e-12);
        assert_eq!(c[1].key(), (0, Partner::Obstacle(0, 0)));
        // with γ = 0.4 the pair is inactive
        let c = detect(
            &world,
            0.0,
            h,
            &Activation {
                gamma: 0.4,
                delta: 0.0,
                keep_separating: false,
                delta_from_tolerance: false,
                close_gaps: false,
            },
        );
        assert_eq!(c.len(), 1);
    }

    pub fn a_floor_of_fixed_balls_is_found_through_the_obstacle_grid() {
        // 10 × 10 fixed balls (a rough floor) under 30 free spheres: the contacts found through
        // the grid are those of testing every obstacle
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut world = World::new();
        world.obstacles.push(Obstacle::fixed(
            "ground",
            Shape::Plane {
                point: Vec3::new(0.0, 0.0, -0.05),
                normal: Vec3::Z,
            },
        ));
        for k in 0..100 {
            let c = Vec3::new(0.1 * (k % 10) as f64, 0.1 * (k / 10) as f64, 0.0);
            world.obstacles.push(Obstacle::fixed(
                "ball",
                Shape::Sphere {
                    center: c,
                    radius: 0.05,
                    inside: false,
                },
            ));
        }
        for _ in 0..30 {
            let x = Vec3::new(
                rng.random_range(0.0..0.9),
                rng.random_range(0.0..0.9),
                rng.random_range(0.06..0.09),
            );
            let mut s = Sphere::new(x, 0.05, 1.0);
            s.velocity = Vec3::new(0.0, 0.0, -0.5);
            world.bodies.push(s);
        }
        let h = 0.01;
        let act = Activation::accurate();
        let contacts = detect(&world, 0.0, h, &act);
        let index = ObstacleIndex::new(&world, 0.0, 1.0);
        assert!(index.grid.is_some());
        // brute force: every obstacle within the same reach
        let mut expected = Vec::new();
        let vmax = 0.5;
        let margin = act.delta + 2.0 * vmax * h * act.gamma + 1e-12;
        let reach = margin + act.gamma * h * (h * 9.81);
        for (i, b) in world.bodies.iter().enumerate() {
            for (o, ob) in world.obstacles.iter().enumerate() {
                let p = ob.proximity(b.position, b.radius, 0.0);
                let u = -0.5 * p.normal.z;
                let free = u + h * world.gravity.dot(p.normal);
                if p.gap <= reach && act.is_active(p.gap, u.min(free), h) {
                    expected.push((i, Partner::Obstacle(o, 0)));
                }
            }
        }
        let got: Vec<_> = contacts
            .iter()
            .filter(|c| matches!(c.partner, Partner::Obstacle(..)))
            .map(|c| c.key())
            .collect();
        assert!(got.len() > 20, "{}", got.len());
        assert_eq!(got, expected);
    }
}
