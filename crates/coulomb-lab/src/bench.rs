//! The engine of `coulomb bench` ([`run`]): solvers side by side on FCLIB collections, compared by Dolan–Moré
//! performance profiles of solve time (the way Acary, Brémond & Huber compare Coulomb friction
//! solvers over FCLIB).
//!
//! Every (problem, solver) pair is solved K times (`--repeat`) from a cold start; the file is
//! read once, outside the timing. The reported time is the median wall-clock time of the
//! `coulomb::solver::solve` call; iterations and status come from the library's
//! [`coulomb::solver::Solution`]; the error of docs/error.md and the balance residual are
//! recomputed from the returned r (and v) on the problem as stored
//! ([`coulomb::fclib::evaluate`], outside the timing). A pair counts as solved only under the rule of
//! [`record`]: status `converged`, error of docs/error.md ≤ tol (balance residual too for global
//! problems), within the time limit, on every repeat. A pair whose first run fails is not
//! repeated.
//!
//! Outputs: a table on the caller's writer (stdout; progress on stderr), `--json` with every
//! record, `--svg` with the performance profile (see [`profile`]).
//!
//! A signal ([`Interrupts`]: SIGINT/SIGTERM in the CLI) stops the benchmark after the solve in
//! progress: the table, JSON and SVG are written for the problems whose solvers all ran (a
//! problem cut short is left out, so that the profile compares every solver on the same
//! problems), the JSON says `"interrupted"`, and [`run`] returns the signal (the CLI's exit
//! status is then 130/143).

mod files;
pub mod plot;
pub mod profile;
pub mod record;
mod solvers;

use record::{Criteria, ProblemInfo, Record, Run, RunSummary};
use serde::Serialize;
use solvers::SolverSpec;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Largest accepted `--repeat`.
const MAX_REPEAT: usize = 1000;
/// Largest accepted `--time-limit`, seconds (one week).
const MAX_TIME_LIMIT_S: f64 = 7.0 * 24.0 * 3600.0;

/// What a bench run does (`coulomb bench`'s arguments).
#[derive(Debug, Clone)]
pub struct Options {
    /// FCLIB files, or directories searched recursively (all levels) for *.hdf5 and *.h5 files
    pub paths: Vec<PathBuf>,
    /// solver names: pgs, apgd, ipm, faceted (plain fixed-point outer iteration), the same
    /// with +anderson (accelerated outer iteration), or all
    pub solvers: Vec<String>,
    /// tolerance on the error of docs/error.md (and on the balance residual of global problems)
    pub tol: f64,
    /// time limit of each solve, in seconds (at most one week)
    pub time_limit: f64,
    /// number of runs of each (problem, solver) pair; the median time is reported
    pub repeat: usize,
    /// write every record (and machine/command metadata) to this JSON file
    pub json: Option<PathBuf>,
    /// write the performance profile to this SVG file
    pub svg: Option<PathBuf>,
}

/// How the caller stops a run early: its signal handlers, installed once the arguments and
/// outputs are checked, and looked at after each solve.
pub struct Interrupts<'a, S> {
    /// installs the handlers
    pub install: &'a dyn Fn() -> std::io::Result<()>,
    /// the signal received since, if any
    pub received: &'a dyn Fn() -> Option<S>,
    /// the signal's name, as reported (`SIGINT`)
    pub name: fn(S) -> &'static str,
}

