//! The one output layer of a run (sphere and rigid runs, the CLI and Python): an output
//! folder opened once as a directory handle, every file of it written relative to that
//! handle, without following links, and a run identity that keeps a restart from mixing its
//! statistics with those of another run.
//!
//! # Links and special files inside an output folder: refused
//!
//! The folder the user names (`--output DIR`, `write_frames(dir)`) is opened once (a link
//! there is followed: the user named it). The files coulomb names inside it (`stats.csv`,
//! `stats.json`, `summary.json`, `checkpoint.h5`, `run.json`, the `.pvd` collections and the
//! `frames/` folder with its `.vtp` files) are created relative to that handle:
//! - each file is written to a temporary file opened with `O_CREAT | O_EXCL | O_NOFOLLOW`
//!   in the same folder, flushed, and renamed over its name (`renameat`): a rename replaces a
//!   name, it never writes through a link;
//! - a name that is a symbolic link, a directory, a FIFO, a device or a socket is **refused**
//!   ([`coulomb::atomic::Refused`], exit status 2), never replaced and never written through:
//!   a link planted in an output folder is not something the user named;
//! - `frames/` is opened with `O_NOFOLLOW | O_DIRECTORY`: a planted `frames` link is refused;
//! - [`OutputDir::check`] looks at every name a run will write *before* the run computes
//!   anything (and before `frames/` is created), so a refusal leaves nothing behind.
//!
//! # Inputs are never outputs
//!
//! [`OutputDir::refuse_inputs`] compares the device and inode of every input of the run (the
//! scene file and the files it reads, a particle file, a checkpoint being restarted) with
//! every file the run would replace in the folder: a match is refused (exit status 2). The
//! one exception is the checkpoint a restart continues: `checkpoint.h5` of the folder is
//! replaced by the continued run's later checkpoint (it was read whole before).
//!
//! # Restarts append only to their own run's files
//!
//! `run.json` holds the kind of run (`spheres`, `rigid`), the step of the folder's first
//! statistics row, and the CRC-32 and length of the last two checkpoints the run wrote. A
//! restart into a folder that holds statistics continues them only when `run.json` is of the
//! same kind and lists the checkpoint being restarted (the rows after its step, written by the
//! same run before a `kill -9`, are dropped) and the rows kept are contiguous up to it; any
//! other folder with statistics is **refused** (exit status 2, nothing written): choose an
//! empty folder. A folder without statistics gets fresh files.

use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The name of the run-identity file of an output folder.
pub const RUN_FILE: &str = "run.json";
/// The statistics, summary and checkpoint files of a run's output folder.
pub const RUN_FILES: [&str; 5] = [
    "stats.csv",
    "stats.json",
    "summary.json",
    "checkpoint.h5",
    RUN_FILE,
];

/// An output folder, opened once (see the module doc).
#[derive(Debug)]
pub struct OutputDir {
    path: PathBuf,
    #[cfg(unix)]
    root: std::os::fd::OwnedFd,
    #[cfg(unix)]
    frames: Option<std::os::fd::OwnedFd>,
}

fn refused(
    path: PathBuf,
    link_to: Option<PathBuf>,
    kind: coulomb::atomic::NotRegular,
) -> io::Error {
    coulomb::atomic::Refused {
        path,
        link_to,
        kind,
    }
    .into()
}

/// What is at a name: nothing, a regular file, or something refused.
enum Found {
    Nothing,
    File { dev: u64, ino: u64 },
    Directory,
    Other(coulomb::atomic::NotRegular),
}

