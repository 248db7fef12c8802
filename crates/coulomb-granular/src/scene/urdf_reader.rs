//! A reader of the part of URDF that the import ([`super::urdf`]) uses, on `quick-xml`'s
//! event reader.
//!
//! Hand-written, not the `urdf-rs` crate: `urdf-rs` brings regex (with regex-automata,
//! regex-syntax, aho-corasick), RustyXML, serde-xml-rs, xml-rs and quick-xml's serde layer
//! into the build, a measurable share of a fresh build's time (docs/testing.md) for a format
//! of a dozen elements.
//!
//! # What is read
//! - `<robot>` (the root; its `name`, default empty; its `version`, default 1.0) and in it every
//!   `<link>` and `<joint>`, in the file's order; other elements (`material`, `transmission`,
//!   `gazebo`, …) are skipped with all they contain;
//! - `<link name>`: one optional `<inertial>` (missing: mass 0, which the import refuses) of
//!   an optional `<origin>`, a required `<mass value>` and a required `<inertia ixx ixy ixz
//!   iyy iyz izz>`; its `<collision>` elements, each an optional `<origin>` and a required
//!   `<geometry>` holding one of `<box size>`, `<cylinder radius length>`, `<capsule radius
//!   length>`, `<sphere radius>`, `<mesh filename [scale]>`; `<visual>` is skipped;
//! - `<joint name type>`, the type one of revolute, continuous, prismatic, fixed, floating,
//!   planar, spherical; a required `<parent link>` and `<child link>`; optional `<origin>`
//!   (`xyz`, `rpy`, each default 0 0 0; `quat_xyzw` from URDF 1.1), `<axis xyz>` (default
//!   1 0 0), `<limit>` (`lower`, `upper` default 0 and `velocity` required before URDF 1.2;
//!   from 1.2 the bounds default to -inf, inf, nothing is required and negative `effort` /
//!   `velocity` or `upper < lower` are refused), `<dynamics damping friction>` (each default
//!   0) and `<mimic joint>`; `calibration` and `safety_controller` are skipped.
//!
//! A missing required element or attribute, a number that does not parse, a single element
//! given twice, an unknown joint type or geometry, and malformed XML are refused with the
//! line they are on. Elements nest at most [`MAX_DEPTH`] deep.

use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

/// The deepest nesting of elements a URDF document may have. A URDF robot is 4 or 5 deep
/// (robot, link, collision, geometry, box). A deeper document is refused by one linear scan
/// (`nesting`, in `scene/urdf.rs`) before it is read (the XML reader of the `urdf-rs`
/// crate, used before this reader, recursed or slowed down quadratically with the depth),
/// and this reader refuses it too.
pub const MAX_DEPTH: usize = 32;

/// A pose: `xyz`, and `rpy` or (URDF 1.1) the unit quaternion `quat_xyzw` (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Origin {
    pub xyz: [f64; 3],
    pub rpy: [f64; 3],
    /// `quat_xyzw`, normalized, when given (then `rpy` is zero)
    pub quat_xyzw: Option<[f64; 4]>,
}

/// The six moments of an `<inertia>`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Inertia {
    pub ixx: f64,
    pub ixy: f64,
    pub ixz: f64,
    pub iyy: f64,
    pub iyz: f64,
    pub izz: f64,
}

/// A link's `<inertial>` (all zero when the link has none).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Inertial {
    pub origin: Origin,
    pub mass: f64,
    pub inertia: Inertia,
}

/// A `<collision>`'s `<geometry>`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Geometry {
    Box {
        size: [f64; 3],
    },
    Cylinder {
        radius: f64,
        length: f64,
    },
    Capsule {
        radius: f64,
        length: f64,
    },
    Sphere {
        radius: f64,
    },
    Mesh {
        filename: String,
        scale: Option<[f64; 3]>,
    },
}

/// A `<collision>`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Collision {
    pub origin: Origin,
    pub geometry: Geometry,
}

/// A `<link>`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Link {
    pub name: String,
    pub inertial: Inertial,
    pub collision: Vec<Collision>,
}

/// A joint's `type`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum JointType {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
    Floating,
    Planar,
    Spherical,
}

