//! The files of data/ are read as data/README.md describes them; every real FCLIB file in
//! ../shared/fclib (when present) is read and matches what h5py shows.

use crate::common;

use coulomb::fclib::{self, FclibFile};
use coulomb::Problem;
use std::path::Path;
use std::process::Command;

use common::{fclib_dir, h5py_available};

/// (file, kind, d, contacts, dofs, has solution, guesses), as h5py lists them
/// (`len(vectors/mu)`, `M/m`, `number_of_guesses`).
type Row = (
    &'static str,
    &'static str,
    usize,
    usize,
    Option<usize>,
    bool,
    usize,
);
const EXPECTED: &[Row] = &[
    ("Box_Stacks-i0122-82-5", "global", 3, 82, Some(450), true, 1),
    ("BoxesStack1-i100000-32", "local", 3, 52, None, false, 0),
    ("Capsules-i101-404", "local", 3, 225, None, false, 0),
    ("Capsules-i125-1213", "local", 3, 286, None, true, 1),
    (
        "Confeti-ex13-4contact-Fc3D-SBM",
        "local",
        3,
        4,
        None,
        false,
        0,
    ),
    ("CubeH8", "global", 3, 1, Some(162), false, 0),
    ("FC3D_Example1", "local", 3, 3, None, false, 0),
    ("FrictionContact3D_1c", "local", 3, 1, None, false, 0),
    (
        "LMGC_100_PR_PerioBox-i00361-60-03000",
        "local",
        3,
        60,
        None,
        false,
        0,
    ),
    (
        "LMGC_GlobalFrictionContactProblem00046",
        "global",
        3,
        9,
        Some(162),
        false,
        0,
    ),
    ("NESpheres_10_1", "local", 3, 9, None, false, 0),
    ("OneObject-i1028-138", "local", 3, 23, None, false, 0),
    ("Rover1039", "local", 3, 4, None, false, 0),
    ("Rover4396", "local", 3, 2, None, false, 0),
    (
        "spheres-in-a-box-98-i10000-256-10",
        "global",
        3,
        256,
        Some(588),
        true,
        1,
    ),
];

/// Reads a file as stored (five real W are not symmetric within 1e-6: see
/// `fclib_non_symmetric_w_is_read_as_stored`).
fn read(dir: &Path, name: &str) -> FclibFile {
    let path = dir.join(format!("{name}.hdf5"));
    match fclib::read(&path) {
        Ok(f) => f,
        Err(e) => panic!("{e}"),
    }
}

/// data/'s files: kind, d, contacts, dofs and the asymmetry of W as data/README.md lists them.
#[test]
fn fclib_data_files_are_as_documented() {
    let dir = common::data_dir();
    let rows = [
        ("box-local", "local", 3, 147, None, false),
        ("box-global", "global", 3, 147, Some(720), false),
        ("pile-nonsym-local", "local", 3, 64, None, true),
        ("painleve", "global", 2, 1, Some(1), false),
    ];
    assert_eq!(
        common::data_files().len(),
        rows.len(),
        "data/README.md lists every file"
    );
    for (name, kind, dim, contacts, dofs, asymmetric) in rows {
        let f = read(&dir, name);
        let p = &f.problem;
        assert_eq!(
            (p.kind(), p.dim(), p.contacts(), p.dofs()),
            (kind, dim, contacts, dofs),
            "{name}"
        );
        // pile-nonsym-local: relative asymmetry 1e-5 by construction (coulomb corpus)
        if asymmetric {
            assert!(
                (p.asymmetry() / 1e-5 - 1.0).abs() < 1e-3,
                "{name}: {}",
                p.asymmetry()
            );
        } else {
            assert_eq!(p.asymmetry(), 0.0, "{name}");
        }
        assert!(f.solution.is_none(), "{name}: data/ stores problems only");
    }
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_fclib_every_shared_file_is_read() {
    let dir = fclib_dir();
    let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "hdf5").then(|| p.file_stem().unwrap().to_string_lossy().into())
        })
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = EXPECTED.iter().map(|e| e.0.to_string()).collect();
    listed.sort();
    assert_eq!(on_disk, listed, "the table must list every file");

    for &(name, kind, d, nc, dofs, has_sol, guesses) in EXPECTED {
        let f = read(&dir, name);
        let p = &f.problem;
        assert_eq!(p.kind(), kind, "{name}");
        assert_eq!(p.dim(), d, "{name}");
        assert_eq!(p.contacts(), nc, "{name}");
        assert_eq!(p.dofs(), dofs, "{name}");
        assert_eq!(f.solution.is_some(), has_sol, "{name}");
        assert_eq!(f.guesses.len(), guesses, "{name}");
        assert!(f.info.is_some(), "{name}: every shared file has /info");
        if let Some(s) = &f.solution {
            assert_eq!(s.r.len(), d * nc, "{name}");
            assert_eq!(s.v.is_some(), kind == "global", "{name}");
        }
    }
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_fclib_storage_details_of_real_files() {
    let dir = fclib_dir();
    // CSR W (nz = -2), LMGC90.
    let f = read(&dir, "LMGC_100_PR_PerioBox-i00361-60-03000");
    let Problem::Local(p) = &f.problem else {
        panic!("local expected")
    };
    assert_eq!((p.w.nrows, p.w.ncols), (180, 180));
    let mu_min = p.mu.iter().cloned().fold(f64::INFINITY, f64::min);
    let mu_max = p.mu.iter().cloned().fold(0.0, f64::max);
    assert!((0.3..=0.5).contains(&mu_min) && (0.3..=0.5).contains(&mu_max));
    assert_eq!(
        f.info.as_ref().unwrap().title,
        "LMGC dump in hdf5",
        "fixed-length string read"
    );
    // Triplet M and H, nzmax (1968) larger than nz (1284).
    let f = read(&dir, "Box_Stacks-i0122-82-5");
    let Problem::Global(g) = &f.problem else {
        panic!("global expected")
    };
    assert_eq!((g.h.nrows, g.h.ncols), (450, 246));
    assert_eq!(g.h.nnz(), 1284);
    assert_eq!(g.m.nnz(), 450);
    // Unallocated dataset (/solution/r never written): HDF5 fill value, zero.
    let s = f.solution.as_ref().unwrap();
    assert!(s.r.iter().all(|&x| x == 0.0));
    assert!(s.u.as_ref().unwrap().iter().any(|&x| x != 0.0));
    // Non-UTF-8 byte in a string: replaced, not an error.
    let f = read(&dir, "CubeH8");
    assert!(f
        .info
        .unwrap()
        .description
        .contains("Rewriting in hdf5 through siconos"));
}

