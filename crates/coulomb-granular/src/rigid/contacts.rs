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
//! distance (negative: penetration). The tangents are t₁ ⟂ n built from the world axis least
//! aligned with n, t₂ = n × t₁ ([`tangent_frame`]).
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

use super::body::BodyState;
use super::parry::bounding_volume::{Aabb, BoundingVolume};
use super::parry::math::{Pose, Vector};
use super::parry::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};
use super::parry::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use super::parry::shape::{PackedFeatureId, SharedShape};
use super::polytope::{self, Polytope};
use super::{RigidError, RigidPartner};
use std::collections::BTreeMap;

/// Key of a manifold point across steps: (A, B, sub-shape of A, sub-shape of B, feature
/// of A, feature of B, rank among points with the same ids).
pub type ContactKey = (usize, RigidPartner, u32, u32, u32, u32, u32);

/// One manifold point at t_k.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactPoint {
    /// body A
    pub a: usize,
    /// B
    pub b: RigidPartner,
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
    pairs: BTreeMap<(usize, RigidPartner), PairCache>,
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
fn ball_key(a: usize, b: RigidPartner) -> ContactKey {
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
    let bp = RigidPartner::Body(b);
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
    let bp = RigidPartner::Obstacle(o);
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

/// t₁ ⟂ n from the world axis least aligned with n, and t₂ = n × t₁.
pub fn tangent_frame(n: Vector) -> (Vector, Vector) {
    let a = n.abs();
    let e = if a.x <= a.y && a.x <= a.z {
        Vector::X
    } else if a.y <= a.z {
        Vector::Y
    } else {
        Vector::Z
    };
    let t1 = n.cross(e).normalize();
    let t2 = n.cross(t1);
    (t1, t2)
}

/// The pair caches of a [`Detector`] as serde sees them (a checkpoint's `/json/detector`):
/// each pair with parry's manifolds (points, normals, feature ids: parry starts the next
/// step's GJK from the stored normal and updates the stored points when the pose barely
/// moved) and parry's workspace of composite shapes.
#[derive(serde::Serialize)]
struct DetectorView<'a> {
    pairs: Vec<(&'a (usize, RigidPartner), &'a PairCache)>,
}

