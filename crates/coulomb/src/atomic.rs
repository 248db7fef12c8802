//! Atomic file replacement: every output of coulomb is written to a temporary file in the
//! destination's own folder, flushed to disk, then renamed over the destination. A failed
//! write (full disk, quota, permissions, interruption) leaves the destination as it was —
//! an input is never truncated, an older output never half-overwritten.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// A temporary name next to `path`: `.NAME.tmp-PID-K` in the same folder (same file system,
/// so that the final rename is atomic).
pub fn temp_name(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let k = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = format!(".{name}.tmp-{}-{k}", std::process::id());
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.join(tmp),
        _ => PathBuf::from(tmp),
    }
}

/// Writes `bytes` to `path` atomically: temporary file in the same folder, `sync_all`, rename.
/// On any error the temporary file is removed and `path` is untouched. A `path` that is a
/// directory is refused (the rename would fail or, on some systems, replace it).
pub fn write(path: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> std::io::Result<()> {
    let (path, bytes) = (path.as_ref(), bytes.as_ref());
    if path.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "is a directory",
        ));
    }
    let tmp = temp_name(path);
    let result = (|| {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Whether a file can be created in `path`'s folder now (a temporary file is created and
/// removed; `path` itself is not touched). Lets a long command refuse an unwritable output
/// before it starts rather than after.
pub fn check_writable(path: &Path) -> std::io::Result<()> {
    if path.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "is a directory",
        ));
    }
    let tmp = temp_name(path);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)?;
    std::fs::remove_file(&tmp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("coulomb-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.txt");
        write(&p, b"one").unwrap();
        write(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        // a directory is refused and stays a directory
        assert!(write(&dir, b"x").is_err());
        assert!(dir.is_dir());
        // a folder that does not exist: an error, nothing created
        assert!(write(dir.join("no/such.txt"), b"x").is_err());
        assert!(check_writable(&p).is_ok());
        assert!(check_writable(&dir.join("no/such.txt")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
