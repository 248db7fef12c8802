//! Writing FCLIB files in the layout Siconos writes (see the module documentation).

use super::error::{FclibError, FclibErrorKind};
use super::{FclibFile, IndexWidth, Info, Storage, StoredSolution, WriteOptions};
use crate::linalg::sparse::CscMatrix;
use crate::problem::Problem;
use hdf5_pure::{FileBuilder, GroupBuilder};

/// Integer arrays in the requested width.
enum Ints {
    I32(Vec<i32>),
    I64(Vec<i64>),
}

fn to_ints(
    values: impl Iterator<Item = i64>,
    width: IndexWidth,
    path: &str,
) -> Result<Ints, FclibErrorKind> {
    match width {
        IndexWidth::Int64 => Ok(Ints::I64(values.collect())),
        IndexWidth::Int32 => {
            let mut out = Vec::new();
            for x in values {
                out.push(i32::try_from(x).map_err(|_| FclibErrorKind::Write {
                    path: path.to_string(),
                    detail: format!("{x} does not fit in int32; write with IndexWidth::Int64"),
                })?);
            }
            Ok(Ints::I32(out))
        }
    }
}

fn put_ints(g: &mut GroupBuilder, name: &str, ints: &Ints) {
    match ints {
        Ints::I32(v) => {
            g.create_dataset(name).with_i32_data(v);
        }
        Ints::I64(v) => {
            g.create_dataset(name).with_i64_data(v);
        }
    }
}

fn put_size(g: &mut GroupBuilder, name: &str, x: usize, path: &str) -> Result<(), FclibErrorKind> {
    let v = i32::try_from(x).map_err(|_| FclibErrorKind::Write {
        path: format!("{path}/{name}"),
        detail: format!("{x} does not fit in int32"),
    })?;
    g.create_dataset(name).with_i32_data(&[v]);
    Ok(())
}

fn put_string(g: &mut GroupBuilder, name: &str, s: &str, path: &str) -> Result<(), FclibErrorKind> {
    let ds = g.create_dataset(name);
    let staged = if s.is_ascii() {
        ds.with_ascii_strings(&[s])
    } else {
        ds.with_strings(&[s])
    };
    staged
        .map_err(|e| FclibErrorKind::Write {
            path: format!("{path}/{name}"),
            detail: e.to_string(),
        })?
        .with_shape(&[]);
    Ok(())
}

/// Writes one matrix group (`m`, `n`, `nz`, `nzmax`, `p`, `i`, `x`).
fn put_matrix(
    parent: &mut GroupBuilder,
    name: &str,
    a: &CscMatrix,
    opts: &WriteOptions,
    parent_path: &str,
) -> Result<(), FclibErrorKind> {
    let path = format!("{parent_path}/{name}");
    let mut g = parent.create_group(name);
    put_size(&mut g, "m", a.nrows, &path)?;
    put_size(&mut g, "n", a.ncols, &path)?;
    let nnz = a.nnz();
    let as_i64 = |x: usize| i64::try_from(x).unwrap_or(i64::MAX);
    let (nz, p, i, x): (i64, Ints, Ints, Vec<f64>) = match opts.storage {
        Storage::Csc => (
            -1,
            to_ints(
                a.col_ptr.iter().map(|&k| as_i64(k)),
                opts.index,
                &format!("{path}/p"),
            )?,
            to_ints(
                a.row_idx.iter().map(|&k| as_i64(k)),
                opts.index,
                &format!("{path}/i"),
            )?,
            a.values.clone(),
        ),
        Storage::Csr => {
            let t = a.transpose();
            (
                -2,
                to_ints(
                    t.col_ptr.iter().map(|&k| as_i64(k)),
                    opts.index,
                    &format!("{path}/p"),
                )?,
                to_ints(
                    t.row_idx.iter().map(|&k| as_i64(k)),
                    opts.index,
                    &format!("{path}/i"),
                )?,
                t.values,
            )
        }
        Storage::Triplet => {
            let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
            for (r, c, v) in a.triplets() {
                rows.push(as_i64(r));
                cols.push(as_i64(c));
                vals.push(v);
            }
            (
                as_i64(nnz),
                to_ints(cols.into_iter(), opts.index, &format!("{path}/p"))?,
                to_ints(rows.into_iter(), opts.index, &format!("{path}/i"))?,
                vals,
            )
        }
    };
    let nz32 = i32::try_from(nz).map_err(|_| FclibErrorKind::Write {
        path: format!("{path}/nz"),
        detail: format!("{nz} does not fit in int32"),
    })?;
    g.create_dataset("nz").with_i32_data(&[nz32]);
    put_size(&mut g, "nzmax", nnz, &path)?;
    put_ints(&mut g, "p", &p);
    put_ints(&mut g, "i", &i);
    g.create_dataset("x").with_f64_data(&x);
    parent.add_group(g.finish());
    Ok(())
}

