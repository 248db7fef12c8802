//! The paper's examples as global problems in FCLIB convention (`M v = H r + f`,
//! `u = Hᵀ v + w`, contact blocks normal first), all in d = 2.
//!
//! - [`painleve`]: the rod of §2.2 with the data (2.12) (Examples 2.1, §5.2–§5.4);
//! - [`rectangle`]: Fig. 7, a rigid rectangle on two circular supports, one of them moving:
//!   Ker H ∩ L = {0}, so (5.1) holds (§5.7);
//! - [`moving_obstacle`]: three discs in a box moving as a rigid body (§5.6): the rigid
//!   velocity field gives Hᵀ v + w = 0, so (4.4) holds;
//! - [`crushed_ball`]: Fig. 3, a ball between the fixed ground and a plane moving towards it:
//!   (4.5) fails, no solution exists.
//!
//! Planar rigid bodies have the generalized velocity (v_x, v_y, ω). At a contact with unit
//! normal n (from body B towards body A) the tangent is t = (n_y, −n_x), and the local relative
//! velocity is u = (nᵀ(V_A − V_B), tᵀ(V_A − V_B)) where V_X is the velocity of body X at the
//! contact point; an obstacle B with prescribed velocity contributes to w only.

use crate::linalg::sparse::CscMatrix;
use crate::problem::{GlobalProblem, ProblemError};

/// Standard gravity used by the multi-body examples (pointing down, −y).
pub const GRAVITY: f64 = 9.81;
/// Time step of the multi-body examples.
pub const TIME_STEP: f64 = 0.01;

/// Painlevé's example (2.12) with m = l = h = 1 and v₀ = 0: one dof θ, one contact.
///
/// The paper's data are M = m l², f_p = −m g l h sin θ − m l² v₀, H_p = l (cos θ, sin θ)ᵀ,
/// w_p = (u₀, 0), with the first component tangential (x) and the second normal (y). In FCLIB
/// convention (normal first) this is H = l [sin θ, cos θ] (1 × 2), w = (0, u₀), f = −f_p =
/// g sin θ. `theta` is in radians, `g > 0` means gravity pointing upwards (paper's
/// convention; Example 2.1 has g = −1).
///
/// By (2.13) (for g = −1, θ ∈ ]0, π/2[) a solution exists iff u₀ ≤ 0 or tan θ > μ, which is
/// exactly (4.4) (§5.2, Fig. 4).
pub fn painleve(theta: f64, mu: f64, u0: f64, g: f64) -> Result<GlobalProblem, ProblemError> {
    check_finite(&[("theta", theta), ("u0", u0), ("g", g)])?;
    let (m, l, h, v0) = (1.0, 1.0, 1.0, 0.0);
    let mass = CscMatrix::from_dense(1, 1, &[m * l * l]);
    let hmat = CscMatrix::from_dense(1, 2, &[l * theta.sin(), l * theta.cos()]);
    let f_p = -m * g * l * h * theta.sin() - m * l * l * v0;
    GlobalProblem::new(2, mass, hmat, vec![-f_p], vec![0.0, u0], vec![mu])
}

/// Fig. 7: a rigid rectangle (mass 1, width 2, height 0.5) resting on two circular supports
/// touching its bottom face at x = ∓0.75 from its centre. The left support is fixed, the right
/// one moves rigidly with `support_velocity` = (s_x, s_y). Gravity acts downwards.
///
/// Both normals are vertical, so the columns of H are n₁ = (0, 1, −0.75), t₁ = (1, 0, 0.25),
/// n₂ = (0, 1, 0.75), t₂ = (1, 0, 0.25): H r = 0 forces r_N = 0 at both contacts, and an
/// impulse of L with r_N = 0 is 0. Hence Ker H ∩ L = {0} (5.1) for every μ, while
/// Ker H = {(0, s, 0, −s)} ≠ {0}: contact forces are not unique (§5.7).
pub fn rectangle(mu: f64, support_velocity: [f64; 2]) -> Result<GlobalProblem, ProblemError> {
    check_finite(&[
        ("support_velocity[0]", support_velocity[0]),
        ("support_velocity[1]", support_velocity[1]),
    ])?;
    let (a, b, c) = (1.0, 0.25, 0.75);
    let mut sys = Planar::default();
    let rect = sys.body(1.0, (a * a + b * b) / 3.0);
    sys.contact(rect, [-c, -b], None, [0.0, 1.0], [0.0, 0.0], mu);
    sys.contact(rect, [c, -b], None, [0.0, 1.0], support_velocity, mu);
    sys.build()
}