#[cfg(unix)]
mod sys {
    use std::ffi::CString;
    use std::io;
    use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};

    pub fn cstr(name: &str) -> io::Result<CString> {
        CString::new(name).map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "NUL in name"))
    }

    pub fn stat_nofollow(dir: RawFd, name: &str) -> io::Result<Option<libc::stat>> {
        let c = cstr(name)?;
        let mut st: libc::stat = unsafe { std::mem::zeroed() };
        // SAFETY: valid fd, NUL-terminated name and a zeroed stat buffer
        let r = unsafe { libc::fstatat(dir, c.as_ptr(), &mut st, libc::AT_SYMLINK_NOFOLLOW) };
        if r == 0 {
            return Ok(Some(st));
        }
        let e = io::Error::last_os_error();
        if e.kind() == io::ErrorKind::NotFound {
            Ok(None)
        } else {
            Err(e)
        }
    }

    pub fn open_at(dir: RawFd, name: &str, flags: i32, mode: u32) -> io::Result<OwnedFd> {
        let c = cstr(name)?;
        // SAFETY: valid fd and NUL-terminated name; the returned fd is owned here
        let fd = unsafe {
            libc::openat(
                dir,
                c.as_ptr(),
                flags | libc::O_CLOEXEC | libc::O_NOFOLLOW,
                mode as libc::c_uint,
            )
        };
        if fd < 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: fd is a new descriptor that nothing else owns
        Ok(unsafe { OwnedFd::from_raw_fd(fd) })
    }

    pub fn mkdir_at(dir: RawFd, name: &str) -> io::Result<()> {
        let c = cstr(name)?;
        // SAFETY: valid fd and NUL-terminated name
        if unsafe { libc::mkdirat(dir, c.as_ptr(), 0o777) } == 0 {
            return Ok(());
        }
        let e = io::Error::last_os_error();
        if e.kind() == io::ErrorKind::AlreadyExists {
            Ok(())
        } else {
            Err(e)
        }
    }

    pub fn rename_at(dir: RawFd, from: &str, to: &str) -> io::Result<()> {
        let (a, b) = (cstr(from)?, cstr(to)?);
        // SAFETY: valid fd and NUL-terminated names
        if unsafe { libc::renameat(dir, a.as_ptr(), dir, b.as_ptr()) } == 0 {
            Ok(())
        } else {
            Err(io::Error::last_os_error())
        }
    }

    pub fn unlink_at(dir: RawFd, name: &str) {
        if let Ok(c) = cstr(name) {
            // SAFETY: valid fd and NUL-terminated name
            unsafe { libc::unlinkat(dir, c.as_ptr(), 0) };
        }
    }

    pub fn raw(fd: &OwnedFd) -> RawFd {
        fd.as_raw_fd()
    }
}

