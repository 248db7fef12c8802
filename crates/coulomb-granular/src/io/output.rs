//! Outputs: per-step statistics as CSV and JSON, and VTK PolyData frames (.vtp) indexed by
//! ParaView collections (.pvd): the beads (positions, radii, velocities, contact forces), the
//! contacts (points, normals, forces, gaps) and the obstacles as surfaces (triangles).
//!
//! Frames are binary by default ([`VtkFormat::Binary`]: VTK XML with raw appended data,
//! `header_type="UInt64"`, little-endian; 8 bytes a number instead of ~20 characters, so a
//! frame of 10⁶ beads is ~100 MB instead of ~300 MB and is written without formatting
//! numbers); [`VtkFormat::Ascii`] writes the same arrays as text.

pub use crate::bodies::surface::{obstacle_surface, Extent, CYLINDER_SEGMENTS};
use crate::math::Vec3;
use crate::output_dir::OutputDir;
use crate::shape::BodyShape;
use crate::simulation::{Simulation, StepStats};
use crate::world::{Motion, Obstacle};
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
        let c = components.max(1);
        match self {
            Values::F64(v) => {
                for row in v.chunks(c) {
                    let line: Vec<String> = row.iter().map(|x| x.to_string()).collect();
                    out.push_str(&line.join(" "));
                    out.push('\n');
                }
            }
            Values::I64(v) => {
                for row in v.chunks(c) {
                    let line: Vec<String> = row.iter().map(|x| x.to_string()).collect();
                    out.push_str(&line.join(" "));
                    out.push('\n');
                }
            }
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
/// triangles.
#[derive(Debug, Clone, PartialEq, Default)]
struct PolyData {
    points: Vec<Vec3>,
    point_data: Vec<Array>,
    cell_data: Vec<Array>,
    /// triangles (point indices); none: one vertex cell per point
    triangles: Option<Vec<[usize; 3]>>,
    /// polygons of any size (point indices), instead of `triangles` when given
    polygons: Option<Vec<Vec<u32>>>,
}

impl PolyData {
    /// The .vtp file.
    fn to_vtp(&self, format: VtkFormat) -> Vec<u8> {
        let n = self.points.len();
        let (cells, conn, offsets): (usize, Vec<i64>, Vec<i64>) =
            match (&self.triangles, &self.polygons) {
                (_, Some(p)) => (
                    p.len(),
                    p.iter().flatten().map(|&i| i as i64).collect(),
                    p.iter()
                        .scan(0i64, |end, f| {
                            *end += f.len() as i64;
                            Some(*end)
                        })
                        .collect(),
                ),
                (None, None) => (n, (0..n as i64).collect(), (1..=n as i64).collect()),
                (Some(t), None) => (
                    t.len(),
                    t.iter().flatten().map(|&i| i as i64).collect(),
                    (1..=t.len() as i64).map(|k| 3 * k).collect(),
                ),
            };
        let polys = self.triangles.is_some() || self.polygons.is_some();
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
            let comps = if components > 1 {
                format!(" NumberOfComponents=\"{components}\"")
            } else {
                String::new()
            };
            let ty = v.vtk_type();
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
            let scalars = arrays.iter().find(|a| a.components == 1);
            let vectors = arrays.iter().find(|a| a.components == 3);
            let _ = write!(xml, "<{tag}");
            if let Some(a) = scalars {
                let _ = write!(xml, " Scalars=\"{}\"", a.name);
            }
            if let Some(a) = vectors {
                let _ = write!(xml, " Vectors=\"{}\"", a.name);
            }
            xml.push_str(">\n");
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
}

/// The total contact force Σ r / h on each sphere (world frame).
fn contact_forces(sim: &Simulation) -> Vec<Vec3> {
    let h = sim.params.h;
    let mut force = vec![Vec3::ZERO; sim.world.bodies.len()];
    for c in &sim.contacts {
        let f = c.world_impulse() * (1.0 / h);
        if let Some(fa) = force.get_mut(c.body) {
            *fa += f;
        }
        if let crate::contact::Partner::Body(j) = c.partner {
            if let Some(fb) = force.get_mut(j) {
                *fb += -f;
            }
        }
    }
    force
}

/// The beads of `sim` as PolyData: points = centres, point data radius, velocity, angular
/// velocity and the total contact force Σ r / h on each sphere.
fn beads_polydata(sim: &Simulation) -> PolyData {
    let b = &sim.world.bodies;
    PolyData {
        points: b.iter().map(|s| s.position).collect(),
        point_data: vec![
            Array::scalars("radius", b.iter().map(|s| s.radius)),
            Array::vectors("velocity", b.iter().map(|s| s.velocity)),
            Array::vectors("angular_velocity", b.iter().map(|s| s.angular_velocity)),
            Array::vectors("contact_force", contact_forces(sim).into_iter()),
        ],
        cell_data: Vec::new(),
        triangles: None,
        polygons: None,
    }
}

/// The active contacts of the last step: points, normals, forces r / h, gaps.
fn contacts_polydata(sim: &Simulation) -> PolyData {
    let h = sim.params.h;
    let c = &sim.contacts;
    PolyData {
        points: c.iter().map(|x| x.point).collect(),
        point_data: vec![
            Array::vectors("normal", c.iter().map(|x| x.normal)),
            Array::vectors("force", c.iter().map(|x| x.world_impulse() * (1.0 / h))),
            Array::scalars("gap", c.iter().map(|x| x.gap)),
        ],
        cell_data: Vec::new(),
        triangles: None,
        polygons: None,
    }
}

/// The frame of the beads and of the contacts (two .vtp files) in `format`.
pub fn vtp_frame_with(sim: &Simulation, format: VtkFormat) -> (Vec<u8>, Vec<u8>) {
    (
        beads_polydata(sim).to_vtp(format),
        contacts_polydata(sim).to_vtp(format),
    )
}

/// VTK PolyData (.vtp, ASCII) of the spheres: points = centres, point data radius, velocity,
/// angular velocity and the total contact force Σ r / h on each sphere; plus a second file
/// with one vertex per contact (point, normal, force r/h, gap).
pub fn vtp_frame(sim: &Simulation) -> (String, String) {
    let (b, c) = vtp_frame_with(sim, VtkFormat::Ascii);
    (
        String::from_utf8_lossy(&b).into_owned(),
        String::from_utf8_lossy(&c).into_owned(),
    )
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
        triangles.extend(
            tris.into_iter()
                .map(|[a, b, c]| [a + base, b + base, c + base]),
        );
    }
    PolyData {
        points,
        point_data: Vec::new(),
        cell_data: vec![Array::scalars("obstacle", index.into_iter())],
        triangles: Some(triangles),
        polygons: None,
    }
}

/// One frame of the collections: time, the beads, contacts and obstacles files.
#[derive(Debug, Clone, PartialEq)]
struct FrameFiles {
    time: f64,
    beads: String,
    contacts: String,
    obstacles: String,
    /// a rigid scene's balls as points (`frames/balls_KKKKKK.vtp`, part 1 of `bodies.pvd`);
    /// empty when none
    balls: String,
}

/// Writes VTK frames into a directory and the ParaView collections `bodies.pvd`,
/// `contacts.pvd` and `obstacles.pvd` indexing them. Obstacles are written as triangles into
/// `frames/obstacles_KKKKKK.vtp` when they move or when the region they must cover (the
/// bodies' [`Extent`], only ever grown) has grown; otherwise the collection points again to
/// the last obstacles file (a scene whose obstacles are fixed has one file as long as the
/// beads stay inside the first extent).
#[derive(Debug)]
pub struct VtkWriter {
    dir: Arc<OutputDir>,
    format: VtkFormat,
    frames: Vec<FrameFiles>,
    /// the region the last obstacles file covers, and that file
    obstacles: Option<(Extent, String)>,
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
        }
    }

    /// A writer into `dir` that continues the collections found there (a restarted run): the
    /// frames before step `first_step` that `bodies.pvd` lists are kept, later ones dropped.
    pub fn resume(dir: &Path, first_step: usize) -> io::Result<Self> {
        let w = Self::new(dir)?;
        Ok(w.resumed(first_step))
    }

    /// The writer continuing the collections of its folder from step `first_step`.
    pub fn resumed(mut self, first_step: usize) -> Self {
        self.frames = frames_before(&self.dir, "bodies.pvd", first_step);
        self
    }

    /// The same writer with frames in `format`.
    pub fn with_format(mut self, format: VtkFormat) -> Self {
        self.format = format;
        self
    }

    /// Writes the frame of the simulation's current state.
    pub fn frame(&mut self, sim: &Simulation) -> io::Result<()> {
        let (beads, contacts) = vtp_frame_with(sim, self.format);
        let k = sim.steps_done;
        let b = format!("frames/bodies_{k:06}.vtp");
        let c = format!("frames/contacts_{k:06}.vtp");
        self.dir.write(&b, &beads)?;
        self.dir.write(&c, &contacts)?;
        let o = self.obstacles_file(sim)?;
        self.frames.push(FrameFiles {
            time: sim.time,
            beads: b,
            contacts: c,
            obstacles: o,
            balls: String::new(),
        });
        self.write_collections()
    }

    /// The obstacles file of this frame: the last one, unless an obstacle moves or the bodies
    /// left the region it covers (then a new one over the grown region).
    fn obstacles_file(&mut self, sim: &Simulation) -> io::Result<String> {
        let now = Extent::of_bodies(sim);
        let moving = sim
            .world
            .obstacles
            .iter()
            .any(|o| o.motion != Motion::Fixed);
        if let Some((covered, file)) = &self.obstacles {
            if !moving && covered.union(now) == *covered {
                return Ok(file.clone());
            }
        }
        // grown by a quarter of its diagonal on every side, so that beads spreading slowly do
        // not make a new file at every frame
        let extent = match &self.obstacles {
            Some((covered, _)) => covered.union(now),
            None => now,
        }
        .grown(0.25);
        let k = sim.steps_done;
        let file = format!("frames/obstacles_{k:06}.vtp");
        let poly = obstacles_polydata(&sim.world.obstacles, sim.time, &extent);
        self.dir.write(&file, &poly.to_vtp(self.format))?;
        self.obstacles = Some((extent, file.clone()));
        Ok(file)
    }

    fn write_collections(&self) -> io::Result<()> {
        write_collections(&self.dir, "bodies.pvd", &self.frames)
    }
}

