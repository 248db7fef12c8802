//! Every problem of ../shared/fclib with the default settings: converged at 1e-8, except the
//! files listed in `KNOWN_FAILURES` (which must then not claim convergence).

use coulomb::fclib::{read_with, ReadOptions, Symmetry};
use coulomb::solver::{solve, Settings, Status};
use std::path::Path;
use std::time::Duration;

/// Files the default settings do not bring to 1e-8 yet, with the reason.
const KNOWN_FAILURES: &[(&str, &str)] = &[
    // Gauss–Seidel stalls near 1e-6 (W singular: 768 unknowns, 588 dofs)
    ("spheres-in-a-box-98-i10000-256-10", "slow"),
    // error ≤ 1e-8, but M is asymmetric by 39 (eigmin 32): the balance residual is 0.16
    ("CubeH8", "balance"),
    ("LMGC_GlobalFrictionContactProblem00046", "balance"),
];

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
    for path in paths {
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        let file = read_with(
            &path,
            &ReadOptions {
                symmetry: Symmetry::Symmetrize,
            },
        )
        .unwrap();
        let known = KNOWN_FAILURES.iter().find(|(n, _)| *n == stem);
        let settings = Settings {
            time_limit: Some(Duration::from_secs(if known.is_some() { 2 } else { 60 })),
            ..Settings::default()
        };
        let sol = solve(&file.problem, &settings).unwrap();
        println!(
            "{stem:45} {:?} err={:.2e} outer={} inner={} t={:?}",
            sol.status, sol.error, sol.outer_iterations, sol.inner_iterations, sol.solve_time
        );
        match known {
            None => {
                assert_eq!(sol.status, Status::Converged, "{stem}");
                assert!(sol.error <= 1e-8, "{stem}");
            }
            Some((_, "balance")) => {
                assert_eq!(sol.status, Status::BalanceResidual, "{stem}");
                assert!(sol.balance_residual.unwrap() > 1e-8);
            }
            Some(_) => assert_ne!(sol.status, Status::Converged, "{stem}"),
        }
    }
}
