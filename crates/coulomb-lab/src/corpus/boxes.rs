//! The `boxes` class: rigid axis-aligned cuboids resting on a floor and on each other, each
//! face contact modelled by four contact points (the corners of the overlap rectangle), as
//! rigid-body codes do. A box has 6 dofs and a face contact 12 unknowns, so m > n and
//! W = Hᵀ M⁻¹ H is rank-deficient.
//!
//! Global problem in FCLIB convention (M v = H r + f, u = Hᵀ v + w), v = (v_b, ω_b) per box in
//! the world frame: M = diag(m_b I₃, J_b) with J_b the cuboid's principal inertia; at a point p
//! between box A (on the side the normal n points to) and box B (or the floor), each direction
//! e ∈ {n, t₁, t₂} gives the column (e, (p − c_A) × e) on A's dofs and −(e, (p − c_B) × e) on
//! B's; f = M v⁻ + h (m_b g, 0); w_N = g_p / h + e_r min(u⁻_N, 0) with u⁻ = Hᵀ v⁻, g_p a small
//! gap (positive: open, negative: penetration), e_r the restitution; w_T = 0.
//!
//! The `gyro` class: the same scenes with the gyroscopic term ω × J ω of the Newton–Euler
//! equations linearized in the time step (a Moreau–Jean step with θ = 1): its Jacobian
//! G(ω) = \[ω\]× J − \[J ω\]× enters the iteration matrix, M̂ = M + h G(ω⁻) on each box's rotational
//! block, and f = M̂ v⁻ − h ω⁻ × J ω⁻ + h (m_b g, 0). M̂ is not symmetric, so neither is
//! W = Hᵀ M̂⁻¹ H, but W has the rank of a symmetric W (6 per box): the asymmetry of real FCLIB
//! files from rigid-body codes (Siconos' RockPile_tob1: rank 743 of 1 389, relative asymmetry
//! 2.5e-3), not the full-rank perturbation of the `nonsym` class.

use super::{both_forms, Item, Preset, Rng};
use coulomb::{CscMatrix, GlobalProblem};

/// Gravity (m/s²).
const GRAVITY: f64 = 9.81;
/// Time step (s).
const H: f64 = 0.01;
/// Density (kg/m³).
const DENSITY: f64 = 1000.0;

#[derive(Debug, Clone, Copy)]
struct Cuboid {
    c: [f64; 3],
    half: [f64; 3],
}

impl Cuboid {
    fn lo(&self, k: usize) -> f64 {
        self.c[k] - self.half[k]
    }
    fn hi(&self, k: usize) -> f64 {
        self.c[k] + self.half[k]
    }
    fn mass(&self) -> f64 {
        DENSITY * 8.0 * self.half[0] * self.half[1] * self.half[2]
    }
    fn inertia(&self) -> [f64; 3] {
        let m = self.mass();
        let [a, b, c] = self.half;
        [
            m * (b * b + c * c) / 3.0,
            m * (a * a + c * c) / 3.0,
            m * (a * a + b * b) / 3.0,
        ]
    }
}

/// A face contact: box `a` on the side the normal `axis` points to, `b` the other box
/// (None: the floor), four points.
struct FaceContact {
    a: usize,
    b: Option<usize>,
    axis: usize,
    points: Vec<[f64; 3]>,
}

const EPS: f64 = 1e-9;

