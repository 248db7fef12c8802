//! Joints between rigid bodies (issue 53): the equality rows of the incremental problem
//! (2.10) extended as in FCLIB's global problems with equality constraints,
//!
//! ```text
//!     M v = H r + G λ + f,     u = Hᵀ v + w,     Gᵀ v + b = 0,     (uⁱ, rⁱ) ∈ C(eⁱ, μⁱ),
//! ```
//!
//! λ free (no sign, no friction). Each joint contributes a block of at most 6 rows of Gᵀ
//! (one per constrained velocity component of body A relative to body B or the world):
//!
//! | kind          | rows                                                        |
//! |---------------|-------------------------------------------------------------|
//! | `spherical`   | 3: the anchor points of A and B coincide (world axes)       |
//! | `revolute`    | 3 point rows + 2: A's axis stays along B's                  |
//! | `cylindrical` | 2: the anchors coincide across the axis + 2 axis rows       |
//! | `prismatic`   | 2 across-axis point rows + 3: relative rotation locked      |
//! | `fixed`       | 3 point rows + 3 rotation rows                              |
//!
//! # Frames
//! The anchor and the axis are given in world coordinates at the initial configuration; they
//! are stored in each body's principal frame (the world's frame for `body_b = None`), so the
//! joint moves with its bodies. The axis and its two normals t₁, t₂ are attached to body B:
//! the across-axis rows use the directions t₁, t₂ of B, and their B columns the lever arm to
//! A's anchor, so that each row is the exact time derivative of its position function C(q)
//! (t_k · (p_A − p_B), t_k · (n_B × n_A), the rotation vector of R_A R_rel⁻¹ R_Bᵀ, ...). The
//! joint coordinate (revolute: angle, prismatic: travel s = n · (p_A − p_B)) is that of A
//! relative to B: its rate is n · (ω_A − ω_B) or n · (v_A(p_A) − v_B(p_A)).
//!
//! # Drift correction
//! The rows hold Gᵀ v_{k+1} + C(q_k)/h = 0: b = C(q_k)/h carries the position error at the
//! start of the step, as the contacts' w carries their gap, so that a violation is removed
//! over the step instead of accumulating. After the position update (2.7), as the contacts'
//! penetration correction, the positions (never the velocities or λ) are projected back on
//! C(q) = 0 by Gauss–Seidel Newton steps in the metric of M (`project`).
//!
//! # Motors and limits
//! A motor is one more row on the joint coordinate's rate with b = −velocity and the impulse
//! bounded, |λ| ≤ h · max_force (a torque for a revolute joint, a force for a prismatic one):
//! clamped in the sweep. A position servo is the same row with the target rate
//! gain · (position − c_k) from the coordinate c_k at t_k (the angle error wrapped to
//! (−π, π]): below its bound the error decays as (1 − gain h)-like steps of e^(−gain t).
//! Joint friction is a row like a motor's with target rate 0 and |λ| ≤ h · friction: it
//! stops (sticks) the coordinate when that impulse suffices and brakes it otherwise. A limit lo ≤ coordinate ≤ hi is a unilateral row (λ ≥ 0, like a
//! frictionless contact), active when the coordinate is at or beyond the limit or reaches it
//! within the step at its current rate, with b = e min(u_k, 0) + (1 − e) gap/h: Newton's
//! impact law with the restitution e = `limit_restitution` on the row's rate u_k at t_k, as
//! the contacts' impact offset and gap closure (e = 0, the default: the step ends at the
//! limit; e = 1: the rate after the impact is minus the rate before).

use crate::bodies::dynamics::BodyState;
use crate::bodies::rigid::RigidError;
use parry3d_f64::math::{Rotation, Vector};

/// Kind of a joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    /// hinge: 1 rotational dof about the axis
    Revolute,
    /// ball: 3 rotational dofs
    Spherical,
    /// slider: 1 translational dof along the axis
    Prismatic,
    /// rotation about and translation along the axis
    Cylindrical,
    /// weld: no dof
    Fixed,
}

impl JointKind {
    /// The kind named `s` ("revolute", "spherical", "prismatic", "cylindrical", "fixed").
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "revolute" => Self::Revolute,
            "spherical" => Self::Spherical,
            "prismatic" => Self::Prismatic,
            "cylindrical" => Self::Cylindrical,
            "fixed" => Self::Fixed,
            _ => return None,
        })
    }
    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Revolute => "revolute",
            Self::Spherical => "spherical",
            Self::Prismatic => "prismatic",
            Self::Cylindrical => "cylindrical",
            Self::Fixed => "fixed",
        }
    }
    fn needs_axis(self) -> bool {
        matches!(self, Self::Revolute | Self::Prismatic | Self::Cylindrical)
    }
    fn has_coordinate(self) -> bool {
        matches!(self, Self::Revolute | Self::Prismatic)
    }
}