impl OutputDir {
    /// Opens the folder `path`, creating it (and its parents) when missing. A `path` that
    /// exists and is not a directory (or a link to one) is refused.
    pub fn open(path: &Path) -> io::Result<Self> {
        match std::fs::metadata(path) {
            Ok(m) if !m.is_dir() => {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!("{} exists and is not a folder", path.display()),
                ))
            }
            Ok(_) => {}
            Err(e) if e.kind() == io::ErrorKind::NotFound => std::fs::create_dir_all(path)?,
            Err(e) => return Err(e),
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            let f = std::fs::OpenOptions::new()
                .read(true)
                .custom_flags(libc::O_DIRECTORY | libc::O_CLOEXEC)
                .open(path)?;
            Ok(Self {
                path: path.to_path_buf(),
                root: f.into(),
                frames: None,
            })
        }
        #[cfg(not(unix))]
        Ok(Self {
            path: path.to_path_buf(),
        })
    }

    /// The folder's path as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `rel` (`name` or `frames/name`) as a path for messages.
    pub fn display_path(&self, rel: &str) -> PathBuf {
        self.path.join(rel)
    }

    #[cfg(unix)]
    fn split<'a>(&self, rel: &'a str) -> io::Result<(std::os::fd::RawFd, &'a str)> {
        match rel.split_once('/') {
            None => Ok((sys::raw(&self.root), rel)),
            Some(("frames", name)) if !name.contains('/') => match &self.frames {
                Some(fd) => Ok((sys::raw(fd), name)),
                None => Err(io::Error::other(
                    "the frames/ folder was not opened (OutputDir::open_frames)",
                )),
            },
            _ => Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{rel}: not a name of an output folder"),
            )),
        }
    }

    fn found(&self, rel: &str) -> io::Result<Found> {
        use coulomb::atomic::NotRegular as K;
        #[cfg(unix)]
        {
            let (dir, name) = match rel.split_once('/') {
                Some(("frames", _)) if self.frames.is_none() => {
                    // frames/ not opened: look through the root without following links
                    match self.found("frames")? {
                        Found::Directory => {}
                        Found::Nothing => return Ok(Found::Nothing),
                        _ => return Ok(Found::Other(K::Symlink)),
                    }
                    let f = sys::open_at(
                        sys::raw(&self.root),
                        "frames",
                        libc::O_RDONLY | libc::O_DIRECTORY,
                        0,
                    )?;
                    let name = &rel["frames/".len()..];
                    let st = sys::stat_nofollow(sys::raw(&f), name)?;
                    return Ok(Self::classify(st));
                }
                _ => self.split(rel)?,
            };
            Ok(Self::classify(sys::stat_nofollow(dir, name)?))
        }
        #[cfg(not(unix))]
        {
            match std::fs::symlink_metadata(self.path.join(rel)) {
                Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(Found::Nothing),
                Err(e) => Err(e),
                Ok(m) if m.file_type().is_symlink() => Ok(Found::Other(K::Symlink)),
                Ok(m) if m.is_dir() => Ok(Found::Directory),
                Ok(m) if m.is_file() => Ok(Found::File { dev: 0, ino: 0 }),
                Ok(_) => Ok(Found::Other(K::Other)),
            }
        }
    }

    #[cfg(unix)]
    // st_dev and st_ino are u64 on Linux, not on every Unix
    #[allow(clippy::unnecessary_cast)]
    fn classify(st: Option<libc::stat>) -> Found {
        use coulomb::atomic::NotRegular as K;
        let Some(st) = st else {
            return Found::Nothing;
        };
        match st.st_mode & libc::S_IFMT {
            libc::S_IFREG => Found::File {
                dev: st.st_dev as u64,
                ino: st.st_ino as u64,
            },
            libc::S_IFDIR => Found::Directory,
            libc::S_IFLNK => Found::Other(K::Symlink),
            libc::S_IFIFO => Found::Other(K::Fifo),
            libc::S_IFCHR => Found::Other(K::CharDevice),
            libc::S_IFBLK => Found::Other(K::BlockDevice),
            libc::S_IFSOCK => Found::Other(K::Socket),
            _ => Found::Other(K::Other),
        }
    }

    fn refusal(&self, rel: &str, kind: coulomb::atomic::NotRegular) -> io::Error {
        let path = self.display_path(rel);
        let link_to = std::fs::read_link(&path).ok();
        refused(path, link_to, kind)
    }

    /// Checks that each of `names` (`name` or `frames/name`) is absent or a regular file,
    /// and that `frames` is absent or a folder (not a link): the refusal of the first that
    /// is not. Nothing is created or written.
    pub fn check(&self, names: &[&str]) -> io::Result<()> {
        for rel in names {
            match self.found(rel)? {
                Found::Nothing | Found::File { .. } => {}
                Found::Directory if *rel == "frames" => {}
                Found::Directory => {
                    return Err(self.refusal(rel, coulomb::atomic::NotRegular::Directory))
                }
                Found::Other(kind) => return Err(self.refusal(rel, kind)),
            }
        }
        Ok(())
    }

    /// Refuses every input among `inputs` that is one of the files `names` of the folder
    /// (same device and inode), or a file of `frames/` when `frames` is among `names`.
    /// `allowed` is an input that may be replaced (the checkpoint that a restart continues,
    /// when it is the folder's `checkpoint.h5`).
    pub fn refuse_inputs(
        &self,
        names: &[&str],
        inputs: &[&Path],
        allowed: Option<(&str, &Path)>,
    ) -> io::Result<()> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            let ids: Vec<(&Path, u64, u64)> = inputs
                .iter()
                .filter_map(|p| std::fs::metadata(p).ok().map(|m| (*p, m.dev(), m.ino())))
                .collect();
            let frames_id = match self.found("frames")? {
                Found::Directory if names.contains(&"frames") => {
                    std::fs::metadata(self.path.join("frames"))
                        .ok()
                        .map(|m| (m.dev(), m.ino()))
                }
                _ => None,
            };
            for (input, dev, ino) in &ids {
                for rel in names {
                    if let Found::File { dev: d, ino: i } = self.found(rel)? {
                        let is_allowed = allowed.is_some_and(|(name, p)| {
                            name == *rel
                                && std::fs::metadata(p).is_ok_and(|m| m.dev() == d && m.ino() == i)
                        });
                        if (d, i) == (*dev, *ino) && !is_allowed {
                            return Err(io::Error::new(
                                io::ErrorKind::InvalidInput,
                                format!(
                                    "{} is an input of this run ({}); refusing to write over it: choose another output folder",
                                    self.display_path(rel).display(),
                                    input.display()
                                ),
                            ));
                        }
                    }
                }
                // an input inside frames/ (any .vtp there may be replaced)
                if let (Some(fid), Some(parent)) = (frames_id, input.parent()) {
                    let parent = if parent.as_os_str().is_empty() {
                        Path::new(".")
                    } else {
                        parent
                    };
                    if std::fs::metadata(parent).is_ok_and(|m| (m.dev(), m.ino()) == fid) {
                        return Err(io::Error::new(
                            io::ErrorKind::InvalidInput,
                            format!(
                                "{} is an input of this run inside {}, where frames are written; refusing: choose another output folder",
                                input.display(),
                                self.display_path("frames").display()
                            ),
                        ));
                    }
                }
            }
        }
        #[cfg(not(unix))]
        let _ = (names, inputs, allowed);
        Ok(())
    }

    /// Creates `frames/` when missing and opens it without following a link (a link there
    /// is refused).
    pub fn open_frames(&mut self) -> io::Result<()> {
        #[cfg(unix)]
        {
            if self.frames.is_some() {
                return Ok(());
            }
            self.check(&["frames"])?;
            sys::mkdir_at(sys::raw(&self.root), "frames")?;
            let fd = sys::open_at(
                sys::raw(&self.root),
                "frames",
                libc::O_RDONLY | libc::O_DIRECTORY,
                0,
            )
            .map_err(|e| match e.raw_os_error() {
                Some(libc::ELOOP) | Some(libc::ENOTDIR) => {
                    self.refusal("frames", coulomb::atomic::NotRegular::Symlink)
                }
                _ => e,
            })?;
            self.frames = Some(fd);
            Ok(())
        }
        #[cfg(not(unix))]
        {
            self.check(&["frames"])?;
            std::fs::create_dir_all(self.path.join("frames"))
        }
    }

    /// Whether `rel` is a regular file now.
    pub fn is_file(&self, rel: &str) -> bool {
        matches!(self.found(rel), Ok(Found::File { .. }))
    }

    /// Replaces `rel` (`name` or `frames/name`) by `bytes` atomically: a temporary file
    /// created in the same folder without following links, flushed, renamed over `rel`. A
    /// `rel` that is a link, folder or special file is refused and left as it is.
    pub fn write(&self, rel: &str, bytes: &[u8]) -> io::Result<()> {
        self.check(&[rel])?;
        let name = rel.rsplit('/').next().unwrap_or(rel);
        let tmp = format!(
            ".{name}.tmp-{}-{}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        );
        #[cfg(unix)]
        {
            let (dir, name) = self.split(rel)?;
            let result = (|| {
                let fd = sys::open_at(
                    dir,
                    &tmp,
                    libc::O_WRONLY | libc::O_CREAT | libc::O_EXCL,
                    0o666,
                )?;
                let mut f = File::from(fd);
                f.write_all(bytes)?;
                f.sync_all()?;
                drop(f);
                // the last look before the rename: a link or special file put there since
                // the check is refused (the rename itself would only replace the name)
                self.check(&[rel])?;
                sys::rename_at(dir, &tmp, name)
            })();
            if result.is_err() {
                sys::unlink_at(dir, &tmp);
            }
            result
        }
        #[cfg(not(unix))]
        {
            let tmp_rel = match rel.rsplit_once('/') {
                Some((d, _)) => format!("{d}/{tmp}"),
                None => tmp,
            };
            let tmp_path = self.path.join(&tmp_rel);
            let result = (|| {
                let mut f = std::fs::OpenOptions::new()
                    .write(true)
                    .create_new(true)
                    .open(&tmp_path)?;
                f.write_all(bytes)?;
                f.sync_all()?;
                drop(f);
                self.check(&[rel])?;
                std::fs::rename(&tmp_path, self.path.join(rel))
            })();
            if result.is_err() {
                let _ = std::fs::remove_file(&tmp_path);
            }
            result
        }
    }

    /// The content of the regular file `rel`, None when absent; a link or special file is
    /// refused (never read through).
    pub fn read(&self, rel: &str) -> io::Result<Option<Vec<u8>>> {
        use std::io::Read as _;
        match self.found(rel)? {
            Found::Nothing => return Ok(None),
            Found::File { .. } => {}
            Found::Directory => {
                return Err(self.refusal(rel, coulomb::atomic::NotRegular::Directory))
            }
            Found::Other(k) => return Err(self.refusal(rel, k)),
        }
        let mut f = self.open_existing(rel, false)?;
        let mut out = Vec::new();
        f.read_to_end(&mut out)?;
        Ok(Some(out))
    }

    /// `rel`, a regular file, opened for reading, or for appending when `append`, without
    /// following a link.
    fn open_existing(&self, rel: &str, append: bool) -> io::Result<File> {
        #[cfg(unix)]
        {
            let (dir, name) = self.split(rel)?;
            let flags = if append {
                libc::O_WRONLY | libc::O_APPEND
            } else {
                libc::O_RDONLY
            } | libc::O_NONBLOCK;
            let f = File::from(sys::open_at(dir, name, flags, 0)?);
            if !f.metadata()?.is_file() {
                return Err(self.refusal(rel, coulomb::atomic::NotRegular::Other));
            }
            Ok(f)
        }
        #[cfg(not(unix))]
        {
            std::fs::OpenOptions::new()
                .read(!append)
                .append(append)
                .open(self.path.join(rel))
        }
    }

    /// `rel`, an existing regular file, opened for appending (not through a link).
    pub fn append(&self, rel: &str) -> io::Result<File> {
        self.open_existing(rel, true)
    }
}

