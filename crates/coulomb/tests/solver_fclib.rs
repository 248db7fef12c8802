//! Every problem of ../shared/fclib with the default settings reaches error ≤ 1e-8, checked
//! independently: the solution is written as the file's /solution group, read back, and its
//! error recomputed by `fclib::evaluate` from r (and v) alone.

use coulomb::fclib::{self, read_with, FclibFile, ReadOptions, StoredSolution, Symmetry};
use coulomb::solver::{solve, Settings, Status};
use std::path::Path;

#[test]
fn every_fclib_problem_converges_with_default_settings() {
    let dir = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/fclib"
    ));
    if !dir.is_dir() {
        println!("skipped: ../shared absent");
        return;
    }
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "hdf5"))
        .collect();
    paths.sort();
    assert!(!paths.is_empty());
    let out_dir = std::env::temp_dir().join(format!("coulomb-solver-fclib-{}", std::process::id()));
    std::fs::create_dir_all(&out_dir).unwrap();
    for path in paths {
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        let file = read_with(
            &path,
            &ReadOptions {
                symmetry: Symmetry::Symmetrize,
            },
        )
        .unwrap();
        let sol = solve(&file.problem, &Settings::default()).unwrap();
        println!(
            "{stem:45} {:?} err={:.2e} outer={} inner={} t={:?}",
            sol.status, sol.error, sol.outer_iterations, sol.inner_iterations, sol.solve_time
        );
        assert_eq!(sol.status, Status::Converged, "{stem}");
        // write /solution, read it back, evaluate it from scratch
        let written = out_dir.join(format!("{stem}.hdf5"));
        let mut with_solution = FclibFile::new(file.problem.clone());
        with_solution.solution = Some(StoredSolution {
            v: sol.v.clone(),
            u: Some(sol.u.clone()),
            r: sol.r.clone(),
            l: None,
        });
        fclib::write(&written, &with_solution).unwrap();
        let back = fclib::read(&written).unwrap();
        let stored = back.solution.expect("the /solution group was written");
        let eval = fclib::evaluate(&back.problem, &stored).unwrap();
        assert!(
            eval.converged(1e-8),
            "{stem}: written solution has error {:.3e}, balance {:?}",
            eval.measure.error,
            eval.balance_residual
        );
    }
    let _ = std::fs::remove_dir_all(&out_dir);
}