/// Default gain of a position servo (1/s): the target rate is gain · (position − coordinate),
/// so that the error decays as e^(−gain t) (time constant 0.1 s) while the force is within
/// its bound.
pub const SERVO_GAIN: f64 = 10.0;

/// A motor: a target rate of the joint coordinate (`velocity`), or a position servo
/// (`position`: target rate gain · (position − coordinate)), with a bounded force (or
/// torque). Exactly one of `velocity` and `position`; `gain` only with `position`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Motor {
    /// target rate (rad/s for a revolute joint, m/s for a prismatic one)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<f64>,
    /// target coordinate of a position servo (rad, in [−π, π], or m)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<f64>,
    /// the servo's gain (1/s, > 0; default [`SERVO_GAIN`])
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain: Option<f64>,
    /// largest torque (N m) or force (N) the motor gives, ≥ 0
    pub max_force: f64,
}

impl Motor {
    /// A motor driving the rate to `velocity` with at most `max_force`.
    pub fn with_velocity(velocity: f64, max_force: f64) -> Self {
        Self {
            velocity: Some(velocity),
            position: None,
            gain: None,
            max_force,
        }
    }
    /// A position servo to `position` with at most `max_force` (default gain).
    pub fn with_position(position: f64, max_force: f64) -> Self {
        Self {
            velocity: None,
            position: Some(position),
            gain: None,
            max_force,
        }
    }
    /// The target rate at the coordinate `c` (a revolute joint's angle error wrapped to
    /// (−π, π]).
    fn target_rate(&self, kind: JointKind, c: f64) -> f64 {
        match (self.velocity, self.position) {
            (Some(v), _) => v,
            (None, Some(p)) => {
                let mut e = p - c;
                if kind == JointKind::Revolute {
                    let tau = 2.0 * std::f64::consts::PI;
                    e -= tau * ((e + std::f64::consts::PI) / tau).floor();
                    if e <= -std::f64::consts::PI {
                        e += tau;
                    }
                }
                self.gain.unwrap_or(SERVO_GAIN) * e
            }
            (None, None) => 0.0,
        }
    }
}

/// A joint as given: bodies by index (insertion order), anchor and axis in world coordinates
/// at the initial configuration.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointDesc {
    /// the kind
    pub kind: JointKind,
    /// body A (the forces reported act on it)
    pub body_a: usize,
    /// body B, None: the world
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body_b: Option<usize>,
    /// anchor point, world, t = 0
    pub anchor: [f64; 3],
    /// axis, world, t = 0 (revolute, prismatic, cylindrical; refused for the others)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// (lo, hi) of the coordinate: angle (rad, in [−π, π]) or travel (m)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limits: Option<(f64, f64)>,
    /// motor on the coordinate
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motor: Option<Motor>,
    /// Newton restitution e ∈ [0, 1] of the limits (with `limits`; default 0: a limit
    /// stops the coordinate)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit_restitution: Option<f64>,
    /// joint friction: the largest torque (N m) or force (N) opposing the coordinate's rate,
    /// ≥ 0 (revolute and prismatic joints)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
}

/// Row slots of a joint (warm start): 0..6 the equality rows, then motor, lower, upper limit,
/// friction.
pub(crate) const SLOTS: usize = 10;
const MOTOR: usize = 6;
const LOWER: usize = 7;
const UPPER: usize = 8;
const FRICTION: usize = 9;

/// What a row's multiplier may be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RowKind {
    /// free (equality row)
    Equality,
    /// lo ≤ λ ≤ hi (a motor's impulse bound)
    Box(f64, f64),
    /// λ ≥ 0 with u ≥ 0 complementary (a limit)
    Unilateral,
}

/// A joint ready for the step (frames in the bodies' principal frames).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Joint {
    pub desc: JointDesc,
    /// anchor in A's principal frame
    ra: Vector,
    /// anchor in B's principal frame (world point for the world)
    rb: Vector,
    /// axis in B's frame, in A's frame
    nb: Vector,
    na: Vector,
    /// the normals t₁, t₂ of the axis in B's frame; t₁ in A's frame (angle reference)
    t1b: Vector,
    t2b: Vector,
    t1a: Vector,
    /// R_A⁻¹ R_B at t = 0
    rel0: Rotation,
}

