//! One record per (problem, solver) pair, aggregated over the K repeats of the solve.
//!
//! A run **converged** iff the library said [`Status::Converged`], the error of `docs/error.md`
//! (recomputed by the library from the returned r and v) is finite and ≤ tol, for global
//! problems the balance residual is ≤ tol as well, and the measured wall-clock time is within the
//! time limit. Anything else — another status, an error above tol, an `Err` from the solver, an
//! unreadable file — is a failure, never a success.
//!
//! A pair converged iff every one of its runs did. Its time is the median of the run times; the
//! other fields (status, error, iterations) come from the first failed run when there is one,
//! otherwise from the run whose time is the (lower) median.

use coulomb::solver::{Solution, Status};
use serde::Serialize;

/// What one solve returned, reduced to what the benchmark reports.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// the library's status
    pub status: Status,
    /// the error of docs/error.md
    pub error: f64,
    /// ‖M v − H r − f‖ / max(1, ‖f‖) for global problems
    pub balance_residual: Option<f64>,
    /// outer iterations
    pub outer_iterations: usize,
    /// inner iterations, summed
    pub inner_iterations: usize,
}

impl From<&Solution> for RunSummary {
    fn from(s: &Solution) -> Self {
        Self {
            status: s.status,
            error: s.error,
            balance_residual: s.balance_residual,
            outer_iterations: s.outer_iterations,
            inner_iterations: s.inner_iterations,
        }
    }
}

/// One timed solve: wall-clock seconds around the call, and its result (an `Err` kept as its
/// message).
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// seconds spent in the solve call
    pub time_s: f64,
    /// what it returned
    pub result: Result<RunSummary, String>,
}

/// The acceptance rule: tolerance and time limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Criteria {
    /// tolerance on the error (and the balance residual)
    pub tol: f64,
    /// time limit in seconds
    pub time_limit_s: f64,
}

impl Criteria {
    /// Whether `run` converged, and the status word reported for it: the library's status in
    /// snake_case, or `above_tol` (the library claimed convergence but the error or balance
    /// residual is above tol), `over_time_limit` (converged, but later than the limit),
    /// `solve_error` (the solver returned an `Err`).
    pub fn judge(&self, run: &Run) -> (bool, String) {
        let s = match &run.result {
            Err(_) => return (false, "solve_error".into()),
            Ok(s) => s,
        };
        if s.status != Status::Converged {
            return (false, status_word(s.status));
        }
        let within = |x: f64| x.is_finite() && x <= self.tol;
        if !within(s.error) || !s.balance_residual.is_none_or(within) {
            return (false, "above_tol".into());
        }
        if run.time_s.is_nan() || run.time_s > self.time_limit_s {
            return (false, "over_time_limit".into());
        }
        (true, status_word(Status::Converged))
    }
}

/// The snake_case name of a status, as the library serializes it.
pub fn status_word(status: Status) -> String {
    serde_json::to_value(status)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_else(|| format!("{status:?}"))
}

/// The problem a record is about.
#[derive(Debug, Clone, PartialEq)]
pub struct ProblemInfo {
    /// short display name (file stem)
    pub name: String,
    /// the file
    pub path: String,
    /// "local" or "global" (None when the file could not be read)
    pub kind: Option<String>,
    /// number of contacts (None when the file could not be read)
    pub contacts: Option<usize>,
    /// relative asymmetry of W (or M) as stored (None when the file could not be read); the
    /// problem is benchmarked as stored
    pub asymmetry: Option<f64>,
}

/// One line of the results: a (problem, solver) pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Record {
    /// problem display name
    pub problem: String,
    /// the FCLIB file
    pub path: String,
    /// "local" or "global"; null when the file could not be read
    pub kind: Option<String>,
    /// number of contacts; null when the file could not be read
    pub contacts: Option<usize>,
    /// relative asymmetry of W (or M) as stored
    #[serde(skip_serializing_if = "Option::is_none")]
    pub asymmetry: Option<f64>,
    /// solver name, e.g. `apgd+anderson`
    pub solver: String,
    /// status word (see [`Criteria::judge`]; `read_error` when the file could not be read)
    pub status: String,
    /// whether every run converged
    pub converged: bool,
    /// the error of docs/error.md; null when there was no solution
    pub error: Option<f64>,
    /// balance residual (global problems)
    #[serde(skip_serializing_if = "Option::is_none")]
    pub balance_residual: Option<f64>,
    /// median wall-clock seconds of the runs; null when nothing ran
    pub time_s: Option<f64>,
    /// outer iterations
    pub outer_iterations: Option<usize>,
    /// inner iterations, summed
    pub inner_iterations: Option<usize>,
    /// how many runs were made (a pair whose first run fails is not repeated)
    pub runs: usize,
    /// why it failed, for `solve_error` and `read_error`
    #[serde(skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
}

/// The median of `xs` (mean of the two middle values for an even count); None when empty.
pub fn median(xs: &[f64]) -> Option<f64> {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => v.get(n / 2).copied(),
        _ => Some((v.get(n / 2 - 1)? + v.get(n / 2)?) / 2.0),
    }
}

