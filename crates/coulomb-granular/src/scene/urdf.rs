//! URDF import (issue 53, item 4): a robot's links become bodies of the scene model and its
//! joints joints, read by our own reader of the URDF elements used here
//! (`scene/urdf_reader.rs`, on `quick-xml`'s event reader).
//!
//! # Mapping (docs/joints.md, "URDF import")
//! - each `<link>` is a body, in the order of the file's links: its shape frame is the link
//!   frame; `inertial` gives the mass, the centre of mass (the inertial origin's `xyz`) and the
//!   inertia tensor (turned from the inertial frame, `rpy`, into the link frame); its
//!   `<collision>` elements give the shape: `box` (a cuboid), `cylinder` and `capsule` (axis
//!   z in URDF, y in ours: turned by +90° about x), `sphere`, and `mesh` (an `.stl` or `.obj`
//!   file, its `scale` applied, as the convex hull of its vertices); one element at the link
//!   origin is the shape itself (a sphere always becomes a one-part compound: a sphere body
//!   has no inertia of its own), several (or one placed by its `origin`) a compound;
//! - `revolute` and `continuous` joints are revolute joints, `prismatic` prismatic, `fixed`
//!   fixed (and `spherical`, a type some URDF readers accept, spherical); body A is the child link,
//!   body B the parent, so that the joint coordinate is the child's relative to its parent
//!   as in URDF; the anchor is the joint frame's origin (the child link's) and the axis the
//!   joint's `axis` in the world, at the zero configuration. `limit lower/upper` become the
//!   limits (revolute: within [−π, π]; URDF 1.2's omitted bounds are ±π for a revolute joint,
//!   none when both are omitted); `effort` and `velocity` are an actuator's bounds, not a
//!   motor, and are not used; `dynamics friction` is the joint's friction;
//! - the world pose of each link at the zero configuration composes the joints' `origin`
//!   (xyz, then the fixed-axis roll–pitch–yaw rotation R = R_z(yaw) R_y(pitch) R_x(roll))
//!   from the root, placed at `position` and turned by `orientation`; the root link is free,
//!   or fixed (`fixed_base`).
//!
//! # Refused ([`UrdfError`], each naming the file and the element)
//! A missing, non-regular or oversized file; malformed XML or a document the reader refuses (a
//! missing required element or attribute, a number that does not parse, an unknown joint type
//! or geometry: `scene/urdf_reader.rs`),
//! elements nested deeper than [`MAX_DEPTH`];
//! two links of one name; a joint naming an unknown link; a link with two parents; a cycle, no
//! root or several roots; `floating` and `planar` joints; a link with no `inertial`
//! (zero mass), a non-positive or non-finite mass, an inertia tensor that is not symmetric
//! positive definite or violates the triangle inequality of principal moments; a link with no
//! `<collision>`; a mesh named by `package://` (no ROS package path here), or not `.stl` /
//! `.obj`, or unreadable; non-finite numbers, zero axes; revolute limits beyond [−π, π] or
//! with lower = upper (a revolute joint without `<limit>`), a one-sided prismatic limit;
//! `mimic` joints and nonzero `dynamics damping` (not modelled).