fn put_info(
    parent: &mut GroupBuilder,
    info: &Info,
    parent_path: &str,
) -> Result<(), FclibErrorKind> {
    let path = format!("{parent_path}/info");
    let mut g = parent.create_group("info");
    put_string(&mut g, "title", &info.title, &path)?;
    put_string(&mut g, "description", &info.description, &path)?;
    put_string(&mut g, "math_info", &info.math_info, &path)?;
    parent.add_group(g.finish());
    Ok(())
}

fn put_solution(g: &mut GroupBuilder, s: &StoredSolution) {
    if let Some(v) = &s.v {
        g.create_dataset("v").with_f64_data(v);
    }
    if let Some(u) = &s.u {
        g.create_dataset("u").with_f64_data(u);
    }
    g.create_dataset("r").with_f64_data(&s.r);
    if let Some(l) = &s.l {
        g.create_dataset("l").with_f64_data(l);
    }
}

/// Serializes `file` into an HDF5 image.
pub(super) fn to_bytes(file: &FclibFile, opts: &WriteOptions) -> Result<Vec<u8>, FclibErrorKind> {
    let mut b = FileBuilder::new();
    match &file.problem {
        Problem::Local(p) => {
            let path = "/fclib_local";
            let mut g = b.create_group("fclib_local");
            put_matrix(&mut g, "W", &p.w, opts, path)?;
            let mut v = g.create_group("vectors");
            v.create_dataset("q").with_f64_data(&p.q);
            v.create_dataset("mu").with_f64_data(&p.mu);
            g.add_group(v.finish());
            put_size(&mut g, "spacedim", p.dim, path)?;
            if let Some(info) = &file.info {
                put_info(&mut g, info, path)?;
            }
            b.add_group(g.finish());
        }
        Problem::Global(p) => {
            let path = "/fclib_global";
            let mut g = b.create_group("fclib_global");
            put_matrix(&mut g, "M", &p.m, opts, path)?;
            put_matrix(&mut g, "H", &p.h, opts, path)?;
            if let Some(e) = &p.equality {
                put_matrix(&mut g, "G", &e.g, opts, path)?;
            }
            let mut v = g.create_group("vectors");
            v.create_dataset("f").with_f64_data(&p.f);
            v.create_dataset("w").with_f64_data(&p.w);
            v.create_dataset("mu").with_f64_data(&p.mu);
            if let Some(e) = &p.equality {
                v.create_dataset("b").with_f64_data(&e.b);
            }
            g.add_group(v.finish());
            put_size(&mut g, "spacedim", p.dim, path)?;
            if let Some(info) = &file.info {
                put_info(&mut g, info, path)?;
            }
            b.add_group(g.finish());
        }
    }
    if let Some(s) = &file.solution {
        let mut g = b.create_group("solution");
        put_solution(&mut g, s);
        b.add_group(g.finish());
    }
    if !file.guesses.is_empty() {
        let mut g = b.create_group("guesses");
        put_size(&mut g, "number_of_guesses", file.guesses.len(), "/guesses")?;
        for (k, s) in file.guesses.iter().enumerate() {
            let mut one = g.create_group(&(k + 1).to_string());
            put_solution(&mut one, s);
            g.add_group(one.finish());
        }
        b.add_group(g.finish());
    }
    b.finish().map_err(|e| FclibErrorKind::Write {
        path: "/".into(),
        detail: e.to_string(),
    })
}

/// Convenience for the public API: attaches the file name.
pub(super) fn to_bytes_named(
    name: &str,
    file: &FclibFile,
    opts: &WriteOptions,
) -> Result<Vec<u8>, FclibError> {
    to_bytes(file, opts).map_err(|k| FclibError::new(name, k))
}