const JOINT_TYPES: [(&str, JointType); 7] = [
    ("revolute", JointType::Revolute),
    ("continuous", JointType::Continuous),
    ("prismatic", JointType::Prismatic),
    ("fixed", JointType::Fixed),
    ("floating", JointType::Floating),
    ("planar", JointType::Planar),
    ("spherical", JointType::Spherical),
];

impl JointType {
    /// The name URDF gives it.
    pub fn name(self) -> &'static str {
        JOINT_TYPES
            .iter()
            .find(|(_, t)| *t == self)
            .map(|(n, _)| *n)
            .unwrap_or("?")
    }
}

/// A joint's `<limit>` bounds (`effort` and `velocity` are checked, not kept).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Limit {
    pub lower: f64,
    pub upper: f64,
}

/// A joint's `<dynamics>`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Dynamics {
    pub damping: f64,
    pub friction: f64,
}

/// A `<joint>`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Joint {
    pub name: String,
    pub joint_type: JointType,
    pub origin: Origin,
    /// the parent link's name
    pub parent: String,
    /// the child link's name
    pub child: String,
    pub axis: [f64; 3],
    pub limit: Limit,
    pub dynamics: Option<Dynamics>,
    /// whether the joint has a `<mimic>`
    pub mimic: bool,
}

/// A URDF `<robot>`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Robot {
    pub name: String,
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
}

/// One element of the document: its name, attributes (unescaped), child elements and byte
/// offset (for the line in messages). Text is dropped: URDF keeps its data in attributes.
struct Element {
    name: String,
    attrs: Vec<(String, String)>,
    children: Vec<Element>,
    at: usize,
}

/// The 1-based line of byte offset `at` in `text`.
fn line(text: &str, at: usize) -> usize {
    let at = at.min(text.len());
    1 + text.as_bytes()[..at]
        .iter()
        .filter(|&&c| c == b'\n')
        .count()
}

/// Whether `name` is an XML name: a letter, `_` or `:` first, then letters, digits, `-`,
/// `.`, `_`, `:` (any non-ASCII character counts as a letter). The event reader takes a tag's
/// name up to the first space and parses attributes on demand, so it is checked here.
fn is_name(name: &str) -> bool {
    let mut chars = name.chars();
    chars
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_' || c == ':')
        && chars.all(|c| c.is_alphanumeric() || matches!(c, '-' | '.' | '_' | ':'))
}

/// The element of a start (or empty-element) tag at byte `at`.
fn element(text: &str, s: &BytesStart, at: usize) -> Result<Element, String> {
    let name = String::from_utf8_lossy(s.name().as_ref()).into_owned();
    if !is_name(&name) {
        return Err(format!(
            "line {}: '<{name}' does not start an element (not an XML name)",
            line(text, at)
        ));
    }
    let mut attrs = Vec::new();
    for a in s.attributes() {
        let a = a.map_err(|e| format!("line {}: <{name}>: {e}", line(text, at)))?;
        let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
        if !is_name(&key) {
            return Err(format!(
                "line {}: <{name}>: '{key}' is not an attribute name",
                line(text, at)
            ));
        }
        let value = a
            .unescape_value()
            .map_err(|e| format!("line {}: <{name}> attribute '{key}': {e}", line(text, at)))?
            .into_owned();
        attrs.push((key, value));
    }
    Ok(Element {
        name,
        attrs,
        children: Vec::new(),
        at,
    })
}

