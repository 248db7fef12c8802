//! The obstacles' surfaces as triangles (plane, box, cylinder, sphere, rectangle, mesh), cut to
//! the region the bodies occupy ([`Extent`]) and placed by their motion at time t: what the VTK
//! writers draw ([`crate::output`]) and the rigid engine collides with ([`crate::scene::rigid`]).

use crate::math::Vec3;
use crate::world::{Motion, Obstacle, Shape};

/// An axis-aligned box [lo, hi]: the region the obstacles' drawings must cover.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extent {
    /// lower corner
    pub lo: Vec3,
    /// upper corner
    pub hi: Vec3,
}

impl Extent {
    /// The bounding box of balls (centre, radius; a point is a ball of radius 0, a ball whose
    /// centre is not finite is left out) grown by 10 % of its diagonal and by the largest
    /// diameter on every side; a unit box around the origin without any.
    pub fn around(balls: impl IntoIterator<Item = (Vec3, f64)>) -> Self {
        Self::of_bounds(Self::bounds(balls))
    }
    /// What [`Extent::around`] needs of the balls: (−lo, hi, largest radius), whose maximum
    /// over the parts of a set of balls is the set's (a reduction over processes, exact).
    pub fn bounds(balls: impl IntoIterator<Item = (Vec3, f64)>) -> [f64; 7] {
        let mut lo = Vec3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = -lo;
        let mut rmax: f64 = 0.0;
        for (x, r) in balls.into_iter().filter(|b| b.0.is_finite()) {
            lo = lo.min(x - Vec3::new(r, r, r));
            hi = hi.max(x + Vec3::new(r, r, r));
            rmax = rmax.max(r);
        }
        [-lo.x, -lo.y, -lo.z, hi.x, hi.y, hi.z, rmax]
    }
    /// [`Extent::around`] of balls whose [`Extent::bounds`] are `b`.
    pub fn of_bounds(b: [f64; 7]) -> Self {
        let (lo, hi, rmax) = (
            Vec3::new(-b[0], -b[1], -b[2]),
            Vec3::new(b[3], b[4], b[5]),
            b[6],
        );
        if !(lo.is_finite() && hi.is_finite()) {
            return Self {
                lo: Vec3::new(-1.0, -1.0, -1.0),
                hi: Vec3::new(1.0, 1.0, 1.0),
            };
        }
        let m = 0.1 * (hi - lo).norm() + 2.0 * rmax;
        let m = Vec3::new(m, m, m);
        Self {
            lo: lo - m,
            hi: hi + m,
        }
    }
    /// The smallest box holding both.
    pub fn union(self, o: Extent) -> Self {
        Self {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }
    /// The box grown by `fraction` of its diagonal on every side.
    pub fn grown(self, fraction: f64) -> Self {
        let m = fraction * (self.hi - self.lo).norm();
        let m = Vec3::new(m, m, m);
        Self {
            lo: self.lo - m,
            hi: self.hi + m,
        }
    }
    fn center(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }
    fn half_diagonal(&self) -> f64 {
        0.5 * (self.hi - self.lo).norm()
    }
    /// The range of (x − p)·a over the box's corners.
    fn range_along(&self, p: Vec3, a: Vec3) -> (f64, f64) {
        let mut r = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { self.lo.x } else { self.hi.x },
                if i & 2 == 0 { self.lo.y } else { self.hi.y },
                if i & 4 == 0 { self.lo.z } else { self.hi.z },
            );
            let d = (c - p).dot(a);
            r = (r.0.min(d), r.1.max(d));
        }
        r
    }
}

/// Segments around a cylinder's circumference in its drawing.
pub const CYLINDER_SEGMENTS: usize = 64;

/// Rotation of `p` by angle `a` about the line through `c` along the unit vector `k`
/// (Rodrigues' formula).
fn rotate_about(p: Vec3, c: Vec3, k: Vec3, a: f64) -> Vec3 {
    let v = p - c;
    let (s, co) = a.sin_cos();
    c + v * co + k.cross(v) * s + k * (k.dot(v) * (1.0 - co))
}

/// The rigid placement of an obstacle's motion at time t, applied to a point of its shape in
/// the reference position: the translation `offset(t)` of an oscillation; the rotation by ω t
/// about the axis of a rotation (the shapes it moves are invariant under it, so contacts see
/// only the surface velocity, but the drawing turns).
fn place(motion: &Motion, t: f64, p: Vec3) -> Vec3 {
    match motion {
        Motion::Rotate {
            center,
            axis,
            omega,
        } => rotate_about(p, *center, *axis, omega * t),
        other => p + other.offset(t),
    }
}

