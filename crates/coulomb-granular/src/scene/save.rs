//! A scene model written as a scene file: the inverse of [`crate::scene_file`] for what a
//! [`SceneModel`] holds (a scene built in Python, `Scene.save(path)`), so that
//! `coulomb simulate FILE` runs the scene the model describes.
//!
//! Every sphere, body and obstacle is written explicitly (spheres as `spheres` lists, bodies
//! as one-body `shape` groups, meshes inline) with the numbers of the model, so that reading
//! the file back builds the same bodies, in the same order, to the bit: a sphere's mass is
//! ρ 4/3 π R³ on both sides ([`crate::model::ball_mass`], [`crate::scene_file::sphere_mass`]),
//! and spheres given by their masses become `shape = sphere` groups with `mass`. Unit vectors
//! (normals, axes) are normalized again when read, which may move their last bit.
//!
//! Obstacles are written as the model holds them (their shapes and motions are the scene
//! file's, `crate::scene_file::ObstacleShape`), meshes inline. What a scene file cannot
//! hold is refused, never dropped: two inlets of one material with different densities (a
//! file's inlet takes its material's density).

use crate::generate::Inlet;
use crate::math::Vec3;
use crate::model::{BodyShape, SceneModel};
use crate::scene_file::{
    BodiesSection, InletSection, LoadedScene, MaterialSection, MeshSource, ObstacleSection,
    ObstacleShape, RunSettings, SceneFile, StepSection, DEFAULT_DENSITY, DEFAULT_MATERIAL,
};
use crate::world::Shape;
use std::collections::BTreeMap;
use std::path::Path;

/// Why a scene cannot be written as a scene file.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    /// a part of the scene has no scene-file form (the message names it)
    #[error("{0}")]
    Unsupported(String),
    /// the path does not end in .toml or .json
    #[error("{}: a scene file must end in .toml or .json", .0.display())]
    Extension(std::path::PathBuf),
    /// serialization failed
    #[error("cannot write the scene as {format}: {message}")]
    Format {
        /// TOML or JSON
        format: &'static str,
        /// the serializer's message
        message: String,
    },
    /// the written text does not read back as the scene (a bug: the scene is not written)
    #[error("the scene file would not load back: {0}")]
    ReadBack(String),
    /// the file could not be written (an existing non-regular file, a link that cannot be
    /// followed, a full disk, …: [`coulomb::atomic::write`])
    #[error("{}: {source}", path.display())]
    Io {
        /// the destination
        path: std::path::PathBuf,
        /// the system's or [`coulomb::atomic`]'s error
        source: std::io::Error,
    },
}

fn a3(v: Vec3) -> [f64; 3] {
    v.to_array()
}