/// The document's root element: one element, at most [`MAX_DEPTH`] deep, with nothing but
/// white space, comments, processing instructions and a declaration around it.
fn root_element(text: &str) -> Result<Element, String> {
    let mut reader = Reader::from_str(text);
    let mut stack: Vec<Element> = Vec::new();
    let mut root: Option<Element> = None;
    loop {
        let at = reader.buffer_position() as usize;
        let event = reader
            .read_event()
            .map_err(|e| format!("line {}: {e}", line(text, reader.error_position() as usize)))?;
        let done = match event {
            Event::Start(s) => {
                if stack.len() >= MAX_DEPTH {
                    return Err(format!(
                        "line {}: elements nested more than {MAX_DEPTH} deep (a URDF robot is about 5 deep)",
                        line(text, at)
                    ));
                }
                stack.push(element(text, &s, at)?);
                None
            }
            Event::Empty(s) => Some(element(text, &s, at)?),
            // the reader checks that the end tag's name is the open element's
            Event::End(_) => stack.pop(),
            Event::Text(t) => {
                if stack.is_empty() && !t.iter().all(|c| c.is_ascii_whitespace()) {
                    return Err(format!(
                        "line {}: text outside the root element (a URDF document is one <robot> element)",
                        line(text, at)
                    ));
                }
                None
            }
            Event::CData(_) | Event::GeneralRef(_) if stack.is_empty() => {
                return Err(format!(
                    "line {}: text outside the root element (a URDF document is one <robot> element)",
                    line(text, at)
                ));
            }
            Event::Eof => {
                if let Some(open) = stack.last() {
                    return Err(format!(
                        "line {}: the document ends inside <{}> (opened on line {})",
                        line(text, text.len()),
                        open.name,
                        line(text, open.at)
                    ));
                }
                return root.ok_or_else(|| {
                    "no root element (a URDF document is one <robot> element)".to_string()
                });
            }
            _ => None,
        };
        if let Some(e) = done {
            match stack.last_mut() {
                Some(parent) => parent.children.push(e),
                None if root.is_some() => {
                    return Err(format!(
                    "line {}: a second root element <{}> (a URDF document is one <robot> element)",
                    line(text, e.at),
                    e.name
                ))
                }
                None => root = Some(e),
            }
        }
    }
}

/// Reads a document's elements into their typed values, naming the line of each problem.
struct Doc<'t> {
    text: &'t str,
    /// URDF version (major, minor) of the `<robot>`
    version: (u32, u32),
}

