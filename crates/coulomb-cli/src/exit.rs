//! Exit statuses of `coulomb` (also listed in `coulomb --help` and docs/reference.md):
//!
//! | status | meaning |
//! |---|---|
//! | 0 | success: `solve` converged, `error` says "yes", `check` proved that a solution exists, other commands finished |
//! | 1 | the command ran and the answer is negative: `solve` did not converge (any status other than converged), `error` says "no", `check` proved that no solution exists, `simulate --until-rest` stopped at its step cap without reaching rest |
//! | 2 | bad input or usage: unknown option, invalid value, unreadable or invalid file, output path refused (same as an input, folder missing, not writable) |
//! | 3 | inconclusive: `check` could neither prove nor disprove existence, or did not finish within its `--time-limit` |
//! | 4 | an output could not be written (disk full, permissions): the destination is left as it was |
//! | 130, 143 | `simulate`, `bench` or `solve` stopped by SIGINT (130) or SIGTERM (143) after the step or solve in progress, its outputs written and saying so (`crate::interrupt`) |
//!
//! Clap's own usage errors exit with 2 too; `--help` and `--version` exit with 0. A closed
//! standard output (`coulomb info … | head`) ends the process with 141, as a shell reports a
//! writer killed by SIGPIPE.

use std::process::ExitCode;

/// The text shown at the end of `coulomb --help`.
pub const HELP: &str =
    "Exit status: 0 success (solve converged, error says yes, check: a solution exists); \
1 negative answer (solve did not converge, error says no, check: no solution exists, \
simulate --until-rest at its step cap); \
2 bad input or usage (invalid option value, unreadable file, refused output path); \
3 inconclusive (check); 4 an output could not be written (destination left as it was); \
130/143 simulate, bench or solve stopped by SIGINT/SIGTERM (outputs written, marked interrupted).";

/// How a command that ran to its end answered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// status 0
    Success,
    /// status 1: not converged, "no", no solution exists
    No,
    /// status 3: the existence criteria are inconclusive (or `check` ran out of time)
    Inconclusive,
    /// status 2, after the command reported its own failures (e.g. `info` on several files,
    /// some unreadable: the table or JSON array names them)
    BadInput,
    /// status 130 (SIGINT) or 143 (SIGTERM): stopped cleanly by a signal, outputs written
    Interrupted(Signal),
}

impl Outcome {
    /// The process exit code.
    pub fn code(self) -> ExitCode {
        match self {
            Outcome::Success => ExitCode::SUCCESS,
            Outcome::No => ExitCode::from(1),
            Outcome::Inconclusive => ExitCode::from(3),
            Outcome::BadInput => ExitCode::from(BAD_INPUT),
            Outcome::Interrupted(signal) => ExitCode::from(signal.exit_status()),
        }
    }
}

/// A signal that stops a run cleanly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Signal {
    /// SIGINT (Ctrl-C): exit status 130
    Int,
    /// SIGTERM: exit status 143
    Term,
}

impl Signal {
    /// The signal's name, as reported in summaries (`SIGINT`, `SIGTERM`).
    pub fn name(self) -> &'static str {
        match self {
            Signal::Int => "SIGINT",
            Signal::Term => "SIGTERM",
        }
    }

    /// The exit status: 128 + the signal's number.
    pub fn exit_status(self) -> u8 {
        match self {
            Signal::Int => 128 + signal_hook::consts::SIGINT as u8,
            Signal::Term => 128 + signal_hook::consts::SIGTERM as u8,
        }
    }
}

/// Exit code 2: bad input or usage.
pub const BAD_INPUT: u8 = 2;
/// Exit code 4: an output could not be written.
pub const WRITE_FAILED: u8 = 4;

/// An output that could not be written (the destination is untouched): exit status 4.
pub use coulomb_lab::outputs::WriteFailed;