/// The kind of a run's outputs (`run.json`): a restart continues only a folder of its own
/// kind (the files' names and statistics columns are the same for both since issue 52).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunKind {
    /// the sphere engine
    Spheres,
    /// the rigid-body engine
    Rigid,
}

/// A checkpoint of a run, by content.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CheckpointId {
    /// the step it stores
    pub step: u64,
    /// CRC-32 of its bytes
    pub crc32: u32,
    /// its length in bytes
    pub bytes: u64,
}

impl CheckpointId {
    /// The identity of a checkpoint's bytes.
    pub fn of(step: u64, bytes: &[u8]) -> Self {
        Self {
            step,
            crc32: crc32fast::hash(bytes),
            bytes: bytes.len() as u64,
        }
    }
}

/// `run.json`: the identity of the run whose statistics an output folder holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunIdentity {
    /// always `"coulomb-run"`
    pub format: String,
    /// the engine
    pub kind: RunKind,
    /// the step of the first statistics row of the folder
    pub first_step: u64,
    /// the last two checkpoints written (oldest first)
    pub checkpoints: Vec<CheckpointId>,
}

/// The statistics files of a run being written into an output folder: `stats.csv` gets one
/// row per step as the run goes (appended and handed to the OS at once, so a run that fails
/// or is killed keeps every completed step's row), `stats.json` is written at the end and on
/// every error path ([`RunOutput::write_json`]).
#[derive(Debug)]
pub struct RunOutput {
    /// the folder (shared with the frame writers)
    pub dir: std::sync::Arc<OutputDir>,
    identity: RunIdentity,
    csv: Option<File>,
    /// the rows of `stats.json` kept from before a restart
    pub old_json: Vec<serde_json::Value>,
}

