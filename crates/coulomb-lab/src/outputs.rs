//! Every file `coulomb` writes goes through here (the CLI's commands and the engines of this
//! crate alike): paths are checked before a long run starts
//! ([`check`]), an output that is one of the run's inputs is refused, files are replaced
//! atomically ([`coulomb::atomic::write`]: temporary file in the same folder, then rename, so a
//! failed write never truncates anything), and replacing an existing file is said on stderr.
//!
//! Decision: an existing output file is replaced (no `--force`), with a note on stderr
//! (`note: replacing existing FILE`); an input of the same run is never replaced.

use anyhow::bail;
use std::path::{Path, PathBuf};

/// An output that could not be written (the destination is untouched): the CLI's exit
/// status 4.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct WriteFailed {
    /// the destination
    pub path: String,
    /// the OS error
    pub source: std::io::Error,
}

/// Whether `a` and `b` name the same existing file (same device and inode on Unix; same
/// canonical path elsewhere). False when either does not exist.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (a.canonicalize(), b.canonicalize()) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        }
    }
}

/// Checks an output path before the work starts: not one of `inputs`, not a directory,
/// device, FIFO, socket or dangling symbolic link ([`coulomb::atomic::destination`]: the
/// message then starts with "output path refused"), and a file can be created in its folder
/// now. `what` names the option (`--output`). The CLI's exit status 2.
pub fn check(what: &str, path: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
    for input in inputs {
        if same_file(path, input) {
            bail!(
                "{what} {} is an input of this run; refusing to write over it (choose another file)",
                path.display()
            );
        }
    }
    if let Err(e) = coulomb::atomic::check_writable(path) {
        if let Some(refused) = coulomb::atomic::refusal(&e) {
            bail!("{what}: {refused}");
        }
        bail!("{what} {}: cannot write there: {e}", path.display());
    }
    Ok(())
}

/// [`check`] on the files `names` that a run will write into the folder `dir`, before the run
/// (`simulate --output DIR`: stats.csv, stats.json, summary.json), so that one of them that
/// is a device, FIFO or folder is refused now rather than after the last step.
pub fn check_in(what: &str, dir: &Path, names: &[&str]) -> anyhow::Result<()> {
    for name in names {
        check(what, &dir.join(name), &[])?;
    }
    Ok(())
}

/// Replaces `path` by `bytes` atomically, saying so when a file was there.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), WriteFailed> {
    let existed = path.is_file();
    coulomb::atomic::write(path, bytes).map_err(|source| WriteFailed {
        path: path.display().to_string(),
        source,
    })?;
    if existed {
        eprintln!("note: replaced existing {}", path.display());
    }
    Ok(())
}

/// Writes an FCLIB file atomically (see [`write()`]).
pub fn write_fclib(path: &Path, file: &coulomb::fclib::FclibFile) -> anyhow::Result<()> {
    let bytes = coulomb::fclib::to_bytes(file, &Default::default())?;
    write(path, &bytes)?;
    Ok(())
}

/// An output written by a third party (a plotting backend) into a temporary file next to
/// its destination, then renamed over it by [`Staged::commit`]; dropped without commit, the
/// temporary file is removed and the destination is untouched.
pub struct Staged {
    tmp: PathBuf,
    dest: PathBuf,
    done: bool,
}

impl Staged {
    /// A temporary path next to the file that `dest` names (the target of a symbolic link
    /// to a regular file; [`coulomb::atomic::destination`]). A `dest` that is refused is
    /// refused again by [`Staged::commit`].
    pub fn new(dest: &Path) -> Self {
        let file = coulomb::atomic::destination(dest).unwrap_or_else(|_| dest.to_path_buf());
        Self {
            tmp: coulomb::atomic::temp_name(&file),
            dest: dest.to_path_buf(),
            done: false,
        }
    }

    /// Where the backend should write.
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// Renames the temporary file over the destination (saying so when one was there) with
    /// [`coulomb::atomic::replace`]: a destination that is not a regular file is refused.
    pub fn commit(mut self) -> Result<(), WriteFailed> {
        let existed = self.dest.is_file();
        coulomb::atomic::replace(&self.tmp, &self.dest).map_err(|source| WriteFailed {
            path: self.dest.display().to_string(),
            source,
        })?;
        self.done = true;
        if existed {
            eprintln!("note: replaced existing {}", self.dest.display());
        }
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.done {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Replaces every −0.0 in a JSON value by 0.0 (a negative zero means nothing to a reader).
pub fn clean(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Number(n)
            if n.as_f64().is_some_and(|x| x == 0.0 && x.is_sign_negative()) =>
        {
            *v = serde_json::json!(0.0);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(clean),
        serde_json::Value::Object(o) => o.values_mut().for_each(clean),
        _ => {}
    }
}

/// JSON text of `x` (pretty or compact) with no −0.0 in it.
pub fn json<T: serde::Serialize + ?Sized>(x: &T, pretty: bool) -> serde_json::Result<String> {
    let mut v = serde_json::to_value(x)?;
    clean(&mut v);
    if pretty {
        serde_json::to_string_pretty(&v)
    } else {
        serde_json::to_string(&v)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn json_has_no_negative_zero() {
        let s = super::json(
            &serde_json::json!({"a": -0.0, "b": [-0.0, 1.5, -2.0]}),
            false,
        )
        .unwrap();
        assert!(!s.contains("-0"), "{s}");
        assert!(s.contains("-2"), "{s}");
    }

    use super::*;

    #[test]
    fn outputs_refuse_inputs_directories_and_unwritable_folders() {
        let dir = std::env::temp_dir().join(format!("coulomb-outputs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let input = dir.join("in.hdf5");
        std::fs::write(&input, b"data").unwrap();
        // the same file under another name
        let alias = dir.join(".").join("in.hdf5");
        assert!(check("--output", &alias, &[&input]).is_err());
        let e = check("--output", &dir, &[]).unwrap_err().to_string();
        assert!(e.starts_with("--output: output path refused: "), "{e}");
        assert!(e.contains("is a directory"), "{e}");
        assert!(check("--output", &dir.join("missing/x.json"), &[]).is_err());
        assert!(check("--output", Path::new("/proc/x.json"), &[]).is_err());
        assert!(check("--output", &dir.join("new.json"), &[&input]).is_ok());
        write(&dir.join("new.json"), b"{}").unwrap();
        assert_eq!(std::fs::read(&input).unwrap(), b"data");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
