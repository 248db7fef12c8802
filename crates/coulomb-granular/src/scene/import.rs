//! Particles and meshes from files: spheres from CSV (`x,y,z,r[,vx,vy,vz][,material]`) or
//! NPY ((n, 4) or (n, 7) float64 arrays), triangle meshes from STL (binary or ASCII, read by
//! `stl_io`) and OBJ (read by `tobj`) into vertices (n, 3) and triangles (m, 3), with a
//! scale / rotate / translate transform. Every error names the file.

use crate::math::Vec3;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Why a file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// the file could not be opened or read
    #[error("{}: {source}", path.display())]
    Io {
        /// the file
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
    /// the path is not a regular file of bounded size, or cannot be opened or read
    /// ([`coulomb::input`])
    #[error(transparent)]
    Input(#[from] coulomb::input::InputError),
    /// the content is not what the format requires
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Format {
        /// the file
        path: PathBuf,
        /// the line (1-based), when known
        line: Option<u64>,
        /// what is wrong
        message: String,
    },
}

fn format_err<T>(
    path: &Path,
    line: Option<u64>,
    message: impl Into<String>,
) -> Result<T, ImportError> {
    Err(ImportError::Format {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    })
}

/// A sphere read from a file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParticleRecord {
    /// centre (m)
    pub position: Vec3,
    /// radius (m)
    pub radius: f64,
    /// initial velocity (m/s), when the file has one
    pub velocity: Option<Vec3>,
    /// material name, when the file has one
    pub material: Option<String>,
}

/// Reads spheres from a `.csv` or `.npy` file (by extension).
pub fn read_particles(path: &Path) -> Result<Vec<ParticleRecord>, ImportError> {
    match extension(path).as_deref() {
        Some("csv") => read_csv(path),
        Some("npy") => read_npy(path),
        _ => format_err(path, None, "particle files must end in .csv or .npy"),
    }
}

/// The records [`read_particles`] returns, handed to `emit` one at a time in the same order
/// and to the bit, holding none of them (a CSV file is read row by row; an NPY file's bytes are
/// read whole, its records built one at a time); returns their number. An error where
/// [`read_particles`] gives one (not necessarily the same: the caller reads the file with
/// [`read_particles`] to say why), possibly after some records were emitted.
pub fn for_each_particle(
    path: &Path,
    emit: &mut dyn FnMut(ParticleRecord),
) -> Result<usize, ImportError> {
    match extension(path).as_deref() {
        Some("csv") => csv_each(path, emit),
        Some("npy") => npy_each(path, emit),
        _ => format_err(path, None, "particle files must end in .csv or .npy"),
    }
}

/// [`read_npy`]'s records handed to `emit` one at a time, in order; their number.
fn npy_each(path: &Path, emit: &mut dyn FnMut(ParticleRecord)) -> Result<usize, ImportError> {
    let bytes = coulomb::input::read(path, coulomb::input::Kind::Particles)?;
    let npy = match Npy::parse(&bytes) {
        Ok(npy) => npy,
        Err(e) => return format_err(path, None, format!("not an NPY file: {e}")),
    };
    if !matches!(npy.descr.as_str(), "<f8" | ">f8" | "=f8") {
        return format_err(path, None, format!("dtype {} must be float64", npy.descr));
    }
    let shape = &npy.shape;
    if shape.len() != 2 || !(shape[1] == 4 || shape[1] == 7) {
        return format_err(
            path,
            None,
            format!("shape {shape:?} must be (n, 4) or (n, 7)"),
        );
    }
    let (n, w) = (shape[0], shape[1] as usize);
    if n > 100_000_000 {
        return format_err(path, None, format!("{n} rows: above the limit of 1e8"));
    }
    let n = n as usize;
    let data = &bytes[npy.data_at..];
    if data.len() != n * w * 8 {
        return format_err(
            path,
            None,
            format!(
                "{} bytes of data for shape {shape:?} of float64 ({} expected)",
                data.len(),
                n * w * 8
            ),
        );
    }
    let at = |i: usize, j: usize| {
        let k = if npy.fortran { j * n + i } else { i * w + j };
        let b: [u8; 8] = data[8 * k..8 * k + 8].try_into().expect("8 bytes");
        if npy.descr.starts_with('>') {
            f64::from_be_bytes(b)
        } else {
            f64::from_le_bytes(b)
        }
    };
    for i in 0..n {
        let r = ParticleRecord {
            position: Vec3::new(at(i, 0), at(i, 1), at(i, 2)),
            radius: at(i, 3),
            velocity: (w == 7).then(|| Vec3::new(at(i, 4), at(i, 5), at(i, 6))),
            material: None,
        };
        if let Err(ImportError::Format { message, .. }) = check_record(path, None, &r) {
            return format_err(path, None, format!("row {i}: {message}"));
        }
        emit(r);
    }
    Ok(n)
}