fn bad(joint: usize, field: &'static str, detail: String) -> RigidError {
    RigidError::Joint {
        joint,
        field,
        detail,
    }
}

/// Position and orientation of a party of a joint (the world: origin, identity).
fn pose(bodies: &[BodyState], b: Option<usize>) -> (Vector, Rotation) {
    match b {
        Some(i) => (bodies[i].x, bodies[i].q),
        None => (Vector::ZERO, Rotation::IDENTITY),
    }
}

/// Two unit vectors normal to the unit vector n and to each other (t₁ × t₂ = n).
fn normals(n: Vector) -> (Vector, Vector) {
    let pick = if n.x.abs() < 0.6 {
        Vector::X
    } else if n.y.abs() < 0.6 {
        Vector::Y
    } else {
        Vector::Z
    };
    let t1 = (pick - n * n.dot(pick)).normalize();
    (t1, n.cross(t1))
}

impl Joint {
    /// The joint `i` of `d` on the bodies at t = 0, validated (typed errors naming the joint
    /// and the field).
    pub fn new(i: usize, d: &JointDesc, bodies: &[BodyState]) -> Result<Self, RigidError> {
        let n = bodies.len();
        if d.body_a >= n {
            return Err(bad(
                i,
                "body_a",
                format!("no body {} (the scene has {n} bodies)", d.body_a),
            ));
        }
        if let Some(b) = d.body_b {
            if b >= n {
                return Err(bad(
                    i,
                    "body_b",
                    format!("no body {b} (the scene has {n} bodies)"),
                ));
            }
            if b == d.body_a {
                return Err(bad(i, "body_b", format!("a joint of body {b} with itself")));
            }
        }
        let b_fixed = d.body_b.is_none_or(|b| bodies[b].fixed);
        if bodies[d.body_a].fixed && b_fixed {
            return Err(bad(
                i,
                "body_a",
                format!(
                    "both parties are fixed (body {} and {}): the joint has nothing to move",
                    d.body_a,
                    d.body_b
                        .map_or("the world".to_string(), |b| format!("body {b}"))
                ),
            ));
        }
        if !d.anchor.iter().all(|x| x.is_finite()) {
            return Err(bad(i, "anchor", format!("{:?} is not finite", d.anchor)));
        }
        let axis = match (d.axis, d.kind.needs_axis()) {
            (Some(a), true) => {
                let v = Vector::from_array(a);
                let len = v.length();
                if !(a.iter().all(|x| x.is_finite()) && len.is_finite() && len > 1e-12) {
                    return Err(bad(
                        i,
                        "axis",
                        format!("{a:?} is zero or not finite"),
                    ));
                }
                v / len
            }
            (None, true) => {
                return Err(bad(
                    i,
                    "axis",
                    format!("a {} joint needs an axis", d.kind.name()),
                ))
            }
            (Some(_), false) => {
                return Err(bad(
                    i,
                    "axis",
                    format!(
                        "an axis does not apply to a {} joint (revolute, prismatic and cylindrical joints have one)",
                        d.kind.name()
                    ),
                ))
            }
            (None, false) => Vector::Z,
        };
        if let Some((lo, hi)) = d.limits {
            if !d.kind.has_coordinate() {
                return Err(bad(
                    i,
                    "limits",
                    format!(
                        "limits do not apply to a {} joint (revolute: angle, prismatic: travel)",
                        d.kind.name()
                    ),
                ));
            }
            if !(lo.is_finite() && hi.is_finite()) {
                return Err(bad(i, "limits", format!("({lo}, {hi}) is not finite")));
            }
            if lo > hi {
                return Err(bad(i, "limits", format!("lo = {lo} > hi = {hi}")));
            }
            let pi = std::f64::consts::PI;
            if d.kind == JointKind::Revolute && (lo < -pi || hi > pi) {
                return Err(bad(
                    i,
                    "limits",
                    format!("angles ({lo}, {hi}) must lie in [-pi, pi]"),
                ));
            }
        }
        if let Some(f) = d.friction {
            if !d.kind.has_coordinate() {
                return Err(bad(
                    i,
                    "friction",
                    format!(
                        "friction does not apply to a {} joint (revolute and prismatic joints have it)",
                        d.kind.name()
                    ),
                ));
            }
            if !(f.is_finite() && f >= 0.0) {
                return Err(bad(i, "friction", format!("{f} must be finite and >= 0")));
            }
        }
        if let Some(e) = d.limit_restitution {
            if d.limits.is_none() {
                return Err(bad(
                    i,
                    "limit_restitution",
                    "applies to limits: give limits = (lo, hi) too".to_string(),
                ));
            }
            if !(0.0..=1.0).contains(&e) {
                return Err(bad(
                    i,
                    "limit_restitution",
                    format!("{e} must lie in [0, 1]"),
                ));
            }
        }
        if let Some(m) = d.motor {
            if !d.kind.has_coordinate() {
                return Err(bad(
                    i,
                    "motor",
                    format!(
                        "a motor does not apply to a {} joint (revolute and prismatic joints have one)",
                        d.kind.name()
                    ),
                ));
            }
            match (m.velocity, m.position) {
                (Some(_), Some(_)) => {
                    return Err(bad(
                        i,
                        "motor",
                        "velocity and position both given: a motor drives the rate (velocity) or is a position servo (position), not both".to_string(),
                    ))
                }
                (None, None) => {
                    return Err(bad(
                        i,
                        "motor",
                        "give velocity (target rate) or position (servo)".to_string(),
                    ))
                }
                (Some(v), None) => {
                    if !v.is_finite() {
                        return Err(bad(i, "motor.velocity", format!("{v} is not finite")));
                    }
                    if m.gain.is_some() {
                        return Err(bad(
                            i,
                            "motor.gain",
                            "applies to a position servo: give position instead of velocity"
                                .to_string(),
                        ));
                    }
                }
                (None, Some(p)) => {
                    let pi = std::f64::consts::PI;
                    if !p.is_finite() {
                        return Err(bad(i, "motor.position", format!("{p} is not finite")));
                    }
                    if d.kind == JointKind::Revolute && !(-pi..=pi).contains(&p) {
                        return Err(bad(
                            i,
                            "motor.position",
                            format!("angle {p} must lie in [-pi, pi]"),
                        ));
                    }
                    if let Some(g) = m.gain {
                        if !(g.is_finite() && g > 0.0) {
                            return Err(bad(
                                i,
                                "motor.gain",
                                format!("{g} must be finite and > 0"),
                            ));
                        }
                    }
                }
            }
            if !(m.max_force.is_finite() && m.max_force >= 0.0) {
                return Err(bad(
                    i,
                    "motor.max_force",
                    format!("{} must be finite and >= 0", m.max_force),
                ));
            }
        }
        let p = Vector::from_array(d.anchor);
        let (xa, qa) = pose(bodies, Some(d.body_a));
        let (xb, qb) = pose(bodies, d.body_b);
        let (t1, t2) = normals(axis);
        Ok(Self {
            desc: d.clone(),
            ra: qa.conjugate() * (p - xa),
            rb: qb.conjugate() * (p - xb),
            nb: qb.conjugate() * axis,
            na: qa.conjugate() * axis,
            t1b: qb.conjugate() * t1,
            t2b: qb.conjugate() * t2,
            t1a: qa.conjugate() * t1,
            rel0: (qa.conjugate() * qb).normalize(),
        })
    }

