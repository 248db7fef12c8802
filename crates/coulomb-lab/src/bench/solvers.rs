//! Solver names of `coulomb bench --solvers` and the [`Settings`] they stand for.
//!
//! A name is an inner solver of F(s) (§6 of the paper) — `pgs`, `apgd`, `ipm`, `faceted` — run
//! inside the plain fixed-point outer iteration s ← F(s), optionally followed by `+anderson` for
//! the Anderson-accelerated outer iteration. `pgs+fused` (Gauss–Seidel directly on the De Saxcé
//! form, no separate outer loop) is accepted too but is not in the default list; the library
//! rejects `+fused` with other inner solvers, which the benchmark records as a `solve_error`.

use coulomb::{InnerKind, Method, MethodParams, OuterKind, Settings};
use std::time::Duration;

/// One benchmarked solver: an inner solver and an outer iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolverSpec {
    /// the solver of the inner problem (3.15)/(4.7)
    pub inner: InnerKind,
    /// the outer iteration on s
    pub outer: OuterKind,
    /// the library's default strategy (`default`): `inner`/`outer` first, then its fallback
    pub fallback: bool,
}

/// A `--solvers` entry that is not understood.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SolverNameError {
    /// not one of the known names
    #[error("unknown solver {0:?}; expected one of {list}", list = all_names().join(", "))]
    Unknown(String),
    /// the same solver was listed twice
    #[error("solver {0:?} is listed twice")]
    Duplicate(String),
    /// the list is empty
    #[error("the solver list is empty")]
    Empty,
}

impl SolverSpec {
    /// The name used on the command line and in reports, e.g. `apgd+anderson` (the
    /// library's [`Method`] spelling).
    pub fn name(&self) -> String {
        if self.fallback {
            return "default".into();
        }
        Method::new(self.inner, self.outer).to_string()
    }

    /// Parses one name (case-insensitive, surrounding blanks ignored): `default` or a
    /// [`Method`].
    pub fn parse(name: &str) -> Result<Self, SolverNameError> {
        if name.trim().eq_ignore_ascii_case("default") {
            return Ok(Self::library_default());
        }
        let m: Method = name
            .parse()
            .map_err(|_| SolverNameError::Unknown(name.trim().to_string()))?;
        Ok(Self {
            inner: m.inner,
            outer: m.outer,
            fallback: false,
        })
    }

    /// The library's default settings (`Settings::default()`), named `default`.
    pub fn library_default() -> Self {
        let d = Settings::default();
        Self {
            inner: d.inner,
            outer: d.outer,
            fallback: true,
        }
    }

    /// The library settings: defaults, with this inner/outer pair, `tol` and `time_limit`.
    pub fn settings(&self, tol: f64, time_limit: Duration) -> Settings {
        Settings {
            inner: self.inner,
            outer: self.outer,
            tol,
            time_limit: Some(time_limit),
            fallback: if self.fallback {
                Settings::default().fallback
            } else {
                None
            },
            params: MethodParams {
                warmup_sweeps: if self.fallback {
                    MethodParams::default().warmup_sweeps
                } else {
                    0
                },
                barrier_steps: if self.fallback {
                    MethodParams::default().barrier_steps
                } else {
                    0
                },
                ..Default::default()
            },
            ..Default::default()
        }
    }
}

/// The library default, then the four inner solvers with the fixed-point outer iteration, then
/// the same four with Anderson acceleration (each of these eight without fallback).
pub fn all() -> Vec<SolverSpec> {
    let mut out = vec![SolverSpec::library_default()];
    out.extend(
        [OuterKind::FixedPoint, OuterKind::Anderson]
            .into_iter()
            .flat_map(|outer| {
                InnerKind::ALL.iter().map(move |&inner| SolverSpec {
                    inner,
                    outer,
                    fallback: false,
                })
            }),
    );
    out
}

fn all_names() -> Vec<String> {
    all().iter().map(SolverSpec::name).collect()
}

/// Parses a `--solvers` list (already split at commas); `all` stands for the nine solvers (default + eight).
/// Empty entries are ignored; an empty list or a repeated solver is an error.
pub fn parse_list(names: &[String]) -> Result<Vec<SolverSpec>, SolverNameError> {
    let mut out: Vec<SolverSpec> = Vec::new();
    for name in names.iter().map(|n| n.trim()).filter(|n| !n.is_empty()) {
        let specs = if name.eq_ignore_ascii_case("all") {
            all()
        } else {
            vec![SolverSpec::parse(name)?]
        };
        for spec in specs {
            if out.contains(&spec) {
                return Err(SolverNameError::Duplicate(spec.name()));
            }
            out.push(spec);
        }
    }
    if out.is_empty() {
        return Err(SolverNameError::Empty);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_map_to_settings() {
        let all = all();
        assert_eq!(all.len(), 9);
        assert!(all[0]
            .settings(1e-8, Duration::from_secs(1))
            .fallback
            .is_some());
        assert!(all[1]
            .settings(1e-8, Duration::from_secs(1))
            .fallback
            .is_none());
        let names: Vec<String> = all.iter().map(SolverSpec::name).collect();
        assert_eq!(
            names,
            [
                "default",
                "pgs",
                "apgd",
                "ipm",
                "faceted",
                "pgs+anderson",
                "apgd+anderson",
                "ipm+anderson",
                "faceted+anderson"
            ]
        );
        for spec in &all {
            assert_eq!(SolverSpec::parse(&spec.name()), Ok(*spec));
        }
        let s = SolverSpec::parse(" IPM+Anderson ")
            .unwrap()
            .settings(1e-6, Duration::from_secs(3));
        assert_eq!(s.inner, InnerKind::Ipm);
        assert_eq!(s.outer, OuterKind::Anderson);
        assert_eq!(s.tol, 1e-6);
        assert_eq!(s.time_limit, Some(Duration::from_secs(3)));
        assert_eq!(s.max_outer, Settings::default().max_outer);
    }

    #[test]
    fn lists_are_validated() {
        let l = |v: &[&str]| parse_list(&v.iter().map(|s| s.to_string()).collect::<Vec<_>>());
        assert_eq!(l(&["all"]).unwrap().len(), 9);
        assert_eq!(
            l(&["pgs", "", "apgd+anderson"]).unwrap(),
            vec![
                SolverSpec {
                    inner: InnerKind::Pgs,
                    outer: OuterKind::FixedPoint,
                    fallback: false,
                },
                SolverSpec {
                    inner: InnerKind::Apgd,
                    outer: OuterKind::Anderson,
                    fallback: false,
                }
            ]
        );
        assert_eq!(l(&[]), Err(SolverNameError::Empty));
        assert_eq!(
            l(&["pgs", "PGS"]),
            Err(SolverNameError::Duplicate("pgs".into()))
        );
        let e = l(&["newton"]).unwrap_err();
        assert_eq!(e, SolverNameError::Unknown("newton".into()));
        assert!(e.to_string().contains("faceted+anderson"));
        assert!(l(&["pgs+nesterov"]).is_err());
        assert_eq!(l(&["pgs+fused"]).unwrap()[0].outer, OuterKind::Fused);
    }
}