impl Doc<'_> {
    fn err(&self, e: &Element, what: impl std::fmt::Display) -> String {
        format!("line {}: <{}>: {what}", line(self.text, e.at), e.name)
    }

    fn attr<'e>(&self, e: &'e Element, key: &str) -> Option<&'e str> {
        e.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    fn required<'e>(&self, e: &'e Element, key: &str) -> Result<&'e str, String> {
        self.attr(e, key)
            .ok_or_else(|| self.err(e, format!("the attribute '{key}' is missing")))
    }

    fn number(&self, e: &Element, key: &str, v: &str) -> Result<f64, String> {
        v.trim()
            .parse::<f64>()
            .map_err(|_| self.err(e, format!("the attribute {key}=\"{v}\" is not a number")))
    }

    fn number_or(&self, e: &Element, key: &str, default: Option<f64>) -> Result<f64, String> {
        match (self.attr(e, key), default) {
            (Some(v), _) => self.number(e, key, v),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.err(e, format!("the attribute '{key}' is missing"))),
        }
    }

    fn numbers<const N: usize>(&self, e: &Element, key: &str, v: &str) -> Result<[f64; N], String> {
        let bad = || {
            self.err(
                e,
                format!("the attribute {key}=\"{v}\" is not {N} numbers separated by spaces"),
            )
        };
        let mut out = [0.0; N];
        let mut words = v.split_whitespace();
        for x in out.iter_mut() {
            *x = words.next().ok_or_else(bad)?.parse().map_err(|_| bad())?;
        }
        if words.next().is_some() {
            return Err(bad());
        }
        Ok(out)
    }

    fn vec3_or(&self, e: &Element, key: &str, default: [f64; 3]) -> Result<[f64; 3], String> {
        self.attr(e, key)
            .map_or(Ok(default), |v| self.numbers(e, key, v))
    }

    /// The child element `name` of `e`, refused when given twice.
    fn one<'e>(&self, e: &'e Element, name: &str) -> Result<Option<&'e Element>, String> {
        let mut found = e.children.iter().filter(|c| c.name == name);
        let first = found.next();
        if let Some(second) = found.next() {
            return Err(self.err(
                second,
                format!("a second <{name}> in <{}> (one is allowed)", e.name),
            ));
        }
        Ok(first)
    }

    fn one_required<'e>(&self, e: &'e Element, name: &str) -> Result<&'e Element, String> {
        self.one(e, name)?
            .ok_or_else(|| self.err(e, format!("the element <{name}> is missing")))
    }

    fn since(&self, major: u32, minor: u32) -> bool {
        self.version >= (major, minor)
    }

    fn origin(&self, parent: &Element) -> Result<Origin, String> {
        let Some(e) = self.one(parent, "origin")? else {
            return Ok(Origin::default());
        };
        let mut o = Origin {
            xyz: self.vec3_or(e, "xyz", [0.0; 3])?,
            rpy: self.vec3_or(e, "rpy", [0.0; 3])?,
            quat_xyzw: None,
        };
        if let Some(v) = self.attr(e, "quat_xyzw") {
            if !self.since(1, 1) {
                return Err(self.err(
                    e,
                    "quat_xyzw needs URDF 1.1 or later (<robot version=\"1.1\">); give rpy",
                ));
            }
            if self.attr(e, "rpy").is_some() {
                return Err(self.err(e, "both rpy and quat_xyzw are given: give one"));
            }
            let q: [f64; 4] = self.numbers(e, "quat_xyzw", v)?;
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !(n.is_finite() && n > 0.0) {
                return Err(self.err(
                    e,
                    format!("quat_xyzw {q:?} is zero or not finite: not a rotation"),
                ));
            }
            o.quat_xyzw = Some(q.map(|x| x / n));
        }
        Ok(o)
    }

    fn inertial(&self, link: &Element) -> Result<Inertial, String> {
        let Some(e) = self.one(link, "inertial")? else {
            return Ok(Inertial::default());
        };
        let mass = self.one_required(e, "mass")?;
        let t = self.one_required(e, "inertia")?;
        let m = |k| self.number_or(t, k, None);
        Ok(Inertial {
            origin: self.origin(e)?,
            mass: self.number_or(mass, "value", None)?,
            inertia: Inertia {
                ixx: m("ixx")?,
                ixy: m("ixy")?,
                ixz: m("ixz")?,
                iyy: m("iyy")?,
                iyz: m("iyz")?,
                izz: m("izz")?,
            },
        })
    }

    fn geometry(&self, collision: &Element) -> Result<Geometry, String> {
        let g = self.one_required(collision, "geometry")?;
        let (s, rest) = match g.children.as_slice() {
            [s, rest @ ..] => (s, rest),
            [] => {
                return Err(self.err(g, "no shape (box, cylinder, capsule, sphere or mesh) in it"))
            }
        };
        if let Some(second) = rest.first() {
            return Err(self.err(
                second,
                "a second shape in one <geometry> (give one shape per <collision>)",
            ));
        }
        let dims = |keys: &[&str]| -> Result<(), String> {
            // URDF 1.2: the dimensions are positive and finite
            if self.since(1, 2) {
                for k in keys {
                    if let Some(v) = self.attr(s, k) {
                        let ok = v
                            .split_whitespace()
                            .all(|w| w.parse::<f64>().is_ok_and(|x| x.is_finite() && x > 0.0));
                        if !ok {
                            return Err(self.err(
                                s,
                                format!("{k}=\"{v}\" must be positive and finite (URDF 1.2)"),
                            ));
                        }
                    }
                }
            }
            Ok(())
        };
        Ok(match s.name.as_str() {
            "box" => {
                dims(&["size"])?;
                Geometry::Box {
                    size: self.numbers(s, "size", self.required(s, "size")?)?,
                }
            }
            "cylinder" | "capsule" => {
                dims(&["radius", "length"])?;
                let radius = self.number_or(s, "radius", None)?;
                let length = self.number_or(s, "length", None)?;
                if s.name == "cylinder" {
                    Geometry::Cylinder { radius, length }
                } else {
                    Geometry::Capsule { radius, length }
                }
            }
            "sphere" => {
                dims(&["radius"])?;
                Geometry::Sphere {
                    radius: self.number_or(s, "radius", None)?,
                }
            }
            "mesh" => Geometry::Mesh {
                filename: self.required(s, "filename")?.to_string(),
                scale: self
                    .attr(s, "scale")
                    .map(|v| self.numbers(s, "scale", v))
                    .transpose()?,
            },
            other => {
                return Err(self.err(
                    s,
                    format!("unknown geometry <{other}> (box, cylinder, capsule, sphere or mesh)"),
                ))
            }
        })
    }

    fn link(&self, e: &Element) -> Result<Link, String> {
        let mut collision = Vec::new();
        for c in e.children.iter().filter(|c| c.name == "collision") {
            collision.push(Collision {
                origin: self.origin(c)?,
                geometry: self.geometry(c)?,
            });
        }
        Ok(Link {
            name: self.required(e, "name")?.to_string(),
            inertial: self.inertial(e)?,
            collision,
        })
    }

    fn limit(&self, joint: &Element) -> Result<Limit, String> {
        let v12 = self.since(1, 2);
        let Some(e) = self.one(joint, "limit")? else {
            return Ok(if v12 {
                Limit {
                    lower: f64::NEG_INFINITY,
                    upper: f64::INFINITY,
                }
            } else {
                Limit {
                    lower: 0.0,
                    upper: 0.0,
                }
            });
        };
        if !v12 {
            self.number_or(e, "effort", Some(0.0))?;
            self.number_or(e, "velocity", None)?;
            return Ok(Limit {
                lower: self.number_or(e, "lower", Some(0.0))?,
                upper: self.number_or(e, "upper", Some(0.0))?,
            });
        }
        let get = |k: &str, d: f64| -> Result<f64, String> {
            let x = self.number_or(e, k, Some(d))?;
            if x.is_nan() {
                return Err(self.err(e, format!("{k} is not a number")));
            }
            Ok(x)
        };
        let (lower, upper) = (
            get("lower", f64::NEG_INFINITY)?,
            get("upper", f64::INFINITY)?,
        );
        if upper < lower {
            return Err(self.err(e, format!("upper = {upper} < lower = {lower}")));
        }
        for k in ["effort", "velocity", "acceleration", "deceleration", "jerk"] {
            let x = get(k, f64::INFINITY)?;
            if x < 0.0 {
                return Err(self.err(e, format!("{k} = {x} is negative")));
            }
        }
        Ok(Limit { lower, upper })
    }

    fn joint(&self, e: &Element) -> Result<Joint, String> {
        let name = self.required(e, "name")?.to_string();
        let kind = self.required(e, "type")?;
        let joint_type = JOINT_TYPES
            .iter()
            .find(|(n, _)| *n == kind)
            .map(|(_, t)| *t)
            .ok_or_else(|| {
                self.err(
                    e,
                    format!("joint '{name}': unknown type '{kind}' (revolute, continuous, prismatic, fixed, floating, planar or spherical)"),
                )
            })?;
        let link_of = |role: &str| -> Result<String, String> {
            let r = self.one_required(e, role)?;
            Ok(self.required(r, "link")?.to_string())
        };
        let dynamics = match self.one(e, "dynamics")? {
            Some(d) => Some(Dynamics {
                damping: self.number_or(d, "damping", Some(0.0))?,
                friction: self.number_or(d, "friction", Some(0.0))?,
            }),
            None => None,
        };
        let mimic = match self.one(e, "mimic")? {
            Some(m) => {
                self.required(m, "joint")?;
                true
            }
            None => false,
        };
        let axis = match self.one(e, "axis")? {
            Some(a) => self.numbers(a, "xyz", self.required(a, "xyz")?)?,
            None => [1.0, 0.0, 0.0],
        };
        Ok(Joint {
            joint_type,
            origin: self.origin(e)?,
            parent: link_of("parent")?,
            child: link_of("child")?,
            axis,
            limit: self.limit(e)?,
            dynamics,
            mimic,
            name,
        })
    }
}

