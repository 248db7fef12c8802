//! Mean time of one Moreau–Jean step of the `box` scene (600 beads, paper tolerance), after the
//! pile has formed. Run: `cargo bench -p coulomb-granular`.

use coulomb::solver::{InnerKind, OuterKind, Settings};
use coulomb_granular::{Params, Scene, Simulation};
use criterion::{criterion_group, criterion_main, Criterion};

fn paper_params(inner: InnerKind) -> Params {
    Params {
        // the paper's tolerance, as `coulomb paper table1|scaling` use it
        solver: Settings {
            inner,
            outer: OuterKind::FixedPoint,
            tol: 1e-4,
            max_outer: 20,
            max_inner: 250,
            fixed_point_tol: Some(0.01),
            inner_tol_factor: 1e-6,
            fallback: None,
            warmup_sweeps: 0,
            ..Settings::default()
        },
        // the paper's time stepping (Siconos' activation, no position correction)
        activation: coulomb_granular::Activation::default(),
        projection: None,
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
        // let the contacts form first (as `coulomb paper scaling --settle 50`)
        for _ in 0..50 {
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
