//! The worker-thread pool of the parallel subcommands (`simulate`, `paper scaling`).

use anyhow::Context;

/// Runs `f` on a rayon pool of `threads` workers (default: all cores).
pub fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> anyhow::Result<T> + Send,
) -> anyhow::Result<T> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        b = b.num_threads(n);
    }
    let pool = b.build().context("cannot start the worker threads")?;
    pool.install(f)
}
