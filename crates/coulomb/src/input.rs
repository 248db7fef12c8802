//! The one checked reader of every input file of coulomb (FCLIB problems, scene files,
//! particle and mesh files, checkpoints).
//!
//! An input is a **regular file of bounded size**. [`read`] opens the path without blocking
//! (`O_NONBLOCK`, so that opening a FIFO with no writer returns at once instead of waiting for
//! one), looks at the *opened* handle (`fstat`, so that what is read is what was checked,
//! even if the path is replaced in between), and refuses anything that is not a regular
//! file — a FIFO, a character device such as `/dev/zero` or a terminal, a block device, a
//! directory, a socket — with an [`InputError`] that names the path and what it is. A regular
//! file larger than the limit of its [`Kind`] is refused before anything is read; the read
//! itself stops at the limit too (a file that grows while it is read, or a file whose size
//! the system does not report, such as those of `/proc`, is never read without bound).
//!
//! `O_NONBLOCK` is left set on the regular file: POSIX gives it no effect on regular files
//! (reads of a regular file never return `EAGAIN`), so clearing it would change nothing.
//!
//! Standard input and other streams are not inputs of coulomb: every input is named by a path.

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

use crate::atomic::NotRegular;

const MIB: u64 = 1 << 20;
const GIB: u64 = 1 << 30;

/// What an input file is: it sets the size limit and the name used in messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// an FCLIB problem (HDF5); limit 8 GiB
    Fclib,
    /// a scene file (TOML or JSON); limit 16 MiB
    Scene,
    /// a particle file (CSV or NPY); limit 8 GiB
    Particles,
    /// a surface mesh (STL or OBJ); limit 2 GiB
    Mesh,
    /// a checkpoint of a simulation (HDF5); limit 16 GiB
    Checkpoint,
    /// any other small text input (settings, lists); limit 16 MiB
    Text,
}

impl Kind {
    /// The largest file of this kind that is read, in bytes. Far above any file met in
    /// practice (the largest FCLIB file of the collection is under 200 MB, a checkpoint of
    /// 10⁷ beads about 1.5 GB), and far below what would exhaust memory silently: a file over
    /// it is refused with [`InputReason::TooLarge`] before anything is read.
    pub const fn limit(self) -> u64 {
        match self {
            Kind::Fclib => 8 * GIB,
            Kind::Scene => 16 * MIB,
            Kind::Particles => 8 * GIB,
            Kind::Mesh => 2 * GIB,
            Kind::Checkpoint => 16 * GIB,
            Kind::Text => 16 * MIB,
        }
    }

    /// The kind in words, for messages.
    pub const fn name(self) -> &'static str {
        match self {
            Kind::Fclib => "FCLIB file",
            Kind::Scene => "scene file",
            Kind::Particles => "particle file",
            Kind::Mesh => "mesh file",
            Kind::Checkpoint => "checkpoint",
            Kind::Text => "input file",
        }
    }
}

/// Why an input could not be read (the path is in [`InputError`]).
#[derive(Debug)]
pub enum InputReason {
    /// opening the path failed (no such file, no permission, ...)
    Open(std::io::Error),
    /// the path is not a regular file
    NotRegular(NotRegular),
    /// the file is larger than the limit of its kind
    TooLarge {
        /// the size found (at least; a file that grew while read may be larger)
        size: u64,
        /// the limit of the kind ([`Kind::limit`])
        limit: u64,
    },
    /// reading the opened file failed
    Read(std::io::Error),
    /// a text input is not UTF-8
    NotUtf8 {
        /// the offset of the first byte that is not UTF-8
        offset: usize,
    },
}

impl fmt::Display for InputReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InputReason::Open(e) => write!(f, "cannot be opened: {}", os_message(e)),
            InputReason::NotRegular(NotRegular::Directory) => {
                write!(f, "is a directory, expected a file")
            }
            InputReason::NotRegular(kind) => write!(
                f,
                "is {kind}, not a regular file; inputs are read from regular files only"
            ),
            InputReason::TooLarge { size, limit } => write!(
                f,
                "is {size} bytes, over the limit of {limit} bytes for this kind of input"
            ),
            InputReason::Read(e) => write!(f, "cannot be read: {}", os_message(e)),
            InputReason::NotUtf8 { offset } => {
                write!(f, "is not UTF-8 text (invalid byte at offset {offset})")
            }
        }
    }
}

