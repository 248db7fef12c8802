//! `coulomb info`: what is in FCLIB files.

use crate::read::read_relaxed;
use coulomb::fclib::FclibFile;
use coulomb::Problem;
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `coulomb info`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// FCLIB files (.hdf5)
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Print JSON: one object per file, an array when several files are given
    #[arg(long)]
    pub json: bool,
}

/// Summary of one file. `nnz` counts the entries of W (local) or of M plus H (global) as
/// coulomb holds them after reading: CSC, duplicates summed, explicit zeros kept.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// the path as given
    pub file: String,
    /// "local" or "global"
    pub kind: &'static str,
    /// space dimension d
    pub dim: usize,
    /// number of contacts
    pub contacts: usize,
    /// degrees of freedom n (null for a local problem)
    pub dofs: Option<usize>,
    /// equality (bilateral) constraint rows p, `/fclib_global/G` (null for a local problem,
    /// 0 for a global problem without them)
    pub equality_rows: Option<usize>,
    /// stored entries of W, or of M + H
    pub nnz: usize,
    /// smallest friction coefficient (null without contacts)
    pub mu_min: Option<f64>,
    /// largest friction coefficient (null without contacts)
    pub mu_max: Option<f64>,
    /// whether /solution is present
    pub has_solution: bool,
    /// number of /guesses
    pub guesses: usize,
    /// /fclib_*/info/title, when present
    pub title: Option<String>,
    /// relative asymmetry max|A − Aᵀ| / max|A| of W (local) or M (global) as stored; the
    /// problem is solved as stored whatever its value
    pub asymmetry: f64,
}

/// Summarizes a file already read.
pub fn summarize(file: String, f: &FclibFile) -> Summary {
    let p = &f.problem;
    let nnz = match p {
        Problem::Local(l) => l.w.nnz(),
        Problem::Global(g) => g.m.nnz() + g.h.nnz(),
    };
    let mu = p.mu();
    let (mu_min, mu_max) = if mu.is_empty() {
        (None, None)
    } else {
        (
            Some(mu.iter().cloned().fold(f64::INFINITY, f64::min)),
            Some(mu.iter().cloned().fold(f64::NEG_INFINITY, f64::max)),
        )
    };
    Summary {
        file,
        kind: p.kind(),
        dim: p.dim(),
        contacts: p.contacts(),
        dofs: p.dofs(),
        equality_rows: match p {
            Problem::Local(_) => None,
            Problem::Global(g) => Some(g.equality_rows()),
        },
        nnz,
        mu_min,
        mu_max,
        has_solution: f.solution.is_some(),
        guesses: f.guesses.len(),
        title: f.info.as_ref().map(|i| i.title.clone()),
        asymmetry: p.asymmetry(),
    }
}

fn opt<T: std::fmt::Display>(x: Option<T>) -> String {
    x.map_or_else(|| "-".to_string(), |v| v.to_string())
}

/// Runs `coulomb info`: exit status 2 when a file could not be read (each is named in the
/// table or the JSON), 0 otherwise.
pub fn run(args: Args) -> anyhow::Result<crate::exit::Outcome> {
    let mut rows = Vec::new();
    let mut failures = 0;
    for path in &args.files {
        let name = path.display().to_string();
        match read_relaxed(path) {
            Ok(f) => rows.push(Ok(summarize(name, &f))),
            Err(e) => {
                failures += 1;
                rows.push(Err((name, e.to_string())));
            }
        }
    }
    if args.json {
        let values: Vec<serde_json::Value> = rows
            .iter()
            .map(|r| match r {
                Ok(s) => serde_json::to_value(s),
                Err((file, error)) => Ok(serde_json::json!({ "file": file, "error": error })),
            })
            .collect::<Result<_, _>>()?;
        let out = if values.len() == 1 {
            crate::outputs::json(&values[0], true)?
        } else {
            crate::outputs::json(&values, true)?
        };
        println!("{out}");
    } else {
        println!(
            "{:<45} {:>6} {:>3} {:>8} {:>6} {:>8} {:>7} {:>7} {:>4} {:>7} {:>5}",
            "file",
            "kind",
            "d",
            "contacts",
            "dofs",
            "nnz",
            "mu_min",
            "mu_max",
            "sol",
            "guesses",
            "eq"
        );
        for r in &rows {
            match r {
                Ok(s) => {
                    let name = std::path::Path::new(&s.file)
                        .file_name()
                        .map_or(s.file.clone(), |n| n.to_string_lossy().into_owned());
                    println!(
                        "{:<45} {:>6} {:>3} {:>8} {:>6} {:>8} {:>7} {:>7} {:>4} {:>7} {:>5}",
                        name,
                        s.kind,
                        s.dim,
                        s.contacts,
                        opt(s.dofs),
                        s.nnz,
                        opt(s.mu_min.map(|m| format!("{m:.3}"))),
                        opt(s.mu_max.map(|m| format!("{m:.3}"))),
                        if s.has_solution { "yes" } else { "no" },
                        s.guesses,
                        opt(s.equality_rows)
                    );
                }
                Err((file, _)) => println!("{file:<45} (unreadable, see below)"),
            }
        }
        for s in rows.iter().flatten() {
            if s.asymmetry > coulomb::problem::SYMMETRY_TOLERANCE {
                let w = if s.kind == "local" { "W" } else { "M" };
                eprintln!(
                    "note: {}: {w} is not symmetric (relative asymmetry {:.3e}); it is used as stored",
                    s.file, s.asymmetry
                );
            }
        }
        for r in &rows {
            if let Err((_, e)) = r {
                eprintln!("error: {e}");
            }
        }
    }
    if failures > 0 {
        eprintln!(
            "error: {failures} of {} files could not be read",
            args.files.len()
        );
        return Ok(crate::exit::Outcome::BadInput);
    }
    Ok(crate::exit::Outcome::Success)
}