/// Why a restart may not append to the statistics of a folder.
fn foreign(dir: &Path, why: &str) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "{} holds the statistics of another run ({why}); a restart appends only to its own run's files: choose an empty output folder, or restart from that folder's checkpoint.h5",
            dir.display()
        ),
    )
}

impl RunOutput {
    /// Opens the outputs of a run of `kind` in `dir`: checks every name the run will write
    /// (`names`: the `.pvd` collections, plus [`RUN_FILES`] and `frames`) and refuses the
    /// inputs among them, all before anything is created; then, for a new run
    /// (`restart` None), starts fresh statistics (header `csv_header`); for a restart from
    /// the checkpoint at `restart = (path, step)`, keeps the rows before `step` when the
    /// folder is the checkpoint's run's (see the module doc), else refuses.
    pub fn open(
        path: &Path,
        kind: RunKind,
        names: &[&str],
        inputs: &[&Path],
        restart: Option<(&Path, u64)>,
        csv_header: &str,
    ) -> io::Result<Self> {
        let mut dir = OutputDir::open(path)?;
        let mut all: Vec<&str> = RUN_FILES.to_vec();
        all.extend_from_slice(names);
        all.push("frames");
        dir.check(&all)?;
        dir.refuse_inputs(&all, inputs, restart.map(|(p, _)| ("checkpoint.h5", p)))?;
        let (first_step, csv_rows, old_json) = match restart {
            None => (0, Vec::new(), Vec::new()),
            Some((checkpoint, step)) => Self::continued(&dir, kind, checkpoint, step)?,
        };
        let mut csv = String::from(csv_header);
        csv.push('\n');
        for row in &csv_rows {
            csv.push_str(row);
            csv.push('\n');
        }
        let identity = RunIdentity {
            format: "coulomb-run".into(),
            kind,
            first_step,
            checkpoints: match restart {
                Some((checkpoint, step)) => std::fs::read(checkpoint)
                    .map(|b| vec![CheckpointId::of(step, &b)])
                    .unwrap_or_default(),
                None => Vec::new(),
            },
        };
        dir.open_frames()?;
        dir.write(RUN_FILE, &serde_json::to_vec_pretty(&identity)?)?;
        dir.write("stats.csv", csv.as_bytes())?;
        let file = dir.append("stats.csv")?;
        Ok(Self {
            dir: std::sync::Arc::new(dir),
            identity,
            csv: Some(file),
            old_json,
        })
    }