use super::urdf_reader::{self as reader, Geometry};
use crate::bodies::joints::{JointDesc, JointKind};
use crate::bodies::rigid::MassProperties;
use crate::import::{self, Scale, Transform};
use crate::model::{BodyShape, BodySpec, CompoundPart};
use crate::shape::{check_quaternion, IDENTITY};
use crate::Vec3;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Why a URDF file could not be imported.
#[derive(Debug, thiserror::Error)]
pub enum UrdfError {
    /// the path is not a regular file of bounded size, or cannot be opened or read
    /// ([`coulomb::input`])
    #[error(transparent)]
    Input(#[from] coulomb::input::InputError),
    /// the XML is malformed, or the document is not the URDF the reader reads
    /// (`scene/urdf_reader.rs`); the message names the line
    #[error("{}: not a valid URDF document: {message}", path.display())]
    Xml {
        /// the URDF file
        path: PathBuf,
        /// the parser's message
        message: String,
    },
    /// a link's data are refused (mass, inertia, shape, mesh)
    #[error("{}: link '{link}': {message}", path.display())]
    Link {
        /// the URDF file
        path: PathBuf,
        /// the link's name
        link: String,
        /// what is wrong
        message: String,
    },
    /// a joint's data are refused (unknown link, axis, limits, …)
    #[error("{}: joint '{joint}': {message}", path.display())]
    Joint {
        /// the URDF file
        path: PathBuf,
        /// the joint's name
        joint: String,
        /// what is wrong
        message: String,
    },
    /// a joint names a link the file does not have
    #[error("{}: joint '{joint}': its {role} link '{link}' is not a link of the robot", path.display())]
    UnknownLink {
        /// the URDF file
        path: PathBuf,
        /// the joint's name
        joint: String,
        /// "parent" or "child"
        role: &'static str,
        /// the name it gives
        link: String,
    },
    /// a joint of a kind that has no counterpart here (`floating`, `planar`)
    #[error("{}: joint '{joint}': a {kind} joint cannot be imported (revolute, continuous, prismatic, fixed and spherical joints can); for a free root link leave fixed_base false", path.display())]
    UnsupportedJoint {
        /// the URDF file
        path: PathBuf,
        /// the joint's name
        joint: String,
        /// its type
        kind: String,
    },
    /// a collision geometry that has no counterpart here
    #[error("{}: link '{link}': collision {index}: {message}", path.display())]
    UnsupportedGeometry {
        /// the URDF file
        path: PathBuf,
        /// the link's name
        link: String,
        /// the collision element's index in the link
        index: usize,
        /// what is not supported
        message: String,
    },
    /// a mesh named by a ROS package URI
    #[error("{}: link '{link}': collision {index}: mesh '{filename}': package:// URIs are not resolved (there is no ROS package path here); give the mesh's path relative to the URDF file", path.display())]
    PackageUri {
        /// the URDF file
        path: PathBuf,
        /// the link's name
        link: String,
        /// the collision element's index in the link
        index: usize,
        /// the mesh's filename as written
        filename: String,
    },
    /// the links and joints are not one tree (a link with two parents, a cycle, several
    /// roots, two links of one name, no link)
    #[error("{}: {message}", path.display())]
    Tree {
        /// the URDF file
        path: PathBuf,
        /// what is wrong
        message: String,
    },
    /// the placement asked for is invalid
    #[error("{}: {message}", path.display())]
    Options {
        /// the URDF file
        path: PathBuf,
        /// what is wrong
        message: String,
    },
}

fn origin() -> [f64; 3] {
    [0.0; 3]
}
fn identity() -> [f64; 4] {
    IDENTITY
}
fn default_material() -> String {
    crate::model::DEFAULT_MATERIAL.to_string()
}

/// Where and how a robot is placed: the same meaning in a scene file's `[[urdf]]` and in
/// Python's `Scene.add_urdf`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UrdfPlacement {
    /// world position of the root link's frame (m)
    #[serde(default = "origin")]
    pub position: [f64; 3],
    /// unit quaternion (w, x, y, z) turning the root link's frame into the world's
    /// (default identity; refused when not of unit norm)
    #[serde(default = "identity")]
    pub orientation: [f64; 4],
    /// the root link fixed to the world (default false: free)
    #[serde(default)]
    pub fixed_base: bool,
    /// the material of every link
    #[serde(default = "default_material")]
    pub material: String,
}

impl Default for UrdfPlacement {
    fn default() -> Self {
        Self {
            position: origin(),
            orientation: identity(),
            fixed_base: false,
            material: default_material(),
        }
    }
}

/// A robot read from a URDF file: one body per link (the file's order) and its joints, the
/// bodies numbered from 0 ([`UrdfRobot::joints_from`] renumbers them).
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfRobot {
    /// the robot's name
    pub name: String,
    /// the links' names, one per body
    pub links: Vec<String>,
    /// the bodies
    pub bodies: Vec<BodySpec>,
    /// the joints (body A: the child link, body B: the parent)
    pub joints: Vec<JointDesc>,
}

