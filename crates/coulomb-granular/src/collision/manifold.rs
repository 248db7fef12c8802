//! Contacts of rigid bodies: parry's BVH broad phase, parry's contact manifolds (several
//! points per face–face contact, as Bullet and LMGC90 give), the contact frame and the
//! warm-start keys.
//!
//! # Frame convention
//! As in the sphere code ([`crate::contact::Contact`]): contact i is between body A (the
//! smaller index) and B (a body of larger index, or an obstacle). Its normal n points
//! **from B towards A**, so the relative velocity u = v_A(p) − v_B(p) has u_N = n·u > 0 when
//! the two separate and the impulse r acts on A (−r on B). parry gives the normal of a
//! manifold in the first shape's frame pointing out of A towards B: n is its opposite. The
//! point p is midway between the two surfaces' closest points and the gap g is parry's signed
//! distance (negative: penetration). The tangents are those of every contact, sphere or not
//! ([`tangent_frame`], `Vec3::tangent_basis`): t₁ = e × n / |e × n| for the world axis e least
//! aligned with n, t₂ = n × t₁.
//!
//! # Manifolds and warm start
//! Each pair of the broad phase keeps its manifolds and parry's workspace across steps
//! (composite shapes reuse them). Each manifold point carries parry's feature ids (vertex,
//! edge or face of each shape) and the sub-shape indices of compound or mesh shapes: the key
//! (A, B, sub-shape A, sub-shape B, feature A, feature B) names the same physical contact at
//! the next step, whose impulse (kept in world axes) warm starts it.
//!
//! # Broad phase
//! parry's [`Bvh`] of the bodies' AABBs, each enlarged by the distance the body can travel
//! in the step (`margin`), traversed against itself for body pairs; bounded obstacles query
//! it with their AABB, half-spaces (unbounded) meet every body.
//!
//! # Balls: the analytic fast path
//! A pair of two balls, and a ball against a half-space obstacle, is not handed to parry:
//! its one contact point is computed in closed form (`ball_ball`, `ball_half_space`) with
//! exactly parry's frame, gap, acceptance test (`prediction`) and warm-start key (sub-shapes
//! 0, the face-0 feature of each shape, rank 0), and it keeps no pair cache (parry keeps no
//! state of such a pair that changes its next result). The points are then the same as
//! parry's up to round-off (tests below), in the same order. Ball–half-space pairs are
//! found by one loop over the balls, outside the per-pair machinery.

use crate::bodies::dynamics::BodyState;
use crate::bodies::rigid::RigidError;
use crate::collision::contact::Partner;
use crate::collision::polytope::{self, Polytope};
use crate::math::Vec3;
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};
use parry3d_f64::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use parry3d_f64::shape::{PackedFeatureId, SharedShape};
use std::collections::BTreeMap;

/// Key of a manifold point across steps: (A, B, sub-shape of A, sub-shape of B, feature
/// of A, feature of B, rank among points with the same ids).
pub type ContactKey = (usize, Partner, u32, u32, u32, u32, u32);

/// One manifold point at t_k.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactPoint {
    /// body A
    pub a: usize,
    /// B
    pub b: Partner,
    /// warm-start key
    pub key: ContactKey,
    /// point p, world
    pub point: Vector,
    /// unit normal B → A
    pub normal: Vector,
    /// t₁
    pub t1: Vector,
    /// t₂ = n × t₁
    pub t2: Vector,
    /// gap g_k (negative: penetration)
    pub gap: f64,
}

/// An obstacle's shape and pose at one time.
#[derive(Debug, Clone)]
pub struct PlacedObstacle<'a> {
    /// shape
    pub shape: &'a SharedShape,
    /// pose at that time
    pub pose: Pose,
}

/// The pair caches of the narrow phase (kept across steps).
#[derive(Default)]
pub struct Detector {
    pairs: BTreeMap<(usize, Partner), PairCache>,
    bvh_workspace: BvhWorkspace,
    /// each body's polytope (cuboids and convex polyhedra), built at the first detection
    polytopes: Vec<Option<Polytope>>,
    /// every pair through parry, balls included (the reference of the fast path's tests)
    parry_only: bool,
}

