//! Inlets that pour bodies of any shape (issue 52, item 3): a scene file's `[[inlets]]` with a
//! `shape` runs in the rigid-body simulator, pours at its rate without overlap (bounding
//! balls), and a checkpoint restart continues the pour to the bit.

use coulomb_granular::model::BodyShape;
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::{BuildOptions, BuiltScene, LoadedScene};
use std::path::Path;

/// A floor, one cuboid lying on it, and two inlets pouring into one region: capsules
/// (200/s) and rocks (a convex hull, 150/s), falling at 0.3 m/s.
const POUR: &str = r#"
    [step]
    h = 0.002
    tol = 1e-8

    [default_pair]
    mu = 0.4

    [materials.stone]
    density = 2600

    [[obstacles]]
    name = "floor"
    shape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }

    [[bodies]]
    shape = { kind = "cuboid", half_extents = [0.05, 0.05, 0.02] }
    positions = [[0.0, 0.0, 0.02]]

    [[inlets]]
    region = { kind = "box", lo = [-0.15, -0.15, 0.15], hi = [0.15, 0.15, 0.3] }
    sizes = { kind = "uniform", min = 0.015, max = 0.025 }
    rate = { count = 200.0 }
    velocity = [0.0, 0.0, -0.3]
    shape = { kind = "capsule", radius = 0.5, half_height = 1.0 }

    [[inlets]]
    material = "stone"
    region = { kind = "box", lo = [-0.15, -0.15, 0.15], hi = [0.15, 0.15, 0.3] }
    sizes = { kind = "uniform", min = 0.015, max = 0.025 }
    rate = { count = 150.0 }
    velocity = [0.0, 0.0, -0.3]
    shape = { kind = "convex_hull", points = [[1.0, 0.1, 0.0], [-0.8, 0.3, 0.2], [0.1, 0.9, -0.3], [0.0, -0.7, 0.6], [0.2, 0.0, -0.9], [-0.3, -0.5, -0.4]] }
"#;

fn built(text: &str) -> BuiltScene {
    LoadedScene::parse(Path::new("pour.toml"), text.to_string(), true)
        .expect("scene file")
        .build(&BuildOptions::default())
        .expect("build")
}

/// One step, then the inlets' bodies due in (t_k, t_{k+1}]; returns how many were inserted.
fn step(scene: &mut BuiltScene, rigid: &mut RigidScene) -> usize {
    let t0 = rigid.world.time();
    rigid.step().expect("step");
    let t1 = rigid.world.time();
    scene.pour_rigid(rigid, t0, t1).expect("pour").inserted
}

/// Positions, orientations, velocities, angular velocities and contact impulses, as bits.
fn snapshot(s: &RigidScene) -> Vec<u64> {
    let w = &s.world;
    let mut bits: Vec<u64> = Vec::new();
    for v in [w.positions(), w.velocities(), w.angular_velocities()] {
        bits.extend(v.iter().flatten().map(|x| x.to_bits()));
    }
    bits.extend(w.orientations().iter().flatten().map(|x| x.to_bits()));
    for c in w.contacts() {
        bits.extend(c.impulse.iter().map(|x| x.to_bits()));
    }
    bits
}

#[test]
fn an_inlet_shape_is_parsed_validated_and_sends_the_scene_to_the_rigid_engine() {
    let scene = built(POUR);
    assert!(scene.runs_rigid());
    assert_eq!(scene.inlets.len(), 2);
    assert_eq!(
        scene.inlets[0].inlet.poured_shape().map(|s| s.kind()),
        Some("capsule")
    );
    assert_eq!(scene.inlets[1].density, 2600.0);
    // one law for every pair: the materials only gave densities, and become `default`
    assert_eq!(scene.inlets[1].material, "default");
    assert_eq!(
        scene.inlets[0].density,
        coulomb_granular::scene_file::DEFAULT_DENSITY
    );
    // a sphere scene whose inlet pours capsules: its spheres are bodies of the rigid model
    let spheres = "[[bodies]]\nspheres = [[0.0, 0.0, 0.1, 0.05]]\n\
        [[inlets]]\nregion = { kind = \"box\", lo = [0, 0, 1], hi = [1, 1, 2] }\n\
        sizes = { kind = \"uniform\", min = 0.02, max = 0.03 }\nrate = { count = 10 }\n";
    let plain = built(spheres);
    assert!(!plain.runs_rigid() && plain.model.bodies.is_empty());
    let capsules =
        spheres.to_string() + "shape = { kind = \"capsule\", radius = 0.1, half_height = 0.2 }\n";
    let c = built(&capsules);
    assert!(c.runs_rigid());
    assert!(c.model.sphere_batches.is_empty() && c.model.bodies.len() == 1);
    // a sphere as the shape is the inlet without one (the same spheres, the sphere engine)
    let ball = spheres.to_string() + "shape = { kind = \"sphere\", radius = 7.0 }\n";
    let b = built(&ball);
    assert!(!b.runs_rigid());
    assert_eq!(b.inlets[0].inlet, plain.inlets[0].inlet);
    // a bad shape is refused at its key, with its line
    let bad =
        spheres.to_string() + "shape = { kind = \"capsule\", radius = -1.0, half_height = 0.2 }\n";
    let e = LoadedScene::parse(Path::new("bad.toml"), bad, true)
        .unwrap()
        .build(&BuildOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("inlets[0].shape") && e.contains("capsule refused") && e.contains(":7:"),
        "{e}"
    );
    // an unknown key of the shape: a syntax error
    let unknown =
        spheres.to_string() + "shape = { kind = \"capsule\", radius = 1.0, height = 0.2 }\n";
    assert!(LoadedScene::parse(Path::new("bad.toml"), unknown, true).is_err());
}

