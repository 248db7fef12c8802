//! Triangle-mesh obstacles: any closed or open surface given by vertices and triangles, with a
//! bounding-volume hierarchy of the triangles' boxes (a sphere's query costs O(log T + k), k
//! the triangles near it), the closest point of a sphere centre on a triangle (face, edge or
//! vertex region), the removal of duplicate contacts at shared edges and vertices, and an
//! inside test for closed meshes (ray parity, majority of three rays).
//!
//! # Contacts with a mesh
//! A sphere (centre x, radius R) gets one candidate per triangle T whose closest point p_T is
//! within R + reach of x (gap g_T = |x − p_T| − R, normal (x − p_T)/|x − p_T|, or the face's
//! normal in its interior: the surface is two-sided unless the obstacle says which side the
//! spheres live on). Candidates are ordered by gap, ties (|g_T' − g_T| ≤ ε = 1e-12 (1 + R))
//! by triangle index. A candidate T is *dropped* when a better-ordered candidate T'
//! - contains the edge or vertex on which T's closest point lies: the distance to T' is then
//!   at most the distance to that feature, so T's constraint is implied by T''s (at a shared
//!   edge or vertex it is the same contact); or
//! - has nearly the same normal direction (n_T · n_T' ≥ cos 2°, [`SAME_DIRECTION`]):
//!   coplanar triangles under the sphere (a point on the diagonal of a flat quad), a parallel
//!   face behind the closer one, and the facets of a tessellated curved surface at a concave
//!   edge (a sphere inside a drum of 500 segments touches two faces 0.72° apart: two nearly
//!   parallel constraints, on which the Gauss–Seidel needed 3× the sweeps of the analytic
//!   drum; the closer face stands for the surface there, docs/granular.md "A mesh obstacle
//!   against the analytic one").
//!
//! The rule depends on the geometry and the triangle indices only (not on rounding: a sphere
//! resting on the shared edge of two coplanar triangles keeps the lower triangle until it
//! moves ~√(2 R ε) off the edge), so the surviving contact is the same from step to step: its
//! key (obstacle, triangle index) keeps its warm start.

use crate::math::Vec3;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::Arc;

/// Why a triangle mesh is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// no vertex or no triangle
    #[error("the mesh has no triangles (or no vertices)")]
    Empty,
    /// a vertex coordinate is NaN or infinite
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex {
        /// vertex index
        vertex: usize,
    },
    /// a triangle names a vertex that does not exist
    #[error("triangle {triangle} names vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// triangle index
        triangle: usize,
        /// the offending vertex index
        index: u64,
        /// number of vertices
        vertices: usize,
    },
    /// a triangle has (nearly) zero area or repeats a vertex
    #[error(
        "triangle {triangle} is degenerate (area {area:e}, below 1e-12 of the squared mesh size)"
    )]
    Degenerate {
        /// triangle index
        triangle: usize,
        /// its area
        area: f64,
    },
    /// an edge is not shared by exactly two triangles (the mesh is not closed): no inside
    #[error("the mesh is not closed: edge ({0}, {1}) belongs to {2} triangle(s), not 2")]
    NotClosed(u32, u32, usize),
    /// two triangles sharing an edge run it in the same direction: inconsistent orientation
    #[error("inconsistent orientation: the triangles sharing edge ({0}, {1}) run it in the same direction")]
    InconsistentOrientation(u32, u32),
    /// too many triangles or vertices for 32-bit indices
    #[error("the mesh has {0} triangles or vertices, more than 2^32 - 1")]
    TooLarge(usize),
}

/// The plain data of a mesh (its serialized form): vertices and triangles (three vertex
/// indices each, counter-clockwise seen from the outside for a closed mesh).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshData {
    /// vertex positions
    pub vertices: Vec<Vec3>,
    /// triangles: indices into `vertices`
    pub triangles: Vec<[u64; 3]>,
}

/// Where on a triangle its closest point to a query point lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Region {
    /// the interior of the face
    Face,
    /// the edge between local vertices (k, k + 1 mod 3)
    Edge(u8),
    /// local vertex k
    Vertex(u8),
}

/// A validated triangle mesh with its spatial index (shared: clones are cheap).
#[derive(Debug, Clone)]
pub struct TriangleMesh {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    bvh: Bvh,
    /// Some(±1) when closed and consistently oriented: the sign of the signed volume
    /// (+1: triangles counter-clockwise seen from outside)
    orientation: Option<f64>,
    /// why the mesh is not closed / not orientable (None: closed and oriented)
    closure: Option<MeshError>,
    /// radius of the bounding sphere about the origin of the mesh frame
    max_norm: f64,
    /// each triangle's unit normal, outward for a closed mesh ([`TriangleMesh::face_normal`]),
    /// computed once: the queries of every step read it
    normals: Vec<Vec3>,
    /// the last answer of [`TriangleMesh::max_distance_from_axis`] (key: the bits of c and
    /// the axis)
    axis_distance: std::sync::Mutex<Option<([u64; 6], f64)>>,
}