impl std::fmt::Debug for Detector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Detector")
            .field("pairs", &self.pairs.len())
            .finish()
    }
}

#[derive(Default, serde::Serialize, serde::Deserialize)]
struct PairCache {
    manifolds: Vec<ContactManifold<(), ()>>,
    workspace: Option<ContactManifoldsWorkspace>,
}

/// Each of the sorted, distinct `keys` with its entry of `old` (the default when it has none),
/// by one merge of the two sorted lists; the entries of the other keys are dropped: the
/// pairs' caches handed from one detection to the next (what `old.remove(key)` per key
/// gives, without the tree's searches and rebalancing).
fn take_caches<K: Ord + Copy, V: Default>(old: BTreeMap<K, V>, keys: &[K]) -> Vec<(K, V)> {
    let mut old = old.into_iter().peekable();
    keys.iter()
        .map(|&p| {
            while old.next_if(|(k, _)| *k < p).is_some() {}
            let cache = old.next_if(|(k, _)| *k == p).map(|(_, c)| c);
            (p, cache.unwrap_or_default())
        })
        .collect()
}

/// Bodies per task of the parallel poses and boxes of [`Detector::detect`] (a constant: the
/// numbers are each body's own whatever the number of threads).
const BOX_CHUNK: usize = 64;

/// The warm-start key of the one contact of a ball with a body or a half-space: parry's
/// (sub-shape 0, sub-shape 0, face 0, face 0, rank 0).
fn ball_key(a: usize, b: Partner) -> ContactKey {
    let face = PackedFeatureId::face(0).0;
    (a, b, 0, 0, face, face, 0)
}

/// The contact of ball A (centre `ca`, radius `ra`, shape pose `pose_a`) with ball B (body
/// `b` > `a`, centre `cb`, radius `rb`) when its gap g = |c_B − c_A| − r_A − r_B is below
/// `prediction` (parry's test): normal n = (c_A − c_B)/|c_A − c_B| (B → A; concentric balls:
/// −R_A e_y, parry's choice), point midway between c_A − r_A n and c_B + r_B n.
#[allow(clippy::too_many_arguments)]
pub(crate) fn ball_ball(
    a: usize,
    pose_a: &Pose,
    ra: f64,
    b: usize,
    cb: Vector,
    rb: f64,
    prediction: f64,
) -> Option<ContactPoint> {
    let ca = pose_a.translation;
    let d = cb - ca;
    let dist = d.length();
    let gap = dist - ra - rb;
    if gap.is_nan() || gap >= prediction {
        return None;
    }
    let n1 = if dist != 0.0 {
        d / dist
    } else {
        pose_a.rotation * Vector::Y
    };
    let normal = -n1;
    let (t1, t2) = tangent_frame(normal);
    let bp = Partner::Body(b);
    Some(ContactPoint {
        a,
        b: bp,
        key: ball_key(a, bp),
        point: 0.5 * ((ca + ra * n1) + (cb - rb * n1)),
        normal,
        t1,
        t2,
        gap,
    })
}

/// The contact of ball A (centre `ca`, radius `ra`) with half-space obstacle `o` (outward
/// unit normal `n` and boundary point `origin`, world) when its gap g = n·(c_A − origin) − r_A
/// is at most `prediction` (parry's test): normal n (B → A), point midway between the ball's
/// lowest point c_A − r_A n and the centre's projection on the plane.
pub(crate) fn ball_half_space(
    a: usize,
    ca: Vector,
    ra: f64,
    o: usize,
    n: Vector,
    origin: Vector,
    prediction: f64,
) -> Option<ContactPoint> {
    let s = n.dot(ca - origin);
    let gap = s - ra;
    let accepted = s <= ra + prediction && gap <= prediction && gap.is_finite();
    if !accepted {
        return None;
    }
    let (t1, t2) = tangent_frame(n);
    let bp = Partner::Obstacle(o, 0);
    Some(ContactPoint {
        a,
        b: bp,
        key: ball_key(a, bp),
        point: 0.5 * ((ca - ra * n) + (ca - s * n)),
        normal: n,
        t1,
        t2,
        gap,
    })
}