/// The frames of the collections in `dir` (`bodies`, contacts.pvd, obstacles.pvd) whose
/// bodies file is of a step before `first_step` (a restarted run keeps them; missing or
/// unreadable collections give none).
fn frames_before(dir: &OutputDir, bodies: &str, first_step: usize) -> Vec<FrameFiles> {
    let listed = |name: &str| -> Vec<(f64, String)> {
        dir.read(name)
            .ok()
            .flatten()
            .map(|s| collection_entries(&String::from_utf8_lossy(&s)))
            .unwrap_or_default()
    };
    let contacts = listed("contacts.pvd");
    let obstacles = listed("obstacles.pvd");
    // bodies.pvd lists a rigid scene's ball files (part 1) beside its body files
    let (balls, bodies): (Vec<_>, Vec<_>) = listed(bodies)
        .into_iter()
        .partition(|(_, f)| f.starts_with("frames/balls_"));
    let mut frames = Vec::new();
    for (k, (time, beads)) in bodies.into_iter().enumerate() {
        let step = beads
            .rsplit('_')
            .next()
            .and_then(|s| s.trim_end_matches(".vtp").parse::<usize>().ok());
        if step.is_none_or(|s| s >= first_step) {
            continue;
        }
        let file = |list: &[(f64, String)]| list.get(k).map(|x| x.1.clone()).unwrap_or_default();
        let ball_file = balls
            .iter()
            .find(|(_, f)| f.trim_start_matches("frames/balls_") == step_suffix(&beads))
            .map(|x| x.1.clone())
            .unwrap_or_default();
        frames.push(FrameFiles {
            time,
            beads,
            contacts: file(&contacts),
            obstacles: file(&obstacles),
            balls: ball_file,
        });
    }
    frames
}

