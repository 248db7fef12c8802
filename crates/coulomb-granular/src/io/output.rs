//! Outputs: per-step statistics as CSV and JSON, and VTK PolyData frames (.vtp) of every
//! scene ([`VtkWriter`] over a [`FrameSource`]) indexed by ParaView collections (.pvd): the
//! balls as glyph-ready points (positions, radii, velocities, contact forces), the other
//! bodies as their shapes' polygons, the contacts (points, normals, forces, gaps) and the
//! obstacles as surfaces (triangles).
//!
//! Frames are binary by default ([`VtkFormat::Binary`]: VTK XML with raw appended data,
//! `header_type="UInt64"`, little-endian; 8 bytes a number instead of ~20 characters, so a
//! frame of 10⁶ beads is ~100 MB instead of ~300 MB and is written without formatting
//! numbers); [`VtkFormat::Ascii`] writes the same arrays as text.

pub use crate::bodies::surface::{obstacle_surface, Extent, CYLINDER_SEGMENTS};
use crate::contact::{Contact, Partner};
use crate::math::Vec3;
use crate::output_dir::OutputDir;
use crate::scene::rigid::RigidScene;
use crate::shape::{BodyShape, IDENTITY};
use crate::simulation::{Simulation, StepStats};
use crate::world::{Motion, Obstacle, Sphere};
use std::fmt::Write as _;
use std::fs;
use std::io;
use std::path::Path;
use std::sync::Arc;

/// The collections every run writes beside `frames/` (sphere and rigid scenes alike, issue 52:
/// spheres are glyph-ready points with a `radius` array, other shapes polygons).
pub const BODIES_NAMES: [&str; 3] = ["bodies.pvd", "contacts.pvd", "obstacles.pvd"];

pub use crate::report::CSV_HEADER;

/// The `stats.csv` row of a sphere step ([`crate::report::StepRecord`], the columns of every
/// scene).
pub fn csv_line(s: &StepStats) -> String {
    crate::report::StepRecord::of_spheres(s).csv_line()
}

/// Writes `stats.csv` and `stats.json` in `dir`.
pub fn write_stats(dir: &Path, stats: &[StepStats]) -> io::Result<()> {
    write_stats_after(dir, Vec::new(), Vec::new(), stats)
}

/// Writes `stats.csv` and `stats.json` in `dir` for a run restarted at step `first_step`: the
/// rows of the files already there (the run that wrote the checkpoint, or an earlier restart)
/// for the steps before `first_step` are kept, this run's `stats` follow. Files that are
/// missing or unreadable contribute no rows.
pub fn write_stats_continued(dir: &Path, first_step: usize, stats: &[StepStats]) -> io::Result<()> {
    let (csv_rows, json_rows) = stats_rows_before(dir, first_step as u64);
    write_stats_after(dir, csv_rows, json_rows, stats)
}

/// The rows of `dir/stats.csv` (without its header) and of `dir/stats.json` whose step is
/// before `first_step`: what a run restarted at `first_step` keeps of the files already there
/// (sphere and rigid runs alike; missing or unreadable files give no rows).
pub fn stats_rows_before(dir: &Path, first_step: u64) -> (Vec<String>, Vec<serde_json::Value>) {
    let before = |step: Option<u64>| step.is_some_and(|k| k < first_step);
    let csv_rows: Vec<String> = fs::read_to_string(dir.join("stats.csv"))
        .map(|text| {
            text.lines()
                .skip(1)
                .filter(|l| before(l.split(',').next().and_then(|k| k.parse().ok())))
                .map(str::to_string)
                .collect()
        })
        .unwrap_or_default();
    let json_rows: Vec<serde_json::Value> = fs::read_to_string(dir.join("stats.json"))
        .ok()
        .and_then(|text| serde_json::from_str::<Vec<serde_json::Value>>(&text).ok())
        .unwrap_or_default()
        .into_iter()
        .filter(|v| before(v.get("step").and_then(|k| k.as_u64())))
        .collect();
    (csv_rows, json_rows)
}

fn write_stats_after(
    dir: &Path,
    csv_rows: Vec<String>,
    json_rows: Vec<serde_json::Value>,
    stats: &[StepStats],
) -> io::Result<()> {
    let out = OutputDir::open(dir)?;
    out.check(&["stats.csv", "stats.json"])?;
    let mut csv = String::from(CSV_HEADER);
    csv.push('\n');
    for row in csv_rows {
        csv.push_str(&row);
        csv.push('\n');
    }
    for s in stats {
        csv.push_str(&csv_line(s));
        csv.push('\n');
    }
    out.write("stats.csv", csv.as_bytes())?;
    // the rows of every scene's stats.json: the record's keys, the engine's under "details"
    let mut all = json_rows;
    for s in stats {
        let row = crate::report::EngineStep::of_spheres(s.clone()).json_row();
        all.push(row.map_err(io::Error::other)?);
    }
    let json = serde_json::to_string_pretty(&all).map_err(io::Error::other)?;
    out.write("stats.json", json.as_bytes())
}

/// How the arrays of a .vtp file are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VtkFormat {
    /// raw little-endian binary in an `<AppendedData encoding="raw">` block, each array
    /// preceded by its length in bytes as UInt64 (VTK XML's `header_type="UInt64"`)
    #[default]
    Binary,
    /// numbers as text inside each `<DataArray>` (readable, ~2.5× larger)
    Ascii,
}

/// Values of one VTK data array.
#[derive(Debug, Clone, PartialEq)]
enum Values {
    F64(Vec<f64>),
    I64(Vec<i64>),
}

impl Values {
    fn vtk_type(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::I64(_) => "Int64",
        }
    }
    fn byte_len(&self) -> usize {
        match self {
            Values::F64(v) => 8 * v.len(),
            Values::I64(v) => 8 * v.len(),
        }
    }
    fn append_bytes(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&(self.byte_len() as u64).to_le_bytes());
        match self {
            Values::F64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Values::I64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        }
    }
    fn append_text(&self, components: usize, out: &mut String) {
        let text: Vec<String> = match self {
            Values::F64(v) => v.iter().map(f64::to_string).collect(),
            Values::I64(v) => v.iter().map(i64::to_string).collect(),
        };
        for row in text.chunks(components.max(1)) {
            out.push_str(&row.join(" "));
            out.push('\n');
        }
    }
}

/// A named data array (`components` values per point or cell).
#[derive(Debug, Clone, PartialEq)]
struct Array {
    name: &'static str,
    components: usize,
    values: Values,
}

impl Array {
    fn vectors(name: &'static str, v: impl Iterator<Item = Vec3>) -> Self {
        Self {
            name,
            components: 3,
            values: Values::F64(v.flat_map(Vec3::to_array).collect()),
        }
    }
    fn scalars(name: &'static str, v: impl Iterator<Item = f64>) -> Self {
        Self {
            name,
            components: 1,
            values: Values::F64(v.collect()),
        }
    }
}

/// A VTK PolyData piece: points with point and cell data, and either one vertex per point or
/// polygons.
#[derive(Debug, Clone, PartialEq, Default)]
struct PolyData {
    points: Vec<Vec3>,
    point_data: Vec<Array>,
    cell_data: Vec<Array>,
    /// polygons (point indices); none: one vertex cell per point
    polygons: Option<Vec<Vec<u32>>>,
}