/// §5.6: three discs (radius 1, mass 1) in a box [0, 4] × [0, 4] that moves as one rigid body
/// with translational velocity `box_velocity` and angular velocity `box_omega` about its
/// centre (2, 2). Discs 0 and 1 rest on the floor against the left and right walls and touch
/// each other; disc 2 sits on top of both. Seven contacts, nine dofs.
///
/// Moving every disc with the box's rigid field gives Hᵀ v + w = 0 ∈ L*, so (4.4) holds
/// whatever the box motion and μ; with a motionless box w = 0.
pub fn moving_obstacle(
    mu: f64,
    box_velocity: [f64; 2],
    box_omega: f64,
) -> Result<GlobalProblem, ProblemError> {
    check_finite(&[
        ("box_velocity[0]", box_velocity[0]),
        ("box_velocity[1]", box_velocity[1]),
        ("box_omega", box_omega),
    ])?;
    let r = 1.0;
    let centre = [2.0, 2.0];
    let centres = [[1.0, 1.0], [3.0, 1.0], [2.0, 1.0 + 3f64.sqrt()]];
    let obstacle_velocity = |p: [f64; 2]| -> [f64; 2] {
        [
            box_velocity[0] - box_omega * (p[1] - centre[1]),
            box_velocity[1] + box_omega * (p[0] - centre[0]),
        ]
    };
    let mut sys = Planar::default();
    let discs: Vec<usize> = centres.iter().map(|_| sys.body(1.0, 0.5 * r * r)).collect();
    // Walls: (disc, normal from the wall into the disc).
    let walls = [
        (0usize, [0.0, 1.0]),
        (0, [1.0, 0.0]),
        (1, [0.0, 1.0]),
        (1, [-1.0, 0.0]),
    ];
    for (k, n) in walls {
        let offset = [-r * n[0], -r * n[1]];
        let point = [centres[k][0] + offset[0], centres[k][1] + offset[1]];
        sys.contact(discs[k], offset, None, n, obstacle_velocity(point), mu);
    }
    // Disc–disc contacts (A, B), normal from B to A.
    for (a, b) in [(1usize, 0usize), (2, 0), (2, 1)] {
        let d = [centres[a][0] - centres[b][0], centres[a][1] - centres[b][1]];
        let len = d[0].hypot(d[1]);
        let n = [d[0] / len, d[1] / len];
        sys.contact(
            discs[a],
            [-r * n[0], -r * n[1]],
            Some((discs[b], [r * n[0], r * n[1]])),
            n,
            [0.0, 0.0],
            mu,
        );
    }
    sys.build()
}

/// Fig. 3: a ball (radius 1, mass 1) between the fixed ground (contact 0, normal +y) and a
/// rigid plane above it moving down towards the ground with speed `u0 > 0` (contact 1, normal
/// −y). Whatever v, u₀_N + u₁_N = −u₀ < 0: penetration cannot be prevented, (4.5) fails with
/// the Farkas vector y = (½, ½) and no solution exists.
pub fn crushed_ball(mu: f64, u0: f64) -> Result<GlobalProblem, ProblemError> {
    check_finite(&[("u0", u0)])?;
    let mut sys = Planar::default();
    let ball = sys.body(1.0, 0.5);
    sys.contact(ball, [0.0, -1.0], None, [0.0, 1.0], [0.0, 0.0], mu);
    sys.contact(ball, [0.0, 1.0], None, [0.0, -1.0], [0.0, -u0], mu);
    sys.build()
}

