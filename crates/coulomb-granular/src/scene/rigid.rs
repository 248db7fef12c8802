//! The glue from a [`SceneModel`] with bodies of any shape to the rigid-body simulator
//! ([`crate::step::rigid::RigidWorld`]): [`RigidScene::new`].
//!
//! - every body becomes a [`RigidBodyDesc`]: its shape's parry3d shape
//!   ([`BodyShape::to_parry`]), its mass properties from the density (or, with `mass`, those
//!   of a uniform body of that mass; `inertia` replaces the tensor, `centre_of_mass` the
//!   centroid), its position, orientation
//!   (w, x, y, z), velocities and material; spheres (bodies and batches) are balls; fixed
//!   bodies stay bodies that do not move;
//! - every obstacle becomes one or more [`RigidObstacle`]s with its [`Motion`]: a plane a
//!   half-space; a box container its walls as half-spaces (without the top when open); a solid
//!   box a cuboid; a solid cylinder a parry cylinder; a solid sphere a ball; a cylinder
//!   container, a spherical container, a rectangle and a triangle mesh the triangle mesh of
//!   their surface (the one the output draws). The infinite `cylinder_inside` (rotating drum)
//!   is refused: use a finite cylinder.
//! - the step settings: h, θ, the tolerance, the sweep cap, the relaxation, the method, γ,
//!   the position correction, the gap closure and the warm start of the model's
//!   [`crate::StepSettings`] (its `projection_velocities` only as `positions_only`: the rigid
//!   correction moves positions only), the model's gravity; the rest [`RigidSettings::default`].
//!
//! The bodies keep the model's order (`bodies`, then the spheres of each batch).

use crate::bodies::rigid::{MassProperties, RigidBodyDesc, RigidObstacle};
use crate::bodies::surface::{obstacle_surface, Extent};
use crate::model::{BodyShape, BodySpec, SceneError, SceneModel};
use crate::shape::{check_quaternion, Tessellation, IDENTITY};
use crate::step::rigid::{RigidSettings, RigidStepReport, RigidWorld};
use crate::world::{Motion, Obstacle, Shape};
use crate::Vec3;
use parry3d_f64::math::Vector;
use parry3d_f64::shape::SharedShape;

/// A scene built for the rigid-body simulator, with what the outputs need.
#[derive(Debug)]
pub struct RigidScene {
    /// the simulator
    pub world: RigidWorld,
    /// the shape of each body (world order)
    pub shapes: Vec<BodyShape>,
    /// the model's obstacles (for drawing them)
    pub obstacles: Vec<Obstacle>,
    /// for each obstacle of the rigid world, the index of the model's obstacle it comes from
    pub obstacle_of: Vec<usize>,
    /// the reports of the steps taken
    pub reports: Vec<RigidStepReport>,
    /// the model the scene was built from (stored by its checkpoints,
    /// [`crate::io::rigid_checkpoint`])
    pub model: SceneModel,
}

fn arr(v: Vec3) -> [f64; 3] {
    v.to_array()
}

fn invalid(what: &str, reason: impl Into<String>) -> SceneError {
    SceneError::InvalidBody {
        what: what.to_string(),
        reason: reason.into(),
    }
}

/// Refuses the settings of `model` that the rigid-body step cannot honour (issue 52, item 3:
/// a setting means the same in every scene, or is refused, never dropped): `method =
/// "library"` with a joint that has limits, a motor or friction (bounded rows, which the
/// library does not solve). `method = "library"` otherwise ([`RigidSettings::library_only`]),
/// `relaxation` and `max_sweeps` apply as in sphere scenes; rolling friction applies to the
/// contacts of balls ([`RigidWorld`] refuses it between two bodies neither of which is a ball,
/// naming the materials and the shapes).
fn check_settings(model: &SceneModel) -> Result<(), SceneError> {
    let library = model.step.method == crate::model::StepChoice::Library;
    let bounded = |j: &crate::bodies::joints::JointDesc| {
        j.limits.is_some() || j.motor.is_some() || j.friction.is_some()
    };
    if let Some(k) = model.joints.iter().position(bounded).filter(|_| library) {
        return Err(SceneError::InvalidStep(format!(
            "method = \"library\" cannot apply to joint {k}: its limits, motor or friction are bounded rows that only nsgs solves (the library solves contacts and equality constraints); use method = \"nsgs\""
        )));
    }
    Ok(())
}