impl PartialEq for TriangleMesh {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.inner, &o.inner)
            || (self.inner.vertices == o.inner.vertices
                && self.inner.triangles == o.inner.triangles)
    }
}

impl Serialize for TriangleMesh {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Ref<'a> {
            vertices: &'a [Vec3],
            triangles: &'a [[u32; 3]],
        }
        Ref {
            vertices: &self.inner.vertices,
            triangles: &self.inner.triangles,
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for TriangleMesh {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let data = MeshData::deserialize(d)?;
        TriangleMesh::new(data.vertices, data.triangles).map_err(serde::de::Error::custom)
    }
}

impl TriangleMesh {
    /// Validates the vertices and triangles (finite vertices, indices in range, no degenerate
    /// triangle) and builds the spatial index. Whether the mesh is closed and consistently
    /// oriented is recorded ([`TriangleMesh::check_closed`]), not required.
    pub fn new(vertices: Vec<Vec3>, triangles: Vec<[u64; 3]>) -> Result<Self, MeshError> {
        if vertices.is_empty() || triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if vertices.len() > u32::MAX as usize || triangles.len() > u32::MAX as usize {
            return Err(MeshError::TooLarge(vertices.len().max(triangles.len())));
        }
        if let Some(v) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(MeshError::NonFiniteVertex { vertex: v });
        }
        let mut tris = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            for &i in tri {
                if i >= vertices.len() as u64 {
                    return Err(MeshError::IndexOutOfRange {
                        triangle: t,
                        index: i,
                        vertices: vertices.len(),
                    });
                }
            }
            tris.push([tri[0] as u32, tri[1] as u32, tri[2] as u32]);
        }
        let (lo, hi) = vertices
            .iter()
            .fold((vertices[0], vertices[0]), |(l, h), v| {
                (l.min(*v), h.max(*v))
            });
        let size2 = (hi - lo).norm_sq();
        for (t, tri) in tris.iter().enumerate() {
            let [a, b, c] = tri.map(|i| vertices[i as usize]);
            let area = 0.5 * (b - a).cross(c - a).norm();
            if area.is_nan()
                || area <= 1e-12 * size2
                || tri[0] == tri[1]
                || tri[1] == tri[2]
                || tri[0] == tri[2]
            {
                return Err(MeshError::Degenerate { triangle: t, area });
            }
        }
        let closure = closure_error(&tris);
        let orientation = if closure.is_none() {
            let vol: f64 = tris
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| vertices[i as usize]);
                    a.dot(b.cross(c))
                })
                .sum();
            Some(if vol >= 0.0 { 1.0 } else { -1.0 })
        } else {
            None
        };
        let max_norm = vertices.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let bvh = Bvh::build(&vertices, &tris);
        let normals = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                (b - a).cross(c - a).normalized_or(Vec3::Z) * orientation.unwrap_or(1.0)
            })
            .collect();
        Ok(Self {
            inner: Arc::new(Inner {
                vertices,
                triangles: tris,
                bvh,
                orientation,
                closure,
                max_norm,
                normals,
                axis_distance: std::sync::Mutex::new(None),
            }),
        })
    }

    /// The vertices.
    pub fn vertices(&self) -> &[Vec3] {
        &self.inner.vertices
    }
    /// The triangles (vertex indices).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.inner.triangles
    }
    /// Largest distance of a vertex from the origin of the mesh frame.
    pub fn max_norm(&self) -> f64 {
        self.inner.max_norm
    }
    /// The largest distance of a vertex from the line through c along the unit vector
    /// `axis` (the largest distance of any point of the surface: the distance to a line is
    /// convex). The last answer is kept: a rotating obstacle asks it every step.
    pub fn max_distance_from_axis(&self, c: Vec3, axis: Vec3) -> f64 {
        let key = [c.x, c.y, c.z, axis.x, axis.y, axis.z].map(f64::to_bits);
        if let Ok(last) = self.inner.axis_distance.lock() {
            if let Some((k, d)) = *last {
                if k == key {
                    return d;
                }
            }
        }
        let d = self
            .inner
            .vertices
            .iter()
            .map(|v| {
                let r = *v - c;
                (r - axis * r.dot(axis)).norm()
            })
            .fold(0.0, f64::max);
        if let Ok(mut last) = self.inner.axis_distance.lock() {
            *last = Some((key, d));
        }
        d
    }
    /// Bounding box (lo, hi) of the vertices.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let v = &self.inner.vertices;
        v.iter()
            .fold((v[0], v[0]), |(l, h), x| (l.min(*x), h.max(*x)))
    }
    /// Ok when every edge is shared by exactly two triangles that run it in opposite
    /// directions (closed, consistently oriented): the condition of the inside test.
    pub fn check_closed(&self) -> Result<(), MeshError> {
        match &self.inner.closure {
            None => Ok(()),
            Some(e) => Err(e.clone()),
        }
    }
    /// The outward unit normal of triangle `t` (for a closed mesh; the winding normal of an
    /// open one).
    pub fn face_normal(&self, t: usize) -> Vec3 {
        self.inner.normals.get(t).copied().unwrap_or(Vec3::Z)
    }
    fn corners(&self, t: usize) -> [Vec3; 3] {
        self.inner.triangles[t].map(|i| self.inner.vertices[i as usize])
    }

    /// Whether the point x is inside the closed mesh: parity of the crossings of three rays
    /// (fixed, non-axis directions) with the triangles, majority vote (a ray through an edge
    /// or vertex miscounts at most one of the three). `None` when the mesh is not closed.
    pub fn contains(&self, x: Vec3) -> Option<bool> {
        self.inner.orientation?;
        let dirs = [
            Vec3::new(0.5773, 0.5774, 0.5773503).normalized_or(Vec3::Z),
            Vec3::new(-0.2672, 0.8018, -0.5345).normalized_or(Vec3::Z),
            Vec3::new(0.8165, -0.4082, 0.4083).normalized_or(Vec3::Z),
        ];
        let votes = dirs
            .iter()
            .filter(|d| self.ray_crossings(x, **d) % 2 == 1)
            .count();
        Some(votes >= 2)
    }

    /// Number of triangles the ray x + s d, s > 0, crosses (Möller–Trumbore), found with the
    /// hierarchy.
    fn ray_crossings(&self, x: Vec3, d: Vec3) -> usize {
        let inv = Vec3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
        let mut count = 0;
        self.inner.bvh.visit(
            |lo, hi| ray_hits_box(x, inv, lo, hi),
            |t| {
                let [a, b, c] = self.corners(t as usize);
                if ray_crosses_triangle(x, d, a, b, c) {
                    count += 1;
                }
            },
        );
        count
    }

    /// The contact candidates of a sphere (centre x, radius R, in the mesh frame) within
    /// `reach` of it (gap |x − p| − R ≤ reach), after the duplicate rule of the module docs,
    /// in increasing triangle order: (triangle, closest point p, region).
    pub fn near(&self, x: Vec3, radius: f64, reach: f64, out: &mut Vec<(u32, Vec3, Region)>) {
        out.clear();
        self.near_each(x, radius, reach, |t, p, region| out.push((t, p, region)));
    }

    /// [`TriangleMesh::near`], each candidate handed to `found` in increasing triangle order.
    /// The per-query lists live in a scratch buffer of the calling thread (every bead queries
    /// the mesh once or twice a step: allocating them per query cost about a quarter of the
    /// query, docs/granular.md "A mesh obstacle against the analytic one").
    pub fn near_each(
        &self,
        x: Vec3,
        radius: f64,
        reach: f64,
        mut found: impl FnMut(u32, Vec3, Region),
    ) {
        thread_local! {
            static SCRATCH: std::cell::RefCell<NearScratch> =
                std::cell::RefCell::new(NearScratch::default());
        }
        SCRATCH.with(|cell| {
            let mut shared = cell.try_borrow_mut().ok();
            // a query from inside `found` (not done by this crate) finds the thread's buffers
            // borrowed: it gets its own
            let mut own = None;
            let scratch = match shared.as_deref_mut() {
                Some(s) => s,
                None => own.insert(NearScratch::default()),
            };
            self.near_into(x, radius, reach, scratch);
            for &(t, p, region) in &scratch.out {
                found(t, p, region);
            }
        });
    }

    /// The query of [`TriangleMesh::near`] into `scratch.out` (its other lists are scratch).
    fn near_into(&self, x: Vec3, radius: f64, reach: f64, scratch: &mut NearScratch) {
        let NearScratch { cand, normals, out } = scratch;
        cand.clear();
        normals.clear();
        out.clear();
        let r = radius + reach.max(0.0);
        let (qlo, qhi) = (x - Vec3::new(r, r, r), x + Vec3::new(r, r, r));
        self.inner.bvh.visit(
            |lo, hi| boxes_overlap(lo, hi, qlo, qhi),
            |t| {
                let [a, b, c] = self.corners(t as usize);
                let (p, region) = closest_on_triangle(x, a, b, c);
                let gap = (x - p).norm() - radius;
                if gap <= reach {
                    cand.push((t, p, region, gap));
                }
            },
        );
        cand.sort_unstable_by_key(|c| c.0);
        // the direction of each candidate's contact normal (face: the face's normal)
        normals.extend(cand.iter().map(|&(t, p, region, _)| {
            let n = self.face_normal(t as usize);
            match region {
                Region::Face if (x - p).dot(n) < 0.0 => -n,
                Region::Face => n,
                _ => (x - p).normalized_or(n),
            }
        }));
        let eps = 1e-12 * (1.0 + radius);
        for (k, &(t, p, region, gap)) in cand.iter().enumerate() {
            let tri = self.inner.triangles[t as usize];
            let shared: &[u32] = match region {
                Region::Face => &[],
                Region::Edge(e) => &[tri[e as usize], tri[(e as usize + 1) % 3]],
                Region::Vertex(v) => &[tri[v as usize]],
            };
            let dominated = cand.iter().enumerate().any(|(k2, &(t2, _, _, g2))| {
                let better = g2 < gap - eps || ((g2 - gap).abs() <= eps && t2 < t);
                let on_its_feature = !shared.is_empty()
                    && shared
                        .iter()
                        .all(|v| self.inner.triangles[t2 as usize].contains(v));
                let same_direction = normals[k].dot(normals[k2]) >= SAME_DIRECTION;
                k2 != k && better && (on_its_feature || same_direction)
            });
            if !dominated {
                out.push((t, p, region));
            }
        }
    }

    /// Every triangle within `reach` of the sphere (x, R) as the hierarchy finds it, before the
    /// duplicate rule, in increasing order (tests).
    #[cfg(feature = "unit-tests")]
    fn bvh_candidates(&self, x: Vec3, radius: f64, reach: f64, out: &mut Vec<u32>) {
        let mut scratch = NearScratch::default();
        self.near_into(x, radius, reach, &mut scratch);
        out.clear();
        out.extend(scratch.cand.iter().map(|c| c.0));
    }

    /// The closest point of triangle `t` to x (for a contact's own feature).
    pub fn closest_on(&self, t: usize, x: Vec3) -> Option<(Vec3, Region)> {
        (t < self.inner.triangles.len()).then(|| {
            let [a, b, c] = self.corners(t);
            closest_on_triangle(x, a, b, c)
        })
    }

    /// The sign (+1/−1) that turns the winding normals outward, for a closed oriented mesh.
    pub fn orientation(&self) -> Option<f64> {
        self.inner.orientation
    }
}

