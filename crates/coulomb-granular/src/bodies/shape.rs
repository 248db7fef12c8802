//! Body shapes: the serde value a scene (file, Python, Rust) gives for each body, its
//! validation, its collision shape for parry3d ([`BodyShape::to_parry`]), its mass properties
//! for a density ([`BodyShape::mass_properties`]) and its tessellation for output
//! ([`BodyShape::tessellation`]).
//!
//! Shapes are defined in the body's *shape frame*; a body's `position` is the origin of that
//! frame in the world and its `orientation` the unit quaternion (w, x, y, z) that turns the
//! shape frame into the world frame. The centre of mass is wherever the shape puts it
//! ([`ShapeMass::local_com`]): at the origin for the symmetric shapes, at the centroid of the
//! volume for hulls, polyhedra and compounds.
//!
//! | kind | parameters | frame |
//! |---|---|---|
//! | `sphere` | `radius` | centred |
//! | `cuboid` | `half_extents` [a, b, c] | centred, edges along x, y, z |
//! | `capsule` | `radius`, `half_height` (of the segment) | axis along **y**, centred |
//! | `cylinder` | `radius`, `half_height` | axis along **y**, centred |
//! | `cone` | `radius` (of the base), `half_height` | axis along **y**, base at y = −half_height, apex at +half_height |
//! | `convex_hull` | `points` (≥ 4, not coplanar) | as given |
//! | `convex_polyhedron` | `vertices`, `faces` (vertex-index polygons, counter-clockwise seen from outside) | as given |
//! | `compound` | `parts`: [{ shape, position, orientation }] of the kinds above (not compounds) | as given |
//!
//! The round shapes follow parry3d's convention: their axis is the shape frame's y axis.
//!
//! # Validation ([`ShapeError`])
//! Non-finite numbers; non-positive radii, half-heights and half-extents; hulls of fewer than
//! 4 points or of coplanar points (thinner than 10⁻⁹ of their size); polyhedra whose faces are
//! not closed, consistently oriented, planar and convex; zero volume; non-unit quaternions of
//! compound parts (|‖q‖ − 1| > 10⁻⁹: refused, never normalized); empty or nested compounds;
//! an aspect ratio (longest extent over thinnest width) above [`MAX_ASPECT_RATIO`].

use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::shape::{Compound, SharedShape};
use serde::{Deserialize, Serialize};

/// The largest aspect ratio a shape may have: its longest extent over its thinnest width
/// (a cuboid's longest over its shortest side, a capsule's length over its diameter, a
/// cylinder's or cone's larger of length and diameter over the smaller, a polyhedron's
/// bounding-box diagonal over its smallest width across a face). Beyond it, the contact
/// detection's tolerances (relative to the body's size) exceed the 1 % of the thinnest
/// width that a resting body may penetrate, and the time step that resolves the thinnest
/// width becomes impractical for the longest.
pub const MAX_ASPECT_RATIO: f64 = 1000.0;

/// Largest deviation of a quaternion's norm from 1 that is accepted (it is refused beyond,
/// not normalized).
pub const QUATERNION_TOLERANCE: f64 = 1e-9;

/// Segments around the axis of the tessellations of curved shapes (spheres, capsules,
/// cylinders, cones); spheres and capsule caps have half as many rings.
pub const CURVE_SEGMENTS: u32 = 24;

/// The identity rotation (w, x, y, z).
pub const IDENTITY: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

fn identity() -> [f64; 4] {
    IDENTITY
}

/// The shape of a body, in its shape frame (module docs: kinds, parameters, frames).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum BodyShape {
    /// a solid ball of radius R (I = 2/5 m R²)
    Sphere {
        /// radius R (m)
        radius: f64,
    },
    /// a box of half-extents (a, b, c) along the shape frame's x, y, z
    Cuboid {
        /// half-extents (m)
        half_extents: [f64; 3],
    },
    /// the points within `radius` of the segment from (0, −half_height, 0) to (0, half_height, 0)
    Capsule {
        /// radius (m)
        radius: f64,
        /// half-length of the segment (m)
        half_height: f64,
    },
    /// a circular cylinder about the y axis from y = −half_height to half_height
    Cylinder {
        /// radius (m)
        radius: f64,
        /// half-length (m)
        half_height: f64,
    },
    /// a circular cone about the y axis, base (of `radius`) at y = −half_height, apex at
    /// y = half_height
    Cone {
        /// radius of the base (m)
        radius: f64,
        /// half-length (m)
        half_height: f64,
    },
    /// the convex hull of points (at least 4, not coplanar)
    ConvexHull {
        /// points (m)
        points: Vec<[f64; 3]>,
    },
    /// a convex polyhedron given by its vertices and its faces
    ConvexPolyhedron {
        /// vertices (m)
        vertices: Vec<[f64; 3]>,
        /// faces: polygons of vertex indices (from 0), counter-clockwise seen from outside
        faces: Vec<Vec<usize>>,
    },
    /// a union of convex parts, each placed in the compound's frame (parts should not
    /// overlap: the mass of an overlap is counted twice)
    Compound {
        /// the parts
        parts: Vec<CompoundPart>,
    },
}

/// One part of a [`BodyShape::Compound`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompoundPart {
    /// its shape (any kind but a compound)
    pub shape: BodyShape,
    /// origin of the part's shape frame in the compound's frame (m)
    #[serde(default)]
    pub position: [f64; 3],
    /// unit quaternion (w, x, y, z): part frame → compound frame (default identity)
    #[serde(default = "identity")]
    pub orientation: [f64; 4],
}

