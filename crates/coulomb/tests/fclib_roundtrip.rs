//! write → read round trips in every storage and index width, and h5py reading what
//! coulomb writes.

use crate::common;

use coulomb::fclib::{self, FclibFile, IndexWidth, Info, Storage, StoredSolution, WriteOptions};
use coulomb::{CscMatrix, GlobalProblem, LocalProblem, Problem};
use std::path::PathBuf;
use std::process::Command;

/// Deterministic pseudo-random numbers in [-1, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
    fn vec(&mut self, n: usize) -> Vec<f64> {
        (0..n).map(|_| self.next()).collect()
    }
}

/// A sparse SPD matrix B Bᵀ + I with B having about a third of its entries non-zero.
fn spd(n: usize, rng: &mut Lcg) -> CscMatrix {
    let b: Vec<f64> = (0..n * n)
        .map(|_| {
            let x = rng.next();
            if x.abs() < 0.4 {
                x
            } else {
                0.0
            }
        })
        .collect();
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let s: f64 = (0..n).map(|k| b[i * n + k] * b[j * n + k]).sum();
            a[i * n + j] = s + if i == j { 1.0 } else { 0.0 };
        }
    }
    CscMatrix::from_dense(n, n, &a)
}

fn sparse(nr: usize, nc: usize, rng: &mut Lcg) -> CscMatrix {
    let d: Vec<f64> = (0..nr * nc)
        .map(|_| {
            let x = rng.next();
            if x.abs() < 0.5 {
                x
            } else {
                0.0
            }
        })
        .collect();
    CscMatrix::from_dense(nr, nc, &d)
}

fn local_file(seed: u64) -> FclibFile {
    let mut rng = Lcg(seed);
    let (d, nc) = (3, 4);
    let m = d * nc;
    let p = LocalProblem::new(
        d as i64,
        spd(m, &mut rng),
        rng.vec(m),
        (0..nc).map(|i| 0.1 + 0.2 * i as f64).collect(),
    )
    .unwrap();
    FclibFile {
        problem: Problem::Local(p),
        info: Some(Info {
            title: "round trip — local".into(),
            description: "two lines\nof text".into(),
            math_info: String::new(),
        }),
        solution: Some(StoredSolution {
            v: None,
            u: Some(rng.vec(m)),
            r: rng.vec(m),
            l: None,
        }),
        guesses: vec![
            StoredSolution {
                v: None,
                u: Some(rng.vec(m)),
                r: rng.vec(m),
                l: None,
            },
            StoredSolution {
                v: None,
                u: None,
                r: rng.vec(m),
                l: Some(rng.vec(2)),
            },
        ],
    }
}

fn global_file(seed: u64) -> FclibFile {
    let mut rng = Lcg(seed);
    let (d, nc, n) = (2, 3, 7);
    let m = d * nc;
    let p = GlobalProblem::new(
        d as i64,
        spd(n, &mut rng),
        sparse(n, m, &mut rng),
        rng.vec(n),
        rng.vec(m),
        vec![0.0, 0.5, 1.5],
    )
    .unwrap();
    FclibFile {
        problem: Problem::Global(p),
        info: None,
        solution: Some(StoredSolution {
            v: Some(rng.vec(n)),
            u: Some(rng.vec(m)),
            r: rng.vec(m),
            l: None,
        }),
        guesses: vec![StoredSolution {
            v: Some(rng.vec(n)),
            u: Some(rng.vec(m)),
            r: rng.vec(m),
            l: None,
        }],
    }
}

const STORAGES: [Storage; 3] = [Storage::Csc, Storage::Csr, Storage::Triplet];
const WIDTHS: [IndexWidth; 2] = [IndexWidth::Int32, IndexWidth::Int64];

#[test]
fn fclib_roundtrip_all_storages_and_widths() {
    for (k, file) in [local_file(1), global_file(2)].iter().enumerate() {
        for storage in STORAGES {
            for index in WIDTHS {
                let opts = WriteOptions { storage, index };
                let bytes = fclib::to_bytes(file, &opts).unwrap();
                let back = fclib::read_bytes("mem.hdf5", bytes)
                    .unwrap_or_else(|e| panic!("{k} {opts:?}: {e}"));
                assert_eq!(&back, file, "{k} {opts:?}");
            }
        }
    }
}

#[test]
fn fclib_roundtrip_through_disk_and_zero_contacts() {
    let dir = tempdir("disk");
    let path = dir.join("local.hdf5");
    let file = local_file(7);
    fclib::write(&path, &file).unwrap();
    assert_eq!(fclib::read(&path).unwrap(), file);
    let sol = fclib::read_solution(&path).unwrap().unwrap();
    assert_eq!(Some(sol), file.solution);

    let empty = FclibFile::new(Problem::Local(
        LocalProblem::new(3, CscMatrix::zeros(0, 0), vec![], vec![]).unwrap(),
    ));
    let path = dir.join("empty.hdf5");
    fclib::write(&path, &empty).unwrap();
    assert_eq!(fclib::read(&path).unwrap(), empty);
    assert_eq!(fclib::read_solution(&path).unwrap(), None);
}

