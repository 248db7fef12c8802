//! Reading FCLIB files the way the inspecting subcommands (`info`, `solve`, `error`) do.

use coulomb::fclib::{self, FclibFile};

/// Reads a file exactly as stored for inspection; a malformed /solution or /guesses group
/// (stored solutions are data, not truth) is left out with a warning on stderr.
pub fn read_relaxed(path: &std::path::Path) -> Result<FclibFile, fclib::FclibError> {
    let (file, dropped) = read_relaxed_dropped(path)?;
    for e in dropped {
        eprintln!("warning: {e}; going on without it");
    }
    Ok(file)
}

/// [`read_relaxed`] without the warnings: the errors of the groups left out are returned.
pub fn read_relaxed_dropped(
    path: &std::path::Path,
) -> Result<(FclibFile, Vec<fclib::FclibError>), fclib::FclibError> {
    fclib::read_lenient(path, &fclib::ReadOptions::default())
}