    /// The rows of the folder's statistics before `step` when the folder is the run of the
    /// checkpoint `checkpoint` (of `kind`), with the step of its first row; no rows when the
    /// folder has no statistics; a refusal otherwise.
    #[allow(clippy::type_complexity)]
    fn continued(
        dir: &OutputDir,
        kind: RunKind,
        checkpoint: &Path,
        step: u64,
    ) -> io::Result<(u64, Vec<String>, Vec<serde_json::Value>)> {
        let csv = dir.read("stats.csv")?;
        let json = dir.read("stats.json")?;
        let run = dir.read(RUN_FILE)?;
        if csv.is_none() && json.is_none() {
            return Ok((step, Vec::new(), Vec::new()));
        }
        let Some(run) = run else {
            return Err(foreign(dir.path(), "it has no run.json"));
        };
        let run: RunIdentity = serde_json::from_slice(&run)
            .map_err(|e| foreign(dir.path(), &format!("its run.json is unreadable: {e}")))?;
        if run.kind != kind {
            return Err(foreign(
                dir.path(),
                &format!(
                    "a {:?} run, this checkpoint is of a {:?} run",
                    run.kind, kind
                )
                .to_lowercase(),
            ));
        }
        let bytes = std::fs::read(checkpoint)?;
        let id = CheckpointId::of(step, &bytes);
        if !run.checkpoints.contains(&id) {
            return Err(foreign(
                dir.path(),
                &format!(
                    "the checkpoint {} of step {step} is not one that run wrote",
                    checkpoint.display()
                ),
            ));
        }
        let step_of = |l: &str| l.split(',').next().and_then(|k| k.parse::<u64>().ok());
        let text = String::from_utf8_lossy(csv.as_deref().unwrap_or_default()).into_owned();
        let rows: Vec<String> = text
            .lines()
            .skip(1)
            .filter(|l| step_of(l).is_some_and(|k| k < step))
            .map(str::to_string)
            .collect();
        let contiguous = rows
            .iter()
            .enumerate()
            .all(|(i, l)| step_of(l) == Some(run.first_step + i as u64));
        if !contiguous || (run.first_step + rows.len() as u64) != step {
            return Err(foreign(
                dir.path(),
                &format!(
                    "its stats.csv does not hold every step from {} to {} (the rows of this run must be contiguous)",
                    run.first_step,
                    step.saturating_sub(1)
                ),
            ));
        }
        let json_rows: Vec<serde_json::Value> = json
            .and_then(|t| serde_json::from_slice::<Vec<serde_json::Value>>(&t).ok())
            .unwrap_or_default()
            .into_iter()
            .filter(|v| {
                v.get("step")
                    .and_then(|k| k.as_u64())
                    .is_some_and(|k| k < step)
            })
            .collect();
        Ok((run.first_step, rows, json_rows))
    }

