//! `coulomb bench`: solvers side by side on FCLIB collections, compared by Dolan–Moré
//! performance profiles of solve time. The engine (the runs, the records, the profile, the
//! table, the JSON and the SVG) is [`coulomb_lab::bench`]; this module parses the arguments
//! and stops the run cleanly on SIGINT/SIGTERM ([`crate::interrupt`]: exit status 130/143).

use crate::exit::{Outcome, Signal};
use coulomb_lab::bench::{self, Interrupts, Options};
use std::path::PathBuf;

pub use coulomb_lab::bench::is_write_error;

/// Arguments of `coulomb bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// FCLIB files, or directories searched recursively (all levels) for *.hdf5 and *.h5 files
    #[arg(required = true, value_name = "PATH")]
    pub paths: Vec<PathBuf>,
    /// Comma-separated solvers: pgs, apgd, ipm, faceted (plain fixed-point outer iteration),
    /// the same with +anderson (accelerated outer iteration), or all
    #[arg(long, value_delimiter = ',', default_value = "all")]
    pub solvers: Vec<String>,
    /// Tolerance on the error of docs/error.md (and on the balance residual of global problems)
    #[arg(long, default_value_t = 1e-8, value_parser = crate::values::tolerance)]
    pub tol: f64,
    /// Time limit of each solve, in seconds (at most one week)
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0, value_parser = crate::values::time_limit)]
    pub time_limit: f64,
    /// Number of runs of each (problem, solver) pair; the median time is reported
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = crate::values::count)]
    pub repeat: usize,
    /// Write every record (and machine/command metadata) to this JSON file
    #[arg(long, value_name = "OUT.json")]
    pub json: Option<PathBuf>,
    /// Write the performance profile to this SVG file
    #[arg(long, value_name = "OUT.svg")]
    pub svg: Option<PathBuf>,
}

/// Runs `coulomb bench`: 0 when it ran to its end, 130/143 when a signal stopped it.
pub fn run(args: Args) -> anyhow::Result<Outcome> {
    let options = Options {
        paths: args.paths,
        solvers: args.solvers,
        tol: args.tol,
        time_limit: args.time_limit,
        repeat: args.repeat,
        json: args.json,
        svg: args.svg,
    };
    let signals = Interrupts {
        install: &crate::interrupt::install,
        received: &crate::interrupt::received,
        name: Signal::name,
    };
    let stdout = std::io::stdout();
    let interrupted = bench::run(&options, &signals, &mut stdout.lock())?;
    Ok(interrupted.map_or(Outcome::Success, Outcome::Interrupted))
}