/// The scene file of `model` with the inlets `inlets` (each with the material of its
/// spheres). The `[step]` section carries the model's step settings; its run keys (steps,
/// duration, until_rest, …) are the defaults, for the caller to set.
pub fn scene_file_of(
    model: &SceneModel,
    inlets: &[(Inlet, String)],
) -> Result<SceneFile, SaveError> {
    let step = StepSection {
        settings: model.step.clone(),
        run: RunSettings::default(),
    };
    // materials: every name, with the density of its inlets (bodies carry their own)
    let mut materials: BTreeMap<String, MaterialSection> = BTreeMap::new();
    for name in &model.materials.names {
        if name != DEFAULT_MATERIAL {
            materials.insert(
                name.clone(),
                MaterialSection {
                    density: DEFAULT_DENSITY,
                },
            );
        }
    }
    let mut inlet_density: BTreeMap<&str, f64> = BTreeMap::new();
    for (k, (inlet, material)) in inlets.iter().enumerate() {
        if let Some(&d) = inlet_density.get(material.as_str()) {
            if d.to_bits() != inlet.density.to_bits() {
                return Err(SaveError::Unsupported(format!(
                    "inlet {k}: density {} differs from {d} of an earlier inlet of material '{material}' (a scene file's inlet pours spheres of its material's density): use another material",
                    inlet.density
                )));
            }
        }
        inlet_density.insert(material.as_str(), inlet.density);
        materials.insert(
            material.clone(),
            MaterialSection {
                density: inlet.density,
            },
        );
    }
    let group = |material: &str, fixed: bool| BodiesSection {
        material: material.to_string(),
        fixed,
        ..BodiesSection::default()
    };
    let mut bodies = Vec::new();
    // bodies one by one (they come first in the world, as in the model)
    for b in &model.bodies {
        bodies.push(BodiesSection {
            density: b.density,
            velocity: (!b.fixed).then(|| a3(b.velocity)),
            angular_velocity: a3(b.angular_velocity),
            shape: Some(b.shape.clone()),
            positions: Some(vec![a3(b.position)]),
            orientations: Some(vec![b.orientation]),
            mass: b.mass,
            inertia: b.inertia,
            centre_of_mass: b.centre_of_mass,
            ..group(&b.material, b.fixed)
        });
    }
    // sphere batches: runs of consecutive spheres with the same velocities (and radius and
    // mass when given by masses) make one group
    for (bi, batch) in model.sphere_batches.iter().enumerate() {
        let n = batch.positions.len();
        let pick = |v: &[f64], i: usize| -> Option<f64> {
            match v.len() {
                0 => None,
                1 => Some(v[0]),
                _ => v.get(i).copied(),
            }
        };
        let vec_at = |v: &[Vec3], i: usize| v.get(i).copied().unwrap_or(Vec3::ZERO);
        for i in 0..n {
            let r = pick(&batch.radii, i).ok_or_else(|| {
                SaveError::Unsupported(format!("sphere batch {bi}: no radius for sphere {i}"))
            })?;
            let v = if batch.fixed {
                [0.0; 3]
            } else {
                a3(vec_at(&batch.velocities, i))
            };
            let w = if batch.fixed {
                [0.0; 3]
            } else {
                a3(vec_at(&batch.angular_velocities, i))
            };
            let x = a3(batch.positions[i]);
            let by_mass = !batch.masses.is_empty();
            let mass = pick(&batch.masses, i);
            let last = bodies.last_mut().filter(|g: &&mut BodiesSection| {
                g.material == batch.material
                    && g.fixed == batch.fixed
                    && g.velocity.unwrap_or([0.0; 3]) == v
                    && g.angular_velocity == w
                    && if by_mass {
                        g.mass == mass
                            && g.shape == Some(BodyShape::Sphere { radius: r })
                            && g.orientations.is_none()
                    } else {
                        g.spheres.is_some() && g.density == batch.density
                    }
            });
            match (last, by_mass) {
                (Some(g), false) => g
                    .spheres
                    .get_or_insert_with(Vec::new)
                    .push([x[0], x[1], x[2], r]),
                (Some(g), true) => g.positions.get_or_insert_with(Vec::new).push(x),
                (None, false) => bodies.push(BodiesSection {
                    density: batch.density,
                    velocity: (!batch.fixed).then_some(v),
                    angular_velocity: w,
                    spheres: Some(vec![[x[0], x[1], x[2], r]]),
                    ..group(&batch.material, batch.fixed)
                }),
                (None, true) => bodies.push(BodiesSection {
                    velocity: (!batch.fixed).then_some(v),
                    angular_velocity: w,
                    shape: Some(BodyShape::Sphere { radius: r }),
                    positions: Some(vec![x]),
                    mass,
                    ..group(&batch.material, batch.fixed)
                }),
            }
        }
    }
    let mut obstacles = Vec::new();
    for (k, o) in model.obstacles.iter().enumerate() {
        let name = if o.name.is_empty() {
            format!("obstacle-{k}")
        } else {
            o.name.clone()
        };
        let shape = match &o.shape {
            Shape::Mesh { mesh, side } => ObstacleShape::Mesh {
                source: MeshSource {
                    vertices: Some(mesh.vertices().iter().map(|&v| a3(v)).collect()),
                    triangles: Some(
                        mesh.triangles()
                            .iter()
                            .map(|t| t.map(|i| i as usize))
                            .collect(),
                    ),
                    ..MeshSource::default()
                },
                side: *side,
            },
            other => ObstacleShape::Shape(other.clone()),
        };
        obstacles.push(ObstacleSection {
            name: Some(name),
            material: o.material.clone(),
            shape,
            motion: o.motion.clone(),
        });
    }
    let inlets = inlets
        .iter()
        .map(|(i, material)| InletSection {
            material: material.clone(),
            region: i.region.clone(),
            sizes: i.sizes.clone(),
            rate: i.rate,
            start: i.start,
            end: i.end.is_finite().then_some(i.end),
            velocity: i.velocity,
            attempts: Some(i.attempts),
            seed: Some(i.seed),
            shape: i.poured_shape().cloned(),
        })
        .collect();
    Ok(SceneFile {
        name: None,
        seed: 1,
        gravity: a3(model.gravity),
        step,
        materials,
        default_pair: model.materials.default,
        pairs: model.materials.pairs.clone(),
        bodies,
        obstacles,
        inlets,
        // the file's bodies are written in the model's order (bodies, then each batch's
        // spheres), the numbering the joints use
        joints: model.joints.clone(),
        // a robot imported from URDF is in the model as its bodies and joints: written so
        urdf: Vec::new(),
    })
}