/// The index of material `name` in `table`, for the body or inlet `what` (else an error that
/// lists the materials known).
fn material_index(
    table: &crate::world::MaterialTable,
    what: &str,
    name: &str,
) -> Result<u32, SceneError> {
    table
        .index(name)
        .ok_or_else(|| SceneError::UnknownMaterial {
            what: what.to_string(),
            name: name.to_string(),
            known: table.names.join(", "),
        })
}

/// The mass properties of a body spec: from the density, or scaled to `mass`, its inertia
/// replaced by `inertia` and its centre of mass by `centre_of_mass`.
fn body_mass(b: &BodySpec, shape: &SharedShape, what: &str) -> Result<MassProperties, SceneError> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    let from =
        |rho: f64| MassProperties::from_shape(shape, rho).map_err(|e| invalid(what, e.to_string()));
    let mut m = match (b.mass, b.density) {
        (Some(m), None) if positive(m) => {
            let unit = from(1.0)?;
            let s = m / unit.mass;
            MassProperties {
                mass: m,
                local_com: unit.local_com,
                inertia: unit.inertia.map(|row| row.map(|x| x * s)),
            }
        }
        (None, Some(rho)) if positive(rho) => from(rho)?,
        (Some(m), None) => return Err(invalid(what, format!("mass {m} must be positive"))),
        (None, Some(r)) => return Err(invalid(what, format!("density {r} must be positive"))),
        (Some(_), Some(_)) => return Err(invalid(what, "give a mass or a density, not both")),
        (None, None) => return Err(invalid(what, "give a mass or a density")),
    };
    if let Some(c) = b.centre_of_mass {
        if b.shape.is_sphere() {
            return Err(invalid(
                what,
                "a sphere's centre of mass is its centre: `centre_of_mass` is for other shapes",
            ));
        }
        if b.inertia.is_none() {
            return Err(invalid(
                what,
                "`centre_of_mass` needs `inertia` (the tensor about that centre of mass)",
            ));
        }
        if !c.iter().all(|x| x.is_finite()) {
            return Err(invalid(what, format!("centre_of_mass {c:?} is not finite")));
        }
        m.local_com = c;
    }
    if let Some(i) = b.inertia {
        if b.shape.is_sphere() {
            return Err(invalid(
                what,
                "a sphere's inertia is 2/5 m R²: `inertia` is for other shapes",
            ));
        }
        m.inertia = i;
        m.check()
            .map_err(|e| invalid(what, format!("inertia: {e}")))?;
        // the principal moments of a body satisfy the triangle inequality (I₁ + I₂ ≥ I₃: the
        // mass lies in space, not beyond it); a tensor that does not is no body's
        let (p, _) = m
            .principal()
            .map_err(|e| invalid(what, format!("inertia: {e}")))?;
        let trace = p[0] + p[1] + p[2];
        for k in 0..3 {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            if a + b < c - 1e-9 * trace {
                return Err(invalid(
                    what,
                    format!(
                        "inertia: principal moments {} {} {} violate the triangle inequality ({} + {} < {}): no mass distribution has them",
                        p[0], p[1], p[2], a, b, c
                    ),
                ));
            }
        }
    }
    Ok(m)
}

fn halfspace(point: Vec3, normal: Vec3) -> (SharedShape, [f64; 3]) {
    (
        SharedShape::halfspace(Vector::new(normal.x, normal.y, normal.z).normalize()),
        arr(point),
    )
}

/// The unit quaternion (w, x, y, z) turning the y axis onto the unit vector `a`.
fn y_to(a: Vec3) -> [f64; 4] {
    let y = Vector::Y;
    let r = parry3d_f64::math::Rotation::from_rotation_arc(y, Vector::new(a.x, a.y, a.z));
    [r.w, r.x, r.y, r.z]
}

/// A parry shape with its position and orientation (w, x, y, z).
type Placed = (SharedShape, [f64; 3], [f64; 4]);

