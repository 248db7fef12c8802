//! A minimal 3-vector for the geometry of spheres and obstacles.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::ops::{Add, AddAssign, Mul, Neg, Sub};

/// A vector of ℝ³. Serialized as the array `[x, y, z]` (scene files, checkpoints); read from
/// that array or from a map `{ x, y, z }`. Shown (`{:?}` and `{}`) as that array too,
/// `[1.0, 0.0, 2.5]`, in every message (issue 55: `Vec3 { x: 1.0, … }` in errors).
#[derive(Clone, Copy, PartialEq, Default)]
pub struct Vec3 {
    /// first component
    pub x: f64,
    /// second component
    pub y: f64,
    /// third component (vertical in every scene: gravity is −g e_z)
    pub z: f64,
}

impl std::fmt::Debug for Vec3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "[{:?}, {:?}, {:?}]", self.x, self.y, self.z)
    }
}

impl std::fmt::Display for Vec3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "[{}, {}, {}]", self.x, self.y, self.z)
    }
}

impl Vec3 {
    /// The zero vector.
    pub const ZERO: Vec3 = Vec3::new(0.0, 0.0, 0.0);
    /// e_x.
    pub const X: Vec3 = Vec3::new(1.0, 0.0, 0.0);
    /// e_y.
    pub const Y: Vec3 = Vec3::new(0.0, 1.0, 0.0);
    /// e_z.
    pub const Z: Vec3 = Vec3::new(0.0, 0.0, 1.0);

    /// (x, y, z).
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }
    /// From a slice of at least three entries (missing entries read as 0).
    pub fn from_slice(s: &[f64]) -> Self {
        let g = |i: usize| s.get(i).copied().unwrap_or(0.0);
        Self::new(g(0), g(1), g(2))
    }
    /// As an array.
    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
    /// Scalar product a·b.
    pub fn dot(self, o: Vec3) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Cross product a × b.
    pub fn cross(self, o: Vec3) -> Vec3 {
        Vec3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    /// Euclidean norm.
    pub fn norm(self) -> f64 {
        self.dot(self).sqrt()
    }
    /// Squared norm.
    pub fn norm_sq(self) -> f64 {
        self.dot(self)
    }
    /// self / ‖self‖, or `fallback` when the norm is (nearly) zero or not finite.
    pub fn normalized_or(self, fallback: Vec3) -> Vec3 {
        let n = self.norm();
        if n > 1e-300 && n.is_finite() {
            self * (1.0 / n)
        } else {
            fallback
        }
    }
    /// Whether every component is finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
    /// Two unit vectors (t₁, t₂) completing the unit vector n to a right-handed orthonormal
    /// frame (n, t₁, t₂): the contact frame, normal first.
    pub fn tangent_basis(self) -> (Vec3, Vec3) {
        let a = if self.x.abs() <= self.y.abs() && self.x.abs() <= self.z.abs() {
            Vec3::X
        } else if self.y.abs() <= self.z.abs() {
            Vec3::Y
        } else {
            Vec3::Z
        };
        let t1 = a.cross(self).normalized_or(Vec3::X);
        let t2 = self.cross(t1);
        (t1, t2)
    }
}

impl Serialize for Vec3 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.to_array().serialize(s)
    }
}

impl<'de> Deserialize<'de> for Vec3 {
    /// From `[x, y, z]` (an array of another length is refused with its length: TOML's
    /// fixed-size arrays drop extra elements, issue 55) or `{ x, y, z }`.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::{Error, IgnoredAny, MapAccess, SeqAccess, Visitor};
        struct Xyz;
        impl<'de> Visitor<'de> for Xyz {
            type Value = Vec3;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a vector [x, y, z] of 3 numbers")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<Vec3, A::Error> {
                let mut c = [0.0; 3];
                for (i, x) in c.iter_mut().enumerate() {
                    *x = s
                        .next_element()?
                        .ok_or_else(|| A::Error::invalid_length(i, &self))?;
                }
                let mut n = 3;
                while s.next_element::<IgnoredAny>()?.is_some() {
                    n += 1;
                }
                if n > 3 {
                    return Err(A::Error::invalid_length(n, &self));
                }
                Ok(Vec3::new(c[0], c[1], c[2]))
            }
            fn visit_map<A: MapAccess<'de>>(self, m: A) -> Result<Vec3, A::Error> {
                #[derive(Deserialize)]
                struct Map {
                    x: f64,
                    y: f64,
                    z: f64,
                }
                let Map { x, y, z } =
                    Map::deserialize(serde::de::value::MapAccessDeserializer::new(m))?;
                Ok(Vec3::new(x, y, z))
            }
        }
        d.deserialize_any(Xyz)
    }
}

impl Vec3 {
    /// The vector rotated by the angle `angle` (rad, right-handed) about the unit `axis`
    /// (Rodrigues' formula v cos a + (k × v) sin a + k (k·v)(1 − cos a)).
    pub fn rotated(self, axis: Vec3, angle: f64) -> Vec3 {
        let (s, c) = angle.sin_cos();
        self.rotated_sc(axis, s, c)
    }
    /// [`Vec3::rotated`] by the angle whose sine and cosine are (s, c) (computed once for
    /// several vectors; −s for the inverse rotation: the sine is odd to the bit).
    pub fn rotated_sc(self, axis: Vec3, s: f64, c: f64) -> Vec3 {
        self * c + axis.cross(self) * s + axis * (axis.dot(self) * (1.0 - c))
    }
    /// Component-wise minimum.
    pub fn min(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x.min(o.x), self.y.min(o.y), self.z.min(o.z))
    }
    /// Component-wise maximum.
    pub fn max(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x.max(o.x), self.y.max(o.y), self.z.max(o.z))
    }
    /// Component `k` (0: x, 1: y, otherwise z).
    pub fn get(self, k: usize) -> f64 {
        match k {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    fn add(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl AddAssign for Vec3 {
    fn add_assign(&mut self, o: Vec3) {
        *self = *self + o;
    }
}
impl Sub for Vec3 {
    type Output = Vec3;
    fn sub(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl Mul<f64> for Vec3 {
    type Output = Vec3;
    fn mul(self, s: f64) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}
impl Neg for Vec3 {
    type Output = Vec3;
    fn neg(self) -> Vec3 {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    /// A vector in a message reads as the array of a scene file, not as a Rust struct.
    pub fn shown_as_an_array() {
        let v = super::Vec3::new(1.0, -0.5, 2.0);
        assert_eq!(format!("{v:?}"), "[1.0, -0.5, 2.0]");
        assert_eq!(format!("{v}"), "[1, -0.5, 2]");
    }

    use super::*;

    pub fn tangent_basis_is_orthonormal_and_right_handed() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(1.0, 2.0, -3.0).normalized_or(Vec3::Z),
            Vec3::new(0.0, -1.0, 1e-9).normalized_or(Vec3::Z),
        ] {
            let (t1, t2) = n.tangent_basis();
            assert!((t1.norm() - 1.0).abs() < 1e-12);
            assert!((t2.norm() - 1.0).abs() < 1e-12);
            assert!(n.dot(t1).abs() < 1e-12 && n.dot(t2).abs() < 1e-12 && t1.dot(t2).abs() < 1e-12);
            assert!((n.cross(t1) - t2).norm() < 1e-12);
        }
    }
}