/// cos 2°: two candidates whose contact normals are closer than 2° are one contact (the
/// module docs' duplicate rule); facets of a tessellated surface that meet at less than 2°
/// (180 or more segments around a cylinder) are treated as one smooth surface.
pub const SAME_DIRECTION: f64 = 0.999_390_827_019_095_8;

/// The lists of one [`TriangleMesh::near`] query, kept per thread between queries.
#[derive(Default)]
struct NearScratch {
    /// (triangle, closest point, region, gap) within reach
    cand: Vec<(u32, Vec3, Region, f64)>,
    /// the contact normal direction of each candidate
    normals: Vec<Vec3>,
    /// the candidates that survive the duplicate rule
    out: Vec<(u32, Vec3, Region)>,
}

/// None when every undirected edge is used by exactly two triangles in opposite directions.
fn closure_error(tris: &[[u32; 3]]) -> Option<MeshError> {
    let mut edges: HashMap<(u32, u32), (usize, i32)> = HashMap::with_capacity(3 * tris.len());
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            let e = edges.entry(key).or_insert((0, 0));
            e.0 += 1;
            e.1 += if a < b { 1 } else { -1 };
        }
    }
    let mut keys: Vec<_> = edges.into_iter().collect();
    keys.sort_unstable_by_key(|x| x.0);
    for ((a, b), (n, _)) in &keys {
        if *n != 2 {
            return Some(MeshError::NotClosed(*a, *b, *n));
        }
    }
    for ((a, b), (_, dir)) in &keys {
        if *dir != 0 {
            return Some(MeshError::InconsistentOrientation(*a, *b));
        }
    }
    None
}