impl PolyData {
    /// The .vtp file.
    fn to_vtp(&self, format: VtkFormat) -> Vec<u8> {
        let n = self.points.len();
        let (cells, conn, offsets): (usize, Vec<i64>, Vec<i64>) = match &self.polygons {
            Some(p) => (
                p.len(),
                p.iter().flatten().map(|&i| i as i64).collect(),
                (p.iter())
                    .scan(0i64, |end, f| {
                        *end += f.len() as i64;
                        Some(*end)
                    })
                    .collect(),
            ),
            None => (n, (0..n as i64).collect(), (1..=n as i64).collect()),
        };
        let polys = self.polygons.is_some();
        let (nverts, npolys) = if polys { (0, cells) } else { (cells, 0) };
        let mut xml = String::new();
        let header = match format {
            VtkFormat::Binary => " header_type=\"UInt64\"",
            VtkFormat::Ascii => "",
        };
        let _ = writeln!(
            xml,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\"{header}>\n<PolyData>\n<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{nverts}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"{npolys}\">"
        );
        let mut appended: Vec<u8> = Vec::new();
        let mut array = |xml: &mut String, name: Option<&str>, components: usize, v: &Values| {
            let name = name.map(|s| format!(" Name=\"{s}\"")).unwrap_or_default();
            let (comps, ty) = (self::components(components), v.vtk_type());
            match format {
                VtkFormat::Binary => {
                    let _ = writeln!(
                        xml,
                        "<DataArray type=\"{ty}\"{name}{comps} format=\"appended\" offset=\"{}\"/>",
                        appended.len()
                    );
                    v.append_bytes(&mut appended);
                }
                VtkFormat::Ascii => {
                    let _ = writeln!(
                        xml,
                        "<DataArray type=\"{ty}\"{name}{comps} format=\"ascii\">"
                    );
                    v.append_text(components, xml);
                    xml.push_str("</DataArray>\n");
                }
            }
        };
        xml.push_str("<Points>\n");
        let pts = Values::F64(self.points.iter().flat_map(|p| p.to_array()).collect());
        array(&mut xml, Some("points"), 3, &pts);
        xml.push_str("</Points>\n");
        for (tag, arrays) in [
            ("PointData", &self.point_data),
            ("CellData", &self.cell_data),
        ] {
            if arrays.is_empty() {
                continue;
            }
            open_data(&mut xml, tag, arrays);
            for a in arrays {
                array(&mut xml, Some(a.name), a.components, &a.values);
            }
            let _ = writeln!(xml, "</{tag}>");
        }
        let cell_tag = if polys { "Polys" } else { "Verts" };
        let _ = writeln!(xml, "<{cell_tag}>");
        array(&mut xml, Some("connectivity"), 1, &Values::I64(conn));
        array(&mut xml, Some("offsets"), 1, &Values::I64(offsets));
        let _ = writeln!(xml, "</{cell_tag}>");
        xml.push_str("</Piece>\n</PolyData>\n");
        let mut out = xml.into_bytes();
        if format == VtkFormat::Binary {
            out.extend_from_slice(b"<AppendedData encoding=\"raw\">\n_");
            out.extend_from_slice(&appended);
            out.extend_from_slice(b"\n</AppendedData>\n");
        }
        out.extend_from_slice(b"</VTKFile>\n");
        out
    }

    /// The parallel file (.pvtp) joining `pieces` (names relative to it), each a .vtp of
    /// this polydata's arrays ([`PolyData::to_vtp`]) with its own points and cells.
    fn to_pvtp(&self, pieces: impl Iterator<Item = String>) -> Vec<u8> {
        let mut xml = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"PPolyData\" version=\"1.0\" byte_order=\"LittleEndian\">\n<PPolyData GhostLevel=\"0\">\n<PPoints>\n<PDataArray type=\"Float64\" Name=\"points\" NumberOfComponents=\"3\"/>\n</PPoints>\n",
        );
        for (tag, arrays) in [
            ("PPointData", &self.point_data),
            ("PCellData", &self.cell_data),
        ] {
            if arrays.is_empty() {
                continue;
            }
            open_data(&mut xml, tag, arrays);
            for a in arrays {
                let (ty, name, comps) = (a.values.vtk_type(), a.name, components(a.components));
                let _ = writeln!(xml, "<PDataArray type=\"{ty}\" Name=\"{name}\"{comps}/>");
            }
            let _ = writeln!(xml, "</{tag}>");
        }
        for p in pieces {
            let _ = writeln!(xml, "<Piece Source=\"{p}\"/>");
        }
        xml.push_str("</PPolyData>\n</VTKFile>\n");
        xml.into_bytes()
    }
}

/// The `NumberOfComponents` attribute of an array of `n` components (none for 1).
fn components(n: usize) -> String {
    match n {
        1 => String::new(),
        n => format!(" NumberOfComponents=\"{n}\""),
    }
}

/// The opening tag `<{tag} Scalars=… Vectors=…>` of a point or cell data section: its first
/// scalar and its first vector array are the active ones.
fn open_data(xml: &mut String, tag: &str, arrays: &[Array]) {
    let _ = write!(xml, "<{tag}");
    if let Some(a) = arrays.iter().find(|a| a.components == 1) {
        let _ = write!(xml, " Scalars=\"{}\"", a.name);
    }
    if let Some(a) = arrays.iter().find(|a| a.components == 3) {
        let _ = write!(xml, " Vectors=\"{}\"", a.name);
    }
    xml.push_str(">\n");
}

/// The obstacles at time t as one PolyData of triangles, with the obstacle's index as cell
/// data (`obstacle`).
fn obstacles_polydata(obstacles: &[Obstacle], t: f64, extent: &Extent) -> PolyData {
    let mut points = Vec::new();
    let mut triangles = Vec::new();
    let mut index = Vec::new();
    for (k, o) in obstacles.iter().enumerate() {
        let (p, tris) = obstacle_surface(o, t, extent);
        let base = points.len();
        points.extend(p);
        index.extend(std::iter::repeat_n(k as f64, tris.len()));
        let at = |i: usize| (i + base) as u32;
        triangles.extend(tris.into_iter().map(|[a, b, c]| vec![at(a), at(b), at(c)]));
    }
    PolyData {
        points,
        cell_data: vec![Array::scalars("obstacle", index.into_iter())],
        polygons: Some(triangles),
        ..PolyData::default()
    }
}

/// How a frame draws a body: a ball as a glyph-ready point with its radius, any other shape as
/// its tessellation's polygons ([`BodyShape::tessellation`]).
#[derive(Debug, Clone, Copy)]
pub enum Look<'a> {
    /// a sphere of this radius
    Ball(f64),
    /// another shape
    Shape(&'a BodyShape),
}

/// A body in a frame: how it is drawn, its pose and velocities (world frame).
#[derive(Debug, Clone, Copy)]
pub struct FrameBody<'a> {
    /// ball or shape
    pub look: Look<'a>,
    /// centre (the origin of the shape's frame)
    pub position: Vec3,
    /// orientation of the shape's frame (w, x, y, z; not used for balls)
    pub orientation: [f64; 4],
    /// velocity
    pub velocity: Vec3,
    /// angular velocity ω
    pub angular_velocity: Vec3,
}

impl FrameBody<'_> {
    /// A sphere of the sphere engine, drawn as a ball.
    pub fn ball(s: &Sphere) -> Self {
        FrameBody {
            look: Look::Ball(s.radius),
            position: s.position,
            orientation: IDENTITY,
            velocity: s.velocity,
            angular_velocity: s.angular_velocity,
        }
    }
}

