//! Tests of [`super`] that drive a whole world.

use super::*;
use parry3d_f64::math::Rotation;
use rand::{Rng, SeedableRng};

fn body(x: Vector, q: Rotation) -> BodyState {
    BodyState {
        mass: 1.0,
        inertia: [1.0; 3],
        local_com: Vector::ZERO,
        principal: Rotation::IDENTITY,
        x,
        q,
        v: Vector::ZERO,
        omega: Vector::ZERO,
        material: 0,
        fixed: false,
        reach: 1.0,
    }
}

fn unit(rng: &mut impl Rng) -> Vector {
    loop {
        let v = Vector::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if v.length() > 0.1 && v.length() < 1.0 {
            return v.normalize();
        }
    }
}

fn rotation(rng: &mut impl Rng) -> Rotation {
    let v = unit(rng);
    Rotation::from_xyzw(v.x, v.y, v.z, rng.random_range(-1.0..1.0)).normalize()
}

/// The points of the fast path and of parry on the same scene: same keys in the same
/// order, gap, normal and point within 1e-12, and the fast path's tangents those of
/// [`tangent_frame`] (parry's normal of an axis-aligned plane carries round-off of 1e-16
/// off the axis, on which `tangent_frame` may choose another axis: the same frame turned
/// about n). Against a half-space parry's normal is (c − proj)/|c − proj| in the plane's
/// frame, whose round-off grows as ε|c|/s when the centre nears the plane (s its
/// distance): the tolerance there is 1e-12 max(1, r/s).
fn same_points(
    bodies: &[BodyState],
    shapes: &[SharedShape],
    obstacles: &[PlacedObstacle<'_>],
    margins: &[f64],
) -> usize {
    let fast = Detector::default()
        .detect(bodies, shapes, obstacles, margins)
        .unwrap();
    let parry = Detector::parry_only()
        .detect(bodies, shapes, obstacles, margins)
        .unwrap();
    assert_eq!(fast.len(), parry.len());
    for (f, p) in fast.iter().zip(&parry) {
        assert_eq!(f.key, p.key);
        assert_eq!((f.a, f.b), (p.a, p.b));
        let tol = match (f.b, shapes[f.a].as_ball()) {
            (Partner::Obstacle(_, _), Some(ball)) => {
                1e-12 * (ball.radius / (f.gap + ball.radius).abs()).max(1.0)
            }
            _ => 1e-12,
        };
        assert!((f.gap - p.gap).abs() <= 1e-12, "{f:?} {p:?}");
        assert!((f.normal - p.normal).length() <= tol, "{f:?} {p:?}");
        assert!((f.point - p.point).length() <= 1e-12, "{f:?} {p:?}");
        assert_eq!((f.t1, f.t2), tangent_frame(f.normal));
        assert!(f.t1.dot(f.normal).abs() <= 1e-15 && (f.t1.length() - 1.0).abs() <= 1e-15);
        assert!((f.t1.cross(f.t2) - f.normal).length() <= 1e-15);
    }
    fast.len()
}

pub fn the_caches_handed_on_are_those_remove_gives() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(52);
    for case in 0..50 {
        let n = 1 + case * 3;
        let old: BTreeMap<(usize, u8), u32> = (0..n)
            .map(|_| {
                (
                    (rng.random_range(0..40), rng.random_range(0..3)),
                    rng.random_range(1..1000),
                )
            })
            .collect();
        let mut keys: Vec<(usize, u8)> = (0..n)
            .map(|_| (rng.random_range(0..40), rng.random_range(0..3)))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        let mut reference = old.clone();
        let expected: Vec<((usize, u8), u32)> = keys
            .iter()
            .map(|k| (*k, reference.remove(k).unwrap_or_default()))
            .collect();
        let got = take_caches(old.clone(), &keys);
        assert_eq!(got, expected, "case {case}");
        // not vacuous: some keys find their entry, some do not
        if case > 10 {
            assert!(got.iter().any(|(k, v)| *v != 0 && old.get(k) == Some(v)));
        }
    }
}

