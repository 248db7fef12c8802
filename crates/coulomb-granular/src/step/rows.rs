//! One contact of the step problem (2.10) in body-block form ([`ContactRow`]): the column
//! block H_i of H split by body, w_i, μ and the diagonal block W_ii of the Delassus operator —
//! the record the Gauss–Seidel sweep ([`crate::nsgs`]) and its corrections
//! ([`crate::subspace`], [`crate::coarse`]) share.

use crate::contact::{Contact, Partner};
use crate::world::World;

/// One contact of the step problem: its column block H_i of H, split by body, w_i and μ,
/// with the diagonal block W_ii of the Delassus operator and its inverse.
///
/// H_i is stored through the contact frame and the lever arms: row k of J_A is
/// (t_k, arm_A × t_k) and row k of J_B is −(t_k, arm_B × t_k) (the numbers
/// [`crate::assembly::assemble`] puts into H), so that
/// u_i = J_A v_A + J_B v_B + w_i = (t_k · (ẋ_A + ω_A × arm_A − ẋ_B − ω_B × arm_B))_k + w_i.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactRow {
    /// sphere A
    pub a: usize,
    /// sphere B, `None` for an obstacle
    pub b: Option<usize>,
    /// the frame (n, t₁, t₂), normal first
    pub frame: [[f64; 3]; 3],
    /// arm_A = p − x_A (zero when A's rotation is locked)
    pub arm_a: [f64; 3],
    /// arm_B = p − x_B (zero for an obstacle or when B's rotation is locked)
    pub arm_b: [f64; 3],
    /// w_i (obstacle motion and impact law, see [`crate::assembly`])
    pub w: [f64; 3],
    /// μ of the contact
    pub mu: f64,
    /// W_ii = J_A M_A⁻¹ J_Aᵀ + J_B M_B⁻¹ J_Bᵀ, row-major
    pub w_ii: [f64; 9],
    /// W_ii⁻¹, row-major
    pub w_inv: [f64; 9],
}

impl ContactRow {
    /// The row of contact `c` of `world` with w_i from `w`.
    pub(crate) fn new(
        world: &World,
        c: &Contact,
        w: [f64; 3],
        mu: f64,
        inv_mass: &[[f64; 6]],
    ) -> Option<Self> {
        let arm = |body: usize| -> Option<[f64; 3]> {
            let b = world.bodies.get(body)?;
            Some(if b.rotation_locked {
                [0.0; 3]
            } else {
                (c.point - b.position).to_array()
            })
        };
        let arm_a = arm(c.body)?;
        let (b, arm_b) = match c.partner {
            Partner::Body(j) if j != c.body => (Some(j), arm(j)?),
            Partner::Body(_) => return None,
            Partner::Obstacle(..) => (None, [0.0; 3]),
        };
        let mut row = Self {
            a: c.body,
            b,
            frame: [c.normal.to_array(), c.t1.to_array(), c.t2.to_array()],
            arm_a,
            arm_b,
            w,
            mu,
            w_ii: [0.0; 9],
            w_inv: [0.0; 9],
        };
        let minv_b = match b {
            Some(j) => Some(inv_mass.get(j)?),
            None => None,
        };
        row.set_delassus(inv_mass.get(c.body)?, minv_b)?;
        Some(row)
    }

    /// W_ii = J_A M_A⁻¹ J_Aᵀ + J_B M_B⁻¹ J_Bᵀ and its inverse for the inverse masses given
    /// (the diagonals of M_A⁻¹ and M_B⁻¹); `None` (row unchanged) when W_ii is not positive
    /// definite.
    pub fn set_delassus(&mut self, minv_a: &[f64; 6], minv_b: Option<&[f64; 6]>) -> Option<()> {
        let mut w_ii = [0.0; 9];
        add_jmj(&self.jacobian(false), minv_a, &mut w_ii);
        if let Some(mb) = minv_b {
            add_jmj(&self.jacobian(true), mb, &mut w_ii);
        }
        // symmetric by construction; make it exactly so
        for (k, l) in [(0, 1), (0, 2), (1, 2)] {
            let s = 0.5 * (w_ii[3 * k + l] + w_ii[3 * l + k]);
            w_ii[3 * k + l] = s;
            w_ii[3 * l + k] = s;
        }
        self.w_inv = invert_spd(&w_ii)?;
        self.w_ii = w_ii;
        Some(())
    }