/// A contact point of the last step in a frame.
#[derive(Debug, Clone, Copy)]
pub struct FrameContact {
    /// body A
    pub a: usize,
    /// body B; `None` for an obstacle
    pub b: Option<usize>,
    /// the point, midway between the two surfaces
    pub point: Vec3,
    /// unit normal n, from B towards A
    pub normal: Vec3,
    /// the force on A: the impulse r in world axes over h (−force on B)
    pub force: Vec3,
    /// the gap at the start of the step (negative: penetration)
    pub gap: f64,
}

impl FrameContact {
    /// A contact (of either engine) whose impulse was taken over a step `h` (its bodies'
    /// indices as the contact holds them).
    pub fn of(c: &Contact, h: f64) -> Self {
        FrameContact {
            a: c.body,
            b: match c.partner {
                Partner::Body(j) => Some(j),
                Partner::Obstacle(..) => None,
            },
            point: c.point,
            normal: c.normal,
            force: c.world_impulse() * (1.0 / h),
            gap: c.gap,
        }
    }
}

/// What a frame shows of a scene at t_k, the same for every scene (issue 52, item 4).
#[derive(Debug, Clone)]
pub struct FrameData<'a> {
    /// k
    pub step: usize,
    /// t_k
    pub time: f64,
    /// every body, in the scene's order
    pub bodies: Vec<FrameBody<'a>>,
    /// the last step's contact points
    pub contacts: Vec<FrameContact>,
    /// the obstacles, drawn at t_k
    pub obstacles: &'a [Obstacle],
}

/// One process's part of a frame of a run split over processes (a distributed run,
/// docs/distributed.md), for [`VtkWriter::write_frame`]; `max` is collective.
pub struct FramePart<'a> {
    /// this process (0 writes the .pvtp files, the obstacles and the collections)
    pub rank: usize,
    /// the processes, each writing one piece
    pub ranks: usize,
    /// the global index of each body of the frame (its `body` array)
    pub ids: &'a [usize],
    /// replaces each number by its maximum over the processes (collective)
    pub max: &'a mut dyn FnMut(&mut [f64]),
}

/// A scene that frames are drawn of: [`Simulation`] and [`RigidScene`].
pub trait FrameSource {
    /// What the frame of the current state shows.
    fn frame_data(&self) -> FrameData<'_>;
}

impl FrameSource for Simulation {
    fn frame_data(&self) -> FrameData<'_> {
        let h = self.params.h;
        FrameData {
            step: self.steps_done,
            time: self.time,
            bodies: self.world.bodies.iter().map(FrameBody::ball).collect(),
            contacts: (self.contacts.iter())
                .map(|c| FrameContact::of(c, h))
                .collect(),
            obstacles: &self.world.obstacles,
        }
    }
}

impl FrameSource for RigidScene {
    fn frame_data(&self) -> FrameData<'_> {
        let w = &self.world;
        let (x, q, v, om) = (
            w.positions(),
            w.orientations(),
            w.velocities(),
            w.angular_velocities(),
        );
        let h = w.settings().h;
        let v3 = Vec3::from_slice;
        FrameData {
            step: w.steps() as usize,
            time: w.time(),
            bodies: (self.shapes.iter().zip(x).zip(q).zip(v).zip(om))
                .map(|((((s, x), q), v), om)| FrameBody {
                    look: match s {
                        BodyShape::Sphere { radius } => Look::Ball(*radius),
                        s => Look::Shape(s),
                    },
                    position: v3(&x),
                    orientation: q,
                    velocity: v3(&v),
                    angular_velocity: v3(&om),
                })
                .collect(),
            contacts: (w.contacts().iter())
                .map(|c| FrameContact::of(c, h))
                .collect(),
            obstacles: &self.obstacles,
        }
    }
}

/// One frame of the collections: its time and files (`shapes` empty when the frame has no
/// body other than balls).
#[derive(Debug, Clone, PartialEq)]
struct FrameFiles {
    time: f64,
    bodies: String,
    shapes: String,
    contacts: String,
    obstacles: String,
}

/// Writes VTK frames of any scene ([`FrameSource`]) into a directory, with the ParaView
/// collections `bodies.pvd`, `contacts.pvd` and `obstacles.pvd` indexing them. Each frame:
/// - `frames/bodies_KKKKKK.vtp` (part 0 of `bodies.pvd`): the balls as points (centres) with
///   point data `radius`, `velocity`, `angular_velocity`, `contact_force` (Σ r / h over the
///   ball's contacts) and, when the frame has other shapes, `body` (the ball's index among
///   the bodies), for ParaView's *Glyph* filter; written every frame, balls or not;
/// - `frames/shapes_KKKKKK.vtp` (part 1, when the frame has a body that is not a ball): each
///   such body as its shape's polygons (tessellated once) placed by its pose, with cell data
///   `body`, `velocity`, `angular_velocity` and `contact_force`;
/// - `frames/contacts_KKKKKK.vtp`: one point per contact point with `normal` (B → A), `force`
///   (the impulse over h, on A) and `gap`;
/// - the obstacles as triangles into `frames/obstacles_KKKKKK.vtp`, written when one moves or
///   when the region they must cover (the bodies' [`Extent`], only ever grown) has grown;
///   otherwise the collection points again to the last obstacles file.
#[derive(Debug)]
pub struct VtkWriter {
    dir: Arc<OutputDir>,
    format: VtkFormat,
    frames: Vec<FrameFiles>,
    /// the region the last obstacles file covers, and that file
    obstacles: Option<(Extent, String)>,
    /// the tessellations of the bodies that are not balls, in the bodies' order (bodies are
    /// only ever added: an inlet pouring)
    tessellations: Vec<crate::shape::Tessellation>,
}

impl VtkWriter {
    /// A writer into `dir` (created), binary frames; the files of the collections and
    /// `frames/` are written without following links ([`OutputDir`]; a link or special file
    /// at one of those names is refused).
    pub fn new(dir: &Path) -> io::Result<Self> {
        let mut out = OutputDir::open(dir)?;
        out.check(&BODIES_NAMES)?;
        out.open_frames()?;
        Ok(Self::in_dir(Arc::new(out)))
    }

    /// A writer into the output folder `dir` (its `frames/` opened: [`OutputDir::open_frames`]).
    pub fn in_dir(dir: Arc<OutputDir>) -> Self {
        Self {
            dir,
            format: VtkFormat::default(),
            frames: Vec::new(),
            obstacles: None,
            tessellations: Vec::new(),
        }
    }

    /// The writer continuing the collections of its folder from step `first_step` (a restarted
    /// run): the frames before `first_step` that `bodies.pvd` lists are kept, later ones dropped.
    pub fn resumed(mut self, first_step: usize) -> Self {
        self.frames = frames_before(&self.dir, first_step);
        self
    }

    /// The same writer with frames in `format`.
    pub fn with_format(mut self, format: VtkFormat) -> Self {
        self.format = format;
        self
    }

    /// Writes the frame of the scene's current state.
    pub fn frame<S: FrameSource + ?Sized>(&mut self, scene: &S) -> io::Result<()> {
        let f = scene.frame_data();
        self.write_frame(&f, &contact_forces(&f), None)
    }