/// The contact frame's tangents (t₁, t₂) of the unit normal n: [`Vec3::tangent_basis`], the
/// one rule of every contact, sphere or not, on parry's vector type.
pub fn tangent_frame(n: Vector) -> (Vector, Vector) {
    let (t1, t2) = Vec3::new(n.x, n.y, n.z).tangent_basis();
    (Vector::new(t1.x, t1.y, t1.z), Vector::new(t2.x, t2.y, t2.z))
}

/// The pair caches of a [`Detector`] as serde sees them (a checkpoint's `/json/detector`):
/// each pair with parry's manifolds (points, normals, feature ids: parry starts the next
/// step's GJK from the stored normal and updates the stored points when the pose barely
/// moved) and parry's workspace of composite shapes.
#[derive(serde::Serialize)]
struct DetectorView<'a> {
    pairs: Vec<(&'a (usize, Partner), &'a PairCache)>,
}

#[derive(serde::Deserialize)]
struct DetectorOwned {
    pairs: Vec<((usize, Partner), PairCache)>,
}

impl Detector {
    /// The pair caches as a JSON document (floats round-trip exactly); `Err` when some value
    /// JSON cannot hold.
    pub(crate) fn to_json(&self) -> Result<String, String> {
        let view = DetectorView {
            pairs: self.pairs.iter().collect(),
        };
        serde_json::to_string(&view).map_err(|e| e.to_string())
    }

    /// The detector whose pair caches [`Detector::to_json`] wrote; every pair's body indices
    /// must be below `bodies` and its obstacle indices below `obstacles` (feature 0).
    pub(crate) fn from_json(json: &str, bodies: usize, obstacles: usize) -> Result<Self, String> {
        let owned: DetectorOwned = serde_json::from_str(json).map_err(|e| e.to_string())?;
        let mut pairs = BTreeMap::new();
        for ((a, b), cache) in owned.pairs {
            let ok = a < bodies
                && match b {
                    Partner::Body(j) => a < j && j < bodies,
                    // a rigid pair is the whole obstacle: feature 0
                    Partner::Obstacle(o, f) => o < obstacles && f == 0,
                };
            if !ok {
                return Err(format!("pair ({a}, {b:?}) out of range"));
            }
            if pairs.insert((a, b), cache).is_some() {
                return Err(format!("pair ({a}, {b:?}) twice"));
            }
        }
        Ok(Self {
            pairs,
            ..Self::default()
        })
    }

    /// Drops the pair caches (parry's manifolds and workspaces, kept from the last
    /// detection) of every pair with a body `i` where `moved[i]`: after a body is moved
    /// between steps, its next detection starts afresh rather than from the manifolds of
    /// where it was ([`crate::step::rigid::RigidWorld::set_positions`]).
    pub(crate) fn forget_moved(&mut self, moved: &[bool]) {
        let gone = |i: usize| moved.get(i).copied().unwrap_or(false);
        self.pairs
            .retain(|(a, b), _| !(gone(*a) || matches!(b, Partner::Body(j) if gone(*j))));
    }

    /// The pairs cached with body `i` (tests).
    #[cfg(feature = "unit-tests")]
    pub(crate) fn pairs_of(&self, i: usize) -> Vec<(usize, Partner)> {
        self.pairs
            .keys()
            .filter(|(a, b)| *a == i || *b == Partner::Body(i))
            .copied()
            .collect()
    }

    /// The detector that hands every pair to parry, balls included (no fast path): the
    /// reference the fast path is tested against.
    #[cfg(feature = "unit-tests")]
    pub(crate) fn parry_only() -> Self {
        Self {
            parry_only: true,
            ..Self::default()
        }
    }

