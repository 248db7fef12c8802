//! Outputs: per-step statistics as CSV and JSON, and VTK PolyData frames (.vtp, ASCII)
//! indexed by a ParaView collection (.pvd) with positions, radii, velocities and contact
//! forces.

use crate::simulation::{Simulation, StepStats};
use std::fmt::Write as _;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

/// Header of the per-step CSV.
pub const CSV_HEADER: &str = "step,time,contacts,subproblems,inner_iterations,solve_ms,assembly_ms,delassus_ms,error,rule_6_1,status,converged,kinetic_energy,potential_energy,max_penetration,warm_started";

/// One CSV line of a step's statistics.
pub fn csv_line(s: &StepStats) -> String {
    format!(
        "{},{:.6},{},{},{},{:.4},{:.4},{:.4},{:.6e},{:.6e},{},{},{:.9e},{:.9e},{:.6e},{}",
        s.step,
        s.time,
        s.contacts,
        s.subproblems,
        s.inner_iterations,
        s.solve_ms,
        s.assembly_ms,
        s.delassus_ms,
        s.error,
        s.rule_6_1,
        s.status,
        s.converged,
        s.kinetic_energy,
        s.potential_energy,
        s.max_penetration,
        s.warm_started
    )
}

/// Writes `stats.csv` and `stats.json` in `dir`.
pub fn write_stats(dir: &Path, stats: &[StepStats]) -> io::Result<()> {
    fs::create_dir_all(dir)?;
    let mut csv = String::from(CSV_HEADER);
    csv.push('\n');
    for s in stats {
        csv.push_str(&csv_line(s));
        csv.push('\n');
    }
    coulomb::atomic::write(dir.join("stats.csv"), csv)?;
    let json = serde_json::to_string_pretty(stats).map_err(io::Error::other)?;
    coulomb::atomic::write(dir.join("stats.json"), json)
}

/// VTK PolyData (.vtp, ASCII) of the spheres: points = centres, point data radius, velocity,
/// angular velocity and the total contact force Σ r / h on each sphere; plus a second file
/// with one vertex per contact (point, normal, force r/h).
pub fn vtp_frame(sim: &Simulation) -> (String, String) {
    let h = sim.params.h;
    let nb = sim.world.bodies.len();
    let mut force = vec![[0.0f64; 3]; nb];
    for c in &sim.contacts {
        let f = c.world_impulse() * (1.0 / h);
        if let Some(fa) = force.get_mut(c.body) {
            fa[0] += f.x;
            fa[1] += f.y;
            fa[2] += f.z;
        }
        if let crate::contact::Partner::Body(j) = c.partner {
            if let Some(fb) = force.get_mut(j) {
                fb[0] -= f.x;
                fb[1] -= f.y;
                fb[2] -= f.z;
            }
        }
    }
    let bodies = &sim.world.bodies;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n<Piece NumberOfPoints=\"{nb}\" NumberOfVerts=\"{nb}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    s.push_str("<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for b in bodies {
        let _ = writeln!(s, "{} {} {}", b.position.x, b.position.y, b.position.z);
    }
    s.push_str("</DataArray></Points>\n<PointData Scalars=\"radius\" Vectors=\"velocity\">\n");
    s.push_str("<DataArray type=\"Float64\" Name=\"radius\" format=\"ascii\">\n");
    for b in bodies {
        let _ = writeln!(s, "{}", b.radius);
    }
    s.push_str("</DataArray>\n");
    let vec_array = |s: &mut String, name: &str, it: &mut dyn Iterator<Item = [f64; 3]>| {
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"3\" format=\"ascii\">"
        );
        for v in it {
            let _ = writeln!(s, "{} {} {}", v[0], v[1], v[2]);
        }
        s.push_str("</DataArray>\n");
    };
    vec_array(
        &mut s,
        "velocity",
        &mut bodies.iter().map(|b| b.velocity.to_array()),
    );
    vec_array(
        &mut s,
        "angular_velocity",
        &mut bodies.iter().map(|b| b.angular_velocity.to_array()),
    );
    vec_array(&mut s, "contact_force", &mut force.iter().copied());
    s.push_str("</PointData>\n");
    verts(&mut s, nb);
    s.push_str("</Piece>\n</PolyData>\n</VTKFile>\n");

    let nc = sim.contacts.len();
    let mut c = String::new();
    let _ = writeln!(
        c,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n<Piece NumberOfPoints=\"{nc}\" NumberOfVerts=\"{nc}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    c.push_str("<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for ct in &sim.contacts {
        let _ = writeln!(c, "{} {} {}", ct.point.x, ct.point.y, ct.point.z);
    }
    c.push_str("</DataArray></Points>\n<PointData Vectors=\"force\">\n");
    vec_array(
        &mut c,
        "normal",
        &mut sim.contacts.iter().map(|x| x.normal.to_array()),
    );
    vec_array(
        &mut c,
        "force",
        &mut sim
            .contacts
            .iter()
            .map(|x| (x.world_impulse() * (1.0 / h)).to_array()),
    );
    c.push_str("<DataArray type=\"Float64\" Name=\"gap\" format=\"ascii\">\n");
    for ct in &sim.contacts {
        let _ = writeln!(c, "{}", ct.gap);
    }
    c.push_str("</DataArray>\n</PointData>\n");
    verts(&mut c, nc);
    c.push_str("</Piece>\n</PolyData>\n</VTKFile>\n");
    (s, c)
}

fn verts(s: &mut String, n: usize) {
    s.push_str("<Verts><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = writeln!(s, "{i}");
    }
    s.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = writeln!(s, "{}", i + 1);
    }
    s.push_str("</DataArray></Verts>\n");
}

/// Writes VTK frames into a directory and the ParaView collections `beads.pvd` and
/// `contacts.pvd` indexing them.
#[derive(Debug)]
pub struct VtkWriter {
    dir: PathBuf,
    frames: Vec<(f64, String, String)>,
}

impl VtkWriter {
    /// A writer into `dir` (created).
    pub fn new(dir: &Path) -> io::Result<Self> {
        fs::create_dir_all(dir.join("frames"))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            frames: Vec::new(),
        })
    }
    /// Writes the frame of the simulation's current state.
    pub fn frame(&mut self, sim: &Simulation) -> io::Result<()> {
        let (beads, contacts) = vtp_frame(sim);
        let k = sim.steps_done;
        let b = format!("frames/beads_{k:06}.vtp");
        let c = format!("frames/contacts_{k:06}.vtp");
        coulomb::atomic::write(self.dir.join(&b), beads)?;
        coulomb::atomic::write(self.dir.join(&c), contacts)?;
        self.frames.push((sim.time, b, c));
        self.write_collections()
    }
    fn write_collections(&self) -> io::Result<()> {
        for (name, pick) in [("beads.pvd", 0usize), ("contacts.pvd", 1)] {
            let mut s = String::from(
                "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
            );
            for (t, b, c) in &self.frames {
                let file = if pick == 0 { b } else { c };
                let _ = writeln!(
                    s,
                    "<DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{file}\"/>"
                );
            }
            s.push_str("</Collection>\n</VTKFile>\n");
            coulomb::atomic::write(self.dir.join(name), s)?;
        }
        Ok(())
    }
}