    /// Anchor of A, world.
    pub fn anchor_a(&self, bodies: &[BodyState]) -> Vector {
        let (x, q) = pose(bodies, Some(self.desc.body_a));
        x + q * self.ra
    }

    /// The joint coordinate (angle or travel) and its rate at the bodies' state.
    pub fn coordinate(&self, bodies: &[BodyState]) -> Option<(f64, f64)> {
        let g = self.geometry(bodies);
        let rate_row = self.coordinate_row(&g)?;
        let (ja, jb) = rate_row;
        let va = body_velocity(bodies, Some(self.desc.body_a));
        let vb = body_velocity(bodies, self.desc.body_b);
        let rate = dot6(&ja, &va) + dot6(&jb, &vb);
        let c = match self.desc.kind {
            JointKind::Revolute => {
                let u = g.qa * self.t1a;
                let w = g.qb * self.t1b;
                w.cross(u).dot(g.n).atan2(w.dot(u))
            }
            _ => g.n.dot(g.pa - g.pb),
        };
        Some((c, rate))
    }

    fn geometry(&self, bodies: &[BodyState]) -> Geometry {
        let (xa, qa) = pose(bodies, Some(self.desc.body_a));
        let (xb, qb) = pose(bodies, self.desc.body_b);
        Geometry {
            xa,
            qa,
            xb,
            qb,
            pa: xa + qa * self.ra,
            pb: xb + qb * self.rb,
            n: qb * self.nb,
            t1: qb * self.t1b,
            t2: qb * self.t2b,
        }
    }

