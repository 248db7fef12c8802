//! Time to solve each problem of ../shared/fclib to error 1e-8 with each solver combination
//! (skipped quietly when the directory is absent). `cargo bench -p coulomb-bench --bench inner`.

use coulomb::fclib::read;
use coulomb::solver::{solve, InnerKind, OuterKind, Settings};
use criterion::{criterion_group, criterion_main, Criterion};
use std::path::Path;
use std::time::Duration;

fn combos() -> Vec<(&'static str, InnerKind, OuterKind)> {
    vec![
        ("pgs-fused", InnerKind::Pgs, OuterKind::Fused),
        ("pgs-fixed-point", InnerKind::Pgs, OuterKind::FixedPoint),
        ("apgd-fixed-point", InnerKind::Apgd, OuterKind::FixedPoint),
        ("apgd-anderson", InnerKind::Apgd, OuterKind::Anderson),
        ("ipm-fixed-point", InnerKind::Ipm, OuterKind::FixedPoint),
    ]
}

fn bench(c: &mut Criterion) {
    let dir = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/fclib"
    ));
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut paths: Vec<_> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "hdf5"))
        .collect();
    paths.sort();
    for path in paths {
        let Ok(file) = read(&path) else {
            continue;
        };
        let stem = path
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let mut group = c.benchmark_group(stem);
        group.sample_size(10);
        group.measurement_time(Duration::from_secs(5));
        for (name, inner, outer) in combos() {
            let settings = Settings {
                tol: 1e-8,
                time_limit: Some(Duration::from_secs(5)),
                ..Settings::method(inner, outer)
            };
            // only time the combinations that reach 1e-8
            match solve(&file.problem, &settings) {
                Ok(sol) if sol.converged() => {}
                _ => continue,
            }
            group.bench_function(name, |b| b.iter(|| solve(&file.problem, &settings)));
        }
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
