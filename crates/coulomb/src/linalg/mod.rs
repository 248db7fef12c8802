//! One home for the linear algebra of the solvers (issue #42 item 5): every factorization a
//! method uses lives here, and no method module exports one to another.
//!
//! - [`sparse`]: the CSC storage of M, H and W ([`sparse::CscMatrix`]);
//! - [`dense`]: the dense LU with a per-matrix parallelism (Schur complements, skeletons, the
//!   method of multipliers' J);
//! - [`blocks`]: products with and inverses of the small d × d blocks of one contact;
//! - [`pattern_lu`]: the sparse LU of the Newton systems on the block pattern of W;
//! - [`normal`]: the normal equations JᵀJ + λ I of Levenberg–Marquardt (sparse Cholesky);
//! - [`vector`]: the overflow-safe Euclidean norm (re-exported as [`crate::law::norm`]);
//! - [`skeleton`]: the skeleton W ≈ C A⁻¹ R of a rank-deficient W and the
//!   Sherman–Morrison–Woodbury solves through it.

pub mod blocks;
pub mod dense;
pub mod normal;
pub mod pattern_lu;
pub mod skeleton;
pub mod sparse;
pub mod vector;