/// The closest point of triangle (a, b, c) to x and its region (Ericson, Real-Time Collision
/// Detection, §5.1.5: Voronoi regions of the vertices, edges and face).
pub fn closest_on_triangle(x: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (Vec3, Region) {
    let ab = b - a;
    let ac = c - a;
    let ap = x - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Region::Vertex(0));
    }
    let bp = x - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Region::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, Region::Edge(0));
    }
    let cp = x - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Region::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, Region::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, Region::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, Region::Face)
}

/// Whether the ray x + s d (s > 0) crosses triangle (a, b, c) (Möller–Trumbore).
fn ray_crosses_triangle(x: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> bool {
    let e1 = b - a;
    let e2 = c - a;
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return false;
    }
    let inv = 1.0 / det;
    let s = x - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    e2.dot(q) * inv > 0.0
}

fn boxes_overlap(lo: Vec3, hi: Vec3, qlo: Vec3, qhi: Vec3) -> bool {
    lo.x <= qhi.x
        && lo.y <= qhi.y
        && lo.z <= qhi.z
        && qlo.x <= hi.x
        && qlo.y <= hi.y
        && qlo.z <= hi.z
}

/// Slab test of the ray x + s inv⁻¹ (s ≥ 0) against the box [lo, hi].
fn ray_hits_box(x: Vec3, inv: Vec3, lo: Vec3, hi: Vec3) -> bool {
    let mut t0 = 0.0_f64;
    let mut t1 = f64::INFINITY;
    for k in 0..3 {
        let (a, b) = (
            (lo.get(k) - x.get(k)) * inv.get(k),
            (hi.get(k) - x.get(k)) * inv.get(k),
        );
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        t0 = t0.max(a);
        t1 = t1.min(b);
    }
    t0 <= t1
}