    /// Writes the frame `f` with the contact force Σ r / h on each body (`force`, from the
    /// contacts of every process): the files of one process, or with `part` this process's
    /// part of a frame of balls split over processes (every process for the same step): the
    /// pieces `frames/bodies_K_R.vtp`, `frames/contacts_K_R.vtp` with the arrays of one
    /// process plus `body` (the global index) and `rank`; rank 0 also the `.pvtp` files
    /// joining them, listed by the collections, and the obstacles over every process's balls.
    pub fn write_frame(
        &mut self,
        f: &FrameData,
        force: &[Vec3],
        mut part: Option<FramePart<'_>>,
    ) -> io::Result<()> {
        let k = f.step;
        let radius = |b: &FrameBody| match b.look {
            Look::Ball(r) => Some(r),
            Look::Shape(_) => None,
        };
        let balls: Vec<(&FrameBody, f64, usize)> = (f.bodies.iter().enumerate())
            .filter_map(|(i, b)| Some((b, radius(b)?, i)))
            .collect();
        let (n, shaped) = (f.bodies.len(), balls.len() < f.bodies.len());
        if force.len() != n || part.as_ref().is_some_and(|p| shaped || p.ids.len() != n) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "a frame takes one force per body; split over processes, balls with one index each",
            ));
        }
        let mut point_data = vec![
            Array::scalars("radius", balls.iter().map(|b| b.1)),
            Array::vectors("velocity", balls.iter().map(|b| b.0.velocity)),
            Array::vectors(
                "angular_velocity",
                balls.iter().map(|b| b.0.angular_velocity),
            ),
            Array::vectors("contact_force", balls.iter().map(|b| force[b.2])),
        ];
        if shaped || part.is_some() {
            let id = |i: usize| part.as_ref().map_or(i, |p| p.ids[i]) as f64;
            point_data.push(Array::scalars("body", balls.iter().map(|b| id(b.2))));
        }
        if let Some(rank) = part.as_ref().map(|p| p.rank as f64) {
            point_data.push(Array::scalars("rank", balls.iter().map(|_| rank)));
        }
        let shapes = shaped.then(|| self.shapes_polydata(f, force));
        // the region the obstacles must cover: the balls and the shapes' vertices (of every
        // process)
        let mut bounds = Extent::bounds(
            (balls.iter().map(|b| (b.0.position, b.1))).chain(
                shapes
                    .iter()
                    .flat_map(|s| s.points.iter().map(|&p| (p, 0.0))),
            ),
        );
        if let Some(p) = part.as_mut() {
            (p.max)(&mut bounds);
        }
        let extent = Extent::of_bounds(bounds);
        let balls = PolyData {
            points: balls.iter().map(|b| b.0.position).collect(),
            point_data,
            ..PolyData::default()
        };
        let contacts = PolyData {
            points: f.contacts.iter().map(|c| c.point).collect(),
            point_data: vec![
                Array::vectors("normal", f.contacts.iter().map(|c| c.normal)),
                Array::vectors("force", f.contacts.iter().map(|c| c.force)),
                Array::scalars("gap", f.contacts.iter().map(|c| c.gap)),
            ],
            ..PolyData::default()
        };
        // the file a collection lists: written whole by one process, or this process's
        // piece, joined by rank 0's .pvtp
        let put = |what: &str, poly: &PolyData| -> io::Result<String> {
            let Some(p) = &part else {
                let file = format!("frames/{what}_{k:06}.vtp");
                self.dir.write(&file, &poly.to_vtp(self.format))?;
                return Ok(file);
            };
            let piece = |r: usize| format!("{what}_{k:06}_{r}.vtp");
            let mine = format!("frames/{}", piece(p.rank));
            self.dir.write(&mine, &poly.to_vtp(self.format))?;
            let file = format!("frames/{what}_{k:06}.pvtp");
            if p.rank == 0 {
                self.dir
                    .write(&file, &poly.to_pvtp((0..p.ranks).map(piece)))?;
            }
            Ok(file)
        };
        let b = put("bodies", &balls)?;
        let s = shapes
            .as_ref()
            .map(|poly| put("shapes", poly))
            .transpose()?;
        let c = put("contacts", &contacts)?;
        if part.is_some_and(|p| p.rank != 0) {
            return Ok(());
        }
        let o = self.obstacles_file(f, extent)?;
        self.frames.push(FrameFiles {
            time: f.time,
            bodies: b,
            shapes: s.unwrap_or_default(),
            contacts: c,
            obstacles: o,
        });
        write_collections(&self.dir, &self.frames)
    }

    /// The bodies of `f` that are not balls as polygons: each one's tessellation placed by its
    /// position and orientation; cell data: the body's index, velocity, angular velocity and
    /// `contact_force` (Σ r / h on the body).
    fn shapes_polydata(&mut self, f: &FrameData, force: &[Vec3]) -> PolyData {
        let (mut points, mut polygons, mut body) = (Vec::new(), Vec::new(), Vec::new());
        let shaped = (f.bodies.iter().enumerate()).filter_map(|(i, b)| match b.look {
            Look::Shape(s) => Some((i, b, s)),
            Look::Ball(_) => None,
        });
        for (k, (i, b, shape)) in shaped.enumerate() {
            if k == self.tessellations.len() {
                let t = shape.tessellation().unwrap_or_default();
                self.tessellations.push(t);
            }
            let t = &self.tessellations[k];
            let base = points.len() as u32;
            points.extend(t.vertices.iter().map(|p| {
                let r = crate::shape::rotate(b.orientation, *p);
                Vec3::new(r[0], r[1], r[2]) + b.position
            }));
            polygons.extend(
                t.faces
                    .iter()
                    .map(|face| face.iter().map(|v| v + base).collect()),
            );
            body.extend(std::iter::repeat_n(i, t.faces.len()));
        }
        let at = |i: &usize| &f.bodies[*i];
        PolyData {
            points,
            cell_data: vec![
                Array::scalars("body", body.iter().map(|&i| i as f64)),
                Array::vectors("velocity", body.iter().map(|i| at(i).velocity)),
                Array::vectors(
                    "angular_velocity",
                    body.iter().map(|i| at(i).angular_velocity),
                ),
                Array::vectors("contact_force", body.iter().map(|&i| force[i])),
            ],
            polygons: Some(polygons),
            ..PolyData::default()
        }
    }

    /// The obstacles file of this frame: the last one, unless an obstacle moves or the bodies
    /// left the region it covers (`now`; then a new one over the grown region).
    fn obstacles_file(&mut self, f: &FrameData, now: Extent) -> io::Result<String> {
        let moving = f.obstacles.iter().any(|o| o.motion != Motion::Fixed);
        if let Some((covered, file)) = &self.obstacles {
            if !moving && covered.union(now) == *covered {
                return Ok(file.clone());
            }
        }
        // grown by a quarter of its diagonal on every side, so that bodies spreading slowly
        // do not make a new file at every frame
        let extent = match &self.obstacles {
            Some((covered, _)) => covered.union(now),
            None => now,
        }
        .grown(0.25);
        let file = format!("frames/obstacles_{:06}.vtp", f.step);
        let poly = obstacles_polydata(f.obstacles, f.time, &extent);
        self.dir.write(&file, &poly.to_vtp(self.format))?;
        self.obstacles = Some((extent, file.clone()));
        Ok(file)
    }
}