    /// J_A (`side_b` false) or J_B (true): 3 × 6, row k the entries of H's column 3i + k on
    /// the body's dofs, exactly as [`crate::assembly::assemble`] computes them.
    pub fn jacobian(&self, side_b: bool) -> [[f64; 6]; 3] {
        let (arm, sign) = if side_b {
            (crate::math::Vec3::from_slice(&self.arm_b), -1.0)
        } else {
            (crate::math::Vec3::from_slice(&self.arm_a), 1.0)
        };
        let mut j = [[0.0; 6]; 3];
        for (k, t) in self.frame.iter().enumerate() {
            let rot = arm.cross(crate::math::Vec3::from_slice(t)).to_array();
            for d in 0..3 {
                j[k][d] = sign * t[d];
                j[k][3 + d] = sign * rot[d];
            }
        }
        j
    }

    /// u_i = J_A v_A + J_B v_B + w_i, with the entries of H as stored (evaluation on the
    /// stored problem).
    pub fn velocity(&self, va: &[f64; 6], vb: Option<&[f64; 6]>) -> [f64; 3] {
        let mut u = self.w;
        let mut side = |j: [[f64; 6]; 3], v: &[f64; 6]| {
            for k in 0..3 {
                u[k] += (0..6).map(|d| j[k][d] * v[d]).sum::<f64>();
            }
        };
        side(self.jacobian(false), va);
        if let Some(vb) = vb {
            side(self.jacobian(true), vb);
        }
        u
    }

    /// u_i = (t_k · (ẋ_A + ω_A × arm_A − ẋ_B − ω_B × arm_B))_k + w_i: the same as
    /// [`ContactRow::velocity`] up to rounding, with fewer operations (the sweep's).
    #[inline]
    pub fn velocity_fast(&self, va: &[f64; 6], vb: Option<&[f64; 6]>) -> [f64; 3] {
        let point = |v: &[f64; 6], arm: &[f64; 3]| {
            let w = cross(&[v[3], v[4], v[5]], arm);
            [v[0] + w[0], v[1] + w[1], v[2] + w[2]]
        };
        let mut rel = point(va, &self.arm_a);
        if let Some(vb) = vb {
            let pb = point(vb, &self.arm_b);
            for d in 0..3 {
                rel[d] -= pb[d];
            }
        }
        [
            dot3(&self.frame[0], &rel) + self.w[0],
            dot3(&self.frame[1], &rel) + self.w[1],
            dot3(&self.frame[2], &rel) + self.w[2],
        ]
    }
}

#[inline]
pub(crate) fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// J M⁻¹ Jᵀ added into `out` (row-major 3 × 3).
pub(crate) fn add_jmj(j: &[[f64; 6]; 3], minv: &[f64; 6], out: &mut [f64; 9]) {
    for k in 0..3 {
        for l in 0..3 {
            let mut s = 0.0;
            for d in 0..6 {
                s += j[k][d] * minv[d] * j[l][d];
            }
            out[3 * k + l] += s;
        }
    }
}

/// Inverse of a symmetric positive definite 3 × 3 matrix by cofactors; `None` unless the
/// leading minors are positive (relative to the diagonal) and the result finite.
pub fn invert_spd(a: &[f64; 9]) -> Option<[f64; 9]> {
    let scale = a[0].abs() + a[4].abs() + a[8].abs();
    let m2 = a[0] * a[4] - a[1] * a[3];
    let c00 = a[4] * a[8] - a[5] * a[7];
    let c01 = a[5] * a[6] - a[3] * a[8];
    let c02 = a[3] * a[7] - a[4] * a[6];
    let det = a[0] * c00 + a[1] * c01 + a[2] * c02;
    let tiny = 1e-13 * scale;
    if !(a[0] > tiny && m2 > tiny * scale && det > tiny * scale * scale) {
        return None;
    }
    let inv = [
        c00 / det,
        (a[2] * a[7] - a[1] * a[8]) / det,
        (a[1] * a[5] - a[2] * a[4]) / det,
        c01 / det,
        (a[0] * a[8] - a[2] * a[6]) / det,
        (a[2] * a[3] - a[0] * a[5]) / det,
        c02 / det,
        (a[1] * a[6] - a[0] * a[7]) / det,
        (a[0] * a[4] - a[1] * a[3]) / det,
    ];
    inv.iter().all(|x| x.is_finite()).then_some(inv)
}
