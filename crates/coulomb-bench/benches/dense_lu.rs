//! Factor and solve of a dense n × n system by [`coulomb::dense::Lu`] on one thread and on
//! all of rayon's, for the sizes of the rigid problems' Newton systems (the Schur complement
//! and the skeleton: n ≤ `BarrierParams::max_schur_dofs` = 1 500) and one above: the
//! measurement behind `BarrierParams::dense_parallel_dim`.
//! `cargo bench -p coulomb-bench --bench dense_lu`.

use coulomb::dense::Lu;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use faer::{Mat, Par};
use std::time::Duration;

/// A diagonally dominant non-symmetric n × n matrix (no pivot is near zero).
fn matrix(n: usize) -> Mat<f64> {
    Mat::from_fn(n, n, |i, j| {
        if i == j {
            n as f64
        } else {
            ((i * 7 + j * 13) % 17) as f64 / 17.0
        }
    })
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("dense_lu");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(3));
    for n in [100, 384, 1000, 1500, 3000] {
        let a = matrix(n);
        let b: Vec<f64> = (0..n).map(|i| i as f64).collect();
        for (name, par) in [("one-thread", Par::Seq), ("all-threads", Par::rayon(0))] {
            group.bench_with_input(BenchmarkId::new(name, n), &n, |bench, _| {
                bench.iter(|| {
                    let lu = Lu::new(a.clone(), par).expect("square");
                    let mut x = b.clone();
                    assert!(lu.solve_in_place(&mut x));
                    x
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
