//! Mean time of one Moreau–Jean step of the `box` scene after the pile has formed: the paper's
//! tolerance with the library's APGD (150 and 600 beads), and the accurate step of `coulomb
//! simulate` — body-level Gauss–Seidel to err ≤ 1e-4 (`nsgs_*`, 600 and 10 000 beads, on the
//! ambient rayon pool: `RAYON_NUM_THREADS=1` for one thread). Run: `cargo bench -p
//! coulomb-bench --bench box_step` (or `--bench box_step -- nsgs_10000`).

use coulomb::solver::{InnerKind, MethodParams, OuterKind, Settings};
use coulomb_granular::{NsgsSettings, Params, Scene, Simulation, StepMethod};
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
            fallback: None,
            params: MethodParams {
                fixed_point_tol: Some(0.01),
                inner_tol_factor: 1e-6,
                warmup_sweeps: 0,
                barrier_steps: 0,
                ..MethodParams::default()
            },
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
    // the accurate step (docs/scaling.md), each bench step continuing the same simulation
    for beads in [600usize, 10_000] {
        let params = Params {
            method: StepMethod::Nsgs(NsgsSettings::default()),
            ..Params::default()
        };
        let mut sim = match Simulation::new(Scene::box_spread(beads, 1), params) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        };
        for _ in 0..40 {
            if sim.step().is_err() {
                return;
            }
        }
        group.bench_function(format!("nsgs_{beads}"), |b| {
            b.iter(|| sim.step().map(|s| s.contacts).unwrap_or(0))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_box);
criterion_main!(benches);
