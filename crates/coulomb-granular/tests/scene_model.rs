//! Simulations built from the scene model: per-pair materials act, a triangle mesh acts as the
//! surface it describes, container walls keep their warm starts, spheres inserted mid-run.

use coulomb_granular::mesh::{box_mesh, TriangleMesh};
use coulomb_granular::model::{BodySpec, MaterialPair, ObstacleSpec, SceneModel, SphereBatch};
use coulomb_granular::{MeshSide, Motion, Partner, Shape, Simulation, Vec3};

const R: f64 = 0.05;

fn slab(name: &str, x0: f64, x1: f64, material: &str) -> ObstacleSpec {
    ObstacleSpec {
        name: name.into(),
        shape: Shape::Box {
            lo: Vec3::new(x0, -5.0, -1.0),
            hi: Vec3::new(x1, 5.0, 0.0),
            inside: false,
            open_top: false,
        },
        motion: Motion::Fixed,
        material: material.into(),
    }
}

#[test]
fn a_sphere_slides_further_on_ice_than_on_rubber() {
    // two floors side by side, (default, ice) μ = 0.1 and (default, rubber) μ = 0.5; a sphere
    // launched at 2 m/s along y on each. Sliding decelerates at μ g until rolling starts at
    // t_s = 2 v₀ / (7 μ g) (0.58 s on ice, 0.12 s on rubber), then it rolls at 5/7 v₀.
    let mut m = SceneModel::default();
    m.materials.names = vec!["ice".into(), "rubber".into()];
    for (name, mu) in [("ice", 0.1), ("rubber", 0.5)] {
        m.materials.pairs.push(MaterialPair {
            materials: [name.into(), "default".into()],
            mu: Some(mu),
            restitution: Some(0.0),
            rolling_friction: Some(0.0),
        });
    }
    m.obstacles.push(slab("ice", -5.0, 0.0, "ice"));
    m.obstacles.push(slab("rubber", 0.0, 5.0, "rubber"));
    for x in [-2.0, 2.0] {
        let mut b = BodySpec::sphere(Vec3::new(x, 0.0, R), R, 2500.0);
        b.velocity = Vec3::new(0.0, 2.0, 0.0);
        m.bodies.push(b);
    }
    let (world, params) = m.build().unwrap();
    assert!(world.materials.is_some());
    let mut sim = Simulation::new(world, params).unwrap();
    let steps = 10;
    for _ in 0..steps {
        let s = sim.step().unwrap();
        assert!(s.converged, "{s:?}");
    }
    let t = steps as f64 * sim.params.h;
    let (ice, rubber) = (
        sim.world.bodies[0].velocity.y,
        sim.world.bodies[1].velocity.y,
    );
    let g = 9.81;
    assert!((ice - (2.0 - 0.1 * g * t)).abs() < 0.02, "ice {ice}");
    assert!((rubber - 2.0 * 5.0 / 7.0).abs() < 0.02, "rubber {rubber}");
    for b in &sim.world.bodies {
        assert!((b.position.z - R).abs() < 1e-3 * R, "{b:?}");
    }
}

/// One sphere dropped (and thrown sideways across the square's diagonal) onto `floor`.
fn drop_on(floor: Shape) -> Vec<(Vec3, Vec3)> {
    let mut m = SceneModel::default();
    m.obstacles.push(ObstacleSpec::fixed("floor", floor));
    let mut b = BodySpec::sphere(Vec3::new(-0.3, -0.25, 0.2), R, 2500.0);
    b.velocity = Vec3::new(1.5, 1.0, 0.0);
    m.bodies.push(b);
    let (world, params) = m.build().unwrap();
    let mut sim = Simulation::new(world, params).unwrap();
    (0..30)
        .map(|_| {
            sim.step().unwrap();
            assert!(sim.contacts.len() <= 1, "{:?}", sim.contacts);
            let b = &sim.world.bodies[0];
            (b.position, b.velocity)
        })
        .collect()
}

