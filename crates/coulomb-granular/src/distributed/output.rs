//! VTK output of a distributed run: each rank writes the piece of its owned beads and contacts
//! (`frames/bodies_KKKKKK_R.vtp`, `frames/contacts_KKKKKK_R.vtp`), rank 0 the parallel files
//! `frames/bodies_KKKKKK.pvtp` / `frames/contacts_KKKKKK.pvtp` that join the pieces, and the
//! ParaView collections `bodies.pvd` / `contacts.pvd` indexing them by time, so that ParaView
//! opens the whole run as one scene.

use super::DistributedSimulation;
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

/// Point arrays of the bead pieces: (name, components).
const BEAD_ARRAYS: [(&str, usize); 6] = [
    ("radius", 1),
    ("velocity", 3),
    ("angular_velocity", 3),
    ("contact_force", 3),
    ("id", 1),
    ("rank", 1),
];
/// Point arrays of the contact pieces.
const CONTACT_ARRAYS: [(&str, usize); 3] = [("normal", 3), ("force", 3), ("gap", 1)];

/// Writes the frames of a distributed run (every rank calls [`DistributedVtk::frame`]).
#[derive(Debug)]
pub struct DistributedVtk {
    dir: PathBuf,
    frames: Vec<(f64, usize)>,
}

impl DistributedVtk {
    /// A writer into `dir` (created by every rank; harmless when shared).
    pub fn new(dir: &Path) -> io::Result<Self> {
        std::fs::create_dir_all(dir.join("frames"))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            frames: Vec::new(),
        })
    }

    /// Writes this rank's pieces of the current state; rank 0 also the .pvtp files and the
    /// collections.
    pub fn frame(&mut self, sim: &DistributedSimulation) -> io::Result<()> {
        let k = sim.steps_done;
        let (rank, size) = (sim.comm.rank(), sim.comm.size());
        let h = sim.params.h;
        let beads = &sim.beads;
        let mut points = Vec::with_capacity(beads.len());
        let mut arrays: Vec<Vec<f64>> = vec![Vec::new(); BEAD_ARRAYS.len()];
        for ((gid, b), f) in beads.iter().zip(&sim.forces) {
            points.push(b.position.to_array());
            arrays[0].push(b.radius);
            arrays[1].extend_from_slice(&b.velocity.to_array());
            arrays[2].extend_from_slice(&b.angular_velocity.to_array());
            arrays[3].extend_from_slice(&f.to_array());
            arrays[4].push(*gid as f64);
            arrays[5].push(rank as f64);
        }
        let piece = polydata(&points, &BEAD_ARRAYS, &arrays);
        coulomb::atomic::write(
            self.dir.join(format!("frames/bodies_{k:06}_{rank}.vtp")),
            piece,
        )?;
        let mut points = Vec::with_capacity(sim.contacts.len());
        let mut arrays: Vec<Vec<f64>> = vec![Vec::new(); CONTACT_ARRAYS.len()];
        for c in &sim.contacts {
            points.push(c.point.to_array());
            arrays[0].extend_from_slice(&c.normal.to_array());
            arrays[1].extend_from_slice(&(c.world_impulse() * (1.0 / h)).to_array());
            arrays[2].push(c.gap);
        }
        let piece = polydata(&points, &CONTACT_ARRAYS, &arrays);
        coulomb::atomic::write(
            self.dir.join(format!("frames/contacts_{k:06}_{rank}.vtp")),
            piece,
        )?;
        self.frames.push((sim.time, k));
        if rank == 0 {
            for (name, arrays) in [
                ("bodies", &BEAD_ARRAYS[..]),
                ("contacts", &CONTACT_ARRAYS[..]),
            ] {
                let pvtp = parallel(name, k, size, arrays);
                coulomb::atomic::write(self.dir.join(format!("frames/{name}_{k:06}.pvtp")), pvtp)?;
                let mut s = String::from(
                    "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
                );
                for (t, k) in &self.frames {
                    let _ = writeln!(
                        s,
                        "<DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"frames/{name}_{k:06}.pvtp\"/>"
                    );
                }
                s.push_str("</Collection>\n</VTKFile>\n");
                coulomb::atomic::write(self.dir.join(format!("{name}.pvd")), s)?;
            }
        }
        Ok(())
    }
}

/// A PolyData piece (.vtp, ASCII): one vertex per point, point arrays as given.
fn polydata(points: &[[f64; 3]], names: &[(&str, usize)], arrays: &[Vec<f64>]) -> String {
    let n = points.len();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    s.push_str("<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for p in points {
        let _ = writeln!(s, "{} {} {}", p[0], p[1], p[2]);
    }
    s.push_str("</DataArray></Points>\n<PointData>\n");
    for ((name, comps), data) in names.iter().zip(arrays) {
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"ascii\">"
        );
        for row in data.chunks(*comps) {
            let line: Vec<String> = row.iter().map(|x| x.to_string()).collect();
            let _ = writeln!(s, "{}", line.join(" "));
        }
        s.push_str("</DataArray>\n");
    }
    s.push_str("</PointData>\n");
    s.push_str("<Verts><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = writeln!(s, "{i}");
    }
    s.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = writeln!(s, "{}", i + 1);
    }
    s.push_str("</DataArray></Verts>\n</Piece>\n</PolyData>\n</VTKFile>\n");
    s
}

/// The parallel file (.pvtp) joining the `size` pieces `{name}_{k}_{rank}.vtp`.
fn parallel(name: &str, k: usize, size: usize, arrays: &[(&str, usize)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PPolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PPolyData GhostLevel=\"0\">\n<PPoints><PDataArray type=\"Float64\" NumberOfComponents=\"3\"/></PPoints>\n<PPointData>\n",
    );
    for (n, c) in arrays {
        let _ = writeln!(
            s,
            "<PDataArray type=\"Float64\" Name=\"{n}\" NumberOfComponents=\"{c}\"/>"
        );
    }
    s.push_str("</PPointData>\n");
    for r in 0..size {
        let _ = writeln!(s, "<Piece Source=\"{name}_{k:06}_{r}.vtp\"/>");
    }
    s.push_str("</PPolyData>\n</VTKFile>\n");
    s
}