/// A bad argument or output failure of `coulomb bench`.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// --tol is not a positive finite number
    #[error("--tol must be a positive finite number, got {0}")]
    Tol(f64),
    /// --time-limit out of range
    #[error("--time-limit must be a positive number of seconds up to {MAX_TIME_LIMIT_S}, got {0}")]
    TimeLimit(f64),
    /// --repeat out of range
    #[error("--repeat must be between 1 and {MAX_REPEAT}, got {0}")]
    Repeat(usize),
    /// bad --solvers
    #[error("--solvers: {0}")]
    Solvers(#[from] solvers::SolverNameError),
    /// a PATH cannot be searched
    #[error(transparent)]
    Files(#[from] files::FilesError),
    /// the PATHs hold no FCLIB file
    #[error("no FCLIB file (*.hdf5, *.h5) found in {0}")]
    NoFiles(String),
    /// the profile could not be formed
    #[error(transparent)]
    Profile(#[from] profile::ProfileError),
    /// the figure could not be made
    #[error(transparent)]
    Plot(#[from] plot::PlotError),
    /// the JSON could not be written
    #[error("cannot write {path}: {source}")]
    Write {
        /// the output path
        path: PathBuf,
        /// the OS error
        source: std::io::Error,
    },
    /// the JSON could not be serialized
    #[error("cannot serialize the results: {0}")]
    Json(#[from] serde_json::Error),
}

/// Checked settings of a bench run.
struct Plan {
    solvers: Vec<SolverSpec>,
    criteria: Criteria,
    time_limit: Duration,
    repeat: usize,
}

fn plan(args: &Options) -> Result<Plan, BenchError> {
    if !(args.tol.is_finite() && args.tol > 0.0) {
        return Err(BenchError::Tol(args.tol));
    }
    let time_limit = (args.time_limit > 0.0 && args.time_limit <= MAX_TIME_LIMIT_S)
        .then(|| Duration::try_from_secs_f64(args.time_limit).ok())
        .flatten()
        .ok_or(BenchError::TimeLimit(args.time_limit))?;
    if args.repeat == 0 || args.repeat > MAX_REPEAT {
        return Err(BenchError::Repeat(args.repeat));
    }
    Ok(Plan {
        solvers: solvers::parse_list(&args.solvers)?,
        criteria: Criteria {
            tol: args.tol,
            time_limit_s: args.time_limit,
        },
        time_limit,
        repeat: args.repeat,
    })
}

/// How far an interrupted benchmark got (`"interrupted"` in the JSON).
#[derive(Debug, Clone, Serialize)]
struct Partial {
    /// SIGINT or SIGTERM
    signal: &'static str,
    /// problems whose solvers all ran (those reported)
    problems_done: usize,
    /// problems found in the PATHs
    problems_found: usize,
}

/// Runs the benchmark of `args`, the table on `out`: `None` when it ran to its end, the signal
/// that stopped it otherwise.
pub fn run<S: Copy>(
    args: &Options,
    signals: &Interrupts<'_, S>,
    mut out: &mut dyn Write,
) -> anyhow::Result<Option<S>> {
    let plan = plan(args)?;
    let files = files::collect(&args.paths)?;
    if files.is_empty() {
        let list: Vec<String> = args.paths.iter().map(|p| p.display().to_string()).collect();
        return Err(BenchError::NoFiles(list.join(", ")).into());
    }
    // outputs checked before the (long) run: not an input, folder writable, not each other
    let inputs: Vec<&Path> = files.iter().map(|f| f.as_path()).collect();
    if let Some(path) = &args.json {
        crate::outputs::check("--json", path, &inputs)?;
    }
    if let Some(path) = &args.svg {
        crate::outputs::check("--svg", path, &inputs)?;
        if args.json.as_ref().is_some_and(|j| j == path) {
            anyhow::bail!("--json and --svg name the same file {}", path.display());
        }
    }
    let names = files::display_names(&files);
    let solver_names: Vec<String> = plan.solvers.iter().map(SolverSpec::name).collect();
    (signals.install)()?;
    let stopped = || (signals.received)().is_some();

    // by_problem[p][s]: the record of solver s on problem p (problems whose solvers all ran)
    let mut by_problem: Vec<Vec<Record>> = Vec::with_capacity(files.len());
    let mut interrupted: Option<S> = None;
    for (i, (file, name)) in files.iter().zip(&names).enumerate() {
        let progress = format!("[{}/{}] {name}", i + 1, files.len());
        let records = bench_file(file, name, &plan, &progress, &stopped);
        let complete = records.len() == plan.solvers.len();
        if complete {
            by_problem.push(records);
        }
        interrupted = (signals.received)();
        if let Some(signal) = interrupted {
            eprintln!(
                "interrupted by {}: {} of {} problems benched{}",
                (signals.name)(signal),
                by_problem.len(),
                files.len(),
                if complete {
                    String::new()
                } else {
                    format!(" ({name} cut short, left out)")
                }
            );
            break;
        }
    }
    let partial = interrupted.map(|signal| Partial {
        signal: (signals.name)(signal),
        problems_done: by_problem.len(),
        problems_found: files.len(),
    });
    if let (Some(signal), true) = (interrupted, by_problem.is_empty()) {
        eprintln!("no problem was benched by every solver: nothing written");
        return Ok(Some(signal));
    }
    let n_problems = by_problem.len();
    let prof = profile::performance_profile(&time_table(&by_problem))?;
    let records: Vec<Record> = by_problem.into_iter().flatten().collect();
    write_table(&mut out, &records)?;
    writeln!(out)?;
    write_summary(&mut out, &records, &prof, &solver_names, n_problems)?;

    if let Some(path) = &args.json {
        write_json(
            path,
            &records,
            &prof,
            &solver_names,
            &plan,
            partial.as_ref(),
        )?;
        writeln!(out, "wrote {}", path.display())?;
    }
    if let Some(path) = &args.svg {
        let curves: Vec<plot::Curve> = plan
            .solvers
            .iter()
            .map(|spec| plot::Curve {
                label: format!(
                    "{} ({}/{} solved)",
                    spec.name(),
                    solved_count(&records, &spec.name()),
                    n_problems
                ),
                color: inner_index(spec),
                dashed: !spec.fallback && spec.outer != coulomb::solver::OuterKind::FixedPoint,
            })
            .collect();
        let mut title = format!(
            "Performance profile: {} problems, tol {:e}, time limit {} s",
            n_problems, plan.criteria.tol, plan.criteria.time_limit_s
        );
        if let Some(p) = &partial {
            title.push_str(&format!(
                " (interrupted: {} of {} problems)",
                p.problems_done, p.problems_found
            ));
        }
        plot::write_svg(path, &prof, &curves, &title)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(interrupted)
}

/// Colour slot of a solver: one per inner solver, so that `x` and `x+anderson` share a colour.
/// Palette index: one colour per inner solver, a colour of its own for the library default.
fn inner_index(spec: &SolverSpec) -> usize {
    if spec.fallback {
        return 5;
    }
    solvers::all()
        .iter()
        .filter(|s| !s.fallback)
        .position(|s| s.inner == spec.inner)
        .unwrap_or(0)
}

fn solved_count(records: &[Record], solver: &str) -> usize {
    records
        .iter()
        .filter(|r| r.solver == solver && r.converged)
        .count()
}

/// Reads one file and runs every solver on it; never fails (failures become records). Fewer
/// records than solvers when `stopped` (a signal was received, [`Interrupts`]).
fn bench_file(
    file: &Path,
    name: &str,
    plan: &Plan,
    progress: &str,
    stopped: &dyn Fn() -> bool,
) -> Vec<Record> {
    let mut info = ProblemInfo {
        name: name.to_string(),
        path: file.display().to_string(),
        kind: None,
        contacts: None,
        asymmetry: None,
    };
    let problem = match coulomb::fclib::read(file) {
        Ok(f) => {
            info.asymmetry = Some(f.problem.asymmetry());
            f.problem
        }
        Err(e) => {
            let msg = e.to_string();
            eprintln!("{progress}: cannot read {}: {msg}", file.display());
            return plan
                .solvers
                .iter()
                .map(|s| Record::unreadable(&info, &s.name(), &msg))
                .collect();
        }
    };
    info.kind = Some(problem.kind().to_string());
    info.contacts = Some(problem.contacts());
    // a received signal stops the loop before the next solve (the records so far are kept)
    plan.solvers
        .iter()
        .map_while(|spec| {
            if stopped() {
                return None;
            }
            let settings = spec.settings(plan.criteria.tol, plan.time_limit);
            let mut runs = Vec::with_capacity(plan.repeat);
            for _ in 0..plan.repeat {
                let run = timed_solve(&problem, &settings);
                let failed = !plan.criteria.judge(&run).0;
                runs.push(run);
                if failed || stopped() {
                    break;
                }
            }
            let rec = Record::from_runs(&info, &spec.name(), &runs, &plan.criteria);
            eprintln!(
                "{progress} {:<17} {:<16} error {:<9} time {}",
                rec.solver,
                rec.status,
                fmt_opt_sci(rec.error),
                fmt_opt_time(rec.time_s)
            );
            Some(rec)
        })
        .collect()
}

/// One cold-start solve, timed with the wall clock. A panic inside the solver is caught and
/// recorded as an `Err`, so that one broken pair does not end the whole benchmark.
fn timed_solve(problem: &coulomb::Problem, settings: &coulomb::solver::Settings) -> Run {
    let start = Instant::now();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        coulomb::solver::solve(problem, settings)
    }));
    let time_s = start.elapsed().as_secs_f64();
    let result = match outcome {
        Ok(Ok(sol)) => Ok(recomputed(problem, &sol)),
        Ok(Err(e)) => Err(e.to_string()),
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown payload".into());
            Err(format!("solver panicked: {what}"))
        }
    };
    Run { time_s, result }
}

/// The run's summary with err (and the balance residual) recomputed from the returned r
/// (and v) on the problem as stored by [`coulomb::fclib::evaluate`], outside the timed
/// region: the benchmark judges convergence on these numbers, not on the solver's own.
fn recomputed(problem: &coulomb::Problem, sol: &coulomb::solver::Solution) -> RunSummary {
    let mut summary = RunSummary::from(sol);
    let stored = coulomb::fclib::StoredSolution {
        r: sol.r.clone(),
        u: None,
        v: sol.v.clone(),
        l: None,
    };
    match coulomb::fclib::evaluate(problem, &stored) {
        Ok(e) => {
            summary.error = e.measure.error;
            summary.balance_residual = e.balance_residual;
        }
        Err(_) => summary.error = f64::NAN,
    }
    summary
}

/// `times[p][s]` = median time of solver s on problem p when the pair converged, `None`
/// otherwise.
fn time_table(by_problem: &[Vec<Record>]) -> Vec<Vec<Option<f64>>> {
    by_problem
        .iter()
        .map(|row| {
            row.iter()
                .map(|r| if r.converged { r.time_s } else { None })
                .collect()
        })
        .collect()
}

fn fmt_opt_sci(x: Option<f64>) -> String {
    x.map_or_else(|| "-".into(), |x| format!("{x:.2e}"))
}

fn fmt_opt_time(t: Option<f64>) -> String {
    t.map_or_else(|| "-".into(), |t| format!("{t:.6}"))
}

fn fmt_opt_usize(n: Option<usize>) -> String {
    n.map_or_else(|| "-".into(), |n| n.to_string())
}

/// Writes rows as a plain aligned table (the first `left` columns left-aligned, the others
/// right-aligned).
fn write_rows(
    out: &mut impl Write,
    header: &[&str],
    rows: &[Vec<String>],
    left: usize,
) -> std::io::Result<()> {
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for row in rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let line = |cells: Vec<&str>| {
        cells
            .iter()
            .zip(&widths)
            .enumerate()
            .map(|(i, (c, &w))| {
                if i < left {
                    format!("{c:<w$}")
                } else {
                    format!("{c:>w$}")
                }
            })
            .collect::<Vec<_>>()
            .join("  ")
    };
    writeln!(out, "{}", line(header.to_vec()))?;
    let total: usize = widths.iter().sum::<usize>() + 2 * widths.len().saturating_sub(1);
    writeln!(out, "{}", "-".repeat(total))?;
    for row in rows {
        writeln!(out, "{}", line(row.iter().map(String::as_str).collect()))?;
    }
    Ok(())
}

/// The per-pair table.
fn write_table(out: &mut impl Write, records: &[Record]) -> std::io::Result<()> {
    let header = [
        "problem", "solver", "status", "contacts", "error", "time [s]", "outer", "inner",
    ];
    let rows: Vec<Vec<String>> = records
        .iter()
        .map(|r| {
            vec![
                r.problem.clone(),
                r.solver.clone(),
                if r.converged {
                    r.status.clone()
                } else {
                    format!("{} (failed)", r.status)
                },
                fmt_opt_usize(r.contacts),
                fmt_opt_sci(r.error),
                fmt_opt_time(r.time_s),
                fmt_opt_usize(r.outer_iterations),
                fmt_opt_usize(r.inner_iterations),
            ]
        })
        .collect();
    write_rows(out, &header, &rows, 3)
}

/// Per-solver summary of the profile.
#[derive(Debug, Serialize)]
struct SolverSummary {
    solver: String,
    solved: usize,
    problems: usize,
    /// ρ_s(1): fraction of problems where s was fastest (ties count for all tied)
    rho_at_1: f64,
    /// ρ_s(∞): fraction of problems s solved
    rho_max: f64,
    /// smallest τ with ρ_s(τ) = ρ_s(∞) (null when nothing was solved)
    tau_at_max: Option<f64>,
    /// total time on the problems s solved, seconds
    time_solved_s: f64,
}

fn summaries(
    records: &[Record],
    prof: &profile::Profile,
    solvers: &[String],
    n_problems: usize,
) -> Vec<SolverSummary> {
    solvers
        .iter()
        .enumerate()
        .map(|(s, name)| SolverSummary {
            solver: name.clone(),
            solved: solved_count(records, name),
            problems: n_problems,
            rho_at_1: prof.rho(s, 1.0),
            rho_max: prof.rho_max(s),
            tau_at_max: prof.tau_at_max(s),
            time_solved_s: records
                .iter()
                .filter(|r| r.solver == *name && r.converged)
                .filter_map(|r| r.time_s)
                .fold(0.0, |a, t| a + t),
        })
        .collect()
}

fn write_summary(
    out: &mut impl Write,
    records: &[Record],
    prof: &profile::Profile,
    solvers: &[String],
    n_problems: usize,
) -> std::io::Result<()> {
    let rows: Vec<Vec<String>> = summaries(records, prof, solvers, n_problems)
        .into_iter()
        .map(|s| {
            vec![
                s.solver,
                format!("{}/{}", s.solved, s.problems),
                format!("{:.3}", s.rho_at_1),
                format!("{:.3}", s.rho_max),
                s.tau_at_max
                    .map_or_else(|| "-".into(), |t| format!("{t:.3}")),
                format!("{:.6}", s.time_solved_s),
            ]
        })
        .collect();
    write_rows(
        out,
        &[
            "solver",
            "solved",
            "rho(1) wins",
            "rho(inf)",
            "tau at max",
            "time on solved [s]",
        ],
        &rows,
        1,
    )
}

/// Where and how the benchmark ran.
#[derive(Debug, Serialize)]
struct Machine {
    /// logical CPUs available to the process
    available_parallelism: Option<usize>,
    /// the CPU's model name from /proc/cpuinfo, when readable
    cpu: Option<String>,
    os: &'static str,
    arch: &'static str,
    /// seconds since the Unix epoch at the end of the run
    unix_time: Option<u64>,
}

fn machine() -> Machine {
    let cpu = std::fs::read_to_string("/proc/cpuinfo").ok().and_then(|s| {
        s.lines()
            .find(|l| l.starts_with("model name"))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
    });
    Machine {
        available_parallelism: std::thread::available_parallelism().ok().map(|n| n.get()),
        cpu,
        os: std::env::consts::OS,
        arch: std::env::consts::ARCH,
        unix_time: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .ok()
            .map(|d| d.as_secs()),
    }
}

/// Whether `e` is one of `bench`'s own write failures (the JSON or the SVG profile could not
/// be written): the CLI's exit status 4.
pub fn is_write_error(e: &(dyn std::error::Error + 'static)) -> bool {
    matches!(
        e.downcast_ref::<BenchError>(),
        Some(BenchError::Write { .. })
    ) || matches!(
        e.downcast_ref::<plot::PlotError>(),
        Some(plot::PlotError::Write { .. })
    )
}

/// The JSON document: metadata, then `records` (one per (problem, solver) pair, the array the
/// profile is computed from), then the per-solver `profile` summary.
#[derive(Debug, Serialize)]
struct Report<'a> {
    machine: Machine,
    command: String,
    tol: f64,
    time_limit_s: f64,
    repeat: usize,
    solvers: &'a [String],
    records: &'a [Record],
    profile: Vec<SolverSummary>,
    /// present when a signal stopped the benchmark early
    #[serde(skip_serializing_if = "Option::is_none")]
    interrupted: Option<&'a Partial>,
}

fn command_line() -> String {
    std::env::args()
        .map(|a| {
            if a.is_empty() || a.contains(char::is_whitespace) {
                format!("'{a}'")
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

fn write_json(
    path: &Path,
    records: &[Record],
    prof: &profile::Profile,
    solvers: &[String],
    plan: &Plan,
    interrupted: Option<&Partial>,
) -> Result<(), BenchError> {
    let n_problems = prof.n_problems();
    let report = Report {
        machine: machine(),
        command: command_line(),
        tol: plan.criteria.tol,
        time_limit_s: plan.criteria.time_limit_s,
        repeat: plan.repeat,
        solvers,
        records,
        profile: summaries(records, prof, solvers, n_problems),
        interrupted,
    };
    let text = crate::outputs::json(&report, true)?;
    crate::outputs::write(path, (text + "\n").as_bytes()).map_err(|e| BenchError::Write {
        path: path.to_path_buf(),
        source: e.source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(problem: &str, solver: &str, converged: bool, time: f64) -> Record {
        Record {
            problem: problem.into(),
            path: format!("{problem}.hdf5"),
            kind: Some("local".into()),
            contacts: Some(1),
            asymmetry: None,
            solver: solver.into(),
            status: if converged { "converged" } else { "time_limit" }.into(),
            converged,
            error: Some(1e-9),
            balance_residual: None,
            time_s: Some(time),
            outer_iterations: Some(1),
            inner_iterations: Some(1),
            runs: 1,
            message: None,
        }
    }

    #[test]
    fn time_table_keeps_only_converged_pairs() {
        let records = vec![
            vec![rec("p", "a", true, 1.0), rec("p", "b", false, 9.0)],
            vec![rec("q", "a", true, 2.0), rec("q", "b", true, 1.0)],
        ];
        assert_eq!(
            time_table(&records),
            vec![vec![Some(1.0), None], vec![Some(2.0), Some(1.0)]]
        );
    }

    #[test]
    fn arguments_are_validated() {
        let args = |tol: f64, time_limit: f64, repeat: usize, solvers: &str| Options {
            paths: vec![],
            solvers: solvers.split(',').map(str::to_string).collect(),
            tol,
            time_limit,
            repeat,
            json: None,
            svg: None,
        };
        assert!(plan(&args(1e-8, 60.0, 1, "all")).is_ok());
        assert!(matches!(
            plan(&args(0.0, 60.0, 1, "all")),
            Err(BenchError::Tol(_))
        ));
        assert!(matches!(
            plan(&args(f64::NAN, 60.0, 1, "all")),
            Err(BenchError::Tol(_))
        ));
        assert!(matches!(
            plan(&args(1e-8, -1.0, 1, "all")),
            Err(BenchError::TimeLimit(_))
        ));
        assert!(matches!(
            plan(&args(1e-8, f64::INFINITY, 1, "all")),
            Err(BenchError::TimeLimit(_))
        ));
        assert!(matches!(
            plan(&args(1e-8, 60.0, 0, "all")),
            Err(BenchError::Repeat(0))
        ));
        assert!(matches!(
            plan(&args(1e-8, 60.0, 1, "pgs,nope")),
            Err(BenchError::Solvers(_))
        ));
    }

    #[test]
    fn table_lists_every_pair_and_marks_failures() {
        let records = vec![rec("p", "a", true, 1.0), rec("p", "b", false, 9.0)];
        let mut buf = Vec::new();
        write_table(&mut buf, &records).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert_eq!(text.lines().count(), 4);
        assert!(text.contains("time_limit (failed)"));
        assert!(text.lines().nth(2).unwrap().contains("converged"));
    }
}