pub fn ball_pairs_match_parry_on_random_pairs() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(52);
    let (mut ball_ball_points, mut plane_points) = (0, 0);
    for _ in 0..2000 {
        // two balls with a gap in [−r_min/2, 2 prediction], one random half-space
        let (ra, rb): (f64, f64) = (rng.random_range(0.01..0.2), rng.random_range(0.01..0.2));
        let margin: f64 = rng.random_range(0.0..0.02);
        let gap = rng.random_range(-0.5 * ra.min(rb)..4.0 * margin + 1e-3);
        let ca = Vector::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let cb = ca + (ra + rb + gap) * unit(&mut rng);
        let bodies = [body(ca, rotation(&mut rng)), body(cb, rotation(&mut rng))];
        let shapes = [SharedShape::ball(ra), SharedShape::ball(rb)];
        let n = unit(&mut rng);
        let plane = SharedShape::halfspace(n);
        // the plane's boundary at a random signed distance from ball A's surface
        let s = ra + rng.random_range(-0.5 * ra..4.0 * margin + 1e-3);
        let origin_offset = unit(&mut rng).cross(n);
        let obstacle_pose = Pose::from_parts(ca - s * n + origin_offset, Rotation::IDENTITY);
        let obstacles = [PlacedObstacle {
            shape: &plane,
            pose: obstacle_pose,
        }];
        let found = Detector::default()
            .detect(&bodies, &shapes, &obstacles, &[margin, margin])
            .unwrap();
        ball_ball_points += found
            .iter()
            .filter(|c| matches!(c.b, Partner::Body(_)))
            .count();
        plane_points += found
            .iter()
            .filter(|c| c.a == 0 && matches!(c.b, Partner::Obstacle(_, _)))
            .count();
        same_points(&bodies, &shapes, &obstacles, &[margin, margin]);
    }
    // both kinds of pairs were met often, in and out of the prediction
    assert!(
        ball_ball_points > 500 && ball_ball_points < 1900,
        "{ball_ball_points}"
    );
    assert!(plane_points > 500 && plane_points < 1900, "{plane_points}");
}

/// A stored pair cache names a whole obstacle (feature 0): the JSON written reads back, and
/// the same JSON with a feature on the obstacle, which no rigid pair has, is refused.
pub fn stored_pair_caches_refuse_an_obstacle_feature() {
    let bodies = vec![body(Vector::new(0.0, 0.0, 0.05), Rotation::IDENTITY)];
    let shapes = vec![SharedShape::cuboid(0.05, 0.05, 0.05)];
    let floor = SharedShape::halfspace(Vector::Z);
    let obstacles = [PlacedObstacle {
        shape: &floor,
        pose: Pose::IDENTITY,
    }];
    let mut detector = Detector::default();
    let points = detector
        .detect(&bodies, &shapes, &obstacles, &[0.01])
        .unwrap();
    assert!(!points.is_empty());
    let json = detector.to_json().unwrap();
    let partner = r#""kind":"obstacle","index":0"#;
    assert!(json.contains(partner), "{json}");
    assert!(Detector::from_json(&json, 1, 1).is_ok());
    let tampered = json.replace(partner, &format!("{partner},\"feature\":5"));
    let e = Detector::from_json(&tampered, 1, 1).unwrap_err();
    assert!(e.contains("out of range"), "{e}");
}