impl std::error::Error for InputReason {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        None
    }
}

/// An input that could not be read: displays as `PATH: the scene file is a FIFO (named
/// pipe), not a regular file; ...`.
#[derive(Debug)]
pub struct InputError {
    /// the path as given
    pub path: PathBuf,
    /// what the input was read as
    pub kind: Kind,
    /// what is wrong
    pub reason: InputReason,
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: the {} {}",
            self.path.display(),
            self.kind.name(),
            self.reason
        )
    }
}

impl std::error::Error for InputError {}

impl InputError {
    /// True when the file does not exist.
    pub fn is_not_found(&self) -> bool {
        matches!(&self.reason, InputReason::Open(e) if e.kind() == std::io::ErrorKind::NotFound)
    }
}

/// An OS error as one short phrase ("No such file or directory (os error 2)").
fn os_message(e: &std::io::Error) -> String {
    e.to_string()
}

fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    options.open(path)
}

/// Opens `path` as an input of kind `kind`: a regular file no larger than `limit` bytes.
/// Returns the open file and its size.
fn open_checked(path: &Path, kind: Kind, limit: u64) -> Result<(std::fs::File, u64), InputError> {
    let err = |reason| InputError {
        path: path.to_path_buf(),
        kind,
        reason,
    };
    let file = match open_nonblocking(path) {
        Ok(f) => f,
        // Opening a socket fails (ENXIO), opening a directory may (EISDIR, not on Linux): say
        // what the path is rather than the system's reason
        Err(e) => {
            let what = std::fs::metadata(path)
                .ok()
                .and_then(|m| NotRegular::of(m.file_type()));
            return Err(err(match what {
                Some(kind) => InputReason::NotRegular(kind),
                None => InputReason::Open(e),
            }));
        }
    };
    let meta = file.metadata().map_err(|e| err(InputReason::Read(e)))?;
    if let Some(what) = NotRegular::of(meta.file_type()) {
        return Err(err(InputReason::NotRegular(what)));
    }
    if meta.len() > limit {
        return Err(err(InputReason::TooLarge {
            size: meta.len(),
            limit,
        }));
    }
    Ok((file, meta.len()))
}

/// Reads the input file `path` of kind `kind` whole (see the module doc): a typed error when
/// it is not a regular file or is larger than [`Kind::limit`].
pub fn read(path: &Path, kind: Kind) -> Result<Vec<u8>, InputError> {
    read_limited(path, kind, kind.limit())
}

/// [`read`] with a limit other than the kind's (`limit` bytes at most).
pub fn read_limited(path: &Path, kind: Kind, limit: u64) -> Result<Vec<u8>, InputError> {
    let (file, size) = open_checked(path, kind, limit)?;
    let mut bytes = Vec::new();
    // capacity from the size checked against the limit, never more
    bytes
        .try_reserve_exact(size as usize)
        .map_err(|_| InputError {
            path: path.to_path_buf(),
            kind,
            reason: InputReason::Read(std::io::Error::new(
                std::io::ErrorKind::OutOfMemory,
                format!("cannot allocate {size} bytes to read it"),
            )),
        })?;
    // one byte past the limit is read to tell a file that grew past it
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| InputError {
            path: path.to_path_buf(),
            kind,
            reason: InputReason::Read(e),
        })?;
    if bytes.len() as u64 > limit {
        return Err(InputError {
            path: path.to_path_buf(),
            kind,
            reason: InputReason::TooLarge {
                size: bytes.len() as u64,
                limit,
            },
        });
    }
    Ok(bytes)
}