/// A bounding-volume hierarchy of the triangles' axis-aligned boxes: median splits along
/// the longest axis of the centroids, leaves of at most [`Bvh::LEAF`] triangles.
#[derive(Debug)]
struct Bvh {
    nodes: Vec<Node>,
    /// triangle indices, leaves are ranges of it
    order: Vec<u32>,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// leaf: `order[start..start + count]`; inner (count 0): children `start`, `start + 1`
    start: u32,
    count: u32,
}

impl Bvh {
    const LEAF: usize = 4;
    /// bins per axis of the surface-area split
    const BINS: usize = 16;
    /// below this depth nodes split by surface area, from it on at the median (which halves
    /// the triangles, so the depth stays ≤ 48 + ⌈log2 T⌉ + 1 < 96: the stack of `visit`)
    const SAH_DEPTH: usize = 48;

    /// The hierarchy of the triangles' boxes. A node splits where the binned surface-area
    /// heuristic is lowest (Σ over the two sides of box area × triangles, 16 bins of the
    /// centroids per axis): it separates the parts of a mesh that a median split along the
    /// longest axis mixes, such as a drum's end caps (fans of slivers from the centre) and
    /// its side, whose mixed boxes would cover the drum's interior and make every bead
    /// there descend deep (docs/granular.md, "A mesh obstacle against the analytic one").
    /// Falls back to the median split when no binned split separates the centroids or below
    /// [`Bvh::SAH_DEPTH`]. The queries' results do not depend on the hierarchy's shape.
    fn build(vertices: &[Vec3], tris: &[[u32; 3]]) -> Self {
        let boxes: Vec<(Vec3, Vec3)> = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                (a.min(b).min(c), a.max(b).max(c))
            })
            .collect();
        // doubled centroids l + h (the split keys)
        let cent: Vec<Vec3> = boxes.iter().map(|&(l, h)| l + h).collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut nodes = vec![Node {
            lo: Vec3::ZERO,
            hi: Vec3::ZERO,
            start: 0,
            count: 0,
        }];
        let mut scratch: Vec<u32> = Vec::new();
        // explicit stack of (node, range, depth) to build without recursion
        let mut stack = vec![(0usize, 0usize, tris.len(), 0usize)];
        while let Some((node, s, e, depth)) = stack.pop() {
            let (mut lo, mut hi) = boxes[order[s] as usize];
            let (mut clo, mut chi) = (lo + hi, lo + hi);
            for &t in &order[s..e] {
                let (l, h) = boxes[t as usize];
                lo = lo.min(l);
                hi = hi.max(h);
                clo = clo.min(l + h);
                chi = chi.max(l + h);
            }
            nodes[node].lo = lo;
            nodes[node].hi = hi;
            if e - s <= Self::LEAF {
                nodes[node].start = s as u32;
                nodes[node].count = (e - s) as u32;
                continue;
            }
            let split = if depth < Self::SAH_DEPTH {
                Self::sah_split(&boxes, &cent, &order[s..e], clo, chi)
            } else {
                None
            };
            let mid = match split {
                Some((axis, k)) => {
                    // stable partition of the range: bins < k to the left
                    let (a, b) = (clo.get(axis), chi.get(axis));
                    scratch.clear();
                    let mut left = s;
                    for i in s..e {
                        let t = order[i];
                        if Self::bin_of(cent[t as usize].get(axis), a, b) < k {
                            order[left] = t;
                            left += 1;
                        } else {
                            scratch.push(t);
                        }
                    }
                    order[left..e].copy_from_slice(&scratch);
                    left
                }
                None => {
                    let ext = chi - clo;
                    let axis = if ext.x >= ext.y && ext.x >= ext.z {
                        0
                    } else if ext.y >= ext.z {
                        1
                    } else {
                        2
                    };
                    let mid = (s + e) / 2;
                    let key = |t: &u32| cent[*t as usize].get(axis);
                    order[s..e].select_nth_unstable_by(mid - s, |a, b| {
                        key(a).total_cmp(&key(b)).then(a.cmp(b))
                    });
                    mid
                }
            };
            let left = nodes.len();
            nodes.push(nodes[node]);
            nodes.push(nodes[node]);
            nodes[node].start = left as u32;
            nodes[node].count = 0;
            stack.push((left, s, mid, depth + 1));
            stack.push((left + 1, mid, e, depth + 1));
        }
        Self { nodes, order }
    }

    /// The bin (0..BINS) of a (doubled) centroid coordinate c within the bounds [a, b] of
    /// the node's centroids along the split axis.
    fn bin_of(c: f64, a: f64, b: f64) -> usize {
        let f = (c - a) / (b - a) * Self::BINS as f64;
        (f.max(0.0) as usize).min(Self::BINS - 1)
    }

    /// The (axis, first bin of the right side) of the lowest surface-area cost, None when no
    /// binned split has triangles on both sides. Ties go to the lower axis, then the lower bin.
    fn sah_split(
        boxes: &[(Vec3, Vec3)],
        cent: &[Vec3],
        range: &[u32],
        clo: Vec3,
        chi: Vec3,
    ) -> Option<(usize, usize)> {
        let area = |lo: Vec3, hi: Vec3| {
            let d = hi - lo;
            d.x * d.y + d.y * d.z + d.z * d.x
        };
        let mut best: Option<(f64, usize, usize)> = None;
        for axis in 0..3 {
            let (a, b) = (clo.get(axis), chi.get(axis));
            if b - a <= 0.0 {
                continue;
            }
            let mut bins = [(0usize, Vec3::ZERO, Vec3::ZERO); Self::BINS];
            for &t in range {
                let (l, h) = boxes[t as usize];
                let bin = &mut bins[Self::bin_of(cent[t as usize].get(axis), a, b)];
                if bin.0 == 0 {
                    (bin.1, bin.2) = (l, h);
                } else {
                    (bin.1, bin.2) = (bin.1.min(l), bin.2.max(h));
                }
                bin.0 += 1;
            }
            // right-side sweeps: cost of bins k.. for every k
            let mut right = [(0usize, 0.0f64); Self::BINS];
            let mut acc: Option<(Vec3, Vec3)> = None;
            let mut n = 0;
            for k in (0..Self::BINS).rev() {
                let (c, l, h) = bins[k];
                if c > 0 {
                    n += c;
                    acc = Some(acc.map_or((l, h), |(a, b)| (a.min(l), b.max(h))));
                }
                right[k] = (n, acc.map_or(0.0, |(a, b)| area(a, b)));
            }
            let mut acc: Option<(Vec3, Vec3)> = None;
            let mut n = 0;
            for k in 1..Self::BINS {
                let (c, l, h) = bins[k - 1];
                if c > 0 {
                    n += c;
                    acc = Some(acc.map_or((l, h), |(a, b)| (a.min(l), b.max(h))));
                }
                let (nr, ar) = right[k];
                if n == 0 || nr == 0 {
                    continue;
                }
                let cost = acc.map_or(0.0, |(a, b)| area(a, b)) * n as f64 + ar * nr as f64;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, k));
                }
            }
        }
        best.map(|(_, axis, k)| (axis, k))
    }

    /// Calls `leaf` on every triangle of the leaves whose boxes pass `test`.
    fn visit(&self, test: impl Fn(Vec3, Vec3) -> bool, mut leaf: impl FnMut(u32)) {
        // the depth is below 96 (`Bvh::build`) and a depth-first descent holds at most
        // depth + 1 nodes: a fixed stack, no allocation
        let mut stack = [0u32; 128];
        let mut len = 1;
        while len > 0 {
            len -= 1;
            let i = stack[len] as usize;
            let Some(n) = self.nodes.get(i) else { continue };
            if !test(n.lo, n.hi) {
                continue;
            }
            if n.count > 0 {
                let s = n.start as usize;
                for &t in &self.order[s..s + n.count as usize] {
                    leaf(t);
                }
            } else if len + 2 <= stack.len() {
                stack[len] = n.start + 1;
                stack[len + 1] = n.start;
                len += 2;
            }
        }
    }
}

