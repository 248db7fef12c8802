//! Atomic file replacement: every output of coulomb is written to a temporary file in the
//! destination's own folder, flushed to disk, then renamed over the destination. A failed
//! write (full disk, quota, permissions, interruption) leaves the destination as it was —
//! an input is never truncated, an older output never half-overwritten.
//!
//! Only regular files are ever replaced. A destination that exists and is anything else — a
//! directory, a character or block device (`/dev/null`, `/dev/full`, a disk), a FIFO, a
//! socket — is refused with [`Refused`] (wrapped in an [`std::io::Error`] of kind
//! `InvalidInput`; [`refusal`] finds it again): renaming a file over a device node would
//! replace the node itself, which as root on `/dev/null` breaks the machine. Writing *through*
//! such a destination (`--output /dev/stdout`) is not supported either: a write that cannot be
//! atomic is not offered under the name of one.
//!
//! Symbolic links are resolved. A link to a regular file is kept: the resolved target is
//! replaced atomically (temporary file in the target's folder, rename over the target), so the
//! link still points at the new content. A link to a non-regular file is refused like that
//! file. A dangling link (its target does not exist) or one that cannot be resolved (a loop,
//! a folder without search permission) is refused too: writing through it would create a file
//! at a place the user never named (possibly in another folder, or one left by another user),
//! and replacing the link by a file would silently break what it was for; either surprises, so
//! the user is asked to remove the link or name the target.
//!
//! The destination is checked before a long run ([`check_writable`]) and again at write time
//! ([`write()`], [`replace`]), the second time just before the rename, so the window in which
//! another process could put a device in its place is the rename itself.

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// What an existing destination is, when it is not a regular file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum NotRegular {
    /// a directory
    Directory,
    /// a character device (`/dev/null`, `/dev/full`, a terminal)
    CharDevice,
    /// a block device (a disk, a partition)
    BlockDevice,
    /// a FIFO (named pipe)
    Fifo,
    /// a Unix domain socket
    Socket,
    /// a symbolic link whose target does not exist
    DanglingSymlink,
    /// a symbolic link that cannot be resolved (loop, no permission): the OS's reason
    UnresolvableSymlink(String),
    /// a symbolic link planted where a file inside an output folder goes: files that coulomb
    /// names inside an output folder are never written through a link
    /// (`coulomb_granular::output_dir`)
    Symlink,
    /// a file of a kind not listed above
    Other,
}

impl fmt::Display for NotRegular {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NotRegular::Directory => write!(f, "a directory"),
            NotRegular::CharDevice => write!(f, "a character device"),
            NotRegular::BlockDevice => write!(f, "a block device"),
            NotRegular::Fifo => write!(f, "a FIFO (named pipe)"),
            NotRegular::Socket => write!(f, "a socket"),
            NotRegular::DanglingSymlink => {
                write!(f, "a dangling symbolic link (its target does not exist)")
            }
            NotRegular::UnresolvableSymlink(why) => {
                write!(f, "a symbolic link that cannot be resolved ({why})")
            }
            NotRegular::Symlink => write!(f, "a symbolic link"),
            NotRegular::Other => write!(f, "a special file"),
        }
    }
}

impl NotRegular {
    /// The kind of `file_type`, None for a regular file (or a symbolic link, resolved by the
    /// caller).
    pub(crate) fn of(file_type: std::fs::FileType) -> Option<Self> {
        if file_type.is_file() || file_type.is_symlink() {
            return None;
        }
        if file_type.is_dir() {
            return Some(NotRegular::Directory);
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            if file_type.is_char_device() {
                return Some(NotRegular::CharDevice);
            }
            if file_type.is_block_device() {
                return Some(NotRegular::BlockDevice);
            }
            if file_type.is_fifo() {
                return Some(NotRegular::Fifo);
            }
            if file_type.is_socket() {
                return Some(NotRegular::Socket);
            }
        }
        Some(NotRegular::Other)
    }
}

