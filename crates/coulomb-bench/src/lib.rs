//! Criterion benchmarks of coulomb and coulomb-granular (`benches/`), in a crate of their own so
//! that criterion is compiled only by `cargo bench -p coulomb-bench` (docs/testing.md). This
//! library is empty.