/// Reads the text input `path` of kind `kind` (see [`read`]); a typed error when it is not
/// UTF-8.
pub fn read_to_string(path: &Path, kind: Kind) -> Result<String, InputError> {
    let bytes = read(path, kind)?;
    String::from_utf8(bytes).map_err(|e| InputError {
        path: path.to_path_buf(),
        kind,
        reason: InputReason::NotUtf8 {
            offset: e.utf8_error().valid_up_to(),
        },
    })
}

#[cfg(all(feature = "unit-tests", unix))]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    fn tmpdir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("coulomb-input-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    pub fn regular_file_is_read_whole() {
        let d = tmpdir("regular");
        let p = d.join("a.toml");
        std::fs::write(&p, b"x = 1\n").unwrap();
        assert_eq!(read(&p, Kind::Scene).unwrap(), b"x = 1\n");
        assert_eq!(read_to_string(&p, Kind::Scene).unwrap(), "x = 1\n");
        std::fs::remove_dir_all(&d).unwrap();
    }

    pub fn fifo_is_refused_without_blocking() {
        let d = tmpdir("fifo");
        let p = d.join("pipe.h5");
        let st = std::process::Command::new("mkfifo")
            .arg(&p)
            .status()
            .unwrap();
        assert!(st.success());
        let t = Instant::now();
        let e = read(&p, Kind::Fclib).unwrap_err();
        assert!(t.elapsed() < Duration::from_secs(5));
        assert!(
            matches!(e.reason, InputReason::NotRegular(NotRegular::Fifo)),
            "{e}"
        );
        let msg = e.to_string();
        assert!(msg.contains("pipe.h5") && msg.contains("FIFO"), "{msg}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    pub fn dev_zero_and_directory_are_refused() {
        let e = read(Path::new("/dev/zero"), Kind::Particles).unwrap_err();
        assert!(
            matches!(e.reason, InputReason::NotRegular(NotRegular::CharDevice)),
            "{e}"
        );
        assert!(e
            .to_string()
            .contains("/dev/zero: the particle file is a character device"));
        let d = tmpdir("dir");
        let e = read(&d, Kind::Mesh).unwrap_err();
        assert!(
            matches!(e.reason, InputReason::NotRegular(NotRegular::Directory)),
            "{e}"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }

    pub fn a_socket_is_named_as_one() {
        let d = tmpdir("socket");
        let p = d.join("s.csv");
        let _listener = std::os::unix::net::UnixListener::bind(&p).unwrap();
        let e = read(&p, Kind::Particles).unwrap_err();
        assert!(
            matches!(e.reason, InputReason::NotRegular(NotRegular::Socket)),
            "{e}"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }

    pub fn over_the_limit_is_refused_before_reading() {
        let d = tmpdir("limit");
        let p = d.join("big.csv");
        std::fs::write(&p, vec![b'1'; 100]).unwrap();
        let e = read_limited(&p, Kind::Particles, 99).unwrap_err();
        assert!(
            matches!(
                e.reason,
                InputReason::TooLarge {
                    size: 100,
                    limit: 99
                }
            ),
            "{e}"
        );
        assert_eq!(read_limited(&p, Kind::Particles, 100).unwrap().len(), 100);
        // a file whose size is not reported (as those of /proc) is read up to the limit only
        let e = read_limited(Path::new("/proc/self/maps"), Kind::Text, 1).unwrap_err();
        assert!(matches!(e.reason, InputReason::TooLarge { .. }), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    pub fn missing_file_and_bad_text_are_typed() {
        let e = read(Path::new("/nonexistent/x.toml"), Kind::Scene).unwrap_err();
        assert!(e.is_not_found());
        let msg = e.to_string();
        // the OS's reason appears once
        assert_eq!(msg.matches("No such file").count(), 1, "{msg}");
        let d = tmpdir("utf8");
        let p = d.join("bad.toml");
        std::fs::write(&p, b"ab\xffcd").unwrap();
        let e = read_to_string(&p, Kind::Scene).unwrap_err();
        assert!(
            matches!(e.reason, InputReason::NotUtf8 { offset: 2 }),
            "{e}"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }
}