/// The header of an NPY file (NumPy's `.npy` format, versions 1 to 3): the magic string
/// `\x93NUMPY`, the version, the header's length, then the header, a Python dict literal
/// `{'descr': '<f8', 'fortran_order': False, 'shape': (n, 4), }`, then the array's bytes.
///
/// Read here rather than with the `npyz` crate, which this project used before: for these
/// three keys of a fixed dict, npyz parses any Python literal with a pest grammar and big
/// integers (py_literal, num-bigint, pest), dependencies that took a noticeable share of a
/// fresh build (docs/testing.md).
#[derive(Debug, PartialEq)]
struct Npy {
    /// the dtype string, e.g. `<f8`
    descr: String,
    /// column-major (Fortran) order
    fortran: bool,
    /// the array's shape
    shape: Vec<u64>,
    /// where the array's bytes start
    data_at: usize,
}

impl Npy {
    /// Parses the header of `bytes`; an error says what is wrong.
    fn parse(bytes: &[u8]) -> Result<Npy, String> {
        if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
            return Err("no NPY magic string".into());
        }
        let (len, start) = match bytes[6] {
            1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10usize),
            2 | 3 if bytes.len() >= 12 => (
                u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
                12,
            ),
            v => return Err(format!("NPY version {v} (1 to 3 are read)")),
        };
        let end = start
            .checked_add(len)
            .filter(|&e| e <= bytes.len())
            .ok_or("the header runs past the end of the file")?;
        let text = std::str::from_utf8(&bytes[start..end]).map_err(|_| "a header not UTF-8")?;
        let mut p = DictParser { s: text.trim_end() };
        let (mut descr, mut fortran, mut shape) = (None, None, None);
        p.expect('{')?;
        while !p.eat('}') {
            let key = p.string()?;
            p.expect(':')?;
            match key.as_str() {
                "descr" => descr = Some(p.string()?),
                "fortran_order" => fortran = Some(p.boolean()?),
                "shape" => shape = Some(p.tuple()?),
                k => return Err(format!("an unknown header key '{k}'")),
            }
            if !p.eat(',') {
                p.expect('}')?;
                break;
            }
        }
        if !p.s.trim().is_empty() {
            return Err("text after the header's dict".into());
        }
        Ok(Npy {
            descr: descr.ok_or("no 'descr' in the header")?,
            fortran: fortran.ok_or("no 'fortran_order' in the header")?,
            shape: shape.ok_or("no 'shape' in the header")?,
            data_at: end,
        })
    }
}

/// The few tokens of an NPY header: quoted strings, `True`/`False`, tuples of integers.
struct DictParser<'a> {
    s: &'a str,
}

impl DictParser<'_> {
    fn eat(&mut self, c: char) -> bool {
        self.s = self.s.trim_start();
        match self.s.strip_prefix(c) {
            Some(rest) => {
                self.s = rest;
                true
            }
            None => false,
        }
    }

    fn expect(&mut self, c: char) -> Result<(), String> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(format!("'{c}' expected in the header"))
        }
    }

    fn string(&mut self) -> Result<String, String> {
        self.s = self.s.trim_start();
        let q = match self.s.chars().next() {
            Some(q @ ('\'' | '"')) => q,
            _ => return Err("a quoted string expected in the header".into()),
        };
        let body = &self.s[1..];
        let close = body.find(q).ok_or("an unterminated string in the header")?;
        self.s = &body[close + 1..];
        Ok(body[..close].to_string())
    }

    fn boolean(&mut self) -> Result<bool, String> {
        self.s = self.s.trim_start();
        for (word, value) in [("True", true), ("False", false)] {
            if let Some(rest) = self.s.strip_prefix(word) {
                self.s = rest;
                return Ok(value);
            }
        }
        Err("True or False expected in the header".into())
    }

    fn tuple(&mut self) -> Result<Vec<u64>, String> {
        self.expect('(')?;
        let mut out = Vec::new();
        while !self.eat(')') {
            self.s = self.s.trim_start();
            let digits = self.s.bytes().take_while(u8::is_ascii_digit).count();
            let n = self.s[..digits]
                .parse::<u64>()
                .map_err(|_| "a shape of non-negative integers expected in the header")?;
            out.push(n);
            self.s = &self.s[digits..];
            if !self.eat(',') {
                self.expect(')')?;
                break;
            }
        }
        Ok(out)
    }
}

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
}

