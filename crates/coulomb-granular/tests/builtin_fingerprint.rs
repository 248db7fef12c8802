//! The four built-in scenes, stepped with the parameters `coulomb simulate` uses by default,
//! give the same numbers bit for bit as before the scene model (issue 40): the fingerprints
//! below are FNV-1a hashes of every f64 bit of the positions, velocities and angular
//! velocities after the steps, RECORDED FROM THE PREVIOUS IMPLEMENTATION (the hand-built
//! scenes of `scene.rs` and the global μ, e of `Params`) before the scene model was written.
//! Hard-coding them is deliberate: this is a regression test against that implementation.

use coulomb::{InnerKind, Method, MethodParams, OuterKind, Settings};
use coulomb_granular::{
    Activation, NsgsSettings, Params, Projection, Scene, Simulation, StepMethod,
};

/// The `Params` of `coulomb simulate` with its default arguments (crates/coulomb-cli/src/sim_args.rs).
fn cli_params() -> Params {
    let d = Settings::time_stepping(Method::new(InnerKind::Pgs, Settings::default().outer));
    let solver = Settings {
        tol: 1e-4,
        max_outer: 20,
        params: MethodParams {
            fixed_point_tol: None,
            ..d.params
        },
        outer: OuterKind::Fused,
        fallback: Some((InnerKind::Apgd, OuterKind::Anderson)),
        ..d
    };
    Params {
        h: 0.02,
        theta: 0.5,
        restitution: 0.2,
        mu: 0.3,
        activation: Activation {
            gamma: 1.0,
            close_gaps: true,
            ..Activation::accurate()
        },
        solver,
        warm_start: true,
        projection: Some(Projection::default()),
        method: StepMethod::Nsgs(NsgsSettings {
            tol: 1e-4,
            max_sweeps: 20_000,
            relaxation: 1.5,
            ..NsgsSettings::default()
        }),
        rolling_friction: 0.0,
    }
}

fn fingerprint(scene: Scene, beads: usize, steps: usize) -> u64 {
    let world = scene.build(beads, 1);
    let mut sim = Simulation::new(world, cli_params()).unwrap();
    for _ in 0..steps {
        sim.step().unwrap();
    }
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in &sim.world.bodies {
        for v in [b.position, b.velocity, b.angular_velocity] {
            for x in v.to_array() {
                for byte in x.to_bits().to_le_bytes() {
                    h ^= byte as u64;
                    h = h.wrapping_mul(0x0100_0000_01b3);
                }
            }
        }
    }
    h
}

#[test]
fn builtin_scenes_are_unchanged_bit_for_bit() {
    let got = [
        fingerprint(Scene::Box, 300, 20),
        fingerprint(Scene::Funnel, 150, 10),
        fingerprint(Scene::VibratingPlate, 150, 10),
        fingerprint(Scene::RotatingDrum, 150, 10),
    ];
    println!("fingerprints: {got:#018x?}");
    // recorded from the implementation before the scene model (commit d2d3faf)
    let want: [u64; 4] = [
        0xc8e5_7167_2770_5352,
        0xd0ad_7798_74cc_2cb6,
        0x77c2_9b29_635c_b42a,
        0x0507_a309_08e7_fd9c,
    ];
    assert_eq!(got, want);
}