/// Whether `e` is (or wraps, as the payload of an [`std::io::Error`]) a refusal of
/// [`coulomb::atomic`]: the output path exists and is not a regular file.
fn refused(e: &(dyn std::error::Error + 'static)) -> bool {
    use coulomb::fclib::{FclibError, FclibErrorKind};
    let io = e.downcast_ref::<std::io::Error>().or_else(|| {
        match e.downcast_ref::<FclibError>().map(|f| &f.kind) {
            Some(FclibErrorKind::Io(io)) => Some(io),
            _ => None,
        }
    });
    e.downcast_ref::<coulomb::atomic::Refused>().is_some()
        || io.and_then(coulomb::atomic::refusal).is_some()
}

/// The exit status of a failed command: 2 when an output path was refused (a device, FIFO,
/// socket, directory or dangling link: [`coulomb::atomic::Refused`], found through the
/// I/O errors that carry it), else 4 when an output could not be written ([`WriteFailed`], or
/// a link of the chain for which `write_error` says so: the commands' own write errors, such
/// as `bench`'s, which this module does not know), else 2.
pub fn status_of(
    e: &anyhow::Error,
    write_error: fn(&(dyn std::error::Error + 'static)) -> bool,
) -> u8 {
    // the write errors carry their io::Error as `source`, so it is a link of the chain; an
    // io::Error's own `source()` skips its payload, hence `refusal` on each link
    if e.chain().any(refused) {
        return BAD_INPUT;
    }
    let write_failed = |c: &(dyn std::error::Error + 'static)| {
        c.downcast_ref::<WriteFailed>().is_some() || write_error(c)
    };
    if e.chain().any(write_failed) {
        WRITE_FAILED
    } else {
        BAD_INPUT
    }
}

/// The longest error message printed, in bytes: a longer one (a scene file listing thousands
/// of overlaps, a parser quoting a whole line of a huge file) is cut there with a note of how
/// much was left out.
pub const MESSAGE_LIMIT: usize = 4096;

/// The message of `e` and its causes on one line, `outer: inner: ...`, each cause shown only
/// when its text is not already part of what was printed (a file error that names the path
/// and the system's reason, wrapped by one that repeats them, shows them once), cut at
/// [`MESSAGE_LIMIT`] bytes.
pub fn message(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let m = cause.to_string();
        if m.is_empty() || out.contains(&m) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&m);
    }
    bounded(out, MESSAGE_LIMIT)
}

/// `text` cut at `limit` bytes (on a character boundary) with a note of what was left out.
pub fn bounded(mut text: String, limit: usize) -> String {
    if text.len() <= limit {
        return text;
    }
    let mut cut = limit;
    while !text.is_char_boundary(cut) {
        cut -= 1;
    }
    let left = text.len() - cut;
    text.truncate(cut);
    text.push_str(&format!(" … ({left} more bytes left out)"));
    text
}

#[cfg(test)]
mod message_tests {
    use super::*;

    #[derive(Debug)]
    struct Inner;
    impl std::fmt::Display for Inner {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "a.csv: No such file or directory (os error 2)")
        }
    }
    impl std::error::Error for Inner {}

    #[derive(Debug)]
    struct Outer(Inner);
    impl std::fmt::Display for Outer {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "scene.toml: particles.file: {}", self.0)
        }
    }
    impl std::error::Error for Outer {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn a_cause_already_in_the_message_is_printed_once() {
        let e = anyhow::Error::new(Outer(Inner)).context("loading the scene");
        let m = message(&e);
        assert_eq!(
            m,
            "loading the scene: scene.toml: particles.file: a.csv: No such file or directory (os error 2)"
        );
        assert_eq!(m.matches("os error 2").count(), 1);
    }

    #[test]
    fn a_huge_message_is_cut() {
        let e = anyhow::anyhow!("{}", "é".repeat(100_000));
        let m = message(&e);
        assert!(m.len() < MESSAGE_LIMIT + 64, "{}", m.len());
        assert!(
            m.ends_with("more bytes left out)"),
            "{}",
            &m[m.len() - 40..]
        );
    }
}