/// Face contacts of touching boxes (and with the floor z = 0).
fn contacts(boxes: &[Cuboid]) -> Vec<FaceContact> {
    let mut out = Vec::new();
    let rect = |a: &Cuboid, b: Option<&Cuboid>, axis: usize, at: f64| -> Option<Vec<[f64; 3]>> {
        let (k1, k2) = ((axis + 1) % 3, (axis + 2) % 3);
        let (lo1, hi1, lo2, hi2) = match b {
            Some(b) => (
                a.lo(k1).max(b.lo(k1)),
                a.hi(k1).min(b.hi(k1)),
                a.lo(k2).max(b.lo(k2)),
                a.hi(k2).min(b.hi(k2)),
            ),
            None => (a.lo(k1), a.hi(k1), a.lo(k2), a.hi(k2)),
        };
        if hi1 - lo1 <= EPS || hi2 - lo2 <= EPS {
            return None;
        }
        let mut pts = Vec::new();
        for (x1, x2) in [(lo1, lo2), (hi1, lo2), (hi1, hi2), (lo1, hi2)] {
            let mut p = [0.0; 3];
            p[axis] = at;
            p[k1] = x1;
            p[k2] = x2;
            pts.push(p);
        }
        Some(pts)
    };
    for (ia, a) in boxes.iter().enumerate() {
        if a.lo(2).abs() < EPS {
            if let Some(points) = rect(a, None, 2, 0.0) {
                out.push(FaceContact {
                    a: ia,
                    b: None,
                    axis: 2,
                    points,
                });
            }
        }
        for (ib, b) in boxes.iter().enumerate() {
            if ia == ib {
                continue;
            }
            for axis in 0..3 {
                if (a.lo(axis) - b.hi(axis)).abs() < EPS {
                    if let Some(points) = rect(a, Some(b), axis, a.lo(axis)) {
                        out.push(FaceContact {
                            a: ia,
                            b: Some(ib),
                            axis,
                            points,
                        });
                    }
                }
            }
        }
    }
    out
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The arrangements: a single box, a column, a pile (grid, touching laterally), a wall of
/// bricks in running bond (each brick on two below, touching its neighbours).
fn layout(scene: &str, rng: &mut Rng) -> Vec<Cuboid> {
    let mut out = Vec::new();
    let parse = |s: &str| -> Vec<usize> { s.split('x').filter_map(|x| x.parse().ok()).collect() };
    if scene == "single" {
        out.push(Cuboid {
            c: [0.0, 0.0, 0.1],
            half: [0.1, 0.1, 0.1],
        });
    } else if let Some(k) = scene.strip_prefix("column-") {
        let k: usize = k.parse().unwrap_or(1);
        let mut z = 0.0;
        for _ in 0..k {
            let hz = 0.05;
            out.push(Cuboid {
                c: [rng.uniform(-0.03, 0.03), rng.uniform(-0.03, 0.03), z + hz],
                half: [0.1, 0.1, hz],
            });
            z += 2.0 * hz;
        }
    } else if let Some(dims) = scene.strip_prefix("pile-") {
        let d = parse(dims);
        let (nx, ny, nz) = (d[0], d[1], d[2]);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    out.push(Cuboid {
                        c: [0.2 * i as f64, 0.2 * j as f64, 0.1 + 0.2 * k as f64],
                        half: [0.1, 0.1, 0.1],
                    });
                }
            }
        }
    } else if let Some(dims) = scene.strip_prefix("wall-") {
        let d = parse(dims);
        let (w, h) = (d[0], d[1]);
        for j in 0..h {
            let shift = if j % 2 == 1 { 0.1 } else { 0.0 };
            for i in 0..w {
                out.push(Cuboid {
                    c: [0.2 * i as f64 + shift, 0.0, 0.05 + 0.1 * j as f64],
                    half: [0.1, 0.05, 0.05],
                });
            }
        }
    }
    out
}

/// The cross-product matrix \[a\]×: \[a\]× x = a × x.
fn cross_matrix(a: [f64; 3]) -> [[f64; 3]; 3] {
    [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]]
}

