//! The contacts of one subdomain as local 3 × 3 problems, and the nonsmooth Gauss–Seidel sweep
//! over them (the body-level form of the fused iteration of `coulomb::inner::pgs`).
//!
//! For contact i between bead A and B (bead or obstacle), Hᵢᵀ v = G_A v_A + G_B v_B with
//! G_A the 3 × 6 block whose row k is (t_k, (p − x_A) × t_k) and G_B the opposite one at x_B
//! (assembly module, FCLIB convention u = Hᵀ v + w, M v = H r + f of (2.10)). The local
//! Delassus block is Wᵢᵢ = G_A M_A⁻¹ G_Aᵀ + G_B M_B⁻¹ G_Bᵀ and the local velocity
//! uᵢ = G_A v_A + G_B v_B + wᵢ. One Gauss–Seidel step on contact i solves Coulomb's law (2.9)
//! for u = Wᵢᵢ rᵢ + cᵢ, cᵢ = uᵢ − Wᵢᵢ rᵢ, the others frozen (`solve_contact_law`, or the
//! one-contact SOC-QP with De Saxcé's s = μ‖u_T‖ where the slip equation fails), then updates
//! v_A += M_A⁻¹ G_Aᵀ Δrᵢ and v_B += M_B⁻¹ G_Bᵀ Δrᵢ, so that M v = H r + f stays exact up to
//! rounding.

use crate::contact::{Contact, Partner};
use crate::world::World;
use coulomb::cone;
use coulomb::inner::pgs::{solve_contact, solve_contact_law, OneContact};

/// One side (a bead) of a contact.
#[derive(Debug, Clone, Copy)]
pub struct Side {
    /// local index of the bead
    pub bead: usize,
    /// G (3 × 6), row k = ±(t_k, (p − x) × t_k)
    pub g: [[f64; 6]; 3],
    /// M⁻¹ Gᵀ by rows: row k = M⁻¹ (row k of G)
    pub mg: [[f64; 6]; 3],
}

/// One contact of the subdomain as a local problem.
#[derive(Debug, Clone, Copy)]
pub struct Block {
    /// bead A (owned by this rank)
    pub a: Side,
    /// bead B, or none for an obstacle
    pub b: Option<Side>,
    /// Wᵢᵢ, row-major
    pub w: [f64; 9],
    /// Wᵢᵢ⁻¹
    pub winv: [f64; 9],
    /// μ
    pub mu: f64,
    /// wᵢ (obstacle motion and impact law)
    pub offset: [f64; 3],
    /// qᵢ = Hᵢᵀ M⁻¹ f + wᵢ, the Delassus vector of docs/error.md
    pub q: [f64; 3],
}

impl Side {
    fn new(world: &World, bead: usize, c: &Contact, sign: f64) -> Option<Self> {
        let b = world.bodies.get(bead)?;
        let arm = c.point - b.position;
        let mut g = [[0.0; 6]; 3];
        let mut mg = [[0.0; 6]; 3];
        let (im, ii) = (1.0 / b.mass, 1.0 / b.inertia());
        for (k, t) in [c.normal, c.t1, c.t2].iter().enumerate() {
            let rot = if b.rotation_locked {
                [0.0; 3]
            } else {
                arm.cross(*t).to_array()
            };
            let tr = t.to_array();
            for j in 0..3 {
                g[k][j] = sign * tr[j];
                g[k][3 + j] = sign * rot[j];
                mg[k][j] = g[k][j] * im;
                mg[k][3 + j] = g[k][3 + j] * ii;
            }
        }
        Some(Self { bead, g, mg })
    }
    /// G x_bead (3 values) for the 6 velocity entries of the bead in `v`.
    #[inline]
    fn apply(&self, v: &[f64]) -> [f64; 3] {
        let x = &v[6 * self.bead..6 * self.bead + 6];
        let mut out = [0.0; 3];
        for (k, o) in out.iter_mut().enumerate() {
            *o = (0..6).map(|j| self.g[k][j] * x[j]).sum();
        }
        out
    }
    /// v_bead += M⁻¹ Gᵀ d.
    #[inline]
    fn push(&self, d: &[f64; 3], v: &mut [f64]) {
        let x = &mut v[6 * self.bead..6 * self.bead + 6];
        for (j, xj) in x.iter_mut().enumerate() {
            *xj += self.mg[0][j] * d[0] + self.mg[1][j] * d[1] + self.mg[2][j] * d[2];
        }
    }
    /// imp_bead += Gᵀ d (an impulse, not yet divided by the mass).
    #[inline]
    fn push_impulse(&self, d: &[f64], imp: &mut [f64]) {
        let x = &mut imp[6 * self.bead..6 * self.bead + 6];
        for (j, xj) in x.iter_mut().enumerate() {
            *xj += self.g[0][j] * d[0] + self.g[1][j] * d[1] + self.g[2][j] * d[2];
        }
    }
}