impl Record {
    /// Aggregates the runs of one pair (see the module documentation).
    pub fn from_runs(problem: &ProblemInfo, solver: &str, runs: &[Run], crit: &Criteria) -> Self {
        let verdicts: Vec<(bool, String)> = runs.iter().map(|r| crit.judge(r)).collect();
        let times: Vec<f64> = runs.iter().map(|r| r.time_s).collect();
        let converged = !runs.is_empty() && verdicts.iter().all(|(c, _)| *c);
        // representative run: first failure, else the lower-median time
        let rep = verdicts.iter().position(|(c, _)| !c).or_else(|| {
            let mut idx: Vec<usize> = (0..runs.len()).collect();
            idx.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
            idx.get(runs.len().saturating_sub(1) / 2).copied()
        });
        let mut rec = Record {
            problem: problem.name.clone(),
            path: problem.path.clone(),
            kind: problem.kind.clone(),
            contacts: problem.contacts,
            asymmetry: problem.asymmetry,
            solver: solver.to_string(),
            status: "not_run".into(),
            converged,
            error: None,
            balance_residual: None,
            time_s: median(&times),
            outer_iterations: None,
            inner_iterations: None,
            runs: runs.len(),
            message: None,
        };
        if let (Some(run), Some((_, word))) = (
            rep.and_then(|i| runs.get(i)),
            rep.and_then(|i| verdicts.get(i)),
        ) {
            rec.status = word.clone();
            match &run.result {
                Ok(s) => {
                    rec.error = Some(s.error);
                    rec.balance_residual = s.balance_residual;
                    rec.outer_iterations = Some(s.outer_iterations);
                    rec.inner_iterations = Some(s.inner_iterations);
                }
                Err(msg) => rec.message = Some(msg.clone()),
            }
        }
        rec
    }

    /// The record of a pair whose problem file could not be read: failed, with the reason.
    pub fn unreadable(problem: &ProblemInfo, solver: &str, message: &str) -> Self {
        Record {
            status: "read_error".into(),
            message: Some(message.to_string()),
            ..Self::from_runs(
                problem,
                solver,
                &[],
                &Criteria {
                    tol: 0.0,
                    time_limit_s: 0.0,
                },
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(status: Status, error: f64, time_s: f64) -> Run {
        Run {
            time_s,
            result: Ok(RunSummary {
                status,
                error,
                balance_residual: None,
                outer_iterations: 3,
                inner_iterations: 40,
            }),
        }
    }

    const CRIT: Criteria = Criteria {
        tol: 1e-8,
        time_limit_s: 10.0,
    };

    fn info() -> ProblemInfo {
        ProblemInfo {
            name: "p".into(),
            path: "p.hdf5".into(),
            kind: Some("local".into()),
            contacts: Some(2),
            asymmetry: None,
        }
    }

    #[test]
    fn judge_never_calls_a_failure_converged() {
        assert_eq!(
            CRIT.judge(&ok(Status::Converged, 1e-9, 1.0)),
            (true, "converged".into())
        );
        assert_eq!(
            CRIT.judge(&ok(Status::Converged, 1e-7, 1.0)),
            (false, "above_tol".into())
        );
        assert_eq!(
            CRIT.judge(&ok(Status::Converged, f64::NAN, 1.0)),
            (false, "above_tol".into())
        );
        assert_eq!(
            CRIT.judge(&ok(Status::Converged, 1e-9, 11.0)),
            (false, "over_time_limit".into())
        );
        assert_eq!(
            CRIT.judge(&ok(Status::TimeLimit, 1e-9, 1.0)),
            (false, "time_limit".into())
        );
        assert_eq!(
            CRIT.judge(&ok(Status::MaxIterations, 1e-3, 1.0)),
            (false, "max_iterations".into())
        );
        let mut global = ok(Status::Converged, 1e-9, 1.0);
        if let Ok(s) = &mut global.result {
            s.balance_residual = Some(1e-3);
        }
        assert_eq!(CRIT.judge(&global), (false, "above_tol".into()));
        let err = Run {
            time_s: 0.1,
            result: Err("bad".into()),
        };
        assert_eq!(CRIT.judge(&err), (false, "solve_error".into()));
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[]), None);
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
    }

    #[test]
    fn records_aggregate_repeats() {
        let runs = [
            ok(Status::Converged, 1e-9, 3.0),
            ok(Status::Converged, 2e-9, 1.0),
            ok(Status::Converged, 3e-9, 2.0),
        ];
        let r = Record::from_runs(&info(), "pgs", &runs, &CRIT);
        assert!(r.converged);
        assert_eq!(r.status, "converged");
        assert_eq!(r.time_s, Some(2.0));
        assert_eq!(r.error, Some(3e-9)); // from the median-time run
        assert_eq!(r.runs, 3);
        assert_eq!(r.outer_iterations, Some(3));

        // one failing repeat makes the pair a failure, reported from that run
        let runs = [
            ok(Status::Converged, 1e-9, 1.0),
            ok(Status::TimeLimit, 1e-4, 10.0),
        ];
        let r = Record::from_runs(&info(), "pgs", &runs, &CRIT);
        assert!(!r.converged);
        assert_eq!(r.status, "time_limit");
        assert_eq!(r.error, Some(1e-4));
        assert_eq!(r.time_s, Some(5.5));

        let r = Record::from_runs(
            &info(),
            "ipm",
            &[Run {
                time_s: 0.5,
                result: Err("singular".into()),
            }],
            &CRIT,
        );
        assert!(!r.converged);
        assert_eq!(r.status, "solve_error");
        assert_eq!(r.message.as_deref(), Some("singular"));
        assert_eq!(r.error, None);

        let r = Record::unreadable(&info(), "apgd", "no such group");
        assert!(!r.converged);
        assert_eq!(r.status, "read_error");
        assert_eq!(r.time_s, None);
        assert_eq!(r.runs, 0);
    }
}