/// The reference-position surface of an unmoved obstacle as triangles. Planes are drawn as
/// squares centred at the projection of the extent's centre, as wide as the extent's
/// diagonal; infinite cylinders over the extent's range along their axis; curved shapes
/// tessellated with [`CYLINDER_SEGMENTS`] sides; meshes as they are.
fn reference_surface(shape: &Shape, extent: &Extent) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let quad = |c: Vec3, u: Vec3, v: Vec3, hu: f64, hv: f64| {
        let pts = vec![
            c - u * hu - v * hv,
            c + u * hu - v * hv,
            c + u * hu + v * hv,
            c - u * hu + v * hv,
        ];
        (pts, vec![[0, 1, 2], [0, 2, 3]])
    };
    match shape {
        Shape::Plane { point, normal } => {
            let (u, v) = normal.tangent_basis();
            let e = extent.center();
            let c = e - *normal * (e - *point).dot(*normal);
            let half = extent.half_diagonal();
            quad(c, u, v, half, half)
        }
        Shape::Rectangle {
            center,
            normal,
            u,
            half_u,
            half_v,
        } => quad(*center, *u, normal.cross(*u), *half_u, *half_v),
        Shape::CylinderInside {
            point,
            axis,
            radius,
        } => {
            let (a0, a1) = extent.range_along(*point, *axis);
            cylinder_surface(*point, *axis, *radius, (a0, a1), None, None)
        }
        Shape::Cylinder {
            base,
            axis,
            radius,
            height,
            bottom_cap,
            top_cap,
            orifice,
            ..
        } => cylinder_surface(
            *base,
            *axis,
            *radius,
            (0.0, *height),
            bottom_cap.then_some(*orifice),
            top_cap.then_some(0.0),
        ),
        Shape::Box {
            lo,
            hi,
            inside,
            open_top,
        } => {
            let data = crate::mesh::box_mesh(*lo, *hi);
            // the box mesh's faces in order z = lo, z = hi, …: two triangles each
            let skip_top = *inside && *open_top;
            let tris = data
                .triangles
                .iter()
                .enumerate()
                .filter(|(k, _)| !(skip_top && (2..4).contains(k)))
                .map(|(_, t)| t.map(|i| i as usize))
                .collect();
            (data.vertices, tris)
        }
        Shape::Sphere { center, radius, .. } => sphere_surface(*center, *radius),
        Shape::Mesh { mesh, .. } => (
            mesh.vertices().to_vec(),
            mesh.triangles()
                .iter()
                .map(|t| t.map(|i| i as usize))
                .collect(),
        ),
    }
}

/// A tessellated cylinder surface about the line through `base` along the unit `axis`, from
/// `range.0` to `range.1` along it ([`CYLINDER_SEGMENTS`] sides), with a cap at either end
/// when given: an annulus from the given inner radius (0: a disc; an orifice otherwise) to
/// `radius`.
fn cylinder_surface(
    base: Vec3,
    axis: Vec3,
    radius: f64,
    range: (f64, f64),
    bottom: Option<f64>,
    top: Option<f64>,
) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let (u, v) = axis.tangent_basis();
    let n = CYLINDER_SEGMENTS;
    let ring = |along: f64, r: f64| -> Vec<Vec3> {
        (0..n)
            .map(|k| {
                let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                let (s, c) = phi.sin_cos();
                base + axis * along + (u * c + v * s) * r
            })
            .collect()
    };
    let mut pts = ring(range.0, radius);
    pts.extend(ring(range.1, radius));
    let mut tris = Vec::with_capacity(4 * n);
    // a band of quads between the rings starting at i and j
    let band = |tris: &mut Vec<[usize; 3]>, i: usize, j: usize| {
        for k in 0..n {
            let k1 = (k + 1) % n;
            tris.push([i + k, i + k1, j + k1]);
            tris.push([i + k, j + k1, j + k]);
        }
    };
    band(&mut tris, 0, n);
    for (cap, along, outer) in [(bottom, range.0, 0), (top, range.1, n)] {
        let Some(inner) = cap else { continue };
        let start = pts.len();
        if inner > 0.0 {
            pts.extend(ring(along, inner));
            band(&mut tris, start, outer);
        } else {
            pts.push(base + axis * along);
            for k in 0..n {
                tris.push([start, outer + k, outer + (k + 1) % n]);
            }
        }
    }
    (pts, tris)
}

/// A tessellated sphere (latitude–longitude, [`CYLINDER_SEGMENTS`] around, half as many from
/// pole to pole).
fn sphere_surface(center: Vec3, radius: f64) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let n = CYLINDER_SEGMENTS;
    let m = n / 2;
    let mut pts = Vec::with_capacity(n * (m - 1) + 2);
    pts.push(center - Vec3::Z * radius);
    for i in 1..m {
        let theta = std::f64::consts::PI * i as f64 / m as f64;
        let (st, ct) = theta.sin_cos();
        for k in 0..n {
            let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            let (s, c) = phi.sin_cos();
            pts.push(center + Vec3::new(st * c, st * s, -ct) * radius);
        }
    }
    pts.push(center + Vec3::Z * radius);
    let top = pts.len() - 1;
    let ring = |i: usize, k: usize| 1 + (i - 1) * n + k % n;
    let mut tris = Vec::with_capacity(2 * n * m);
    for k in 0..n {
        tris.push([0, ring(1, k + 1), ring(1, k)]);
        tris.push([top, ring(m - 1, k), ring(m - 1, k + 1)]);
    }
    for i in 1..m - 1 {
        for k in 0..n {
            tris.push([ring(i, k), ring(i, k + 1), ring(i + 1, k + 1)]);
            tris.push([ring(i, k), ring(i + 1, k + 1), ring(i + 1, k)]);
        }
    }
    (pts, tris)
}

/// The surface of `obstacle` at time t as triangles (points, index triples), for drawing:
/// its shape in the reference position (unbounded shapes cut to `extent`), then placed by its
/// motion at t. One arm per [`Shape`]; a new shape adds its tessellation here.
pub fn obstacle_surface(
    obstacle: &Obstacle,
    t: f64,
    extent: &Extent,
) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    // unbounded shapes are cut to the extent in the reference position: move the extent back
    // by the translation so that a moving plane stays under the beads
    let back = match &obstacle.motion {
        Motion::Rotate { .. } => Vec3::ZERO,
        other => other.offset(t),
    };
    let local = Extent {
        lo: extent.lo - back,
        hi: extent.hi - back,
    };
    let (pts, tris) = reference_surface(&obstacle.shape, &local);
    let pts = pts
        .into_iter()
        .map(|p| place(&obstacle.motion, t, p))
        .collect();
    (pts, tris)
}