/// The parry shapes (with their positions and orientations) of one obstacle.
fn obstacle_shapes(k: usize, o: &Obstacle) -> Result<Vec<Placed>, SceneError> {
    let bad = |reason: &str| SceneError::InvalidObstacle {
        index: k,
        name: o.name.clone(),
        reason: reason.to_string(),
    };
    let surface = || -> Result<Placed, SceneError> {
        let fixed = Obstacle {
            motion: Motion::Fixed,
            ..o.clone()
        };
        let unit = Extent {
            lo: Vec3::new(-1.0, -1.0, -1.0),
            hi: Vec3::new(1.0, 1.0, 1.0),
        };
        let (pts, tris) = obstacle_surface(&fixed, 0.0, &unit);
        let v = pts.iter().map(|p| Vector::new(p.x, p.y, p.z)).collect();
        let t = tris
            .iter()
            .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
            .collect();
        let s = SharedShape::trimesh(v, t)
            .map_err(|e| bad(&format!("its surface is not a valid triangle mesh: {e:?}")))?;
        Ok((s, [0.0; 3], IDENTITY))
    };
    Ok(match &o.shape {
        Shape::Plane { point, normal } => {
            let (s, p) = halfspace(*point, *normal);
            vec![(s, p, IDENTITY)]
        }
        Shape::Box {
            lo,
            hi,
            inside: true,
            open_top,
        } => {
            let mut walls = vec![
                halfspace(*lo, Vec3::X),
                halfspace(*hi, -Vec3::X),
                halfspace(*lo, Vec3::Y),
                halfspace(*hi, -Vec3::Y),
                halfspace(*lo, Vec3::Z),
            ];
            if !open_top {
                walls.push(halfspace(*hi, -Vec3::Z));
            }
            walls.into_iter().map(|(s, p)| (s, p, IDENTITY)).collect()
        }
        Shape::Box { lo, hi, .. } => {
            let h = (*hi - *lo) * 0.5;
            vec![(
                SharedShape::cuboid(h.x, h.y, h.z),
                arr((*lo + *hi) * 0.5),
                IDENTITY,
            )]
        }
        Shape::Cylinder {
            base,
            axis,
            radius,
            height,
            inside: false,
            ..
        } => vec![(
            SharedShape::cylinder(0.5 * height, *radius),
            arr(*base + *axis * (0.5 * height)),
            y_to(*axis),
        )],
        Shape::Sphere {
            center,
            radius,
            inside: false,
        } => vec![(SharedShape::ball(*radius), arr(*center), IDENTITY)],
        Shape::CylinderInside { .. } => {
            return Err(bad(
                "an infinite cylinder (cylinder_inside) has no rigid-body counterpart: use a finite cylinder container",
            ))
        }
        Shape::Rectangle { .. }
        | Shape::Cylinder { .. }
        | Shape::Sphere { .. }
        | Shape::Mesh { .. } => vec![surface()?],
    })
}

/// What building a scene does with bodies interpenetrating at the start.
#[derive(Debug, Clone, Copy)]
enum InitialOverlaps {
    /// refused ([`crate::bodies::rigid::RigidError::Interpenetration`])
    Refuse,
    /// relaxed in at most this many sweeps, then refused if some are left
    Relax(usize),
    /// kept (a checkpoint's state replaces the world's)
    Ignore,
}

/// The rigid body of the model's body `k` (validated: shape, quaternion, finite state, a
/// fixed body at rest, mass properties, material).
fn body_desc(
    k: usize,
    b: &BodySpec,
    material: &dyn Fn(&str, &str) -> Result<u32, SceneError>,
) -> Result<RigidBodyDesc, SceneError> {
    let what = format!("body {k}");
    let shape = b
        .shape
        .to_parry()
        .map_err(|e| invalid(&what, format!("{} refused: {e}", b.shape.kind())))?;
    check_quaternion("orientation", b.orientation).map_err(|e| invalid(&what, e.to_string()))?;
    if !(b.position.is_finite() && b.velocity.is_finite() && b.angular_velocity.is_finite()) {
        return Err(invalid(
            &what,
            "non-finite position, velocity or angular velocity",
        ));
    }
    if b.fixed && (b.velocity != Vec3::ZERO || b.angular_velocity != Vec3::ZERO) {
        return Err(invalid(
            &what,
            "a fixed body cannot have a velocity (use a moving obstacle)",
        ));
    }
    let mass = body_mass(b, &shape, &what)?;
    Ok(RigidBodyDesc {
        shape,
        mass,
        position: arr(b.position),
        orientation: b.orientation,
        velocity: arr(b.velocity),
        angular_velocity: arr(b.angular_velocity),
        material: material(&what, &b.material)?,
        fixed: b.fixed,
    })
}