/// The `KKKKKK.vtp` end of a frame file's name.
fn step_suffix(file: &str) -> &str {
    file.rsplit('_').next().unwrap_or("")
}

/// The three .pvd collections of a run's frames in `dir`: `bodies` (the beads' or bodies'
/// files), contacts.pvd and obstacles.pvd, one `<DataSet …/>` per frame that has the file,
/// each written atomically.
fn write_collections(dir: &OutputDir, bodies: &str, frames: &[FrameFiles]) -> io::Result<()> {
    for name in [bodies, "contacts.pvd", "obstacles.pvd"] {
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
        );
        for f in frames {
            let files: [&str; 2] = match name {
                "contacts.pvd" => [&f.contacts, ""],
                "obstacles.pvd" => [&f.obstacles, ""],
                _ => [&f.beads, &f.balls],
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

/// The (timestep, file) entries of a .pvd collection written by [`VtkWriter`] (one
/// `<DataSet …/>` element a line).
fn collection_entries(pvd: &str) -> Vec<(f64, String)> {
    let attr = |line: &str, name: &str| -> Option<String> {
        let start = line.find(&format!(" {name}=\""))? + name.len() + 3;
        let len = line[start..].find('"')?;
        Some(line[start..start + len].to_string())
    };
    pvd.lines()
        .filter(|l| l.trim_start().starts_with("<DataSet"))
        .filter_map(|l| Some((attr(l, "timestep")?.parse().ok()?, attr(l, "file")?)))
        .collect()
}

// ------------------------------------------------------------------------------------------
// Rigid bodies of any shape (issue 41)
// ------------------------------------------------------------------------------------------

fn v3a(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// The bodies of a rigid scene as polygons: each body's tessellation (shape frame, computed
/// once: polyhedra as their faces, curved shapes with [`crate::shape::CURVE_SEGMENTS`]
/// segments) placed by its position and orientation; cell data: the body's index, its
/// velocity and angular velocity.
fn rigid_bodies_polydata(
    scene: &crate::rigid_scene::RigidScene,
    shapes: &[crate::shape::Tessellation],
) -> PolyData {
    let w = &scene.world;
    let (x, q, v, om) = (
        w.positions(),
        w.orientations(),
        w.velocities(),
        w.angular_velocities(),
    );
    let mut points = Vec::new();
    let mut polygons = Vec::new();
    let (mut body, mut vel, mut ang) = (Vec::new(), Vec::new(), Vec::new());
    for (i, t) in shapes.iter().enumerate() {
        if matches!(scene.shapes.get(i), Some(BodyShape::Sphere { .. })) {
            continue;
        }
        let base = points.len() as u32;
        for p in &t.vertices {
            let r = crate::shape::rotate(q[i], *p);
            points.push(Vec3::new(r[0] + x[i][0], r[1] + x[i][1], r[2] + x[i][2]));
        }
        for f in &t.faces {
            polygons.push(f.iter().map(|k| k + base).collect());
            body.push(i as f64);
            vel.push(v3a(v[i]));
            ang.push(v3a(om[i]));
        }
    }
    PolyData {
        points,
        point_data: Vec::new(),
        cell_data: vec![
            Array::scalars("body", body.into_iter()),
            Array::vectors("velocity", vel.into_iter()),
            Array::vectors("angular_velocity", ang.into_iter()),
        ],
        triangles: None,
        polygons: Some(polygons),
    }
}

/// The balls of a rigid scene as glyph-ready points (as the sphere scenes' beads): the
/// centres, point data `radius`, `body` (the body's index), `velocity` and
/// `angular_velocity`; `None` when the scene has no ball.
fn rigid_balls_polydata(scene: &crate::rigid_scene::RigidScene) -> Option<PolyData> {
    let balls: Vec<(usize, f64)> = scene
        .shapes
        .iter()
        .enumerate()
        .filter_map(|(i, s)| match s {
            BodyShape::Sphere { radius } => Some((i, *radius)),
            _ => None,
        })
        .collect();
    if balls.is_empty() {
        return None;
    }
    let w = &scene.world;
    let (x, v, om) = (w.positions(), w.velocities(), w.angular_velocities());
    Some(PolyData {
        points: balls.iter().map(|&(i, _)| v3a(x[i])).collect(),
        point_data: vec![
            Array::scalars("radius", balls.iter().map(|b| b.1)),
            Array::scalars("body", balls.iter().map(|b| b.0 as f64)),
            Array::vectors("velocity", balls.iter().map(|&(i, _)| v3a(v[i]))),
            Array::vectors("angular_velocity", balls.iter().map(|&(i, _)| v3a(om[i]))),
        ],
        cell_data: Vec::new(),
        triangles: None,
        polygons: None,
    })
}

/// The last step's contacts of a rigid scene as points (one per manifold point): the normal
/// (from B to A), the force (the impulse in world axes over h, acting on A), the normal
/// impulse r_N and the gap at the start of the step.
fn rigid_contacts_polydata(scene: &crate::rigid_scene::RigidScene) -> PolyData {
    let h = scene.world.settings().h;
    let c = scene.world.contacts();
    PolyData {
        points: c.iter().map(|c| v3a(c.point)).collect(),
        point_data: vec![
            Array::vectors("normal", c.iter().map(|c| v3a(c.normal))),
            Array::vectors(
                "force",
                c.iter().map(|c| v3a(c.world_impulse()) * (1.0 / h)),
            ),
            Array::scalars("normal_impulse", c.iter().map(|c| c.impulse[0])),
            Array::scalars("gap", c.iter().map(|c| c.gap)),
        ],
        cell_data: Vec::new(),
        triangles: None,
        polygons: None,
    }
}

/// Writes the frames of a rigid scene into a directory: `frames/bodies_KKKKKK.vtp` (each body
/// but the balls as its shape's polygons), `frames/balls_KKKKKK.vtp` (the balls as points
/// with a `radius` array, for glyphs; part 1 of the same frame in `bodies.pvd`, only when the
/// scene has balls), `frames/contacts_KKKKKK.vtp` (contact points, normals, forces)
/// and the obstacles (`frames/obstacles_KKKKKK.vtp`, written again only when one moves), with
/// the collections `bodies.pvd`, `contacts.pvd` and `obstacles.pvd`.
#[derive(Debug)]
pub struct RigidVtkWriter {
    dir: Arc<OutputDir>,
    format: VtkFormat,
    shapes: Vec<crate::shape::Tessellation>,
    frames: Vec<FrameFiles>,
    obstacles: Option<String>,
}

impl RigidVtkWriter {
    /// A writer into `dir` (created) for `scene`: the bodies' shapes tessellated once here.
    pub fn new(dir: &Path, scene: &crate::rigid_scene::RigidScene) -> io::Result<Self> {
        let mut out = OutputDir::open(dir)?;
        out.check(&BODIES_NAMES)?;
        out.open_frames()?;
        Ok(Self::in_dir(Arc::new(out), scene))
    }

    /// A writer into the output folder `dir` (its `frames/` opened) for `scene`.
    pub fn in_dir(dir: Arc<OutputDir>, scene: &crate::rigid_scene::RigidScene) -> Self {
        Self {
            dir,
            format: VtkFormat::Binary,
            shapes: scene.tessellations(),
            frames: Vec::new(),
            obstacles: None,
        }
    }

    /// The writer continuing the collections of its folder from step `first_step`.
    pub fn resumed(mut self, first_step: usize) -> Self {
        self.frames = frames_before(&self.dir, "bodies.pvd", first_step);
        self
    }

    /// A writer into `dir` for `scene` that continues the collections found there (a
    /// restarted run): the frames before step `first_step` that `bodies.pvd` lists are kept,
    /// later ones dropped.
    pub fn resume(
        dir: &Path,
        scene: &crate::rigid_scene::RigidScene,
        first_step: usize,
    ) -> io::Result<Self> {
        Ok(Self::new(dir, scene)?.resumed(first_step))
    }

    /// The same writer with `format`.
    pub fn with_format(mut self, format: VtkFormat) -> Self {
        self.format = format;
        self
    }

    /// Writes the frame of the scene's current state.
    pub fn frame(&mut self, scene: &crate::rigid_scene::RigidScene) -> io::Result<()> {
        // bodies inserted since the last frame (an inlet pouring): their shapes tessellated
        let have = self.shapes.len().min(scene.shapes.len());
        self.shapes.extend(
            scene.shapes[have..]
                .iter()
                .map(|s| s.tessellation().unwrap_or_default()),
        );
        let k = scene.world.steps();
        let b = format!("frames/bodies_{k:06}.vtp");
        let c = format!("frames/contacts_{k:06}.vtp");
        let bodies = rigid_bodies_polydata(scene, &self.shapes);
        self.dir.write(&b, &bodies.to_vtp(self.format))?;
        let balls = rigid_balls_polydata(scene);
        let ball_file = match &balls {
            Some(poly) => {
                let f = format!("frames/balls_{k:06}.vtp");
                self.dir.write(&f, &poly.to_vtp(self.format))?;
                f
            }
            None => String::new(),
        };
        self.dir
            .write(&c, &rigid_contacts_polydata(scene).to_vtp(self.format))?;
        let moving = scene.obstacles.iter().any(|o| o.motion != Motion::Fixed);
        let o = match &self.obstacles {
            Some(f) if !moving => f.clone(),
            _ => {
                let (mut lo, mut hi) = (
                    Vec3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
                    Vec3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
                );
                for p in &bodies.points {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
                if let Some(poly) = &balls {
                    let radii = match &poly.point_data[0].values {
                        Values::F64(r) => r.as_slice(),
                        Values::I64(_) => &[],
                    };
                    for (p, r) in poly.points.iter().zip(radii) {
                        let r = Vec3::new(*r, *r, *r);
                        lo = lo.min(*p - r);
                        hi = hi.max(*p + r);
                    }
                }
                let extent = if lo.x.is_finite() {
                    Extent { lo, hi }.grown(0.25)
                } else {
                    Extent {
                        lo: Vec3::new(-1.0, -1.0, -1.0),
                        hi: Vec3::new(1.0, 1.0, 1.0),
                    }
                };
                let file = format!("frames/obstacles_{k:06}.vtp");
                let poly = obstacles_polydata(&scene.obstacles, scene.world.time(), &extent);
                self.dir.write(&file, &poly.to_vtp(self.format))?;
                self.obstacles = Some(file.clone());
                file
            }
        };
        self.frames.push(FrameFiles {
            time: scene.world.time(),
            beads: b,
            contacts: c,
            obstacles: o,
            balls: ball_file,
        });
        write_collections(&self.dir, "bodies.pvd", &self.frames)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use crate::simulation::Params;
    use crate::world::Shape;

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

    #[test]
    fn binary_frames_hold_the_exact_positions_and_are_smaller() {
        let sim = stepped(Scene::Box, 200, 5);
        let (bin, _) = vtp_frame_with(&sim, VtkFormat::Binary);
        let (ascii, _) = vtp_frame_with(&sim, VtkFormat::Ascii);
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

    #[test]
    fn obstacle_surfaces_lie_on_the_obstacles_and_cover_the_beads() {
        for scene in Scene::ALL {
            let sim = stepped(scene, 60, 3);
            let extent = Extent::of_bodies(&sim);
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

    #[test]
    fn moving_obstacles_are_drawn_at_their_place() {
        let sim = stepped(Scene::VibratingPlate, 20, 1);
        let plate = sim
            .world
            .obstacles
            .iter()
            .find(|o| o.motion != Motion::Fixed)
            .unwrap();
        let e = Extent::of_bodies(&sim);
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

    #[test]
    fn writer_keeps_one_obstacles_file_when_nothing_moves_and_resumes() {
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
        assert!(files.iter().all(|f| f.1 == files[0].1), "{pvd}");
        let obstacles = fs::read(dir.join(&files[0].1)).unwrap();
        let text = String::from_utf8_lossy(&obstacles);
        assert!(
            text.contains("NumberOfPolys=\"10\""),
            "5 planes, 2 triangles each"
        );
        // a restart at step 10 keeps frames 0 and 5, then adds its own
        let mut r = VtkWriter::resume(&dir, 10).unwrap();
        assert_eq!(r.frames.len(), 2);
        r.frame(&sim).unwrap();
        let beads = collection_entries(&fs::read_to_string(dir.join("bodies.pvd")).unwrap());
        let names: Vec<&str> = beads.iter().map(|x| x.1.as_str()).collect();
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
    #[test]
    fn sphere_frames_are_those_of_the_sphere_only_writer() {
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
                            0 => crate::contact::Partner::Obstacle(0, 0),
                            _ => crate::contact::Partner::Body(i + 1),
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

    #[test]
    fn stats_continue_after_a_restart() {
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
    #[test]
    fn rigid_frames_hold_each_body_as_its_polygons() {
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
        let mut scene = crate::rigid_scene::RigidScene::new(&m).unwrap();
        let dir = std::env::temp_dir().join(format!("coulomb-rigid-vtk-{}", std::process::id()));
        let mut w = RigidVtkWriter::new(&dir, &scene)
            .unwrap()
            .with_format(VtkFormat::Ascii);
        scene.step().unwrap();
        w.frame(&scene).unwrap();
        let text = fs::read_to_string(dir.join("frames/bodies_000001.vtp")).unwrap();
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
        let pts = &w.shapes[0].vertices;
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

    #[test]
    fn rigid_frames_hold_balls_as_points_with_radii_in_the_same_collection() {
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
        let mut scene = crate::rigid_scene::RigidScene::new(&m).unwrap();
        let dir = std::env::temp_dir().join(format!("coulomb-rigid-balls-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let mut w = RigidVtkWriter::new(&dir, &scene).unwrap();
        for _ in 0..2 {
            scene.step().unwrap();
            w.frame(&scene).unwrap();
        }
        // the cuboid alone as polygons
        let body =
            String::from_utf8_lossy(&fs::read(dir.join("frames/bodies_000002.vtp")).unwrap())
                .into_owned();
        assert!(body.contains("NumberOfPolys=\"6\""), "{body}");
        // the balls as two points: centres exact, radii and velocities as point data
        let file = fs::read(dir.join("frames/balls_000002.vtp")).unwrap();
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
        // one collection: part 0 the meshes, part 1 the balls, per frame
        let pvd = fs::read_to_string(dir.join("bodies.pvd")).unwrap();
        assert!(
            pvd.contains("part=\"1\" file=\"frames/balls_000001.vtp\""),
            "{pvd}"
        );
        assert!(
            pvd.contains("part=\"0\" file=\"frames/bodies_000002.vtp\""),
            "{pvd}"
        );
        // a restart from step 2 keeps frame 1's two parts and drops frame 2's
        let mut w = RigidVtkWriter::resume(&dir, &scene, 2).unwrap();
        scene.step().unwrap();
        w.frame(&scene).unwrap();
        let pvd = fs::read_to_string(dir.join("bodies.pvd")).unwrap();
        for f in [
            "balls_000001",
            "bodies_000001",
            "balls_000003",
            "bodies_000003",
        ] {
            assert!(pvd.contains(f), "{f}: {pvd}");
        }
        assert!(!pvd.contains("balls_000002"), "{pvd}");
        let _ = fs::remove_dir_all(&dir);
    }
}