/// Checks a record: finite centre and velocity, finite positive radius.
fn check_record(path: &Path, line: Option<u64>, r: &ParticleRecord) -> Result<(), ImportError> {
    if !r.position.is_finite() || !r.velocity.unwrap_or(Vec3::ZERO).is_finite() {
        return format_err(path, line, "non-finite position or velocity");
    }
    if !(r.radius.is_finite() && r.radius > 0.0) {
        return format_err(
            path,
            line,
            format!("radius {} must be finite and positive", r.radius),
        );
    }
    Ok(())
}

/// Reads a CSV file whose header names the columns `x, y, z, r` (required), `vx, vy, vz`
/// (together or not at all) and `material` (optional), in any order; other columns are
/// refused. Spaces around fields are ignored.
pub fn read_csv(path: &Path) -> Result<Vec<ParticleRecord>, ImportError> {
    let mut out = Vec::new();
    csv_each(path, &mut |r| out.push(r))?;
    Ok(out)
}

/// [`read_csv`] handing each record to `emit` as it is read; returns their number.
fn csv_each(path: &Path, emit: &mut dyn FnMut(ParticleRecord)) -> Result<usize, ImportError> {
    let bytes = coulomb::input::read(path, coulomb::input::Kind::Particles)?;
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(bytes.as_slice());
    let header = match reader.headers() {
        Ok(h) => h.clone(),
        Err(e) => return format_err(path, Some(1), e.to_string()),
    };
    let mut col: HashMap<&str, usize> = HashMap::new();
    const KNOWN: [&str; 8] = ["x", "y", "z", "r", "vx", "vy", "vz", "material"];
    for (i, name) in header.iter().enumerate() {
        let Some(k) = KNOWN.iter().find(|k| **k == name) else {
            return format_err(
                path,
                Some(1),
                format!(
                    "unknown column '{name}': expected x, y, z, r, optionally vx, vy, vz and material"
                ),
            );
        };
        if col.insert(k, i).is_some() {
            return format_err(path, Some(1), format!("column '{name}' appears twice"));
        }
    }
    for k in ["x", "y", "z", "r"] {
        if !col.contains_key(k) {
            return format_err(path, Some(1), format!("missing column '{k}'"));
        }
    }
    let has_v = ["vx", "vy", "vz"].map(|k| col.contains_key(k));
    if has_v.iter().any(|&b| b) && !has_v.iter().all(|&b| b) {
        return format_err(path, Some(1), "columns vx, vy, vz go together");
    }
    let mut count = 0usize;
    for rec in reader.records() {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                let line = e.position().map(|p| p.line());
                return format_err(path, line, e.to_string());
            }
        };
        let line = rec.position().map(|p| p.line());
        let num = |k: &str| -> Result<f64, ImportError> {
            let s = rec.get(col[k]).unwrap_or("");
            s.parse::<f64>()
                .or_else(|_| format_err(path, line, format!("column '{k}': '{s}' is not a number")))
        };
        let position = Vec3::new(num("x")?, num("y")?, num("z")?);
        let radius = num("r")?;
        let velocity = if has_v[0] {
            Some(Vec3::new(num("vx")?, num("vy")?, num("vz")?))
        } else {
            None
        };
        let material = col
            .get("material")
            .and_then(|&i| rec.get(i))
            .filter(|s| !s.is_empty())
            .map(str::to_string);
        let r = ParticleRecord {
            position,
            radius,
            velocity,
            material,
        };
        check_record(path, line, &r)?;
        count += 1;
        emit(r);
    }
    Ok(count)
}