/// An output destination that exists and is not a regular file (see the module doc): nothing
/// was written and the destination is untouched.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refused {
    /// the path as given
    pub path: PathBuf,
    /// the target of a symbolic link `path` (as far as it could be read), None when `path`
    /// is not a link
    pub link_to: Option<PathBuf>,
    /// what is there
    pub kind: NotRegular,
}

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "output path refused: {}", self.path.display())?;
        match (&self.link_to, &self.kind) {
            (to, NotRegular::Symlink) => write!(
                f,
                " is a symbolic link{}; coulomb does not write through links inside an output folder: remove it or choose another folder",
                to.as_ref()
                    .map(|t| format!(" to {}", t.display()))
                    .unwrap_or_default()
            ),
            (Some(to), NotRegular::DanglingSymlink | NotRegular::UnresolvableSymlink(_)) => write!(
                f,
                " is {} pointing to {}; remove the link or name the target",
                self.kind,
                to.display()
            ),
            (Some(to), kind) => write!(
                f,
                " is a symbolic link to {}, {kind}, not a regular file",
                to.display()
            ),
            (None, NotRegular::Directory) => {
                write!(f, " is a directory, expected a file name")
            }
            (None, kind) => write!(
                f,
                " is {kind}, not a regular file; coulomb replaces regular files only"
            ),
        }
    }
}

impl std::error::Error for Refused {}

impl From<Refused> for std::io::Error {
    fn from(r: Refused) -> Self {
        std::io::Error::new(std::io::ErrorKind::InvalidInput, r)
    }
}

/// The [`Refused`] inside `e`, when `e` is a refusal of [`write()`], [`replace`],
/// [`check_writable`] or [`destination`].
pub fn refusal(e: &std::io::Error) -> Option<&Refused> {
    e.get_ref()
        .and_then(|inner| inner.downcast_ref::<Refused>())
}

/// The file that writing to `path` replaces: `path` itself when nothing is there or when it is
/// a regular file; the resolved target (absolute, every link followed) when `path` is a
/// symbolic link to a regular file. A [`Refused`] error when `path` exists and is (or links
/// to) anything else, or is a dangling or unresolvable link; other I/O errors (e.g. no
/// permission to look at `path`) as they come.
pub fn destination(path: &Path) -> std::io::Result<PathBuf> {
    let refuse = |link_to: Option<PathBuf>, kind| -> std::io::Error {
        Refused {
            path: path.to_path_buf(),
            link_to,
            kind,
        }
        .into()
    };
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(path.to_path_buf()),
        Err(e) => return Err(e),
    };
    if !meta.file_type().is_symlink() {
        return match NotRegular::of(meta.file_type()) {
            None => Ok(path.to_path_buf()),
            Some(kind) => Err(refuse(None, kind)),
        };
    }
    let link_to = std::fs::read_link(path).ok();
    let target = match std::fs::canonicalize(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(refuse(link_to, NotRegular::DanglingSymlink))
        }
        Err(e) => {
            return Err(refuse(
                link_to,
                NotRegular::UnresolvableSymlink(e.to_string()),
            ))
        }
    };
    let target_meta = std::fs::metadata(&target)?;
    match NotRegular::of(target_meta.file_type()) {
        None => Ok(target),
        Some(kind) => Err(refuse(Some(target), kind)),
    }
}

/// The last look before a rename over `dest` (a path from [`destination`]): nothing there, or
/// a regular file (not a link: a link that appeared since is refused as well).
fn recheck(path: &Path, dest: &Path) -> std::io::Result<()> {
    match std::fs::symlink_metadata(dest) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e),
        Ok(m) if m.file_type().is_file() => Ok(()),
        Ok(m) => Err(Refused {
            path: path.to_path_buf(),
            link_to: (dest != path).then(|| dest.to_path_buf()),
            kind: NotRegular::of(m.file_type()).unwrap_or(NotRegular::DanglingSymlink),
        }
        .into()),
    }
}

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

