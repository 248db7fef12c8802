//! Which files `coulomb bench PATH...` runs on.
//!
//! - A PATH that is a file is taken as it is, whatever its extension.
//! - A PATH that is a directory is searched **recursively** (all levels, up to [`MAX_DEPTH`]) for
//!   files whose name ends in `.hdf5` or `.h5` (case-insensitive). Symbolic links to files are
//!   followed; symbolic links to directories inside the tree are not (no cycles). The PATH itself
//!   may be a symbolic link to a directory.
//! - Files are listed in the order of the PATHs, each directory's files sorted by path; a file
//!   reached twice (same canonical path) is kept once.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// How deep directories are searched below a PATH.
pub const MAX_DEPTH: usize = 64;

/// A PATH that cannot be searched.
#[derive(Debug, thiserror::Error)]
pub enum FilesError {
    /// the path does not exist or cannot be inspected
    #[error("cannot open {path}: {source}")]
    Open {
        /// the path
        path: PathBuf,
        /// the OS error
        source: std::io::Error,
    },
    /// a directory cannot be listed
    #[error("cannot list directory {path}: {source}")]
    List {
        /// the directory
        path: PathBuf,
        /// the OS error
        source: std::io::Error,
    },
}

/// Whether `path` names an FCLIB file by its extension (`.hdf5` or `.h5`, any case).
pub fn has_fclib_extension(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("hdf5") || e.eq_ignore_ascii_case("h5"))
}

/// The FCLIB files named by `paths` (see the module documentation for the rules).
pub fn collect(paths: &[PathBuf]) -> Result<Vec<PathBuf>, FilesError> {
    let mut out = Vec::new();
    let mut seen = HashSet::new();
    for path in paths {
        let meta = std::fs::metadata(path).map_err(|source| FilesError::Open {
            path: path.clone(),
            source,
        })?;
        let mut found = Vec::new();
        if meta.is_dir() {
            walk(path, 0, &mut found)?;
            found.sort();
        } else {
            found.push(path.clone());
        }
        for file in found {
            let key = std::fs::canonicalize(&file).unwrap_or_else(|_| file.clone());
            if seen.insert(key) {
                out.push(file);
            }
        }
    }
    Ok(out)
}

fn walk(dir: &Path, depth: usize, out: &mut Vec<PathBuf>) -> Result<(), FilesError> {
    let list_err = |source| FilesError::List {
        path: dir.to_path_buf(),
        source,
    };
    for entry in std::fs::read_dir(dir).map_err(list_err)? {
        let entry = entry.map_err(list_err)?;
        let path = entry.path();
        let ty = entry.file_type().map_err(|source| FilesError::Open {
            path: path.clone(),
            source,
        })?;
        if ty.is_dir() {
            if depth < MAX_DEPTH {
                walk(&path, depth + 1, out)?;
            }
        } else if has_fclib_extension(&path) {
            // a plain file, or a symbolic link: keep links only when they lead to a file
            let is_file = ty.is_file() || std::fs::metadata(&path).is_ok_and(|m| m.is_file());
            if is_file {
                out.push(path);
            }
        }
    }
    Ok(())
}

/// Short display names for the files: the file stem when it is unique among `files`, the path
/// as given otherwise.
pub fn display_names(files: &[PathBuf]) -> Vec<String> {
    let stem = |p: &PathBuf| {
        p.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| p.display().to_string())
    };
    let stems: Vec<String> = files.iter().map(stem).collect();
    files
        .iter()
        .zip(&stems)
        .map(|(p, s)| {
            if stems.iter().filter(|t| *t == s).count() > 1 {
                p.display().to_string()
            } else {
                s.clone()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collects_recursively_sorted_and_deduplicated() {
        let root = std::env::temp_dir().join(format!("coulomb-bench-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(root.join("sub/deeper")).unwrap();
        for f in [
            "b.hdf5",
            "a.H5",
            "notes.txt",
            "sub/c.hdf5",
            "sub/deeper/d.h5",
        ] {
            std::fs::write(root.join(f), b"x").unwrap();
        }
        let got = collect(&[root.clone(), root.join("a.H5"), root.join("notes.txt")]).unwrap();
        let rel: Vec<String> = got
            .iter()
            .map(|p| p.strip_prefix(&root).unwrap().display().to_string())
            .collect();
        assert_eq!(
            rel,
            [
                "a.H5",
                "b.hdf5",
                "sub/c.hdf5",
                "sub/deeper/d.h5",
                "notes.txt"
            ]
        );
        assert!(matches!(
            collect(&[root.join("missing")]),
            Err(FilesError::Open { .. })
        ));
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn names_are_stems_unless_ambiguous() {
        let files: Vec<PathBuf> = ["x/Rover.hdf5", "y/A.hdf5", "z/A.h5"]
            .iter()
            .map(PathBuf::from)
            .collect();
        assert_eq!(display_names(&files), ["Rover", "y/A.hdf5", "z/A.h5"]);
    }
}