impl RigidScene {
    /// The rigid world of `model` (module docs), every body and obstacle validated; the
    /// world refuses bodies interpenetrating at the start (count and depth).
    pub fn new(model: &SceneModel) -> Result<Self, SceneError> {
        Ok(Self::build(model, InitialOverlaps::Refuse)?.0)
    }

    /// [`RigidScene::new`] without the check of initial interpenetrations, for a checkpoint's
    /// state to replace the world's (a run started with `--resolve-overlaps`).
    pub(crate) fn for_restore(model: &SceneModel) -> Result<Self, SceneError> {
        Ok(Self::build(model, InitialOverlaps::Ignore)?.0)
    }

    /// [`RigidScene::new`] with the bodies' initial interpenetrations relaxed first
    /// ([`crate::step::rigid::RigidWorld::relaxed`], at most `max_sweeps` sweeps; the scene is
    /// refused if some are left). The model keeps the positions as given; the world starts
    /// from the relaxed ones.
    pub fn new_relaxed(
        model: &SceneModel,
        max_sweeps: usize,
    ) -> Result<(Self, crate::step::rigid::Relaxed), SceneError> {
        let (scene, relaxed) = Self::build(model, InitialOverlaps::Relax(max_sweeps))?;
        Ok((scene, relaxed.unwrap_or_default()))
    }

    fn build(
        model: &SceneModel,
        overlaps: InitialOverlaps,
    ) -> Result<(Self, Option<crate::step::rigid::Relaxed>), SceneError> {
        model.step.check()?;
        if let Some(v) = model
            .step
            .projection_velocities
            .filter(|v| *v != crate::projection::Velocities::PositionsOnly)
        {
            let name = serde_json::to_string(&v).unwrap_or_default();
            return Err(SceneError::InvalidStep(format!(
                "projection_velocities = {name} cannot apply to a scene with bodies of other shapes than spheres: their correction moves positions only (\"positions_only\"); remove it"
            )));
        }
        let g = model.gravity;
        if !g.is_finite() {
            return Err(SceneError::InvalidGravity(g.to_array()));
        }
        // the sphere world validates materials, obstacles and sphere batches; bodies of other
        // shapes are validated here
        let spheres_only = SceneModel {
            bodies: model
                .bodies
                .iter()
                .filter(|b| b.shape.is_sphere())
                .cloned()
                .collect(),
            joints: Vec::new(),
            ..model.clone()
        };
        let sphere_world = spheres_only.world()?;
        let (table, _) = model.material_table()?;
        check_settings(model)?;
        let material = |what: &str, name: &str| material_index(&table, what, name);
        let mut bodies = Vec::new();
        let mut shapes = Vec::new();
        for (k, b) in model.bodies.iter().enumerate() {
            bodies.push(body_desc(k, b, &material)?);
            shapes.push(b.shape.clone());
        }
        for (k, batch) in model.sphere_batches.iter().enumerate() {
            let m = material(&format!("sphere batch {k}"), &batch.material)?;
            let spheres = model.spheres_of(batch)?;
            for s in spheres {
                let ball = SharedShape::ball(s.radius);
                let r2 = 0.4 * s.mass * s.radius * s.radius;
                bodies.push(RigidBodyDesc {
                    shape: ball,
                    mass: MassProperties {
                        mass: s.mass,
                        local_com: [0.0; 3],
                        inertia: [[r2, 0.0, 0.0], [0.0, r2, 0.0], [0.0, 0.0, r2]],
                    },
                    position: arr(s.position),
                    orientation: IDENTITY,
                    velocity: arr(s.velocity),
                    angular_velocity: arr(s.angular_velocity),
                    material: m,
                    fixed: batch.fixed,
                });
                shapes.push(BodyShape::Sphere { radius: s.radius });
            }
        }
        // the model's obstacles (without the sphere world's fixed-body spheres)
        let obstacles: Vec<Obstacle> = sphere_world
            .obstacles
            .iter()
            .take(model.obstacles.len())
            .enumerate()
            .map(|(k, o)| Obstacle {
                material: table
                    .index(&model.obstacles[k].material)
                    .unwrap_or(o.material),
                ..o.clone()
            })
            .collect();
        let mut rigid_obstacles = Vec::new();
        let mut obstacle_of = Vec::new();
        for (k, o) in obstacles.iter().enumerate() {
            for (j, (shape, position, orientation)) in
                obstacle_shapes(k, o)?.into_iter().enumerate()
            {
                rigid_obstacles.push(RigidObstacle {
                    name: if j == 0 {
                        o.name.clone()
                    } else {
                        format!("{}#{j}", o.name)
                    },
                    shape,
                    position,
                    orientation,
                    motion: o.motion.clone(),
                    material: o.material,
                });
                obstacle_of.push(k);
            }
        }
        let settings = RigidSettings {
            h: model.step.h,
            theta: model.step.theta,
            gravity: g.to_array(),
            tolerance: model.step.tol,
            max_sweeps: model.step.max_sweeps,
            relaxation: model.step.relaxation,
            library_only: model.step.method == crate::model::StepChoice::Library,
            activation_gamma: model.step.gamma,
            position_correction: model.step.projection,
            gap_closure: model.step.gap_closure,
            warm_start: model.step.warm_start,
            ..RigidSettings::default()
        };
        let (world, relaxed) = match overlaps {
            InitialOverlaps::Refuse => (
                RigidWorld::with_joints(bodies, rigid_obstacles, table, settings, &model.joints)
                    .map_err(SceneError::Rigid)?,
                None,
            ),
            InitialOverlaps::Ignore => (
                RigidWorld::overlapping(bodies, rigid_obstacles, table, settings, &model.joints)
                    .map_err(SceneError::Rigid)?,
                None,
            ),
            InitialOverlaps::Relax(sweeps) => {
                let (w, r) = RigidWorld::relaxed(
                    bodies,
                    rigid_obstacles,
                    table,
                    settings,
                    &model.joints,
                    sweeps,
                )
                .map_err(SceneError::Rigid)?;
                (w, Some(r))
            }
        };
        let scene = Self {
            world,
            shapes,
            obstacles,
            obstacle_of,
            reports: Vec::new(),
            model: model.clone(),
        };
        Ok((scene, relaxed))
    }

