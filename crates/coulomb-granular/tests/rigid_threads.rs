//! The rigid engine's coloured parallel Gauss–Seidel (issue 52, item 2) and its parallel
//! exact evaluations (v gathered per body, u per contact): the same bits whatever the number
//! of threads, on scenes whose colours are large enough to be swept in parallel
//! ([`coulomb_granular::nsgs::PARALLEL_MIN`] rows and more) and whose steps have enough
//! contacts to be evaluated in parallel
//! ([`coulomb_granular::rigid::step::nsgs::EVAL_PARALLEL_MIN`] and more).

use coulomb_granular::rigid::validation::{cube_pyramid, floor, one_material, rock_pile};
use coulomb_granular::rigid::{RigidBodyDesc, RigidObstacle, RigidSettings, RigidWorld};

/// Positions, orientations, velocities, angular velocities and contact impulses after
/// `steps` steps on a pool of `threads` threads, as bits; and the most contacts in a step.
fn run(
    bodies: &[RigidBodyDesc],
    obstacles: &[RigidObstacle],
    steps: usize,
    threads: usize,
) -> (Vec<u64>, usize) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let settings = RigidSettings {
            tolerance: 1e-6,
            ..RigidSettings::default()
        };
        let mut w = RigidWorld::new(
            bodies.to_vec(),
            obstacles.to_vec(),
            one_material(0.6),
            settings,
        )
        .unwrap();
        let mut most = 0;
        for _ in 0..steps {
            let r = w.step().unwrap();
            most = most.max(r.contacts);
        }
        let mut bits: Vec<u64> = Vec::new();
        for v in [w.positions(), w.velocities(), w.angular_velocities()] {
            bits.extend(v.iter().flatten().map(|x| x.to_bits()));
        }
        bits.extend(w.orientations().iter().flatten().map(|x| x.to_bits()));
        for c in w.contacts() {
            bits.extend(c.impulse.iter().map(|x| x.to_bits()));
        }
        (bits, most)
    })
}

#[test]
fn a_cube_pyramid_gives_the_same_bits_on_one_and_two_threads() {
    // 7 layers: 140 cubes, 49 on the floor (4 points each): colours of more than 64 rows
    let bodies = cube_pyramid(7).unwrap();
    let obstacles = vec![floor()];
    let (one, contacts) = run(&bodies, &obstacles, 8, 1);
    assert!(
        contacts > 4 * coulomb_granular::nsgs::PARALLEL_MIN,
        "{contacts} contacts: too few for parallel colours"
    );
    assert!(
        contacts >= coulomb_granular::rigid::step::nsgs::EVAL_PARALLEL_MIN,
        "{contacts} contacts: too few for the parallel evaluation"
    );
    let (two, _) = run(&bodies, &obstacles, 8, 2);
    assert_eq!(one.len(), two.len());
    let differ = one.iter().zip(&two).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} numbers differ between 1 and 2 threads");
    let (three, _) = run(&bodies, &obstacles, 8, 3);
    assert!(one == three, "1 and 3 threads differ");
}

#[test]
fn a_rock_pile_gives_the_same_bits_on_one_and_two_threads() {
    // 64 hull rocks poured in a box (the bench's pile, smaller): hull–hull and hull–half-space
    // pairs, the narrow phase in parallel too
    let (bodies, obstacles) = rock_pile(64, 3).unwrap();
    let (one, contacts) = run(&bodies, &obstacles, 120, 1);
    assert!(contacts > 0, "the rocks never touched");
    let (two, _) = run(&bodies, &obstacles, 120, 2);
    assert!(one == two, "1 and 2 threads differ");
}
