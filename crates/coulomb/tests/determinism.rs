//! Same input and settings → the same bits (issue #42 item 4): every stage of the default
//! policy has a budget in work (iterations, factorizations), none a share of the wall-clock
//! time, and the method of multipliers' runs decide in lock-step rounds, in index order. So
//! r, the iteration counts and the history are the same on 1 and on 2 threads, and with busy
//! threads competing for the CPUs (a loaded machine, on which a share of the time left would
//! end stages earlier).
//!
//! Files: `data/pile-nonsym-local.hdf5` (rigid boxes, W of rank 48 of 192, non-symmetric: the
//! interior-point try and the method of multipliers on its skeleton) and
//! `data/box-local.hdf5` (a settled heap of 120 spheres: the warm-up and the main method).

use crate::common;

use coulomb::solver::{solve, Settings, Solution};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// What must not change between runs: the bits of r, u and the error, the status, the
/// iteration counts and every history record (NaN compared as bits).
#[derive(PartialEq)]
struct Fingerprint {
    r: Vec<u64>,
    u: Vec<u64>,
    error: u64,
    status: String,
    outer: usize,
    inner: usize,
    history: Vec<[u64; 4]>,
}

fn fingerprint(sol: &Solution) -> Fingerprint {
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    Fingerprint {
        r: bits(&sol.r),
        u: bits(&sol.u),
        error: sol.error.to_bits(),
        status: format!("{:?}", sol.status),
        outer: sol.outer_iterations,
        inner: sol.inner_iterations,
        history: sol
            .history
            .iter()
            .map(|h| {
                [
                    h.error.to_bits(),
                    h.fixed_point_residual.to_bits(),
                    h.rule_6_1.to_bits(),
                    h.inner_iterations as u64,
                ]
            })
            .collect(),
    }
}

/// The default solve of `file` on a rayon pool of `threads` threads.
fn solve_on(file: &str, threads: usize) -> Solution {
    let path = common::data_dir().join(file);
    let problem = coulomb::fclib::read(&path).unwrap().problem;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| solve(&problem, &Settings::default()).unwrap())
}

/// Busy threads (one per available CPU) until the returned flag is raised.
fn burner() -> (Arc<AtomicBool>, Vec<std::thread::JoinHandle<()>>) {
    let stop = Arc::new(AtomicBool::new(false));
    let n = std::thread::available_parallelism().map_or(2, |n| n.get());
    let handles = (0..n)
        .map(|_| {
            let stop = Arc::clone(&stop);
            std::thread::spawn(move || {
                let mut x = 1u64;
                while !stop.load(Ordering::Relaxed) {
                    for _ in 0..10_000 {
                        x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
                    }
                    std::hint::black_box(x);
                }
            })
        })
        .collect();
    (stop, handles)
}

#[test]
fn the_default_gives_the_same_bits_on_one_or_two_threads_and_under_load() {
    for file in ["pile-nonsym-local.hdf5", "box-local.hdf5"] {
        let one = solve_on(file, 1);
        assert!(one.converged(), "{file}: {:?}", one.status);
        let reference = fingerprint(&one);
        let two = solve_on(file, 2);
        assert!(fingerprint(&two) == reference, "{file}: 2 threads differ");
        let (stop, handles) = burner();
        let loaded = [solve_on(file, 1), solve_on(file, 2)];
        stop.store(true, Ordering::Relaxed);
        handles.into_iter().for_each(|h| h.join().unwrap());
        for (k, sol) in loaded.iter().enumerate() {
            assert!(
                fingerprint(sol) == reference,
                "{file}: under load on {} thread(s) differs",
                k + 1
            );
        }
    }
}