/// Σ r / h on each body of `f` (A gets the force, B its opposite).
fn contact_forces(f: &FrameData) -> Vec<Vec3> {
    let mut force = vec![Vec3::ZERO; f.bodies.len()];
    for c in &f.contacts {
        if let Some(fa) = force.get_mut(c.a) {
            *fa += c.force;
        }
        if let Some(fb) = c.b.and_then(|j| force.get_mut(j)) {
            *fb += -c.force;
        }
    }
    force
}

/// The frames of the collections in `dir` whose bodies file (part 0 of `bodies.pvd`) is of a
/// step before `first_step` (a restarted run keeps them; missing or unreadable collections
/// give none).
fn frames_before(dir: &OutputDir, first_step: usize) -> Vec<FrameFiles> {
    let listed = |name: &str| -> Vec<(f64, usize, String)> {
        dir.read(name)
            .ok()
            .flatten()
            .map(|s| collection_entries(&String::from_utf8_lossy(&s)))
            .unwrap_or_default()
    };
    let (contacts, obstacles) = (listed("contacts.pvd"), listed("obstacles.pvd"));
    let (bodies, shapes): (Vec<_>, Vec<_>) =
        listed("bodies.pvd").into_iter().partition(|e| e.1 == 0);
    let step = |file: &str| {
        let end = file.rsplit('_').next()?;
        end.trim_end_matches(".vtp").parse::<usize>().ok()
    };
    let mut frames = Vec::new();
    for (k, (time, _, bodies)) in bodies.into_iter().enumerate() {
        let s = step(&bodies);
        if s.is_none_or(|s| s >= first_step) {
            continue;
        }
        let file = |list: &[(f64, usize, String)]| list.get(k).map(|x| x.2.clone());
        frames.push(FrameFiles {
            time,
            bodies,
            shapes: (shapes.iter().find(|x| step(&x.2) == s))
                .map(|x| x.2.clone())
                .unwrap_or_default(),
            contacts: file(&contacts).unwrap_or_default(),
            obstacles: file(&obstacles).unwrap_or_default(),
        });
    }
    frames
}

/// The three .pvd collections of a run's frames in `dir`: bodies.pvd (part 0 the balls, part
/// 1 the other shapes), contacts.pvd and obstacles.pvd, one `<DataSet …/>` per file, each
/// written atomically.
fn write_collections(dir: &OutputDir, frames: &[FrameFiles]) -> io::Result<()> {
    for name in BODIES_NAMES {
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
        );
        for f in frames {
            let files: [&str; 2] = match name {
                "contacts.pvd" => [&f.contacts, ""],
                "obstacles.pvd" => [&f.obstacles, ""],
                _ => [&f.bodies, &f.shapes],
            };
            for (part, file) in files.iter().enumerate() {
                if file.is_empty() {
                    continue;
                }
                let _ = writeln!(
                    s,
                    "<DataSet timestep=\"{}\" group=\"\" part=\"{part}\" file=\"{file}\"/>",
                    f.time
                );
            }
        }
        s.push_str("</Collection>\n</VTKFile>\n");
        dir.write(name, s.as_bytes())?;
    }
    Ok(())
}

