//! Malformed FCLIB files: each gives an `FclibError` naming the file and the object, and
//! nothing panics. Files are made with a low-level HDF5 writer (hdf5-pure, coulomb's own
//! HDF5 dependency) from a valid layout with one thing changed, or by byte edits.

use crate::common;

use coulomb::fclib::{self, FclibError, FclibErrorKind, FclibFile, WriteOptions};
use coulomb::{CscMatrix, LocalProblem, Problem};
use hdf5_pure::{FileBuilder, GroupBuilder};
use std::collections::BTreeMap;

#[derive(Clone, Debug)]
enum Data {
    F64(Vec<f64>),
    I32(Vec<i32>),
    I64(Vec<i64>),
    Str(&'static str),
}

type Layout = BTreeMap<String, Data>;

/// A valid local problem (d = 3, two contacts, W = 2 I stored CSC with nzmax padding).
fn valid_local() -> Layout {
    let mut l = Layout::new();
    let put = |l: &mut Layout, p: &str, d: Data| {
        l.insert(p.to_string(), d);
    };
    put(&mut l, "fclib_local/W/m", Data::I32(vec![6]));
    put(&mut l, "fclib_local/W/n", Data::I32(vec![6]));
    put(&mut l, "fclib_local/W/nz", Data::I32(vec![-1]));
    put(&mut l, "fclib_local/W/nzmax", Data::I32(vec![8]));
    put(
        &mut l,
        "fclib_local/W/p",
        Data::I32(vec![0, 1, 2, 3, 4, 5, 6]),
    );
    put(
        &mut l,
        "fclib_local/W/i",
        Data::I32(vec![0, 1, 2, 3, 4, 5, 99, -7]),
    );
    put(&mut l, "fclib_local/W/x", Data::F64(vec![2.0; 8]));
    put(
        &mut l,
        "fclib_local/vectors/q",
        Data::F64(vec![-1.0, 0.0, 0.0, 1.0, 0.0, 0.0]),
    );
    put(&mut l, "fclib_local/vectors/mu", Data::F64(vec![0.3, 0.5]));
    put(&mut l, "fclib_local/spacedim", Data::I32(vec![3]));
    put(&mut l, "fclib_local/info/title", Data::Str("test"));
    put(&mut l, "solution/r", Data::F64(vec![0.0; 6]));
    put(&mut l, "guesses/number_of_guesses", Data::I32(vec![1]));
    put(&mut l, "guesses/1/r", Data::F64(vec![0.0; 6]));
    l
}

/// Builds the HDF5 image of a layout (every path at least one group deep).
fn build(layout: &Layout) -> Vec<u8> {
    #[derive(Default)]
    struct Node {
        children: BTreeMap<String, Node>,
        data: Option<Data>,
    }
    let mut root = Node::default();
    for (path, d) in layout {
        let mut node = &mut root;
        for part in path.split('/') {
            node = node.children.entry(part.to_string()).or_default();
        }
        node.data = Some(d.clone());
    }
    fn fill(g: &mut GroupBuilder, node: &Node) {
        for (name, child) in &node.children {
            match &child.data {
                Some(Data::F64(v)) => {
                    g.create_dataset(name).with_f64_data(v);
                }
                Some(Data::I32(v)) => {
                    g.create_dataset(name).with_i32_data(v);
                }
                Some(Data::I64(v)) => {
                    g.create_dataset(name).with_i64_data(v);
                }
                Some(Data::Str(s)) => {
                    g.create_dataset(name)
                        .with_ascii_strings(&[s])
                        .unwrap()
                        .with_shape(&[]);
                }
                None => {
                    let mut sub = g.create_group(name);
                    fill(&mut sub, child);
                    g.add_group(sub.finish());
                }
            }
        }
    }
    let mut b = FileBuilder::new();
    for (name, child) in &root.children {
        assert!(child.data.is_none(), "root datasets are not used");
        let mut g = b.create_group(name);
        fill(&mut g, child);
        b.add_group(g.finish());
    }
    b.finish().unwrap()
}

fn read(layout: &Layout) -> Result<FclibFile, FclibError> {
    fclib::read_bytes("bad.hdf5", build(layout))
}

/// Reads a modified layout and checks the error names the file and `path`, and that its
/// message contains `needle`.
fn expect_err(layout: &Layout, path: &str, needle: &str) -> FclibErrorKind {
    let err = read(layout).expect_err(path);
    let msg = err.to_string();
    assert!(msg.starts_with("bad.hdf5: "), "{msg}");
    assert_eq!(err.object_path(), Some(path), "{msg}");
    assert!(msg.contains(path) && msg.contains(needle), "{msg}");
    err.kind
}

#[test]
fn fclib_corrupt_valid_layout_reads() {
    let f = read(&valid_local()).unwrap();
    let Problem::Local(p) = &f.problem else {
        panic!()
    };
    assert_eq!(
        p.w,
        CscMatrix::identity(6, 2.0),
        "only the first p[n] entries used"
    );
    assert_eq!(f.guesses.len(), 1);
    // int64 indices are read too.
    let mut l = valid_local();
    l.insert("fclib_local/W/i".into(), Data::I64(vec![0, 1, 2, 3, 4, 5]));
    l.insert(
        "fclib_local/W/p".into(),
        Data::I64(vec![0, 1, 2, 3, 4, 5, 6]),
    );
    assert_eq!(read(&l).unwrap().problem, f.problem);
}

#[test]
fn fclib_corrupt_not_hdf5_and_truncated() {
    let err =
        fclib::read_bytes("text.hdf5", b"this is not an HDF5 file at all".to_vec()).unwrap_err();
    assert!(matches!(err.kind, FclibErrorKind::NotHdf5), "{err}");
    assert!(err.to_string().starts_with("text.hdf5: not an HDF5 file"));
    let err = fclib::read_bytes("empty.hdf5", Vec::new()).unwrap_err();
    assert!(matches!(err.kind, FclibErrorKind::NotHdf5), "{err}");

    let bytes = build(&valid_local());
    let mut kinds = BTreeMap::new();
    for cut in (0..bytes.len()).step_by(7) {
        let err = fclib::read_bytes("cut.hdf5", bytes[..cut].to_vec())
            .expect_err("a truncated file is never valid");
        assert!(err.to_string().starts_with("cut.hdf5: "));
        let name = format!("{:?}", err.kind);
        *kinds
            .entry(name.split([' ', '(', '{']).next().unwrap().to_string())
            .or_insert(0) += 1;
    }
    println!("truncation error kinds: {kinds:?}");
    assert!(kinds.contains_key("Corrupt") || kinds.contains_key("MissingGroup"));

    // A missing file is an input error (coulomb::input) naming it, the OS's reason once.
    let err = fclib::read(std::path::Path::new("/nonexistent/x.hdf5")).unwrap_err();
    assert!(matches!(
        &err.kind,
        FclibErrorKind::Input(coulomb::input::InputReason::Open(e)) if e.kind() == std::io::ErrorKind::NotFound
    ));
    assert_eq!(err.to_string().matches("os error 2").count(), 1, "{err}");
    assert!(err.to_string().contains("/nonexistent/x.hdf5"));
}

#[test]
fn fclib_corrupt_wrong_group() {
    let mut l = Layout::new();
    l.insert("something_else/x".into(), Data::F64(vec![1.0]));
    let err = read(&l).unwrap_err();
    assert!(
        matches!(err.kind, FclibErrorKind::MissingGroup { .. }),
        "{err}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("/fclib_local") && msg.contains("/fclib_global"),
        "{msg}"
    );

    let mut l = valid_local();
    l.retain(|k, _| !k.starts_with("fclib_local/W/"));
    l.insert("fclib_local/W".into(), Data::F64(vec![1.0]));
    expect_err(&l, "/fclib_local/W", "expected a group, found a dataset");
}

#[test]
fn fclib_corrupt_wrong_lengths() {
    let mut l = valid_local();
    l.insert("fclib_local/vectors/q".into(), Data::F64(vec![1.0; 4]));
    expect_err(
        &l,
        "/fclib_local/vectors/q",
        "expected 6 (m of /fclib_local/W) entries, found 4",
    );

    let mut l = valid_local();
    l.insert("fclib_local/vectors/mu".into(), Data::F64(vec![0.3]));
    expect_err(&l, "/fclib_local/vectors/mu", "found 1");

    let mut l = valid_local();
    l.insert("fclib_local/W/p".into(), Data::I32(vec![0, 1]));
    expect_err(&l, "/fclib_local/W/p", "expected 7 entries, found 2");

    let mut l = valid_local();
    l.insert("fclib_local/W/x".into(), Data::F64(vec![2.0; 3]));
    expect_err(&l, "/fclib_local/W/x", "at least 6 (p[n])");

    let mut l = valid_local();
    l.insert("solution/r".into(), Data::F64(vec![0.0; 5]));
    expect_err(&l, "/solution/r", "found 5");

    let mut l = valid_local();
    l.insert("fclib_local/spacedim".into(), Data::I32(vec![3, 3]));
    expect_err(&l, "/fclib_local/spacedim", "expected 1 entries, found 2");
}

#[test]
fn fclib_corrupt_wrong_types() {
    let mut l = valid_local();
    l.insert("fclib_local/vectors/q".into(), Data::Str("0 0 0 0 0 0"));
    expect_err(
        &l,
        "/fclib_local/vectors/q",
        "expected a float64 array, found a fixed-length string",
    );

    let mut l = valid_local();
    l.insert("fclib_local/W/p".into(), Data::F64(vec![0.0; 7]));
    expect_err(&l, "/fclib_local/W/p", "expected an integer array");

    let mut l = valid_local();
    l.insert("fclib_local/info/title".into(), Data::F64(vec![1.0]));
    expect_err(&l, "/fclib_local/info/title", "expected a string");

    let mut l = valid_local();
    l.remove("fclib_local/vectors/mu");
    l.insert("fclib_local/vectors/mu/x".into(), Data::F64(vec![0.3, 0.5]));
    expect_err(
        &l,
        "/fclib_local/vectors/mu",
        "expected a dataset, found a group",
    );
}

#[test]
fn fclib_corrupt_inconsistent_storage() {
    // p[n] larger than the index array.
    let mut l = valid_local();
    l.insert(
        "fclib_local/W/p".into(),
        Data::I32(vec![0, 1, 2, 3, 4, 5, 9]),
    );
    expect_err(&l, "/fclib_local/W/i", "at least 9 (p[n])");
    // Decreasing pointers.
    let mut l = valid_local();
    l.insert(
        "fclib_local/W/p".into(),
        Data::I32(vec![0, 2, 1, 3, 4, 5, 6]),
    );
    expect_err(&l, "/fclib_local/W/p", "pointer 2 = 1 is smaller");
    // Triplets: nz larger than the arrays.
    let mut l = valid_local();
    l.insert("fclib_local/W/nz".into(), Data::I32(vec![20]));
    expect_err(&l, "/fclib_local/W/i", "at least 20 (nz)");
    // Triplets: a column index out of range.
    let mut l = valid_local();
    l.insert("fclib_local/W/nz".into(), Data::I32(vec![6]));
    l.insert("fclib_local/W/p".into(), Data::I32(vec![0, 1, 2, 3, 4, 6]));
    expect_err(
        &l,
        "/fclib_local/W/p",
        "entry 5 = 6 is not a column index in 0..6",
    );
    // A negative row index among the used entries.
    let mut l = valid_local();
    l.insert("fclib_local/W/i".into(), Data::I32(vec![0, 1, -2, 3, 4, 5]));
    expect_err(&l, "/fclib_local/W/i", "entry 2 = -2");
    // nz code that means nothing.
    let mut l = valid_local();
    l.insert("fclib_local/W/nz".into(), Data::I32(vec![-3]));
    expect_err(&l, "/fclib_local/W/nz", "nz = -3");
    // W not square / m not a multiple of d / bad spacedim / negative size.
    let mut l = valid_local();
    l.insert("fclib_local/W/n".into(), Data::I32(vec![5]));
    expect_err(&l, "/fclib_local/W/n", "square");
    let mut l = valid_local();
    l.insert("fclib_local/spacedim".into(), Data::I32(vec![4]));
    expect_err(&l, "/fclib_local/spacedim", "spacedim = 4");
    let mut l = valid_local();
    l.insert("fclib_local/W/m".into(), Data::I32(vec![-6]));
    expect_err(&l, "/fclib_local/W/m", "-6 is not a valid size");
    // Guesses announced but absent.
    let mut l = valid_local();
    l.insert("guesses/number_of_guesses".into(), Data::I32(vec![2]));
    expect_err(&l, "/guesses/2", "missing group");
    // Missing dataset.
    let mut l = valid_local();
    l.remove("fclib_local/vectors/q");
    expect_err(&l, "/fclib_local/vectors/q", "missing dataset");
    // Constraints coulomb does not model.
    let mut l = valid_local();
    l.insert("fclib_local/V/m".into(), Data::I32(vec![0]));
    expect_err(&l, "/fclib_local/V", "not supported");
    // Readable but invalid: ½(W + Wᵀ) indefinite (W₀₀ = 0, W₁₀ = 2), NaN in q.
    let mut l = valid_local();
    l.insert("fclib_local/W/i".into(), Data::I32(vec![1, 1, 2, 3, 4, 5]));
    let kind = expect_err(&l, "/fclib_local", "not positive semidefinite");
    assert!(matches!(kind, FclibErrorKind::InvalidProblem { .. }));
    let mut l = valid_local();
    l.insert("fclib_local/vectors/q".into(), Data::F64(vec![f64::NAN; 6]));
    expect_err(&l, "/fclib_local", "non-finite entry in q");
}

/// Byte edits of a written file, of data/'s files and of the real files (when ../shared is there): every outcome is Ok or an
/// `FclibError`, never a panic (the test fails if one happens).
#[test]
fn fclib_corrupt_byte_edits_never_panic() {
    let mut files: Vec<Vec<u8>> = vec![build(&valid_local())];
    let p = LocalProblem::new(3, CscMatrix::identity(6, 1.0), vec![0.0; 6], vec![0.1; 2]).unwrap();
    files.push(
        fclib::to_bytes(&FclibFile::new(Problem::Local(p)), &WriteOptions::default()).unwrap(),
    );
    for path in common::data_files() {
        files.push(std::fs::read(path).unwrap());
    }
    let shared = common::shared_fclib();
    for name in ["Capsules-i125-1213", "Box_Stacks-i0122-82-5", "Rover4396"] {
        if let Ok(b) = std::fs::read(shared.join(format!("{name}.hdf5"))) {
            files.push(b);
        }
    }
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut rnd = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let (mut ok, mut err) = (0, 0);
    for bytes in &files {
        for _ in 0..400 {
            let mut b = bytes.clone();
            for _ in 0..1 + rnd() % 3 {
                let pos = (rnd() as usize) % b.len();
                b[pos] = rnd() as u8;
            }
            match fclib::read_bytes("fuzz.hdf5", b) {
                Ok(_) => ok += 1,
                Err(e) => {
                    assert!(e.to_string().starts_with("fuzz.hdf5: "));
                    err += 1
                }
            }
        }
        for k in 1..60 {
            let cut = bytes.len() * k / 60;
            let _ = fclib::read_bytes("fuzz.hdf5", bytes[..cut].to_vec());
        }
    }
    println!("byte edits: {ok} still valid, {err} errors");
    assert!(err > 0);
}

/// Replaces every little-endian u64 equal to `from` by `to`; returns how many.
fn patch_u64(bytes: &mut [u8], from: u64, to: u64) -> usize {
    let (pattern, repl) = (from.to_le_bytes(), to.to_le_bytes());
    let (mut hits, mut k) = (0, 0);
    while k + 8 <= bytes.len() {
        if bytes[k..k + 8] == pattern {
            bytes[k..k + 8].copy_from_slice(&repl);
            hits += 1;
            k += 8;
        } else {
            k += 1;
        }
    }
    hits
}

/// Dataspaces patched to declare 2⁵⁰ entries: refused as corrupt before anything is
/// allocated (honouring them would abort the process on allocation failure). The real
/// files have no metadata checksums (v1 object headers), so the patch reaches the reader;
/// in Box_Stacks the 246-entry vectors (w, solution r/u, guesses) are patched, among them
/// never-written datasets that HDF5 would fill with zeros of the declared size.
#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared")]
fn needs_shared_fclib_corrupt_huge_declared_size_is_refused() {
    let path = common::fclib_dir().join("Box_Stacks-i0122-82-5.hdf5");
    let mut bytes = std::fs::read(&path).unwrap();
    assert!(
        patch_u64(&mut bytes, 246, 1 << 50) > 0,
        "dataspace sizes found"
    );
    let err = fclib::read_bytes("huge.hdf5", bytes).unwrap_err();
    let msg = err.to_string();
    println!("{msg}");
    assert!(matches!(err.kind, FclibErrorKind::Corrupt { .. }), "{msg}");
    assert!(msg.contains("declares shape [1125899906842624]"), "{msg}");
}

/// A valid global problem with one equality row (d = 2, two dofs, one contact; M = I, H = I,
/// G = e₀, b = −1), all matrices stored CSC.
fn valid_equality() -> Layout {
    let mut l = Layout::new();
    let mut put = |p: &str, d: Data| {
        l.insert(p.to_string(), d);
    };
    for name in ["M", "H"] {
        put(&format!("fclib_global/{name}/m"), Data::I32(vec![2]));
        put(&format!("fclib_global/{name}/n"), Data::I32(vec![2]));
        put(&format!("fclib_global/{name}/nz"), Data::I32(vec![-1]));
        put(&format!("fclib_global/{name}/nzmax"), Data::I32(vec![2]));
        put(&format!("fclib_global/{name}/p"), Data::I32(vec![0, 1, 2]));
        put(&format!("fclib_global/{name}/i"), Data::I32(vec![0, 1]));
        put(&format!("fclib_global/{name}/x"), Data::F64(vec![1.0, 1.0]));
    }
    put("fclib_global/G/m", Data::I32(vec![2]));
    put("fclib_global/G/n", Data::I32(vec![1]));
    put("fclib_global/G/nz", Data::I32(vec![-1]));
    put("fclib_global/G/nzmax", Data::I32(vec![1]));
    put("fclib_global/G/p", Data::I32(vec![0, 1]));
    put("fclib_global/G/i", Data::I32(vec![0]));
    put("fclib_global/G/x", Data::F64(vec![1.0]));
    put("fclib_global/vectors/f", Data::F64(vec![0.0, -1.0]));
    put("fclib_global/vectors/w", Data::F64(vec![0.0, 0.0]));
    put("fclib_global/vectors/mu", Data::F64(vec![0.5]));
    put("fclib_global/vectors/b", Data::F64(vec![-1.0]));
    put("fclib_global/spacedim", Data::I32(vec![2]));
    put("solution/r", Data::F64(vec![0.0; 2]));
    put("solution/v", Data::F64(vec![0.0; 2]));
    put("solution/l", Data::F64(vec![0.0]));
    l
}

#[test]
fn fclib_corrupt_equality_constraints() {
    let f = read(&valid_equality()).unwrap();
    let Problem::Global(p) = &f.problem else {
        panic!()
    };
    let e = p.equality.as_ref().unwrap();
    assert_eq!((e.g.nrows, e.g.ncols, e.b.clone()), (2, 1, vec![-1.0]));
    // G without b, b without G
    let mut l = valid_equality();
    l.remove("fclib_global/vectors/b");
    expect_err(&l, "/fclib_global/vectors/b", "missing dataset");
    let mut l = valid_equality();
    l.retain(|k, _| !k.starts_with("fclib_global/G/"));
    expect_err(&l, "/fclib_global/G", "both");
    // G with the wrong number of rows, b of the wrong length, an index out of range
    let mut l = valid_equality();
    l.insert("fclib_global/G/m".into(), Data::I32(vec![3]));
    expect_err(&l, "/fclib_global/G/m", "as many rows as M");
    let mut l = valid_equality();
    l.insert("fclib_global/vectors/b".into(), Data::F64(vec![1.0, 2.0]));
    expect_err(&l, "/fclib_global/vectors/b", "n of /fclib_global/G");
    let mut l = valid_equality();
    l.insert("fclib_global/G/i".into(), Data::I32(vec![5]));
    expect_err(&l, "/fclib_global/G/i", "row index");
    // G stored as a dataset, not a matrix group
    let mut l = valid_equality();
    l.retain(|k, _| !k.starts_with("fclib_global/G/"));
    l.insert("fclib_global/G".into(), Data::F64(vec![1.0]));
    expect_err(&l, "/fclib_global/G", "expected a group");
    // l of the wrong length
    let mut l = valid_equality();
    l.insert("solution/l".into(), Data::F64(vec![0.0, 0.0]));
    expect_err(&l, "/solution/l", "equality rows");
}
