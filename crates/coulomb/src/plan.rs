//! Problem → structure → plan: what [`crate::Solver::solve`] runs, as data.
//!
//! [`Structure`] is what the solver learns about a problem once, in [`crate::Solver::new`]:
//! local or global (with its degrees of freedom), contacts, whether W is symmetric, the
//! density of W, the range of μ, and whether the rigid-body methods apply (a Schur complement
//! of the size of M, or a local W small enough to be probed for a skeleton W ≈ C A⁻¹ R).
//!
//! [`Plan`] is the list of steps a solve runs, chosen from the structure and the settings by
//! one function, [`choose`]: each step a method, its budget in work (sweeps, Newton steps,
//! factorizations, iterations: never a share of the wall-clock time, so that the path is the
//! same on any machine and under any load) and the point it starts from. A step that
//! converges ends the solve; the time limit only truncates. The paper's algorithm
//! ([`crate::Settings::paper`]) is the plan of one step. `coulomb solve --explain` prints it,
//! and every history record names the step that made it ([`crate::solution::OuterRecord::step`]).

use crate::settings::{Method, Settings};
use std::fmt;

pub use crate::solution::StepKind;

/// Where a step starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Start {
    /// the caller's guess (r = 0 without one)
    Caller,
    /// r = 0, whatever the guess (the interior point starts inside the cones)
    Cold,
    /// the best point of the step before, and the end points of its other runs
    PreviousBest,
    /// the last iterate of the step before
    PreviousLast,
}

/// The budget of a step, in work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Budget {
    /// Gauss–Seidel sweeps
    Sweeps(usize),
    /// Newton steps per run and in all (with the LM finishes)
    Steps {
        /// per run (path)
        per_run: usize,
        /// in all
        total: usize,
    },
    /// factorizations of J in all runs, from at most this many starts
    Factorizations {
        /// factorizations
        total: usize,
        /// starts run side by side
        starts: usize,
    },
    /// outer iterations, inner iterations per inner solve, and the end game's Newton steps
    Iterations {
        /// outer iterations
        outer: usize,
        /// inner iterations per inner solve
        inner: usize,
        /// Newton steps of the end game
        newton: usize,
    },
}

impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Budget::Sweeps(n) => write!(f, "{n} sweeps"),
            Budget::Steps { per_run, total } => {
                write!(f, "{per_run} Newton steps per run, {total} steps in all")
            }
            Budget::Factorizations { total, starts } => {
                write!(f, "{total} factorizations, {starts} starts")
            }
            Budget::Iterations {
                outer,
                inner,
                newton,
            } => write!(
                f,
                "{outer} outer iterations × {inner} inner, {newton} end-game Newton steps"
            ),
        }
    }
}

/// One step of a [`Plan`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Step {
    /// which step
    pub kind: StepKind,
    /// its (inner, outer) method, for the steps that are one
    pub method: Option<Method>,
    /// its budget in work
    pub budget: Budget,
    /// where it starts
    pub start: Start,
}

/// The steps of a solve, in order ([`choose`]).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Plan {
    /// the steps; a step that converges ends the solve
    pub steps: Vec<Step>,
    /// why the main method is not the settings' own (None: it is)
    pub main_reason: Option<String>,
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, s) in self.steps.iter().enumerate() {
            write!(f, "{}. {}", k + 1, s.kind)?;
            if let Some(m) = s.method {
                write!(f, " ({m})")?;
            }
            let start = match s.start {
                Start::Caller => "the caller's point",
                Start::Cold => "r = 0",
                Start::PreviousBest => "the previous step's best points",
                Start::PreviousLast => "the previous step's last iterate",
            };
            writeln!(f, ": {}, from {start}", s.budget)?;
        }
        if let Some(why) = &self.main_reason {
            writeln!(f, "main method: {why}")?;
        }
        Ok(())
    }
}

/// Whether the rigid-body steps (interior point, multipliers) may apply.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Rigid {
    /// neither: too large, or W has no low-rank structure to use
    No,
    /// a global problem with at most half as many degrees of freedom as contact unknowns
    /// (and at most [`crate::settings::BarrierParams::max_schur_dofs`]): Newton systems on
    /// M + H G⁻¹ Hᵀ
    Schur,
    /// a local problem with at most [`crate::settings::BarrierParams::max_skeleton_unknowns`]
    /// contact unknowns: W is probed for a skeleton of low rank when the interior point runs
    SkeletonProbe,
}