    /// Rows (J_A, J_B) of the coordinate's rate (revolute and prismatic).
    fn coordinate_row(&self, g: &Geometry) -> Option<([f64; 6], [f64; 6])> {
        match self.desc.kind {
            JointKind::Revolute => Some((angular(g.qa, g.n, 1.0), angular(g.qb, g.n, -1.0))),
            JointKind::Prismatic => Some((
                linear(g.qa, g.pa - g.xa, g.n, 1.0),
                linear(g.qb, g.pa - g.xb, g.n, -1.0),
            )),
            _ => None,
        }
    }

    /// The equality rows at the bodies' current configuration: (slot, J_A, J_B, C).
    fn equality_rows(&self, bodies: &[BodyState]) -> Vec<(usize, [f64; 6], [f64; 6], f64)> {
        let g = self.geometry(bodies);
        let d = g.pa - g.pb;
        let mut rows = Vec::with_capacity(6);
        let point = |rows: &mut Vec<_>| {
            for (k, e) in [Vector::X, Vector::Y, Vector::Z].into_iter().enumerate() {
                rows.push((
                    k,
                    linear(g.qa, g.pa - g.xa, e, 1.0),
                    linear(g.qb, g.pb - g.xb, e, -1.0),
                    e.dot(d),
                ));
            }
        };
        let across = |rows: &mut Vec<_>| {
            for (k, t) in [g.t1, g.t2].into_iter().enumerate() {
                rows.push((
                    k,
                    linear(g.qa, g.pa - g.xa, t, 1.0),
                    linear(g.qb, g.pa - g.xb, t, -1.0),
                    t.dot(d),
                ));
            }
        };
        let align = |rows: &mut Vec<_>, slot: usize| {
            let na = g.qa * self.na;
            let c = g.n.cross(na);
            for (k, t) in [g.t1, g.t2].into_iter().enumerate() {
                rows.push((
                    slot + k,
                    angular(g.qa, t, 1.0),
                    angular(g.qb, t, -1.0),
                    t.dot(c),
                ));
            }
        };
        let lock = |rows: &mut Vec<_>, slot: usize| {
            // rotation vector φ of R_A R_rel0 R_Bᵀ (its rate is ω_A − ω_B)
            let e = (g.qa * self.rel0 * g.qb.conjugate()).normalize();
            let phi = rotation_vector(e);
            for (k, a) in [Vector::X, Vector::Y, Vector::Z].into_iter().enumerate() {
                rows.push((
                    slot + k,
                    angular(g.qa, a, 1.0),
                    angular(g.qb, a, -1.0),
                    a.dot(phi),
                ));
            }
        };
        match self.desc.kind {
            JointKind::Spherical => point(&mut rows),
            JointKind::Revolute => {
                point(&mut rows);
                align(&mut rows, 3);
            }
            JointKind::Cylindrical => {
                across(&mut rows);
                align(&mut rows, 2);
            }
            JointKind::Prismatic => {
                across(&mut rows);
                lock(&mut rows, 2);
            }
            JointKind::Fixed => {
                point(&mut rows);
                lock(&mut rows, 3);
            }
        }
        rows
    }

    /// The rows of the step at the bodies' state (t_k), with b = C/h and the motor and
    /// active limit rows; `delta`: the activation distance of the limits.
    pub fn step_rows(&self, bodies: &[BodyState], h: f64, delta: f64) -> Vec<JointRow> {
        let mut rows: Vec<JointRow> = self
            .equality_rows(bodies)
            .into_iter()
            .map(|(slot, ja, jb, c)| JointRow {
                slot,
                ja,
                jb,
                b: c / h,
                kind: RowKind::Equality,
            })
            .collect();
        let g = self.geometry(bodies);
        if let (Some((ja, jb)), Some((c, rate))) =
            (self.coordinate_row(&g), self.coordinate(bodies))
        {
            if let Some(m) = self.desc.motor {
                let bound = h * m.max_force;
                rows.push(JointRow {
                    slot: MOTOR,
                    ja,
                    jb,
                    b: -m.target_rate(self.desc.kind, c),
                    kind: RowKind::Box(-bound, bound),
                });
            }
            if let Some(f) = self.desc.friction {
                // a motor with target rate 0 and bound h · friction: the impulse that
                // opposes the coordinate's motion, sticking below it
                let bound = h * f;
                rows.push(JointRow {
                    slot: FRICTION,
                    ja,
                    jb,
                    b: 0.0,
                    kind: RowKind::Box(-bound, bound),
                });
            }
            if let Some((lo, hi)) = self.desc.limits {
                let neg = |j: [f64; 6]| j.map(|x| -x);
                let e = self.desc.limit_restitution.unwrap_or(0.0);
                for (slot, gap, sign) in [(LOWER, c - lo, 1.0), (UPPER, hi - c, -1.0)] {
                    let approach = (sign * rate).min(0.0);
                    if gap + h * approach <= delta {
                        let (ja, jb) = if sign > 0.0 {
                            (ja, jb)
                        } else {
                            (neg(ja), neg(jb))
                        };
                        // Newton's law as the contacts' (impact offset e u_k, gap closure
                        // (1 − e) g / h): e = 0 ends the step at the limit, e = 1 gives
                        // the coordinate back its approach rate
                        rows.push(JointRow {
                            slot,
                            ja,
                            jb,
                            b: e * approach + (1.0 - e) * gap / h,
                            kind: RowKind::Unilateral,
                        });
                    }
                }
            }
        }
        rows
    }