impl Block {
    /// The local problem of contact `c` of `world` (local indices), with offset wᵢ and the
    /// free velocities `v_free` = M⁻¹ f (6 per bead). None when W is singular (never for
    /// spheres of positive mass: Wᵢᵢ ⪰ I / m_A).
    pub fn new(
        world: &World,
        c: &Contact,
        offset: [f64; 3],
        mu: f64,
        v_free: &[f64],
    ) -> Option<Self> {
        let a = Side::new(world, c.body, c, 1.0)?;
        let b = match c.partner {
            Partner::Body(j) => Some(Side::new(world, j, c, -1.0)?),
            Partner::Obstacle(_) => None,
        };
        let mut w = [0.0; 9];
        for side in std::iter::once(&a).chain(b.as_ref()) {
            for k in 0..3 {
                for l in 0..3 {
                    w[3 * k + l] += (0..6).map(|j| side.g[k][j] * side.mg[l][j]).sum::<f64>();
                }
            }
        }
        let winv = invert3(&w)?;
        let mut block = Self {
            a,
            b,
            w,
            winv,
            mu,
            offset,
            q: [0.0; 3],
        };
        block.q = block.velocity(v_free);
        Some(block)
    }
    /// uᵢ = G_A v_A + G_B v_B + wᵢ.
    #[inline]
    pub fn velocity(&self, v: &[f64]) -> [f64; 3] {
        let mut u = self.a.apply(v);
        if let Some(b) = &self.b {
            let ub = b.apply(v);
            for k in 0..3 {
                u[k] += ub[k];
            }
        }
        for k in 0..3 {
            u[k] += self.offset[k];
        }
        u
    }
}

/// 3 × 3 inverse by the adjugate; None when the determinant is not positive relative to the
/// entries (W is symmetric positive definite here).
pub fn invert3(a: &[f64; 9]) -> Option<[f64; 9]> {
    let c00 = a[4] * a[8] - a[5] * a[7];
    let c01 = a[5] * a[6] - a[3] * a[8];
    let c02 = a[3] * a[7] - a[4] * a[6];
    let det = a[0] * c00 + a[1] * c01 + a[2] * c02;
    let size = a.iter().map(|x| x.abs()).fold(0.0, f64::max);
    if !(det > 1e-14 * size * size * size) || !det.is_finite() {
        return None;
    }
    let d = 1.0 / det;
    Some([
        c00 * d,
        (a[2] * a[7] - a[1] * a[8]) * d,
        (a[1] * a[5] - a[2] * a[4]) * d,
        c01 * d,
        (a[0] * a[8] - a[2] * a[6]) * d,
        (a[2] * a[3] - a[0] * a[5]) * d,
        c02 * d,
        (a[1] * a[6] - a[0] * a[7]) * d,
        (a[0] * a[4] - a[1] * a[3]) * d,
    ])
}