/// Why a shape is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// a number is NaN or infinite
    #[error("{what} is not finite")]
    NonFinite {
        /// which number (`"radius"`, `"points[3]"`)
        what: String,
    },
    /// a length that must be positive is not
    #[error("{what} = {value} must be positive")]
    NonPositive {
        /// which length
        what: String,
        /// its value
        value: f64,
    },
    /// a hull or polyhedron with fewer than 4 points
    #[error("a {kind} needs at least 4 points, {count} given")]
    TooFewPoints {
        /// `convex_hull` or `convex_polyhedron`
        kind: &'static str,
        /// points given
        count: usize,
    },
    /// the points of a hull or polyhedron are (nearly) coplanar
    #[error("the {count} points are coplanar (thickness {thickness:.3e} m for a size of {size:.3e} m): a flat hull has no volume")]
    Coplanar {
        /// points
        count: usize,
        /// largest distance of a point to the plane of the three most spread points
        thickness: f64,
        /// largest distance between two points (about)
        size: f64,
    },
    /// a face of a convex polyhedron is invalid
    #[error("face {face}: {reason}")]
    Face {
        /// face index
        face: usize,
        /// what is wrong
        reason: String,
    },
    /// a convex polyhedron is not closed or not consistently oriented
    #[error("the faces do not close the polyhedron: {reason}")]
    NotClosed {
        /// what is wrong
        reason: String,
    },
    /// the shape has no volume
    #[error("volume {volume:.3e} m³: the shape must have a positive volume")]
    ZeroVolume {
        /// the computed volume
        volume: f64,
    },
    /// the shape is too elongated or too flat for the contact detection
    #[error(
        "aspect ratio {ratio:.1} exceeds the limit {limit} (longest extent over thinnest width)"
    )]
    AspectRatio {
        /// the shape's ratio
        ratio: f64,
        /// [`MAX_ASPECT_RATIO`]
        limit: f64,
    },
    /// a quaternion is not finite or not of unit norm
    #[error("{what} {q:?} is not a unit quaternion (norm {norm}); quaternions are refused, not normalized")]
    Quaternion {
        /// which quaternion
        what: String,
        /// its value (w, x, y, z)
        q: [f64; 4],
        /// its norm
        norm: f64,
    },
    /// a compound has no part
    #[error("a compound needs at least one part")]
    EmptyCompound,
    /// a compound part is itself a compound
    #[error("part {part}: compounds cannot be nested")]
    NestedCompound {
        /// part index
        part: usize,
    },
    /// a part of a compound is invalid
    #[error("part {part}: {source}")]
    Part {
        /// part index
        part: usize,
        /// the part's error
        source: Box<ShapeError>,
    },
    /// parry3d could not build the hull or polyhedron
    #[error("the convex hull could not be computed ({0})")]
    Hull(String),
}

/// Mass properties of a shape for a density: mass, centre of mass and inertia tensor about
/// the centre of mass, both in the shape frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ShapeMass {
    /// mass m (kg)
    pub mass: f64,
    /// centre of mass in the shape frame (m)
    pub local_com: [f64; 3],
    /// inertia tensor about the centre of mass, in the shape frame (kg m²), symmetric
    pub inertia: [[f64; 3]; 3],
}

impl ShapeMass {
    /// The same body with mass `mass`: inertia scaled by mass / self.mass (same density
    /// distribution), centre of mass unchanged.
    pub fn with_mass(&self, mass: f64) -> Self {
        let s = mass / self.mass;
        let mut inertia = self.inertia;
        for row in &mut inertia {
            for x in row.iter_mut() {
                *x *= s;
            }
        }
        Self {
            mass,
            local_com: self.local_com,
            inertia,
        }
    }
}

/// A surface made of polygons (vertex indices, counter-clockwise seen from outside), in the
/// shape frame: what the output writes for a body.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Tessellation {
    /// vertices (m)
    pub vertices: Vec<[f64; 3]>,
    /// polygons of vertex indices
    pub faces: Vec<Vec<u32>>,
}

impl Tessellation {
    /// Appends `other` with its vertices moved by the pose (position, orientation).
    fn append(&mut self, other: &Tessellation, position: [f64; 3], orientation: [f64; 4]) {
        let base = self.vertices.len() as u32;
        for v in &other.vertices {
            let r = rotate(orientation, *v);
            self.vertices
                .push([r[0] + position[0], r[1] + position[1], r[2] + position[2]]);
        }
        for f in &other.faces {
            self.faces.push(f.iter().map(|i| i + base).collect());
        }
    }
}

/// Checks that `q` (w, x, y, z) is finite and of unit norm within [`QUATERNION_TOLERANCE`].
pub fn check_quaternion(what: &str, q: [f64; 4]) -> Result<(), ShapeError> {
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !norm.is_finite() || (norm - 1.0).abs() > QUATERNION_TOLERANCE {
        return Err(ShapeError::Quaternion {
            what: what.to_string(),
            q,
            norm,
        });
    }
    Ok(())
}

/// `q v q*`: the vector v rotated by the unit quaternion q = (w, x, y, z).
pub fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [w, x, y, z] = q;
    // t = 2 (u × v), v' = v + w t + u × t with u = (x, y, z)
    let t = [
        2.0 * (y * v[2] - z * v[1]),
        2.0 * (z * v[0] - x * v[2]),
        2.0 * (x * v[1] - y * v[0]),
    ];
    [
        v[0] + w * t[0] + (y * t[2] - z * t[1]),
        v[1] + w * t[1] + (z * t[0] - x * t[2]),
        v[2] + w * t[2] + (x * t[1] - y * t[0]),
    ]
}

/// parry's rotation of the unit quaternion (w, x, y, z).
pub fn to_rotation(q: [f64; 4]) -> Rotation {
    Rotation::from_xyzw(q[1], q[2], q[3], q[0])
}

/// parry's pose of a position and a unit quaternion (w, x, y, z).
pub fn to_pose(position: [f64; 3], q: [f64; 4]) -> Pose {
    Pose::from_parts(vec(position), to_rotation(q))
}

fn vec(a: [f64; 3]) -> Vector {
    Vector::new(a[0], a[1], a[2])
}

fn arr(v: Vector) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn finite(what: &str, x: f64) -> Result<(), ShapeError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(ShapeError::NonFinite {
            what: what.to_string(),
        })
    }
}

fn positive(what: &str, x: f64) -> Result<(), ShapeError> {
    finite(what, x)?;
    if x > 0.0 {
        Ok(())
    } else {
        Err(ShapeError::NonPositive {
            what: what.to_string(),
            value: x,
        })
    }
}