fn check_finite(values: &[(&'static str, f64)]) -> Result<(), ProblemError> {
    for &(what, x) in values {
        if !x.is_finite() {
            return Err(ProblemError::NonFinite {
                what,
                location: format!("value {x}"),
            });
        }
    }
    Ok(())
}

/// A small assembler of planar rigid-body systems: bodies with dofs (v_x, v_y, ω), contacts
/// with a prescribed obstacle velocity.
#[derive(Default)]
struct Planar {
    /// (mass, moment of inertia) per body
    bodies: Vec<(f64, f64)>,
    /// H triplets (row = dof, col = contact component)
    rows: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
    w: Vec<f64>,
    mu: Vec<f64>,
}

impl Planar {
    fn body(&mut self, mass: f64, inertia: f64) -> usize {
        self.bodies.push((mass, inertia));
        self.bodies.len() - 1
    }

    /// d(dirᵀ V_p)/d(v_x, v_y, ω) for the point at offset p from the body's centre:
    /// V_p = v + ω (−p_y, p_x).
    fn jacobian(p: [f64; 2], dir: [f64; 2]) -> [f64; 3] {
        [dir[0], dir[1], -dir[0] * p[1] + dir[1] * p[0]]
    }

    /// A contact of body `a` (contact point at offset `pa`) with either body `b` (offset `pb`)
    /// or an obstacle whose velocity at the contact point is `obstacle_velocity`.
    fn contact(
        &mut self,
        a: usize,
        pa: [f64; 2],
        b: Option<(usize, [f64; 2])>,
        n: [f64; 2],
        obstacle_velocity: [f64; 2],
        mu: f64,
    ) {
        let t = [n[1], -n[0]];
        let col0 = self.w.len();
        for (k, dir) in [n, t].into_iter().enumerate() {
            for (dof, x) in Self::jacobian(pa, dir).into_iter().enumerate() {
                self.push(3 * a + dof, col0 + k, x);
            }
            if let Some((b, pb)) = b {
                for (dof, x) in Self::jacobian(pb, dir).into_iter().enumerate() {
                    self.push(3 * b + dof, col0 + k, -x);
                }
            }
            self.w
                .push(-(dir[0] * obstacle_velocity[0] + dir[1] * obstacle_velocity[1]));
        }
        self.mu.push(mu);
    }

    fn push(&mut self, row: usize, col: usize, x: f64) {
        if x != 0.0 {
            self.rows.push(row);
            self.cols.push(col);
            self.vals.push(x);
        }
    }

    /// M = diag(m, m, I) per body; f = h F with gravity F = (0, −m g, 0) and v₀ = 0.
    fn build(self) -> Result<GlobalProblem, ProblemError> {
        let n = 3 * self.bodies.len();
        let mut diag = Vec::with_capacity(n);
        let mut f = Vec::with_capacity(n);
        for &(m, i) in &self.bodies {
            diag.extend([m, m, i]);
            f.extend([0.0, -TIME_STEP * m * GRAVITY, 0.0]);
        }
        let idx: Vec<usize> = (0..n).collect();
        let mass = CscMatrix::from_triplets(n, n, &idx, &idx, &diag)
            .map_err(|source| ProblemError::Sparse { what: "M", source })?;
        let h = CscMatrix::from_triplets(n, self.w.len(), &self.rows, &self.cols, &self.vals)
            .map_err(|source| ProblemError::Sparse { what: "H", source })?;
        GlobalProblem::new(2, mass, h, f, self.w, self.mu)
    }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    pub fn painleve_matches_paper_data() {
        let th = 0.3;
        let p = painleve(th, 0.5, 1.0, -1.0).unwrap();
        let (hp, fp) = p.to_paper();
        // H_p = (cos θ, sin θ)ᵀ in the paper's (x, y) order = (tangent, normal); ours is normal first.
        assert_eq!(hp.to_dense(), vec![th.sin(), th.cos()]);
        assert!((fp[0] - th.sin()).abs() < 1e-15); // f_p = −m g l h sin θ with g = −1
        assert_eq!(p.w, vec![0.0, 1.0]);
        // u = Hᵀ v + w: normal l sin θ v, tangent l cos θ v + u₀.
        let u = p.velocity(&[2.0]);
        assert!((u[0] - 2.0 * th.sin()).abs() < 1e-15);
        assert!((u[1] - (2.0 * th.cos() + 1.0)).abs() < 1e-15);
    }

    pub fn rigid_box_motion_gives_zero_relative_velocity() {
        let (vb, om) = ([0.3, -0.2], 0.7);
        let p = moving_obstacle(0.4, vb, om).unwrap();
        let centres = [[1.0, 1.0], [3.0, 1.0], [2.0, 1.0 + 3f64.sqrt()]];
        let mut v = Vec::new();
        for c in centres {
            v.extend([vb[0] - om * (c[1] - 2.0), vb[1] + om * (c[0] - 2.0), om]);
        }
        let u = p.velocity(&v);
        assert!(u.iter().all(|x| x.abs() < 1e-14), "{u:?}");
        assert_eq!(p.contacts(), 7);
    }

    pub fn crushed_ball_normals_sum_to_minus_u0() {
        let p = crushed_ball(0.3, 2.0).unwrap();
        for v in [[0.0, 0.0, 0.0], [1.0, -3.0, 0.5], [0.0, 5.0, 2.0]] {
            let u = p.velocity(&v);
            assert!((u[0] + u[2] + 2.0).abs() < 1e-14);
        }
    }

    pub fn bad_arguments_are_errors() {
        assert!(painleve(f64::NAN, 0.5, 1.0, -1.0).is_err());
        assert!(painleve(0.5, -0.5, 1.0, -1.0).is_err());
        assert!(crushed_ball(0.3, f64::INFINITY).is_err());
    }
}
