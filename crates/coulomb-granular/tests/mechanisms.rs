//! The shipped mechanism scenes of issue 53 built from many parts (examples/scenes/rigid,
//! written by make_joint_scenes.py), run on small variants (`BuildOptions::max_fill` caps
//! their sphere fills): the ball mill and the vehicle on granular ground.

use coulomb_granular::rigid::RigidStatus;
use coulomb_granular::rigid_scene::RigidScene;
use coulomb_granular::scene_file::{BuildOptions, LoadedScene};
use std::path::PathBuf;

fn scene(name: &str, max_fill: usize) -> (RigidScene, f64) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/scenes/rigid")
        .join(name);
    let built = LoadedScene::load(&path)
        .unwrap_or_else(|e| panic!("{e}"))
        .build(&BuildOptions {
            max_fill: Some(max_fill),
            ..BuildOptions::default()
        })
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(built.model.has_shapes());
    let tol = built.model.step.tol;
    (RigidScene::new(&built.model).unwrap(), tol)
}

/// The ball mill with 40 balls: the drum (body 0, a compound of 16 staves, 2 end plates and
/// 8 lifters, hinged to the world about y at (0, 0, 0.5) with a motor of 3 rad/s and at most
/// 300 N m) spins up, then turns at the motor's speed while its lifters carry the load up
/// the rising side (−x for a rotation about +y); every ball stays inside; every step is solved
/// within the file's tolerance and the hinge does not drift.
#[test]
fn the_ball_mill_turns_at_its_motor_speed_and_lifts_its_load() {
    let (mut s, tol) = scene("ball-mill.toml", 40);
    let w = &mut s.world;
    assert_eq!(w.len(), 41);
    assert_eq!(w.joint_count(), 1);
    let (omega, centre, radius, half_length, ball) = (3.0, [0.0, 0.0, 0.5], 0.3, 0.15, 0.015);
    let load = |w: &coulomb_granular::rigid::RigidWorld| {
        let c = w.centres_of_mass();
        let n = (c.len() - 1) as f64;
        c[1..].iter().fold([0.0; 3], |a, p| {
            [a[0] + p[0] / n, a[1] + p[1] / n, a[2] + p[2] / n]
        })
    };
    let z0 = load(w)[2];
    let mut rates = Vec::new();
    let mut settled_x = Vec::new();
    for k in 0..500 {
        let r = s.step().unwrap();
        assert!(
            r.status != RigidStatus::NotConverged && r.error <= tol,
            "step {k}: {r:?}"
        );
        let w = &s.world;
        let (_, rate) = w.joint_coordinate(0).unwrap();
        if k >= 150 {
            rates.push(rate);
        }
        if k >= 400 {
            settled_x.push(load(w)[0]);
        }
        for (b, p) in w.centres_of_mass().iter().enumerate().skip(1) {
            let (dx, dz) = (p[0] - centre[0], p[2] - centre[2]);
            // the wall is a 16-gon whose flat faces are at the apothem `radius` from the
            // axis: a ball inside is at most radius - ball from the axis along every face's
            // normal (turned with the drum; 1 mm of slack for the contacts' penetration)
            let (turn, _) = w.joint_coordinate(0).unwrap();
            let off_axis = (0..16)
                .map(|f| {
                    let a = turn + f as f64 * std::f64::consts::PI / 8.0;
                    dx * a.cos() - dz * a.sin()
                })
                .fold(f64::MIN, f64::max);
            assert!(
                off_axis <= radius - ball + 1e-3 && p[1].abs() <= half_length - ball + 1e-3,
                "step {k}: ball {b} at {p:?} left the drum"
            );
        }
    }
    // the drum turns at the motor's speed once spun up (the motor's row holds it exactly
    // while its torque stays below 300 N m)
    let worst = rates
        .iter()
        .map(|r| (r - omega).abs() / omega)
        .fold(0.0, f64::max);
    eprintln!(
        "ball mill: drum rate within {worst:.2e} of {omega} rad/s over steps 150-500; drift {:.2e}",
        s.world.joint_drift()
    );
    assert!(worst < 1e-3, "{worst}");
    assert!(s.world.joint_drift() < 1e-6, "{}", s.world.joint_drift());
    // the load is carried up the rising side: its centre of mass moved to −x and rose
    let x = settled_x.iter().sum::<f64>() / settled_x.len() as f64;
    let z = load(&s.world)[2];
    eprintln!("ball mill: load centre x = {x:.4} m, rose {:.4} m", z - z0);
    assert!(x < -0.02, "load centre x = {x}");
    assert!(z > z0, "load centre z {z} vs {z0} at the start");
}

/// The vehicle on granular ground with a bed of 264 spheres (the shipped file's bed of 10⁴
/// spheres of r = 10 mm with the spheres' radius set to 30 mm and the lattice's pitch to 66 mm:
/// one layer of 33 × 8): the chassis (body 0) on four wheels (bodies 1–4, cylinders r = 0.1 m)
/// driven at 5 rad/s by motors of at most 20 N m drops onto the bed and drives along +x; no
/// wheel sinks through the bed (every wheel's lowest point stays above the floor by more than
/// a sphere's radius); every step is solved and the joints do not drift.
#[test]
fn the_vehicle_drives_over_a_bed_of_spheres() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/scenes/rigid/vehicle-on-spheres.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let small = text
        .replace("count = 10000", "count = 264")
        .replace(
            "sizes = { kind = \"mono\", radius = 0.01 }",
            "sizes = { kind = \"mono\", radius = 0.03 }",
        )
        .replace("pitch = 0.022,", "pitch = 0.066,");
    assert_ne!(small, text);
    let built = LoadedScene::parse(&path, small, true)
        .unwrap_or_else(|e| panic!("{e}"))
        .build(&BuildOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let tol = built.model.step.tol;
    let mut s = RigidScene::new(&built.model).unwrap();
    assert_eq!(s.world.len(), 5 + 264);
    assert_eq!(s.world.joint_count(), 4);
    let (wheel, ball) = (0.1, 0.03);
    let x0 = s.world.centres_of_mass()[0][0];
    let mut drift: f64 = 0.0;
    let mut lowest = f64::MAX;
    let steps = 600;
    for k in 0..steps {
        let r = s.step().unwrap();
        assert!(
            r.status != RigidStatus::NotConverged && r.error <= tol,
            "step {k}: {r:?}"
        );
        drift = drift.max(s.world.joint_drift());
        let c = s.world.centres_of_mass();
        for p in &c[1..5] {
            lowest = lowest.min(p[2] - wheel);
        }
    }
    let c = s.world.centres_of_mass();
    let advance = c[0][0] - x0;
    let rates: Vec<f64> = (0..4)
        .map(|j| s.world.joint_coordinate(j).unwrap().1)
        .collect();
    eprintln!(
        "vehicle: advanced {advance:.4} m in {steps} steps (0.5 m/s without slip: {:.3} m); \
         lowest wheel bottom {lowest:.4} m; drift {drift:.2e}; wheel rates {rates:?}",
        0.5 * steps as f64 * 1e-3
    );
    assert!(advance > 0.05, "advanced {advance} m");
    assert!(lowest > ball, "a wheel's bottom reached {lowest} m");
    assert!(drift < 1e-6, "{drift}");
}
