//! `coulomb solve`.

/// Arguments of `coulomb solve`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `coulomb solve`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("coulomb solve is not available yet")
}