    /// The limits the coordinate is beyond: (slot, J_A, J_B, gap < 0), the rows oriented so
    /// that the gap grows along them.
    fn violated_limits(&self, bodies: &[BodyState]) -> Vec<(usize, [f64; 6], [f64; 6], f64)> {
        let Some((lo, hi)) = self.desc.limits else {
            return Vec::new();
        };
        let g = self.geometry(bodies);
        let (Some((ja, jb)), Some((c, _))) = (self.coordinate_row(&g), self.coordinate(bodies))
        else {
            return Vec::new();
        };
        let mut rows = Vec::new();
        if c < lo {
            rows.push((LOWER, ja, jb, c - lo));
        }
        if c > hi {
            rows.push((UPPER, ja.map(|x| -x), jb.map(|x| -x), hi - c));
        }
        rows
    }

    /// The rows the position projection drives to zero: the equality rows and the limits
    /// the coordinate is beyond.
    fn projection_rows(&self, bodies: &[BodyState]) -> Vec<(usize, [f64; 6], [f64; 6], f64)> {
        let mut rows = self.equality_rows(bodies);
        rows.extend(self.violated_limits(bodies));
        rows
    }

    /// The largest |C| of the equality rows and of the limits' violations.
    fn projection_error(&self, bodies: &[BodyState]) -> f64 {
        self.projection_rows(bodies)
            .iter()
            .map(|r| r.3.abs())
            .fold(0.0, f64::max)
    }

    /// The largest |C| of the equality rows (m for point rows, rad for angular ones).
    pub fn violation(&self, bodies: &[BodyState]) -> f64 {
        self.equality_rows(bodies)
            .iter()
            .map(|r| r.3.abs())
            .fold(0.0, f64::max)
    }
}

struct Geometry {
    xa: Vector,
    qa: Rotation,
    xb: Vector,
    qb: Rotation,
    pa: Vector,
    pb: Vector,
    n: Vector,
    t1: Vector,
    t2: Vector,
}

/// One row of a joint in the step.
#[derive(Debug, Clone, PartialEq)]
pub struct JointRow {
    /// slot (warm start)
    pub slot: usize,
    /// J_A (v, Ω body frame)
    pub ja: [f64; 6],
    /// J_B
    pub jb: [f64; 6],
    /// b of Gᵀ v + b
    pub b: f64,
    /// what λ may be
    pub kind: RowKind,
}

/// Row of a translational constraint along t at lever arm `arm`: (t, Rᵀ(arm × t)) · sign.
fn linear(q: Rotation, arm: Vector, t: Vector, sign: f64) -> [f64; 6] {
    let r = q.conjugate() * arm.cross(t);
    [t.x, t.y, t.z, r.x, r.y, r.z].map(|x| sign * x)
}

/// Row of a rotational constraint about the world direction a: (0, Rᵀ a) · sign.
fn angular(q: Rotation, a: Vector, sign: f64) -> [f64; 6] {
    let r = q.conjugate() * a;
    [0.0, 0.0, 0.0, r.x, r.y, r.z].map(|x| sign * x)
}

fn dot6(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    (0..6).map(|k| a[k] * b[k]).sum()
}

fn body_velocity(bodies: &[BodyState], b: Option<usize>) -> [f64; 6] {
    match b {
        Some(i) => {
            let (v, w) = (bodies[i].v, bodies[i].omega);
            [v.x, v.y, v.z, w.x, w.y, w.z]
        }
        None => [0.0; 6],
    }
}

/// The rotation vector (axis × angle, angle in [0, π]) of a unit quaternion.
fn rotation_vector(q: Rotation) -> Vector {
    let q = if q.w < 0.0 { -q } else { q };
    let v = Vector::new(q.x, q.y, q.z);
    let s = v.length();
    if s < 1e-300 {
        return Vector::ZERO;
    }
    let angle = 2.0 * s.atan2(q.w);
    v * (angle / s)
}