/// What the solver knows about a problem, computed once ([`crate::Solver::structure`]).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Structure {
    /// dimension d of the contact space (2 or 3)
    pub dim: usize,
    /// number of contacts
    pub contacts: usize,
    /// contact unknowns m = d · contacts
    pub unknowns: usize,
    /// degrees of freedom n of a global problem (None: a local problem)
    pub dofs: Option<usize>,
    /// whether W is exactly symmetric
    pub symmetric: bool,
    /// stored entries of W / m²
    pub density: f64,
    /// smallest and largest μ (NaN, NaN without contacts)
    pub mu_range: (f64, f64),
    /// whether every μ is finite and positive (the interior point needs it)
    pub mu_positive: bool,
    /// the rigid-body steps' applicability
    pub rigid: Rigid,
    /// a global problem: the size of the largest diagonal block of M, where M is block
    /// diagonal in consecutive indices (6 for spheres or rigid bodies in 3-D; n for a
    /// deformable body); None for a local problem
    pub m_block: Option<usize>,
}

impl Structure {
    /// Whether the problem has the structure of a step of granular matter
    /// ([`GRANULAR_MIN_CONTACTS`] contacts or more, global, W symmetric, M block diagonal
    /// with blocks of at most [`GRANULAR_MAX_BLOCK`], no rigid-body structure: the bodies do
    /// not carry many contacts each, 2n > m), where Gauss–Seidel on Coulomb's law (pgs +
    /// fused) is the faster method (measured: docs/scaling.md, "The default plan on deep
    /// steps").
    pub fn granular(&self) -> bool {
        self.contacts >= GRANULAR_MIN_CONTACTS
            && self.symmetric
            && self.rigid == Rigid::No
            && self.m_block.is_some_and(|b| b <= GRANULAR_MAX_BLOCK)
    }
}

/// The fewest contacts of a [`Structure::granular`] problem: below it the default plan keeps
/// its order (the corpus' granular steps of fewer contacts are solved by the warm-up or by
/// APGD + Anderson; docs/scaling.md).
pub const GRANULAR_MIN_CONTACTS: usize = 1000;

/// The tightest tolerance at which a [`Structure::granular`] problem runs Gauss–Seidel first:
/// at 1e-4 it is 5–6× faster than APGD + Anderson on deep steps and solves the 8-layer steps
/// the default order fails; at 1e-8 the default order (APGD + Anderson with the Newton end
/// game) solves more of the corpus' granular steps (docs/scaling.md).
pub const GRANULAR_MIN_TOL: f64 = 1e-6;

/// The largest diagonal block of M of a [`Structure::granular`] problem: one body, 6 degrees
/// of freedom in 3-D.
pub const GRANULAR_MAX_BLOCK: usize = 6;

impl fmt::Display for Structure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let form = match self.dofs {
            Some(n) => format!("global, {n} degrees of freedom"),
            None => "local".to_string(),
        };
        let rigid = match self.rigid {
            Rigid::No => "no",
            Rigid::Schur => "Schur complement of size n",
            Rigid::SkeletonProbe => "skeleton probe of W",
        };
        let form = match self.m_block {
            Some(b) => format!("{form} (M's largest diagonal block {b})"),
            None => form,
        };
        writeln!(
            f,
            "{form}; d = {}, {} contacts, m = {}; W {}, density {:.3e}; μ in [{}, {}]; rigid steps: {rigid}",
            self.dim,
            self.contacts,
            self.unknowns,
            if self.symmetric { "symmetric" } else { "not symmetric" },
            self.density,
            self.mu_range.0,
            self.mu_range.1,
        )
    }
}