#[test]
fn capsules_and_rocks_are_poured_at_the_rate_without_overlap() {
    let mut scene = built(POUR);
    let mut rigid = RigidScene::new(&scene.model).expect("rigid scene");
    let steps = 50;
    let mut poured = 0;
    for _ in 0..steps {
        let before = rigid.world.len();
        poured += step(&mut scene, &mut rigid);
        let after = rigid.world.len();
        // the new bodies' bounding balls overlap no other body's
        let x = rigid.world.positions();
        let r: Vec<f64> = rigid.shapes.iter().map(|s| s.bounding_radius()).collect();
        for i in before..after {
            for j in 0..after {
                if i == j {
                    continue;
                }
                let d = (0..3).map(|k| (x[i][k] - x[j][k]).powi(2)).sum::<f64>();
                assert!(
                    d.sqrt() >= r[i] + r[j],
                    "bodies {i} and {j} overlap at insertion"
                );
            }
        }
    }
    // N(t) = ⌊rate · t⌋ per inlet at t = 50 h = 0.1 s: 20 capsules and 15 rocks, all placed
    let t = rigid.world.time();
    let due = (200.0 * t + 1e-9).floor() as usize + (150.0 * t + 1e-9).floor() as usize;
    assert_eq!(due, 35);
    assert_eq!(poured, due);
    assert_eq!(rigid.world.len(), 1 + due);
    assert_eq!(rigid.model.bodies.len(), 1 + due);
    let kinds = |k: &str| rigid.shapes.iter().filter(|s| s.kind() == k).count();
    assert_eq!((kinds("capsule"), kinds("convex_hull")), (20, 15));
    let masses = rigid.world.masses();
    let mut turned = std::collections::BTreeSet::new();
    for (i, s) in rigid.shapes.iter().enumerate().skip(1) {
        let b = &rigid.model.bodies[i];
        // scaled to a sampled size, with the inlet's density and material
        let rb = s.bounding_radius();
        assert!(
            (0.015 * (1.0 - 1e-12)..=0.025 * (1.0 + 1e-12)).contains(&rb),
            "{rb}"
        );
        let from = &scene.inlets[usize::from(!matches!(s, BodyShape::Capsule { .. }))];
        assert_eq!(b.material, from.material);
        let rho = from.density;
        let m = rho * s.volume().unwrap();
        assert!((masses[i] - m).abs() <= 1e-12 * m, "{} vs {m}", masses[i]);
        turned.insert(b.orientation.map(f64::to_bits));
    }
    assert_eq!(turned.len(), due, "every body has its own orientation");
    // the pour falls onto the cuboid and the floor: contacts happen, nothing goes through
    // the floor (every centre of mass above it, less than 1 mm of penetration)
    for _ in 0..100 {
        step(&mut scene, &mut rigid);
    }
    assert!(rigid.reports.iter().any(|r| r.contacts > 0));
    assert!(rigid.world.centres_of_mass().iter().all(|x| x[2] > 0.0));
    let worst = rigid
        .reports
        .iter()
        .map(|r| r.max_penetration)
        .fold(0.0, f64::max);
    assert!(worst < 1e-3, "penetration {worst}");
}

#[test]
fn a_restart_continues_the_pour_to_the_bit() {
    let mut scene = built(POUR);
    let mut a = RigidScene::new(&scene.model).expect("rigid scene");
    for _ in 0..60 {
        step(&mut scene, &mut a);
    }
    let bytes = a.checkpoint_bytes().expect("checkpoint");
    // the restarted run: the checkpoint and the scene file built again (fresh inlets)
    let mut b = RigidScene::from_checkpoint_bytes("pour.h5", bytes).expect("restart");
    let mut again = built(POUR);
    assert_eq!(b.world.len(), a.world.len());
    assert_eq!(snapshot(&b), snapshot(&a));
    for _ in 0..60 {
        let na = step(&mut scene, &mut a);
        let nb = step(&mut again, &mut b);
        assert_eq!(na, nb);
    }
    assert!(
        a.world.len() > 1 + 30,
        "the pour went on: {}",
        a.world.len()
    );
    assert_eq!(b.world.len(), a.world.len());
    assert_eq!(b.model, a.model);
    assert_eq!(snapshot(&b), snapshot(&a));
}

#[test]
fn the_pour_gives_the_same_bits_on_one_and_two_threads() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut scene = built(POUR);
            let mut rigid = RigidScene::new(&scene.model).expect("rigid scene");
            for _ in 0..80 {
                step(&mut scene, &mut rigid);
            }
            snapshot(&rigid)
        })
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn bodies_cannot_be_inserted_where_the_model_has_sphere_batches() {
    use coulomb_granular::model::{BodySpec, SceneModel, SphereBatch};
    use coulomb_granular::Vec3;
    let model = SceneModel {
        bodies: vec![BodySpec::new(
            BodyShape::Cuboid {
                half_extents: [0.1; 3],
            },
            Vec3::new(0.0, 0.0, 1.0),
            [1.0, 0.0, 0.0, 0.0],
            1000.0,
        )],
        sphere_batches: vec![SphereBatch {
            positions: vec![Vec3::new(1.0, 0.0, 1.0)],
            radii: vec![0.1],
            density: Some(1000.0),
            ..SphereBatch::default()
        }],
        ..SceneModel::default()
    };
    let mut rigid = RigidScene::new(&model).expect("rigid scene");
    let e = rigid
        .insert_bodies(vec![BodySpec::sphere(
            Vec3::new(2.0, 0.0, 1.0),
            0.1,
            1000.0,
        )])
        .unwrap_err()
        .to_string();
    assert!(e.contains("sphere batches"), "{e}");
    assert_eq!(rigid.world.len(), 2);
}
