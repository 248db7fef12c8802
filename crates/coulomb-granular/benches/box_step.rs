//! Mean time of one Moreau–Jean step of the `box` scene (600 beads, paper tolerance), after the
//! pile has formed. Run: `cargo bench -p coulomb-granular`.

use coulomb::solver::{InnerKind, Settings};
use coulomb_granular::{Params, Scene, Simulation};
use criterion::{criterion_group, criterion_main, Criterion};

fn paper_params(inner: InnerKind) -> Params {
    Params {
        solver: Settings {
            inner,
            tol: 1e-3,
            max_outer: 20,
            fixed_point_tol: Some(0.01),
            ..Settings::default()
        },
        ..Params::default()
    }
}

fn bench_box(c: &mut Criterion) {
    let mut group = c.benchmark_group("box_step");
    group.sample_size(10);
    for beads in [150usize, 600] {
        let mut sim =
            match Simulation::new(Scene::Box.build(beads, 1), paper_params(InnerKind::Apgd)) {
                Ok(s) => s,
                Err(e) => panic!("{e}"),
            };
        // let the pile form first
        for _ in 0..150 {
            if sim.step().is_err() {
                return;
            }
        }
        group.bench_function(format!("apgd_{beads}"), |b| {
            b.iter(|| sim.step().map(|s| s.contacts).unwrap_or(0))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_box);
criterion_main!(benches);