fn aspect(longest: f64, thinnest: f64) -> Result<(), ShapeError> {
    let ratio = longest / thinnest;
    if ratio > MAX_ASPECT_RATIO {
        return Err(ShapeError::AspectRatio {
            ratio,
            limit: MAX_ASPECT_RATIO,
        });
    }
    Ok(())
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Checks the points of a hull or polyhedron: finite, at least 4, not coplanar.
fn check_points(kind: &'static str, name: &str, pts: &[[f64; 3]]) -> Result<(), ShapeError> {
    for (i, p) in pts.iter().enumerate() {
        for x in p {
            finite(&format!("{name}[{i}]"), *x)?;
        }
    }
    if pts.len() < 4 {
        return Err(ShapeError::TooFewPoints {
            kind,
            count: pts.len(),
        });
    }
    // the three most spread points: p0, the farthest from p0, the farthest from their line
    let p0 = pts[0];
    let far = |f: &dyn Fn([f64; 3]) -> f64| {
        pts.iter().copied().fold(
            (p0, -1.0),
            |best, p| if f(p) > best.1 { (p, f(p)) } else { best },
        )
    };
    let (p1, size) = far(&|p| norm(sub(p, p0)));
    let axis = sub(p1, p0);
    let (p2, _) = far(&|p| norm(cross(axis, sub(p, p0))));
    let n = cross(axis, sub(p2, p0));
    let nn = norm(n);
    let thickness = if nn > 0.0 {
        pts.iter()
            .map(|p| (dot(n, sub(*p, p0)) / nn).abs())
            .fold(0.0, f64::max)
    } else {
        0.0
    };
    if size.is_nan() || size <= 0.0 || thickness <= 1e-9 * size {
        return Err(ShapeError::Coplanar {
            count: pts.len(),
            thickness,
            size,
        });
    }
    Ok(())
}

/// The aspect check (bounding-box diagonal over the smallest width across a face) of a
/// convex polyhedron built by parry, in O(points + faces ×
/// walk) instead of O(points × faces) (issue 55: a hull of 10⁵ points on a sphere took 99 s).
/// The extent of the points along a face normal is found by walking the polyhedron's edges
/// (the sides of its faces) to the farthest vertex: a linear function on a convex polytope
/// has no local maximum on its vertex graph other than the global one, so the walk ends at
/// the same value as a scan of every point. Each walk starts where the previous face's
/// ended; neighbouring faces in parry's order have nearby extreme vertices. Points on no face
/// (parry may keep some) bound no width and are never visited.
fn check_hull_aspect(poly: &parry3d_f64::shape::ConvexPolyhedron) -> Result<(), ShapeError> {
    let (diagonal, thinnest) = hull_extent(poly);
    aspect(diagonal, thinnest)
}

/// The bounding-box diagonal and the smallest width across a face of `poly` (see
/// [`check_hull_aspect`]).
fn hull_extent(poly: &parry3d_f64::shape::ConvexPolyhedron) -> (f64, f64) {
    let points = poly.points();
    let (mut lo, mut hi) = (points[0], points[0]);
    for p in points {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let diagonal = (hi - lo).length();
    // the edges of parry's triangulation of the hull (those inside a merged polygonal face
    // too: a face merged from nearly coplanar triangles may leave a vertex on no face's
    // boundary), and the sides of the faces
    let mut adjacent: Vec<Vec<u32>> = vec![Vec::new(); points.len()];
    for e in poly.edges() {
        let [a, b] = e.vertices;
        adjacent[a as usize].push(b);
        adjacent[b as usize].push(a);
    }
    let ids = poly.vertices_adj_to_face();
    for f in poly.faces() {
        let first = f.first_vertex_or_edge as usize;
        let k = f.num_vertices_or_edges as usize;
        for j in 0..k {
            let (a, b) = (ids[first + j], ids[first + (j + 1) % k]);
            adjacent[a as usize].push(b);
            adjacent[b as usize].push(a);
        }
    }
    // points on no edge (none in the hulls met; scanned for every face if there are any)
    let isolated: Vec<usize> = (0..points.len())
        .filter(|&i| adjacent[i].is_empty())
        .collect();
    // the largest of dir · p over the points, walking uphill from vertex `v`
    let farthest = |dir: Vector, mut v: usize| -> (f64, usize) {
        let mut best = dir.dot(points[v]);
        loop {
            let mut moved = false;
            for &w in &adjacent[v] {
                let d = dir.dot(points[w as usize]);
                if d > best {
                    best = d;
                    v = w as usize;
                    moved = true;
                }
            }
            if !moved {
                return (best, v);
            }
        }
    };
    // a vertex of the hull to start from (parry may keep points on no face: a walk from one
    // of them would not move)
    let start = poly
        .faces()
        .first()
        .map_or(0, |f| ids[f.first_vertex_or_edge as usize] as usize);
    let (mut top, mut bottom) = (start, start);
    let mut thinnest = f64::INFINITY;
    for f in poly.faces() {
        let n = f.normal;
        let (mut b, t) = farthest(n, top);
        let (mut minus_a, m) = farthest(-n, bottom);
        for &i in &isolated {
            b = b.max(n.dot(points[i]));
            minus_a = minus_a.max(-n.dot(points[i]));
        }
        (top, bottom) = (t, m);
        thinnest = thinnest.min(b + minus_a);
    }
    (diagonal, thinnest)
}

/// Checks a polyhedron given by vertices and polygon faces: indices in range, every vertex
/// used, closed and consistently oriented (every directed edge once, its reverse once),
/// faces planar, the solid convex with outward (counter-clockwise) faces.
///
/// Convexity in O(n log n) (issue 55: the scan of every vertex against every face plane took
/// 99 s for 10⁵ points): locally, the vertices of the faces across each edge of a face lie
/// below its plane (within 10⁻⁹ of the size); globally, the volume the faces enclose equals
/// that of the convex hull of the vertices (parry's quickhull) to 10⁻⁶. A closed surface that
/// is locally convex everywhere can fail to bound a convex body only by winding around it more
/// than once, which changes the enclosed volume; a dent is a local failure.
fn check_faces(vertices: &[[f64; 3]], faces: &[Vec<usize>]) -> Result<(), ShapeError> {
    let n = vertices.len();
    let mut used = vec![false; n];
    let mut edges = std::collections::HashMap::new();
    let size = vertices
        .iter()
        .map(|v| norm(sub(*v, vertices[0])))
        .fold(0.0, f64::max);
    let tol = (1e-9 * size).max(1e-12);
    if faces.len() < 4 {
        return Err(ShapeError::NotClosed {
            reason: format!("{} faces, a polyhedron has at least 4", faces.len()),
        });
    }
    let mut normals = Vec::with_capacity(faces.len());
    for (fi, f) in faces.iter().enumerate() {
        let bad = |reason: String| ShapeError::Face { face: fi, reason };
        if f.len() < 3 {
            return Err(bad(format!(
                "{} vertices, a face needs at least 3",
                f.len()
            )));
        }
        for (k, &i) in f.iter().enumerate() {
            if i >= n {
                return Err(bad(format!("vertex index {i} out of range ({n} vertices)")));
            }
            if f[..k].contains(&i) {
                return Err(bad(format!("vertex {i} appears twice")));
            }
            used[i] = true;
            let j = f[(k + 1) % f.len()];
            if edges.insert((i, j), fi).is_some() {
                return Err(ShapeError::NotClosed {
                    reason: format!(
                        "edge {i} → {j} is in two faces with the same direction (inconsistent orientation or a non-manifold edge)"
                    ),
                });
            }
        }
        // Newell normal, outward for counter-clockwise faces
        let mut nrm = [0.0; 3];
        for k in 0..f.len() {
            let a = vertices[f[k]];
            let b = vertices[f[(k + 1) % f.len()]];
            nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
            nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
            nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
        }
        let len = norm(nrm);
        if len.is_nan() || len <= 0.0 {
            return Err(bad("the face has no area".into()));
        }
        let nrm = [nrm[0] / len, nrm[1] / len, nrm[2] / len];
        let c = vertices[f[0]];
        for &i in f {
            if dot(nrm, sub(vertices[i], c)).abs() > tol {
                return Err(bad(format!("vertex {i} is off the face's plane")));
            }
        }
        normals.push(nrm);
    }
    if let Some(i) = used.iter().position(|u| !u) {
        return Err(ShapeError::NotClosed {
            reason: format!("vertex {i} is on no face"),
        });
    }
    let mut sorted: Vec<(usize, usize)> = edges.keys().copied().collect();
    sorted.sort_unstable();
    for &(i, j) in &sorted {
        if !edges.contains_key(&(j, i)) {
            return Err(ShapeError::NotClosed {
                reason: format!("edge {i} → {j} has no neighbouring face (an open surface)"),
            });
        }
    }
    // local convexity: the faces across the edges of each face lie below its plane
    let not_convex = |fi: usize, i: usize| {
        ShapeError::Face {
        face: fi,
        reason: format!(
            "vertex {i} lies outside the face's plane: the polyhedron is not convex or the face is not counter-clockwise seen from outside"
        ),
    }
    };
    for (fi, f) in faces.iter().enumerate() {
        let (nrm, c) = (normals[fi], vertices[f[0]]);
        for k in 0..f.len() {
            let (i, j) = (f[k], f[(k + 1) % f.len()]);
            let other = edges[&(j, i)];
            if let Some(&v) = faces[other]
                .iter()
                .find(|&&v| dot(nrm, sub(vertices[v], c)) > tol)
            {
                return Err(not_convex(fi, v));
            }
        }
    }
    // global convexity: the enclosed volume is the hull's
    let o = vertices[0];
    let tet = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
        let (a, b, c) = (sub(a, o), sub(b, o), sub(c, o));
        dot(
            a,
            [
                b[1] * c[2] - b[2] * c[1],
                b[2] * c[0] - b[0] * c[2],
                b[0] * c[1] - b[1] * c[0],
            ],
        ) / 6.0
    };
    let volume: f64 = faces
        .iter()
        .map(|f| {
            (1..f.len() - 1)
                .map(|k| tet(vertices[f[0]], vertices[f[k]], vertices[f[k + 1]]))
                .sum::<f64>()
        })
        .sum();
    let pts: Vec<Vector> = vertices.iter().map(|p| vec(*p)).collect();
    let (hv, ht) =
        match std::panic::catch_unwind(move || parry3d_f64::transformation::convex_hull(&pts)) {
            Ok(h) => h,
            Err(_) => return Err(ShapeError::Hull("parry3d failed on these vertices".into())),
        };
    let p = |i: u32| {
        let v = hv[i as usize];
        [v.x, v.y, v.z]
    };
    let hull: f64 = ht.iter().map(|t| tet(p(t[0]), p(t[1]), p(t[2]))).sum();
    if !(volume > 0.0 && (volume - hull).abs() <= 1e-6 * hull) {
        return Err(ShapeError::NotClosed {
            reason: format!(
                "the faces enclose a volume of {volume:.6e}, the convex hull of the vertices {hull:.6e}: the polyhedron is not convex (or its faces wind around it more than once, or are not counter-clockwise seen from outside)"
            ),
        });
    }
    Ok(())
}

/// Runs parry's convex-hull code, turning a panic into an error.
fn guarded<T>(f: impl FnOnce() -> Option<T> + std::panic::UnwindSafe) -> Result<T, ShapeError> {
    match std::panic::catch_unwind(f) {
        Ok(Some(t)) => Ok(t),
        Ok(None) => Err(ShapeError::Hull(
            "parry3d found the points degenerate".into(),
        )),
        Err(_) => Err(ShapeError::Hull("parry3d failed on these points".into())),
    }
}

impl BodyShape {
    /// The kind's name as in files (`sphere`, `cuboid`, …).
    pub fn kind(&self) -> &'static str {
        match self {
            BodyShape::Sphere { .. } => "sphere",
            BodyShape::Cuboid { .. } => "cuboid",
            BodyShape::Capsule { .. } => "capsule",
            BodyShape::Cylinder { .. } => "cylinder",
            BodyShape::Cone { .. } => "cone",
            BodyShape::ConvexHull { .. } => "convex_hull",
            BodyShape::ConvexPolyhedron { .. } => "convex_polyhedron",
            BodyShape::Compound { .. } => "compound",
        }
    }

    /// Whether this is a sphere (the sphere simulator's fast path).
    pub fn is_sphere(&self) -> bool {
        matches!(self, BodyShape::Sphere { .. })
    }

    /// Checks the shape (module docs, "Validation") without building it.
    pub fn validate(&self) -> Result<(), ShapeError> {
        self.to_parry().map(|_| ())
    }

    /// The validated collision shape for parry3d, in the shape frame (module docs).
    pub fn to_parry(&self) -> Result<SharedShape, ShapeError> {
        let shape = match self {
            BodyShape::Sphere { radius } => {
                positive("radius", *radius)?;
                SharedShape::ball(*radius)
            }
            BodyShape::Cuboid { half_extents: h } => {
                for (k, x) in h.iter().enumerate() {
                    positive(&format!("half_extents[{k}]"), *x)?;
                }
                aspect(h[0].max(h[1]).max(h[2]), h[0].min(h[1]).min(h[2]))?;
                SharedShape::cuboid(h[0], h[1], h[2])
            }
            BodyShape::Capsule {
                radius,
                half_height,
            } => {
                positive("radius", *radius)?;
                positive("half_height", *half_height)?;
                aspect(half_height + radius, *radius)?;
                SharedShape::capsule_y(*half_height, *radius)
            }
            BodyShape::Cylinder {
                radius,
                half_height,
            }
            | BodyShape::Cone {
                radius,
                half_height,
            } => {
                positive("radius", *radius)?;
                positive("half_height", *half_height)?;
                aspect(radius.max(*half_height), radius.min(*half_height))?;
                if matches!(self, BodyShape::Cone { .. }) {
                    SharedShape::cone(*half_height, *radius)
                } else {
                    SharedShape::cylinder(*half_height, *radius)
                }
            }
            BodyShape::ConvexHull { points } => {
                check_points("convex_hull", "points", points)?;
                let pts: Vec<Vector> = points.iter().map(|p| vec(*p)).collect();
                let s = guarded(move || SharedShape::convex_hull(&pts))?;
                let poly = s
                    .as_convex_polyhedron()
                    .ok_or_else(|| ShapeError::Hull("not a polyhedron".into()))?;
                check_hull_aspect(poly)?;
                s
            }
            BodyShape::ConvexPolyhedron { vertices, faces } => {
                check_points("convex_polyhedron", "vertices", vertices)?;
                check_faces(vertices, faces)?;
                let pts: Vec<Vector> = vertices.iter().map(|p| vec(*p)).collect();
                let mut tris = Vec::new();
                for f in faces {
                    for k in 1..f.len() - 1 {
                        tris.push([f[0] as u32, f[k] as u32, f[k + 1] as u32]);
                    }
                }
                let s = guarded(move || SharedShape::convex_mesh(pts, &tris))?;
                let poly = s
                    .as_convex_polyhedron()
                    .ok_or_else(|| ShapeError::Hull("not a polyhedron".into()))?;
                check_hull_aspect(poly)?;
                s
            }
            BodyShape::Compound { parts } => {
                if parts.is_empty() {
                    return Err(ShapeError::EmptyCompound);
                }
                let mut list = Vec::with_capacity(parts.len());
                for (k, p) in parts.iter().enumerate() {
                    let wrap = |e: ShapeError| ShapeError::Part {
                        part: k,
                        source: Box::new(e),
                    };
                    if matches!(p.shape, BodyShape::Compound { .. }) {
                        return Err(ShapeError::NestedCompound { part: k });
                    }
                    for (i, x) in p.position.iter().enumerate() {
                        finite(&format!("position[{i}]"), *x).map_err(wrap)?;
                    }
                    check_quaternion("orientation", p.orientation).map_err(wrap)?;
                    let s = p.shape.to_parry().map_err(wrap)?;
                    list.push((to_pose(p.position, p.orientation), s));
                }
                SharedShape(std::sync::Arc::new(Compound::new(list)))
            }
        };
        let volume = shape.mass_properties(1.0).mass();
        if !(volume.is_finite() && volume > 0.0) {
            return Err(ShapeError::ZeroVolume { volume });
        }
        Ok(shape)
    }

    /// Mass, centre of mass and inertia tensor (about the centre of mass, shape frame) of the
    /// solid of density ρ, from parry3d's mass properties.
    pub fn mass_properties(&self, density: f64) -> Result<ShapeMass, ShapeError> {
        positive("density", density)?;
        let shape = self.to_parry()?;
        Ok(mass_of(&shape, density))
    }

    /// The volume (m³).
    pub fn volume(&self) -> Result<f64, ShapeError> {
        Ok(self.mass_properties(1.0)?.mass)
    }

    /// The radius of a ball about the shape frame's origin that holds the shape: the
    /// smallest one, except for a compound with round parts (a part's origin distance plus
    /// its own bounding radius). What an inlet scales to the sampled size
    /// ([`crate::generate::Inlet::shape`]).
    pub fn bounding_radius(&self) -> f64 {
        let norm = |p: [f64; 3]| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let far = |pts: &[[f64; 3]]| pts.iter().map(|p| norm(*p)).fold(0.0, f64::max);
        match self {
            BodyShape::Sphere { radius } => *radius,
            BodyShape::Cuboid { half_extents } => norm(*half_extents),
            BodyShape::Capsule {
                radius,
                half_height,
            } => radius + half_height,
            // the rim of the base (and of the top) is the farthest point
            BodyShape::Cylinder {
                radius,
                half_height,
            }
            | BodyShape::Cone {
                radius,
                half_height,
            } => radius.hypot(*half_height),
            BodyShape::ConvexHull { points } => far(points),
            BodyShape::ConvexPolyhedron { vertices, .. } => far(vertices),
            BodyShape::Compound { parts } => parts
                .iter()
                .map(|p| match &p.shape {
                    BodyShape::ConvexHull { points: v }
                    | BodyShape::ConvexPolyhedron { vertices: v, .. } => v
                        .iter()
                        .map(|x| {
                            let r = rotate(p.orientation, *x);
                            norm([
                                r[0] + p.position[0],
                                r[1] + p.position[1],
                                r[2] + p.position[2],
                            ])
                        })
                        .fold(0.0, f64::max),
                    s => norm(p.position) + s.bounding_radius(),
                })
                .fold(0.0, f64::max),
        }
    }

    /// The shape scaled by `s` about its frame's origin (every length times `s`; compound
    /// parts' positions too, orientations kept).
    pub fn scaled(&self, s: f64) -> BodyShape {
        let p = |v: &[f64; 3]| v.map(|x| x * s);
        match self {
            BodyShape::Sphere { radius } => BodyShape::Sphere { radius: radius * s },
            BodyShape::Cuboid { half_extents } => BodyShape::Cuboid {
                half_extents: p(half_extents),
            },
            BodyShape::Capsule {
                radius,
                half_height,
            } => BodyShape::Capsule {
                radius: radius * s,
                half_height: half_height * s,
            },
            BodyShape::Cylinder {
                radius,
                half_height,
            } => BodyShape::Cylinder {
                radius: radius * s,
                half_height: half_height * s,
            },
            BodyShape::Cone {
                radius,
                half_height,
            } => BodyShape::Cone {
                radius: radius * s,
                half_height: half_height * s,
            },
            BodyShape::ConvexHull { points } => BodyShape::ConvexHull {
                points: points.iter().map(p).collect(),
            },
            BodyShape::ConvexPolyhedron { vertices, faces } => BodyShape::ConvexPolyhedron {
                vertices: vertices.iter().map(p).collect(),
                faces: faces.clone(),
            },
            BodyShape::Compound { parts } => BodyShape::Compound {
                parts: parts
                    .iter()
                    .map(|c| CompoundPart {
                        shape: c.shape.scaled(s),
                        position: p(&c.position),
                        orientation: c.orientation,
                    })
                    .collect(),
            },
        }
    }

    /// The surface as polygons in the shape frame: polyhedra (cuboids, hulls, polyhedra) as
    /// their faces, curved shapes as [`CURVE_SEGMENTS`] segments around their axis,
    /// compounds as their parts' surfaces. Computed once per shape; the output moves it.
    pub fn tessellation(&self) -> Result<Tessellation, ShapeError> {
        let shape = self.to_parry()?;
        Ok(tessellate(self, &shape))
    }
}