/// Reads an NPY file holding a float64 array of shape (n, 4) — x, y, z, r — or (n, 7) —
/// x, y, z, r, vx, vy, vz — in C or Fortran order, either byte order.
pub fn read_npy(path: &Path) -> Result<Vec<ParticleRecord>, ImportError> {
    let mut out = Vec::new();
    npy_each(path, &mut |r| out.push(r))?;
    Ok(out)
}

/// A rotation by `degrees` about `axis` (right-handed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// rotation axis (normalized here)
    pub axis: [f64; 3],
    /// angle (degrees)
    pub degrees: f64,
}

/// A scale factor: one for all axes, or one per axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Scale {
    /// the same factor on every axis
    Uniform(f64),
    /// a factor per axis
    PerAxis([f64; 3]),
}

impl Default for Scale {
    fn default() -> Self {
        Scale::Uniform(1.0)
    }
}

/// x ↦ translate + R (scale ∘ x): first the scale, then the rotation, then the translation.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transform {
    /// scale (default 1)
    #[serde(default)]
    pub scale: Scale,
    /// rotation (default none)
    #[serde(default)]
    pub rotate: Option<Rotation>,
    /// translation (m, default 0)
    #[serde(default)]
    pub translate: [f64; 3],
}

impl Transform {
    /// Applies the transform to a point (Rodrigues' formula for the rotation).
    pub fn apply(&self, p: Vec3) -> Vec3 {
        let s = match self.scale {
            Scale::Uniform(k) => [k; 3],
            Scale::PerAxis(k) => k,
        };
        let mut x = Vec3::new(p.x * s[0], p.y * s[1], p.z * s[2]);
        if let Some(r) = &self.rotate {
            let k = Vec3::new(r.axis[0], r.axis[1], r.axis[2]).normalized_or(Vec3::Z);
            let (sin, cos) = r.degrees.to_radians().sin_cos();
            x = x * cos + k.cross(x) * sin + k * (k.dot(x) * (1.0 - cos));
        }
        x + Vec3::new(self.translate[0], self.translate[1], self.translate[2])
    }

    /// Checks that every number is finite, the scale non-zero and the axis non-zero.
    pub fn validate(&self) -> Result<(), String> {
        let s = match self.scale {
            Scale::Uniform(k) => [k; 3],
            Scale::PerAxis(k) => k,
        };
        if !s.iter().all(|k| k.is_finite() && *k != 0.0) {
            return Err(format!("scale {s:?} must be finite and non-zero"));
        }
        if let Some(r) = &self.rotate {
            let a = Vec3::new(r.axis[0], r.axis[1], r.axis[2]);
            if !(a.is_finite() && a.norm() > 0.0 && r.degrees.is_finite()) {
                return Err(format!(
                    "rotate: axis {:?} must be non-zero and degrees {} finite",
                    r.axis, r.degrees
                ));
            }
        }
        if !self.translate.iter().all(|x| x.is_finite()) {
            return Err(format!("translate {:?} must be finite", self.translate));
        }
        Ok(())
    }
}

/// A triangle mesh: vertices (n, 3) and triangles (m, 3) indexing them, counter-clockwise
/// seen from the side the normal points to.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct TriMesh {
    /// vertex positions (m)
    pub vertices: Vec<Vec3>,
    /// vertex indices of each triangle
    pub triangles: Vec<[usize; 3]>,
}

impl TriMesh {
    /// Applies `t` to every vertex. A transform with a negative determinant (an odd number of
    /// negative scale factors) mirrors the mesh, so each triangle's order is reversed to
    /// keep its normals pointing the same way relative to the surface.
    pub fn transformed(mut self, t: &Transform) -> Self {
        for v in &mut self.vertices {
            *v = t.apply(*v);
        }
        let det = match t.scale {
            Scale::Uniform(k) => k * k * k,
            Scale::PerAxis(k) => k[0] * k[1] * k[2],
        };
        if det < 0.0 {
            for tri in &mut self.triangles {
                tri.swap(1, 2);
            }
        }
        self
    }