#[derive(serde::Deserialize)]
struct DetectorOwned {
    pairs: Vec<((usize, RigidPartner), PairCache)>,
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
    /// must be below `bodies` and its obstacle indices below `obstacles`.
    pub(crate) fn from_json(json: &str, bodies: usize, obstacles: usize) -> Result<Self, String> {
        let owned: DetectorOwned = serde_json::from_str(json).map_err(|e| e.to_string())?;
        let mut pairs = BTreeMap::new();
        for ((a, b), cache) in owned.pairs {
            let ok = a < bodies
                && match b {
                    RigidPartner::Body(j) => a < j && j < bodies,
                    RigidPartner::Obstacle(o) => o < obstacles,
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
    /// where it was ([`super::RigidWorld::set_positions`]).
    pub(crate) fn forget_moved(&mut self, moved: &[bool]) {
        let gone = |i: usize| moved.get(i).copied().unwrap_or(false);
        self.pairs
            .retain(|(a, b), _| !(gone(*a) || matches!(b, RigidPartner::Body(j) if gone(*j))));
    }

    /// The pairs cached with body `i` (tests).
    #[cfg(test)]
    pub(crate) fn pairs_of(&self, i: usize) -> Vec<(usize, RigidPartner)> {
        self.pairs
            .keys()
            .filter(|(a, b)| *a == i || *b == RigidPartner::Body(i))
            .copied()
            .collect()
    }

    /// The detector that hands every pair to parry, balls included (no fast path): the
    /// reference the fast path is tested against.
    #[cfg(test)]
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
        let mut pairs: Vec<(usize, RigidPartner)> = Vec::new();
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
                        pairs.push((i, RigidPartner::Body(j)));
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
                            pairs.push((i, RigidPartner::Obstacle(o)));
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
                            pairs.push((i, RigidPartner::Obstacle(o)));
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
        let narrow = |((a, b), mut cache): ((usize, RigidPartner), PairCache)|
         -> Result<(Vec<ContactPoint>, Option<PairCache>), RigidError> {
            let mut points = Vec::new();
            let (shape_b, pose_b, margin_b): (&SharedShape, Pose, f64) = match b {
                RigidPartner::Body(j) => (&shapes[j], poses[j], margins[j]),
                RigidPartner::Obstacle(o) => (obstacles[o].shape, obstacles[o].pose, 0.0),
            };
            let pose_a = poses[a];
            let prediction = margins[a] + margin_b;
            // two convex polyhedra (not two cuboids): separating axes and face clipping
            let poly_b = match b {
                RigidPartner::Body(j) => polytopes[j].as_ref(),
                RigidPartner::Obstacle(o) => obstacle_polytopes[o].as_ref(),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rigid::parry::math::Rotation;
    use rand::{Rng, SeedableRng};

    fn body(x: Vector, q: Rotation) -> BodyState {
        BodyState {
            mass: 1.0,
            inertia: [1.0; 3],
            local_com: Vector::ZERO,
            principal: Rotation::IDENTITY,
            x,
            q,
            v: Vector::ZERO,
            omega: Vector::ZERO,
            material: 0,
            fixed: false,
            reach: 1.0,
        }
    }

    fn unit(rng: &mut impl Rng) -> Vector {
        loop {
            let v = Vector::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            if v.length() > 0.1 && v.length() < 1.0 {
                return v.normalize();
            }
        }
    }

    fn rotation(rng: &mut impl Rng) -> Rotation {
        let v = unit(rng);
        Rotation::from_xyzw(v.x, v.y, v.z, rng.random_range(-1.0..1.0)).normalize()
    }

    /// The points of the fast path and of parry on the same scene: same keys in the same
    /// order, gap, normal and point within 1e-12, and the fast path's tangents those of
    /// [`tangent_frame`] (parry's normal of an axis-aligned plane carries round-off of 1e-16
    /// off the axis, on which `tangent_frame` may choose another axis: the same frame turned
    /// about n). Against a half-space parry's normal is (c − proj)/|c − proj| in the plane's
    /// frame, whose round-off grows as ε|c|/s when the centre nears the plane (s its
    /// distance): the tolerance there is 1e-12 max(1, r/s).
    fn same_points(
        bodies: &[BodyState],
        shapes: &[SharedShape],
        obstacles: &[PlacedObstacle<'_>],
        margins: &[f64],
    ) -> usize {
        let fast = Detector::default()
            .detect(bodies, shapes, obstacles, margins)
            .unwrap();
        let parry = Detector::parry_only()
            .detect(bodies, shapes, obstacles, margins)
            .unwrap();
        assert_eq!(fast.len(), parry.len());
        for (f, p) in fast.iter().zip(&parry) {
            assert_eq!(f.key, p.key);
            assert_eq!((f.a, f.b), (p.a, p.b));
            let tol = match (f.b, shapes[f.a].as_ball()) {
                (RigidPartner::Obstacle(_), Some(ball)) => {
                    1e-12 * (ball.radius / (f.gap + ball.radius).abs()).max(1.0)
                }
                _ => 1e-12,
            };
            assert!((f.gap - p.gap).abs() <= 1e-12, "{f:?} {p:?}");
            assert!((f.normal - p.normal).length() <= tol, "{f:?} {p:?}");
            assert!((f.point - p.point).length() <= 1e-12, "{f:?} {p:?}");
            assert_eq!((f.t1, f.t2), tangent_frame(f.normal));
            assert!(f.t1.dot(f.normal).abs() <= 1e-15 && (f.t1.length() - 1.0).abs() <= 1e-15);
            assert!((f.t1.cross(f.t2) - f.normal).length() <= 1e-15);
        }
        fast.len()
    }

    #[test]
    fn the_caches_handed_on_are_those_remove_gives() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(52);
        for case in 0..50 {
            let n = 1 + case * 3;
            let old: BTreeMap<(usize, u8), u32> = (0..n)
                .map(|_| {
                    (
                        (rng.random_range(0..40), rng.random_range(0..3)),
                        rng.random_range(1..1000),
                    )
                })
                .collect();
            let mut keys: Vec<(usize, u8)> = (0..n)
                .map(|_| (rng.random_range(0..40), rng.random_range(0..3)))
                .collect();
            keys.sort_unstable();
            keys.dedup();
            let mut reference = old.clone();
            let expected: Vec<((usize, u8), u32)> = keys
                .iter()
                .map(|k| (*k, reference.remove(k).unwrap_or_default()))
                .collect();
            let got = take_caches(old.clone(), &keys);
            assert_eq!(got, expected, "case {case}");
            // not vacuous: some keys find their entry, some do not
            if case > 10 {
                assert!(got.iter().any(|(k, v)| *v != 0 && old.get(k) == Some(v)));
            }
        }
    }

    #[test]
    fn ball_pairs_match_parry_on_random_pairs() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(52);
        let (mut ball_ball_points, mut plane_points) = (0, 0);
        for _ in 0..2000 {
            // two balls with a gap in [−r_min/2, 2 prediction], one random half-space
            let (ra, rb): (f64, f64) = (rng.random_range(0.01..0.2), rng.random_range(0.01..0.2));
            let margin: f64 = rng.random_range(0.0..0.02);
            let gap = rng.random_range(-0.5 * ra.min(rb)..4.0 * margin + 1e-3);
            let ca = Vector::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let cb = ca + (ra + rb + gap) * unit(&mut rng);
            let bodies = [body(ca, rotation(&mut rng)), body(cb, rotation(&mut rng))];
            let shapes = [SharedShape::ball(ra), SharedShape::ball(rb)];
            let n = unit(&mut rng);
            let plane = SharedShape::halfspace(n);
            // the plane's boundary at a random signed distance from ball A's surface
            let s = ra + rng.random_range(-0.5 * ra..4.0 * margin + 1e-3);
            let origin_offset = unit(&mut rng).cross(n);
            let obstacle_pose = Pose::from_parts(ca - s * n + origin_offset, Rotation::IDENTITY);
            let obstacles = [PlacedObstacle {
                shape: &plane,
                pose: obstacle_pose,
            }];
            let found = Detector::default()
                .detect(&bodies, &shapes, &obstacles, &[margin, margin])
                .unwrap();
            ball_ball_points += found
                .iter()
                .filter(|c| matches!(c.b, RigidPartner::Body(_)))
                .count();
            plane_points += found
                .iter()
                .filter(|c| c.a == 0 && matches!(c.b, RigidPartner::Obstacle(_)))
                .count();
            same_points(&bodies, &shapes, &obstacles, &[margin, margin]);
        }
        // both kinds of pairs were met often, in and out of the prediction
        assert!(
            ball_ball_points > 500 && ball_ball_points < 1900,
            "{ball_ball_points}"
        );
        assert!(plane_points > 500 && plane_points < 1900, "{plane_points}");
    }

    #[test]
    fn a_box_of_balls_and_cuboids_gives_parry_points_in_parry_order() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut bodies = Vec::new();
        let mut shapes = Vec::new();
        for i in 0..6 {
            for j in 0..6 {
                for k in 0..4 {
                    let x = Vector::new(0.1 * i as f64, 0.1 * j as f64, 0.05 + 0.1 * k as f64)
                        + 0.01 * unit(&mut rng);
                    bodies.push(body(x, rotation(&mut rng)));
                    shapes.push(if (i + j + k) % 7 == 0 {
                        SharedShape::cuboid(0.03, 0.04, 0.035)
                    } else {
                        SharedShape::ball(rng.random_range(0.04..0.055))
                    });
                }
            }
        }
        bodies[5].fixed = true;
        let planes: Vec<SharedShape> = [Vector::Z, Vector::X, -Vector::X]
            .iter()
            .map(|n| SharedShape::halfspace(*n))
            .collect();
        let cuboid = SharedShape::cuboid(0.1, 0.1, 0.1);
        let mut obstacles: Vec<PlacedObstacle<'_>> = planes
            .iter()
            .zip([0.0, 0.0, 0.5])
            .map(|(shape, x)| PlacedObstacle {
                shape,
                pose: Pose::from_parts(Vector::new(x, 0.0, 0.0), Rotation::IDENTITY),
            })
            .collect();
        obstacles.push(PlacedObstacle {
            shape: &cuboid,
            pose: Pose::from_parts(Vector::new(0.25, 0.25, 0.6), rotation(&mut rng)),
        });
        let margins: Vec<f64> = (0..bodies.len())
            .map(|_| rng.random_range(0.0..0.01))
            .collect();
        let n = same_points(&bodies, &shapes, &obstacles, &margins);
        assert!(n > 100, "{n}");
    }

    use crate::rigid::validation::{floor, one_material};
    use crate::rigid::{MassProperties, RigidBodyDesc, RigidSettings, RigidWorld};

    fn ball_desc(r: f64, x: [f64; 3], v: [f64; 3], w: [f64; 3]) -> RigidBodyDesc {
        let shape = SharedShape::ball(r);
        let mass = MassProperties::from_shape(&shape, 1000.0).unwrap();
        RigidBodyDesc {
            shape,
            mass,
            position: x,
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: v,
            angular_velocity: w,
            material: 0,
            fixed: false,
        }
    }

    /// The run of `steps` steps with the fast path and with parry only: the same contacts,
    /// statuses and warm starts each step, and positions, orientations, velocities and
    /// angular velocities within `tol` (absolute; both runs solve each step to the settings'
    /// tolerance from tangent frames that may differ by a turn about n, see
    /// [`same_points`]); returns the fast run's last state and the largest difference.
    fn same_run(
        bodies: Vec<RigidBodyDesc>,
        settings: RigidSettings,
        steps: usize,
        tol: f64,
    ) -> (RigidWorld, f64) {
        let make = || {
            RigidWorld::new(
                bodies.clone(),
                vec![floor()],
                one_material(0.5),
                settings.clone(),
            )
            .unwrap()
        };
        let (mut fast, mut parry) = (make(), make().parry_only_detection());
        let (mut contacts, mut worst) = (0, 0.0f64);
        for _ in 0..steps {
            let (rf, rp) = (fast.step().unwrap(), parry.step().unwrap());
            assert_eq!(rf.contacts, rp.contacts);
            assert_eq!(rf.status, rp.status);
            assert_eq!(rf.warm_started, rp.warm_started);
            contacts += rf.contacts;
            let state = |w: &RigidWorld| -> Vec<f64> {
                let mut s: Vec<f64> = w.positions().into_iter().flatten().collect();
                s.extend(w.velocities().into_iter().flatten());
                s.extend(w.angular_velocities().into_iter().flatten());
                s.extend(w.orientations().into_iter().flatten());
                s
            };
            let d = state(&fast)
                .iter()
                .zip(state(&parry))
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            worst = worst.max(d);
        }
        assert!(contacts > 0);
        assert!(worst <= tol, "largest difference {worst:e}");
        (fast, worst)
    }

    #[test]
    fn a_ball_sliding_then_rolling_on_the_floor_moves_as_with_parry() {
        // thrown along x without spin: it slides, friction spins it up until it rolls
        let r = 0.1;
        let b = ball_desc(r, [0.0, 0.0, r], [1.0, 0.0, 0.0], [0.0; 3]);
        // measured: 4.8e-12
        let (w, _) = same_run(vec![b], RigidSettings::default(), 400, 1e-9);
        // rolling without slipping at the end: v_x = ω_y r = 5/7 of the throw
        let (v, om) = (w.velocities()[0], w.angular_velocities()[0]);
        assert!((v[0] - 5.0 / 7.0).abs() < 1e-3, "{v:?}");
        assert!((v[0] - om[1] * r).abs() < 1e-6, "{v:?} {om:?}");
    }

    #[test]
    fn two_balls_colliding_above_the_floor_move_as_with_parry() {
        // head-on and off-centre, in free fall above the floor, then resting on it
        let a = ball_desc(0.05, [0.0, 0.0, 0.3], [2.0, 0.0, 0.0], [0.0, 0.0, 3.0]);
        let b = ball_desc(0.07, [0.3, 0.03, 0.3], [-1.0, 0.0, 0.0], [0.0; 3]);
        let settings = RigidSettings {
            h: 2e-3,
            ..RigidSettings::default()
        };
        // measured: 3.6e-9 (each step solved to 1e-8 from frames turned about n)
        let (w, _) = same_run(vec![a, b], settings, 300, 1e-7);
        // perfectly inelastic (e = 0): A (2 m/s) meets the 2.7 times heavier B (−1 m/s)
        // and both leave at (2 m_A − m_B)/(m_A + m_B) ≈ −0.2 m/s, then friction acts
        let v = w.velocities();
        assert!(v[0][0] < 0.5 && v[1][0] < 0.5, "{v:?}");
    }

    #[test]
    fn a_ball_pile_with_a_cuboid_gives_the_same_bits_on_one_and_two_threads() {
        // 180 balls stacked in touching layers (jittered) on the floor around one cuboid:
        // fast-path pairs beside parry's (cuboid–ball, cuboid–floor), swept in parallel
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut bodies =
            vec![
                crate::rigid::validation::cuboid([0.1, 0.1, 0.05], 1000.0, [0.3, 0.3, 0.05])
                    .unwrap(),
            ];
        for k in 0..5 {
            for i in 0..6 {
                for j in 0..6 {
                    let (x, y) = (0.11 * i as f64, 0.11 * j as f64);
                    if k == 0 && (0.15..0.45).contains(&x) && (0.15..0.45).contains(&y) {
                        continue;
                    }
                    let dx = rng.random_range(-0.005..0.005);
                    let dy = rng.random_range(-0.005..0.005);
                    // layer 1 just above the cuboid's top (z = 0.1), each 1 mm above the last
                    let z = if k == 0 {
                        0.05
                    } else {
                        0.151 + 0.101 * (k - 1) as f64
                    };
                    bodies.push(ball_desc(0.05, [x + dx, y + dy, z], [0.0; 3], [0.0; 3]));
                }
            }
        }
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let settings = RigidSettings {
                    tolerance: 1e-6,
                    ..RigidSettings::default()
                };
                let mut w =
                    RigidWorld::new(bodies.clone(), vec![floor()], one_material(0.5), settings)
                        .unwrap();
                let mut most = 0;
                for _ in 0..80 {
                    most = most.max(w.step().unwrap().contacts);
                }
                let mut bits: Vec<u64> = Vec::new();
                for v in [w.positions(), w.velocities(), w.angular_velocities()] {
                    bits.extend(v.iter().flatten().map(|x| x.to_bits()));
                }
                bits.extend(w.orientations().iter().flatten().map(|x| x.to_bits()));
                (bits, most)
            })
        };
        let (one, most) = run(1);
        assert!(most > 100, "{most} contacts");
        let (two, _) = run(2);
        assert!(one == two, "1 and 2 threads differ");
    }
}