/// Small dense solve of W x = rhs (W symmetric positive semidefinite, k ≤ 9, row-major) by
/// Cholesky with diagonal pivoting: a row whose remaining pivot is ≤ 1e-12 · max diag(W) is
/// dependent on the others and gets x = 0 (no singular factor, no regularization).
pub fn solve_spd(w: &[f64], rhs: &[f64], k: usize) -> Vec<f64> {
    let mut a = w.to_vec();
    let mut perm: Vec<usize> = (0..k).collect();
    let dmax = (0..k).map(|i| w[i * k + i]).fold(0.0, f64::max);
    let threshold = 1e-12 * dmax;
    let mut rank = 0;
    // in-place LDLᵀ-free Cholesky on the permuted matrix
    while rank < k {
        let mut p = rank;
        for i in rank + 1..k {
            if a[perm[i] * k + perm[i]] > a[perm[p] * k + perm[p]] {
                p = i;
            }
        }
        let piv = a[perm[p] * k + perm[p]];
        if !(piv.is_finite() && piv > threshold && dmax > 0.0) {
            break;
        }
        perm.swap(rank, p);
        let r = perm[rank];
        let l = piv.sqrt();
        a[r * k + r] = l;
        for &i in &perm[rank + 1..] {
            a[i * k + r] /= l;
        }
        for (ii, &i) in perm.iter().enumerate().skip(rank + 1) {
            for &j in &perm[rank + 1..=ii] {
                a[i * k + j] -= a[i * k + r] * a[j * k + r];
                a[j * k + i] = a[i * k + j];
            }
        }
        rank += 1;
    }
    // forward, then backward substitution over the accepted rows
    let acc = &perm[..rank];
    let mut y = vec![0.0; rank];
    for (ii, &i) in acc.iter().enumerate() {
        let mut s = rhs[i];
        for (jj, &j) in acc[..ii].iter().enumerate() {
            s -= a[i * k + j] * y[jj];
        }
        y[ii] = s / a[i * k + i];
    }
    let mut x = vec![0.0; k];
    for ii in (0..rank).rev() {
        let i = acc[ii];
        let mut s = y[ii];
        for (jj, &j) in acc.iter().enumerate().skip(ii + 1) {
            s -= a[j * k + i] * x[acc[jj]];
        }
        x[i] = s / a[i * k + i];
    }
    x
}

/// Newton steps with all the joints' rows together in `project` at most.
pub const GLOBAL_NEWTON_STEPS: usize = 4;

/// One Newton step on all the joints' projection rows together: Δq = M⁻¹ Jᵀ δ with
/// (J M⁻¹ Jᵀ) δ = −C over every row of every joint (the sparse factor of
/// [`crate::step::rigid::equality`], dependent rows given no update). False, nothing moved,
/// when the factor is refused or a value is not finite.
fn global_newton_step(joints: &[Joint], bodies: &mut [BodyState]) -> bool {
    use crate::step::rigid::equality::{EqRow, EqualitySolve};
    let mass: Vec<[f64; 6]> = bodies.iter().map(BodyState::mass_block).collect();
    let moving = |p: Option<usize>| p.filter(|&i| !bodies[i].fixed);
    let mut rows = Vec::new();
    for j in joints {
        for (_, ja, jb, c) in j.projection_rows(bodies) {
            rows.push(EqRow {
                lambda: rows.len(),
                a: moving(Some(j.desc.body_a)).map(|i| (i, ja)),
                b: moving(j.desc.body_b).map(|i| (i, jb)),
                rhs: c,
            });
        }
    }
    let n = rows.len();
    let Some(eq) = EqualitySolve::new(rows, &mass) else {
        return false;
    };
    let mut dq = vec![[0.0; 6]; bodies.len()];
    let mut delta = vec![0.0; n];
    eq.update(&mass, &mut dq, &mut delta);
    if !dq.iter().flatten().all(|x| x.is_finite()) {
        return false;
    }
    for (b, d) in bodies.iter_mut().zip(&dq) {
        if b.fixed || d.iter().all(|x| *x == 0.0) {
            continue;
        }
        b.x += Vector::new(d[0], d[1], d[2]);
        b.q = crate::bodies::dynamics::integrate_orientation(b.q, Vector::new(d[3], d[4], d[5]));
    }
    true
}

