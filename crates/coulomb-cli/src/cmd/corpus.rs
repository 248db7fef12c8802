//! `coulomb corpus`: writes a test corpus that nobody tunes on — FCLIB files named
//! `CLASS--NAME.hdf5` and a `manifest.json` describing each of them. The engine (the classes,
//! the generators, the manifest) is [`coulomb_lab::corpus`]; this module parses the arguments,
//! reports each file on stderr and the summary on stdout.

use crate::values::one_of;
use coulomb_lab::corpus::{self, ClassName, Entry, Options, Preset};
use std::path::PathBuf;

/// Arguments of `coulomb corpus`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// output folder (created if needed; existing corpus files in it are overwritten)
    #[arg(long)]
    pub output: PathBuf,
    /// size preset
    #[arg(long, default_value = "small", value_parser = one_of(&Preset::ALL, Preset::as_str, Some(Preset::about)))]
    pub preset: Preset,
    /// seed of every random choice
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// print one JSON object (the manifest's summary) on stdout instead of text (the per-file
    /// progress lines stay on stderr)
    #[arg(long)]
    pub json: bool,
    /// write only these classes (repeatable; default: all). `nonsym` is made from the local
    /// files of `granular` and `boxes`, which it then writes too. The files of a class are the
    /// same whatever else is written.
    #[arg(long = "class", value_parser = one_of(&ClassName::ALL, ClassName::as_str, None))]
    pub classes: Vec<ClassName>,
}

/// The line on stderr of a file written.
fn report(e: &Entry) {
    eprintln!(
        "{:<64} {:>6} {:>6} contacts, m {:>6}, n {:>6}, rank {}",
        e.file,
        e.kind,
        e.contacts,
        e.unknowns,
        e.dofs.map_or("-".into(), |n| n.to_string()),
        e.rank_w.map_or("-".into(), |r| r.to_string())
    );
}

/// Runs `coulomb corpus`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let options = Options {
        output: args.output,
        preset: args.preset,
        seed: args.seed,
        classes: args.classes,
    };
    let written = corpus::write(&options, &mut report)?;
    let dir = &options.output;
    let by_class = written.by_class();
    let secs = written.seconds;
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "output": dir.display().to_string(),
                "preset": options.preset,
                "seed": options.seed,
                "files": written.entries.len(),
                "by_class": by_class,
                "rank_deficient": written.rank_deficient(),
                "seconds": secs,
            })
        );
    } else {
        let list: Vec<String> = by_class.iter().map(|(c, n)| format!("{c} {n}")).collect();
        println!(
            "wrote {} files ({}) and manifest.json into {} in {secs:.1} s",
            written.entries.len(),
            list.join(", "),
            dir.display()
        );
    }
    Ok(())
}