impl UrdfRobot {
    /// The joints with their body indices shifted by `first` (the index of the robot's
    /// first body in the scene).
    pub fn joints_from(&self, first: usize) -> Vec<JointDesc> {
        self.joints
            .iter()
            .map(|j| JointDesc {
                body_a: j.body_a + first,
                body_b: j.body_b.map(|b| b + first),
                ..j.clone()
            })
            .collect()
    }
}

/// Quaternion product a b (w, x, y, z).
fn qmul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The unit quaternion of URDF's roll–pitch–yaw: R = R_z(yaw) R_y(pitch) R_x(roll).
fn rpy_quaternion(rpy: [f64; 3]) -> [f64; 4] {
    let half = |a: f64| (0.5 * a).sin_cos();
    let (sr, cr) = half(rpy[0]);
    let (sp, cp) = half(rpy[1]);
    let (sy, cy) = half(rpy[2]);
    let qx = [cr, sr, 0.0, 0.0];
    let qy = [cp, 0.0, sp, 0.0];
    let qz = [cy, 0.0, 0.0, sy];
    qmul(qz, qmul(qy, qx))
}

/// The rotation matrix of a unit quaternion.
fn matrix(q: [f64; 4]) -> [[f64; 3]; 3] {
    let c = |v| crate::shape::rotate(q, v);
    let (x, y, z) = (c([1.0, 0.0, 0.0]), c([0.0, 1.0, 0.0]), c([0.0, 0.0, 1.0]));
    std::array::from_fn(|r| [x[r], y[r], z[r]])
}

/// A pose: translation and rotation (w, x, y, z).
#[derive(Debug, Clone, Copy)]
struct Pose {
    p: [f64; 3],
    q: [f64; 4],
}

impl Pose {
    fn of(o: &reader::Origin) -> Self {
        Self {
            p: o.xyz,
            q: match o.quat_xyzw {
                Some([x, y, z, w]) => [w, x, y, z],
                None => rpy_quaternion(o.rpy),
            },
        }
    }
    /// self ∘ other: `other` expressed in `self`'s frame, in the frame `self` is in.
    fn then(&self, other: &Pose) -> Pose {
        let r = crate::shape::rotate(self.q, other.p);
        Pose {
            p: [self.p[0] + r[0], self.p[1] + r[1], self.p[2] + r[2]],
            q: normalized(qmul(self.q, other.q)),
        }
    }
    fn is_identity(&self) -> bool {
        self.p == [0.0; 3] && self.q == IDENTITY
    }
}