/// Asks h5py for (kind, d, contacts, dofs, nnz stored, solution, guesses) of every file.
fn h5py_summary(dir: &Path) -> Option<String> {
    let script = r#"
import h5py, sys, glob, os
for fn in sorted(glob.glob(os.path.join(sys.argv[1], '*.hdf5'))):
    h = h5py.File(fn, 'r')
    kind = 'local' if 'fclib_local' in h else 'global'
    g = h['fclib_' + kind]
    d = int(g['spacedim'][0])
    nc = len(g['vectors/mu'])
    dofs = int(g['M/m'][0]) if kind == 'global' else -1
    sol = 'solution' in h
    ng = int(h['guesses/number_of_guesses'][0]) if 'guesses' in h else 0
    print(os.path.basename(fn)[:-5], kind, d, nc, dofs, int(sol), ng)
"#;
    let out = Command::new("python3")
        .arg("-c")
        .arg(script)
        .arg(dir)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_fclib_matches_live_h5py() {
    let dir = fclib_dir();
    if !h5py_available() {
        println!("skipped: python3 with h5py not available");
        return;
    }
    let summary = h5py_summary(&dir).expect("h5py script runs");
    let mut lines = 0;
    for line in summary.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(w.len(), 7, "{line}");
        let f = read(&dir, w[0]);
        let p = &f.problem;
        assert_eq!(p.kind(), w[1], "{line}");
        assert_eq!(p.dim().to_string(), w[2], "{line}");
        assert_eq!(p.contacts().to_string(), w[3], "{line}");
        let dofs = p.dofs().map_or(-1, |n| n as i64);
        assert_eq!(dofs.to_string(), w[4], "{line}");
        assert_eq!((f.solution.is_some() as i32).to_string(), w[5], "{line}");
        assert_eq!(f.guesses.len().to_string(), w[6], "{line}");
        lines += 1;
    }
    assert_eq!(lines, EXPECTED.len());
}

/// Relative asymmetry max|W − Wᵀ| / max|W| of the W that fail the 1e-6 tolerance, as
/// numpy computes it from the raw arrays.
const ASYMMETRIC: &[(&str, f64)] = &[
    ("Capsules-i101-404", 5.973e-4),
    ("Capsules-i125-1213", 1.337e-3),
    ("OneObject-i1028-138", 1.154e-4),
    ("Rover1039", 9.157e-6),
    ("Rover4396", 2.562e-5),
];

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_fclib_non_symmetric_w_is_read_as_stored() {
    let dir = fclib_dir();
    for &(name, ..) in EXPECTED {
        let f = read(&dir, name);
        let asym = f.problem.asymmetry();
        match ASYMMETRIC.iter().find(|a| a.0 == name) {
            Some(&(_, expected)) => {
                // the matrix is the stored one, with its asymmetry, not ½(W + Wᵀ)
                assert!((asym / expected - 1.0).abs() < 1e-3, "{name}: {asym}");
                let Problem::Local(p) = &f.problem else {
                    panic!("{name} is local")
                };
                assert!(!p.is_symmetric());
            }
            None => assert!(asym <= 1e-6, "{name}: {asym}"),
        }
    }
}

/// The stored solutions of docs/fclib.md, evaluated with the error of docs/error.md.
#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_fclib_stored_solutions_evaluate_as_documented() {
    let dir = fclib_dir();
    let f = read(&dir, "Capsules-i125-1213");
    let e = fclib::evaluate(&f.problem, f.solution.as_ref().unwrap()).unwrap();
    println!("Capsules-i125-1213 solution: {e:?}");
    assert!((e.measure.error / 1.58e-2 - 1.0).abs() < 0.01, "{e:?}");
    assert!(e.balance_residual.is_none());
    assert!(!e.converged(1e-8));
    let g = fclib::evaluate(&f.problem, &f.guesses[0]).unwrap();
    println!("Capsules-i125-1213 guess 1: {g:?}");
    assert!((g.measure.error / 1.1e-2 - 1.0).abs() < 0.05, "{g:?}");

    let f = read(&dir, "Box_Stacks-i0122-82-5");
    let e = fclib::evaluate(&f.problem, f.solution.as_ref().unwrap()).unwrap();
    println!("Box_Stacks-i0122-82-5 solution: {e:?}");
    assert_eq!(e.measure.error, 0.0);
    let b = e.balance_residual.unwrap();
    assert!((b / 3.97e-2 - 1.0).abs() < 0.01, "{b}");
    assert!(!e.converged(1e-8));
}
