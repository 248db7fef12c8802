//! `coulomb check FILE [--json]`: the existence criteria (4.1), (4.4), (4.5), (4.6), (5.1) of
//! an FCLIB problem, each with a verified certificate, and what the theory concludes.

use crate::exit::Outcome;
use coulomb::existence::{self, CheckSettings, Conclusion, CriterionReport, ExistenceReport};
use coulomb::fclib;
use coulomb::Problem;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Arguments of `coulomb check`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// FCLIB file (.hdf5), local or global
    pub file: PathBuf,
    /// print one JSON object instead of a table
    #[arg(long)]
    pub json: bool,
    /// decision tolerance on margins and dual bounds (relative to ‖w‖∞)
    #[arg(long, default_value_t = 1e-7, value_parser = crate::values::nonnegative)]
    pub tol: f64,
    /// largest accepted certificate residual
    #[arg(long, default_value_t = 1e-6, value_parser = crate::values::nonnegative)]
    pub certificate_tol: f64,
    /// print the certificate vectors too (table: first entries; JSON: in full)
    #[arg(long)]
    pub certificates: bool,
    /// wall-clock limit of the whole check in seconds (each conic solve is also capped at
    /// 30 s); past it the conclusion is "unknown" (exit status 3)
    #[arg(long, value_name = "SECONDS", default_value_t = 300.0,
          value_parser = crate::values::time_limit)]
    pub time_limit: f64,
}

/// Runs `coulomb check`: exit status 0 when a solution exists, 1 when none can exist, 3 when
/// the criteria are inconclusive or the check did not finish within `--time-limit`. A spinner
/// on stderr (terminal only, not with --json) names the criterion being evaluated.
pub fn run(args: Args) -> anyhow::Result<Outcome> {
    let problem = read_problem(&args.file)?;
    let budget = Duration::from_secs_f64(args.time_limit);
    let defaults = CheckSettings::default();
    let settings = CheckSettings {
        tol: args.tol,
        certificate_tol: args.certificate_tol,
        time_limit: defaults.time_limit.min(budget),
        ..defaults
    };
    let spinner = if args.json || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let pb = ProgressBar::new_spinner();
        pb.set_draw_target(ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template("{spinner} {elapsed} {msg}") {
            pb.set_style(style);
        }
        pb.enable_steady_tick(std::time::Duration::from_millis(120));
        pb
    };
    let contacts = problem.contacts();
    let shown = spinner.clone();
    // the check runs on its own thread, abandoned past the budget (a conic solve's setup is
    // not interruptible)
    let checked = crate::budget::within(budget, move || {
        existence::check_with_progress(&problem, &settings, &mut |c| {
            shown.set_message(format!("criterion ({}) on {contacts} contacts", c.label()));
        })
    });
    spinner.finish_and_clear();
    let Some(report) = checked else {
        let why = format!(
            "the check did not finish within {} s (--time-limit)",
            args.time_limit
        );
        if args.json {
            let j = serde_json::json!({
                "file": args.file.display().to_string(),
                "conclusion": "unknown",
                "skipped": why,
            });
            println!("{}", crate::outputs::json(&j, true)?);
        } else {
            println!("{}: conclusion: UNKNOWN: {why}", args.file.display());
        }
        return Ok(Outcome::Inconclusive);
    };
    let report = report?;
    if args.json {
        println!(
            "{}",
            crate::outputs::json(&to_json(&args.file, &report, args.certificates), true)?
        );
    } else {
        print_table(&args.file, &report, args.certificates);
    }
    Ok(match report.conclusion {
        Conclusion::Exists { .. } => Outcome::Success,
        Conclusion::None { .. } => Outcome::No,
        Conclusion::Unknown => Outcome::Inconclusive,
    })
}

/// Reads an FCLIB problem, exactly as stored.
fn read_problem(path: &Path) -> anyhow::Result<Problem> {
    let (file, dropped) = fclib::read_lenient(path, &fclib::ReadOptions::default())?;
    for e in dropped {
        eprintln!("warning: {e}; going on without it");
    }
    Ok(file.problem)
}

use crate::existence_json::{to_json, ORDER};

fn print_table(file: &Path, report: &ExistenceReport, certificates: bool) {
    println!(
        "{}: {} problem, d = {}, {} contacts{}",
        file.display(),
        report.kind,
        report.dim,
        report.contacts,
        if report.frictionless {
            ", frictionless"
        } else {
            ""
        }
    );
    println!(
        "{:<10} {:<10} {:>12} {:>12}  detail",
        "criterion", "verdict", "residual", "margin"
    );
    for criterion in ORDER {
        let label = criterion.label();
        let c: &CriterionReport = report.criteria.get(criterion);
        println!(
            "{:<10} {:<10} {:>12} {:>12}  {}",
            format!("({label})"),
            format!("{:?}", c.verdict).to_lowercase(),
            c.certificate_residual
                .map_or_else(|| "-".to_string(), |x| format!("{x:.2e}")),
            c.margin
                .map_or_else(|| "-".to_string(), |x| format!("{x:.3e}")),
            c.detail
        );
        if certificates {
            if let (Some(kind), Some(v)) = (c.certificate_kind, &c.certificate) {
                let shown: Vec<String> = v.iter().take(12).map(|x| format!("{x:.4e}")).collect();
                println!(
                    "{:<10} {:?} certificate ({} entries): [{}{}]",
                    "",
                    kind,
                    v.len(),
                    shown.join(", "),
                    if v.len() > 12 { ", …" } else { "" }
                );
            }
        }
    }
    match &report.conclusion {
        Conclusion::Exists { by, theorem } => {
            println!("conclusion: a solution EXISTS, by {by}: {theorem}")
        }
        Conclusion::None { by, theorem } => {
            println!("conclusion: NO solution exists, {by} fails: {theorem}")
        }
        Conclusion::Unknown => match &report.note {
            Some(note) => println!("conclusion: UNKNOWN: {note}"),
            None => println!(
                "conclusion: UNKNOWN: no sufficient criterion holds and the necessary (4.5) does not fail"
            ),
        },
    }
    println!("({:.3} s)", report.seconds);
}