#[test]
fn a_sphere_on_a_two_triangle_square_moves_as_on_a_plane() {
    let square = TriangleMesh::new(
        vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let on_mesh = drop_on(Shape::Mesh {
        mesh: square,
        side: MeshSide::Surface,
    });
    let on_plane = drop_on(Shape::Plane {
        point: Vec3::ZERO,
        normal: Vec3::Z,
    });
    // it lands, then rolls across the diagonal (the shared edge) of the square
    assert!(on_plane.last().unwrap().0.z < R + 1e-4);
    assert!(on_plane.first().unwrap().0.x < on_plane.first().unwrap().0.y + 0.1);
    let last = on_plane.last().unwrap().0;
    assert!(last.x > last.y, "crossed the diagonal: {last:?}");
    for (k, (a, b)) in on_mesh.iter().zip(&on_plane).enumerate() {
        assert!((a.0 - b.0).norm() < 1e-9, "step {k}: {a:?} vs {b:?}");
        assert!((a.1 - b.1).norm() < 1e-9, "step {k}: {a:?} vs {b:?}");
    }
}

#[test]
fn spheres_in_a_box_container_and_a_closed_mesh_cup_stay_in_and_keep_warm_starts() {
    for container in [
        Shape::Box {
            lo: Vec3::ZERO,
            hi: Vec3::new(0.3, 0.3, 0.6),
            inside: true,
            open_top: true,
        },
        {
            let cup = box_mesh(Vec3::ZERO, Vec3::new(0.3, 0.3, 0.6));
            Shape::Mesh {
                mesh: TriangleMesh::new(cup.vertices, cup.triangles).unwrap(),
                side: MeshSide::Inside,
            }
        },
    ] {
        let mut m = SceneModel::default();
        m.obstacles
            .push(ObstacleSpec::fixed("bin", container.clone()));
        // a sphere in the corner, and a small heap
        let mut positions = vec![Vec3::new(R, R, R)];
        for k in 0..12 {
            let (i, j, l) = (k % 2, (k / 2) % 2, k / 4);
            positions.push(Vec3::new(
                0.12 + 0.11 * i as f64,
                0.12 + 0.11 * j as f64,
                0.08 + 0.11 * l as f64,
            ));
        }
        m.sphere_batches.push(SphereBatch {
            positions,
            radii: vec![R],
            density: Some(2500.0),
            ..SphereBatch::default()
        });
        let (world, params) = m.build().unwrap();
        let mut sim = Simulation::new(world, params).unwrap();
        let corner_keys = |sim: &Simulation| -> Vec<Partner> {
            sim.contacts
                .iter()
                .filter(|c| c.body == 0 && matches!(c.partner, Partner::Obstacle(..)))
                .map(|c| c.partner)
                .collect()
        };
        let mut last = Vec::new();
        for k in 0..60 {
            let s = sim.step().unwrap();
            assert!(s.converged, "{s:?}");
            let keys = corner_keys(&sim);
            if k >= 50 {
                // the corner sphere rests on three walls: three contacts, one per wall
                // (feature), the same keys from step to step (warm started)
                assert_eq!(keys.len(), 3, "{container:?}: {keys:?}");
                assert_eq!(keys, last, "{container:?}");
                assert!(s.warm_started >= 3);
            }
            last = keys;
        }
        for b in &sim.world.bodies {
            let p = b.position;
            let inside =
                p.x > R * 0.99 && p.x < 0.3 - R * 0.99 && p.y > R * 0.99 && p.y < 0.3 - R * 0.99;
            assert!(inside && p.z > 0.99 * R, "{container:?}: {p:?}");
        }
    }
}

#[test]
fn inserted_spheres_leave_the_others_and_their_warm_starts_unchanged() {
    let mut m = SceneModel::default();
    m.obstacles.push(ObstacleSpec::fixed(
        "floor",
        Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Z,
        },
    ));
    for k in 0..5 {
        m.bodies.push(BodySpec::sphere(
            Vec3::new(0.2 * k as f64, 0.0, R + 0.01),
            R,
            2500.0,
        ));
    }
    let (world, params) = m.build().unwrap();
    let mut a = Simulation::new(world.clone(), params.clone()).unwrap();
    let mut b = Simulation::new(world, params).unwrap();
    for _ in 0..5 {
        a.step().unwrap();
        b.step().unwrap();
    }
    let inlet = SphereBatch {
        positions: vec![Vec3::new(0.0, 3.0, 2.0), Vec3::new(0.3, 3.0, 2.0)],
        radii: vec![R],
        density: Some(2500.0),
        ..SphereBatch::default()
    };
    let new = b.insert_bodies(m.spheres_of(&inlet).unwrap()).unwrap();
    assert_eq!(new, 5..7);
    let (sa, sb) = (a.step().unwrap(), b.step().unwrap());
    assert_eq!(sa.warm_started, 5);
    assert_eq!(sb.warm_started, 5);
    for k in 0..5 {
        assert!((a.world.bodies[k].position - b.world.bodies[k].position).norm() < 1e-12);
    }
    assert!(b.world.bodies[5].position.z < 2.0);
    // invalid inserts are refused
    let mut bad = m.spheres_of(&inlet).unwrap();
    bad[1].radius = -1.0;
    assert!(b.insert_bodies(bad).is_err());
    let mut bad = m.spheres_of(&inlet).unwrap();
    bad[0].material = 3;
    assert!(b.insert_bodies(bad).is_err());
    assert_eq!(b.world.bodies.len(), 7);
}