    /// The manifold points of every pair whose shapes are closer than the sum of their
    /// margins (`margins[i]`: how far body i may travel in the step, 0 for a fixed body), at
    /// the bodies' current poses and the obstacles' `obstacles`, sorted by key. Pairs of two
    /// fixed bodies are skipped.
    pub fn detect(
        &mut self,
        bodies: &[BodyState],
        shapes: &[SharedShape],
        obstacles: &[PlacedObstacle<'_>],
        margins: &[f64],
    ) -> Result<Vec<ContactPoint>, RigidError> {
        // the poses and boxes of every body, in parallel (rayon; each its own numbers)
        let (poses, aabbs): (Vec<Pose>, Vec<Aabb>) = {
            use rayon::prelude::*;
            bodies
                .par_iter()
                .zip(shapes)
                .zip(margins)
                .with_min_len(BOX_CHUNK)
                .map(|((b, s), m)| {
                    let pose = b.shape_pose();
                    (pose, s.compute_aabb(&pose).loosened(*m))
                })
                .unzip()
        };
        // the balls (radius) and the half-space obstacles (world normal, boundary point) of
        // the fast path
        let fast = !self.parry_only;
        let balls: Vec<Option<f64>> = shapes
            .iter()
            .map(|s| s.as_ball().filter(|_| fast).map(|b| b.radius))
            .collect();
        let planes: Vec<Option<(Vector, Vector)>> = obstacles
            .iter()
            .map(|o| {
                let hs = o.shape.as_halfspace().filter(|_| fast)?;
                Some((o.pose.rotation * hs.normal, o.pose.translation))
            })
            .collect();
        let mut pairs: Vec<(usize, Partner)> = Vec::new();
        let mut fast_points: Vec<ContactPoint> = Vec::new();
        if !aabbs.is_empty() {
            let bvh = Bvh::from_leaves(BvhBuildStrategy::default(), &aabbs);
            bvh.traverse_bvtt_single_tree::<false>(&mut self.bvh_workspace, &mut |i, j| {
                let (i, j) = (i.min(j) as usize, i.max(j) as usize);
                if i != j && !(bodies[i].fixed && bodies[j].fixed) {
                    if let (Some(ri), Some(rj)) = (balls[i], balls[j]) {
                        let prediction = margins[i] + margins[j];
                        let cj = poses[j].translation;
                        fast_points.extend(ball_ball(i, &poses[i], ri, j, cj, rj, prediction));
                    } else {
                        pairs.push((i, Partner::Body(j)));
                    }
                }
            });
            for (o, ob) in obstacles.iter().enumerate() {
                let aabb = ob.shape.compute_aabb(&ob.pose);
                let bounded = aabb.mins.is_finite()
                    && aabb.maxs.is_finite()
                    && (aabb.maxs - aabb.mins).max_element() < 1e12;
                if bounded {
                    for i in bvh.intersect_aabb(&aabb) {
                        let i = i as usize;
                        if !bodies[i].fixed {
                            pairs.push((i, Partner::Obstacle(o, 0)));
                        }
                    }
                } else {
                    for (i, b) in bodies.iter().enumerate() {
                        if b.fixed {
                            continue;
                        }
                        if let (Some(r), Some((n, origin))) = (balls[i], planes[o]) {
                            let c = poses[i].translation;
                            fast_points.extend(ball_half_space(i, c, r, o, n, origin, margins[i]));
                        } else {
                            pairs.push((i, Partner::Obstacle(o, 0)));
                        }
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        // bodies inserted between steps (an inlet) are appended: only theirs are built
        if self.polytopes.len() > shapes.len() {
            self.polytopes.clear();
        }
        let have = self.polytopes.len();
        self.polytopes
            .extend(shapes[have..].iter().map(Polytope::of));
        let obstacle_polytopes: Vec<Option<Polytope>> =
            obstacles.iter().map(|o| Polytope::of(o.shape)).collect();
        let dispatcher = DefaultQueryDispatcher;
        // the narrow phase of every pair in parallel (rayon): each pair owns its cache, the
        // points are gathered in pair order and sorted by key, so the result does not depend
        // on the number of threads; the first error in pair order is returned
        let jobs = take_caches(std::mem::take(&mut self.pairs), &pairs);
        let polytopes = &self.polytopes;
        let narrow = |((a, b), mut cache): ((usize, Partner), PairCache)|
         -> Result<(Vec<ContactPoint>, Option<PairCache>), RigidError> {
            let mut points = Vec::new();
            let (shape_b, pose_b, margin_b): (&SharedShape, Pose, f64) = match b {
                Partner::Body(j) => (&shapes[j], poses[j], margins[j]),
                Partner::Obstacle(o, _) => (obstacles[o].shape, obstacles[o].pose, 0.0),
            };
            let pose_a = poses[a];
            let prediction = margins[a] + margin_b;
            // two convex polyhedra (not two cuboids): separating axes and face clipping
            let poly_b = match b {
                Partner::Body(j) => polytopes[j].as_ref(),
                Partner::Obstacle(o, _) => obstacle_polytopes[o].as_ref(),
            };
            let hull = shapes[a].as_convex_polyhedron().is_some()
                || shape_b.as_convex_polyhedron().is_some();
            if let (Some(pa), Some(pb), true) = (polytopes[a].as_ref(), poly_b, hull) {
                let mut seen: BTreeMap<(u32, u32, u32), u32> = BTreeMap::new();
                for c in polytope::manifold(pa, &pose_a, pb, &pose_b, prediction) {
                    let ids = (c.sub1, c.sub2, c.feature);
                    let rank = seen.entry(ids).or_insert(0);
                    let key = (a, b, ids.0, ids.1, ids.2, 0, *rank);
                    *rank += 1;
                    let (t1, t2) = tangent_frame(c.normal);
                    points.push(ContactPoint {
                        a,
                        b,
                        key,
                        point: c.point,
                        normal: c.normal,
                        t1,
                        t2,
                        gap: c.gap,
                    });
                }
                return Ok((points, None));
            }
            let pos12 = pose_a.inv_mul(&pose_b);
            dispatcher
                .contact_manifolds(
                    &pos12,
                    shapes[a].as_ref(),
                    shape_b.as_ref(),
                    prediction,
                    &mut cache.manifolds,
                    &mut cache.workspace,
                )
                .map_err(|_| RigidError::Unsupported {
                    a,
                    shape_a: format!("{:?}", shapes[a].shape_type()),
                    b,
                    shape_b: format!("{:?}", shape_b.shape_type()),
                })?;
            let mut seen: BTreeMap<(u32, u32, u32, u32), u32> = BTreeMap::new();
            for m in &cache.manifolds {
                let sub1 = m.subshape_pos1().copied().unwrap_or(Pose::IDENTITY);
                let sub2 = m.subshape_pos2().copied().unwrap_or(Pose::IDENTITY);
                let world1 = pose_a * sub1;
                let world2 = pose_b * sub2;
                let n1 = world1.rotation * m.local_n1;
                if !n1.is_finite() || n1.length_squared() == 0.0 {
                    continue;
                }
                let normal = -n1.normalize();
                let (t1, t2) = tangent_frame(normal);
                for c in &m.points {
                    if c.dist > prediction || !c.dist.is_finite() {
                        continue;
                    }
                    let p1 = world1 * c.local_p1;
                    let p2 = world2 * c.local_p2;
                    let ids = (m.subshape1, m.subshape2, c.fid1.0, c.fid2.0);
                    let rank = seen.entry(ids).or_insert(0);
                    let key = (a, b, ids.0, ids.1, ids.2, ids.3, *rank);
                    *rank += 1;
                    points.push(ContactPoint {
                        a,
                        b,
                        key,
                        point: 0.5 * (p1 + p2),
                        normal,
                        t1,
                        t2,
                        gap: c.dist,
                    });
                }
            }
            Ok((points, Some(cache)))
        };
        let results: Vec<_> = {
            use rayon::prelude::*;
            jobs.into_par_iter().map(narrow).collect()
        };
        let mut points = fast_points;
        // the caches kept, in pair order: the map is built in one pass from the sorted list
        let mut kept = Vec::with_capacity(results.len());
        let mut failed = None;
        for (result, &pair) in results.into_iter().zip(&pairs) {
            match result {
                Ok((found, cache)) => {
                    points.extend(found);
                    kept.extend(cache.map(|c| (pair, c)));
                }
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            }
        }
        self.pairs = kept.into_iter().collect();
        if let Some(e) = failed {
            return Err(e);
        }
        points.sort_by_key(|x| x.key);
        Ok(points)
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests;