    /// Checks the mesh: at least one triangle, finite vertices, indices in range, no
    /// degenerate triangle (area below 1e-12 × the squared bounding-box diagonal).
    pub fn validate(&self) -> Result<(), String> {
        if self.triangles.is_empty() {
            return Err("the mesh has no triangle".into());
        }
        if let Some(i) = self.vertices.iter().position(|v| !v.is_finite()) {
            return Err(format!("vertex {i} is not finite"));
        }
        let n = self.vertices.len();
        let (lo, hi) = self.bounds();
        let scale = (hi - lo).norm_sq();
        for (k, t) in self.triangles.iter().enumerate() {
            if t.iter().any(|&i| i >= n) {
                return Err(format!("triangle {k} indexes a vertex ≥ {n}"));
            }
            let [a, b, c] = t.map(|i| self.vertices[i]);
            let area2 = (b - a).cross(c - a).norm();
            if area2.is_nan() || area2 <= 1e-12 * scale {
                return Err(format!("triangle {k} {t:?} is degenerate (zero area)"));
            }
        }
        Ok(())
    }

    /// Checks that the orientation is consistent: no directed edge (a → b) is used by two
    /// triangles (two neighbours must traverse their common edge in opposite directions),
    /// and, for a closed mesh, every edge has two triangles. Needed by [`TriMesh::inside`].
    pub fn check_closed_and_oriented(&self) -> Result<(), String> {
        let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
        for (k, t) in self.triangles.iter().enumerate() {
            for e in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                if let Some(other) = edges.insert(e, k) {
                    return Err(format!(
                        "inconsistent orientation: triangles {other} and {k} both run the edge {} → {}",
                        e.0, e.1
                    ));
                }
            }
        }
        // closed: each directed edge has its reverse
        let mut open: Vec<(usize, usize)> = edges
            .keys()
            .filter(|(a, b)| !edges.contains_key(&(*b, *a)))
            .copied()
            .collect();
        if !open.is_empty() {
            open.sort_unstable();
            return Err(format!(
                "the mesh is not closed: {} boundary edges (the first {} → {})",
                open.len(),
                open[0].0,
                open[0].1
            ));
        }
        Ok(())
    }

    /// The axis-aligned bounding box.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = -lo;
        for v in &self.vertices {
            lo = Vec3::new(lo.x.min(v.x), lo.y.min(v.y), lo.z.min(v.z));
            hi = Vec3::new(hi.x.max(v.x), hi.y.max(v.y), hi.z.max(v.z));
        }
        (lo, hi)
    }

    /// Whether `p` is inside the closed mesh: the parity of the crossings of a ray from `p`
    /// (Möller–Trumbore; the ray's direction is chosen off every axis and diagonal so that it
    /// rarely grazes an edge of a mesh built on a grid). O(triangles).
    pub fn inside(&self, p: Vec3) -> bool {
        let d = Vec3::new(0.577_350_3, 0.577_251_1, 0.577_449_5).normalized_or(Vec3::X);
        let mut crossings = 0usize;
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.vertices[i]);
            let (e1, e2) = (b - a, c - a);
            let q = d.cross(e2);
            let det = e1.dot(q);
            if det.abs() < 1e-300 {
                continue;
            }
            let s = p - a;
            let u = s.dot(q) / det;
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let r = s.cross(e1);
            let v = d.dot(r) / det;
            if v < 0.0 || u + v > 1.0 {
                continue;
            }
            if e2.dot(r) / det > 0.0 {
                crossings += 1;
            }
        }
        crossings % 2 == 1
    }
}

/// Reads a mesh from a `.stl` (binary or ASCII) or `.obj` file (by extension), then applies
/// `transform`. OBJ polygons are triangulated; every object of the file goes into one mesh.
pub fn read_mesh(path: &Path, transform: &Transform) -> Result<TriMesh, ImportError> {
    if let Err(e) = transform.validate() {
        return format_err(path, None, e);
    }
    let mesh = match extension(path).as_deref() {
        Some("stl") => read_stl(path)?,
        Some("obj") => read_obj(path)?,
        _ => return format_err(path, None, "mesh files must end in .stl or .obj"),
    };
    let mesh = mesh.transformed(transform);
    if let Err(e) = mesh.validate() {
        return format_err(path, None, e);
    }
    Ok(mesh)
}