#[test]
fn fclib_write_refuses_int32_overflow_by_name() {
    // A matrix with more columns than int32 can index cannot be written as int32: here the
    // column count itself (an int32[1] header) is the first thing that does not fit.
    let huge = CscMatrix {
        nrows: 1,
        ncols: 1,
        col_ptr: vec![0, 1],
        row_idx: vec![0],
        values: vec![1.0],
    };
    let mut f = FclibFile::new(Problem::Local(LocalProblem {
        dim: 3,
        w: huge,
        q: vec![],
        mu: vec![],
    }));
    if let Problem::Local(p) = &mut f.problem {
        p.w.ncols = (i32::MAX as usize) + 1;
    }
    let err = fclib::to_bytes(&f, &WriteOptions::default()).unwrap_err();
    assert!(err.to_string().contains("/fclib_local/W/n"), "{err}");
}

fn tempdir(tag: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("coulomb-fclib-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

use common::h5py_available;

/// h5py dumps every dataset as {path: [dtype, shape, values]}.
const DUMP: &str = r#"
import h5py, json, sys
out = {}
def visit(name, obj):
    if isinstance(obj, h5py.Dataset):
        v = obj[()]
        if obj.dtype.kind == 'S':
            out[name] = [obj.dtype.str, list(obj.shape), v.decode('utf-8')]
        else:
            out[name] = [obj.dtype.name, list(obj.shape), v.tolist()]
h5py.File(sys.argv[1], 'r').visititems(visit)
print(json.dumps(out))
"#;

#[test]
fn fclib_h5py_reads_what_coulomb_writes() {
    if !h5py_available() {
        println!("skipped: python3 with h5py not available");
        return;
    }
    let dir = tempdir("h5py");
    for (k, file) in [local_file(3), global_file(4)].iter().enumerate() {
        let path = dir.join(format!("f{k}.hdf5"));
        fclib::write(&path, file).unwrap();
        let out = Command::new("python3")
            .args(["-c", DUMP])
            .arg(&path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let dump: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let get = |p: &str| -> &serde_json::Value {
            dump.get(p).unwrap_or_else(|| panic!("h5py lacks {p}"))
        };
        let floats = |p: &str| -> Vec<f64> {
            let e = get(p);
            assert_eq!(e[0], "float64", "{p}");
            e[2].as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        };
        let ints = |p: &str| -> Vec<i64> {
            let e = get(p);
            assert_eq!(e[0], "int32", "{p}: Siconos-compatible int32");
            e[2].as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_i64().unwrap())
                .collect()
        };
        let check_matrix = |g: &str, a: &CscMatrix| {
            assert_eq!(ints(&format!("{g}/m")), vec![a.nrows as i64]);
            assert_eq!(ints(&format!("{g}/n")), vec![a.ncols as i64]);
            assert_eq!(ints(&format!("{g}/nz")), vec![-1]);
            assert_eq!(ints(&format!("{g}/nzmax")), vec![a.nnz() as i64]);
            let p: Vec<i64> = a.col_ptr.iter().map(|&x| x as i64).collect();
            let i: Vec<i64> = a.row_idx.iter().map(|&x| x as i64).collect();
            assert_eq!(ints(&format!("{g}/p")), p);
            assert_eq!(ints(&format!("{g}/i")), i);
            assert_eq!(floats(&format!("{g}/x")), a.values);
        };
        match &file.problem {
            Problem::Local(p) => {
                check_matrix("fclib_local/W", &p.w);
                assert_eq!(floats("fclib_local/vectors/q"), p.q);
                assert_eq!(floats("fclib_local/vectors/mu"), p.mu);
                assert_eq!(ints("fclib_local/spacedim"), vec![p.dim as i64]);
                let info = file.info.as_ref().unwrap();
                assert_eq!(get("fclib_local/info/title")[2], info.title.as_str());
                assert_eq!(
                    get("fclib_local/info/description")[2],
                    info.description.as_str()
                );
                assert_eq!(get("fclib_local/info/title")[1], serde_json::json!([]));
            }
            Problem::Global(p) => {
                check_matrix("fclib_global/M", &p.m);
                check_matrix("fclib_global/H", &p.h);
                assert_eq!(floats("fclib_global/vectors/f"), p.f);
                assert_eq!(floats("fclib_global/vectors/w"), p.w);
                assert_eq!(floats("fclib_global/vectors/mu"), p.mu);
                assert_eq!(ints("fclib_global/spacedim"), vec![p.dim as i64]);
                assert_eq!(
                    floats("solution/v"),
                    *file.solution.as_ref().unwrap().v.as_ref().unwrap()
                );
            }
        }
        let sol = file.solution.as_ref().unwrap();
        assert_eq!(floats("solution/r"), sol.r);
        assert_eq!(floats("solution/u"), *sol.u.as_ref().unwrap());
        assert_eq!(
            ints("guesses/number_of_guesses"),
            vec![file.guesses.len() as i64]
        );
        for (g, s) in file.guesses.iter().enumerate() {
            assert_eq!(floats(&format!("guesses/{}/r", g + 1)), s.r);
        }
    }
}

/// A global problem with equality constraints (G n × 3 with a repeated column: redundant rows
/// are valid data), a solution with multipliers l and a guess without.
fn equality_file(seed: u64) -> FclibFile {
    let FclibFile {
        problem: Problem::Global(p),
        ..
    } = global_file(seed)
    else {
        unreachable!()
    };
    let mut rng = Lcg(seed + 100);
    let n = p.m.nrows;
    let mut gd = sparse(n, 3, &mut rng).to_dense();
    for i in 0..n {
        gd[i * 3 + 2] = gd[i * 3];
    }
    let g = CscMatrix::from_dense(n, 3, &gd);
    let p = p.with_equality(g, rng.vec(3)).unwrap();
    let m = p.h.ncols;
    FclibFile {
        problem: Problem::Global(p),
        info: None,
        solution: Some(StoredSolution {
            v: Some(rng.vec(n)),
            u: Some(rng.vec(m)),
            r: rng.vec(m),
            l: Some(rng.vec(3)),
        }),
        guesses: vec![StoredSolution {
            v: Some(rng.vec(n)),
            u: None,
            r: rng.vec(m),
            l: None,
        }],
    }
}

#[test]
fn fclib_roundtrip_equality_constraints() {
    let file = equality_file(5);
    for storage in STORAGES {
        for index in WIDTHS {
            let opts = WriteOptions { storage, index };
            let bytes = fclib::to_bytes(&file, &opts).unwrap();
            let back =
                fclib::read_bytes("mem.hdf5", bytes).unwrap_or_else(|e| panic!("{opts:?}: {e}"));
            assert_eq!(back, file, "{opts:?}");
            let Problem::Global(p) = &back.problem else {
                panic!()
            };
            assert_eq!(p.equality_rows(), 3);
        }
    }
    // through disk, and h5py sees G, b and l under FCLIB's names
    let dir = tempdir("equality");
    let path = dir.join("eq.hdf5");
    fclib::write(&path, &file).unwrap();
    assert_eq!(fclib::read(&path).unwrap(), file);
    assert_eq!(fclib::read_solution(&path).unwrap(), file.solution);
    if !h5py_available() {
        println!("h5py part skipped: python3 with h5py not available");
        return;
    }
    let out = Command::new("python3")
        .args(["-c", DUMP])
        .arg(&path)
        .output()
        .unwrap();
    assert!(out.status.success());
    let dump: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let Problem::Global(p) = &file.problem else {
        panic!()
    };
    let e = p.equality.as_ref().unwrap();
    let floats = |k: &str| -> Vec<f64> {
        dump[k][2]
            .as_array()
            .unwrap_or_else(|| panic!("h5py lacks {k}"))
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    assert_eq!(floats("fclib_global/vectors/b"), e.b);
    assert_eq!(floats("fclib_global/G/x"), e.g.values);
    assert_eq!(dump["fclib_global/G/m"][2], serde_json::json!([p.m.nrows]));
    assert_eq!(dump["fclib_global/G/n"][2], serde_json::json!([3]));
    assert_eq!(
        floats("solution/l"),
        *file.solution.as_ref().unwrap().l.as_ref().unwrap()
    );
}

#[test]
fn fclib_equality_inconsistent_datasets_are_refused() {
    let file = equality_file(6);
    let bytes = fclib::to_bytes(&file, &WriteOptions::default()).unwrap();
    assert!(fclib::read_bytes("ok.hdf5", bytes).is_ok());
    // l of the wrong length
    let mut bad = file.clone();
    bad.solution.as_mut().unwrap().l = Some(vec![0.0; 2]);
    let bytes = fclib::to_bytes(&bad, &WriteOptions::default()).unwrap();
    let err = fclib::read_bytes("bad.hdf5", bytes).unwrap_err();
    assert_eq!(err.object_path(), Some("/solution/l"), "{err}");
    // a non-finite b: the problem's validation names it
    let mut bad = file.clone();
    if let Problem::Global(p) = &mut bad.problem {
        p.equality.as_mut().unwrap().b[1] = f64::NAN;
    }
    let bytes = fclib::to_bytes(&bad, &WriteOptions::default()).unwrap();
    let err = fclib::read_bytes("bad.hdf5", bytes).unwrap_err();
    assert!(err.to_string().contains("non-finite entry in b"), "{err}");
}