fn normalized(q: [f64; 4]) -> [f64; 4] {
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.map(|x| x / n)
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The quaternion turning y onto z: +90° about x (URDF's cylinders and capsules are along z,
/// ours along y).
const Y_TO_Z: [f64; 4] = [
    std::f64::consts::FRAC_1_SQRT_2,
    std::f64::consts::FRAC_1_SQRT_2,
    0.0,
    0.0,
];

pub use super::urdf_reader::MAX_DEPTH;

/// Refuses a document whose elements nest deeper than [`MAX_DEPTH`], by one linear scan of
/// its tags (comments, CDATA, processing instructions and declarations skipped, quoted
/// attribute values respected); malformed markup is left to the XML reader.
fn nesting(text: &str) -> Result<(), String> {
    let b = text.as_bytes();
    let find = |from: usize, pat: &[u8]| {
        b[from.min(b.len())..]
            .windows(pat.len())
            .position(|w| w == pat)
            .map(|k| from + k + pat.len())
    };
    let (mut i, mut depth, mut line) = (0, 0usize, 1usize);
    while i < b.len() {
        if b[i] == b'\n' {
            line += 1;
        }
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &b[i..];
        let end = if rest.starts_with(b"<!--") {
            find(i + 4, b"-->")
        } else if rest.starts_with(b"<![CDATA[") {
            find(i + 9, b"]]>")
        } else if rest.starts_with(b"<?") {
            find(i + 2, b"?>")
        } else if rest.starts_with(b"<!") || rest.starts_with(b"</") {
            if rest.starts_with(b"</") {
                depth = depth.saturating_sub(1);
            }
            find(i + 1, b">")
        } else {
            // a start tag: to its '>' outside quotes; `/>` closes it at once
            let mut j = i + 1;
            let mut quote = None;
            while j < b.len() {
                match (quote, b[j]) {
                    (None, b'"' | b'\'') => quote = Some(b[j]),
                    (Some(q), c) if c == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if j < b.len() && b[j - 1] != b'/' {
                depth += 1;
                if depth > MAX_DEPTH {
                    return Err(format!(
                        "line {line}: elements nested more than {MAX_DEPTH} deep (a URDF robot is about 5 deep)"
                    ));
                }
            }
            (j < b.len()).then_some(j + 1)
        };
        let next = end.unwrap_or(b.len());
        line += b[i..next].iter().filter(|&&c| c == b'\n').count();
        i = next;
    }
    Ok(())
}

/// Reads the URDF file `path` (a regular file of at most 16 MiB, [`coulomb::input`]); mesh
/// files it names are resolved against its folder.
pub fn read(path: &Path, placement: &UrdfPlacement) -> Result<UrdfRobot, UrdfError> {
    let text = coulomb::input::read_to_string(path, coulomb::input::Kind::Text)?;
    parse(path, &text, placement)
}

/// A mesh file named `name` (a path, `file://` already stripped) in a URDF file of folder `dir`.
fn mesh_path(dir: &Path, name: &str) -> std::path::PathBuf {
    let p = Path::new(name);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        dir.join(p)
    }
}

/// The mesh files the URDF file `path` names in its links' collision elements, resolved as
/// [`read`] resolves them (the run's inputs, which its outputs never replace); none when the
/// file cannot be read or parsed ([`read`] then says why). URIs other than `file://` are left
/// out: [`read`] refuses them.
pub fn mesh_files(path: &Path) -> Vec<std::path::PathBuf> {
    let Ok(text) = coulomb::input::read_to_string(path, coulomb::input::Kind::Text) else {
        return Vec::new();
    };
    if nesting(&text).is_err() {
        return Vec::new();
    }
    let Ok(robot) = reader::read(&text) else {
        return Vec::new();
    };
    let dir = path.parent().unwrap_or_else(|| Path::new("."));
    let mut files = Vec::new();
    for link in &robot.links {
        for c in &link.collision {
            if let Geometry::Mesh { filename, .. } = &c.geometry {
                let name = filename.strip_prefix("file://").unwrap_or(filename);
                if !name.contains("://") {
                    files.push(mesh_path(dir, name));
                }
            }
        }
    }
    files
}

/// Imports the URDF document `text`, read from `path` (named in errors, its folder resolves
/// the meshes' relative paths).
pub fn parse(path: &Path, text: &str, placement: &UrdfPlacement) -> Result<UrdfRobot, UrdfError> {
    let file = path.to_path_buf();
    let options = |message: String| UrdfError::Options {
        path: file.clone(),
        message,
    };
    if !finite(&placement.position) {
        return Err(options(format!(
            "position {:?} is not finite",
            placement.position
        )));
    }
    check_quaternion("orientation", placement.orientation).map_err(|e| options(e.to_string()))?;
    nesting(text).map_err(|message| UrdfError::Xml {
        path: file.clone(),
        message,
    })?;
    let robot = reader::read(text).map_err(|message| UrdfError::Xml {
        path: file.clone(),
        message,
    })?;
    let tree = |message: String| UrdfError::Tree {
        path: file.clone(),
        message,
    };
    if robot.links.is_empty() {
        return Err(tree(format!("robot '{}' has no link", robot.name)));
    }
    let mut index: HashMap<&str, usize> = HashMap::new();
    for (k, l) in robot.links.iter().enumerate() {
        if index.insert(l.name.as_str(), k).is_some() {
            return Err(tree(format!("two links are named '{}'", l.name)));
        }
    }
    let n = robot.links.len();
    // the joint into each link, and each link's joints out
    let mut parent_joint: Vec<Option<usize>> = vec![None; n];
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (j, joint) in robot.joints.iter().enumerate() {
        let find = |role: &'static str, name: &str| {
            index
                .get(name)
                .copied()
                .ok_or_else(|| UrdfError::UnknownLink {
                    path: file.clone(),
                    joint: joint.name.clone(),
                    role,
                    link: name.to_string(),
                })
        };
        let p = find("parent", &joint.parent)?;
        let c = find("child", &joint.child)?;
        if p == c {
            return Err(UrdfError::Joint {
                path: file.clone(),
                joint: joint.name.clone(),
                message: format!("joins link '{}' to itself", joint.parent),
            });
        }
        if let Some(other) = parent_joint[c] {
            return Err(tree(format!(
                "link '{}' has two parents: joint '{}' (parent '{}') and joint '{}' (parent '{}'); a URDF robot is a tree",
                joint.child,
                robot.joints[other].name,
                robot.joints[other].parent,
                joint.name,
                joint.parent
            )));
        }
        parent_joint[c] = Some(j);
        children[p].push(j);
    }
    let roots: Vec<usize> = (0..n).filter(|&k| parent_joint[k].is_none()).collect();
    let root = match roots.as_slice() {
        [r] => *r,
        [] => {
            return Err(tree(
                "every link has a parent: the joints make a cycle (a URDF robot is a tree)".into(),
            ))
        }
        many => {
            let names: Vec<&str> = many.iter().map(|&k| robot.links[k].name.as_str()).collect();
            return Err(tree(format!(
                "{} links have no parent ({}): a URDF robot is one tree with one root",
                many.len(),
                names.join(", ")
            )));
        }
    };
    // world poses of the links, from the root down
    let mut pose: Vec<Option<Pose>> = vec![None; n];
    pose[root] = Some(Pose {
        p: placement.position,
        q: placement.orientation,
    });
    let mut stack = vec![root];
    let mut reached = 1;
    while let Some(k) = stack.pop() {
        let here = pose[k].unwrap_or(Pose {
            p: placement.position,
            q: placement.orientation,
        });
        for &j in &children[k] {
            let joint = &robot.joints[j];
            if !(finite(&joint.origin.xyz) && finite(&joint.origin.rpy)) {
                return Err(UrdfError::Joint {
                    path: file.clone(),
                    joint: joint.name.clone(),
                    message: format!(
                        "origin xyz {:?} rpy {:?} is not finite",
                        joint.origin.xyz, joint.origin.rpy
                    ),
                });
            }
            let c = index[joint.child.as_str()];
            if pose[c].is_some() {
                // unreachable for a tree (one parent each), kept as the loop's guard
                return Err(tree(format!("link '{}' is reached twice", joint.child)));
            }
            pose[c] = Some(here.then(&Pose::of(&joint.origin)));
            reached += 1;
            stack.push(c);
        }
    }
    if reached < n {
        let cut: Vec<&str> = (0..n)
            .filter(|&k| pose[k].is_none())
            .map(|k| robot.links[k].name.as_str())
            .collect();
        return Err(tree(format!(
            "the joints make a cycle: links {} are not below the root '{}'",
            cut.join(", "),
            robot.links[root].name
        )));
    }
    let dir = path.parent().unwrap_or_else(|| Path::new("."));
    let mut bodies = Vec::with_capacity(n);
    for (k, link) in robot.links.iter().enumerate() {
        let at = pose[k].unwrap_or(Pose {
            p: placement.position,
            q: placement.orientation,
        });
        bodies.push(link_body(
            &file,
            dir,
            link,
            at,
            k == root && placement.fixed_base,
            &placement.material,
        )?);
    }
    let mut joints = Vec::with_capacity(robot.joints.len());
    for joint in &robot.joints {
        let c = index[joint.child.as_str()];
        let p = index[joint.parent.as_str()];
        let frame = pose[c].unwrap_or(Pose {
            p: placement.position,
            q: placement.orientation,
        });
        joints.push(joint_desc(&file, joint, c, p, frame)?);
    }
    Ok(UrdfRobot {
        name: robot.name.clone(),
        links: robot.links.iter().map(|l| l.name.clone()).collect(),
        bodies,
        joints,
    })
}

/// The body of one link whose frame is at `at` in the world.
fn link_body(
    file: &Path,
    dir: &Path,
    link: &reader::Link,
    at: Pose,
    fixed: bool,
    material: &str,
) -> Result<BodySpec, UrdfError> {
    let bad = |message: String| UrdfError::Link {
        path: file.to_path_buf(),
        link: link.name.clone(),
        message,
    };
    let inertial = &link.inertial;
    let m = inertial.mass;
    if !(m.is_finite() && m > 0.0) {
        return Err(bad(format!(
            "mass {m} must be finite and positive (a link without <inertial> has mass 0: give every link its <inertial>)"
        )));
    }
    if !(finite(&inertial.origin.xyz) && finite(&inertial.origin.rpy)) {
        return Err(bad(format!(
            "inertial origin xyz {:?} rpy {:?} is not finite",
            inertial.origin.xyz, inertial.origin.rpy
        )));
    }
    let t = &inertial.inertia;
    let i_inertial = [
        [t.ixx, t.ixy, t.ixz],
        [t.ixy, t.iyy, t.iyz],
        [t.ixz, t.iyz, t.izz],
    ];
    // I_link = R I Rᵀ, R the inertial frame's rotation in the link frame
    let r = matrix(rpy_quaternion(inertial.origin.rpy));
    let inertia: [[f64; 3]; 3] = std::array::from_fn(|a| {
        std::array::from_fn(|b| {
            let mut s = 0.0;
            for (c, row) in i_inertial.iter().enumerate() {
                for (d, x) in row.iter().enumerate() {
                    s += r[a][c] * x * r[b][d];
                }
            }
            s
        })
    });
    let props = MassProperties {
        mass: m,
        local_com: inertial.origin.xyz,
        inertia,
    };
    props.check().map_err(|e| {
        bad(format!(
            "inertia ixx={} ixy={} ixz={} iyy={} iyz={} izz={}: {e}",
            t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz
        ))
    })?;
    let (p, _) = props
        .principal()
        .map_err(|e| bad(format!("inertia: {e}")))?;
    let trace = p[0] + p[1] + p[2];
    for k in 0..3 {
        let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
        if a + b < c - 1e-9 * trace {
            return Err(bad(format!(
                "inertia: principal moments {} {} {} violate the triangle inequality ({a} + {b} < {c}): no mass distribution has them",
                p[0], p[1], p[2]
            )));
        }
    }
    if link.collision.is_empty() {
        return Err(bad(
            "no <collision> element: a body needs a shape (box, cylinder, capsule, sphere or mesh)"
                .into(),
        ));
    }
    let mut parts = Vec::with_capacity(link.collision.len());
    for (index, c) in link.collision.iter().enumerate() {
        if !(finite(&c.origin.xyz) && finite(&c.origin.rpy)) {
            return Err(bad(format!(
                "collision {index}: origin xyz {:?} rpy {:?} is not finite",
                c.origin.xyz, c.origin.rpy
            )));
        }
        let place = Pose::of(&c.origin);
        let (shape, turn) = geometry(file, dir, link, index, &c.geometry)?;
        parts.push((
            shape,
            place.then(&Pose {
                p: [0.0; 3],
                q: turn,
            }),
        ));
    }
    let shape = match parts.as_slice() {
        [(s, place)] if place.is_identity() && !s.is_sphere() => s.clone(),
        _ => BodyShape::Compound {
            parts: parts
                .into_iter()
                .map(|(shape, place)| CompoundPart {
                    shape,
                    position: place.p,
                    orientation: place.q,
                })
                .collect(),
        },
    };
    shape
        .validate()
        .map_err(|e| bad(format!("collision shape ({}) refused: {e}", shape.kind())))?;
    Ok(BodySpec {
        shape,
        position: Vec3::new(at.p[0], at.p[1], at.p[2]),
        orientation: at.q,
        velocity: Vec3::ZERO,
        angular_velocity: Vec3::ZERO,
        mass: Some(m),
        density: None,
        inertia: Some(inertia),
        centre_of_mass: Some(inertial.origin.xyz),
        material: material.to_string(),
        fixed,
    })
}

/// The shape of one collision geometry and the rotation that takes it from our frame
/// convention to URDF's (cylinders and capsules: y → z).
fn geometry(
    file: &Path,
    dir: &Path,
    link: &reader::Link,
    index: usize,
    g: &reader::Geometry,
) -> Result<(BodyShape, [f64; 4]), UrdfError> {
    let unsupported = |message: String| UrdfError::UnsupportedGeometry {
        path: file.to_path_buf(),
        link: link.name.clone(),
        index,
        message,
    };
    Ok(match g {
        Geometry::Box { size } => (
            BodyShape::Cuboid {
                half_extents: size.map(|s| 0.5 * s),
            },
            IDENTITY,
        ),
        Geometry::Cylinder { radius, length } => (
            BodyShape::Cylinder {
                radius: *radius,
                half_height: 0.5 * length,
            },
            Y_TO_Z,
        ),
        Geometry::Capsule { radius, length } => (
            BodyShape::Capsule {
                radius: *radius,
                half_height: 0.5 * length,
            },
            Y_TO_Z,
        ),
        Geometry::Sphere { radius } => (BodyShape::Sphere { radius: *radius }, IDENTITY),
        Geometry::Mesh { filename, scale } => {
            if filename.starts_with("package://") {
                return Err(UrdfError::PackageUri {
                    path: file.to_path_buf(),
                    link: link.name.clone(),
                    index,
                    filename: filename.clone(),
                });
            }
            let name = filename.strip_prefix("file://").unwrap_or(filename);
            if name.contains("://") {
                return Err(unsupported(format!(
                    "mesh '{filename}': only file paths (relative to the URDF file) and file:// URIs are read"
                )));
            }
            let ext = Path::new(name)
                .extension()
                .and_then(|e| e.to_str())
                .map(|e| e.to_ascii_lowercase());
            if !matches!(ext.as_deref(), Some("stl") | Some("obj")) {
                return Err(unsupported(format!(
                    "mesh '{filename}': only .stl and .obj meshes are read (convert it, e.g. a .dae, to one of them)"
                )));
            }
            let resolved = mesh_path(dir, name);
            let transform = Transform {
                scale: Scale::PerAxis(scale.unwrap_or([1.0; 3])),
                ..Transform::default()
            };
            let mesh = import::read_mesh(&resolved, &transform).map_err(|e| UrdfError::Link {
                path: file.to_path_buf(),
                link: link.name.clone(),
                message: format!("collision {index}: mesh: {e}"),
            })?;
            (
                BodyShape::ConvexHull {
                    points: mesh.vertices.iter().map(|v| v.to_array()).collect(),
                },
                IDENTITY,
            )
        }
    })
}

/// The joint `joint` between the child body `c` and the parent body `p`, the child's frame
/// (the joint frame at the zero configuration) at `frame` in the world.
fn joint_desc(
    file: &Path,
    joint: &reader::Joint,
    c: usize,
    p: usize,
    frame: Pose,
) -> Result<JointDesc, UrdfError> {
    let bad = |message: String| UrdfError::Joint {
        path: file.to_path_buf(),
        joint: joint.name.clone(),
        message,
    };
    use reader::JointType as T;
    let kind = match joint.joint_type {
        T::Revolute | T::Continuous => JointKind::Revolute,
        T::Prismatic => JointKind::Prismatic,
        T::Fixed => JointKind::Fixed,
        T::Spherical => JointKind::Spherical,
        T::Floating | T::Planar => {
            return Err(UrdfError::UnsupportedJoint {
                path: file.to_path_buf(),
                joint: joint.name.clone(),
                kind: joint.joint_type.name().to_string(),
            })
        }
    };
    if joint.mimic {
        return Err(bad(
            "<mimic> (a joint driven by another) is not modelled; remove it".into(),
        ));
    }
    let mut friction = None;
    if let Some(d) = &joint.dynamics {
        if d.damping != 0.0 {
            return Err(bad(format!(
                "dynamics damping = {}: viscous joint damping is not modelled; remove it (friction is)",
                d.damping
            )));
        }
        if d.friction != 0.0 {
            if !matches!(kind, JointKind::Revolute | JointKind::Prismatic) {
                return Err(bad(format!(
                    "dynamics friction = {} does not apply to a {} joint",
                    d.friction,
                    kind.name()
                )));
            }
            if !(d.friction.is_finite() && d.friction > 0.0) {
                return Err(bad(format!(
                    "dynamics friction = {} must be finite and >= 0",
                    d.friction
                )));
            }
            friction = Some(d.friction);
        }
    }
    let axis = match kind {
        JointKind::Revolute | JointKind::Prismatic => {
            let a = joint.axis;
            let len = a.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !(finite(&a) && len > 1e-12 && len.is_finite()) {
                return Err(bad(format!("axis {a:?} is zero or not finite")));
            }
            Some(crate::shape::rotate(frame.q, a.map(|x| x / len)))
        }
        _ => None,
    };
    let limits = match joint.joint_type {
        T::Revolute | T::Prismatic => {
            let (lo, hi) = (joint.limit.lower, joint.limit.upper);
            let what = if kind == JointKind::Revolute {
                "angle"
            } else {
                "travel"
            };
            if lo.is_nan() || hi.is_nan() || lo > hi {
                return Err(bad(format!("limit lower = {lo} > upper = {hi}")));
            }
            if lo == hi {
                return Err(bad(format!(
                    "limit lower = upper = {lo}: no range of motion ({} joints need a <limit> with lower < upper; use a fixed joint, or a continuous one for no limits)",
                    joint.joint_type.name()
                )));
            }
            let pi = std::f64::consts::PI;
            match kind {
                JointKind::Revolute => {
                    if lo == f64::NEG_INFINITY && hi == f64::INFINITY {
                        None
                    } else {
                        let lo = if lo == f64::NEG_INFINITY { -pi } else { lo };
                        let hi = if hi == f64::INFINITY { pi } else { hi };
                        if lo < -pi || hi > pi {
                            return Err(bad(format!(
                                "limit ({lo}, {hi}): the {what} of a revolute joint lies in [-pi, pi]; give limits within it, or use a continuous joint"
                            )));
                        }
                        Some((lo, hi))
                    }
                }
                _ => match (lo.is_finite(), hi.is_finite()) {
                    (true, true) => Some((lo, hi)),
                    (false, false) => None,
                    _ => {
                        return Err(bad(format!(
                            "limit ({lo}, {hi}): a one-sided {what} limit is not modelled; give both bounds or neither"
                        )))
                    }
                },
            }
        }
        _ => None,
    };
    Ok(JointDesc {
        kind,
        body_a: c,
        body_b: Some(p),
        anchor: frame.p,
        axis,
        limits,
        motor: None,
        limit_restitution: None,
        friction,
    })
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    pub fn rpy_is_fixed_axis_roll_pitch_yaw() {
        // yaw 90° turns x onto y; roll 90° turns y onto z; R = Rz Ry Rx: roll first
        let q = rpy_quaternion([
            std::f64::consts::FRAC_PI_2,
            0.0,
            std::f64::consts::FRAC_PI_2,
        ]);
        let y = crate::shape::rotate(q, [0.0, 1.0, 0.0]);
        // Rx(90°) y = z, then Rz(90°) z = z
        assert!((y[2] - 1.0).abs() < 1e-12, "{y:?}");
        let x = crate::shape::rotate(q, [1.0, 0.0, 0.0]);
        // Rx x = x, Rz(90°) x = y
        assert!((x[1] - 1.0).abs() < 1e-12, "{x:?}");
        let z = crate::shape::rotate(Y_TO_Z, [0.0, 1.0, 0.0]);
        assert!((z[2] - 1.0).abs() < 1e-12, "{z:?}");
    }
}