/// The plan of a solve with `settings` of a problem of structure `s`; `cold`: no guess
/// given (the rigid-body steps run only then). The steps, in order, each present when its
/// setting turns it on:
///
/// 1. warm-up ([`crate::MethodParams::warmup_sweeps`] > 0);
/// 2. interior point ([`crate::MethodParams::barrier_steps`] > 0, cold, every μ finite
///    and > 0, and [`Rigid::Schur`] or [`Rigid::SkeletonProbe`]; it runs only if its Newton
///    systems have a Schur complement or a skeleton);
/// 3. multipliers (after the interior point, when it did not converge,
///    [`crate::settings::MultiplierParams::max_steps`] > 0; on a local problem only if W's
///    skeleton reproduces it);
/// 4. main, from the caller's point (not the warm-up's);
/// 5. fallback ([`Settings::fallback`]), when main stops on a cap, a stall or a failure.
///
/// On a [`Structure::granular`] problem, at a tolerance of at least [`GRANULAR_MIN_TOL`], whose
/// settings name Gauss–Seidel on Coulomb's law (pgs + fused) as the fallback of another main
/// method (the default settings), the two
/// change places: pgs + fused is the main method and the settings' main method its
/// fallback, and there is no warm-up (it would be the main method's first sweeps).
/// [`Plan::main_reason`] says so.
pub fn choose(s: &Structure, settings: &Settings, cold: bool) -> Plan {
    let t = &settings.params.tuning;
    let gauss_seidel = Method::new(crate::InnerKind::Pgs, crate::OuterKind::Fused);
    let swapped = s.granular()
        && settings.tol >= GRANULAR_MIN_TOL
        && settings.fallback.map(Method::from) == Some(gauss_seidel)
        && settings.main_method() != gauss_seidel;
    let (main, fallback) = if swapped {
        (gauss_seidel, Some(settings.main_method()))
    } else {
        (settings.main_method(), settings.fallback.map(Method::from))
    };
    let main_reason = swapped.then(|| {
        format!(
            "{gauss_seidel} first, {} as its fallback: a granular step ({} contacts ≥ {GRANULAR_MIN_CONTACTS}, \
             global with M block diagonal in blocks ≤ {GRANULAR_MAX_BLOCK}, W symmetric, no rigid-body \
             structure) at tol {:e} ≥ {GRANULAR_MIN_TOL:e}, where Gauss–Seidel on Coulomb's law is the \
             faster method (docs/scaling.md)",
            settings.main_method(),
            s.contacts,
            settings.tol,
        )
    });
    let mut steps = Vec::new();
    if settings.params.warmup_sweeps > 0 && !swapped {
        steps.push(Step {
            kind: StepKind::Warmup,
            method: Some(Method::new(crate::InnerKind::Pgs, crate::OuterKind::Fused)),
            budget: Budget::Sweeps(settings.params.warmup_sweeps),
            start: Start::Caller,
        });
    }
    let rigid = s.rigid != Rigid::No;
    if cold && rigid && settings.params.barrier_steps > 0 && s.mu_positive && s.contacts > 0 {
        steps.push(Step {
            kind: StepKind::InteriorPoint,
            method: None,
            budget: Budget::Steps {
                per_run: settings.params.barrier_steps,
                total: t.barrier.max_work,
            },
            start: Start::Cold,
        });
        if t.multiplier.max_steps > 0 && s.mu_range.1.is_finite() {
            steps.push(Step {
                kind: StepKind::Multipliers,
                method: None,
                budget: Budget::Factorizations {
                    total: t.multiplier.max_factorizations,
                    starts: t.multiplier.starts,
                },
                start: Start::PreviousBest,
            });
        }
    }
    let iterations = Budget::Iterations {
        outer: settings.max_outer,
        inner: settings.max_inner,
        newton: settings.params.newton_steps,
    };
    steps.push(Step {
        kind: StepKind::Main,
        method: Some(main),
        budget: iterations,
        start: Start::Caller,
    });
    if let Some(fallback) = fallback {
        steps.push(Step {
            kind: StepKind::Fallback,
            method: Some(fallback),
            budget: iterations,
            start: Start::PreviousLast,
        });
    }
    Plan { steps, main_reason }
}

#[cfg(feature = "unit-tests")]
#[allow(missing_docs)]
pub mod tests {
    use super::*;
    use crate::settings::{InnerKind, OuterKind};

    fn structure(rigid: Rigid) -> Structure {
        Structure {
            dim: 3,
            contacts: 4,
            unknowns: 12,
            dofs: None,
            symmetric: true,
            density: 1.0,
            mu_range: (0.3, 0.3),
            mu_positive: true,
            rigid,
            m_block: None,
        }
    }

