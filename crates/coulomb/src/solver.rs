//! The public entry point, kept where callers have always found it: `solve(&problem,
//! &settings)` runs the outer fixed-point iteration s ← F(s) of §3.3 around an inner solver of
//! (3.15)/(4.7), and reports the error of `docs/error.md` recomputed from the returned r
//! (and v).
//!
//! Everything here is re-exported from its home: the settings from [`crate::settings`], the
//! results from [`crate::solution`], the algorithm and its policy from [`crate::outer`]
//! (the stage loop in `outer/stage.rs`), the set-up/solve split as [`Solver`].

pub use crate::outer::{solve, solve_with_guess, Solver};
pub use crate::settings::{
    InnerKind, InnerParams, Method, MethodParams, OuterKind, Settings, Tuning, STALL_WINDOW,
    UNBOUNDED_RATIO,
};
pub use crate::solution::{Guess, OuterRecord, Solution, SolveError, Status};