    /// Inserts `bodies` between two steps (an inlet pouring,
    /// [`crate::scene_file::InletRun::pour_rigid`]): each validated as the model's bodies are,
    /// appended to the world ([`RigidWorld::insert_bodies`]: the indices, warm-start keys and
    /// contacts of the bodies present unchanged) and to the model's `bodies`, so that a
    /// checkpoint, which rebuilds the world from its model, holds them and a restart continues
    /// to the bit. Refused, nothing inserted, when the model has sphere batches (the world
    /// numbers their spheres after `bodies`: a body appended to `bodies` would take another
    /// index when the model is rebuilt) and for the errors of the bodies. Overlaps are not
    /// checked: the caller places the bodies apart. Returns the world indices given.
    pub fn insert_bodies(
        &mut self,
        bodies: Vec<BodySpec>,
    ) -> Result<std::ops::Range<usize>, SceneError> {
        if !self.model.sphere_batches.is_empty() {
            return Err(SceneError::InvalidStep(
                "bodies cannot be inserted into a rigid scene built with sphere batches: give its spheres as bodies (BodySpec::sphere)".into(),
            ));
        }
        let (table, _) = self.model.material_table()?;
        let material = |what: &str, name: &str| material_index(&table, what, name);
        let first = self.world.len();
        let descs = bodies
            .iter()
            .enumerate()
            .map(|(k, b)| body_desc(first + k, b, &material))
            .collect::<Result<Vec<_>, _>>()?;
        let range = self.world.insert_bodies(descs).map_err(SceneError::Rigid)?;
        self.shapes.extend(bodies.iter().map(|b| b.shape.clone()));
        self.model.bodies.extend(bodies);
        Ok(range)
    }

    /// Whether this scene was built from `model`, with bodies appended since by
    /// [`RigidScene::insert_bodies`] (`model`'s inlets pouring) when `poured` is true: what a
    /// restart checks of the scene file it is given against the checkpoint.
    pub fn is_built_from(&self, model: &SceneModel, poured: bool) -> bool {
        let n = model.bodies.len();
        let m = &self.model;
        m.bodies.len() >= n
            && (poured || m.bodies.len() == n)
            && m.bodies[..n] == model.bodies[..]
            && SceneModel {
                bodies: Vec::new(),
                ..m.clone()
            } == SceneModel {
                bodies: Vec::new(),
                ..model.clone()
            }
    }