/// One Gauss–Seidel sweep over `blocks` in order: r (3 per block) and v (6 per local bead)
/// updated in place; `dv` (6 per local bead) accumulates the velocity changes M⁻¹ Gᵀ Δr of
/// every bead, so that those of ghost beads can be sent to their owners.
pub fn sweep(blocks: &[Block], r: &mut [f64], v: &mut [f64], dv: &mut [f64]) {
    for (i, blk) in blocks.iter().enumerate() {
        let old = [r[3 * i], r[3 * i + 1], r[3 * i + 2]];
        let u = blk.velocity(v);
        let mut c = [0.0; 3];
        for k in 0..3 {
            c[k] = u[k] - (0..3).map(|l| blk.w[3 * k + l] * old[l]).sum::<f64>();
        }
        let mut contact = OneContact {
            a: &blk.w,
            ainv: &blk.winv,
            d: 3,
            mu: blk.mu,
            c,
        };
        let new = solve_contact_law(&contact, &old, &u).unwrap_or_else(|| {
            contact.c[0] += blk.mu * cone::tangent_norm(&u);
            solve_contact(&contact, &old)
        });
        let d = [new[0] - old[0], new[1] - old[1], new[2] - old[2]];
        if d == [0.0; 3] {
            continue;
        }
        r[3 * i..3 * i + 3].copy_from_slice(&new);
        blk.a.push(&d, v);
        blk.a.push(&d, dv);
        if let Some(b) = &blk.b {
            b.push(&d, v);
            b.push(&d, dv);
        }
    }
}

/// imp += H r restricted to the subdomain's contacts: Gᵀ rᵢ added to each bead of each block
/// (6 per local bead).
pub fn impulses(blocks: &[Block], r: &[f64], imp: &mut [f64]) {
    for (i, blk) in blocks.iter().enumerate() {
        let ri = &r[3 * i..3 * i + 3];
        blk.a.push_impulse(ri, imp);
        if let Some(b) = &blk.b {
            b.push_impulse(ri, imp);
        }
    }
}

/// Sums over the blocks for the error of docs/error.md, every entry multiplied by `alpha`
/// first (a power of two, exact): [Σ‖eᵢ‖², Σ‖qᵢ‖², Σ‖rᵢ‖², Σ‖uᵢ‖²] with uᵢ from v.
pub fn error_sums(blocks: &[Block], r: &[f64], v: &[f64], alpha: f64) -> [f64; 4] {
    let mut s = [0.0; 4];
    for (i, blk) in blocks.iter().enumerate() {
        let u = blk.velocity(v);
        let mut rs = [0.0; 3];
        let mut us = [0.0; 3];
        for k in 0..3 {
            rs[k] = r[3 * i + k] * alpha;
            us[k] = u[k] * alpha;
            let qk = blk.q[k] * alpha;
            s[1] += qk * qk;
            s[2] += rs[k] * rs[k];
            s[3] += us[k] * us[k];
        }
        s[0] += coulomb::law::contact_residual_sq(blk.mu, &us, &rs);
    }
    s
}

