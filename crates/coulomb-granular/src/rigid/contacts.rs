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

use super::body::BodyState;
use super::parry::bounding_volume::{Aabb, BoundingVolume};
use super::parry::math::{Pose, Vector};
use super::parry::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};
use super::parry::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use super::parry::shape::SharedShape;
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
        let poses: Vec<Pose> = bodies.iter().map(|b| b.shape_pose()).collect();
        let aabbs: Vec<Aabb> = shapes
            .iter()
            .zip(&poses)
            .zip(margins)
            .map(|((s, p), m)| s.compute_aabb(p).loosened(*m))
            .collect();
        let mut pairs: Vec<(usize, RigidPartner)> = Vec::new();
        if !aabbs.is_empty() {
            let bvh = Bvh::from_leaves(BvhBuildStrategy::default(), &aabbs);
            bvh.traverse_bvtt_single_tree::<false>(&mut self.bvh_workspace, &mut |i, j| {
                let (i, j) = (i.min(j) as usize, i.max(j) as usize);
                if i != j && !(bodies[i].fixed && bodies[j].fixed) {
                    pairs.push((i, RigidPartner::Body(j)));
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
                        if !b.fixed {
                            pairs.push((i, RigidPartner::Obstacle(o)));
                        }
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        // drop the caches of pairs that left the broad phase
        let mut old = std::mem::take(&mut self.pairs);
        if self.polytopes.len() != shapes.len() {
            self.polytopes = shapes.iter().map(Polytope::of).collect();
        }
        let obstacle_polytopes: Vec<Option<Polytope>> =
            obstacles.iter().map(|o| Polytope::of(o.shape)).collect();
        let dispatcher = DefaultQueryDispatcher;
        // the narrow phase of every pair in parallel (rayon): each pair owns its cache, the
        // points are gathered in pair order and sorted by key, so the result does not depend
        // on the number of threads; the first error in pair order is returned
        let jobs: Vec<((usize, RigidPartner), PairCache)> = pairs
            .iter()
            .map(|&p| (p, old.remove(&p).unwrap_or_default()))
            .collect();
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
        let mut points = Vec::new();
        for (result, &pair) in results.into_iter().zip(&pairs) {
            let (found, cache) = result?;
            points.extend(found);
            if let Some(cache) = cache {
                self.pairs.insert(pair, cache);
            }
        }
        points.sort_by_key(|x| x.key);
        Ok(points)
    }
}