    /// One Moreau–Jean step of the rigid world; its report is kept in `reports`.
    pub fn step(&mut self) -> Result<RigidStepReport, crate::bodies::rigid::RigidError> {
        let r = self.world.step()?;
        self.reports.push(r.clone());
        Ok(r)
    }

    /// The tessellation of each body's shape in its shape frame (computed once; the output
    /// places it by the body's position and orientation each frame).
    pub fn tessellations(&self) -> Vec<Tessellation> {
        self.shapes
            .iter()
            .map(|s| s.tessellation().unwrap_or_default())
            .collect()
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::model::ObstacleSpec;

    fn floor() -> ObstacleSpec {
        ObstacleSpec::fixed(
            "floor",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        )
    }

    pub fn a_box_and_a_ball_on_the_floor_build_and_step() {
        let mut m = SceneModel::default();
        m.step.h = 1e-3;
        m.step.tol = 1e-8;
        m.obstacles.push(floor());
        let c = BodyShape::Cuboid {
            half_extents: [0.1, 0.1, 0.05],
        };
        m.bodies.push(BodySpec::new(
            c,
            Vec3::new(0.0, 0.0, 0.05),
            IDENTITY,
            1000.0,
        ));
        m.bodies
            .push(BodySpec::sphere(Vec3::new(1.0, 0.0, 0.3), 0.05, 1000.0));
        assert!(m.has_shapes());
        let mut s = RigidScene::new(&m).unwrap();
        assert_eq!(s.world.len(), 2);
        assert_eq!(s.obstacle_of, vec![0]);
        for _ in 0..20 {
            s.step().unwrap();
        }
        let p = s.world.positions();
        // the box rests (penetration < 1 % of its height), the ball falls
        assert!((p[0][2] - 0.05).abs() < 1e-3, "{:?}", p[0]);
        assert!(p[1][2] < 0.3, "{:?}", p[1]);
        assert_eq!(s.tessellations()[0].faces.len(), 6);
    }

    pub fn overrides_and_bad_bodies() {
        let c = BodyShape::Cuboid {
            half_extents: [0.1, 0.1, 0.1],
        };
        let shape = c.to_parry().unwrap();
        let mut b = BodySpec::new(c.clone(), Vec3::ZERO, IDENTITY, 1000.0);
        b.density = None;
        b.mass = Some(2.0);
        let m = body_mass(&b, &shape, "body 0").unwrap();
        assert!((m.mass - 2.0).abs() < 1e-12);
        // a cube of side 0.2 and mass 2: I = m a²/6
        assert!((m.inertia[0][0] - 2.0 * 0.04 / 6.0).abs() < 1e-12);
        b.inertia = Some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]);
        assert!(body_mass(&b, &shape, "body 0").is_err());
        // positive definite but beyond the triangle inequality (1 + 1 < 3): refused
        b.inertia = Some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 3.0]]);
        let e = body_mass(&b, &shape, "body 0").unwrap_err().to_string();
        assert!(e.contains("triangle inequality"), "{e}");
        // on the bound (a flat plate: 1 + 1 = 2) and within it: accepted
        b.inertia = Some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]]);
        assert!(body_mass(&b, &shape, "body 0").is_ok());
        b.inertia = Some([[1.0, 0.0, 0.0], [0.0, 1.5, 0.0], [0.0, 0.0, 2.0]]);
        assert!(body_mass(&b, &shape, "body 0").is_ok());
        // a non-unit orientation is refused, not normalized
        let mut model = SceneModel::default();
        let mut q = BodySpec::new(c, Vec3::new(0.0, 0.0, 1.0), [1.0, 0.0, 0.0, 0.01], 1.0);
        q.material = "default".into();
        model.bodies.push(q);
        let e = RigidScene::new(&model).unwrap_err().to_string();
        assert!(e.contains("body 0") && e.contains("unit"), "{e}");
        // bodies interpenetrating at the start: the world's typed error
        let mut model = SceneModel::default();
        let cube = BodyShape::Cuboid {
            half_extents: [0.1; 3],
        };
        for x in [0.0, 0.15] {
            model.bodies.push(BodySpec::new(
                cube.clone(),
                Vec3::new(x, 0.0, 1.0),
                IDENTITY,
                1.0,
            ));
        }
        let e = RigidScene::new(&model).unwrap_err();
        assert!(matches!(e, SceneError::Rigid(_)), "{e}");
    }
}
