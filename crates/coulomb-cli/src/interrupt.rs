//! Runs that end well: SIGINT (Ctrl-C) and SIGTERM (`kill`, a batch system's time limit)
//! during the long commands (`simulate`, `bench`, `solve`).
//!
//! [`install`] replaces the default action of both signals (end the process at once) by a
//! flag per signal ([`signal_hook::flag`]); the command looks at [`received`] at points where
//! stopping is clean — `simulate` after each time step, `bench` after each solve, `solve`
//! inside the solver through [`cancel`] (the library's [`coulomb::deadline::Cancel`]) — writes
//! what it writes at a normal end, says that it was interrupted, and exits with 128 + the
//! signal's number: 130 for SIGINT, 143 for SIGTERM, the statuses a shell reports for a
//! process killed by them. A second signal (of either kind) while the first is handled ends
//! the process at once with that status, as without the handlers.

use crate::exit::Outcome;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

pub use crate::exit::Signal;

/// The flags set by the handlers.
struct Flags {
    int: Arc<AtomicBool>,
    term: Arc<AtomicBool>,
    /// either signal: the library's cancel flag, and the condition of the second-signal exit
    any: Arc<AtomicBool>,
}

static FLAGS: OnceLock<Flags> = OnceLock::new();

/// Installs the handlers of SIGINT and SIGTERM (once per process; later calls do nothing).
/// Called by the commands that stop cleanly, never by the others, so that those still end at
/// once on a signal.
pub fn install() -> std::io::Result<()> {
    if FLAGS.get().is_some() {
        return Ok(());
    }
    let flags = Flags {
        int: Arc::new(AtomicBool::new(false)),
        term: Arc::new(AtomicBool::new(false)),
        any: Arc::new(AtomicBool::new(false)),
    };
    for (signal, own) in [(Signal::Int, &flags.int), (Signal::Term, &flags.term)] {
        let number = match signal {
            Signal::Int => signal_hook::consts::SIGINT,
            Signal::Term => signal_hook::consts::SIGTERM,
        };
        // first: exit at once when a signal was already received (actions run in the
        // order they were registered, so this looks before this delivery sets `any`)
        signal_hook::flag::register_conditional_shutdown(
            number,
            i32::from(signal.exit_status()),
            Arc::clone(&flags.any),
        )?;
        signal_hook::flag::register(number, Arc::clone(own))?;
        signal_hook::flag::register(number, Arc::clone(&flags.any))?;
    }
    let _ = FLAGS.set(flags);
    Ok(())
}

/// The signal received since [`install`], if any (SIGINT first when both were).
pub fn received() -> Option<Signal> {
    let flags = FLAGS.get()?;
    if flags.int.load(Ordering::Relaxed) {
        Some(Signal::Int)
    } else if flags.term.load(Ordering::Relaxed) {
        Some(Signal::Term)
    } else {
        None
    }
}

/// A cancel request for the library's solver ([`coulomb::Settings::cancel`]) that a
/// received signal sets; None before [`install`].
pub fn cancel() -> Option<coulomb::deadline::Cancel> {
    let flags: &'static Flags = FLAGS.get()?;
    Some(coulomb::deadline::Cancel::new(&flags.any))
}

/// The end of an interrupted `coulomb simulate`, after its last frame, statistics and summary
/// (saying `"stopped": "interrupted"`) were written: says so on stderr. The one place for
/// what an interrupted simulation does besides a normal end.
///
/// The last checkpoint (`OUTPUT/checkpoint.h5`) is written with the other outputs, before
/// this (`run_loop::steps`), so that an interrupted run can be resumed with `--restart`.
pub fn simulation_interrupted(
    steps_done: usize,
    output: Option<&std::path::Path>,
    signal: Signal,
) -> anyhow::Result<Outcome> {
    match output {
        Some(dir) => eprintln!(
            "interrupted by {} after {} steps: frames, stats.csv, stats.json, summary.json and checkpoint.h5 (resume with --restart) in {} cover those steps",
            signal.name(),
            steps_done,
            dir.display()
        ),
        None => eprintln!("interrupted by {} after {} steps", signal.name(), steps_done),
    }
    Ok(Outcome::Interrupted(signal))
}

/// The exit of a run that was not interrupted, the same for every scene and for distributed
/// runs: status 1 when a step ended above its tolerance or `--until-rest` stopped at its step
/// cap without reaching rest (said on stderr), as `solve` does when it does not converge; 0
/// otherwise.
pub fn simulation_outcome(summary: &coulomb_granular::Summary, max_steps: usize) -> Outcome {
    if summary.not_converged_steps > 0 {
        eprintln!(
            "{} of {} step(s) ended above their tolerance (\"converged\": false in stats.csv)",
            summary.not_converged_steps, summary.steps
        );
        Outcome::No
    } else if summary.stopped == coulomb_granular::Stopped::StepCap {
        eprintln!(
            "not at rest: --until-rest stopped at its step cap ({max_steps} steps, --max-steps) with bodies still moving faster than --rest-speed"
        );
        Outcome::No
    } else {
        Outcome::Success
    }
}

/// The words after the step count in the one-line summary of `simulate`: at rest, at the
/// step cap, interrupted, or nothing.
pub fn stopped_note(summary: &coulomb_granular::Summary) -> String {
    use coulomb_granular::Stopped;
    match summary.stopped {
        Stopped::Rest => " (at rest)".into(),
        Stopped::StepCap => " (step cap reached, not at rest)".into(),
        Stopped::Interrupted => format!(
            " (interrupted by {})",
            summary.signal.as_deref().unwrap_or("a signal")
        ),
        Stopped::Steps => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_statuses_are_those_a_shell_reports() {
        assert_eq!(Signal::Int.exit_status(), 130);
        assert_eq!(Signal::Term.exit_status(), 143);
        assert_eq!(Signal::Term.name(), "SIGTERM");
    }
}
