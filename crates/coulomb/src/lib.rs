//! # coulomb
//!
//! The discrete (one time-step) Coulomb frictional contact problem, after Acary, Cadoux,
//! Lemaréchal and Malick, *A formulation of the linear discrete Coulomb friction problem via
//! convex optimization*, ZAMM 2011. A solve reads **problem → structure → plan → methods →
//! solution**:
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let file = coulomb::fclib::read(std::path::Path::new("problem.hdf5"))?; // problem (2.10)
//! let mut solver = coulomb::Solver::new(&file.problem, coulomb::Settings::default())?;
//! println!("{:?}", solver.structure());                        // structure, found once
//! println!("{}", solver.plan(None));                           // plan: the steps, as data
//! let solution = solver.solve(None)?;                          // methods, step by step
//! println!("{:?} {:e}", solution.status, solution.error);      // judged on the stored problem
//! # Ok(()) }
//! ```
//!
//! ## Problem
//! - [`problem`]: the incremental problem (2.10), global (M, H, f, w, μ) and local (W, q, μ);
//!   [`fclib`] reads and writes it in the FCLIB HDF5 format; [`examples`]: Painlevé (2.12)
//!   and the other examples of §4–5;
//! - [`cone`] and [`law`]: Coulomb cones (3.2), projections, the De Saxcé change (3.7),
//!   Coulomb's law (2.9) and the error measure results are reported in;
//! - [`mass`] (the block Cholesky factorization of M) and [`delassus`] (W = Hᵀ M⁻¹ H,
//!   q = Hᵀ M⁻¹ f + w);
//! - [`existence`]: the criteria (4.1), (4.4), (4.5), (4.6), (5.1) with certificates.
//!
//! ## Structure
//! - [`plan::Structure`]: what [`Solver::new`] learns once (local or global, contacts,
//!   symmetry and density of W, the range of μ, whether the rigid-body methods apply: a Schur
//!   complement or the skeleton W ≈ C A⁻¹ R of [`linalg::skeleton`]).
//!
//! ## Plan
//! - [`plan`]: the [`plan::Plan`], a list of steps (method, budget in work, start point)
//!   chosen from the structure and the [`Settings`] by [`plan::choose`]; [`Settings::paper`]
//!   is the paper's algorithm as a plan of one step; [`settings`] holds what a user changes
//!   and, one level down, [`MethodParams`].
//!
//! ## Methods
//! - [`outer`]: [`Solver`], which runs the plan's steps behind one method trait, and the
//!   algorithm of §3.3 — the stage loop s ← F(s) with rule (6.1) ([`outer::fixed_point`]),
//!   Anderson mixing, the fused Gauss–Seidel, the Newton end game;
//! - [`inner`]: solvers of the second-order-cone QP (3.15)/(4.7) that defines F(s);
//! - [`newton`] (semismooth Newton on the natural map, the one Newton driver),
//!   [`levenberg`] (Levenberg–Marquardt on the Alart–Curnier map), [`proximal`] (the proximal
//!   point), [`multiplier`] (the method of multipliers in the velocities), [`barrier`] (the
//!   interior point on the law); one Armijo line search serves the Newton-type methods;
//! - [`natural_map`]: the natural map r − P_K(r − ũ) and its Jacobian (the error measure,
//!   the inner solvers' stopping tests, the Newton systems);
//! - [`linalg`]: the linear algebra of every method — sparse and dense storage and LU, the
//!   small blocks, the patterned sparse LU, the normal equations, the skeleton of W;
//! - [`deadline`]: the one [`deadline::Deadline`] of every time limit (it only truncates).
//!
//! ## Solution
//! - [`solution`]: the [`Solution`] (r, u, v, its history step by step), its [`Status`],
//!   the [`SolveError`]; [`evaluation`]: the error of `docs/error.md` and the balance residual
//!   of a candidate, shared by the solver and [`fclib::evaluate`]; [`solver`]: where
//!   [`solve`] and the settings and results have always been re-exported; [`atomic`]: atomic
//!   file writes.
//!
//! Every error and every "converged" is that of `docs/error.md`, computed on the problem as
//! stored, from the returned r (and v).

#![warn(missing_docs)]

pub mod atomic;
pub mod barrier;
pub mod cone;
pub mod deadline;
pub mod delassus;
pub mod equality;
pub mod evaluation;
pub mod examples;
pub mod existence;
pub mod fclib;
pub mod inner;
pub mod input;
pub mod law;
pub mod levenberg;
pub mod linalg;
pub(crate) mod line_search;
pub mod mass;
pub mod multiplier;
pub mod natural_map;
pub mod newton;
pub mod outer;
pub mod plan;
pub mod problem;
pub mod proximal;
pub mod settings;
pub mod solution;
pub mod solver;
#[cfg(feature = "unit-tests")]
pub(crate) mod test_problems;
// The unit tests, compiled into the library for the integration test binary (docs/testing.md,
// "Unit tests in the library"); the feature is on only when the crate's tests are built.
#[cfg(feature = "unit-tests")]
#[doc(hidden)]
pub mod unit_tests;

/// The linear algebra at its former paths (`coulomb::sparse`, `coulomb::dense`,
/// `coulomb::skeleton`).
pub use linalg::{dense, skeleton, sparse};

/// The outer iteration's pieces, at their former path (`coulomb::fixed_point`).
pub use outer::fixed_point;

pub use linalg::sparse::CscMatrix;
pub use outer::{solve, solve_with_guess, Solver};
pub use problem::{GlobalProblem, LocalProblem, Problem, ProblemError};
pub use settings::{InnerKind, Method, MethodParams, OuterKind, Settings};
pub use solution::{Guess, Solution, SolveError, Status};