fn read_stl(path: &Path) -> Result<TriMesh, ImportError> {
    let bytes = coulomb::input::read(path, coulomb::input::Kind::Mesh)?;
    let mut reader = std::io::Cursor::new(bytes);
    let m = match stl_io::read_stl(&mut reader) {
        Ok(m) => m,
        Err(e) => return format_err(path, None, format!("not a valid STL file: {e}")),
    };
    Ok(TriMesh {
        vertices: m
            .vertices
            .iter()
            .map(|v| Vec3::new(v.0[0] as f64, v.0[1] as f64, v.0[2] as f64))
            .collect(),
        triangles: m.faces.iter().map(|f| f.vertices).collect(),
    })
}

fn read_obj(path: &Path) -> Result<TriMesh, ImportError> {
    let bytes = coulomb::input::read(path, coulomb::input::Kind::Mesh)?;
    let mut reader = bytes.as_slice();
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    // materials (.mtl) are not used: the loader refuses to open them
    let (models, _) = match tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::GenericFailure)
    }) {
        Ok(r) => r,
        Err(e) => return format_err(path, None, format!("not a valid OBJ file: {e}")),
    };
    let mut mesh = TriMesh::default();
    for m in models {
        let base = mesh.vertices.len();
        let p = &m.mesh.positions;
        mesh.vertices
            .extend(p.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        for t in m.mesh.indices.chunks_exact(3) {
            mesh.triangles.push([
                base + t[0] as usize,
                base + t[1] as usize,
                base + t[2] as usize,
            ]);
        }
    }
    Ok(mesh)
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;

    fn tmp(name: &str, bytes: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("coulomb-import-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    /// An NPY version-1.0 file of float64 values in C order.
    pub(crate) fn npy_bytes(shape: (usize, usize), data: &[f64]) -> Vec<u8> {
        let dict = format!(
            "{{'descr': '<f8', 'fortran_order': False, 'shape': ({}, {}), }}",
            shape.0, shape.1
        );
        let mut header = dict.into_bytes();
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(b' ');
        }
        header.push(b'\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(&header);
        for x in data {
            out.extend_from_slice(&x.to_le_bytes());
        }
        out
    }

    pub fn csv_particles_with_velocities_and_materials() {
        let p = tmp(
            "a.csv",
            b"x, y, z, r, vx, vy, vz, material\n0,0,1,0.1,1,2,3,glass\n1,0,1,0.2,0,0,0,\n",
        );
        let r = read_particles(&p).unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].position, Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(r[0].velocity, Some(Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(r[0].material.as_deref(), Some("glass"));
        assert_eq!(r[1].radius, 0.2);
        assert_eq!(r[1].material, None);
        let p = tmp("b.csv", b"r,z,y,x\n0.1,3,2,1\n");
        let r = read_particles(&p).unwrap();
        assert_eq!(r[0].position, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(r[0].velocity, None);
    }

    pub fn bad_csv_files_name_the_file_and_line() {
        let cases: [(&str, &[u8], &str); 5] = [
            (
                "c1.csv",
                b"x,y,z,radius\n0,0,0,1\n",
                "unknown column 'radius'",
            ),
            ("c2.csv", b"x,y,z\n0,0,0\n", "missing column 'r'"),
            ("c3.csv", b"x,y,z,r\n0,0,0,1\n0,0,abc,1\n", ":3: column 'z'"),
            ("c4.csv", b"x,y,z,r\n0,0,0,-1\n", ":2: radius -1"),
            ("c5.csv", b"x,y,z,r,vx\n0,0,0,1,0\n", "go together"),
        ];
        for (name, bytes, want) in cases {
            let e = read_particles(&tmp(name, bytes)).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(want), "{e}");
        }
        let e = read_particles(Path::new("/nonexistent/p.csv")).unwrap_err();
        assert!(
            matches!(&e, ImportError::Input(i) if i.is_not_found()),
            "{e}"
        );
    }

    pub fn npy_particles() {
        let data = [0.0, 0.0, 1.0, 0.1, 1.0, 0.0, 1.0, 0.2];
        let r = read_particles(&tmp("a.npy", &npy_bytes((2, 4), &data))).unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[1].position, Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(r[1].radius, 0.2);
        let data7 = [0.0, 0.0, 1.0, 0.1, 5.0, 6.0, 7.0];
        let r = read_particles(&tmp("b.npy", &npy_bytes((1, 7), &data7))).unwrap();
        assert_eq!(r[0].velocity, Some(Vec3::new(5.0, 6.0, 7.0)));
        let e = read_particles(&tmp("c.npy", &npy_bytes((2, 3), &data[..6])))
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.npy") && e.contains("(n, 4)"), "{e}");
        let e = read_particles(&tmp("d.npy", b"not numpy"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("d.npy"), "{e}");
        let bad = [0.0, f64::NAN, 1.0, 0.1];
        let e = read_particles(&tmp("e.npy", &npy_bytes((1, 4), &bad)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("row 0"), "{e}");
    }

    /// The NPY header of every version, both orders and byte orders; every malformed header
    /// refused with its reason.
    pub fn npy_headers_orders_and_byte_orders() {
        let npy = Npy::parse(&npy_bytes((2, 4), &[0.0; 8])).unwrap();
        assert_eq!(
            npy,
            Npy {
                descr: "<f8".into(),
                fortran: false,
                shape: vec![2, 4],
                data_at: 128,
            }
        );
        // version 2, Fortran order, big-endian, a 1-tuple-style trailing comma, double quotes
        let with = |version: u8, dict: &str, data: &[u8]| {
            let mut out = b"\x93NUMPY".to_vec();
            out.extend_from_slice(&[version, 0]);
            if version == 1 {
                out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
            } else {
                out.extend_from_slice(&(dict.len() as u32).to_le_bytes());
            }
            out.extend_from_slice(dict.as_bytes());
            out.extend_from_slice(data);
            out
        };
        // the (2, 4) array [[0, 0, 1, 0.1], [1, 0, 1, 0.2]] stored column by column, big-endian
        let columns = [0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.1, 0.2];
        let be: Vec<u8> = columns.iter().flat_map(|x: &f64| x.to_be_bytes()).collect();
        let dict = "{\"descr\": '>f8', 'shape': (2, 4,), 'fortran_order': True}\n";
        let p = tmp("f.npy", &with(2, dict, &be));
        let r = read_particles(&p).unwrap();
        assert_eq!(r[1].position, Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(r[1].radius, 0.2);
        assert_eq!(r[0].radius, 0.1);
        let cases: [(&str, Vec<u8>, &str); 8] = [
            ("h1.npy", b"\x93NUMPY".to_vec(), "no NPY magic"),
            ("h2.npy", with(4, "{}", &[]), "version 4"),
            (
                "h3.npy",
                {
                    let mut b = with(
                        1,
                        "{'descr': '<f8', 'fortran_order': False, 'shape': (0, 4), }",
                        &[],
                    );
                    b.truncate(20);
                    b
                },
                "runs past the end",
            ),
            (
                "h4.npy",
                with(
                    1,
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (1, 4), 'x': 1}",
                    &[],
                ),
                "unknown header key 'x'",
            ),
            (
                "h5.npy",
                with(1, "{'descr': '<f8', 'shape': (1, 4)}", &[0; 32]),
                "no 'fortran_order'",
            ),
            (
                "h6.npy",
                with(
                    1,
                    "{'descr': '<i4', 'fortran_order': False, 'shape': (1, 4)}",
                    &[0; 16],
                ),
                "dtype <i4 must be float64",
            ),
            (
                "h7.npy",
                with(
                    1,
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 4)}",
                    &[0; 32],
                ),
                "32 bytes of data",
            ),
            (
                "h8.npy",
                with(
                    1,
                    "{'descr': '<f8', 'fortran_order': Maybe, 'shape': (1, 4)}",
                    &[0; 32],
                ),
                "True or False",
            ),
        ];
        for (name, bytes, want) in cases {
            let e = read_particles(&tmp(name, &bytes)).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(want), "{name}: {e}");
        }
    }

    /// [`for_each_particle`] hands out the records of [`read_particles`], in order, and fails
    /// where it fails.
    pub fn streamed_particles_are_the_read_ones() {
        let data = [0.0, 0.0, 1.0, 0.1, 1.0, 0.0, 1.0, 0.2];
        let data7 = [0.0, 0.0, 1.0, 0.1, 5.0, 6.0, 7.0];
        let good = [
            tmp("s1.npy", &npy_bytes((2, 4), &data)),
            tmp("s2.npy", &npy_bytes((1, 7), &data7)),
            tmp("s3.csv", b"r,x,y,z,material\n0.1,1,2,3,\n0.2,4,5,6,steel\n"),
        ];
        for p in &good {
            let mut out = Vec::new();
            let n = for_each_particle(p, &mut |r| out.push(r)).unwrap();
            assert_eq!(n, out.len());
            assert_eq!(out, read_particles(p).unwrap(), "{}", p.display());
        }
        let bad = [
            tmp("s4.npy", &npy_bytes((2, 3), &data[..6])),
            tmp("s5.npy", &npy_bytes((1, 4), &[0.0, f64::NAN, 1.0, 0.1])),
            tmp("s6.csv", b"x,y,z,r\n0,0,0,1\n0,0,abc,1\n"),
            tmp("s7.txt", b"x,y,z,r\n"),
        ];
        for p in &bad {
            assert!(read_particles(p).is_err());
            assert!(
                for_each_particle(p, &mut |_| {}).is_err(),
                "{}",
                p.display()
            );
        }
    }

    const CUBE_OBJ: &str =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
        f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

    pub fn obj_cube_is_closed_oriented_and_answers_inside() {
        let p = tmp("cube.obj", CUBE_OBJ.as_bytes());
        let t = Transform {
            scale: Scale::Uniform(2.0),
            rotate: Some(Rotation {
                axis: [0.0, 0.0, 1.0],
                degrees: 90.0,
            }),
            translate: [10.0, 0.0, 0.0],
        };
        let m = read_mesh(&p, &t).unwrap();
        assert_eq!(m.vertices.len(), 8);
        assert_eq!(m.triangles.len(), 12);
        m.check_closed_and_oriented().unwrap();
        let (lo, hi) = m.bounds();
        assert!((lo - Vec3::new(8.0, 0.0, 0.0)).norm() < 1e-12, "{lo:?}");
        assert!((hi - Vec3::new(10.0, 2.0, 2.0)).norm() < 1e-12, "{hi:?}");
        assert!(m.inside(Vec3::new(9.0, 1.0, 1.0)));
        assert!(m.inside(Vec3::new(8.1, 1.9, 0.1)));
        assert!(!m.inside(Vec3::new(7.9, 1.0, 1.0)));
        assert!(!m.inside(Vec3::new(9.0, 1.0, 2.1)));
        // a face flipped: inconsistent orientation
        let mut bad = m.clone();
        bad.triangles[0].swap(1, 2);
        assert!(bad
            .check_closed_and_oriented()
            .unwrap_err()
            .contains("orientation"));
        // a face removed: open
        let mut open = m.clone();
        open.triangles.pop();
        assert!(open
            .check_closed_and_oriented()
            .unwrap_err()
            .contains("closed"));
    }

    pub fn stl_binary_and_ascii_read_the_same_triangle() {
        let ascii = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let a = read_mesh(&tmp("t.stl", ascii.as_bytes()), &Transform::default()).unwrap();
        let mut bin = vec![0u8; 80];
        bin.extend_from_slice(&1u32.to_le_bytes());
        for x in [0f32, 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0.] {
            bin.extend_from_slice(&x.to_le_bytes());
        }
        bin.extend_from_slice(&[0, 0]);
        let b = read_mesh(&tmp("tb.stl", &bin), &Transform::default()).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.triangles.len(), 1);
        assert_eq!(a.vertices.len(), 3);
    }

    pub fn bad_meshes_are_refused_with_the_path() {
        let cases: [(&str, &str, &str); 3] = [
            (
                "nan.obj",
                "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n",
                "nan.obj",
            ),
            (
                "deg.obj",
                "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
                "degenerate",
            ),
            ("empty.obj", "v 0 0 0\n", "no triangle"),
        ];
        for (name, text, want) in cases {
            let e = read_mesh(&tmp(name, text.as_bytes()), &Transform::default())
                .unwrap_err()
                .to_string();
            assert!(e.contains(name) && e.contains(want), "{e}");
        }
        let e = read_mesh(&tmp("x.ply", b""), &Transform::default()).unwrap_err();
        assert!(e.to_string().contains(".stl or .obj"));
        let bad = Transform {
            scale: Scale::Uniform(0.0),
            ..Default::default()
        };
        let e = read_mesh(&tmp("cube2.obj", CUBE_OBJ.as_bytes()), &bad).unwrap_err();
        assert!(e.to_string().contains("scale"), "{e}");
    }
}