/// Writes `bytes` to `path` atomically: temporary file in the folder of the file replaced
/// ([`destination`]: `path`, or the target of a symbolic link to a regular file), `sync_all`,
/// rename. On any error the temporary file is removed and `path` is untouched. A `path` that
/// is not a regular file (directory, device, FIFO, socket, dangling link) is refused with
/// [`Refused`] before anything is written.
pub fn write(path: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> std::io::Result<()> {
    let (path, bytes) = (path.as_ref(), bytes.as_ref());
    let dest = destination(path)?;
    remove_stale_temps_once(&dest);
    let tmp = temp_name(&dest);
    let result = (|| {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        recheck(path, &dest)?;
        std::fs::rename(&tmp, &dest)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// The process id in a temporary name of [`temp_name`] (`.NAME.tmp-PID-K`), `None` for any
/// other name.
fn temp_pid(file_name: &str) -> Option<u32> {
    let rest = file_name.strip_prefix('.')?;
    let at = rest.rfind(".tmp-")?;
    let (pid, k) = rest[at + 5..].split_once('-')?;
    if pid.is_empty() || k.is_empty() || !k.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    pid.parse()
        .ok()
        .filter(|_| pid.bytes().all(|b| b.is_ascii_digit()))
}

/// Removes from `dir` the temporary files of [`write()`] left by processes that no longer run
/// (a `kill -9` or a power cut between the creation and the rename; every error path of
/// [`write()`] removes its own). A file is removed only when its name is exactly a temporary
/// name (`.NAME.tmp-PID-K`), it is a regular file, and no process PID exists (Linux: no
/// `/proc/PID`; elsewhere nothing is removed). A PID reused by another process keeps the file
/// (the safe side). Returns the number removed.
pub fn remove_stale_temps(dir: &Path) -> usize {
    let proc_fs = Path::new("/proc/self").exists();
    if !proc_fs {
        return 0;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_pid) else {
            continue;
        };
        if pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists() {
            continue;
        }
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if is_file && std::fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// [`remove_stale_temps`] in the folder of `dest`, once per folder and process (the first
/// write there), so that a run writing thousands of frames reads its folder once.
fn remove_stale_temps_once(dest: &Path) {
    static CLEANED: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
    let dir = match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let Ok(mut cleaned) = CLEANED.lock() else {
        return;
    };
    if cleaned.contains(&dir) {
        return;
    }
    cleaned.push(dir.clone());
    drop(cleaned);
    remove_stale_temps(&dir);
}

/// Renames `tmp`, a finished file written by someone else (e.g. a plotting backend) next to
/// `path`'s [`destination`], over that destination after flushing it to disk; the same
/// refusals as [`write()`]. On error `tmp` is left for the caller to remove.
pub fn replace(tmp: &Path, path: &Path) -> std::io::Result<()> {
    let dest = destination(path)?;
    std::fs::File::open(tmp)?.sync_all()?;
    recheck(path, &dest)?;
    std::fs::rename(tmp, &dest)
}

/// Whether `path` could be written now: it is not a directory, device, FIFO, socket or
/// dangling link ([`destination`]), and a file can be created in the folder of the file it
/// would replace (a temporary file is created and removed; `path` itself is not touched).
/// Lets a long command refuse an unwritable output before it starts rather than after.
pub fn check_writable(path: &Path) -> std::io::Result<()> {
    let dest = destination(path)?;
    let tmp = temp_name(&dest);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)?;
    std::fs::remove_file(&tmp)
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;

    /// The temporary files of a dead process are removed by the first write into their
    /// folder; those of a live process (this one, PID 1), other dot files and a directory of
    /// a temporary name are kept (issue 55: stale `.tmp-PID` files were never removed).
    #[cfg(target_os = "linux")]
    pub fn stale_temporaries_of_dead_processes_are_removed() {
        let dir = scratch("stale");
        // a PID above the kernel's maximum (4194304) never runs
        let dead = dir.join(".stats.csv.tmp-4999999-3");
        let live = dir.join(format!(".x.tmp-{}-0", std::process::id()));
        let init = dir.join(".y.tmp-1-0");
        let other = dir.join(".stats.csv.tmp-abc-1");
        let folder = dir.join(".z.tmp-4999999-1");
        for p in [&dead, &live, &init, &other] {
            std::fs::write(p, b"partial").unwrap();
        }
        std::fs::create_dir(&folder).unwrap();
        assert_eq!(temp_pid(".stats.csv.tmp-4999999-3"), Some(4_999_999));
        assert_eq!(temp_pid(".stats.csv.tmp-abc-1"), None);
        assert_eq!(temp_pid("stats.csv"), None);
        write(dir.join("out.txt"), b"x").unwrap();
        assert!(!dead.exists());
        for p in [&live, &init, &other, &folder] {
            assert!(p.exists(), "{}", p.display());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn scratch(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("coulomb-atomic-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    pub fn atomic_write_replaces_and_leaves_no_temporary() {
        let dir = scratch("plain");
        let p = dir.join("a.txt");
        write(&p, b"one").unwrap();
        write(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        // a directory is refused and stays a directory
        let e = write(&dir, b"x").unwrap_err();
        assert_eq!(refusal(&e).unwrap().kind, NotRegular::Directory);
        assert!(dir.is_dir());
        // a folder that does not exist: an error (not a refusal), nothing created
        let e = write(dir.join("no/such.txt"), b"x").unwrap_err();
        assert!(refusal(&e).is_none());
        assert!(check_writable(&p).is_ok());
        assert!(check_writable(&dir.join("no/such.txt")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Asserts that `path` is refused as `kind` by every entry point, that the message names
    /// the path, and that nothing was left in `dir` but `keep` entries.
    fn assert_refused(dir: &Path, path: &Path, kind: &NotRegular, keep: usize) {
        for e in [
            write(path, b"x").unwrap_err(),
            check_writable(path).unwrap_err(),
            destination(path).unwrap_err(),
        ] {
            let r = refusal(&e).unwrap_or_else(|| panic!("{} not refused: {e}", path.display()));
            assert_eq!(&r.kind, kind);
            assert_eq!(r.path, path);
            assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
            let msg = e.to_string();
            assert!(msg.starts_with("output path refused: "), "{msg}");
            assert!(msg.contains(&path.display().to_string()), "{msg}");
        }
        assert_eq!(std::fs::read_dir(dir).unwrap().count(), keep);
    }

    #[cfg(unix)]
    pub fn fifos_and_dangling_links_are_refused_and_left_as_they_are() {
        use std::os::unix::fs::FileTypeExt;
        let dir = scratch("fifo");
        let fifo = dir.join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|s| s.success()) {
            println!("skipped: mkfifo failed");
            return;
        }
        assert_refused(&dir, &fifo, &NotRegular::Fifo, 1);
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
        // a link to the FIFO: refused as the FIFO, the link kept
        let to_fifo = dir.join("to-pipe");
        std::os::unix::fs::symlink(&fifo, &to_fifo).unwrap();
        assert_refused(&dir, &to_fifo, &NotRegular::Fifo, 2);
        let e = write(&to_fifo, b"x").unwrap_err();
        assert!(e.to_string().contains("symbolic link to"), "{e}");
        // a dangling link: refused, still a link to the same (missing) place
        let dangling = dir.join("dangling");
        std::os::unix::fs::symlink(dir.join("missing/target"), &dangling).unwrap();
        assert_refused(&dir, &dangling, &NotRegular::DanglingSymlink, 3);
        assert_eq!(
            std::fs::read_link(&dangling).unwrap(),
            dir.join("missing/target")
        );
        // a loop: refused as unresolvable
        let a = dir.join("loop-a");
        let b = dir.join("loop-b");
        std::os::unix::fs::symlink(&b, &a).unwrap();
        std::os::unix::fs::symlink(&a, &b).unwrap();
        let e = write(&a, b"x").unwrap_err();
        assert!(
            matches!(
                refusal(&e).map(|r| &r.kind),
                Some(NotRegular::UnresolvableSymlink(_))
            ),
            "{e}"
        );
        // a link to a directory: refused as a directory
        let to_dir = dir.join("to-dir");
        std::fs::create_dir(dir.join("sub")).unwrap();
        std::os::unix::fs::symlink(dir.join("sub"), &to_dir).unwrap();
        assert_refused(&dir, &to_dir, &NotRegular::Directory, 7);
        assert_eq!(std::fs::read_dir(dir.join("sub")).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    pub fn a_link_to_a_regular_file_is_kept_and_its_target_replaced() {
        let dir = scratch("link");
        std::fs::create_dir(dir.join("data")).unwrap();
        let target = dir.join("data/out.txt");
        std::fs::write(&target, b"old").unwrap();
        let link = dir.join("out.txt");
        std::os::unix::fs::symlink("data/out.txt", &link).unwrap();
        check_writable(&link).unwrap();
        assert_eq!(
            destination(&link).unwrap(),
            std::fs::canonicalize(&target).unwrap()
        );
        write(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(
            std::fs::read_link(&link).unwrap(),
            Path::new("data/out.txt")
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        // no temporary left beside the link or the target
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
        assert_eq!(std::fs::read_dir(dir.join("data")).unwrap().count(), 1);
        // replace() of a staged file goes to the target too
        let tmp = temp_name(&destination(&link).unwrap());
        std::fs::write(&tmp, b"staged").unwrap();
        replace(&tmp, &link).unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"staged");
        assert!(!tmp.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A character device made with `mknod` in a scratch folder (never a real one in /dev):
    /// refused by every entry point, and still a character device with the same numbers.
    #[cfg(unix)]
    pub fn a_device_node_is_refused_and_stays_a_device() {
        use std::os::unix::fs::{FileTypeExt, MetadataExt};
        let dir = scratch("dev");
        let dev = dir.join("full");
        // 1,7 are the numbers of /dev/full; the node here is a new one
        let made = std::process::Command::new("mknod")
            .arg(&dev)
            .args(["c", "1", "7"])
            .output();
        match made {
            Ok(out) if out.status.success() => {}
            Ok(out) => {
                println!(
                    "skipped: mknod failed (needs root or CAP_MKNOD): {}",
                    String::from_utf8_lossy(&out.stderr).trim()
                );
                return;
            }
            Err(e) => {
                println!("skipped: mknod not available: {e}");
                return;
            }
        }
        let rdev = std::fs::symlink_metadata(&dev).unwrap().rdev();
        assert_refused(&dir, &dev, &NotRegular::CharDevice, 1);
        let link = dir.join("link-to-dev");
        std::os::unix::fs::symlink(&dev, &link).unwrap();
        assert_refused(&dir, &link, &NotRegular::CharDevice, 2);
        let tmp = dir.join("staged");
        std::fs::write(&tmp, b"x").unwrap();
        let e = replace(&tmp, &dev).unwrap_err();
        assert_eq!(refusal(&e).unwrap().kind, NotRegular::CharDevice);
        let meta = std::fs::symlink_metadata(&dev).unwrap();
        assert!(meta.file_type().is_char_device());
        assert_eq!(meta.rdev(), rdev);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    pub fn a_socket_is_refused() {
        let dir = scratch("sock");
        let path = dir.join("s");
        let _listener = std::os::unix::net::UnixListener::bind(&path).unwrap();
        assert_refused(&dir, &path, &NotRegular::Socket, 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
