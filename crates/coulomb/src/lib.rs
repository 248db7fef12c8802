//! # coulomb
//!
//! The discrete (one time-step) Coulomb frictional contact problem, after Acary, Cadoux,
//! Lemaréchal and Malick, *A formulation of the linear discrete Coulomb friction problem via
//! convex optimization*, ZAMM 2011:
//!
//! - [`problem`]: the incremental problem (2.10), global (M, H, f, w, μ) and local (W, q, μ);
//! - [`cone`] and [`law`]: Coulomb cones (3.2), projections, the De Saxcé change (3.7),
//!   Coulomb's law (2.9) and the error measure results are reported in;
//! - [`mass`]: the block Cholesky factorization of M, with its own [`mass::MassError`];
//! - [`delassus`]: W = Hᵀ M⁻¹ H and q = Hᵀ M⁻¹ f + w;
//! - [`linalg`]: the linear algebra of every method — sparse and dense storage and LU, the
//!   small blocks, the patterned sparse LU, the normal equations, the skeleton of W;
//! - [`settings`] and [`solution`]: the typed [`Settings`] (with [`Settings::paper`], the
//!   paper's algorithm, and the [`settings::Tuning`] constants), the [`Method`] names, the
//!   [`Solution`], its [`Status`] and the [`SolveError`];
//! - [`natural_map`]: the natural map r − P_K(r − ũ) and its Jacobian (one home for the
//!   error measure, the inner solvers' stopping tests and the Newton systems);
//! - [`inner`]: solvers of the second-order-cone QP (3.15)/(4.7) that defines F(s);
//! - [`outer`]: the algorithm of §3.3 — the stage loop s ← F(s) with rule (6.1)
//!   ([`outer::fixed_point`]), Anderson mixing, the fused Gauss–Seidel, the Newton end game —
//!   the policy around it (warm-up, fallback) and the set-up/solve split [`Solver`];
//! - [`newton`]: semismooth Newton on the natural map of the whole law (the end game's steps);
//! - `line_search`: the one Armijo search of the Newton-type methods;
//! - [`levenberg`]: Levenberg–Marquardt on the Alart–Curnier map, the end game for rigid,
//!   rank-deficient problems after the Newton end game has spent its budget;
//! - [`multiplier`]: the proximal point on r solved in the velocities (method of
//!   multipliers), a stage of the default for rigid problems whose W is rank-deficient;
//! - [`solver`]: where [`solve`] and the settings and results have always been re-exported;
//! - [`deadline`]: the one [`deadline::Deadline`] type of every time limit;
//! - [`existence`]: the criteria (4.1), (4.4), (4.5), (4.6), (5.1) with certificates;
//! - [`evaluation`]: the error of `docs/error.md` and the balance residual of a candidate,
//!   shared by the solver and [`fclib::evaluate`];
//! - [`examples`]: Painlevé (2.12) and the other examples of §4–5;
//! - [`fclib`]: the FCLIB HDF5 exchange format.
//!
//! Every error and every "converged" is that of `docs/error.md`, computed on the problem as
//! stored, from the returned r (and v).

#![warn(missing_docs)]

pub mod atomic;
pub mod barrier;
pub mod cone;
pub mod deadline;
pub mod delassus;
pub mod evaluation;
pub mod examples;
pub mod existence;
pub mod fclib;
pub mod inner;
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
#[cfg(test)]
pub(crate) mod test_problems;

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