    pub fn the_paper_is_one_step_and_the_default_follows_the_structure() {
        let kinds = |p: &Plan| p.steps.iter().map(|s| s.kind).collect::<Vec<_>>();
        let paper = choose(
            &structure(Rigid::SkeletonProbe),
            &Settings::paper(InnerKind::Apgd),
            true,
        );
        assert_eq!(kinds(&paper), [StepKind::Main]);
        assert_eq!(
            paper.steps[0].method,
            Some(Method::new(InnerKind::Apgd, OuterKind::FixedPoint))
        );
        let d = Settings::default();
        use StepKind::*;
        assert_eq!(
            kinds(&choose(&structure(Rigid::SkeletonProbe), &d, true)),
            [Warmup, InteriorPoint, Multipliers, Main, Fallback]
        );
        // from a guess, or without the rigid structure: no rigid steps
        assert_eq!(
            kinds(&choose(&structure(Rigid::SkeletonProbe), &d, false)),
            [Warmup, Main, Fallback]
        );
        assert_eq!(
            kinds(&choose(&structure(Rigid::No), &d, true)),
            [Warmup, Main, Fallback]
        );
        let text = choose(&structure(Rigid::Schur), &d, true).to_string();
        assert!(text.contains("2. interior point"), "{text}");
        assert!(text.contains("5. fallback"), "{text}");
    }

    /// A global problem of granular matter: 1 200 spheres, 2 000 contacts, 6 × 6 blocks of M.
    fn granular() -> Structure {
        Structure {
            contacts: GRANULAR_MIN_CONTACTS * 2,
            unknowns: GRANULAR_MIN_CONTACTS * 6,
            dofs: Some(7200),
            density: 1e-3,
            m_block: Some(6),
            ..structure(Rigid::No)
        }
    }

    pub fn a_granular_step_runs_gauss_seidel_first_and_other_problems_keep_their_plan() {
        use StepKind::*;
        let d = Settings {
            tol: 1e-4,
            ..Settings::default()
        };
        let gs = Method::new(InnerKind::Pgs, OuterKind::Fused);
        let plan = choose(&granular(), &d, true);
        let pairs: Vec<_> = plan.steps.iter().map(|s| (s.kind, s.method)).collect();
        assert_eq!(
            pairs,
            [(Main, Some(gs)), (Fallback, Some(d.main_method()))],
            "{plan}"
        );
        let text = plan.to_string();
        assert!(
            text.contains("main method: pgs+fused first") && text.contains("granular"),
            "{text}"
        );
        // the other kinds keep the settings' order, with the warm-up and no reason
        let default_order = |s: &Structure| {
            let p = choose(s, &d, true);
            assert!(p.main_reason.is_none(), "{p}");
            let main = p.steps.iter().find(|s| s.kind == Main).unwrap();
            assert_eq!(main.method, Some(d.main_method()), "{p}");
            assert_eq!(p.steps[0].kind, Warmup, "{p}");
        };
        for other in [
            // too few contacts
            Structure {
                contacts: GRANULAR_MIN_CONTACTS - 1,
                ..granular()
            },
            // a deformable body: M not in body blocks
            Structure {
                m_block: Some(162),
                ..granular()
            },
            // W not symmetric (gyroscopic M)
            Structure {
                symmetric: false,
                ..granular()
            },
            // rigid bodies carrying many contacts each: the Schur complement applies
            Structure {
                rigid: Rigid::Schur,
                ..granular()
            },
            // a local problem (no M to read)
            Structure {
                dofs: None,
                m_block: None,
                ..granular()
            },
        ] {
            default_order(&other);
        }
        // a tight tolerance: the default order (the Newton end game of the main method)
        let tight = Settings {
            tol: GRANULAR_MIN_TOL / 10.0,
            ..d.clone()
        };
        let p = choose(&granular(), &tight, true);
        assert!(p.main_reason.is_none(), "{p}");
        assert_eq!(p.steps[0].kind, Warmup, "{p}");
        assert!(choose(
            &granular(),
            &Settings {
                tol: GRANULAR_MIN_TOL,
                ..d.clone()
            },
            true
        )
        .main_reason
        .is_some());
        // a method the caller chose runs as chosen: without the default fallback, or when
        // the main method is Gauss–Seidel already
        let alone = Settings {
            tol: 1e-4,
            ..Settings::method(InnerKind::Apgd, OuterKind::Anderson)
        };
        let p = choose(&granular(), &alone, true);
        assert_eq!(p.steps.len(), 1);
        assert_eq!(p.steps[0].method, Some(alone.main_method()));
        let gs_main = Settings {
            inner: InnerKind::Pgs,
            outer: OuterKind::Fused,
            ..d.clone()
        };
        let p = choose(&granular(), &gs_main, true);
        assert!(p.main_reason.is_none());
        assert_eq!(p.steps[0].kind, Warmup);
    }
}
