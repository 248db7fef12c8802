//! The C allocator's settings for this process (glibc on Linux only; a no-op elsewhere).
//!
//! A step of 10⁶ beads allocates ≈ 1 GB of arrays (contacts, rows, their sweep-order copy) and
//! frees them at its end. glibc serves every block above 32 MiB with a fresh `mmap` and unmaps
//! it on free, so each step's arrays arrived as new zeroed pages that the kernel cleared
//! (8.7 M page faults, 15 % of the CPU time of a 30-step 10⁶-bead run; docs/scaling.md,
//! "Memory churn"). Kept in the heap instead, the next step reuses them (10⁵ beads: −12 % wall
//! time on one thread, −15 % on two; a 10⁶-bead scene from Python: half the CPU time), for a
//! peak RSS up to 16 % higher (the freed blocks are not always reused in place), and the process
//! keeps its peak until it exits. Written by hand: three calls of `mallopt`, which no crate
//! wraps.

/// Serves large blocks from the heap (no `mmap`), keeps freed memory (trim threshold 2 GiB)
/// and uses one arena for all threads (the threads' own arenas cannot grow past 64 MiB and map
/// the rest). Call first in `main`, before any thread starts.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; called before any other thread exists.
    // A refused setting (return value 0) leaves glibc's default, which is correct, only slower.
    unsafe {
        libc::mallopt(libc::M_MMAP_MAX, 0);
        libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX);
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}
