//! The progress report of the time-stepping subcommands (`simulate`, `paper`), on stderr: a
//! bar on a terminal; plain lines every [`PLAIN_EVERY`] when stderr is not a terminal (a log
//! file, CI, `nohup`), so that a long run shows it is alive; nothing when `hidden` (the other
//! ranks of a distributed run). Standard output is never written to, so `--json` stays one
//! JSON document.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::borrow::Cow;
use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Time between two plain progress lines (unless `COULOMB_PROGRESS_SECONDS` says otherwise).
pub const PLAIN_EVERY: Duration = Duration::from_secs(5);

/// The time between two plain progress lines: `COULOMB_PROGRESS_SECONDS` (a nonnegative
/// number of seconds; 0: a line per step) when set to one, else [`PLAIN_EVERY`].
fn plain_every() -> Duration {
    std::env::var("COULOMB_PROGRESS_SECONDS")
        .ok()
        .and_then(|s| s.trim().parse::<f64>().ok())
        .filter(|x| x.is_finite() && *x >= 0.0 && *x < 1e9)
        .map_or(PLAIN_EVERY, Duration::from_secs_f64)
}

/// A progress report: see the module doc. Same calls as an indicatif bar.
pub struct Progress {
    bar: ProgressBar,
    plain: Option<Mutex<Plain>>,
}

/// A progress bar on stderr when stderr is a terminal, plain lines on stderr otherwise;
/// nothing when `hidden`.
pub fn bar(len: usize, hidden: bool) -> Progress {
    let pb = ProgressBar::new(len as u64);
    let terminal = std::io::stderr().is_terminal();
    if hidden || !terminal {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    if let Ok(style) = ProgressStyle::with_template(
        "{prefix} [{bar:30}] {pos}/{len} steps {msg} ({elapsed}, ETA {eta})",
    ) {
        pb.set_style(style.progress_chars("=> "));
    }
    let plain = (!hidden && !terminal).then(|| {
        Mutex::new(Plain::new(
            len,
            plain_every(),
            Box::new(std::io::stderr()) as Box<dyn Write + Send>,
        ))
    });
    Progress { bar: pb, plain }
}

impl Progress {
    /// The text before the count (scene and size).
    pub fn set_prefix(&self, prefix: impl Into<Cow<'static, str>>) {
        let prefix = prefix.into();
        if let Some(mut p) = self.plain() {
            p.prefix = prefix.to_string();
        }
        self.bar.set_prefix(prefix);
    }

    /// The text after the count (the last step's figures).
    pub fn set_message(&self, msg: impl Into<Cow<'static, str>>) {
        let msg = msg.into();
        if let Some(mut p) = self.plain() {
            p.message = msg.to_string();
        }
        self.bar.set_message(msg);
    }

    /// `delta` more steps done.
    pub fn inc(&self, delta: u64) {
        if let Some(mut p) = self.plain() {
            p.advance(delta as usize);
        }
        self.bar.inc(delta);
    }

    /// Removes the bar (plain lines stay in the log).
    pub fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }

    fn plain(&self) -> Option<std::sync::MutexGuard<'_, Plain>> {
        self.plain
            .as_ref()
            .map(|m| m.lock().unwrap_or_else(|e| e.into_inner()))
    }
}

/// The progress report of the engines of `coulomb_lab` (`paper`'s runs) is this one.
impl coulomb_lab::progress::Steps for Progress {
    fn set_prefix(&self, prefix: String) {
        Progress::set_prefix(self, prefix);
    }
    fn set_message(&self, message: String) {
        Progress::set_message(self, message);
    }
    fn inc(&self, delta: u64) {
        Progress::inc(self, delta);
    }
    fn finish_and_clear(&self) {
        Progress::finish_and_clear(self);
    }
}

/// Plain progress lines: `PREFIX: step K/N, MESSAGE (T s)`, at most one per `every`.
struct Plain {
    len: usize,
    pos: usize,
    prefix: String,
    message: String,
    every: Duration,
    start: Instant,
    last: Instant,
    out: Box<dyn Write + Send>,
}

impl Plain {
    fn new(len: usize, every: Duration, out: Box<dyn Write + Send>) -> Self {
        let now = Instant::now();
        Self {
            len,
            pos: 0,
            prefix: String::new(),
            message: String::new(),
            every,
            start: now,
            last: now,
            out,
        }
    }

    /// Counts `delta` steps and writes a line when `every` has passed since the last one (or
    /// since the start). A failed write (closed stderr) is ignored: progress is not output.
    fn advance(&mut self, delta: usize) {
        self.pos += delta;
        let now = Instant::now();
        if now.duration_since(self.last) < self.every {
            return;
        }
        self.last = now;
        let mut line = format!("{}: step {}/{}", self.prefix, self.pos, self.len);
        if !self.message.is_empty() {
            line.push_str(", ");
            line.push_str(&self.message);
        }
        let _ = writeln!(
            self.out,
            "{line} ({:.0} s)",
            now.duration_since(self.start).as_secs_f64()
        );
        let _ = self.out.flush();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    /// A writer whose bytes the test can read.
    #[derive(Clone, Default)]
    struct Shared(Arc<Mutex<Vec<u8>>>);

    impl Write for Shared {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn plain_lines_carry_prefix_count_and_message_and_are_spaced() {
        let buf = Shared::default();
        let mut p = Plain::new(10, Duration::ZERO, Box::new(buf.clone()));
        p.prefix = "box 300".into();
        p.message = "12 contacts".into();
        p.advance(1);
        p.advance(2);
        let text = String::from_utf8(buf.0.lock().unwrap().clone()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 2, "{text}");
        assert!(
            lines[0].starts_with("box 300: step 1/10, 12 contacts ("),
            "{text}"
        );
        assert!(lines[1].starts_with("box 300: step 3/10, "), "{text}");
        // an interval not yet over: no line
        let quiet = Shared::default();
        let mut p = Plain::new(10, Duration::from_secs(3600), Box::new(quiet.clone()));
        p.advance(5);
        assert!(quiet.0.lock().unwrap().is_empty());
        assert_eq!(p.pos, 5);
    }
}