/// The global problem of one scene (see the module documentation); with `gyroscopic`, M̂ and
/// f of the `gyro` class.
fn problem(
    scene: &str,
    mu: f64,
    motion: &str,
    restitution: f64,
    gyroscopic: bool,
    rng: &mut Rng,
) -> anyhow::Result<GlobalProblem> {
    let boxes = layout(scene, rng);
    anyhow::ensure!(!boxes.is_empty(), "unknown boxes scene {scene}");
    let faces = contacts(&boxes);
    let nb = boxes.len();
    let n = 6 * nb;
    // v⁻
    let mut vminus = vec![0.0; n];
    for (b, vb) in vminus.chunks_mut(6).enumerate() {
        match motion {
            "impact" => {
                vb[0] = rng.uniform(-0.1, 0.1);
                vb[1] = rng.uniform(-0.1, 0.1);
                vb[2] = -rng.uniform(0.2, 1.0);
                for x in &mut vb[3..] {
                    *x = rng.uniform(-0.5, 0.5);
                }
            }
            // the upper boxes pushed sideways
            "slide" if b + 1 > nb / 2 => {
                vb[0] = 0.5;
                vb[1] = rng.uniform(-0.2, 0.2);
            }
            _ => {}
        }
    }
    // M (M̂ with the gyroscopic term)
    let (mut mr, mut mc, mut mv) = (Vec::new(), Vec::new(), Vec::new());
    for (b, bx) in boxes.iter().enumerate() {
        let m = bx.mass();
        let j = bx.inertia();
        for k in 0..3 {
            mr.push(6 * b + k);
            mc.push(6 * b + k);
            mv.push(m);
        }
        let omega = [vminus[6 * b + 3], vminus[6 * b + 4], vminus[6 * b + 5]];
        let jw = [j[0] * omega[0], j[1] * omega[1], j[2] * omega[2]];
        let (wx, jwx) = (cross_matrix(omega), cross_matrix(jw));
        for r in 0..3 {
            for c in 0..3 {
                let g = if gyroscopic {
                    H * (wx[r][c] * j[c] - jwx[r][c])
                } else {
                    0.0
                };
                let v = if r == c { j[r] } else { 0.0 } + g;
                if v != 0.0 {
                    mr.push(6 * b + 3 + r);
                    mc.push(6 * b + 3 + c);
                    mv.push(v);
                }
            }
        }
    }
    let m = CscMatrix::from_triplets(n, n, &mr, &mc, &mv)?;
    // H
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    let mut gaps = Vec::new();
    let mut col = 0;
    for fc in &faces {
        let mut frame = [[0.0; 3]; 3];
        for (j, e) in frame.iter_mut().enumerate() {
            e[(fc.axis + j) % 3] = 1.0;
        }
        for p in &fc.points {
            for (j, e) in frame.iter().enumerate() {
                let mut put = |body: usize, sign: f64| {
                    let c = boxes[body].c;
                    let arm = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
                    let t = cross(arm, *e);
                    for k in 0..3 {
                        if e[k] != 0.0 {
                            rows.push(6 * body + k);
                            cols.push(col + j);
                            vals.push(sign * e[k]);
                        }
                        if t[k] != 0.0 {
                            rows.push(6 * body + 3 + k);
                            cols.push(col + j);
                            vals.push(sign * t[k]);
                        }
                    }
                };
                put(fc.a, 1.0);
                if let Some(b) = fc.b {
                    put(b, -1.0);
                }
            }
            // most points touch; some are slightly open or slightly penetrating
            gaps.push(match rng.below(4) {
                0 => rng.uniform(0.0, 2e-4),
                1 => -rng.uniform(0.0, 1e-4),
                _ => 0.0,
            });
            col += 3;
        }
    }
    let hmat = CscMatrix::from_triplets(n, col, &rows, &cols, &vals)?;
    let mut f = vec![0.0; n];
    m.gemv_acc(1.0, &vminus, &mut f);
    for (b, bx) in boxes.iter().enumerate() {
        f[6 * b + 2] -= H * bx.mass() * GRAVITY;
        if gyroscopic {
            let j = bx.inertia();
            let omega = [vminus[6 * b + 3], vminus[6 * b + 4], vminus[6 * b + 5]];
            let gyro = cross(omega, [j[0] * omega[0], j[1] * omega[1], j[2] * omega[2]]);
            for k in 0..3 {
                f[6 * b + 3 + k] -= H * gyro[k];
            }
        }
    }
    let uminus = hmat.mul_t_vec(&vminus);
    let mut w = vec![0.0; col];
    for (i, g) in gaps.iter().enumerate() {
        w[3 * i] = g / H + restitution * uminus[3 * i].min(0.0);
    }
    let contacts = col / 3;
    Ok(GlobalProblem::new(3, m, hmat, f, w, vec![mu; contacts])?)
}

