//! `coulomb`: solve, check, simulate and benchmark discrete Coulomb frictional contact problems.

mod cmd;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "coulomb",
    version,
    about = "Discrete Coulomb frictional contact: FCLIB problems, convex fixed-point solver, existence checks, granular simulation"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Summarize FCLIB files (kind, dimension, contacts, dofs, nnz, friction, stored solution)
    Info(cmd::info::Args),
    /// Error (docs/error.md) of a stored or given solution
    Error(cmd::error::Args),
    /// Solve an FCLIB problem
    Solve(cmd::solve::Args),
    /// Existence criteria (4.1), (4.4), (4.5), (4.6), (5.1) with certificates
    Check(cmd::check::Args),
    /// Write one of the paper's examples as an FCLIB file
    Example(cmd::example::Args),
    /// Granular simulation (Moreau–Jean time stepping of rigid spheres)
    Simulate(cmd::simulate::Args),
    /// Reproduce the paper's Table 1, Fig. 8 and Fig. 9
    Paper(cmd::paper::Args),
    /// Solvers side by side on FCLIB collections, with performance profiles
    Bench(cmd::bench::Args),
    /// Build a small problem, write it as FCLIB, read it back, solve it, simulate a few beads
    Demo(cmd::demo::Args),
    /// Write a test corpus (granular dumps, rigid boxes, non-symmetric W, Painlevé, random)
    Corpus(cmd::corpus::Args),
    /// Physics validation suite of the granular simulator (docs/validation.md)
    Validate(cmd::validate::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(a) => cmd::info::run(a),
        Command::Error(a) => cmd::error::run(a),
        Command::Solve(a) => cmd::solve::run(a),
        Command::Check(a) => cmd::check::run(a),
        Command::Example(a) => cmd::example::run(a),
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::Paper(a) => cmd::paper::run(a),
        Command::Bench(a) => cmd::bench::run(a),
        Command::Demo(a) => cmd::demo::run(a),
        Command::Corpus(a) => cmd::corpus::run(a),
        Command::Validate(a) => cmd::validate::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