/// The text of `file` in the format of `path`'s extension (`.toml` or `.json`).
pub fn scene_text(path: &Path, file: &SceneFile) -> Result<String, SaveError> {
    match is_toml(path)? {
        true => toml::to_string(file).map_err(|e| SaveError::Format {
            format: "TOML",
            message: e.to_string(),
        }),
        false => serde_json::to_string_pretty(file).map_err(|e| SaveError::Format {
            format: "JSON",
            message: e.to_string(),
        }),
    }
}

fn is_toml(path: &Path) -> Result<bool, SaveError> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("toml") => Ok(true),
        Some("json") => Ok(false),
        _ => Err(SaveError::Extension(path.to_path_buf())),
    }
}

/// Writes `file` to `path` (TOML or JSON by the extension), atomically
/// ([`coulomb::atomic::write`]: a destination that exists and is not a regular file is
/// refused, a failed write leaves it as it was), after checking that the text reads back as
/// the same scene file and builds ([`LoadedScene::build`]).
pub fn save(path: &Path, file: &SceneFile) -> Result<(), SaveError> {
    let text = scene_text(path, file)?;
    let loaded = LoadedScene::parse(path, text.clone(), is_toml(path)?)
        .map_err(|e| SaveError::ReadBack(e.to_string()))?;
    if &loaded.file != file {
        return Err(SaveError::ReadBack(
            "the scene read back differs from the scene written".into(),
        ));
    }
    coulomb::atomic::write(path, text.as_bytes()).map_err(|source| SaveError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::model::{BodySpec, ObstacleSpec, SphereBatch};
    use crate::scene_file::BuildOptions;
    use crate::shape::IDENTITY;
    use crate::world::Motion;

    /// A folder of its own, removed when dropped.
    struct TempDir(std::path::PathBuf);
    impl TempDir {
        fn path(&self) -> &Path {
            &self.0
        }
    }
    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
    fn temp_dir() -> TempDir {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static N: AtomicUsize = AtomicUsize::new(0);
        let d = std::env::temp_dir().join(format!(
            "coulomb-scene-save-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&d).unwrap();
        TempDir(d)
    }

    /// A model with spheres by density and by mass, per-sphere velocities, a fixed batch, a
    /// plane, a box container, a moving cylinder and a mesh.
    fn model() -> SceneModel {
        let mut m = SceneModel {
            gravity: Vec3::new(0.1, 0.0, -9.81),
            ..SceneModel::default()
        };
        m.step.h = 0.005;
        m.step.tol = 1e-6;
        m.sphere_batches.push(SphereBatch {
            positions: vec![
                Vec3::new(0.1, 0.1, 0.2),
                Vec3::new(0.3, 0.1, 0.2),
                Vec3::new(0.5, 0.1, 0.2),
            ],
            radii: vec![0.05],
            velocities: vec![
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 0.3, 0.0),
            ],
            density: Some(1234.5),
            ..SphereBatch::default()
        });
        m.sphere_batches.push(SphereBatch {
            positions: vec![Vec3::new(0.1, 0.5, 0.2), Vec3::new(0.3, 0.5, 0.2)],
            radii: vec![0.04, 0.06],
            masses: vec![0.7, 0.9],
            ..SphereBatch::default()
        });
        m.sphere_batches.push(SphereBatch {
            positions: vec![Vec3::new(0.5, 0.5, 0.05)],
            radii: vec![0.05],
            density: Some(2500.0),
            fixed: true,
            ..SphereBatch::default()
        });
        m.obstacles.push(ObstacleSpec::fixed(
            "floor",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        m.obstacles.push(ObstacleSpec::fixed(
            "",
            Shape::Box {
                lo: Vec3::new(-1.0, -1.0, -1.0),
                hi: Vec3::new(2.0, 2.0, 2.0),
                inside: true,
                open_top: true,
            },
        ));
        let mut post = ObstacleSpec::fixed(
            "post",
            Shape::Cylinder {
                base: Vec3::new(1.5, 1.5, 0.0),
                axis: Vec3::Z,
                radius: 0.1,
                height: 0.5,
                inside: false,
                bottom_cap: true,
                top_cap: true,
                orifice: 0.0,
            },
        );
        post.motion = Motion::Oscillate {
            direction: Vec3::X,
            amplitude: 0.01,
            frequency: 5.0,
        };
        m.obstacles.push(post);
        let mesh = crate::TriangleMesh::new(
            vec![
                Vec3::new(-0.5, -0.5, 1.5),
                Vec3::new(0.5, -0.5, 1.5),
                Vec3::new(0.0, 0.5, 1.5),
            ],
            vec![[0, 1, 2]],
        )
        .unwrap();
        m.obstacles.push(ObstacleSpec::fixed(
            "lid",
            Shape::Mesh {
                mesh,
                side: Default::default(),
            },
        ));
        m
    }

    fn round_trip(m: &SceneModel, name: &str) -> (SceneFile, crate::scene_file::BuiltScene) {
        let dir = temp_dir();
        let path = dir.path().join(name);
        let file = scene_file_of(m, &[]).unwrap();
        save(&path, &file).unwrap();
        let loaded = LoadedScene::load(&path).unwrap();
        assert_eq!(loaded.file, file);
        let built = loaded.build(&BuildOptions::default()).unwrap();
        (file, built)
    }

    pub fn a_saved_sphere_scene_builds_the_same_world_to_the_bit() {
        let m = model();
        for name in ["s.toml", "s.json"] {
            let (_, built) = round_trip(&m, name);
            assert_eq!(built.model.step, m.step);
            assert_eq!(built.model.gravity, m.gravity);
            let (w0, p0) = m.build().unwrap();
            let (w1, p1) = built.build(&Default::default()).unwrap();
            assert_eq!(p0.h, p1.h);
            assert_eq!(p0.solver.tol, p1.solver.tol);
            assert_eq!(w0.bodies.len(), 6 - 1);
            assert_eq!(w0.bodies.len(), w1.bodies.len());
            for (a, b) in w0.bodies.iter().zip(&w1.bodies) {
                assert_eq!(a.position, b.position);
                assert_eq!(a.radius, b.radius);
                assert_eq!(a.mass.to_bits(), b.mass.to_bits());
                assert_eq!(a.velocity, b.velocity);
            }
            assert_eq!(w0.obstacles.len(), w1.obstacles.len());
            for (a, b) in w0.obstacles.iter().zip(&w1.obstacles) {
                assert_eq!(a.shape, b.shape);
                assert_eq!(a.motion, b.motion);
            }
        }
    }

    pub fn a_saved_rigid_scene_reads_back_its_bodies() {
        let mut m = SceneModel::default();
        let mut cube = BodySpec::new(
            BodyShape::Cuboid {
                half_extents: [0.1, 0.2, 0.3],
            },
            Vec3::new(0.0, 0.0, 0.5),
            [0.6, 0.8, 0.0, 0.0],
            800.0,
        );
        cube.angular_velocity = Vec3::new(0.0, 0.0, 2.0);
        m.bodies.push(cube);
        let mut ball = BodySpec::sphere(Vec3::new(1.0, 0.0, 0.5), 0.1, 1.0);
        ball.density = None;
        ball.mass = Some(0.25);
        m.bodies.push(ball);
        m.obstacles.push(ObstacleSpec::fixed(
            "floor",
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Z,
            },
        ));
        m.joints.push(crate::bodies::joints::JointDesc {
            kind: crate::bodies::joints::JointKind::Revolute,
            body_a: 1,
            body_b: Some(0),
            anchor: [0.5, 0.0, 0.5],
            axis: Some([0.0, 1.0, 0.0]),
            limits: Some((-0.5, 0.25)),
            motor: Some(crate::bodies::joints::Motor::with_velocity(1.5, 2.0)),
            limit_restitution: Some(0.5),
            friction: Some(0.25),
        });
        let (_, built) = round_trip(&m, "r.toml");
        assert_eq!(built.model.bodies, m.bodies);
        assert_eq!(built.model.joints, m.joints);
        assert_eq!(built.model.obstacles, m.obstacles);
        assert_eq!(m.bodies[0].orientation, [0.6, 0.8, 0.0, 0.0]);
        assert_ne!(m.bodies[0].orientation, IDENTITY);
    }

    pub fn what_a_scene_file_cannot_hold_is_refused_and_a_device_is_not_replaced() {
        let mut m = model();
        m.obstacles.push(ObstacleSpec::fixed(
            "drum",
            Shape::CylinderInside {
                point: Vec3::ZERO,
                axis: Vec3::X,
                radius: 1.0,
            },
        ));
        // an infinite cylinder is a shape of the file as of the model: written as it is
        let file = scene_file_of(&m, &[]).unwrap();
        assert_eq!(
            file.obstacles[4].shape,
            ObstacleShape::Shape(m.obstacles[4].shape.clone())
        );
        let dir = temp_dir();
        let path = dir.path().join("drum.toml");
        save(&path, &file).unwrap();
        assert_eq!(LoadedScene::load(&path).unwrap().file, file);
        let file = scene_file_of(&model(), &[]).unwrap();
        let e = save(Path::new("/dev/null"), &file).unwrap_err();
        assert!(matches!(e, SaveError::Extension(_)), "{e}");
        let sub = dir.path().join("x.toml");
        std::fs::create_dir(&sub).unwrap();
        let e = save(&sub, &file).unwrap_err();
        assert!(matches!(e, SaveError::Io { .. }), "{e}");
        assert!(sub.is_dir());
    }
}