/// The (timestep, part, file) entries of a .pvd collection written by [`VtkWriter`] (one
/// `<DataSet …/>` element a line; a missing part reads as 0).
fn collection_entries(pvd: &str) -> Vec<(f64, usize, String)> {
    let attr = |line: &str, name: &str| -> Option<String> {
        let start = line.find(&format!(" {name}=\""))? + name.len() + 3;
        let len = line[start..].find('"')?;
        Some(line[start..start + len].to_string())
    };
    pvd.lines()
        .filter(|l| l.trim_start().starts_with("<DataSet"))
        .filter_map(|l| {
            let part = attr(l, "part").and_then(|p| p.parse().ok()).unwrap_or(0);
            Some((attr(l, "timestep")?.parse().ok()?, part, attr(l, "file")?))
        })
        .collect()
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::scene::Scene;
    use crate::simulation::Params;
    use crate::world::Shape;

    fn extent(sim: &Simulation) -> Extent {
        Extent::around(sim.world.bodies.iter().map(|b| (b.position, b.radius)))
    }

    /// The files `frames/bodies_KKKKKK.vtp` and `frames/contacts_KKKKKK.vtp` of `sim`'s frame
    /// in `format` (written into a scratch folder, removed).
    fn frame_files(sim: &Simulation, format: VtkFormat) -> (Vec<u8>, Vec<u8>) {
        let dir = std::env::temp_dir().join(format!(
            "coulomb-vtk-{format:?}-{}-{}",
            std::process::id(),
            sim.world.bodies.len()
        ));
        let _ = fs::remove_dir_all(&dir);
        let mut w = VtkWriter::new(&dir).unwrap().with_format(format);
        w.frame(sim).unwrap();
        let k = sim.steps_done;
        let read = |f: &str| fs::read(dir.join(format!("frames/{f}_{k:06}.vtp"))).unwrap();
        let files = (read("bodies"), read("contacts"));
        fs::remove_dir_all(&dir).ok();
        files
    }

    fn stepped(scene: Scene, beads: usize, steps: usize) -> Simulation {
        let mut sim = Simulation::new(scene.build(beads, 1), Params::default()).unwrap();
        for _ in 0..steps {
            sim.step().unwrap();
        }
        sim
    }

    /// The value of attribute `name` in the XML element `elem`.
    fn attr<'a>(elem: &'a str, name: &str) -> &'a str {
        let key = format!(" {name}=\"");
        let start = elem.find(&key).map(|k| k + key.len()).expect(name);
        let len = elem[start..].find('"').unwrap();
        &elem[start..start + len]
    }

    /// The f64 values of the appended array whose `<DataArray` element starts at `at`.
    fn appended_f64(file: &[u8], at: usize) -> Vec<f64> {
        let text = String::from_utf8_lossy(file);
        let elem = &text[at..at + text[at..].find("/>").unwrap()];
        assert_eq!(attr(elem, "format"), "appended");
        assert_eq!(attr(elem, "type"), "Float64");
        let offset: usize = attr(elem, "offset").parse().unwrap();
        let marker = b"<AppendedData encoding=\"raw\">\n_";
        let base = file
            .windows(marker.len())
            .position(|w| w == marker)
            .unwrap()
            + marker.len();
        let p = base + offset;
        let len = u64::from_le_bytes(file[p..p + 8].try_into().unwrap()) as usize;
        file[p + 8..p + 8 + len]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }

    pub fn binary_frames_hold_the_exact_positions_and_are_smaller() {
        let sim = stepped(Scene::Box, 200, 5);
        let (bin, _) = frame_files(&sim, VtkFormat::Binary);
        let (ascii, _) = frame_files(&sim, VtkFormat::Ascii);
        assert!(
            bin.len() < ascii.len(),
            "binary {} B, ascii {} B",
            bin.len(),
            ascii.len()
        );
        let text = String::from_utf8_lossy(&bin);
        assert!(text.contains("header_type=\"UInt64\""));
        let points = text.find("<Points>").unwrap();
        let at = points + text[points..].find("<DataArray").unwrap();
        let xyz = appended_f64(&bin, at);
        let want: Vec<f64> = sim
            .world
            .bodies
            .iter()
            .flat_map(|b| b.position.to_array())
            .collect();
        assert_eq!(xyz.len(), want.len());
        assert!(xyz
            .iter()
            .zip(&want)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        let r_at = text.find("Name=\"radius\"").unwrap();
        let r_at = text[..r_at].rfind("<DataArray").unwrap();
        let radii = appended_f64(&bin, r_at);
        assert!(radii
            .iter()
            .zip(&sim.world.bodies)
            .all(|(r, b)| *r == b.radius));
        // the ASCII frame lists the same numbers
        let a = String::from_utf8(ascii).unwrap();
        let p = sim.world.bodies[7].position;
        assert!(a.contains(&format!("{} {} {}", p.x, p.y, p.z)));
    }

    /// The names of the data arrays of a .vtp or .pvtp file, in order.
    fn array_names(file: &[u8]) -> Vec<String> {
        let text = String::from_utf8_lossy(file);
        let end = text.find("<AppendedData").unwrap_or(text.len());
        (text[..end].split('<').filter(|e| e.contains("DataArray ")))
            .map(|e| attr(e, "Name").to_string())
            .collect()
    }

    /// The f64 values of the appended array `name` of a binary .vtp file.
    fn named_f64(file: &[u8], name: &str) -> Vec<f64> {
        let text = String::from_utf8_lossy(file);
        let at = text.find(&format!("Name=\"{name}\"")).expect(name);
        appended_f64(file, text[..at].rfind("<DataArray").unwrap())
    }

    /// A frame split over two processes in one (rank 0 the even beads of a stepped box, rank 1
    /// the odd ones, the bounds' reduction standing for MPI's): each piece holds the arrays of
    /// one process plus `body` and `rank`, their values those of the one-process frame to the
    /// bit; the .pvtp declares the same arrays and lists both pieces; the collections list the
    /// .pvtp files where one process lists .vtp files; the obstacles file is byte-identical. A
    /// force missing for a body, or an index for a ball of a part, is refused.
    pub fn frames_split_over_processes_hold_the_arrays_of_one_process() {
        let sim = stepped(Scene::Box, 60, 8);
        let base = std::env::temp_dir().join(format!("coulomb-parts-{}", std::process::id()));
        let (one, two) = (base.join("one"), base.join("two"));
        VtkWriter::new(&one).unwrap().frame(&sim).unwrap();
        let f = sim.frame_data();
        assert!(!f.contacts.is_empty());
        let force = contact_forces(&f);
        let all = Extent::bounds(f.bodies.iter().map(|b| (b.position, radius(b))));
        let mut w = VtkWriter::new(&two).unwrap();
        for rank in [1usize, 0] {
            let ids: Vec<usize> = (rank..f.bodies.len()).step_by(2).collect();
            let part_of = FrameData {
                bodies: ids.iter().map(|&i| f.bodies[i]).collect(),
                contacts: (f.contacts.iter().filter(|c| c.a % 2 == rank).copied()).collect(),
                ..f.clone()
            };
            let force: Vec<Vec3> = ids.iter().map(|&i| force[i]).collect();
            let mut max = |x: &mut [f64]| {
                for (x, a) in x.iter_mut().zip(all) {
                    assert!(*x <= a);
                    *x = a;
                }
            };
            fn part<'a>(
                rank: usize,
                ids: &'a [usize],
                max: &'a mut dyn FnMut(&mut [f64]),
            ) -> Option<FramePart<'a>> {
                let ranks = 2;
                Some(FramePart {
                    rank,
                    ranks,
                    ids,
                    max,
                })
            }
            let refused = w.write_frame(&part_of, &force[1..], part(rank, &ids, &mut max));
            assert_eq!(refused.unwrap_err().kind(), io::ErrorKind::InvalidInput);
            let refused = w.write_frame(&part_of, &force, part(rank, &ids[1..], &mut max));
            assert_eq!(refused.unwrap_err().kind(), io::ErrorKind::InvalidInput);
            w.write_frame(&part_of, &force, part(rank, &ids, &mut max))
                .unwrap();
        }
        let read = |dir: &Path, name: &str| fs::read(dir.join(name)).unwrap();
        let k = sim.steps_done;
        let whole = read(&one, &format!("frames/bodies_{k:06}.vtp"));
        let mut names = array_names(&whole);
        let at = names.iter().position(|n| n == "connectivity").unwrap();
        names.splice(at..at, ["body".to_string(), "rank".to_string()]);
        let pvtp = read(&two, &format!("frames/bodies_{k:06}.pvtp"));
        assert_eq!(array_names(&pvtp), names[..at + 2]);
        let text = String::from_utf8_lossy(&pvtp);
        assert!(text.contains(&format!("<Piece Source=\"bodies_{k:06}_1.vtp\"/>")));
        for (name, width) in [("points", 3), ("radius", 1), ("contact_force", 3)] {
            let want = named_f64(&whole, name);
            let mut seen = 0;
            for rank in 0..2 {
                let piece = read(&two, &format!("frames/bodies_{k:06}_{rank}.vtp"));
                assert_eq!(array_names(&piece), names);
                assert!(named_f64(&piece, "rank").iter().all(|&r| r == rank as f64));
                let got = named_f64(&piece, name);
                for (j, id) in named_f64(&piece, "body").into_iter().enumerate() {
                    let (id, j) = (id as usize * width, j * width);
                    assert_eq!(got[j..j + width], want[id..id + width], "{name}");
                    seen += 1;
                }
            }
            assert_eq!(seen, sim.world.bodies.len());
        }
        let pvd = |dir: &Path, name: &str| String::from_utf8(read(dir, name)).unwrap();
        for name in ["bodies.pvd", "contacts.pvd"] {
            assert_eq!(pvd(&two, name), pvd(&one, name).replace(".vtp", ".pvtp"));
        }
        let obstacles = format!("frames/obstacles_{k:06}.vtp");
        assert_eq!(read(&two, &obstacles), read(&one, &obstacles));
        fs::remove_dir_all(&base).ok();
    }

    fn radius(b: &FrameBody) -> f64 {
        match b.look {
            Look::Ball(r) => r,
            Look::Shape(_) => 0.0,
        }
    }

    pub fn obstacle_surfaces_lie_on_the_obstacles_and_cover_the_beads() {
        for scene in Scene::ALL {
            let sim = stepped(scene, 60, 3);
            let extent = extent(&sim);
            for o in &sim.world.obstacles {
                let (pts, tris) = obstacle_surface(o, sim.time, &extent);
                assert!(!tris.is_empty(), "{}", o.name);
                assert!(tris.iter().flatten().all(|&i| i < pts.len()));
                // every vertex is on the obstacle's surface: zero distance to it
                for p in &pts {
                    let d = o.proximity(*p, 0.0, sim.time).gap.abs();
                    assert!(d < 1e-9, "{} vertex {p:?} at {d}", o.name);
                }
                if let Shape::Plane { normal, .. } = o.shape {
                    // the quad covers every bead's foot on the plane
                    let (u, v) = normal.tangent_basis();
                    let (lo_u, hi_u) = minmax(pts.iter().map(|p| p.dot(u)));
                    let (lo_v, hi_v) = minmax(pts.iter().map(|p| p.dot(v)));
                    for b in &sim.world.bodies {
                        let (bu, bv) = (b.position.dot(u), b.position.dot(v));
                        assert!(bu > lo_u && bu < hi_u && bv > lo_v && bv < hi_v);
                    }
                }
            }
        }
    }

    fn minmax(it: impl Iterator<Item = f64>) -> (f64, f64) {
        it.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        })
    }

    pub fn moving_obstacles_are_drawn_at_their_place() {
        let sim = stepped(Scene::VibratingPlate, 20, 1);
        let plate = sim
            .world
            .obstacles
            .iter()
            .find(|o| o.motion != Motion::Fixed)
            .unwrap();
        let e = extent(&sim);
        for t in [0.0, 0.013, 0.031] {
            let (pts, _) = obstacle_surface(plate, t, &e);
            for p in pts {
                assert!(plate.proximity(p, 0.0, t).gap.abs() < 1e-12);
            }
        }
        // a rotating drum turns by ω t
        let drum = Obstacle {
            name: "drum".into(),
            material: 0,
            shape: Shape::CylinderInside {
                point: Vec3::ZERO,
                axis: Vec3::Y,
                radius: 1.0,
            },
            motion: Motion::Rotate {
                center: Vec3::ZERO,
                axis: Vec3::Y,
                omega: 2.0,
            },
        };
        let (p0, _) = obstacle_surface(&drum, 0.0, &e);
        let (p1, _) = obstacle_surface(&drum, 0.25, &e);
        let radial = |p: Vec3| p - Vec3::Y * p.y;
        let (a, b) = (radial(p0[0]), radial(p1[0]));
        let angle = a.cross(b).dot(Vec3::Y).atan2(a.dot(b));
        assert!((angle - 0.5).abs() < 1e-12, "{angle}");
    }

    pub fn writer_keeps_one_obstacles_file_when_nothing_moves_and_resumes() {
        let dir = std::env::temp_dir().join(format!("coulomb-vtk-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let mut sim = Simulation::new(Scene::Box.build(30, 1), Params::default()).unwrap();
        let mut w = VtkWriter::new(&dir).unwrap();
        for _ in 0..3 {
            w.frame(&sim).unwrap();
            for _ in 0..5 {
                sim.step().unwrap();
            }
        }
        let pvd = fs::read_to_string(dir.join("obstacles.pvd")).unwrap();
        let files = collection_entries(&pvd);
        assert_eq!(files.len(), 3);
        // the beads fall and stay inside the first frame's (grown) extent: one file
        assert!(files.iter().all(|f| f.2 == files[0].2), "{pvd}");
        let obstacles = fs::read(dir.join(&files[0].2)).unwrap();
        let text = String::from_utf8_lossy(&obstacles);
        assert!(
            text.contains("NumberOfPolys=\"10\""),
            "5 planes, 2 triangles each"
        );
        // a restart at step 10 keeps frames 0 and 5, then adds its own
        let mut r = VtkWriter::new(&dir).unwrap().resumed(10);
        assert_eq!(r.frames.len(), 2);
        r.frame(&sim).unwrap();
        let beads = collection_entries(&fs::read_to_string(dir.join("bodies.pvd")).unwrap());
        let names: Vec<&str> = beads.iter().map(|x| x.2.as_str()).collect();
        assert_eq!(
            names,
            [
                "frames/bodies_000000.vtp",
                "frames/bodies_000005.vtp",
                "frames/bodies_000015.vtp"
            ]
        );
        fs::remove_dir_all(&dir).ok();
    }

    /// The sphere frames are those of the writer before the two writers became one (issue 52,
    /// item 4): the FNV-1a fingerprints of the folders (file names and bytes) were recorded
    /// with the sphere-only `VtkWriter` (commit 79e1757) on beads, contacts and times set by
    /// hand (no physics involved): three frames, the beads moving away (the obstacles' extent
    /// grows), binary and ASCII.
    pub fn sphere_frames_are_those_of_the_sphere_only_writer() {
        let mut got = Vec::new();
        for format in [VtkFormat::Binary, VtkFormat::Ascii] {
            let dir = std::env::temp_dir().join(format!("coulomb-golden-{}", std::process::id()));
            let _ = fs::remove_dir_all(&dir);
            let mut sim = Simulation::new(Scene::Box.build(4, 1), Params::default()).unwrap();
            let mut w = VtkWriter::new(&dir).unwrap().with_format(format);
            for (frame, k) in [0usize, 5, 9].into_iter().enumerate() {
                let f = frame as f64;
                for (i, b) in sim.world.bodies.iter_mut().enumerate() {
                    let x = i as f64;
                    b.position = Vec3::new(0.01 * x + 0.3 * f, 0.02 + f * f, 0.05 * x + 0.1);
                    b.velocity = Vec3::new(0.1 * x, -0.2 * f, 0.3);
                    b.angular_velocity = Vec3::new(f, 0.5 * x, -0.25);
                    b.radius = 0.005 + 0.001 * x;
                }
                sim.contacts = (0..frame)
                    .map(|i| crate::contact::Contact {
                        body: i,
                        partner: match i {
                            0 => Partner::Obstacle(0, 0),
                            _ => Partner::Body(i + 1),
                        },
                        normal: Vec3::Z,
                        t1: Vec3::X,
                        t2: Vec3::Y,
                        point: Vec3::new(0.1 * i as f64, 0.0, 0.001),
                        gap: -1e-4 * (i + 1) as f64,
                        normal_velocity: 0.0,
                        impulse: [1e-3 * (i + 1) as f64, 2e-4, -3e-4 / 7.0],
                    })
                    .collect();
                (sim.steps_done, sim.time) = (k, k as f64 * 1e-3 / 3.0);
                w.frame(&sim).unwrap();
            }
            let mut files: Vec<_> = [dir.clone(), dir.join("frames")]
                .iter()
                .flat_map(|d| fs::read_dir(d).unwrap().map(|e| e.unwrap().path()))
                .filter(|p| p.is_file())
                .collect();
            files.sort();
            let mut h: u64 = 0xcbf2_9ce4_8422_2325;
            for f in files {
                let name = f.strip_prefix(&dir).unwrap().to_string_lossy().into_owned();
                for b in name.bytes().chain(fs::read(&f).unwrap()) {
                    h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
                }
            }
            got.push(h);
            fs::remove_dir_all(&dir).ok();
        }
        assert_eq!(
            got,
            [0x4e7b_ef5d_299a_4c09, 0x06fa_bd14_a9a3_b0e6],
            "{got:x?}"
        );
    }

    pub fn stats_continue_after_a_restart() {
        let dir = std::env::temp_dir().join(format!("coulomb-stats-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let mut sim = Simulation::new(Scene::Box.build(10, 1), Params::default()).unwrap();
        let stats: Vec<StepStats> = (0..6).map(|_| sim.step().unwrap()).collect();
        write_stats(&dir, &stats).unwrap();
        // restarted at step 4: rows 0..3 kept, the new 4, 5 appended
        write_stats_continued(&dir, 4, &stats[4..]).unwrap();
        let csv = fs::read_to_string(dir.join("stats.csv")).unwrap();
        let steps: Vec<&str> = csv.lines().skip(1).map(|l| &l[..1]).collect();
        assert_eq!(steps, ["0", "1", "2", "3", "4", "5"]);
        let json: Vec<serde_json::Value> =
            serde_json::from_str(&fs::read_to_string(dir.join("stats.json")).unwrap()).unwrap();
        let steps: Vec<u64> = json.iter().map(|v| v["step"].as_u64().unwrap()).collect();
        assert_eq!(steps, [0, 1, 2, 3, 4, 5]);
        // the rows of every scene: the record's keys, the sphere engine's under "details"
        let row = json[5].as_object().unwrap();
        assert_eq!(row.len(), CSV_HEADER.split(',').count() + 1);
        assert!(CSV_HEADER.split(',').all(|k| row.contains_key(k)));
        assert_eq!(
            row["details"]["subproblems"].as_u64(),
            Some(stats[5].subproblems as u64)
        );
        assert!(row["details"].get("contacts").is_none());
        fs::remove_dir_all(&dir).ok();
    }
    pub fn rigid_frames_hold_each_body_as_its_polygons() {
        use crate::model::{BodySpec, ObstacleSpec, SceneModel};
        use crate::shape::{BodyShape, IDENTITY};
        let mut m = SceneModel::default();
        m.step.h = 1e-3;
        m.obstacles.push(ObstacleSpec::fixed(
            "floor",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        let h = 0.5f64.sqrt();
        m.bodies.push(BodySpec::new(
            BodyShape::Cuboid {
                half_extents: [0.1, 0.2, 0.05],
            },
            Vec3::new(1.0, 2.0, 0.05),
            [h, 0.0, 0.0, h],
            1000.0,
        ));
        m.bodies.push(BodySpec::new(
            BodyShape::Cylinder {
                radius: 0.05,
                half_height: 0.1,
            },
            Vec3::new(0.0, 0.0, 0.5),
            IDENTITY,
            1000.0,
        ));
        let mut scene = crate::scene::rigid::RigidScene::new(&m).unwrap();
        let dir = std::env::temp_dir().join(format!("coulomb-rigid-vtk-{}", std::process::id()));
        let mut w = VtkWriter::new(&dir).unwrap().with_format(VtkFormat::Ascii);
        scene.step().unwrap();
        w.frame(&scene).unwrap();
        let text = fs::read_to_string(dir.join("frames/shapes_000001.vtp")).unwrap();
        let cyl = BodyShape::Cylinder {
            radius: 0.05,
            half_height: 0.1,
        }
        .tessellation()
        .unwrap();
        let polys = 6 + cyl.faces.len();
        assert!(
            text.contains(&format!("NumberOfPolys=\"{polys}\"")),
            "{text}"
        );
        // the box turned 90° about z: its x half-extent 0.1 now along y, so its corners lie
        // at x = 1 ± 0.2, y = 2 ± 0.1
        let x = scene.world.positions()[0];
        let pts = &w.tessellations[0].vertices;
        let placed: Vec<[f64; 3]> = pts
            .iter()
            .map(|p| {
                let r = crate::shape::rotate([h, 0.0, 0.0, h], *p);
                [r[0] + x[0], r[1] + x[1], r[2] + x[2]]
            })
            .collect();
        assert!(placed
            .iter()
            .all(|p| ((p[0] - 1.0).abs() - 0.2).abs() < 1e-6));
        assert!(placed
            .iter()
            .all(|p| ((p[1] - 2.0).abs() - 0.1).abs() < 1e-6));
        for f in ["bodies.pvd", "contacts.pvd", "obstacles.pvd"] {
            assert!(dir.join(f).exists(), "{f}");
        }
        let contacts = fs::read_to_string(dir.join("frames/contacts_000001.vtp")).unwrap();
        assert!(contacts.contains("Name=\"force\""));
        let _ = fs::remove_dir_all(&dir);
    }

    pub fn rigid_frames_hold_balls_as_points_with_radii_in_the_same_collection() {
        use crate::model::{BodySpec, ObstacleSpec, SceneModel};
        use crate::shape::IDENTITY;
        let mut m = SceneModel::default();
        m.step.h = 1e-3;
        m.obstacles.push(ObstacleSpec::fixed(
            "floor",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        m.bodies.push(BodySpec::new(
            BodyShape::Cuboid {
                half_extents: [0.1, 0.2, 0.05],
            },
            Vec3::new(1.0, 2.0, 0.05),
            IDENTITY,
            1000.0,
        ));
        for (x, r) in [(0.0, 0.05), (0.5, 0.08)] {
            m.bodies.push(BodySpec::new(
                BodyShape::Sphere { radius: r },
                Vec3::new(x, 0.0, 0.5),
                IDENTITY,
                1000.0,
            ));
        }
        let mut scene = crate::scene::rigid::RigidScene::new(&m).unwrap();
        let dir = std::env::temp_dir().join(format!("coulomb-rigid-balls-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let mut w = VtkWriter::new(&dir).unwrap();
        for _ in 0..2 {
            scene.step().unwrap();
            w.frame(&scene).unwrap();
        }
        // the cuboid alone as polygons
        let body =
            String::from_utf8_lossy(&fs::read(dir.join("frames/shapes_000002.vtp")).unwrap())
                .into_owned();
        assert!(body.contains("NumberOfPolys=\"6\""), "{body}");
        // the balls as two points: centres exact, radii and velocities as point data
        let file = fs::read(dir.join("frames/bodies_000002.vtp")).unwrap();
        let text = String::from_utf8_lossy(&file).into_owned();
        assert!(
            text.contains("NumberOfPoints=\"2\" NumberOfVerts=\"2\""),
            "{text}"
        );
        let at = |name: &str| {
            text.find(&format!("Name=\"{name}\"")).unwrap() - "<DataArray type=\"Float64\" ".len()
        };
        let radius = appended_f64(&file, at("radius"));
        assert_eq!(radius, [0.05, 0.08]);
        let points = appended_f64(&file, at("points"));
        let x = scene.world.positions();
        assert_eq!(points, [x[1], x[2]].concat());
        let v = appended_f64(&file, at("velocity"));
        assert_eq!(
            v,
            [scene.world.velocities()[1], scene.world.velocities()[2]].concat()
        );
        assert_eq!(appended_f64(&file, at("body")), [1.0, 2.0]);
        // the cuboid's contact force on each of its faces: Σ r / h over its points on the floor
        let shapes = fs::read(dir.join("frames/shapes_000002.vtp")).unwrap();
        let at = String::from_utf8_lossy(&shapes)
            .find("Name=\"contact_force\"")
            .unwrap();
        let force = appended_f64(&shapes, at - "<DataArray type=\"Float64\" ".len());
        let h = scene.world.settings().h;
        let mut want = Vec3::ZERO;
        for c in scene.world.contacts() {
            assert_eq!(c.key(), (0, crate::contact::Partner::Obstacle(0, 0)));
            want += c.world_impulse() * (1.0 / h);
        }
        assert!(want.z > 0.0, "{want:?}");
        assert_eq!(force, [want.to_array(); 6].concat());
        // one collection: part 0 the balls, part 1 the other shapes, per frame
        let pvd = fs::read_to_string(dir.join("bodies.pvd")).unwrap();
        assert!(
            pvd.contains("part=\"1\" file=\"frames/shapes_000001.vtp\""),
            "{pvd}"
        );
        assert!(
            pvd.contains("part=\"0\" file=\"frames/bodies_000002.vtp\""),
            "{pvd}"
        );
        // a restart from step 2 keeps frame 1's two parts and drops frame 2's
        let mut w = VtkWriter::new(&dir).unwrap().resumed(2);
        scene.step().unwrap();
        w.frame(&scene).unwrap();
        let pvd = fs::read_to_string(dir.join("bodies.pvd")).unwrap();
        for f in [
            "shapes_000001",
            "bodies_000001",
            "shapes_000003",
            "bodies_000003",
        ] {
            assert!(pvd.contains(f), "{f}: {pvd}");
        }
        assert!(!pvd.contains("shapes_000002"), "{pvd}");
        let _ = fs::remove_dir_all(&dir);
    }
}
