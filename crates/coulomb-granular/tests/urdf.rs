//! URDF import (issue 53, item 4; `coulomb_granular::urdf`): the shipped URDF double
//! pendulum builds the bodies and joints of the same scene written by hand and simulates as
//! it does; a URDF pendulum swings with the period 2π √(I/(m g d)); the collision geometries
//! map to body shapes (meshes read next to the URDF file); every bad input is refused with
//! its typed error naming the file and the element.

use coulomb_granular::model::{BodyShape, BodySpec, SceneModel};
use coulomb_granular::rigid::joint_checks::measured_period;
use coulomb_granular::rigid::joints::{JointDesc, JointKind};
use coulomb_granular::rigid::RigidSettings;
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::{BuildOptions, LoadedScene, SceneFileError};
use coulomb_granular::shape::rotate;
use coulomb_granular::urdf::{self, UrdfError, UrdfPlacement};
use coulomb_granular::Vec3;
use std::path::{Path, PathBuf};

fn rigid_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/rigid")
}

/// A scratch folder under the target's temporary directory, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let p = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("urdf-{name}"));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        Self(p)
    }
    fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join(name);
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d).unwrap();
        }
        std::fs::write(&p, text).unwrap();
        p
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Mass, world centre of mass and world inertia tensor of a body spec.
fn world_mass(b: &BodySpec) -> (f64, [f64; 3], [[f64; 3]; 3]) {
    let (mass, com, inertia) = match (b.mass, b.density) {
        (Some(m), _) if b.inertia.is_some() => {
            (m, b.centre_of_mass.unwrap_or([0.0; 3]), b.inertia.unwrap())
        }
        (Some(m), _) => {
            let p = b.shape.mass_properties(1.0).unwrap().with_mass(m);
            (m, p.local_com, p.inertia)
        }
        (None, Some(rho)) => {
            let p = b.shape.mass_properties(rho).unwrap();
            (p.mass, p.local_com, p.inertia)
        }
        _ => panic!("no mass"),
    };
    let c = rotate(b.orientation, com);
    let x = [
        b.position.x + c[0],
        b.position.y + c[1],
        b.position.z + c[2],
    ];
    let cols =
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|e| rotate(b.orientation, e));
    // R I Rᵀ with R's columns the turned axes
    let r: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| cols[j][i]));
    let w = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let mut s = 0.0;
            for k in 0..3 {
                for l in 0..3 {
                    s += r[i][k] * inertia[k][l] * r[j][l];
                }
            }
            s
        })
    });
    (mass, x, w)
}

fn close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() <= tol, "{what}: {a:?} vs {b:?}");
    }
}

fn hinge(a: usize, b: usize, anchor: [f64; 3], axis: [f64; 3]) -> JointDesc {
    JointDesc {
        kind: JointKind::Revolute,
        body_a: a,
        body_b: Some(b),
        anchor,
        axis: Some(axis),
        limits: None,
        motor: None,
        limit_restitution: None,
        friction: None,
    }
}

/// double-pendulum-urdf.toml written by hand: the base block (fixed, 1 kg) and two bars of
/// 1000 kg/m³ as cuboids at their centres, turned by q, hinged at the robot's origin and at
/// the upper bar's lower end.
fn hand_written(step: &coulomb_granular::model::StepSettings) -> SceneModel {
    let p = [0.0, 0.0, 1.2];
    let q = [0.9689124217106447, 0.0, -0.24740395925452294, 0.0];
    let at = |z: f64| {
        let d = rotate(q, [0.0, 0.0, z]);
        [p[0] + d[0], p[1] + d[1], p[2] + d[2]]
    };
    let v = |a: [f64; 3]| Vec3::new(a[0], a[1], a[2]);
    let mut base = BodySpec::new(
        BodyShape::Cuboid {
            half_extents: [0.05, 0.05, 0.025],
        },
        v(at(0.05)),
        q,
        1.0,
    );
    base.density = None;
    base.mass = Some(1.0);
    base.fixed = true;
    let bar = |z: f64| {
        BodySpec::new(
            BodyShape::Cuboid {
                half_extents: [0.02, 0.02, 0.25],
            },
            v(at(z)),
            q,
            1000.0,
        )
    };
    let axis = rotate(q, [0.0, 1.0, 0.0]);
    SceneModel {
        bodies: vec![base, bar(-0.25), bar(-0.75)],
        joints: vec![hinge(1, 0, p, axis), hinge(2, 1, at(-0.5), axis)],
        step: step.clone(),
        ..SceneModel::default()
    }
}