/// Reads the URDF document `text`; the error names the problem and its line.
pub(crate) fn read(text: &str) -> Result<Robot, String> {
    let root = root_element(text)?;
    if root.name != "robot" {
        return Err(format!(
            "line {}: the root element is <{}>, not <robot>",
            line(text, root.at),
            root.name
        ));
    }
    let mut doc = Doc {
        text,
        version: (1, 0),
    };
    if let Some(v) = doc.attr(&root, "version") {
        let parsed = v
            .trim()
            .split_once('.')
            .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)));
        doc.version = parsed.ok_or_else(|| {
            doc.err(
                &root,
                format!("version=\"{v}\" is not a URDF version (major.minor, e.g. 1.0)"),
            )
        })?;
    }
    let mut robot = Robot {
        name: doc.attr(&root, "name").unwrap_or("").to_string(),
        links: Vec::new(),
        joints: Vec::new(),
    };
    for e in &root.children {
        match e.name.as_str() {
            "link" => robot.links.push(doc.link(e)?),
            "joint" => robot.joints.push(doc.joint(e)?),
            _ => {}
        }
    }
    Ok(robot)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    const LINK: &str = r#"<link name="a"><inertial><mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial><collision><geometry><box size="1 2 3"/></geometry></collision></link>"#;

    fn joint(inner: &str) -> String {
        format!(
            r#"<robot name="r">{LINK}<link name="b"/><joint name="j" type="revolute"><parent link="a"/><child link="b"/>{inner}</joint></robot>"#
        )
    }

    pub fn omitted_parts_take_urdf_defaults() {
        let r = read(&joint("")).unwrap();
        assert_eq!(r.name, "r");
        assert_eq!(r.links.len(), 2);
        let a = &r.links[0];
        assert_eq!(a.inertial.mass, 2.0);
        assert_eq!(a.inertial.origin, Origin::default());
        assert_eq!(a.collision[0].origin, Origin::default());
        assert_eq!(
            a.collision[0].geometry,
            Geometry::Box {
                size: [1.0, 2.0, 3.0]
            }
        );
        // a link without <inertial>: mass 0 (the import refuses it), no collision
        assert_eq!(r.links[1].inertial, Inertial::default());
        assert!(r.links[1].collision.is_empty());
        let j = &r.joints[0];
        assert_eq!(j.joint_type, JointType::Revolute);
        assert_eq!((j.parent.as_str(), j.child.as_str()), ("a", "b"));
        assert_eq!(j.axis, [1.0, 0.0, 0.0]);
        assert_eq!(j.origin, Origin::default());
        // URDF 1.0: no <limit> is lower = upper = 0; 1.2: none (infinite)
        assert_eq!(
            j.limit,
            Limit {
                lower: 0.0,
                upper: 0.0
            }
        );
        assert_eq!((j.dynamics, j.mimic), (None, false));
        let v12 =
            read(&joint("").replace("<robot name=\"r\">", "<robot name=\"r\" version=\"1.2\">"))
                .unwrap();
        assert_eq!(
            v12.joints[0].limit,
            Limit {
                lower: f64::NEG_INFINITY,
                upper: f64::INFINITY
            }
        );
        // <limit> without lower/upper (velocity given), <dynamics> without attributes
        let r = read(&joint(
            r#"<limit velocity="1"/><dynamics/><mimic joint="x"/>"#,
        ))
        .unwrap();
        let j = &r.joints[0];
        assert_eq!(
            j.limit,
            Limit {
                lower: 0.0,
                upper: 0.0
            }
        );
        assert_eq!(j.dynamics, Some(Dynamics::default()));
        assert!(j.mimic);
        // a mesh without scale; elements not modelled are skipped with their content
        let r = read(
            r#"<robot><material name="m"><color rgba="1 0 0 1"/></material><link name="m"><visual><geometry><teapot/></geometry></visual><collision><origin rpy="0 0 1"/><geometry><mesh filename="a.stl"/></geometry></collision></link><gazebo><x/></gazebo><transmission name="t"/></robot>"#,
        )
        .unwrap();
        assert_eq!(r.name, "");
        let c = &r.links[0].collision[0];
        assert_eq!(
            c.geometry,
            Geometry::Mesh {
                filename: "a.stl".into(),
                scale: None
            }
        );
        assert_eq!((c.origin.xyz, c.origin.rpy), ([0.0; 3], [0.0, 0.0, 1.0]));
    }

    pub fn a_missing_required_attribute_is_named_with_its_line() {
        // <limit> before URDF 1.2 needs velocity
        let e = read(&joint(r#"<limit lower="-1" upper="1"/>"#)).unwrap_err();
        assert!(
            e.contains("<limit>") && e.contains("'velocity' is missing"),
            "{e}"
        );
        assert!(e.starts_with("line 1:"), "{e}");
        // an <inertia> moment, on line 3
        let text = "<robot name=\"r\">\n<link name=\"a\"><inertial><mass value=\"1\"/>\n<inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\"/></inertial></link></robot>";
        let e = read(text).unwrap_err();
        assert!(
            e.starts_with("line 3: <inertia>") && e.contains("'izz' is missing"),
            "{e}"
        );
        // a joint's child
        let e = read(&joint("").replace(r#"<child link="b"/>"#, "")).unwrap_err();
        assert!(e.contains("<child> is missing"), "{e}");
        // a number that is not one, a vector of two
        let e = read(&format!("<robot>{LINK}</robot>").replace("value=\"2\"", "value=\"two\""))
            .unwrap_err();
        assert!(e.contains("value=\"two\" is not a number"), "{e}");
        let e = read(&joint(r#"<axis xyz="0 1"/>"#)).unwrap_err();
        assert!(e.contains("xyz=\"0 1\" is not 3 numbers"), "{e}");
        // one <inertial> per link
        let e = read(&format!(
            "<robot>{}</robot>",
            LINK.replace("</link>", "<inertial/></link>")
        ))
        .unwrap_err();
        assert!(e.contains("a second <inertial>"), "{e}");
    }

    pub fn an_unknown_joint_type_or_shape_is_refused() {
        let e = read(&joint("").replace("revolute", "hinge")).unwrap_err();
        assert!(
            e.contains("joint 'j': unknown type 'hinge'") && e.contains("spherical"),
            "{e}"
        );
        let e = read(&format!("<robot>{LINK}</robot>").replace("<box size=\"1 2 3\"/>", "<cone/>"))
            .unwrap_err();
        assert!(e.contains("unknown geometry <cone>"), "{e}");
        for (kind, t) in JOINT_TYPES {
            assert_eq!(t.name(), kind);
        }
    }

    pub fn malformed_xml_is_refused_with_its_line() {
        // an element left open
        let e = read("<robot name=\"r\">\n<link name=\"a\">").unwrap_err();
        assert!(e.contains("ends inside <link> (opened on line 2)"), "{e}");
        // mismatched end tag, on line 2
        let e = read("<robot>\n<link name=\"a\"></joint></robot>").unwrap_err();
        assert!(e.starts_with("line 2:") && e.contains("joint"), "{e}");
        // not XML, no root, two roots, an attribute without quotes, another root
        let e = read("not xml at all").unwrap_err();
        assert!(e.contains("text outside the root element"), "{e}");
        let e = read("<?xml version=\"1.0\"?>\n<!-- c -->\n").unwrap_err();
        assert!(e.contains("no root element"), "{e}");
        let e = read("<robot/><robot/>").unwrap_err();
        assert!(e.contains("a second root element <robot>"), "{e}");
        let e = read("<robot><link name=a/></robot>").unwrap_err();
        assert!(e.starts_with("line 1: <link>"), "{e}");
        let e = read("<robot>\n<or&amp;igin/></robot>").unwrap_err();
        assert!(
            e.starts_with("line 2: '<or&amp;igin'") && e.contains("not an XML name"),
            "{e}"
        );
        let e = read("<robot na<me=\"r\"/>").unwrap_err();
        assert!(e.contains("'na<me' is not an attribute name"), "{e}");
        let e = read("<sdf/>").unwrap_err();
        assert!(e.contains("root element is <sdf>, not <robot>"), "{e}");
        // too deep
        let deep = format!("<robot>{}{}</robot>", "<a>".repeat(40), "</a>".repeat(40));
        let e = read(&deep).unwrap_err();
        assert!(e.contains("nested more than"), "{e}");
        // entities in attribute values are unescaped
        let r = read("<robot name=\"a&amp;b\"/>").unwrap();
        assert_eq!(r.name, "a&b");
    }
}