/// Largest magnitude of the entries of r, u and q over the blocks (NaN when one is NaN).
pub fn max_entry(blocks: &[Block], r: &[f64], v: &[f64]) -> f64 {
    let mut m = 0.0f64;
    let mut nan = false;
    for (i, blk) in blocks.iter().enumerate() {
        let u = blk.velocity(v);
        for k in 0..3 {
            for x in [r[3 * i + k], u[k], blk.q[k]] {
                nan |= x.is_nan();
                m = m.max(x.abs());
            }
        }
    }
    if nan {
        f64::NAN
    } else {
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::{assemble, contact_offset, free_momentum, mass_diagonal, StepData};
    use crate::contact::{detect, Activation};
    use crate::scene::Scene;

    /// The blocks reproduce the assembled global problem: Wᵢᵢ = Hᵢᵀ M⁻¹ Hᵢ, qᵢ, and a sweep
    /// sequence keeps M v = H r + f while driving the error of docs/error.md down.
    #[test]
    fn blocks_match_the_assembled_problem_and_the_sweep_converges() {
        let mut sim =
            crate::Simulation::new(Scene::Box.build(120, 3), crate::Params::default()).unwrap();
        for _ in 0..40 {
            sim.step().unwrap();
        }
        let world = &sim.world;
        let h = sim.params.h;
        let contacts = detect(world, sim.time, h, &Activation::accurate());
        assert!(contacts.len() > 50, "{}", contacts.len());
        let data = StepData {
            h,
            t_end: sim.time + h,
            restitution: 0.2,
            mu: 0.3,
        };
        let p = assemble(world, &contacts, &data).unwrap();
        let w = contact_offset(world, &contacts, &data);
        let f = free_momentum(world, h);
        let m = mass_diagonal(world);
        let v_free: Vec<f64> = f.iter().zip(&m).map(|(f, m)| f / m).collect();
        let blocks: Vec<Block> = contacts
            .iter()
            .enumerate()
            .map(|(i, c)| {
                Block::new(
                    world,
                    c,
                    [w[3 * i], w[3 * i + 1], w[3 * i + 2]],
                    0.3,
                    &v_free,
                )
                .unwrap()
            })
            .collect();
        let delassus = coulomb::delassus::Delassus::new(&p).unwrap();
        let mut wmat = std::collections::HashMap::new();
        for (i, j, x) in delassus.local.w.triplets() {
            wmat.insert((i, j), x);
        }
        let q = &delassus.local.q;
        for (i, b) in blocks.iter().enumerate() {
            for k in 0..3 {
                for l in 0..3 {
                    let exact = wmat.get(&(3 * i + k, 3 * i + l)).copied().unwrap_or(0.0);
                    assert!((b.w[3 * k + l] - exact).abs() <= 1e-9 * (1.0 + exact.abs()));
                }
                assert!((b.q[k] - q[3 * i + k]).abs() <= 1e-9);
            }
        }
        let mut r = vec![0.0; 3 * blocks.len()];
        let mut v = v_free.clone();
        let mut dv = vec![0.0; v.len()];
        let err = |r: &[f64], v: &[f64]| {
            let s = error_sums(&blocks, r, v, 1.0);
            s[0].sqrt() / s[1].sqrt().max(s[2].sqrt()).max(s[3].sqrt())
        };
        let e0 = err(&r, &v);
        for _ in 0..300 {
            sweep(&blocks, &mut r, &mut v, &mut dv);
        }
        let e1 = err(&r, &v);
        assert!(e1 < 1e-4 && e1 < e0 * 1e-2, "{e0} → {e1}");
        // v = M⁻¹ (f + H r)
        let mut imp = vec![0.0; v.len()];
        impulses(&blocks, &r, &mut imp);
        for j in 0..v.len() {
            let exact = (f[j] + imp[j]) / m[j];
            assert!((v[j] - exact).abs() <= 1e-9 * (1.0 + exact.abs()), "{j}");
            assert!((dv[j] - (v[j] - v_free[j])).abs() <= 1e-9 * (1.0 + v[j].abs()));
        }
        // and the library's error measure on the assembled problem agrees
        let u = p.velocity(&v);
        let lib = coulomb::law::error_measure(3, &p.mu, &r, &u, coulomb::law::norm(q));
        assert!(
            (lib.error - e1).abs() <= 1e-9 + 1e-6 * e1,
            "{} vs {e1}",
            lib.error
        );
    }

    #[test]
    fn inverse_of_a_3x3_block() {
        let a = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
        let b = invert3(&a).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let x: f64 = (0..3).map(|k| a[3 * i + k] * b[3 * k + j]).sum();
                assert!((x - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        assert!(invert3(&[1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 0.0, 1.0]).is_none());
    }
}
