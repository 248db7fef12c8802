//! The progress bar of the time-stepping subcommands (`simulate`, `paper`), on stderr and only
//! on a terminal.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// A progress bar on stderr, hidden when stderr is not a terminal or when `hidden`.
pub fn bar(len: usize, hidden: bool) -> ProgressBar {
    let pb = ProgressBar::new(len as u64);
    if hidden || !std::io::stderr().is_terminal() {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    if let Ok(style) = ProgressStyle::with_template(
        "{prefix} [{bar:30}] {pos}/{len} steps {msg} ({elapsed}, ETA {eta})",
    ) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb
}