#[test]
fn restitution_and_rolling_friction_are_per_pair() {
    // two floors: (default, bouncy) e = 0.9, μ_r = 0.02; (default, dead) e = 0, μ_r = 0.2.
    // A sphere dropped on each bounces (or not) by its pair's e; a sphere rolling on each
    // decelerates at 5/7 μ_r g by its pair's μ_r (crate::rolling).
    let mut m = SceneModel::default();
    m.materials.names = vec!["bouncy".into(), "dead".into()];
    for (name, e, mu_r) in [("bouncy", 0.9, 0.02), ("dead", 0.0, 0.2)] {
        m.materials.pairs.push(MaterialPair {
            materials: ["default".into(), name.into()],
            mu: Some(0.5),
            restitution: Some(e),
            rolling_friction: Some(mu_r),
        });
    }
    m.obstacles.push(slab("bouncy", -5.0, 0.0, "bouncy"));
    m.obstacles.push(slab("dead", 0.0, 5.0, "dead"));
    let v0 = 1.0;
    for x in [-2.0, 2.0] {
        let mut drop = BodySpec::sphere(Vec3::new(x, -2.0, R + 0.02), R, 2500.0);
        drop.velocity = Vec3::new(0.0, 0.0, -1.0);
        m.bodies.push(drop);
        let mut roll = BodySpec::sphere(Vec3::new(x, 2.0, R), R, 2500.0);
        roll.velocity = Vec3::new(0.0, v0, 0.0);
        roll.angular_velocity = Vec3::new(-v0 / R, 0.0, 0.0);
        m.bodies.push(roll);
    }
    m.step.h = 0.005;
    let (world, params) = m.build().unwrap();
    assert!(world.has_rolling(params.rolling_friction));
    let mut sim = Simulation::new(world, params).unwrap();
    let mut top = [0.0_f64; 2];
    let steps = 40;
    for k in 0..steps {
        sim.step().unwrap();
        if k > 5 {
            for (i, b) in [0, 2].into_iter().enumerate() {
                top[i] = top[i].max(sim.world.bodies[b].velocity.z);
            }
        }
    }
    // the bouncy floor sends the sphere back up at about 0.9 m/s; the dead one does not
    assert!(top[0] > 0.7, "{top:?}");
    assert!(top[1] < 0.05, "{top:?}");
    let t = steps as f64 * sim.params.h;
    let g = 9.81;
    for (b, mu_r) in [(1, 0.02), (3, 0.2)] {
        let v = sim.world.bodies[b].velocity.y;
        let expected = v0 - 5.0 / 7.0 * mu_r * g * t;
        assert!((v - expected).abs() < 0.02, "μ_r {mu_r}: {v} vs {expected}");
    }
}