    /// Appends one row (without its newline) to `stats.csv`, handed to the OS at once; a
    /// row that could not be written whole is cut off again (the file keeps whole rows).
    pub fn row(&mut self, line: &str) -> io::Result<()> {
        if let Some(f) = self.csv.as_mut() {
            let mut l = String::with_capacity(line.len() + 1);
            l.push_str(line);
            l.push('\n');
            let before = f.metadata()?.len();
            if let Err(e) = f.write_all(l.as_bytes()) {
                let _ = f.set_len(before);
                return Err(e);
            }
        }
        Ok(())
    }

    /// Writes `stats.json` (`text`) and flushes `stats.csv` to disk.
    pub fn write_json(&mut self, text: &str) -> io::Result<()> {
        if let Some(f) = self.csv.as_mut() {
            f.sync_all()?;
        }
        self.dir.write("stats.json", text.as_bytes())
    }

    /// `stats.json` of the rows kept from before a restart followed by `rows`: the typed rows
    /// alone when none were kept (the text of a run that was never restarted).
    pub fn json_text<T: Serialize>(&self, rows: &[T]) -> io::Result<String> {
        if self.old_json.is_empty() {
            serde_json::to_string_pretty(rows)
        } else {
            let mut all = self.old_json.clone();
            for r in rows {
                all.push(serde_json::to_value(r)?);
            }
            serde_json::to_string_pretty(&all)
        }
        .map_err(io::Error::other)
    }

    /// Writes the checkpoint `bytes` of step `step` as `checkpoint.h5`, recorded first in
    /// `run.json` (which keeps the last two), so that a restart from it may continue here.
    pub fn checkpoint(&mut self, step: u64, bytes: &[u8]) -> io::Result<()> {
        let id = CheckpointId::of(step, bytes);
        self.identity.checkpoints.push(id);
        let n = self.identity.checkpoints.len();
        if n > 2 {
            self.identity.checkpoints.drain(..n - 2);
        }
        self.dir.write(
            RUN_FILE,
            &serde_json::to_vec_pretty(&self.identity).map_err(io::Error::other)?,
        )?;
        self.dir.write("checkpoint.h5", bytes)
    }
}

#[cfg(all(feature = "unit-tests", unix))]
pub mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("coulomb-outdir-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    pub fn links_planted_in_the_folder_are_refused_not_written_through() {
        let d = scratch("links");
        let victim = d.join("victim.txt");
        std::fs::write(&victim, b"keep").unwrap();
        let out = d.join("out");
        std::fs::create_dir(&out).unwrap();
        std::os::unix::fs::symlink(&victim, out.join("summary.json")).unwrap();
        let dir = OutputDir::open(&out).unwrap();
        let e = dir.write("summary.json", b"x").unwrap_err();
        let r = coulomb::atomic::refusal(&e).expect("a refusal");
        assert_eq!(r.kind, coulomb::atomic::NotRegular::Symlink);
        assert!(e.to_string().contains("symbolic link"), "{e}");
        assert_eq!(std::fs::read(&victim).unwrap(), b"keep");
        assert!(std::fs::symlink_metadata(out.join("summary.json"))
            .unwrap()
            .file_type()
            .is_symlink());
        // a planted frames link: refused, nothing created where it points
        let elsewhere = d.join("elsewhere");
        std::fs::create_dir(&elsewhere).unwrap();
        std::os::unix::fs::symlink(&elsewhere, out.join("frames")).unwrap();
        let mut dir = OutputDir::open(&out).unwrap();
        assert!(dir.check(&["frames"]).is_err());
        assert!(dir.open_frames().is_err());
        assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0);
        // plain files are replaced and no temporary is left
        let clean = d.join("clean");
        let mut dir = OutputDir::open(&clean).unwrap();
        dir.open_frames().unwrap();
        dir.write("stats.csv", b"a").unwrap();
        dir.write("stats.csv", b"b").unwrap();
        dir.write("frames/x.vtp", b"c").unwrap();
        assert_eq!(std::fs::read(clean.join("stats.csv")).unwrap(), b"b");
        assert_eq!(std::fs::read_dir(&clean).unwrap().count(), 2);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