/// Writes the class.
pub fn generate(
    preset: Preset,
    seed: u64,
    sink: &mut dyn FnMut(Item) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let cases: Vec<(&str, f64, &str)> = match preset {
        Preset::Small => vec![
            ("single", 0.5, "rest"),
            ("column-5", 0.3, "impact"),
            ("pile-2x2x2", 0.8, "rest"),
            ("wall-4x3", 0.1, "slide"),
        ],
        Preset::Full => {
            let mut v = Vec::new();
            for scene in [
                "single",
                "column-5",
                "column-10",
                "pile-3x3x3",
                "wall-10x5",
                "pile-4x4x4",
            ] {
                for mu in [0.1, 0.3, 0.6, 1.0] {
                    for motion in ["rest", "impact", "slide"] {
                        v.push((scene, mu, motion));
                    }
                }
            }
            v
        }
    };
    for (k, (scene, mu, motion)) in cases.into_iter().enumerate() {
        let restitution = if motion == "impact" { 0.3 } else { 0.0 };
        // the boxes spin only when they impact: their gyroscopic twins (same layout and v⁻);
        // not for cubes, whose J = j I makes ω × J ω = 0
        let cubes = scene == "single" || scene.starts_with("pile-");
        let classes: &[(&'static str, bool)] = if motion == "impact" && !cubes {
            &[("boxes", false), ("gyro", true)]
        } else {
            &[("boxes", false)]
        };
        for &(class, gyroscopic) in classes {
            let mut rng = Rng::new(seed.wrapping_mul(1_000_003).wrapping_add(k as u64));
            let g = problem(scene, mu, motion, restitution, gyroscopic, &mut rng)?;
            let nb = g.m.nrows / 6;
            both_forms(
                class,
                &format!("{scene}-mu{mu}-{motion}"),
                g,
                None,
                serde_json::json!({
                    "scene": scene, "boxes": nb, "mu": mu, "motion": motion,
                    "restitution": restitution, "h": H, "points_per_face": 4,
                    "gyroscopic": gyroscopic,
                }),
                sink,
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_on_the_floor_has_twelve_unknowns_and_rank_six() {
        let mut rng = Rng::new(1);
        let g = problem("single", 0.5, "rest", 0.0, false, &mut rng).unwrap();
        assert_eq!(g.h.nrows, 6);
        assert_eq!(g.h.ncols, 12);
        let w = coulomb::delassus::Delassus::new(&g).unwrap().local.w;
        assert_eq!(super::super::psd_rank(&w), 6);
        // the floor's reaction on a resting box: the normal columns sum to (0,0,4,·,·,0)
        let mut ones = vec![0.0; 12];
        for i in 0..4 {
            ones[3 * i] = 1.0;
        }
        let s = g.h.mul_vec(&ones);
        assert!((s[2] - 4.0).abs() < 1e-12 && s[0].abs() < 1e-12 && s[5].abs() < 1e-12);
    }

    #[test]
    fn a_spinning_box_has_a_non_symmetric_w_of_a_symmetric_ones_rank() {
        // the gyroscopic twin of an impact: M̂ not symmetric, W = Hᵀ M̂⁻¹ H neither, rank 6
        // per box (its skeleton reproduces it exactly); the twin without the term is
        // symmetric, and so is a cube's (J = j I: no gyroscopic term)
        let mut rng = Rng::new(4);
        let cube = problem("single", 0.5, "impact", 0.3, true, &mut rng).unwrap();
        assert_eq!(cube.m.asymmetry(), 0.0);
        for scene in ["column-5", "wall-4x3"] {
            let twin = |gyroscopic| {
                let mut rng = Rng::new(4);
                problem(scene, 0.5, "impact", 0.3, gyroscopic, &mut rng).unwrap()
            };
            let (g0, g1) = (twin(false), twin(true));
            assert_eq!(
                (g0.h.to_dense(), g0.w.clone()),
                (g1.h.to_dense(), g1.w.clone())
            );
            assert_eq!(g0.m.asymmetry(), 0.0);
            assert!(g1.m.asymmetry() > 1e-6, "M̂ asymmetry {}", g1.m.asymmetry());
            let w = coulomb::delassus::Delassus::new(&g1).unwrap().local.w;
            let (m, n) = (w.nrows, g1.m.nrows);
            assert!(w.asymmetry() > 1e-4, "W asymmetry {}", w.asymmetry());
            assert_eq!(super::super::psd_rank(&w), n);
            let sk = coulomb::skeleton::Skeleton::new(
                &w,
                3,
                m,
                1e-10,
                coulomb::deadline::Deadline::NEVER,
            )
            .unwrap();
            assert_eq!(sk.rank(), n);
            assert!(sk.residual(&w, 1500).unwrap() < 1e-10);
        }
    }

    #[test]
    fn a_running_bond_wall_touches_two_bricks_below() {
        let mut rng = Rng::new(1);
        let b = layout("wall-3x2", &mut rng);
        let faces = contacts(&b);
        // brick 3 (row 1, first) rests on bricks 0 and 1; brick 5 overhangs and rests on 2
        let on = |a: usize| {
            faces
                .iter()
                .filter(|f| f.a == a && f.axis == 2)
                .map(|f| f.b)
                .collect::<Vec<_>>()
        };
        assert_eq!(on(3), vec![Some(0), Some(1)]);
        assert_eq!(on(5), vec![Some(2)]);
        assert_eq!(on(0), vec![None]);
    }
}
