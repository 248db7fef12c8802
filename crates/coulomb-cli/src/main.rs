//! `coulomb`: solve, check, simulate and benchmark discrete Coulomb frictional contact problems.

mod allocator;
mod budget;
mod cmd;
mod existence_json;
mod exit;
mod interrupt;
mod method;
mod progress;
mod read;
mod run_loop;
mod run_output;
mod scene_arg;
mod sim_args;
mod values;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use coulomb_lab::{outputs, threads};
use exit::Outcome;
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "coulomb",
    version,
    about = "Discrete Coulomb frictional contact: FCLIB problems, convex fixed-point solver, existence checks, granular simulation",
    after_help = exit::HELP
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
    /// Moreau–Jean time stepping of a granular scene: built-in sphere scenes, or a scene file of spheres and rigid bodies of any shape
    Simulate(Box<sim_args::Args>),
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

impl Command {
    /// Whether the command prints JSON on stdout (then a failure is reported as a JSON object).
    fn json(&self) -> bool {
        match self {
            Command::Info(a) => a.json,
            Command::Error(a) => a.json,
            Command::Solve(a) => a.json,
            Command::Check(a) => a.json,
            Command::Simulate(a) => a.json,
            Command::Demo(a) => a.json,
            Command::Corpus(a) => a.json,
            Command::Validate(a) => a.json,
            Command::Example(_) | Command::Paper(_) | Command::Bench(_) => false,
        }
    }
}

/// Every argument of every (sub)command accepts values that look like negative numbers, so
/// that `--tol -1` reaches the value checks (and their message about the value) instead of
/// clap's "unexpected argument '-1'".
fn allow_negative_numbers(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|a| {
        if a.get_action().takes_values() {
            a.allow_negative_numbers(true)
        } else {
            a
        }
    })
    .mut_subcommands(allow_negative_numbers)
}

/// A closed stdout (`coulomb info … | head`) ends the process quietly with status 141
/// (128 + SIGPIPE, what a shell reports for a killed writer) instead of a panic message.
fn quiet_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("Broken pipe") {
            std::process::exit(141);
        }
        default(info);
    }));
}

fn main() -> ExitCode {
    allocator::keep_freed_memory();
    quiet_broken_pipe();
    let matches = allow_negative_numbers(Cli::command()).get_matches();
    let mut cli = match Cli::from_arg_matches(&matches) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    if let (Command::Simulate(a), Some(("simulate", m))) = (&mut cli.command, matches.subcommand())
    {
        a.given = sim_args::given_options(m);
    }
    let json = cli.command.json();
    let result: anyhow::Result<Outcome> = match cli.command {
        Command::Info(a) => cmd::info::run(a),
        Command::Error(a) => cmd::error::run(a),
        Command::Solve(a) => cmd::solve::run(a),
        Command::Check(a) => cmd::check::run(a),
        Command::Example(a) => cmd::example::run(a).map(|()| Outcome::Success),
        Command::Simulate(a) => simulate(*a),
        Command::Paper(a) => cmd::paper::run(a).map(|()| Outcome::Success),
        Command::Bench(a) => cmd::bench::run(a),
        Command::Demo(a) => cmd::demo::run(a).map(|()| Outcome::Success),
        Command::Corpus(a) => cmd::corpus::run(a).map(|()| Outcome::Success),
        Command::Validate(a) => cmd::validate::run(a).map(|()| Outcome::Success),
    };
    match result {
        Ok(outcome) => outcome.code(),
        Err(e) => {
            let status = exit::status_of(&e, cmd::bench::is_write_error);
            if json {
                let obj = serde_json::json!({
                    "error": exit::message(&e),
                    "exit_status": status,
                });
                println!("{obj}");
            }
            // one write of the whole line: under mpirun every rank may report the same error
            // at once into one pipe, and `eprintln!` writes a chain of causes piece by piece
            // (lines of two ranks came interleaved); a pipe keeps a write of ≤ 4 KiB whole
            let line = format!("error: {}\n", exit::message(&e));
            let _ = std::io::Write::write_all(&mut std::io::stderr().lock(), line.as_bytes());
            ExitCode::from(status)
        }
    }
}

/// `coulomb simulate`: the scene checked, then the run in this process or, under an MPI
/// launcher or with `--mpi`, distributed over the ranks, on `--threads` worker threads.
fn simulate(args: sim_args::Args) -> anyhow::Result<Outcome> {
    threads::with_threads(args.threads, || {
        #[cfg(feature = "mpi")]
        if args.grid.is_some() && !(args.mpi || sim_args::under_launcher()) {
            anyhow::bail!(
                "--grid applies to distributed runs (under mpirun/srun, or with --mpi); this run is one process"
            );
        }
        #[cfg(feature = "mpi")]
        if args.balance.is_some() && !(args.mpi || sim_args::under_launcher()) {
            anyhow::bail!(
                "--balance applies to distributed runs (under mpirun/srun, or with --mpi); this run is one process"
            );
        }
        #[cfg(feature = "mpi")]
        if args.restart.is_some() && (args.mpi || sim_args::under_launcher()) {
            anyhow::bail!("--restart runs in one process, not distributed");
        }
        if args.restart.is_some() {
            return match args.scene.as_deref() {
                None => cmd::simulate::restart(args.clone()),
                Some(s) if scene_arg::is_scene_file(s) => scene_arg::restart(&args),
                Some(s) => anyhow::bail!(
                    "--restart takes the scene from the checkpoint: give no scene name ('{s}'), or the run's scene file"
                ),
            };
        }
        if args.scene.as_deref().is_some_and(scene_arg::is_scene_file) {
            return scene_arg::run(&args);
        }
        if args.resolve_overlaps.is_some() {
            anyhow::bail!(
                "--resolve-overlaps applies to scene files: the built-in scenes start without overlaps"
            );
        }
        let scene = sim_args::checked_scene(&args)?;
        #[cfg(feature = "mpi")]
        if args.mpi || sim_args::under_launcher() {
            if args.checkpoint_every > 0 {
                anyhow::bail!("--checkpoint-every is not supported by distributed runs");
            }
            return cmd::simulate_mpi::run(args.clone(), scene);
        }
        cmd::simulate::run(args.clone(), scene)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// clap's own consistency checks on the whole command tree, as `main` builds it.
    #[test]
    fn command_tree_is_consistent() {
        allow_negative_numbers(Cli::command()).debug_assert();
    }

    /// One run loop for every scene (issue 52): `run_loop::steps`; the two simulate files
    /// build their scenes and hand them to it, and the rigid one imports nothing of the
    /// sphere one (no import circle).
    #[test]
    fn the_simulate_files_share_one_loop_without_an_import_circle() {
        let rigid = include_str!("cmd/simulate_rigid.rs");
        let spheres = include_str!("cmd/simulate.rs");
        let run_loop = include_str!("run_loop.rs");
        assert!(!rigid.contains(concat!("cmd::", "simulate::")));
        assert!(!rigid.contains(concat!("use super::", "simulate")));
        assert!(!run_loop.contains(concat!("cmd::", "simulate")));
        for file in [rigid, spheres] {
            assert!(file.contains(concat!("run_loop::", "steps(")));
            assert!(!file.contains(concat!("fn ", "steps")));
            assert!(!file.contains(concat!(".step", "()")));
        }
    }
}
