//! `coulomb simulate`.

/// Arguments of `coulomb simulate`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `coulomb simulate`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("coulomb simulate is not available yet")
}