pub fn a_box_of_balls_and_cuboids_gives_parry_points_in_parry_order() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut bodies = Vec::new();
    let mut shapes = Vec::new();
    for i in 0..6 {
        for j in 0..6 {
            for k in 0..4 {
                let x = Vector::new(0.1 * i as f64, 0.1 * j as f64, 0.05 + 0.1 * k as f64)
                    + 0.01 * unit(&mut rng);
                bodies.push(body(x, rotation(&mut rng)));
                shapes.push(if (i + j + k) % 7 == 0 {
                    SharedShape::cuboid(0.03, 0.04, 0.035)
                } else {
                    SharedShape::ball(rng.random_range(0.04..0.055))
                });
            }
        }
    }
    bodies[5].fixed = true;
    let planes: Vec<SharedShape> = [Vector::Z, Vector::X, -Vector::X]
        .iter()
        .map(|n| SharedShape::halfspace(*n))
        .collect();
    let cuboid = SharedShape::cuboid(0.1, 0.1, 0.1);
    let mut obstacles: Vec<PlacedObstacle<'_>> = planes
        .iter()
        .zip([0.0, 0.0, 0.5])
        .map(|(shape, x)| PlacedObstacle {
            shape,
            pose: Pose::from_parts(Vector::new(x, 0.0, 0.0), Rotation::IDENTITY),
        })
        .collect();
    obstacles.push(PlacedObstacle {
        shape: &cuboid,
        pose: Pose::from_parts(Vector::new(0.25, 0.25, 0.6), rotation(&mut rng)),
    });
    let margins: Vec<f64> = (0..bodies.len())
        .map(|_| rng.random_range(0.0..0.01))
        .collect();
    let n = same_points(&bodies, &shapes, &obstacles, &margins);
    assert!(n > 100, "{n}");
}

use crate::bodies::rigid::{MassProperties, RigidBodyDesc};
use crate::step::rigid::{RigidSettings, RigidWorld};
use crate::validation::rigid::{floor, one_material};

fn ball_desc(r: f64, x: [f64; 3], v: [f64; 3], w: [f64; 3]) -> RigidBodyDesc {
    let shape = SharedShape::ball(r);
    let mass = MassProperties::from_shape(&shape, 1000.0).unwrap();
    RigidBodyDesc {
        shape,
        mass,
        position: x,
        orientation: [1.0, 0.0, 0.0, 0.0],
        velocity: v,
        angular_velocity: w,
        material: 0,
        fixed: false,
    }
}

/// The run of `steps` steps with the fast path and with parry only: the same contacts,
/// statuses and warm starts each step, and positions, orientations, velocities and
/// angular velocities within `tol` (absolute; both runs solve each step to the settings'
/// tolerance from tangent frames that may differ by a turn about n, see
/// [`same_points`]); returns the fast run's last state and the largest difference.
fn same_run(
    bodies: Vec<RigidBodyDesc>,
    settings: RigidSettings,
    steps: usize,
    tol: f64,
) -> (RigidWorld, f64) {
    let make = || {
        RigidWorld::new(
            bodies.clone(),
            vec![floor()],
            one_material(0.5),
            settings.clone(),
        )
        .unwrap()
    };
    let (mut fast, mut parry) = (make(), make().parry_only_detection());
    let (mut contacts, mut worst) = (0, 0.0f64);
    for _ in 0..steps {
        let (rf, rp) = (fast.step().unwrap(), parry.step().unwrap());
        assert_eq!(rf.contacts, rp.contacts);
        assert_eq!(rf.status, rp.status);
        assert_eq!(rf.warm_started, rp.warm_started);
        contacts += rf.contacts;
        let state = |w: &RigidWorld| -> Vec<f64> {
            let mut s: Vec<f64> = w.positions().into_iter().flatten().collect();
            s.extend(w.velocities().into_iter().flatten());
            s.extend(w.angular_velocities().into_iter().flatten());
            s.extend(w.orientations().into_iter().flatten());
            s
        };
        let d = state(&fast)
            .iter()
            .zip(state(&parry))
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        worst = worst.max(d);
    }
    assert!(contacts > 0);
    assert!(worst <= tol, "largest difference {worst:e}");
    (fast, worst)
}