/// Mass properties of a parry shape for density ρ.
pub fn mass_of(shape: &SharedShape, density: f64) -> ShapeMass {
    let mp = shape.mass_properties(density);
    let i = mp.reconstruct_inertia_matrix();
    let c = [i.x_axis, i.y_axis, i.z_axis];
    let mut inertia = [[0.0; 3]; 3];
    for (col, v) in c.iter().enumerate() {
        inertia[0][col] = v.x;
        inertia[1][col] = v.y;
        inertia[2][col] = v.z;
    }
    ShapeMass {
        mass: mp.mass(),
        local_com: arr(mp.local_com),
        inertia,
    }
}

fn triangles(v: Vec<Vector>, idx: Vec<[u32; 3]>) -> Tessellation {
    Tessellation {
        vertices: v.into_iter().map(arr).collect(),
        faces: idx.into_iter().map(|t| t.to_vec()).collect(),
    }
}

fn tessellate(spec: &BodyShape, shape: &SharedShape) -> Tessellation {
    let n = CURVE_SEGMENTS;
    if let Some(b) = shape.as_ball() {
        let (v, i) = b.to_trimesh(n, n / 2);
        return triangles(v, i);
    }
    if let Some(c) = shape.as_capsule() {
        let (v, i) = c.to_trimesh(n, n / 4);
        return triangles(v, i);
    }
    if let Some(c) = shape.as_cylinder() {
        let (v, i) = c.to_trimesh(n);
        return triangles(v, i);
    }
    if let Some(c) = shape.as_cone() {
        let (v, i) = c.to_trimesh(n);
        return triangles(v, i);
    }
    if let Some(c) = shape.as_cuboid() {
        let h = c.half_extents;
        let vertices = (0..8)
            .map(|k| {
                [
                    if k & 1 == 0 { -h.x } else { h.x },
                    if k & 2 == 0 { -h.y } else { h.y },
                    if k & 4 == 0 { -h.z } else { h.z },
                ]
            })
            .collect();
        // counter-clockwise seen from outside: −x, +x, −y, +y, −z, +z
        let faces = vec![
            vec![0, 4, 6, 2],
            vec![1, 3, 7, 5],
            vec![0, 1, 5, 4],
            vec![2, 6, 7, 3],
            vec![0, 2, 3, 1],
            vec![4, 5, 7, 6],
        ];
        return Tessellation { vertices, faces };
    }
    if let Some(p) = shape.as_convex_polyhedron() {
        let adj = p.vertices_adj_to_face();
        let faces = p
            .faces()
            .iter()
            .map(|f| {
                let a = f.first_vertex_or_edge as usize;
                adj[a..a + f.num_vertices_or_edges as usize].to_vec()
            })
            .collect();
        return Tessellation {
            vertices: p.points().iter().map(|v| arr(*v)).collect(),
            faces,
        };
    }
    if let (Some(c), BodyShape::Compound { parts }) = (shape.as_compound(), spec) {
        let mut out = Tessellation::default();
        for ((_, s), part) in c.shapes().iter().zip(parts) {
            out.append(&tessellate(&part.shape, s), part.position, part.orientation);
        }
        return out;
    }
    Tessellation::default()
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1.0)
    }

    fn cube_polyhedron(a: f64) -> BodyShape {
        let t = BodyShape::Cuboid {
            half_extents: [a; 3],
        }
        .tessellation()
        .unwrap();
        BodyShape::ConvexPolyhedron {
            vertices: t.vertices,
            faces: t
                .faces
                .iter()
                .map(|f| f.iter().map(|&i| i as usize).collect())
                .collect(),
        }
    }

    pub fn mass_properties_match_the_closed_forms() {
        let rho = 2000.0;
        let (a, b, c) = (0.1, 0.2, 0.3);
        let m = BodyShape::Cuboid {
            half_extents: [a, b, c],
        }
        .mass_properties(rho)
        .unwrap();
        let mass = rho * 8.0 * a * b * c;
        assert!(close(m.mass, mass, 1e-12));
        let ixx = mass / 3.0 * (b * b + c * c);
        let izz = mass / 3.0 * (a * a + b * b);
        assert!(close(m.inertia[0][0], ixx, 1e-9), "{:?}", m.inertia);
        assert!(close(m.inertia[2][2], izz, 1e-9));
        assert!(m.inertia[0][1].abs() < 1e-12 && m.local_com == [0.0; 3]);
        // sphere: 4/3 π R³ ρ, 2/5 m R²
        let s = BodyShape::Sphere { radius: 0.05 }
            .mass_properties(rho)
            .unwrap();
        let ms = rho * 4.0 / 3.0 * std::f64::consts::PI * 0.05f64.powi(3);
        assert!(close(s.mass, ms, 1e-12));
        assert!(close(s.inertia[1][1], 0.4 * ms * 0.0025, 1e-9));
        // cylinder about y: m r²/2 about the axis
        let cy = BodyShape::Cylinder {
            radius: 0.1,
            half_height: 0.2,
        }
        .mass_properties(rho)
        .unwrap();
        let mc = rho * std::f64::consts::PI * 0.01 * 0.4;
        assert!(close(cy.mass, mc, 1e-9));
        assert!(close(cy.inertia[1][1], 0.5 * mc * 0.01, 1e-9));
        // the hull of the cube's corners is the cube
        let pts: Vec<[f64; 3]> = (0..8)
            .map(|k| {
                [
                    if k & 1 == 0 { -a } else { a },
                    if k & 2 == 0 { -b } else { b },
                    if k & 4 == 0 { -c } else { c },
                ]
            })
            .collect();
        let h = BodyShape::ConvexHull { points: pts }
            .mass_properties(rho)
            .unwrap();
        assert!(close(h.mass, mass, 1e-9));
        assert!(close(h.inertia[0][0], ixx, 1e-9));
        // a polyhedron from faces: the same cube
        let p = cube_polyhedron(0.1).mass_properties(rho).unwrap();
        assert!(close(p.mass, rho * 0.008, 1e-9));
        // override: inertia scales with the mass
        let o = m.with_mass(2.0 * m.mass);
        assert!(close(o.inertia[0][0], 2.0 * ixx, 1e-12));
    }

    pub fn a_compound_combines_its_parts() {
        // two unit cubes side by side along x: a 2 × 1 × 1 box centred at x = 0.5
        let cube = BodyShape::Cuboid {
            half_extents: [0.5; 3],
        };
        let part = |x: f64| CompoundPart {
            shape: cube.clone(),
            position: [x, 0.0, 0.0],
            orientation: IDENTITY,
        };
        let c = BodyShape::Compound {
            parts: vec![part(0.0), part(1.0)],
        };
        let m = c.mass_properties(1.0).unwrap();
        assert!(close(m.mass, 2.0, 1e-12));
        assert!(close(m.local_com[0], 0.5, 1e-12));
        // box 2 × 1 × 1, mass 2: I_yy = m/12 (4 + 1)
        assert!(close(m.inertia[1][1], 2.0 / 12.0 * 5.0, 1e-9));
        let t = c.tessellation().unwrap();
        assert_eq!((t.vertices.len(), t.faces.len()), (16, 12));
        assert!(t.vertices.iter().any(|v| close(v[0], 1.5, 1e-12)));
    }

    pub fn tessellations_are_closed_and_outward() {
        let shapes = [
            BodyShape::Sphere { radius: 0.3 },
            BodyShape::Cuboid {
                half_extents: [0.1, 0.2, 0.3],
            },
            BodyShape::Capsule {
                radius: 0.1,
                half_height: 0.3,
            },
            BodyShape::Cylinder {
                radius: 0.1,
                half_height: 0.3,
            },
            BodyShape::Cone {
                radius: 0.1,
                half_height: 0.3,
            },
            BodyShape::ConvexHull {
                points: vec![
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                    [0.2, 0.2, 0.2],
                ],
            },
            cube_polyhedron(0.2),
        ];
        for s in &shapes {
            let t = s.tessellation().unwrap();
            assert!(!t.faces.is_empty(), "{}", s.kind());
            // the divergence theorem: Σ over faces of (centroid · area normal) / 3 = volume,
            // positive when every face is counter-clockwise seen from outside
            let mut vol = 0.0;
            for f in &t.faces {
                let p0 = t.vertices[f[0] as usize];
                for k in 1..f.len() - 1 {
                    let (p1, p2) = (t.vertices[f[k] as usize], t.vertices[f[k + 1] as usize]);
                    vol += dot(p0, cross(p1, p2)) / 6.0;
                }
            }
            let exact = s.volume().unwrap();
            // tessellated curved shapes are inscribed: within a few per cent
            assert!(
                vol > 0.0 && (vol - exact).abs() <= 0.05 * exact,
                "{}: {vol} vs {exact}",
                s.kind()
            );
        }
    }

    pub fn bad_shapes_are_refused_with_what_is_wrong() {
        #[track_caller]
        fn err(s: BodyShape) -> ShapeError {
            s.validate().unwrap_err()
        }
        assert!(matches!(
            err(BodyShape::Sphere { radius: -1.0 }),
            ShapeError::NonPositive { .. }
        ));
        assert!(matches!(
            err(BodyShape::Cuboid {
                half_extents: [1.0, f64::NAN, 1.0]
            }),
            ShapeError::NonFinite { .. }
        ));
        assert!(matches!(
            err(BodyShape::Cuboid {
                half_extents: [1.0, 1.0, 1e-4]
            }),
            ShapeError::AspectRatio { .. }
        ));
        assert!(matches!(
            err(BodyShape::Capsule {
                radius: 1e-4,
                half_height: 1.0
            }),
            ShapeError::AspectRatio { .. }
        ));
        assert!(matches!(
            err(BodyShape::ConvexHull {
                points: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
            }),
            ShapeError::TooFewPoints { count: 3, .. }
        ));
        // coplanar: a flat square
        assert!(matches!(
            err(BodyShape::ConvexHull {
                points: vec![
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [1.0, 1.0, 0.0],
                    [0.5, 0.5, 1e-12]
                ]
            }),
            ShapeError::Coplanar { .. }
        ));
        // all points equal
        assert!(matches!(
            err(BodyShape::ConvexHull {
                points: vec![[1.0; 3]; 6]
            }),
            ShapeError::Coplanar { .. }
        ));
        // a polyhedron with a face turned inside out
        let BodyShape::ConvexPolyhedron {
            vertices,
            mut faces,
        } = cube_polyhedron(0.5)
        else {
            unreachable!()
        };
        faces[0].reverse();
        let e = err(BodyShape::ConvexPolyhedron {
            vertices: vertices.clone(),
            faces: faces.clone(),
        });
        assert!(
            matches!(e, ShapeError::NotClosed { .. } | ShapeError::Face { .. }),
            "{e}"
        );
        // a missing face: open
        faces[0].reverse();
        let open: Vec<Vec<usize>> = faces[1..].to_vec();
        assert!(matches!(
            err(BodyShape::ConvexPolyhedron {
                vertices: vertices.clone(),
                faces: open
            }),
            ShapeError::NotClosed { .. }
        ));
        // out-of-range index
        let mut bad = faces.clone();
        bad[2][1] = 99;
        assert!(matches!(
            err(BodyShape::ConvexPolyhedron {
                vertices: vertices.clone(),
                faces: bad
            }),
            ShapeError::Face { face: 2, .. }
        ));
        // compound: non-unit quaternion refused (not normalized), nesting, emptiness
        let cube = BodyShape::Cuboid {
            half_extents: [0.5; 3],
        };
        let e = err(BodyShape::Compound {
            parts: vec![CompoundPart {
                shape: cube.clone(),
                position: [0.0; 3],
                orientation: [1.0, 0.0, 0.0, 1e-3],
            }],
        });
        assert!(
            matches!(&e, ShapeError::Part { part: 0, source } if matches!(**source, ShapeError::Quaternion { .. })),
            "{e}"
        );
        assert!(matches!(
            err(BodyShape::Compound { parts: vec![] }),
            ShapeError::EmptyCompound
        ));
        let nested = BodyShape::Compound {
            parts: vec![CompoundPart {
                shape: cube,
                position: [0.0; 3],
                orientation: IDENTITY,
            }],
        };
        assert!(matches!(
            err(BodyShape::Compound {
                parts: vec![CompoundPart {
                    shape: nested,
                    position: [0.0; 3],
                    orientation: IDENTITY
                }]
            }),
            ShapeError::NestedCompound { part: 0 }
        ));
        assert!(check_quaternion("q", [f64::NAN, 0.0, 0.0, 0.0]).is_err());
        assert!(check_quaternion("q", [0.0, 0.6, 0.8, 0.0]).is_ok());
    }

    pub fn rotate_matches_parry() {
        let h = 0.5f64.sqrt();
        let q = [h, 0.0, 0.0, h]; // 90° about z
        let r = rotate(q, [1.0, 0.0, 0.0]);
        assert!(norm(sub(r, [0.0, 1.0, 0.0])) < 1e-15);
        let q = [0.5, 0.5, 0.5, 0.5];
        let v = [0.3, -0.2, 0.7];
        let p = to_rotation(q) * vec(v);
        assert!(norm(sub(rotate(q, v), arr(p))) < 1e-15);
    }

    pub fn shapes_round_trip_through_toml_and_json() {
        let s = BodyShape::Compound {
            parts: vec![CompoundPart {
                shape: BodyShape::Capsule {
                    radius: 0.1,
                    half_height: 0.2,
                },
                position: [1.0, 0.0, 0.0],
                orientation: IDENTITY,
            }],
        };
        let j = serde_json::to_string(&s).unwrap();
        assert_eq!(serde_json::from_str::<BodyShape>(&j).unwrap(), s);
        let t: BodyShape =
            toml::from_str("kind = \"cuboid\"\nhalf_extents = [0.1, 0.2, 0.3]\n").unwrap();
        assert_eq!(
            t,
            BodyShape::Cuboid {
                half_extents: [0.1, 0.2, 0.3]
            }
        );
        assert!(
            toml::from_str::<BodyShape>("kind = \"cuboid\"\nhalf_extent = [1, 1, 1]\n").is_err()
        );
    }
    /// The widths of a hull found by walking its edges are those of a scan of every point
    /// (random clouds in a ball, on a sphere, in a thin slab), and a hull of 10⁵ points on a
    /// sphere (every point a vertex: 99 s before, O(points × faces)) is validated; its time
    /// is in docs/fuzz.md, the bound here only catches a return to the quadratic scan.
    pub fn hull_widths_by_walking_equal_the_scan() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for k in 0..60 {
            let n = 4 + rng.random_range(0..400);
            let pts: Vec<Vector> = (0..n)
                .map(|_| {
                    let v = Vector::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    );
                    match k % 3 {
                        0 => v,
                        1 => v / v.length(),
                        _ => Vector::new(v.x, v.y, 0.01 * v.z),
                    }
                })
                .collect();
            let s = SharedShape::convex_hull(&pts).expect("hull");
            let poly = s.as_convex_polyhedron().expect("polyhedron");
            let (diagonal, thinnest) = hull_extent(poly);
            let mut scan = f64::INFINITY;
            for f in poly.faces() {
                let d: Vec<f64> = poly.points().iter().map(|p| f.normal.dot(*p)).collect();
                let (a, b) = d
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                        (a.min(*x), b.max(*x))
                    });
                scan = scan.min(b - a);
            }
            assert!(
                (thinnest - scan).abs() <= 1e-12 * diagonal,
                "{k}: {thinnest} vs {scan}"
            );
        }
        let pts: Vec<[f64; 3]> = (0..100_000)
            .map(|_| {
                let v = Vector::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                arr(v / v.length())
            })
            .collect();
        let t = std::time::Instant::now();
        let shape = BodyShape::ConvexHull { points: pts };
        assert!(shape.validate().is_ok());
        assert!(
            t.elapsed() < std::time::Duration::from_secs(30),
            "{:?}",
            t.elapsed()
        );
    }

    pub fn random_and_degenerate_point_sets_never_panic() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
        let mut accepted = 0;
        for k in 0..300 {
            let n = rng.random_range(0..9);
            let flat = k % 3 == 0; // every third set on a plane, up to a tiny offset
            let line = k % 7 == 0; // some on a line
            let pts: Vec<[f64; 3]> = (0..n)
                .map(|_| {
                    let t: f64 = rng.random_range(-1.0..1.0);
                    if line {
                        [t, 2.0 * t, -t]
                    } else {
                        let z = if flat {
                            rng.random_range(-1e-12..1e-12)
                        } else {
                            rng.random_range(-1.0..1.0)
                        };
                        [t, rng.random_range(-1.0..1.0), z]
                    }
                })
                .collect();
            // duplicates
            let mut pts2 = pts.clone();
            pts2.extend(pts.iter().take(2));
            for p in [pts, pts2] {
                let s = BodyShape::ConvexHull { points: p };
                if let Ok(m) = s.mass_properties(1.0) {
                    accepted += 1;
                    assert!(m.mass > 0.0 && m.inertia[0][0] > 0.0);
                    assert!(!s.tessellation().unwrap().faces.is_empty());
                }
            }
        }
        assert!(accepted > 50, "{accepted}");
    }

    /// A convex polyhedron of 10⁵ vertices (the hull of points on a sphere, as triangles) is
    /// checked in O(n log n) and accepted; the same with one vertex pushed in (a dent), with
    /// one face reversed, or with its vertices pushed out of convex position is refused.
    pub fn a_large_convex_polyhedron_is_checked_and_a_dent_refused() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let pts: Vec<Vector> = (0..100_000)
            .map(|_| {
                let v = Vector::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                v / v.length()
            })
            .collect();
        let (hv, ht) = parry3d_f64::transformation::convex_hull(&pts);
        let vertices: Vec<[f64; 3]> = hv.iter().map(|v| [v.x, v.y, v.z]).collect();
        let faces: Vec<Vec<usize>> = ht
            .iter()
            .map(|t| t.iter().map(|&i| i as usize).collect())
            .collect();
        assert!(vertices.len() > 50_000, "{}", vertices.len());
        let start = std::time::Instant::now();
        check_faces(&vertices, &faces).expect("a convex polyhedron");
        eprintln!(
            "check_faces: {} vertices, {} faces in {:.3} s",
            vertices.len(),
            faces.len(),
            start.elapsed().as_secs_f64()
        );
        // a dent: one vertex pulled halfway to the centre
        let mut dented = vertices.clone();
        dented[17] = dented[17].map(|x| 0.5 * x);
        let e = check_faces(&dented, &faces).unwrap_err().to_string();
        assert!(e.contains("not convex"), "{e}");
        // one face reversed: not closed consistently
        let mut flipped = faces.clone();
        flipped[3].reverse();
        assert!(check_faces(&vertices, &flipped).is_err());
        // an octahedron whose faces wind twice around... is not closed; a small one with one
        // vertex pushed outward past its neighbours' planes is a local failure
        let octa = vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let of: Vec<Vec<usize>> = vec![
            vec![0, 2, 4],
            vec![2, 1, 4],
            vec![1, 3, 4],
            vec![3, 0, 4],
            vec![2, 0, 5],
            vec![1, 2, 5],
            vec![3, 1, 5],
            vec![0, 3, 5],
        ];
        check_faces(&octa, &of).expect("octahedron");
        let mut inward = octa.clone();
        inward[4] = [0.0, 0.0, -0.5];
        assert!(check_faces(&inward, &of).is_err());
    }

    pub fn bounding_radius_holds_the_shape_and_scales_with_it() {
        let shapes = [
            BodyShape::Sphere { radius: 0.3 },
            BodyShape::Cuboid {
                half_extents: [0.1, 0.2, 0.3],
            },
            BodyShape::Capsule {
                radius: 0.1,
                half_height: 0.2,
            },
            BodyShape::Cylinder {
                radius: 0.1,
                half_height: 0.2,
            },
            BodyShape::Cone {
                radius: 0.3,
                half_height: 0.1,
            },
            BodyShape::ConvexHull {
                points: vec![
                    [0.0, 0.0, 0.0],
                    [0.4, 0.0, 0.0],
                    [0.0, 0.3, 0.0],
                    [0.0, 0.0, 0.2],
                ],
            },
            cube_polyhedron(0.2),
            BodyShape::Compound {
                parts: vec![
                    CompoundPart {
                        shape: BodyShape::Cuboid {
                            half_extents: [0.1; 3],
                        },
                        position: [0.0; 3],
                        orientation: IDENTITY,
                    },
                    CompoundPart {
                        shape: BodyShape::ConvexHull {
                            points: vec![
                                [0.0, 0.0, 0.0],
                                [0.1, 0.0, 0.0],
                                [0.0, 0.1, 0.0],
                                [0.0, 0.0, 0.1],
                            ],
                        },
                        position: [0.0, 0.3, 0.0],
                        orientation: [0.0, 1.0, 0.0, 0.0],
                    },
                ],
            },
        ];
        for s in &shapes {
            let r = s.bounding_radius();
            // every point of the surface (the tessellation's vertices lie on it) is inside,
            // and some vertex reaches the radius (all these shapes touch their ball)
            let t = s.tessellation().unwrap();
            let far = t
                .vertices
                .iter()
                .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
                .fold(0.0, f64::max);
            assert!(far <= r * (1.0 + 1e-12), "{}: {far} > {r}", s.kind());
            assert!(close(far, r, 1e-12), "{}: {far} vs {r}", s.kind());
            // scaled by 0.5: the radius halves, the volume is divided by 8
            let h = s.scaled(0.5);
            assert!(close(h.bounding_radius(), 0.5 * r, 1e-14), "{}", s.kind());
            let (v, vh) = (s.volume().unwrap(), h.volume().unwrap());
            assert!(
                close(vh, v / 8.0, 1e-9),
                "{}: {vh} vs {}",
                s.kind(),
                v / 8.0
            );
        }
    }
}
