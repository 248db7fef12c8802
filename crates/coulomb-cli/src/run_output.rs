//! The pieces of a simulation run's outputs that every `coulomb simulate` engine shares (the
//! one run loop [`crate::run_loop`] and the distributed run use them, issue 52): the output folder opened and checked once, the statistics,
//! summary and checkpoint files, the FCLIB dumps, and the exit status of a failed write.

use anyhow::Context;
use coulomb_granular::output_dir::{RunKind, RunOutput};
use coulomb_granular::CheckpointError;
use std::path::{Path, PathBuf};

use crate::sim_args::Args;

/// The checkpoint file that `--checkpoint-every` writes into the output folder.
pub const CHECKPOINT_FILE: &str = "checkpoint.h5";

/// An I/O error writing `what` into the output folder `dir`: an output that could not be
/// written (exit status 4), unless it is a refusal of a link or special file put there (the
/// refusal is kept in the chain: exit status 2).
pub(crate) fn write_failed(dir: &Path, what: &str) -> impl FnOnce(std::io::Error) -> anyhow::Error {
    let path = dir.join(what).display().to_string();
    move |source| crate::exit::WriteFailed { path, source }.into()
}

/// The outputs of a run into `--output DIR` ([`RunOutput`]: every name checked, the inputs
/// refused and a restart's statistics continued only in its own run's folder, all before
/// anything is computed or created; exit status 2 for a refusal).
pub(crate) fn open_outputs(
    args: &Args,
    kind: RunKind,
    names: &[&str],
    header: &str,
    inputs: &[PathBuf],
    first_step: Option<u64>,
) -> anyhow::Result<Option<RunOutput>> {
    let Some(dir) = &args.output else {
        return Ok(None);
    };
    let mut all: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    if let Some(r) = &args.restart {
        all.push(r);
    }
    let restart = match (first_step, &args.restart) {
        (Some(step), Some(file)) => Some((file.as_path(), step)),
        _ => None,
    };
    RunOutput::open(dir, kind, names, &all, restart, header)
        .map(Some)
        .with_context(|| format!("--output {}", dir.display()))
}

/// Writes `summary.json` into the run's folder, saying so when it replaces one.
pub(crate) fn write_summary(out: &RunOutput, json: &str) -> anyhow::Result<()> {
    let existed = out.dir.is_file("summary.json");
    out.dir
        .write("summary.json", json.as_bytes())
        .map_err(write_failed(out.dir.path(), "summary.json"))?;
    if existed {
        eprintln!(
            "note: replaced existing {}",
            out.dir.display_path("summary.json").display()
        );
    }
    Ok(())
}

/// Writes `stats.json` (`text`) and flushes `stats.csv`.
pub(crate) fn write_stats_json(out: &mut RunOutput, text: &str) -> anyhow::Result<()> {
    let dir = out.dir.path().to_path_buf();
    out.write_json(text)
        .map_err(write_failed(&dir, "stats.json"))
}

/// Writes the checkpoint `bytes` (of step `step`) into the run's folder.
pub(crate) fn write_checkpoint_bytes(
    out: &mut RunOutput,
    step: u64,
    bytes: Result<Vec<u8>, CheckpointError>,
) -> anyhow::Result<()> {
    let dir = out.dir.path().to_path_buf();
    let bytes = bytes.map_err(|e| crate::exit::WriteFailed {
        path: dir.join(CHECKPOINT_FILE).display().to_string(),
        source: std::io::Error::other(e.to_string()),
    })?;
    out.checkpoint(step, &bytes)
        .map_err(write_failed(&dir, CHECKPOINT_FILE))
}

/// Writes one step's problem as `step_KKKKKK.hdf5` in FCLIB global format.
pub(crate) fn dump_fclib(
    dir: &std::path::Path,
    step: usize,
    problem: &coulomb::problem::GlobalProblem,
) -> anyhow::Result<()> {
    use coulomb::fclib::{FclibFile, Info};
    let path = dir.join(format!("step_{step:06}.hdf5"));
    let mut file = FclibFile::new(coulomb::problem::Problem::Global(problem.clone()));
    file.info = Some(Info {
        title: format!("granular step {step}"),
        description: "Moreau-Jean step of coulomb simulate (coulomb-granular)".into(),
        math_info: String::new(),
    });
    crate::outputs::write_fclib(&path, &file)
}

/// Where a run stopped, for [`finish`].
pub(crate) struct RunEnd {
    /// steps done k at the end (the checkpoint's step)
    pub steps_done: u64,
    /// whether this run took a step
    pub stepped: bool,
    /// whether a signal stopped the run
    pub interrupted: bool,
}

/// The end of a run's outputs, the same for every engine: `stats.json` (`stats_json`), the end
/// state's checkpoint (`checkpoint`) unless the last step just wrote it — an interrupted run
/// always leaves one, to be resumed with `--restart` — and `summary.json` (`summary_json`).
pub(crate) fn finish(
    out: &mut RunOutput,
    args: &Args,
    end: RunEnd,
    checkpoint: impl FnOnce() -> Result<Vec<u8>, CheckpointError>,
    stats_json: &str,
    summary_json: &str,
) -> anyhow::Result<()> {
    write_stats_json(out, stats_json)?;
    let every = args.checkpoint_every as u64;
    let written = end.stepped && every > 0 && end.steps_done % every == 0;
    if (every > 0 || end.interrupted) && !written {
        write_checkpoint_bytes(out, end.steps_done, checkpoint())?;
    }
    write_summary(out, summary_json)
}