pub fn a_ball_sliding_then_rolling_on_the_floor_moves_as_with_parry() {
    // thrown along x without spin: it slides, friction spins it up until it rolls
    let r = 0.1;
    let b = ball_desc(r, [0.0, 0.0, r], [1.0, 0.0, 0.0], [0.0; 3]);
    // measured: 4.8e-12
    let (w, _) = same_run(vec![b], RigidSettings::default(), 400, 1e-9);
    // rolling without slipping at the end: v_x = ω_y r = 5/7 of the throw
    let (v, om) = (w.velocities()[0], w.angular_velocities()[0]);
    assert!((v[0] - 5.0 / 7.0).abs() < 1e-3, "{v:?}");
    assert!((v[0] - om[1] * r).abs() < 1e-6, "{v:?} {om:?}");
}

pub fn two_balls_colliding_above_the_floor_move_as_with_parry() {
    // head-on and off-centre, in free fall above the floor, then resting on it
    let a = ball_desc(0.05, [0.0, 0.0, 0.3], [2.0, 0.0, 0.0], [0.0, 0.0, 3.0]);
    let b = ball_desc(0.07, [0.3, 0.03, 0.3], [-1.0, 0.0, 0.0], [0.0; 3]);
    let settings = RigidSettings {
        h: 2e-3,
        ..RigidSettings::default()
    };
    // measured: 3.6e-9 (each step solved to 1e-8 from frames turned about n)
    let (w, _) = same_run(vec![a, b], settings, 300, 1e-7);
    // perfectly inelastic (e = 0): A (2 m/s) meets the 2.7 times heavier B (−1 m/s)
    // and both leave at (2 m_A − m_B)/(m_A + m_B) ≈ −0.2 m/s, then friction acts
    let v = w.velocities();
    assert!(v[0][0] < 0.5 && v[1][0] < 0.5, "{v:?}");
}

pub fn a_ball_pile_with_a_cuboid_gives_the_same_bits_on_one_and_two_threads() {
    // 180 balls stacked in touching layers (jittered) on the floor around one cuboid:
    // fast-path pairs beside parry's (cuboid–ball, cuboid–floor), swept in parallel
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut bodies =
        vec![crate::validation::rigid::cuboid([0.1, 0.1, 0.05], 1000.0, [0.3, 0.3, 0.05]).unwrap()];
    for k in 0..5 {
        for i in 0..6 {
            for j in 0..6 {
                let (x, y) = (0.11 * i as f64, 0.11 * j as f64);
                if k == 0 && (0.15..0.45).contains(&x) && (0.15..0.45).contains(&y) {
                    continue;
                }
                let dx = rng.random_range(-0.005..0.005);
                let dy = rng.random_range(-0.005..0.005);
                // layer 1 just above the cuboid's top (z = 0.1), each 1 mm above the last
                let z = if k == 0 {
                    0.05
                } else {
                    0.151 + 0.101 * (k - 1) as f64
                };
                bodies.push(ball_desc(0.05, [x + dx, y + dy, z], [0.0; 3], [0.0; 3]));
            }
        }
    }
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let settings = RigidSettings {
                tolerance: 1e-6,
                ..RigidSettings::default()
            };
            let mut w = RigidWorld::new(bodies.clone(), vec![floor()], one_material(0.5), settings)
                .unwrap();
            let mut most = 0;
            for _ in 0..80 {
                most = most.max(w.step().unwrap().contacts);
            }
            let mut bits: Vec<u64> = Vec::new();
            for v in [w.positions(), w.velocities(), w.angular_velocities()] {
                bits.extend(v.iter().flatten().map(|x| x.to_bits()));
            }
            bits.extend(w.orientations().iter().flatten().map(|x| x.to_bits()));
            (bits, most)
        })
    };
    let (one, most) = run(1);
    assert!(most > 100, "{most} contacts");
    let (two, _) = run(2);
    assert!(one == two, "1 and 2 threads differ");
}