#[test]
fn the_urdf_double_pendulum_is_the_hand_written_one() {
    let path = rigid_dir().join("double-pendulum-urdf.toml");
    let built = LoadedScene::load(&path)
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let urdf = built.model;
    let hand = hand_written(&urdf.step);
    assert_eq!(urdf.bodies.len(), 3);
    for (k, (a, b)) in urdf.bodies.iter().zip(&hand.bodies).enumerate() {
        let (ma, xa, ia) = world_mass(a);
        let (mb, xb, ib) = world_mass(b);
        let what = format!("body {k}");
        assert!((ma - mb).abs() <= 1e-12 * mb, "{what}: mass {ma} vs {mb}");
        close(&xa, &xb, 1e-12, &format!("{what}: centre of mass"));
        for r in 0..3 {
            close(
                &ia[r],
                &ib[r],
                1e-12 * ib[0][0].abs().max(ib[2][2].abs()),
                &what,
            );
        }
        assert_eq!(a.fixed, b.fixed, "{what}");
        close(&a.orientation, &b.orientation, 1e-15, &what);
    }
    assert_eq!(urdf.joints.len(), hand.joints.len());
    for (a, b) in urdf.joints.iter().zip(&hand.joints) {
        assert_eq!((a.kind, a.body_a, a.body_b), (b.kind, b.body_a, b.body_b));
        close(&a.anchor, &b.anchor, 1e-12, "anchor");
        close(&a.axis.unwrap(), &b.axis.unwrap(), 1e-12, "axis");
        assert_eq!((a.limits, a.motor, a.friction), (None, None, None));
    }
    // both simulate, the same motion
    let mut u = RigidScene::new(&urdf).unwrap_or_else(|e| panic!("{e}"));
    let mut h = RigidScene::new(&hand).unwrap_or_else(|e| panic!("{e}"));
    let start = u.world.centres_of_mass();
    for _ in 0..300 {
        u.step().unwrap();
        h.step().unwrap();
    }
    let (xu, xh) = (u.world.centres_of_mass(), h.world.centres_of_mass());
    for k in 0..3 {
        close(&xu[k], &xh[k], 1e-9, &format!("body {k} after 300 steps"));
    }
    // the bars swung (the lower bar's centre moved by centimetres), the base stayed
    let moved = |k: usize| {
        (0..3)
            .map(|i| (xu[k][i] - start[k][i]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    assert!(moved(2) > 0.02, "{}", moved(2));
    assert_eq!(moved(0), 0.0);
    assert!(u.world.joint_drift() < 1e-6, "{}", u.world.joint_drift());
}

const PENDULUM: &str = r#"<robot name="pendulum">
  <link name="base">
    <inertial><mass value="1"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial>
    <collision><origin xyz="0 0 0.05"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
  </link>
  <link name="bar">
    <inertial>
      <origin xyz="0 0 -0.25"/>
      <mass value="0.8"/>
      <inertia ixx="0.016773333333333335" ixy="0" ixz="0" iyy="0.016773333333333335" iyz="0" izz="2.1333333333333336e-4"/>
    </inertial>
    <collision><origin xyz="0 0 -0.25"/><geometry><box size="0.04 0.04 0.5"/></geometry></collision>
  </link>
  <joint name="hinge" type="continuous">
    <parent link="base"/><child link="bar"/>
    <axis xyz="0 1 0"/>
  </joint>
</robot>
"#;

#[test]
fn a_urdf_pendulum_has_the_period_of_the_formula() {
    let dir = Scratch::new("pendulum");
    let path = dir.write("pendulum.urdf", PENDULUM);
    let placement = UrdfPlacement {
        fixed_base: true,
        ..UrdfPlacement::default()
    };
    let robot = urdf::read(&path, &placement).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(robot.links, ["base", "bar"]);
    // the bar of the simple pendulum check (joint_checks::pendulum_period): I about the
    // hinge, d = 0.25 m, amplitude 0.01 rad given as the initial angular velocity
    let (m, a, c) = (0.8, 0.02, 0.25);
    let g = coulomb_granular::world::GRAVITY;
    let i = m * (a * a + c * c) / 3.0 + m * c * c;
    let w0 = 0.01 * (m * g * c / i).sqrt();
    let mut model = SceneModel {
        bodies: robot.bodies.clone(),
        joints: robot.joints.clone(),
        ..SceneModel::default()
    };
    model.bodies[1].angular_velocity = Vec3::new(0.0, w0, 0.0);
    model.bodies[1].velocity = Vec3::new(-w0 * c, 0.0, 0.0);
    let d = RigidSettings::default();
    model.step.h = d.h;
    model.step.tol = d.tolerance;
    let mut scene = RigidScene::new(&model).unwrap_or_else(|e| panic!("{e}"));
    let period = 2.0 * std::f64::consts::PI * (i / (m * g * c)).sqrt();
    let (measured, bad) = measured_period(&mut scene.world, 0, 3.2 * period).unwrap();
    assert_eq!(bad, 0);
    let rel = (measured - period).abs() / period;
    eprintln!("URDF pendulum: period {measured} s, 2π √(I/(m g d)) = {period} s, {rel:.2e}");
    assert!(rel < 0.005, "period {measured} s vs {period} s: {rel:.2e}");
}

/// An ASCII STL of the unit cube [0, 1]³ (12 triangles, outward normals).
fn cube_stl() -> String {
    let v = |i: usize| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64];
    let tris = [
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    let mut s = String::from("solid cube\n");
    for t in tris {
        s.push_str("facet normal 0 0 0\nouter loop\n");
        for i in t {
            let p = v(i);
            s.push_str(&format!("vertex {} {} {}\n", p[0], p[1], p[2]));
        }
        s.push_str("endloop\nendfacet\n");
    }
    s.push_str("endsolid cube\n");
    s
}

const INERTIAL: &str = r#"<inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>"#;

fn link(name: &str, collision: &str) -> String {
    format!("<link name=\"{name}\">{INERTIAL}{collision}</link>")
}

fn robot(body: &str) -> String {
    format!("<robot name=\"r\">{body}</robot>")
}

fn parse(dir: &Path, text: &str) -> Result<urdf::UrdfRobot, UrdfError> {
    urdf::parse(&dir.join("robot.urdf"), text, &UrdfPlacement::default())
}

#[test]
fn collision_geometries_become_body_shapes() {
    let dir = Scratch::new("shapes");
    dir.write("meshes/cube.stl", &cube_stl());
    let text = robot(&[
        link(
            "box",
            r#"<collision><geometry><box size="0.2 0.4 0.6"/></geometry></collision>"#,
        ),
        link(
            "cylinder",
            r#"<collision><geometry><cylinder radius="0.1" length="0.5"/></geometry></collision>"#,
        ),
        link(
            "ball",
            r#"<collision><geometry><sphere radius="0.1"/></geometry></collision>"#,
        ),
        link(
            "mesh",
            r#"<collision><geometry><mesh filename="meshes/cube.stl" scale="0.1 0.2 0.3"/></geometry></collision>"#,
        ),
        link(
            "two",
            r#"<collision><origin xyz="0 0 0.1"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
               <collision><origin xyz="0 0 -0.1"/><geometry><sphere radius="0.05"/></geometry></collision>"#,
        ),
        r#"<joint name="j1" type="fixed"><parent link="box"/><child link="cylinder"/><origin xyz="1 0 0"/></joint>
           <joint name="j2" type="fixed"><parent link="box"/><child link="ball"/><origin xyz="2 0 0"/></joint>
           <joint name="j3" type="fixed"><parent link="box"/><child link="mesh"/><origin xyz="3 0 0"/></joint>
           <joint name="j4" type="prismatic"><parent link="box"/><child link="two"/><origin xyz="4 0 0" rpy="0 0 1.5707963267948966"/>
             <axis xyz="1 0 0"/><limit lower="-0.1" upper="0.2" effort="10" velocity="1"/></joint>"#
            .to_string(),
    ]
    .concat());
    let r = parse(&dir.0, &text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.links, ["box", "cylinder", "ball", "mesh", "two"]);
    // the mesh a link names is one of the run's inputs (outputs never replace it), through
    // the URDF file and through a scene file naming the URDF file
    let urdf_path = dir.write("robot.urdf", &text);
    let meshes = urdf::mesh_files(&urdf_path);
    assert_eq!(meshes, [dir.0.join("meshes/cube.stl")]);
    let scene = dir.write("scene.toml", "[[urdf]]\nfile = \"robot.urdf\"\n");
    let inputs = LoadedScene::load(&scene).unwrap().input_files();
    assert!(
        inputs.iter().any(|p| p.ends_with("meshes/cube.stl")),
        "{inputs:?}"
    );
    let s: Vec<&BodyShape> = r.bodies.iter().map(|b| &b.shape).collect();
    assert_eq!(
        s[0],
        &BodyShape::Cuboid {
            half_extents: [0.1, 0.2, 0.3]
        }
    );
    // URDF's cylinder is along z: ours (along y) turned by +90° about x
    let BodyShape::Compound { parts } = s[1] else {
        panic!("{:?}", s[1])
    };
    assert_eq!(
        parts[0].shape,
        BodyShape::Cylinder {
            radius: 0.1,
            half_height: 0.25
        }
    );
    close(
        &rotate(parts[0].orientation, [0.0, 1.0, 0.0]),
        &[0.0, 0.0, 1.0],
        1e-15,
        "cylinder axis",
    );
    // a sphere is a one-part compound (it carries the link's inertia)
    let BodyShape::Compound { parts } = s[2] else {
        panic!("{:?}", s[2])
    };
    assert_eq!(parts[0].shape, BodyShape::Sphere { radius: 0.1 });
    // the mesh: the hull of the scaled cube's 8 corners
    let BodyShape::ConvexHull { points } = s[3] else {
        panic!("{:?}", s[3])
    };
    assert!(points.contains(&[0.1, 0.2, 0.3]), "{points:?}");
    assert!(points
        .iter()
        .all(|p| p[0] <= 0.1 + 1e-12 && p[1] <= 0.2 + 1e-12 && p[2] <= 0.3 + 1e-12));
    let BodyShape::Compound { parts } = s[4] else {
        panic!("{:?}", s[4])
    };
    assert_eq!(parts.len(), 2);
    assert_eq!(parts[1].position, [0.0, 0.0, -0.1]);
    // poses, masses and joints
    assert_eq!(r.bodies[3].position, Vec3::new(3.0, 0.0, 0.0));
    assert!(r.bodies.iter().all(|b| b.mass == Some(1.0) && !b.fixed));
    let j = &r.joints[3];
    assert_eq!(
        (j.kind, j.body_a, j.body_b),
        (JointKind::Prismatic, 4, Some(0))
    );
    assert_eq!(j.limits, Some((-0.1, 0.2)));
    // the joint frame turned by 90° about z: its x axis is the world's y
    close(&j.axis.unwrap(), &[0.0, 1.0, 0.0], 1e-15, "prismatic axis");
    assert_eq!(j.anchor, [4.0, 0.0, 0.0]);
    assert!(r.joints[..3].iter().all(|j| j.kind == JointKind::Fixed));
    // the robot builds into a rigid scene
    let model = SceneModel {
        bodies: r.bodies.clone(),
        joints: r.joints.clone(),
        ..SceneModel::default()
    };
    RigidScene::new(&model).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn bad_urdf_inputs_are_refused_with_their_typed_error() {
    let dir = Scratch::new("bad");
    let placement = UrdfPlacement::default();
    // a missing file, a folder
    let e = urdf::read(&dir.0.join("none.urdf"), &placement).unwrap_err();
    assert!(matches!(&e, UrdfError::Input(i) if i.is_not_found()), "{e}");
    assert!(e.to_string().contains("none.urdf"), "{e}");
    let e = urdf::read(&dir.0, &placement).unwrap_err();
    assert!(matches!(e, UrdfError::Input(_)), "{e}");
    let good = |name: &str| {
        link(
            name,
            r#"<collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision>"#,
        )
    };
    let joint = |name: &str, kind: &str, parent: &str, child: &str| {
        format!(
            r#"<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"#
        )
    };
    let err = |text: String| parse(&dir.0, &text).unwrap_err();
    // malformed XML
    let e = err("<robot name=\"r\"><link name=\"a\">".into());
    assert!(matches!(e, UrdfError::Xml { .. }), "{e}");
    assert!(e.to_string().contains("robot.urdf"), "{e}");
    let e = err("not xml at all".into());
    assert!(matches!(e, UrdfError::Xml { .. }), "{e}");
    // elements nested deeper than a robot's: refused at once (the XML reader slows down
    // quadratically with the depth)
    let deep = format!(
        "<robot name=\"r\">{}{}</robot>",
        "<a>".repeat(200_000),
        "</a>".repeat(200_000)
    );
    let t = std::time::Instant::now();
    let e = err(deep);
    assert!(
        matches!(&e, UrdfError::Xml { message, .. } if message.contains("nested")),
        "{e}"
    );
    assert!(t.elapsed().as_secs() < 10);
    // markup in comments, CDATA and attribute values does not count
    let commented = format!(
        "<?xml version=\"1.0\"?><!-- {} --><robot name=\"r>\">{}<![CDATA[{}]]></robot>",
        "<a>".repeat(100),
        good("a"),
        "<b>".repeat(100)
    );
    parse(&dir.0, &commented).unwrap_or_else(|e| panic!("{e}"));
    // a joint naming an unknown link
    let e = err(robot(&(good("a") + &joint("j", "revolute", "a", "ghost"))));
    match &e {
        UrdfError::UnknownLink {
            joint, role, link, ..
        } => assert_eq!(
            (joint.as_str(), *role, link.as_str()),
            ("j", "child", "ghost")
        ),
        _ => panic!("{e}"),
    }
    // zero, negative mass (no <inertial>: mass 0)
    let e = err(robot(
        r#"<link name="a"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>"#,
    ));
    assert!(
        matches!(&e, UrdfError::Link { link, message, .. } if link == "a" && message.contains("mass")),
        "{e}"
    );
    let neg = r#"<link name="a"><inertial><mass value="-1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>"#;
    let e = err(robot(neg));
    assert!(
        matches!(&e, UrdfError::Link { message, .. } if message.contains("mass -1")),
        "{e}"
    );
    // an inertia that is not positive definite, one beyond the triangle inequality
    for (inertia, words) in [
        (
            r#"ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="-0.01""#,
            "positive definite",
        ),
        (
            r#"ixx="0.01" ixy="0.02" ixz="0" iyy="0.01" iyz="0" izz="0.01""#,
            "positive definite",
        ),
        (
            r#"ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.03""#,
            "triangle",
        ),
    ] {
        let text = format!(
            r#"<link name="a"><inertial><mass value="1"/><inertia {inertia}/></inertial><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>"#
        );
        let e = err(robot(&text));
        assert!(
            matches!(&e, UrdfError::Link { link, message, .. } if link == "a" && message.contains(words)),
            "{e}"
        );
    }
    // a cycle (no root; a root and a loop below no one), two parents, several roots
    let e = err(robot(
        &(good("a")
            + &good("b")
            + &joint("ab", "revolute", "a", "b")
            + &joint("ba", "revolute", "b", "a")),
    ));
    assert!(
        matches!(&e, UrdfError::Tree { message, .. } if message.contains("cycle")),
        "{e}"
    );
    let e = err(robot(
        &(good("r")
            + &good("a")
            + &good("b")
            + &joint("ab", "revolute", "a", "b")
            + &joint("ba", "revolute", "b", "a")),
    ));
    assert!(
        matches!(&e, UrdfError::Tree { message, .. } if message.contains("cycle")),
        "{e}"
    );
    let e = err(robot(
        &(good("a")
            + &good("b")
            + &good("c")
            + &joint("ac", "revolute", "a", "c")
            + &joint("bc", "revolute", "b", "c")),
    ));
    assert!(
        matches!(&e, UrdfError::Tree { message, .. } if message.contains("two parents")),
        "{e}"
    );
    let e = err(robot(&(good("a") + &good("b"))));
    assert!(
        matches!(&e, UrdfError::Tree { message, .. } if message.contains("no parent")),
        "{e}"
    );
    let e = err(robot(&(good("a") + &good("a"))));
    assert!(
        matches!(&e, UrdfError::Tree { message, .. } if message.contains("two links")),
        "{e}"
    );
    // floating and planar joints
    for kind in ["floating", "planar"] {
        let e = err(robot(
            &(good("a") + &good("b") + &joint("free", kind, "a", "b")),
        ));
        match &e {
            UrdfError::UnsupportedJoint { joint, kind: k, .. } => {
                assert_eq!((joint.as_str(), k.as_str()), ("free", kind))
            }
            _ => panic!("{e}"),
        }
        assert!(e.to_string().contains("joint 'free'"), "{e}");
    }
    // unsupported geometry: a .dae mesh, a package:// mesh, a link without collision
    let mesh = |f: &str| {
        link(
            "m",
            &format!(r#"<collision><geometry><mesh filename="{f}"/></geometry></collision>"#),
        )
    };
    let e = err(robot(&mesh("meshes/arm.dae")));
    assert!(
        matches!(&e, UrdfError::UnsupportedGeometry { link, index: 0, .. } if link == "m"),
        "{e}"
    );
    let e = err(robot(&mesh("package://arm/meshes/arm.stl")));
    assert!(
        matches!(&e, UrdfError::PackageUri { link, filename, .. } if link == "m" && filename.starts_with("package://")),
        "{e}"
    );
    assert!(e.to_string().contains("package://"), "{e}");
    let e = err(robot(&mesh("meshes/missing.stl")));
    assert!(
        matches!(&e, UrdfError::Link { link, message, .. } if link == "m" && message.contains("missing.stl")),
        "{e}"
    );
    let e = err(robot(&link("bare", "")));
    assert!(
        matches!(&e, UrdfError::Link { link, message, .. } if link == "bare" && message.contains("collision")),
        "{e}"
    );
    // limits a revolute joint cannot have, a zero axis, mimic
    let e = err(robot(
        &(good("a")
            + &good("b")
            + r#"<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/><limit lower="-6.3" upper="6.3" effort="1" velocity="1"/></joint>"#),
    ));
    assert!(
        matches!(&e, UrdfError::Joint { joint, message, .. } if joint == "j" && message.contains("[-pi, pi]")),
        "{e}"
    );
    let e = err(robot(
        &(good("a")
            + &good("b")
            + r#"<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/></joint>"#),
    ));
    assert!(
        matches!(&e, UrdfError::Joint { message, .. } if message.contains("no range of motion")),
        "{e}"
    );
    let e = err(robot(
        &(good("a")
            + &good("b")
            + r#"<joint name="j" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 0 0"/></joint>"#),
    ));
    assert!(
        matches!(&e, UrdfError::Joint { message, .. } if message.contains("axis")),
        "{e}"
    );
    // a placement that is not one
    let e = urdf::parse(
        &dir.0.join("robot.urdf"),
        &robot(&good("a")),
        &UrdfPlacement {
            orientation: [1.0, 0.0, 0.0, 0.1],
            ..UrdfPlacement::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, UrdfError::Options { .. }), "{e}");
}

#[test]
fn a_scene_file_names_its_urdf_and_is_refused_where_it_is_bad() {
    let dir = Scratch::new("scene");
    dir.write("pendulum.urdf", PENDULUM);
    // the robot after a [[bodies]] group, a [[joints]] entry naming one of its links
    let scene = dir.write(
        "scene.toml",
        "[[bodies]]\nshape = { kind = \"cuboid\", half_extents = [0.1, 0.1, 0.1] }\npositions = [[5, 0, 1]]\n\n\
         [[urdf]]\npath = \"pendulum.urdf\"\nposition = [0, 0, 2]\nfixed_base = true\n\n\
         [[joints]]\nkind = \"spherical\"\nbody_a = 0\nbody_b = 2\nanchor = [0, 0, 1.5]\n",
    );
    let built = LoadedScene::load(&scene)
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &built.model;
    assert_eq!(m.bodies.len(), 3);
    assert!(m.bodies[1].fixed && !m.bodies[2].fixed);
    assert_eq!(m.bodies[2].position, Vec3::new(0.0, 0.0, 2.0));
    assert_eq!(m.joints.len(), 2);
    assert_eq!(m.joints[0].kind, JointKind::Spherical);
    assert_eq!((m.joints[1].body_a, m.joints[1].body_b), (2, Some(1)));
    // the URDF is one of the scene's input files (outputs never replace it)
    let inputs = LoadedScene::load(&scene).unwrap().input_files();
    assert!(
        inputs.iter().any(|p| p.ends_with("pendulum.urdf")),
        "{inputs:?}"
    );
    // a bad robot: the scene file, the entry and the URDF's element named
    dir.write(
        "floating.urdf",
        &PENDULUM.replace("type=\"continuous\"", "type=\"floating\""),
    );
    let bad = dir.write("bad.toml", "[[urdf]]\nfile = \"floating.urdf\"\n");
    let e = LoadedScene::load(&bad)
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap_err();
    assert!(
        matches!(&e, SceneFileError::Urdf { key, source, .. } if key == "urdf[0]" && matches!(**source, UrdfError::UnsupportedJoint { .. })),
        "{e}"
    );
    let s = e.to_string();
    assert!(
        s.contains("bad.toml:1:1") && s.contains("floating.urdf") && s.contains("joint 'hinge'"),
        "{s}"
    );
    let missing = dir.write("missing.toml", "[[urdf]]\nfile = \"nowhere.urdf\"\n");
    let e = LoadedScene::load(&missing)
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap_err();
    assert!(
        matches!(&e, SceneFileError::Urdf { source, .. } if matches!(**source, UrdfError::Input(_))),
        "{e}"
    );
    let unknown = dir.write(
        "unknown.toml",
        "[[urdf]]\nfile = \"pendulum.urdf\"\nspeed = 1\n",
    );
    assert!(matches!(
        LoadedScene::load(&unknown),
        Err(SceneFileError::Syntax { .. })
    ));
}

/// Mutated URDF documents (bytes replaced, deleted, inserted: markup, digits, signs, `nan`,
/// `inf`) are imported or refused with a typed error, never a panic, and the imported ones
/// build a rigid scene or are refused by it.
#[test]
fn mutated_urdf_documents_are_imported_or_refused_never_a_panic() {
    use rand::{Rng, SeedableRng};
    let dir = Scratch::new("mutants");
    let shipped = std::fs::read_to_string(rigid_dir().join("double-pendulum.urdf")).unwrap();
    let alphabet: &[&str] = &[
        "<",
        ">",
        "/",
        "\"",
        "=",
        " ",
        "0",
        "1",
        "-",
        ".",
        "e9",
        "nan",
        "inf",
        "-1",
        "link",
        "joint",
        "</robot>",
        "<link name=\"a\"/>",
        "type=\"planar\"",
    ];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(53);
    let (mut imported, mut refused) = (0, 0);
    for k in 0..1500 {
        let base = if k % 2 == 0 { PENDULUM } else { &shipped };
        let mut text = base.to_string();
        for _ in 0..rng.random_range(1..4) {
            let mut at = rng.random_range(0..text.len());
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            let mut end = (at + rng.random_range(0..4)).min(text.len());
            while !text.is_char_boundary(end) {
                end -= 1;
            }
            let with = alphabet[rng.random_range(0..alphabet.len())];
            match rng.random_range(0..3) {
                0 => text.replace_range(at..end, with),
                1 => text.replace_range(at..end, ""),
                _ => text.insert_str(at, with),
            }
        }
        let placement = UrdfPlacement {
            fixed_base: k % 3 == 0,
            ..UrdfPlacement::default()
        };
        match urdf::parse(&dir.0.join("mutant.urdf"), &text, &placement) {
            Ok(r) => {
                imported += 1;
                let model = SceneModel {
                    bodies: r.bodies,
                    joints: r.joints,
                    ..SceneModel::default()
                };
                let _ = RigidScene::new(&model);
            }
            Err(e) => {
                refused += 1;
                assert!(e.to_string().contains("mutant.urdf"), "{e}");
            }
        }
    }
    // both outcomes are exercised
    assert!(
        imported > 50 && refused > 50,
        "{imported} imported, {refused} refused"
    );
}