/// A closed, outward-oriented box mesh [lo, hi] (12 triangles): tests and examples.
pub fn box_mesh(lo: Vec3, hi: Vec3) -> MeshData {
    let v = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let vertices = (0..8).map(v).collect();
    // faces as quads (counter-clockwise seen from outside), split into two triangles
    let quads = [
        [0, 2, 3, 1], // z = lo
        [4, 5, 7, 6], // z = hi
        [0, 1, 5, 4], // y = lo
        [2, 6, 7, 3], // y = hi
        [0, 4, 6, 2], // x = lo
        [1, 3, 7, 5], // x = hi
    ];
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    MeshData {
        vertices,
        triangles,
    }
}

/// A closed, outward-oriented cylinder mesh about the z axis from z0 to z1 with `n` sides
/// (lateral quads and two capped fans): the rotating drum of triangles, tests.
pub fn cylinder_mesh(radius: f64, z0: f64, z1: f64, n: usize) -> MeshData {
    let n = n.max(3);
    let mut vertices = Vec::with_capacity(2 * n + 2);
    for z in [z0, z1] {
        for k in 0..n {
            let a = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            vertices.push(Vec3::new(radius * a.cos(), radius * a.sin(), z));
        }
    }
    vertices.push(Vec3::new(0.0, 0.0, z0));
    vertices.push(Vec3::new(0.0, 0.0, z1));
    let (c0, c1) = (2 * n as u64, 2 * n as u64 + 1);
    let mut triangles = Vec::with_capacity(4 * n);
    let n64 = n as u64;
    for k in 0..n64 {
        let k1 = (k + 1) % n64;
        triangles.push([k, k1, n64 + k1]);
        triangles.push([k, n64 + k1, n64 + k]);
        triangles.push([c0, k1, k]);
        triangles.push([c1, n64 + k, n64 + k1]);
    }
    MeshData {
        vertices,
        triangles,
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    fn mesh(d: MeshData) -> TriangleMesh {
        TriangleMesh::new(d.vertices, d.triangles).unwrap()
    }

    pub fn closest_points_by_region() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let (p, r) = closest_on_triangle(Vec3::new(0.2, 0.2, 1.0), a, b, c);
        assert_eq!(r, Region::Face);
        assert!((p - Vec3::new(0.2, 0.2, 0.0)).norm() < 1e-15);
        let (p, r) = closest_on_triangle(Vec3::new(0.5, -1.0, 0.3), a, b, c);
        assert_eq!(r, Region::Edge(0));
        assert!((p - Vec3::new(0.5, 0.0, 0.0)).norm() < 1e-15);
        let (p, r) = closest_on_triangle(Vec3::new(1.0, 1.0, 0.0), a, b, c);
        assert_eq!(r, Region::Edge(1));
        assert!((p - Vec3::new(0.5, 0.5, 0.0)).norm() < 1e-15);
        let (p, r) = closest_on_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c);
        assert_eq!((p, r), (a, Region::Vertex(0)));
        let (p, r) = closest_on_triangle(Vec3::new(2.0, -0.5, 0.0), a, b, c);
        assert_eq!((p, r), (b, Region::Vertex(1)));
        let (p, r) = closest_on_triangle(Vec3::new(-0.1, 3.0, 0.0), a, b, c);
        assert_eq!((p, r), (c, Region::Vertex(2)));
        let (p, r) = closest_on_triangle(Vec3::new(-1.0, 0.5, 0.0), a, b, c);
        assert_eq!(r, Region::Edge(2));
        assert!((p - Vec3::new(0.0, 0.5, 0.0)).norm() < 1e-15);
    }

    pub fn a_query_from_inside_a_query_gets_the_same_contacts() {
        let m = mesh(cylinder_mesh(1.0, 0.0, 2.0, 40));
        let (x, y) = (Vec3::new(0.95, 0.0, 1.0), Vec3::new(0.0, -0.97, 0.02));
        let mut outer = Vec::new();
        let mut inner = Vec::new();
        m.near_each(x, 0.1, 0.0, |t, p, r| {
            outer.push((t, p, r));
            if outer.len() == 1 {
                // the thread's buffers are borrowed by the outer query here
                m.near_each(y, 0.1, 0.0, |t, p, r| inner.push((t, p, r)));
            }
        });
        let (mut a, mut b) = (Vec::new(), Vec::new());
        m.near(x, 0.1, 0.0, &mut a);
        m.near(y, 0.1, 0.0, &mut b);
        assert!(!a.is_empty() && !b.is_empty());
        assert_eq!(outer, a);
        assert_eq!(inner, b);
    }

    pub fn box_mesh_is_closed_and_contains_its_inside() {
        let m = mesh(box_mesh(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)));
        assert!(m.check_closed().is_ok());
        assert_eq!(m.orientation(), Some(1.0));
        assert_eq!(m.contains(Vec3::new(0.5, 1.0, 1.5)), Some(true));
        assert_eq!(m.contains(Vec3::new(0.5, 1.0, 3.5)), Some(false));
        assert_eq!(m.contains(Vec3::new(-0.1, 1.0, 1.5)), Some(false));
        // a point level with an edge and a vertex of the box still counts right
        assert_eq!(m.contains(Vec3::new(0.5, 0.5, 0.5)), Some(true));
        // outward normals
        for t in 0..12 {
            let n = m.face_normal(t);
            let [a, _, _] = m.corners(t);
            let centre = Vec3::new(0.5, 1.0, 1.5);
            assert!(n.dot(a - centre) > 0.0, "triangle {t}");
        }
        let cyl = mesh(cylinder_mesh(1.0, 0.0, 2.0, 40));
        assert!(cyl.check_closed().is_ok());
        assert_eq!(cyl.contains(Vec3::new(0.3, -0.2, 1.0)), Some(true));
        assert_eq!(cyl.contains(Vec3::new(1.2, 0.0, 1.0)), Some(false));
    }

    pub fn bad_meshes_are_refused() {
        let sq = |tris: Vec<[u64; 3]>| {
            TriangleMesh::new(
                vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
                tris,
            )
        };
        assert!(matches!(
            sq(vec![[0, 1, 4]]),
            Err(MeshError::IndexOutOfRange { index: 4, .. })
        ));
        assert!(matches!(
            sq(vec![[0, 1, 1]]),
            Err(MeshError::Degenerate { triangle: 0, .. })
        ));
        assert!(matches!(sq(vec![]), Err(MeshError::Empty)));
        let nan = TriangleMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(f64::NAN, 0.0, 0.0)],
            vec![[0, 1, 2]],
        );
        assert!(matches!(nan, Err(MeshError::NonFiniteVertex { vertex: 2 })));
        // collinear vertices
        let line = TriangleMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0], vec![[0, 1, 2]]);
        assert!(matches!(line, Err(MeshError::Degenerate { .. })));
        // an open square is accepted but not closed
        let open = sq(vec![[0, 1, 2], [0, 2, 3]]).unwrap();
        assert!(matches!(open.check_closed(), Err(MeshError::NotClosed(..))));
        assert_eq!(open.contains(Vec3::ZERO), None);
        // a box with one triangle flipped: inconsistent orientation
        let mut d = box_mesh(Vec3::ZERO, Vec3::new(1.0, 1.0, 1.0));
        d.triangles[3].swap(1, 2);
        let flipped = TriangleMesh::new(d.vertices, d.triangles).unwrap();
        assert!(matches!(
            flipped.check_closed(),
            Err(MeshError::InconsistentOrientation(..))
        ));
    }

    pub fn shared_edges_and_vertices_give_one_contact() {
        // a flat square of two triangles: a sphere over the diagonal touches both triangles
        // at the same point; one contact survives, from the lower triangle
        let sq = TriangleMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap();
        let mut out = Vec::new();
        sq.near(Vec3::new(0.5, 0.5, 0.1), 0.1, 0.01, &mut out);
        assert_eq!(out.len(), 1, "{out:?}");
        assert_eq!(out[0].0, 0);
        // over triangle 1's face near the diagonal: triangle 0's edge is dominated
        sq.near(Vec3::new(0.45, 0.5, 0.1), 0.1, 0.2, &mut out);
        assert_eq!(out.len(), 1, "{out:?}");
        assert_eq!((out[0].0, out[0].2), (1, Region::Face));
        // over the shared vertex 0 from outside the square: one contact
        sq.near(Vec3::new(-0.05, -0.05, 0.05), 0.1, 0.0, &mut out);
        assert_eq!(out.len(), 1, "{out:?}");
        // a sphere in a box's corner touches three faces: three contacts (distinct points)
        let b = mesh(box_mesh(Vec3::ZERO, Vec3::new(1.0, 1.0, 1.0)));
        b.near(Vec3::new(0.1, 0.1, 0.1), 0.1, 1e-3, &mut out);
        assert_eq!(out.len(), 3, "{out:?}");
        // outside a convex edge of the box: one contact
        b.near(Vec3::new(1.05, 0.5, 1.05), 0.1, 1e-3, &mut out);
        assert_eq!(out.len(), 1, "{out:?}");
        // the hierarchy finds the same triangles as brute force on a finer mesh
        let cyl = mesh(cylinder_mesh(1.0, 0.0, 2.0, 64));
        for x in [
            Vec3::new(0.9, 0.1, 1.0),
            Vec3::new(0.0, 0.0, 0.05),
            Vec3::new(0.95, 0.0, 1.95),
        ] {
            cyl.near(x, 0.1, 0.05, &mut out);
            let mut brute = 0;
            for t in 0..cyl.triangles().len() {
                let (p, _) = cyl.closest_on(t, x).unwrap();
                if (x - p).norm() - 0.1 <= 0.05 {
                    brute += 1;
                }
            }
            assert!(
                !out.is_empty() && out.len() <= brute,
                "{x:?}: {} of {brute}",
                out.len()
            );
        }
    }

    pub fn facets_closer_than_two_degrees_give_one_contact_at_a_concave_edge() {
        let mut out = Vec::new();
        // a sphere inside a drum, touching the wall at the vertex column k = 0 (angle 0),
        // where two facets meet: 360°/n apart
        let x = Vec3::new(0.9, 0.0, 1.0);
        for (n, want) in [(500, 1), (200, 1), (100, 2), (64, 2)] {
            let cyl = TriangleMesh::new(
                cylinder_mesh(1.0, 0.0, 2.0, n).vertices,
                cylinder_mesh(1.0, 0.0, 2.0, n).triangles,
            )
            .unwrap();
            cyl.near(x, 0.1, 1e-3, &mut out);
            assert_eq!(out.len(), want, "{n} segments: {out:?}");
        }
        // and the hierarchy (surface-area splits) finds what brute force finds on a mesh of
        // caps (fans of slivers) and side, from inside and near the caps
        let cyl = TriangleMesh::new(
            cylinder_mesh(1.0, 0.0, 2.0, 300).vertices,
            cylinder_mesh(1.0, 0.0, 2.0, 300).triangles,
        )
        .unwrap();
        for x in [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.3, -0.2, 0.08),
            Vec3::new(-0.85, 0.4, 1.92),
            Vec3::new(0.7, 0.7, 0.05),
        ] {
            let mut found = Vec::new();
            cyl.bvh_candidates(x, 0.1, 0.05, &mut found);
            let brute: Vec<u32> = (0..cyl.triangles().len() as u32)
                .filter(|&t| {
                    let (p, _) = cyl.closest_on(t as usize, x).unwrap();
                    (x - p).norm() - 0.1 <= 0.05
                })
                .collect();
            assert_eq!(found, brute, "{x:?}");
        }
    }
}