/// Projects the positions of `bodies` back on the joints' equality constraints C(q) = 0:
/// first up to [`GLOBAL_NEWTON_STEPS`] Newton steps on all the rows together
/// (`global_newton_step`; one is undone and the loop left if it does not lower the largest
/// |C|), then Gauss–Seidel Newton steps: per joint, Δq = M⁻¹ Jᵀ δ with J M⁻¹ Jᵀ δ = −C
/// (translations and body-frame rotation vectors, the metric of M), sweeps until every
/// |C| ≤ `target` or 100 sweeps; a limit the coordinate is beyond is brought back to it the
/// same way. Positions only. Returns the largest |C| left.
pub(crate) fn project(joints: &[Joint], bodies: &mut [BodyState], target: f64) -> f64 {
    let error = |bodies: &[BodyState]| {
        joints
            .iter()
            .map(|j| j.projection_error(bodies))
            .fold(0.0, f64::max)
    };
    let mut worst = error(bodies);
    for _ in 0..GLOBAL_NEWTON_STEPS {
        if worst.is_nan() || worst <= target {
            break;
        }
        let saved: Vec<(Vector, Rotation)> = bodies.iter().map(|b| (b.x, b.q)).collect();
        if !global_newton_step(joints, bodies) {
            break;
        }
        let now = error(bodies);
        if now.is_nan() || now >= worst {
            for (b, (x, q)) in bodies.iter_mut().zip(saved) {
                b.x = x;
                b.q = q;
            }
            break;
        }
        worst = now;
    }
    for _ in 0..100 {
        if worst.is_nan() || worst <= target {
            break;
        }
        for j in joints {
            let rows = j.projection_rows(bodies);
            let parties = [Some(j.desc.body_a), j.desc.body_b];
            let inv = |p: Option<usize>| -> [f64; 6] {
                match p {
                    Some(i) if !bodies[i].fixed => {
                        let b = &bodies[i];
                        [
                            1.0 / b.mass,
                            1.0 / b.mass,
                            1.0 / b.mass,
                            1.0 / b.inertia[0],
                            1.0 / b.inertia[1],
                            1.0 / b.inertia[2],
                        ]
                    }
                    _ => [0.0; 6],
                }
            };
            let (ma, mb) = (inv(parties[0]), inv(parties[1]));
            let k = rows.len();
            let mut w = vec![0.0; k * k];
            for r in 0..k {
                for c in 0..k {
                    w[r * k + c] = (0..6)
                        .map(|d| {
                            rows[r].1[d] * rows[c].1[d] * ma[d]
                                + rows[r].2[d] * rows[c].2[d] * mb[d]
                        })
                        .sum();
                }
            }
            let rhs: Vec<f64> = rows.iter().map(|r| -r.3).collect();
            let x = solve_spd(&w, &rhs, k);
            for (p, m, pick) in [(parties[0], ma, 1usize), (parties[1], mb, 2usize)] {
                let Some(i) = p else { continue };
                if bodies[i].fixed {
                    continue;
                }
                let mut dq = [0.0; 6];
                for (r, row) in rows.iter().enumerate() {
                    let jr = if pick == 1 { &row.1 } else { &row.2 };
                    for d in 0..6 {
                        dq[d] += jr[d] * x[r] * m[d];
                    }
                }
                let b = &mut bodies[i];
                b.x += Vector::new(dq[0], dq[1], dq[2]);
                b.q = crate::bodies::dynamics::integrate_orientation(
                    b.q,
                    Vector::new(dq[3], dq[4], dq[5]),
                );
            }
        }
        worst = joints
            .iter()
            .map(|j| j.projection_error(bodies))
            .fold(0.0, f64::max);
    }
    worst
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn spd_solve_handles_dependent_rows() {
        // rows 0 and 2 identical: W singular; the consistent system still solves
        let w = [2.0, 1.0, 2.0, 1.0, 2.0, 1.0, 2.0, 1.0, 2.0];
        let rhs = [3.0, 3.0, 3.0];
        let x = solve_spd(&w, &rhs, 3);
        for r in 0..3 {
            let s: f64 = (0..3).map(|c| w[r * 3 + c] * x[c]).sum();
            assert!((s - rhs[r]).abs() < 1e-12, "{x:?}");
        }
        // a regular one
        let w = [4.0, 1.0, 1.0, 3.0];
        let x = solve_spd(&w, &[1.0, 2.0], 2);
        assert!((4.0 * x[0] + x[1] - 1.0).abs() < 1e-14);
        assert!((x[0] + 3.0 * x[1] - 2.0).abs() < 1e-14);
    }

    pub fn rotation_vector_of_a_quarter_turn() {
        let q = Rotation::from_axis_angle(Vector::Y, 0.5);
        let phi = rotation_vector(q);
        assert!((phi - Vector::new(0.0, 0.5, 0.0)).length() < 1e-15);
    }
}
